//! What light tracing and BDPT share: random-walk state with the MIS
//! bookkeeping of Georgiev's "Implementing Vertex Connection and Merging"
//! (2012, "the report" below), starting light paths, scattering, and
//! connecting light vertices to the camera.
//!
//! Every subpath carries two running quantities, `d_vcm` and `d_vc` (the
//! report's eqs. 31–35 with vertex merging switched off), from which the MIS
//! weight of any connection follows in constant time. Densities enter them
//! through `mis` (the power heuristic's square). Russian roulette is left out
//! of these densities on purpose: the weights are then a function of the path
//! alone, so they sum to one over all strategies whatever roulette does, and
//! roulette stays an unbiased reweighting of the throughput.

use super::ROULETTE_START;
use crate::color::{is_black, is_finite, Rgb};
use crate::film::Splat;
use crate::geometry::ray::offset_origin;
use crate::geometry::Ray;
use crate::material::{Bsdf, SurfacePoint, Transport};
use crate::sampling::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// The power heuristic (β = 2) applied to one density or density ratio.
pub fn mis(x: f32) -> f32 {
    x * x
}

/// A random walk in progress, from the camera or from a light.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    pub origin: Vec3,
    pub dir: Vec3,
    pub throughput: Rgb,
    /// Segments from the walk's start to the vertex it is about to find.
    pub length: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
    /// False for walks from a directional light: their first segment has no length.
    pub finite_start: bool,
}

/// A non-delta vertex of a light subpath, kept for connections.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub surface: SurfacePoint,
    pub bsdf: Bsdf,
    /// Unit direction towards the previous vertex (where the light came from).
    pub wo: Vec3,
    pub throughput: Rgb,
    /// Segments from the light to this vertex.
    pub length: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
}

impl Walk {
    /// Updates the MIS quantities for arriving at a surface at `distance`
    /// with `cos_in` between the ray and the geometric normal (report eq. 31).
    pub fn arrive(&mut self, distance: f32, cos_in: f32) {
        if self.length > 1 || self.finite_start {
            self.d_vcm *= mis(distance * distance);
        }
        let c = mis(cos_in);
        self.d_vcm /= c;
        self.d_vc /= c;
    }

    /// Samples the next direction at `surface`; false when the walk ends
    /// (no valid direction, or Russian roulette).
    pub fn scatter(
        &mut self,
        bsdf: &Bsdf,
        surface: &SurfacePoint,
        wo: Vec3,
        sampler: &mut Sampler,
        mode: Transport,
    ) -> bool {
        let u = sampler.next_2d();
        let u_lobe = sampler.next_1d();
        let Some(s) = bsdf.sample(wo, u, u_lobe, mode) else {
            return false;
        };
        let cos_out = s.wi.dot(surface.geometric_normal).abs();
        if s.delta {
            // Report eq. 34–35 for a specular vertex: it cannot be connected.
            self.d_vcm = 0.0;
            self.d_vc *= mis(cos_out);
        } else {
            let (_, reverse_pdf) = bsdf.pdfs(wo, s.wi);
            self.d_vc = mis(cos_out / s.pdf) * (self.d_vc * mis(reverse_pdf) + self.d_vcm);
            self.d_vcm = mis(1.0 / s.pdf);
        }
        self.throughput *= s.weight;
        self.origin = offset_origin(
            surface.position,
            surface.geometric_normal,
            s.wi,
            surface.magnitude,
        );
        self.dir = s.wi;
        if self.length >= ROULETTE_START {
            let survive = self.throughput.max_element().min(1.0);
            if sampler.next_1d() >= survive {
                return false;
            }
            self.throughput /= survive;
        }
        true
    }
}

/// Light paths per unit of samples per pixel: one per pixel.
pub fn light_paths_per_pass(scene: &Scene) -> f32 {
    (scene.camera.width() as f32) * (scene.camera.height() as f32)
}

/// Chooses a light by power and starts a walk from it (report eqs. 31–33).
/// Also returns the light's index, the emission sample and the pick probability.
pub fn start_light_walk(
    scene: &Scene,
    sampler: &mut Sampler,
) -> Option<(Walk, usize, crate::light::EmissionSample, f32)> {
    let (index, pick) = scene.light_selector.sample(sampler.next_1d())?;
    let light = &scene.lights[index];
    let u_pos = sampler.next_2d();
    let u_dir = sampler.next_2d();
    let e = light.sample_emission(u_pos, u_dir)?;
    let emission_pdf = e.emission_pdf * pick;
    let direct_pdf = e.direct_pdf_area * pick;
    let origin = if e.normal == Vec3::ZERO {
        e.origin
    } else {
        offset_origin(e.origin, e.normal, e.dir, e.magnitude)
    };
    let cos_used = if light.is_finite() { e.cos_light } else { 1.0 };
    let walk = Walk {
        origin,
        dir: e.dir,
        throughput: e.value / emission_pdf,
        length: 1,
        d_vcm: mis(direct_pdf / emission_pdf),
        d_vc: if light.is_delta() {
            0.0
        } else {
            mis(cos_used / emission_pdf)
        },
        finite_start: light.is_finite(),
    };
    Some((walk, index, e, pick))
}

