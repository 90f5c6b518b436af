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

use super::Light;
use crate::color::Rgb;
use glam::Vec3;

/// The start of a light path.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    /// Where the path starts: on the light, or for a directional or
    /// environment light on a disk just outside the scene's bounding sphere.
    pub origin: Vec3,
    /// Unit direction the path leaves in.
    pub dir: Vec3,
    /// Emitted radiance times the cosine at the light (area lights), or
    /// intensity (point, spot), or irradiance (directional), or radiance
    /// (environment).
    pub value: Rgb,
    /// Position density × direction density (directional: position only).
    pub emission_pdf: f32,
    /// Density of light sampling choosing this position, in area measure (1
    /// for deltas); for the environment, of choosing the direction, in solid angle.
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
    /// Density of light sampling choosing this point from the receiver: solid
    /// angle for area and environment lights, d² for point and spot lights,
    /// 1 for directional ones.
    pub direct: f32,
    /// Density of emitting along the connecting direction: position (area
    /// measure) × direction (solid angle); directional lights: position only.
    pub emission: f32,
    /// Cosine between the connecting direction and the light's normal; 1 for
    /// lights that are not surfaces.
    pub cos_light: f32,
}

impl Light {
    /// Whether the light sits at a single point (a path can never hit it).
    pub fn is_delta_position(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_))
    }

    /// Lights at infinity: the first segment of their paths has no distance.
    pub fn is_finite(&self) -> bool {
        !matches!(self, Light::Directional(_) | Light::Environment(_))
    }

    /// Starts a light path: a point on the light and a direction, from four
    /// uniform numbers.
    pub fn sample_emission(&self, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmissionSample> {
        match self {
            Light::Area(l) => l.sample_emission(u_pos, u_dir),
            Light::Point(l) => Some(l.sample_emission(u_dir)),
            Light::Spot(l) => l.sample_emission(u_dir),
            Light::Directional(l) => Some(l.sample_emission(u_pos)),
            Light::Environment(l) => l.sample_emission(u_pos, u_dir),
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
            Light::Area(l) => l.pdfs_for_incident(wi, light_normal, area_pdf_solid_angle),
            Light::Point(l) => l.pdfs_for_incident(distance),
            Light::Spot(l) => l.pdfs_for_incident(distance),
            Light::Directional(l) => l.pdfs_for_incident(),
            Light::Environment(l) => l.pdfs_for_direction(wi),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;
    use crate::light::{
        AreaLight, DirectionalLight, EnvironmentLight, EnvironmentMap, PointLight, SpotLight,
    };

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
            Light::Environment(EnvironmentLight::constant(
                Rgb::new(0.5, 1.0, 2.0),
                Vec3::ONE,
                3.0,
            )),
            Light::Environment(EnvironmentLight::from_map(
                std::sync::Arc::new(
                    EnvironmentMap::new(
                        16,
                        8,
                        (0..128)
                            .map(|k| {
                                Rgb::new(
                                    0.5 + (k % 16) as f32 / 16.0,
                                    1.0,
                                    0.2 + (k / 16) as f32 / 8.0,
                                )
                            })
                            .collect(),
                    )
                    .unwrap(),
                ),
                1.5,
                glam::Mat3::from_rotation_x(0.4),
                Vec3::ZERO,
                2.0,
            )),
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
