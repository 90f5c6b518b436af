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

mod diffuse;

pub(super) use diffuse::DiffuseLanes;

use super::connect::{sample_lens, shadow_ray};
use super::mis::power_heuristic;
use super::PixelSample;
use super::ROULETTE_START;
use crate::bvh::Hit;
use crate::camera::Camera;
use crate::color::{is_black, Rgb};
use crate::geometry::ray::offset_origin;
use crate::geometry::Ray;
use crate::geometry::SurfacePoint;
use crate::light::Light;
use crate::material::{Bsdf, Transport};
use crate::sampling::{Sampler, VertexNumbers};
use crate::scene::{Scene, NO_LIGHT};
use glam::Vec3;

/// The path tracer and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathTracer {
    /// The most segments a path may have, the camera ray included.
    pub max_depth: u32,
}

impl PathTracer {
    /// One sample of `pixel`: a jittered camera ray and the radiance along
    /// it. The renderer takes the path tracer's samples in lanes
    /// (`lanes.rs`); this one-path-at-a-time form is the reference the
    /// lanes are tested against. Out of line: inlined into the tile loop,
    /// it made the other integrators' code there slower.
    #[inline(never)]
    pub fn sample(&self, scene: &Scene, camera: &Camera, pixel: PixelSample) -> Rgb {
        let mut path = CameraPath::start(camera, pixel);
        loop {
            let hit = scene.intersect(&path.ray);
            let vertex = path.vertex(scene, hit, self.max_depth);
            if let Some(direct) = vertex.direct {
                if direct.shadow.is_none_or(|ray| !scene.occluded(&ray)) {
                    path.add_direct(direct.value);
                } else {
                    path.add_direct(direct.blocked);
                }
            }
            if !vertex.continues {
                return path.radiance;
            }
        }
    }
}

/// A camera path in progress: the ray it is about to trace, the radiance
/// it has gathered, and what its next vertex needs to know. The path
/// tracer's one step is [`CameraPath::vertex`]: `PathTracer::sample` takes
/// a path's steps one after another, `lanes` takes those of sixteen paths
/// in turn, tracing their rays together; both compute the same numbers.
pub(super) struct CameraPath {
    /// The ray to the path's next vertex.
    pub ray: Ray,
    /// Radiance gathered so far, the direct light of shadow rays still out
    /// excepted.
    pub radiance: Rgb,
    sampler: Sampler,
    throughput: Rgb,
    /// What the previous vertex knew, to weigh an emitter hit by BSDF sampling.
    previous_pdf: f32,
    previous_delta: bool,
    previous_position: Vec3,
    segments: u32,
    /// The product of eta² over the refractions so far. Radiance entering a
    /// denser medium is scaled by 1/eta² and regains it on leaving; roulette
    /// reads the throughput with that factor undone, or it would end most
    /// paths inside glass just for being inside, and the caustics they carry
    /// would come from a few heavily weighted survivors.
    eta_squared: f32,
}

/// What a vertex leaves its caller to do.
#[derive(Clone, Copy, Debug)]
pub(super) struct Vertex {
    /// Direct light from a light sample, to add if its shadow ray is free.
    pub direct: Option<DirectLight>,
    /// Whether the path goes on along its new `ray`.
    pub continues: bool,
}

/// A light sample's contribution, throughput included, and the shadow ray
/// that decides it (`None`: nothing can block it).
#[derive(Clone, Copy, Debug)]
pub(super) struct DirectLight {
    /// What the light sample adds if its shadow ray is free.
    pub value: Rgb,
    /// What it adds if the shadow ray is blocked: the throughput times
    /// zero (see `CameraPath::vertex`).
    pub blocked: Rgb,
    pub shadow: Option<Ray>,
}

impl CameraPath {
    /// The path of `pixel`'s sample: a jittered ray through the pixel.
    #[inline(always)]
    pub fn start(camera: &Camera, pixel: PixelSample) -> CameraPath {
        let mut sampler = pixel.camera_sampler();
        let (jx, jy) = sampler.next_2d();
        let (x, y) = (pixel.x as f32 + jx, pixel.y as f32 + jy);
        let ray = camera.ray_from(sample_lens(camera, &mut sampler), x, y);
        CameraPath {
            ray,
            radiance: Rgb::ZERO,
            sampler,
            throughput: Rgb::ONE,
            previous_pdf: 0.0,
            previous_delta: true,
            previous_position: ray.origin,
            segments: 0,
            eta_squared: 1.0,
        }
    }

    /// Adds a vertex's direct light once its shadow ray is traced.
    #[inline(always)]
    pub fn add_direct(&mut self, value: Rgb) {
        self.radiance += value;
    }

    /// The path's vertex where its ray found `hit` (`None`: it left the
    /// scene): light emitted there, a light sample, and the next direction.
    #[inline(always)]
    pub fn vertex(&mut self, scene: &Scene, hit: Option<Hit>, max_depth: u32) -> Vertex {
        let Some(arrival) = self.arrive(scene, hit, max_depth) else {
            return Vertex::END;
        };
        self.shade(scene, &arrival)
    }

