//! Turns a [`SceneDesc`] into a renderable [`Scene`]: materials with their
//! textures, objects as world-space triangles, lights, and the BVH.

use super::cache::{self, Cache, CacheUse};
use super::desc::*;
use super::obj::{load_obj, MtlMaterial};
use super::texture::load_texture;
use super::{format, trs, LoadReport, Scene, Settings, TriangleShading, NO_LIGHT};
use crate::bvh::{BuildOptions, WideBvh};
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::shapes::{self, MeshData};
use crate::geometry::{Aabb, Triangle};
use crate::light::{AreaLight, DirectionalLight, Light, LightSelector, PointLight, SpotLight};
use crate::material::{Albedo, Material, Texture};
use crate::pod_array::PodArray;
use crate::{Error, Result};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Reads a scene file (`.json`, or `.trs` for T-racer scenes) into a description.
pub fn parse_file(path: &Path) -> Result<SceneDesc> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let is_trs = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("trs"));
    if is_trs {
        trs::parse(&text, path)
    } else {
        format::parse(&text, path)
    }
}

/// Reads and prepares the scene in `path`.
pub fn load(path: &Path) -> Result<Scene> {
    load_desc(parse_file(path)?)
}

/// Reads and prepares the scene in `path`, taking its geometry and BVH from
/// `cache` when an entry for exactly this geometry is there, and storing
/// one when not.
pub fn load_cached(path: &Path, cache: Option<&Cache>) -> Result<Scene> {
    load_desc_cached(parse_file(path)?, cache)
}

/// What a scene's objects become: triangles, their shading data, emitters,
/// the materials their MTL files add, and the BVH. This is the part of
/// loading that the scene cache keeps.
pub struct Geometry {
    pub triangles: PodArray<Triangle>,
    /// With each emitter's light index set: area lights are the first
    /// lights, in emitter order.
    pub shading: PodArray<TriangleShading>,
    pub emitters: Vec<Emitter>,
    /// Materials from the meshes' MTL files, in the order they were added
    /// (after the scene's own materials).
    pub mtl_materials: Vec<MtlRecord>,
    /// What parsing the meshes warned about.
    pub mesh_warnings: Vec<String>,
    pub degenerate_triangles_dropped: usize,
    pub bvh: WideBvh,
}

/// An emissive triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    pub triangle: u32,
    pub radiance: Rgb,
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
    pub desc: MaterialDesc,
    /// `Kd`: the albedo when the texture cannot be read.
    pub kd: Rgb,
}

pub(super) fn make_camera(c: &CameraDesc, width: u32, height: u32) -> Option<Camera> {
    Camera::new(c.position.0, c.look_at.0, c.up.0, c.fov.0, width, height)
}

struct Builder<'a> {
    file: &'a Path,
    materials: Vec<Material>,
    material_names: Vec<String>,
    by_name: HashMap<String, u32>,
    textures: HashMap<PathBuf, Arc<Texture>>,
    triangles: Vec<Triangle>,
    shading: Vec<TriangleShading>,
    emitters: Vec<Emitter>,
    mtl_records: Vec<MtlRecord>,
    mesh_warnings: Vec<String>,
    report: LoadReport,
}

/// Prepares a described scene for rendering.
pub fn load_desc(desc: SceneDesc) -> Result<Scene> {
    load_desc_cached(desc, None)
}

