//! Following a light subpath, and joining its vertices to the camera (the
//! t = 1 strategy). Light tracing and BDPT both walk light paths this way;
//! they differ only in what they do at each vertex.

use super::connect::{sample_lens, segment_ray, visible, CameraConnection, Endpoint};
use super::walk::{start_light_walk, LightStart, LightVertex, MergeWeights, Walk};
use crate::bvh::Hit;
use crate::camera::Camera;
use crate::color::{is_black, Rgb};
use crate::geometry::{Ray, SurfacePoint};
use crate::material::{Material, Transport};
use crate::sampling::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// The start of a light path: its numbers from a fresh group, a light and
/// the walk's first point and direction on it, then the lens point its
/// connections to the camera aim at (drawn only by a thin lens). Light
/// tracing and BDPT begin here, and BDPT's lanes make the same draws in
/// the same order (`bdpt_lanes.rs`, through `emission_numbers`), so their
/// paths agree. `None` when no light can start one.
#[inline(always)]
pub fn begin_light_path(
    scene: &Scene,
    camera: &Camera,
    sampler: &mut Sampler,
    merging: MergeWeights,
) -> Option<(LightStart, Vec3)> {
    sampler.start_vertex();
    let start = start_light_walk(scene, sampler, merging)?;
    Some((start, sample_lens(camera, sampler)))
}

/// Continues `walk` from a light, calling `visit` (which must draw no
/// numbers from `sampler`) at every vertex that is not a delta (the
/// vertices a connection can reach), until the path would need more than
/// `max_depth` segments to reach the camera, leaves the scene, or ends by
/// Russian roulette.
pub fn follow_light_walk(
    scene: &Scene,
    sampler: &mut Sampler,
    mut walk: Walk,
    max_depth: u32,
    mut visit: impl FnMut(&LightVertex),
) {
    while looks_further(&walk, max_depth) {
        let Some(hit) = scene.intersect(&Ray::new(walk.origin, walk.dir)) else {
            break;
        };
        if !light_vertex(scene, sampler, &mut walk, max_depth, &hit, &mut visit) {
            break;
        }
    }
}

/// Whether a light walk looks for another vertex: one it reaches is
/// `walk.length` segments from the light, and one more from the camera.
#[inline(always)]
pub fn looks_further(walk: &Walk, max_depth: u32) -> bool {
    walk.length < max_depth
}

/// One vertex of a light walk, where its ray found `hit`: `visit` (which
/// must draw no numbers from `sampler`) sees it if it is not a delta, and
/// the walk moves on to its next ray, unless it ends there. Returns
/// whether it goes on.
#[inline(always)]
pub fn light_vertex(
    scene: &Scene,
    sampler: &mut Sampler,
    walk: &mut Walk,
    max_depth: u32,
    hit: &Hit,
    visit: &mut impl FnMut(&LightVertex),
) -> bool {
    let (surface, wo, material) = light_arrive(scene, walk, hit);
    light_scatter(sampler, walk, max_depth, (surface, wo, material), visit)
}

/// The first part of a light vertex: the surface the walk's ray found at
/// `hit`, the direction back along the ray, and the material, the walk's
/// weights carried to the vertex.
#[inline(always)]
pub fn light_arrive<'a>(
    scene: &'a Scene,
    walk: &mut Walk,
    hit: &Hit,
) -> (SurfacePoint, Vec3, &'a Material) {
    let surface = scene.surface(hit);
    let wo = -walk.dir;
    walk.arrive(hit.t, wo.dot(surface.geometric_normal).abs());
    let material = &scene.materials[scene.shading[hit.triangle as usize].material as usize];
    (surface, wo, material)
}

/// Whether a light walk at a vertex goes on to look for another: a
/// further vertex would need at least one more segment to reach the camera.
#[inline(always)]
pub fn light_goes_on(walk: &Walk, max_depth: u32) -> bool {
    walk.length + 2 <= max_depth
}

/// The rest of a light vertex after `light_arrive`: the visit, and the
/// walk followed. Returns whether it goes on.
#[inline(always)]
pub fn light_scatter(
    sampler: &mut Sampler,
    walk: &mut Walk,
    max_depth: u32,
    (surface, wo, material): (SurfacePoint, Vec3, &Material),
    visit: &mut impl FnMut(&LightVertex),
) -> bool {
    let bsdf = material.bsdf(&surface, wo);
    // The next direction before the visit's shadow ray (see `Walk::follow`);
    // the visit draws no numbers, so they are the same either way.
    let numbers = light_goes_on(walk, max_depth).then(|| sampler.walk_numbers());
    let sampled = numbers.and_then(|n| bsdf.sample(wo, n.direction, n.lobe, Transport::Importance));

    if !bsdf.is_delta() {
        visit(&LightVertex::new(surface, bsdf, wo, walk));
    }
    let Some(numbers) = numbers else {
        return false;
    };
    if !walk.follow(
        sampled,
        &bsdf,
        &surface,
        wo,
        numbers.roulette,
        Transport::Importance,
    ) {
        return false;
    }
    walk.length += 1;
    true
}

/// A light vertex seen by the camera: where it lands, and its splat before
/// any MIS weight (`None` when it is outside the image, behind the camera,
/// occluded, or reflects nothing towards the camera).
// Always inlined: left to itself the compiler outlines it once the BSDF
// enum grows, which costs light tracing 3% (perf gate, callgrind).
#[inline(always)]
pub fn camera_splat(
    scene: &Scene,
    camera: &Camera,
    lens: Vec3,
    v: &LightVertex,
    light_paths: f32,
) -> Option<(CameraConnection, Rgb)> {
    let (c, f) = camera_connection(camera, lens, v)?;
    if !visible(
        scene,
        Endpoint::surface(&v.surface),
        Endpoint::point(c.lens),
    ) {
        return None;
    }
    let value = c.splat(v.throughput * f, light_paths);
    Some((c, value))
}

/// [`camera_splat`] with its shadow ray left to the caller: the splat
/// should the ray (`None`: nothing can block it) be free.
#[inline(always)]
pub fn camera_splat_unshadowed(
    camera: &Camera,
    lens: Vec3,
    v: &LightVertex,
    light_paths: f32,
) -> Option<(CameraConnection, Rgb, Option<Ray>)> {
    let (c, f) = camera_connection(camera, lens, v)?;
    let ray = segment_ray(Endpoint::surface(&v.surface), Endpoint::point(c.lens));
    let value = c.splat(v.throughput * f, light_paths);
    Some((c, value, ray))
}

/// The light vertex's connection to the lens point `lens`, and its BSDF
/// value towards it; `None` where it lands outside the image or reflects
/// nothing towards the camera.
#[inline(always)]
fn camera_connection(
    camera: &Camera,
    lens: Vec3,
    v: &LightVertex,
) -> Option<(CameraConnection, Rgb)> {
    let c = CameraConnection::new(camera, lens, v.surface.position)?;
    let f = v
        .bsdf
        .eval_mode(v.wo, c.dir_to_camera, Transport::Importance);
    (!is_black(f)).then_some((c, f))
}
