//! Light tracing: paths start on lights, and every vertex that is not a delta
//! is connected to the camera and splatted into the pixel it projects to.
//! Area lights seen directly are splatted too (the s = 1, t = 1 strategy), so
//! this estimator shares no strategy with the path tracer: their agreement is
//! a real check. Point and spot lights have no area and are never seen
//! directly by the pinhole camera, in any integrator.

use super::subpath::{trace_light_path, SplatSink};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// Traces one light path and pushes its splats.
pub fn sample(scene: &Scene, sampler: &mut Sampler, max_depth: u32, sink: &mut SplatSink) {
    trace_light_path(scene, sampler, max_depth, true, None, sink);
}
