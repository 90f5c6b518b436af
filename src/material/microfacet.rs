//! The GGX (Trowbridge–Reitz) microfacet distribution with Smith shadowing,
//! sampled by its visible normals (Heitz, "Sampling the GGX Distribution of
//! Visible Normals", JCGT 2018).
//!
//! Every rough material uses the separable masking-shadowing term
//! G(wo, wi) = G1(wo) G1(wi), as Mitsuba 3 does, so our images agree with
//! its `roughconductor`, `roughdielectric` and `roughplastic`. Directions
//! are in the local shading frame (normal +z).

use glam::Vec3;
use std::f32::consts::PI;

/// Below this width a surface is treated as perfectly smooth: the
/// distribution is then narrower than f32 can sample or evaluate reliably.
pub const SMOOTH_ALPHA: f32 = 1e-4;

/// An isotropic GGX distribution of width `alpha` (not squared).
#[derive(Clone, Copy, Debug)]
pub struct Ggx {
    /// The width parameter, > [`SMOOTH_ALPHA`].
    pub alpha: f32,
}

impl Ggx {
    /// Microfacet normal density D(m), per unit projected area.
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
        1.0 / (PI * a2 * t * t)
    }

    /// Smith's masking term for direction `v` and microfacet normal `m`:
    /// zero when `v` sees the back of the facet.
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy = self.alpha * self.alpha * (v.x * v.x + v.y * v.y);
        if xy == 0.0 {
            return 1.0;
        }
        let tan2 = xy / (v.z * v.z);
        2.0 / (1.0 + (1.0 + tan2).sqrt())
    }

    /// The density of normals visible from `wo` (`wo.z > 0`):
    /// D_wo(m) = G1(wo, m) max(0, wo·m) D(m) / wo.z.
    pub fn visible_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo, m) * wo.dot(m).max(0.0) * self.d(m) / wo.z
    }

    /// A microfacet normal distributed by [`Ggx::visible_pdf`] for `wo`
    /// (`wo.z > 0`): stretch the view to the unit-width configuration,
    /// sample the projected hemisphere there, and unstretch.
    pub fn sample_visible(&self, wo: Vec3, u: (f32, f32)) -> Vec3 {
        let a = self.alpha;
        let vh = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        let r = u.0.sqrt();
        let phi = 2.0 * PI * u.1;
        let p1 = r * phi.cos();
        let mut p2 = r * phi.sin();
        // Squeeze the disk onto the part of the hemisphere visible from wo.
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(m) cos θm dm = 1 over the hemisphere (projected area normalisation).
    #[test]
    fn distribution_is_normalised() {
        for alpha in [0.05f32, 0.3, 1.0] {
            let g = Ggx { alpha };
            let (n_theta, n_phi) = (4000, 8);
            let mut total = 0.0f64;
            for i in 0..n_theta {
                // Substitution t = cos θ, denser near the pole for narrow lobes.
                let s = (i as f64 + 0.5) / n_theta as f64;
                let cos = 1.0 - s * s;
                let jacobian = 2.0 * s / n_theta as f64;
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                for j in 0..n_phi {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n_phi as f64;
                    let m = Vec3::new(
                        (sin * phi.cos()) as f32,
                        (sin * phi.sin()) as f32,
                        cos as f32,
                    );
                    total +=
                        g.d(m) as f64 * cos * jacobian * 2.0 * std::f64::consts::PI / n_phi as f64;
                }
            }
            assert!((total - 1.0).abs() < 2e-3, "alpha {alpha}: {total}");
        }
    }

    #[test]
    fn masking_is_one_at_normal_incidence_and_falls_at_grazing() {
        let g = Ggx { alpha: 0.5 };
        assert_eq!(g.g1(Vec3::Z, Vec3::Z), 1.0);
        let grazing = Vec3::new(0.999, 0.0, 0.0447).normalize();
        assert!(g.g1(grazing, Vec3::Z) < 0.5);
        // A facet facing away from a direction above the surface hides it...
        let away = Vec3::new(-1.0, 0.0, 0.2).normalize();
        assert_eq!(g.g1(Vec3::new(0.6, 0.0, 0.8), away), 0.0);
        // ...while a direction below the surface (a refracted one) sees it from below.
        assert_eq!(g.g1(Vec3::new(0.0, 0.0, -1.0), Vec3::Z), 1.0);
    }
}
