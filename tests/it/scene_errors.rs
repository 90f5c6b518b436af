//! Bad scenes are refused before rendering with one message that names the
//! file and the offending key path (the contract's "Errors" section), and
//! degenerate triangles are dropped and counted, never a crash.

use crate::common::{self, assert_names, load_error, write, write_json};
use serde_json::{json, Value};
use std::path::Path;
use tempfile::TempDir;

/// A small valid scene: a sphere, an emissive quad and a point light.
fn base_scene() -> Value {
    json!({
        "format": 1,
        "name": "tiny",
        "camera": { "position": [0, 0, -5], "look_at": [0, 0, 0], "fov": 40 },
        "film": { "width": 8, "height": 8 },
        "render": { "spp": 1 },
        "materials": {
            "white": { "type": "diffuse", "albedo": [0.8, 0.8, 0.8] }
        },
        "objects": [
            { "type": "sphere", "radius": 1, "subdivisions": 1, "material": "white" },
            {
                "type": "quad",
                "material": "white",
                "emission": [1, 1, 1],
                "transform": { "translate": [0, 3, 0] }
            }
        ],
        "lights": [
            { "type": "point", "position": [0, 5, 0], "intensity": [10, 10, 10] }
        ]
    })
}

/// Writes `scene` as `name` into a fresh folder, loads it and checks that the
/// error names the file and every one of `parts`. Returns the message.
fn refused(scene: &Value, name: &str, parts: &[&str]) -> String {
    let dir = TempDir::new().unwrap();
    let path = write_json(dir.path(), name, scene);
    common::refused(&path, parts)
}

#[test]
fn the_base_scene_loads() {
    let dir = TempDir::new().unwrap();
    let path = write_json(dir.path(), "base.json", &base_scene());
    let (scene, settings) = tracer::scene::load(&path).expect("the base scene is valid");
    assert_eq!(settings.film.width, 8);
    assert_eq!(scene.report.degenerate_triangles_dropped, 0);
    // 80 sphere triangles (icosphere level 1), 2 quad triangles.
    assert_eq!(scene.triangles.len(), 82);
    // Two emissive quad triangles and the point light.
    assert_eq!(scene.lights.len(), 3);
}

#[test]
fn a_missing_scene_file_is_named() {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("absent.json");
    let message = load_error(&path);
    assert_names(&message, &path, &[]);
}

#[test]
fn malformed_json_gives_line_and_column() {
    let dir = TempDir::new().unwrap();
    // A missing comma after the camera block: the error is on line 4.
    let text = "{\n  \"camera\": { \"position\": [0, 0, -5], \"look_at\": [0, 0, 0] }\n\n  \"film\": { \"width\": 8 }\n}\n";
    let path = write(&dir.path().join("syntax.json"), text);
    let message = load_error(&path);
    assert_names(&message, &path, &["line 4", "column 3"]);

    // A file cut short: the end of input is reported with its position.
    let path = write(&dir.path().join("truncated.json"), "{\n  \"camera\": {\n");
    let message = load_error(&path);
    assert_names(&message, &path, &["line ", "column "]);

    // Trailing garbage after the scene object.
    let mut text = serde_json::to_string_pretty(&base_scene()).unwrap();
    let lines = text.lines().count();
    text.push_str("\n]");
    let path = write(&dir.path().join("trailing.json"), &text);
    let message = load_error(&path);
    assert_names(
        &message,
        &path,
        &[&format!("line {}", lines + 1), "column 1"],
    );
}

#[test]
fn a_missing_required_key_is_named() {
    let mut scene = base_scene();
    scene["camera"].as_object_mut().unwrap().remove("position");
    refused(
        &scene,
        "no-position.json",
        &["camera", "position", "missing"],
    );

    let mut scene = base_scene();
    scene.as_object_mut().unwrap().remove("camera");
    refused(&scene, "no-camera.json", &["camera", "missing"]);

    let mut scene = base_scene();
    scene["objects"][1].as_object_mut().unwrap().remove("type");
    refused(&scene, "no-type.json", &["objects[1].type", "missing"]);

    let mut scene = base_scene();
    scene["lights"][0]
        .as_object_mut()
        .unwrap()
        .remove("intensity");
    refused(&scene, "no-intensity.json", &["lights[0]", "intensity"]);

    let mut scene = base_scene();
    scene["objects"][0] = json!({ "type": "mesh" });
    refused(&scene, "no-file.json", &["objects[0]", "file"]);
}

