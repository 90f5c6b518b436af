//! What light tracing and BDPT share: random-walk state with the MIS
//! bookkeeping of Georgiev's "Implementing Vertex Connection and Merging"
//! (2012, "the report" below), starting light paths and scattering.
//!
//! Every subpath carries two running quantities, `d_vcm` and `d_vc` (the
//! report's eqs. 31–35 with vertex merging switched off), from which the MIS
//! weight of any connection follows in constant time. Densities enter them
//! through `mis` (the power heuristic's square). Russian roulette is left out
//! of these densities on purpose: the weights are then a function of the path
//! alone, so they sum to one over all strategies whatever roulette does, and
//! roulette stays an unbiased reweighting of the throughput.

use super::mis::mis;
use super::ROULETTE_START;
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::ray::offset_origin;
use crate::geometry::SurfacePoint;
use crate::light::EmissionSample;
use crate::material::{Bsdf, Transport};
use crate::sampling::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// A random walk in progress, from the camera or from a light.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    pub origin: Vec3,
    pub dir: Vec3,
    pub throughput: Rgb,
    /// Segments from the walk's start to the vertex it is about to find.
    pub length: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
    /// False for walks from a directional or environment light: their first
    /// segment has no length.
    pub finite_start: bool,
}

/// A non-delta vertex of a light subpath, kept for connections.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub surface: SurfacePoint,
    pub bsdf: Bsdf,
    /// Unit direction towards the previous vertex (where the light came from).
    pub wo: Vec3,
    pub throughput: Rgb,
    /// Segments from the light to this vertex.
    pub length: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
}

impl Walk {
    /// Updates the MIS quantities for arriving at a surface at `distance`
    /// with `cos_in` between the ray and the geometric normal (report eq. 31).
    pub fn arrive(&mut self, distance: f32, cos_in: f32) {
        if self.length > 1 || self.finite_start {
            self.d_vcm *= mis(distance * distance);
        }
        let c = mis(cos_in);
        self.d_vcm /= c;
        self.d_vc /= c;
    }

    /// Samples the next direction at `surface`; false when the walk ends
    /// (no valid direction, or Russian roulette).
    pub fn scatter(
        &mut self,
        bsdf: &Bsdf,
        surface: &SurfacePoint,
        wo: Vec3,
        sampler: &mut Sampler,
        mode: Transport,
    ) -> bool {
        let u = sampler.next_2d();
        let u_lobe = sampler.next_1d();
        let Some(s) = bsdf.sample(wo, u, u_lobe, mode) else {
            return false;
        };
        let cos_out = s.wi.dot(surface.geometric_normal).abs();
        if s.delta {
            // Report eq. 34–35 for a specular vertex: it cannot be connected.
            self.d_vcm = 0.0;
            self.d_vc *= mis(cos_out);
        } else {
            let (_, reverse_pdf) = bsdf.pdfs(wo, s.wi);
            self.d_vc = mis(cos_out / s.pdf) * (self.d_vc * mis(reverse_pdf) + self.d_vcm);
            self.d_vcm = mis(1.0 / s.pdf);
        }
        self.throughput *= s.weight;
        self.origin = offset_origin(
            surface.position,
            surface.geometric_normal,
            s.wi,
            surface.magnitude,
        );
        self.dir = s.wi;
        if self.length >= ROULETTE_START {
            let survive = self.throughput.max_element().min(1.0);
            if sampler.next_1d() >= survive {
                return false;
            }
            self.throughput /= survive;
        }
        true
    }
}

/// Light paths per unit of samples per pixel: one per pixel.
pub fn light_paths_per_pass(camera: &Camera) -> f32 {
    (camera.width() as f32) * (camera.height() as f32)
}

/// The start of a light subpath: the walk leaving the light, which light
/// was chosen, the emission sample and the probability of choosing it.
pub struct LightStart {
    pub walk: Walk,
    pub light: usize,
    pub emission: EmissionSample,
    pub pick: f32,
}

/// Chooses a light by power and starts a walk from it (report eqs. 31–33).
pub fn start_light_walk(scene: &Scene, sampler: &mut Sampler) -> Option<LightStart> {
    let (index, pick) = scene.light_selector.sample(sampler.next_1d())?;
    let light = &scene.lights[index];
    let u_pos = sampler.next_2d();
    let u_dir = sampler.next_2d();
    let e = light.sample_emission(u_pos, u_dir)?;
    let emission_pdf = e.emission_pdf * pick;
    let direct_pdf = e.direct_pdf_area * pick;
    let origin = if e.normal == Vec3::ZERO {
        e.origin
    } else {
        offset_origin(e.origin, e.normal, e.dir, e.magnitude)
    };
    let cos_used = if light.is_finite() { e.cos_light } else { 1.0 };
    let walk = Walk {
        origin,
        dir: e.dir,
        throughput: e.value / emission_pdf,
        length: 1,
        d_vcm: mis(direct_pdf / emission_pdf),
        d_vc: if light.is_delta() {
            0.0
        } else {
            mis(cos_used / emission_pdf)
        },
        finite_start: light.is_finite(),
    };
    Some(LightStart {
        walk,
        light: index,
        emission: e,
        pick,
    })
}
