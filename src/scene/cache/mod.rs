//! The scene cache: a scene's prepared geometry (world-space triangles,
//! shading data, emitters, MTL materials) and its 8-wide BVH, kept on disk
//! so that rendering the same scene again skips parsing meshes and building
//! the BVH.
//!
//! Entries live in one folder, one file per key (`<key>.tcache`, see
//! [`key`]); the file format is in [`entry`]. Nothing read is trusted: an
//! entry that fails any check is reported in one warning, removed and
//! rebuilt. Entries are written to a temporary file and renamed into place,
//! so a reader sees a whole entry or none, and two renders storing the same
//! entry at once both leave a whole one. Each use refreshes an entry's
//! modification time, which `prune` reads as "last used".

mod contents;
pub mod entry;
pub mod key;
mod shared_fs;

pub use key::{scene_hash, scene_key, Key};

use super::Geometry;
use contents::{read_entry, read_scene_name, Meta};
use entry::Invalid;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

const EXTENSION: &str = "tcache";
/// Scenes smaller than this load faster than an entry would: not stored.
pub const DEFAULT_MIN_TRIANGLES: usize = 10_000;
/// The cache's size limit unless `$TRACER_CACHE_MAX_SIZE` says otherwise.
pub const DEFAULT_MAX_SIZE: u64 = 20 << 30;

/// What the cache did for one load.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum CacheUse {
    /// No cache was asked for.
    #[default]
    Off,
    /// The geometry and BVH came from the cache.
    Hit,
    /// Built, and stored for next time.
    Stored,
    /// Built, not stored (too small, or the folder cannot be written).
    NotStored,
}

/// The scene cache in one folder (created when first stored to).
pub struct Cache {
    dir: PathBuf,
    min_triangles: usize,
}

/// One entry, as `tracer cache list` shows it.
#[derive(Clone, Debug)]
pub struct EntryInfo {
    /// The entry's file.
    pub path: PathBuf,
    /// The key, in hex: the file name without its extension.
    pub key: String,
    /// The scene file that made it, or why the entry cannot be read.
    pub scene: std::result::Result<String, String>,
    /// Size of the file, in bytes.
    pub bytes: u64,
    /// The file's modification time, which every use refreshes.
    pub last_used: SystemTime,
}

impl Cache {
    /// The cache in `dir`, storing scenes of at least [`DEFAULT_MIN_TRIANGLES`] triangles.
    pub fn new(dir: impl Into<PathBuf>) -> Cache {
        Cache {
            dir: dir.into(),
            min_triangles: DEFAULT_MIN_TRIANGLES,
        }
    }

    /// Stores scenes of at least `n` triangles (default [`DEFAULT_MIN_TRIANGLES`]).
    pub fn with_min_triangles(mut self, n: usize) -> Cache {
        self.min_triangles = n;
        self
    }

    /// `$TRACER_CACHE_DIR`, else the platform's cache folder
    /// (`~/.cache/tracer` on Linux, `~/Library/Caches/tracer` on macOS).
    pub fn default_dir() -> Option<PathBuf> {
        if let Some(dir) = std::env::var_os("TRACER_CACHE_DIR").filter(|d| !d.is_empty()) {
            return Some(dir.into());
        }
        directories::ProjectDirs::from("", "", "tracer").map(|d| d.cache_dir().to_path_buf())
    }

    /// Where the entry for `key` lives (whether or not it exists).
    pub fn entry_path(&self, key: &Key) -> PathBuf {
        self.dir.join(format!("{}.{EXTENSION}", hex(key)))
    }