/// A point a shadow ray can start or end at: its normal (zero for points
/// not on a surface, such as the camera) and its triangle's coordinate
/// magnitude, which sets how far it is moved off its surface.
#[derive(Clone, Copy, Debug)]
pub struct Endpoint {
    pub position: Vec3,
    pub normal: Vec3,
    pub magnitude: f32,
}

impl Endpoint {
    pub fn surface(s: &SurfacePoint) -> Endpoint {
        Endpoint {
            position: s.position,
            normal: s.geometric_normal,
            magnitude: s.magnitude,
        }
    }

    pub fn point(position: Vec3) -> Endpoint {
        Endpoint {
            position,
            normal: Vec3::ZERO,
            magnitude: 0.0,
        }
    }

    /// The position moved off its surface towards `toward`.
    fn lifted(&self, toward: Vec3) -> Vec3 {
        if self.normal == Vec3::ZERO {
            self.position
        } else {
            offset_origin(self.position, self.normal, toward, self.magnitude)
        }
    }
}

/// Whether the segment between two points is free, each end moved off its surface.
pub fn visible(scene: &Scene, from: Endpoint, to: Endpoint) -> bool {
    let dir = to.position - from.position;
    let origin = from.lifted(dir);
    let target = to.lifted(-dir);
    let d = target - origin;
    let distance = d.length();
    if distance.is_nan() || distance <= 0.0 {
        return true;
    }
    !scene.occluded(&Ray::segment(origin, d / distance, distance))
}

/// What a light-side point at `position` contributes to the pixel it
/// projects to, given `value` = (light-path weight) × f × cos towards the
/// camera. Returns the pixel and the factor that turns `value` into a splat:
/// the camera's importance over the light path count (report §5.1), and the
/// camera's area density (for MIS, in per-pixel units over the path count).
pub struct CameraConnection {
    pub pixel: u32,
    pub dir_to_camera: Vec3,
    pub distance: f32,
    /// (distance to the image point)² / cos at the camera: solid angle to image area.
    image_to_solid_angle: f32,
}

impl CameraConnection {
    pub fn new(scene: &Scene, position: Vec3) -> Option<CameraConnection> {
        let camera = &scene.camera;
        let (x, y) = camera.project(position)?;
        let to_camera = camera.position - position;
        let distance = to_camera.length();
        let dir_to_camera = to_camera / distance;
        let cos_camera = (-dir_to_camera).dot(camera.forward());
        if cos_camera <= 0.0 || distance <= 0.0 {
            return None;
        }
        let image_distance = camera.image_plane_distance() / cos_camera;
        Some(CameraConnection {
            pixel: y as u32 * camera.width() + x as u32,
            dir_to_camera,
            distance,
            image_to_solid_angle: image_distance * image_distance / cos_camera,
        })
    }

    /// The camera's density of choosing this point, in area measure at the
    /// point whose surface makes `cos_surface` with the direction to the camera.
    pub fn camera_pdf_area(&self, cos_surface: f32) -> f32 {
        self.image_to_solid_angle * cos_surface / (self.distance * self.distance)
    }

    /// Turns `f · cos` (times the path weight) into the splatted value.
    pub fn splat(&self, value: Rgb, light_paths: f32) -> Rgb {
        value * (self.image_to_solid_angle / (light_paths * self.distance * self.distance))
    }
}

/// One strategy's share of one sample, kept only for `--bdpt-strategies`.
/// A path of `s` light vertices (the light's own point included) joined to
/// `t` camera vertices (the pinhole included).
#[derive(Clone, Copy, Debug)]
pub struct StrategySample {
    pub s: u32,
    pub t: u32,
    pub pixel: u32,
    /// The strategy's estimate alone, as if it were the only one.
    pub unweighted: Rgb,
    /// Its MIS weight: `unweighted × weight` is what enters the image.
    pub weight: f32,
}

/// What the light side of a sample produces besides the camera pixel's own
/// estimate: splats to other pixels, discarded splats, and optionally
/// per-strategy records.
#[derive(Default)]
pub struct SplatSink {
    pub splats: Vec<Splat>,
    /// Splats dropped for being NaN or infinite.
    pub discarded: u64,
    pub strategies: Option<Vec<StrategySample>>,
}

