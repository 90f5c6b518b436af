//! Stamps the build with a hash of its own source, so the scene cache can
//! tell entries made by a different build of the renderer (whose BVH
//! builder may differ) from its own, whatever the version number says.

use std::hash::{Hash, Hasher};
use std::path::Path;

fn hash_tree(dir: &Path, h: &mut impl Hasher) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect())
        .unwrap_or_default();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            hash_tree(&path, h);
        } else if let Ok(bytes) = std::fs::read(&path) {
            path.to_string_lossy().hash(h);
            bytes.hash(h);
        }
    }
}

fn main() {
    // `new` uses fixed keys: the same source gives the same stamp.
    let mut h = std::hash::DefaultHasher::new();
    hash_tree(Path::new("src"), &mut h);
    if let Ok(lock) = std::fs::read("Cargo.lock") {
        lock.hash(&mut h);
    }
    std::env::var("TARGET").unwrap_or_default().hash(&mut h);
    std::env::var("CARGO_CFG_TARGET_FEATURE")
        .unwrap_or_default()
        .hash(&mut h);
    println!("cargo:rustc-env=TRACER_SOURCE_HASH={:016x}", h.finish());
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.lock");
}
