//! The path tracer's diffuse vertices, shaded eight lanes at a time.
//!
//! Where the lanes' rays land on Lambertian surfaces (the common case in
//! a room), each lane's numbers, surface and chosen area light are staged
//! in arrays, one entry per lane; then one pass of eight-lane SIMD
//! arithmetic per half of the lanes builds the shading frames, samples
//! the cosine-weighted next directions, evaluates the light samples with
//! their MIS weights and shadow rays, and plays Russian roulette; each
//! lane then takes its results back. A lane computes exactly what
//! [`CameraPath::vertex`] computes for it, operation for operation in the
//! same order (IEEE arithmetic gives the same bits in a SIMD lane as in a
//! scalar register), so the image stays the one-path-at-a-time path
//! tracer's, bit for bit; the lanes' test checks that on every bundled
//! scene. Other materials, and light samples of lights other than
//! emissive triangles, take the scalar vertex.
//!
//! Scalar, each vertex spends some 500 instructions building its BSDF,
//! sampling it, sampling the light and weighing the two; here the staging
//! (a store per number) and the shared arithmetic cost a fraction of that.

use super::{Arrival, CameraPath, DirectLight, Vertex, ROULETTE_START};
use crate::bvh::LANES;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::light::{AreaLight, Light};
use crate::material::Albedo;
use crate::scene::Scene;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};
use wide::f32x8;

/// One number per lane.
type Lanes = [f32; LANES];
/// A vector per lane, as three arrays of coordinates.
type Lanes3 = [Lanes; 3];

/// The staged inputs of a step's diffuse vertices, and their results.
#[derive(Default)]
pub(in crate::integrator) struct DiffuseLanes {
    /// Lanes staged this step.
    staged: u32,
    position: Lanes3,
    /// The geometric normal as the surface gives it (not yet facing `wo`).
    normal: Lanes3,
    shading_normal: Lanes3,
    magnitude: Lanes,
    wo: Lanes3,
    albedo: Lanes3,
    throughput: Lanes3,
    eta_squared: Lanes,
    direction: [Lanes; 2],
    roulette: Lanes,
    /// Lanes whose paths are long enough for roulette.
    roulette_on: u32,
    /// Lanes with an area light's sample to evaluate, and its numbers.
    lit: u32,
    pick: Lanes,
    light_point: [Lanes; 2],
    light_vertices: [Lanes3; 3],
    light_normal: Lanes3,
    light_area: Lanes,
    light_radiance: Lanes3,
    light_magnitude: Lanes,
    light_two_sided: u32,
    out: Shaded,
}

/// What the SIMD pass hands back, per lane.
#[derive(Default)]
struct Shaded {
    /// Lanes whose light sample adds something (if its shadow ray is free).
    direct_some: u32,
    /// Of those, the lanes that have a shadow ray (the others: nothing can block it).
    shadow_some: u32,
    direct: Lanes3,
    shadow_origin: Lanes3,
    shadow_dir: Lanes3,
    shadow_tmax: Lanes,
    /// Lanes whose BSDF sample gave a direction.
    sampled: u32,
    /// Of those, the lanes whose path goes on (roulette spared it).
    survives: u32,
    throughput: Lanes3,
    pdf: Lanes,
    next_origin: Lanes3,
    next_dir: Lanes3,
}

impl DiffuseLanes {
    /// Forgets the previous step's lanes.
    pub fn clear(&mut self) {
        self.staged = 0;
        self.roulette_on = 0;
        self.lit = 0;
        self.light_two_sided = 0;
    }

    /// Shades every staged lane.
    pub fn shade(&mut self) {
        for half in 0..LANES / 8 {
            if (self.staged >> (8 * half)) & 0xff != 0 {
                self.shade_half(8 * half);
            }
        }
    }
}