impl SplatSink {
    fn emit(&mut self, pixel: u32, value: Rgb) {
        if is_finite(value) {
            self.splats.push(Splat { pixel, value });
        } else {
            self.discarded += 1;
        }
    }

    /// Records a strategy's contribution when strategies are being kept.
    pub fn record(&mut self, s: u32, t: u32, pixel: u32, unweighted: Rgb, weight: f32) {
        if let Some(list) = self.strategies.as_mut() {
            if weight > 0.0 && is_finite(unweighted) && !is_black(unweighted) {
                list.push(StrategySample {
                    s,
                    t,
                    pixel,
                    unweighted,
                    weight,
                });
            }
        }
    }
}

/// Traces one light subpath. Every non-delta vertex is connected to the
/// camera (t = 1) and splatted; with `keep` the vertices are also stored for
/// BDPT's connections. Splats and strategy records go to `sink`.
/// `light_tracing_only` selects the pure light tracer:
/// no MIS weight, and the light's own point is also connected to the camera
/// (which BDPT leaves to camera paths that hit the light, s = 0).
#[allow(clippy::too_many_arguments)]
pub fn trace_light_path(
    scene: &Scene,
    sampler: &mut Sampler,
    max_depth: u32,
    light_tracing_only: bool,
    mut keep: Option<&mut Vec<LightVertex>>,
    sink: &mut SplatSink,
) {
    sampler.start_vertex();
    let Some((mut walk, index, emission, pick)) = start_light_walk(scene, sampler) else {
        return;
    };
    let paths = light_paths_per_pass(scene);

    if light_tracing_only {
        if let crate::light::Light::Area(light) = &scene.lights[index] {
            // s = 1, t = 1: the light seen directly by the camera.
            if let Some(c) = CameraConnection::new(scene, emission.origin) {
                let le = light.emitted(c.dir_to_camera);
                let cos = c.dir_to_camera.dot(light.normal).abs();
                if !is_black(le)
                    && visible(
                        scene,
                        Endpoint {
                            position: emission.origin,
                            normal: light.normal,
                            magnitude: light.magnitude,
                        },
                        Endpoint::point(scene.camera.position),
                    )
                {
                    let value = le * cos / (pick * emission.direct_pdf_area);
                    sink.emit(c.pixel, c.splat(value, paths));
                }
            }
        }
    }

    loop {
        // A vertex here is walk.length segments from the light, and one more to the camera.
        if walk.length + 1 > max_depth {
            break;
        }
        let ray = Ray::new(walk.origin, walk.dir);
        let Some(hit) = scene.intersect(&ray) else {
            break;
        };
        let surface = scene.surface(&hit);
        let wo = -ray.dir;
        walk.arrive(hit.t, wo.dot(surface.geometric_normal).abs());
        let material = &scene.materials[scene.shading[hit.triangle as usize].material as usize];
        let bsdf = material.bsdf(&surface, wo);

        if !bsdf.is_delta() {
            if let Some(vertices) = keep.as_deref_mut() {
                vertices.push(LightVertex {
                    surface,
                    bsdf,
                    wo,
                    throughput: walk.throughput,
                    length: walk.length,
                    d_vcm: walk.d_vcm,
                    d_vc: walk.d_vc,
                });
            }
            // t = 1: this vertex seen by the camera (report eq. 44 for the weight).
            if let Some(c) = CameraConnection::new(scene, surface.position) {
                let f = bsdf.eval_mode(wo, c.dir_to_camera, Transport::Importance);
                if !is_black(f)
                    && visible(
                        scene,
                        Endpoint::surface(&surface),
                        Endpoint::point(scene.camera.position),
                    )
                {
                    let weight = if light_tracing_only {
                        1.0
                    } else {
                        let (_, reverse_pdf) = bsdf.pdfs(wo, c.dir_to_camera);
                        let cos_surface = c.dir_to_camera.dot(surface.geometric_normal).abs();
                        let w_light = mis(c.camera_pdf_area(cos_surface) / paths)
                            * (walk.d_vcm + walk.d_vc * mis(reverse_pdf));
                        1.0 / (w_light + 1.0)
                    };
                    let value = c.splat(walk.throughput * f, paths);
                    sink.emit(c.pixel, value * weight);
                    sink.record(walk.length + 1, 1, c.pixel, value, weight);
                }
            }
        }
        // A further vertex would need at least one more segment to reach the camera.
        if walk.length + 2 > max_depth {
            break;
        }
        sampler.start_vertex();
        if !walk.scatter(&bsdf, &surface, wo, sampler, Transport::Importance) {
            break;
        }
        walk.length += 1;
    }
}
