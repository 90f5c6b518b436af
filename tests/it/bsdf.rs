//! Each BSDF samples the directions its pdf describes, and the pdf integrates
//! to one: a chi-square test over a grid on the sphere (`common::chi_square`),
//! and binomial tests for the delta lobes' choices.

use crate::common::chi_square::{self, Grid, SphereGrid};
use crate::common::Rng;
use glam::{Vec2, Vec3};
use tracer::color::Rgb;
use tracer::geometry::SurfacePoint;
use tracer::material::{fresnel_dielectric, Albedo, Bsdf, Material, Transport};

fn surface(ng: Vec3, ns: Vec3) -> SurfacePoint {
    SurfacePoint {
        position: Vec3::ZERO,
        geometric_normal: ng,
        shading_normal: ns,
        uv: Vec2::ZERO,
        magnitude: 1.0,
    }
}

/// Samples the BSDF (200 000 times) and checks each sample's pdf and weight
/// against `pdf()` and `eval()`, then the directions against the pdf with a
/// chi-square test over the whole sphere. Refused samples (wrong geometric
/// side) count in one more bin, expecting the probability the pdf misses.
fn check_sampling_matches_pdf(what: &str, bsdf: &Bsdf, wo: Vec3, seed: u64) {
    const N: usize = 200_000;
    chi_square::check(
        what,
        &SphereGrid::sphere(),
        N,
        seed,
        |rng| {
            let s = bsdf.sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Radiance)?;
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
            Some((s.wi, s.pdf as f64))
        },
        |w| bsdf.pdf(wo, w) as f64,
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
        let total: f64 = SphereGrid::sphere()
            .integrate(&|w| bsdf.pdf(wo, w) as f64)
            .iter()
            .sum();
        assert!((total - 1.0).abs() < 2e-3, "integral {total}");
    }
}

#[test]
fn diffuse_sampling_matches_pdf() {
    let bsdf = diffuse().bsdf(
        &surface(Vec3::Z, Vec3::Z),
        Vec3::new(0.3, 0.2, 0.9).normalize(),
    );
    check_sampling_matches_pdf("diffuse", &bsdf, Vec3::new(0.3, 0.2, 0.9).normalize(), 1);
}

#[test]
fn diffuse_sampling_matches_pdf_from_the_back_face() {
    // Arriving from below: the frame flips, and sampling follows.
    let wo = Vec3::new(0.1, 0.4, -0.8).normalize();
    let bsdf = diffuse().bsdf(&surface(Vec3::Z, Vec3::Z), wo);
    check_sampling_matches_pdf("diffuse, back face", &bsdf, wo, 2);
}

#[test]
fn diffuse_sampling_matches_pdf_with_tilted_shading_normal() {
    // Directions below the geometric surface are refused; the pdf says so too.
    let ns = Vec3::new(0.5, 0.0, 0.8).normalize();
    let wo = Vec3::new(-0.2, 0.3, 0.9).normalize();
    let bsdf = diffuse().bsdf(&surface(Vec3::Z, ns), wo);
    check_sampling_matches_pdf("diffuse, tilted shading normal", &bsdf, wo, 3);
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
