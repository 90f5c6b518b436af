//! Eight lanes of the path tracer's vertex arithmetic: glam's `Vec3`
//! operations, the shading frame, the cosine warp, the ray offset and the
//! power heuristic, each written with the scalar code's operations in the
//! scalar code's order, so that a lane's result is the scalar one bit for
//! bit (IEEE arithmetic rounds alike in a SIMD lane and a scalar register).
//! The unit tests compare each against its scalar original.

use crate::bvh::LANES;
use crate::geometry::SurfacePoint;
use crate::light::AreaLight;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};
use wide::f32x8;

/// One number per lane.
pub(super) type Lanes = [f32; LANES];
/// A vector per lane, as three arrays of coordinates.
pub(super) type Lanes3 = [Lanes; 3];

/// A lane mask from the low eight bits of `bits`.
#[inline(always)]
pub(super) fn lane_mask(bits: u32) -> f32x8 {
    let all = f32::from_bits(u32::MAX);
    f32x8::new(std::array::from_fn(|k| {
        if (bits >> k) & 1 != 0 {
            all
        } else {
            0.0
        }
    }))
}

#[inline(always)]
pub(super) fn set3(a: &mut Lanes3, lane: usize, v: Vec3) {
    a[0][lane] = v.x;
    a[1][lane] = v.y;
    a[2][lane] = v.z;
}

#[inline(always)]
pub(super) fn get3(a: &Lanes3, lane: usize) -> Vec3 {
    Vec3::new(a[0][lane], a[1][lane], a[2][lane])
}

/// Eight vectors, one per lane, with glam's `Vec3` arithmetic in the
/// same order of operations.
#[derive(Clone, Copy)]
pub(super) struct V3 {
    pub x: f32x8,
    pub y: f32x8,
    pub z: f32x8,
}

impl V3 {
    #[inline(always)]
    pub(super) fn zero() -> V3 {
        V3 {
            x: f32x8::ZERO,
            y: f32x8::ZERO,
            z: f32x8::ZERO,
        }
    }

    /// `Vec3::dot`: (x x' + y y') + z z'.
    #[inline(always)]
    pub(super) fn dot(self, o: V3) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `f32 * Vec3`.
    #[inline(always)]
    pub(super) fn scale(self, k: f32x8) -> V3 {
        V3 {
            x: k * self.x,
            y: k * self.y,
            z: k * self.z,
        }
    }

    /// `Vec3 / f32`.
    #[inline(always)]
    pub(super) fn div(self, k: f32x8) -> V3 {
        V3 {
            x: self.x / k,
            y: self.y / k,
            z: self.z / k,
        }
    }

    /// `Vec3::max_element`, with glam's comparison.
    #[inline(always)]
    pub(super) fn max_element(self) -> f32x8 {
        let max = |a: f32x8, b: f32x8| a.simd_gt(b).select(a, b);
        max(self.x, max(self.y, self.z))
    }

    pub(super) fn abs(self) -> V3 {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// Whether all three coordinates are zero.
    #[inline(always)]
    pub(super) fn is_zero(self) -> f32x8 {
        self.x.simd_eq(f32x8::ZERO) & self.y.simd_eq(f32x8::ZERO) & self.z.simd_eq(f32x8::ZERO)
    }

    #[inline(always)]
    pub(super) fn select(m: f32x8, a: V3, b: V3) -> V3 {
        V3 {
            x: m.select(a.x, b.x),
            y: m.select(a.y, b.y),
            z: m.select(a.z, b.z),
        }
    }
}

impl std::ops::Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl std::ops::Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl std::ops::Mul for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}

impl std::ops::Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// `geometry::Frame`, lane by lane.
pub(super) struct Frame {
    pub s: V3,
    pub t: V3,
    pub n: V3,
}

impl Frame {
    /// `Frame::new`: Duff et al.'s branchless basis.
    #[inline(always)]
    pub(super) fn new(n: V3) -> Frame {
        let sign = f32x8::ONE | (n.z & f32x8::splat(-0.0));
        let a = f32x8::splat(-1.0) / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            s: V3 {
                x: f32x8::ONE + sign * n.x * n.x * a,
                y: sign * b,
                z: -sign * n.x,
            },
            t: V3 {
                x: b,
                y: sign + n.y * n.y * a,
                z: -n.y,
            },
            n,
        }
    }

    /// `Frame::to_world`.
    #[inline(always)]
    pub(super) fn to_world(&self, v: V3) -> V3 {
        self.s.scale(v.x) + self.t.scale(v.y) + self.n.scale(v.z)
    }
}

