//! Area light: one emissive triangle with constant radiance, emitting from its
//! front face (counter-clockwise winding) or from both.

use super::{EmissionSample, IncidentSample, LightPdfs};
use crate::color::{average, Rgb};
use crate::geometry::Frame;
use crate::geometry::Triangle;
use crate::sampling::warp::{cosine_hemisphere, uniform_triangle};
use glam::Vec3;
use std::f32::consts::PI;

/// An emissive triangle of the scene. Not a delta light: rays can hit it.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// The triangle, in world space.
    pub triangle: Triangle,
    /// Index of the triangle in the scene, so a ray that hits it finds this light.
    pub triangle_index: u32,
    /// Unit geometric normal (the front face).
    pub normal: Vec3,
    /// Area of the triangle, in squared world units.
    pub area: f32,
    /// Emitted radiance, the same at every point and in every direction it emits.
    pub radiance: Rgb,
    /// Whether the back face emits too; if not, only the front (counter-clockwise) face does.
    pub two_sided: bool,
    /// Coordinate magnitude of the triangle, for ray offsets.
    pub magnitude: f32,
}

impl AreaLight {
    /// The light of triangle number `triangle_index` of the scene, emitting `radiance`.
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

    /// Emitted flux averaged over RGB: π · area · radiance, doubled when two-sided.
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
    // Inlined: see `Light::sample_incident`.
    #[inline(always)]
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
    /// Density of emitting at `cos_light` from the normal: cosine-weighted,
    /// split evenly between the faces of a two-sided light.
    pub fn emission_dir_pdf(&self, cos_light: f32) -> f32 {
        let sides = if self.two_sided { 0.5 } else { 1.0 };
        sides * cos_light.abs() / PI
    }

    /// For a path that hits this light at some point, leaving it along `w`:
    /// (area density of light sampling, emission density).
    pub fn pdfs_for_hit(&self, w: Vec3) -> (f32, f32) {
        let pdf_pos = 1.0 / self.area;
        (pdf_pos, pdf_pos * self.emission_dir_pdf(w.dot(self.normal)))
    }

    /// Starts a light path: a uniform point, a cosine-weighted direction.
    pub fn sample_emission(&self, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmissionSample> {
        let (b1, b2) = uniform_triangle(u_pos.0, u_pos.1);
        let origin = self.triangle.point(b1, b2);
        let (mut u, v) = u_dir;
        let mut normal = self.normal;
        if self.two_sided {
            // Reuse the first number to choose the face, keeping it uniform.
            if u < 0.5 {
                u *= 2.0;
            } else {
                u = 2.0 * u - 1.0;
                normal = -normal;
            }
        }
        let local = cosine_hemisphere(u.min(1.0 - f32::EPSILON), v);
        let cos_light = local.z;
        if cos_light <= 0.0 {
            return None;
        }
        Some(EmissionSample {
            origin,
            dir: Frame::new(normal).to_world(local),
            value: self.radiance * cos_light,
            emission_pdf: self.emission_dir_pdf(cos_light) / self.area,
            direct_pdf_area: 1.0 / self.area,
            cos_light,
            normal: self.normal,
            magnitude: self.magnitude,
        })
    }

    /// Densities for the point reached by light sampling along `wi` (from
    /// the receiver to the light), whose solid-angle density was `pdf_solid_angle`.
    pub fn pdfs_for_incident(
        &self,
        wi: Vec3,
        light_normal: Vec3,
        pdf_solid_angle: f32,
    ) -> LightPdfs {
        let cos_light = wi.dot(light_normal).abs();
        LightPdfs {
            direct: pdf_solid_angle,
            emission: self.emission_dir_pdf(cos_light) / self.area,
            cos_light,
        }
    }
}
