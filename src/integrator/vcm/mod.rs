//! Vertex connection and merging (Georgiev, Křivánek, Davidovič and
//! Slusallek 2012; Hachisuka, Pantaleoni and Jensen 2012): BDPT plus photon
//! density estimation, each path weighed by the power heuristic over both.
//!
//! Merging is what lets a renderer see paths that no connection can make:
//! light → mirror → diffuse → mirror → camera with a point light, say (a
//! caustic seen in a mirror). Every connection between two subpaths needs a
//! non-delta vertex at each end, and that path has none to offer.
//!
//! Render sample `i` of every pixel is iteration `i`: first the light pass
//! traces one light path per pixel (each the very path BDPT would trace
//! for that pixel and sample), splats their camera connections, and puts
//! their vertices in a hash grid; then each pixel's camera path connects
//! to its own light path, as in BDPT, and merges at each non-delta vertex
//! with every light vertex of the iteration within the radius
//! r_i = r_0 · (i + 1)^((α − 1)/2), α = 3/4. The radius follows the global
//! sample index, so a render split by `--sample-offset` and merged equals
//! the render made in one go. Merging is biased for a radius above zero;
//! the bias vanishes as the radius shrinks.

mod grid;

use super::bdpt::{start_camera_walk, Bidirectional};
use super::mis::mis;
use super::sink::SampleSink;
use super::walk::{light_paths_per_pass, LightVertex, MergeWeights, Walk};
use super::PixelSample;
use crate::camera::Camera;
use crate::color::{is_black, Rgb};
use crate::film::Splat;
use crate::geometry::SurfacePoint;
use crate::material::{Bsdf, Transport};
use crate::scene::Scene;
use glam::Vec3;
use grid::{HashGrid, Located};
use rayon::prelude::*;

/// How fast the merging radius shrinks: r_i ∝ i^((α − 1)/2). 3/4 is the
/// usual compromise between variance (α → 1) and bias (α → 0).
pub const RADIUS_ALPHA: f64 = 0.75;

/// The first iteration's radius when the render does not set one, as a
/// fraction of the radius of the scene's bounding sphere.
pub const DEFAULT_RADIUS_FRACTION: f32 = 0.003;

/// Vertex connection and merging, and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexMerging {
    /// The most segments a path may have, whichever strategy makes it.
    pub max_depth: u32,
    /// The merging radius of the first iteration, in scene units; `None`
    /// for [`DEFAULT_RADIUS_FRACTION`] of the scene's bounding sphere.
    pub radius: Option<f32>,
}

impl VertexMerging {
    /// BDPT with the same depth bound: VCM's camera walks and
    /// connections are its own.
    pub(super) fn bdpt(&self) -> Bidirectional {
        Bidirectional {
            max_depth: self.max_depth,
        }
    }

    /// The first iteration's merging radius for `scene`.
    pub fn base_radius(&self, scene: &Scene) -> f32 {
        self.radius.unwrap_or_else(|| {
            let (_, r) = scene.bounds.bounding_sphere();
            // An empty scene has no radius; any positive one will do.
            (DEFAULT_RADIUS_FRACTION * r).max(1e-6)
        })
    }

    /// The merging radius of the iteration that takes sample `index` (from 0).
    pub fn radius_at(&self, scene: &Scene, index: u64) -> f32 {
        let iteration = (index + 1) as f64;
        let shrink = iteration.powf((RADIUS_ALPHA - 1.0) / 2.0);
        (self.base_radius(scene) as f64 * shrink) as f32
    }

