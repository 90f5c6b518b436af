//! Pearson's chi-square goodness-of-fit test of a sampling routine against
//! the density it claims: samples are counted in the cells of a [`Grid`],
//! each cell's expected count comes from integrating the density over it,
//! cells expecting fewer than [`MIN_EXPECTED`] samples are pooled, and the
//! statistic's p-value comes from the chi-square distribution (a regularized
//! incomplete gamma function, written out below).
//!
//! Every test in the suite uses the same significance, [`SIGNIFICANCE`]: a
//! family-wise false-alarm rate of [`FAMILY_SIGNIFICANCE`] split evenly
//! (Bonferroni) over at most [`MAX_TESTS`] tests. The samples come from
//! fixed seeds, so a run is reproducible; the significance says how likely
//! a correct sampler would be to fail under some other seed.

use super::Rng;
use glam::{DVec2, DVec3, Vec2, Vec3};
use std::f64::consts::PI;
use std::fmt::Debug;

/// The chance that any chi-square test of the suite fails while every
/// sampler is right.
pub const FAMILY_SIGNIFICANCE: f64 = 1e-3;

/// At most this many chi-square tests in the suite (there are about twenty).
pub const MAX_TESTS: f64 = 100.0;

/// The p-value below which one test fails.
pub const SIGNIFICANCE: f64 = FAMILY_SIGNIFICANCE / MAX_TESTS;

/// Cells expecting fewer samples than this are pooled: Pearson's statistic
/// is only close to chi-square distributed when every count is large enough.
pub const MIN_EXPECTED: f64 = 5.0;

/// How closely the density a sampler reports for its sample must match the
/// density function there (relative).
const PDF_TOLERANCE: f64 = 1e-3;

/// A grid of cells over a domain, each sample falling in one cell or outside.
pub trait Grid {
    type Point: Copy + Debug;
    fn cells(&self) -> usize;
    /// The cell holding `p`, or `None` when `p` is outside the grid.
    fn cell(&self, p: Self::Point) -> Option<usize>;
    /// The integral of `density` over every cell.
    fn integrate(&self, density: &dyn Fn(Self::Point) -> f64) -> Vec<f64>;
    /// Where a cell is, for messages.
    fn describe(&self, cell: usize) -> String;
}

/// Each cell is split into `SUB × SUB` parts, and the density is taken at
/// one point in each, jittered within the part by a fixed sequence (R2): a
/// smooth density is integrated about as well as by the midpoint rule, and
/// an edge of the density's support that runs along the parts (a cone's
/// rim, a triangle's diagonal, which would pass exactly through midpoints)
/// errs both ways instead of always one way. With 64 × 64 parts a cell's
/// integral is good to about 1e-4 of the total even for a large triangle
/// seen up close; 24 × 24 was off by 4e-3 there, enough to bias the test.
const SUB: usize = 64;

fn jitter(k: usize) -> (f64, f64) {
    // The plastic number's inverse powers: the R2 low-discrepancy sequence.
    const G: f64 = 1.324_717_957_244_746;
    let k = k as f64;
    ((0.5 + k / G).fract(), (0.5 + k / (G * G)).fract())
}

/// Which part of `[0, 1]` `t` is in, out of `n`; `None` outside (with a
/// little slack for rounding at the ends).
fn slot(t: f64, n: usize) -> Option<usize> {
    if !(-1e-6..=1.0 + 1e-6).contains(&t) {
        return None;
    }
    Some(((t * n as f64).max(0.0) as usize).min(n - 1))
}

/// Directions in the band `z.0 ≤ cos θ ≤ z.1` around +z, cut uniformly in
/// cos θ and in φ, so all cells have the same solid angle. The density is
/// per unit solid angle.
pub struct SphereGrid {
    pub z: (f64, f64),
    pub z_bins: usize,
    pub phi_bins: usize,
}

impl SphereGrid {
    /// The whole sphere, 10 × 20 cells.
    pub fn sphere() -> SphereGrid {
        SphereGrid::band(-1.0, 1.0)
    }

    /// The band `z_min ≤ cos θ ≤ z_max`, 10 × 20 cells.
    pub fn band(z_min: f64, z_max: f64) -> SphereGrid {
        assert!(-1.0 <= z_min && z_min < z_max && z_max <= 1.0);
        SphereGrid {
            z: (z_min, z_max),
            z_bins: 10,
            phi_bins: 20,
        }
    }

    fn direction(z: f64, phi: f64) -> Vec3 {
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3()
    }
}

impl Grid for SphereGrid {
    type Point = Vec3;

    fn cells(&self) -> usize {
        self.z_bins * self.phi_bins
    }

