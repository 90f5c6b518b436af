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

use super::{Arrival, CameraPath, DirectLight, Vertex, ROULETTE_START};
use crate::bvh::LANES;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::integrator::simd::{
    cosine_hemisphere, diffuse_eval, get3, lane_mask, load, load3, offset_origin, oriented_frame,
    power_heuristic, roulette, set3, set_bits, store, store3, Lanes, Lanes3, StagedLights,
};
use crate::light::Light;
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
    /// The lanes' lights to sample.
    lights: StagedLights,
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
        self.lights.clear();
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
            lanes.lights.stage(lane, light, pick, u_point);
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
        if lanes.lights.lit & bit != 0 {
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
    /// The SIMD pass over lanes `base .. base + 8`.
    fn shade_half(&mut self, base: usize) {
        let mask = |bits: u32| lane_mask(bits >> base);
        let position = load3(&self.position, base);
        let normal = load3(&self.normal, base);
        let wo = load3(&self.wo, base);
        let magnitude = load(&self.magnitude, base);
        let throughput = load3(&self.throughput, base);
        let albedo = load3(&self.albedo, base);

        // The BSDF (`Material::bsdf`): the normals turned to `wo`'s side,
        // and the shading frame around the shading normal.
        let (_, ng, frame) = oriented_frame(normal, load3(&self.shading_normal, base), wo);

        // The next direction (`Bsdf::sample`, diffuse).
        let local = cosine_hemisphere(
            load(&self.direction[0], base),
            load(&self.direction[1], base),
        );
        let pdf = local.z.max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI);
        let wi = frame.to_world(local);
        let reflected = local.z.simd_gt(f32x8::ZERO);
        let sampled = !pdf.simd_le(f32x8::ZERO) & !(wi.dot(ng).simd_gt(f32x8::ZERO) ^ reflected);
        let next_origin = offset_origin(position, normal, wi, magnitude);
        // A diffuse bounce leaves eta² as it is (it multiplies by 1).
        let (next, dies) = roulette(
            throughput * albedo,
            load(&self.eta_squared, base),
            mask(self.roulette_on),
            load(&self.roulette, base),
        );

        let out = &mut self.out;
        set_bits(&mut out.sampled, sampled, base);
        set_bits(&mut out.survives, !dies, base);
        store3(next, &mut out.throughput, base);
        store(pdf, &mut out.pdf, base);
        store3(next_origin, &mut out.next_origin, base);
        store3(wi, &mut out.next_dir, base);

        if (self.lights.lit >> base) & 0xff == 0 {
            set_bits(&mut out.direct_some, f32x8::ZERO, base);
            return;
        }
        // The light sample, the BSDF's value and density there, the weight
        // against BSDF sampling, and the estimate (`direct_light`).
        let light = self.lights.sample(base, position, normal, magnitude);
        let (f, bsdf_pdf) = diffuse_eval(albedo, frame.n, ng, light.wi);
        let some = light.some & !f.is_zero();
        let light_pdf = light.pick * light.pdf;
        let weight = power_heuristic(light_pdf, bsdf_pdf);
        let value = (f * light.radiance).scale(weight / light_pdf);
        let direct = throughput * value;

        set_bits(&mut out.direct_some, some, base);
        set_bits(&mut out.shadow_some, some & light.has_ray, base);
        store3(direct, &mut out.direct, base);
        store3(light.ray_origin, &mut out.shadow_origin, base);
        store3(light.ray_dir, &mut out.shadow_dir, base);
        store(light.ray_tmax, &mut out.shadow_tmax, base);
    }
}
