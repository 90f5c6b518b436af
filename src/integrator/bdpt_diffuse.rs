//! BDPT's camera vertices on Lambertian surfaces, shaded eight lanes at a
//! time, as the path tracer's are (`pt/diffuse.rs`): each lane stages its
//! surface, walk and numbers, and the emissive triangle its light sample
//! chose; one SIMD pass per half of the lanes then samples the next
//! direction, evaluates the light sample (s = 1) with its weight against
//! the other strategies, and follows the walk: its MIS quantities, its
//! throughput and Russian roulette. The connections to the light
//! vertices are staged between staging and the pass, and evaluated in a
//! pass of their own (`bdpt_connect.rs`). Every operation is
//! the scalar code's (`Bidirectional::camera_vertex`, `light_sample`,
//! `Walk::follow`) in its order, so each sample stays bit for bit what it
//! is alone (`tests/it/determinism.rs`).

use super::bdpt::{light_sample, Bidirectional, CameraVertex, Share};
use super::bdpt_connect::ConnectionLanes;
use super::simd::{
    diffuse_eval, follow_weights, get3, load, set_bits, store, store3, Continued, DiffuseVertices,
    Lanes, Lanes3, StagedVertices, V3,
};
use super::walk::Walk;
use super::ROULETTE_START;
use crate::bvh::LANES;
use crate::color::Rgb;
use crate::geometry::{Ray, SurfacePoint};
use crate::light::{AreaLight, Light};
use crate::material::{facing_normals, Albedo, Bsdf};
use crate::sampling::Sampler;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};
use wide::f32x8;

/// A step's shares waiting on their shadow rays (lane, ray, share), in
/// the order they add up.
pub(super) type Shares = Vec<(usize, Option<Ray>, Share)>;

impl Bidirectional {
    /// Lane `lane`'s camera vertex on `walk` at `surface`, seen along `wo`,
    /// of a diffuse material of reflectance `albedo`, as
    /// `camera_scatter` takes it, in three parts: the light sample (s = 1)
    /// staged in `diffuse` with its place taken in `connections`, or made
    /// at once for a light other than an emissive triangle; the
    /// connections to the light vertices (`connect_diffuse`, staged in
    /// `pairs` or made at once); and the vertex staged in `diffuse` for
    /// its next direction.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn stage_diffuse_camera_vertex(
        &self,
        lane: usize,
        at: CameraVertex,
        walk: &Walk,
        sampler: &mut Sampler,
        (surface, wo): (&SurfacePoint, Vec3),
        albedo: &Albedo,
        (connections, diffuse, pairs): (&mut Shares, &mut DiffuseCameraLanes, &mut ConnectionLanes),
    ) {
        let scene = at.scene;
        // The BSDF itself only for the scalar code (lights other than
        // emissive triangles, light vertices of other materials): the
        // passes read its reflectance and normals.
        let albedo = albedo.at(surface);
        let (shading, facing, _) = facing_normals(surface, wo);
        let bsdf = || Bsdf::lambertian_with(albedo, shading, facing);
        let numbers = sampler.vertex_numbers(true);
        let (u_select, u_point) = numbers.light.expect("diffuse vertices sample lights");
        let chosen = scene.light_selector.sample(u_select);
        match chosen.and_then(|(index, pick)| match &scene.lights[index] {
            Light::Area(light) => Some((light, pick)),
            _ => None,
        }) {
            Some((light, pick)) => {
                diffuse.stage_light(lane, light, pick, u_point, connections.len());
                // Its place in the list, filled after the pass.
                let waiting = Share::light_sample(walk, Rgb::ZERO, 0.0);
                connections.push((lane, None, waiting));
            }
            None => {
                let (l, weight, ray) =
                    light_sample(scene, surface, &bsdf(), wo, walk, u_select, u_point);
                connections.push((lane, ray, Share::light_sample(walk, l, weight)));
            }
        }
        let light_vertices = at.light_vertices;
        self.connect_diffuse(
            lane,
            walk,
            (surface, (albedo, shading, facing), bsdf),
            wo,
            light_vertices,
            connections,
            pairs,
        );
        diffuse.stage(
            lane,
            surface,
            wo,
            albedo,
            walk,
            numbers.direction,
            numbers.roulette,
        );
    }
}

/// The staged inputs of a step's diffuse camera vertices, and their results.
#[derive(Default)]
pub(super) struct DiffuseCameraLanes {
    vertices: StagedVertices,
    walks: StagedWalks,
    /// Each lit lane's place in the step's list of shares, where its
    /// s = 1 share waits for the pass.
    slots: [usize; LANES],
    out: Followed,
}