    /// The geometry stored under `key`, if a sound entry is there. A bad
    /// entry is removed and named in one line pushed to `warnings`.
    /// `scene_materials`: how many materials the scene defines before the
    /// entry's MTL materials, so material indices can be checked.
    pub fn lookup(
        &self,
        key: &Key,
        scene_materials: usize,
        warnings: &mut Vec<String>,
    ) -> Option<Geometry> {
        let path = self.entry_path(key);
        // Not there, or the folder is unusable: a miss (storing will say
        // so if the folder cannot be written).
        let meta = std::fs::symlink_metadata(&path).ok()?;
        let result = if meta.is_file() {
            read_entry(&path, key, scene_materials)
        } else {
            Err(Invalid::Malformed("not a regular file".into()))
        };
        match result {
            Ok(g) => {
                // Refresh "last used" for prune; failing to is harmless.
                if let Ok(f) = File::options().append(true).open(&path) {
                    let _ = f.set_modified(SystemTime::now());
                }
                Some(g)
            }
            // The entry may be sound; this process just cannot read it now
            // (out of file handles, say). Leave it be.
            Err(Invalid::Io(e)) => {
                warnings.push(format!(
                    "cache entry {} cannot be read ({e}); rebuilding without it",
                    path.display()
                ));
                None
            }
            Err(reason) => {
                // Another render may have just renamed a sound entry into
                // place: only remove the very file that was found bad.
                let still_there =
                    std::fs::symlink_metadata(&path).is_ok_and(|now| same_file(&now, &meta));
                let removed = if !still_there {
                    Ok(())
                } else if meta.is_dir() {
                    std::fs::remove_dir_all(&path)
                } else {
                    std::fs::remove_file(&path)
                };
                let action = match removed {
                    Ok(()) => "removed it, rebuilding",
                    Err(_) => "could not remove it, rebuilding",
                };
                warnings.push(format!(
                    "cache entry {} is invalid ({reason}); {action}",
                    path.display()
                ));
                None
            }
        }
    }

    /// Stores `geometry` under `key`, atomically. Problems become a warning
    /// and the render goes on without the cache.
    pub fn store(
        &self,
        key: &Key,
        geometry: &Geometry,
        scene_file: &Path,
        warnings: &mut Vec<String>,
    ) -> CacheUse {
        if geometry.triangles.len() < self.min_triangles {
            return CacheUse::NotStored;
        }
        let meta = Meta::of(geometry, scene_file);
        if !meta.is_finite() {
            // JSON has no infinities: such an entry could never be read back.
            return CacheUse::NotStored;
        }
        match self.write_entry(key, geometry, &meta) {
            Ok(()) => {
                if let Some(max) = max_size_from_env() {
                    let _ = self.prune(max);
                }
                CacheUse::Stored
            }
            Err(e) => {
                warnings.push(format!(
                    "cannot write to the scene cache in {} ({e}); continuing without it",
                    self.dir.display()
                ));
                CacheUse::NotStored
            }
        }
    }

    fn write_entry(&self, key: &Key, g: &Geometry, meta: &Meta) -> std::io::Result<()> {
        std::fs::create_dir_all(&self.dir)?;
        let meta = serde_json::to_vec(meta).map_err(std::io::Error::other)?;
        let emitters = contents::emitter_records(g);
        let sections = contents::sections(g, &meta, &emitters);
        // A fresh, exclusively created name (random, so writers on other
        // machines sharing the folder cannot collide either); removed if
        // anything below fails.
        let temp = tempfile::Builder::new()
            .prefix(&format!(".{}.", hex(key)))
            .suffix(".tmp")
            .tempfile_in(&self.dir)?;
        let mut out = BufWriter::with_capacity(1 << 20, temp);
        entry::write(&mut out, key, &sections)?;
        let temp = out.into_inner().map_err(|e| e.into_error())?;
        temp.as_file().sync_all()?;
        temp.persist(self.entry_path(key)).map_err(|e| e.error)?;
        Ok(())
    }

    /// Every entry, least recently used first; temporary files are skipped.
    pub fn list(&self) -> std::io::Result<Vec<EntryInfo>> {
        let mut entries = self.scan()?;
        for e in &mut entries {
            e.scene = read_scene_name(&e.path).map_err(|e| e.to_string());
        }
        Ok(entries)
    }