/// `Material::bsdf`'s orientation, lane by lane: whether `wo` is on the
/// geometric normal's side, the geometric normal turned to `wo`'s side,
/// and the shading frame around the shading normal turned likewise (the
/// geometric one where it tilts past `wo`).
#[inline(always)]
pub(super) fn oriented_frame(normal: V3, shading_normal: V3, wo: V3) -> (f32x8, V3, Frame) {
    let outside = wo.dot(normal).simd_ge(f32x8::ZERO);
    let ng = V3::select(outside, normal, -normal);
    let ns = V3::select(outside, shading_normal, -shading_normal);
    let ns = V3::select(ns.dot(wo).simd_le(f32x8::ZERO), ng, ns);
    (outside, ng, Frame::new(ns))
}

/// `CameraPath::scatter`'s Russian roulette, lane by lane, for the lanes
/// of `on`: the throughput after it, and the lanes whose paths it ends.
#[inline(always)]
pub(super) fn roulette(throughput: V3, eta_squared: f32x8, on: f32x8, u: f32x8) -> (V3, f32x8) {
    let survive = (throughput.max_element() * eta_squared).min(f32x8::ONE);
    let dies = on & u.simd_ge(survive);
    (V3::select(on, throughput.div(survive), throughput), dies)
}

/// Vertices on Lambertian surfaces, staged lane by lane: what the path
/// tracer's and BDPT's passes both read, and the lights their light
/// samples chose.
#[derive(Default)]
pub(super) struct StagedVertices {
    /// Lanes staged this step.
    pub staged: u32,
    position: Lanes3,
    /// The geometric normal as the surface gives it (not yet facing `wo`).
    normal: Lanes3,
    shading_normal: Lanes3,
    magnitude: Lanes,
    wo: Lanes3,
    albedo: Lanes3,
    throughput: Lanes3,
    direction: [Lanes; 2],
    roulette: Lanes,
    /// Lanes whose walks are long enough for roulette.
    roulette_on: u32,
    pub lights: StagedLights,
}

/// Lanes `base .. base + 8` of the staged vertices, with the BSDF's
/// orientation and its sample (`Material::bsdf`, `Bsdf::sample` for a
/// diffuse surface) and the next ray's origin.
pub(super) struct DiffuseVertices {
    pub position: V3,
    /// The geometric normal as the surface gives it.
    pub normal: V3,
    pub magnitude: f32x8,
    pub wo: V3,
    pub albedo: V3,
    pub throughput: V3,
    /// The geometric normal on `wo`'s side, and the shading frame.
    pub ng: V3,
    pub frame: Frame,
    /// The sampled direction, its density, and the lanes where sampling
    /// gave one.
    pub wi: V3,
    pub pdf: f32x8,
    pub sampled: f32x8,
    pub next_origin: V3,
    /// The roulette numbers, and the lanes that play it.
    pub roulette: f32x8,
    pub roulette_on: f32x8,
}

impl StagedVertices {
    pub fn clear(&mut self) {
        self.staged = 0;
        self.roulette_on = 0;
        self.lights.clear();
    }

