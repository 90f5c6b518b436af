//! What light tracing and BDPT need of a light beyond [`Light::sample_incident`]:
//! starting light paths ([`Light::sample_emission`]) and the densities with
//! which each strategy could have produced a light vertex ([`LightPdfs`]).
//!
//! The conventions follow Georgiev's "Implementing Vertex Connection and
//! Merging" (2012), §5: `direct` is the density of choosing the point by
//! light sampling from a receiver, `emission` that of emitting along the
//! connecting direction (position × direction density). For delta-position
//! lights `direct` is in the report's unit (d² for point and spot lights),
//! so that ratios of the two come out right.

use super::{AreaLight, DirectionalLight, Light, PointLight};
use crate::color::Rgb;
use crate::material::Frame;
use crate::sampling::warp::{
    concentric_disk, cosine_hemisphere, uniform_sphere, UNIFORM_SPHERE_PDF,
};
use glam::Vec3;
use std::f32::consts::PI;

/// The start of a light path.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub origin: Vec3,
    pub dir: Vec3,
    /// Emitted radiance times the cosine at the light (area lights), or
    /// intensity (point, spot), or irradiance (directional).
    pub value: Rgb,
    /// Position density × direction density (directional: position only).
    pub emission_pdf: f32,
    /// Density of light sampling choosing this position, in area measure (1 for deltas).
    pub direct_pdf_area: f32,
    /// Cosine between the emitted direction and the light's normal (1 if none).
    pub cos_light: f32,
    /// The light's surface normal at `origin`, zero for lights that are not surfaces.
    pub normal: Vec3,
    /// Coordinate magnitude of the light's triangle (for ray offsets); zero if none.
    pub magnitude: f32,
}

/// Densities of the two light-side strategies for one light point and direction.
#[derive(Clone, Copy, Debug)]
pub struct LightPdfs {
    pub direct: f32,
    pub emission: f32,
    pub cos_light: f32,
}

fn uniform_cone(cos_max: f32, u: f32, v: f32) -> Vec3 {
    let z = 1.0 - u * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

impl Light {
    /// Whether the light sits at a single point (a path can never hit it).
    pub fn is_delta_position(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_))
    }

    /// Lights at infinity: the first segment of their paths has no distance.
    pub fn is_finite(&self) -> bool {
        !matches!(self, Light::Directional(_))
    }

    /// Starts a light path: a point on the light and a direction, from four
    /// uniform numbers.
    pub fn sample_emission(&self, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmissionSample> {
        match self {
            Light::Area(l) => l.sample_emission(u_pos, u_dir),
            Light::Point(PointLight {
                position,
                intensity,
            }) => Some(EmissionSample {
                origin: *position,
                dir: uniform_sphere(u_dir.0, u_dir.1),
                value: *intensity,
                emission_pdf: UNIFORM_SPHERE_PDF,
                direct_pdf_area: 1.0,
                cos_light: 1.0,
                normal: Vec3::ZERO,
                magnitude: 0.0,
            }),
            Light::Spot(l) => {
                let local = uniform_cone(l.cos_cone, u_dir.0, u_dir.1);
                let value = l.intensity * l.falloff(local.z);
                (value != Rgb::ZERO).then(|| EmissionSample {
                    origin: l.position,
                    dir: Frame::new(l.axis).to_world(local),
                    value,
                    emission_pdf: uniform_cone_pdf(l.cos_cone),
                    direct_pdf_area: 1.0,
                    cos_light: 1.0,
                    normal: Vec3::ZERO,
                    magnitude: 0.0,
                })
            }
            Light::Directional(l) => {
                let frame = Frame::new(l.direction);
                let d = concentric_disk(u_pos.0, u_pos.1) * l.scene_radius;
                let origin =
                    l.scene_center - l.direction * l.scene_radius + frame.s * d.x + frame.t * d.y;
                Some(EmissionSample {
                    origin,
                    dir: l.direction,
                    value: l.irradiance,
                    emission_pdf: 1.0 / (PI * l.scene_radius * l.scene_radius),
                    direct_pdf_area: 1.0,
                    cos_light: 1.0,
                    normal: Vec3::ZERO,
                    magnitude: 0.0,
                })
            }
        }
    }

    /// Densities for a light point reached by light sampling from a receiver
    /// at `distance` along `wi` (the direction from the receiver to the light).
    pub fn pdfs_for_incident(
        &self,
        wi: Vec3,
        distance: f32,
        light_normal: Vec3,
        area_pdf_solid_angle: f32,
    ) -> LightPdfs {
        match self {
            Light::Area(l) => {
                let cos_light = wi.dot(light_normal).abs();
                LightPdfs {
                    direct: area_pdf_solid_angle,
                    emission: l.emission_dir_pdf(cos_light) / l.area,
                    cos_light,
                }
            }
            Light::Point(_) => LightPdfs {
                direct: distance * distance,
                emission: UNIFORM_SPHERE_PDF,
                cos_light: 1.0,
            },
            Light::Spot(l) => LightPdfs {
                direct: distance * distance,
                emission: uniform_cone_pdf(l.cos_cone),
                cos_light: 1.0,
            },
            Light::Directional(DirectionalLight { scene_radius, .. }) => LightPdfs {
                direct: 1.0,
                emission: 1.0 / (PI * scene_radius * scene_radius),
                cos_light: 1.0,
            },
        }
    }
}

impl AreaLight {
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

    fn sample_emission(&self, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmissionSample> {
        let (b1, b2) = crate::sampling::warp::uniform_triangle(u_pos.0, u_pos.1);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;
    use crate::light::SpotLight;

    /// Emission samples carry power: E[value / pdf] over all directions is
    /// the light's flux, which selection by power assumes.
    #[test]
    fn emission_estimates_power() {
        let lights = [
            Light::Point(PointLight {
                position: Vec3::ZERO,
                intensity: Rgb::new(2.0, 2.0, 2.0),
            }),
            Light::Spot(SpotLight {
                position: Vec3::ZERO,
                axis: Vec3::Y,
                intensity: Rgb::ONE,
                cos_cone: 0.5,
                cos_falloff_start: 0.8,
            }),
            Light::Area(AreaLight::new(
                Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Z),
                0,
                Rgb::splat(3.0),
                true,
            )),
            Light::Directional(DirectionalLight {
                direction: Vec3::NEG_Y,
                irradiance: Rgb::ONE,
                scene_center: Vec3::ZERO,
                scene_radius: 2.0,
            }),
        ];
        for light in &lights {
            let n = 256;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let u = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    if let Some(e) = light.sample_emission(u, u) {
                        sum += (crate::color::average(e.value) / e.emission_pdf) as f64;
                    }
                }
            }
            let estimate = sum / (n * n) as f64;
            let power = light.power() as f64;
            assert!(
                (estimate - power).abs() < 0.01 * power,
                "{light:?}: {estimate} vs {power}"
            );
        }
    }
}
