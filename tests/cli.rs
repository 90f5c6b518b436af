//! The `tracer` binary end to end: render a bundled scene, override settings
//! with flags, describe a scene.

mod common;

use std::process::Command;

fn tracer() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tracer"))
}

#[test]
fn renders_a_bundled_scene_with_overrides() {
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
        .current_dir(common::repo())
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let stderr = String::from_utf8_lossy(&status.stderr);
    assert!(stderr.contains("2 spp"), "{stderr}");
    let image = tracer::film::write::read_pfm(&out).unwrap();
    assert_eq!((image.width, image.height), (24, 16));
    let mean = image.mean();
    assert!(mean.x > 0.0 && mean.x.is_finite());
}

#[test]
fn time_limit_stops_early_with_a_correctly_normalised_image() {
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
        .current_dir(common::repo())
        .output()
        .unwrap();
    assert!(output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !stderr.contains("100000 spp"),
        "the time limit did not stop the render: {stderr}"
    );
    // Same brightness as a short full render: normalised by the samples taken.
    let image = tracer::film::write::read_pfm(&out).unwrap();
    let mut scene = tracer::scene::load(&common::repo().join("scenes/cornell-box.json")).unwrap();
    scene.set_resolution(16, 16);
    scene.settings.spp = 256;
    let (reference, _) = tracer::render::render(&scene, &Default::default()).unwrap();
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
        .current_dir(common::repo())
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
        let output = tracer()
            .args(&args)
            .current_dir(common::repo())
            .output()
            .unwrap();
        assert!(!output.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains("error"), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

#[test]
fn writes_bdpt_strategy_images() {
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
        .current_dir(common::repo())
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