    /// Stages `lane`'s vertex at `surface`, seen along `wo`, of
    /// reflectance `albedo`, on a walk of `throughput`, with its numbers
    /// for the direction and roulette (`roulette_on`: whether it plays).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn stage(
        &mut self,
        lane: usize,
        surface: &SurfacePoint,
        wo: Vec3,
        albedo: Vec3,
        throughput: Vec3,
        direction: (f32, f32),
        roulette: f32,
        roulette_on: bool,
    ) {
        self.staged |= 1 << lane;
        set3(&mut self.position, lane, surface.position);
        set3(&mut self.normal, lane, surface.geometric_normal);
        set3(&mut self.shading_normal, lane, surface.shading_normal);
        self.magnitude[lane] = surface.magnitude;
        set3(&mut self.wo, lane, wo);
        set3(&mut self.albedo, lane, albedo);
        set3(&mut self.throughput, lane, throughput);
        self.direction[0][lane] = direction.0;
        self.direction[1][lane] = direction.1;
        self.roulette[lane] = roulette;
        if roulette_on {
            self.roulette_on |= 1 << lane;
        }
    }

    /// Lane `lane`'s position.
    #[inline(always)]
    pub fn position(&self, lane: usize) -> Vec3 {
        get3(&self.position, lane)
    }

    /// The first lane of each eight that has staged lanes.
    pub fn halves(&self) -> impl Iterator<Item = usize> + use<> {
        eights_with(self.staged)
    }

    /// Lanes `base .. base + 8`, oriented and sampled.
    #[inline(always)]
    pub fn vertices(&self, base: usize) -> DiffuseVertices {
        let position = load3(&self.position, base);
        let normal = load3(&self.normal, base);
        let wo = load3(&self.wo, base);
        let magnitude = load(&self.magnitude, base);
        let (_, ng, frame) = oriented_frame(normal, load3(&self.shading_normal, base), wo);
        let local = cosine_hemisphere(
            load(&self.direction[0], base),
            load(&self.direction[1], base),
        );
        let pdf = local.z.max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI);
        let wi = frame.to_world(local);
        let reflected = local.z.simd_gt(f32x8::ZERO);
        let sampled = !pdf.simd_le(f32x8::ZERO) & !(wi.dot(ng).simd_gt(f32x8::ZERO) ^ reflected);
        DiffuseVertices {
            position,
            normal,
            magnitude,
            wo,
            albedo: load3(&self.albedo, base),
            throughput: load3(&self.throughput, base),
            ng,
            frame,
            wi,
            pdf,
            sampled,
            next_origin: offset_origin(position, normal, wi, magnitude),
            roulette: load(&self.roulette, base),
            roulette_on: lane_mask(self.roulette_on >> base),
        }
    }
}

/// The walks after a diffuse bounce, per lane: which sampled a direction
/// and which roulette spared, and their next throughputs and rays.
#[derive(Default)]
pub(super) struct Continued {
    pub sampled: u32,
    pub survives: u32,
    throughput: Lanes3,
    origin: Lanes3,
    dir: Lanes3,
}

impl Continued {
    /// Lanes `base .. base + 8` continued from `v`: the throughput times
    /// the sample's `weight` (the reflectance, for radiance; for
    /// importance, times the shading correction), then roulette, which
    /// reads the throughput times `scale` (the path tracer's eta², or a
    /// BDPT walk's roulette scale; a diffuse bounce leaves either as it
    /// is).
    #[inline(always)]
    pub fn store(&mut self, v: &DiffuseVertices, weight: V3, scale: f32x8, base: usize) {
        let (next, dies) = roulette(v.throughput * weight, scale, v.roulette_on, v.roulette);
        set_bits(&mut self.sampled, v.sampled, base);
        set_bits(&mut self.survives, !dies, base);
        store3(next, &mut self.throughput, base);
        store3(v.next_origin, &mut self.origin, base);
        store3(v.wi, &mut self.dir, base);
    }

    /// Lane `lane`'s next throughput, ray origin and direction.
    #[inline(always)]
    pub fn get(&self, lane: usize) -> (Vec3, Vec3, Vec3) {
        (
            get3(&self.throughput, lane),
            get3(&self.origin, lane),
            get3(&self.dir, lane),
        )
    }
}

/// Emissive triangles chosen by light sampling, staged lane by lane.
#[derive(Default)]
pub(super) struct StagedLights {
    /// Lanes with a light staged.
    pub lit: u32,
    pick: Lanes,
    point: [Lanes; 2],
    vertices: [Lanes3; 3],
    normal: Lanes3,
    area: Lanes,
    radiance: Lanes3,
    magnitude: Lanes,
    two_sided: u32,
}

