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

/// One end of a connection, as staged: a Lambertian vertex.
#[derive(Clone, Copy, Default)]
struct Ends {
    position: Block3,
    /// The geometric normal as the surface gives it, for the ray's offset.
    normal: Block3,
    magnitude: Block,
    /// The shading and geometric normals on the side of the vertex's `wo`.
    shading: Block3,
    facing: Block3,
    albedo: Block3,
    /// The walk's part of the other end's weight: vm + d_vcm + d_vc
    /// mis(reverse density of `wo`) (eq. 45).
    mis_factor: Block,
    throughput: Block3,
}

/// Eight staged pairs and what the pass makes of them.
#[derive(Clone, Copy, Default)]
struct PairBlock {
    camera: Ends,
    light: Ends,
    /// The light vertex's `wo`, for the shading correction.
    light_wo: Block3,
    /// The share's value (throughputs times estimate) and weight.
    value: Block3,
    weight: Block,
    /// Pairs with a shadow ray, and the rays.
    has_ray: u32,
    ray_origin: Block3,
    ray_dir: Block3,
    ray_tmax: Block,
}

/// A Lambertian vertex, ready to stage as either end of a pair.
pub(super) struct DiffuseEnd {
    position: Vec3,
    normal: Vec3,
    magnitude: f32,
    shading: Vec3,
    facing: Vec3,
    albedo: Rgb,
    mis_factor: f32,
    throughput: Rgb,
    wo: Vec3,
}

impl DiffuseEnd {
    /// The vertex at `surface` with the Lambertian `bsdf` (`None` for any
    /// other), seen along `wo`, on a walk with these MIS quantities,
    /// merging constant `vm` and throughput.
    #[inline(always)]
    fn new(
        surface: &SurfacePoint,
        bsdf: &Bsdf,
        wo: Vec3,
        (vm, d_vcm, d_vc): (f32, f32, f32),
        throughput: Rgb,
    ) -> Option<DiffuseEnd> {
        let mis = |x: f32| x * x;
        let (albedo, shading, facing) = bsdf.lambertian()?;
        // `Bsdf::eval_pdfs`' reverse density, which is all that it reads
        // of `wo` for a Lambertian lobe.
        let reverse_pdf = cosine_hemisphere_pdf(wo.dot(shading));
        Some(DiffuseEnd {
            position: surface.position,
            normal: surface.geometric_normal,
            magnitude: surface.magnitude,
            shading,
            facing,
            albedo,
            mis_factor: vm + d_vcm + d_vc * mis(reverse_pdf),
            throughput,
            wo,
        })
    }
}

impl Ends {
    #[inline(always)]
    fn set(&mut self, lane: usize, end: &DiffuseEnd) {
        let set3 = |a: &mut Block3, v: Vec3| {
            a[0][lane] = v.x;
            a[1][lane] = v.y;
            a[2][lane] = v.z;
        };
        set3(&mut self.position, end.position);
        set3(&mut self.normal, end.normal);
        self.magnitude[lane] = end.magnitude;
        set3(&mut self.shading, end.shading);
        set3(&mut self.facing, end.facing);
        set3(&mut self.albedo, end.albedo);
        self.mis_factor[lane] = end.mis_factor;
        set3(&mut self.throughput, end.throughput);
    }
}

/// The pairs staged in a step, and their places in its list of shares.
#[derive(Default)]
pub(super) struct ConnectionLanes {
    blocks: Vec<PairBlock>,
    slots: Vec<usize>,
}

impl ConnectionLanes {
    /// Forgets the previous step's pairs, and makes room for `most` new
    /// ones: staging then never grows the blocks, a test that would
    /// otherwise stand in every pair's way.
    pub fn clear(&mut self, most: usize) {
        self.slots.clear();
        let blocks = most.div_ceil(8);
        if self.blocks.len() < blocks {
            self.blocks.resize(blocks, PairBlock::default());
        }
    }

