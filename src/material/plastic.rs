//! Plastic: a diffuse base under a smooth or GGX-rough dielectric coat,
//! defined as Mitsuba 3's `plastic` and `roughplastic` (non-linear mode
//! off) so that images of the same scene agree.
//!
//! Light either reflects off the coat (Fresnel, or the GGX lobe of a rough
//! coat) or enters it, scatters diffusely in the base and leaves again.
//! The diffuse part is `ρ / (1 − Ri) · (1/π) · (1/η²) · T(wo) · T(wi)`: the
//! coat lets `T(cos)` through on the way in and on the way out, light
//! bouncing inside between the coat and the base adds the geometric series
//! `1 / (1 − Ri)` with `Ri` the coat's reflectance from inside averaged over
//! the diffuse base's cosine-weighted directions, and `1/η²` is the radiance
//! compression of refraction. For a smooth coat `T` is `1 − F` and `Ri` the
//! Egan–Hilgeman fit of the diffuse Fresnel reflectance; for a rough coat
//! both come from integrating the GGX coat over its visible normals, once per
//! (alpha, η), with Gauss–Legendre quadrature as Mitsuba does (64
//! tabulated cosines, `T` interpolated linearly between them).
//!
//! The lobes are chosen in proportion to `(1 − T(wo)) · s` for the coat and
//! `T(wo) · (1 − s)` for the base, with `s = 1 / (mean albedo + 1)`.
//! Both the BSDF and that choice are symmetric in the two directions, so
//! light paths use the same BSDF (no adjoint correction).

use super::dielectric::fresnel_dielectric;
use super::microfacet::{Ggx, SMOOTH_ALPHA};
use super::{reflect, reflect_local};
use crate::color::Rgb;
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::f32::consts::FRAC_1_PI;
use std::sync::{Mutex, OnceLock};

/// Cosines at which the rough coat's transmittance is tabulated.
const TABLE_SIZE: usize = 64;

/// The rough coat's transmittance and internal reflectance, for one
/// (alpha, η): computed once per process and shared (leaked, so that a
/// [`Plastic`] stays `Copy`; there is one per distinct coat).
#[derive(Debug)]
pub struct CoatTables {
    /// Transmittance into the coat at cos θ = i / 63 (the first at 1e-6).
    transmittance: [f32; TABLE_SIZE],
    /// Reflectance of the coat from inside, cosine-weighted over directions.
    internal_reflectance: f32,
}

/// A plastic BSDF at a surface point.
#[derive(Clone, Copy, Debug)]
pub struct Plastic {
    /// GGX width of the coat; at most [`SMOOTH_ALPHA`] for a smooth coat.
    pub alpha: f32,
    /// Index of refraction of the coat; > 0.
    pub eta: f32,
    /// Reflectance of the diffuse base at this point.
    pub albedo: Rgb,
    /// `1 / (mean albedo + 1)`: the coat's share in choosing a lobe.
    pub specular_weight: f32,
    /// The rough coat's tables; `None` for a smooth coat.
    pub tables: Option<&'static CoatTables>,
}

/// The share of sampling given to the coat, from the material's mean albedo
/// (over the texture, if it has one), as Mitsuba computes it.
pub fn specular_weight(mean_albedo: f32) -> f32 {
    1.0 / (mean_albedo.max(0.0) + 1.0)
}

/// The rough coat's tables for (`alpha`, `eta`), computed on first use.
pub fn coat_tables(alpha: f32, eta: f32) -> &'static CoatTables {
    static TABLES: OnceLock<Mutex<HashMap<(u32, u32), &'static CoatTables>>> = OnceLock::new();
    let tables = TABLES.get_or_init(Default::default);
    let key = (alpha.to_bits(), eta.to_bits());
    if let Some(t) = tables.lock().unwrap().get(&key) {
        return t;
    }
    // Computed without the lock, so coats of different widths build in
    // parallel; a coat computed twice at once is kept once.
    let computed = CoatTables::new(alpha, eta);
    tables
        .lock()
        .unwrap()
        .entry(key)
        .or_insert_with(|| Box::leak(Box::new(computed)))
}

