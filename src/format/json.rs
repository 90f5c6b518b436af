//! Reads the JSON scene format (`docs/scene-format.md`, version 1) into a
//! [`SceneDesc`].
//!
//! Plain sections deserialise straight into serde types with unknown keys
//! refused. Tagged sections (materials, objects, lights) are read as JSON
//! values first, then dispatched on `type` into per-type structs, so each
//! type refuses the keys it does not know. Every error carries the key path.

use super::desc::*;
use super::resolve;
use super::sections::{self, CameraDesc, FilmDesc, RenderDesc};
use crate::geometry::transform::Transform;
use crate::settings::{Invalid, Setting};
use crate::{Error, Result};
use glam::Vec3;
use serde::de::DeserializeOwned;
use serde::Deserialize;
use serde_json::{Map, Value};
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default = "format_version")]
    format: u32,
    #[serde(default)]
    name: Option<String>,
    camera: CameraDesc,
    #[serde(default)]
    film: FilmDesc,
    #[serde(default)]
    render: RenderDesc,
    #[serde(default)]
    materials: UniqueMap,
    #[serde(default)]
    objects: Vec<Value>,
    #[serde(default)]
    lights: Vec<Value>,
}

fn format_version() -> u32 {
    1
}

/// Parses `text`, the contents of `file`.
pub fn parse(text: &str, file: &Path) -> Result<SceneDesc> {
    let mut de = serde_json::Deserializer::from_str(text);
    let scene: SceneFile =
        serde_path_to_error::deserialize(&mut de).map_err(|e| json_error(file, e))?;
    de.end().map_err(|e| Error::Syntax {
        file: file.to_path_buf(),
        line: e.line(),
        column: e.column(),
        message: strip_position(&e.to_string()),
    })?;
    if scene.format != 1 {
        return Err(Error::scene(
            file,
            "format",
            format!(
                "unsupported format version {}; this renderer reads version 1",
                scene.format
            ),
        ));
    }
    if scene.name.as_deref().is_some_and(|n| n.trim().is_empty()) {
        return Err(Error::scene(
            file,
            "name",
            "expected a non-empty name (it names the default output file)",
        ));
    }
    if scene
        .film
        .output
        .as_deref()
        .is_some_and(|o| o.trim().is_empty())
    {
        return Err(Error::scene(
            file,
            "film.output",
            "expected a file name, found an empty string",
        ));
    }
    let output = match &scene.film.output {
        Some(o) => resolve(file, o),
        None => resolve(
            file,
            &format!("{}.exr", name_of(file, scene.name.as_deref())),
        ),
    };
    let settings = sections::settings(&scene.camera, &scene.film, &scene.render, output);
    settings.check().map_err(|e| settings_error(file, e))?;
    let ctx = Ctx { file };
    let materials = scene
        .materials
        .0
        .iter()
        .map(|(name, v)| Ok((name.clone(), ctx.material(v, &format!("materials.{name}"))?)))
        .collect::<Result<Vec<_>>>()?;
    let objects = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, v)| ctx.object(v, &format!("objects[{i}]")))
        .collect::<Result<Vec<_>>>()?;
    let lights = scene
        .lights
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let path = format!("lights[{i}]");
            Ok((path.clone(), ctx.light(v, &path)?))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(SceneDesc {
        file: file.to_path_buf(),
        name: name_of(file, scene.name.as_deref()),
        settings,
        materials,
        objects,
        lights,
    })
}

/// The scene's name: its `name` key, or the file's name without extension.
fn name_of(file: &Path, name: Option<&str>) -> String {
    name.map(str::to_string).unwrap_or_else(|| {
        file.file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
    })
}

/// A refused setting, placed at the key of the file that holds it.
fn settings_error(file: &Path, e: Invalid) -> Error {
    let key = match e.setting {
        Setting::Fov => "camera.fov",
        Setting::Camera => "camera",
        Setting::ImageSize => "film",
        Setting::Crop | Setting::SampleRange | Setting::Adaptive => "render",
    };
    Error::scene(file, key, e.message)
}