/// What the SIMD pass hands back, per lane.
#[derive(Default)]
struct Followed {
    /// s = 1: the lanes whose light sample adds something, and of those
    /// the ones with a shadow ray.
    light_some: u32,
    light_ray: u32,
    light_value: Lanes3,
    light_weight: Lanes,
    ray_origin: Lanes3,
    ray_dir: Lanes3,
    ray_tmax: Lanes,
    next: FollowedWalks,
}

/// A BDPT walk's MIS quantities and roulette scale at its staged diffuse
/// vertex, lane by lane: what both walks' passes read of it.
#[derive(Default)]
pub(super) struct StagedWalks {
    roulette_scale: Lanes,
    d_vcm: Lanes,
    d_vc: Lanes,
    d_vm: Lanes,
    vm: Lanes,
    vc: Lanes,
}

impl StagedWalks {
    #[inline(always)]
    pub fn stage(&mut self, lane: usize, walk: &Walk) {
        self.roulette_scale[lane] = walk.roulette_scale;
        self.d_vcm[lane] = walk.d_vcm;
        self.d_vc[lane] = walk.d_vc;
        self.d_vm[lane] = walk.d_vm;
        self.vm[lane] = walk.merging.vm;
        self.vc[lane] = walk.merging.vc;
    }

    /// Lanes `base .. base + 8`: `d_vcm`, `d_vc` and the merging constant
    /// `vm`, which the strategies' weights at the vertex read.
    #[inline(always)]
    pub fn weights(&self, base: usize) -> (f32x8, f32x8, f32x8) {
        (
            load(&self.d_vcm, base),
            load(&self.d_vc, base),
            load(&self.vm, base),
        )
    }

    /// `Walk::follow` for lanes `base .. base + 8` after the diffuse
    /// bounce of `v`, whose sample has the weight `weight`, into `out`:
    /// the MIS quantities, the throughput, the next ray and roulette.
    #[inline(always)]
    pub fn follow(&self, v: &DiffuseVertices, weight: V3, base: usize, out: &mut FollowedWalks) {
        let (d_vcm, d_vc, vm) = self.weights(base);
        let d_vm = load(&self.d_vm, base);
        let (next_d_vcm, next_d_vc, next_d_vm) =
            follow_weights(v, (d_vcm, d_vc, d_vm), (vm, load(&self.vc, base)));
        out.next
            .store(v, weight, load(&self.roulette_scale, base), base);
        store(next_d_vcm, &mut out.d_vcm, base);
        store(next_d_vc, &mut out.d_vc, base);
        store(next_d_vm, &mut out.d_vm, base);
    }
}

/// The walks after a staged diffuse vertex, lane by lane.
#[derive(Default)]
pub(super) struct FollowedWalks {
    /// The next throughputs and rays, and which go on.
    next: Continued,
    d_vcm: Lanes,
    d_vc: Lanes,
    d_vm: Lanes,
}

impl FollowedWalks {
    /// Follows lane `lane`'s walk as `Walk::follow` would, and counts the
    /// vertex; returns whether the walk goes on.
    #[inline(always)]
    pub fn apply(&self, lane: usize, walk: &mut Walk) -> bool {
        let bit = 1u32 << lane;
        if self.next.sampled & bit == 0 {
            return false;
        }
        walk.d_vcm = self.d_vcm[lane];
        walk.d_vc = self.d_vc[lane];
        walk.d_vm = self.d_vm[lane];
        let (throughput, origin, dir) = self.next.get(lane);
        walk.throughput = throughput;
        // A diffuse bounce leaves the roulette scale as it is (it
        // multiplies by eta² = 1).
        walk.origin = origin;
        walk.dir = dir;
        if self.next.survives & bit == 0 {
            return false;
        }
        walk.length += 1;
        true
    }
}

impl DiffuseCameraLanes {
    /// Forgets the previous step's lanes.
    pub fn clear(&mut self) {
        self.vertices.clear();
    }

    /// Lanes staged this step.
    pub fn staged(&self) -> u32 {
        self.vertices.staged
    }

