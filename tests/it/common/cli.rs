//! The `tracer` binary, as the tests run it.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

/// A command for the `tracer` binary, run from the repository's root (so
/// `scenes/cornell-box.json` names a bundled scene), with the scene cache
/// in a folder of the calling test's own ([`cache_dir`]): what the tests
/// render never reaches the user's cache, and no test sees another's
/// entries. `--cache-dir` still overrides it.
pub fn tracer() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_tracer"));
    c.current_dir(super::repo())
        .env("TRACER_CACHE_DIR", cache_dir())
        .env_remove("TRACER_CACHE_MAX_SIZE");
    c
}

/// Runs `tracer` with `args`, asserts that it succeeded, and returns its output.
pub fn run(args: &[&str]) -> Output {
    let out = tracer().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "tracer {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Standard output and standard error, in that order, as text.
pub fn output_text(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
}

/// The scene cache folder of the calling test:
/// `target/tmp/scene-cache/<test name>`, emptied the first time the test
/// asks for it in this process, so each run starts from an empty cache.
/// (The test harness names each test's thread after the test; a test run
/// on an unnamed thread gets `main`.)
pub fn cache_dir() -> PathBuf {
    static EMPTIED: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    let current = std::thread::current();
    let test = current.name().unwrap_or("main").replace(['/', '\\'], "_");
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scene-cache")
        .join(&test);
    let mut emptied = EMPTIED.lock().unwrap_or_else(|e| e.into_inner());
    if emptied.get_or_insert_with(HashSet::new).insert(test) {
        match std::fs::remove_dir_all(&dir) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => panic!("cannot empty {}: {e}", dir.display()),
        }
    }
    dir
}

#[cfg(test)]
mod tests {
    use crate::common::{cache_dir, tracer};
    use std::ffi::OsStr;

    #[test]
    fn each_test_has_a_scene_cache_of_its_own() {
        let command = tracer();
        let env = |name: &str| {
            command
                .get_envs()
                .find(|(k, _)| *k == OsStr::new(name))
                .map(|(_, v)| v.map(|v| v.to_owned()))
        };
        let dir = cache_dir();
        assert_eq!(env("TRACER_CACHE_DIR"), Some(Some(dir.clone().into())));
        assert_eq!(env("TRACER_CACHE_MAX_SIZE"), Some(None), "removed");
        assert!(
            dir.ends_with("common::cli::tests::each_test_has_a_scene_cache_of_its_own"),
            "{}",
            dir.display()
        );
        let other = std::thread::Builder::new()
            .name("another test".into())
            .spawn(cache_dir)
            .unwrap()
            .join()
            .unwrap();
        assert_ne!(other, dir);
        assert_eq!(other.parent(), dir.parent());
    }
}
