//! What an entry holds and how it maps onto the prepared geometry: the
//! section kinds and their record types, the JSON metadata, and reading a
//! whole entry back with every check the cache makes before trusting it.

use super::entry::{self, Invalid, Section, SectionReader};
use super::Key;
use crate::bvh::wide::BuildReport;
use crate::bvh::WideBvh;
use crate::color::Rgb;
use crate::format::desc::{AlbedoDesc, MaterialDesc};
use crate::geometry::Aabb;
use crate::pod_array::PodArray;
use crate::scene::{Emitter, Geometry, MtlRecord, TriangleShading, NO_LIGHT};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub(super) const SECTION_META: u32 = 1;
pub(super) const SECTION_TRIANGLES: u32 = 2;
pub(super) const SECTION_SHADING: u32 = 3;
pub(super) const SECTION_EMITTERS: u32 = 4;
pub(super) const SECTION_NODES: u32 = 5;
pub(super) const SECTION_BLOCKS: u32 = 6;

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(super) struct EmitterRecord {
    triangle: u32,
    radiance: [f32; 3],
    two_sided: u32,
}

impl From<&Emitter> for EmitterRecord {
    fn from(e: &Emitter) -> Self {
        EmitterRecord {
            triangle: e.triangle,
            radiance: e.radiance.to_array(),
            two_sided: e.two_sided as u32,
        }
    }
}

/// The small, variable-sized part of an entry, as JSON.
#[derive(Serialize, Deserialize)]
pub(super) struct Meta {
    scene: String,
    triangles: usize,
    degenerate_triangles_dropped: usize,
    mesh_warnings: Vec<String>,
    mtl_materials: Vec<MtlJson>,
    bvh_root: u32,
    bvh_bounds: [[f32; 3]; 2],
    bvh_binary_sah_cost: f32,
    bvh_sah_cost: f32,
}

#[derive(Serialize, Deserialize)]
struct MtlJson {
    name: String,
    context: String,
    kd: [f32; 3],
    #[serde(flatten)]
    material: MaterialJson,
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum MaterialJson {
    Diffuse {
        albedo: [f32; 3],
    },
    DiffuseTexture {
        texture: PathBuf,
    },
    Mirror {
        reflectance: [f32; 3],
    },
    Dielectric {
        ior: f32,
        transmittance: [f32; 3],
    },
    Conductor {
        alpha: f32,
        ior: Option<[[f32; 3]; 2]>,
        reflectance: [f32; 3],
    },
    RoughDielectric {
        ior: f32,
        alpha: f32,
        transmittance: [f32; 3],
    },
    Plastic {
        albedo: [f32; 3],
        ior: f32,
        alpha: f32,
    },
    PlasticTexture {
        texture: PathBuf,
        ior: f32,
        alpha: f32,
    },
}

impl Meta {
    pub(super) fn is_finite(&self) -> bool {
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        finite(&[self.bvh_sah_cost, self.bvh_binary_sah_cost])
            && self.bvh_bounds.iter().all(|b| finite(b))
            && self.mtl_materials.iter().all(|m| {
                finite(&m.kd)
                    && match &m.material {
                        MaterialJson::Diffuse { albedo } => finite(albedo),
                        MaterialJson::DiffuseTexture { .. } => true,
                        MaterialJson::Mirror { reflectance } => finite(reflectance),
                        MaterialJson::Dielectric { ior, transmittance } => {
                            ior.is_finite() && finite(transmittance)
                        }
                        MaterialJson::Conductor {
                            alpha,
                            ior,
                            reflectance,
                        } => {
                            alpha.is_finite()
                                && finite(reflectance)
                                && ior.is_none_or(|[eta, k]| finite(&eta) && finite(&k))
                        }
                        MaterialJson::RoughDielectric {
                            ior,
                            alpha,
                            transmittance,
                        } => ior.is_finite() && alpha.is_finite() && finite(transmittance),
                        MaterialJson::Plastic { albedo, ior, alpha } => {
                            finite(albedo) && ior.is_finite() && alpha.is_finite()
                        }
                        MaterialJson::PlasticTexture { ior, alpha, .. } => {
                            ior.is_finite() && alpha.is_finite()
                        }
                    }
            })
    }

