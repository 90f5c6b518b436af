//! PT, LT and BDPT are independent unbiased estimators of the same image:
//! on every scene all three can render, their images must agree within
//! statistical error, block by block (borders included, where mis-scaled
//! light-tracing splats would show first).

use crate::common::{self, assert_agree, block_stats, write_scene, BlockStats};
use tracer::settings::IntegratorKind;

/// Per-block comparisons are many (blocks × channels × pairs); five standard
/// errors keeps the chance of a false alarm below one in ten thousand.
const Z: f64 = 5.0;

/// Independent renders per estimate. Light-transport estimators have heavy
/// tails (rare, bright paths), so the variance estimate needs many of them.
const SEEDS: u64 = 16;

/// Blocks of 8 × 8 pixels: each block of each render pools enough samples
/// that its mean is close to normal.
const BLOCK: u32 = 8;

fn stats(path: &std::path::Path, integrator: IntegratorKind, size: u32, spp: u32) -> BlockStats {
    let (scene, mut settings) = common::load_scene(path);
    settings.film.width = size;
    settings.film.height = size;
    settings.integrator = integrator;
    settings.stop.spp = spp;
    let s = block_stats(&scene, &settings, SEEDS, BLOCK);
    assert_eq!(
        s.discarded, 0,
        "{integrator:?} produced NaN or infinite samples"
    );
    s
}

fn all_three_agree(path: &std::path::Path, size: u32, spp: [u32; 3]) {
    let _guard = common::heavy();
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let pt = stats(path, IntegratorKind::Pt, size, spp[0]);
    let lt = stats(path, IntegratorKind::Lt, size, spp[1]);
    let bdpt = stats(path, IntegratorKind::Bdpt, size, spp[2]);
    assert_agree(&pt, &lt, Z, &format!("{name}: pt vs lt"));
    assert_agree(&pt, &bdpt, Z, &format!("{name}: pt vs bdpt"));
    assert_agree(&lt, &bdpt, Z, &format!("{name}: lt vs bdpt"));
}

#[test]
fn cornell_box() {
    all_three_agree(
        &common::repo().join("scenes/cornell-box.json"),
        32,
        [16, 16, 8],
    );
}

#[test]
fn textured_scene() {
    all_three_agree(
        &common::repo().join("scenes/textured.json"),
        32,
        [16, 16, 8],
    );
}

#[test]
fn rough_materials_scene() {
    all_three_agree(
        &common::repo().join("scenes/rough-materials.json"),
        32,
        [16, 16, 8],
    );
}

/// The sky scene's smooth plastic, chrome and glass are seen directly,
/// which a light tracer cannot render; PT and BDPT must still agree.
#[test]
fn sky_materials_pt_and_bdpt() {
    let _guard = common::heavy();
    let path = common::repo().join("scenes/sky-materials.json");
    let pt = stats(&path, IntegratorKind::Pt, 32, 32);
    let bdpt = stats(&path, IntegratorKind::Bdpt, 32, 16);
    assert_agree(&pt, &bdpt, Z, "sky-materials: pt vs bdpt");
}

/// The caustic scene's glass and mirror are seen directly, which a light
/// tracer cannot render; PT and BDPT must still agree.
#[test]
fn caustics_pt_and_bdpt() {
    let _guard = common::heavy();
    let path = common::repo().join("scenes/cornell-caustics.json");
    let pt = stats(&path, IntegratorKind::Pt, 32, 32);
    let bdpt = stats(&path, IntegratorKind::Bdpt, 32, 16);
    assert_agree(&pt, &bdpt, Z, "caustics: pt vs bdpt");
}

const ROOM: &str = r#"
  "camera": {"position": [0, 1, -3.2], "look_at": [0, 0.8, 0], "fov": 55},
  "materials": {
    "white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
    "red": {"type": "diffuse", "albedo": [0.8, 0.2, 0.1]}
  },
  "objects": [
    {"type": "quad", "material": "white", "transform": {"scale": 6}},
    {"type": "quad", "material": "red", "transform": {"scale": 6, "rotate": [1, 0, 0, -90], "translate": [0, 3, 2]}},
    {"type": "cube", "material": "white", "transform": {"scale": [0.6, 1.2, 0.6], "rotate": [0, 1, 0, 25], "translate": [0.7, 0.6, 0.6]}},
    {"type": "sphere", "center": [-0.6, 0.5, 0.2], "radius": 0.5, "subdivisions": 1, "material": "white"}
  ],"#;

