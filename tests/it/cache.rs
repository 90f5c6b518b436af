//! The scene cache: a warm load renders the very same image as a cold one;
//! every kind of damaged entry is detected, removed and rebuilt; the key
//! changes with everything that shapes the geometry; concurrent writers
//! leave a whole entry; an unwritable folder only costs the cache.

use crate::common::{self, output_text};
use std::path::{Path, PathBuf};
use tracer::bvh::BuildOptions;
use tracer::format::read_scene;
use tracer::render::{render, RenderOptions};
use tracer::scene::cache::{scene_key, Cache, CacheUse};
use tracer::scene::{self, Scene};

/// A bumpy grid of `n × n` quads with normals and UVs, in two MTL
/// materials, one of them emissive, so every shading field is exercised.
fn write_mesh(dir: &Path, n: usize) -> PathBuf {
    let mut obj = String::from("mtllib grid.mtl\n");
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            let h = 0.05 * (13.0 * u).sin() * (7.0 * v).cos();
            obj += &format!(
                "v {} {h} {}\nvn {} 1 {}\nvt {u} {v}\n",
                u - 0.5,
                v - 0.5,
                -h,
                h
            );
        }
    }
    let index = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        if j == n / 2 {
            obj += "usemtl glow\n";
        } else if j == 0 || j == n / 2 + 1 {
            obj += "usemtl clay\n";
        }
        for i in 0..n {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            obj += &format!(
                "f {a}/{a}/{a} {c}/{c}/{c} {b}/{b}/{b}\nf {a}/{a}/{a} {d}/{d}/{d} {c}/{c}/{c}\n"
            );
        }
    }
    std::fs::write(dir.join("grid.obj"), obj).unwrap();
    std::fs::write(
        dir.join("grid.mtl"),
        "newmtl clay\nKd 0.7 0.5 0.3\nnewmtl glow\nKd 0.2 0.2 0.2\nKe 4 3 2\n",
    )
    .unwrap();
    let scene = r#"{
      "format": 1,
      "camera": {"position": [0, 1.2, -1.2], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 45},
      "film": {"width": 24, "height": 24},
      "render": {"spp": 2, "seed": 5},
      "objects": [
        {"type": "mesh", "file": "grid.obj", "transform": {"rotate": [0, 1, 0, 20]}},
        {"type": "quad", "emission": [2, 2, 2], "transform": {"translate": [0, 2, 0], "rotate": [1, 0, 0, 90]}}
      ]
    }"#;
    let path = dir.join("scene.json");
    std::fs::write(&path, scene).unwrap();
    path
}

fn cache_in(dir: &Path) -> Cache {
    Cache::new(dir.join("cache")).with_min_triangles(0)
}

fn load(scene: &Path, cache: &Cache) -> Scene {
    scene::build(&read_scene(scene).unwrap(), Some(cache)).unwrap()
}

/// The scene built without the cache.
fn uncached(scene: &Path) -> Scene {
    common::load_scene(scene).0
}

/// The scene rendered with the settings of its file.
fn image(scene: &Scene) -> tracer::film::Image {
    let settings = read_scene(&scene.file).unwrap().settings;
    let options = RenderOptions {
        threads: Some(2),
        progress: false,
        ..RenderOptions::default()
    };
    render(scene, &settings, &options).unwrap().0
}

fn the_entry(cache: &Cache) -> PathBuf {
    let entries = cache.list().unwrap();
    assert_eq!(entries.len(), 1, "{entries:?}");
    entries[0].path.clone()
}

fn assert_same_geometry(a: &Scene, b: &Scene) {
    assert_eq!(&a.triangles[..], &b.triangles[..]);
    assert_eq!(&a.shading[..], &b.shading[..]);
    assert_eq!(a.material_names, b.material_names);
    assert_eq!(a.lights.len(), b.lights.len());
    assert_eq!(a.bvh.root(), b.bvh.root());
    let bytes = |s: &Scene| {
        let nodes: &[u8] = bytemuck::cast_slice(s.bvh.nodes());
        let blocks: &[u8] = bytemuck::cast_slice(s.bvh.blocks());
        [nodes, blocks].concat()
    };
    assert!(bytes(a) == bytes(b), "BVHs differ");
}