    pub(super) fn of(g: &Geometry, scene_file: &Path) -> Meta {
        let r = g.bvh.report();
        let b = g.bvh.bounds();
        Meta {
            scene: scene_file.display().to_string(),
            triangles: g.triangles.len(),
            degenerate_triangles_dropped: g.degenerate_triangles_dropped,
            mesh_warnings: g.mesh_warnings.clone(),
            mtl_materials: g
                .mtl_materials
                .iter()
                .map(|m| MtlJson {
                    name: m.name.clone(),
                    context: m.context.clone(),
                    kd: m.kd.to_array(),
                    material: match &m.desc {
                        MaterialDesc::Diffuse {
                            albedo: AlbedoDesc::Constant(c),
                        } => MaterialJson::Diffuse {
                            albedo: c.to_array(),
                        },
                        MaterialDesc::Diffuse {
                            albedo: AlbedoDesc::Texture(t),
                        } => MaterialJson::DiffuseTexture { texture: t.clone() },
                        MaterialDesc::Mirror { reflectance } => MaterialJson::Mirror {
                            reflectance: reflectance.to_array(),
                        },
                        MaterialDesc::Dielectric { ior, transmittance } => {
                            MaterialJson::Dielectric {
                                ior: *ior,
                                transmittance: transmittance.to_array(),
                            }
                        }
                        MaterialDesc::Conductor {
                            alpha,
                            ior,
                            reflectance,
                        } => MaterialJson::Conductor {
                            alpha: *alpha,
                            ior: ior.map(|(eta, k)| [eta.to_array(), k.to_array()]),
                            reflectance: reflectance.to_array(),
                        },
                        MaterialDesc::RoughDielectric {
                            ior,
                            alpha,
                            transmittance,
                        } => MaterialJson::RoughDielectric {
                            ior: *ior,
                            alpha: *alpha,
                            transmittance: transmittance.to_array(),
                        },
                        MaterialDesc::Plastic {
                            albedo: AlbedoDesc::Constant(c),
                            ior,
                            alpha,
                        } => MaterialJson::Plastic {
                            albedo: c.to_array(),
                            ior: *ior,
                            alpha: *alpha,
                        },
                        MaterialDesc::Plastic {
                            albedo: AlbedoDesc::Texture(t),
                            ior,
                            alpha,
                        } => MaterialJson::PlasticTexture {
                            texture: t.clone(),
                            ior: *ior,
                            alpha: *alpha,
                        },
                    },
                })
                .collect(),
            bvh_root: g.bvh.root(),
            bvh_bounds: [b.min.to_array(), b.max.to_array()],
            bvh_binary_sah_cost: r.binary_sah_cost,
            bvh_sah_cost: r.sah_cost,
        }
    }
}

fn mtl_record(m: MtlJson) -> MtlRecord {
    MtlRecord {
        name: m.name,
        context: m.context,
        kd: Rgb::from_array(m.kd),
        desc: match m.material {
            MaterialJson::Diffuse { albedo } => MaterialDesc::Diffuse {
                albedo: AlbedoDesc::Constant(Rgb::from_array(albedo)),
            },
            MaterialJson::DiffuseTexture { texture } => MaterialDesc::Diffuse {
                albedo: AlbedoDesc::Texture(texture),
            },
            MaterialJson::Mirror { reflectance } => MaterialDesc::Mirror {
                reflectance: Rgb::from_array(reflectance),
            },
            MaterialJson::Dielectric { ior, transmittance } => MaterialDesc::Dielectric {
                ior,
                transmittance: Rgb::from_array(transmittance),
            },
            MaterialJson::Conductor {
                alpha,
                ior,
                reflectance,
            } => MaterialDesc::Conductor {
                alpha,
                ior: ior.map(|[eta, k]| (Rgb::from_array(eta), Rgb::from_array(k))),
                reflectance: Rgb::from_array(reflectance),
            },
            MaterialJson::RoughDielectric {
                ior,
                alpha,
                transmittance,
            } => MaterialDesc::RoughDielectric {
                ior,
                alpha,
                transmittance: Rgb::from_array(transmittance),
            },
            MaterialJson::Plastic { albedo, ior, alpha } => MaterialDesc::Plastic {
                albedo: AlbedoDesc::Constant(Rgb::from_array(albedo)),
                ior,
                alpha,
            },
            MaterialJson::PlasticTexture {
                texture,
                ior,
                alpha,
            } => MaterialDesc::Plastic {
                albedo: AlbedoDesc::Texture(texture),
                ior,
                alpha,
            },
        },
    }
}

/// Maps an entry and reads its header. `populate` faults every page in at
/// once, which a full read needs anyway; a listing only touches the
/// header and metadata.
///
/// On a shared (network) filesystem the entry is copied into memory
/// instead: another machine may replace or truncate it there, and a
/// truncated mapping kills the process that reads it (SIGBUS). Locally,
/// writers only ever rename new files into place.
pub(super) fn open_entry(
    path: &Path,
    populate: bool,
) -> Result<(Arc<memmap2::Mmap>, entry::Header), Invalid> {
    let mut file = crate::files::open_regular(path)?;
    let length = file.metadata()?.len();
    if length == 0 {
        return Err(Invalid::Length("empty file".into()));
    }
    if super::shared_fs::is_shared(path) {
        let map = Arc::new(read_into_memory(&mut file, length)?);
        let header = entry::read_header(&map)?;
        return Ok((map, header));
    }
    let mut options = memmap2::MmapOptions::new();
    if populate {
        options.populate();
    }
    // SAFETY: entries are never modified in place: writers create a new
    // file and rename it over the old one, which leaves this mapping's file
    // intact. (Truncating an entry by hand while a render maps it would
    // crash that render, as with any mapped file.)
    let map = unsafe { options.map(&file)? };
    let map = Arc::new(map);
    let header = entry::read_header(&map)?;
    Ok((map, header))
}

/// Copies the whole file into an anonymous mapping (page-aligned, like a
/// file mapping, so the sections' alignment holds), then seals it read-only.
fn read_into_memory(file: &mut File, length: u64) -> Result<memmap2::Mmap, Invalid> {
    use std::io::Read;
    let length = usize::try_from(length).map_err(|_| Invalid::Length("too large".into()))?;
    let mut memory = memmap2::MmapMut::map_anon(length)?;
    file.read_exact(&mut memory)?;
    Ok(memory.make_read_only()?)
}

pub(super) fn read_scene_name(path: &Path) -> Result<String, Invalid> {
    let (map, header) = open_entry(path, false)?;
    let mut sections = SectionReader::new(&map, &header);
    let meta: Meta = serde_json::from_slice(&sections.take::<u8>(SECTION_META)?)
        .map_err(|e| Invalid::Malformed(format!("metadata: {e}")))?;
    Ok(meta.scene)
}

pub(super) fn read_entry(
    path: &Path,
    key: &Key,
    scene_materials: usize,
) -> Result<Geometry, Invalid> {
    let (map, header) = open_entry(path, true)?;
    if header.key != *key {
        return Err(Invalid::Key);
    }
    let mut sections = SectionReader::new(&map, &header);
    let meta_bytes = sections.take::<u8>(SECTION_META)?;
    let triangles = sections.take(SECTION_TRIANGLES)?;
    let shading: PodArray<TriangleShading> = sections.take(SECTION_SHADING)?;
    let emitters: PodArray<EmitterRecord> = sections.take(SECTION_EMITTERS)?;
    let nodes = sections.take(SECTION_NODES)?;
    let blocks = sections.take(SECTION_BLOCKS)?;
    sections.finish()?;

    let malformed = |what: String| Invalid::Malformed(what);
    let meta: Meta =
        serde_json::from_slice(&meta_bytes).map_err(|e| malformed(format!("metadata: {e}")))?;
    let count = triangles.len();
    if meta.triangles != count || shading.len() != count {
        return Err(malformed(format!(
            "{} triangles, {} shading records, metadata says {}",
            count,
            shading.len(),
            meta.triangles
        )));
    }
    let materials = scene_materials + meta.mtl_materials.len();
    let lit = shading.iter().filter(|s| s.light != NO_LIGHT).count();
    if shading.iter().any(|s| s.material as usize >= materials) {
        return Err(malformed("a material index out of range".into()));
    }
    let emitter_of = |k: usize, e: &EmitterRecord| {
        shading
            .get(e.triangle as usize)
            .is_some_and(|s| s.light as usize == k)
    };
    if lit != emitters.len() || !emitters.iter().enumerate().all(|(k, e)| emitter_of(k, e)) {
        return Err(malformed("emitters and light indices disagree".into()));
    }
    let bounds = Aabb {
        min: Vec3::from_array(meta.bvh_bounds[0]),
        max: Vec3::from_array(meta.bvh_bounds[1]),
    };
    let report = BuildReport {
        // Not stored, so that the same geometry always makes the same bytes.
        seconds: 0.0,
        binary_sah_cost: meta.bvh_binary_sah_cost,
        sah_cost: meta.bvh_sah_cost,
        nodes: nodes.len(),
        leaves: blocks.len(),
        triangles: count,
        references: blocks
            .iter()
            .map(|b: &crate::bvh::wide::TriangleBlock| {
                b.id.iter().filter(|&&id| id != u32::MAX).count()
            })
            .sum(),
    };
    let bvh = WideBvh::from_parts(nodes, blocks, meta.bvh_root, bounds, report, count)
        .map_err(|e| malformed(format!("BVH: {e}")))?;
    Ok(Geometry {
        triangles,
        shading,
        emitters: emitters
            .iter()
            .map(|e| Emitter {
                triangle: e.triangle,
                radiance: Rgb::from_array(e.radiance),
                two_sided: e.two_sided != 0,
            })
            .collect(),
        mtl_materials: meta.mtl_materials.into_iter().map(mtl_record).collect(),
        mesh_warnings: meta.mesh_warnings,
        degenerate_triangles_dropped: meta.degenerate_triangles_dropped,
        bvh,
    })
}

pub(super) fn emitter_records(g: &Geometry) -> Vec<EmitterRecord> {
    g.emitters.iter().map(EmitterRecord::from).collect()
}

/// The sections of an entry for `g`, in the order `read_entry` takes them.
pub(super) fn sections<'a>(
    g: &'a Geometry,
    meta: &'a [u8],
    emitters: &'a [EmitterRecord],
) -> [Section<'a>; 6] {
    [
        Section::of(SECTION_META, meta),
        Section::of(SECTION_TRIANGLES, &g.triangles),
        Section::of(SECTION_SHADING, &g.shading),
        Section::of(SECTION_EMITTERS, emitters),
        Section::of(SECTION_NODES, g.bvh.nodes()),
        Section::of(SECTION_BLOCKS, g.bvh.blocks()),
    ]
}