impl CoatTables {
    fn new(alpha: f32, eta: f32) -> CoatTables {
        // Mitsuba's resolutions: 32 nodes per axis entering a denser
        // medium, 128 leaving it (total internal reflection makes that
        // integrand less smooth).
        let nodes_in = gauss_legendre_01(if eta > 1.0 { 32 } else { 128 });
        let nodes_out = gauss_legendre_01(if 1.0 / eta > 1.0 { 32 } else { 128 });
        let (alpha, eta) = (alpha as f64, eta as f64);
        // About 75 ms of quadrature per coat on one core, paid at load:
        // the 64 cosines are independent, so they run on the pool. The sum
        // below is taken in index order, so the tables do not depend on it.
        let rows: Vec<(f32, f64)> = (0..TABLE_SIZE)
            .into_par_iter()
            .map(|i| {
                let mu = (i as f64 / (TABLE_SIZE - 1) as f64).max(1e-6);
                let wi = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                (
                    coat_integral(alpha, wi, eta, &nodes_in, true) as f32,
                    coat_integral(alpha, wi, 1.0 / eta, &nodes_out, false) * mu,
                )
            })
            .collect();
        let transmittance = std::array::from_fn(|i| rows[i].0);
        let internal: f64 = rows.iter().map(|r| r.1).sum();
        CoatTables {
            transmittance,
            // Mitsuba's estimate of 2 ∫ R(μ) μ dμ: the plain mean over the table's cosines.
            internal_reflectance: (2.0 * internal / TABLE_SIZE as f64) as f32,
        }
    }

    /// Transmittance into the coat at `cos` in (0, 1], interpolated linearly.
    fn transmittance(&self, cos: f32) -> f32 {
        let x = cos * (TABLE_SIZE - 1) as f32;
        let i = (x.max(0.0) as usize).min(TABLE_SIZE - 2);
        let f = x - i as f32;
        self.transmittance[i] * (1.0 - f) + self.transmittance[i + 1] * f
    }
}

/// ∫ over the normals visible from `wi` of the light the coat lets
/// through (`transmit`: `G1(wo) (1 − F)` for the refracted `wo`) or
/// reflects back above it (`G1(wo) F` for the mirrored `wo`); `eta` is
/// the index on the far side relative to `wi`'s side. In f64, with the
/// quadrature nodes mapped to normals exactly as Mitsuba maps them (its
/// concentric-disk form of Heitz's sampler), so the tables agree with its
/// own to about 1e-6 rather than to the quadrature's error.
fn coat_integral(alpha: f64, wi: DVec3, eta: f64, nodes: &[(f64, f64)], transmit: bool) -> f64 {
    let mut sum = 0.0f64;
    for &(x, wx) in nodes {
        for &(y, wy) in nodes {
            let m = tabulation_normal(alpha, wi, x, y);
            let cos = wi.dot(m);
            let (f, cos_t) = fresnel_f64(cos, eta);
            let value = if transmit {
                // Snell's law through the facet, into the far side.
                let wo = m * (cos / eta - cos_t) - wi / eta;
                if wo.z * wi.z >= 0.0 {
                    continue;
                }
                g1_f64(alpha, wo, m) * (1.0 - f)
            } else {
                let wo = 2.0 * cos * m - wi;
                if wo.z <= 0.0 {
                    continue;
                }
                g1_f64(alpha, wo, m) * f
            };
            sum += value * wx * wy;
        }
    }
    sum
}

/// The visible normal for `wi` at sample (`s1`, `s2`), as Mitsuba's GGX
/// sampler computes it.
fn tabulation_normal(alpha: f64, wi: DVec3, s1: f64, s2: f64) -> DVec3 {
    use std::f64::consts::FRAC_PI_4;
    let stretched = DVec3::new(alpha * wi.x, alpha * wi.y, wi.z).normalize();
    let (cos_theta, sin_theta) = (stretched.z, stretched.x.hypot(stretched.y));
    // Shirley and Chiu's concentric map of the square onto the disk.
    let (a, b) = (2.0 * s1 - 1.0, 2.0 * s2 - 1.0);
    let (r, phi) = if a == 0.0 && b == 0.0 {
        (0.0, 0.0)
    } else if a.abs() < b.abs() {
        (b, 2.0 * FRAC_PI_4 - FRAC_PI_4 * a / b)
    } else {
        (a, FRAC_PI_4 * b / a)
    };
    let (px, mut py) = (r * phi.cos(), r * phi.sin());
    let s = 0.5 * (1.0 + cos_theta);
    py = (1.0 - s) * (1.0 - px * px).max(0.0).sqrt() + s * py;
    let z = (1.0 - px * px - py * py).max(0.0).sqrt();
    let norm = 1.0 / (sin_theta * py + cos_theta * z);
    let (slope_x, slope_y) = ((cos_theta * py - sin_theta * z) * norm, px * norm);
    let (cos_phi, sin_phi) = if sin_theta == 0.0 {
        (1.0, 0.0)
    } else {
        (stretched.x / sin_theta, stretched.y / sin_theta)
    };
    let sx = (cos_phi * slope_x - sin_phi * slope_y) * alpha;
    let sy = (sin_phi * slope_x + cos_phi * slope_y) * alpha;
    DVec3::new(-sx, -sy, 1.0).normalize()
}