    /// The light pass of iteration `index`: one light path per pixel of
    /// `camera`'s image, traced in parallel on the current rayon pool, row
    /// by row, and gathered in pixel order. `previous`, a pass no longer
    /// needed, lends its buffers.
    pub fn light_pass(
        &self,
        scene: &Scene,
        camera: &Camera,
        seed: u64,
        index: u64,
        previous: Option<LightPass>,
    ) -> LightPass {
        let paths = light_paths_per_pass(camera);
        // Keep the kernel π r² N a normal f32, whatever the scene's scale.
        let (lowest, highest) = radius_limits(paths);
        let radius = self.radius_at(scene, index).clamp(lowest, highest);
        let merging = MergeWeights::new(radius, paths);
        let bdpt = self.bdpt();
        let (width, height) = (camera.width(), camera.height());
        let mut pass = previous.unwrap_or_default();
        pass.rows.resize_with(height as usize, Row::default);
        pass.rows.par_iter_mut().enumerate().for_each(|(y, row)| {
            row.vertices.clear();
            row.ends.clear();
            row.sink.splats.clear();
            row.sink.discarded = 0;
            for x in 0..width {
                let pixel = PixelSample::new(x, y as u32, index, seed);
                bdpt.trace_light_path::<true>(
                    scene,
                    camera,
                    &mut pixel.light_sampler(),
                    merging,
                    &mut row.vertices,
                    &mut row.sink,
                );
                row.ends.push(row.vertices.len() as u32);
            }
        });
        pass.points.clear();
        for row in &pass.rows {
            pass.points
                .extend(row.vertices.iter().map(MergePoint::from));
        }
        pass.grid.rebuild(&pass.points, radius);
        pass.merging = merging;
        let kernel = std::f64::consts::PI * (radius as f64).powi(2) * paths as f64;
        pass.normalization = (1.0 / kernel) as f32;
        pass
    }

    /// One camera path of `pixel` in the iteration whose light pass is `pass`.
    pub fn sample(
        &self,
        scene: &Scene,
        camera: &Camera,
        pixel: PixelSample,
        pass: &LightPass,
        sink: &mut SampleSink,
    ) -> Rgb {
        let mut sampler = pixel.camera_sampler();
        let jitter = sampler.next_2d();
        let Some((walk, index)) =
            start_camera_walk(camera, &mut sampler, pixel, jitter, pass.merging)
        else {
            return Rgb::ZERO;
        };
        let bdpt = self.bdpt();
        let own = pass.path_of(pixel.x, pixel.y);
        bdpt.trace_camera_path::<true>(scene, walk, &mut sampler, own, Some(pass), index, sink)
    }
}

/// The merging radii whose kernel area π r² N, over `light_paths` paths,
/// lies within 1e±30: below, the density estimate's normalisation would
/// overflow; above, the kernel would.
pub fn radius_limits(light_paths: f32) -> (f32, f32) {
    let area = std::f64::consts::PI * light_paths.max(1.0) as f64;
    ((1e-30 / area).sqrt() as f32, (1e30 / area).sqrt() as f32)
}

/// What one iteration's light paths leave for its camera paths: their
/// vertices (for connections, each pixel its own path, and for merging,
/// all of them through the grid) and their splats into the image.
pub struct LightPass {
    /// The light paths of each row of pixels.
    rows: Vec<Row>,
    /// What merging needs of every light vertex, in row order.
    points: Vec<MergePoint>,
    grid: HashGrid<MergePoint>,
    pub(in crate::integrator) merging: MergeWeights,
    /// 1 / (π r² N): the density estimate's kernel over the path count.
    normalization: f32,
}

impl Default for LightPass {
    fn default() -> Self {
        LightPass {
            rows: Vec::new(),
            points: Vec::new(),
            grid: HashGrid::new(),
            merging: MergeWeights::NONE,
            normalization: 0.0,
        }
    }
}

/// One row of pixels' light paths, one after the other.
#[derive(Default)]
struct Row {
    vertices: Vec<LightVertex>,
    /// Pixel `x`'s path ends at `vertices[ends[x]]` and starts where pixel
    /// `x − 1`'s ends.
    ends: Vec<u32>,
    /// The paths' connections to the camera.
    sink: SampleSink,
}