/// A light sample in eight lanes (`AreaLight::sample_incident`), with its
/// shadow ray (`connect::shadow_ray`).
pub(super) struct LightSample {
    /// Lanes whose sample can add light: a light was staged, the point is
    /// apart from the receiver, and the light emits towards it.
    pub some: f32x8,
    pub wi: V3,
    /// Solid-angle density of the point, seen from the receiver.
    pub pdf: f32x8,
    /// The light's selection probability.
    pub pick: f32x8,
    pub radiance: V3,
    pub cos_light: f32x8,
    pub light_area: f32x8,
    pub two_sided: f32x8,
    /// Lanes with a shadow ray (the others: nothing can block the sample).
    pub has_ray: f32x8,
    pub ray_origin: V3,
    pub ray_dir: V3,
    pub ray_tmax: f32x8,
}

impl StagedLights {
    pub fn clear(&mut self) {
        self.lit = 0;
        self.two_sided = 0;
    }

    /// Stages `light`, chosen with probability `pick`, and the numbers `u`
    /// of its point, in `lane`.
    #[inline(always)]
    pub fn stage(&mut self, lane: usize, light: &AreaLight, pick: f32, u: (f32, f32)) {
        self.lit |= 1 << lane;
        self.pick[lane] = pick;
        self.point[0][lane] = u.0;
        self.point[1][lane] = u.1;
        for (vertex, v) in self.vertices.iter_mut().zip(light.triangle.v) {
            set3(vertex, lane, v);
        }
        set3(&mut self.normal, lane, light.normal);
        self.area[lane] = light.area;
        set3(&mut self.radiance, lane, light.radiance);
        self.magnitude[lane] = light.magnitude;
        if light.two_sided {
            self.two_sided |= 1 << lane;
        }
    }

    /// The samples of lanes `base .. base + 8` from receivers at
    /// `position` (with their geometric normals and magnitudes, for the
    /// shadow rays).
    #[inline(always)]
    pub fn sample(&self, base: usize, position: V3, normal: V3, magnitude: f32x8) -> LightSample {
        let load = |a: &Lanes| load(a, base);
        let load3 = |a: &Lanes3| load3(a, base);
        let (u, v) = (load(&self.point[0]), load(&self.point[1]));
        // `warp::uniform_triangle` and `Triangle::point`.
        let fold = (u + v).simd_gt(f32x8::ONE);
        let b1 = fold.select(f32x8::ONE - u, u);
        let b2 = fold.select(f32x8::ONE - v, v);
        let [v0, v1, v2] = self.vertices.each_ref().map(load3);
        let point = v0.scale(f32x8::ONE - b1 - b2) + v1.scale(b1) + v2.scale(b2);
        let to_light = point - position;
        let d2 = to_light.dot(to_light);
        let distance = d2.sqrt();
        let wi = to_light.div(distance);
        let light_normal = load3(&self.normal);
        let radiance = load3(&self.radiance);
        let two_sided = lane_mask(self.two_sided >> base);
        let emits = two_sided | (-wi).dot(light_normal).simd_gt(f32x8::ZERO);
        let cos_light = wi.dot(light_normal).abs();
        let light_area = load(&self.area);
        let pdf = d2 / (cos_light * light_area);
        let some = lane_mask(self.lit >> base)
            & !d2.simd_le(f32x8::ZERO)
            & !cos_light.simd_le(f32x8::ZERO)
            & emits
            & !radiance.is_zero();
        // The shadow ray, each end moved off its surface.
        let origin = offset_origin(position, normal, wi, magnitude);
        let target = offset_origin(point, light_normal, -wi, load(&self.magnitude));
        let to_target = target - origin;
        let length = to_target.dot(to_target).sqrt();
        let unbounded = distance.is_inf();
        LightSample {
            some,
            wi,
            pdf,
            pick: load(&self.pick),
            radiance,
            cos_light,
            light_area,
            two_sided,
            has_ray: unbounded | !(length.is_nan() | length.simd_le(f32x8::ZERO)),
            ray_origin: origin,
            ray_dir: V3::select(unbounded, wi, to_target.div(length)),
            ray_tmax: unbounded.select(f32x8::splat(f32::INFINITY), length),
        }
    }
}