fn room(lights: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let json = format!("{{{ROOM} \"lights\": [{lights}]}}");
    let path = write_scene(dir.path(), "room.json", &json);
    (dir, path)
}

/// Delta lights: every integrator must weigh them right (BSDF sampling can
/// never hit them, nor can a camera path end on them). The low-poly sphere's
/// smooth normals differ from its facets, which exercises the shading-normal
/// correction of light paths.
#[test]
fn spot_light_only() {
    let (_dir, path) = room(
        r#"{"type": "spot", "position": [0.2, 2.6, -0.5], "look_at": [0, 0, 0.3], "intensity": [30, 28, 25],
            "cone_angle": 45, "falloff_start": 25}"#,
    );
    all_three_agree(&path, 32, [16, 16, 8]);
}

#[test]
fn directional_light_only() {
    let (_dir, path) =
        room(r#"{"type": "directional", "direction": [0.4, -1, 0.5], "irradiance": [3, 3, 2.5]}"#);
    all_three_agree(&path, 32, [16, 16, 8]);
}

#[test]
fn point_and_area_lights_together() {
    let dir = tempfile::tempdir().unwrap();
    let json = format!(
        r#"{{{ROOM} "lights": [{{"type": "point", "position": [-1, 2, -1], "intensity": [8, 8, 8]}}]}}"#
    )
    .replacen(
        r#""objects": ["#,
        r#""objects": [{"type": "quad", "material": "white", "emission": [6, 5, 4],
                        "transform": {"scale": 0.8, "rotate": [1, 0, 0, 180], "translate": [0, 2.9, 0.5]}},"#,
        1,
    );
    let path = write_scene(dir.path(), "room.json", &json);
    all_three_agree(&path, 32, [16, 16, 8]);
}

