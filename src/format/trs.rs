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
use crate::settings::{CameraSettings, Display, Setting, Settings};
use crate::{Error, Result};
use glam::Vec3;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

/// Name of the black material T-racer's area-light triangles get.
pub const LIGHT_MATERIAL: &str = "trs-light";

/// Parses `text`, the contents of `file`.
pub fn parse(text: &str, file: &Path) -> Result<SceneDesc> {
    let mut de = serde_json::Deserializer::from_str(text);
    let root: Value =
        serde_path_to_error::deserialize(&mut de).map_err(|e| super::json::json_error(file, e))?;
    if !root.is_object() {
        return Err(Error::scene(
            file,
            "(top level)",
            "expected an object of named members",
        ));
    }
    // Read again keeping every member: a name given twice is refused, not
    // resolved silently in favour of the last.
    let members: UniqueMap = serde_json::from_str(text).map_err(|e| {
        Error::scene(
            file,
            "(top level)",
            super::json::strip_position(&e.to_string()),
        )
    })?;
    let members = members.0;
    let mut reader = Reader {
        file,
        name: file
            .file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned()),
        camera: None,
        size: None,
        display: None,
        objects: Vec::new(),
        lights: Vec::new(),
        needs_light_material: false,
    };
    for (key, value) in &members {
        reader.member(key, value)?;
    }
    reader.finish()
}

/// What the members read so far describe.
struct Reader<'a> {
    file: &'a Path,
    name: String,
    /// The camera and the key path of its member.
    camera: Option<(CameraSettings, String)>,
    size: Option<(u32, u32)>,
    display: Option<Display>,
    objects: Vec<ObjectDesc>,
    lights: Vec<(String, LightDesc)>,
    needs_light_material: bool,
}

impl Reader<'_> {
    fn err(&self, path: &str, msg: impl Into<String>) -> Error {
        Error::scene(self.file, path, msg)
    }

    fn member(&mut self, key: &str, value: &Value) -> Result<()> {
        let path = format!("\"{key}\"");
        if key == "SceneName" {
            self.name = value
                .as_str()
                .ok_or_else(|| self.err(&path, "expected a string"))?
                .to_string();
            return Ok(());
        }
        let Value::Object(m) = value else {
            return Err(self.err(&path, "expected an object"));
        };
        let member = Member {
            file: self.file,
            path: &path,
            map: m,
        };
        if key == "Display" {
            return self.display(&member);
        }
        match member.string("Type")? {
            "Camera" => {
                member.only(&["Type", "Name", "Position", "fov"])?;
                let position = member.vec3("Position")?;
                let camera = CameraSettings {
                    position,
                    look_at: position + Vec3::Z,
                    up: Vec3::Y,
                    fov: member.number("fov")?,
                    aperture_radius: 0.0,
                    focus_distance: None,
                };
                self.camera = Some((camera, path.clone()));
                Ok(())
            }
            "Light" => self.light(&member),
            "Mesh" => self.mesh(&member),
            other => Err(self.err(
                &format!("{path}.Type"),
                format!("unknown member type \"{other}\", expected Camera, Light or Mesh"),
            )),
        }
    }

    fn display(&mut self, member: &Member) -> Result<()> {
        member.only(&["Name", "Type", "ResX", "ResY"])?;
        self.size = Some((member.count("ResX")?, member.count("ResY")?));
        self.display = Some(match member.string("Type")? {
            "PFM" => Display::Pfm,
            "TGA" => Display::Tga,
            "Window" => Display::Window,
            other => {
                return Err(member.err(
                    "Type",
                    format!("unknown display type \"{other}\", expected PFM, TGA or Window"),
                ))
            }
        });
        Ok(())
    }

    fn light(&mut self, member: &Member) -> Result<()> {
        let path = member.path.to_string();
        match member.string("LightType")? {
            "Point" => {
                member.only(&["Type", "Name", "LightType", "Position", "Intensity"])?;
                self.lights.push((
                    path,
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
                    return Err(member.err(
                        "Vertices",
                        format!(
                            "expected whole triangles (a multiple of 3 vertices), found {}",
                            positions.len()
                        ),
                    ));
                }
                self.needs_light_material = true;
                self.objects.push(ObjectDesc {
                    key_path: path,
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
                return Err(member.err(
                    "LightType",
                    format!("unknown light type \"{other}\", expected Point or Area"),
                ))
            }
        }
        Ok(())
    }

    fn mesh(&mut self, member: &Member) -> Result<()> {
        member.only(&[
            "Type",
            "Name",
            "MeshName",
            "Mesh Material",
            "Colour",
            "Texture",
        ])?;
        let mesh_name = member.string("MeshName")?;
        let file = find_mesh(self.file, mesh_name).ok_or_else(|| {
            member.err(
                "MeshName",
                format!(
                    "mesh file \"{mesh_name}\" not found beside the scene or in its resources/ folder"
                ),
            )
        })?;
        let mtl_override = match member.map.get("Mesh Material") {
            None => None,
            Some(_) => Some(match member.string("Mesh Material")? {
                "Diffuse" => MaterialOverride::Diffuse,
                "Mirror" => MaterialOverride::Mirror,
                "Glass" => MaterialOverride::Glass,
                other => {
                    return Err(member.err(
                        "Mesh Material",
                        format!("unknown material \"{other}\", expected Diffuse, Mirror or Glass"),
                    ))
                }
            }),
        };
        self.objects.push(ObjectDesc {
            key_path: member.path.to_string(),
            shape: ShapeDesc::Mesh { file, mtl_override },
            material: None,
            transform: Transform::IDENTITY,
            emission: None,
            two_sided: false,
        });
        Ok(())
    }

    /// The description, with the settings checked as the JSON format's are.
    fn finish(self) -> Result<SceneDesc> {
        let Some((camera, camera_path)) = self.camera.clone() else {
            return Err(self.err("(top level)", "missing a member of Type \"Camera\""));
        };
        let extension = match self.display {
            Some(Display::Pfm) => "pfm",
            Some(Display::Tga) => "tga",
            _ => "exr",
        };
        let output = super::resolve(self.file, &format!("{}.{extension}", self.name));
        let mut settings = Settings::new(camera, output);
        if let Some((width, height)) = self.size {
            settings.film.width = width;
            settings.film.height = height;
        }
        settings.display = self.display;
        settings.check().map_err(|e| {
            let key = match e.setting {
                Setting::Fov => format!("{camera_path}.fov"),
                Setting::ImageSize => "\"Display\"".into(),
                _ => camera_path.clone(),
            };
            self.err(&key, e.message)
        })?;
        let materials = if self.needs_light_material {
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
            file: self.file.to_path_buf(),
            name: self.name,
            settings,
            materials,
            objects: self.objects,
            lights: self.lights,
        })
    }
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
