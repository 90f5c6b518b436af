//! The reliability fixes, one test each: settings checked wherever they
//! come from, output files staged through exclusive random temporary
//! files, memory estimated before building, image and sidecar replaced
//! together, time limits of any size, regular files only, cache entries
//! that vanish under a render, unwritable outputs found early, Ctrl-C
//! before the first pass, `-o` onto the scene, duplicate names, meshes
//! without triangles, huge strings, empty names and byte-order marks.
//!
//! Each test says what the renderer did before its fix (commit de7c7df),
//! which is what the test would have caught.

use crate::common::{self, load_error, refused, run_limited, tracer, write, Watched};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Duration;
use tempfile::TempDir;

/// A small valid JSON scene: an emissive quad above a sphere, 8 × 8, 1 spp.
fn small_scene() -> Value {
    json!({
        "camera": { "position": [0, 0, -5], "look_at": [0, 0, 0], "fov": 40 },
        "film": { "width": 8, "height": 8 },
        "render": { "spp": 1 },
        "objects": [
            { "type": "sphere", "subdivisions": 1 },
            { "type": "quad", "emission": [1, 1, 1], "transform": { "translate": [0, 3, 0] } }
        ]
    })
}

fn write_scene(dir: &Path, name: &str, scene: &Value) -> PathBuf {
    common::write_json(dir, name, scene)
}

/// Creates a named pipe at `path`.
fn mkfifo(path: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    let r = unsafe { libc::mkfifo(c.as_ptr(), 0o644) };
    assert_eq!(
        r,
        0,
        "mkfifo {}: {}",
        path.display(),
        std::io::Error::last_os_error()
    );
}

/// The names in `dir` that look like temporary files.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

// ---------------------------------------------------------------------------
// 1 and 5. Settings are checked wherever they come from.

/// `--width 65536 --height 65536` is refused (status 1, the flags named)
/// before any geometry is read: here the scene's mesh file does not exist,
/// and the size is what the error is about. (The message itself is also
/// checked by `cli::settings_from_flags_are_checked_and_the_flag_named`.)
///
/// Before: the flags were applied after the scene was built, so this
/// scene failed on its mesh, and with the Cornell box the render
/// allocated the 65536 × 65536 film (killed for memory after a minute).
#[test]
fn settings_from_flags_are_checked_before_any_geometry_is_read() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let mut scene = small_scene();
    scene["objects"][0] = json!({ "type": "mesh", "file": "missing.obj" });
    let path = write_scene(dir.path(), "missing-mesh.json", &scene);
    let output = tracer()
        .args([
            "render",
            s(&path),
            "-q",
            "--width",
            "65536",
            "--height",
            "65536",
        ])
        .args(["-o", s(&dir.path().join("out.exr"))])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--width/--height: 65536 x 65536 is too large"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("missing.obj"),
        "the mesh was read first: {stderr}"
    );
}

/// A `.trs` file's `Display` size and `Camera` field of view pass the same
/// checks as a JSON scene's and a flag's, and the error names the member.
/// (The flags' case is `cli::settings_from_flags_are_checked_and_the_flag_named`.)
///
/// Before: a `Display` too large was refused under the key `film`, which
/// a `.trs` file does not have, and `fov` was taken without a check: 0 or
/// a negative angle loaded and rendered.
#[test]
fn a_trs_display_too_large_or_a_field_of_view_not_above_zero_is_refused_with_its_key() {
    let dir = TempDir::new().unwrap();
    let camera = |fov: f64| json!({ "Type": "Camera", "Position": [0.0, 1.0, -3.0], "fov": fov });
    let big = json!({
        "Display": { "Type": "PFM", "ResX": 65536, "ResY": 65536 },
        "Camera": camera(60.0)
    });
    let path = write_scene(dir.path(), "big.trs", &big);
    refused(&path, &["\"Display\"", "65536 x 65536 is too large"]);

    for (name, fov, expect) in [
        ("zero.trs", 0.0, "greater than zero"),
        ("negative.trs", -30.0, "greater than zero"),
        ("flat.trs", 180.0, "less than 180"),
    ] {
        let path = write_scene(dir.path(), name, &json!({ "Camera": camera(fov) }));
        refused(&path, &["\"Camera\".fov", expect]);
    }
    // A sound field of view loads.
    let path = write_scene(dir.path(), "fine.trs", &json!({ "Camera": camera(60.0) }));
    tracer::format::read_scene(&path).unwrap();
}

