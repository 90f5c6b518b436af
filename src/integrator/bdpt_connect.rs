//! BDPT's connections (s > 1, t > 1) between a camera vertex and a light
//! vertex that are both Lambertian, evaluated eight pairs at a time.
//!
//! While the camera lanes take their step (`bdpt_lanes.rs`), each diffuse
//! camera vertex stages one pair per light vertex it connects to, and
//! takes the pair's place in the step's list of shares; one SIMD pass then
//! evaluates every staged pair (both BSDFs, the importance-mode shading
//! correction, the cosines and the weight, eq. 45 of Georgiev's report),
//! makes its shadow ray, and fills its place. A pair with any other BSDF
//! at its light end is connected at once by the scalar code. Every
//! operation is `connect_vertices`' in its order, so each share is the
//! scalar one bit for bit, and the shares add up in the same order
//! (`tests/it/determinism.rs`).

use super::bdpt::{connect_vertices, Bidirectional, Share};
use super::bdpt_diffuse::Shares;
use super::simd::{diffuse_eval, offset_origin, shading_correction, V3};
use super::walk::{LightVertex, Walk};
use crate::bvh::LANES;
use crate::color::Rgb;
use crate::geometry::{Ray, SurfacePoint};
use crate::material::Bsdf;
use crate::sampling::warp::cosine_hemisphere_pdf;
use glam::Vec3;
use wide::f32x8;

/// Eight numbers, one per pair of a block.
type Block = [f32; 8];
/// Eight vectors, as three blocks of coordinates.
type Block3 = [Block; 3];

/// A Lambertian vertex packed as one end of a connection: three rows of
/// eight numbers, which the pass loads for eight pairs at once and
/// transposes into lanes (`f32x8::transpose`). Each camera vertex and each
/// light vertex is packed once, however many pairs it ends, and staging a
/// pair copies its two ends whole: writing them into the pass's lanes one
/// number at a time cost about three instructions a number.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
struct End([f32; 24]);

// Where each quantity sits in an `End`.
const POSITION: usize = 0;
/// The geometric normal as the surface gives it, for the ray's offset.
const NORMAL: usize = 3;
const MAGNITUDE: usize = 6;
/// The walk's part of the other end's weight: vm + d_vcm + d_vc
/// mis(reverse density of `wo`) (eq. 45).
const MIS_FACTOR: usize = 7;
/// The shading and geometric normals on the side of the vertex's `wo`.
const SHADING: usize = 8;
const FACING: usize = 11;
const ALBEDO: usize = 14;
const THROUGHPUT: usize = 17;
/// The vertex's `wo`, which the light end's shading correction reads.
const WO: usize = 20;

impl End {
    /// The vertex at `surface` with a Lambertian BSDF (its reflectance
    /// and its shading and geometric normals on the side of `wo`, see
    /// `Bsdf::lambertian`), seen along `wo`, on a walk with these MIS
    /// quantities, merging constant `vm` and throughput.
    #[inline(always)]
    fn new(
        surface: &SurfacePoint,
        (albedo, shading, facing): (Rgb, Vec3, Vec3),
        wo: Vec3,
        (vm, d_vcm, d_vc): (f32, f32, f32),
        throughput: Rgb,
    ) -> End {
        let mis = |x: f32| x * x;
        // `Bsdf::eval_pdfs`' reverse density, which is all that it reads
        // of `wo` for a Lambertian lobe.
        let reverse_pdf = cosine_hemisphere_pdf(wo.dot(shading));
        let mut end = End::default();
        let mut put = |at: usize, v: Vec3| end.0[at..at + 3].copy_from_slice(&v.to_array());
        put(POSITION, surface.position);
        put(NORMAL, surface.geometric_normal);
        put(SHADING, shading);
        put(FACING, facing);
        put(ALBEDO, albedo);
        put(THROUGHPUT, throughput);
        put(WO, wo);
        end.0[MAGNITUDE] = surface.magnitude;
        end.0[MIS_FACTOR] = vm + d_vcm + d_vc * mis(reverse_pdf);
        end
    }
}

/// Eight ends in lanes: `lanes[i]` is quantity `i` of each end.
struct EndLanes {
    lanes: [f32x8; 24],
}

impl EndLanes {
    /// The ends of eight pairs, one per lane.
    #[inline(always)]
    fn new(ends: &[End; 8]) -> EndLanes {
        let row = |i: usize, part: usize| {
            let numbers: &[f32; 8] = ends[i].0[part * 8..part * 8 + 8].try_into().unwrap();
            f32x8::new(*numbers)
        };
        let columns = |part: usize| f32x8::transpose(std::array::from_fn(|i| row(i, part)));
        let [a, b, c] = [0, 1, 2].map(columns);
        let mut lanes = [f32x8::ZERO; 24];
        lanes[..8].copy_from_slice(&a);
        lanes[8..16].copy_from_slice(&b);
        lanes[16..].copy_from_slice(&c);
        EndLanes { lanes }
    }

