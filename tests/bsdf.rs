//! Each BSDF samples the directions its pdf describes, and the pdf integrates
//! to one: a chi-square test over a grid on the sphere, and binomial tests for
//! the delta lobes' choices.

mod common;

use common::Rng;
use glam::{Vec2, Vec3};
use std::f64::consts::PI;
use tracer::color::Rgb;
use tracer::material::{fresnel_dielectric, Albedo, Bsdf, Material, SurfacePoint, Transport};

const THETA_BINS: usize = 10;
const PHI_BINS: usize = 20;

fn surface(ng: Vec3, ns: Vec3) -> SurfacePoint {
    SurfacePoint {
        position: Vec3::ZERO,
        geometric_normal: ng,
        shading_normal: ns,
        uv: Vec2::ZERO,
        magnitude: 1.0,
    }
}

/// Bin of a world direction on a (cos θ, φ) grid over the whole sphere.
fn bin(w: Vec3) -> usize {
    let t = (((w.z + 1.0) * 0.5 * THETA_BINS as f32) as usize).min(THETA_BINS - 1);
    let phi = w.y.atan2(w.x).rem_euclid(2.0 * std::f32::consts::PI);
    let p = ((phi / (2.0 * std::f32::consts::PI) * PHI_BINS as f32) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + p
}

/// Expected probability of each bin, by integrating `pdf` on a fine grid
/// (uniform in cos θ and φ, so each cell has equal solid angle).
fn integrate_pdf(pdf: impl Fn(Vec3) -> f32) -> Vec<f64> {
    const SUB: usize = 24;
    let mut p = vec![0.0; THETA_BINS * PHI_BINS];
    let (nt, np) = (THETA_BINS * SUB, PHI_BINS * SUB);
    let cell = 4.0 * PI / (nt * np) as f64;
    for i in 0..nt {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / nt as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..np {
            let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            p[bin(w)] += pdf(w) as f64 * cell;
        }
    }
    p
}

/// Pearson's chi-square test, pooling sparse bins (expected < 5) into one.
/// Returns the statistic and its degrees of freedom.
fn chi_square(observed: &[u64], expected: &[f64]) -> (f64, usize) {
    let (mut stat, mut dof) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < 5.0 {
            pool_o += o as f64;
            pool_e += e;
        } else {
            stat += (o as f64 - e).powi(2) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e.max(5.0);
        dof += 1;
    }
    (stat, dof.saturating_sub(1))
}

/// Upper 0.1% quantile of chi-square with `k` degrees of freedom (Wilson–Hilferty).
fn chi_square_critical(k: usize) -> f64 {
    let k = k as f64;
    let z = 3.09; // one-sided 0.999 normal quantile
    k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
}

fn check_sampling_matches_pdf(bsdf: &Bsdf, wo: Vec3, seed: u64) {
    const N: usize = 200_000;
    let mut rng = Rng::new(seed);
    // One extra bin counts samples the BSDF refuses (wrong geometric side).
    let mut observed = vec![0u64; THETA_BINS * PHI_BINS + 1];
    for _ in 0..N {
        match bsdf.sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Radiance) {
            Some(s) => {
                assert!(s.pdf > 0.0 && s.pdf.is_finite());
                assert!((s.wi.length() - 1.0).abs() < 1e-4);
                // The sample's pdf and weight agree with pdf() and eval().
                let pdf = bsdf.pdf(wo, s.wi);
                assert!(
                    (pdf - s.pdf).abs() <= 1e-4 * s.pdf,
                    "pdf {pdf} vs sampled {}",
                    s.pdf
                );
                let expected_weight = bsdf.eval(wo, s.wi) / s.pdf;
                assert!(
                    expected_weight.abs_diff_eq(s.weight, 1e-4),
                    "{expected_weight} vs {}",
                    s.weight
                );
                observed[bin(s.wi)] += 1;
            }
            None => observed[THETA_BINS * PHI_BINS] += 1,
        }
    }
    let mut expected = integrate_pdf(|w| bsdf.pdf(wo, w));
    let total: f64 = expected.iter().sum();
    assert!(total <= 1.0 + 2e-3, "pdf integrates to {total} > 1");
    expected.push((1.0 - total).max(0.0));
    let expected: Vec<f64> = expected.iter().map(|p| p * N as f64).collect();
    let (stat, dof) = chi_square(&observed, &expected);
    let critical = chi_square_critical(dof);
    assert!(
        stat < critical,
        "chi-square {stat:.1} > {critical:.1} with {dof} degrees of freedom"
    );
}

fn diffuse() -> Material {
    Material::Diffuse {
        albedo: Albedo::Constant(Rgb::new(0.8, 0.5, 0.2)),
    }
}

