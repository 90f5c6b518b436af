//! T-racer `.trs` import (the contract's "Compatibility" section): members by
//! `Type`, meshes looked up beside the scene and then in `resources/`,
//! "Mesh Material" overrides, `Display` resolution and output type, and
//! errors that name the member and the key.

use crate::common::{self, load_scene, refused, write, write_json as write_trs};
use serde_json::{json, Value};
use std::path::PathBuf;
use tempfile::TempDir;
use tracer::light::Light;
use tracer::material::{Albedo, Material};
use tracer::scene::Scene;
use tracer::settings::Display;

/// Two quads (four triangles) in two MTL materials.
const FLOOR_OBJ: &str = "mtllib floor.mtl
v -2 0 -2
v -2 0 2
v 2 0 2
v 2 0 -2
v -2 0 2
v -2 3 2
v 2 3 2
v 2 0 2
usemtl red
f 1 2 3 4
usemtl blue
f 5 6 7 8
";
const FLOOR_MTL: &str = "newmtl red
Kd 0.8 0.1 0.1
illum 1

newmtl blue
Kd 0.1 0.2 0.9
illum 1
";
/// A tetrahedron (four triangles) in one MTL material.
const BALL_OBJ: &str = "mtllib ball.mtl
v 0 0.5 0
v 1 0.5 0
v 0 1.5 0
v 0 0.5 1
usemtl shiny
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
";
const BALL_MTL: &str = "newmtl shiny
Kd 0.9 0.8 0.7
Ni 1.0
d 0.0
illum 2
";

fn camera() -> Value {
    json!({ "Type": "Camera", "Position": [0.0, 1.0, -3.0], "fov": 60.0 })
}

/// A scene folder with `floor.obj` beside the scene and `ball.obj` in `resources/`.
fn scene_folder() -> TempDir {
    let dir = TempDir::new().unwrap();
    write(&dir.path().join("floor.obj"), FLOOR_OBJ);
    write(&dir.path().join("floor.mtl"), FLOOR_MTL);
    write(&dir.path().join("resources/ball.obj"), BALL_OBJ);
    write(&dir.path().join("resources/ball.mtl"), BALL_MTL);
    dir
}

fn full_scene() -> Value {
    json!({
        "SceneName": "Imported",
        "Display": { "Name": "Preview", "Type": "PFM", "ResX": 24, "ResY": 16 },
        "Camera": camera(),
        "Lamp": {
            "Type": "Light",
            "LightType": "Point",
            "Position": [0.0, 2.0, 0.0],
            "Intensity": [4.0, 4.0, 4.0]
        },
        "Panel": {
            "Type": "Light",
            "LightType": "Area",
            "Intensity": [5.0, 5.0, 5.0],
            "NumberOfVertices": 6,
            "Vertices": [
                [-0.5, 2.9, -0.5], [0.5, 2.9, -0.5], [0.5, 2.9, 0.5],
                [-0.5, 2.9, -0.5], [0.5, 2.9, 0.5], [-0.5, 2.9, 0.5]
            ]
        },
        "Floor": {
            "Type": "Mesh",
            "MeshName": "floor.obj",
            "Mesh Material": "Diffuse",
            "Colour": [1.0, 1.0, 1.0],
            "Texture": "Null"
        },
        "Ball": {
            "Type": "Mesh",
            "Name": "Mirror ball",
            "MeshName": "ball.obj",
            "Mesh Material": "Mirror"
        }
    })
}

fn approx(a: glam::Vec3, b: [f32; 3]) -> bool {
    (a - glam::Vec3::from(b)).abs().max_element() < 1e-6
}

/// How many triangles use a material that matches `f`.
fn triangles_with(scene: &Scene, f: impl Fn(&Material) -> bool) -> usize {
    scene
        .shading
        .iter()
        .filter(|s| f(&scene.materials[s.material as usize]))
        .count()
}

