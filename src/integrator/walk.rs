//! What light tracing and BDPT share: random-walk state with the MIS
//! bookkeeping of Georgiev's "Implementing Vertex Connection and Merging"
//! (2012, "the report" below), starting light paths and scattering.
//!
//! Every subpath carries three running quantities, `d_vcm`, `d_vc` and
//! `d_vm` (the report's eqs. 31–35), from which the MIS weight of any
//! connection or merge follows in constant time. BDPT runs them with vertex
//! merging switched off ([`MergeWeights::NONE`]): `d_vm` is then unused and
//! the others reduce to the report's BDPT form. Densities enter them
//! through `mis` (the power heuristic's square). Russian roulette is left out
//! of these densities on purpose: the weights are then a function of the path
//! alone, so they sum to one over all strategies whatever roulette does, and
//! roulette stays an unbiased reweighting of the throughput.

use super::mis::mis;
use super::{LIGHT_ROULETTE_START, ROULETTE_START};
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::ray::offset_origin;
use crate::geometry::SurfacePoint;
use crate::light::EmissionSample;
use crate::material::{Bsdf, BsdfSample, Transport};
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
    pub d_vm: f32,
    /// How merging enters the weights; [`MergeWeights::NONE`] for BDPT.
    pub merging: MergeWeights,
    /// False for walks from a directional or environment light: their first
    /// segment has no length.
    pub finite_start: bool,
    /// What Russian roulette multiplies the throughput by before it reads it
    /// as a survival probability: one over the starting throughput's largest
    /// channel, so a walk is judged by how much of its start it still
    /// carries. A light walk starts at emitted power over density, often in
    /// the hundreds; read raw, it would survive every bounce until that had
    /// decayed below one, and tracing twice as many segments per path as a
    /// camera walk buys little. A camera walk also multiplies in eta² at
    /// each refraction, undoing the 1/eta² its radiance throughput takes.
    pub roulette_scale: f32,
    /// Whether the walk keeps `d_vcm`, `d_vc` and `d_vm` up to date. The
    /// light tracer, which weighs its paths against no other strategy,
    /// turns it off and saves a reverse density and the divisions per bounce.
    pub weighted: bool,
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
    pub d_vm: f32,
}

impl LightVertex {
    /// The vertex of the light walk `walk` (arrived, not yet followed) at
    /// `surface`, with its BSDF and the direction `wo` back along the walk.
    #[inline(always)]
    pub fn new(surface: SurfacePoint, bsdf: Bsdf, wo: Vec3, walk: &Walk) -> LightVertex {
        LightVertex {
            surface,
            bsdf,
            wo,
            throughput: walk.throughput,
            length: walk.length,
            d_vcm: walk.d_vcm,
            d_vc: walk.d_vc,
            d_vm: walk.d_vm,
        }
    }
}

/// The two constants by which vertex merging enters the MIS quantities,
/// from η = π r² N (merging radius r, N light paths per iteration): the
/// report's η_VCM and its inverse, through the power heuristic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeWeights {
    /// mis(η): how much more likely merging makes a path than a connection.
    pub vm: f32,
    /// mis(1/η): the inverse.
    pub vc: f32,
}

impl MergeWeights {
    /// No merging: BDPT.
    pub const NONE: MergeWeights = MergeWeights { vm: 0.0, vc: 0.0 };

    /// Merging within `radius` of a vertex, among `light_paths` paths.
    /// η is kept within 1e±18, so that neither constant overflows: the
    /// weights stay a partition of one whatever the radius.
    pub fn new(radius: f32, light_paths: f32) -> MergeWeights {
        let eta = (std::f64::consts::PI * (radius as f64).powi(2) * light_paths as f64)
            .clamp(1e-18, 1e18) as f32;
        MergeWeights {
            vm: mis(eta),
            vc: mis(1.0 / eta),
        }
    }
}

impl Walk {
    /// Updates the MIS quantities for arriving at a surface at `distance`
    /// with `cos_in` between the ray and the geometric normal (report eq. 31).
    pub fn arrive(&mut self, distance: f32, cos_in: f32) {
        if !self.weighted {
            return;
        }
        if self.length > 1 || self.finite_start {
            self.d_vcm *= mis(distance * distance);
        }
        let c = mis(cos_in);
        self.d_vcm /= c;
        self.d_vc /= c;
        self.d_vm /= c;
    }

    /// Continues the walk along `sampled` (the BSDF's sample at `surface`),
    /// or ends it when there is none or Russian roulette says so, which
    /// compares `roulette`, the vertex's number for it (see
    /// `Sampler::vertex_numbers`), with the survival probability. The
    /// integrators sample the direction first and follow it after their
    /// connections at the vertex, so that the sample's chain of dependent
    /// divisions and roots can run while the connections' shadow rays are
    /// traversed, rather than after them on the way to the next closest
    /// hit: the Cornell box renders 1.07x (`pt`) and 1.05x (`lt`, `bdpt`)
    /// the samples per second with the same images (docs/benchmarks.md,
    /// "The next direction sampled before the shadow rays").
    pub fn follow(
        &mut self,
        sampled: Option<BsdfSample>,
        bsdf: &Bsdf,
        surface: &SurfacePoint,
        wo: Vec3,
        roulette: f32,
        mode: Transport,
    ) -> bool {
        let Some(s) = sampled else {
            return false;
        };
        if self.weighted {
            self.update_weights(bsdf, wo, &s, surface);
        }
        self.throughput *= s.weight;
        if mode == Transport::Radiance {
            // Undo the 1/eta² radiance takes on entering glass, as the path
            // tracer does (see `CameraPath::vertex` in pt.rs); importance
            // does not take it.
            self.roulette_scale *= s.eta * s.eta;
        }
        self.origin = offset_origin(
            surface.position,
            surface.geometric_normal,
            s.wi,
            surface.magnitude,
        );
        self.dir = s.wi;
        let roulette_start = match mode {
            Transport::Radiance => ROULETTE_START,
            Transport::Importance => LIGHT_ROULETTE_START,
        };
        if self.length >= roulette_start {
            let survive = (self.throughput.max_element() * self.roulette_scale).min(1.0);
            if roulette >= survive {
                return false;
            }
            self.throughput /= survive;
        }
        true
    }