#[test]
fn diffuse_pdf_integrates_to_one() {
    for wo in [
        Vec3::Z,
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(0.0, -0.99, 0.141),
    ] {
        let bsdf = diffuse().bsdf(&surface(Vec3::Z, Vec3::Z), wo.normalize());
        let total: f64 = integrate_pdf(|w| bsdf.pdf(wo, w)).iter().sum();
        assert!((total - 1.0).abs() < 2e-3, "integral {total}");
    }
}

#[test]
fn diffuse_sampling_matches_pdf() {
    let bsdf = diffuse().bsdf(
        &surface(Vec3::Z, Vec3::Z),
        Vec3::new(0.3, 0.2, 0.9).normalize(),
    );
    check_sampling_matches_pdf(&bsdf, Vec3::new(0.3, 0.2, 0.9).normalize(), 1);
}

#[test]
fn diffuse_sampling_matches_pdf_from_the_back_face() {
    // Arriving from below: the frame flips, and sampling follows.
    let wo = Vec3::new(0.1, 0.4, -0.8).normalize();
    let bsdf = diffuse().bsdf(&surface(Vec3::Z, Vec3::Z), wo);
    check_sampling_matches_pdf(&bsdf, wo, 2);
}

#[test]
fn diffuse_sampling_matches_pdf_with_tilted_shading_normal() {
    // Directions below the geometric surface are refused; the pdf says so too.
    let ns = Vec3::new(0.5, 0.0, 0.8).normalize();
    let wo = Vec3::new(-0.2, 0.3, 0.9).normalize();
    let bsdf = diffuse().bsdf(&surface(Vec3::Z, ns), wo);
    check_sampling_matches_pdf(&bsdf, wo, 3);
}

#[test]
fn mirror_reflects_about_the_normal() {
    let m = Material::Mirror {
        reflectance: Rgb::new(0.9, 0.8, 0.7),
    };
    let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
    let bsdf = m.bsdf(&surface(Vec3::Z, Vec3::Z), wo);
    let s = bsdf
        .sample(wo, (0.5, 0.5), 0.5, Transport::Radiance)
        .unwrap();
    assert!(s.delta);
    assert!(s.wi.abs_diff_eq(Vec3::new(-wo.x, -wo.y, wo.z), 1e-6));
    assert_eq!(s.weight, Rgb::new(0.9, 0.8, 0.7));
    assert_eq!(
        bsdf.eval(wo, s.wi),
        Rgb::ZERO,
        "a delta lobe has no finite value"
    );
    assert_eq!(bsdf.pdf(wo, s.wi), 0.0);
}

/// Reflection is chosen with probability F, refraction otherwise, and
/// refracted radiance scales by 1/η² (importance does not).
#[test]
fn dielectric_chooses_lobes_by_fresnel() {
    let glass = Material::Dielectric {
        ior: 1.5,
        transmittance: Rgb::ONE,
    };
    let mut rng = Rng::new(9);
    for (wo, outside) in [
        (Vec3::new(0.5, 0.1, 0.86).normalize(), true),
        (Vec3::new(0.2, 0.0, 0.98).normalize(), true),
        (Vec3::new(0.3, 0.2, -0.93).normalize(), false),
        // Beyond the critical angle from inside: total internal reflection.
        (Vec3::new(0.9, 0.0, -0.3).normalize(), false),
    ] {
        let bsdf = glass.bsdf(&surface(Vec3::Z, Vec3::Z), wo);
        let eta = if outside { 1.5 } else { 1.0 / 1.5 };
        let f = fresnel_dielectric(wo.z.abs(), eta) as f64;
        const N: usize = 100_000;
        let mut reflected = 0;
        for _ in 0..N {
            let s = bsdf
                .sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Radiance)
                .unwrap();
            assert!(s.delta);
            if s.wi.z * wo.z > 0.0 {
                reflected += 1;
                assert!(s.wi.abs_diff_eq(Vec3::new(-wo.x, -wo.y, wo.z), 1e-5));
                assert_eq!(s.weight, Rgb::ONE);
            } else {
                // Snell: sin θt = sin θi / η.
                let (si, st) = ((1.0 - wo.z * wo.z).sqrt(), (1.0 - s.wi.z * s.wi.z).sqrt());
                assert!((si - eta * st).abs() < 1e-4);
                assert!((s.weight.x - 1.0 / (eta * eta)).abs() < 1e-5);
                let imp = bsdf
                    .sample(wo, (0.5, 0.5), 0.999_999, Transport::Importance)
                    .unwrap();
                assert_eq!(imp.weight, Rgb::ONE);
            }
        }
        let p = reflected as f64 / N as f64;
        let sigma = (f * (1.0 - f) / N as f64).sqrt().max(1e-9);
        assert!(
            (p - f).abs() <= 5.0 * sigma + 1e-9,
            "reflected {p}, Fresnel {f}"
        );
    }
}
