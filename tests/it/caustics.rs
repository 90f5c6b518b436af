//! Where BDPT earns its cost: caustics from a small light through glass,
//! which path tracing finds only when a BSDF-sampled ray happens to hit the
//! light. At equal samples per pixel BDPT must be closer to a long reference.

use crate::common;
use tracer::film::relative_mse;
use tracer::render::{render, RenderOptions};
use tracer::settings::IntegratorKind;

fn render_with(integrator: IntegratorKind, spp: u32, seed: u64) -> tracer::film::Image {
    let (scene, mut settings) = common::load_scene("scenes/cornell-caustics.json");
    settings.film.width = 32;
    settings.film.height = 32;
    settings.integrator = integrator;
    settings.stop.spp = spp;
    settings.seed = seed;
    let (image, stats) = render(&scene, &settings, &RenderOptions::default()).unwrap();
    assert_eq!(stats.discarded, 0);
    image
}

#[test]
fn bdpt_beats_path_tracing_at_equal_samples() {
    let _guard = common::heavy();
    // An independent seed for the reference, so its own noise adds equally
    // to both errors rather than favouring one estimator.
    let reference = render_with(IntegratorKind::Bdpt, 512, 1000);
    let mut pt_error = 0.0;
    let mut bdpt_error = 0.0;
    for seed in 0..4 {
        pt_error += relative_mse(&render_with(IntegratorKind::Pt, 16, seed), &reference).unwrap();
        bdpt_error +=
            relative_mse(&render_with(IntegratorKind::Bdpt, 16, seed), &reference).unwrap();
    }
    eprintln!(
        "relative MSE at 16 spp: pt {:.4}, bdpt {:.4}",
        pt_error / 4.0,
        bdpt_error / 4.0
    );
    assert!(
        bdpt_error < 0.5 * pt_error,
        "BDPT relative MSE {bdpt_error:.4} is not clearly below PT's {pt_error:.4}"
    );
}
