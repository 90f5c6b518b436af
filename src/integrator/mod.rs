//! Light transport estimators. Each takes one sample of one pixel: it
//! returns an unbiased estimate of the radiance reaching that pixel, and may
//! also splat light into other pixels through a [`SampleSink`].
//!
//! [`Integrator`] is the one interface the renderer's tile loop sees: the
//! per-sample entry point ([`Integrator::sample`]), the batch entry point
//! of an estimator that takes many pixels' samples at once in lanes
//! ([`Integrator::sample_pixels`], the path tracer's), and the few facts
//! the scheduler needs (whether samples splat, whether a pixel's noise is
//! its own). Adding an estimator means a variant here and its file beside
//! this one; `render/` never names one.

mod bdpt;
mod bdpt_connect;
mod bdpt_diffuse;
mod bdpt_lanes;
mod bdpt_light_diffuse;
mod connect;
mod lanes;
mod light_path;
mod lt;
pub mod mis;
mod pt;
mod simd;
mod sink;
mod vcm;
mod walk;

pub use bdpt::Bidirectional;
pub use lt::LightTracer;
pub use pt::PathTracer;
pub use sink::{SampleSink, StrategySample};
pub use vcm::{radius_limits, LightPass, VertexMerging, DEFAULT_RADIUS_FRACTION, RADIUS_ALPHA};

use crate::camera::Camera;
use crate::color::Rgb;
use crate::sampling::{PixelSeed, Sampler};
use crate::scene::Scene;
use crate::settings::{IntegratorKind, Settings};
use walk::LightVertex;

/// Camera paths (the path tracer's, and the camera walks of BDPT and VCM)
/// at least this many segments long are continued by Russian roulette.
/// Short paths carry most of the image and always continue, so roulette adds
/// little variance; it only trims the long tail.
pub const ROULETTE_START: u32 = 4;

/// Light walks (of LT, BDPT and VCM) are continued by Russian roulette from
/// this many segments on, sooner than camera paths. A light vertex costs
/// more than its own rays (a connection to the camera, and one from every
/// vertex of the camera walk in BDPT and VCM), and light paths in a closed
/// room run long, so ending them sooner pays for its noise: efficiency
/// (1 / (relMSE x seconds)) 1.05x (`lt`, `bdpt`) and 1.11x (`vcm`) on the
/// Cornell box, 1.14-1.16x on the caustic scene, unchanged on the open
/// dragon scene. Camera walks ending as soon cost the dragon 0.81x, and
/// the path tracer gained nothing (docs/benchmarks.md, "Roulette of light
/// walks from the second segment").
pub const LIGHT_ROULETTE_START: u32 = 2;

/// Light paths draw from a sequence of their own, independent of camera paths.
const LIGHT_SEED_DOMAIN: u64 = 0x9e37_79b9_7f4a_7c15;

/// An estimator with its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// Path tracing: next-event estimation and BSDF sampling, combined by MIS.
    Pt(PathTracer),
    /// Light tracing: light paths connected to the camera.
    Lt(LightTracer),
    /// Bidirectional path tracing: every connection strategy, MIS-weighted.
    Bdpt(Bidirectional),
    /// Vertex connection and merging: BDPT's strategies and photon merging.
    Vcm(VertexMerging),
}

/// Which sample this is: sample `index` of pixel (`x`, `y`) of a render
/// with a given seed (made by [`PixelSample::new`]). Every random number of
/// the sample follows from these, so an image is the same whichever thread
/// takes which tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSample {
    /// The camera and light paths' seeds for this pixel (see [`PixelSample::new`]).
    seeds: [PixelSeed; 2],
    /// Column, in pixels from the left of the full image.
    pub x: u32,
    /// Row, in pixels from the top of the full image.
    pub y: u32,
    /// The sample's index within the pixel (the render's sample offset included).
    pub index: u64,
}

impl PixelSample {
    /// Sample `index` of pixel (`x`, `y`) of a render with `seed`. The
    /// pixel's seeds are worked out here: make one per pixel and change
    /// `index` for its samples.
    pub fn new(x: u32, y: u32, index: u64, seed: u64) -> PixelSample {
        PixelSample {
            seeds: [
                PixelSeed::new(seed, x, y),
                PixelSeed::new(seed ^ LIGHT_SEED_DOMAIN, x, y),
            ],
            x,
            y,
            index,
        }
    }

    /// The same pixel's sample `index`.
    pub fn with_index(self, index: u64) -> PixelSample {
        PixelSample { index, ..self }
    }

    /// The random numbers of the camera path.
    pub fn camera_sampler(&self) -> Sampler {
        Sampler::for_pixel(self.seeds[0], self.index)
    }

    /// The random numbers of the light path, independent of the camera's.
    pub fn light_sampler(&self) -> Sampler {
        Sampler::for_pixel(self.seeds[1], self.index)
    }
}

/// Memory one worker thread reuses from sample to sample.
#[derive(Default)]
pub struct ThreadState {
    light_vertices: Vec<LightVertex>,
    lanes: bdpt_lanes::LaneState,
}

impl Integrator {
    /// The estimator `settings` ask for, with their path length and merging radius.
    pub fn new(settings: &Settings) -> Integrator {
        let max_depth = settings.max_depth;
        match settings.integrator {
            IntegratorKind::Pt => Integrator::Pt(PathTracer { max_depth }),
            IntegratorKind::Lt => Integrator::Lt(LightTracer { max_depth }),
            IntegratorKind::Bdpt => Integrator::Bdpt(Bidirectional { max_depth }),
            IntegratorKind::Vcm => Integrator::Vcm(VertexMerging {
                max_depth,
                radius: settings.vcm_radius,
            }),
        }
    }

