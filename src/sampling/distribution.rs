//! A discrete distribution sampled by inverting its cumulative sum.

/// A discrete distribution over `0..len()`, proportional to non-negative
/// weights (negative weights count as zero).
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    /// cdf[i] = sum of weights[..i] / total; cdf.len() = n + 1.
    cdf: Vec<f32>,
    pmf: Vec<f32>,
}

impl Distribution1D {
    /// `None` when every weight is zero (nothing can be sampled).
    pub fn new(weights: &[f32]) -> Option<Distribution1D> {
        let total: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
        if !total.is_finite() || total <= 0.0 {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            acc += w.max(0.0) as f64;
            cdf.push((acc / total) as f32);
        }
        *cdf.last_mut().unwrap() = 1.0;
        let pmf = weights
            .iter()
            .map(|&w| (w.max(0.0) as f64 / total) as f32)
            .collect();
        Some(Distribution1D { cdf, pmf })
    }

    /// Number of entries, including zero-weight ones.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Whether there are no entries (never true of one built by [`Distribution1D::new`]).
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Probability of entry `i`. Panics when `i >= len()`.
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// An index with probability proportional to its weight, and that probability.
    /// Zero-weight entries are never returned.
    pub fn sample(&self, u: f32) -> (usize, f32) {
        // First i with cdf[i + 1] > u; zero-weight entries have cdf[i+1] == cdf[i].
        let i = self.cdf[1..]
            .partition_point(|&c| c <= u)
            .min(self.pmf.len() - 1);
        let mut i = i;
        while self.pmf[i] == 0.0 && i > 0 {
            i -= 1;
        }
        (i, self.pmf[i])
    }

    /// [`Distribution1D::sample`], and `u` remapped to [0, 1) within the chosen
    /// entry's share of the cumulative sum, so one number can also place a
    /// point inside the entry.
    pub fn sample_remapped(&self, u: f32) -> (usize, f32, f32) {
        let (i, pmf) = self.sample(u);
        let within = ((u - self.cdf[i]) / pmf).clamp(0.0, ONE_MINUS_EPSILON);
        (i, pmf, within)
    }
}

/// The largest f32 below one.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_weights_and_skip_zeros() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 0.0]).unwrap();
        let mut counts = [0; 4];
        for k in 0..4000 {
            counts[d.sample((k as f32 + 0.5) / 4000.0).0] += 1;
        }
        assert_eq!(counts, [1000, 0, 3000, 0]);
        assert_eq!(d.sample(0.999_999).0, 2);
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
    }
}
