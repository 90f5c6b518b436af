//! Bidirectional path tracing (Veach and Guibas 1995; Lafortune and Willems
//! 1993) with every connection strategy weighted by the power heuristic.
//!
//! Each sample traces a light subpath (splatting its t = 1 connections to the
//! camera, see `light_path.rs`) and a camera subpath, whose vertices take the
//! remaining strategies: s = 0 (the camera path hits an emitter), s = 1
//! (a point sampled on a light) and s > 1 (a connection to each stored light
//! vertex). The weights come from the running quantities of Georgiev's report
//! in constant time per connection; equation numbers below are the report's.
//!
//! A path of `k` segments is produced by every strategy with s + t − 1 = k,
//! and `max_depth` bounds k for all of them alike, so the weights of a path
//! always sum to one. Strategies a path cannot use get zero weight by
//! construction: a delta light has `d_vc = 0` (nothing can hit it), a delta
//! BSDF vertex has `d_vcm = 0` (nothing can connect to it), and the
//! light point seen directly (s = 1, t = 1) is left to s = 0.

use super::connect::{sample_lens, visible, Endpoint};
use super::light_path::{camera_splat, follow_light_walk};
use super::mis::mis;
use super::sink::SampleSink;
use super::vcm::LightPass;
use super::walk::{light_paths_per_pass, start_light_walk, LightVertex, MergeWeights, Walk};
use super::{PixelSample, ThreadState};
use crate::camera::Camera;
use crate::color::{is_black, Rgb};
use crate::geometry::{Ray, SurfacePoint};
use crate::light::Light;
use crate::material::{Bsdf, Transport};
use crate::sampling::Sampler;
use crate::scene::{Scene, NO_LIGHT};
use glam::Vec3;

/// Bidirectional path tracing and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bidirectional {
    /// The most segments a path may have, whichever strategy makes it.
    pub max_depth: u32,
}

/// A strategy's estimate on its own and its MIS weight.
type Weighted = (Rgb, f32);

const NOTHING: Weighted = (Rgb::ZERO, 0.0);

impl Bidirectional {
    /// One BDPT sample of `pixel`: returns the camera-side estimate for the
    /// pixel and pushes the light-side splats to `sink`.
    pub fn sample(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixel: PixelSample,
        state: &mut ThreadState,
        sink: &mut SampleSink,
    ) -> Rgb {
        let mut camera_sampler = pixel.camera_sampler();
        let mut light_sampler = pixel.light_sampler();
        let jitter = camera_sampler.next_2d();
        let light_vertices = &mut state.light_vertices;
        light_vertices.clear();
        self.trace_light_path::<false>(
            scene,
            camera,
            &mut light_sampler,
            MergeWeights::NONE,
            light_vertices,
            sink,
        );
        let Some((walk, index)) = start_camera_walk(
            camera,
            &mut camera_sampler,
            pixel,
            jitter,
            MergeWeights::NONE,
        ) else {
            return Rgb::ZERO;
        };
        self.trace_camera_path::<false>(
            scene,
            walk,
            &mut camera_sampler,
            light_vertices,
            None,
            index,
            sink,
        )
    }

    /// The light subpath: its vertices are kept for connections (and
    /// merges), and each is joined to the camera (t = 1, report eq. 44 for
    /// the weight).
    ///
    /// `VCM` only makes a separate copy for VCM: each copy then has one
    /// caller, and the compiler inlines BDPT's into the tile loop as it
    /// did before VCM shared the code (4% fewer instructions, perf gate).
    pub(super) fn trace_light_path<const VCM: bool>(
        &self,
        scene: &Scene,
        camera: &Camera,
        sampler: &mut Sampler,
        merging: MergeWeights,
        keep: &mut Vec<LightVertex>,
        sink: &mut SampleSink,
    ) {
        sampler.start_vertex();
        let Some(start) = start_light_walk(scene, sampler, merging) else {
            return;
        };
        let paths = light_paths_per_pass(camera);
        let lens = sample_lens(camera, sampler);
        follow_light_walk(scene, sampler, start.walk, self.max_depth, |v| {
            keep.push(*v);
            if let Some((c, value)) = camera_splat(scene, camera, lens, v, paths) {
                let (_, reverse_pdf) = v.bsdf.pdfs(v.wo, c.dir_to_camera);
                let cos_surface = c.dir_to_camera.dot(v.surface.geometric_normal).abs();
                let w_light = mis(c.camera_pdf_area(cos_surface) / paths)
                    * (merging.vm + v.d_vcm + v.d_vc * mis(reverse_pdf));
                let weight = 1.0 / (w_light + 1.0);
                sink.emit(c.pixel, value * weight);
                sink.record(v.length + 1, 1, c.pixel, value, weight);
            }
        });
    }