    fn cell(&self, w: Vec3) -> Option<usize> {
        let w = w.as_dvec3();
        let t = (w.z - self.z.0) / (self.z.1 - self.z.0);
        let phi = w.y.atan2(w.x).rem_euclid(2.0 * PI);
        let p = ((phi / (2.0 * PI) * self.phi_bins as f64) as usize).min(self.phi_bins - 1);
        Some(slot(t, self.z_bins)? * self.phi_bins + p)
    }

    fn integrate(&self, density: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let dz = (self.z.1 - self.z.0) / self.z_bins as f64;
        let dphi = 2.0 * PI / self.phi_bins as f64;
        let part = dz * dphi / (SUB * SUB) as f64;
        (0..self.cells())
            .map(|c| {
                let (zi, pi) = (c / self.phi_bins, c % self.phi_bins);
                let mut sum = 0.0;
                for k in 0..SUB * SUB {
                    let (a, b) = jitter(k);
                    let z = self.z.0 + dz * (zi as f64 + ((k / SUB) as f64 + a) / SUB as f64);
                    let phi = dphi * (pi as f64 + ((k % SUB) as f64 + b) / SUB as f64);
                    sum += density(Self::direction(z, phi));
                }
                sum * part
            })
            .collect()
    }

    fn describe(&self, c: usize) -> String {
        let dz = (self.z.1 - self.z.0) / self.z_bins as f64;
        let z0 = self.z.0 + dz * (c / self.phi_bins) as f64;
        let phi0 = 360.0 * (c % self.phi_bins) as f64 / self.phi_bins as f64;
        format!(
            "cos θ {z0:.3}..{:.3}, φ {phi0:.0}°..{:.0}°",
            z0 + dz,
            phi0 + 360.0 / self.phi_bins as f64
        )
    }
}

/// Points in the rectangle `x.0..x.1` × `y.0..y.1`, cut into equal cells.
/// The density is per unit area.
pub struct PlaneGrid {
    pub x: (f64, f64),
    pub y: (f64, f64),
    pub x_bins: usize,
    pub y_bins: usize,
}

impl PlaneGrid {
    /// `bins × bins` cells over the rectangle.
    pub fn new(x: (f64, f64), y: (f64, f64), bins: usize) -> PlaneGrid {
        PlaneGrid {
            x,
            y,
            x_bins: bins,
            y_bins: bins,
        }
    }
}

impl Grid for PlaneGrid {
    type Point = Vec2;

    fn cells(&self) -> usize {
        self.x_bins * self.y_bins
    }

    fn cell(&self, p: Vec2) -> Option<usize> {
        let p = p.as_dvec2();
        let i = slot((p.x - self.x.0) / (self.x.1 - self.x.0), self.x_bins)?;
        let j = slot((p.y - self.y.0) / (self.y.1 - self.y.0), self.y_bins)?;
        Some(j * self.x_bins + i)
    }

    fn integrate(&self, density: &dyn Fn(Vec2) -> f64) -> Vec<f64> {
        let dx = (self.x.1 - self.x.0) / self.x_bins as f64;
        let dy = (self.y.1 - self.y.0) / self.y_bins as f64;
        let part = dx * dy / (SUB * SUB) as f64;
        (0..self.cells())
            .map(|c| {
                let (i, j) = (c % self.x_bins, c / self.x_bins);
                let mut sum = 0.0;
                for k in 0..SUB * SUB {
                    let (a, b) = jitter(k);
                    let x = self.x.0 + dx * (i as f64 + ((k % SUB) as f64 + a) / SUB as f64);
                    let y = self.y.0 + dy * (j as f64 + ((k / SUB) as f64 + b) / SUB as f64);
                    sum += density(DVec2::new(x, y).as_vec2());
                }
                sum * part
            })
            .collect()
    }

    fn describe(&self, c: usize) -> String {
        let dx = (self.x.1 - self.x.0) / self.x_bins as f64;
        let dy = (self.y.1 - self.y.0) / self.y_bins as f64;
        let (x0, y0) = (
            self.x.0 + dx * (c % self.x_bins) as f64,
            self.y.0 + dy * (c / self.x_bins) as f64,
        );
        format!("x {x0:.3}..{:.3}, y {y0:.3}..{:.3}", x0 + dx, y0 + dy)
    }
}

/// What one test found.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// The density's integral over the grid: its total probability there.
    pub total: f64,
    /// Samples the routine refused, and samples that fell outside the grid;
    /// together they are one more cell, expecting `1 − total` of the samples.
    pub refused: u64,
    pub outside: u64,
    /// The cells that contributed most to the statistic: where, observed,
    /// expected.
    pub worst: Vec<(String, u64, f64)>,
}