    #[inline(always)]
    fn get(&self, at: usize) -> f32x8 {
        self.lanes[at]
    }

    #[inline(always)]
    fn get3(&self, at: usize) -> V3 {
        V3 {
            x: self.lanes[at],
            y: self.lanes[at + 1],
            z: self.lanes[at + 2],
        }
    }
}

/// Eight staged pairs.
#[derive(Clone, Copy, Default)]
struct PairEnds {
    camera: [End; 8],
    light: [End; 8],
}

/// What the pass makes of eight pairs.
#[derive(Default)]
struct PairBlock {
    /// The share's value (throughputs times estimate) and weight.
    value: Block3,
    weight: Block,
    /// Pairs with a shadow ray, and the rays.
    has_ray: u32,
    ray_origin: Block3,
    ray_dir: Block3,
    ray_tmax: Block,
}

/// The pairs staged in a step, and their places in its list of shares.
#[derive(Default)]
pub(super) struct ConnectionLanes {
    /// Each lane's light vertices as ends (`NOT_LAMBERTIAN` where one is
    /// not): lane k's vertex i is `light_ends[light_first[k] + i]`, an
    /// index into `lights`.
    lights: Vec<End>,
    light_ends: Vec<u32>,
    light_first: [usize; LANES],
    /// The merging constant the light ends were made with.
    vm: f32,
    /// The step's staged pairs, and their places in its list of shares.
    blocks: Vec<PairEnds>,
    slots: Vec<usize>,
}

/// A light vertex that is no end of a staged pair.
const NOT_LAMBERTIAN: u32 = u32::MAX;

impl ConnectionLanes {
    /// Packs the light vertices of lanes `0..lanes` (`vertices(k)` for
    /// lane k) as ends, for camera walks of merging constant `vm`: once
    /// per batch of samples, where a light vertex may end a pair at each
    /// vertex of its sample's camera walk.
    pub fn begin<'a>(
        &mut self,
        lanes: usize,
        vertices: impl Fn(usize) -> &'a [LightVertex],
        vm: f32,
    ) {
        self.lights.clear();
        self.light_ends.clear();
        self.vm = vm;
        for k in 0..lanes {
            self.light_first[k] = self.light_ends.len();
            for v in vertices(k) {
                let weights = (vm, v.d_vcm, v.d_vc);
                let index = match v.bsdf.lambertian() {
                    Some(lobe) => {
                        let end = End::new(&v.surface, lobe, v.wo, weights, v.throughput);
                        self.lights.push(end);
                        self.lights.len() as u32 - 1
                    }
                    None => NOT_LAMBERTIAN,
                };
                self.light_ends.push(index);
            }
        }
    }

    /// Forgets the previous step's pairs, and makes room for `most` new
    /// ones: staging then never grows the blocks, a test that would
    /// otherwise stand in every pair's way.
    pub fn clear(&mut self, most: usize) {
        self.slots.clear();
        let blocks = most.div_ceil(8);
        if self.blocks.len() < blocks {
            self.blocks.resize(blocks, PairEnds::default());
        }
    }

    /// Evaluates every staged pair and fills its place in `connections`.
    pub fn connect(&mut self, connections: &mut [(usize, Option<Ray>, Share)]) {
        // A short last block computes its spare lanes from what they held
        // before, and nothing reads them.
        for (ends, slots) in self.blocks.iter().zip(self.slots.chunks(8)) {
            let camera = EndLanes::new(&ends.camera);
            let light = EndLanes::new(&ends.light);
            let block = connect_block(&camera, &light);
            for (lane, &slot) in slots.iter().enumerate() {
                let get3 = |a: &Block3| Vec3::new(a[0][lane], a[1][lane], a[2][lane]);
                let (_, ray, share) = &mut connections[slot];
                share.set_estimate(get3(&block.value), block.weight[lane]);
                *ray = (block.has_ray >> lane & 1 != 0).then(|| {
                    Ray::segment(
                        get3(&block.ray_origin),
                        get3(&block.ray_dir),
                        block.ray_tmax[lane],
                    )
                });
            }
        }
    }

    /// Stages a pair: the camera end `camera`, the light end
    /// `lights[light_index]`, and its place `slot` in the step's shares.
    #[inline(always)]
    fn stage(&mut self, camera: &End, light_index: u32, slot: usize) {
        let pair = self.slots.len();
        let block = &mut self.blocks[pair / 8];
        block.camera[pair % 8] = *camera;
        block.light[pair % 8] = self.lights[light_index as usize];
        self.slots.push(slot);
    }
}