impl CameraPath {
    /// The rest of the vertex at `arrival`, a Lambertian surface of
    /// reflectance `albedo` (its material's): draws the vertex's numbers and chooses its
    /// light as [`CameraPath::vertex`] does, then stages the lane for
    /// [`DiffuseLanes::shade`] and returns `None`; or, where the light
    /// chosen is not an emissive triangle, finishes the vertex here, one
    /// path alone, and returns it.
    #[inline(always)]
    pub(in crate::integrator) fn stage_diffuse(
        &mut self,
        scene: &Scene,
        arrival: &Arrival,
        albedo: &Albedo,
        lane: usize,
        lanes: &mut DiffuseLanes,
    ) -> Option<Vertex> {
        let numbers = self.sampler.vertex_numbers(true);
        let (u_select, u_point) = numbers.light.expect("a diffuse vertex samples a light");
        let bit = 1u32 << lane;
        let chosen = scene.light_selector.sample(u_select);
        if let Some((index, pick)) = chosen {
            let Light::Area(light) = &scene.lights[index] else {
                let material = &scene.materials[arrival.material as usize];
                let bsdf = material.bsdf(&arrival.surface, arrival.wo);
                return Some(self.scatter(scene, arrival, &bsdf, numbers));
            };
            lanes.stage_light(lane, light, pick, u_point);
        } else {
            // No light to sample: the sample adds the throughput times zero.
            self.radiance += self.throughput * Rgb::ZERO;
        }
        let surface = &arrival.surface;
        let albedo = albedo.at(surface);
        lanes.staged |= bit;
        set3(&mut lanes.position, lane, surface.position);
        set3(&mut lanes.normal, lane, surface.geometric_normal);
        set3(&mut lanes.shading_normal, lane, surface.shading_normal);
        lanes.magnitude[lane] = surface.magnitude;
        set3(&mut lanes.wo, lane, arrival.wo);
        set3(&mut lanes.albedo, lane, albedo);
        set3(&mut lanes.throughput, lane, self.throughput);
        lanes.eta_squared[lane] = self.eta_squared;
        lanes.direction[0][lane] = numbers.direction.0;
        lanes.direction[1][lane] = numbers.direction.1;
        lanes.roulette[lane] = numbers.roulette;
        if self.segments >= ROULETTE_START {
            lanes.roulette_on |= bit;
        }
        None
    }

    /// Takes back lane `lane`'s results from [`DiffuseLanes::shade`]: the
    /// vertex, as [`CameraPath::vertex`] would have returned it.
    #[inline(always)]
    pub(in crate::integrator) fn finish_diffuse(
        &mut self,
        lane: usize,
        lanes: &DiffuseLanes,
    ) -> Vertex {
        let bit = 1u32 << lane;
        let out = &lanes.out;
        let mut direct = None;
        if lanes.lit & bit != 0 {
            let nothing = self.throughput * Rgb::ZERO;
            if out.direct_some & bit != 0 {
                let shadow = (out.shadow_some & bit != 0).then(|| {
                    Ray::segment(
                        get3(&out.shadow_origin, lane),
                        get3(&out.shadow_dir, lane),
                        out.shadow_tmax[lane],
                    )
                });
                direct = Some(DirectLight {
                    value: get3(&out.direct, lane),
                    blocked: nothing,
                    shadow,
                });
            } else {
                self.radiance += nothing;
            }
        }
        if out.sampled & bit == 0 {
            return Vertex {
                direct,
                continues: false,
            };
        }
        // A diffuse bounce leaves eta² as it is (it multiplies by 1).
        self.throughput = get3(&out.throughput, lane);
        self.previous_pdf = out.pdf[lane];
        self.previous_delta = false;
        self.previous_position = get3(&lanes.position, lane);
        self.ray = Ray::new(get3(&out.next_origin, lane), get3(&out.next_dir, lane));
        Vertex {
            direct,
            continues: out.survives & bit != 0,
        }
    }
}

impl DiffuseLanes {
    #[inline(always)]
    fn stage_light(&mut self, lane: usize, light: &AreaLight, pick: f32, u: (f32, f32)) {
        self.lit |= 1 << lane;
        self.pick[lane] = pick;
        self.light_point[0][lane] = u.0;
        self.light_point[1][lane] = u.1;
        for (vertex, v) in self.light_vertices.iter_mut().zip(light.triangle.v) {
            set3(vertex, lane, v);
        }
        set3(&mut self.light_normal, lane, light.normal);
        self.light_area[lane] = light.area;
        set3(&mut self.light_radiance, lane, light.radiance);
        self.light_magnitude[lane] = light.magnitude;
        if light.two_sided {
            self.light_two_sided |= 1 << lane;
        }
    }

