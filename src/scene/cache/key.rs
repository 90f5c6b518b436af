//! The cache key: a BLAKE3 hash of everything that determines a scene's
//! prepared geometry, so an entry can only be found by a scene that would
//! build exactly the same triangles and BVH.
//!
//! Hashed, in order: the cache format version, the crate version and the
//! running executable's size and modification time (a rebuilt renderer may
//! build a different BVH from the same scene), the BVH build parameters,
//! the scene's materials and objects (shapes, transforms, material names,
//! emission), and the bytes of every mesh file and of the MTL files those
//! meshes name. Files are memory-mapped and hashed in place: hashing reads
//! each byte once, at several GB/s, where parsing the same OBJ runs at tens
//! of MB/s.

use super::entry::FORMAT_VERSION;
use crate::bvh::BuildOptions;
use crate::scene::desc::{SceneDesc, ShapeDesc};
use std::path::Path;

pub type Key = [u8; 32];

/// The key of `desc`'s geometry; `None` when a mesh file cannot be read (the
/// load that follows reports that error at its key).
pub fn scene_key(desc: &SceneDesc, build: &BuildOptions) -> Option<Key> {
    let mut h = blake3::Hasher::new();
    h.update(b"tracer scene cache\0");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(env!("CARGO_PKG_VERSION").as_bytes());
    h.update(&executable_stamp());
    hash_geometry_inputs(&mut h, desc, build)?;
    Some(*h.finalize().as_bytes())
}

/// A hash of what a scene renders: its geometry inputs as in the cache key,
/// its camera and its lights — but not the executable, so renders of the
/// same scene by separately built copies of `tracer` (on several machines)
/// can be merged. Textures are named by path, not hashed.
pub fn scene_hash(desc: &SceneDesc) -> Option<Key> {
    let mut h = blake3::Hasher::new();
    h.update(b"tracer scene hash\0");
    hash_geometry_inputs(&mut h, desc, &BuildOptions::default())?;
    h.update(format!("{:?}|{:?}", desc.camera, desc.lights).as_bytes());
    Some(*h.finalize().as_bytes())
}

fn hash_geometry_inputs(
    h: &mut blake3::Hasher,
    desc: &SceneDesc,
    build: &BuildOptions,
) -> Option<()> {
    // Debug output is exact for every field involved (floats print as the
    // shortest string that reads back to the same value) and names every
    // variant, so equal text means equal descriptions.
    h.update(format!("{build:?}").as_bytes());
    h.update(format!("{:?}", desc.materials).as_bytes());
    for object in &desc.objects {
        h.update(format!("{object:?}\0").as_bytes());
        if let ShapeDesc::Mesh { file, .. } = &object.shape {
            hash_mesh_file(h, file).ok()?;
        }
    }
    Some(())
}

/// The executable's size and modification time: a stand-in for its
/// contents that costs one `stat`.
fn executable_stamp() -> Vec<u8> {
    let meta = std::env::current_exe().and_then(std::fs::metadata);
    match meta {
        Ok(m) => {
            let modified = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                .map_or(0, |d| d.as_nanos());
            [m.len().to_le_bytes().as_slice(), &modified.to_le_bytes()].concat()
        }
        Err(_) => b"unknown executable".to_vec(),
    }
}

/// Hashes an OBJ file and the MTL files its `mtllib` lines name.
fn hash_mesh_file(h: &mut blake3::Hasher, path: &Path) -> std::io::Result<()> {
    let bytes = map(path)?;
    let bytes: &[u8] = bytes.as_deref().unwrap_or(&[]);
    h.update(&(bytes.len() as u64).to_le_bytes());
    hash_bytes(h, bytes);
    let folder = path.parent().unwrap_or(Path::new("."));
    for name in mtllib_names(bytes) {
        h.update(name.as_bytes());
        match map(&folder.join(&name)) {
            Ok(mtl) => {
                let mtl: &[u8] = mtl.as_deref().unwrap_or(&[]);
                h.update(&(mtl.len() as u64).to_le_bytes());
                h.update(mtl);
            }
            // A missing MTL file is part of the input too (tobj then
            // warns and the default material is used).
            Err(_) => {
                h.update(b"\0missing");
            }
        }
    }
    Ok(())
}

/// The file's bytes, mapped; `None` for an empty file (which cannot be mapped).
fn map(path: &Path) -> std::io::Result<Option<memmap2::Mmap>> {
    let file = std::fs::File::open(path)?;
    if file.metadata()?.len() == 0 {
        return Ok(None);
    }
    // SAFETY: the map is read once, here; a file changed while it is hashed
    // gives a key that matches neither version, which only costs a miss.
    unsafe { memmap2::Mmap::map(&file) }.map(Some)
}

fn hash_bytes(h: &mut blake3::Hasher, bytes: &[u8]) {
    if bytes.len() >= 1 << 20 {
        h.update_rayon(bytes);
    } else {
        h.update(bytes);
    }
}

/// The names on an OBJ's `mtllib` lines: the whole rest of the line (as tobj
/// reads it) and, when it has several words, each word.
pub fn mtllib_names(obj: &[u8]) -> Vec<String> {
    let mut names = Vec::new();
    for start in memchr::memmem::find_iter(obj, b"mtllib") {
        let at_line_start = start == 0 || matches!(obj[start - 1], b'\n' | b'\r');
        if !at_line_start {
            continue;
        }
        let rest = &obj[start + 6..];
        let end = memchr::memchr2(b'\n', b'\r', rest).unwrap_or(rest.len());
        let line = String::from_utf8_lossy(&rest[..end]);
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        names.push(line.to_string());
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() > 1 {
            names.extend(words.iter().map(|w| w.to_string()));
        }
    }
    names
}
