//! Owen-scrambled Sobol samples (Burley, "Practical Hash-based Owen
//! Scrambling", JCGT 2020, via the `sobol_burley` crate).
//!
//! A sample is a pure function of (seed, pixel, sample index, dimension), so an
//! image does not depend on which thread rendered which tile, or in what order.
//! Dimensions are drawn four at a time from a 4D Sobol sequence; each group of
//! four gets its own scramble seed ("padding" by independent shuffles), which
//! keeps every group well stratified without running out of dimensions.
//!
//! Every group uses the sequence's first four dimensions, so their Sobol
//! points (before scrambling) come from two 256-entry tables, one per byte
//! of the 16-bit shuffled index, built once with the crate's own generator:
//! Sobol points are XORs of per-bit direction vectors, so two lookups give
//! what the crate's bit-by-bit loop gives, bit for bit.

use sobol_burley::parts::{self, Int4};
use std::sync::OnceLock;

/// Hash of 32-bit words (a variant of the lowbias32 finaliser by C. Wellons).
pub const fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x21f0_aaad);
    x ^= x >> 15;
    x = x.wrapping_mul(0x735a_2d97);
    x ^= x >> 15;
    x
}

/// Hash of the pair (`a`, `b`); order matters.
pub fn hash_combine(a: u32, b: u32) -> u32 {
    hash(a ^ combine_key(b))
}

/// What `hash_combine` mixes in for its second argument.
const fn combine_key(b: u32) -> u32 {
    hash(b).wrapping_add(0x9e37_79b9)
}

/// `combine_key` of the first group numbers, worked out at compile time: a
/// path of up to 31 vertices opens no more groups than these.
const GROUP_KEYS: [u32; 64] = {
    let mut keys = [0; 64];
    let mut g = 0;
    while g < 64 {
        keys[g] = combine_key(g as u32);
        g += 1;
    }
    keys
};

/// The sequence length `sobol_burley` supports; later samples continue with a
/// freshly seeded sequence.
const SEQUENCE_LENGTH: u32 = 1 << 16;

/// The first four Sobol dimensions (bit-reversed, unscrambled) of every
/// value of the index's top byte (`high`) and next byte (`low`).
struct SobolTables {
    high: [Int4; 256],
    low: [Int4; 256],
}

fn sobol_tables() -> &'static SobolTables {
    static TABLES: OnceLock<SobolTables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let zero = Int4::from([0; 4]);
        let mut t = SobolTables {
            high: [zero; 256],
            low: [zero; 256],
        };
        for v in 0..256u32 {
            t.high[v as usize] = parts::sobol_int4_rev(v << 24, 0);
            t.low[v as usize] = parts::sobol_int4_rev(v << 16, 0);
        }
        t
    })
}

/// Four Owen-scrambled Sobol dimensions: exactly `sobol_burley::sample_4d(
/// index, 0, seed)` (a test checks it) for `index_reversed` =
/// `index.reverse_bits()`, with the Sobol point from the tables.
#[inline]
fn sample_4d(tables: &SobolTables, index_reversed: u32, seed: u32) -> [f32; 4] {
    // Shuffle the index: a statistically independent sequence per seed.
    let shuffled = parts::owen_scramble_rev(index_reversed, parts::hash(seed ^ 0x79c6_8e4a));
    let sobol =
        tables.high[(shuffled >> 24) as usize] ^ tables.low[((shuffled >> 16) & 0xff) as usize];
    // The crate's per-dimension scrambles of `seed` (for dimension set 0).
    let scramble = Int4::from([seed.wrapping_mul(0x9c8f_2d3b); 4])
        ^ Int4::from([0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8]);
    parts::owen_scramble_int4_rev(sobol, parts::hash_int4(scramble))
        .reverse_bits()
        .to_f32_norm()
}

/// The random numbers of one sample of one pixel: successive dimensions of an
/// Owen-scrambled Sobol sequence, deterministic in (seed, pixel, sample index).
pub struct Sampler {
    tables: &'static SobolTables,
    pixel_seed: u32,
    /// The sample index within its sequence, bit-reversed once here rather
    /// than at every group.
    index_reversed: u32,
    group: u32,
    cached: [f32; 4],
    used: usize,
}