/// GGX masking as [`Ggx::g1`], in f64.
fn g1_f64(alpha: f64, v: DVec3, m: DVec3) -> f64 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    let xy = alpha * alpha * (v.x * v.x + v.y * v.y);
    if xy == 0.0 {
        return 1.0;
    }
    2.0 / (1.0 + (1.0 + xy / (v.z * v.z)).sqrt())
}

/// Unpolarised Fresnel reflectance for `cos` > 0 on the side of index 1,
/// into index `eta`, and the cosine of the refracted ray (0 under total
/// internal reflection, where the reflectance is 1).
fn fresnel_f64(cos: f64, eta: f64) -> (f64, f64) {
    let cos_t2 = 1.0 - (1.0 - cos * cos) / (eta * eta);
    if cos_t2 <= 0.0 || cos <= 0.0 {
        return (1.0, 0.0);
    }
    let cos_t = cos_t2.sqrt();
    let a_s = (cos - eta * cos_t) / (cos + eta * cos_t);
    let a_p = (cos_t - eta * cos) / (cos_t + eta * cos);
    (0.5 * (a_s * a_s + a_p * a_p), cos_t)
}

/// Gauss–Legendre nodes and weights on [0, 1] (weights summing to one).
fn gauss_legendre_01(n: usize) -> Vec<(f64, f64)> {
    use std::f64::consts::PI;
    (0..n)
        .map(|i| {
            // Newton's method on P_n from the Chebyshev-like first guess.
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut derivative = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / derivative;
                x -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
            (0.5 * x + 0.5, 0.5 * weight)
        })
        .collect()
}

/// Egan and Hilgeman's fit of the diffuse Fresnel reflectance from inside
/// a medium of index `eta` (relative to outside); Mitsuba's
/// `fresnel_diffuse_reflectance(1/eta)`.
fn internal_diffuse_reflectance(eta: f32) -> f32 {
    let e = 1.0 / eta;
    if e < 1.0 {
        0.0636 / e + e * (e * -1.4399 + 0.7099) + 0.6681
    } else {
        // d'Eon and Irving's fit, for a coat less dense than the outside.
        let x = 1.0 / e;
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &k| acc * x + k)
    }
}

impl Plastic {
    /// Whether the coat is smooth (a delta lobe on top of the diffuse one).
    pub fn is_smooth(&self) -> bool {
        self.tables.is_none()
    }

    /// Transmittance through the coat at `cos`, and the diffuse factor
    /// `ρ / (1 − Ri) / η²`.
    fn coat(&self) -> (Rgb, f32) {
        let ri = match self.tables {
            Some(t) => t.internal_reflectance,
            None => internal_diffuse_reflectance(self.eta),
        };
        (self.albedo / (1.0 - ri), 1.0 / (self.eta * self.eta))
    }

    fn transmittance(&self, cos: f32) -> f32 {
        match self.tables {
            Some(t) => t.transmittance(cos),
            None => 1.0 - fresnel_dielectric(cos, self.eta),
        }
    }

    /// Probability of choosing the coat's lobe when leaving towards `wo`,
    /// given the coat's transmittance there.
    fn coat_probability(&self, t_o: f32) -> f32 {
        let coat = (1.0 - t_o) * self.specular_weight;
        let base = t_o * (1.0 - self.specular_weight);
        if coat + base <= 0.0 {
            return 0.0;
        }
        coat / (coat + base)
    }

