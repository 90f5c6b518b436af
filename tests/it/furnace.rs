//! Analytic furnaces: closed spheres whose radiance is known exactly. Every
//! integrator must reproduce it: energy neither created nor lost, whichever
//! end the paths start from.

use crate::common::{self, block_stats, write_scene};
use tracer::settings::IntegratorKind;

/// Light tracing reaches a pixel only by splatting, so it needs more paths
/// for the same per-pixel noise.
fn spp(integrator: IntegratorKind) -> u32 {
    match integrator {
        IntegratorKind::Lt => 1024,
        _ => 256,
    }
}

const ALL: [IntegratorKind; 4] = [
    IntegratorKind::Pt,
    IntegratorKind::Lt,
    IntegratorKind::Bdpt,
    IntegratorKind::Vcm,
];

/// Renders the scene with `integrator` from several seeds and checks every
/// 4 × 4 block and the image mean against `expected`, within five standard
/// errors plus `geometric` (a relative allowance for the scene's own
/// deviation from the ideal, e.g. a tessellated sphere).
fn check(json: &str, integrator: IntegratorKind, spp: u32, expected: f64, geometric: f64) {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "furnace.json", json);
    let (scene, mut settings) = common::load_scene(path);
    settings.integrator = integrator;
    settings.stop.spp = spp;
    let s = block_stats(&scene, &settings, 8, 4);
    assert_eq!(s.discarded, 0, "{integrator:?}: NaN or infinite samples");
    let near = |got: f64, stderr: f64| {
        (got - expected).abs() <= 5.0 * stderr + geometric * expected + 1e-9
    };
    for c in 0..3 {
        assert!(
            near(s.image_mean[c], s.image_stderr[c]),
            "{integrator:?}: image mean {:.5} ± {:.5}, expected {expected}",
            s.image_mean[c],
            s.image_stderr[c]
        );
        for (k, (m, e)) in s.mean.iter().zip(&s.stderr).enumerate() {
            assert!(
                near(m[c], e[c]),
                "{integrator:?}: block {k} mean {:.5} ± {:.5}, expected {expected}",
                m[c],
                e[c]
            );
        }
    }
}

/// Camera inside a closed sphere of radius 1 and diffuse albedo ρ = 0.5, with
/// a point light of intensity π at its centre. Direct radiance from the wall
/// is ρ/π · π/1² = 0.5, and every further bounce keeps a fraction ρ of it, so
/// the wall's radiance is 0.5 / (1 − ρ) = 1 in every direction.
const POINT_FURNACE: &str = r#"{
  "camera": {"position": [0.1, 0.05, -0.2], "look_at": [0.3, 0.1, 1], "fov": 100},
  "film": {"width": 8, "height": 8},
  "render": {"max_depth": 64},
  "materials": {"half": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
  "objects": [{"type": "sphere", "radius": 1, "subdivisions": 5, "material": "half"}],
  "lights": [{"type": "point", "position": [0, 0, 0], "intensity": [3.14159265, 3.14159265, 3.14159265]}]
}"#;

/// Camera inside a closed, two-sided emitting cube (radiance 1) of albedo
/// 0.5: in any closed enclosure every wall point then has radiance
/// Le / (1 − ρ) = 2, whatever its shape. Exercises emitter hits, area-light
/// sampling and their MIS weights together. Flat faces keep the answer
/// exact: smooth shading normals (as on the sphere) bend it slightly.
const EMISSIVE_FURNACE: &str = r#"{
  "camera": {"position": [0.1, -0.2, 0.05], "look_at": [0.3, 0.1, 1], "fov": 90},
  "film": {"width": 8, "height": 8},
  "render": {"max_depth": 64},
  "materials": {"half": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
  "objects": [{"type": "cube", "material": "half", "transform": {"scale": 2},
               "emission": [1, 1, 1], "two_sided": true}]
}"#;

#[test]
fn point_light_furnace_sees_radiance_one() {
    let _guard = common::heavy();
    // The icosphere's flat facets lie inside the unit sphere, so they
    // receive slightly more than 1/r²: about 0.05% at this subdivision.
    for integrator in ALL {
        check(POINT_FURNACE, integrator, spp(integrator), 1.0, 0.001);
    }
}

#[test]
fn emissive_furnace_sees_radiance_two() {
    let _guard = common::heavy();
    for integrator in ALL {
        check(EMISSIVE_FURNACE, integrator, spp(integrator), 2.0, 0.0);
    }
}

/// VCM in the point-light furnace at 16 × 16 with wide merging radii (0.05
/// and 0.15 on the unit sphere): merges carry much of the weight, and the
/// kernel has no bias here however wide it is, since a ball centred on a
/// sphere cuts a cap of area exactly π r² from it (Archimedes). MIS
/// weights that do not sum to one show as a wrong brightness.
#[test]
fn vcm_merging_conserves_energy_with_a_wide_radius() {
    let _guard = common::heavy();
    for radius in ["0.05", "0.15"] {
        let json = POINT_FURNACE
            .replace(
                r#""film": {"width": 8, "height": 8}"#,
                r#""film": {"width": 16, "height": 16}"#,
            )
            .replace(
                r#""render": {"max_depth": 64}"#,
                &format!(r#""render": {{"max_depth": 64, "vcm_radius": {radius}}}"#),
            );
        assert!(json.contains("vcm_radius") && json.contains(r#""width": 16"#));
        check(&json, IntegratorKind::Vcm, 64, 1.0, 0.002);
    }
}

/// A white diffuse sphere (albedo 1) and a perfect mirror sphere under a
/// constant white sky: radiance 1 leaves every point in every direction,
/// so every pixel, sky or sphere, is 1. Exercises escaped rays, sky
/// sampling and their MIS weights, and light paths that start from the
/// sky's disk. The spheres' smooth normals lose a little light into the
/// facets (directions below a facet that the shading normal allows).
const SKY_FURNACE: &str = r#"{
  "format": 2,
  "camera": {"position": [0, 0.3, -4], "look_at": [0, 0, 0], "fov": 50},
  "film": {"width": 16, "height": 16},
  "render": {"max_depth": 64},
  "materials": {"white": {"type": "diffuse", "albedo": [1, 1, 1]}, "mirror": {"type": "mirror"}},
  "objects": [
    {"type": "sphere", "center": [-0.6, 0, 0], "radius": 0.7, "subdivisions": 5, "material": "white"},
    {"type": "sphere", "center": [0.8, 0.2, 0.6], "radius": 0.6, "subdivisions": 5, "material": "mirror"}
  ],
  "lights": [{"type": "environment", "radiance": [1, 1, 1]}]
}"#;

#[test]
fn constant_sky_furnace_sees_radiance_one() {
    let _guard = common::heavy();
    check(SKY_FURNACE, IntegratorKind::Pt, 64, 1.0, 0.002);
    check(SKY_FURNACE, IntegratorKind::Bdpt, 64, 1.0, 0.002);
    check(SKY_FURNACE, IntegratorKind::Vcm, 64, 1.0, 0.002);
    // A light path cannot reach the camera by way of a perfect mirror, so
    // the light tracer sees the diffuse sphere alone.
    let diffuse_only = SKY_FURNACE.replace(r#""material": "mirror""#, r#""material": "white""#);
    check(&diffuse_only, IntegratorKind::Lt, 1024, 1.0, 0.002);
}