#[test]
fn a_warm_load_renders_the_same_image_as_a_cold_one() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 40);
    let cache = cache_in(dir.path());

    let uncached = uncached(&scene_path);
    let cold = load(&scene_path, &cache);
    assert_eq!(cold.report.cache, CacheUse::Stored);
    let warm = load(&scene_path, &cache);
    assert_eq!(warm.report.cache, CacheUse::Hit);
    assert!(warm.triangles.is_mapped() && warm.shading.is_mapped());
    assert!(warm.lights.len() > 1, "the MTL emitter became area lights");

    assert_same_geometry(&uncached, &cold);
    assert_same_geometry(&cold, &warm);
    let (a, b) = (image(&cold), image(&warm));
    assert!(a.mean().x > 0.0);
    assert!(a == b, "warm and cold images differ");
    assert!(image(&uncached) == a);
}

/// Damage done to an entry; each must be detected, reported in one
/// warning, removed, and rebuilt into a sound entry.
/// A description of the damage, and what does it to the entry's file.
type Damage = (String, Box<dyn Fn(&Path)>);

fn damage_cases(len: usize) -> Vec<Damage> {
    let mut cases: Vec<Damage> = Vec::new();
    let mut state = 0x1234_5678u64;
    let mut random = move |n: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as usize) % n
    };
    for _ in 0..6 {
        let at = random(len);
        cases.push((
            format!("truncated to {at} bytes"),
            Box::new(move |p| {
                let f = std::fs::OpenOptions::new().write(true).open(p).unwrap();
                f.set_len(at as u64).unwrap();
            }),
        ));
    }
    // The header, the table, then anywhere.
    let mut flips = vec![3, 20, 50, 60, 90, 100, 120];
    flips.extend((0..8).map(|_| random(len)));
    for at in flips {
        let bit = 1u8 << random(8);
        cases.push((
            format!("bit flipped at byte {at}"),
            Box::new(move |p| {
                let mut bytes = std::fs::read(p).unwrap();
                bytes[at] ^= bit;
                std::fs::write(p, bytes).unwrap();
            }),
        ));
    }
    cases.push((
        "an older format version".into(),
        Box::new(|p| {
            let mut bytes = std::fs::read(p).unwrap();
            bytes[8..12].copy_from_slice(&0u32.to_le_bytes());
            std::fs::write(p, bytes).unwrap();
        }),
    ));
    cases.push((
        "longer than its header says".into(),
        Box::new(|p| {
            let mut bytes = std::fs::read(p).unwrap();
            bytes.extend_from_slice(&[0; 64]);
            std::fs::write(p, bytes).unwrap();
        }),
    ));
    cases.push((
        "an empty file".into(),
        Box::new(|p| std::fs::write(p, b"").unwrap()),
    ));
    cases.push((
        "a foreign file".into(),
        Box::new(|p| std::fs::write(p, "not a cache entry at all, just text").unwrap()),
    ));
    cases.push((
        "a directory".into(),
        Box::new(|p| {
            std::fs::remove_file(p).unwrap();
            std::fs::create_dir_all(p.join("inside")).unwrap();
        }),
    ));
    cases
}

#[test]
fn every_kind_of_damaged_entry_is_detected_and_rebuilt() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 12);
    let cache = cache_in(dir.path());
    let cold = load(&scene_path, &cache);
    let reference = image(&cold);
    let entry = the_entry(&cache);
    let pristine = std::fs::read(&entry).unwrap();

    for (what, damage) in damage_cases(pristine.len()) {
        damage(&entry);
        let scene = load(&scene_path, &cache);
        assert_ne!(
            scene.report.cache,
            CacheUse::Hit,
            "{what}: trusted a damaged entry"
        );
        let warnings: Vec<_> = scene
            .report
            .warnings
            .iter()
            .filter(|w| w.contains("cache entry"))
            .collect();
        assert_eq!(warnings.len(), 1, "{what}: {:?}", scene.report.warnings);
        assert!(warnings[0].contains("invalid"), "{what}: {}", warnings[0]);
        assert_eq!(scene.report.cache, CacheUse::Stored, "{what}: not rebuilt");
        assert!(image(&scene) == reference, "{what}: a different image");
        assert!(
            std::fs::read(&entry).unwrap() == pristine,
            "{what}: rebuilt differently"
        );
        let warm = load(&scene_path, &cache);
        assert_eq!(
            warm.report.cache,
            CacheUse::Hit,
            "{what}: the rebuilt entry is not used"
        );
    }
}