/// The part of a sampler's scramble fixed by the render's seed and the
/// pixel: worked out once per pixel rather than once per sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSeed(u32);

impl PixelSeed {
    /// The seed of pixel (`x`, `y`) of an image rendered with `seed`.
    pub fn new(seed: u64, x: u32, y: u32) -> PixelSeed {
        let seed_word = hash_combine(seed as u32, (seed >> 32) as u32);
        PixelSeed(hash_combine(hash_combine(seed_word, x), y))
    }
}

impl Sampler {
    /// The sampler for sample `index` of the pixel whose seed is `pixel`.
    pub fn for_pixel(pixel: PixelSeed, index: u64) -> Sampler {
        let block = (index / SEQUENCE_LENGTH as u64) as u32;
        Sampler {
            tables: sobol_tables(),
            pixel_seed: hash_combine(pixel.0, block),
            index_reversed: ((index % SEQUENCE_LENGTH as u64) as u32).reverse_bits(),
            group: 0,
            cached: [0.0; 4],
            used: 4,
        }
    }

    /// A number in [0, 1).
    pub fn next_1d(&mut self) -> f32 {
        if self.used == 4 {
            let key = match GROUP_KEYS.get(self.group as usize) {
                Some(&key) => key,
                None => combine_key(self.group),
            };
            let seed = hash(self.pixel_seed ^ key);
            self.cached = sample_4d(self.tables, self.index_reversed, seed);
            self.group += 1;
            self.used = 0;
        }
        self.used += 1;
        self.cached[self.used - 1]
    }

    /// Two numbers from the same 4D group when possible, so the pair is stratified.
    pub fn next_2d(&mut self) -> (f32, f32) {
        if self.used == 3 {
            self.used = 4;
        }
        (self.next_1d(), self.next_1d())
    }

    /// Starts the dimensions of a new path vertex on a fresh group, so each
    /// bounce's decisions use the same well-stratified dimensions every sample.
    pub fn start_vertex(&mut self) {
        self.used = 4;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_give_the_crates_samples_bit_for_bit() {
        let tables = sobol_tables();
        let mut seed = 12345u32;
        for index in (0..SEQUENCE_LENGTH).step_by(7).chain([SEQUENCE_LENGTH - 1]) {
            seed = hash(seed);
            let ours = sample_4d(tables, index.reverse_bits(), seed);
            let crate_4d = sobol_burley::sample_4d(index, 0, seed);
            assert_eq!(
                ours.map(f32::to_bits),
                crate_4d.map(f32::to_bits),
                "index {index}"
            );
        }
    }

    /// The sampler's numbers are group `g`'s `sample_4d` for the g-th group
    /// it opens, whatever mix of 1D, 2D and vertex starts asks for them.
    #[test]
    fn draws_follow_one_group_after_another() {
        let tables = sobol_tables();
        for (pixel, index) in [
            (PixelSeed::new(7, 3, 4), 0u64),
            (PixelSeed::new(1, 0, 9), 70_000),
        ] {
            let mut sampler = Sampler::for_pixel(pixel, index);
            let block = (index / SEQUENCE_LENGTH as u64) as u32;
            let seed = hash_combine(pixel.0, block);
            let i = (index % SEQUENCE_LENGTH as u64) as u32;
            let group = |g: u32| sample_4d(tables, i.reverse_bits(), hash_combine(seed, g));
            // A pinhole camera sample, then vertices of light, BSDF and
            // roulette draws, as the path tracer makes them.
            let (x, y) = sampler.next_2d();
            assert_eq!([x, y], group(0)[..2]);
            // 40 vertices: past the groups whose keys are precomputed.
            for vertex in 0..40u32 {
                sampler.start_vertex();
                let (g_light, g_bsdf) = (1 + 2 * vertex, 2 + 2 * vertex);
                let select = sampler.next_1d();
                let (u, v) = sampler.next_2d();
                assert_eq!([select, u, v], group(g_light)[..3], "vertex {vertex}");
                let (a, b) = sampler.next_2d();
                let (lobe, roulette) = (sampler.next_1d(), sampler.next_1d());
                assert_eq!([a, b, lobe, roulette], group(g_bsdf), "vertex {vertex}");
            }
        }
    }
}
