//! Progressive rendering: each stopping rule, the noise estimate against
//! the true error, interruption (in the library and by a real signal to a
//! child process), checkpoints, metadata, and merging partial renders.

use crate::common::{self, run, tracer};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracer::film::read::read_with_metadata;
use tracer::film::tonemap::Tonemap;
use tracer::film::write::write_image_with;
use tracer::film::Image;
use tracer::render::{render, RenderOptions, StopReason};
use tracer::scene::Scene;
use tracer::settings::{Crop, IntegratorKind, Settings};

// Tests that time a render or a child process take `common::serial()`, so
// no other guarded test shares the cores with them; the others here take
// `common::heavy()`.

/// The Cornell box at `size` × `size`, `spp` samples per pixel, no time limit.
fn cornell(size: u32, spp: u32) -> (Scene, Settings) {
    let (scene, mut settings) = common::load_scene("scenes/cornell-box.json");
    settings.film.width = size;
    settings.film.height = size;
    settings.stop.spp = spp;
    settings.stop.time_limit = None;
    (scene, settings)
}

/// The Cornell box rendered with `integrator` at `size` × `size` and `spp`
/// samples per pixel: a reference for renders stopped early.
fn reference(size: u32, spp: u32, integrator: IntegratorKind) -> Image {
    let (scene, mut settings) = cornell(size, spp);
    settings.integrator = integrator;
    render(&scene, &settings, &options()).unwrap().0
}

fn options() -> RenderOptions {
    RenderOptions {
        threads: Some(2),
        ..RenderOptions::default()
    }
}

fn luminance_mean(image: &Image) -> f64 {
    let m = image.mean();
    (m.x + m.y + m.z) as f64 / 3.0
}

/// Mean over pixels of 2|I − R| / (I + R + 0.01) on channel means: what the
/// half-buffer estimate (|A − B| / (A + B + 0.01)) estimates.
fn true_error(image: &Image, reference: &Image) -> f64 {
    let l = |c: glam::Vec3| (c.x + c.y + c.z) as f64 / 3.0;
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(&i, &r)| 2.0 * (l(i) - l(r)).abs() / (l(i) + l(r) + 0.01))
        .sum();
    sum / image.pixels.len() as f64
}

#[test]
fn the_sample_count_stops_a_render_exactly() {
    let _guard = common::heavy();
    let (scene, settings) = cornell(16, 9);
    let (_, stats) = render(&scene, &settings, &options()).unwrap();
    assert_eq!((stats.spp, stats.max_spp), (9, 9));
    assert_eq!(stats.stopped_by, StopReason::SampleCount);
}

#[test]
fn the_time_limit_stops_within_a_tile_and_normalises_by_samples_taken() {
    let _guard = common::serial();
    let (scene, mut settings) = cornell(48, 1 << 30);
    settings.stop.time_limit = Some(0.3);
    let start = Instant::now();
    let (image, stats) = render(&scene, &settings, &options()).unwrap();
    let took = start.elapsed().as_secs_f64();
    assert_eq!(stats.stopped_by, StopReason::TimeLimit);
    assert!(took < 0.3 + 1.0, "took {took} s");
    assert!(stats.spp >= 1 && stats.spp < 1 << 20);
    let reference = reference(48, 64, IntegratorKind::Pt);
    let (a, b) = (luminance_mean(&image), luminance_mean(&reference));
    assert!((a / b - 1.0).abs() < 0.03, "mean {a} against {b}");
}

#[test]
fn the_target_noise_stops_when_the_estimate_falls_below_it_and_tracks_the_true_error() {
    let _guard = common::heavy();
    let reference = reference(32, 2048, IntegratorKind::Pt);
    let mut previous_spp = 0;
    for target in [0.2, 0.1, 0.05] {
        let (scene, mut settings) = cornell(32, 1 << 20);
        settings.stop.target_noise = Some(target);
        let (image, stats) = render(&scene, &settings, &options()).unwrap();
        assert_eq!(stats.stopped_by, StopReason::TargetNoise, "target {target}");
        let noise = stats.noise.unwrap();
        assert!(noise < target, "noise {noise} above target {target}");
        assert!(
            stats.spp > previous_spp,
            "a lower target took no more samples"
        );
        previous_spp = stats.spp;
        let truth = true_error(&image, &reference);
        let ratio = noise / truth;
        eprintln!(
            "target {target}: {} spp, estimated {noise:.4}, true {truth:.4}",
            stats.spp
        );
        // Sobol samples converge faster than independent ones, and either
        // half alone is less well stratified than the whole: the estimate
        // errs high, more so as samples grow (a safe side for a stopping rule).
        assert!(
            (0.8..1.7).contains(&ratio),
            "target {target}: estimated {noise:.4}, true {truth:.4} at {} spp",
            stats.spp
        );
    }
}