// ---------------------------------------------------------------------------
// 2. Output temporary files are random and exclusive.

/// Symbolic links planted at every temporary name the writer used to
/// choose (`.NAME.PID-N.tmp`, for the image and its sidecar) are left
/// alone: the victim they point at is unchanged, the image and sidecar are
/// plain files with the right contents, and they carry the permissions a
/// plainly created file gets (0644 under a umask of 022), not 0600.
///
/// Before: the writer created `.NAME.PID-N.tmp` with `File::create`, which
/// follows a symbolic link: the image's bytes went into the victim, and
/// the rename then put the link itself in the output's place.
#[test]
fn symbolic_links_at_the_old_temporary_names_are_never_written_through() {
    use std::os::unix::fs::PermissionsExt;
    use tracer::film::tonemap::{to_8bit, Tonemap};
    let dir = TempDir::new().unwrap();
    let victim = write(&dir.path().join("victim.txt"), "the victim's own bytes\n");
    let out = dir.path().join("out.png");
    let pid = std::process::id();
    // The old counter was shared by every write in the process: plant
    // well beyond the writes the other tests make.
    for name in ["out.png", "out.png.json"] {
        for n in 0..1024 {
            let link = dir.path().join(format!(".{name}.{pid}-{n}.tmp"));
            std::os::unix::fs::symlink(&victim, link).unwrap();
        }
    }
    let mut image = tracer::film::Image::new(7, 5);
    for (k, p) in image.pixels.iter_mut().enumerate() {
        *p = glam::Vec3::new(k as f32 * 0.03, 0.5, 1.0 - k as f32 * 0.02);
    }
    // SAFETY: umask(2) only swaps the process's file mode mask; the old
    // one is put back below.
    let old_umask = unsafe { libc::umask(0o022) };
    let written = tracer::film::write::write_image_with(
        &out,
        &image,
        Tonemap::Srgb,
        0.0,
        Some(&common::metadata(7, 5, 1)),
    );
    // SAFETY: as above.
    unsafe { libc::umask(old_umask) };
    written.unwrap();

    assert_eq!(
        std::fs::read(&victim).unwrap(),
        b"the victim's own bytes\n",
        "the write went through a planted link"
    );
    let sidecar = tracer::film::metadata::sidecar_path(&out);
    for file in [&out, &sidecar] {
        let meta = std::fs::symlink_metadata(file).unwrap();
        assert!(
            meta.file_type().is_file(),
            "{} is not a plain file",
            file.display()
        );
        assert_eq!(
            meta.permissions().mode() & 0o777,
            0o644,
            "{} has the permissions of a private temporary file",
            file.display()
        );
    }
    let decoded = image::open(&out).unwrap().to_rgb8();
    for y in 0..5 {
        for x in 0..7 {
            assert_eq!(
                decoded.get_pixel(x, y).0,
                to_8bit(image.get(x, y), Tonemap::Srgb, 0.0)
            );
        }
    }
    let side: tracer::film::metadata::Metadata =
        serde_json::from_slice(&std::fs::read(&sidecar).unwrap()).unwrap();
    assert_eq!(side.seed, 1);
    // Every planted link is still there, still a link, and nothing else
    // was left beside the outputs.
    let links = std::fs::read_dir(dir.path())
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_type().unwrap().is_symlink())
        .count();
    assert_eq!(links, 2048);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2048 + 3);
}

// ---------------------------------------------------------------------------
// 3. Memory is estimated before anything is built.

