//! Light tracing: paths start on lights, and every vertex that is not a delta
//! is connected to the camera and splatted into the pixel it projects to.
//! Area lights and the environment seen directly are splatted too (the
//! s = 1, t = 1 strategy), so this estimator shares no strategy with the
//! path tracer: their agreement is a real check. Point and spot lights have
//! no area and are never seen directly by the pinhole camera, in any
//! integrator.

use super::connect::{visible, CameraConnection, Endpoint};
use super::light_path::{begin_light_path, camera_splat, follow_light_walk};
use super::sink::SampleSink;
use super::walk::{light_paths_per_pass, LightStart, MergeWeights};
use crate::camera::Camera;
use crate::color::is_black;
use crate::geometry::Ray;
use crate::light::Light;
use crate::sampling::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// The light tracer and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightTracer {
    /// The most segments a path may have, the camera connection included.
    pub max_depth: u32,
}

impl LightTracer {
    /// Traces one light path and pushes its splats.
    pub fn sample(
        &self,
        scene: &Scene,
        camera: &Camera,
        sampler: &mut Sampler,
        sink: &mut SampleSink,
    ) {
        let Some((mut start, lens)) = begin_light_path(scene, camera, sampler, MergeWeights::NONE)
        else {
            return;
        };
        start.walk.weighted = false;
        let paths = light_paths_per_pass(camera);
        splat_light_point(scene, camera, lens, &start, paths, sink);
        follow_light_walk(scene, sampler, start.walk, self.max_depth, |v| {
            if let Some((c, value)) = camera_splat(scene, camera, lens, v, paths) {
                sink.emit(c.pixel, value);
                sink.record(v.length + 1, 1, c.pixel, value, 1.0);
            }
        });
    }
}

/// s = 1, t = 1: the point chosen on an area light, or the direction
/// chosen in the environment, seen by the camera.
fn splat_light_point(
    scene: &Scene,
    camera: &Camera,
    lens: Vec3,
    start: &LightStart,
    paths: f32,
    sink: &mut SampleSink,
) {
    let light = match &scene.lights[start.light] {
        Light::Area(light) => light,
        Light::Environment(_) => {
            splat_sky(scene, camera, lens, start, paths, sink);
            return;
        }
        _ => return,
    };
    let emission = &start.emission;
    let Some(c) = CameraConnection::new(camera, lens, emission.origin) else {
        return;
    };
    let le = light.emitted(c.dir_to_camera);
    let cos = c.dir_to_camera.dot(light.normal).abs();
    let light_point = Endpoint::Surface {
        position: emission.origin,
        normal: light.normal,
        magnitude: light.magnitude,
    };
    if !is_black(le) && visible(scene, light_point, Endpoint::point(lens)) {
        let value = le * cos / (start.pick * emission.direct_pdf_area);
        sink.emit(c.pixel, c.splat(value, paths));
    }
}

/// s = 1, t = 1 for the environment: the sampled direction, if the camera
/// sees the sky that way. As for an area light, but the solid-angle density
/// of the direction replaces area density × cos / distance².
fn splat_sky(
    scene: &Scene,
    camera: &Camera,
    lens: Vec3,
    start: &LightStart,
    paths: f32,
    sink: &mut SampleSink,
) {
    let to_sky = -start.emission.dir;
    // A point one unit away along the direction projects where the direction does.
    let Some(c) = CameraConnection::new(camera, lens, lens + to_sky) else {
        return;
    };
    if scene.occluded(&Ray::new(lens, to_sky)) {
        return;
    }
    // The emission sample's value is the sky's radiance along `to_sky`.
    let value = start.emission.value / (start.pick * start.emission.direct_pdf_area);
    sink.emit(c.pixel, c.splat(value, paths));
}
