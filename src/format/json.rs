//! Reads the JSON scene format (`docs/scene-format.md`, version 1) into a
//! [`SceneDesc`].
//!
//! Plain sections deserialise straight into serde types with unknown keys
//! refused. Tagged sections (materials, objects, lights) are read as JSON
//! values first, then dispatched on `type` into per-type structs, so each
//! type refuses the keys it does not know. Every error carries the key path.

use super::desc::*;
pub use super::json_objects::MAX_SUBDIVISIONS;
use super::resolve;
use super::sections::{self, CameraDesc, FilmDesc, RenderDesc};
use crate::settings::{Invalid, Setting};
use crate::{Error, Result};
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
    if !(1..=2).contains(&scene.format) {
        return Err(Error::scene(
            file,
            "format",
            format!(
                "unsupported format version {}; this renderer reads versions 1 and 2",
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
        Setting::VcmRadius => "render.vcm_radius",
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

/// Where values come from, for errors: the file being read.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a Path,
}

impl Ctx<'_> {
    pub(super) fn err(&self, path: &str, message: impl Into<String>) -> Error {
        Error::scene(self.file, path, message)
    }

    /// Deserialises `value` (the section at `path`) into `T`, reporting the full path on error.
    pub(super) fn typed<T: DeserializeOwned>(&self, value: Value, path: &str) -> Result<T> {
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
    pub(super) fn tagged(
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
}

pub(super) fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}