#[test]
fn a_self_contained_trs_scene_is_imported() {
    let dir = scene_folder();
    let path = write_trs(dir.path(), "imported.trs", &full_scene());
    let (scene, settings) = load_scene(&path);

    assert_eq!(scene.name, "Imported");
    // Floor 4 + ball 4 + area light 2.
    assert_eq!(scene.triangles.len(), 10);
    assert_eq!(scene.report.degenerate_triangles_dropped, 0);

    let area = scene
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Area(_)))
        .count();
    let point = scene
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Point(_)))
        .count();
    assert_eq!((area, point), (2, 1));
    assert_eq!(scene.lights.len(), 3);
    let emissive = scene
        .shading
        .iter()
        .filter(|s| s.light != tracer::scene::NO_LIGHT)
        .count();
    assert_eq!(emissive, 2);

    // Display: resolution and output type.
    assert_eq!((settings.film.width, settings.film.height), (24, 16));
    assert_eq!(settings.display, Some(Display::Pfm));
    let output = &settings.film.output;
    assert_eq!(
        output.extension().and_then(|e| e.to_str()),
        Some("pfm"),
        "output {} should be a PFM",
        output.display()
    );
    assert!(output.starts_with(dir.path()), "{}", output.display());

    // "Mesh Material": "Mirror" makes the MTL's Kd the mirror's reflectance.
    let mirrors: Vec<_> = scene
        .materials
        .iter()
        .filter_map(|m| match m {
            Material::Mirror { reflectance } => Some(*reflectance),
            _ => None,
        })
        .collect();
    assert_eq!(mirrors.len(), 1, "one mirror material: {mirrors:?}");
    assert!(approx(mirrors[0], [0.9, 0.8, 0.7]), "{:?}", mirrors[0]);
    assert_eq!(
        triangles_with(&scene, |m| matches!(m, Material::Mirror { .. })),
        4
    );

    // "Mesh Material": "Diffuse" keeps each MTL material's Kd as the albedo.
    let albedo_triangles = |kd: [f32; 3]| {
        triangles_with(
            &scene,
            |m| matches!(m, Material::Diffuse { albedo: Albedo::Constant(c) } if approx(*c, kd)),
        )
    };
    assert_eq!(albedo_triangles([0.8, 0.1, 0.1]), 2);
    assert_eq!(albedo_triangles([0.1, 0.2, 0.9]), 2);
}

#[test]
fn the_glass_override_keeps_kd_as_transmittance() {
    let dir = scene_folder();
    let mut members = full_scene();
    members["Ball"]["Mesh Material"] = json!("Glass");
    let path = write_trs(dir.path(), "glass.trs", &members);
    let (scene, _) = load_scene(&path);
    let glass: Vec<_> = scene
        .materials
        .iter()
        .filter_map(|m| match m {
            Material::Dielectric { ior, transmittance } => Some((*ior, *transmittance)),
            _ => None,
        })
        .collect();
    assert_eq!(glass.len(), 1, "{glass:?}");
    assert!(glass[0].0 > 1.0, "ior {}", glass[0].0);
    assert!(approx(glass[0].1, [0.9, 0.8, 0.7]), "{:?}", glass[0].1);
    assert!(!scene
        .materials
        .iter()
        .any(|m| matches!(m, Material::Mirror { .. })));
}

#[test]
fn meshes_are_found_beside_the_scene_before_resources() {
    let dir = TempDir::new().unwrap();
    // The same name in both places: one triangle beside, two in resources/.
    let beside = write(
        &dir.path().join("dup.obj"),
        "v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n",
    );
    write(
        &dir.path().join("resources/dup.obj"),
        "v 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\nf 1 2 3\nf 2 4 3\n",
    );
    let members = json!({
        "Camera": camera(),
        "Dup": { "Type": "Mesh", "MeshName": "dup.obj" }
    });
    let path = write_trs(dir.path(), "lookup.trs", &members);
    assert_eq!(
        load_scene(&path).0.triangles.len(),
        1,
        "the file beside the scene"
    );

    std::fs::remove_file(beside).unwrap();
    assert_eq!(
        load_scene(&path).0.triangles.len(),
        2,
        "the file in resources/"
    );
}

