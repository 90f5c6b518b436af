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
                (pdf - s.pdf).abs() <= 1e-3 * s.pdf,
                "pdf {pdf} vs sampled {}",
                s.pdf
            );
            let expected_weight = bsdf.eval(wo, s.wi) / s.pdf;
            assert!(
                expected_weight.abs_diff_eq(s.weight, 1e-3 * s.weight.max_element().max(0.1)),
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

/// The adjoint correction |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|) is exactly
/// one under flat shading, on both faces and at every angle, so light paths
/// scatter with the camera paths' weights there; with a tilted shading
/// normal it is not, and the weights differ.
#[test]
fn flat_shading_has_no_adjoint_correction() {
    let mut rng = Rng::new(5);
    for (ng, ns, flat) in [
        (Vec3::Z, Vec3::Z, true),
        (Vec3::Z, Vec3::new(0.3, 0.0, 1.0).normalize(), false),
    ] {
        let at = surface(ng, ns);
        let mut differ = 0;
        for _ in 0..2000 {
            let z = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
            let wo = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, z * rng.f32()).normalize();
            let bsdf = diffuse().bsdf(&at, wo);
            let u = (rng.f32(), rng.f32());
            let radiance = bsdf.sample(wo, u, 0.5, Transport::Radiance);
            let importance = bsdf.sample(wo, u, 0.5, Transport::Importance);
            match (radiance, importance) {
                (Some(r), Some(i)) if flat => assert_eq!(r.weight, i.weight, "wo {wo}"),
                (Some(r), Some(i)) => differ += (r.weight != i.weight) as u32,
                (r, i) => assert_eq!(r.is_some(), i.is_some(), "wo {wo}"),
            }
        }
        assert_eq!(differ > 1000, !flat, "{differ} of 2000 differ");
    }
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
                assert_eq!(s.eta, 1.0);
            } else {
                // Snell: sin θt = sin θi / η.
                let (si, st) = ((1.0 - wo.z * wo.z).sqrt(), (1.0 - s.wi.z * s.wi.z).sqrt());
                assert!((si - eta * st).abs() < 1e-4);
                assert!((s.weight.x - 1.0 / (eta * eta)).abs() < 1e-5);
                // The index crossed, which roulette uses to undo the 1/eta².
                assert!((s.eta - eta).abs() < 1e-6, "eta {} vs {eta}", s.eta);
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

#[test]
fn rough_glass_reports_the_index_it_crosses() {
    let mut rng = Rng::new(4);
    for (wo, eta) in [
        (Vec3::new(0.3, 0.1, 0.95).normalize(), 1.5),
        (Vec3::new(0.1, -0.2, -0.97).normalize(), 1.0 / 1.5),
    ] {
        let bsdf = rough_glass(0.3).bsdf(&surface(Vec3::Z, Vec3::Z), wo);
        let (mut reflections, mut refractions) = (0, 0);
        for _ in 0..10_000 {
            let u = (rng.f32(), rng.f32());
            let Some(s) = bsdf.sample(wo, u, rng.f32(), Transport::Radiance) else {
                continue;
            };
            if s.wi.z * wo.z > 0.0 {
                reflections += 1;
                assert_eq!(s.eta, 1.0);
            } else {
                refractions += 1;
                assert!((s.eta - eta).abs() < 1e-6, "eta {} vs {eta}", s.eta);
            }
        }
        assert!(reflections > 0 && refractions > 0);
    }
}

fn conductor(alpha: f32) -> Material {
    // Roughly gold: a complex index per channel.
    Material::Conductor {
        alpha,
        eta: Rgb::new(0.18, 0.42, 1.37),
        k: Rgb::new(3.42, 2.35, 1.77),
        reflectance: Rgb::new(1.0, 0.9, 0.8),
    }
}

fn rough_glass(alpha: f32) -> Material {
    Material::RoughDielectric {
        ior: 1.5,
        alpha,
        transmittance: Rgb::new(1.0, 0.9, 0.8),
    }
}

fn plastic(alpha: f32) -> Material {
    Material::plastic(Albedo::Constant(Rgb::new(0.7, 0.4, 0.2)), 1.5, alpha)
}

/// Several widths, from normal to grazing incidence, with the shading
/// normal equal to the geometric one and tilted.
fn microfacet_cases() -> Vec<(f32, Vec3, Vec3)> {
    let tilted = Vec3::new(0.3, -0.2, 0.93).normalize();
    vec![
        (0.1, Vec3::new(0.2, 0.1, 0.97), Vec3::Z),
        (0.3, Vec3::new(0.5, 0.1, 0.86), Vec3::Z),
        (0.6, Vec3::new(-0.9, 0.3, 0.3), Vec3::Z),
        (1.0, Vec3::Z, Vec3::Z),
        (0.3, Vec3::new(0.1, 0.3, 0.95), tilted),
    ]
}

#[test]
fn conductor_sampling_matches_pdf() {
    for (i, (alpha, wo, ns)) in microfacet_cases().into_iter().enumerate() {
        let wo = wo.normalize();
        let bsdf = conductor(alpha).bsdf(&surface(Vec3::Z, ns), wo);
        assert!(!bsdf.is_delta());
        check_sampling_matches_pdf(
            &format!("conductor alpha {alpha}, wo {wo}, ns {ns}"),
            &bsdf,
            wo,
            100 + i as u64,
        );
    }
}

#[test]
fn rough_dielectric_sampling_matches_pdf() {
    // Refraction narrows the lobe below 0.2, too narrow for the whole-sphere
    // grid to integrate: those widths are tested on a cap, below.
    let cases = microfacet_cases().into_iter().filter(|c| c.0 >= 0.2);
    for (i, (alpha, wo, ns)) in cases.enumerate() {
        // From outside, and the same direction from inside (eta inverted,
        // total internal reflection at the grazing angles).
        for side in [1.0, -1.0] {
            let wo = (wo * Vec3::new(1.0, 1.0, side)).normalize();
            let bsdf = rough_glass(alpha).bsdf(&surface(Vec3::Z, ns), wo);
            check_sampling_matches_pdf(
                &format!("rough dielectric alpha {alpha}, wo {wo}, ns {ns}"),
                &bsdf,
                wo,
                200 + 2 * i as u64 + (side < 0.0) as u64,
            );
        }
    }
}

/// Rough plastic from both faces: the coat's GGX lobe and the base's
/// cosine lobe, mixed by the coat's transmittance towards `wo`.
#[test]
fn plastic_sampling_matches_pdf() {
    for (i, (alpha, wo, ns)) in microfacet_cases().into_iter().enumerate() {
        for side in [1.0, -1.0] {
            // The same direction on the back face: the BSDF turns to face it.
            let wo = (wo * Vec3::new(1.0, 1.0, side)).normalize();
            let bsdf = plastic(alpha).bsdf(&surface(Vec3::Z, ns), wo);
            assert!(!bsdf.is_delta());
            check_sampling_matches_pdf(
                &format!("plastic alpha {alpha}, wo {wo}, ns {ns}"),
                &bsdf,
                wo,
                300 + 2 * i as u64 + (side < 0.0) as u64,
            );
        }
    }
}

/// A smooth coat: its mirror lobe is chosen with the probability the
/// sample reports (binomial test) and carries F / p; the other samples
/// follow the base's density, which integrates to the rest.
#[test]
fn smooth_plastic_mixes_a_mirror_and_the_base() {
    let material = plastic(0.0);
    for (k, wo) in [Vec3::new(0.1, 0.0, 0.99), Vec3::new(0.9, 0.2, 0.3)]
        .into_iter()
        .enumerate()
    {
        let wo = wo.normalize();
        let bsdf = material.bsdf(&surface(Vec3::Z, Vec3::Z), wo);
        let mut rng = Rng::new(40 + k as u64);
        let (n, mut mirrored, mut probability) = (100_000, 0, 0.0);
        for _ in 0..n {
            let s = bsdf
                .sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Radiance)
                .unwrap();
            if s.delta {
                mirrored += 1;
                probability = s.pdf;
                let fresnel = fresnel_dielectric(wo.z, 1.5);
                assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-5);
                assert!((s.weight - Rgb::splat(fresnel / s.pdf)).abs().max_element() < 1e-4);
            }
        }
        let expected = n as f64 * probability as f64;
        let sd = (expected * (1.0 - probability as f64)).sqrt();
        assert!(
            (mirrored as f64 - expected).abs() < 5.0 * sd,
            "mirror chosen {mirrored} times, expected {expected:.0} ± {sd:.0}"
        );
        chi_square::check(
            &format!("smooth plastic base, wo {wo}"),
            &SphereGrid::sphere(),
            200_000,
            50 + k as u64,
            |rng| {
                let s = bsdf.sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Radiance)?;
                (!s.delta).then_some((s.wi, s.pdf as f64))
            },
            |w| bsdf.pdf(wo, w) as f64,
        );
    }
}

