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

use super::connect::{sample_lens, segment_ray, shadow_ray, CameraConnection, Endpoint};
use super::light_path::{begin_light_path, camera_splat, follow_light_walk};
use super::mis::mis;
use super::sink::SampleSink;
use super::vcm::LightPass;
use super::walk::{light_paths_per_pass, LightVertex, MergeWeights, Walk};
use super::{PixelSample, ThreadState};
use crate::bvh::Hit;
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
        let Some((start, lens)) = begin_light_path(scene, camera, sampler, merging) else {
            return;
        };
        let paths = light_paths_per_pass(camera);
        follow_light_walk(scene, sampler, start.walk, self.max_depth, |v| {
            keep.push(*v);
            if let Some((c, value)) = camera_splat(scene, camera, lens, v, paths) {
                let weight = camera_splat_weight(&c, v, paths, merging);
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
        let mut result = Rgb::ZERO;
        // Each connection's shadow ray is traced at once.
        let mut connect =
            |ray: Option<Ray>, share: Share, result: &mut Rgb, sink: &mut SampleSink| {
                let free = ray.is_none_or(|ray| !scene.occluded(&ray));
                share.add(free, result, pixel, sink);
            };
        loop {
            let hit = scene.intersect(&Ray::new(walk.origin, walk.dir));
            let vertex = CameraVertex {
                scene,
                light_vertices,
                merges,
                pixel,
            };
            if !self.camera_vertex::<MERGE>(
                vertex,
                &mut walk,
                sampler,
                hit,
                &mut result,
                sink,
                &mut connect,
            ) {
                return result;
            }
        }
    }

    /// The vertex of the camera subpath `walk` where its ray found `hit`
    /// (`None`: it left the scene). s = 0 goes into `result` at once; the
    /// strategies that need a shadow ray (s = 1, and a connection to each
    /// stored light vertex) go to `connect` with their ray, in order, for
    /// the caller to trace and add (see [`Share`]), and so do VCM's merges,
    /// without a ray, so that they are added after the connections whenever
    /// the caller adds those. Returns whether the walk goes on, along its
    /// next ray.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn camera_vertex<const MERGE: bool>(
        &self,
        at: CameraVertex,
        walk: &mut Walk,
        sampler: &mut Sampler,
        hit: Option<Hit>,
        result: &mut Rgb,
        sink: &mut SampleSink,
        connect: &mut impl FnMut(Option<Ray>, Share, &mut Rgb, &mut SampleSink),
    ) -> bool {
        let Some(arrival) = self.camera_arrive(at, walk, hit, result, sink) else {
            return false;
        };
        self.camera_scatter::<MERGE>(at, walk, sampler, arrival, result, sink, connect)
    }

    /// The rest of a camera vertex after `camera_arrive`: the strategies
    /// s > 0 to `connect`, and the walk followed. Returns whether it goes on.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn camera_scatter<const MERGE: bool>(
        &self,
        at: CameraVertex,
        walk: &mut Walk,
        sampler: &mut Sampler,
        (surface, wo, material): (SurfacePoint, Vec3, u32),
        result: &mut Rgb,
        sink: &mut SampleSink,
        connect: &mut impl FnMut(Option<Ray>, Share, &mut Rgb, &mut SampleSink),
    ) -> bool {
        let bsdf = at.scene.materials[material as usize].bsdf(&surface, wo);
        // The vertex's numbers (see `Sampler::vertex_numbers`), and the
        // next direction before the shadow rays (see `Walk::follow`).
        let numbers = sampler.vertex_numbers(!bsdf.is_delta());
        let sampled = bsdf.sample(wo, numbers.direction, numbers.lobe, Transport::Radiance);
        if let Some((u_select, u_point)) = numbers.light {
            // A strategy that adds nothing, or whose ray is blocked, still
            // adds the throughputs times zero: zero, unless a throughput has
            // overflowed, when it makes the sample NaN, and the renderer
            // discards it.
            let (l, weight, ray) =
                light_sample(at.scene, &surface, &bsdf, wo, walk, u_select, u_point);
            connect(ray, Share::light_sample(walk, l, weight), result, sink);
            self.connect_light_vertices::<MERGE>(
                at, walk, &surface, &bsdf, wo, result, sink, connect,
            );
        }
        if !walk.follow(
            sampled,
            &bsdf,
            &surface,
            wo,
            numbers.roulette,
            Transport::Radiance,
        ) {
            return false;
        }
        walk.length += 1;
        true
    }

    /// The first part of a camera vertex: s = 0 (the light the walk's ray
    /// found, or the sky it left for) into `result`, the walk's weights
    /// carried to the vertex; then the surface, the direction back along
    /// the ray and the material, unless the walk ends here.
    #[inline(always)]
    pub(super) fn camera_arrive(
        &self,
        at: CameraVertex,
        walk: &mut Walk,
        hit: Option<Hit>,
        result: &mut Rgb,
        sink: &mut SampleSink,
    ) -> Option<(SurfacePoint, Vec3, u32)> {
        let CameraVertex { scene, pixel, .. } = at;
        // Adds one strategy's share; `t` counts the camera's vertices, the pinhole included.
        let add = |result: &mut Rgb,
                   (unweighted, weight): Weighted,
                   s: u32,
                   t: u32,
                   sink: &mut SampleSink| {
            *result += unweighted * weight;
            sink.record(s, t, pixel, unweighted, weight);
        };
        let Some(hit) = hit else {
            if scene.environment.is_some() {
                let (le, weight) = escaped(scene, walk.dir, walk);
                add(
                    result,
                    (walk.throughput * le, weight),
                    0,
                    walk.length + 1,
                    sink,
                );
            }
            return None;
        };
        let surface = scene.surface(&hit);
        let wo = -walk.dir;
        walk.arrive(hit.t, wo.dot(surface.geometric_normal).abs());
        let shading = scene.shading[hit.triangle as usize];

        let t = walk.length + 1;
        if shading.light != NO_LIGHT {
            let (le, weight) = hit_emitter(scene, shading.light as usize, wo, walk);
            add(result, (walk.throughput * le, weight), 0, t, sink);
        }
        if walk.length >= self.max_depth {
            return None;
        }
        Some((surface, wo, shading.material))
    }

    /// s > 1 at a camera vertex: a connection to each stored light vertex
    /// the path length allows, then VCM's merges (`MERGE`), to `connect`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn connect_light_vertices<const MERGE: bool>(
        &self,
        at: CameraVertex,
        walk: &Walk,
        surface: &SurfacePoint,
        bsdf: &Bsdf,
        wo: Vec3,
        result: &mut Rgb,
        sink: &mut SampleSink,
        connect: &mut impl FnMut(Option<Ray>, Share, &mut Rgb, &mut SampleSink),
    ) {
        for v in at.light_vertices {
            if v.length + 1 + walk.length > self.max_depth {
                break;
            }
            let (l, weight, ray) = connect_vertices(surface, bsdf, wo, walk, v);
            connect(ray, Share::connection(walk, v, l, weight), result, sink);
        }
        if let Some(pass) = at.merges.filter(|_| MERGE) {
            // After the connections, whenever the caller adds them.
            let merged = walk.throughput * pass.merge(surface, bsdf, wo, walk, self.max_depth);
            connect(None, Share::merges(merged), result, sink);
        }
    }
}

