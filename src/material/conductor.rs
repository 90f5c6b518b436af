//! Conductors: GGX microfacet reflection with the exact Fresnel term of a
//! complex index of refraction, as Mitsuba 3's `roughconductor`; below
//! [`SMOOTH_ALPHA`] a Fresnel-weighted mirror, as its `conductor`.

use super::microfacet::{Ggx, SMOOTH_ALPHA};
use super::{reflect, reflect_local};
use crate::color::Rgb;
use glam::Vec3;

/// A conductor's parameters at a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// GGX width; at most [`SMOOTH_ALPHA`] means a smooth mirror.
    pub alpha: f32,
    /// Real part of the index of refraction, per channel (0 with `k` 1: Fresnel 1).
    pub eta: Rgb,
    /// Imaginary part (extinction coefficient), per channel.
    pub k: Rgb,
    /// Multiplier on the reflected light, per channel.
    pub reflectance: Rgb,
}

/// Unpolarised Fresnel reflectance of a conductor with complex index
/// `eta + i k` (relative to the outside) for light arriving at `cos_i`.
/// With `eta` 0 and `k` 1 it is exactly 1.
pub fn fresnel_conductor(cos_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let cos2 = Rgb::splat(cos_i * cos_i);
    let sin2 = Rgb::ONE - cos2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - sin2;
    let a2_plus_b2 = (t0 * t0 + 4.0 * eta2 * k2).max(Rgb::ZERO).powf(0.5);
    let t1 = a2_plus_b2 + cos2;
    let a = (0.5 * (a2_plus_b2 + t0)).max(Rgb::ZERO).powf(0.5);
    let t2 = 2.0 * cos_i * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = cos2 * a2_plus_b2 + sin2 * sin2;
    let t4 = t2 * sin2;
    // t3 + t4 vanishes only at normal incidence on eta = k = 0, where rp = rs.
    let rp = rs * ((t3 - t4) / (t3 + t4)).map(|r| if r.is_finite() { r } else { 1.0 });
    0.5 * (rp + rs)
}

impl Conductor {
    /// Whether this is a smooth mirror (a delta lobe).
    pub fn is_smooth(&self) -> bool {
        self.alpha <= SMOOTH_ALPHA
    }

    fn fresnel(&self, cos_i: f32) -> Rgb {
        self.reflectance * fresnel_conductor(cos_i, self.eta, self.k)
    }

    /// `f · cos θi` for local directions on the normal's side.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if self.is_smooth() || wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let ggx = Ggx { alpha: self.alpha };
        let g = ggx.g1(wo, h) * ggx.g1(wi, h);
        self.fresnel(wo.dot(h)) * (ggx.d(h) * g / (4.0 * wo.z))
    }

    /// Density of sampling `wi` from `wo`, per solid angle.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.is_smooth() || wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        Ggx { alpha: self.alpha }.visible_pdf(wo, h) / (4.0 * wo.dot(h))
    }

    /// Returns (wi, weight, pdf, delta): a visible normal, and `wo` mirrored about it.
    #[inline(never)]
    pub fn sample(&self, wo: Vec3, u: (f32, f32)) -> Option<(Vec3, Rgb, f32, bool)> {
        if wo.z <= 0.0 {
            return None;
        }
        if self.is_smooth() {
            return Some((reflect_local(wo), self.fresnel(wo.z), 1.0, true));
        }
        let ggx = Ggx { alpha: self.alpha };
        let m = ggx.sample_visible(wo, u);
        let cos_om = wo.dot(m);
        if cos_om <= 0.0 {
            return None;
        }
        let wi = reflect(wo, m, cos_om);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = ggx.visible_pdf(wo, m) / (4.0 * cos_om);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        // f cos / pdf with visible-normal sampling reduces to F G1(wi).
        Some((wi, self.fresnel(cos_om) * ggx.g1(wi, m), pdf, false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_one_and_known_metals() {
        for c in [0.0, 0.3, 1.0] {
            let f = fresnel_conductor(c, Rgb::ZERO, Rgb::ONE);
            assert!((f - Rgb::ONE).abs().max_element() < 1e-6, "{f}");
        }
        // A dielectric (k = 0) at normal incidence: ((n - 1) / (n + 1))².
        let f = fresnel_conductor(1.0, Rgb::splat(1.5), Rgb::ZERO);
        assert!((f.x - 0.04).abs() < 1e-6, "{f}");
        // Gold at normal incidence, |n - 1|² + k²  over |n + 1|² + k².
        let (n, k) = (0.2f32, 3.0f32);
        let expected = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let f = fresnel_conductor(1.0, Rgb::splat(n), Rgb::splat(k));
        assert!((f.x - expected).abs() < 1e-5, "{f} vs {expected}");
        // Grazing incidence reflects everything.
        let f = fresnel_conductor(0.0, Rgb::splat(n), Rgb::splat(k));
        assert!((f.x - 1.0).abs() < 1e-5, "{f}");
    }
}
