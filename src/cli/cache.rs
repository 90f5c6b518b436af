//! `tracer cache`: list, clear and prune the scene cache; the cache flags
//! of `render` and `info`.

use clap::{Args, Subcommand};
use std::path::PathBuf;
use tracer::error::human_bytes;
use tracer::scene::cache::Cache;
use tracer::{Error, Result};

#[derive(Subcommand, Debug)]
pub enum CacheCommand {
    /// One line per entry: key, scene, size, time since last use.
    List,
    /// Remove every entry.
    Clear,
    /// Remove least recently used entries until the rest fit in a size.
    Prune {
        /// e.g. 2G, 500M (binary multiples).
        #[arg(long, value_parser = tracer::scene::cache::parse_size)]
        max_size: u64,
    },
}

/// Where prepared geometry is cached between runs.
#[derive(Args, Debug, Default, Clone)]
pub struct CacheArgs {
    /// The scene cache folder (default: $TRACER_CACHE_DIR, else the
    /// platform's cache folder, ~/.cache/tracer on Linux).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Neither read nor write the scene cache.
    #[arg(long, conflicts_with = "cache_dir")]
    pub no_cache: bool,
}

impl CacheArgs {
    pub fn cache(&self) -> Option<Cache> {
        if self.no_cache {
            return None;
        }
        self.cache_dir
            .clone()
            .or_else(Cache::default_dir)
            .map(Cache::new)
    }
}

pub fn run_cache(action: &CacheCommand, dir: Option<PathBuf>) -> Result<()> {
    let dir = dir.or_else(Cache::default_dir).ok_or(Error::NoCacheDir)?;
    let cache = Cache::new(&dir);
    let io = |e| Error::io(&dir, e);
    match action {
        CacheCommand::List => {
            let entries = cache.list().map_err(io)?;
            outln!("{:<16}  {:>10}  {:>10}  scene", "key", "size", "last used");
            for e in &entries {
                let age = e.last_used.elapsed().unwrap_or_default();
                let scene = match &e.scene {
                    Ok(s) => s.clone(),
                    Err(why) => format!("(invalid: {why})"),
                };
                outln!(
                    "{:<16}  {:>10}  {:>10}  {scene}",
                    &e.key[..e.key.len().min(16)],
                    human_bytes(e.bytes),
                    human_age(age)
                );
            }
            let total: u64 = entries.iter().map(|e| e.bytes).sum();
            outln!(
                "{} entries, {} in {}",
                entries.len(),
                human_bytes(total),
                dir.display()
            );
        }
        CacheCommand::Clear => {
            let (n, bytes) = cache.clear().map_err(io)?;
            outln!("removed {n} files ({})", human_bytes(bytes));
        }
        CacheCommand::Prune { max_size } => {
            let (n, bytes) = cache.prune(*max_size).map_err(io)?;
            outln!(
                "removed {n} entries ({}), least recently used first",
                human_bytes(bytes)
            );
        }
    }
    Ok(())
}

fn human_age(d: std::time::Duration) -> String {
    let s = d.as_secs();
    match s {
        0..60 => format!("{s} s ago"),
        60..3600 => format!("{} min ago", s / 60),
        3600..86400 => format!("{} h ago", s / 3600),
        _ => format!("{} d ago", s / 86400),
    }
}