#[test]
fn an_entry_under_another_key_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_mesh(dir.path(), 10);
    let cache = cache_in(dir.path());
    load(&a, &cache);
    let entry_a = the_entry(&cache);
    // The same mesh, moved: another key. Put A's entry where B's belongs.
    let text = std::fs::read_to_string(&a)
        .unwrap()
        .replace("[0, 1, 0, 20]", "[0, 1, 0, 25]");
    let b = dir.path().join("b.json");
    std::fs::write(&b, text).unwrap();
    let key_b = scene_key(&read_scene(&b).unwrap(), &BuildOptions::default()).unwrap();
    std::fs::copy(&entry_a, cache.entry_path(&key_b)).unwrap();
    let scene_b = load(&b, &cache);
    assert_eq!(scene_b.report.cache, CacheUse::Stored);
    assert!(
        scene_b.report.warnings.iter().any(|w| w.contains("key")),
        "{:?}",
        scene_b.report.warnings
    );
    assert_eq!(scene_b.triangles.len(), uncached(&b).triangles.len());
    assert_same_geometry(&scene_b, &uncached(&b));
}

#[test]
fn the_key_changes_with_everything_that_shapes_the_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 6);
    let key = || {
        let desc = read_scene(&scene_path).unwrap();
        scene_key(&desc, &BuildOptions::default()).unwrap()
    };
    let original = key();
    assert_eq!(original, key(), "the key is deterministic");

    let mut keys = vec![original];
    let changed = |what: &str, keys: &mut Vec<_>| {
        let k = key();
        assert!(!keys.contains(&k), "{what} did not change the key");
        keys.push(k);
    };
    // One byte of the mesh.
    let obj = dir.path().join("grid.obj");
    let text = std::fs::read_to_string(&obj).unwrap();
    std::fs::write(&obj, text.replacen("vt 0 0", "vt 0 1", 1)).unwrap();
    changed("a mesh byte", &mut keys);
    // One byte of the MTL file the mesh names.
    let mtl = dir.path().join("grid.mtl");
    let text = std::fs::read_to_string(&mtl).unwrap();
    std::fs::write(&mtl, text.replace("Ke 4 3 2", "Ke 4 3 3")).unwrap();
    changed("an MTL byte", &mut keys);
    // A transform.
    let text = std::fs::read_to_string(&scene_path).unwrap();
    std::fs::write(
        &scene_path,
        text.replace("[0, 1, 0, 20]", "[0, 1, 0, 20.5]"),
    )
    .unwrap();
    changed("a transform", &mut keys);
    // Emission on an object.
    let text = std::fs::read_to_string(&scene_path).unwrap();
    std::fs::write(&scene_path, text.replace("[2, 2, 2]", "[2, 2, 3]")).unwrap();
    changed("an emission", &mut keys);
    // A scene material named "default" (it replaces the built-in one).
    let text = std::fs::read_to_string(&scene_path).unwrap();
    let with_default = text.replacen(
        "\"objects\"",
        "\"materials\": {\"default\": {\"type\": \"diffuse\", \"albedo\": [0.2, 0.3, 0.4]}},\n      \"objects\"",
        1,
    );
    std::fs::write(&scene_path, with_default).unwrap();
    changed("a default material", &mut keys);
    // An indented `mtllib` line still names the MTL file (tobj reads it).
    let text = std::fs::read_to_string(&obj).unwrap();
    std::fs::write(
        &obj,
        text.replacen("mtllib grid.mtl", "\t mtllib grid.mtl", 1),
    )
    .unwrap();
    changed("indenting mtllib", &mut keys);
    let text = std::fs::read_to_string(&mtl).unwrap();
    std::fs::write(&mtl, text.replace("Kd 0.7", "Kd 0.6")).unwrap();
    changed("an MTL byte behind an indented mtllib", &mut keys);
    // The MTL file going missing.
    std::fs::remove_file(&mtl).unwrap();
    changed("a missing MTL file", &mut keys);
    // T-racer's material override of a mesh.
    let mut desc = read_scene(&scene_path).unwrap();
    let plain = scene_key(&desc, &BuildOptions::default()).unwrap();
    let tracer::format::desc::ShapeDesc::Mesh { mtl_override, .. } = &mut desc.objects[0].shape
    else {
        panic!("object 0 is the mesh")
    };
    *mtl_override = Some(tracer::format::desc::MaterialOverride::Mirror);
    assert_ne!(scene_key(&desc, &BuildOptions::default()).unwrap(), plain);
    // The BVH build parameters.
    let desc = read_scene(&scene_path).unwrap();
    let other = BuildOptions {
        bins: 8,
        ..BuildOptions::default()
    };
    assert_ne!(
        scene_key(&desc, &other).unwrap(),
        scene_key(&desc, &BuildOptions::default()).unwrap()
    );
    // Settings that do not shape geometry keep the key.
    let before = key();
    let text = std::fs::read_to_string(&scene_path).unwrap();
    std::fs::write(&scene_path, text.replace("\"spp\": 2", "\"spp\": 7")).unwrap();
    assert_eq!(key(), before, "samples per pixel changed the key");
}

