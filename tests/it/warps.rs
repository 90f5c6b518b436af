//! Each warp in `tracer::sampling::warp` turns uniform numbers into the
//! density it is meant to have: chi-square tests (`common::chi_square`) of
//! the directions over a grid on the sphere or a band of it, and of the
//! points over a grid on the plane, with each density written out here
//! rather than taken from the library.

use crate::common::chi_square::{self, PlaneGrid, SphereGrid};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;
use tracer::sampling::warp::{
    concentric_disk, cosine_hemisphere, cosine_hemisphere_pdf, uniform_cone, uniform_cone_pdf,
    uniform_sphere, uniform_triangle, UNIFORM_SPHERE_PDF,
};

const N: usize = 200_000;

/// Asserts that a warped direction has unit length.
fn unit(w: Vec3) -> Vec3 {
    assert!((w.length() - 1.0).abs() < 1e-5, "{w} is not a unit vector");
    w
}

#[test]
fn uniform_sphere_is_uniform_over_the_sphere() {
    chi_square::check(
        "uniform_sphere",
        &SphereGrid::sphere(),
        N,
        11,
        |r| {
            let w = unit(uniform_sphere(r.f32(), r.f32()));
            Some((w, UNIFORM_SPHERE_PDF as f64))
        },
        |_| 1.0 / (4.0 * PI),
    );
}

#[test]
fn cosine_hemisphere_is_cosine_weighted() {
    // The upper hemisphere in 10 × 20 cells; a direction below it would be
    // outside the grid, where the density expects nothing.
    chi_square::check(
        "cosine_hemisphere",
        &SphereGrid::band(0.0, 1.0),
        N,
        12,
        |r| {
            let w = unit(cosine_hemisphere(r.f32(), r.f32()));
            Some((w, cosine_hemisphere_pdf(w.z) as f64))
        },
        |w| (w.z as f64).max(0.0) / PI,
    );
}

#[test]
fn uniform_cone_is_uniform_over_its_cap() {
    // Wider than a hemisphere, a wide cone, a spot's, and a narrow one
    // (half-angle 3°): the grid covers just the cap.
    for (k, cos_max) in [
        -0.5f32,
        0.3,
        30f32.to_radians().cos(),
        3f32.to_radians().cos(),
    ]
    .into_iter()
    .enumerate()
    {
        let uniform = 1.0 / (2.0 * PI * (1.0 - cos_max as f64));
        chi_square::check(
            &format!("uniform_cone({cos_max})"),
            &SphereGrid::band(cos_max as f64, 1.0),
            N,
            20 + k as u64,
            |r| {
                let w = unit(uniform_cone(cos_max, r.f32(), r.f32()));
                Some((w, uniform_cone_pdf(cos_max) as f64))
            },
            // Rounding may put a sample a hair below the rim.
            |w| {
                if w.z >= cos_max - 1e-6 {
                    uniform
                } else {
                    0.0
                }
            },
        );
    }
}

#[test]
fn concentric_disk_is_uniform_over_the_disk() {
    // A 20 × 20 grid over the disk's bounding square: the cells the rim
    // cuts expect the part of them inside it.
    chi_square::check(
        "concentric_disk",
        &PlaneGrid::new((-1.0, 1.0), (-1.0, 1.0), 20),
        N,
        31,
        |r| Some((concentric_disk(r.f32(), r.f32()), 1.0 / PI)),
        |p: Vec2| {
            if p.length_squared() <= 1.0 + 1e-6 {
                1.0 / PI
            } else {
                0.0
            }
        },
    );
}

#[test]
fn uniform_triangle_is_uniform_over_the_triangle() {
    // Barycentrics (b1, b2) on a 20 × 20 grid over the unit square: the
    // triangle b1 + b2 ≤ 1 has area 1/2, so density 2, and the cells along
    // the diagonal expect the part of them below it.
    chi_square::check(
        "uniform_triangle",
        &PlaneGrid::new((0.0, 1.0), (0.0, 1.0), 20),
        N,
        32,
        |r| {
            let (b1, b2) = uniform_triangle(r.f32(), r.f32());
            Some((Vec2::new(b1, b2), 2.0))
        },
        |p: Vec2| {
            if p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0 + 1e-6 {
                2.0
            } else {
                0.0
            }
        },
    );
}
