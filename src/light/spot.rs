//! Spot light: a point light whose intensity falls off away from its axis.
//! At angle θ from the axis the intensity is
//! `intensity × smoothstep(cos cone_angle, cos falloff_start, cos θ)`.

use super::{EmissionSample, IncidentSample, LightPdfs};
use crate::color::{average, Rgb};
use crate::geometry::Frame;
use crate::sampling::warp::{uniform_cone, uniform_cone_pdf};
use glam::Vec3;
use std::f32::consts::PI;

/// A point light that emits only within a cone around its axis. A delta light.
#[derive(Clone, Debug)]
pub struct SpotLight {
    /// Where the light is, in world space.
    pub position: Vec3,
    /// Unit axis direction.
    pub axis: Vec3,
    /// Radiant intensity (W/sr per channel) along the axis, before falloff.
    pub intensity: Rgb,
    /// Cosine of the angle from the axis to the cone's edge.
    pub cos_cone: f32,
    /// Cosine of the angle where the falloff begins (>= `cos_cone`).
    pub cos_falloff_start: f32,
}

impl SpotLight {
    /// The fraction of the axial intensity emitted at `cos_theta` from the axis.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        let (e0, e1) = (self.cos_cone, self.cos_falloff_start);
        if cos_theta < e0 {
            return 0.0;
        }
        if cos_theta >= e1 {
            return 1.0;
        }
        let x = ((cos_theta - e0) / (e1 - e0)).clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    }

    /// Exact flux: 2π ∫ falloff(cos θ) d(cos θ), which for the smoothstep ramp
    /// is the full-intensity cap plus half the ramp's width in cos θ.
    pub fn power(&self) -> f32 {
        let full = 1.0 - self.cos_falloff_start;
        let ramp = 0.5 * (self.cos_falloff_start - self.cos_cone);
        2.0 * PI * average(self.intensity) * (full + ramp)
    }

    /// Light arriving at `receiver`: `value` is intensity × falloff / d², `pdf` 1.
    /// `None` outside the cone or at the light's position.
    pub fn sample_incident(&self, receiver: Vec3) -> Option<IncidentSample> {
        let to_light = self.position - receiver;
        let d2 = to_light.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let distance = d2.sqrt();
        let wi = to_light / distance;
        let scale = self.falloff((-wi).dot(self.axis));
        if scale <= 0.0 {
            return None;
        }
        Some(IncidentSample {
            wi,
            distance,
            point: self.position,
            normal: Vec3::ZERO,
            magnitude: 0.0,
            value: self.intensity * (scale / d2),
            pdf: 1.0,
            delta: true,
        })
    }

    /// Starts a light path: uniform over the cone, weighted by the falloff.
    pub fn sample_emission(&self, u_dir: (f32, f32)) -> Option<EmissionSample> {
        let local = uniform_cone(self.cos_cone, u_dir.0, u_dir.1);
        let value = self.intensity * self.falloff(local.z);
        (value != Rgb::ZERO).then(|| EmissionSample {
            origin: self.position,
            dir: Frame::new(self.axis).to_world(local),
            value,
            emission_pdf: uniform_cone_pdf(self.cos_cone),
            direct_pdf_area: 1.0,
            cos_light: 1.0,
            normal: Vec3::ZERO,
            magnitude: 0.0,
        })
    }

    /// Densities for the light reached from a receiver `distance` away.
    pub fn pdfs_for_incident(&self, distance: f32) -> LightPdfs {
        LightPdfs {
            direct: distance * distance,
            emission: uniform_cone_pdf(self.cos_cone),
            cos_light: 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(cone: f32, start: f32) -> SpotLight {
        SpotLight {
            position: Vec3::ZERO,
            axis: Vec3::NEG_Y,
            intensity: Rgb::ONE,
            cos_cone: cone.to_radians().cos(),
            cos_falloff_start: start.to_radians().cos(),
        }
    }

    #[test]
    fn hard_edge_when_falloff_equals_cone() {
        let s = spot(30.0, 30.0);
        assert_eq!(s.falloff(29.9f32.to_radians().cos()), 1.0);
        assert_eq!(s.falloff(30.1f32.to_radians().cos()), 0.0);
    }

    #[test]
    fn power_matches_numeric_integral() {
        let s = spot(40.0, 20.0);
        let n = 100_000;
        let integral: f64 = (0..n)
            .map(|i| {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                s.falloff(c as f32) as f64 * 2.0 / n as f64
            })
            .sum();
        let expected = 2.0 * std::f64::consts::PI * integral;
        assert!((s.power() as f64 - expected).abs() < 1e-3 * expected);
    }
}
