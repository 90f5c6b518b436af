//! Wavefront OBJ meshes with their MTL materials, through `tobj`.
//!
//! MTL materials map onto ours as the scene format says: `Kd`/`map_Kd` →
//! diffuse, `Ke` → emission, `illum 3`/`5` → mirror, `illum 7` or `d` < 1
//! with an `Ni` other than 1 → dielectric, `Pm`/`Pr` or `illum 2` with
//! `Ks` and `Ns` → conductor or plastic. (Exporters such as Blender's write
//! `d 0` with `Ni 1` on opaque materials; a dielectric of index 1 would be
//! invisible, so that combination stays diffuse.)

use super::desc::{AlbedoDesc, MaterialDesc, MaterialOverride};
use crate::color::Rgb;
use crate::files::open_regular;
use crate::geometry::shapes::MeshData;
use glam::{Vec2, Vec3};
use std::io::{BufReader, Read};
use std::path::Path;

/// One part of an OBJ file that uses a single MTL material.
pub struct ObjGroup {
    /// Its triangles, in the OBJ file's (object) space.
    pub mesh: MeshData,
    /// Its MTL material, converted; `None` when it names none or the MTL file
    /// could not be read.
    pub material: Option<MtlMaterial>,
}

/// An MTL material, converted to one of ours.
#[derive(Clone, Debug)]
pub struct MtlMaterial {
    /// The material's name in the MTL file.
    pub name: String,
    /// What it becomes (after any [`MaterialOverride`]).
    pub desc: MaterialDesc,
    /// `Ke`, when it is not black.
    pub emission: Option<Rgb>,
    /// `Kd`: the albedo to fall back on when `map_Kd` cannot be read.
    pub kd: Rgb,
}

/// A loaded OBJ file.
pub struct ObjFile {
    /// Its parts, each with a single material, in file order.
    pub groups: Vec<ObjGroup>,
    /// What did not load but did not stop the mesh (such as a missing MTL file).
    pub warnings: Vec<String>,
}

/// Loads `path`; the error is a message for the caller to place at a key path.
pub fn load_obj(path: &Path, mtl_override: Option<MaterialOverride>) -> Result<ObjFile, String> {
    let file =
        open_regular(path).map_err(|e| format!("cannot read mesh file {}: {e}", path.display()))?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let folder = path.parent().unwrap_or(Path::new("."));
    // MTL files are named relative to the OBJ's folder, and are opened only
    // when they are regular files, as the OBJ is.
    let load_mtl = |name: &Path| {
        let mut mtl =
            open_regular(&folder.join(name)).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        let mut bytes = Vec::new();
        mtl.read_to_end(&mut bytes)
            .map_err(|_| tobj::LoadError::ReadError)?;
        tobj::load_mtl_buf(&mut BufReader::new(&complete_colours(bytes)[..]))
    };
    // tobj computes texture-coordinate and normal offsets from a face's
    // indices unchecked: a relative index before the first `vt`/`vn`
    // (`f 1//-2`) overflows, which panics where overflow is
    // checked (debug and test builds; release builds wrap, to an
    // out-of-bounds error or another vertex's normal). A panic in the
    // parser is a file it cannot read. Release builds abort on a panic
    // (Cargo.toml), so this catch serves the builds that check overflow,
    // where the panic happens.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut BufReader::new(file), &options, load_mtl)
    }))
    .map_err(|_| {
        format!(
            "cannot parse mesh file {}: a face's index is out of range",
            path.display()
        )
    })?;
    let (models, materials) =
        parsed.map_err(|e| format!("cannot parse mesh file {}: {e}", path.display()))?;
    let mut warnings = Vec::new();
    let materials = materials.unwrap_or_else(|e| {
        warnings.push(format!(
            "{}: materials not loaded ({e}); using the default material",
            path.display()
        ));
        Vec::new()
    });
    let converted: Vec<_> = materials
        .iter()
        .map(|m| convert_material(m, folder, mtl_override, &mut warnings))
        .collect();

    let mut groups = Vec::new();
    for model in models {
        let m = model.mesh;
        let vec3s = |v: &[f32]| {
            v.chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect::<Vec<_>>()
        };
        let positions = vec3s(&m.positions);
        let vertex_count = positions.len();
        let normals = (m.normals.len() == m.positions.len() && !m.normals.is_empty())
            .then(|| vec3s(&m.normals));
        let uvs = (m.texcoords.len() / 2 == vertex_count && vertex_count > 0).then(|| {
            m.texcoords
                .chunks_exact(2)
                .map(|c| Vec2::new(c[0], c[1]))
                .collect()
        });
        if m.indices.iter().any(|&i| i as usize >= vertex_count) {
            return Err(format!(
                "mesh file {} has a face index out of range",
                path.display()
            ));
        }
        let material = m.material_id.and_then(|id| converted.get(id).cloned());
        groups.push(ObjGroup {
            mesh: MeshData {
                positions,
                normals,
                uvs,
                indices: m.indices,
            },
            material,
        });
    }
    if groups.iter().all(|g| g.mesh.indices.len() < 3) {
        warnings.push(format!(
            "mesh file {} has no triangles (is it an OBJ file?)",
            path.display()
        ));
    }
    Ok(ObjFile { groups, warnings })
}