/// A 10 KB scene of 100 spheres at 10 subdivisions (2 billion triangles,
/// about 500 GiB) is refused at once, by a process allowed 1 GiB of
/// address space. (Peak memory cannot be read from `wait4`: a child's
/// `ru_maxrss` counts its parent's memory, shared until the exec.)
///
/// Before: it was built sphere by sphere; under the 1 GiB limit it
/// aborted when an allocation failed (without it, it ran until the
/// machine was out of memory).
#[test]
fn a_scene_that_would_not_fit_in_memory_is_refused_before_it_is_built() {
    let _guard = common::serial();
    let dir = TempDir::new().unwrap();
    let objects: Vec<Value> = (0..100)
        .map(|i| json!({ "type": "sphere", "subdivisions": 10, "center": [i, 0, 0] }))
        .collect();
    let mut scene = small_scene();
    scene["objects"] = Value::Array(objects);
    let path = write_scene(dir.path(), "spheres.json", &scene);
    let mut command = tracer();
    command
        .args(["render", s(&path), "-q", "-o"])
        .arg(dir.path().join("out.exr"));
    // The default limit is the memory available now; on a machine with
    // more than the scene needs, name a limit so the test still means
    // something.
    let needs = 100u64 * 20 * (1 << 20) * tracer::scene::estimate::BYTES_PER_TRIANGLE;
    if tracer::scene::estimate::available_memory().is_none_or(|a| a >= needs) {
        command.args(["--memory-limit", "64G"]);
    }
    // SAFETY: the closure only calls setrlimit(2), which is
    // async-signal-safe, between fork and exec.
    unsafe {
        use std::os::unix::process::CommandExt;
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 1 << 30,
                rlim_max: 1 << 30,
            };
            match libc::setrlimit(libc::RLIMIT_AS, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let run = run_limited(&mut command, Duration::from_secs(20));
    assert!(!run.timed_out, "still running after 20 s: {run:?}");
    assert_eq!(run.signal, None, "{run:?}");
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(
        run.stderr.contains("needs about") && run.stderr.contains("available"),
        "{}",
        run.stderr
    );
    assert!(
        run.stderr.contains("2097152000 triangles"),
        "{}",
        run.stderr
    );
    assert!(
        run.elapsed < Duration::from_secs(3),
        "took {:?}",
        run.elapsed
    );
}

/// `--memory-limit` sets the limit: 1K refuses even the Cornell box.
///
/// Before: there was no such flag (clap refused it with status 2).
#[test]
fn a_memory_limit_refuses_even_the_cornell_box() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("box.exr");
    let output = tracer()
        .args([
            "render",
            "scenes/cornell-box.json",
            "-q",
            "--memory-limit",
            "1K",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("needs about"), "{stderr}");
    assert!(stderr.contains("but 1.0 KiB is available"), "{stderr}");
    assert!(!out.exists());
}

/// The estimate counts each shape's triangles as the builder makes them:
/// quad 2, cube 12, sphere 20·4^s, a triangle list its thirds, and an OBJ
/// face of n vertices n − 2 (a triangle, a quad and a pentagon: 6).
///
/// Before: there was no estimate.
#[test]
fn the_memory_estimate_counts_the_triangles_each_shape_makes() {
    use tracer::scene::estimate::{estimate, BYTES_PER_PIXEL, BYTES_PER_TRIANGLE};
    let dir = TempDir::new().unwrap();
    write(
        &dir.path().join("faces.obj"),
        "# a triangle, a quad and a pentagon\n\
         v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -0.5 0.5 0\n\
         v 0 0 1\nv 1 0 1\nv 1 1 1\n\
         vt 0 0\nvn 0 0 1\n\
         f 6/1/1 7/1/1 8/1/1\n\
         f 1 2 3 4\n\
           f\t1 2 3 4 5\n\
         fo 1 2 3\n",
    );
    let scene = json!({
        "camera": { "position": [0, 0, -5], "look_at": [0, 0, 0], "fov": 40 },
        "film": { "width": 30, "height": 20 },
        "objects": [
            { "type": "quad" },
            { "type": "cube", "transform": { "translate": [3, 0, 0] } },
            { "type": "sphere", "subdivisions": 0, "center": [0, 3, 0] },
            { "type": "sphere", "subdivisions": 3, "center": [0, -3, 0] },
            { "type": "triangles", "positions": [[0, 0, 2], [1, 0, 2], [0, 1, 2], [0, 0, 3], [1, 0, 3], [0, 1, 3]] },
            { "type": "mesh", "file": "faces.obj" }
        ]
    });
    let path = write_scene(dir.path(), "shapes.json", &scene);
    let desc = tracer::format::read_scene(&path).unwrap();
    let e = estimate(&desc, &desc.settings);
    let expected = 2 + 12 + 20 + 20 * 4u64.pow(3) + 2 + (1 + 2 + 3);
    assert_eq!(e.triangles, expected);
    assert_eq!(e.pixels, 600);
    assert_eq!(
        e.bytes,
        expected * BYTES_PER_TRIANGLE + 600 * BYTES_PER_PIXEL
    );
    // The builder makes exactly as many (none of these is degenerate).
    let built = tracer::scene::build(&desc, None).unwrap();
    assert_eq!(built.triangles.len() as u64, expected);
}

// ---------------------------------------------------------------------------
// 4. An image and its sidecar are replaced together.

/// A PNG whose image cannot be put in place (its name is now a folder)
/// leaves the sidecar of the previous render byte for byte, and a fresh
/// name whose image fails gets no orphan sidecar. (A folder in the way
/// works as root too, where permissions would not.)
///
/// Before: the sidecar was written first, on its own: it was replaced by
/// one describing an image that was never written.
#[test]
fn an_image_and_its_sidecar_are_replaced_together_or_not_at_all() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("out.png");
    let sidecar = tracer::film::metadata::sidecar_path(&out);
    let render = |out: &Path, seed: &str| {
        tracer()
            .args([
                "render",
                "scenes/cornell-box.json",
                "--width",
                "8",
                "--height",
                "8",
            ])
            .args(["--spp", "1", "--seed", seed, "-q", "-o"])
            .arg(out)
            .output()
            .unwrap()
    };
    let first = render(&out, "1");
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert!(out.is_file() && sidecar.is_file());
    let old_sidecar = std::fs::read(&sidecar).unwrap();

    std::fs::remove_file(&out).unwrap();
    write(&out.join("in-the-way"), "a folder where the image was");
    let second = render(&out, "2");
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("out.png"), "{stderr}");
    assert!(
        std::fs::read(&sidecar).unwrap() == old_sidecar,
        "the sidecar was replaced though its image was not"
    );

    let fresh = dir.path().join("fresh.png");
    std::fs::create_dir(&fresh).unwrap();
    let third = render(&fresh, "3");
    assert_eq!(third.status.code(), Some(1));
    assert!(
        !tracer::film::metadata::sidecar_path(&fresh).exists(),
        "a sidecar without its image was left"
    );
    assert_eq!(temporaries(dir.path()), Vec::<String>::new());
}