/// Rough metal, rough glass (seen from outside and, through it, from
/// inside) and a Fresnel-1 conductor: each integrator samples and evaluates
/// them differently (BSDF sampling, light connections, adjoint scattering
/// on light paths), so agreement checks all of that at once.
#[test]
fn rough_conductor_rough_glass_and_thin_lens() {
    let dir = tempfile::tempdir().unwrap();
    let json = format!(r#"{{{ROOM} "lights": [{{"type": "point", "position": [-1, 2, -1], "intensity": [6, 6, 6]}}]}}"#)
        .replace(
            r#""red": {"type": "diffuse", "albedo": [0.8, 0.2, 0.1]}"#,
            r#""red": {"type": "diffuse", "albedo": [0.8, 0.2, 0.1]},
               "gold": {"type": "conductor", "alpha": 0.3, "eta": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77]},
               "steel": {"type": "conductor", "alpha": 0.15, "reflectance": [0.7, 0.7, 0.75]},
               "frosted": {"type": "rough_dielectric", "ior": 1.5, "alpha": 0.25}"#,
        )
        .replace(
            r#""translate": [0.7, 0.6, 0.6]}}"#,
            r#""translate": [0.7, 0.6, 0.6]}, "material": "gold"}"#,
        )
        .replace(r#""subdivisions": 1, "material": "white""#, r#""subdivisions": 1, "material": "frosted""#)
        .replacen(
            r#""objects": ["#,
            r#""objects": [{"type": "quad", "material": "white", "emission": [6, 5, 4],
                            "transform": {"scale": 0.8, "rotate": [1, 0, 0, 180], "translate": [0, 2.9, 0.5]}},
                           {"type": "sphere", "center": [0.1, 0.25, -0.7], "radius": 0.25, "subdivisions": 2, "material": "steel"},"#,
            1,
        )
        .replace(r#"{"type": "cube", "material": "white","#, r#"{"type": "cube","#);
    assert!(json.contains("\"gold\"}") && json.contains("frosted\"}") && json.contains("steel\"}"));
    let path = write_scene(dir.path(), "room.json", &json);
    all_three_agree(&path, 32, [16, 16, 8]);
    // The same room through a wide thin lens focused in front of everything
    // (blurs of several pixels, so a misplaced lens shows in 8 × 8 blocks): light
    // paths connect to points on the lens, camera paths start on it.
    let lens = json.replace(
        r#""fov": 55}"#,
        r#""fov": 55, "aperture_radius": 0.4, "focus_distance": 1.8}"#,
    );
    assert_ne!(lens, json);
    let path = write_scene(dir.path(), "lens.json", &lens);
    all_three_agree(&path, 32, [16, 16, 8]);
}

/// Writes a 32 × 16 latitude–longitude sky: blue above the horizon, dim
/// ground below, and a small sun thirty times brighter.
fn write_sky(path: &std::path::Path) {
    exr::prelude::write_rgb_file(path, 32, 16, |x, y| {
        if (4..6).contains(&x) && (4..6).contains(&y) {
            (30.0f32, 28.0f32, 24.0f32)
        } else if y < 8 {
            (0.3 + 0.02 * y as f32, 0.5 + 0.01 * x as f32, 1.0)
        } else {
            (0.25, 0.2, 0.15)
        }
    })
    .unwrap();
}

/// An open scene under an image sky with a sun, seen through a thin lens:
/// escaped camera rays and their MIS weights (PT, BDPT), light paths from
/// the sky's disk (LT, BDPT), the sky seen directly by light tracing, and
/// every material of format 2 (rough plastic among them; then a smooth one).
#[test]
fn image_sky_with_rough_materials_and_thin_lens() {
    let dir = tempfile::tempdir().unwrap();
    write_sky(&dir.path().join("sky.exr"));
    let json = r#"{
      "format": 2,
      "camera": {"position": [0, 1, -3.2], "look_at": [0, 0.9, 0], "fov": 55,
                 "aperture_radius": 0.12, "focus_distance": 3.3},
      "render": {"max_depth": 12},
      "materials": {
        "white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
        "gold": {"type": "conductor", "alpha": 0.3, "eta": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77]},
        "frosted": {"type": "rough_dielectric", "ior": 1.5, "alpha": 0.25},
        "plastic": {"type": "plastic", "albedo": [0.2, 0.5, 0.8], "ior": 1.5, "alpha": 0.2}
      },
      "objects": [
        {"type": "quad", "material": "white", "transform": {"scale": 6}},
        {"type": "sphere", "center": [-0.6, 0.5, 0.2], "radius": 0.5, "subdivisions": 2, "material": "gold"},
        {"type": "sphere", "center": [0.7, 0.45, 0.3], "radius": 0.45, "subdivisions": 2, "material": "frosted"},
        {"type": "cube", "material": "plastic", "transform": {"scale": 0.4, "rotate": [0, 1, 0, 30], "translate": [0.1, 0.2, -0.8]}}
      ],
      "lights": [{"type": "environment", "file": "sky.exr", "transform": {"rotate": [0, 1, 0, 40]}}]
    }"#;
    let path = write_scene(dir.path(), "sky.json", json);
    // Most rays escape after a bounce or two, so samples are cheap: take more.
    all_three_agree(&path, 32, [64, 64, 32]);
    // A smooth coat mirrors the sky, which light paths cannot bring to the
    // camera: PT and BDPT only.
    let smooth = json.replace(r#""alpha": 0.2}"#, r#""alpha": 0}"#);
    assert_ne!(smooth, json);
    let path = write_scene(dir.path(), "smooth.json", &smooth);
    let _guard = common::heavy();
    let pt = stats(&path, IntegratorKind::Pt, 32, 64);
    let bdpt = stats(&path, IntegratorKind::Bdpt, 32, 32);
    assert_agree(&pt, &bdpt, Z, "smooth plastic: pt vs bdpt");
}