/// What a camera vertex reads besides its walk: the scene, the sample's
/// light vertices, the iteration's light pass for VCM, and the pixel the
/// sample is for.
#[derive(Clone, Copy)]
pub(super) struct CameraVertex<'a> {
    pub scene: &'a Scene,
    pub light_vertices: &'a [LightVertex],
    pub merges: Option<&'a LightPass>,
    pub pixel: u32,
}

/// A strategy at a camera vertex that waits on its shadow ray: what it
/// adds if the ray is free (`value` times `weight`), and if it is blocked
/// (`blocked`, the throughputs times zero, with weight zero), as a strategy
/// of `s` light and `t` camera vertices. VCM's merges at the vertex travel
/// as a share too (see [`Share::merges`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Share {
    value: Rgb,
    weight: f32,
    blocked: Rgb,
    s: u32,
    t: u32,
    /// Whether it is one strategy's, for `--bdpt-strategies`; VCM's merges
    /// at a vertex, already weighted, are not.
    recorded: bool,
}

impl Share {
    /// s = 1 at the camera vertex of `walk`: `light_sample`'s estimate
    /// `l` with its weight, times the walk's throughput.
    #[inline(always)]
    pub(super) fn light_sample(walk: &Walk, l: Rgb, weight: f32) -> Share {
        Share {
            value: walk.throughput * l,
            weight,
            blocked: walk.throughput * Rgb::ZERO,
            s: 1,
            t: walk.length + 1,
            recorded: true,
        }
    }

    /// s > 1, t > 1: the connection of the camera vertex of `walk` to the
    /// light vertex `v`, `connect_vertices`' estimate `l` with its weight,
    /// times both subpaths' throughputs.
    #[inline(always)]
    pub(super) fn connection(walk: &Walk, v: &LightVertex, l: Rgb, weight: f32) -> Share {
        let throughput = walk.throughput * v.throughput;
        Share {
            value: throughput * l,
            weight,
            blocked: throughput * Rgb::ZERO,
            s: v.length + 1,
            t: walk.length + 1,
            recorded: true,
        }
    }

