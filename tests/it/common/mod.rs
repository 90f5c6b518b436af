//! Helpers shared by the integration tests: a seedable generator, scene
//! files, loading, block statistics for comparing estimators, the `tracer`
//! binary ([`tracer()`]) and a watched child of it with a time limit
//! ([`Watched`]), the chi-square test ([`chi_square`]) and the locks
//! that keep timing tests apart from heavy ones ([`serial()`], [`heavy()`]).
#![allow(dead_code)]

pub mod chi_square;
mod child;
mod cli;
mod serial;

pub use child::{run_limited, Finished, Watched};
pub use cli::{cache_dir, output_text, run, tracer};
pub use serial::{heavy, serial};

use std::path::{Path, PathBuf};
use tracer::scene::Scene;
use tracer::settings::Settings;

/// A small, seedable generator (PCG32) so tests are reproducible without a
/// dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        let mut r = Rng(seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407));
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    pub fn vec3(&mut self, lo: f32, hi: f32) -> glam::Vec3 {
        glam::Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    pub fn unit_vector(&mut self) -> glam::Vec3 {
        loop {
            let v = self.vec3(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

/// Writes `text` to `path`, creating its folder, and returns the path.
pub fn write(path: &Path, text: impl AsRef<[u8]>) -> PathBuf {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

/// Writes `json` as `name` in `dir` and returns its path.
/// Metadata of a finished `width` × `height` render of `spp` samples per
/// pixel in one pass: what a writer needs to put beside a test image.
pub fn metadata(width: u32, height: u32, spp: u32) -> tracer::film::metadata::Metadata {
    tracer::film::metadata::Metadata {
        program: "tracer test".into(),
        scene_hash: "0".repeat(64),
        integrator: "pt".into(),
        vcm_radius: None,
        seed: 1,
        max_depth: 4,
        width,
        height,
        crop: [0, 0, width, height],
        spp,
        max_spp: spp,
        samples: vec![(0, spp)],
        render_seconds: 0.5,
        passes: 1,
        stopped_by: "spp".into(),
        noise: None,
        pixels_hash: None,
    }
}

pub fn write_scene(dir: &Path, name: &str, json: &str) -> PathBuf {
    write(&dir.join(name), json)
}

/// Writes `value` as pretty-printed JSON to `dir/name` and returns its path.
pub fn write_json(dir: &Path, name: &str, value: &serde_json::Value) -> PathBuf {
    write(
        &dir.join(name),
        serde_json::to_string_pretty(value).unwrap(),
    )
}

/// The repository's root folder.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Reads and builds the scene at `path` (relative paths are taken from the
/// repository's root, so `load_scene("scenes/cornell-box.json")` works),
/// without the scene cache, and returns it with the settings its file asks
/// for. Panics with the file's name when it does not load.
pub fn load_scene(path: impl AsRef<Path>) -> (Scene, Settings) {
    let path = repo().join(path);
    tracer::scene::load(&path).unwrap_or_else(|e| panic!("{} did not load: {e}", path.display()))
}

/// Loads `path`, expecting an error, and returns its message.
pub fn load_error(path: &Path) -> String {
    match tracer::scene::load(path) {
        Ok(_) => panic!("{} loaded, but should have been refused", path.display()),
        Err(e) => e.to_string(),
    }
}

/// Asserts that `message` names the file and contains every one of `parts`.
pub fn assert_names(message: &str, file: &Path, parts: &[&str]) {
    let name = file.file_name().unwrap().to_str().unwrap();
    assert!(
        message.contains(name),
        "message does not name the file {name}: {message}"
    );
    for part in parts {
        assert!(
            message.contains(part),
            "message does not contain {part:?}: {message}"
        );
    }
}

/// Loads `path`, expecting an error whose message names the file and
/// contains every one of `parts`; returns the message.
pub fn refused(path: &Path, parts: &[&str]) -> String {
    let message = load_error(path);
    assert_names(&message, path, parts);
    message
}

/// Block means of several independent renders (seeds 0..`seeds`, the other
/// settings as given) and their standard errors: a noise estimate for
/// comparing unbiased estimators with a tolerance derived from their
/// variance, not a hand-picked constant.
pub struct BlockStats {
    pub blocks_x: u32,
    pub blocks_y: u32,
    /// Per block and channel: mean over seeds, and standard error of that mean.
    pub mean: Vec<glam::DVec3>,
    pub stderr: Vec<glam::DVec3>,
    /// The whole image's mean and its standard error: far tighter than any
    /// block's, so it catches small biases spread over the image.
    pub image_mean: glam::DVec3,
    pub image_stderr: glam::DVec3,
    pub discarded: u64,
}

pub fn block_stats(scene: &Scene, settings: &Settings, seeds: u64, block: u32) -> BlockStats {
    use glam::DVec3;
    let (w, h) = (settings.film.width, settings.film.height);
    let (bx, by) = (w / block, h / block);
    let n = (bx * by) as usize;
    let mut sum = vec![DVec3::ZERO; n];
    let mut sum2 = vec![DVec3::ZERO; n];
    let mut discarded = 0;
    let (mut image_sum, mut image_sum2) = (DVec3::ZERO, DVec3::ZERO);
    let mut settings = settings.clone();
    for seed in 0..seeds {
        settings.seed = seed;
        let (image, stats) = tracer::render::render(scene, &settings, &Default::default()).unwrap();
        discarded += stats.discarded;
        let mut blocks = vec![DVec3::ZERO; n];
        for y in 0..by * block {
            for x in 0..bx * block {
                blocks[((y / block) * bx + x / block) as usize] += image.get(x, y).as_dvec3();
            }
        }
        for (k, b) in blocks.iter().enumerate() {
            let m = *b / (block * block) as f64;
            sum[k] += m;
            sum2[k] += m * m;
        }
        let m = blocks.iter().sum::<DVec3>() / (n as u32 * block * block) as f64;
        image_sum += m;
        image_sum2 += m * m;
    }
    let k = seeds as f64;
    let standard_error = |s2: DVec3, m: DVec3| {
        ((s2 / k - m * m).max(DVec3::ZERO) * (k / (k - 1.0)) / k).map(f64::sqrt)
    };
    let mean: Vec<DVec3> = sum.iter().map(|s| *s / k).collect();
    let stderr = sum2
        .iter()
        .zip(&mean)
        .map(|(s2, m)| standard_error(*s2, *m))
        .collect();
    let image_mean = image_sum / k;
    BlockStats {
        blocks_x: bx,
        blocks_y: by,
        mean,
        stderr,
        image_mean,
        image_stderr: standard_error(image_sum2, image_mean),
        discarded,
    }
}

/// Asserts that two estimates agree in every block and channel within `z`
/// combined standard errors (plus a hair for blocks that are exactly black).
pub fn assert_agree(a: &BlockStats, b: &BlockStats, z: f64, what: &str) {
    let mut worst = 0.0f64;
    for k in 0..a.mean.len() {
        for c in 0..3 {
            let diff = (a.mean[k][c] - b.mean[k][c]).abs();
            let sigma = (a.stderr[k][c].powi(2) + b.stderr[k][c].powi(2)).sqrt() + 1e-6;
            worst = worst.max(diff / sigma);
            assert!(
                diff <= z * sigma,
                "{what}: block ({}, {}) channel {c}: {:.5} vs {:.5}, {:.1} standard errors apart",
                k as u32 % a.blocks_x,
                k as u32 / a.blocks_x,
                a.mean[k][c],
                b.mean[k][c],
                diff / sigma
            );
        }
    }
    for c in 0..3 {
        let diff = (a.image_mean[c] - b.image_mean[c]).abs();
        let sigma = (a.image_stderr[c].powi(2) + b.image_stderr[c].powi(2)).sqrt() + 1e-9;
        assert!(
            diff <= z * sigma,
            "{what}: image means differ in channel {c}: {:.5} vs {:.5} ({:.1} standard errors)",
            a.image_mean[c],
            b.image_mean[c],
            diff / sigma
        );
        worst = worst.max(diff / sigma);
    }
    eprintln!("{what}: largest difference {worst:.2} standard errors");
}