    /// The MIS quantities after scattering into `s` (report eqs. 34–36).
    fn update_weights(&mut self, bsdf: &Bsdf, wo: Vec3, s: &BsdfSample, surface: &SurfacePoint) {
        let cos_out = s.wi.dot(surface.geometric_normal).abs();
        if s.delta {
            // A specular vertex can be neither connected nor merged at.
            let c = mis(cos_out);
            self.d_vcm = 0.0;
            self.d_vc *= c;
            self.d_vm *= c;
        } else {
            let (_, reverse_pdf) = bsdf.pdfs(wo, s.wi);
            let (scale, reverse) = (mis(cos_out / s.pdf), mis(reverse_pdf));
            // With merging off, `+ vm` adds an exact zero: BDPT's weights
            // are bit for bit those of the report's BDPT form.
            self.d_vc = scale * (self.d_vc * reverse + self.d_vcm + self.merging.vm);
            self.d_vm = scale * (self.d_vm * reverse + self.d_vcm * self.merging.vc + 1.0);
            self.d_vcm = mis(1.0 / s.pdf);
        }
    }
}

/// One over `start`'s largest channel: a walk starting there begins
/// roulette with a survival probability of one. One where that is not a
/// positive finite number: a black start ends at its first vertex anyway,
/// and an infinite one (a sample about to be discarded) must not turn the
/// survival probability into 0 × ∞ = NaN, which no roulette draw rejects.
pub fn roulette_scale(start: Rgb) -> f32 {
    let scale = 1.0 / start.max_element();
    if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
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
pub fn start_light_walk(
    scene: &Scene,
    sampler: &mut Sampler,
    merging: MergeWeights,
) -> Option<LightStart> {
    let (index, pick) = scene.light_selector.sample(sampler.next_1d())?;
    start_walk_on(scene, index, pick, sampler, merging)
}

/// The numbers of a light walk's start once its light is chosen: its
/// point's, then its direction's. BDPT's lanes draw them here too, so
/// that a start staged for SIMD draws what `start_walk_on` would.
#[inline(always)]
pub fn emission_numbers(sampler: &mut Sampler) -> ((f32, f32), (f32, f32)) {
    let u_point = sampler.next_2d();
    (u_point, sampler.next_2d())
}

/// The rest of `start_light_walk` once light `index` is chosen, with
/// probability `pick`.
pub fn start_walk_on(
    scene: &Scene,
    index: usize,
    pick: f32,
    sampler: &mut Sampler,
    merging: MergeWeights,
) -> Option<LightStart> {
    let light = &scene.lights[index];
    let (u_pos, u_dir) = emission_numbers(sampler);
    let e = light.sample_emission(u_pos, u_dir)?;
    let emission_pdf = e.emission_pdf * pick;
    let direct_pdf = e.direct_pdf_area * pick;
    let origin = if e.normal == Vec3::ZERO {
        e.origin
    } else {
        offset_origin(e.origin, e.normal, e.dir, e.magnitude)
    };
    let cos_used = if light.is_finite() { e.cos_light } else { 1.0 };
    let d_vc = if light.is_delta() {
        0.0
    } else {
        mis(cos_used / emission_pdf)
    };
    let throughput = e.value / emission_pdf;
    let walk = Walk {
        origin,
        dir: e.dir,
        throughput,
        roulette_scale: roulette_scale(throughput),
        length: 1,
        d_vcm: mis(direct_pdf / emission_pdf),
        d_vc,
        d_vm: d_vc * merging.vc,
        merging,
        finite_start: light.is_finite(),
        weighted: true,
    };
    Some(LightStart {
        walk,
        light: index,
        emission: e,
        pick,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roulette_scale_brings_the_largest_channel_to_one() {
        let start = Rgb::new(250.0, 120.0, 40.0);
        assert_eq!(start.max_element() * roulette_scale(start), 1.0);
        assert_eq!(roulette_scale(Rgb::new(0.5, 0.25, 0.0)), 2.0);
        // No finite positive maximum: roulette reads the throughput raw.
        assert_eq!(roulette_scale(Rgb::ZERO), 1.0);
        assert_eq!(roulette_scale(Rgb::new(1e-45, 0.0, 0.0)), 1.0);
        assert_eq!(roulette_scale(Rgb::new(f32::INFINITY, 1.0, 1.0)), 1.0);
        assert_eq!(roulette_scale(Rgb::new(f32::NAN, 1.0, 1.0)), 1.0);
    }
}