#[test]
fn display_types_choose_the_default_output() {
    let dir = TempDir::new().unwrap();
    let mut members = json!({
        "SceneName": "Shot",
        "Camera": camera(),
        "Display": { "Type": "TGA", "ResX": 7, "ResY": 5 }
    });
    let path = write_trs(dir.path(), "tga.trs", &members);
    let (_, settings) = load_scene(&path);
    assert_eq!(settings.display, Some(Display::Tga));
    assert_eq!((settings.film.width, settings.film.height), (7, 5));
    assert!(settings.film.output.ends_with("Shot.tga"));

    members["Display"]["Type"] = json!("Window");
    let path = write_trs(dir.path(), "window.trs", &members);
    let (_, settings) = load_scene(&path);
    assert_eq!(settings.display, Some(Display::Window));
    let ext = settings.film.output.extension().unwrap().to_owned();
    assert!(ext == "exr" || ext == "pfm", "{ext:?}");

    members.as_object_mut().unwrap().remove("Display");
    let path = write_trs(dir.path(), "no-display.trs", &members);
    let (_, settings) = load_scene(&path);
    assert_eq!(settings.display, None);
    assert!(settings.film.output.extension().is_some());
}

/// The real T-racer scenes, where the shared folder is present.
fn shared_resources() -> Option<PathBuf> {
    let dir = common::repo().join("../shared/t-racer/resources");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: {} is absent (the T-racer scenes are not shared here)",
            dir.display()
        );
        None
    }
}

#[test]
fn every_shared_t_racer_scene_loads() {
    let Some(dir) = shared_resources() else {
        return;
    };
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "trs"))
        .collect();
    scenes.sort();
    assert!(!scenes.is_empty(), "no .trs files in {}", dir.display());
    for path in &scenes {
        let (scene, settings) = load_scene(path);
        assert!(!scene.triangles.is_empty(), "{}", path.display());
        assert!(!scene.lights.is_empty(), "{}", path.display());
        assert!(
            scene.lights.iter().any(|l| l.power() > 0.0),
            "{} has no emitting light",
            path.display()
        );
        assert!(settings.film.width > 0 && settings.film.height > 0);
    }
}

#[test]
fn cornell_4_renders_at_tiny_size() {
    let Some(dir) = shared_resources() else {
        return;
    };
    let _guard = common::heavy();
    let path = dir.join("cornell 4.trs");
    let (scene, mut settings) = load_scene(&path);
    assert_eq!((settings.film.width, settings.film.height), (512, 512));
    // The sphere's "Mesh Material": "Mirror".
    assert!(scene
        .materials
        .iter()
        .any(|m| matches!(m, Material::Mirror { .. })));
    // The area light is two triangles.
    assert_eq!(
        scene
            .lights
            .iter()
            .filter(|l| matches!(l, Light::Area(_)))
            .count(),
        2
    );

    settings.film.width = 16;
    settings.film.height = 16;
    settings.stop.spp = 2;
    let (image, stats) = tracer::render::render(&scene, &settings, &Default::default()).unwrap();
    assert_eq!((image.width, image.height), (16, 16));
    assert_eq!(image.pixels.len(), 256);
    assert!(image
        .pixels
        .iter()
        .all(|p| p.is_finite() && p.min_element() >= 0.0));
    assert!(image.mean().max_element() > 0.0, "the image is black");
    let lit = image
        .pixels
        .iter()
        .filter(|p| p.max_element() > 0.0)
        .count();
    assert!(lit > 64, "only {lit} of 256 pixels received light");
    assert_eq!(stats.discarded, 0);
}

#[test]
fn an_unknown_member_type_is_named() {
    let dir = TempDir::new().unwrap();
    let path = write_trs(
        dir.path(),
        "member.trs",
        &json!({ "Camera": camera(), "Ball": { "Type": "Sphere", "Radius": 1.0 } }),
    );
    refused(&path, &["\"Ball\".Type", "Sphere"]);

    let path = write_trs(
        dir.path(),
        "light-type.trs",
        &json!({
            "Camera": camera(),
            "Sun": { "Type": "Light", "LightType": "Spot", "Position": [0, 1, 0] }
        }),
    );
    refused(&path, &["\"Sun\".LightType", "Spot"]);

    let path = write_trs(
        dir.path(),
        "display-type.trs",
        &json!({ "Camera": camera(), "Display": { "Type": "PNG", "ResX": 8, "ResY": 8 } }),
    );
    refused(&path, &["\"Display\".Type", "PNG"]);

    let dir = scene_folder();
    let mut members = full_scene();
    members["Floor"]["Mesh Material"] = json!("Plastic");
    let path = write_trs(dir.path(), "mesh-material.trs", &members);
    refused(&path, &["\"Floor\"", "Mesh Material", "Plastic"]);
}

