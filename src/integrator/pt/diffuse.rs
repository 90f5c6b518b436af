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
//! Why: one path's vertex repeats, scalar, the arithmetic of fifteen
//! others. Shading them together saves about 330 instructions per diffuse
//! vertex net of the staging (perf gate's `render-cornell-pt`, 17% of the
//! path tracer's instructions; docs/benchmarks.md, "The path tracer's
//! diffuse vertices in SIMD lanes").

use super::simd::{
    cosine_hemisphere, get3, lane_mask, offset_origin, oriented_frame, power_heuristic, roulette,
    set3, Lanes, Lanes3, V3,
};
use super::{Arrival, CameraPath, DirectLight, Vertex, ROULETTE_START};
use crate::bvh::LANES;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::light::{AreaLight, Light};
use crate::material::Albedo;
use crate::scene::Scene;
use std::f32::consts::FRAC_1_PI;
use wide::f32x8;

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
        let (_, ng, frame) = oriented_frame(normal, load3(&self.shading_normal), wo);

        // The next direction (`Bsdf::sample`, diffuse).
        let local = cosine_hemisphere(load(&self.direction[0]), load(&self.direction[1]));
        let pdf = local.z.max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI);
        let wi = frame.to_world(local);
        let reflected = local.z.simd_gt(f32x8::ZERO);
        let sampled = !pdf.simd_le(f32x8::ZERO) & !(wi.dot(ng).simd_gt(f32x8::ZERO) ^ reflected);
        let next_origin = offset_origin(position, normal, wi, magnitude);
        // A diffuse bounce leaves eta² as it is (it multiplies by 1).
        let (next, dies) = roulette(
            throughput * albedo,
            load(&self.eta_squared),
            mask(self.roulette_on),
            load(&self.roulette),
        );

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