    /// Which [`IntegratorKind`] this estimator is.
    pub fn kind(&self) -> IntegratorKind {
        match self {
            Integrator::Pt(_) => IntegratorKind::Pt,
            Integrator::Lt(_) => IntegratorKind::Lt,
            Integrator::Bdpt(_) => IntegratorKind::Bdpt,
            Integrator::Vcm(_) => IntegratorKind::Vcm,
        }
    }

    /// Whether samples add light to pixels other than their own: the
    /// renderer then traces every pixel's paths even for a crop, and adds
    /// the splats to the image divided by the light paths traced.
    pub fn splats(&self) -> bool {
        self.light_paths_per_sample() > 0
    }

    /// Light paths each pixel sample traces, over which the splats are
    /// averaged: one for light tracing, BDPT and VCM, none for path tracing.
    pub fn light_paths_per_sample(&self) -> u64 {
        match self {
            Integrator::Pt(_) => 0,
            Integrator::Lt(_) | Integrator::Bdpt(_) | Integrator::Vcm(_) => 1,
        }
    }

    /// Whether a pixel's own samples estimate its value, so its noise can
    /// decide when it has enough (adaptive sampling). A light tracer's
    /// paths land anywhere: none of a pixel's light is its own. VCM's
    /// iteration traces every pixel's light path before any camera path,
    /// so a pixel cannot stop on its own.
    pub fn supports_adaptive(&self) -> bool {
        matches!(self, Integrator::Pt(_) | Integrator::Bdpt(_))
    }

    /// Whether each sample index is an iteration that starts with a light
    /// pass over the whole image ([`Integrator::light_pass`]), whose
    /// result every camera sample of that index reads (VCM).
    pub fn has_light_pass(&self) -> bool {
        matches!(self, Integrator::Vcm(_))
    }

    /// The light pass of sample `index` (see [`Integrator::has_light_pass`]),
    /// run on the current rayon pool; `None` for estimators without one.
    /// `previous`, a pass no longer needed, lends its buffers.
    pub fn light_pass(
        &self,
        scene: &Scene,
        camera: &Camera,
        seed: u64,
        index: u64,
        previous: Option<LightPass>,
    ) -> Option<LightPass> {
        match self {
            Integrator::Vcm(vcm) => Some(vcm.light_pass(scene, camera, seed, index, previous)),
            _ => None,
        }
    }

    /// Whether the estimator takes a tile's samples many paths at a time,
    /// through [`Integrator::sample_pixels`], rather than one by one
    /// through [`Integrator::sample`]: all but the light tracer, whose
    /// paths measured no faster in lanes.
    pub fn samples_in_lanes(&self) -> bool {
        !matches!(self, Integrator::Lt(_))
    }

    /// For an estimator that [`samples_in_lanes`](Integrator::samples_in_lanes):
    /// samples `pixels[p].index .. + count` of each pixel `pixels[p]`, the
    /// estimate of sample `pixels[p].index + i` in `out[p * count + i]`
    /// and its splats in `sinks[(pixels[p].index + i) % 2]`, the same
    /// numbers, in the same order, as [`Integrator::sample`] gives one by
    /// one. Strategies are not recorded. `light_pass` is as for
    /// [`Integrator::sample`].
    #[allow(clippy::too_many_arguments)]
    pub fn sample_pixels(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixels: &[PixelSample],
        count: u32,
        out: &mut [Rgb],
        sinks: &mut [SampleSink; 2],
        state: &mut ThreadState,
        light_pass: Option<&LightPass>,
    ) {
        match self {
            Integrator::Pt(pt) => pt.sample_pixels(scene, camera, pixels, count, out),
            Integrator::Bdpt(bdpt) => {
                let lanes = &mut state.lanes;
                bdpt.sample_pixels(scene, camera, pixels, count, out, sinks, lanes)
            }
            Integrator::Vcm(vcm) => match light_pass {
                Some(pass) => {
                    let lanes = &mut state.lanes;
                    vcm.sample_pixels(scene, camera, pixels, count, out, pass, lanes)
                }
                None => out.fill(Rgb::ZERO),
            },
            Integrator::Lt(_) => unreachable!("the light tracer takes its samples one by one"),
        }
    }

    /// Takes one sample of `pixel` through `camera`: returns the estimate
    /// for the pixel itself, and pushes splats for other pixels to `sink`.
    /// `light_pass` is the pass of the sample's index for an estimator that
    /// has one; without it, such an estimator returns zero.
    #[inline]
    pub fn sample(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixel: PixelSample,
        state: &mut ThreadState,
        sink: &mut SampleSink,
        light_pass: Option<&LightPass>,
    ) -> Rgb {
        match self {
            Integrator::Pt(pt) => pt.sample(scene, camera, pixel),
            Integrator::Lt(lt) => {
                lt.sample(scene, camera, &mut pixel.light_sampler(), sink);
                Rgb::ZERO
            }
            Integrator::Bdpt(bdpt) => bdpt.sample(scene, camera, pixel, state, sink),
            Integrator::Vcm(vcm) => light_pass.map_or(Rgb::ZERO, |pass| {
                vcm.sample(scene, camera, pixel, pass, sink)
            }),
        }
    }
}
