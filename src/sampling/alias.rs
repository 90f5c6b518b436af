//! A discrete distribution sampled in constant time by Walker's alias method
//! (Vose's construction, "A Linear Algorithm for Generating Random Numbers
//! with a Given Distribution", 1991).
//!
//! Each of the n equal bins holds one entry up to a threshold and another
//! (its alias) above it, so a sample is one multiplication, one lookup and
//! one comparison. Inverting a cumulative sum instead takes a binary
//! search, whose branches a random number makes a coin toss each: the light
//! selector, sampled once per path vertex, uses this table.

/// A discrete distribution over the indices of its weights, proportional to
/// them (negative and NaN weights count as zero).
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    bins: Vec<Bin>,
    pmf: Vec<f32>,
}

#[derive(Clone, Copy, Debug)]
struct Bin {
    /// The bin's own entry is chosen below this fraction of the bin.
    threshold: f32,
    /// The entry chosen above it.
    alias: u32,
}

impl AliasTable {
    /// `None` when no weight is positive (nothing can be sampled).
    pub fn new(weights: &[f32]) -> Option<AliasTable> {
        let weight = |w: f32| if w > 0.0 { w as f64 } else { 0.0 };
        let total: f64 = weights.iter().map(|&w| weight(w)).sum();
        if !total.is_finite() || total <= 0.0 {
            return None;
        }
        let n = weights.len();
        let pmf: Vec<f32> = weights
            .iter()
            .map(|&w| (weight(w) / total) as f32)
            .collect();
        // Each entry's weight in units of one bin.
        let mut scaled: Vec<f64> = weights
            .iter()
            .map(|&w| weight(w) / total * n as f64)
            .collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        let mut bins = vec![
            Bin {
                threshold: 1.0,
                alias: 0,
            };
            n
        ];
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            // The small entry's bin is topped up from the large one.
            bins[s] = Bin {
                threshold: scaled[s] as f32,
                alias: l as u32,
            };
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left holds (up to rounding) exactly one bin's weight and
        // keeps its bin whole; an entry of zero weight never does, however
        // the rounding fell: it passes its bin to the heaviest entry.
        let heaviest = (0..n)
            .max_by(|&a, &b| pmf[a].total_cmp(&pmf[b]))
            .unwrap_or(0);
        for i in small.into_iter().chain(large) {
            bins[i] = Bin {
                threshold: if pmf[i] > 0.0 { 1.0 } else { 0.0 },
                alias: heaviest as u32,
            };
        }
        Some(AliasTable { bins, pmf })
    }

    /// Probability of entry `i`. Panics when `i >= len()`.
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// An index with probability proportional to its weight, and that
    /// probability, for `u` in [0, 1). Zero-weight entries are never returned.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let n = self.bins.len();
        // In f64, so the fraction within the bin keeps all of u's bits.
        let scaled = u as f64 * n as f64;
        let bin_index = (scaled as usize).min(n - 1);
        let bin = self.bins[bin_index];
        let within = (scaled - bin_index as f64) as f32;
        let chosen = if within < bin.threshold {
            bin_index
        } else {
            bin.alias as usize
        };
        (chosen, self.pmf[chosen])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact probability the table gives each entry, from its bins.
    fn bin_shares(table: &AliasTable) -> Vec<f64> {
        let n = table.bins.len();
        let mut p = vec![0.0; n];
        for (i, bin) in table.bins.iter().enumerate() {
            let t = (bin.threshold as f64).clamp(0.0, 1.0);
            p[i] += t / n as f64;
            p[bin.alias as usize] += (1.0 - t) / n as f64;
        }
        p
    }

    #[test]
    fn bins_give_every_entry_its_weight() {
        let weights = [1.0, 0.0, 3.0, 0.5, 7.25, 0.0, 2.0, -1.0, f32::NAN, 0.125];
        let table = AliasTable::new(&weights).unwrap();
        let total: f64 = weights
            .iter()
            .filter(|w| **w > 0.0)
            .map(|&w| w as f64)
            .sum();
        for (i, share) in bin_shares(&table).into_iter().enumerate() {
            let expected = if weights[i] > 0.0 {
                weights[i] as f64 / total
            } else {
                0.0
            };
            assert!(
                (share - expected).abs() < 1e-7,
                "entry {i}: {share} vs {expected}"
            );
            assert_eq!(table.pmf(i), expected as f32);
        }
    }

    #[test]
    fn stratified_numbers_follow_the_weights_and_skip_zeros() {
        let table = AliasTable::new(&[1.0, 0.0, 3.0, 0.0]).unwrap();
        let mut counts = [0; 4];
        for k in 0..4000 {
            let (i, pmf) = table.sample((k as f32 + 0.5) / 4000.0);
            assert_eq!(pmf, [0.25, 0.0, 0.75, 0.0][i]);
            counts[i] += 1;
        }
        assert_eq!(counts, [1000, 0, 3000, 0]);
        for u in [0.0, 0.999_999_94, 0.5, 0.25, 0.75] {
            assert_ne!(table.sample(u).0 % 2, 1, "u = {u}");
        }
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[]).is_none());
    }

    #[test]
    fn many_entries_with_rounding_leftovers_never_pick_a_zero() {
        // Weights whose bin units do not add up exactly in floating point.
        let weights: Vec<f32> = (0..1000)
            .map(|i| {
                if i % 3 == 0 {
                    0.0
                } else {
                    1.0 / (1.0 + i as f32 * 0.37)
                }
            })
            .collect();
        let table = AliasTable::new(&weights).unwrap();
        let shares = bin_shares(&table);
        for (i, &w) in weights.iter().enumerate() {
            if w == 0.0 {
                assert_eq!(shares[i], 0.0, "entry {i}");
            } else {
                assert!(
                    (shares[i] / table.pmf(i) as f64 - 1.0).abs() < 1e-4,
                    "entry {i}"
                );
            }
        }
        for k in 0..100_000 {
            let (i, pmf) = table.sample(k as f32 / 100_000.0);
            assert!(weights[i] > 0.0 && pmf > 0.0);
        }
    }
}
