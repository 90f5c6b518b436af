//! Collects what a scene's objects become while they are built: materials
//! (with their textures, loaded once each), world-space triangles and their
//! shading records, and emitters.

use super::build::{Emitter, MtlRecord};
use super::{LoadReport, TriangleShading, NO_LIGHT};
use crate::color::Rgb;
use crate::film::read::read_texture;
use crate::format::desc::{AlbedoDesc, MaterialDesc, ObjectDesc, ShapeDesc};
use crate::format::obj::{load_obj, MtlMaterial};
use crate::geometry::shapes::{self, MeshData};
use crate::geometry::Triangle;
use crate::material::{Albedo, Material, Texture};
use crate::{Error, Result};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub(super) struct Builder<'a> {
    file: &'a Path,
    materials: Vec<Material>,
    material_names: Vec<String>,
    by_name: HashMap<String, u32>,
    textures: HashMap<PathBuf, Arc<Texture>>,
    pub triangles: Vec<Triangle>,
    pub shading: Vec<TriangleShading>,
    pub emitters: Vec<Emitter>,
    pub mtl_records: Vec<MtlRecord>,
    pub mesh_warnings: Vec<String>,
    pub report: LoadReport,
}

impl<'a> Builder<'a> {
    pub fn new(file: &'a Path) -> Builder<'a> {
        Builder {
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
        }
    }

    pub fn material_index(&self, name: &str) -> Option<u32> {
        self.by_name.get(name).copied()
    }

    pub fn material_count(&self) -> usize {
        self.materials.len()
    }

    /// The materials and their names, in index order.
    pub fn into_materials(self) -> (Vec<Material>, Vec<String>) {
        (self.materials, self.material_names)
    }

    pub fn add_material(&mut self, name: String, m: Material) -> u32 {
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
        let image = read_texture(path)?;
        let t = Arc::new(Texture::new(
            image.width as usize,
            image.height as usize,
            image.pixels,
        ));
        self.textures.insert(path.to_path_buf(), t.clone());
        Ok(t)
    }

    /// A diffuse or plastic material's albedo, its texture loaded (see [`Builder::material`]).
    fn albedo(&mut self, albedo: &AlbedoDesc, path: &str, fallback: Option<Rgb>) -> Result<Albedo> {
        Ok(match albedo {
            AlbedoDesc::Constant(c) => Albedo::Constant(*c),
            AlbedoDesc::Texture(t) => match (self.texture(t), fallback) {
                (Ok(t), _) => Albedo::Texture(t),
                (Err(e), Some(kd)) => {
                    self.report
                        .warnings
                        .push(format!("{path}: {e}; using Kd instead"));
                    Albedo::Constant(kd)
                }
                (Err(e), None) => return Err(Error::scene(self.file, format!("{path}.albedo"), e)),
            },
        })
    }

    /// Builds a material. For MTL materials, `fallback` is the `Kd` to use
    /// (with a warning) when `map_Kd` cannot be read; a texture named in the
    /// scene file itself must load.
    pub fn material(
        &mut self,
        m: &MaterialDesc,
        path: &str,
        fallback: Option<Rgb>,
    ) -> Result<Material> {
        Ok(match m {
            MaterialDesc::Diffuse { albedo } => Material::Diffuse {
                albedo: self.albedo(albedo, path, fallback)?,
            },
            MaterialDesc::Plastic { albedo, ior, alpha } => {
                Material::plastic(self.albedo(albedo, path, fallback)?, *ior, *alpha)
            }
            MaterialDesc::Mirror { reflectance } => Material::Mirror {
                reflectance: *reflectance,
            },
            MaterialDesc::Dielectric { ior, transmittance } => Material::Dielectric {
                ior: *ior,
                transmittance: *transmittance,
            },
            MaterialDesc::Conductor {
                alpha,
                ior,
                reflectance,
            } => {
                // Fresnel 1 is the complex index 0 + 1i, as in Mitsuba 3.
                let (eta, k) = ior.unwrap_or((Rgb::ZERO, Rgb::ONE));
                Material::Conductor {
                    alpha: *alpha,
                    eta,
                    k,
                    reflectance: *reflectance,
                }
            }
            MaterialDesc::RoughDielectric {
                ior,
                alpha,
                transmittance,
            } => Material::RoughDielectric {
                ior: *ior,
                alpha: *alpha,
                transmittance: *transmittance,
            },
        })
    }

    pub fn object(&mut self, o: &ObjectDesc, default_material: u32) -> Result<()> {
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
