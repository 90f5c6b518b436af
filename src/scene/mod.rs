//! The scene as built: world-space triangles and their shading records,
//! materials, lights and the BVH over them — what every render of a scene
//! shares, and what the scene [`cache`] keeps between runs. It is built
//! from a [`crate::format::SceneDesc`] by [`build`]; what one render does
//! with it (camera, film, integrator) is [`crate::settings::Settings`].

mod build;
mod builder;
pub mod cache;
pub mod estimate;

pub use build::{build, build_limited, load, Emitter, Geometry, MtlRecord};

use crate::bvh::{Hit, WideBvh, LANES};
use crate::geometry::SurfacePoint;
use crate::geometry::{Aabb, Ray, Triangle};
use crate::light::{EnvironmentLight, Light, LightSelector};
use crate::material::Material;
use crate::pod_array::PodArray;
use glam::{Vec2, Vec3};
use std::path::PathBuf;

/// Marks a triangle that is not part of an area light.
pub const NO_LIGHT: u32 = u32::MAX;

/// What shading needs of a triangle beyond its vertices. A plain record of
/// fixed layout, so the scene cache stores and loads it as bytes.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct TriangleShading {
    /// Per-vertex shading normals; all zero when the mesh has none (a mesh's
    /// normals are only kept when none of the three is zero).
    pub normals: [Vec3; 3],
    /// Per-vertex texture coordinates; all zero when the mesh has none.
    pub uvs: [Vec2; 3],
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Index into [`Scene::lights`] for emissive triangles, else [`NO_LIGHT`].
    pub light: u32,
}

impl TriangleShading {
    /// Whether the triangle has per-vertex shading normals (else it shades flat).
    pub fn has_normals(&self) -> bool {
        self.normals[0] != Vec3::ZERO
    }
}

/// What surface reconstruction reads of a triangle's vertices at every
/// hit, worked out once at load: the unit normal of its plane (a cross
/// product and a square root) and its largest coordinate (nine
/// comparisons). Not cached: it is a pass over the triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facet {
    /// `Triangle::normal`: the winding's unit normal.
    pub normal: Vec3,
    /// `ray::magnitude` of the vertices, for `offset_origin`.
    pub magnitude: f32,
}

impl Facet {
    /// The facts of `triangle`.
    pub fn new(triangle: &Triangle) -> Facet {
        Facet {
            normal: triangle.normal(),
            magnitude: crate::geometry::ray::magnitude(&triangle.v),
        }
    }
}

/// What loading noticed that the user should hear about.
#[derive(Clone, Debug, Default)]
pub struct LoadReport {
    /// Triangles dropped for zero area or non-finite vertices.
    pub degenerate_triangles_dropped: usize,
    /// Problems that did not stop the load, one line each.
    pub warnings: Vec<String>,
    /// Wall-clock time of the BVH build, in seconds; zero when it came from the cache.
    pub bvh_build_seconds: f64,
    /// Whether the geometry came from the scene cache.
    pub cache: cache::CacheUse,
}

/// A built scene, ready to be traced.
pub struct Scene {
    /// The scene's name: its `name` key, or the file name without extension.
    pub name: String,
    /// The scene file it was described in.
    pub file: PathBuf,
    /// Every triangle, in world space; a [`crate::bvh::Hit`]'s `triangle` indexes it.
    pub triangles: PodArray<Triangle>,
    /// Shading data of each triangle, by the same index.
    pub shading: PodArray<TriangleShading>,
    /// Each triangle's plane normal and scale, by the same index.
    pub facets: Vec<Facet>,
    /// The materials, by the index [`TriangleShading::material`] holds.
    pub materials: Vec<Material>,
    /// Each material's name, by the same index (MTL materials: `mesh.obj:name`).
    pub material_names: Vec<String>,
    /// Area lights first, one per emissive triangle, then the scene's other lights.
    pub lights: Vec<Light>,
    /// Chooses a light, in proportion to its power, for light sampling and for
    /// starting light paths.
    pub light_selector: LightSelector,
    /// Index in `lights` of the environment light, if the scene has one.
    pub environment: Option<usize>,
    /// The BVH over `triangles`.
    pub bvh: WideBvh,
    /// Box around every triangle.
    pub bounds: Aabb,
    /// What loading noticed.
    pub report: LoadReport,
}

impl Scene {
    /// The closest hit with `ray.tmin < t < ray.tmax`, if any.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.bvh.intersect(ray)
    }

    /// Whether anything lies on the ray within (`tmin`, `tmax`): for shadow rays.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.bvh.occluded(ray)
    }

    /// The closest hit of each ray named in `active` (bit k for `rays[k]`),
    /// into the same lane of `hits`.
    pub fn intersect_lanes(
        &self,
        rays: &[Ray; LANES],
        active: u32,
        hits: &mut [Option<Hit>; LANES],
    ) {
        self.bvh.intersect_lanes(rays, active, hits);
    }

    /// For each of `items` in turn, `done(item, free)`, where `free` is
    /// whether nothing blocks the shadow ray `ray(item)` (`None`: nothing
    /// can); see `WideBvh::shadow_run`.
    pub fn shadow_run<T>(
        &self,
        items: &[T],
        ray: impl Fn(&T) -> Option<Ray>,
        done: impl FnMut(&T, bool),
    ) {
        self.bvh.shadow_run(items, ray, done);
    }

    /// Which of the rays named in `active` are blocked, as a bit mask.
    pub fn occluded_lanes(&self, rays: &[Ray; LANES], active: u32) -> u32 {
        self.bvh.occluded_lanes(rays, active)
    }

    /// The environment light and its index in `lights`, if there is one.
    #[inline]
    pub fn environment(&self) -> Option<(usize, &EnvironmentLight)> {
        let index = self.environment?;
        match &self.lights[index] {
            Light::Environment(e) => Some((index, e)),
            _ => None,
        }
    }

    /// Position, normals and UV at a hit.
    // Inlined: see `Light::sample_incident`.
    #[inline(always)]
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let i = hit.triangle as usize;
        let tri = &self.triangles[i];
        let sh = &self.shading[i];
        let facet = self.facets[i];
        let (b1, b2) = (hit.b1, hit.b2);
        let b0 = 1.0 - b1 - b2;
        let ng = facet.normal;
        let ns = match sh.has_normals().then_some(sh.normals) {
            Some(n) => {
                let n = (b0 * n[0] + b1 * n[1] + b2 * n[2]).normalize_or_zero();
                match n.dot(ng) {
                    d if d > 0.0 => n,
                    d if d < 0.0 => -n,
                    _ => ng,
                }
            }
            None => ng,
        };
        SurfacePoint {
            position: crate::geometry::triangle::interpolate_precise(tri, b1, b2),
            geometric_normal: ng,
            shading_normal: ns,
            uv: b0 * sh.uvs[0] + b1 * sh.uvs[1] + b2 * sh.uvs[2],
            magnitude: facet.magnitude,
        }
    }
}
