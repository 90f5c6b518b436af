//! Smooth dielectric: Fresnel-weighted choice between mirror reflection and
//! refraction by Snell's law.

use super::{reflect_local, refract, safe_sqrt, Transport};
use crate::color::Rgb;
use glam::Vec3;

/// Unpolarised Fresnel reflectance for light arriving at `cos_i` (> 0) from a
/// medium into one whose index is `eta` times larger.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

/// Returns (wi, weight, pdf, delta) for local `wo` with `wo.z > 0`.
pub fn sample(
    eta: f32,
    transmittance: Rgb,
    wo: Vec3,
    u_lobe: f32,
    mode: Transport,
) -> Option<(Vec3, Rgb, f32, bool)> {
    let cos_o = wo.z;
    if cos_o <= 0.0 {
        return None;
    }
    let f = fresnel_dielectric(cos_o, eta);
    if u_lobe < f {
        // Reflection with probability F: weight F / F.
        return Some((reflect_local(wo), Rgb::ONE, f, true));
    }
    let wi = refract(wo, Vec3::Z, cos_o, eta);
    // Radiance is compressed into the smaller solid angle of the denser side:
    // it scales by 1/eta² on crossing; importance does not (Veach, §5.2).
    let scale = match mode {
        Transport::Radiance => 1.0 / (eta * eta),
        Transport::Importance => 1.0,
    };
    Some((wi, transmittance * scale, 1.0 - f, true))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_known_values() {
        // Normal incidence: ((n - 1) / (n + 1))².
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        // Total internal reflection from inside glass beyond the critical angle.
        assert_eq!(fresnel_dielectric(0.3, 1.0 / 1.5), 1.0);
        // Index-matched: no reflection.
        assert!(fresnel_dielectric(0.5, 1.0).abs() < 1e-7);
    }

    #[test]
    fn refraction_obeys_snell() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        // u_lobe = 1 always refracts (F < 1 here).
        let (wi, _, _, _) = sample(1.5, Rgb::ONE, wo, 0.999_999, Transport::Radiance).unwrap();
        let sin_o = (1.0 - wo.z * wo.z).sqrt();
        let sin_i = (1.0 - wi.z * wi.z).sqrt();
        assert!(wi.z < 0.0);
        assert!((sin_o - 1.5 * sin_i).abs() < 1e-5);
        assert!(wi.x < 0.0, "refracted ray continues through the surface");
    }
}
