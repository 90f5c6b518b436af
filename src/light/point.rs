//! Isotropic point light of radiant intensity `intensity` (W/sr).

use super::IncidentSample;
use crate::color::{average, Rgb};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Rgb,
}

impl PointLight {
    pub fn power(&self) -> f32 {
        4.0 * PI * average(self.intensity)
    }

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
}