/// Prepares a described scene for rendering, through `cache` when given.
pub fn load_desc_cached(desc: SceneDesc, cache: Option<&Cache>) -> Result<Scene> {
    let file = desc.file.as_path();
    let err = |path: &str, msg: String| Error::scene(file, path, msg);

    let (width, height) = (desc.film.width.0, desc.film.height.0);
    // The parsers check these with their own key names; descriptions built in code get checked here.
    format::check_view(file, &desc.camera, &desc.film, "camera.fov", "film")?;
    let camera = make_camera(&desc.camera, width, height).ok_or_else(|| {
        err(
            "camera",
            "position and look_at must differ, and up must not be parallel to the view direction"
                .into(),
        )
    })?;

    let mut b = Builder {
        file,
        materials: Vec::new(),
        material_names: Vec::new(),
        by_name: HashMap::new(),
        textures: HashMap::new(),
        triangles: Vec::new(),
        shading: Vec::new(),
        emitters: Vec::new(),
        mtl_records: Vec::new(),
        mesh_warnings: Vec::new(),
        report: LoadReport::default(),
    };
    for (name, m) in &desc.materials {
        let material = b.material(m, &format!("materials.{name}"), None)?;
        b.add_material(name.clone(), material);
    }
    let default_material = match b.by_name.get("default") {
        Some(&i) => i,
        None => b.add_material(
            "(built-in default)".into(),
            Material::Diffuse {
                albedo: Albedo::Constant(Rgb::splat(0.5)),
            },
        ),
    };
    let build_options = BuildOptions::default();
    let key = cache.and_then(|_| cache::scene_key(&desc, &build_options));
    let scene_materials = b.materials.len();
    let cached = match (cache, &key) {
        (Some(c), Some(k)) => c.lookup(k, scene_materials, &mut b.report.warnings),
        _ => None,
    };
    let geometry = match cached {
        Some(g) => {
            for record in &g.mtl_materials {
                let m = b.material(&record.desc, &record.context, Some(record.kd))?;
                b.add_material(record.name.clone(), m);
            }
            b.report.cache = CacheUse::Hit;
            g
        }
        None => {
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
                b.report.cache = c.store(k, &g, file, &mut b.report.warnings);
            }
            g
        }
    };
    b.report.degenerate_triangles_dropped = geometry.degenerate_triangles_dropped;
    let mut warnings = geometry.mesh_warnings.clone();
    warnings.append(&mut b.report.warnings);
    b.report.warnings = warnings;

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
    for (_, l) in &desc.lights {
        lights.push(make_light(l, &bounds));
    }
    if lights.iter().all(|l| l.power() <= 0.0) {
        b.report
            .warnings
            .push("the scene has no light that emits anything: the image will be black".into());
    }

    let output = match &desc.film.output {
        Some(o) => format::resolve(file, o),
        None => format::resolve(file, &format!("{}.exr", desc.name)),
    };
    Ok(Scene {
        name: desc.name.clone(),
        file: file.to_path_buf(),
        camera_desc: desc.camera.clone(),
        camera,
        settings: Settings {
            integrator: desc.render.integrator,
            spp: desc.render.spp.0,
            time_limit: desc.render.time_limit.map(|t| t.0),
            max_depth: desc.render.max_depth.0,
            seed: desc.render.seed,
            width,
            height,
            output,
            tonemap: desc.film.tonemap,
            exposure: desc.film.exposure.0,
        },
        display: desc.display,
        light_selector: LightSelector::new(&lights),
        lights,
        bvh: geometry.bvh,
        bounds,
        triangles: geometry.triangles,
        shading: geometry.shading,
        materials: b.materials,
        material_names: b.material_names,
        report: b.report,
    })
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
    }
}

