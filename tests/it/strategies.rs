//! `--bdpt-strategies`: the per-strategy images must add up to BDPT's image,
//! and each strategy alone must be an unbiased estimate of its path length.

use crate::common;
use tracer::render::{render, render_strategies, RenderOptions};
use tracer::settings::IntegratorKind;

#[test]
fn strategies_add_up_and_each_estimates_its_path_length() {
    let _guard = common::heavy();
    let (scene, mut settings) = common::load_scene("scenes/cornell-box.json");
    settings.film.width = 32;
    settings.film.height = 32;
    settings.integrator = IntegratorKind::Bdpt;
    settings.stop.spp = 64;
    settings.max_depth = 4;
    let options = RenderOptions::default();
    let (bdpt, _) = render(&scene, &settings, &options).unwrap();
    let strategies = render_strategies(&scene, &settings, &options).unwrap();

    // Every strategy a diffuse scene allows, for path lengths 1 to 4: s + t = k + 1,
    // t ≥ 1, and s = 1 with t = 1 is left to s = 0 (the light seen directly).
    let mut names: Vec<(u32, u32)> = strategies.iter().map(|i| (i.s, i.t)).collect();
    names.sort();
    let mut expected = Vec::new();
    for k in 1..=4u32 {
        for s in 0..=k {
            let t = k + 1 - s;
            if (s, t) != (1, 1) {
                expected.push((s, t));
            }
        }
    }
    expected.sort();
    assert_eq!(names, expected);

    // The weighted images sum to BDPT's own image (summation order aside).
    for (k, p) in bdpt.pixels.iter().enumerate() {
        let sum: glam::Vec3 = strategies.iter().map(|i| i.weighted.pixels[k]).sum();
        assert!(
            (sum - *p).abs().max_element() <= 1e-4 * p.max_element().max(1e-3),
            "pixel {k}: strategies sum to {sum}, BDPT gives {p}"
        );
    }

    // Each unweighted strategy estimates the whole of its path length's
    // light on its own: over several seeds, its image mean minus the
    // weighted sum's must be zero within six standard errors.
    const SEEDS: u64 = 12;
    let mut differences: std::collections::BTreeMap<(u32, u32), Vec<glam::DVec3>> =
        Default::default();
    for seed in 0..SEEDS {
        settings.seed = seed;
        settings.stop.spp = 16;
        let strategies = render_strategies(&scene, &settings, &options).unwrap();
        for k in 1..=4u32 {
            let of_length: Vec<_> = strategies.iter().filter(|i| i.s + i.t == k + 1).collect();
            let total: glam::Vec3 = of_length.iter().map(|i| i.weighted.mean()).sum();
            for i in &of_length {
                let d = (i.unweighted.mean() - total).as_dvec3() / total.as_dvec3();
                differences.entry((i.s, i.t)).or_default().push(d);
            }
        }
    }
    for ((s, t), d) in &differences {
        assert_eq!(
            d.len() as u64,
            SEEDS,
            "strategy ({s}, {t}) missing in some renders"
        );
        let n = d.len() as f64;
        let mean = d.iter().sum::<glam::DVec3>() / n;
        let var = d
            .iter()
            .map(|x| (*x - mean) * (*x - mean))
            .sum::<glam::DVec3>()
            / (n - 1.0);
        let stderr = (var / n).map(f64::sqrt);
        for c in 0..3 {
            assert!(
                mean[c].abs() <= 6.0 * stderr[c] + 2e-3,
                "s = {s}, t = {t}, channel {c}: unweighted mean off by {:.2}% ± {:.2}%",
                100.0 * mean[c],
                100.0 * stderr[c]
            );
        }
    }
}