    /// The SIMD pass over lanes `base .. base + 8`.
    fn shade_half(&mut self, base: usize) {
        let load = |a: &Lanes| f32x8::new(a[base..base + 8].try_into().expect("eight lanes"));
        let load3 = |a: &Lanes3| V3 {
            x: load(&a[0]),
            y: load(&a[1]),
            z: load(&a[2]),
        };
        let mask = |bits: u32| lane_mask(bits >> base);
        let position = load3(&self.position);
        let normal = load3(&self.normal);
        let wo = load3(&self.wo);
        let magnitude = load(&self.magnitude);
        let throughput = load3(&self.throughput);
        let albedo = load3(&self.albedo);

        // The BSDF (`Material::bsdf`): the normals turned to `wo`'s side,
        // and the shading frame around the shading normal.
        let outside = wo.dot(normal).simd_ge(f32x8::ZERO);
        let ng = V3::select(outside, normal, -normal);
        let shading_normal = load3(&self.shading_normal);
        let ns = V3::select(outside, shading_normal, -shading_normal);
        let ns = V3::select(ns.dot(wo).simd_le(f32x8::ZERO), ng, ns);
        let frame = Frame::new(ns);

        // The next direction (`Bsdf::sample`, diffuse).
        let local = cosine_hemisphere(load(&self.direction[0]), load(&self.direction[1]));
        let pdf = local.z.max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI);
        let wi = frame.to_world(local);
        let reflected = local.z.simd_gt(f32x8::ZERO);
        let sampled = !pdf.simd_le(f32x8::ZERO) & !(wi.dot(ng).simd_gt(f32x8::ZERO) ^ reflected);
        let mut next = throughput * albedo;
        let next_origin = offset_origin(position, normal, wi, magnitude);
        // Roulette, for the lanes long enough for it.
        let survive = (next.max_element() * load(&self.eta_squared)).min(f32x8::ONE);
        let roulette_on = mask(self.roulette_on);
        let dies = roulette_on & load(&self.roulette).simd_ge(survive);
        let divided = next.div(survive);
        next = V3::select(roulette_on, divided, next);

        let out = &mut self.out;
        let sampled_bits = sampled.to_bitmask() << base;
        let survives_bits = (!dies).to_bitmask() << base;
        let keep = !(0xffu32 << base);
        out.sampled = (out.sampled & keep) | sampled_bits;
        out.survives = (out.survives & keep) | survives_bits;
        let store = |v: f32x8, a: &mut Lanes| a[base..base + 8].copy_from_slice(&v.to_array());
        let store3 = |v: V3, a: &mut Lanes3| {
            store(v.x, &mut a[0]);
            store(v.y, &mut a[1]);
            store(v.z, &mut a[2]);
        };
        store3(next, &mut out.throughput);
        store(pdf, &mut out.pdf);
        store3(next_origin, &mut out.next_origin);
        store3(wi, &mut out.next_dir);

        if (self.lit >> base) & 0xff == 0 {
            out.direct_some &= keep;
            return;
        }
        // The light sample (`AreaLight::sample_incident`).
        let (u, v) = (load(&self.light_point[0]), load(&self.light_point[1]));
        let fold = (u + v).simd_gt(f32x8::ONE);
        let b1 = fold.select(f32x8::ONE - u, u);
        let b2 = fold.select(f32x8::ONE - v, v);
        let [v0, v1, v2] = self.light_vertices.each_ref().map(load3);
        let point = v0.scale(f32x8::ONE - b1 - b2) + v1.scale(b1) + v2.scale(b2);
        let to_light = point - position;
        let d2 = to_light.dot(to_light);
        let distance = d2.sqrt();
        let light_wi = to_light.div(distance);
        let light_normal = load3(&self.light_normal);
        let radiance = load3(&self.light_radiance);
        let emits = mask(self.light_two_sided) | (-light_wi).dot(light_normal).simd_gt(f32x8::ZERO);
        let cos_light = light_wi.dot(light_normal).abs();
        let black_light = radiance.is_zero();
        let light_pdf_area = d2 / (cos_light * load(&self.light_area));
        let mut some = mask(self.lit)
            & !d2.simd_le(f32x8::ZERO)
            & !cos_light.simd_le(f32x8::ZERO)
            & emits
            & !black_light;
        // The BSDF's value and density there (`Bsdf::eval`, `Bsdf::pdf`).
        let light_reflected = light_wi.dot(ng).simd_gt(f32x8::ZERO);
        let same_side = !(light_wi.dot(frame.n).simd_gt(f32x8::ZERO) ^ light_reflected);
        let cos = light_wi.dot(frame.n);
        let lobe = same_side & light_reflected;
        let f = albedo.scale(f32x8::splat(FRAC_1_PI) * cos);
        let f = V3::select(lobe & !cos.simd_le(f32x8::ZERO), f, V3::zero());
        some &= !f.is_zero();
        let bsdf_pdf = lobe.select(cos.max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI), f32x8::ZERO);
        // The shadow ray (`connect::shadow_ray`).
        let origin = offset_origin(position, normal, light_wi, magnitude);
        let target = offset_origin(point, light_normal, -light_wi, load(&self.light_magnitude));
        let to_target = target - origin;
        let length = to_target.dot(to_target).sqrt();
        let unbounded = distance.is_inf();
        let has_ray = unbounded | !(length.is_nan() | length.simd_le(f32x8::ZERO));
        let shadow_dir = V3::select(unbounded, light_wi, to_target.div(length));
        let shadow_tmax = unbounded.select(f32x8::splat(f32::INFINITY), length);
        // The weight against BSDF sampling, and the estimate.
        let light_pdf = load(&self.pick) * light_pdf_area;
        let weight = power_heuristic(light_pdf, bsdf_pdf);
        let value = (f * radiance).scale(weight / light_pdf);
        let direct = throughput * value;

        out.direct_some = (out.direct_some & keep) | (some.to_bitmask() << base);
        out.shadow_some = (out.shadow_some & keep) | ((some & has_ray).to_bitmask() << base);
        store3(direct, &mut out.direct);
        store3(origin, &mut out.shadow_origin);
        store3(shadow_dir, &mut out.shadow_dir);
        store(shadow_tmax, &mut out.shadow_tmax);
    }
}