// ---------------------------------------------------------------------------
// 6. Time limits of any finite size.

/// `--time-limit` and `"time_limit"` of 1e20 or 1e300 seconds, and
/// `--checkpoint` as long, render normally.
///
/// Before: each went through `Duration::from_secs_f64`, which panics on a
/// value too large for a `Duration` (exit status 101).
#[test]
fn time_limits_and_checkpoints_of_any_finite_size_render_normally() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let mut scene = small_scene();
    scene["render"] = json!({ "spp": 4, "time_limit": 1e20 });
    let limited = write_scene(dir.path(), "limited.json", &scene);
    scene["render"] = json!({ "spp": 4, "time_limit": 1e300 });
    let very = write_scene(dir.path(), "very-limited.json", &scene);
    let plain = write_scene(dir.path(), "plain.json", &small_scene());
    let cases: Vec<(&Path, Vec<&str>)> = vec![
        (&plain, vec!["--spp", "4", "--time-limit", "1e20"]),
        (&plain, vec!["--spp", "4", "--time-limit", "1e300"]),
        (&plain, vec!["--spp", "4", "--checkpoint", "1e20"]),
        (&plain, vec!["--spp", "4", "--checkpoint", "1e300"]),
        (&limited, vec![]),
        (&very, vec![]),
    ];
    for (k, (scene, flags)) in cases.into_iter().enumerate() {
        let out = dir.path().join(format!("out{k}.exr"));
        let output = tracer()
            .args(["render", s(scene), "-q", "-o", s(&out)])
            .args(&flags)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{scene:?} {flags:?}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{flags:?}: {stderr}");
        assert!(stderr.contains("4 spp"), "{flags:?}: {stderr}");
        assert!(out.is_file());
    }
}

// ---------------------------------------------------------------------------
// 7. Only regular files are read.

