//! Bidirectional path tracing sixteen samples at a time, as the path tracer
//! takes its paths (`lanes.rs`): the sixteen light walks step together, their
//! rays to the next vertices traced in one call and their splats' shadow
//! rays in another; then the sixteen camera walks, each step's closest hits
//! traced together and then every lane's connections. Tracing is then work
//! on many independent rays in a row, which the processor overlaps, where
//! one sample alone waits on each ray before it can shade.
//!
//! Each sample draws the same numbers and does the same arithmetic as
//! alone ([`Bidirectional::sample`]): its estimate is the same bit for bit,
//! its strategies add up in the same order, and its splats reach the sinks
//! in the order one sample after another would emit them (a test checks
//! all three). VCM's camera paths take the same camera lanes, after the
//! iteration's light pass, each connecting to its own pixel's light path.
//!
//! BDPT's camera vertices on Lambertian surfaces are also shaded together,
//! eight lanes per SIMD operation (`bdpt_diffuse.rs`): each lane stages
//! its connections to Lambertian light vertices as pairs
//! (`bdpt_connect.rs`) and makes the others here, then one pass evaluates
//! the pairs, and another samples every staged lane's light and next
//! direction and follows its walk. The light walks' Lambertian vertices
//! are shaded likewise (`bdpt_light_diffuse.rs`), their splats and next
//! directions in one pass per step.

use super::bdpt::{camera_splat_weight, start_camera_walk, Bidirectional, CameraVertex, Share};
use super::bdpt_connect::ConnectionLanes;
use super::bdpt_diffuse::{DiffuseCameraLanes, Shares};
use super::bdpt_light_diffuse::{DiffuseLightLanes, LightStarts, SplatCamera};
use super::connect::sample_lens;
use super::light_path::{
    camera_splat_unshadowed, light_arrive, light_goes_on, light_scatter, looks_further,
};
use super::sink::SampleSink;
use super::vcm::{LightPass, VertexMerging};
use super::walk::{
    emission_numbers, light_paths_per_pass, start_walk_on, LightVertex, MergeWeights, Walk,
};
use super::PixelSample;
use crate::bvh::{for_lanes, Hit, LANES};
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::light::Light;
use crate::material::{facing_normals, Bsdf, Material};
use crate::sampling::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// What the lanes keep from sample to sample: each lane's light vertices
/// and splats, and the camera lanes' working memory.
#[derive(Default)]
pub struct LaneState {
    vertices: [Vec<LightVertex>; LANES],
    splats: [Vec<(u32, Rgb)>; LANES],
    /// The light lanes' starts and diffuse vertices, staged for their
    /// SIMD passes.
    light_starts: LightStarts,
    light_diffuse: DiffuseLightLanes,
    camera: CameraLanes,
}

/// What a step of the camera lanes fills: the shares waiting on their
/// shadow rays, the diffuse vertices staged for their SIMD pass, and the
/// connections staged for theirs. Kept from step to step, so that no
/// step allocates or clears more than it uses.
#[derive(Default)]
struct CameraLanes {
    connections: Shares,
    diffuse: DiffuseCameraLanes,
    pairs: ConnectionLanes,
}