/// Turns a serde_json error into ours: syntax errors by line and column,
/// everything else by key path.
pub(crate) fn json_error(file: &Path, e: serde_path_to_error::Error<serde_json::Error>) -> Error {
    let path = e.path().to_string();
    let inner = e.into_inner();
    let message = strip_position(&inner.to_string());
    // serde_json calls a number too large for an f64 (1e999) a syntax error;
    // it is a non-finite number, and the key path says where.
    if message.starts_with("number out of range") && path != "." {
        return Error::scene(
            file,
            path,
            format!(
                "expected a finite number, found one out of range (line {}, column {})",
                inner.line(),
                inner.column()
            ),
        );
    }
    match inner.classify() {
        serde_json::error::Category::Syntax | serde_json::error::Category::Eof => Error::Syntax {
            file: file.to_path_buf(),
            line: inner.line(),
            column: inner.column(),
            message,
        },
        _ => Error::scene(file, display_path(&path), message),
    }
}

fn display_path(path: &str) -> String {
    if path == "." {
        "(top level)".into()
    } else {
        path.to_string()
    }
}

/// serde_json appends " at line L column C"; we report the key path instead.
pub(crate) fn strip_position(message: &str) -> String {
    let message = match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
    .replace("unknown field", "unknown key")
    .replace("missing field", "missing required key");
    crate::error::clip(message)
}

// The own keys of each object type.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Mesh {
    file: String,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Empty {}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Sphere {
    #[serde(default)]
    center: Option<V3>,
    #[serde(default)]
    radius: Option<Positive>,
    #[serde(default)]
    subdivisions: Option<u32>,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Triangles {
    positions: Vec<V3>,
    #[serde(default)]
    indices: Option<Vec<u32>>,
    #[serde(default)]
    normals: Option<Vec<V3>>,
    #[serde(default)]
    uvs: Option<Vec<V2>>,
}

struct Ctx<'a> {
    file: &'a Path,
}

