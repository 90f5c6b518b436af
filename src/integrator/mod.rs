//! Light transport estimators. Each takes one sample of one pixel: it
//! returns an unbiased estimate of the radiance reaching that pixel, and may
//! also splat light into other pixels through a [`SampleSink`].
//!
//! [`Integrator`] is the one interface the renderer's tile loop sees: the
//! per-sample entry point ([`Integrator::sample`]) and the few facts the
//! scheduler needs (whether samples splat, whether a pixel's noise is its
//! own). Adding an estimator means a variant here and its file beside this
//! one; `render/` never names one.

mod bdpt;
mod connect;
mod light_path;
mod lt;
pub mod mis;
mod pt;
mod sink;
mod walk;

pub use bdpt::Bidirectional;
pub use lt::LightTracer;
pub use pt::PathTracer;
pub use sink::{SampleSink, StrategySample};

use crate::camera::Camera;
use crate::color::Rgb;
use crate::sampling::{PixelSeed, Sampler};
use crate::scene::Scene;
use crate::settings::IntegratorKind;
use walk::LightVertex;

/// Paths at least this many segments long are continued by Russian roulette.
/// Short paths carry most of the image and always continue, so roulette adds
/// little variance; it only trims the long tail.
pub const ROULETTE_START: u32 = 4;

/// Light paths draw from a sequence of their own, independent of camera paths.
const LIGHT_SEED_DOMAIN: u64 = 0x9e37_79b9_7f4a_7c15;

/// An estimator with its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Path tracing: next-event estimation and BSDF sampling, combined by MIS.
    Pt(PathTracer),
    /// Light tracing: light paths connected to the camera.
    Lt(LightTracer),
    /// Bidirectional path tracing: every connection strategy, MIS-weighted.
    Bdpt(Bidirectional),
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
}

impl Integrator {
    /// The estimator of `kind` with paths of at most `max_depth` segments.
    pub fn new(kind: IntegratorKind, max_depth: u32) -> Integrator {
        match kind {
            IntegratorKind::Pt => Integrator::Pt(PathTracer { max_depth }),
            IntegratorKind::Lt => Integrator::Lt(LightTracer { max_depth }),
            IntegratorKind::Bdpt => Integrator::Bdpt(Bidirectional { max_depth }),
        }
    }

    /// Which [`IntegratorKind`] this estimator is.
    pub fn kind(&self) -> IntegratorKind {
        match self {
            Integrator::Pt(_) => IntegratorKind::Pt,
            Integrator::Lt(_) => IntegratorKind::Lt,
            Integrator::Bdpt(_) => IntegratorKind::Bdpt,
        }
    }

    /// Whether samples add light to pixels other than their own: the
    /// renderer then traces every pixel's paths even for a crop, and adds
    /// the splats to the image divided by the light paths traced.
    pub fn splats(&self) -> bool {
        self.light_paths_per_sample() > 0
    }

    /// Light paths each pixel sample traces, over which the splats are
    /// averaged: one for light tracing and BDPT, none for path tracing.
    pub fn light_paths_per_sample(&self) -> u64 {
        match self {
            Integrator::Pt(_) => 0,
            Integrator::Lt(_) | Integrator::Bdpt(_) => 1,
        }
    }

    /// Whether a pixel's own samples estimate its value, so its noise can
    /// decide when it has enough (adaptive sampling). A light tracer's
    /// paths land anywhere: none of a pixel's light is its own.
    pub fn supports_adaptive(&self) -> bool {
        !matches!(self, Integrator::Lt(_))
    }

    /// Takes one sample of `pixel` through `camera`: returns the estimate
    /// for the pixel itself, and pushes splats for other pixels to `sink`.
    #[inline]
    pub fn sample(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixel: PixelSample,
        state: &mut ThreadState,
        sink: &mut SampleSink,
    ) -> Rgb {
        match self {
            Integrator::Pt(pt) => pt.sample(scene, camera, pixel),
            Integrator::Lt(lt) => {
                lt.sample(scene, camera, &mut pixel.light_sampler(), sink);
                Rgb::ZERO
            }
            Integrator::Bdpt(bdpt) => bdpt.sample(scene, camera, pixel, state, sink),
        }
    }
}