    /// Stages lane `lane`'s vertex at `surface` (reflectance `albedo`, seen
    /// along `wo`) on `walk`, with its numbers for the direction and for
    /// roulette.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn stage(
        &mut self,
        lane: usize,
        surface: &SurfacePoint,
        wo: Vec3,
        albedo: Rgb,
        walk: &Walk,
        direction: (f32, f32),
        roulette: f32,
    ) {
        let roulette_on = walk.length >= ROULETTE_START;
        self.vertices.stage(
            lane,
            surface,
            wo,
            albedo,
            walk.throughput,
            direction,
            roulette,
            roulette_on,
        );
        self.walks.stage(lane, walk);
    }

    /// Stages lane `lane`'s light sample: `light`, chosen with probability
    /// `pick`, and the numbers `u` of its point; its share is to go to
    /// place `slot` of the step's list.
    #[inline(always)]
    pub fn stage_light(
        &mut self,
        lane: usize,
        light: &AreaLight,
        pick: f32,
        u: (f32, f32),
        slot: usize,
    ) {
        self.vertices.lights.stage(lane, light, pick, u);
        self.slots[lane] = slot;
    }

    /// Shades every staged lane.
    pub fn shade(&mut self) {
        for base in self.vertices.halves() {
            self.shade_half(base);
        }
    }

    /// Lane `lane`'s s = 1 share and its shadow ray, where it staged a
    /// light, with the place in the list it goes to.
    #[inline(always)]
    pub fn light_share(&self, lane: usize, walk: &Walk) -> Option<(usize, Option<Ray>, Share)> {
        let bit = 1u32 << lane;
        if self.vertices.lights.lit & bit == 0 {
            return None;
        }
        let out = &self.out;
        // As `light_sample` returns it when it adds nothing.
        let (l, weight, ray) = if out.light_some & bit == 0 {
            (Rgb::ZERO, 0.0, None)
        } else {
            let ray = (out.light_ray & bit != 0).then(|| {
                Ray::segment(
                    get3(&out.ray_origin, lane),
                    get3(&out.ray_dir, lane),
                    out.ray_tmax[lane],
                )
            });
            (get3(&out.light_value, lane), out.light_weight[lane], ray)
        };
        Some((self.slots[lane], ray, Share::light_sample(walk, l, weight)))
    }

    /// Follows lane `lane`'s walk as `Walk::follow` would, and counts the
    /// vertex as `camera_vertex` does; returns whether the walk goes on.
    #[inline(always)]
    pub fn follow(&self, lane: usize, walk: &mut Walk) -> bool {
        self.out.next.apply(lane, walk)
    }

    /// The SIMD pass over lanes `base .. base + 8`.
    fn shade_half(&mut self, base: usize) {
        let (one, zero) = (f32x8::ONE, f32x8::ZERO);
        let mis = |x: f32x8| x * x;
        let v = self.vertices.vertices(base);
        let (d_vcm, d_vc, vm) = self.walks.weights(base);
        // The density of sampling `wo` back from a reflected direction
        // (`Bsdf::pdfs`' reverse density, diffuse).
        let reverse_pdf = v.wo.dot(v.frame.n).max(zero) * f32x8::splat(FRAC_1_PI);

        let lights = &self.vertices.lights;
        if (lights.lit >> base) & 0xff != 0 {
            // s = 1 (`light_sample`).
            let light = lights.sample(base, v.position, v.normal, v.magnitude);
            let (f, bsdf_pdf) = diffuse_eval(v.albedo, v.frame.n, v.ng, light.wi);
            let sides = light.two_sided.select(f32x8::splat(0.5), one);
            let emission = sides * light.cos_light.abs() / f32x8::splat(PI) / light.light_area;
            let direct = light.pdf;
            let cos_receiver = light.wi.dot(v.normal).abs();
            let w_light = mis(bsdf_pdf / (light.pick * direct));
            let w_camera = mis(emission * cos_receiver / (direct * light.cos_light))
                * (vm + d_vcm + d_vc * mis(reverse_pdf));
            let weight = one / (w_light + one + w_camera);
            let contribution = (f * light.radiance).div(light.pick * light.pdf);
            let some = light.some & !f.is_zero() & !contribution.is_zero();
            let out = &mut self.out;
            set_bits(&mut out.light_some, some, base);
            set_bits(&mut out.light_ray, light.has_ray, base);
            store3(contribution, &mut out.light_value, base);
            store(weight, &mut out.light_weight, base);
            store3(light.ray_origin, &mut out.ray_origin, base);
            store3(light.ray_dir, &mut out.ray_dir, base);
            store(light.ray_tmax, &mut out.ray_tmax, base);
        }

        // `Walk::follow`, the sample's weight the reflectance.
        self.walks.follow(&v, v.albedo, base, &mut self.out.next);
    }
}