impl Bidirectional {
    /// Samples `pixels[p].index .. + count` of each pixel `pixels[p]`:
    /// `out[p * count + i]` gets what [`Bidirectional::sample`] returns for
    /// sample `pixels[p].index + i`, and `sinks[index % 2]` the splats it
    /// pushes, in the same order. Strategies are not recorded.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub fn sample_pixels(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixels: &[PixelSample],
        count: u32,
        out: &mut [Rgb],
        sinks: &mut [SampleSink; 2],
        state: &mut LaneState,
    ) {
        in_lane_batches(pixels, count, out, |samples, out| {
            self.light_walks(scene, camera, samples, state);
            for (k, sample) in samples.iter().enumerate() {
                let sink = &mut sinks[(sample.index % 2) as usize];
                for (pixel, value) in state.splats[k].drain(..) {
                    sink.emit(pixel, value);
                }
            }
            let vertices = &state.vertices;
            let estimates = self.camera_walks::<false>(
                scene,
                camera,
                samples,
                None,
                |k| &vertices[k],
                &mut state.camera,
            );
            out.copy_from_slice(&estimates[..samples.len()]);
        });
    }

    /// The light walks of `samples`, one per lane: each lane's vertices
    /// into `state.vertices`, its splats into `state.splats` (see
    /// `Bidirectional::trace_light_path`, which this takes in lanes).
    fn light_walks(
        &self,
        scene: &Scene,
        camera: &Camera,
        samples: &[PixelSample],
        state: &mut LaneState,
    ) {
        let max_depth = self.max_depth;
        let paths = light_paths_per_pass(camera);
        let mut samplers: [Sampler; LANES] =
            std::array::from_fn(|k| samples[k.min(samples.len() - 1)].light_sampler());
        let mut walks = [IDLE; LANES];
        let mut lens = [Vec3::ZERO; LANES];
        let mut active = 0u32;
        // `begin_light_path`, its draws in its order, a start on an
        // emissive triangle staged for the SIMD pass (see
        // `bdpt_light_diffuse.rs`). Such a lane draws its lens point even
        // where the pass then finds no emission, which `begin_light_path`
        // would not: the sampler is the light walk's alone, and that walk
        // ends there, so nothing else reads it.
        let merging = MergeWeights::NONE;
        let starts = &mut state.light_starts;
        starts.clear();
        for k in 0..samples.len() {
            state.vertices[k].clear();
            let sampler = &mut samplers[k];
            sampler.start_vertex();
            let Some((index, pick)) = scene.light_selector.sample(sampler.next_1d()) else {
                continue;
            };
            if let Light::Area(light) = &scene.lights[index] {
                let numbers = emission_numbers(sampler);
                starts.stage(k, light, pick, numbers, merging);
                lens[k] = sample_lens(camera, sampler);
            } else if let Some(start) = start_walk_on(scene, index, pick, sampler, merging) {
                (walks[k], lens[k]) = (start.walk, sample_lens(camera, sampler));
                if looks_further(&walks[k], max_depth) {
                    active |= 1 << k;
                }
            }
        }
        if starts.staged() != 0 {
            starts.start();
            for_lanes(starts.staged(), |k| {
                if let Some(walk) = starts.walk(k, merging) {
                    walks[k] = walk;
                    if looks_further(&walks[k], max_depth) {
                        active |= 1 << k;
                    }
                }
            });
        }
        let unused = Ray::new(Vec3::ZERO, Vec3::Z);
        let mut rays = [unused; LANES];
        let mut hits: [Option<Hit>; LANES] = [None; LANES];
        let mut shadow_rays = [unused; LANES];
        // A lane's splat waiting on its shadow ray: at most one per step.
        let mut waiting = [(0u32, Rgb::ZERO); LANES];
        let splat_camera = SplatCamera::new(camera, paths);
        let diffuse = &mut state.light_diffuse;
        while active != 0 {
            for_lanes(active, |k| {
                rays[k] = Ray::new(walks[k].origin, walks[k].dir)
            });
            scene.intersect_lanes(&rays, active, &mut hits);
            let (mut shadowed, mut going_on) = (0u32, 0u32);
            diffuse.clear();
            for_lanes(active, |k| {
                let Some(hit) = hits[k] else {
                    return;
                };
                let (vertices, splats) = (&mut state.vertices[k], &mut state.splats[k]);
                let (walk, sampler) = (&mut walks[k], &mut samplers[k]);
                let (surface, wo, material) = light_arrive(scene, walk, &hit);
                match material {
                    // Kept for the camera walks here, shaded and splatted
                    // in `diffuse.shade` (see `bdpt_light_diffuse.rs`).
                    Material::Diffuse { albedo } if walk.weighted => {
                        let numbers =
                            light_goes_on(walk, max_depth).then(|| sampler.walk_numbers());
                        // `material.bsdf`, its reflectance looked up once.
                        let albedo = albedo.at(&surface);
                        let (shading, facing, _) = facing_normals(&surface, wo);
                        let bsdf = Bsdf::lambertian_with(albedo, shading, facing);
                        vertices.push(LightVertex::new(surface, bsdf, wo, walk));
                        diffuse.stage(k, &surface, wo, albedo, walk, lens[k], numbers);
                    }
                    _ => {
                        let mut visit = |v: &LightVertex| {
                            vertices.push(*v);
                            let Some((c, value, ray)) =
                                camera_splat_unshadowed(camera, lens[k], v, paths)
                            else {
                                return;
                            };
                            let weighted =
                                value * camera_splat_weight(&c, v, paths, MergeWeights::NONE);
                            match ray {
                                Some(ray) => {
                                    shadow_rays[k] = ray;
                                    waiting[k] = (c.pixel, weighted);
                                    shadowed |= 1 << k;
                                }
                                None => splats.push((c.pixel, weighted)),
                            }
                        };
                        let vertex = (surface, wo, material);
                        if light_scatter(sampler, walk, max_depth, vertex, &mut visit)
                            && looks_further(walk, max_depth)
                        {
                            going_on |= 1 << k;
                        }
                    }
                }
            });
            if diffuse.staged() != 0 {
                diffuse.shade(&splat_camera);
                for_lanes(diffuse.staged(), |k| {
                    if let Some((pixel, value, ray)) = diffuse.splat(k, camera.width()) {
                        match ray {
                            Some(ray) => {
                                shadow_rays[k] = ray;
                                waiting[k] = (pixel, value);
                                shadowed |= 1 << k;
                            }
                            None => state.splats[k].push((pixel, value)),
                        }
                    }
                    if diffuse.follow(k, &mut walks[k]) && looks_further(&walks[k], max_depth) {
                        going_on |= 1 << k;
                    }
                });
            }
            let blocked = scene.occluded_lanes(&shadow_rays, shadowed);
            for_lanes(shadowed & !blocked, |k| state.splats[k].push(waiting[k]));
            active = going_on;
        }
    }

    /// The camera walks of `samples`, one per lane, each connecting to its
    /// lane's light vertices (`vertices(k)` for lane k) and, for VCM
    /// (`MERGE`), merging with `merges` (see `Bidirectional::
    /// trace_camera_path`, which this takes in lanes); returns each lane's
    /// estimate.
    #[allow(clippy::too_many_arguments)]
    fn camera_walks<'a, const MERGE: bool>(
        &self,
        scene: &Scene,
        camera: &Camera,
        samples: &[PixelSample],
        merges: Option<&LightPass>,
        vertices: impl Fn(usize) -> &'a [LightVertex],
        lanes: &mut CameraLanes,
    ) -> [Rgb; LANES] {
        let CameraLanes {
            connections,
            diffuse,
            pairs,
        } = lanes;
        let merging = merges.map_or(MergeWeights::NONE, |pass| pass.merging);
        let mut results = [Rgb::ZERO; LANES];
        let mut walks = [IDLE; LANES];
        let mut pixels = [0u32; LANES];
        let mut active = 0u32;
        let mut samplers: [Sampler; LANES] =
            std::array::from_fn(|k| samples[k.min(samples.len() - 1)].camera_sampler());
        for (k, &sample) in samples.iter().enumerate() {
            // The pixel jitter comes first, as in `Bidirectional::sample`;
            // the light walk, already traced, drew from a sampler of its own.
            let jitter = samplers[k].next_2d();
            let start = start_camera_walk(camera, &mut samplers[k], sample, jitter, merging);
            if let Some((walk, pixel)) = start {
                (walks[k], pixels[k]) = (walk, pixel);
                active |= 1 << k;
            }
        }
        if !MERGE {
            pairs.begin(samples.len(), &vertices, merging.vm);
        }
        // Strategies are not recorded here: a sink that keeps none.
        let mut no_records = SampleSink::default();
        let unused = Ray::new(Vec3::ZERO, Vec3::Z);
        let mut rays = [unused; LANES];
        let mut hits: [Option<Hit>; LANES] = [None; LANES];
        while active != 0 {
            for_lanes(active, |k| {
                rays[k] = Ray::new(walks[k].origin, walks[k].dir)
            });
            scene.intersect_lanes(&rays, active, &mut hits);
            let mut going_on = 0u32;
            connections.clear();
            diffuse.clear();
            let mut most = 0;
            for_lanes(active, |k| most += vertices(k).len());
            pairs.clear(most);
            for_lanes(active, |k| {
                let at = CameraVertex {
                    scene,
                    light_vertices: vertices(k),
                    merges,
                    pixel: pixels[k],
                };
                let walk = &mut walks[k];
                let arrival =
                    self.camera_arrive(at, walk, hits[k], &mut results[k], &mut no_records);
                let Some((surface, wo, material)) = arrival else {
                    return;
                };
                let sampler = &mut samplers[k];
                match &scene.materials[material as usize] {
                    // BDPT's diffuse vertices are staged for `diffuse.shade`
                    // (see `bdpt_diffuse.rs`), their connections made here.
                    Material::Diffuse { albedo } if !MERGE => self.stage_diffuse_camera_vertex(
                        k,
                        at,
                        walk,
                        sampler,
                        (&surface, wo),
                        albedo,
                        (connections, diffuse, pairs),
                    ),
                    _ => {
                        let mut wait =
                            |ray: Option<Ray>, share: Share, _: &mut Rgb, _: &mut SampleSink| {
                                connections.push((k, ray, share))
                            };
                        if self.camera_scatter::<MERGE>(
                            at,
                            walk,
                            sampler,
                            (surface, wo, material),
                            &mut results[k],
                            &mut no_records,
                            &mut wait,
                        ) {
                            going_on |= 1 << k;
                        }
                    }
                }
            });
            pairs.connect(connections);
            if diffuse.staged() != 0 {
                diffuse.shade();
                for_lanes(diffuse.staged(), |k| {
                    if let Some((slot, ray, share)) = diffuse.light_share(k, &walks[k]) {
                        connections[slot] = (k, ray, share);
                    }
                    if diffuse.follow(k, &mut walks[k]) {
                        going_on |= 1 << k;
                    }
                });
            }
            scene.shadow_run(
                connections,
                |&(_, ray, _)| ray,
                |&(k, _, share), free| share.add(free, &mut results[k], pixels[k], &mut no_records),
            );
            active = going_on;
        }
        results
    }
}

