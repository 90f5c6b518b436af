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
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::integrator::simd::{
    diffuse_eval, get3, load, power_heuristic, set_bits, store, store3, Continued, Lanes, Lanes3,
    StagedVertices,
};
use crate::light::Light;
use crate::material::Albedo;
use crate::scene::Scene;
use wide::f32x8;

/// The staged inputs of a step's diffuse vertices, and their results.
#[derive(Default)]
pub(in crate::integrator) struct DiffuseLanes {
    vertices: StagedVertices,
    eta_squared: Lanes,
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
    /// The paths' next throughputs and rays, and which go on.
    next: Continued,
    pdf: Lanes,
}

impl DiffuseLanes {
    /// Forgets the previous step's lanes.
    pub fn clear(&mut self) {
        self.vertices.clear();
    }

    /// Shades every staged lane.
    pub fn shade(&mut self) {
        for base in self.vertices.halves() {
            self.shade_half(base);
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
        let chosen = scene.light_selector.sample(u_select);
        if let Some((index, pick)) = chosen {
            let Light::Area(light) = &scene.lights[index] else {
                let material = &scene.materials[arrival.material as usize];
                let bsdf = material.bsdf(&arrival.surface, arrival.wo);
                return Some(self.scatter(scene, arrival, &bsdf, numbers));
            };
            lanes.vertices.lights.stage(lane, light, pick, u_point);
        } else {
            // No light to sample: the sample adds the throughput times zero.
            self.radiance += self.throughput * Rgb::ZERO;
        }
        let surface = &arrival.surface;
        lanes.vertices.stage(
            lane,
            surface,
            arrival.wo,
            albedo.at(surface),
            self.throughput,
            numbers.direction,
            numbers.roulette,
            self.segments >= ROULETTE_START,
        );
        lanes.eta_squared[lane] = self.eta_squared;
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
        if lanes.vertices.lights.lit & bit != 0 {
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
        if out.next.sampled & bit == 0 {
            return Vertex {
                direct,
                continues: false,
            };
        }
        // A diffuse bounce leaves eta² as it is (it multiplies by 1).
        let (throughput, origin, dir) = out.next.get(lane);
        self.throughput = throughput;
        self.previous_pdf = out.pdf[lane];
        self.previous_delta = false;
        self.previous_position = lanes.vertices.position(lane);
        self.ray = Ray::new(origin, dir);
        Vertex {
            direct,
            continues: out.next.survives & bit != 0,
        }
    }
}

impl DiffuseLanes {
    /// The SIMD pass over lanes `base .. base + 8`.
    fn shade_half(&mut self, base: usize) {
        let v = self.vertices.vertices(base);
        let out = &mut self.out;
        out.next
            .store(&v, v.albedo, load(&self.eta_squared, base), base);
        store(v.pdf, &mut out.pdf, base);

        let lights = &self.vertices.lights;
        if (lights.lit >> base) & 0xff == 0 {
            set_bits(&mut out.direct_some, f32x8::ZERO, base);
            return;
        }
        // The light sample, the BSDF's value and density there, the weight
        // against BSDF sampling, and the estimate (`direct_light`).
        let light = lights.sample(base, v.position, v.normal, v.magnitude);
        let (f, bsdf_pdf) = diffuse_eval(v.albedo, v.frame.n, v.ng, light.wi);
        let some = light.some & !f.is_zero();
        let light_pdf = light.pick * light.pdf;
        let weight = power_heuristic(light_pdf, bsdf_pdf);
        let value = (f * light.radiance).scale(weight / light_pdf);
        let direct = v.throughput * value;

        set_bits(&mut out.direct_some, some, base);
        set_bits(&mut out.shadow_some, some & light.has_ray, base);
        store3(direct, &mut out.direct, base);
        store3(light.ray_origin, &mut out.shadow_origin, base);
        store3(light.ray_dir, &mut out.shadow_dir, base);
        store(light.ray_tmax, &mut out.shadow_tmax, base);
    }
}