/// A point and a direction of emission chosen on each staged light
/// (`AreaLight::sample_emission`), lane by lane.
pub(super) struct Emission {
    /// Lanes whose light emits along the sampled direction.
    pub some: f32x8,
    pub point: V3,
    pub dir: V3,
    /// The radiance times the cosine at the light.
    pub value: V3,
    /// The density of the direction and point (solid angle times area),
    /// and of the point alone (area).
    pub emission_pdf: f32x8,
    pub direct_pdf_area: f32x8,
    pub cos_light: f32x8,
    /// The light's front normal (not turned to the sampled face).
    pub normal: V3,
    pub magnitude: f32x8,
    pub pick: f32x8,
}

impl StagedLights {
    /// The emission samples of lanes `base .. base + 8`, the staged
    /// numbers choosing the point and `(u, v)` the direction.
    #[inline(always)]
    pub fn emission(&self, base: usize, u: f32x8, v: f32x8) -> Emission {
        let (one, zero) = (f32x8::ONE, f32x8::ZERO);
        let load = |a: &Lanes| load(a, base);
        let load3 = |a: &Lanes3| load3(a, base);
        let (pu, pv) = (load(&self.point[0]), load(&self.point[1]));
        let fold = (pu + pv).simd_gt(one);
        let b1 = fold.select(one - pu, pu);
        let b2 = fold.select(one - pv, pv);
        let [v0, v1, v2] = self.vertices.each_ref().map(load3);
        let point = v0.scale(one - b1 - b2) + v1.scale(b1) + v2.scale(b2);
        let normal = load3(&self.normal);
        // A two-sided light reuses `u` to choose its face.
        let two_sided = lane_mask(self.two_sided >> base);
        let half = u.simd_lt(f32x8::splat(0.5));
        let two = f32x8::splat(2.0);
        let u = two_sided.select(half.select(u * two, two * u - one), u);
        let back = two_sided & !half;
        let face = V3::select(back, -normal, normal);
        let local = cosine_hemisphere(u.min(f32x8::splat(1.0 - f32::EPSILON)), v);
        let cos_light = local.z;
        let area = load(&self.area);
        let sides = two_sided.select(f32x8::splat(0.5), one);
        Emission {
            some: lane_mask(self.lit >> base) & !cos_light.simd_le(zero),
            point,
            dir: Frame::new(face).to_world(local),
            value: load3(&self.radiance).scale(cos_light),
            emission_pdf: sides * cos_light.abs() / f32x8::splat(PI) / area,
            direct_pdf_area: one / area,
            cos_light,
            normal,
            magnitude: load(&self.magnitude),
            pick: load(&self.pick),
        }
    }
}

/// A Lambertian BSDF of reflectance `albedo` towards `wi`, lane by lane
/// (`Bsdf::eval` and `Bsdf::pdf`): its value f cos, and the density of
/// sampling `wi`; `n` is the shading normal and `ng` the geometric one,
/// both on `wo`'s side.
#[inline(always)]
pub(super) fn diffuse_eval(albedo: V3, n: V3, ng: V3, wi: V3) -> (V3, f32x8) {
    let reflected = wi.dot(ng).simd_gt(f32x8::ZERO);
    let same_side = !(wi.dot(n).simd_gt(f32x8::ZERO) ^ reflected);
    let cos = wi.dot(n);
    let lobe = same_side & reflected;
    let f = albedo.scale(f32x8::splat(FRAC_1_PI) * cos);
    let f = V3::select(lobe & !cos.simd_le(f32x8::ZERO), f, V3::zero());
    let pdf = lobe.select(cos.max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI), f32x8::ZERO);
    (f, pdf)
}

/// `Bsdf::shading_correction` lane by lane: |wo·ns| |wi·ng| / (|wo·ng|
/// |wi·ns|), with the scalar code's special cases (one, zero or NaN by
/// the sign of the product where the normals are the same).
#[inline(always)]
pub(super) fn shading_correction(wo: V3, wi: V3, shading: V3, facing: V3) -> f32x8 {
    let zero = f32x8::ZERO;
    let flat =
        shading.x.simd_eq(facing.x) & shading.y.simd_eq(facing.y) & shading.z.simd_eq(facing.z);
    let d = wo.dot(facing).abs() * wi.dot(facing).abs();
    let flat_value = d.simd_gt(zero).select(
        f32x8::ONE,
        d.simd_le(zero).select(zero, f32x8::splat(f32::NAN)),
    );
    let denominator = wo.dot(facing).abs() * wi.dot(shading).abs();
    let tilted = denominator.simd_le(zero).select(
        zero,
        wo.dot(shading).abs() * wi.dot(facing).abs() / denominator,
    );
    flat.select(flat_value, tilted)
}