impl VertexMerging {
    /// VCM's camera paths in lanes: samples `pixels[p].index .. + count`
    /// of each pixel `pixels[p]` in the iteration whose light pass is
    /// `pass`, `out[p * count + i]` getting what `VertexMerging::sample`
    /// returns for sample `pixels[p].index + i`. Strategies are not
    /// recorded.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub fn sample_pixels(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixels: &[PixelSample],
        count: u32,
        out: &mut [Rgb],
        pass: &LightPass,
        state: &mut LaneState,
    ) {
        let bdpt = self.bdpt();
        in_lane_batches(pixels, count, out, |samples, out| {
            let estimates = bdpt.camera_walks::<true>(
                scene,
                camera,
                samples,
                Some(pass),
                |k| pass.path_of(samples[k].x, samples[k].y),
                &mut state.camera,
            );
            out.copy_from_slice(&estimates[..samples.len()]);
        });
    }
}

/// Hands `take` each run of up to `LANES` samples of `pixels`' `count`
/// samples each (samples `index .. + count` of every pixel, pixel by
/// pixel) with its slots of `out`, one per sample.
fn in_lane_batches(
    pixels: &[PixelSample],
    count: u32,
    out: &mut [Rgb],
    mut take: impl FnMut(&[PixelSample], &mut [Rgb]),
) {
    let count = count as usize;
    let total = pixels.len() * count;
    assert_eq!(out.len(), total, "one slot per sample");
    for (batch, out) in out.chunks_mut(LANES).enumerate() {
        let first = batch * LANES;
        let samples: [PixelSample; LANES] = std::array::from_fn(|k| {
            let slot = first + k.min(out.len() - 1);
            let pixel = pixels[slot / count];
            pixel.with_index(pixel.index + (slot % count) as u64)
        });
        take(&samples[..out.len()], out);
    }
}

/// A lane's walk before it has one; never traced.
const IDLE: Walk = Walk {
    origin: Vec3::ZERO,
    dir: Vec3::Z,
    throughput: Rgb::ZERO,
    length: 0,
    d_vcm: 0.0,
    d_vc: 0.0,
    d_vm: 0.0,
    merging: MergeWeights::NONE,
    finite_start: true,
    roulette_scale: 1.0,
    weighted: true,
};
