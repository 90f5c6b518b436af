//! Maps from the unit square to directions and points, with their densities.

use glam::{BVec4A, Vec2, Vec3, Vec4};
use std::f32::consts::{FRAC_1_PI, PI};

/// Concentric map of the square onto the unit disk (Shirley and Chiu 1997).
///
/// The angle is π/4 · (ratio of the smaller coordinate to the larger), within
/// ±π/4, plus a quarter turn in the upper and lower wedges: there cos and sin
/// swap. On ±π/4 short series give sin and cos to within an ulp, so no
/// general sine with its range reduction is needed (light and BSDF sampling
/// call this once per bounce).
pub fn concentric_disk(u: f32, v: f32) -> Vec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    // Which wedge a sample falls in is a coin toss: selects, not branches,
    // so the branch predictor has nothing to miss.
    let wide = a.abs() > b.abs();
    let (r, other) = select_pair(wide, (a, b), (b, a));
    let (sin, cos) = sin_cos_quarter(PI / 4.0 * (other / r));
    // In the upper and lower wedges φ = π/2 − θ: cos φ = sin θ, sin φ = cos θ.
    let (x, y) = select_pair(wide, (cos, sin), (sin, cos));
    Vec2::new(r * x, r * y)
}

/// `if_true` when `condition` holds, else `if_false`, by SIMD mask
/// arithmetic. For a condition that is a coin toss per sample, a branch
/// mispredicts half the time; the compiler turns a scalar select back into
/// a branch when it sees fit (even one marked unpredictable), a vector one
/// it does not.
#[inline(always)]
fn select_pair(condition: bool, if_true: (f32, f32), if_false: (f32, f32)) -> (f32, f32) {
    let picked = Vec4::select(
        BVec4A::splat(condition),
        Vec4::new(if_true.0, if_true.1, 0.0, 0.0),
        Vec4::new(if_false.0, if_false.1, 0.0, 0.0),
    );
    (picked.x, picked.y)
}

/// sin and cos of `x` for |x| ≤ π/4, by their Taylor series to x⁹ and x¹⁰:
/// the first omitted terms are below 2e-9, far under f32's resolution.
#[inline]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let sin = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let cos = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0)))));
    (sin, cos)
}

/// Cosine-weighted direction around +z (Malley's method).
pub fn cosine_hemisphere(u: f32, v: f32) -> Vec3 {
    let d = concentric_disk(u, v);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle density of [`cosine_hemisphere`] at angle θ from +z: cos θ / π;
/// zero below the horizon.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere; `u` sets z (1 at `u` = 0).
pub fn uniform_sphere(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Solid-angle density of [`uniform_sphere`]: 1 / 4π.
pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Uniform barycentrics (b1, b2) on a triangle, by the square-to-triangle map
/// that folds the square along its diagonal.
pub fn uniform_triangle(u: f32, v: f32) -> (f32, f32) {
    // Half the samples fold: a select, as in `concentric_disk`.
    select_pair(u + v > 1.0, (1.0 - u, 1.0 - v), (u, v))
}

/// Uniform direction in the cone of half-angle acos(`cos_max`) around +z.
pub fn uniform_cone(cos_max: f32, u: f32, v: f32) -> Vec3 {
    let z = 1.0 - u * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`uniform_cone`] in solid angle.
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turn_sine_and_cosine_match_the_library_to_an_ulp() {
        for i in -1000..=1000 {
            let x = PI / 4.0 * i as f32 / 1000.0;
            let (sin, cos) = sin_cos_quarter(x);
            let (s64, c64) = (x as f64).sin_cos();
            assert!(
                (sin as f64 - s64).abs() <= 1.2e-7 * s64.abs().max(1e-30),
                "sin {x}: {sin} vs {s64}"
            );
            assert!(
                (cos as f64 - c64).abs() <= 1.2e-7,
                "cos {x}: {cos} vs {c64}"
            );
        }
    }

    #[test]
    fn concentric_disk_keeps_the_map_of_angles() {
        // Against the map written with the library's sine and cosine.
        let reference = |u: f32, v: f32| {
            let (a, b) = (2.0 * u as f64 - 1.0, 2.0 * v as f64 - 1.0);
            if a == 0.0 && b == 0.0 {
                return (0.0, 0.0);
            }
            let (r, phi) = if a.abs() > b.abs() {
                (a, std::f64::consts::FRAC_PI_4 * (b / a))
            } else {
                (
                    b,
                    std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b),
                )
            };
            (r * phi.cos(), r * phi.sin())
        };
        for i in 0..=64 {
            for j in 0..=64 {
                let (u, v) = (i as f32 / 64.0, j as f32 / 64.0);
                let d = concentric_disk(u, v);
                let (x, y) = reference(u, v);
                assert!(
                    (d.x as f64 - x).abs() < 3e-7 && (d.y as f64 - y).abs() < 3e-7,
                    "{u} {v}"
                );
                assert!(d.length() <= 1.0 + 1e-6);
            }
        }
    }
}