    /// `f · cos θi` for local directions on the normal's side; the smooth
    /// coat's delta lobe is left out.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let (base, compression) = self.coat();
        let diffuse = base
            * (FRAC_1_PI
                * compression
                * wi.z
                * self.transmittance(wo.z)
                * self.transmittance(wi.z));
        if self.is_smooth() {
            return diffuse;
        }
        let ggx = Ggx { alpha: self.alpha };
        let h = (wo + wi).normalize();
        let specular =
            fresnel_dielectric(wo.dot(h), self.eta) * ggx.d(h) * ggx.g1(wo, h) * ggx.g1(wi, h)
                / (4.0 * wo.z);
        diffuse + Rgb::splat(specular)
    }

    /// Density of sampling `wi` from `wo`, per solid angle (the delta lobe left out).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p_coat = self.coat_probability(self.transmittance(wo.z));
        let diffuse = (1.0 - p_coat) * cosine_hemisphere_pdf(wi.z);
        if self.is_smooth() {
            return diffuse;
        }
        let h = (wo + wi).normalize();
        let ggx = Ggx { alpha: self.alpha };
        diffuse + p_coat * ggx.visible_pdf(wo, h) / (4.0 * wo.dot(h))
    }

    /// Returns (wi, weight, pdf, delta): the coat's reflection (mirror or
    /// GGX) with the coat's probability (see `coat_probability`), else a
    /// cosine-distributed direction into the base.
    #[inline(never)]
    pub fn sample(&self, wo: Vec3, u: (f32, f32), u_lobe: f32) -> Option<(Vec3, Rgb, f32, bool)> {
        if wo.z <= 0.0 {
            return None;
        }
        let t_o = self.transmittance(wo.z);
        let p_coat = self.coat_probability(t_o);
        if self.is_smooth() {
            if u_lobe < p_coat {
                let fresnel = 1.0 - t_o;
                return Some((
                    reflect_local(wo),
                    Rgb::splat(fresnel / p_coat),
                    p_coat,
                    true,
                ));
            }
            let wi = cosine_hemisphere(u.0, u.1);
            let pdf = (1.0 - p_coat) * cosine_hemisphere_pdf(wi.z);
            if pdf <= 0.0 {
                return None;
            }
            return Some((wi, self.eval(wo, wi) / pdf, pdf, false));
        }
        let wi = if u_lobe < p_coat {
            let ggx = Ggx { alpha: self.alpha };
            let m = ggx.sample_visible(wo, u);
            let cos = wo.dot(m);
            if cos <= 0.0 {
                return None;
            }
            reflect(wo, m, cos)
        } else {
            cosine_hemisphere(u.0, u.1)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some((wi, self.eval(wo, wi) / pdf, pdf, false))
    }
}

/// Whether a coat of width `alpha` is rough (it gets tables); at or below
/// [`SMOOTH_ALPHA`] it is smooth.
pub fn is_rough(alpha: f32) -> bool {
    alpha > SMOOTH_ALPHA
}

#[cfg(test)]
mod tests {
    use super::*;