#[test]
fn a_wrong_type_is_named() {
    let mut scene = base_scene();
    scene["film"]["width"] = json!("512");
    refused(&scene, "width-string.json", &["film.width", "string"]);

    let mut scene = base_scene();
    scene["objects"][0]["material"] = json!(3);
    refused(&scene, "material-number.json", &["objects[0].material"]);

    let mut scene = base_scene();
    scene["camera"]["position"] = json!([0, 0]);
    refused(&scene, "short-vector.json", &["camera.position"]);

    let mut scene = base_scene();
    scene["objects"] = json!({ "type": "cube" });
    refused(&scene, "objects-map.json", &["objects"]);

    let mut scene = base_scene();
    scene["materials"]["white"]["albedo"] = json!("white");
    refused(&scene, "albedo-string.json", &["materials.white.albedo"]);
}

/// JSON cannot write NaN or infinity; a literal that overflows an f64 is the
/// closest a file can come, and it must be reported at its key.
#[test]
fn an_overflowing_number_is_named_by_key() {
    let dir = TempDir::new().unwrap();
    let text = serde_json::to_string_pretty(&base_scene()).unwrap();

    let fov = text.replace("\"fov\": 40", "\"fov\": 1e999");
    assert_ne!(fov, text);
    let path = write(&dir.path().join("fov-inf.json"), fov);
    assert_names(&load_error(&path), &path, &["camera.fov"]);

    let radius = text.replace("\"radius\": 1,", "\"radius\": 1e999,");
    assert_ne!(radius, text);
    let path = write(&dir.path().join("radius-inf.json"), radius);
    assert_names(&load_error(&path), &path, &["objects[0].radius"]);
}

/// A number that is finite as an f64 but not as an f32 is refused at its key.
#[test]
fn a_number_too_large_for_f32_is_named() {
    let mut scene = base_scene();
    scene["camera"]["fov"] = json!(1e300);
    refused(&scene, "fov-huge.json", &["camera.fov", "finite"]);

    let mut scene = base_scene();
    scene["lights"][0]["position"] = json!([0.0, 1e39, 0.0]);
    refused(&scene, "light-huge.json", &["lights[0].position", "finite"]);

    let mut scene = base_scene();
    scene["objects"][1]["transform"]["translate"] = json!([-1e300, 0, 0]);
    refused(&scene, "translate-huge.json", &["objects[1].transform"]);
}

#[test]
fn a_zero_or_negative_size_is_named() {
    let mut scene = base_scene();
    scene["film"]["width"] = json!(0);
    refused(
        &scene,
        "width-zero.json",
        &["film.width", "greater than zero"],
    );

    let mut scene = base_scene();
    scene["film"]["height"] = json!(-8);
    refused(&scene, "height-negative.json", &["film.height"]);

    let mut scene = base_scene();
    scene["objects"][0]["radius"] = json!(-1);
    refused(
        &scene,
        "radius-negative.json",
        &["objects[0].radius", "greater than zero"],
    );

    let mut scene = base_scene();
    scene["objects"][0]["radius"] = json!(0.0);
    refused(&scene, "radius-zero.json", &["objects[0].radius"]);

    let mut scene = base_scene();
    scene["camera"]["fov"] = json!(0);
    refused(&scene, "fov-zero.json", &["camera.fov"]);

    let mut scene = base_scene();
    scene["render"]["spp"] = json!(0);
    refused(&scene, "spp-zero.json", &["render.spp"]);

    let mut scene = base_scene();
    scene["objects"][1]["transform"]["scale"] = json!([1, 0, 1]);
    refused(&scene, "scale-zero.json", &["objects[1].transform.scale"]);
}

#[test]
fn an_unknown_material_name_is_named() {
    let mut scene = base_scene();
    scene["objects"][1]["material"] = json!("chrome");
    refused(
        &scene,
        "unknown-material.json",
        &["objects[1].material", "chrome"],
    );
}