    /// The entries' names, sizes and times alone (`scene` left unread),
    /// least recently used first: all that pruning needs.
    fn scan(&self) -> std::io::Result<Vec<EntryInfo>> {
        let mut entries = Vec::new();
        for item in read_dir_or_empty(&self.dir)? {
            let item = item?;
            let path = item.path();
            if path.extension().and_then(|e| e.to_str()) != Some(EXTENSION) {
                continue;
            }
            // Another process may remove entries while we look.
            let meta = match item.metadata() {
                Ok(m) => m,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(e),
            };
            entries.push(EntryInfo {
                key: path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                scene: Err("not read".into()),
                bytes: meta.len(),
                last_used: meta.modified().unwrap_or(SystemTime::UNIX_EPOCH),
                path,
            });
        }
        entries.sort_by_key(|e| e.last_used);
        Ok(entries)
    }

    /// Removes every entry and any temporary file left by an interrupted
    /// write; returns how many files and bytes went.
    pub fn clear(&self) -> std::io::Result<(usize, u64)> {
        let mut removed = (0, 0);
        for item in read_dir_or_empty(&self.dir)? {
            let path = item?.path();
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
            let ours = name.ends_with(&format!(".{EXTENSION}")) || is_stale_temp(&path);
            if ours {
                let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
                if std::fs::remove_file(&path).is_ok() {
                    removed.0 += 1;
                    removed.1 += bytes;
                }
            }
        }
        Ok(removed)
    }

    /// Removes least recently used entries until the rest fit in `max_bytes`;
    /// returns how many files and bytes went.
    pub fn prune(&self, max_bytes: u64) -> std::io::Result<(usize, u64)> {
        let entries = self.scan()?;
        let mut total: u64 = entries.iter().map(|e| e.bytes).sum();
        let mut removed = (0, 0);
        for e in entries {
            if total <= max_bytes {
                break;
            }
            let gone = if e.path.is_dir() {
                std::fs::remove_dir_all(&e.path)
            } else {
                std::fs::remove_file(&e.path)
            };
            if gone.is_ok() {
                total -= e.bytes;
                removed.0 += 1;
                removed.1 += e.bytes;
            }
        }
        Ok(removed)
    }
}

/// `$TRACER_CACHE_MAX_SIZE` (e.g. `20G`), else 20 GiB: after each store the
/// least recently used entries beyond it are removed. `0` or `none` turns
/// the limit off.
fn max_size_from_env() -> Option<u64> {
    match std::env::var("TRACER_CACHE_MAX_SIZE") {
        Ok(v) if v == "0" || v.eq_ignore_ascii_case("none") => None,
        // A value that does not parse keeps the default rather than no limit.
        Ok(v) => Some(parse_size(&v).unwrap_or(DEFAULT_MAX_SIZE)),
        Err(_) => Some(DEFAULT_MAX_SIZE),
    }
}

/// Whether two metadata describe the same file (not merely the same name).
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        a.dev() == b.dev() && a.ino() == b.ino()
    }
    #[cfg(not(unix))]
    {
        a.len() == b.len() && a.modified().ok() == b.modified().ok()
    }
}

/// The folder's entries; none when the folder does not exist yet.
fn read_dir_or_empty(dir: &Path) -> std::io::Result<Vec<std::io::Result<std::fs::DirEntry>>> {
    match std::fs::read_dir(dir) {
        Ok(d) => Ok(d.collect()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(e),
    }
}

/// A temporary file more than an hour old: its writer is gone.
fn is_stale_temp(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    name.starts_with('.')
        && name.ends_with(".tmp")
        && std::fs::metadata(path)
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > Duration::from_secs(3600))
}

/// `key` as 64 lowercase hex digits.
pub fn hex(key: &Key) -> String {
    key.iter().map(|b| format!("{b:02x}")).collect()
}

/// Parses a size such as `2G`, `500M`, `1.5GiB`, `64k` or `1000000`
/// (binary multiples: `1G` is 2^30 bytes).
pub fn parse_size(s: &str) -> std::result::Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let number: f64 = number
        .parse()
        .map_err(|_| format!("expected a size such as 2G or 500M, found {s:?}"))?;
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => return Err(format!("unknown size unit in {s:?}: use K, M, G or T")),
    };
    Ok((number * (1u64 << shift) as f64) as u64)
}