/// A mesh that is a FIFO or `/dev/zero`, a scene file that is a FIFO and a
/// texture that is `/dev/zero` or a FIFO are refused at once, naming the
/// key; an MTL file that is a FIFO costs only the materials. Each run is
/// killed after 20 s, so a regression fails rather than hangs.
///
/// Before: opening a FIFO (mesh, scene, texture or MTL) blocked until a
/// writer came, forever; `/dev/zero` as a mesh was read until memory ran
/// out, and as a texture failed as an image of unknown format.
#[test]
fn devices_and_pipes_are_refused_as_scenes_meshes_and_textures() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    mkfifo(&dir.path().join("pipe.obj"));
    mkfifo(&dir.path().join("pipe.json"));
    mkfifo(&dir.path().join("pipe.png"));
    mkfifo(&dir.path().join("pipe.mtl"));
    let with_object = |name: &str, object: Value| {
        let mut scene = small_scene();
        scene["objects"][0] = object;
        write_scene(dir.path(), name, &scene)
    };
    let with_texture = |name: &str, texture: &str| {
        let mut scene = small_scene();
        scene["materials"] =
            json!({ "t": { "type": "diffuse", "albedo": { "texture": texture } } });
        scene["objects"][0] = json!({ "type": "quad", "material": "t" });
        write_scene(dir.path(), name, &scene)
    };
    let cases = [
        (
            with_object(
                "fifo-mesh.json",
                json!({ "type": "mesh", "file": "pipe.obj" }),
            ),
            vec![
                "fifo-mesh.json",
                "objects[0].file",
                "pipe.obj",
                "not a regular file",
            ],
        ),
        (
            with_object(
                "zero-mesh.json",
                json!({ "type": "mesh", "file": "/dev/zero" }),
            ),
            vec![
                "zero-mesh.json",
                "objects[0].file",
                "/dev/zero",
                "not a regular file",
            ],
        ),
        (
            dir.path().join("pipe.json"),
            vec!["pipe.json", "not a regular file"],
        ),
        (
            with_texture("zero-texture.json", "/dev/zero"),
            vec![
                "zero-texture.json",
                "materials.t.albedo",
                "/dev/zero",
                "not a regular file",
            ],
        ),
        (
            with_texture("fifo-texture.json", "pipe.png"),
            vec![
                "fifo-texture.json",
                "materials.t.albedo",
                "pipe.png",
                "not a regular file",
            ],
        ),
    ];
    for (scene, parts) in cases {
        let run = run_limited(
            tracer().args([
                "render",
                s(&scene),
                "-q",
                "-o",
                s(&dir.path().join("out.exr")),
            ]),
            Duration::from_secs(20),
        );
        assert!(
            !run.timed_out,
            "{}: still running after 20 s",
            scene.display()
        );
        assert_eq!(run.code, Some(1), "{}: {}", scene.display(), run.stderr);
        let line = run
            .stderr
            .lines()
            .find(|l| l.starts_with("error:"))
            .unwrap_or("");
        for part in parts {
            assert!(line.contains(part), "{part:?} not in {:?}", run.stderr);
        }
    }

    // An MTL file that is a pipe: the mesh renders with the default material.
    write(
        &dir.path().join("tri.obj"),
        "mtllib pipe.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    );
    let scene = with_object(
        "fifo-mtl.json",
        json!({ "type": "mesh", "file": "tri.obj" }),
    );
    let run = run_limited(
        tracer().args([
            "render",
            s(&scene),
            "-q",
            "-o",
            s(&dir.path().join("out.exr")),
        ]),
        Duration::from_secs(20),
    );
    assert!(!run.timed_out, "an MTL pipe: still running after 20 s");
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(
        run.stderr.contains("materials not loaded"),
        "{}",
        run.stderr
    );
}

// ---------------------------------------------------------------------------
// 8. Cache entries that change under a render.

/// A scene big enough to be cached (a sphere of 327,680 triangles, a
/// 50 MB entry), stored once into `dir/cache`; returns the scene and the
/// entry's file.
fn cached_sphere(dir: &Path) -> (PathBuf, PathBuf) {
    let mut scene = small_scene();
    scene["film"] = json!({ "width": 16, "height": 16 });
    scene["objects"][0]["subdivisions"] = json!(7);
    let path = write_scene(dir, "sphere.json", &scene);
    let cache = dir.join("cache");
    let out = tracer()
        .args(["render", s(&path), "-q", "--cache-dir", s(&cache), "-o"])
        .arg(dir.join("first.exr"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stderr.contains("cached"),
        "{stderr}"
    );
    let entries: Vec<PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "tcache"))
        .collect();
    assert_eq!(entries.len(), 1, "{entries:?}");
    (path, entries[0].clone())
}

