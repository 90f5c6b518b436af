//! The scene: what the renderer reads ([`format`], [`trs`], [`obj`],
//! [`texture`]) and the prepared, renderable result ([`Scene`]).

pub mod cache;
pub mod desc;
pub mod format;
mod load;
pub mod obj;
pub mod texture;
pub mod trs;

pub use load::{
    load, load_cached, load_desc, load_desc_cached, parse_file, Emitter, Geometry, MtlRecord,
};

use crate::bvh::{Hit, WideBvh};
use crate::camera::Camera;
use crate::geometry::{Aabb, Ray, Triangle};
use crate::light::{Light, LightSelector};
use crate::material::{Material, SurfacePoint};
use crate::pod_array::PodArray;
use desc::{CameraDesc, Display, IntegratorKind, Tonemap};
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
    pub uvs: [Vec2; 3],
    pub material: u32,
    /// Index into [`Scene::lights`] for emissive triangles, else [`NO_LIGHT`].
    pub light: u32,
}

impl TriangleShading {
    pub fn has_normals(&self) -> bool {
        self.normals[0] != Vec3::ZERO
    }
}

/// Render settings after the scene's `film` and `render` blocks and any
/// command-line overrides.
#[derive(Clone, Debug)]
pub struct Settings {
    pub integrator: IntegratorKind,
    pub spp: u32,
    pub time_limit: Option<f32>,
    pub max_depth: u32,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    pub output: PathBuf,
    pub tonemap: Tonemap,
    pub exposure: f32,
}

/// What loading noticed that the user should hear about.
#[derive(Clone, Debug, Default)]
pub struct LoadReport {
    pub degenerate_triangles_dropped: usize,
    pub warnings: Vec<String>,
    pub bvh_build_seconds: f64,
    /// Whether the geometry came from the scene cache.
    pub cache: cache::CacheUse,
}

pub struct Scene {
    pub name: String,
    pub file: PathBuf,
    camera_desc: CameraDesc,
    pub camera: Camera,
    pub settings: Settings,
    pub display: Option<Display>,
    pub triangles: PodArray<Triangle>,
    pub shading: PodArray<TriangleShading>,
    pub materials: Vec<Material>,
    pub material_names: Vec<String>,
    pub lights: Vec<Light>,
    pub light_selector: LightSelector,
    pub bvh: WideBvh,
    pub bounds: Aabb,
    pub report: LoadReport,
}

impl Scene {
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.bvh.intersect(ray)
    }

    pub fn occluded(&self, ray: &Ray) -> bool {
        self.bvh.occluded(ray)
    }

    /// Position, normals and UV at a hit.
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let i = hit.triangle as usize;
        let tri = &self.triangles[i];
        let sh = &self.shading[i];
        let (b1, b2) = (hit.b1, hit.b2);
        let b0 = 1.0 - b1 - b2;
        let ng = tri.normal();
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
            magnitude: crate::geometry::ray::magnitude(&tri.v),
        }
    }

    /// Changes the image size, keeping the camera's view.
    pub fn set_resolution(&mut self, width: u32, height: u32) {
        self.settings.width = width;
        self.settings.height = height;
        self.camera = load::make_camera(&self.camera_desc, width, height)
            .expect("a camera that was valid stays valid at any resolution");
    }
}