    /// The rest of the vertex at `arrival`: its BSDF, its numbers, a light
    /// sample and the next direction.
    #[inline(always)]
    pub fn shade(&mut self, scene: &Scene, arrival: &Arrival) -> Vertex {
        let bsdf = scene.materials[arrival.material as usize].bsdf(&arrival.surface, arrival.wo);
        let numbers = self.sampler.vertex_numbers(!bsdf.is_delta());
        self.scatter(scene, arrival, &bsdf, numbers)
    }

    /// The first part of a vertex: what the path's ray found (`hit`), and
    /// the light emitted there towards the path. `None` where the path ends
    /// here (it left the scene, or reached `max_depth` segments).
    #[inline(always)]
    pub fn arrive(&mut self, scene: &Scene, hit: Option<Hit>, max_depth: u32) -> Option<Arrival> {
        let Some(hit) = hit else {
            if scene.environment.is_some() {
                self.radiance += self.throughput
                    * escaped(scene, self.ray.dir, self.previous_delta, self.previous_pdf);
            }
            return None;
        };
        self.segments += 1;
        let surface = scene.surface(&hit);
        let wo = -self.ray.dir;
        let shading = scene.shading[hit.triangle as usize];

        if shading.light != NO_LIGHT {
            if let Light::Area(light) = &scene.lights[shading.light as usize] {
                let emitted = light.emitted(wo);
                if !is_black(emitted) {
                    let weight = if self.previous_delta {
                        1.0
                    } else {
                        let light_pdf = scene.light_selector.pmf(shading.light as usize)
                            * light.pdf_incident(self.previous_position, surface.position);
                        power_heuristic(self.previous_pdf, light_pdf)
                    };
                    self.radiance += self.throughput * emitted * weight;
                }
            }
        }
        if self.segments >= max_depth {
            return None;
        }
        Some(Arrival {
            surface,
            wo,
            material: shading.material,
        })
    }

    /// The rest of a vertex, given its BSDF and its numbers: a light
    /// sample, and the next direction.
    #[inline(always)]
    pub fn scatter(
        &mut self,
        scene: &Scene,
        arrival: &Arrival,
        bsdf: &Bsdf,
        numbers: VertexNumbers,
    ) -> Vertex {
        let Arrival { surface, wo, .. } = *arrival;
        let surface = &surface;
        // The shadow ray is the caller's to trace: a single path traces it
        // after this step, so the next direction's chain of divisions and
        // square roots runs while it is traversed (see `Walk::follow` for
        // what that measured); the lanes trace sixteen paths' shadow rays
        // together.
        let sampled = bsdf.sample(wo, numbers.direction, numbers.lobe, Transport::Radiance);
        let mut direct = None;
        if let Some((u_select, u_point)) = numbers.light {
            // A light sample that adds nothing still adds throughput × 0:
            // zero, unless the throughput has overflowed, when it makes
            // the sample NaN, and the renderer discards it.
            let nothing = self.throughput * Rgb::ZERO;
            match direct_light(scene, surface, bsdf, wo, u_select, u_point) {
                Some((value, shadow)) => {
                    direct = Some(DirectLight {
                        value: self.throughput * value,
                        shadow,
                        blocked: nothing,
                    })
                }
                None => self.radiance += nothing,
            }
        }
        let Some(s) = sampled else {
            return Vertex {
                direct,
                continues: false,
            };
        };
        self.throughput *= s.weight;
        self.eta_squared *= s.eta * s.eta;
        self.previous_pdf = s.pdf;
        self.previous_delta = s.delta;
        self.previous_position = surface.position;
        self.ray = Ray::new(
            offset_origin(
                surface.position,
                surface.geometric_normal,
                s.wi,
                surface.magnitude,
            ),
            s.wi,
        );

        let mut continues = true;
        if self.segments >= ROULETTE_START {
            let survive = (self.throughput.max_element() * self.eta_squared).min(1.0);
            if numbers.roulette >= survive {
                continues = false;
            } else {
                self.throughput /= survive;
            }
        }
        Vertex { direct, continues }
    }
}

/// Where a path's ray arrived, for the rest of its vertex: the surface,
/// the direction back along the ray, and the surface's material.
#[derive(Clone, Copy, Debug)]
pub(super) struct Arrival {
    pub surface: SurfacePoint,
    pub wo: Vec3,
    pub material: u32,
}

impl Vertex {
    /// A vertex where the path ends, with no light sample.
    pub const END: Vertex = Vertex {
        direct: None,
        continues: false,
    };
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
/// Returns what it adds if its shadow ray (`None`: nothing can block it)
/// is free; `None` where it adds nothing whatever the shadow ray finds.
#[inline(always)]
fn direct_light(
    scene: &Scene,
    surface: &SurfacePoint,
    bsdf: &Bsdf,
    wo: glam::Vec3,
    u_select: f32,
    u_point: (f32, f32),
) -> Option<(Rgb, Option<Ray>)> {
    let (index, pick) = scene.light_selector.sample(u_select)?;
    let sample = scene.lights[index].sample_incident(surface.position, u_point)?;
    let f = bsdf.eval(wo, sample.wi);
    if is_black(f) {
        return None;
    }
    let shadow = shadow_ray(surface, &sample);
    let light_pdf = pick * sample.pdf;
    let weight = if sample.delta {
        1.0
    } else {
        power_heuristic(light_pdf, bsdf.pdf(wo, sample.wi))
    };
    Some((f * sample.value * (weight / light_pdf), shadow))
}
