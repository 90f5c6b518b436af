//! The path tracer sixteen paths at a time. Each path takes the same steps
//! as alone ([`CameraPath::vertex`]), but the sixteen paths' rays to their
//! next vertices are traced in one call, and so are their shadow rays:
//! tracing is then work on sixteen independent rays, which the processor
//! can overlap, where one path alone waits on each hit before it can
//! shade, and on its shading before it can trace again. A lane whose path
//! ends takes the next path at once (path regeneration), so lanes stay
//! busy however unequal the paths' lengths.
//!
//! The paths whose rays land on Lambertian surfaces are also shaded
//! together, eight lanes per SIMD operation (`pt/diffuse.rs`), with each
//! lane's arithmetic that of the one-path vertex.
//!
//! Every path is a pure function of its pixel and sample index, and its
//! estimate lands in its own slot, so the image is the one-path-at-a-time
//! path tracer's, bit for bit (a test checks it).

use super::pt::{CameraPath, DiffuseLanes, Vertex};
use super::{PathTracer, PixelSample};
use crate::bvh::{for_lanes, LANES};
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::material::Material;
use crate::scene::Scene;
use glam::Vec3;

/// The bits of every lane.
const ALL_LANES: u32 = u32::MAX >> (32 - LANES);

impl PathTracer {
    /// Samples `pixels[p].index .. + count` of each pixel `pixels[p]`:
    /// `out[p * count + i]` gets what [`PathTracer::sample`] returns for
    /// sample `pixels[p].index + i`. Out of line, so that what the
    /// compiler inlines into it does not depend on the other integrators'
    /// code beside it in the dispatch.
    #[inline(never)]
    pub fn sample_pixels(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixels: &[PixelSample],
        count: u32,
        out: &mut [Rgb],
    ) {
        let count = count as usize;
        let total = pixels.len() * count;
        assert_eq!(out.len(), total, "one slot per sample");
        let Some(&first_pixel) = pixels.first() else {
            return;
        };
        // Each lane's path, and the slot of `out` it fills; a lane is in
        // use while its bit is set in `active`.
        let mut paths: [CameraPath; LANES] =
            std::array::from_fn(|_| CameraPath::start(camera, first_pixel));
        let mut slots = [0; LANES];
        let mut active = 0u32;
        let mut next = 0;
        let unused = Ray::new(Vec3::ZERO, Vec3::Z);
        let mut rays = [unused; LANES];
        let mut shadow_rays = [unused; LANES];
        let mut direct = [Rgb::ZERO; LANES];
        let mut if_blocked = [Rgb::ZERO; LANES];
        let mut hits = [None; LANES];
        let mut diffuse = DiffuseLanes::default();
        loop {
            let mut free = !active & ALL_LANES;
            while free != 0 && next < total {
                let lane = free.trailing_zeros() as usize;
                free &= free - 1;
                let pixel = pixels[next / count];
                let sample = pixel.with_index(pixel.index + (next % count) as u64);
                paths[lane] = CameraPath::start(camera, sample);
                slots[lane] = next;
                active |= 1 << lane;
                next += 1;
            }
            if active == 0 {
                return;
            }
            for_lanes(active, |lane| rays[lane] = paths[lane].ray);
            scene.intersect_lanes(&rays, active, &mut hits);
            let mut step = Step {
                shadowed: 0,
                ended: 0,
                shadow_rays: &mut shadow_rays,
                direct: &mut direct,
                if_blocked: &mut if_blocked,
            };
            // Vertices on diffuse surfaces are staged and shaded together
            // (see `pt/diffuse.rs`); the others one path at a time.
            diffuse.clear();
            let mut staged = 0u32;
            for_lanes(active, |lane| {
                let path = &mut paths[lane];
                let Some(arrival) = path.arrive(scene, hits[lane], self.max_depth) else {
                    step.ended |= 1 << lane;
                    return;
                };
                let vertex = match &scene.materials[arrival.material as usize] {
                    Material::Diffuse { albedo } => {
                        match path.stage_diffuse(scene, &arrival, albedo, lane, &mut diffuse) {
                            None => {
                                staged |= 1 << lane;
                                return;
                            }
                            Some(vertex) => vertex,
                        }
                    }
                    _ => path.shade(scene, &arrival),
                };
                step.take(lane, path, vertex);
            });
            if staged != 0 {
                diffuse.shade();
                for_lanes(staged, |lane| {
                    let path = &mut paths[lane];
                    let vertex = path.finish_diffuse(lane, &diffuse);
                    step.take(lane, path, vertex);
                });
            }
            let (shadowed, ended) = (step.shadowed, step.ended);
            let blocked = scene.occluded_lanes(&shadow_rays, shadowed);
            for_lanes(shadowed, |lane| {
                let free = blocked & (1 << lane) == 0;
                paths[lane].add_direct(if free { direct[lane] } else { if_blocked[lane] })
            });
            for_lanes(ended, |lane| out[slots[lane]] = paths[lane].radiance);
            active &= !ended;
        }
    }
}

/// What a step's vertices leave to trace: the lanes whose light samples
/// wait on shadow rays (with what each adds if free, and if blocked), and
/// the lanes whose paths end.
struct Step<'a> {
    shadowed: u32,
    ended: u32,
    shadow_rays: &'a mut [Ray; LANES],
    direct: &'a mut [Rgb; LANES],
    if_blocked: &'a mut [Rgb; LANES],
}

impl Step<'_> {
    /// Takes lane `lane`'s vertex: its light sample waits on its shadow
    /// ray, or is added at once when nothing can block it.
    #[inline(always)]
    fn take(&mut self, lane: usize, path: &mut CameraPath, vertex: Vertex) {
        if let Some(light) = vertex.direct {
            match light.shadow {
                Some(ray) => {
                    self.shadow_rays[lane] = ray;
                    self.direct[lane] = light.value;
                    self.if_blocked[lane] = light.blocked;
                    self.shadowed |= 1 << lane;
                }
                None => path.add_direct(light.value),
            }
        }
        if !vertex.continues {
            self.ended |= 1 << lane;
        }
    }
}
