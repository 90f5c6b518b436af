//! Imports T-racer `.trs` scenes (the JSON dialect of this renderer's C++
//! predecessor) into a [`SceneDesc`].
//!
//! Top-level members each have a `"Type"`: `"Camera"` (`Position`, vertical
//! `fov`, looking along +z), `"Light"` (`"Point"` with `Position` and
//! `Intensity`, or `"Area"` with a triangle list `Vertices` and `Intensity` as
//! radiance) or `"Mesh"` (`MeshName`, looked up beside the scene and then in
//! `resources/`; `"Mesh Material"` `"Diffuse"`, `"Mirror"` or `"Glass"`
//! applied to every MTL material with its `Kd` as colour). The member named
//! `"Display"` gives `ResX`, `ResY` and the output `Type`.
//!
//! T-racer also wrote `Colour`, `Texture`, `Name` and `NumberOfVertices`;
//! these are accepted and ignored (the colour comes from the MTL, the vertex
//! count from `Vertices`). Any other key is refused, as in the JSON format.

use super::desc::*;
use crate::color::Rgb;
use crate::geometry::transform::Transform;
use crate::{Error, Result};
use glam::Vec3;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

/// Name of the black material T-racer's area-light triangles get.
pub const LIGHT_MATERIAL: &str = "trs-light";

pub fn parse(text: &str, file: &Path) -> Result<SceneDesc> {
    let mut de = serde_json::Deserializer::from_str(text);
    let root: Value = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| super::format::json_error(file, e))?;
    let err = |path: &str, msg: String| Error::scene(file, path, msg);
    let Value::Object(members) = root else {
        return Err(err(
            "(top level)",
            "expected an object of named members".into(),
        ));
    };

    let mut name = file
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let mut camera = None;
    let mut film = FilmDesc::default();
    let mut display = None;
    let mut objects = Vec::new();
    let mut lights = Vec::new();
    let mut needs_light_material = false;

    for (key, value) in &members {
        let path = format!("\"{key}\"");
        if key == "SceneName" {
            name = value
                .as_str()
                .ok_or_else(|| err(&path, "expected a string".into()))?
                .to_string();
            continue;
        }
        let Value::Object(m) = value else {
            return Err(err(&path, "expected an object".into()));
        };
        let member = Member {
            file,
            path: &path,
            map: m,
        };
        if key == "Display" {
            member.only(&["Name", "Type", "ResX", "ResY"])?;
            film.width = Count(member.count("ResX")?);
            film.height = Count(member.count("ResY")?);
            display = Some(match member.string("Type")? {
                "PFM" => Display::Pfm,
                "TGA" => Display::Tga,
                "Window" => Display::Window,
                other => {
                    return Err(err(
                        &format!("{path}.Type"),
                        format!("unknown display type \"{other}\", expected PFM, TGA or Window"),
                    ))
                }
            });
            continue;
        }
        match member.string("Type")? {
            "Camera" => {
                member.only(&["Type", "Name", "Position", "fov"])?;
                let position = member.vec3("Position")?;
                let fov = member.number("fov")?;
                camera = Some(CameraDesc {
                    kind: CameraType::Perspective,
                    position: V3(position),
                    look_at: V3(position + Vec3::Z),
                    up: V3(Vec3::Y),
                    fov: Positive(fov),
                });
            }
            "Light" => match member.string("LightType")? {
                "Point" => {
                    member.only(&["Type", "Name", "LightType", "Position", "Intensity"])?;
                    lights.push((
                        path.clone(),
                        LightDesc::Point {
                            position: member.vec3("Position")?,
                            intensity: member.color("Intensity")?,
                        },
                    ));
                }
                "Area" => {
                    member.only(&[
                        "Type",
                        "Name",
                        "LightType",
                        "Intensity",
                        "NumberOfVertices",
                        "Vertices",
                    ])?;
                    let radiance = member.color("Intensity")?;
                    let positions = member.vec3_list("Vertices")?;
                    if positions.is_empty() || !positions.len().is_multiple_of(3) {
                        return Err(err(
                            &format!("{path}.Vertices"),
                            format!(
                                "expected whole triangles (a multiple of 3 vertices), found {}",
                                positions.len()
                            ),
                        ));
                    }
                    needs_light_material = true;
                    objects.push(ObjectDesc {
                        key_path: path.clone(),
                        shape: ShapeDesc::Triangles {
                            positions,
                            indices: None,
                            normals: None,
                            uvs: None,
                        },
                        material: Some(LIGHT_MATERIAL.into()),
                        transform: Transform::IDENTITY,
                        emission: Some(radiance),
                        two_sided: false,
                    });
                }
                other => {
                    return Err(err(
                        &format!("{path}.LightType"),
                        format!("unknown light type \"{other}\", expected Point or Area"),
                    ))
                }
            },
            "Mesh" => {
                member.only(&[
                    "Type",
                    "Name",
                    "MeshName",
                    "Mesh Material",
                    "Colour",
                    "Texture",
                ])?;
                let mesh_name = member.string("MeshName")?;
                let file = find_mesh(file, mesh_name).ok_or_else(|| {
                    err(
                        &format!("{path}.MeshName"),
                        format!("mesh file \"{mesh_name}\" not found beside the scene or in its resources/ folder"),
                    )
                })?;
                let mtl_override = match member.map.get("Mesh Material") {
                    None => None,
                    Some(_) => Some(match member.string("Mesh Material")? {
                        "Diffuse" => MaterialOverride::Diffuse,
                        "Mirror" => MaterialOverride::Mirror,
                        "Glass" => MaterialOverride::Glass,
                        other => {
                            return Err(err(
                                &format!("{path}.\"Mesh Material\""),
                                format!(
                                "unknown material \"{other}\", expected Diffuse, Mirror or Glass"
                            ),
                            ))
                        }
                    }),
                };
                objects.push(ObjectDesc {
                    key_path: path.clone(),
                    shape: ShapeDesc::Mesh { file, mtl_override },
                    material: None,
                    transform: Transform::IDENTITY,
                    emission: None,
                    two_sided: false,
                });
            }
            other => {
                return Err(err(
                    &format!("{path}.Type"),
                    format!("unknown member type \"{other}\", expected Camera, Light or Mesh"),
                ))
            }
        }
    }
    let camera =
        camera.ok_or_else(|| err("(top level)", "missing a member of Type \"Camera\"".into()))?;
    let extension = match display {
        Some(Display::Pfm) => "pfm",
        Some(Display::Tga) => "tga",
        _ => "exr",
    };
    film.output = Some(format!("{name}.{extension}"));
    let materials = if needs_light_material {
        vec![(
            LIGHT_MATERIAL.to_string(),
            MaterialDesc::Diffuse {
                albedo: AlbedoDesc::Constant(Rgb::ZERO),
            },
        )]
    } else {
        Vec::new()
    };
    Ok(SceneDesc {
        file: file.to_path_buf(),
        name,
        camera,
        film,
        render: RenderDesc::default(),
        materials,
        objects,
        lights,
        display,
    })
}