    /// Sets the estimate of a share made with a zero one (a connection
    /// evaluated in SIMD lanes after its place in the list was taken):
    /// `value` the throughputs times the estimate, with its weight.
    #[inline(always)]
    pub(super) fn set_estimate(&mut self, value: Rgb, weight: f32) {
        self.value = value;
        self.weight = weight;
    }

    /// VCM's merges at a vertex, weighted and with the throughput: they
    /// need no shadow ray, but come after the vertex's connections.
    #[inline(always)]
    fn merges(value: Rgb) -> Share {
        Share {
            value,
            weight: 1.0,
            blocked: value,
            s: 0,
            t: 0,
            recorded: false,
        }
    }

    /// Adds the share to `result` (and records it in `sink`) once its
    /// shadow ray is known to be `free` or not.
    #[inline(always)]
    pub fn add(&self, free: bool, result: &mut Rgb, pixel: u32, sink: &mut SampleSink) {
        let (unweighted, weight) = if free {
            (self.value, self.weight)
        } else {
            (self.blocked, 0.0)
        };
        *result += unweighted * weight;
        if self.recorded {
            sink.record(self.s, self.t, pixel, unweighted, weight);
        }
    }
}

/// The MIS weight of a light vertex's splat to the camera (t = 1, report eq. 44).
#[inline(always)]
pub(super) fn camera_splat_weight(
    c: &CameraConnection,
    v: &LightVertex,
    paths: f32,
    merging: MergeWeights,
) -> f32 {
    let (_, reverse_pdf) = v.bsdf.pdfs(v.wo, c.dir_to_camera);
    let cos_surface = c.dir_to_camera.dot(v.surface.geometric_normal).abs();
    let w_light = mis(c.camera_pdf_area(cos_surface) / paths)
        * (merging.vm + v.d_vcm + v.d_vc * mis(reverse_pdf));
    1.0 / (w_light + 1.0)
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
/// `u_select` chooses the light, `u_point` the point on it. Returns the
/// estimate and its weight should the shadow ray (`None`: nothing can
/// block it) be free; a sample that adds nothing has no ray.
pub(super) fn light_sample(
    scene: &Scene,
    surface: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    walk: &Walk,
    u_select: f32,
    u_point: (f32, f32),
) -> (Rgb, f32, Option<Ray>) {
    const NONE: (Rgb, f32, Option<Ray>) = (Rgb::ZERO, 0.0, None);
    let Some((index, pick)) = scene.light_selector.sample(u_select) else {
        return NONE;
    };
    let light = &scene.lights[index];
    let Some(sample) = light.sample_incident(surface.position, u_point) else {
        return NONE;
    };
    let (f, bsdf_pdf, reverse_pdf) = bsdf.eval_pdfs(wo, sample.wi, Transport::Radiance);
    if is_black(f) {
        return NONE;
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
    if is_black(contribution) {
        return NONE;
    }
    (contribution, weight, shadow_ray(surface, &sample))
}

/// s > 1, t > 1: the camera vertex joined to a stored light vertex (eq. 45).
/// Returns the contribution without the two subpaths' throughputs and its
/// weight, should the shadow ray (`None`: nothing can block it) be free;
/// a connection that adds nothing has no ray.
// Always inlined: with two camera walks (BDPT's and VCM's) calling it, the
// compiler otherwise keeps it out of line, which costs BDPT 4% (perf gate).
#[inline(always)]
pub(super) fn connect_vertices(
    surface: &SurfacePoint,
    bsdf: &Bsdf,
    wo: Vec3,
    walk: &Walk,
    v: &LightVertex,
) -> (Rgb, f32, Option<Ray>) {
    const NONE: (Rgb, f32, Option<Ray>) = (Rgb::ZERO, 0.0, None);
    let to_light = v.surface.position - surface.position;
    let distance2 = to_light.length_squared();
    if distance2 <= 0.0 {
        return NONE;
    }
    let distance = distance2.sqrt();
    let dir = to_light / distance;
    let (camera_f, camera_pdf, camera_reverse) = bsdf.eval_pdfs(wo, dir, Transport::Radiance);
    if is_black(camera_f) {
        return NONE;
    }
    let (light_f, light_pdf, light_reverse) = v.bsdf.eval_pdfs(v.wo, -dir, Transport::Importance);
    if is_black(light_f) {
        return NONE;
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
    if is_black(contribution) {
        return NONE;
    }
    let ray = segment_ray(Endpoint::surface(surface), Endpoint::surface(&v.surface));
    (contribution, weight, ray)
}
