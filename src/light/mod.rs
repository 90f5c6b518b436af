//! Light sources. Point, spot and directional lights are deltas (they cannot
//! be hit by a ray); area lights are emissive triangles of the scene; the
//! environment is seen by every ray that leaves the scene.
//!
//! Each light can be sampled from a receiving point ([`Light::sample_incident`])
//! and reports its emitted power, which drives light selection ([`LightSelector`]).

mod area;
mod directional;
mod emission;
mod environment;
mod point;
mod selection;
mod spot;

pub use area::AreaLight;
pub use directional::DirectionalLight;
pub use emission::{EmissionSample, LightPdfs};
pub use environment::{EnvironmentLight, EnvironmentMap};
pub use point::PointLight;
pub use selection::LightSelector;
pub use spot::SpotLight;

use crate::color::Rgb;
use glam::Vec3;

/// A light source of the scene, indexed by [`crate::scene::Scene::lights`].
#[derive(Clone, Debug)]
pub enum Light {
    /// Isotropic point light (a delta light).
    Point(PointLight),
    /// Point light limited to a cone (a delta light).
    Spot(SpotLight),
    /// Parallel light from infinitely far away (a delta light).
    Directional(DirectionalLight),
    /// Emissive triangle: the only kind a ray can hit.
    Area(AreaLight),
    /// Light from infinitely far away in every direction: what a ray that
    /// leaves the scene sees.
    Environment(EnvironmentLight),
}

/// Light arriving at a receiving point from a sampled point on a light.
#[derive(Clone, Copy, Debug)]
pub struct IncidentSample {
    /// Unit direction from the receiver towards the light.
    pub wi: Vec3,
    /// Distance to the light point; infinite for directional and environment lights.
    pub distance: f32,
    /// The sampled point on the light (for shadow rays); for lights at an
    /// infinite distance, a point one unit along `wi`, unused.
    pub point: Vec3,
    /// The light's surface normal there; zero for lights that are not surfaces.
    pub normal: Vec3,
    /// Coordinate magnitude of the light's triangle (for ray offsets); zero if none.
    pub magnitude: f32,
    /// Radiance for area lights; for delta lights, the irradiance a surface
    /// facing the light receives (I / d² or E), so that in every case the
    /// contribution is `f · cos · value / pdf`.
    pub value: Rgb,
    /// Solid-angle density of this sample; 1 for delta lights.
    pub pdf: f32,
    /// Whether the light is a delta (point, spot, directional): `pdf` is then 1
    /// and BSDF sampling can never find it.
    pub delta: bool,
}

impl Light {
    /// Whether the light is a delta (point, spot, directional), so paths cannot
    /// hit it and only light sampling reaches it.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point(_) | Light::Spot(_) | Light::Directional(_)
        )
    }

    /// Total emitted power (flux), averaged over RGB.
    pub fn power(&self) -> f32 {
        match self {
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Directional(l) => l.power(),
            Light::Area(l) => l.power(),
            Light::Environment(l) => l.power(),
        }
    }

    /// Samples light arriving at `receiver`; `None` when this light cannot reach it.
    // Inlined, as are `Material::bsdf`, `Bsdf::sample` and `Scene::surface`:
    // called once per path vertex, each returned its result through memory
    // and paid a call's register saves; inlined, renders take 2-3% fewer
    // instructions, and the Cornell box renders 1.03-1.05x (pt) to
    // 1.06-1.08x (lt, bdpt) the samples per second (docs/benchmarks.md,
    // "Four calls inlined"). Inlining more (the sampler, the walk's scattering)
    // was no faster, or slower.
    #[inline(always)]
    pub fn sample_incident(&self, receiver: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        match self {
            Light::Point(l) => l.sample_incident(receiver),
            Light::Spot(l) => l.sample_incident(receiver),
            Light::Directional(l) => Some(l.sample_incident(receiver)),
            Light::Area(l) => l.sample_incident(receiver, u),
            Light::Environment(l) => l.sample_incident(receiver, u),
        }
    }
}