/// Draws `n` samples with `sample`, which takes its random numbers from the
/// generator and returns a point with the density it reports for it (or
/// `None` to refuse), counts them in `grid`'s cells, and compares the counts
/// with those `density` predicts. Asserts only that each reported density
/// matches `density` at its point; see [`check`] for the whole test.
pub fn test<G: Grid>(
    grid: &G,
    n: usize,
    seed: u64,
    mut sample: impl FnMut(&mut Rng) -> Option<(G::Point, f64)>,
    density: impl Fn(G::Point) -> f64,
) -> Outcome {
    let mut rng = Rng::new(seed);
    let mut observed = vec![0u64; grid.cells()];
    let (mut refused, mut outside) = (0, 0);
    for _ in 0..n {
        let Some((p, reported)) = sample(&mut rng) else {
            refused += 1;
            continue;
        };
        let expected = density(p);
        assert!(
            reported.is_finite() && (reported - expected).abs() <= PDF_TOLERANCE * expected,
            "the sample {p:?} reports density {reported}, the density there is {expected}"
        );
        match grid.cell(p) {
            Some(c) => observed[c] += 1,
            None => outside += 1,
        }
    }
    let mut probability = grid.integrate(&density);
    let total: f64 = probability.iter().sum();
    if total > 1.0 {
        // Integration error alone (the caller bounds it): renormalise so the
        // expected counts add up to the samples drawn.
        probability.iter_mut().for_each(|p| *p /= total);
    }
    let mut bins: Vec<(Option<usize>, u64, f64)> = probability
        .iter()
        .enumerate()
        .map(|(c, p)| (Some(c), observed[c], p * n as f64))
        .collect();
    bins.push((None, refused + outside, (1.0 - total).max(0.0) * n as f64));
    let (statistic, dof, mut contributions) = pearson(&bins);
    contributions.sort_by(|a, b| b.0.total_cmp(&a.0));
    let worst = contributions
        .iter()
        .take(5)
        .map(|&(_, cell, o, e)| {
            let at = cell.map_or("refused or outside the grid".into(), |c| grid.describe(c));
            (at, o, e)
        })
        .collect();
    Outcome {
        statistic,
        dof,
        p_value: chi_square_survival(statistic, dof),
        total,
        refused,
        outside,
        worst,
    }
}

/// [`test`], asserting that the density integrates to at most one over the
/// grid (beyond integration error) and that the counts fit it at the
/// suite's [`SIGNIFICANCE`]. `what` names the routine in messages.
pub fn check<G: Grid>(
    what: &str,
    grid: &G,
    n: usize,
    seed: u64,
    sample: impl FnMut(&mut Rng) -> Option<(G::Point, f64)>,
    density: impl Fn(G::Point) -> f64,
) -> Outcome {
    let outcome = test(grid, n, seed, sample, density);
    assert!(
        outcome.total <= 1.0 + 2e-3,
        "{what}: the density integrates to {} > 1",
        outcome.total
    );
    assert!(
        outcome.p_value >= SIGNIFICANCE,
        "{what}: chi-square {:.1} with {} degrees of freedom, p = {:.2e} < {SIGNIFICANCE:e}; \
         the worst cells (where, observed, expected): {:?}",
        outcome.statistic,
        outcome.dof,
        outcome.p_value,
        outcome.worst
    );
    eprintln!(
        "{what}: chi-square {:.1} with {} degrees of freedom, p = {:.3}",
        outcome.statistic, outcome.dof, outcome.p_value
    );
    outcome
}

/// Pearson's statistic over `(cell, observed, expected)` bins, pooling those
/// expecting fewer than [`MIN_EXPECTED`] samples into one (itself merged into
/// the smallest other bin when it is still too small). Returns the
/// statistic, its degrees of freedom, and each bin's contribution.
#[allow(clippy::type_complexity)]
fn pearson(
    bins: &[(Option<usize>, u64, f64)],
) -> (f64, usize, Vec<(f64, Option<usize>, u64, f64)>) {
    let mut kept: Vec<(Option<usize>, u64, f64)> = Vec::new();
    let (mut pool_o, mut pool_e) = (0u64, 0.0);
    for &(cell, o, e) in bins {
        if e >= MIN_EXPECTED {
            kept.push((cell, o, e));
        } else {
            pool_o += o;
            pool_e += e;
        }
    }
    if pool_o > 0 || pool_e > 0.0 {
        let smallest = (0..kept.len()).min_by(|&a, &b| kept[a].2.total_cmp(&kept[b].2));
        match smallest {
            Some(k) if pool_e < MIN_EXPECTED => {
                kept[k].1 += pool_o;
                kept[k].2 += pool_e;
            }
            _ => kept.push((None, pool_o, pool_e)),
        }
    }
    let contributions: Vec<_> = kept
        .iter()
        .map(|&(cell, o, e)| {
            let d = o as f64 - e;
            let x = if e > 0.0 {
                d * d / e
            } else if o > 0 {
                f64::INFINITY
            } else {
                0.0
            };
            (x, cell, o, e)
        })
        .collect();
    let statistic = contributions.iter().map(|c| c.0).sum();
    (statistic, kept.len().saturating_sub(1), contributions)
}