/// MTL colour lines (`Ka`, `Kd`, `Ks`, `Ke`) with fewer than three values
/// completed: `Kd 0.5` means `Kd 0.5 0.5 0.5` (the MTL format allows the
/// short form), a missing value repeats the last one, and a line with no
/// value is dropped. tobj panics on any of them (it unwraps a conversion
/// of the values it found to three). Text that is not UTF-8 is left for
/// tobj to refuse.
fn complete_colours(bytes: Vec<u8>) -> Vec<u8> {
    let text = match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => return e.into_bytes(),
    };
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.split_inclusive('\n') {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or_default();
        let mut values: Vec<&str> = words.take(3).collect();
        match (key, values.last()) {
            ("Ka" | "Kd" | "Ks" | "Ke", _) if values.len() == 3 => out.push_str(line),
            ("Ka" | "Kd" | "Ks" | "Ke", Some(&last)) => {
                values.resize(3, last);
                out.push_str(&format!("{key} {}\n", values.join(" ")));
            }
            ("Ka" | "Kd" | "Ks" | "Ke", None) => {}
            _ => out.push_str(line),
        }
    }
    out.into_bytes()
}

/// The material of an MTL entry that is neither glass nor a mirror: a
/// metal or a coated (plastic) surface when its keys say it is glossy,
/// else diffuse. The PBR extension's `Pm` (metallic, ≥ 0.5: a metal) and
/// `Pr` (roughness r: GGX alpha = r², the usual convention) come first;
/// otherwise `illum 2` (highlights on) with a non-black `Ks` and a Phong
/// exponent `Ns` makes a plastic
/// of alpha = √(2 / (Ns + 2)), Walter et al.'s (2007) match of a Phong
/// lobe to a microfacet one. A metal's colour is `Kd` (the PBR base
/// colour) with Fresnel 1 (a `map_Kd` is not used for it); a plastic's
/// coat takes `Ni` when it is above 1. `Ks`'s magnitude is not used: any
/// non-black `Ks` turns on a full Fresnel coat.
fn glossy_material(
    m: &tobj::Material,
    albedo: AlbedoDesc,
    kd: Rgb,
    ni: Option<f32>,
) -> MaterialDesc {
    let param = |key: &str| {
        m.unknown_param
            .get(key)
            .and_then(|v| v.trim().parse::<f32>().ok())
            .filter(|v| v.is_finite())
    };
    let coat_ior = ni.filter(|&n| n > 1.0).unwrap_or(1.5);
    let roughness = param("Pr").map(|r| r.clamp(0.0, 1.0));
    let metallic = param("Pm").map(|p| p.clamp(0.0, 1.0));
    if metallic.is_some_and(|p| p >= 0.5) {
        let r = roughness.unwrap_or(0.5);
        return MaterialDesc::Conductor {
            alpha: r * r,
            ior: None,
            reflectance: kd,
        };
    }
    if let Some(r) = roughness {
        return MaterialDesc::Plastic {
            albedo,
            ior: coat_ior,
            alpha: r * r,
        };
    }
    let ks = m.specular.map(Rgb::from).unwrap_or(Rgb::ZERO);
    let highlights = m.illumination_model == Some(2);
    match m.shininess.filter(|n| n.is_finite() && *n >= 0.0) {
        Some(ns) if highlights && ks.max_element() > 0.0 => MaterialDesc::Plastic {
            albedo,
            ior: coat_ior,
            alpha: (2.0 / (ns + 2.0)).sqrt(),
        },
        _ => MaterialDesc::Diffuse { albedo },
    }
}

fn convert_material(
    m: &tobj::Material,
    folder: &Path,
    mtl_override: Option<MaterialOverride>,
    warnings: &mut Vec<String>,
) -> MtlMaterial {
    let kd = m.diffuse.map_or(Rgb::splat(0.5), Rgb::from);
    let kd_clamped = kd.clamp(Rgb::ZERO, Rgb::ONE);
    if kd_clamped != kd {
        warnings.push(format!("material {}: Kd clamped to [0, 1]", m.name));
    }
    let emission = m
        .emissive
        .map(Rgb::from)
        .filter(|e| e.max_element() > 0.0 && e.min_element() >= 0.0);
    let desc = match mtl_override {
        Some(MaterialOverride::Diffuse) => MaterialDesc::Diffuse {
            albedo: AlbedoDesc::Constant(kd_clamped),
        },
        Some(MaterialOverride::Mirror) => MaterialDesc::Mirror {
            reflectance: kd_clamped,
        },
        Some(MaterialOverride::Glass) => MaterialDesc::Dielectric {
            ior: m.optical_density.filter(|&n| n > 1.0).unwrap_or(1.5),
            transmittance: kd_clamped,
        },
        None => {
            let illum = m.illumination_model.unwrap_or(0);
            let ni = m.optical_density.filter(|n| n.is_finite() && *n > 0.0);
            let translucent = m.dissolve.is_some_and(|d| d < 1.0) && ni.is_some_and(|n| n != 1.0);
            if illum == 7 || translucent {
                MaterialDesc::Dielectric {
                    ior: ni.unwrap_or(1.5),
                    transmittance: Rgb::ONE,
                }
            } else if illum == 3 || illum == 5 {
                let ks = m.specular.map(Rgb::from).filter(|k| k.max_element() > 0.0);
                MaterialDesc::Mirror {
                    reflectance: ks.unwrap_or(Rgb::ONE).clamp(Rgb::ZERO, Rgb::ONE),
                }
            } else {
                let albedo = match &m.diffuse_texture {
                    Some(t) if !t.is_empty() => {
                        AlbedoDesc::Texture(folder.join(t.replace('\\', "/")))
                    }
                    _ => AlbedoDesc::Constant(kd_clamped),
                };
                glossy_material(m, albedo, kd_clamped, ni)
            }
        }
    };
    MtlMaterial {
        name: m.name.clone(),
        desc,
        emission,
        kd: kd_clamped,
    }
}