/// Starts a long render of `scene` from the cache (`TRACER_CACHE_COPY` set
/// to `copy`), truncates the entry to nothing once the render says it
/// loaded from the cache, and returns how the render ended.
fn truncate_entry_under_a_render(dir: &Path, copy: &str, seconds: &str) -> common::Finished {
    let (scene, entry) = cached_sphere(dir);
    let mut command = tracer();
    command
        .args([
            "render",
            s(&scene),
            "-q",
            "--cache-dir",
            s(&dir.join("cache")),
        ])
        .args([
            "--spp",
            "100000",
            "--time-limit",
            seconds,
            "--threads",
            "2",
            "-o",
        ])
        .arg(dir.join("second.exr"))
        .env("TRACER_CACHE_COPY", copy);
    let child = Watched::spawn(&mut command);
    assert!(
        child.wait_for_line("from the scene cache", Duration::from_secs(60)),
        "the second render did not load from the cache: {}",
        child.stderr_so_far()
    );
    std::fs::OpenOptions::new()
        .write(true)
        .open(&entry)
        .unwrap()
        .set_len(0)
        .unwrap();
    child.finish(Duration::from_secs(120))
}

/// With `TRACER_CACHE_COPY=1` the entry is read into memory: truncating
/// its file while the render runs changes nothing.
///
/// Before: entries were always mapped, so the render died of SIGBUS.
#[test]
fn a_copied_cache_entry_truncated_during_the_render_does_not_stop_it() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let run = truncate_entry_under_a_render(dir.path(), "1", "3");
    assert!(!run.timed_out);
    assert_eq!(run.signal, None, "killed by a signal: {}", run.stderr);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(
        run.stderr.contains("stopped at the time limit"),
        "{}",
        run.stderr
    );
}

/// A mapped entry truncated while the render runs: the next touch of a
/// lost page raises SIGBUS, which the render turns into a message and
/// exit status 135 (128 + SIGBUS). (Truncation takes the pages out of
/// every mapping, so already faulted pages do not stay readable: this
/// happens every time.)
///
/// Before: the process was killed by the signal, with no message.
#[test]
fn a_mapped_cache_entry_truncated_during_the_render_is_reported_and_exits_135() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let run = truncate_entry_under_a_render(dir.path(), "0", "30");
    assert!(!run.timed_out);
    assert_eq!(run.signal, None, "killed by a signal: {}", run.stderr);
    assert_eq!(run.code, Some(135), "{}", run.stderr);
    assert!(
        run.stderr.contains("scene cache entry") && run.stderr.contains("SIGBUS"),
        "{}",
        run.stderr
    );
    assert!(
        run.elapsed < Duration::from_secs(25),
        "ran to its time limit"
    );
}

// ---------------------------------------------------------------------------
// 9. An unwritable output is found before rendering.

/// An output in a folder that does not exist, or under a regular file, is
/// reported at once, naming the output, not after a render of hours.
///
/// Before: the render ran to the end, then failed to write (the test kills
/// it after 30 s).
#[test]
fn an_unwritable_output_is_reported_before_rendering() {
    let _guard = common::serial();
    let dir = TempDir::new().unwrap();
    write(&dir.path().join("a-file"), "not a folder");
    for out in [
        dir.path().join("no-such-folder/x.png"),
        dir.path().join("a-file/x.png"),
    ] {
        let run = run_limited(
            tracer()
                .args([
                    "render",
                    "scenes/cornell-box.json",
                    "--spp",
                    "1000000",
                    "-q",
                ])
                .args(["--width", "64", "--height", "64", "-o", s(&out)]),
            Duration::from_secs(30),
        );
        assert!(
            !run.timed_out,
            "{}: rendered instead of refusing",
            out.display()
        );
        assert_eq!(run.code, Some(1), "{}", run.stderr);
        assert!(run.stderr.contains(s(&out)), "{}", run.stderr);
        assert!(
            !run.stderr.contains("loaded"),
            "it loaded the scene first: {}",
            run.stderr
        );
        assert!(
            run.elapsed < Duration::from_secs(5),
            "took {:?}",
            run.elapsed
        );
    }
}

