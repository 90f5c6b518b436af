//! Rough glass: GGX microfacet reflection and refraction (Walter, Marschner,
//! Li and Torrance, "Microfacet Models for Refraction through Rough
//! Surfaces", EGSR 2007), as Mitsuba 3's `roughdielectric`. A visible
//! normal is sampled from `wo`, then Fresnel chooses between reflecting
//! about it and refracting through it.
//!
//! `eta` is the index on the far side over the index on `wo`'s side, and
//! local `wo` is always above the surface (`wo.z > 0`). Radiance refracted
//! into a denser medium is compressed by 1/eta² (Veach's thesis, §5.2);
//! importance, carried by light paths, is not.

use super::dielectric::{self, fresnel_dielectric};
use super::microfacet::{Ggx, SMOOTH_ALPHA};
use super::{reflect, refract, Transport};
use crate::color::Rgb;
use glam::Vec3;

/// Rough glass at a surface point, as seen from `wo`'s side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// GGX width; at most [`SMOOTH_ALPHA`] means smooth glass.
    pub alpha: f32,
    /// Relative index of refraction across the surface, as seen from `wo`.
    pub eta: f32,
    /// Per-channel factor on refracted light.
    pub transmittance: Rgb,
}

/// The transmission half vector of `wo` and `wi` (on opposite sides, `wi`
/// in the medium `eta` times denser), turned to the `+z` side.
fn refraction_half(wo: Vec3, wi: Vec3, eta: f32) -> Option<Vec3> {
    let h = wo + eta * wi;
    let length = h.length();
    if length <= 0.0 || !length.is_finite() {
        return None;
    }
    let h = h / length;
    Some(if h.z < 0.0 { -h } else { h })
}

impl RoughDielectric {
    /// Whether this is smooth glass (delta lobes only).
    pub fn is_smooth(&self) -> bool {
        self.alpha <= SMOOTH_ALPHA
    }

    fn ggx(&self) -> Ggx {
        Ggx { alpha: self.alpha }
    }

    /// `f · |cos θi|` for local directions, `wo.z > 0`.
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Rgb {
        if self.is_smooth() || wo.z <= 0.0 || wi.z == 0.0 {
            return Rgb::ZERO;
        }
        let ggx = self.ggx();
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let f = fresnel_dielectric(wo.dot(h), self.eta);
            let g = ggx.g1(wo, h) * ggx.g1(wi, h);
            return Rgb::splat(f * ggx.d(h) * g / (4.0 * wo.z));
        }
        let Some(m) = refraction_half(wo, wi, self.eta) else {
            return Rgb::ZERO;
        };
        let (cos_om, cos_im) = (wo.dot(m), wi.dot(m));
        if cos_om <= 0.0 || cos_im >= 0.0 {
            return Rgb::ZERO;
        }
        let f = fresnel_dielectric(cos_om, self.eta);
        let g = ggx.g1(wo, m) * ggx.g1(wi, m);
        let denominator = cos_om + self.eta * cos_im;
        let value =
            (1.0 - f) * ggx.d(m) * g * cos_om * -cos_im / (wo.z * denominator * denominator);
        let scale = match mode {
            Transport::Radiance => 1.0,
            Transport::Importance => self.eta * self.eta,
        };
        self.transmittance * (value * scale)
    }

    /// Density of sampling `wi` from `wo` (`wo.z > 0`), per solid angle.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.is_smooth() || wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let ggx = self.ggx();
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let cos_om = wo.dot(h);
            if cos_om <= 0.0 {
                return 0.0;
            }
            let f = fresnel_dielectric(cos_om, self.eta);
            return f * ggx.visible_pdf(wo, h) / (4.0 * cos_om);
        }
        let Some(m) = refraction_half(wo, wi, self.eta) else {
            return 0.0;
        };
        let (cos_om, cos_im) = (wo.dot(m), wi.dot(m));
        if cos_om <= 0.0 || cos_im >= 0.0 {
            return 0.0;
        }
        let f = fresnel_dielectric(cos_om, self.eta);
        let denominator = cos_om + self.eta * cos_im;
        let jacobian = self.eta * self.eta * -cos_im / (denominator * denominator);
        (1.0 - f) * ggx.visible_pdf(wo, m) * jacobian
    }

    /// The density of sampling `wo` from `wi`: the same surface seen from
    /// `wi`'s side (mirrored through the surface when `wi` is below it).
    pub fn reverse_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wi.z >= 0.0 {
            return self.pdf(wi, wo);
        }
        let flip = |v: Vec3| Vec3::new(v.x, v.y, -v.z);
        let seen_from_inside = RoughDielectric {
            eta: 1.0 / self.eta,
            ..*self
        };
        seen_from_inside.pdf(flip(wi), flip(wo))
    }

    /// Returns (wi, weight, pdf, delta).
    #[inline(never)]
    pub fn sample(
        &self,
        wo: Vec3,
        u: (f32, f32),
        u_lobe: f32,
        mode: Transport,
    ) -> Option<(Vec3, Rgb, f32, bool)> {
        if self.is_smooth() {
            return dielectric::sample(self.eta, self.transmittance, wo, u_lobe, mode);
        }
        if wo.z <= 0.0 {
            return None;
        }
        let ggx = self.ggx();
        let m = ggx.sample_visible(wo, u);
        let cos_om = wo.dot(m);
        if cos_om <= 0.0 {
            return None;
        }
        let visible = ggx.visible_pdf(wo, m);
        let f = fresnel_dielectric(cos_om, self.eta);
        if u_lobe < f {
            let wi = reflect(wo, m, cos_om);
            if wi.z <= 0.0 {
                return None;
            }
            let pdf = f * visible / (4.0 * cos_om);
            // f cos / pdf = G1(wi) with the lobe chosen by Fresnel.
            return (pdf > 0.0).then(|| (wi, Rgb::splat(ggx.g1(wi, m)), pdf, false));
        }
        let wi = refract(wo, m, cos_om, self.eta);
        let cos_im = wi.dot(m);
        if wi.z >= 0.0 || cos_im >= 0.0 {
            return None;
        }
        let denominator = cos_om + self.eta * cos_im;
        let pdf = (1.0 - f) * visible * self.eta * self.eta * -cos_im / (denominator * denominator);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        let scale = match mode {
            Transport::Radiance => 1.0 / (self.eta * self.eta),
            Transport::Importance => 1.0,
        };
        Some((wi, self.transmittance * (ggx.g1(wi, m) * scale), pdf, false))
    }
}