/// The MIS quantities of a walk after the diffuse bounce of `v` (a
/// weighted walk's `update_weights`, report eqs. 34-36), from its
/// `d_vcm`, `d_vc`, `d_vm` at the vertex and the merging constants `vm`
/// and `vc`; returns the new `d_vcm`, `d_vc`, `d_vm`.
#[inline(always)]
pub(super) fn follow_weights(
    v: &DiffuseVertices,
    (d_vcm, d_vc, d_vm): (f32x8, f32x8, f32x8),
    (vm, vc): (f32x8, f32x8),
) -> (f32x8, f32x8, f32x8) {
    let (zero, one) = (f32x8::ZERO, f32x8::ONE);
    let mis = |x: f32x8| x * x;
    // The density of sampling `wo` back from `wi` (`Bsdf::pdfs`' reverse
    // density), given only where `wi` passes the BSDF's own side test in
    // world space: a direction sampled at a grazing angle can fail it even
    // though its local form passed.
    let reverse_pdf = v.wo.dot(v.frame.n).max(zero) * f32x8::splat(FRAC_1_PI);
    let wi_reflected = v.wi.dot(v.ng).simd_gt(zero);
    let wi_side = wi_reflected & !(v.wi.dot(v.frame.n).simd_gt(zero) ^ wi_reflected);
    let reverse = mis(wi_side.select(reverse_pdf, zero));
    let cos_out = v.wi.dot(v.normal).abs();
    let scale = mis(cos_out / v.pdf);
    (
        mis(one / v.pdf),
        scale * (d_vc * reverse + d_vcm + vm),
        scale * (d_vm * reverse + d_vcm * vc + one),
    )
}

/// The first lane of each run of eight lanes (`base`, for the eight-lane
/// passes) with a bit set in `mask`, up to `LANES`.
pub(super) fn eights_with(mask: u32) -> impl Iterator<Item = usize> {
    (0..LANES)
        .step_by(8)
        .filter(move |base| (mask >> base) & 0xff != 0)
}

/// Lanes `base .. base + 8` of `a`.
#[inline(always)]
pub(super) fn load(a: &Lanes, base: usize) -> f32x8 {
    f32x8::new(a[base..base + 8].try_into().expect("eight lanes"))
}

/// Lanes `base .. base + 8` of the vectors `a`.
#[inline(always)]
pub(super) fn load3(a: &Lanes3, base: usize) -> V3 {
    V3 {
        x: load(&a[0], base),
        y: load(&a[1], base),
        z: load(&a[2], base),
    }
}

/// Stores `v` in lanes `base .. base + 8` of `a`.
#[inline(always)]
pub(super) fn store(v: f32x8, a: &mut Lanes, base: usize) {
    a[base..base + 8].copy_from_slice(&v.to_array());
}

/// Stores `v` in lanes `base .. base + 8` of the vectors `a`.
#[inline(always)]
pub(super) fn store3(v: V3, a: &mut Lanes3, base: usize) {
    store(v.x, &mut a[0], base);
    store(v.y, &mut a[1], base);
    store(v.z, &mut a[2], base);
}

/// Sets bits `base .. base + 8` of `bits` to `mask`'s lanes.
#[inline(always)]
pub(super) fn set_bits(bits: &mut u32, mask: f32x8, base: usize) {
    *bits = (*bits & !(0xff << base)) | (mask.to_bitmask() << base);
}