#[test]
fn concurrent_writers_leave_one_whole_entry() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 30);
    let reference = uncached(&scene_path);
    let cache_dir = dir.path().join("cache");
    std::thread::scope(|s| {
        for _ in 0..6 {
            s.spawn(|| {
                let cache = Cache::new(&cache_dir).with_min_triangles(0);
                for _ in 0..3 {
                    let scene = load(&scene_path, &cache);
                    assert!(
                        !scene.report.warnings.iter().any(|w| w.contains("cache")),
                        "{:?}",
                        scene.report.warnings
                    );
                    assert_same_geometry(&scene, &reference);
                }
            });
        }
    });
    let cache = cache_in(dir.path());
    the_entry(&cache);
    let leftovers: Vec<_> = std::fs::read_dir(&cache_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    assert_eq!(load(&scene_path, &cache).report.cache, CacheUse::Hit);
}

#[test]
fn concurrent_processes_leave_one_whole_entry() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    // Large enough for the command line's default threshold.
    let scene_path = write_mesh(dir.path(), 80);
    let cache_dir = dir.path().join("cache");
    let children: Vec<_> = (0..4)
        .map(|k| {
            common::tracer()
                .arg("render")
                .arg(&scene_path)
                .args(["-q", "--threads", "1", "--cache-dir"])
                .arg(&cache_dir)
                .arg("-o")
                .arg(dir.path().join(format!("out{k}.pfm")))
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for child in children {
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert!(!stderr.contains("warning"), "{stderr}");
    }
    let images: Vec<_> = (0..4)
        .map(|k| tracer::film::read::read_pfm(&dir.path().join(format!("out{k}.pfm"))).unwrap())
        .collect();
    assert!(images.iter().all(|i| *i == images[0]));
    let cache = Cache::new(&cache_dir);
    the_entry(&cache);
    assert_eq!(load(&scene_path, &cache).report.cache, CacheUse::Hit);
    let leftovers = std::fs::read_dir(&cache_dir).unwrap().count();
    assert_eq!(leftovers, 1, "temporary files left behind");
}

#[test]
fn an_unwritable_cache_folder_degrades_to_no_cache() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 8);
    let blocker = dir.path().join("a-file");
    std::fs::write(&blocker, "in the way").unwrap();
    let cache = Cache::new(blocker.join("cache")).with_min_triangles(0);
    let scene = load(&scene_path, &cache);
    assert_eq!(scene.report.cache, CacheUse::NotStored);
    let warnings: Vec<_> = scene
        .report
        .warnings
        .iter()
        .filter(|w| w.contains("cache"))
        .collect();
    assert_eq!(warnings.len(), 1, "{:?}", scene.report.warnings);
    assert!(image(&scene) == image(&uncached(&scene_path)));
}

#[test]
fn small_scenes_are_not_stored_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 8);
    let cache = Cache::new(dir.path().join("cache"));
    assert_eq!(load(&scene_path, &cache).report.cache, CacheUse::NotStored);
    assert!(cache.list().unwrap().is_empty());
}