/// A lane mask from the low eight bits of `bits`.
#[inline(always)]
fn lane_mask(bits: u32) -> f32x8 {
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
fn set3(a: &mut Lanes3, lane: usize, v: Vec3) {
    a[0][lane] = v.x;
    a[1][lane] = v.y;
    a[2][lane] = v.z;
}

#[inline(always)]
fn get3(a: &Lanes3, lane: usize) -> Vec3 {
    Vec3::new(a[0][lane], a[1][lane], a[2][lane])
}

/// Eight vectors, one per lane, with glam's `Vec3` arithmetic in the
/// same order of operations.
#[derive(Clone, Copy)]
struct V3 {
    x: f32x8,
    y: f32x8,
    z: f32x8,
}

impl V3 {
    #[inline(always)]
    fn zero() -> V3 {
        V3 {
            x: f32x8::ZERO,
            y: f32x8::ZERO,
            z: f32x8::ZERO,
        }
    }

    /// `Vec3::dot`: (x x' + y y') + z z'.
    #[inline(always)]
    fn dot(self, o: V3) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `f32 * Vec3`.
    #[inline(always)]
    fn scale(self, k: f32x8) -> V3 {
        V3 {
            x: k * self.x,
            y: k * self.y,
            z: k * self.z,
        }
    }

    /// `Vec3 / f32`.
    #[inline(always)]
    fn div(self, k: f32x8) -> V3 {
        V3 {
            x: self.x / k,
            y: self.y / k,
            z: self.z / k,
        }
    }

    /// `Vec3::max_element`, with glam's comparison.
    #[inline(always)]
    fn max_element(self) -> f32x8 {
        let max = |a: f32x8, b: f32x8| a.simd_gt(b).select(a, b);
        max(self.x, max(self.y, self.z))
    }

    fn abs(self) -> V3 {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// Whether all three coordinates are zero.
    #[inline(always)]
    fn is_zero(self) -> f32x8 {
        self.x.simd_eq(f32x8::ZERO) & self.y.simd_eq(f32x8::ZERO) & self.z.simd_eq(f32x8::ZERO)
    }

    #[inline(always)]
    fn select(m: f32x8, a: V3, b: V3) -> V3 {
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
struct Frame {
    s: V3,
    t: V3,
    n: V3,
}

impl Frame {
    /// `Frame::new`: Duff et al.'s branchless basis.
    #[inline(always)]
    fn new(n: V3) -> Frame {
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
    fn to_world(&self, v: V3) -> V3 {
        self.s.scale(v.x) + self.t.scale(v.y) + self.n.scale(v.z)
    }
}

/// `warp::cosine_hemisphere`, lane by lane.
#[inline(always)]
fn cosine_hemisphere(u: f32x8, v: f32x8) -> V3 {
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
fn offset_origin(p: V3, normal: V3, toward: V3, magnitude: f32x8) -> V3 {
    const RELATIVE: f32 = 1.0 / 65536.0;
    let n = V3::select(normal.dot(toward).simd_lt(f32x8::ZERO), -normal, normal);
    let scale = magnitude
        .max(p.abs().max_element())
        .max(f32x8::splat(f32::MIN_POSITIVE));
    p + n.scale(scale * f32x8::splat(RELATIVE))
}

/// `mis::power_heuristic`, lane by lane, its special cases included.
#[inline(always)]
fn power_heuristic(own: f32x8, other: f32x8) -> f32x8 {
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