/// `warp::cosine_hemisphere`, lane by lane.
#[inline(always)]
pub(super) fn cosine_hemisphere(u: f32x8, v: f32x8) -> V3 {
    // `warp::concentric_disk`.
    let two = f32x8::splat(2.0);
    let a = two * u - f32x8::ONE;
    let b = two * v - f32x8::ONE;
    let centre = a.simd_eq(f32x8::ZERO) & b.simd_eq(f32x8::ZERO);
    let wide = a.abs().simd_gt(b.abs());
    let r = wide.select(a, b);
    let other = wide.select(b, a);
    let (sin, cos) = sin_cos_quarter(f32x8::splat(PI / 4.0) * (other / r));
    let x = centre.select(f32x8::ZERO, r * wide.select(cos, sin));
    let y = centre.select(f32x8::ZERO, r * wide.select(sin, cos));
    let z = (f32x8::ONE - (x * x + y * y)).max(f32x8::ZERO).sqrt();
    V3 { x, y, z }
}

/// `warp::sin_cos_quarter`, lane by lane: the same series.
#[inline(always)]
fn sin_cos_quarter(x: f32x8) -> (f32x8, f32x8) {
    let c = f32x8::splat;
    let x2 = x * x;
    let sin = x
        * (c(1.0)
            + x2 * (c(-1.0 / 6.0)
                + x2 * (c(1.0 / 120.0) + x2 * (c(-1.0 / 5040.0) + x2 * c(1.0 / 362_880.0)))));
    let cos = c(1.0)
        + x2 * (c(-0.5)
            + x2 * (c(1.0 / 24.0)
                + x2 * (c(-1.0 / 720.0) + x2 * (c(1.0 / 40_320.0) + x2 * c(-1.0 / 3_628_800.0)))));
    (sin, cos)
}

/// `ray::offset_origin`, lane by lane.
#[inline(always)]
pub(super) fn offset_origin(p: V3, normal: V3, toward: V3, magnitude: f32x8) -> V3 {
    const RELATIVE: f32 = 1.0 / 65536.0;
    let n = V3::select(normal.dot(toward).simd_lt(f32x8::ZERO), -normal, normal);
    let scale = magnitude
        .max(p.abs().max_element())
        .max(f32x8::splat(f32::MIN_POSITIVE));
    p + n.scale(scale * f32x8::splat(RELATIVE))
}