impl Builder<'_> {
    fn add_material(&mut self, name: String, m: Material) -> u32 {
        let index = self.materials.len() as u32;
        self.materials.push(m);
        self.by_name.insert(name.clone(), index);
        self.material_names.push(name);
        index
    }

    fn texture(&mut self, path: &Path) -> std::result::Result<Arc<Texture>, String> {
        if let Some(t) = self.textures.get(path) {
            return Ok(t.clone());
        }
        let t = Arc::new(load_texture(path)?);
        self.textures.insert(path.to_path_buf(), t.clone());
        Ok(t)
    }

    /// Builds a material. For MTL materials, `fallback` is the `Kd` to use
    /// (with a warning) when `map_Kd` cannot be read; a texture named in the
    /// scene file itself must load.
    fn material(
        &mut self,
        m: &MaterialDesc,
        path: &str,
        fallback: Option<Rgb>,
    ) -> Result<Material> {
        Ok(match m {
            MaterialDesc::Diffuse { albedo } => Material::Diffuse {
                albedo: match albedo {
                    AlbedoDesc::Constant(c) => Albedo::Constant(*c),
                    AlbedoDesc::Texture(t) => match (self.texture(t), fallback) {
                        (Ok(t), _) => Albedo::Texture(t),
                        (Err(e), Some(kd)) => {
                            self.report
                                .warnings
                                .push(format!("{path}: {e}; using Kd instead"));
                            Albedo::Constant(kd)
                        }
                        (Err(e), None) => {
                            return Err(Error::scene(self.file, format!("{path}.albedo"), e))
                        }
                    },
                },
            },
            MaterialDesc::Mirror { reflectance } => Material::Mirror {
                reflectance: *reflectance,
            },
            MaterialDesc::Dielectric { ior, transmittance } => Material::Dielectric {
                ior: *ior,
                transmittance: *transmittance,
            },
        })
    }

    fn object(&mut self, o: &ObjectDesc, default_material: u32) -> Result<()> {
        let path = o.key_path.as_str();
        let named = match &o.material {
            Some(name) => Some(*self.by_name.get(name).ok_or_else(|| {
                let mut known: Vec<&str> = self.by_name.keys().map(String::as_str).collect();
                known.sort();
                Error::scene(
                    self.file,
                    format!("{path}.material"),
                    format!(
                        "unknown material \"{name}\" (defined: {})",
                        known.join(", ")
                    ),
                )
            })?),
            None => None,
        };
        match &o.shape {
            ShapeDesc::Mesh { file, mtl_override } => {
                let file_key = if o.key_path.starts_with('"') {
                    "MeshName"
                } else {
                    "file"
                };
                let obj = load_obj(file, *mtl_override)
                    .map_err(|e| Error::scene(self.file, format!("{path}.{file_key}"), e))?;
                self.mesh_warnings.extend(obj.warnings);
                let mut mtl_indices: HashMap<String, (u32, Option<Rgb>)> = HashMap::new();
                for group in obj.groups {
                    let (material, mtl_emission) = match (named, &group.material) {
                        (Some(m), _) => (m, None),
                        (None, Some(mtl)) => {
                            self.mtl_material(mtl, file, path, &mut mtl_indices)?
                        }
                        (None, None) => (default_material, None),
                    };
                    let emission = o.emission.or(mtl_emission);
                    self.add_mesh(&group.mesh, o, material, emission);
                }
            }
            ShapeDesc::Quad => self.add_mesh(
                &shapes::quad(),
                o,
                named.unwrap_or(default_material),
                o.emission,
            ),
            ShapeDesc::Cube => self.add_mesh(
                &shapes::cube(),
                o,
                named.unwrap_or(default_material),
                o.emission,
            ),
            ShapeDesc::Sphere {
                center,
                radius,
                subdivisions,
            } => self.add_mesh(
                &shapes::sphere(*center, *radius, *subdivisions),
                o,
                named.unwrap_or(default_material),
                o.emission,
            ),
            ShapeDesc::Triangles {
                positions,
                indices,
                normals,
                uvs,
            } => {
                let mesh = MeshData {
                    positions: positions.clone(),
                    normals: normals.clone(),
                    uvs: uvs.clone(),
                    indices: indices
                        .clone()
                        .unwrap_or_else(|| (0..positions.len() as u32).collect()),
                };
                self.add_mesh(&mesh, o, named.unwrap_or(default_material), o.emission)
            }
        }
        Ok(())
    }

    fn mtl_material(
        &mut self,
        mtl: &MtlMaterial,
        file: &Path,
        path: &str,
        seen: &mut HashMap<String, (u32, Option<Rgb>)>,
    ) -> Result<(u32, Option<Rgb>)> {
        if let Some(&found) = seen.get(&mtl.name) {
            return Ok(found);
        }
        let context = format!("{path} (material {})", mtl.name);
        let material = self.material(&mtl.desc, &context, Some(mtl.kd))?;
        let name = format!(
            "{}:{}",
            file.file_name().unwrap_or_default().to_string_lossy(),
            mtl.name
        );
        self.mtl_records.push(MtlRecord {
            name: name.clone(),
            context,
            desc: mtl.desc.clone(),
            kd: mtl.kd,
        });
        let index = self.add_material(name, material);
        seen.insert(mtl.name.clone(), (index, mtl.emission));
        Ok((index, mtl.emission))
    }

    /// Transforms `mesh` into world space and appends its triangles, dropping
    /// (and counting) those with zero area.
    fn add_mesh(&mut self, mesh: &MeshData, o: &ObjectDesc, material: u32, emission: Option<Rgb>) {
        let world: Vec<_> = mesh
            .positions
            .iter()
            .map(|&p| o.transform.point(p))
            .collect();
        let normals: Option<Vec<_>> = mesh
            .normals
            .as_ref()
            .map(|ns| ns.iter().map(|&n| o.transform.normal(n)).collect());
        let emission = emission.filter(|e| e.max_element() > 0.0);
        for f in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [f[0] as usize, f[1] as usize, f[2] as usize];
            let tri = Triangle::new(world[a], world[b], world[c]);
            // In double precision: a huge triangle's area overflows f32 but is not degenerate.
            let (p0, p1, p2) = (
                tri.v[0].as_dvec3(),
                tri.v[1].as_dvec3(),
                tri.v[2].as_dvec3(),
            );
            let area = (p1 - p0).cross(p2 - p0).length();
            if !(area > 0.0 && tri.v.iter().all(|v| v.is_finite())) {
                self.report.degenerate_triangles_dropped += 1;
                continue;
            }
            let vertex_normals = normals.as_ref().and_then(|n| {
                let ns = [n[a], n[b], n[c]];
                ns.iter().all(|n| n.length_squared() > 0.0).then_some(ns)
            });
            let uvs = mesh
                .uvs
                .as_ref()
                .map_or([Vec2::ZERO; 3], |uv| [uv[a], uv[b], uv[c]]);
            let index = self.triangles.len() as u32;
            self.triangles.push(tri);
            self.shading.push(TriangleShading {
                normals: vertex_normals.unwrap_or([Vec3::ZERO; 3]),
                uvs,
                material,
                light: NO_LIGHT,
            });
            if let Some(radiance) = emission {
                self.emitters.push(Emitter {
                    triangle: index,
                    radiance,
                    two_sided: o.two_sided,
                });
            }
        }
    }
}