impl Bidirectional {
    /// s > 1 at lane `lane`'s camera vertex on `walk`, at `surface` with a
    /// Lambertian BSDF (`lobe`, as `Bsdf::lambertian` gives it, and `bsdf`
    /// to make it whole), seen along `wo`: as `connect_light_vertices`
    /// (without merges), each connection's share in `connections` in the
    /// same order, those to Lambertian light vertices staged in `pairs`
    /// with their places taken. `light_vertices` are the lane's, whose
    /// ends `pairs.begin` packed.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn connect_diffuse(
        &self,
        lane: usize,
        walk: &Walk,
        (surface, lobe, bsdf): (&SurfacePoint, (Rgb, Vec3, Vec3), impl Fn() -> Bsdf),
        wo: Vec3,
        light_vertices: &[LightVertex],
        connections: &mut Shares,
        pairs: &mut ConnectionLanes,
    ) {
        let vm = walk.merging.vm;
        debug_assert_eq!(vm.to_bits(), pairs.vm.to_bits(), "light ends of another vm");
        let camera = End::new(
            surface,
            lobe,
            wo,
            (vm, walk.d_vcm, walk.d_vc),
            walk.throughput,
        );
        let first = pairs.light_first[lane];
        for (i, v) in light_vertices.iter().enumerate() {
            if v.length + 1 + walk.length > self.max_depth {
                break;
            }
            let light_index = pairs.light_ends[first + i];
            if light_index != NOT_LAMBERTIAN {
                pairs.stage(&camera, light_index, connections.len());
                let waiting = Share::connection(walk, v, Rgb::ZERO, 0.0);
                connections.push((lane, None, waiting));
            } else {
                let (l, weight, ray) = connect_vertices(surface, &bsdf(), wo, walk, v);
                connections.push((lane, ray, Share::connection(walk, v, l, weight)));
            }
        }
    }
}