#[test]
fn an_interrupted_render_returns_quickly_with_each_pixel_normalised() {
    let _guard = common::serial();
    for integrator in [
        IntegratorKind::Pt,
        IntegratorKind::Bdpt,
        IntegratorKind::Vcm,
    ] {
        let (scene, mut settings) = cornell(48, 1 << 30);
        settings.integrator = integrator;
        let flag = Arc::new(AtomicBool::new(false));
        let opts = RenderOptions {
            interrupt: Some(flag.clone()),
            ..options()
        };
        let setter = {
            let flag = flag.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(400));
                flag.store(true, Ordering::SeqCst);
                Instant::now()
            })
        };
        let (image, stats) = render(&scene, &settings, &opts).unwrap();
        let stopped = Instant::now();
        let set_at = setter.join().unwrap();
        assert_eq!(stats.stopped_by, StopReason::Interrupted);
        let lag = stopped.duration_since(set_at).as_secs_f64();
        assert!(lag < 1.0, "{integrator:?}: stopped {lag} s after the flag");
        let reference = reference(48, 64, integrator);
        let (a, b) = (luminance_mean(&image), luminance_mean(&reference));
        assert!(
            (a / b - 1.0).abs() < 0.03,
            "{integrator:?}: mean {a} against {b} ({}..{} spp)",
            stats.spp,
            stats.max_spp
        );
    }
}