// ---------------------------------------------------------------------------
// 10. Ctrl-C before the first pass keeps the previous file.

/// SIGINT half a second into a render whose first pass takes far longer
/// (2048 × 2048 with BDPT on one thread) exits 130, says the image was not
/// written, and leaves the previous file byte for byte.
///
/// Before: the half-rendered first pass was written over the previous
/// file, most of its pixels black (no samples yet).
#[test]
fn ctrl_c_before_the_first_pass_completes_keeps_the_previous_file() {
    let _guard = common::serial();
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("keep.exr");
    std::fs::write(&out, b"the previous image").unwrap();
    let child = Watched::spawn(
        tracer()
            .args(["render", "scenes/cornell-box.json", "--integrator", "bdpt"])
            .args(["--width", "2048", "--height", "2048", "--spp", "4"])
            .args(["--threads", "1", "-q", "-o", s(&out)]),
    );
    assert!(
        child.wait_for_line("loaded", Duration::from_secs(30)),
        "{}",
        child.stderr_so_far()
    );
    std::thread::sleep(Duration::from_millis(500));
    child.signal(libc::SIGINT);
    let run = child.finish(Duration::from_secs(60));
    assert!(!run.timed_out);
    assert_eq!(run.code, Some(130), "{}", run.stderr);
    assert!(run.stderr.contains("was not written"), "{}", run.stderr);
    assert_eq!(std::fs::read(&out).unwrap(), b"the previous image");
    assert_eq!(temporaries(dir.path()), Vec::<String>::new());
}

// ---------------------------------------------------------------------------
// 11. `-o` onto the scene file.

/// An output that is the scene file itself, however spelled (`-o`, a
/// relative path, the scene's own `film.output`), is refused, and the
/// scene is left as it was.
///
/// Before: the render replaced the scene file with the image.
#[test]
fn an_output_naming_the_scene_file_itself_is_refused() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "scene.exr", &small_scene());
    let mut own_output = small_scene();
    own_output["film"]["output"] = json!("own.exr");
    let own = write_scene(dir.path(), "own.exr", &own_output);
    let cases: Vec<(&Path, Vec<String>)> = vec![
        (&scene, vec!["-o".into(), s(&scene).into()]),
        (
            &scene,
            vec!["-o".into(), format!("{}/./scene.exr", s(dir.path()))],
        ),
        (&own, vec![]),
    ];
    for (file, flags) in cases {
        let before = std::fs::read(file).unwrap();
        let output = tracer()
            .args(["render", s(file), "-q"])
            .args(&flags)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{flags:?}: {stderr}");
        assert!(stderr.contains("is the scene file itself"), "{stderr}");
        assert!(
            std::fs::read(file).unwrap() == before,
            "{flags:?}: the scene changed"
        );
    }
    // From the scene's folder, by a relative name.
    let output = tracer()
        .current_dir(dir.path())
        .args(["render", "scene.exr", "-q", "-o", "./scene.exr"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("is the scene file itself"));
}

// ---------------------------------------------------------------------------
// 12. Names given twice.

/// A material name given twice in a JSON scene, or a member name given
/// twice in a `.trs` file, is refused, naming the section and the name.
///
/// Before: serde_json kept the last of the two, silently.
#[test]
fn a_material_or_member_name_given_twice_is_refused() {
    let dir = TempDir::new().unwrap();
    let path = write(
        &dir.path().join("twice.json"),
        r#"{
          "camera": { "position": [0, 0, -5], "look_at": [0, 0, 0], "fov": 40 },
          "materials": {
            "a": { "type": "diffuse", "albedo": [0.8, 0.8, 0.8] },
            "b": { "type": "mirror" },
            "a": { "type": "mirror" }
          },
          "objects": [ { "type": "quad", "material": "a" } ]
        }"#,
    );
    refused(&path, &["materials", "\"a\"", "given twice"]);

    let path = write(
        &dir.path().join("twice.trs"),
        r#"{
          "Camera": { "Type": "Camera", "Position": [0, 1, -3], "fov": 60 },
          "Lamp": { "Type": "Light", "LightType": "Point", "Position": [0, 2, 0], "Intensity": [1, 1, 1] },
          "Lamp": { "Type": "Light", "LightType": "Point", "Position": [0, 3, 0], "Intensity": [1, 1, 1] }
        }"#,
    );
    refused(&path, &["\"Lamp\"", "given twice"]);
}

