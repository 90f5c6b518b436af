//! Isotropic point light of radiant intensity `intensity` (W/sr).

use super::{EmissionSample, IncidentSample, LightPdfs};
use crate::color::{average, Rgb};
use crate::sampling::warp::{uniform_sphere, UNIFORM_SPHERE_PDF};
use glam::Vec3;
use std::f32::consts::PI;

/// An isotropic point light. A delta light.
#[derive(Clone, Debug)]
pub struct PointLight {
    /// Where the light is, in world space.
    pub position: Vec3,
    /// Radiant intensity (W/sr per channel), the same in every direction.
    pub intensity: Rgb,
}

impl PointLight {
    /// Emitted flux averaged over RGB: 4π · intensity.
    pub fn power(&self) -> f32 {
        4.0 * PI * average(self.intensity)
    }

    /// Light arriving at `receiver`: `value` is intensity / d², `pdf` 1. `None`
    /// when the receiver is at the light's position.
    pub fn sample_incident(&self, receiver: Vec3) -> Option<IncidentSample> {
        let to_light = self.position - receiver;
        let d2 = to_light.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let distance = d2.sqrt();
        Some(IncidentSample {
            wi: to_light / distance,
            distance,
            point: self.position,
            normal: Vec3::ZERO,
            magnitude: 0.0,
            value: self.intensity / d2,
            pdf: 1.0,
            delta: true,
        })
    }

    /// Starts a light path: uniform over the sphere of directions.
    pub fn sample_emission(&self, u_dir: (f32, f32)) -> EmissionSample {
        EmissionSample {
            origin: self.position,
            dir: uniform_sphere(u_dir.0, u_dir.1),
            value: self.intensity,
            emission_pdf: UNIFORM_SPHERE_PDF,
            direct_pdf_area: 1.0,
            cos_light: 1.0,
            normal: Vec3::ZERO,
            magnitude: 0.0,
        }
    }

    /// Densities for the light reached from a receiver `distance` away.
    pub fn pdfs_for_incident(&self, distance: f32) -> LightPdfs {
        LightPdfs {
            direct: distance * distance,
            emission: UNIFORM_SPHERE_PDF,
            cos_light: 1.0,
        }
    }
}
