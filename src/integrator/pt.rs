//! Unidirectional path tracing with next-event estimation.
//!
//! At every non-delta vertex the path samples a light (chosen by power) and
//! the BSDF; the two estimates of direct light are combined by the power
//! heuristic. A BSDF-sampled ray that hits an emitter is weighted against the
//! light-sampling density it would have had; after a delta bounce (mirror,
//! glass) it counts in full, since light sampling could not produce it.
//!
//! `max_depth` counts path segments: the camera ray is segment 1, so direct
//! light needs 2. Russian roulette on the throughput ends long paths without
//! bias.

use super::connect::{sample_lens, unoccluded};
use super::mis::power_heuristic;
use super::walk::sample_direction;
use super::PixelSample;
use super::ROULETTE_START;
use crate::camera::Camera;
use crate::color::{is_black, Rgb};
use crate::geometry::ray::offset_origin;
use crate::geometry::Ray;
use crate::geometry::SurfacePoint;
use crate::light::Light;
use crate::material::{Bsdf, Transport};
use crate::sampling::Sampler;
use crate::scene::{Scene, NO_LIGHT};

/// The path tracer and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathTracer {
    /// The most segments a path may have, the camera ray included.
    pub max_depth: u32,
}

impl PathTracer {
    /// One sample of `pixel`: a jittered camera ray and the radiance along it.
    pub fn sample(&self, scene: &Scene, camera: &Camera, pixel: PixelSample) -> Rgb {
        let mut sampler = pixel.camera_sampler();
        let (jx, jy) = sampler.next_2d();
        let (x, y) = (pixel.x as f32 + jx, pixel.y as f32 + jy);
        let ray = camera.ray_from(sample_lens(camera, &mut sampler), x, y);
        radiance(scene, ray, &mut sampler, self.max_depth)
    }
}

/// Radiance arriving at the camera along `ray`.
pub fn radiance(scene: &Scene, mut ray: Ray, sampler: &mut Sampler, max_depth: u32) -> Rgb {
    let mut result = Rgb::ZERO;
    let mut throughput = Rgb::ONE;
    // What the previous vertex knew, to weigh an emitter hit by BSDF sampling.
    let mut previous_pdf = 0.0f32;
    let mut previous_delta = true;
    let mut previous_position = ray.origin;
    let mut segments = 0;
    // The product of eta² over the refractions so far. Radiance entering a
    // denser medium is scaled by 1/eta² and regains it on leaving; roulette
    // reads the throughput with that factor undone, or it would end most
    // paths inside glass just for being inside, and the caustics they carry
    // would come from a few heavily weighted survivors.
    let mut eta_squared = 1.0f32;

    loop {
        sampler.start_vertex();
        let Some(hit) = scene.intersect(&ray) else {
            if scene.environment.is_some() {
                result += throughput * escaped(scene, ray.dir, previous_delta, previous_pdf);
            }
            break;
        };
        segments += 1;
        let surface = scene.surface(&hit);
        let wo = -ray.dir;
        let shading = scene.shading[hit.triangle as usize];

        if shading.light != NO_LIGHT {
            if let Light::Area(light) = &scene.lights[shading.light as usize] {
                let emitted = light.emitted(wo);
                if !is_black(emitted) {
                    let weight = if previous_delta {
                        1.0
                    } else {
                        let light_pdf = scene.light_selector.pmf(shading.light as usize)
                            * light.pdf_incident(previous_position, surface.position);
                        power_heuristic(previous_pdf, light_pdf)
                    };
                    result += throughput * emitted * weight;
                }
            }
        }
        if segments >= max_depth {
            break;
        }

        let bsdf = scene.materials[shading.material as usize].bsdf(&surface, wo);
        // The numbers are drawn in the order they always were (the light
        // sample's, then the BSDF's), but the next direction is sampled
        // before the shadow ray is traced, so that its chain of dependent
        // divisions and square roots can run while the shadow ray is
        // traversed (see `Walk::follow` for what that measured). Tracing
        // the next closest hit before the shadow ray as well was slower.
        let light_numbers = (!bsdf.is_delta()).then(|| (sampler.next_1d(), sampler.next_2d()));
        let sampled = sample_direction(&bsdf, wo, sampler, Transport::Radiance);
        if let Some((u_select, u_point)) = light_numbers {
            result += throughput * direct_light(scene, &surface, &bsdf, wo, u_select, u_point);
        }
        let Some(s) = sampled else {
            break;
        };
        throughput *= s.weight;
        eta_squared *= s.eta * s.eta;
        previous_pdf = s.pdf;
        previous_delta = s.delta;
        previous_position = surface.position;
        ray = Ray::new(
            offset_origin(
                surface.position,
                surface.geometric_normal,
                s.wi,
                surface.magnitude,
            ),
            s.wi,
        );

        if segments >= ROULETTE_START {
            let survive = (throughput.max_element() * eta_squared).min(1.0);
            if sampler.next_1d() >= survive {
                break;
            }
            throughput /= survive;
        }
    }
    result
}

/// The environment seen along `dir` by a ray that left the scene, weighted
/// against light sampling as an emitter hit is.
#[inline(never)]
fn escaped(scene: &Scene, dir: glam::Vec3, previous_delta: bool, previous_pdf: f32) -> Rgb {
    let Some((index, environment)) = scene.environment() else {
        return Rgb::ZERO;
    };
    let radiance = environment.radiance(dir);
    if previous_delta {
        return radiance;
    }
    let light_pdf = scene.light_selector.pmf(index) * environment.pdf_direction(dir);
    radiance * power_heuristic(previous_pdf, light_pdf)
}

/// One light sample at a non-delta surface, MIS-weighted against BSDF
/// sampling: `u_select` chooses the light, `u_point` the point on it.
fn direct_light(
    scene: &Scene,
    surface: &SurfacePoint,
    bsdf: &Bsdf,
    wo: glam::Vec3,
    u_select: f32,
    u_point: (f32, f32),
) -> Rgb {
    let Some((index, pick)) = scene.light_selector.sample(u_select) else {
        return Rgb::ZERO;
    };
    let Some(sample) = scene.lights[index].sample_incident(surface.position, u_point) else {
        return Rgb::ZERO;
    };
    let f = bsdf.eval(wo, sample.wi);
    if is_black(f) || !unoccluded(scene, surface, &sample) {
        return Rgb::ZERO;
    }
    let light_pdf = pick * sample.pdf;
    let weight = if sample.delta {
        1.0
    } else {
        power_heuristic(light_pdf, bsdf.pdf(wo, sample.wi))
    };
    f * sample.value * (weight / light_pdf)
}