    /// Evaluates every staged pair and fills its place in `connections`.
    pub fn connect(&mut self, connections: &mut [(usize, Option<Ray>, Share)]) {
        let count = self.slots.len();
        for block in &mut self.blocks[..count.div_ceil(8)] {
            connect_block(block);
        }
        for (pair, &slot) in self.slots.iter().enumerate() {
            let (block, lane) = (&self.blocks[pair / 8], pair % 8);
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

    #[inline(always)]
    fn stage(&mut self, camera: &DiffuseEnd, light: &DiffuseEnd, slot: usize) {
        let pair = self.slots.len();
        let (block, lane) = (&mut self.blocks[pair / 8], pair % 8);
        block.camera.set(lane, camera);
        block.light.set(lane, light);
        for (axis, c) in light.wo.to_array().into_iter().enumerate() {
            block.light_wo[axis][lane] = c;
        }
        self.slots.push(slot);
    }
}

impl Bidirectional {
    /// s > 1 at lane `lane`'s camera vertex on `walk`, at `surface` with
    /// the Lambertian `bsdf`, seen along `wo`: as `connect_light_vertices`
    /// (without merges), each connection's share in `connections` in the
    /// same order, those to Lambertian light vertices staged in `pairs`
    /// with their places taken.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn connect_diffuse(
        &self,
        lane: usize,
        walk: &Walk,
        surface: &SurfacePoint,
        bsdf: &Bsdf,
        wo: Vec3,
        light_vertices: &[LightVertex],
        connections: &mut Shares,
        pairs: &mut ConnectionLanes,
    ) {
        let vm = walk.merging.vm;
        let camera = DiffuseEnd::new(
            surface,
            bsdf,
            wo,
            (vm, walk.d_vcm, walk.d_vc),
            walk.throughput,
        );
        for v in light_vertices {
            if v.length + 1 + walk.length > self.max_depth {
                break;
            }
            let light = camera.as_ref().and_then(|camera| {
                let weights = (vm, v.d_vcm, v.d_vc);
                Some((
                    camera,
                    DiffuseEnd::new(&v.surface, &v.bsdf, v.wo, weights, v.throughput)?,
                ))
            });
            if let Some((camera, light)) = light {
                pairs.stage(camera, &light, connections.len());
                let waiting = Share::connection(walk, v, Rgb::ZERO, 0.0);
                connections.push((lane, None, waiting));
            } else {
                let (l, weight, ray) = connect_vertices(surface, bsdf, wo, walk, v);
                connections.push((lane, ray, Share::connection(walk, v, l, weight)));
            }
        }
    }
}

/// `connect_vertices` and `Share::connection` for the eight pairs of
/// `block`, Lambertian at both ends.
#[inline(always)]
fn connect_block(block: &mut PairBlock) {
    let (zero, one) = (f32x8::ZERO, f32x8::ONE);
    let mis = |x: f32x8| x * x;
    let load = |a: &Block| f32x8::new(*a);
    let load3 = |a: &Block3| V3 {
        x: load(&a[0]),
        y: load(&a[1]),
        z: load(&a[2]),
    };
    let (camera, light) = (&block.camera, &block.light);
    let camera_normal = load3(&camera.normal);
    let light_normal = load3(&light.normal);

    let to_light = load3(&light.position) - load3(&camera.position);
    let distance2 = to_light.dot(to_light);
    let distance = distance2.sqrt();
    let dir = to_light.div(distance);
    let (camera_f, camera_pdf) = diffuse_eval(
        load3(&camera.albedo),
        load3(&camera.shading),
        load3(&camera.facing),
        dir,
    );
    // The light end, for importance: its value times the shading
    // correction (`Bsdf::eval_pdfs`), where its lobe takes `-dir`.
    let back = -dir;
    let (shading, facing) = (load3(&light.shading), load3(&light.facing));
    let (light_value, light_pdf) = diffuse_eval(load3(&light.albedo), shading, facing, back);
    let reflected = back.dot(facing).simd_gt(zero);
    let lobe = reflected & !(back.dot(shading).simd_gt(zero) ^ reflected);
    let light_f = V3::select(
        lobe,
        light_value.scale(shading_correction(
            load3(&block.light_wo),
            back,
            shading,
            facing,
        )),
        V3::zero(),
    );

    let cos_camera = dir.dot(camera_normal).abs();
    let cos_light = dir.dot(light_normal).abs();
    let camera_pdf_area = camera_pdf * cos_light / distance2;
    let light_pdf_area = light_pdf * cos_camera / distance2;
    let w_light = mis(camera_pdf_area) * load(&light.mis_factor);
    let w_camera = mis(light_pdf_area) * load(&camera.mis_factor);
    let weight = one / (w_light + one + w_camera);
    let contribution = (camera_f * light_f).div(distance2);
    let some = !distance2.simd_le(zero)
        & !camera_f.is_zero()
        & !light_f.is_zero()
        & !contribution.is_zero();

    // `segment_ray`: each end moved off its surface.
    let origin = offset_origin(
        load3(&camera.position),
        camera_normal,
        to_light,
        load(&camera.magnitude),
    );
    let target = offset_origin(
        load3(&light.position),
        light_normal,
        -to_light,
        load(&light.magnitude),
    );
    let to_target = target - origin;
    let length = to_target.dot(to_target).sqrt();
    let has_ray = some & !(length.is_nan() | length.simd_le(zero));

    let throughput = load3(&camera.throughput) * load3(&light.throughput);
    let value = throughput * V3::select(some, contribution, V3::zero());
    let store = |v: f32x8, a: &mut Block| *a = v.to_array();
    let store3 = |v: V3, a: &mut Block3| {
        store(v.x, &mut a[0]);
        store(v.y, &mut a[1]);
        store(v.z, &mut a[2]);
    };
    store3(value, &mut block.value);
    store(some.select(weight, zero), &mut block.weight);
    block.has_ray = has_ray.to_bitmask();
    store3(origin, &mut block.ray_origin);
    store3(to_target.div(length), &mut block.ray_dir);
    store(length, &mut block.ray_tmax);
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
            light_vertices.push(LightVertex {
                bsdf: material(i).bsdf(&surface, wo),
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
            bdpt.connect_diffuse(
                i,
                &walk,
                &surface,
                &bsdf,
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