/// `connect_vertices` and `Share::connection` for eight pairs, Lambertian
/// at both ends.
#[inline(always)]
fn connect_block(camera: &EndLanes, light: &EndLanes) -> PairBlock {
    let (zero, one) = (f32x8::ZERO, f32x8::ONE);
    let mis = |x: f32x8| x * x;
    let camera_normal = camera.get3(NORMAL);
    let light_normal = light.get3(NORMAL);

    let to_light = light.get3(POSITION) - camera.get3(POSITION);
    let distance2 = to_light.dot(to_light);
    let distance = distance2.sqrt();
    let dir = to_light.div(distance);
    let (camera_f, camera_pdf) = diffuse_eval(
        camera.get3(ALBEDO),
        camera.get3(SHADING),
        camera.get3(FACING),
        dir,
    );
    // The light end, for importance: its value times the shading
    // correction (`Bsdf::eval_pdfs`), where its lobe takes `-dir`.
    let back = -dir;
    let (shading, facing) = (light.get3(SHADING), light.get3(FACING));
    let (light_value, light_pdf) = diffuse_eval(light.get3(ALBEDO), shading, facing, back);
    let reflected = back.dot(facing).simd_gt(zero);
    let lobe = reflected & !(back.dot(shading).simd_gt(zero) ^ reflected);
    let light_f = V3::select(
        lobe,
        light_value.scale(shading_correction(light.get3(WO), back, shading, facing)),
        V3::zero(),
    );

    let cos_camera = dir.dot(camera_normal).abs();
    let cos_light = dir.dot(light_normal).abs();
    let camera_pdf_area = camera_pdf * cos_light / distance2;
    let light_pdf_area = light_pdf * cos_camera / distance2;
    let w_light = mis(camera_pdf_area) * light.get(MIS_FACTOR);
    let w_camera = mis(light_pdf_area) * camera.get(MIS_FACTOR);
    let weight = one / (w_light + one + w_camera);
    let contribution = (camera_f * light_f).div(distance2);
    let some = !distance2.simd_le(zero)
        & !camera_f.is_zero()
        & !light_f.is_zero()
        & !contribution.is_zero();

    // `segment_ray`: each end moved off its surface.
    let origin = offset_origin(
        camera.get3(POSITION),
        camera_normal,
        to_light,
        camera.get(MAGNITUDE),
    );
    let target = offset_origin(
        light.get3(POSITION),
        light_normal,
        -to_light,
        light.get(MAGNITUDE),
    );
    let to_target = target - origin;
    let length = to_target.dot(to_target).sqrt();
    let has_ray = some & !(length.is_nan() | length.simd_le(zero));

    let throughput = camera.get3(THROUGHPUT) * light.get3(THROUGHPUT);
    let value = throughput * V3::select(some, contribution, V3::zero());
    let three = |v: V3| [v.x, v.y, v.z].map(|c| c.to_array());
    PairBlock {
        value: three(value),
        weight: some.select(weight, zero).to_array(),
        has_ray: has_ray.to_bitmask(),
        ray_origin: three(origin),
        ray_dir: three(to_target.div(length)),
        ray_tmax: length.to_array(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::walk::MergeWeights;
    use crate::material::{Albedo, Material};
    use glam::Vec2;

    /// A deterministic spread of numbers in [0, 1).
    fn uniform(i: usize) -> f32 {
        ((i as u32).wrapping_mul(2_654_435_769) >> 8) as f32 / (1 << 24) as f32
    }

    fn direction(i: usize) -> Vec3 {
        let u = |k: usize| 2.0 * uniform(i * 3 + k) - 1.0;
        Vec3::new(u(0), u(1), u(2)).normalize()
    }

    /// A point inside a sphere, its geometric normal mostly towards the
    /// centre (so that most pairs face each other), every other time a
    /// shading normal tilted from it, and a `wo` mostly on its front.
    fn vertex(i: usize) -> (SurfacePoint, Vec3) {
        let position = 2.0 * direction(7 * i) * (0.5 + 0.5 * uniform(7 * i + 3));
        let ng = (-position.normalize() + 0.5 * direction(7 * i + 1)).normalize();
        let ns = if i.is_multiple_of(2) {
            ng
        } else {
            (ng + 0.4 * direction(7 * i + 2)).normalize()
        };
        let surface = SurfacePoint {
            position,
            geometric_normal: ng,
            shading_normal: ns,
            uv: Vec2::ZERO,
            magnitude: 2.0,
        };
        (surface, (ng + 0.8 * direction(7 * i + 4)).normalize())
    }

    #[test]
    fn staged_connections_are_the_scalar_ones_bit_for_bit() {
        let bdpt = Bidirectional { max_depth: 64 };
        let material = |i: usize| Material::Diffuse {
            albedo: Albedo::Constant(Rgb::new(0.8, 0.5 * uniform(i), 0.0)),
        };
        let mut light_vertices = Vec::new();
        for i in 0..37 {
            let (surface, wo) = vertex(1000 + i);
            // Every fifth a rough metal, which the scalar code connects.
            let light_material = if i % 5 == 4 {
                Material::Conductor {
                    alpha: 0.3,
                    eta: Rgb::new(0.2, 0.9, 1.1),
                    k: Rgb::new(3.9, 2.4, 2.2),
                    reflectance: Rgb::ONE,
                }
            } else {
                material(i)
            };
            light_vertices.push(LightVertex {
                bsdf: light_material.bsdf(&surface, wo),
                surface,
                wo,
                throughput: Rgb::new(2.0, 0.5, uniform(i)),
                length: 1 + i as u32 % 3,
                d_vcm: 20.0 * uniform(i + 50),
                d_vc: 30.0 * uniform(i + 60),
                d_vm: 0.0,
            });
        }
        let (mut connections, mut expected) = (Vec::new(), Vec::new());
        let mut pairs = ConnectionLanes::default();
        pairs.begin(5, |k| &light_vertices[7 * k..], MergeWeights::NONE.vm);
        pairs.clear(5 * light_vertices.len());
        for i in 0..5 {
            let (surface, wo) = vertex(i);
            let bsdf = material(i + 9).bsdf(&surface, wo);
            let walk = Walk {
                origin: Vec3::ZERO,
                dir: -wo,
                throughput: Rgb::new(0.3, 1.0, 0.7),
                length: 1 + i as u32,
                d_vcm: 20.0 * uniform(i + 70),
                d_vc: 30.0 * uniform(i + 80),
                d_vm: 0.0,
                merging: MergeWeights::NONE,
                finite_start: true,
                roulette_scale: 1.0,
                weighted: true,
            };
            let lights = &light_vertices[7 * i..];
            let lobe = bsdf.lambertian().expect("a Lambertian camera vertex");
            bdpt.connect_diffuse(
                i,
                &walk,
                (&surface, lobe, || bsdf),
                wo,
                lights,
                &mut connections,
                &mut pairs,
            );
            for v in lights {
                let (l, weight, ray) = connect_vertices(&surface, &bsdf, wo, &walk, v);
                expected.push((i, ray, Share::connection(&walk, v, l, weight)));
            }
        }
        pairs.connect(&mut connections);
        assert_eq!(connections.len(), expected.len());
        // Debug prints each float exactly (shortest round trip).
        assert_eq!(format!("{connections:?}"), format!("{expected:?}"));
        let some = expected.iter().filter(|(_, ray, _)| ray.is_some()).count();
        assert!(
            some > expected.len() / 3 && some < expected.len(),
            "{some} of {}",
            expected.len()
        );
    }
}