#[test]
fn an_unknown_key_is_named_with_its_member() {
    let dir = TempDir::new().unwrap();
    let mut cam = camera();
    cam["FOV"] = json!(45.0);
    let path = write_trs(dir.path(), "camera-key.trs", &json!({ "Camera": cam }));
    refused(&path, &["\"Camera\".FOV", "unknown key"]);

    let path = write_trs(
        dir.path(),
        "light-key.trs",
        &json!({
            "Camera": camera(),
            "Lamp": {
                "Type": "Light",
                "LightType": "Point",
                "Position": [0, 1, 0],
                "Intensity": [1, 1, 1],
                "Radius": 0.1
            }
        }),
    );
    refused(&path, &["\"Lamp\".Radius", "unknown key"]);

    let dir = scene_folder();
    let mut members = full_scene();
    members["Floor"]["Mesh Colour"] = json!([1, 0, 0]);
    let path = write_trs(dir.path(), "mesh-key.trs", &members);
    refused(&path, &["\"Floor\"", "Mesh Colour", "unknown key"]);
}

#[test]
fn a_missing_mesh_file_is_named_with_its_member() {
    let dir = scene_folder();
    let mut members = full_scene();
    members["Ball"]["MeshName"] = json!("nowhere.obj");
    let path = write_trs(dir.path(), "missing-mesh.trs", &members);
    refused(&path, &["\"Ball\".MeshName", "nowhere.obj"]);

    // Found, but not a mesh that can be read.
    write(
        &dir.path().join("resources/broken.obj"),
        "v 0 0 0\nf 1 2 3\n",
    );
    members["Ball"]["MeshName"] = json!("broken.obj");
    let path = write_trs(dir.path(), "broken-mesh.trs", &members);
    refused(&path, &["\"Ball\".MeshName", "broken.obj"]);
}

#[test]
fn other_bad_members_are_named() {
    let dir = TempDir::new().unwrap();
    let check = |name: &str, members: Value, parts: &[&str]| {
        let path = write_trs(dir.path(), name, &members);
        refused(&path, parts);
    };

    check(
        "no-camera.trs",
        json!({ "Display": { "Type": "PFM", "ResX": 8, "ResY": 8 } }),
        &["Camera"],
    );
    check(
        "no-fov.trs",
        json!({ "Camera": { "Type": "Camera", "Position": [0, 0, 0] } }),
        &["\"Camera\".fov", "missing"],
    );
    check(
        "fov-string.trs",
        json!({ "Camera": { "Type": "Camera", "Position": [0, 0, 0], "fov": "wide" } }),
        &["\"Camera\".fov"],
    );
    check(
        "position-huge.trs",
        json!({ "Camera": { "Type": "Camera", "Position": [0, 1e300, 0], "fov": 40 } }),
        &["\"Camera\".Position", "finite"],
    );
    check(
        "zero-res.trs",
        json!({ "Camera": camera(), "Display": { "Type": "PFM", "ResX": 0, "ResY": 8 } }),
        &["\"Display\".ResX"],
    );
    check(
        "vertices.trs",
        json!({
            "Camera": camera(),
            "Panel": {
                "Type": "Light",
                "LightType": "Area",
                "Intensity": [1, 1, 1],
                "Vertices": [[0, 2, 0], [1, 2, 0], [1, 2, 1], [0, 2, 1]]
            }
        }),
        &["\"Panel\".Vertices", "4"],
    );
    check(
        "negative-intensity.trs",
        json!({
            "Camera": camera(),
            "Lamp": {
                "Type": "Light",
                "LightType": "Point",
                "Position": [0, 1, 0],
                "Intensity": [1, -1, 1]
            }
        }),
        &["\"Lamp\".Intensity"],
    );
    check(
        "not-an-object.trs",
        json!({ "Camera": camera(), "Lamp": [1, 2, 3] }),
        &["\"Lamp\""],
    );

    let path = write(
        &dir.path().join("syntax.trs"),
        "{\n  \"Camera\": {\n    \"Type\": \"Camera\",\n    \"fov\" 40\n  }\n}\n",
    );
    refused(&path, &["line 4", "column "]);
}
