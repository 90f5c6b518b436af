//! Turns a [`SceneDesc`] into a renderable [`Scene`]: materials with their
//! textures, objects as world-space triangles, lights, and the BVH — taken
//! from the scene cache when an entry for exactly this geometry is there.

use super::builder::Builder;
use super::cache::{self, Cache, CacheUse};
use super::estimate;
use super::{Facet, Scene, TriangleShading};
use crate::bvh::{BuildOptions, WideBvh};
use crate::color::Rgb;
use crate::error::Error;
use crate::film::read::read_texture;
use crate::format::desc::{LightDesc, MaterialDesc, SceneDesc, SkyDesc};
use crate::format::read_scene;
use crate::geometry::{Aabb, Triangle};
use crate::light::{
    AreaLight, DirectionalLight, EnvironmentLight, EnvironmentMap, Light, LightSelector,
    PointLight, SpotLight,
};
use crate::material::{Albedo, Material};
use crate::pod_array::PodArray;
use crate::Result;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Reads the scene file at `path` and builds its scene (no cache).
pub fn load(path: &Path) -> Result<(Scene, crate::settings::Settings)> {
    let desc = read_scene(path)?;
    let scene = build(&desc, None)?;
    Ok((scene, desc.settings))
}

/// What a scene's objects become: triangles, their shading data, emitters,
/// the materials their MTL files add, and the BVH. This is the part of
/// building that the scene cache keeps.
pub struct Geometry {
    /// Every object's triangles, in world space, in object order.
    pub triangles: PodArray<Triangle>,
    /// With each emitter's light index set: area lights are the first
    /// lights, in emitter order.
    pub shading: PodArray<TriangleShading>,
    /// The emissive triangles, in the order their area lights take.
    pub emitters: Vec<Emitter>,
    /// Materials from the meshes' MTL files, in the order they were added
    /// (after the scene's own materials).
    pub mtl_materials: Vec<MtlRecord>,
    /// What parsing the meshes warned about.
    pub mesh_warnings: Vec<String>,
    /// Triangles dropped for zero area or non-finite vertices.
    pub degenerate_triangles_dropped: usize,
    /// The BVH over `triangles`.
    pub bvh: WideBvh,
}

/// An emissive triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// Index of the triangle in [`Geometry::triangles`].
    pub triangle: u32,
    /// Emitted radiance; not black.
    pub radiance: Rgb,
    /// Whether it emits from its back face too.
    pub two_sided: bool,
}

/// A material an MTL file added: enough to build it again (its texture is
/// loaded again, not cached).
#[derive(Clone, Debug, PartialEq)]
pub struct MtlRecord {
    /// `mesh.obj:material`.
    pub name: String,
    /// Where it came from, for warnings: `objects[2] (material wood)`.
    pub context: String,
    /// The material as the MTL described it (after any override).
    pub desc: MaterialDesc,
    /// `Kd`: the albedo when the texture cannot be read.
    pub kd: Rgb,
}

/// Builds a described scene, through `cache` when given, refusing one that
/// would need more memory than the machine has available.
pub fn build(desc: &SceneDesc, cache: Option<&Cache>) -> Result<Scene> {
    build_limited(desc, cache, None)
}

/// [`build`], refusing a scene estimated to need more than `memory_limit`
/// bytes (default: what the machine has available). Meshes are scanned for
/// the estimate only when the geometry is not in the cache: a hit knows its
/// triangle count, and a warm load stays as fast as the cache makes it.
pub fn build_limited(
    desc: &SceneDesc,
    cache: Option<&Cache>,
    memory_limit: Option<u64>,
) -> Result<Scene> {
    let mut b = Builder::new(&desc.file);
    for (name, m) in &desc.materials {
        let material = b.material(m, &format!("materials.{name}"), None)?;
        b.add_material(name.clone(), material);
    }
    let default_material = match b.material_index("default") {
        Some(i) => i,
        None => b.add_material(
            "(built-in default)".into(),
            Material::Diffuse {
                albedo: Albedo::Constant(Rgb::splat(0.5)),
            },
        ),
    };
    let geometry = geometry(desc, cache, &mut b, default_material, memory_limit)?;
    let mut report = std::mem::take(&mut b.report);
    report.degenerate_triangles_dropped = geometry.degenerate_triangles_dropped;
    let mut warnings = geometry.mesh_warnings.clone();
    warnings.append(&mut report.warnings);
    report.warnings = warnings;

    // The BVH's root box is the union of the triangles' boxes.
    let bounds = geometry.bvh.bounds();
    let mut lights = Vec::new();
    for e in &geometry.emitters {
        lights.push(Light::Area(AreaLight::new(
            geometry.triangles[e.triangle as usize],
            e.triangle,
            e.radiance,
            e.two_sided,
        )));
    }
    let mut environment = None;
    for (path, l) in &desc.lights {
        let light = match l {
            LightDesc::Environment {
                sky,
                scale,
                rotation,
            } => {
                if let Some((_, first)) = &environment {
                    return Err(Error::scene(
                        &desc.file,
                        path.clone(),
                        format!("a scene has at most one environment light, and {first} is one"),
                    ));
                }
                environment = Some((lights.len(), path.clone()));
                make_environment(sky, *scale, *rotation, &bounds, &desc.file, path)?
            }
            _ => make_light(l, &bounds),
        };
        lights.push(light);
    }
    if lights.iter().all(|l| l.power() <= 0.0) {
        report
            .warnings
            .push("the scene has no light that emits anything: the image will be black".into());
    }
    let (materials, material_names) = b.into_materials();
    Ok(Scene {
        name: desc.name.clone(),
        file: desc.file.clone(),
        light_selector: LightSelector::new(&lights),
        environment: environment.map(|(index, _)| index),
        lights,
        bvh: geometry.bvh,
        bounds,
        facets: facets(&geometry.triangles),
        triangles: geometry.triangles,
        shading: geometry.shading,
        materials,
        material_names,
        report,
    })
}