/// `mis::power_heuristic`, lane by lane, its special cases included.
#[inline(always)]
pub(super) fn power_heuristic(own: f32x8, other: f32x8) -> f32x8 {
    let largest = own.max(other);
    let degenerate = largest.is_nan() | largest.simd_le(f32x8::ZERO) | largest.is_inf();
    let (a, b) = (own / largest, other / largest);
    let weight = a * a / (a * a + b * b);
    let fallback = own.simd_ge(other).select(f32x8::ONE, f32x8::ZERO);
    let weight = degenerate.select(fallback, weight);
    own.is_inf().select(f32x8::ONE, weight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::mis;
    use crate::sampling::warp;

    /// Eight lanes of `f`'s values, for inputs `k = 0..8` of a run.
    fn lanes(f: impl Fn(usize) -> f32) -> f32x8 {
        f32x8::new(std::array::from_fn(f))
    }

    /// A deterministic spread of numbers in [0, 1).
    fn uniform(i: usize) -> f32 {
        ((i as u32).wrapping_mul(2_654_435_769) >> 8) as f32 / (1 << 24) as f32
    }

    #[test]
    fn emission_samples_are_the_scalar_ones() {
        use crate::geometry::Triangle;
        let triangle = Triangle::new(
            Vec3::new(-1.0, 3.0, 0.5),
            Vec3::new(2.0, 3.5, -0.25),
            Vec3::new(0.5, 2.0, 1.5),
        );
        let radiance = Vec3::new(4.0, 2.5, 1.0);
        for two_sided in [false, true] {
            let light = AreaLight::new(triangle, 0, radiance, two_sided);
            for run in 0..50 {
                let number = |k: usize, d: usize| uniform(64 * run + 8 * d + k);
                let mut staged = StagedLights::default();
                for k in 0..LANES {
                    let k8 = k % 8;
                    staged.stage(k, &light, 0.25, (number(k8, 0), number(k8, 1)));
                }
                let e = staged.emission(8, lanes(|k| number(k, 2)), lanes(|k| number(k, 3)));
                for k in 0..8 {
                    let u = (number(k, 0), number(k, 1));
                    let scalar = light.sample_emission(u, (number(k, 2), number(k, 3)));
                    let lane = |v: f32x8| v.to_array()[k];
                    let lane3 = |v: V3| Vec3::new(lane(v.x), lane(v.y), lane(v.z));
                    assert_eq!(lane(e.some) != 0.0, scalar.is_some());
                    let Some(scalar) = scalar else { continue };
                    assert_eq!(lane3(e.point), scalar.origin);
                    assert_eq!(lane3(e.dir), scalar.dir);
                    assert_eq!(lane3(e.value), scalar.value);
                    assert_eq!(lane(e.emission_pdf), scalar.emission_pdf);
                    assert_eq!(lane(e.direct_pdf_area), scalar.direct_pdf_area);
                    assert_eq!(lane(e.cos_light), scalar.cos_light);
                    assert_eq!(lane3(e.normal), scalar.normal);
                    assert_eq!(lane(e.pick), 0.25);
                }
            }
        }
    }

    #[test]
    fn cosine_directions_are_the_scalar_warps() {
        // The centre of the square, its edges and a spread of points.
        let special = [0.5, 0.0, 1.0 - f32::EPSILON / 2.0, 0.25, 0.75];
        for run in 0..200 {
            let u = |k: usize| match run {
                0..5 => special[run],
                _ => uniform(16 * run + k),
            };
            let v = |k: usize| match run {
                0..5 => special[(run + k) % 5],
                _ => uniform(16 * run + 8 + k),
            };
            let d = cosine_hemisphere(lanes(u), lanes(v));
            for k in 0..8 {
                let w = warp::cosine_hemisphere(u(k), v(k));
                let got = [d.x, d.y, d.z].map(|c| c.to_array()[k].to_bits());
                assert_eq!(got, w.to_array().map(f32::to_bits), "u {} v {}", u(k), v(k));
            }
        }
    }

    #[test]
    fn frames_and_offsets_are_the_scalar_ones() {
        for run in 0..100 {
            let normal = |k: usize| {
                let axis = [Vec3::X, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
                if run == 0 && k < 4 {
                    return axis[k];
                }
                let i = 24 * run + 3 * k;
                Vec3::new(uniform(i) - 0.5, uniform(i + 1) - 0.5, uniform(i + 2) - 0.5).normalize()
            };
            let n = V3 {
                x: lanes(|k| normal(k).x),
                y: lanes(|k| normal(k).y),
                z: lanes(|k| normal(k).z),
            };
            let frame = Frame::new(n);
            let p = n.scale(f32x8::splat(300.0 * uniform(run)));
            let toward = V3 {
                x: n.y,
                y: n.z,
                z: n.x,
            };
            let offset = offset_origin(p, n, toward, f32x8::splat(1.0));
            for k in 0..8 {
                let lane =
                    |v: V3| Vec3::new(v.x.to_array()[k], v.y.to_array()[k], v.z.to_array()[k]);
                let scalar = crate::geometry::Frame::new(normal(k));
                for (ours, theirs) in [(frame.s, scalar.s), (frame.t, scalar.t)] {
                    assert_eq!(
                        lane(ours).to_array().map(f32::to_bits),
                        theirs.to_array().map(f32::to_bits)
                    );
                }
                let expected =
                    crate::geometry::ray::offset_origin(lane(p), normal(k), lane(toward), 1.0);
                assert_eq!(lane(offset), expected);
            }
        }
    }

    #[test]
    fn power_heuristic_is_the_scalar_one_with_its_edge_cases() {
        let values = [
            0.0,
            -0.0,
            1e-30,
            0.3,
            1.0,
            7.5,
            3e38,
            f32::INFINITY,
            f32::NAN,
        ];
        for &own in &values {
            let ours = power_heuristic(f32x8::splat(own), lanes(|k| values[k]));
            let last = power_heuristic(f32x8::splat(own), f32x8::splat(values[8]));
            for (k, &other) in values.iter().enumerate() {
                let got = if k < 8 {
                    ours.to_array()[k]
                } else {
                    last.to_array()[0]
                };
                let expected = mis::power_heuristic(own, other);
                assert_eq!(got.to_bits(), expected.to_bits(), "own {own} other {other}");
            }
        }
    }
}
