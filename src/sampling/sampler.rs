//! Owen-scrambled Sobol samples (Burley, "Practical Hash-based Owen
//! Scrambling", JCGT 2020, via the `sobol_burley` crate).
//!
//! A sample is a pure function of (seed, pixel, sample index, dimension), so an
//! image does not depend on which thread rendered which tile, or in what order.
//! Dimensions are drawn four at a time from a 4D Sobol sequence; each group of
//! four gets its own scramble seed ("padding" by independent shuffles), which
//! keeps every group well stratified without running out of dimensions.

/// Hash of 32-bit words (a variant of the lowbias32 finaliser by C. Wellons).
pub fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x21f0_aaad);
    x ^= x >> 15;
    x = x.wrapping_mul(0x735a_2d97);
    x ^= x >> 15;
    x
}

/// Hash of the pair (`a`, `b`); order matters.
pub fn hash_combine(a: u32, b: u32) -> u32 {
    hash(a ^ hash(b).wrapping_add(0x9e37_79b9))
}

/// The sequence length `sobol_burley` supports; later samples continue with a
/// freshly seeded sequence.
const SEQUENCE_LENGTH: u32 = 1 << 16;

/// The random numbers of one sample of one pixel: successive dimensions of an
/// Owen-scrambled Sobol sequence, deterministic in (seed, pixel, sample index).
pub struct Sampler {
    pixel_seed: u32,
    index: u32,
    group: u32,
    cached: [f32; 4],
    used: usize,
}

impl Sampler {
    /// The sampler for sample `index` of pixel (`x`, `y`) of an image rendered with `seed`.
    pub fn new(seed: u64, x: u32, y: u32, index: u64) -> Sampler {
        let seed_word = hash_combine(seed as u32, (seed >> 32) as u32);
        let pixel = hash_combine(hash_combine(seed_word, x), y);
        let block = (index / SEQUENCE_LENGTH as u64) as u32;
        Sampler {
            pixel_seed: hash_combine(pixel, block),
            index: (index % SEQUENCE_LENGTH as u64) as u32,
            group: 0,
            cached: [0.0; 4],
            used: 4,
        }
    }

    /// A number in [0, 1).
    pub fn next_1d(&mut self) -> f32 {
        if self.used == 4 {
            let seed = hash_combine(self.pixel_seed, self.group);
            self.cached = sobol_burley::sample_4d(self.index, 0, seed);
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