/// A narrow lobe needs a fine grid: the cap around the normal, at normal incidence.
#[test]
fn narrow_microfacet_lobes_match_their_pdf() {
    for (what, material, grid) in [
        ("conductor", conductor(0.03), SphereGrid::band(0.95, 1.0)),
        (
            "rough dielectric",
            rough_glass(0.03),
            SphereGrid::band(0.95, 1.0),
        ),
        (
            "rough dielectric, refraction",
            rough_glass(0.1),
            SphereGrid::band(-1.0, -0.95),
        ),
    ] {
        let wo = Vec3::new(0.01, 0.0, 1.0).normalize();
        let bsdf = material.bsdf(&surface(Vec3::Z, Vec3::Z), wo);
        chi_square::check(
            &format!("{what}, alpha 0.03"),
            &grid,
            200_000,
            7,
            |rng| {
                let s = bsdf.sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Radiance)?;
                Some((s.wi, s.pdf as f64))
            },
            |w| bsdf.pdf(wo, w) as f64,
        );
    }
}

/// Light paths scatter with the adjoint BSDF: its weights match
/// `eval_mode(Importance) / pdf`, and it equals the radiance BSDF with the
/// directions swapped, seen from `wi`'s side (f*(wo, wi) = f(wi, wo)).
/// For reflection, that is plain reciprocity.
#[test]
fn microfacet_adjoint_is_the_swapped_bsdf() {
    let mut rng = Rng::new(11);
    for material in [
        conductor(0.4),
        rough_glass(0.2),
        rough_glass(0.7),
        plastic(0.3),
    ] {
        for (_, wo, _) in microfacet_cases() {
            for side in [1.0, -1.0] {
                let wo = (wo * Vec3::new(1.0, 1.0, side)).normalize();
                let at = surface(Vec3::Z, Vec3::Z);
                let bsdf = material.bsdf(&at, wo);
                for _ in 0..2000 {
                    let u = (rng.f32(), rng.f32());
                    let Some(s) = bsdf.sample(wo, u, rng.f32(), Transport::Importance) else {
                        continue;
                    };
                    let f_adjoint = bsdf.eval_mode(wo, s.wi, Transport::Importance);
                    assert!(
                        (f_adjoint / s.pdf).abs_diff_eq(s.weight, 2e-3 * s.weight.max_element()),
                        "{material:?}: weight {} vs {}",
                        s.weight,
                        f_adjoint / s.pdf
                    );
                    // The BSDF seen from wi, evaluated for radiance from wo.
                    let reverse = material.bsdf(&at, s.wi);
                    let f_swapped = reverse.eval(s.wi, wo);
                    let (cos_o, cos_i) = (wo.z.abs(), s.wi.z.abs());
                    let lhs = f_adjoint / cos_i;
                    let rhs = f_swapped / cos_o;
                    assert!(
                        lhs.abs_diff_eq(rhs, 2e-3 * lhs.max_element().max(1e-3)),
                        "{material:?}: wo {wo}, wi {}: f* {lhs} vs swapped f {rhs}",
                        s.wi
                    );
                    // The reverse density is the density of sampling wo from wi.
                    let (_, reverse_pdf) = bsdf.pdfs(wo, s.wi);
                    let expected = reverse.pdf(s.wi, wo);
                    assert!(
                        (reverse_pdf - expected).abs() <= 2e-3 * expected.max(1e-3),
                        "{material:?}: reverse pdf {reverse_pdf} vs {expected}"
                    );
                }
            }
        }
    }
}

