//! Analytic furnaces: closed spheres whose radiance is known exactly.

mod common;

use common::write_scene;
use tracer::render::{render, RenderOptions};

/// Camera inside a closed sphere of radius 1 and diffuse albedo ρ = 0.5, with
/// a point light of intensity π at its centre. Direct radiance from the wall
/// is ρ/π · π/1² = 0.5, and every further bounce keeps a fraction ρ of it, so
/// the wall's radiance is 0.5 / (1 − ρ) = 1 in every direction.
#[test]
fn point_light_furnace_sees_radiance_one() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(
        dir.path(),
        "furnace.json",
        r#"{
          "camera": {"position": [0.1, 0.05, -0.2], "look_at": [0.3, 0.1, 1], "fov": 100},
          "film": {"width": 8, "height": 8},
          "render": {"spp": 8192, "max_depth": 64},
          "materials": {"half": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
          "objects": [{"type": "sphere", "radius": 1, "subdivisions": 5, "material": "half"}],
          "lights": [{"type": "point", "position": [0, 0, 0], "intensity": [3.14159265, 3.14159265, 3.14159265]}]
        }"#,
    );
    let scene = tracer::scene::load(&path).unwrap();
    let (image, stats) = render(&scene, &RenderOptions::default()).unwrap();
    assert_eq!(stats.discarded, 0);
    let mean = image.mean();
    assert!((mean.x - 1.0).abs() < 0.003, "mean {mean}");
    for (k, p) in image.pixels.iter().enumerate() {
        for c in p.to_array() {
            assert!((c - 1.0).abs() < 0.01, "pixel {k}: {p}");
        }
    }
}

/// Camera inside a closed, two-sided emitting sphere (radiance 1) of albedo
/// 0.5: every wall point has radiance Le / (1 − ρ) = 2. Exercises emitter
/// hits, area-light sampling and their MIS weights together.
#[test]
fn emissive_furnace_sees_radiance_two() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(
        dir.path(),
        "furnace.json",
        r#"{
          "camera": {"position": [0, 0, 0], "look_at": [0, 0, 1], "fov": 90},
          "film": {"width": 8, "height": 8},
          "render": {"spp": 4096, "max_depth": 64},
          "materials": {"half": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
          "objects": [{"type": "sphere", "radius": 1, "subdivisions": 3, "material": "half",
                       "emission": [1, 1, 1], "two_sided": true}]
        }"#,
    );
    let scene = tracer::scene::load(&path).unwrap();
    let (image, _) = render(&scene, &RenderOptions::default()).unwrap();
    let mean = image.mean();
    assert!((mean.x - 2.0).abs() < 0.005, "mean {mean}");
    for p in &image.pixels {
        assert!((p.x - 2.0).abs() < 0.02, "pixel {p}");
    }
}
