//! What the renderer reads: scene files (the JSON format in `json.rs`, the
//! older T-racer `.trs` files in `trs.rs`) into a [`SceneDesc`], and OBJ/MTL
//! meshes (`obj.rs`). Textures and images are read by [`crate::film::read`].
//!
//! A description names files and values; nothing is built here. Every value
//! is checked as it is read, so an error names the file and the key.

pub mod desc;
pub mod json;
mod json_lights;
mod json_materials;
mod json_objects;
pub mod obj;
mod sections;
pub mod trs;

pub use desc::SceneDesc;

use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// Reads a scene file (`.json`, or `.trs` for T-racer scenes) into a description.
pub fn read_scene(path: &Path) -> Result<SceneDesc> {
    let text = crate::files::read_regular_to_string(path).map_err(|e| Error::io(path, e))?;
    // Editors on some systems start UTF-8 files with a byte-order mark.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let is_trs = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("trs"));
    if is_trs {
        trs::parse(text, path)
    } else {
        json::parse(text, path)
    }
}

/// Resolves a path from the scene file against the scene file's folder.
pub fn resolve(scene_file: &Path, relative: &str) -> PathBuf {
    scene_file.parent().unwrap_or(Path::new(".")).join(relative)
}
