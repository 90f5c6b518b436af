//! The cache key: a BLAKE3 hash of everything that determines a scene's
//! prepared geometry, so an entry can only be found by a scene that would
//! build exactly the same triangles and BVH.
//!
//! Hashed, in order: the cache format version, the crate version and a
//! hash of the renderer's own source, lock file and target features taken
//! at build time (a changed renderer may build a different BVH from the
//! same scene), the BVH build parameters, the scene's materials and objects
//! (shapes, transforms, material names, emission), and the bytes of every
//! mesh file and of the MTL files those meshes name. Files are read in
//! large chunks and hashed as they stream by, at several GB/s, where
//! parsing the same OBJ runs at tens of MB/s.

use super::entry::FORMAT_VERSION;
use crate::bvh::BuildOptions;
use crate::format::desc::{SceneDesc, ShapeDesc};
use std::path::Path;

/// A cache key: the 32-byte BLAKE3 hash of a scene's geometry inputs.
pub type Key = [u8; 32];

/// The key of `desc`'s geometry; `None` when a mesh file cannot be read (the
/// load that follows reports that error at its key).
pub fn scene_key(desc: &SceneDesc, build: &BuildOptions) -> Option<Key> {
    let mut h = blake3::Hasher::new();
    h.update(b"tracer scene cache\0");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(env!("CARGO_PKG_VERSION").as_bytes());
    h.update(env!("TRACER_SOURCE_HASH").as_bytes());
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
    h.update(format!("{:?}|{:?}", desc.settings.camera, desc.lights).as_bytes());
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

/// Hashes an OBJ file and the MTL files its `mtllib` lines name.
fn hash_mesh_file(h: &mut blake3::Hasher, path: &Path) -> std::io::Result<()> {
    let mut names = Vec::new();
    let length = hash_file(h, path, Some(&mut names))?;
    h.update(&length.to_le_bytes());
    let folder = path.parent().unwrap_or(Path::new("."));
    for name in names {
        h.update(name.as_bytes());
        let mut mtl = blake3::Hasher::new();
        match hash_file(&mut mtl, &folder.join(&name), None) {
            Ok(_) => h.update(mtl.finalize().as_bytes()),
            // A missing MTL file is part of the input too (tobj then
            // warns and the default material is used).
            Err(_) => h.update(b"\0missing"),
        };
    }
    Ok(())
}

/// Streams `path` into `h`, collecting `mtllib` names when asked; returns
/// the byte count. Read, not mapped: a file truncated by another program
/// while it is hashed gives a wrong key (a miss), not a crash.
fn hash_file(
    h: &mut blake3::Hasher,
    path: &Path,
    mut names: Option<&mut Vec<String>>,
) -> std::io::Result<u64> {
    use std::io::Read;
    let mut file = crate::files::open_regular(path)?;
    let mut buffer = vec![0u8; 1 << 20];
    // The last, unfinished line of the previous chunk.
    let mut carry: Vec<u8> = Vec::new();
    let mut length = 0u64;
    loop {
        let n = match file.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        let chunk = &buffer[..n];
        h.update(chunk);
        length += n as u64;
        if let Some(names) = names.as_deref_mut() {
            match (memchr::memchr(b'\n', chunk), memchr::memrchr(b'\n', chunk)) {
                (Some(first), Some(last)) => {
                    carry.extend_from_slice(&chunk[..=first]);
                    names.extend(mtllib_names(&carry));
                    names.extend(mtllib_names(&chunk[first + 1..=last]));
                    carry.clear();
                    carry.extend_from_slice(&chunk[last + 1..]);
                }
                _ => carry.extend_from_slice(chunk),
            }
        }
    }
    if let Some(names) = names {
        names.extend(mtllib_names(&carry));
    }
    Ok(length)
}

/// The names on the `mtllib` lines of whole lines of an OBJ file: the rest
/// of the line, trimmed (as tobj reads it), and, when it has several words,
/// each word. Like tobj, leading blanks before `mtllib` are allowed.
pub fn mtllib_names(lines: &[u8]) -> Vec<String> {
    let mut names = Vec::new();
    for start in memchr::memmem::find_iter(lines, b"mtllib") {
        let line_start = memchr::memrchr2(b'\n', b'\r', &lines[..start]).map_or(0, |i| i + 1);
        if !lines[line_start..start]
            .iter()
            .all(|b| matches!(b, b' ' | b'\t'))
        {
            continue;
        }
        let rest = &lines[start + 6..];
        if !rest.first().is_some_and(|b| matches!(b, b' ' | b'\t')) {
            continue;
        }
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