    /// The camera subpath from `walk`: at each vertex, the strategies with
    /// t camera vertices (s = 0, s = 1, every stored light vertex and, for
    /// VCM, merges with the iteration's light vertices nearby).
    /// `MERGE` makes the copy that merges (see `trace_light_path`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn trace_camera_path<const MERGE: bool>(
        &self,
        scene: &Scene,
        mut walk: Walk,
        sampler: &mut Sampler,
        light_vertices: &[LightVertex],
        merges: Option<&LightPass>,
        pixel: u32,
        sink: &mut SampleSink,
    ) -> Rgb {
        let max_depth = self.max_depth;
        let mut result = Rgb::ZERO;
        // Adds one strategy's share; `t` counts the camera's vertices, the pinhole included.
        let add = |result: &mut Rgb,
                   (unweighted, weight): Weighted,
                   s: u32,
                   t: u32,
                   sink: &mut SampleSink| {
            *result += unweighted * weight;
            sink.record(s, t, pixel, unweighted, weight);
        };
        loop {
            let ray = Ray::new(walk.origin, walk.dir);
            let Some(hit) = scene.intersect(&ray) else {
                if scene.environment.is_some() {
                    let (le, weight) = escaped(scene, ray.dir, &walk);
                    add(
                        &mut result,
                        (walk.throughput * le, weight),
                        0,
                        walk.length + 1,
                        sink,
                    );
                }
                break;
            };
            let surface = scene.surface(&hit);
            let wo = -ray.dir;
            walk.arrive(hit.t, wo.dot(surface.geometric_normal).abs());
            let shading = scene.shading[hit.triangle as usize];

            let t = walk.length + 1;
            if shading.light != NO_LIGHT {
                let (le, weight) = hit_emitter(scene, shading.light as usize, wo, &walk);
                add(&mut result, (walk.throughput * le, weight), 0, t, sink);
            }
            if walk.length >= max_depth {
                break;
            }
            let bsdf = scene.materials[shading.material as usize].bsdf(&surface, wo);
            // The vertex's numbers (see `Sampler::vertex_numbers`), and the
            // next direction before the shadow rays (see `Walk::follow`).
            let numbers = sampler.vertex_numbers(!bsdf.is_delta());
            let sampled = bsdf.sample(wo, numbers.direction, numbers.lobe, Transport::Radiance);
            if let Some((u_select, u_point)) = numbers.light {
                let (l, weight) =
                    light_sample(scene, &surface, &bsdf, wo, &walk, u_select, u_point);
                add(&mut result, (walk.throughput * l, weight), 1, t, sink);
                for v in light_vertices {
                    if v.length + 1 + walk.length > max_depth {
                        break;
                    }
                    let (l, weight) = connect(scene, &surface, &bsdf, wo, &walk, v);
                    let l = walk.throughput * v.throughput * l;
                    add(&mut result, (l, weight), v.length + 1, t, sink);
                }
                if let Some(pass) = merges.filter(|_| MERGE) {
                    result += walk.throughput * pass.merge(&surface, &bsdf, wo, &walk, max_depth);
                }
            }
            if !walk.follow(
                sampled,
                &bsdf,
                &surface,
                wo,
                numbers.roulette,
                Transport::Radiance,
            ) {
                break;
            }
            walk.length += 1;
        }
        result
    }
}

/// The first segment of a camera subpath through `pixel`, jittered by
/// `jitter`, and the pixel's row-major index; `None` when the camera
/// cannot have sent the ray.
pub(super) fn start_camera_walk(
    camera: &Camera,
    sampler: &mut Sampler,
    pixel: PixelSample,
    (jx, jy): (f32, f32),
    merging: MergeWeights,
) -> Option<(Walk, u32)> {
    let (x, y) = (pixel.x as f32 + jx, pixel.y as f32 + jy);
    let index = y as u32 * camera.width() + x as u32;
    let ray = camera.ray_from(sample_lens(camera, sampler), x, y);
    let camera_pdf = camera.direction_pdf(ray.dir);
    if camera_pdf <= 0.0 {
        return None;
    }
    let walk = Walk {
        origin: ray.origin,
        dir: ray.dir,
        throughput: Rgb::ONE,
        roulette_scale: 1.0,
        length: 1,
        // Eq. 31 for the camera: the light tracer's density relative to this one.
        d_vcm: mis(light_paths_per_pass(camera) / camera_pdf),
        d_vc: 0.0,
        d_vm: 0.0,
        merging,
        finite_start: true,
        weighted: true,
    };
    Some((walk, index))
}

/// s = 0: the camera path has reached an emitter (eq. 43).
fn hit_emitter(scene: &Scene, light: usize, wo: Vec3, walk: &Walk) -> Weighted {
    let Light::Area(area) = &scene.lights[light] else {
        return NOTHING;
    };
    let emitted = area.emitted(wo);
    if is_black(emitted) {
        return NOTHING;
    }
    if walk.length == 1 {
        // Seen directly: no other strategy makes this path.
        return (emitted, 1.0);
    }
    let (direct_pdf, emission_pdf) = area.pdfs_for_hit(wo);
    let pick = scene.light_selector.pmf(light);
    (
        emitted,
        camera_hit_weight(walk, pick * direct_pdf, pick * emission_pdf),
    )
}

