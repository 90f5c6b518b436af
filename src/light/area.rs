//! Area light: one emissive triangle with constant radiance, emitting from its
//! front face (counter-clockwise winding) or from both.

use super::IncidentSample;
use crate::color::{average, Rgb};
use crate::geometry::Triangle;
use crate::sampling::warp::uniform_triangle;
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct AreaLight {
    pub triangle: Triangle,
    /// Index of the triangle in the scene, so a ray that hits it finds this light.
    pub triangle_index: u32,
    /// Unit geometric normal (the front face).
    pub normal: Vec3,
    pub area: f32,
    pub radiance: Rgb,
    pub two_sided: bool,
    /// Coordinate magnitude of the triangle, for ray offsets.
    pub magnitude: f32,
}

impl AreaLight {
    pub fn new(
        triangle: Triangle,
        triangle_index: u32,
        radiance: Rgb,
        two_sided: bool,
    ) -> AreaLight {
        AreaLight {
            normal: triangle.normal(),
            area: triangle.area(),
            triangle,
            triangle_index,
            radiance,
            two_sided,
            magnitude: crate::geometry::ray::magnitude(&triangle.v),
        }
    }

    pub fn power(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        sides * PI * self.area * average(self.radiance)
    }

    /// Radiance leaving the light towards `w` (a direction away from its surface).
    pub fn emitted(&self, w: Vec3) -> Rgb {
        if self.two_sided || w.dot(self.normal) > 0.0 {
            self.radiance
        } else {
            Rgb::ZERO
        }
    }

    /// Solid-angle density, seen from `receiver`, of sampling `point` on this light.
    pub fn pdf_incident(&self, receiver: Vec3, point: Vec3) -> f32 {
        let to_light = point - receiver;
        let d2 = to_light.length_squared();
        let cos_light = (to_light.dot(self.normal) / d2.sqrt()).abs();
        if cos_light <= 0.0 || d2 <= 0.0 {
            return 0.0;
        }
        d2 / (cos_light * self.area)
    }

    /// A point chosen uniformly by area.
    pub fn sample_incident(&self, receiver: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        let (b1, b2) = uniform_triangle(u.0, u.1);
        let point = self.triangle.point(b1, b2);
        let to_light = point - receiver;
        let d2 = to_light.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let distance = d2.sqrt();
        let wi = to_light / distance;
        let value = self.emitted(-wi);
        let cos_light = wi.dot(self.normal).abs();
        if cos_light <= 0.0 || value == Rgb::ZERO {
            return None;
        }
        Some(IncidentSample {
            wi,
            distance,
            point,
            normal: self.normal,
            magnitude: self.magnitude,
            value,
            pdf: d2 / (cos_light * self.area),
            delta: false,
        })
    }
}