/// Without absorption a rough glass surface loses nothing: reflection and
/// refraction together carry all the importance that arrives (estimated
/// by sampling; Smith masking makes single scattering lose a little at
/// large widths, so only narrow widths are held to 1%).
#[test]
fn rough_dielectric_conserves_importance_at_small_widths() {
    let mut rng = Rng::new(12);
    let glass = Material::RoughDielectric {
        ior: 1.5,
        alpha: 0.05,
        transmittance: Rgb::ONE,
    };
    for wo in [
        Vec3::Z,
        Vec3::new(0.5, 0.0, 0.86),
        Vec3::new(0.3, 0.0, -0.95),
    ] {
        let wo = wo.normalize();
        let bsdf = glass.bsdf(&surface(Vec3::Z, Vec3::Z), wo);
        const N: usize = 200_000;
        let mut total = 0.0f64;
        for _ in 0..N {
            if let Some(s) =
                bsdf.sample(wo, (rng.f32(), rng.f32()), rng.f32(), Transport::Importance)
            {
                total += s.weight.x as f64;
            }
        }
        let albedo = total / N as f64;
        assert!((albedo - 1.0).abs() < 0.01, "wo {wo}: albedo {albedo}");
    }
}

#[test]
fn smooth_widths_are_delta_lobes() {
    let wo = Vec3::new(0.3, 0.0, 0.95).normalize();
    let at = surface(Vec3::Z, Vec3::Z);
    let metal = conductor(0.0).bsdf(&at, wo);
    assert!(metal.is_delta());
    let s = metal
        .sample(wo, (0.3, 0.7), 0.5, Transport::Radiance)
        .unwrap();
    assert!(s.delta && s.wi.abs_diff_eq(Vec3::new(-wo.x, -wo.y, wo.z), 1e-6));
    let f = tracer::material::fresnel_conductor(
        wo.z,
        Rgb::new(0.18, 0.42, 1.37),
        Rgb::new(3.42, 2.35, 1.77),
    );
    assert!(s.weight.abs_diff_eq(f * Rgb::new(1.0, 0.9, 0.8), 1e-6));
    assert!(rough_glass(0.0).bsdf(&at, wo).is_delta());
}