// ---------------------------------------------------------------------------
// 13. Meshes without triangles.

/// An empty mesh file and a text file that is not an OBJ load as no
/// triangles, with a warning naming each on standard error.
///
/// Before: both loaded as nothing, silently.
#[test]
fn a_mesh_file_without_triangles_is_warned_about() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    write(&dir.path().join("empty.obj"), "");
    write(
        &dir.path().join("notes.obj"),
        "Shopping list:\n- milk\n- a better mesh\n",
    );
    let mut scene = small_scene();
    scene["objects"][0] = json!({ "type": "mesh", "file": "empty.obj" });
    scene["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "type": "mesh", "file": "notes.obj" }));
    let path = write_scene(dir.path(), "hollow.json", &scene);
    let output = tracer()
        .args([
            "render",
            s(&path),
            "-q",
            "-o",
            s(&dir.path().join("out.exr")),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    for name in ["empty.obj", "notes.obj"] {
        assert!(
            stderr.lines().any(|l| l.starts_with("warning:")
                && l.contains(name)
                && l.contains("has no triangles")),
            "no warning for {name}: {stderr}"
        );
    }
}

// ---------------------------------------------------------------------------
// 14. Huge strings are not echoed whole.

/// A 100 MB material name, key or type in a scene gives an error message
/// under 2 KB that still names the file and the key.
///
/// Before: the message repeated the 100 MB string.
#[test]
fn a_huge_string_in_a_scene_is_not_echoed_whole() {
    let dir = TempDir::new().unwrap();
    let huge = "x".repeat(100_000_000);
    let path = dir.path().join("huge.json");
    let mut unknown_key = json!({ "type": "quad" });
    unknown_key[huge.as_str()] = json!(1);
    let cases = [
        (
            json!({ "type": "quad", "material": huge }),
            "objects[0].material",
        ),
        (json!({ "type": huge }), "objects[0].type"),
        (unknown_key, "objects[0]"),
    ];
    for (object, key) in cases {
        let mut scene = small_scene();
        scene["objects"][0] = object;
        std::fs::write(&path, serde_json::to_vec(&scene).unwrap()).unwrap();
        let message = load_error(&path);
        assert!(
            message.len() < 2048,
            "{key}: a message of {} bytes",
            message.len()
        );
        assert!(
            message.contains("huge.json") && message.contains(key),
            "{message}"
        );
    }
}

// ---------------------------------------------------------------------------
// 15. Empty names and byte-order marks.

/// `"name": ""` is refused naming `name` (it names the default output),
/// and a UTF-8 byte-order mark before a JSON or `.trs` scene is accepted.
///
/// Before: the empty name made the output `.exr`, refused only at render
/// time as an unknown image format; the byte-order mark was a syntax error.
#[test]
fn an_empty_name_is_refused_and_a_byte_order_mark_is_accepted() {
    let dir = TempDir::new().unwrap();
    for name in ["", "   "] {
        let mut scene = small_scene();
        scene["name"] = json!(name);
        let path = write_scene(dir.path(), "nameless.json", &scene);
        let message = refused(&path, &["name", "non-empty"]);
        assert!(!message.contains("unknown image format"), "{message}");
    }

    let json_text = serde_json::to_string(&small_scene()).unwrap();
    let path = write(&dir.path().join("bom.json"), format!("\u{feff}{json_text}"));
    let desc = tracer::format::read_scene(&path).unwrap();
    assert_eq!(desc.settings.film.width, 8);
    let trs = r#"{ "Camera": { "Type": "Camera", "Position": [0, 1, -3], "fov": 60 } }"#;
    let path = write(&dir.path().join("bom.trs"), format!("\u{feff}{trs}"));
    tracer::format::read_scene(&path).unwrap();
}