/// Each triangle's [`Facet`], made on every load (cache hit or not) and so
/// made in parallel: one thread took about 20 ms for the dragon's 871k
/// triangles, a quarter of its load from the cache.
fn facets(triangles: &[crate::geometry::Triangle]) -> Vec<Facet> {
    use rayon::prelude::*;
    triangles.par_iter().map(Facet::new).collect()
}

/// The scene's geometry: from the cache when it holds this scene's, else
/// built from the objects (and stored in the cache when there is one).
fn geometry(
    desc: &SceneDesc,
    cache: Option<&Cache>,
    b: &mut Builder,
    default_material: u32,
    memory_limit: Option<u64>,
) -> Result<Geometry> {
    let build_options = BuildOptions::default();
    let key = cache.and_then(|_| cache::scene_key(desc, &build_options));
    let scene_materials = b.material_count();
    let cached = match (cache, &key) {
        (Some(c), Some(k)) => c.lookup(k, scene_materials, &mut b.report.warnings),
        _ => None,
    };
    if let Some(g) = cached {
        let e = estimate::with_triangles(g.triangles.len() as u64, &desc.settings);
        estimate::check_estimate(e, memory_limit)?;
        for record in &g.mtl_materials {
            let m = b.material(&record.desc, &record.context, Some(record.kd))?;
            b.add_material(record.name.clone(), m);
        }
        b.report.cache = CacheUse::Hit;
        return Ok(g);
    }
    // Before anything is allocated for the objects.
    estimate::check(desc, memory_limit)?;
    for object in &desc.objects {
        b.object(object, default_material)?;
    }
    let start = Instant::now();
    let bvh = WideBvh::build_with(&b.triangles, &build_options);
    b.report.bvh_build_seconds = start.elapsed().as_secs_f64();
    for (k, e) in b.emitters.iter().enumerate() {
        b.shading[e.triangle as usize].light = k as u32;
    }
    let g = Geometry {
        triangles: std::mem::take(&mut b.triangles).into(),
        shading: std::mem::take(&mut b.shading).into(),
        emitters: std::mem::take(&mut b.emitters),
        mtl_materials: std::mem::take(&mut b.mtl_records),
        mesh_warnings: std::mem::take(&mut b.mesh_warnings),
        degenerate_triangles_dropped: b.report.degenerate_triangles_dropped,
        bvh,
    };
    if let (Some(c), Some(k)) = (cache, &key) {
        b.report.cache = c.store(k, &g, &desc.file, &mut b.report.warnings);
    }
    Ok(g)
}

fn make_light(l: &LightDesc, bounds: &Aabb) -> Light {
    match *l {
        LightDesc::Point {
            position,
            intensity,
        } => Light::Point(PointLight {
            position,
            intensity,
        }),
        LightDesc::Spot {
            position,
            look_at,
            intensity,
            cone_angle,
            falloff_start,
        } => Light::Spot(SpotLight {
            position,
            axis: (look_at - position).normalize(),
            intensity,
            cos_cone: cone_angle.to_radians().cos(),
            cos_falloff_start: falloff_start.to_radians().cos(),
        }),
        LightDesc::Directional {
            direction,
            irradiance,
        } => Light::Directional(DirectionalLight {
            direction: direction.normalize(),
            irradiance,
            scene_center: bounds.bounding_sphere().0,
            scene_radius: bounds.bounding_sphere().1,
        }),
        LightDesc::Environment { .. } => unreachable!("built by make_environment"),
    }
}

/// The environment light, with its image read and its sampling density built.
fn make_environment(
    sky: &SkyDesc,
    scale: f32,
    rotation: glam::Mat3,
    bounds: &Aabb,
    file: &Path,
    path: &str,
) -> Result<Light> {
    let (center, radius) = bounds.bounding_sphere();
    // A scene without triangles still needs a disk that light paths can leave from.
    let radius = radius.max(1e-3);
    Ok(Light::Environment(match sky {
        SkyDesc::Constant(radiance) => {
            EnvironmentLight::constant(*radiance * scale, center, radius)
        }
        SkyDesc::Image(image) => {
            let key = format!("{path}.file");
            let image = read_texture(image).map_err(|e| Error::scene(file, key.clone(), e))?;
            let map =
                EnvironmentMap::new(image.width as usize, image.height as usize, image.pixels)
                    .map_err(|e| Error::scene(file, key, e))?;
            EnvironmentLight::from_map(Arc::new(map), scale, rotation, center, radius)
        }
    }))
}
