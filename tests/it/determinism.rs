//! The image is a pure function of scene, settings and seed.

use crate::common;
use tracer::render::{render, RenderOptions};
use tracer::scene::Scene;
use tracer::settings::Settings;

fn cornell(seed: u64) -> (Scene, Settings) {
    let (scene, mut settings) = common::load_scene("scenes/cornell-caustics.json");
    settings.film.width = 40;
    settings.film.height = 36;
    settings.stop.spp = 6;
    settings.seed = seed;
    (scene, settings)
}

/// `settings` rendered on `threads` worker threads.
fn render_on(scene: &Scene, settings: &Settings, threads: usize) -> tracer::film::Image {
    let options = RenderOptions {
        threads: Some(threads),
        progress: false,
        ..RenderOptions::default()
    };
    render(scene, settings, &options).unwrap().0
}

/// Every pixel's channels as bits: equal only when the images are the same
/// to the last bit (NaN included).
fn bits(image: &tracer::film::Image) -> Vec<u32> {
    image
        .pixels
        .iter()
        .flat_map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// The scene's own integrator (path tracing), and VCM with a radius wide
/// enough that merges happen: its merges sum over the grid in a fixed
/// order, and its light pass gathers its rows in order.
#[test]
fn same_seed_same_image_for_any_thread_count() {
    use tracer::settings::IntegratorKind;
    let _guard = common::heavy();
    for (integrator, radius) in [(None, None), (Some(IntegratorKind::Vcm), Some(20.0))] {
        let (scene, mut settings) = cornell(5);
        if let Some(integrator) = integrator {
            settings.integrator = integrator;
        }
        settings.vcm_radius = radius;
        let images: Vec<_> = [1, 2, 3]
            .iter()
            .map(|&threads| render_on(&scene, &settings, threads))
            .collect();
        assert!(images[0].mean().x > 0.0);
        let what = settings.integrator.name();
        assert_eq!(bits(&images[0]), bits(&images[1]), "{what}: 1 vs 2 threads");
        assert_eq!(bits(&images[0]), bits(&images[2]), "{what}: 1 vs 3 threads");
    }
}

#[test]
fn adaptive_renders_and_sample_offsets_are_the_same_for_any_thread_count() {
    use tracer::settings::IntegratorKind;
    let _guard = common::heavy();
    for integrator in [
        IntegratorKind::Pt,
        IntegratorKind::Bdpt,
        IntegratorKind::Lt,
        IntegratorKind::Vcm,
    ] {
        let (scene, mut settings) = cornell(3);
        settings.integrator = integrator;
        settings.stop.spp = 1 << 12;
        settings.sample_offset = 5;
        settings.stop.target_noise = Some(0.3);
        settings.stop.adaptive = matches!(integrator, IntegratorKind::Pt | IntegratorKind::Bdpt);
        let results: Vec<_> = [1, 3]
            .iter()
            .map(|&threads| {
                let options = RenderOptions {
                    threads: Some(threads),
                    ..RenderOptions::default()
                };
                render(&scene, &settings, &options).unwrap()
            })
            .collect();
        let (a, b) = (&results[0], &results[1]);
        assert!(
            a.0 == b.0,
            "{integrator:?}: the image depends on the thread count"
        );
        assert_eq!(
            (a.1.spp, a.1.max_spp),
            (b.1.spp, b.1.max_spp),
            "{integrator:?}"
        );
    }
}

#[test]
fn different_seeds_give_different_noise() {
    let _guard = common::heavy();
    let image = |(scene, settings): (Scene, Settings)| {
        render(&scene, &settings, &RenderOptions::default())
            .unwrap()
            .0
    };
    let a = image(cornell(1));
    let b = image(cornell(2));
    assert_ne!(a, b);
}

/// Splatting renders add a batch's splats while the next batch renders: an
/// image of more 16 x 16 tiles than one batch holds (64) takes that path.
/// Every thread count must give the same bits (that every batch is added
/// exactly once is checked in `render`'s own tests, by the paths counted).
#[test]
fn splats_of_many_batches_add_up_alike_for_any_thread_count() {
    use tracer::settings::IntegratorKind;
    let _guard = common::heavy();
    let (scene, mut settings) = common::load_scene("scenes/cornell-box.json");
    // 10 x 9 = 90 tiles: two batches.
    settings.film.width = 160;
    settings.film.height = 144;
    settings.stop.spp = 4;
    settings.seed = 3;
    let image = |integrator: IntegratorKind, threads: usize| {
        let mut settings = settings.clone();
        settings.integrator = integrator;
        render_on(&scene, &settings, threads)
    };
    for integrator in [IntegratorKind::Lt, IntegratorKind::Bdpt] {
        let one = bits(&image(integrator, 1));
        for threads in [2, 3] {
            assert!(
                one == bits(&image(integrator, threads)),
                "{}: 1 vs {threads} threads",
                integrator.name()
            );
        }
    }
}

/// The bundled scenes the lanes are checked on: between them flat and
/// tree traversal, every material, every kind of light, the environment
/// and a thin lens.
const LANE_SCENES: [&str; 7] = [
    "scenes/cornell-box.json",
    "scenes/cornell-caustics.json",
    "scenes/mirror-caustic.json",
    "scenes/lights.json",
    "scenes/textured.json",
    "scenes/rough-materials.json",
    "scenes/sky-materials.json",
];

/// `path` loaded for `kind`, its estimator and camera, and `n` pixels
/// spread over the image, each from sample `index` of seed 17.
fn lanes_setup(
    path: &str,
    kind: tracer::settings::IntegratorKind,
    n: u32,
    index: u64,
) -> (
    Scene,
    tracer::integrator::Integrator,
    tracer::camera::Camera,
    Vec<tracer::integrator::PixelSample>,
) {
    let (scene, mut settings) = common::load_scene(path);
    settings.integrator = kind;
    let integrator = tracer::integrator::Integrator::new(&settings);
    assert!(integrator.samples_in_lanes());
    let camera = settings.camera().unwrap();
    let (w, h) = (settings.film.width, settings.film.height);
    let pixels = (0..n)
        .map(|k| tracer::integrator::PixelSample::new(k * 97 % w, k * 61 % h, index, 17))
        .collect();
    (scene, integrator, camera, pixels)
}

/// The samples `index .. + count` of every pixel of `pixels`, taken in
/// lanes (in `light_pass`'s iteration, for VCM), and the sinks their
/// splats went to.
fn sample_in_lanes(
    scene: &Scene,
    integrator: &tracer::integrator::Integrator,
    camera: &tracer::camera::Camera,
    pixels: &[tracer::integrator::PixelSample],
    count: u32,
    light_pass: Option<&tracer::integrator::LightPass>,
) -> (Vec<tracer::color::Rgb>, [tracer::integrator::SampleSink; 2]) {
    use tracer::integrator::{SampleSink, ThreadState};
    let mut in_lanes = vec![tracer::color::Rgb::ZERO; pixels.len() * count as usize];
    let mut sinks = [SampleSink::default(), SampleSink::default()];
    integrator.sample_pixels(
        scene,
        camera,
        pixels,
        count,
        &mut in_lanes,
        &mut sinks,
        &mut ThreadState::default(),
        light_pass,
    );
    (in_lanes, sinks)
}

/// Panics unless the samples taken in lanes are those taken alone, bit for
/// bit, and a quarter of them at least carry light.
fn assert_same_samples(path: &str, in_lanes: &[tracer::color::Rgb], alone: &[tracer::color::Rgb]) {
    let bits = |c: &tracer::color::Rgb| c.to_array().map(f32::to_bits);
    if let Some(k) = (0..alone.len()).find(|&k| bits(&in_lanes[k]) != bits(&alone[k])) {
        panic!(
            "{path}: sample {k} is {} in lanes, {} alone",
            in_lanes[k], alone[k]
        );
    }
    let lit = alone.iter().filter(|c| c.max_element() > 0.0).count();
    assert!(lit > alone.len() / 4, "{path}: only {lit} lit samples");
}

/// The path tracer takes a tile's samples sixteen paths at a time, their
/// rays traced together; every sample must be the one it takes alone, bit
/// for bit.
#[test]
fn paths_in_lanes_are_the_paths_one_by_one() {
    use tracer::color::Rgb;
    use tracer::integrator::{SampleSink, ThreadState};
    use tracer::settings::IntegratorKind;
    for path in LANE_SCENES {
        // 37 paths per pixel, not a multiple of the lanes, from a first
        // index past zero.
        let (scene, integrator, camera, pixels) = lanes_setup(path, IntegratorKind::Pt, 23, 5);
        let count = 37;
        let (in_lanes, _) = sample_in_lanes(&scene, &integrator, &camera, &pixels, count, None);
        let mut state = ThreadState::default();
        let mut sink = SampleSink::default();
        let alone: Vec<Rgb> = pixels
            .iter()
            .flat_map(|p| (0..count as u64).map(move |i| p.with_index(p.index + i)))
            .map(|sample| integrator.sample(&scene, &camera, sample, &mut state, &mut sink, None))
            .collect();
        assert_same_samples(path, &in_lanes, &alone);
    }
}

/// BDPT takes a tile's samples sixteen at a time, their rays traced
/// together: every sample's estimate must be the one it gives alone, bit
/// for bit, and the splats must reach each half's sink as one sample after
/// another would push them, value for value and in the same order.
#[test]
fn bdpt_samples_in_lanes_are_the_samples_one_by_one() {
    use tracer::color::Rgb;
    use tracer::integrator::{SampleSink, ThreadState};
    use tracer::settings::IntegratorKind;
    for path in LANE_SCENES {
        // 37 samples per pixel: not a multiple of the lanes, and from an
        // odd first index, so both halves get samples from every batch.
        let (scene, integrator, camera, pixels) = lanes_setup(path, IntegratorKind::Bdpt, 23, 5);
        let count = 37;
        let (in_lanes, lane_sinks) =
            sample_in_lanes(&scene, &integrator, &camera, &pixels, count, None);
        let mut state = ThreadState::default();
        let mut sinks = [SampleSink::default(), SampleSink::default()];
        let mut alone = Vec::new();
        for p in &pixels {
            for i in 0..count as u64 {
                let sample = p.with_index(p.index + i);
                let sink = &mut sinks[(sample.index % 2) as usize];
                alone.push(integrator.sample(&scene, &camera, sample, &mut state, sink, None));
            }
        }
        assert_same_samples(path, &in_lanes, &alone);
        let bits = |c: &Rgb| c.to_array().map(f32::to_bits);
        for (half, (lanes, one_by_one)) in lane_sinks.iter().zip(&sinks).enumerate() {
            let splats = |sink: &SampleSink| -> Vec<(u32, [u32; 3])> {
                sink.splats
                    .iter()
                    .map(|s| (s.pixel, bits(&s.value)))
                    .collect()
            };
            assert_eq!(lanes.discarded, one_by_one.discarded, "{path}: half {half}");
            assert!(
                splats(lanes) == splats(one_by_one),
                "{path}: half {half}: {} splats in lanes, {} alone, or in another order",
                lanes.splats.len(),
                one_by_one.splats.len()
            );
        }
        let splatted = sinks[0].splats.len() + sinks[1].splats.len();
        // Open scenes lose most light paths to the sky: a few splats there.
        assert!(splatted >= 20, "{path}: only {splatted} splats");
    }
}

/// VCM's camera paths too go sixteen at a time, after each iteration's
/// light pass: every sample must be the one it gives alone, bit for bit.
#[test]
fn vcm_samples_in_lanes_are_the_samples_one_by_one() {
    use tracer::color::Rgb;
    use tracer::integrator::{SampleSink, ThreadState};
    use tracer::settings::IntegratorKind;
    for path in [
        "scenes/cornell-box.json",
        "scenes/cornell-caustics.json",
        "scenes/lights.json",
        "scenes/sky-materials.json",
    ] {
        // One sample per pixel and iteration; 301 pixels, not a multiple
        // of the lanes.
        let index = 3;
        let (scene, integrator, camera, pixels) =
            lanes_setup(path, IntegratorKind::Vcm, 301, index);
        let pass = integrator
            .light_pass(&scene, &camera, 17, index, None)
            .expect("VCM has a light pass");
        let (in_lanes, _) = sample_in_lanes(&scene, &integrator, &camera, &pixels, 1, Some(&pass));
        let mut state = ThreadState::default();
        let mut sink = SampleSink::default();
        let alone: Vec<Rgb> = pixels
            .iter()
            .map(|&p| integrator.sample(&scene, &camera, p, &mut state, &mut sink, Some(&pass)))
            .collect();
        assert_same_samples(path, &in_lanes, &alone);
    }
}
