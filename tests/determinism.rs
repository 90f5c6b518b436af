//! The image is a pure function of scene, settings and seed.

mod common;

use tracer::render::{render, RenderOptions};

fn cornell(seed: u64) -> tracer::scene::Scene {
    let mut scene =
        tracer::scene::load(&common::repo().join("scenes/cornell-caustics.json")).unwrap();
    scene.set_resolution(40, 36);
    scene.settings.spp = 6;
    scene.settings.seed = seed;
    scene
}

#[test]
fn same_seed_same_image_for_any_thread_count() {
    let scene = cornell(5);
    let images: Vec<_> = [1, 2, 3]
        .iter()
        .map(|&threads| {
            let options = RenderOptions {
                threads: Some(threads),
                progress: false,
                ..RenderOptions::default()
            };
            render(&scene, &options).unwrap().0
        })
        .collect();
    assert!(images[0].mean().x > 0.0);
    let bits = |i: &tracer::film::Image| {
        i.pixels
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&images[0]), bits(&images[1]), "1 vs 2 threads");
    assert_eq!(bits(&images[0]), bits(&images[2]), "1 vs 3 threads");
}

#[test]
fn adaptive_renders_and_sample_offsets_are_the_same_for_any_thread_count() {
    use tracer::scene::desc::IntegratorKind;
    for integrator in [IntegratorKind::Pt, IntegratorKind::Bdpt, IntegratorKind::Lt] {
        let mut scene = cornell(3);
        scene.settings.integrator = integrator;
        scene.settings.spp = 1 << 12;
        let adaptive = integrator != IntegratorKind::Lt;
        let results: Vec<_> = [1, 3]
            .iter()
            .map(|&threads| {
                let options = RenderOptions {
                    threads: Some(threads),
                    sample_offset: 5,
                    target_noise: Some(0.3),
                    adaptive,
                    ..RenderOptions::default()
                };
                render(&scene, &options).unwrap()
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
    let a = render(&cornell(1), &RenderOptions::default()).unwrap().0;
    let b = render(&cornell(2), &RenderOptions::default()).unwrap().0;
    assert_ne!(a, b);
}
