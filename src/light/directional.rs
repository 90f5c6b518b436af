//! Directional light: parallel light travelling along `direction`, delivering
//! `irradiance` to a surface that faces it.

use super::{EmissionSample, IncidentSample, LightPdfs};
use crate::color::{average, Rgb};
use crate::geometry::Frame;
use crate::sampling::warp::concentric_disk;
use glam::Vec3;
use std::f32::consts::PI;

/// A light at infinity: parallel rays from one direction. A delta light.
#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Unit direction the light travels in.
    pub direction: Vec3,
    /// Irradiance on a surface that faces the light (perpendicular to `direction`).
    pub irradiance: Rgb,
    /// A sphere that bounds the scene: the beam that matters is a disk of
    /// this radius, which sets the light's power and where light paths start.
    pub scene_center: Vec3,
    /// Radius of the bounding sphere around `scene_center`, in world units.
    pub scene_radius: f32,
}

impl DirectionalLight {
    /// Flux through the disk that covers the scene, averaged over RGB:
    /// π · `scene_radius`² · irradiance.
    pub fn power(&self) -> f32 {
        PI * self.scene_radius * self.scene_radius * average(self.irradiance)
    }

    /// Light arriving at `receiver`: from `-direction`, at infinite distance, with
    /// `value` = irradiance and `pdf` 1. Never fails (shadow rays decide visibility).
    pub fn sample_incident(&self, receiver: Vec3) -> IncidentSample {
        IncidentSample {
            wi: -self.direction,
            distance: f32::INFINITY,
            // Unused at an infinite distance (shadow rays go along `wi`).
            point: receiver - self.direction,
            normal: Vec3::ZERO,
            magnitude: 0.0,
            value: self.irradiance,
            pdf: 1.0,
            delta: true,
        }
    }

    /// Starts a light path: a point on the disk that covers the scene, seen
    /// along the light's direction.
    pub fn sample_emission(&self, u_pos: (f32, f32)) -> EmissionSample {
        let frame = Frame::new(self.direction);
        let d = concentric_disk(u_pos.0, u_pos.1) * self.scene_radius;
        let origin =
            self.scene_center - self.direction * self.scene_radius + frame.s * d.x + frame.t * d.y;
        EmissionSample {
            origin,
            dir: self.direction,
            value: self.irradiance,
            emission_pdf: self.disk_pdf(),
            direct_pdf_area: 1.0,
            cos_light: 1.0,
            normal: Vec3::ZERO,
            magnitude: 0.0,
        }
    }

    /// Densities for the light reached from any receiver.
    pub fn pdfs_for_incident(&self) -> LightPdfs {
        LightPdfs {
            direct: 1.0,
            emission: self.disk_pdf(),
            cos_light: 1.0,
        }
    }

    fn disk_pdf(&self) -> f32 {
        1.0 / (PI * self.scene_radius * self.scene_radius)
    }
}