#[test]
fn a_missing_mesh_file_is_named() {
    let mut scene = base_scene();
    scene["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "type": "mesh", "file": "meshes/nope.obj" }));
    refused(
        &scene,
        "missing-mesh.json",
        &["objects[2].file", "nope.obj"],
    );
}

#[test]
fn an_unreadable_mesh_file_is_named() {
    let dir = TempDir::new().unwrap();
    // A face that refers to vertices the file does not have.
    write(
        &dir.path().join("bad-index.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
    );
    let mut scene = base_scene();
    scene["objects"][0] = json!({ "type": "mesh", "file": "bad-index.obj" });
    let path = write_json(dir.path(), "bad-index.json", &scene);
    assert_names(
        &load_error(&path),
        &path,
        &["objects[0].file", "bad-index.obj"],
    );

    // A folder where a mesh file should be.
    std::fs::create_dir(dir.path().join("folder.obj")).unwrap();
    scene["objects"][0] = json!({ "type": "mesh", "file": "folder.obj" });
    let path = write_json(dir.path(), "folder.json", &scene);
    assert_names(
        &load_error(&path),
        &path,
        &["objects[0].file", "folder.obj"],
    );
}

/// Bytes that are not an OBJ at all: refused with the key named, or read as an
/// empty mesh; never a panic.
#[test]
fn a_garbage_mesh_file_does_not_panic() {
    let dir = TempDir::new().unwrap();
    let garbage: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    write(&dir.path().join("garbage.obj"), &garbage);
    let mut scene = base_scene();
    scene["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "type": "mesh", "file": "garbage.obj" }));
    let path = write_json(dir.path(), "garbage.json", &scene);
    let result =
        std::panic::catch_unwind(|| tracer::scene::load(&path).map(|(s, _)| s.triangles.len()));
    match result.expect("loading a garbage mesh panicked") {
        Ok(triangles) => assert!(triangles >= 82),
        Err(e) => assert_names(&e.to_string(), &path, &["objects[2].file", "garbage.obj"]),
    }
}

#[test]
fn a_texture_that_fails_to_decode_is_named() {
    let dir = TempDir::new().unwrap();
    write(
        &dir.path().join("broken.png"),
        b"this is not a PNG image\x00\x01\x02\xff",
    );
    let mut scene = base_scene();
    scene["materials"]["painted"] =
        json!({ "type": "diffuse", "albedo": { "texture": "broken.png" } });
    scene["objects"][0]["material"] = json!("painted");
    let path = write_json(dir.path(), "broken-texture.json", &scene);
    assert_names(
        &load_error(&path),
        &path,
        &["materials.painted", "broken.png"],
    );

    // A PNG signature followed by garbage fails in the decoder, not the sniffer.
    let mut fake = b"\x89PNG\r\n\x1a\n".to_vec();
    fake.extend_from_slice(&[0xAB; 64]);
    write(&dir.path().join("truncated.png"), &fake);
    scene["materials"]["painted"]["albedo"]["texture"] = json!("truncated.png");
    let path = write_json(dir.path(), "truncated-texture.json", &scene);
    assert_names(
        &load_error(&path),
        &path,
        &["materials.painted", "truncated.png"],
    );

    // A texture file that does not exist.
    scene["materials"]["painted"]["albedo"]["texture"] = json!("tex/absent.png");
    let path = write_json(dir.path(), "absent-texture.json", &scene);
    assert_names(
        &load_error(&path),
        &path,
        &["materials.painted", "absent.png"],
    );
}

#[test]
fn an_unknown_key_is_named_with_its_path() {
    // The contract's own example.
    let mut scene = base_scene();
    let objects = scene["objects"].as_array_mut().unwrap();
    objects.push(json!({ "type": "cube", "material": "white" }));
    objects.push(json!({ "type": "cube", "materail": "white" }));
    refused(&scene, "typo.json", &["objects[3].materail", "unknown key"]);

    let mut scene = base_scene();
    scene["objects"][0]["materail"] = json!("white");
    refused(&scene, "typo-sphere.json", &["objects[0].materail"]);

    let mut scene = base_scene();
    scene["camera"]["fvo"] = json!(50);
    refused(&scene, "typo-camera.json", &["camera.fvo"]);

    let mut scene = base_scene();
    scene["lights"][0]["colour"] = json!([1, 1, 1]);
    refused(&scene, "typo-light.json", &["lights[0].colour"]);

    let mut scene = base_scene();
    scene["materials"]["white"]["albdo"] = json!([1, 1, 1]);
    refused(&scene, "typo-material.json", &["materials.white.albdo"]);

    let mut scene = base_scene();
    scene["objects"][1]["transform"]["rotation"] = json!([0, 1, 0, 90]);
    refused(
        &scene,
        "typo-transform.json",
        &["objects[1].transform.rotation"],
    );

    let mut scene = base_scene();
    scene["lamps"] = json!([]);
    refused(&scene, "typo-top.json", &["lamps"]);
}

#[test]
fn an_unknown_type_is_named() {
    let mut scene = base_scene();
    scene["objects"][0]["type"] = json!("cylinder");
    refused(&scene, "cylinder.json", &["objects[0].type", "cylinder"]);

    let mut scene = base_scene();
    scene["materials"]["white"]["type"] = json!("vinyl");
    refused(
        &scene,
        "vinyl.json",
        &["materials.white.type", "vinyl", "plastic"],
    );

    let mut scene = base_scene();
    scene["lights"][0]["type"] = json!("sky");
    refused(
        &scene,
        "sky.json",
        &["lights[0].type", "sky", "environment"],
    );

    let mut scene = base_scene();
    scene["lights"][0]["type"] = json!("area");
    refused(&scene, "area.json", &["lights[0].type", "area"]);

    let mut scene = base_scene();
    scene["camera"]["type"] = json!("orthographic");
    refused(&scene, "ortho.json", &["camera.type", "orthographic"]);

    let mut scene = base_scene();
    scene["render"]["integrator"] = json!("mlt");
    refused(&scene, "mlt.json", &["render.integrator", "mlt"]);

    let mut scene = base_scene();
    scene["film"]["tonemap"] = json!("reinhard");
    refused(&scene, "reinhard.json", &["film.tonemap", "reinhard"]);
}

/// Format 2's microfacet materials and thin lens: read in either version,
/// each bad value named by its key.
#[test]
fn version_two_keys_are_read_and_checked() {
    let mut scene = base_scene();
    scene["format"] = json!(2);
    scene["camera"]["aperture_radius"] = json!(0.1);
    scene["camera"]["focus_distance"] = json!(3.0);
    scene["materials"]["metal"] =
        json!({"type": "conductor", "alpha": 0.2, "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2]});
    scene["materials"]["frosted"] = json!({"type": "rough_dielectric", "alpha": 0.3});
    scene["materials"]["chrome"] = json!({"type": "conductor"});
    scene["materials"]["coated"] =
        json!({"type": "plastic", "albedo": [0.1, 0.2, 0.7], "alpha": 0.2});
    scene["materials"]["gloss"] = json!({"type": "plastic", "alpha": 0});
    let dir = tempfile::tempdir().unwrap();
    let path = common::write_json(dir.path(), "v2.json", &scene);
    tracer::scene::load(&path).unwrap();

    let mut bad = scene.clone();
    bad["format"] = json!(3);
    refused(&bad, "v3.json", &["format", "versions 1 and 2"]);
    let mut bad = scene.clone();
    bad["camera"]["aperture_radius"] = json!(-0.1);
    refused(
        &bad,
        "aperture.json",
        &["camera.aperture_radius", "zero or greater"],
    );
    let mut bad = scene.clone();
    bad["camera"]["focus_distance"] = json!(0);
    refused(
        &bad,
        "focus.json",
        &["camera.focus_distance", "greater than zero"],
    );
    let mut bad = scene.clone();
    bad["materials"]["metal"]["alpha"] = json!(-1);
    refused(
        &bad,
        "alpha.json",
        &["materials.metal.alpha", "zero or greater"],
    );
    let mut bad = scene.clone();
    bad["materials"]["metal"]
        .as_object_mut()
        .unwrap()
        .remove("k");
    refused(&bad, "no-k.json", &["materials.metal.k", "both"]);
    let mut bad = scene.clone();
    bad["materials"]["metal"]["eta"] = json!([0.2, -0.9, 1.1]);
    refused(&bad, "eta.json", &["materials.metal.eta", "negative"]);
    let mut bad = scene.clone();
    bad["materials"]["frosted"]["roughness"] = json!(0.3);
    refused(
        &bad,
        "roughness.json",
        &["materials.frosted.roughness", "unknown key"],
    );
    let mut bad = scene.clone();
    bad["materials"]["coated"]["albedo"] = json!([0.1, 1.2, 0.7]);
    refused(&bad, "albedo.json", &["materials.coated.albedo"]);
    let mut bad = scene.clone();
    bad["materials"]["coated"]["albedo"] = json!({"texture": "missing.png"});
    refused(
        &bad,
        "texture.json",
        &["materials.coated.albedo", "missing.png"],
    );
    let mut bad = scene.clone();
    bad["materials"]["gloss"]["roughness"] = json!(0.1);
    refused(
        &bad,
        "gloss.json",
        &["materials.gloss.roughness", "unknown key"],
    );
    let mut bad = scene;
    bad["materials"]["frosted"]["ior"] = json!(0);
    refused(
        &bad,
        "ior.json",
        &["materials.frosted.ior", "greater than zero"],
    );
}

/// The environment light: a constant sky or an image, one per scene,
/// turned but never moved or scaled; its image must load.
#[test]
fn environment_keys_are_read_and_checked() {
    let dir = tempfile::tempdir().unwrap();
    let sky = dir.path().join("sky.png");
    image::RgbImage::from_fn(8, 4, |x, y| image::Rgb([30 * x as u8, 60 * y as u8, 200]))
        .save(&sky)
        .unwrap();
    let mut scene = base_scene();
    scene["format"] = json!(2);
    scene["lights"][0] = json!({"type": "environment", "file": "sky.png", "scale": 2,
                                "transform": {"rotate": [0, 1, 0, 30]}});
    let path = common::write_json(dir.path(), "env.json", &scene);
    let (loaded, _) = tracer::scene::load(&path).unwrap();
    assert!(loaded.environment().is_some());

    let mut constant = scene.clone();
    constant["lights"][0] = json!({"type": "environment", "radiance": [0.5, 0.6, 0.7]});
    let path = common::write_json(dir.path(), "constant.json", &constant);
    tracer::scene::load(&path).unwrap();

    let refused_here = |scene: &Value, name: &str, parts: &[&str]| {
        let path = common::write_json(dir.path(), name, scene);
        common::refused(&path, parts)
    };
    let mut bad = scene.clone();
    bad["lights"][0]["radiance"] = json!([1, 1, 1]);
    refused_here(&bad, "both.json", &["lights[0]", "not both"]);
    let mut bad = scene.clone();
    bad["lights"][0] = json!({"type": "environment"});
    refused_here(&bad, "neither.json", &["lights[0]", "radiance, file"]);
    let mut bad = scene.clone();
    bad["lights"][0]["file"] = json!("missing.exr");
    refused_here(&bad, "missing.json", &["lights[0].file", "missing.exr"]);
    write(&dir.path().join("garbage.png"), "not a png");
    let mut bad = scene.clone();
    bad["lights"][0]["file"] = json!("garbage.png");
    refused_here(&bad, "garbage.json", &["lights[0].file", "garbage.png"]);
    let mut bad = scene.clone();
    bad["lights"][0]["scale"] = json!(-1);
    refused_here(&bad, "scale.json", &["lights[0].scale", "zero or greater"]);
    for (name, transform) in [
        ("moved.json", json!({"translate": [0, 1, 0]})),
        ("scaled.json", json!({"scale": 2})),
        ("mirrored.json", json!({"scale": [1, 1, -1]})),
    ] {
        let mut bad = scene.clone();
        bad["lights"][0]["transform"] = transform;
        refused_here(&bad, name, &["lights[0].transform", "rotation only"]);
    }
    let mut bad = scene.clone();
    bad["lights"]
        .as_array_mut()
        .unwrap()
        .push(json!({"type": "environment", "radiance": [1, 1, 1]}));
    refused_here(
        &bad,
        "two.json",
        &["lights[1]", "at most one environment", "lights[0]"],
    );
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let mut scene = base_scene();
    scene["objects"] = json!([
        {
            "type": "triangles",
            "positions": [
                [0, 0, 0], [1, 0, 0], [0, 1, 0],
                [0, 0, 0], [1, 1, 1], [2, 2, 2],
                [3, 3, 3], [3, 3, 3], [3, 3, 3],
                [0, 0, 1], [1, 0, 1], [0, 1, 1]
            ],
            "material": "white"
        },
        {
            "type": "triangles",
            "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]],
            "indices": [0, 1, 2, 0, 0, 1, 3, 3, 3]
        }
    ]);
    let dir = TempDir::new().unwrap();
    let path = write_json(dir.path(), "degenerate.json", &scene);
    let (scene, _) = tracer::scene::load(&path).expect("degenerate triangles are not an error");
    assert_eq!(scene.report.degenerate_triangles_dropped, 4);
    assert_eq!(scene.triangles.len(), 3);
    assert_eq!(scene.shading.len(), 3);
    assert!(scene.triangles.iter().all(|t| t.area() > 0.0));

    // A scale that flattens a cube in one axis is refused (singular), but a
    // mesh that is entirely degenerate loads as nothing and still renders.
    let mut scene = base_scene();
    scene["objects"] = json!([
        {
            "type": "triangles",
            "positions": [[0, 0, 0], [1, 1, 1], [2, 2, 2]],
            "emission": [5, 5, 5]
        }
    ]);
    let path = write_json(dir.path(), "all-degenerate.json", &scene);
    let (scene, mut settings) =
        tracer::scene::load(&path).expect("degenerate triangles are not an error");
    assert_eq!(scene.report.degenerate_triangles_dropped, 1);
    assert!(scene.triangles.is_empty());
    // The dropped emitter does not become a light: only the point light is left.
    assert_eq!(scene.lights.len(), 1);
    settings.film.width = 4;
    settings.film.height = 4;
    let (image, _) = tracer::render::render(&scene, &settings, &Default::default()).unwrap();
    assert!(image.pixels.iter().all(|p| p.is_finite()));
}

#[test]
fn degenerate_triangles_in_a_mesh_file_are_counted() {
    let dir = TempDir::new().unwrap();
    write(
        &dir.path().join("flat.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 3 3 3\n",
    );
    let mut scene = base_scene();
    scene["objects"] = json!([{ "type": "mesh", "file": "flat.obj" }]);
    let path = write_json(dir.path(), "flat.json", &scene);
    let (scene, _) = tracer::scene::load(&path).expect("degenerate triangles are not an error");
    assert_eq!(scene.triangles.len(), 1);
    assert_eq!(scene.report.degenerate_triangles_dropped, 2);
}

/// Runs the built binary with `args` and returns (success, stdout, stderr).
fn run_cli(args: &[&std::ffi::OsStr]) -> (bool, String, String) {
    let out = common::tracer()
        .args(args)
        .output()
        .expect("the tracer binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn assert_cli_refuses(args: &[&std::ffi::OsStr], file: &Path, parts: &[&str]) {
    let (ok, stdout, stderr) = run_cli(args);
    assert!(!ok, "tracer {args:?} succeeded; stderr: {stderr}");
    assert!(
        !stderr.contains("panicked") && !stdout.contains("panicked"),
        "tracer {args:?} panicked: {stderr}"
    );
    let line = stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no line starting with `error:` in stderr: {stderr}"));
    assert_names(line, file, parts);
}

#[test]
fn the_cli_reports_a_bad_scene_without_panicking() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("out.png");

    let mut scene = base_scene();
    scene["objects"][1]["material"] = json!("chrome");
    let path = write_json(dir.path(), "bad-material.json", &scene);
    let args = [
        "render".as_ref(),
        path.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "-q".as_ref(),
    ];
    assert_cli_refuses(&args, &path, &["objects[1].material"]);
    assert!(!out.exists(), "a refused scene must not write an image");

    assert_cli_refuses(
        &["info".as_ref(), path.as_os_str()],
        &path,
        &["objects[1].material"],
    );

    let path = write(&dir.path().join("syntax.json"), "{\n  \"camera\": [\n");
    assert_cli_refuses(
        &["render".as_ref(), path.as_os_str(), "-q".as_ref()],
        &path,
        &["line ", "column "],
    );

    let path = dir.path().join("nowhere.json");
    assert_cli_refuses(
        &["render".as_ref(), path.as_os_str(), "-q".as_ref()],
        &path,
        &[],
    );

    let mut scene = base_scene();
    scene["film"]["width"] = json!(0);
    let path = write_json(dir.path(), "zero-width.json", &scene);
    assert_cli_refuses(
        &["render".as_ref(), path.as_os_str(), "-q".as_ref()],
        &path,
        &["film.width"],
    );
}
