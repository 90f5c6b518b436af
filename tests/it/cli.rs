//! The `tracer` binary end to end: render a bundled scene, override settings
//! with flags, describe a scene.

use crate::common::{self, tracer};
use tracer::film::read::read_pfm;

#[test]
fn renders_a_bundled_scene_with_overrides() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.pfm");
    let status = tracer()
        .args([
            "render",
            "scenes/cornell-box.json",
            "--spp",
            "2",
            "--width",
            "24",
            "--height",
            "16",
        ])
        .args(["--threads", "2", "--seed", "3", "--max-depth", "4", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let stderr = String::from_utf8_lossy(&status.stderr);
    assert!(stderr.contains("2 spp"), "{stderr}");
    let image = read_pfm(&out).unwrap();
    assert_eq!((image.width, image.height), (24, 16));
    let mean = image.mean();
    assert!(mean.x > 0.0 && mean.x.is_finite());
}

#[test]
fn time_limit_stops_early_with_a_correctly_normalised_image() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.pfm");
    let output = tracer()
        .args([
            "render",
            "scenes/cornell-box.json",
            "--spp",
            "100000",
            "--width",
            "16",
            "--height",
            "16",
        ])
        .args(["--time-limit", "0.3", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !stderr.contains("100000 spp"),
        "the time limit did not stop the render: {stderr}"
    );
    // Same brightness as a short full render: normalised by the samples taken.
    let image = read_pfm(&out).unwrap();
    let (scene, mut settings) = common::load_scene("scenes/cornell-box.json");
    settings.film.width = 16;
    settings.film.height = 16;
    settings.stop.spp = 256;
    let (reference, _) = tracer::render::render(&scene, &settings, &Default::default()).unwrap();
    let (a, b) = (image.mean(), reference.mean());
    assert!(
        (a - b).abs().max_element() < 0.05 * b.max_element(),
        "{a} vs {b}"
    );
}

#[test]
fn info_describes_the_scene() {
    let output = tracer()
        .args(["info", "scenes/cornell-box.json"])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(text.contains("triangles:  32"), "{text}");
    assert!(text.contains("area triangles 2"), "{text}");
    assert!(text.contains("SAH cost"), "{text}");
}

#[test]
fn bad_flags_are_refused_without_a_panic() {
    for args in [
        vec!["render", "scenes/cornell-box.json", "--spp", "0"],
        vec!["render", "scenes/cornell-box.json", "--time-limit", "-1"],
        vec!["render", "scenes/cornell-box.json", "-o", "/tmp/out.bmp"],
        vec!["render", "no-such-scene.json"],
    ] {
        let output = tracer().args(&args).output().unwrap();
        assert!(!output.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains("error"), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

/// A reader that closes the pipe before `tracer` writes (`tracer bench
/// --json | head`) ends it with the status of a process killed by SIGPIPE,
/// without a panic's message.
#[test]
fn a_closed_stdout_pipe_ends_quietly() {
    use std::process::Stdio;
    let mut child = tracer()
        .args(["bench", "scenes/cornell-box.json", "--rays", "primary"])
        .args(["--runs", "1", "--threads", "1", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The bench builds and traces before it prints: the pipe is closed by then.
    drop(child.stdout.take());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(output.status.code(), Some(141), "{stderr}");
}

/// Settings given as flags pass the same checks as a scene's, before any
/// geometry is built, and the message names the flag.
#[test]
fn settings_from_flags_are_checked_and_the_flag_named() {
    for (args, expect) in [
        (
            vec!["--width", "65536", "--height", "65536"],
            "--width/--height: 65536 x 65536 is too large (at most 268435456 pixels)",
        ),
        (
            vec!["--crop", "0,0,300,10"],
            "--crop: crop 0,0,300,10 is not a non-empty part of the 256x256 image",
        ),
    ] {
        let output = tracer()
            .args(["render", "scenes/cornell-box.json", "-q"])
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

#[test]
fn writes_bdpt_strategy_images() {
    let _guard = common::heavy();
    let dir = tempfile::tempdir().unwrap();
    let strategies = dir.path().join("strategies");
    let output = tracer()
        .args(["render", "scenes/cornell-box.json", "--integrator", "bdpt"])
        .args([
            "--spp",
            "2",
            "--width",
            "16",
            "--height",
            "16",
            "--max-depth",
            "2",
        ])
        .arg("-o")
        .arg(dir.path().join("box.exr"))
        .arg("--bdpt-strategies")
        .arg(&strategies)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut names: Vec<String> = std::fs::read_dir(&strategies)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    // Lengths 1 and 2: (0,2); (0,3), (1,2), (2,1); each unweighted and weighted.
    let expected: Vec<String> = ["s0_t2", "s0_t3", "s1_t2", "s2_t1"]
        .iter()
        .flat_map(|s| [format!("{s}_unweighted.exr"), format!("{s}_weighted.exr")])
        .collect();
    assert_eq!(names, expected);
}

#[test]
fn compare_reports_relative_mse() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, small) = (
        dir.path().join("a.pfm"),
        dir.path().join("b.exr"),
        dir.path().join("small.pfm"),
    );
    let mut image = tracer::film::Image::new(2, 1);
    image.pixels = vec![glam::Vec3::splat(1.0), glam::Vec3::splat(0.0)];
    let mut other = image.clone();
    other.pixels[0] = glam::Vec3::splat(1.5);
    let linear = tracer::film::tonemap::Tonemap::Clamp;
    tracer::film::write::write_image(&a, &image, linear, 0.0).unwrap();
    tracer::film::write::write_image(&b, &other, linear, 0.0).unwrap();
    tracer::film::write::write_image(&small, &tracer::film::Image::new(1, 1), linear, 0.0).unwrap();
    let run = |x: &std::path::Path, y: &std::path::Path| {
        tracer().arg("compare").arg(x).arg(y).output().unwrap()
    };
    // Pixel 0: (1.5 − 1)² / (1 + 0.01) in each channel; pixel 1: zero. Mean over 6 values.
    let out = run(&b, &a);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let error: f64 = String::from_utf8_lossy(&out.stdout).trim().parse().unwrap();
    assert!((error - 0.25 / 1.01 / 2.0).abs() < 1e-6, "{error}");
    let out = run(&a, &a);
    assert_eq!(
        String::from_utf8_lossy(&out.stdout)
            .trim()
            .parse::<f64>()
            .unwrap(),
        0.0
    );
    let out = run(&small, &a);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("small.pfm"));
}