impl Ctx<'_> {
    fn err(&self, path: &str, message: impl Into<String>) -> Error {
        Error::scene(self.file, path, message)
    }

    /// Deserialises `value` (the section at `path`) into `T`, reporting the full path on error.
    fn typed<T: DeserializeOwned>(&self, value: Value, path: &str) -> Result<T> {
        serde_path_to_error::deserialize(value).map_err(|e| {
            let inner = e.path().to_string();
            let full = if inner == "." {
                path.to_string()
            } else {
                format!("{path}.{inner}")
            };
            let full = full.replace(".[", "[");
            self.err(&full, strip_position(&e.into_inner().to_string()))
        })
    }

    /// Splits a tagged section into its `type` and its other keys.
    fn tagged(
        &self,
        value: &Value,
        path: &str,
        types: &[&str],
    ) -> Result<(String, Map<String, Value>)> {
        let Value::Object(map) = value else {
            return Err(self.err(
                path,
                format!("expected an object, found {}", kind_of(value)),
            ));
        };
        let mut map = map.clone();
        let kind = match map.remove("type") {
            Some(Value::String(s)) if types.contains(&s.as_str()) => s,
            Some(Value::String(s)) => {
                return Err(self.err(
                    &format!("{path}.type"),
                    format!(
                        "unknown type \"{s}\", expected one of: {}",
                        types.join(", ")
                    ),
                ))
            }
            Some(other) => {
                return Err(self.err(
                    &format!("{path}.type"),
                    format!("expected a string, found {}", kind_of(&other)),
                ))
            }
            None => {
                return Err(self.err(
                    &format!("{path}.type"),
                    format!("missing required key (one of: {})", types.join(", ")),
                ))
            }
        };
        Ok((kind, map))
    }

    fn material(&self, value: &Value, path: &str) -> Result<MaterialDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Diffuse {
            #[serde(default)]
            albedo: Option<Value>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Mirror {
            #[serde(default)]
            reflectance: Option<Reflectance>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Dielectric {
            #[serde(default)]
            ior: Option<Positive>,
            #[serde(default)]
            transmittance: Option<Reflectance>,
        }
        let (kind, map) = self.tagged(value, path, &["diffuse", "mirror", "dielectric"])?;
        let map = Value::Object(map);
        Ok(match kind.as_str() {
            "diffuse" => {
                let d: Diffuse = self.typed(map, path)?;
                let albedo = match d.albedo {
                    None => AlbedoDesc::Constant(glam::Vec3::splat(0.5)),
                    Some(v) => self.albedo(v, &format!("{path}.albedo"))?,
                };
                MaterialDesc::Diffuse { albedo }
            }
            "mirror" => {
                let m: Mirror = self.typed(map, path)?;
                MaterialDesc::Mirror {
                    reflectance: m.reflectance.map_or(Vec3::ONE, |r| r.0),
                }
            }
            _ => {
                let d: Dielectric = self.typed(map, path)?;
                MaterialDesc::Dielectric {
                    ior: d.ior.map_or(1.5, |x| x.0),
                    transmittance: d.transmittance.map_or(Vec3::ONE, |r| r.0),
                }
            }
        })
    }

    fn albedo(&self, value: Value, path: &str) -> Result<AlbedoDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct TextureRef {
            texture: String,
        }
        match value {
            Value::Object(_) => {
                let t: TextureRef = self.typed(value, path)?;
                Ok(AlbedoDesc::Texture(resolve(self.file, &t.texture)))
            }
            Value::Array(_) => Ok(AlbedoDesc::Constant(
                self.typed::<Reflectance>(value, path)?.0,
            )),
            other => Err(self.err(
                path,
                format!(
                    "expected an RGB colour or {{\"texture\": file}}, found {}",
                    kind_of(&other)
                ),
            )),
        }
    }

    fn object(&self, value: &Value, path: &str) -> Result<ObjectDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Common {
            #[serde(default)]
            material: Option<String>,
            #[serde(default)]
            transform: Option<Value>,
            #[serde(default)]
            emission: Option<Color>,
            #[serde(default)]
            two_sided: bool,
        }
        const COMMON: [&str; 4] = ["material", "transform", "emission", "two_sided"];

        let (kind, mut map) = self.tagged(
            value,
            path,
            &["mesh", "quad", "cube", "sphere", "triangles"],
        )?;
        let mut common_map = Map::new();
        for key in COMMON {
            if let Some(v) = map.remove(key) {
                common_map.insert(key.to_string(), v);
            }
        }
        let common: Common = self.typed(Value::Object(common_map), path)?;
        let own_keys: &[&str] = match kind.as_str() {
            "mesh" => &["file"],
            "sphere" => &["center", "radius", "subdivisions"],
            "triangles" => &["positions", "indices", "normals", "uvs"],
            _ => &[],
        };
        if let Some(unknown) = map.keys().find(|k| !own_keys.contains(&k.as_str())) {
            let allowed: Vec<&str> = own_keys.iter().chain(COMMON.iter()).copied().collect();
            return Err(self.err(
                &format!("{path}.{unknown}"),
                format!("unknown key, a {kind} takes: {}", allowed.join(", ")),
            ));
        }
        let shape = self.shape(&kind, Value::Object(map), path)?;
        let transform = match common.transform {
            None => Transform::IDENTITY,
            Some(v) => self.transform(v, &format!("{path}.transform"))?,
        };
        Ok(ObjectDesc {
            key_path: path.to_string(),
            shape,
            material: common.material,
            transform,
            emission: common.emission.map(|c| c.0),
            two_sided: common.two_sided,
        })
    }

    /// The shape of an object of type `kind`, from its own keys (`rest`).
    fn shape(&self, kind: &str, rest: Value, path: &str) -> Result<ShapeDesc> {
        Ok(match kind {
            "mesh" => {
                let m: Mesh = self.typed(rest, path)?;
                ShapeDesc::Mesh {
                    file: resolve(self.file, &m.file),
                    mtl_override: None,
                }
            }
            "quad" => {
                self.typed::<Empty>(rest, path)?;
                ShapeDesc::Quad
            }
            "cube" => {
                self.typed::<Empty>(rest, path)?;
                ShapeDesc::Cube
            }
            "sphere" => {
                let s: Sphere = self.typed(rest, path)?;
                let subdivisions = s.subdivisions.unwrap_or(4);
                if subdivisions > MAX_SUBDIVISIONS {
                    return Err(self.err(
                    &format!("{path}.subdivisions"),
                    format!("expected at most {MAX_SUBDIVISIONS} (20 × 4^{MAX_SUBDIVISIONS} triangles), found {subdivisions}"),
                ));
                }
                ShapeDesc::Sphere {
                    center: s.center.map_or(Vec3::ZERO, |c| c.0),
                    radius: s.radius.map_or(1.0, |r| r.0),
                    subdivisions,
                }
            }
            _ => {
                let t: Triangles = self.typed(rest, path)?;
                self.check_triangles(&t.positions, &t.indices, &t.normals, &t.uvs, path)?;
                ShapeDesc::Triangles {
                    positions: t.positions.into_iter().map(|p| p.0).collect(),
                    indices: t.indices,
                    normals: t.normals.map(|n| n.into_iter().map(|n| n.0).collect()),
                    uvs: t.uvs.map(|u| u.into_iter().map(|u| u.0).collect()),
                }
            }
        })
    }

    fn check_triangles(
        &self,
        positions: &[V3],
        indices: &Option<Vec<u32>>,
        normals: &Option<Vec<V3>>,
        uvs: &Option<Vec<V2>>,
        path: &str,
    ) -> Result<()> {
        let n = positions.len();
        let count = indices.as_ref().map_or(n, Vec::len);
        if count == 0 || !count.is_multiple_of(3) {
            let key = if indices.is_some() {
                "indices"
            } else {
                "positions"
            };
            return Err(self.err(
                &format!("{path}.{key}"),
                format!(
                    "expected a non-empty multiple of 3 entries (whole triangles), found {count}"
                ),
            ));
        }
        if let Some(idx) = indices {
            if let Some((i, &bad)) = idx.iter().enumerate().find(|(_, &k)| k as usize >= n) {
                return Err(self.err(
                    &format!("{path}.indices[{i}]"),
                    format!("index {bad} is out of range: there are {n} positions"),
                ));
            }
        }
        if let Some(normals) = normals {
            if normals.len() != n {
                return Err(self.err(
                    &format!("{path}.normals"),
                    format!(
                        "expected one normal per position ({n}), found {}",
                        normals.len()
                    ),
                ));
            }
        }
        if let Some(uvs) = uvs {
            if uvs.len() != n {
                return Err(self.err(
                    &format!("{path}.uvs"),
                    format!("expected one UV per position ({n}), found {}", uvs.len()),
                ));
            }
        }
        Ok(())
    }

    fn transform(&self, value: Value, path: &str) -> Result<Transform> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct TransformFile {
            #[serde(default)]
            matrix: Option<[Finite; 16]>,
            #[serde(default)]
            scale: Option<Value>,
            #[serde(default)]
            rotate: Option<[Finite; 4]>,
            #[serde(default)]
            translate: Option<V3>,
        }
        let t: TransformFile = self.typed(value, path)?;
        let singular = || {
            self.err(
                path,
                "the transform is singular (it flattens the object to zero volume)",
            )
        };
        if let Some(m) = t.matrix {
            if t.scale.is_some() || t.rotate.is_some() || t.translate.is_some() {
                return Err(self.err(
                    path,
                    "give either \"matrix\" or scale/rotate/translate, not both",
                ));
            }
            let rows: Vec<f32> = m.iter().map(|x| x.0).collect();
            let matrix = glam::Mat4::from_cols_slice(&rows).transpose();
            let bottom = matrix.row(3);
            if bottom != glam::Vec4::new(0.0, 0.0, 0.0, 1.0) {
                return Err(self.err(
                    &format!("{path}.matrix"),
                    "expected an affine matrix: the last row must be [0, 0, 0, 1]",
                ));
            }
            return Transform::new(matrix).ok_or_else(singular);
        }
        let scale = match t.scale {
            None => Vec3::ONE,
            Some(Value::Array(a)) => {
                self.typed::<V3>(Value::Array(a), &format!("{path}.scale"))?
                    .0
            }
            Some(v) => Vec3::splat(self.typed::<Finite>(v, &format!("{path}.scale"))?.0),
        };
        if scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0 {
            return Err(self.err(&format!("{path}.scale"), "expected non-zero scale factors"));
        }
        let rotation = match t.rotate {
            None => None,
            Some([x, y, z, deg]) => {
                let axis = Vec3::new(x.0, y.0, z.0);
                if axis.length_squared() == 0.0 {
                    return Err(self.err(
                        &format!("{path}.rotate"),
                        "expected a non-zero rotation axis",
                    ));
                }
                Some((axis, deg.0))
            }
        };
        Transform::from_srt(scale, rotation, t.translate.map_or(Vec3::ZERO, |v| v.0))
            .ok_or_else(singular)
    }

    fn light(&self, value: &Value, path: &str) -> Result<LightDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Point {
            position: V3,
            intensity: Color,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Spot {
            position: V3,
            look_at: V3,
            intensity: Color,
            #[serde(default)]
            cone_angle: Option<Positive>,
            #[serde(default)]
            falloff_start: Option<Finite>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Directional {
            direction: V3,
            irradiance: Color,
        }
        let (kind, map) = self.tagged(value, path, &["point", "spot", "directional"])?;
        let map = Value::Object(map);
        Ok(match kind.as_str() {
            "point" => {
                let p: Point = self.typed(map, path)?;
                LightDesc::Point {
                    position: p.position.0,
                    intensity: p.intensity.0,
                }
            }
            "spot" => {
                let s: Spot = self.typed(map, path)?;
                let cone = s.cone_angle.map_or(30.0, |c| c.0);
                if cone > 180.0 {
                    return Err(self.err(
                        &format!("{path}.cone_angle"),
                        format!("expected at most 180 degrees, found {cone}"),
                    ));
                }
                let start = s.falloff_start.map_or(cone, |f| f.0);
                if !(0.0..=cone).contains(&start) {
                    return Err(self.err(
                        &format!("{path}.falloff_start"),
                        format!(
                            "expected between 0 and cone_angle ({cone}) degrees, found {start}"
                        ),
                    ));
                }
                if (s.look_at.0 - s.position.0).length_squared() == 0.0 {
                    return Err(self.err(&format!("{path}.look_at"), "must differ from position"));
                }
                LightDesc::Spot {
                    position: s.position.0,
                    look_at: s.look_at.0,
                    intensity: s.intensity.0,
                    cone_angle: cone,
                    falloff_start: start,
                }
            }
            _ => {
                let d: Directional = self.typed(map, path)?;
                if d.direction.0.length_squared() == 0.0 {
                    return Err(self.err(
                        &format!("{path}.direction"),
                        "expected a non-zero direction",
                    ));
                }
                LightDesc::Directional {
                    direction: d.direction.0,
                    irradiance: d.irradiance.0,
                }
            }
        })
    }
}

/// The largest icosphere level accepted: 20 × 4^10 ≈ 21 M triangles.
pub const MAX_SUBDIVISIONS: u32 = 10;

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}