fn find_mesh(scene: &Path, name: &str) -> Option<PathBuf> {
    let folder = scene.parent().unwrap_or(Path::new("."));
    [folder.join(name), folder.join("resources").join(name)]
        .into_iter()
        .find(|p| p.is_file())
}

struct Member<'a> {
    file: &'a Path,
    path: &'a str,
    map: &'a Map<String, Value>,
}

impl Member<'_> {
    fn err(&self, key: &str, msg: impl Into<String>) -> Error {
        let key = if key.contains(' ') {
            format!("\"{key}\"")
        } else {
            key.to_string()
        };
        Error::scene(self.file, format!("{}.{key}", self.path), msg)
    }

    fn get(&self, key: &str) -> Result<&Value> {
        self.map
            .get(key)
            .ok_or_else(|| self.err(key, "missing required key"))
    }

    fn only(&self, allowed: &[&str]) -> Result<()> {
        match self.map.keys().find(|k| !allowed.contains(&k.as_str())) {
            Some(k) => Err(self.err(
                k,
                format!("unknown key, expected one of: {}", allowed.join(", ")),
            )),
            None => Ok(()),
        }
    }

    fn string(&self, key: &str) -> Result<&str> {
        self.get(key)?
            .as_str()
            .ok_or_else(|| self.err(key, "expected a string"))
    }

    fn number(&self, key: &str) -> Result<f32> {
        let x = self
            .get(key)?
            .as_f64()
            .ok_or_else(|| self.err(key, "expected a number"))?;
        if !x.is_finite() || x.abs() > f32::MAX as f64 {
            return Err(self.err(key, "expected a finite number"));
        }
        Ok(x as f32)
    }

    fn count(&self, key: &str) -> Result<u32> {
        match self.get(key)?.as_u64() {
            Some(n) if n > 0 && n <= u32::MAX as u64 => Ok(n as u32),
            _ => Err(self.err(key, "expected a whole number greater than zero")),
        }
    }

    fn vec3_of(&self, key: &str, v: &Value) -> Result<Vec3> {
        let a = v
            .as_array()
            .filter(|a| a.len() == 3)
            .ok_or_else(|| self.err(key, "expected [x, y, z]"))?;
        let mut out = [0.0f32; 3];
        for (o, x) in out.iter_mut().zip(a) {
            let x = x
                .as_f64()
                .filter(|x| x.is_finite() && x.abs() <= f32::MAX as f64);
            *o = x.ok_or_else(|| self.err(key, "expected [x, y, z] of finite numbers"))? as f32;
        }
        Ok(Vec3::from(out))
    }

    fn vec3(&self, key: &str) -> Result<Vec3> {
        self.vec3_of(key, self.get(key)?)
    }

    fn color(&self, key: &str) -> Result<Rgb> {
        let c = self.vec3(key)?;
        if c.min_element() < 0.0 {
            return Err(self.err(key, "expected a colour with no negative channel"));
        }
        Ok(c)
    }

    fn vec3_list(&self, key: &str) -> Result<Vec<Vec3>> {
        let list = self
            .get(key)?
            .as_array()
            .ok_or_else(|| self.err(key, "expected a list of [x, y, z]"))?;
        list.iter()
            .enumerate()
            .map(|(i, v)| self.vec3_of(&format!("{key}[{i}]"), v))
            .collect()
    }
}
