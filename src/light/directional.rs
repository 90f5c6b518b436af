//! Directional light: parallel light travelling along `direction`, delivering
//! `irradiance` to a surface that faces it.

use super::IncidentSample;
use crate::color::{average, Rgb};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Unit direction the light travels in.
    pub direction: Vec3,
    pub irradiance: Rgb,
    /// A sphere that bounds the scene: the beam that matters is a disk of
    /// this radius, which sets the light's power and where light paths start.
    pub scene_center: Vec3,
    pub scene_radius: f32,
}

impl DirectionalLight {
    pub fn power(&self) -> f32 {
        PI * self.scene_radius * self.scene_radius * average(self.irradiance)
    }

    pub fn sample_incident(&self, receiver: Vec3) -> IncidentSample {
        IncidentSample {
            wi: -self.direction,
            distance: f32::INFINITY,
            point: receiver - self.direction * f32::INFINITY,
            normal: Vec3::ZERO,
            magnitude: 0.0,
            value: self.irradiance,
            pdf: 1.0,
            delta: true,
        }
    }
}