/// Runs `tracer` with `args` and `--cache-dir cache_dir`, which must
/// succeed; returns its standard output and error.
fn tracer(args: &[&str], cache_dir: &Path) -> String {
    let out = common::tracer()
        .args(args)
        .arg("--cache-dir")
        .arg(cache_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    output_text(&out)
}

#[test]
fn cache_list_clear_and_prune_from_the_command_line() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let cache_dir = dir.path().join("cache");
    let mut scenes = Vec::new();
    for (k, n) in [(0, 80), (1, 75)] {
        let sub = dir.path().join(format!("s{k}"));
        std::fs::create_dir_all(&sub).unwrap();
        scenes.push(write_mesh(&sub, n));
    }
    let render = |scene: &Path| {
        let out = dir.path().join("out.pfm");
        tracer(
            &[
                "render",
                scene.to_str().unwrap(),
                "-q",
                "-o",
                out.to_str().unwrap(),
            ],
            &cache_dir,
        )
    };
    assert!(render(&scenes[0]).contains("cached"));
    assert!(render(&scenes[0]).contains("from the scene cache"));
    render(&scenes[1]);

    let list = tracer(&["cache", "list"], &cache_dir);
    assert!(list.contains("2 entries"), "{list}");
    assert!(list.contains("/s0/") && list.contains("/s1/"), "{list}");

    // Make s1 the older entry by its clock, whatever the file system's
    // timestamp resolution; then use s0 again, which refreshes its time.
    for e in Cache::new(&cache_dir).list().unwrap() {
        let f = std::fs::File::options().append(true).open(&e.path).unwrap();
        let age = std::time::Duration::from_secs(3600);
        f.set_modified(std::time::SystemTime::now() - age).unwrap();
    }
    render(&scenes[0]);
    let sizes: Vec<u64> = Cache::new(&cache_dir)
        .list()
        .unwrap()
        .iter()
        .map(|e| e.bytes)
        .collect();
    let keep = sizes.iter().max().unwrap().to_string();
    let pruned = tracer(&["cache", "prune", "--max-size", &keep], &cache_dir);
    assert!(pruned.contains("removed 1 entries"), "{pruned}");
    let left = Cache::new(&cache_dir).list().unwrap();
    assert_eq!(left.len(), 1);
    assert!(left[0].scene.as_ref().unwrap().contains("/s0/"), "{left:?}");

    let cleared = tracer(&["cache", "clear"], &cache_dir);
    assert!(cleared.contains("removed 1 files"), "{cleared}");
    assert!(Cache::new(&cache_dir).list().unwrap().is_empty());
}

#[test]
fn sizes_parse_with_binary_units() {
    use tracer::scene::cache::parse_size;
    assert_eq!(parse_size("2G").unwrap(), 2 << 30);
    assert_eq!(parse_size("500M").unwrap(), 500 << 20);
    assert_eq!(parse_size("1.5GiB").unwrap(), 3 << 29);
    assert_eq!(parse_size("4096").unwrap(), 4096);
    assert!(parse_size("lots").is_err());
    assert!(parse_size("3X").is_err());
}

#[test]
fn an_mtllib_line_across_read_chunks_is_still_found() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_mesh(dir.path(), 4);
    let obj = dir.path().join("grid.obj");
    let text = std::fs::read_to_string(&obj).unwrap();
    // Pad with comments so the mtllib line starts 3 bytes before the
    // hasher's 1 MiB chunk boundary.
    let body = text.replacen("mtllib grid.mtl\n", "", 1);
    let pad = (1 << 20) - 3 - 2;
    let padded = format!("#{}\n", "x".repeat(pad - 1)) + "mtllib grid.mtl\n" + &body;
    assert_eq!(padded.find("mtllib"), Some((1 << 20) - 4));
    std::fs::write(&obj, padded).unwrap();
    let key = || scene_key(&read_scene(&scene_path).unwrap(), &BuildOptions::default()).unwrap();
    let before = key();
    let mtl = dir.path().join("grid.mtl");
    let text = std::fs::read_to_string(&mtl).unwrap();
    std::fs::write(&mtl, text.replace("Kd 0.7", "Kd 0.6")).unwrap();
    assert_ne!(
        key(),
        before,
        "the MTL behind a split mtllib line was not hashed"
    );
}
