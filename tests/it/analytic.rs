//! A diffuse plane lit by one delta light has closed-form radiance,
//! L = ρ/π · E, with the irradiance E of each light type:
//! point I·cos θ/d², spot the same times its falloff, directional E·cos θ.
//! Each pixel is compared with that radiance averaged over the pixel's area
//! (the box filter), integrated numerically through the same camera.

use crate::common::{self, block_stats, write_scene};
use glam::Vec3;
use std::f32::consts::PI;
use tracer::render::{render, RenderOptions};
use tracer::scene::Scene;
use tracer::settings::{IntegratorKind, Settings};

const ALBEDO: f32 = 0.6;

const SCENE: &str = r#"{
  "camera": {"position": [0, 4, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 70},
  "film": {"width": 24, "height": 16},
  "render": {"spp": 64, "max_depth": 2},
  "materials": {"m": {"type": "diffuse", "albedo": [ALBEDO, ALBEDO, ALBEDO]}},
  "objects": [{"type": "quad", "material": "m", "transform": {"scale": 100}}],
  "lights": [LIGHTS]
}"#;

fn load(dir: &std::path::Path, lights_json: &str) -> (Scene, Settings) {
    let json = SCENE
        .replace("ALBEDO", &ALBEDO.to_string())
        .replace("LIGHTS", lights_json);
    common::load_scene(write_scene(dir, "plane.json", &json))
}

/// The closed-form radiance of every pixel, averaged over the pixel's area
/// by a 16 × 16 midpoint rule through the scene's own camera.
fn expected_image(settings: &Settings, irradiance: impl Fn(Vec3) -> Vec3) -> Vec<Vec3> {
    const SUB: usize = 16;
    let (w, h) = (settings.film.width, settings.film.height);
    let camera = settings.camera().unwrap();
    let mut image = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut expected = Vec3::ZERO;
            for i in 0..SUB {
                for j in 0..SUB {
                    let ray = camera.ray(
                        x as f32 + (i as f32 + 0.5) / SUB as f32,
                        y as f32 + (j as f32 + 0.5) / SUB as f32,
                    );
                    let p = ray.at(-ray.origin.y / ray.dir.y);
                    expected += ALBEDO / PI * irradiance(p);
                }
            }
            image.push(expected / (SUB * SUB) as f32);
        }
    }
    image
}

/// Path tracing, pixel by pixel: its low per-pixel noise allows a 1% bound.
fn check(lights_json: &str, irradiance: impl Fn(Vec3) -> Vec3) {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let (scene, settings) = load(dir.path(), lights_json);
    let (image, _) = render(&scene, &settings, &RenderOptions::default()).unwrap();
    let expected_image = expected_image(&settings, irradiance);
    // Relative error, except in pixels far darker than the peak (the spot's
    // dim edge), where 1% of the peak is the yardstick.
    let peak = expected_image
        .iter()
        .map(|e| e.max_element())
        .fold(0.0, f32::max);
    assert!(peak > 0.0);
    for (k, (&got, &expected)) in image.pixels.iter().zip(&expected_image).enumerate() {
        let error = (got - expected).abs().max_element() / expected.max_element().max(0.01 * peak);
        assert!(
            error < 0.01,
            "pixel {k}: rendered {got}, expected {expected}"
        );
    }
}

/// Light tracing and BDPT: 4 × 4 blocks over 16 seeds, each within six
/// standard errors (plus 0.1% for the midpoint rule) of the closed form. Six,
/// not five: the standard error is itself estimated from only 16 renders
/// (Student's t with 15 degrees of freedom has heavier tails than a normal).
fn check_statistically(
    integrator: IntegratorKind,
    spp: u32,
    lights_json: &str,
    irradiance: impl Fn(Vec3) -> Vec3,
) {
    const BLOCK: u32 = 4;
    let dir = tempfile::tempdir().unwrap();
    let (scene, mut settings) = load(dir.path(), lights_json);
    settings.integrator = integrator;
    settings.stop.spp = spp;
    let expected_image = expected_image(&settings, irradiance);
    let s = block_stats(&scene, &settings, 16, BLOCK);
    assert_eq!(s.discarded, 0);
    let w = settings.film.width;
    for (k, (mean, stderr)) in s.mean.iter().zip(&s.stderr).enumerate() {
        let (bx, by) = (k as u32 % s.blocks_x, k as u32 / s.blocks_x);
        let mut expected = glam::DVec3::ZERO;
        for y in by * BLOCK..(by + 1) * BLOCK {
            for x in bx * BLOCK..(bx + 1) * BLOCK {
                expected += expected_image[(y * w + x) as usize].as_dvec3();
            }
        }
        expected /= (BLOCK * BLOCK) as f64;
        for c in 0..3 {
            let bound = 6.0 * stderr[c] + 1e-3 * expected[c] + 1e-9;
            assert!(
                (mean[c] - expected[c]).abs() <= bound,
                "{integrator:?} block ({bx}, {by}) channel {c}: {:.5} ± {:.5}, expected {:.5}",
                mean[c],
                stderr[c],
                expected[c]
            );
        }
    }
}

#[test]
fn point_light_on_a_plane() {
    let (pos, intensity) = (Vec3::new(1.0, 2.0, 0.5), Vec3::new(10.0, 5.0, 2.0));
    check(
        r#"{"type": "point", "position": [1, 2, 0.5], "intensity": [10, 5, 2]}"#,
        |p| {
            let d = pos - p;
            intensity * d.y / d.length().powi(3)
        },
    );
}

#[test]
fn point_light_on_a_plane_light_tracing_and_bdpt() {
    let _guard = common::heavy();
    let (pos, intensity) = (Vec3::new(1.0, 2.0, 0.5), Vec3::new(10.0, 5.0, 2.0));
    let irradiance = |p: Vec3| {
        let d = pos - p;
        intensity * d.y / d.length().powi(3)
    };
    let light = r#"{"type": "point", "position": [1, 2, 0.5], "intensity": [10, 5, 2]}"#;
    check_statistically(IntegratorKind::Lt, 256, light, irradiance);
    check_statistically(IntegratorKind::Bdpt, 64, light, irradiance);
}

#[test]
fn spot_light_on_a_plane() {
    // Cone edge at 40°, falloff from 20°: both the full and the ramp region land on the plane.
    let (pos, intensity) = (Vec3::new(0.2, 3.0, -0.1), Vec3::new(20.0, 20.0, 10.0));
    let (cos_cone, cos_start) = (40f32.to_radians().cos(), 20f32.to_radians().cos());
    check(
        r#"{"type": "spot", "position": [0.2, 3, -0.1], "look_at": [0.2, 0, -0.1], "intensity": [20, 20, 10],
            "cone_angle": 40, "falloff_start": 20}"#,
        |p| {
            let d = pos - p;
            let cos_axis = d.y / d.length();
            let t = ((cos_axis - cos_cone) / (cos_start - cos_cone)).clamp(0.0, 1.0);
            intensity * (t * t * (3.0 - 2.0 * t)) * d.y / d.length().powi(3)
        },
    );
}

#[test]
fn directional_light_on_a_plane() {
    let direction = Vec3::new(0.3, -1.0, 0.2).normalize();
    check(
        r#"{"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [2, 1, 0.5]}"#,
        |_| Vec3::new(2.0, 1.0, 0.5) * -direction.y,
    );
}