/// The weight of s = 0 for a path whose light end has these densities
/// (light sampling; emission), the light's selection included (eq. 43).
#[inline]
fn camera_hit_weight(walk: &Walk, direct_pdf: f32, emission_pdf: f32) -> f32 {
    let w_camera = mis(direct_pdf) * walk.d_vcm + mis(emission_pdf) * walk.d_vc;
    1.0 / (1.0 + w_camera)
}

/// s = 0 for the environment: the camera path has left the scene along
/// `dir`. As eq. 43, with the environment's densities: light sampling
/// chooses a direction (solid angle), emission a direction and a point on
/// the scene's disk; the last segment has no length, so `arrive` was never
/// called for it.
#[inline(never)]
fn escaped(scene: &Scene, dir: Vec3, walk: &Walk) -> Weighted {
    let Some((index, environment)) = scene.environment() else {
        return NOTHING;
    };
    let radiance = environment.radiance(dir);
    if is_black(radiance) {
        return NOTHING;
    }
    if walk.length == 1 {
        return (radiance, 1.0);
    }
    let pick = scene.light_selector.pmf(index);
    let pdfs = environment.pdfs_for_direction(dir);
    (
        radiance,
        camera_hit_weight(walk, pick * pdfs.direct, pick * pdfs.emission),
    )
}

/// s = 1: a point chosen on a light, connected to the camera vertex (eq. 44);
/// `u_select` chooses the light, `u_point` the point on it.
fn light_sample(
    scene: &Scene,
    surface: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    walk: &Walk,
    u_select: f32,
    u_point: (f32, f32),
) -> Weighted {
    let Some((index, pick)) = scene.light_selector.sample(u_select) else {
        return NOTHING;
    };
    let light = &scene.lights[index];
    let Some(sample) = light.sample_incident(surface.position, u_point) else {
        return NOTHING;
    };
    let (f, bsdf_pdf, reverse_pdf) = bsdf.eval_pdfs(wo, sample.wi, Transport::Radiance);
    if is_black(f) {
        return NOTHING;
    }
    let pdfs = light.pdfs_for_incident(sample.wi, sample.distance, sample.normal, sample.pdf);
    // BSDF sampling can never hit a delta light.
    let bsdf_pdf = if light.is_delta() { 0.0 } else { bsdf_pdf };
    let cos_receiver = sample.wi.dot(surface.geometric_normal).abs();
    let w_light = mis(bsdf_pdf / (pick * pdfs.direct));
    let w_camera = mis(pdfs.emission * cos_receiver / (pdfs.direct * pdfs.cos_light))
        * (walk.merging.vm + walk.d_vcm + walk.d_vc * mis(reverse_pdf));
    let weight = 1.0 / (w_light + 1.0 + w_camera);
    let contribution = f * sample.value / (pick * sample.pdf);
    if is_black(contribution) || !super::connect::unoccluded(scene, surface, &sample) {
        return NOTHING;
    }
    (contribution, weight)
}

/// s > 1, t > 1: the camera vertex joined to a stored light vertex (eq. 45).
/// Returns the contribution without the two subpaths' throughputs.
// Always inlined: with two camera walks (BDPT's and VCM's) calling it, the
// compiler otherwise keeps it out of line, which costs BDPT 4% (perf gate).
#[inline(always)]
fn connect(
    scene: &Scene,
    surface: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    walk: &Walk,
    v: &LightVertex,
) -> Weighted {
    let to_light = v.surface.position - surface.position;
    let distance2 = to_light.length_squared();
    if distance2 <= 0.0 {
        return NOTHING;
    }
    let distance = distance2.sqrt();
    let dir = to_light / distance;
    let (camera_f, camera_pdf, camera_reverse) = bsdf.eval_pdfs(wo, dir, Transport::Radiance);
    if is_black(camera_f) {
        return NOTHING;
    }
    let (light_f, light_pdf, light_reverse) = v.bsdf.eval_pdfs(v.wo, -dir, Transport::Importance);
    if is_black(light_f) {
        return NOTHING;
    }
    let cos_camera = dir.dot(surface.geometric_normal).abs();
    let cos_light = dir.dot(v.surface.geometric_normal).abs();
    // Solid-angle densities turned into area densities at the other end.
    let camera_pdf_area = camera_pdf * cos_light / distance2;
    let light_pdf_area = light_pdf * cos_camera / distance2;
    let vm = walk.merging.vm;
    let w_light = mis(camera_pdf_area) * (vm + v.d_vcm + v.d_vc * mis(light_reverse));
    let w_camera = mis(light_pdf_area) * (vm + walk.d_vcm + walk.d_vc * mis(camera_reverse));
    let weight = 1.0 / (w_light + 1.0 + w_camera);
    let contribution = camera_f * light_f / distance2;
    if is_black(contribution)
        || !visible(
            scene,
            Endpoint::surface(surface),
            Endpoint::surface(&v.surface),
        )
    {
        return NOTHING;
    }
    (contribution, weight)
}