/// P(X ≥ `x`) for X chi-square distributed with `dof` degrees of freedom.
pub fn chi_square_survival(x: f64, dof: usize) -> f64 {
    if dof == 0 {
        return if x > 0.0 { 0.0 } else { 1.0 };
    }
    if x.is_infinite() {
        return 0.0;
    }
    upper_gamma_regularized(dof as f64 / 2.0, x / 2.0)
}

/// Q(a, x) = Γ(a, x) / Γ(a): by its series below x = a + 1, by Lentz's
/// continued fraction above (Numerical Recipes, §6.2).
pub fn upper_gamma_regularized(a: f64, x: f64) -> f64 {
    const EPS: f64 = 1e-15;
    const TINY: f64 = 1e-300;
    if x <= 0.0 {
        return 1.0;
    }
    let log_prefix = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * EPS {
                break;
            }
        }
        (1.0 - sum * log_prefix.exp()).clamp(0.0, 1.0)
    } else {
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < EPS {
                break;
            }
        }
        (log_prefix.exp() * h).clamp(0.0, 1.0)
    }
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, nine terms: about 15 digits).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut sum = C[0];
    for (k, c) in C.iter().enumerate().skip(1) {
        sum += c / (x + k as f64);
    }
    let t = x + G + 0.5;
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials_and_the_half() {
        let mut factorial = 1.0f64;
        for n in 1..30 {
            // Γ(n) = (n − 1)!
            assert!(
                (ln_gamma(n as f64) - factorial.ln()).abs() < 1e-12 * factorial.ln().max(1.0),
                "ln Γ({n})"
            );
            factorial *= n as f64;
        }
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
        assert!((ln_gamma(0.1) - 2.252_712_651_734_206).abs() < 1e-12);
    }

    #[test]
    fn p_values_match_tabulated_quantiles() {
        // Two degrees of freedom: exactly e^(−x/2).
        for x in [0.1, 1.0, 5.0, 20.0, 60.0] {
            let p = chi_square_survival(x, 2);
            assert!((p - (-x / 2.0f64).exp()).abs() < 1e-13 * p.max(1e-300) + 1e-300);
        }
        // Upper 5%, 0.1% and 1e-5 quantiles (from mpmath, 30 digits).
        for (x, dof, p) in [
            (3.841_458_820_694_124, 1, 0.05),
            (18.307_038_053_275_146, 10, 0.05),
            (124.342_113_404_070_2, 100, 0.05),
            (10.827_566_170_662_733, 1, 1e-3),
            (43.820_195_964_517_53, 19, 1e-3),
            (19.511_420_964_666_268, 1, 1e-5),
            (197.831_075_635_487_6, 120, 1e-5),
        ] {
            let got = chi_square_survival(x, dof);
            assert!(
                (got / p - 1.0).abs() < 1e-6,
                "{dof} degrees of freedom at {x}: {got}, expected {p}"
            );
        }
    }

    /// The test has teeth: cosine-weighted directions do not pass for
    /// uniform ones, nor a slightly wrong cone for the right one.
    #[test]
    fn a_wrong_density_is_rejected() {
        use tracer::sampling::warp::{cosine_hemisphere, uniform_cone};
        let wrong = test(
            &SphereGrid::band(0.0, 1.0),
            100_000,
            1,
            |r| Some((cosine_hemisphere(r.f32(), r.f32()), 1.0 / (2.0 * PI))),
            |_| 1.0 / (2.0 * PI),
        );
        assert!(wrong.p_value < 1e-12, "{wrong:?}");
        let cos_max = 0.8;
        let uniform = 1.0 / (2.0 * PI * (1.0 - cos_max));
        let narrower = test(
            &SphereGrid::band(cos_max, 1.0),
            100_000,
            2,
            |r| Some((uniform_cone(0.81, r.f32(), r.f32()), uniform)),
            |w| if w.z as f64 >= cos_max { uniform } else { 0.0 },
        );
        assert!(narrower.p_value < 1e-12, "{narrower:?}");
    }

    /// Pooling keeps every counted bin at five expected samples or more.
    #[test]
    fn sparse_cells_are_pooled() {
        let bins = [
            (Some(0), 100, 100.0),
            (Some(1), 1, 1.0),
            (Some(2), 2, 2.5),
            (Some(3), 50, 50.0),
            (None, 0, 0.0),
        ];
        let (statistic, dof, contributions) = pearson(&bins);
        assert!(contributions.iter().all(|c| c.3 >= MIN_EXPECTED));
        // 100, 50 and the pool of 3.5 merged into 50: two bins, one degree.
        assert_eq!(dof, 1);
        assert!((statistic - (0.5f64).powi(2) / 53.5).abs() < 1e-12);
    }
}