    fn direction(theta_deg: f32, phi_deg: f32) -> Vec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in [32, 128] {
            let nodes = gauss_legendre_01(n);
            let total: f64 = nodes.iter().map(|&(_, w)| w).sum();
            let cubic: f64 = nodes.iter().map(|&(x, w)| w * x * x * x).sum();
            assert!((total - 1.0).abs() < 1e-12 && (cubic - 0.25).abs() < 1e-12);
        }
    }

    /// The coat's tables against Mitsuba 3.9.1's `roughplastic` (GGX, η 1.5),
    /// printed by its own constructor.
    #[test]
    fn coat_tables_match_mitsuba() {
        for (alpha, ri, t) in [
            (
                0.1,
                0.551894,
                [
                    (0.1, 0.610055),
                    (0.25, 0.763811),
                    (0.5, 0.906497),
                    (1.0, 0.959559),
                ],
            ),
            (
                0.3,
                0.414862,
                [
                    (0.1, 0.714417),
                    (0.25, 0.795487),
                    (0.5, 0.886447),
                    (1.0, 0.953159),
                ],
            ),
        ] {
            let tables = coat_tables(alpha, 1.5);
            assert!(
                (tables.internal_reflectance - ri).abs() < 2e-5,
                "alpha {alpha}: Ri {} vs {ri}",
                tables.internal_reflectance
            );
            for (mu, want) in t {
                let got = tables.transmittance(mu);
                assert!(
                    (got - want).abs() < 2e-5,
                    "alpha {alpha}, cos {mu}: T {got} vs {want}"
                );
            }
        }
    }

    /// `f · cos` and the density against Mitsuba 3.9.1's `roughplastic`
    /// (GGX, albedo 0.5, η 1.5) and `plastic`, at directions given as
    /// (θ, φ) in degrees: (Mitsuba's wi = our wo, wo = wi, value, pdf).
    #[test]
    #[allow(clippy::excessive_precision)] // Mitsuba's printed values, as printed.
    fn values_match_mitsuba() {
        type Case = ((f32, f32), (f32, f32), f32, f32);
        let rough: [(f32, &[Case]); 2] = [
            (
                0.1,
                &[
                    ((0.0, 0.0), (0.0, 0.0), 4.636550e-01, 9.121797e-01),
                    ((30.0, 0.0), (30.0, 180.0), 5.060592e-01, 1.013219e+00),
                    ((60.0, 0.0), (0.0, 0.0), 1.382970e-01, 2.679485e-01),
                    ((45.0, 0.0), (50.0, 170.0), 2.286839e-01, 4.506333e-01),
                    ((20.0, 30.0), (70.0, 250.0), 4.385567e-02, 1.013779e-01),
                    ((10.0, 0.0), (85.0, 0.0), 7.997296e-03, 2.578864e-02),
                ],
            ),
            (
                0.3,
                &[
                    ((0.0, 0.0), (0.0, 0.0), 1.451949e-01, 3.689507e-01),
                    ((60.0, 0.0), (60.0, 180.0), 1.869482e-01, 4.658276e-01),
                    ((80.0, 0.0), (80.0, 180.0), 9.051455e-01, 1.370975e+00),
                    ((35.0, 0.0), (10.0, 90.0), 1.173970e-01, 3.081545e-01),
                ],
            ),
        ];
        let smooth: &[Case] = &[
            ((0.0, 0.0), (0.0, 0.0), 1.616856e-01, 2.938245e-01),
            ((30.0, 0.0), (30.0, 180.0), 1.395800e-01, 2.536845e-01),
            ((80.0, 0.0), (45.0, 90.0), 7.214214e-02, 9.931144e-02),
            ((10.0, 0.0), (85.0, 0.0), 5.683620e-03, 2.560770e-02),
        ];
        let cases = rough
            .iter()
            .map(|&(alpha, c)| (Some(coat_tables(alpha, 1.5)), alpha, c))
            .chain([(None, 0.0, smooth)]);
        for (tables, alpha, cases) in cases {
            let plastic = Plastic {
                alpha,
                eta: 1.5,
                albedo: Rgb::splat(0.5),
                specular_weight: specular_weight(0.5),
                tables,
            };
            for &(wo, wi, value, pdf) in cases {
                let (wo, wi) = (direction(wo.0, wo.1), direction(wi.0, wi.1));
                let got = plastic.eval(wo, wi).x;
                let got_pdf = plastic.pdf(wo, wi);
                assert!(
                    (got - value).abs() < 2e-4 * value,
                    "alpha {alpha} {wo} {wi}: f·cos {got} vs {value}"
                );
                assert!(
                    (got_pdf - pdf).abs() < 2e-4 * pdf,
                    "alpha {alpha} {wo} {wi}: pdf {got_pdf} vs {pdf}"
                );
            }
        }
    }

    #[test]
    fn the_bsdf_is_symmetric() {
        let plastic = Plastic {
            alpha: 0.2,
            eta: 1.4,
            albedo: Rgb::new(0.8, 0.3, 0.1),
            specular_weight: specular_weight(0.4),
            tables: Some(coat_tables(0.2, 1.4)),
        };
        for (a, b) in [((10.0, 0.0), (50.0, 120.0)), ((70.0, 30.0), (20.0, 200.0))] {
            let (wo, wi) = (direction(a.0, a.1), direction(b.0, b.1));
            let forward = plastic.eval(wo, wi) / wi.z;
            let backward = plastic.eval(wi, wo) / wo.z;
            assert!((forward - backward).abs().max_element() < 1e-5 * forward.max_element());
        }
    }
}