/// A light vertex as merging sees it: a third the size of a
/// [`LightVertex`], so the grid's buckets stay small.
#[derive(Clone, Copy, Debug, Default)]
struct MergePoint {
    position: Vec3,
    /// Unit direction towards the previous vertex (where the light came from).
    wo: Vec3,
    throughput: Rgb,
    d_vcm: f32,
    d_vm: f32,
    /// Segments from the light to this vertex.
    length: u32,
}

impl From<&LightVertex> for MergePoint {
    fn from(v: &LightVertex) -> MergePoint {
        MergePoint {
            position: v.surface.position,
            wo: v.wo,
            throughput: v.throughput,
            d_vcm: v.d_vcm,
            d_vm: v.d_vm,
            length: v.length,
        }
    }
}

impl Located for MergePoint {
    fn position(&self) -> Vec3 {
        self.position
    }
}

impl LightPass {
    /// The light vertices traced for pixel (`x`, `y`).
    pub(in crate::integrator) fn path_of(&self, x: u32, y: u32) -> &[LightVertex] {
        let Some(row) = self.rows.get(y as usize) else {
            return &[];
        };
        let start = if x == 0 {
            0
        } else {
            row.ends.get(x as usize - 1).copied().unwrap_or(0)
        };
        let end = row.ends.get(x as usize).copied().unwrap_or(start);
        &row.vertices[start as usize..end as usize]
    }

    /// The light paths' connections to the camera, in pixel order of the
    /// paths that made them.
    pub fn splats(&self) -> impl Iterator<Item = &Splat> {
        self.rows.iter().flat_map(|r| &r.sink.splats)
    }

    /// Splats dropped for being NaN or infinite.
    pub fn discarded(&self) -> u64 {
        self.rows.iter().map(|r| r.sink.discarded).sum()
    }

    /// The merges at a camera vertex (report eqs. 38–39 for the weights),
    /// without the camera path's throughput: every light vertex within the
    /// radius whose path, joined at this vertex, has at most `max_depth`
    /// segments. Kept out of line: it is large, and runs at most once per
    /// camera vertex.
    #[inline(never)]
    pub(super) fn merge(
        &self,
        surface: &SurfacePoint,
        bsdf: &Bsdf,
        wo: Vec3,
        walk: &Walk,
        max_depth: u32,
    ) -> Rgb {
        let mut sum = Rgb::ZERO;
        let vc = self.merging.vc;
        let camera_weight = walk.d_vcm * vc;
        self.grid.for_each_near(surface.position, |v| {
            if v.length + walk.length > max_depth {
                return;
            }
            // The light arrived along -v.wo; the camera's BSDF scatters it to wo.
            let wi = v.wo;
            let cos = wi.dot(surface.geometric_normal).abs();
            let (f, pdf, reverse) = bsdf.eval_pdfs(wo, wi, Transport::Radiance);
            if cos <= 1e-6 || is_black(f) {
                return;
            }
            let w_light = v.d_vcm * vc + v.d_vm * mis(pdf);
            let w_camera = camera_weight + walk.d_vm * mis(reverse);
            // `eval` is f · |cos| about the shading normal; the photon's flux
            // is per unit of geometric area, hence the geometric cosine.
            sum += v.throughput * f * (1.0 / (cos * (w_light + 1.0 + w_camera)));
        });
        sum * self.normalization
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid holds its own small copy of each light vertex, so that a
    /// bucket of merge candidates spans few cache lines.
    #[test]
    fn a_merge_point_is_a_third_of_a_light_vertex_or_less() {
        let (point, vertex) = (
            std::mem::size_of::<MergePoint>(),
            std::mem::size_of::<LightVertex>(),
        );
        eprintln!("merge point {point} bytes, light vertex {vertex} bytes");
        assert!(point <= 48, "{point}");
        assert!(3 * point <= vertex, "{point} against {vertex}");
    }
}