#[test]
fn a_crop_renders_exactly_the_full_images_pixels() {
    let _guard = common::heavy();
    for integrator in [IntegratorKind::Pt, IntegratorKind::Lt] {
        let (scene, mut settings) = cornell(40, 4);
        settings.integrator = integrator;
        let full = render(&scene, &settings, &options()).unwrap().0;
        settings.crop = Some(Crop {
            x0: 7,
            y0: 21,
            x1: 33,
            y1: 40,
        });
        let part = render(&scene, &settings, &options()).unwrap().0;
        assert_eq!((part.width, part.height), (26, 19));
        for y in 0..part.height {
            for x in 0..part.width {
                assert_eq!(
                    part.get(x, y),
                    full.get(x + 7, y + 21),
                    "{integrator:?} at {x},{y}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------
// The command line: signals, checkpoints, metadata, merge.

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn wait_for(path: &Path, limit: Duration) {
    let start = Instant::now();
    while !path.exists() {
        assert!(start.elapsed() < limit, "{} never appeared", path.display());
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn send(pid: u32, signal: i32) {
    // SAFETY: kill(2) on our own child's pid.
    let r = unsafe { libc::kill(pid as i32, signal) };
    assert_eq!(r, 0, "kill failed");
}

/// A render of the Cornell box at 64 × 64 into `out` that would run for hours.
fn long_render(out: &Path, extra: &[&str]) -> std::process::Command {
    let mut c = tracer();
    c.args([
        "render",
        "scenes/cornell-box.json",
        "--width",
        "64",
        "--height",
        "64",
    ])
    .args(["--spp", "1000000", "-q", "-o", path_str(out)])
    .args(extra);
    c
}

/// A long render of the Cornell box into `out`, interrupted by `signals`
/// once its first checkpoint exists; returns the exit status, how long it
/// took to exit after the first signal, and the image with its metadata.
fn interrupt_child(out: &Path, signals: &[i32]) -> (Option<i32>, f64, Image, String) {
    let mut child = long_render(out, &["--threads", "2"]).spawn().unwrap();
    wait_for(out, Duration::from_secs(20));
    std::thread::sleep(Duration::from_millis(300));
    let sent = Instant::now();
    for &s in signals {
        send(child.id(), s);
    }
    let status = child.wait().unwrap();
    let lag = sent.elapsed().as_secs_f64();
    let (image, meta) = read_with_metadata(out).unwrap();
    (status.code(), lag, image, meta.stopped_by)
}

fn reference_mean() -> f64 {
    luminance_mean(&reference(64, 64, IntegratorKind::Pt))
}

#[test]
fn sigint_and_sigterm_stop_a_render_within_a_second_and_write_a_normalised_image() {
    let _guard = common::serial();
    let dir = tempfile::tempdir().unwrap();
    let expected = reference_mean();
    for (name, signal) in [("int", libc::SIGINT), ("term", libc::SIGTERM)] {
        let out = dir.path().join(format!("{name}.exr"));
        let (code, lag, image, stopped_by) = interrupt_child(&out, &[signal]);
        assert_eq!(code, Some(130), "SIG{name}");
        assert!(lag < 1.0, "SIG{name}: exited {lag} s after the signal");
        assert_eq!(stopped_by, "interrupted");
        let mean = luminance_mean(&image);
        assert!(
            (mean / expected - 1.0).abs() < 0.03,
            "SIG{name}: mean {mean} against {expected}"
        );
    }
}

#[test]
fn a_second_ctrl_c_exits_at_once_without_writing() {
    let _guard = common::serial();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("twice.exr");
    // A large image: after the first signal the render stops within a tile
    // but then spends a while encoding and writing 4 M pixels, which is
    // when the second signal arrives.
    let child = tracer()
        .args([
            "render",
            "scenes/cornell-box.json",
            "--width",
            "2048",
            "--height",
            "2048",
        ])
        .args([
            "--spp",
            "1000000",
            "--threads",
            "2",
            "-q",
            "-o",
            path_str(&out),
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&out, Duration::from_secs(60));
    let sent = Instant::now();
    send(child.id(), libc::SIGINT);
    std::thread::sleep(Duration::from_millis(5));
    send(child.id(), libc::SIGINT);
    let output = child.wait_with_output().unwrap();
    let lag = sent.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("interrupted again"),
        "the second signal went unseen: {stderr}"
    );
    assert!(lag < 1.0, "exited {lag} s after two signals");
    // It exited without writing: the file is still the last checkpoint, whole.
    let (image, meta) = read_with_metadata(&out).unwrap();
    assert_eq!(meta.stopped_by, "in progress");
    assert_eq!((image.width, image.height), (2048, 2048));
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 1, "a temporary file was left behind: {left:?}");
}

#[test]
fn checkpoints_are_written_while_the_render_runs_with_the_right_brightness() {
    let _guard = common::serial();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("progress.png");
    let mut child = long_render(&out, &["--checkpoint", "0.2"]).spawn().unwrap();
    let sidecar = tracer::film::metadata::sidecar_path(&out);
    wait_for(&out, Duration::from_secs(20));
    wait_for(&sidecar, Duration::from_secs(5));
    std::thread::sleep(Duration::from_millis(600));
    let first: tracer::film::metadata::Metadata =
        serde_json::from_slice(&std::fs::read(&sidecar).unwrap()).unwrap();
    std::thread::sleep(Duration::from_millis(600));
    let later: tracer::film::metadata::Metadata =
        serde_json::from_slice(&std::fs::read(&sidecar).unwrap()).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(first.stopped_by, "in progress");
    assert!(
        later.spp > first.spp,
        "no newer checkpoint: {} then {}",
        first.spp,
        later.spp
    );
    let png = image::open(&out).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (64, 64));
    let mean: f64 = png
        .pixels()
        .map(|p| p.0.iter().map(|&c| c as f64).sum::<f64>())
        .sum::<f64>()
        / (64.0 * 64.0 * 3.0);
    assert!(mean > 40.0, "the checkpoint looks black (mean {mean})");
}

#[test]
fn outputs_carry_their_metadata() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("a.exr");
    let png = dir.path().join("a.png");
    for out in [&exr, &png] {
        run(&[
            "render",
            "scenes/cornell-box.json",
            "--width",
            "20",
            "--height",
            "12",
            "--spp",
            "3",
        ]
        .into_iter()
        .chain([
            "--seed",
            "7",
            "--integrator",
            "bdpt",
            "-q",
            "-o",
            path_str(out),
        ])
        .collect::<Vec<_>>());
    }
    let (image, m) = read_with_metadata(&exr).unwrap();
    assert_eq!((image.width, image.height), (20, 12));
    assert_eq!((m.spp, m.max_spp, m.seed), (3, 3, 7));
    assert_eq!(m.integrator, "bdpt");
    assert_eq!((m.width, m.height, m.crop), (20, 12, [0, 0, 20, 12]));
    assert_eq!(m.samples, vec![(0, 3)]);
    assert_eq!(m.stopped_by, "spp");
    assert!(m.program.starts_with("tracer "));
    assert!(m.render_seconds > 0.0);
    assert_eq!(m.scene_hash.len(), 64);
    let side: tracer::film::metadata::Metadata =
        serde_json::from_slice(&std::fs::read(tracer::film::metadata::sidecar_path(&png)).unwrap())
            .unwrap();
    assert_eq!(side.scene_hash, m.scene_hash, "the same scene hashes alike");
    assert_eq!((side.spp, side.seed), (3, 7));
}

fn render_part(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(format!("{name}.exr"));
    let mut args = vec![
        "render",
        "scenes/cornell-box.json",
        "--width",
        "48",
        "--height",
        "40",
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-q", "-o", path_str(&out)]);
    run(&args);
    out
}

fn merge(inputs: &[PathBuf], out: &Path) -> Output {
    tracer()
        .arg("merge")
        .args(inputs)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

/// Merges `parts` into `dir/merged.exr`, which must succeed, and reads it.
fn merged(parts: &[PathBuf], dir: &Path) -> (Image, tracer::film::metadata::Metadata) {
    let target = dir.join("merged.exr");
    let out = merge(parts, &target);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_with_metadata(&target).unwrap()
}

#[test]
fn four_sample_ranges_merged_equal_one_render_of_all_samples() {
    let _guard = common::heavy();
    for integrator in ["pt", "lt", "bdpt", "vcm"] {
        let dir = tempfile::tempdir().unwrap();
        let parts: Vec<PathBuf> = [0, 16, 32, 48]
            .iter()
            .map(|o| {
                let offset = o.to_string();
                render_part(
                    dir.path(),
                    &format!("o{o}"),
                    &[
                        "--integrator",
                        integrator,
                        "--spp",
                        "16",
                        "--sample-offset",
                        &offset,
                    ],
                )
            })
            .collect();
        let whole = render_part(
            dir.path(),
            "whole",
            &["--integrator", integrator, "--spp", "64"],
        );
        let (a, ma) = merged(&parts, dir.path());
        let (b, _) = read_with_metadata(&whole).unwrap();
        assert_eq!((ma.spp, ma.samples.clone()), (64, vec![(0, 64)]));
        for (p, q) in a.pixels.iter().zip(&b.pixels) {
            let scale = q.abs().max_element().max(1e-3);
            assert!(
                (*p - *q).abs().max_element() <= 1e-5 * scale,
                "{integrator}: merged {p} against {q}"
            );
        }
    }
}

#[test]
fn four_crops_merged_equal_the_full_image_exactly() {
    let _guard = common::heavy();
    for integrator in ["pt", "bdpt", "vcm"] {
        let dir = tempfile::tempdir().unwrap();
        let crops = ["0,0,20,17", "20,0,48,17", "0,17,20,40", "20,17,48,40"];
        let parts: Vec<PathBuf> = crops
            .iter()
            .enumerate()
            .map(|(k, c)| {
                render_part(
                    dir.path(),
                    &format!("c{k}"),
                    &["--integrator", integrator, "--spp", "4", "--crop", c],
                )
            })
            .collect();
        let whole = render_part(
            dir.path(),
            "whole",
            &["--integrator", integrator, "--spp", "4"],
        );
        let (a, _) = merged(&parts, dir.path());
        let (b, _) = read_with_metadata(&whole).unwrap();
        assert!(
            a == b,
            "{integrator}: the merged crops differ from the full image"
        );
    }
}

#[test]
fn merge_refuses_parts_that_do_not_belong_together() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = render_part(d, "a", &["--spp", "4"]);
    let b = render_part(d, "b", &["--spp", "4", "--sample-offset", "4"]);
    let other_seed = render_part(
        d,
        "seed",
        &["--spp", "4", "--sample-offset", "8", "--seed", "9"],
    );
    let other_integrator = render_part(
        d,
        "lt",
        &["--spp", "4", "--sample-offset", "8", "--integrator", "lt"],
    );
    let other_depth = render_part(
        d,
        "depth",
        &["--spp", "4", "--sample-offset", "8", "--max-depth", "3"],
    );
    let other_scene = d.join("lights.exr");
    run(&[
        "render",
        "scenes/lights.json",
        "--width",
        "48",
        "--height",
        "40",
        "--spp",
        "4",
    ]
    .into_iter()
    .chain(["--sample-offset", "8", "-q", "-o", path_str(&other_scene)])
    .collect::<Vec<_>>());
    let corner = render_part(d, "corner", &["--spp", "4", "--crop", "0,0,10,10"]);
    // An interrupted render's pixels hold different sample counts.
    let (image, mut meta) = read_with_metadata(&b).unwrap();
    meta.max_spp = meta.spp + 2;
    meta.samples = vec![(12, 4)];
    let interrupted = d.join("interrupted.exr");
    write_image_with(&interrupted, &image, Tonemap::Clamp, 0.0, Some(&meta)).unwrap();
    // A PFM whose sidecar was left from an earlier version of the image.
    let stale = d.join("stale.pfm");
    write_image_with(&stale, &image, Tonemap::Clamp, 0.0, Some(&meta)).unwrap();
    let mut brighter = image.clone();
    brighter.pixels[0] += glam::Vec3::splat(1.0);
    tracer::film::write::write_image(&stale, &brighter, Tonemap::Clamp, 0.0).unwrap();
    let plain = d.join("plain.exr");
    tracer::film::write::write_image(&plain, &image, Tonemap::Clamp, 0.0).unwrap();

    let out = merge(&[a.clone(), b.clone()], &d.join("ok.exr"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (what, inputs, expect) in [
        (
            "the same samples twice",
            vec![a.clone(), a.clone()],
            "same samples",
        ),
        ("another seed", vec![a.clone(), other_seed], "the seed"),
        (
            "another integrator",
            vec![a.clone(), other_integrator],
            "the integrator",
        ),
        (
            "another depth",
            vec![a.clone(), other_depth],
            "the maximum depth",
        ),
        ("another scene", vec![a.clone(), other_scene], "the scene"),
        (
            "an interrupted part",
            vec![a.clone(), interrupted],
            "interrupted",
        ),
        (
            "no metadata",
            vec![a.clone(), plain],
            "not written by tracer",
        ),
        (
            "uneven coverage",
            vec![a.clone(), b.clone(), corner.clone()],
            "same samples",
        ),
        ("pixels left uncovered", vec![corner], "uncovered"),
        ("a stale sidecar", vec![a.clone(), stale], "another version"),
    ] {
        let target = d.join("refused.exr");
        let out = merge(&inputs, &target);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{what}: {stderr}");
        assert!(stderr.contains(expect), "{what}: {stderr}");
        assert!(!target.exists(), "{what}: wrote an output anyway");
    }
}

#[test]
fn adaptive_sampling_brings_every_tile_below_the_target_at_less_cost_than_uniform() {
    let _guard = common::heavy();
    let (scene, mut settings) = common::load_scene("scenes/cornell-caustics.json");
    settings.film.width = 48;
    settings.film.height = 48;
    settings.stop.time_limit = None;
    let with_spp = |spp: u32| {
        let mut s = settings.clone();
        s.stop.spp = spp;
        s
    };
    let target = 0.1;
    let mut adaptive = with_spp(1 << 20);
    adaptive.stop.target_noise = Some(target);
    adaptive.stop.adaptive = true;
    let mut worst_adaptive = 0.0f64;
    let (image, stats) = tracer::render::render_with(&scene, &adaptive, &options(), |acc, _| {
        if let Some(noise) = acc.tile_noise() {
            worst_adaptive = noise.into_iter().flatten().fold(0.0, f64::max);
        }
    })
    .unwrap();
    assert_eq!(stats.stopped_by, StopReason::TargetNoise);
    assert!(worst_adaptive < target, "a tile at {worst_adaptive}");
    assert!(
        stats.max_spp > stats.spp,
        "every tile took the same samples"
    );

    // The same number of samples spread evenly leaves some tile noisier.
    let pixels = 48 * 48;
    let even_spp = stats.samples.div_ceil(pixels) as u32;
    let mut worst_uniform = 0.0f64;
    let (uniform, _) =
        tracer::render::render_with(&scene, &with_spp(even_spp), &options(), |acc, _| {
            if let Some(noise) = acc.tile_noise() {
                worst_uniform = noise.into_iter().flatten().fold(0.0, f64::max);
            }
        })
        .unwrap();
    eprintln!(
        "adaptive: {}..{} spp ({} samples), worst tile {worst_adaptive:.4}; uniform at {even_spp} spp: worst tile {worst_uniform:.4}",
        stats.spp, stats.max_spp, stats.samples
    );
    assert!(
        worst_uniform > worst_adaptive,
        "uniform {worst_uniform} against adaptive {worst_adaptive} at equal samples"
    );
    // Unequal sample counts, each pixel normalised by its own: no bias.
    let (a, b) = (luminance_mean(&image), luminance_mean(&uniform));
    assert!((a / b - 1.0).abs() < 0.05, "mean {a} against {b}");
}
