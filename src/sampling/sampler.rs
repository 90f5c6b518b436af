//! Owen-scrambled Sobol samples (Burley, "Practical Hash-based Owen
//! Scrambling", JCGT 2020, via the `sobol_burley` crate).
//!
//! A sample is a pure function of (seed, pixel, sample index, dimension), so an
//! image does not depend on which thread rendered which tile, or in what order.
//! Dimensions are drawn four at a time from a 4D Sobol sequence; each group of
//! four gets its own scramble seed ("padding" by independent shuffles), which
//! keeps every group well stratified without running out of dimensions.
//! A camera path's start draws groups in turn (`next_1d`, `next_2d`); its
//! vertices take groups of their own, laid out so that consecutive bounces
//! share one (`Sampler::vertex_numbers`). A light walk draws all its
//! numbers in turn (`Sampler::walk_numbers`).
//!
//! Every group uses the sequence's first four dimensions, so their Sobol
//! points (before scrambling) come from two 256-entry tables, one per byte
//! of the 16-bit shuffled index, built once with the crate's own generator:
//! Sobol points are XORs of per-bit direction vectors, so two lookups give
//! what the crate's bit-by-bit loop gives, bit for bit.

use sobol_burley::parts;
use std::ops::{AddAssign, BitOr, BitXor, BitXorAssign, Mul, MulAssign, Shr};
use std::sync::OnceLock;
use wide::{f32x8, u32x4, u32x8};

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

/// The first group of camera path vertices' numbers (see
/// `Sampler::vertex_numbers`): the groups before it are for `next_1d` and
/// `next_2d`, which a camera path draws only at its start (pixel, lens).
/// Light walks draw all their numbers in turn, from a sampler of their own.
const VERTEX_GROUPS: u32 = 8;

/// The sequence length `sobol_burley` supports; later samples continue with a
/// freshly seeded sequence.
const SEQUENCE_LENGTH: u32 = 1 << 16;

/// The first four Sobol dimensions (bit-reversed, unscrambled) of every
/// value of the index's top byte (`high`) and next byte (`low`).
struct SobolTables {
    high: [[u32; 4]; 256],
    low: [[u32; 4]; 256],
}

fn sobol_tables() -> &'static SobolTables {
    static TABLES: OnceLock<SobolTables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let mut t = SobolTables {
            high: [[0; 4]; 256],
            low: [[0; 4]; 256],
        };
        for v in 0..256u32 {
            t.high[v as usize] = parts::sobol_int4_rev(v << 24, 0).into();
            t.low[v as usize] = parts::sobol_int4_rev(v << 16, 0).into();
        }
        t
    })
}

/// The crate's per-dimension constants of its scramble (dimension set 0).
const DIMENSION_KEYS: [u32; 4] = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8];

/// The unscrambled Sobol points of the shuffles of `index_reversed` by the
/// four `seeds`, as the crate's `sample_4d` finds them: the index's Owen
/// shuffle (a statistically independent sequence per seed), then two table
/// lookups. The four shuffles are made in one SIMD pass.
#[inline(always)]
fn sobol_points(tables: &SobolTables, index_reversed: u32, seeds: u32x4) -> [u32x4; 4] {
    let shuffle = crate_hash(seeds ^ u32x4::splat(0x79c6_8e4a));
    let shuffled = owen_scramble(u32x4::splat(index_reversed), shuffle).to_array();
    shuffled.map(|s| {
        u32x4::new(tables.high[(s >> 24) as usize])
            ^ u32x4::new(tables.low[((s >> 16) & 0xff) as usize])
    })
}

/// Two groups from their Sobol points `a` and `b` and their seeds: the
/// crate's scramble, hash and bit reversal, step for step, in the eight
/// lanes of one AVX register rather than twice in four.
#[inline(always)]
fn scrambled_pair(a: u32x4, b: u32x4, seed_a: u32, seed_b: u32) -> [f32; 8] {
    let (a, b) = (a.to_array(), b.to_array());
    let sobol = u32x8::new([a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]);
    let [sa, sb] = [seed_a, seed_b].map(|seed| seed.wrapping_mul(0x9c8f_2d3b));
    let k = DIMENSION_KEYS;
    let scramble = u32x8::new([sa, sa, sa, sa, sb, sb, sb, sb])
        ^ u32x8::new([k[0], k[1], k[2], k[3], k[0], k[1], k[2], k[3]]);
    let scrambled = owen_scramble(sobol, crate_hash(scramble));
    let bits = (reverse_bits_8(scrambled) >> 9) | u32x8::splat(0x3f80_0000);
    (bytemuck::cast::<u32x8, f32x8>(bits) - f32x8::ONE).to_array()
}

/// Two groups of four Owen-scrambled Sobol dimensions, for the first two
/// of four group seeds: numbers 0-3 are exactly
/// `sobol_burley::sample_4d(index, 0, seeds[0])` and 4-7 those for
/// `seeds[1]` (a test checks it), for `index_reversed` =
/// `index.reverse_bits()`.
#[inline]
fn sample_8d(tables: &SobolTables, index_reversed: u32, seeds: u32x4) -> [f32; 8] {
    let [a, b, ..] = sobol_points(tables, index_reversed, seeds);
    let [s0, s1, ..] = seeds.to_array();
    scrambled_pair(a, b, s0, s1)
}

/// Four groups, as [`sample_8d`] makes two: numbers `4 * k .. 4 * k + 4`
/// are `sobol_burley::sample_4d(index, 0, seeds[k])`.
#[inline(always)]
fn sample_16d(tables: &SobolTables, index_reversed: u32, seeds: u32x4) -> [f32; 16] {
    let [a, b, c, d] = sobol_points(tables, index_reversed, seeds);
    let [s0, s1, s2, s3] = seeds.to_array();
    let mut out = [0.0; 16];
    out[..8].copy_from_slice(&scrambled_pair(a, b, s0, s1));
    out[8..].copy_from_slice(&scrambled_pair(c, d, s2, s3));
    out
}

/// The integer SIMD types the scramble runs on: four lanes (one group
/// per lane, for seeds and index shuffles) and eight (two groups of four
/// dimensions). Both take the same steps, written once below.
trait Lanes:
    Copy
    + BitXor<Output = Self>
    + BitXorAssign
    + BitOr<Output = Self>
    + Shr<u32, Output = Self>
    + Mul<Output = Self>
    + MulAssign
    + AddAssign
{
    fn splat(x: u32) -> Self;
}

impl Lanes for u32x4 {
    #[inline(always)]
    fn splat(x: u32) -> Self {
        u32x4::splat(x)
    }
}

impl Lanes for u32x8 {
    #[inline(always)]
    fn splat(x: u32) -> Self {
        u32x8::splat(x)
    }
}

/// `parts::hash` (the crate's, not this module's [`hash`]) on every lane.
#[inline(always)]
fn crate_hash<L: Lanes>(mut n: L) -> L {
    n ^= L::splat(0xe6fe_3beb);
    n ^= n >> 16;
    n *= L::splat(0x7feb_352d);
    n ^= n >> 15;
    n *= L::splat(0x846c_a68b);
    n ^ (n >> 16)
}

/// `parts::owen_scramble_rev` on every lane.
#[inline(always)]
fn owen_scramble<L: Lanes>(mut n: L, scramble: L) -> L {
    n ^= n * L::splat(0x3d20_adea);
    n += scramble;
    n *= (scramble >> 16) | L::splat(1);
    n ^= n * L::splat(0x0552_6c56);
    n ^ (n * L::splat(0x53a2_2864))
}

/// This module's [`hash`] on four lanes.
#[inline(always)]
fn group_hash_4(mut x: u32x4) -> u32x4 {
    x ^= x >> 16;
    x *= u32x4::splat(0x21f0_aaad);
    x ^= x >> 15;
    x *= u32x4::splat(0x735a_2d97);
    x ^= x >> 15;
    x
}

/// `u32::reverse_bits` of each lane: swap ever larger halves.
#[inline(always)]
fn reverse_bits_8(mut n: u32x8) -> u32x8 {
    for (shift, mask) in [
        (1, 0x5555_5555u32),
        (2, 0x3333_3333),
        (4, 0x0f0f_0f0f),
        (8, 0x00ff_00ff),
    ] {
        let m = u32x8::splat(mask);
        n = ((n >> shift) & m) | ((n & m) << shift);
    }
    (n >> 16) | (n << 16)
}

/// The random numbers of one sample of one pixel: successive dimensions of an
/// Owen-scrambled Sobol sequence, deterministic in (seed, pixel, sample index).
pub struct Sampler {
    tables: &'static SobolTables,
    pixel_seed: u32,
    /// The sample index within its sequence, bit-reversed once here rather
    /// than at every group.
    index_reversed: u32,
    /// The next group not yet in `cached`.
    group: u32,
    /// Two groups, made together (eight lanes of one SIMD pass).
    cached: [f32; 8],
    /// Numbers of `cached` used or skipped; 4 is the second group's start.
    used: usize,
    /// The path vertices whose numbers `vertex_numbers` has returned.
    vertices: u32,
    /// The four groups of the current pair of vertices (see
    /// `vertex_numbers`).
    vertex_groups: [f32; 16],
}

/// The numbers of one path vertex (see [`Sampler::vertex_numbers`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexNumbers {
    /// The light sample's: one to choose the light, two for its point.
    pub light: Option<(f32, (f32, f32))>,
    /// The BSDF sample's two for its direction.
    pub direction: (f32, f32),
    /// The BSDF sample's choice of lobe.
    pub lobe: f32,
    /// Russian roulette's.
    pub roulette: f32,
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
            cached: [0.0; 8],
            used: 8,
            vertices: 0,
            vertex_groups: [0.0; 16],
        }
    }

    /// The seeds of groups `g` to `g + 3`, in one SIMD pass.
    #[inline(always)]
    fn group_seeds_4(&self, g: u32) -> u32x4 {
        let keys = match GROUP_KEYS.get(g as usize..g as usize + 4) {
            Some(&[a, b, c, d]) => [a, b, c, d],
            _ => [g, g + 1, g + 2, g + 3].map(combine_key),
        };
        group_hash_4(u32x4::splat(self.pixel_seed) ^ u32x4::new(keys))
    }

    /// A number in [0, 1).
    pub fn next_1d(&mut self) -> f32 {
        if self.used == 8 {
            self.refill();
        }
        self.used += 1;
        self.cached[self.used - 1]
    }

    /// Two numbers from the same 4D group when possible, so the pair is stratified.
    pub fn next_2d(&mut self) -> (f32, f32) {
        if self.used & 3 == 3 {
            self.used += 1;
        }
        (self.next_1d(), self.next_1d())
    }

    /// The numbers of a camera path's next vertex: its light sample's (if
    /// `light`), its BSDF sample's and its roulette's. Vertices come in
    /// pairs (the first and second of a path, the third and fourth, ...),
    /// and a pair takes four groups of its own, apart from those of
    /// `next_1d` and `next_2d`:
    ///
    /// - the two vertices' directions, (a, b) of the first vertex and
    ///   (a, b) of the second: one 4D Sobol point, so that a bounce and
    ///   the next are stratified together, not only each alone;
    /// - the first vertex's light sample (choice, then the point's two) and
    ///   lobe choice; then the second vertex's;
    /// - the two vertices' roulette numbers.
    ///
    /// Stratifying two bounces together lowered the Cornell box's `pt`
    /// error at 64 spp by 4% against two bounces from groups of their own
    /// (docs/benchmarks.md, "Two bounces in one group"); the pair costs the
    /// same two refills of eight numbers as two vertices did before.
    #[inline(always)]
    pub fn vertex_numbers(&mut self, light: bool) -> VertexNumbers {
        debug_assert!(
            self.group <= VERTEX_GROUPS,
            "a path that draws its numbers in turn past its start cannot also take vertex groups"
        );
        let vertex = self.vertices;
        self.vertices += 1;
        let second = (vertex & 1) as usize;
        if second == 0 {
            let g = VERTEX_GROUPS + 2 * vertex;
            self.vertex_groups =
                sample_16d(self.tables, self.index_reversed, self.group_seeds_4(g));
        }
        let c = &self.vertex_groups;
        let own = 4 + 4 * second;
        VertexNumbers {
            light: light.then(|| (c[own], (c[own + 1], c[own + 2]))),
            direction: (c[2 * second], c[2 * second + 1]),
            lobe: c[own + 3],
            roulette: c[12 + second],
        }
    }

    /// The numbers of a light walk's next vertex, which samples no light:
    /// its BSDF sample's and its roulette's, from the next group of
    /// `next_1d` and `next_2d` (three of its four). Light walks end sooner
    /// than camera paths (roulette from their second segment), so the
    /// pairs of `vertex_numbers` would often be half wasted on them, and
    /// their bounces gained nothing from being paired (docs/benchmarks.md,
    /// "Two bounces in one group").
    #[inline(always)]
    pub fn walk_numbers(&mut self) -> VertexNumbers {
        self.start_vertex();
        let direction = self.next_2d();
        let lobe = self.next_1d();
        VertexNumbers {
            light: None,
            direction,
            lobe,
            roulette: self.next_1d(),
        }
    }

    /// Makes the next two groups, the cache's eight numbers.
    #[inline(always)]
    fn refill(&mut self) {
        // A camera path's vertex groups start at `VERTEX_GROUPS`: draws in
        // turn must not reach them, or two uses would share dimensions.
        debug_assert!(
            self.vertices == 0 || self.group + 2 <= VERTEX_GROUPS,
            "draws in turn reached the vertices' groups"
        );
        // The four-lane pass makes four seeds and points; a refill uses the
        // first two, the others riding along in the same instructions (two
        // table lookups aside).
        let seeds = self.group_seeds_4(self.group);
        self.cached = sample_8d(self.tables, self.index_reversed, seeds);
        self.group += 2;
        self.used = 0;
    }

    /// Starts the next draws on a fresh group, so that a step of a path
    /// (a light path's start, a light walk's vertex) uses the same
    /// well-stratified dimensions every sample.
    pub fn start_vertex(&mut self) {
        // A group is only made when drawn from, so the first one here has
        // been drawn from; the second has not unless `used` is past 4.
        self.used = if self.used <= 4 { 4 } else { 8 };
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
            let seeds = [hash(seed), hash(hash(seed))];
            seed = seeds[1];
            let four = [seeds[0], seeds[1], hash(seeds[0] ^ 1), hash(seeds[1] ^ 2)];
            let ours = sample_16d(tables, index.reverse_bits(), u32x4::new(four));
            let pair = sample_8d(tables, index.reverse_bits(), u32x4::new(four));
            let first_two: [f32; 8] = ours[..8].try_into().unwrap();
            assert_eq!(pair.map(f32::to_bits), first_two.map(f32::to_bits));
            for (k, seed) in four.into_iter().enumerate() {
                let crate_4d = sobol_burley::sample_4d(index, 0, seed).map(f32::to_bits);
                let ours_4d: [f32; 4] = ours[4 * k..4 * k + 4].try_into().unwrap();
                assert_eq!(ours_4d.map(f32::to_bits), crate_4d, "index {index}");
            }
        }
    }

    /// Vertex numbers follow the layout `vertex_numbers` describes, in
    /// groups of their own whatever else the sampler draws.
    #[test]
    fn vertex_numbers_follow_their_layout() {
        let pixel = PixelSeed::new(3, 5, 8);
        for index in [0u64, 1, 77, 70_000] {
            let mut sampler = Sampler::for_pixel(pixel, index);
            let block = (index / SEQUENCE_LENGTH as u64) as u32;
            let seed = hash_combine(pixel.0, block);
            let i = (index % SEQUENCE_LENGTH as u64) as u32;
            let group = |g: u32| sobol_burley::sample_4d(i, 0, hash_combine(seed, g));
            assert_eq!(<[f32; 2]>::from(sampler.next_2d()), group(0)[..2]);
            // 40 vertices: past the groups whose keys are precomputed.
            for vertex in 0..40u32 {
                let light = vertex % 3 != 1;
                let numbers = sampler.vertex_numbers(light);
                let base = VERTEX_GROUPS + 4 * (vertex / 2);
                let second = (vertex % 2) as usize;
                let directions = group(base);
                let own = group(base + 1 + second as u32);
                let expected = VertexNumbers {
                    light: light.then_some((own[0], (own[1], own[2]))),
                    direction: (directions[2 * second], directions[2 * second + 1]),
                    lobe: own[3],
                    roulette: group(base + 3)[second],
                };
                assert_eq!(numbers, expected, "index {index}, vertex {vertex}");
                // Draws in between take their own groups.
                if vertex % 5 == 0 {
                    sampler.next_1d();
                }
            }
        }
    }

    /// A camera path's draws in turn stop short of its vertices' groups.
    #[test]
    #[cfg(debug_assertions)]
    #[should_panic(expected = "reached the vertices' groups")]
    fn draws_in_turn_cannot_reach_vertex_groups() {
        let mut sampler = Sampler::for_pixel(PixelSeed::new(1, 2, 3), 4);
        sampler.vertex_numbers(true);
        // The groups before the vertices' hold 4 x VERTEX_GROUPS numbers.
        for _ in 0..=4 * VERTEX_GROUPS {
            sampler.next_1d();
        }
    }

    /// A light walk's vertex takes the first four numbers of a fresh group
    /// in turn: the crate's `sample_4d` for that group, whether the draws
    /// before it ended mid-group or not.
    #[test]
    fn walk_numbers_take_a_fresh_group_in_turn() {
        let pixel = PixelSeed::new(9, 1, 2);
        let mut sampler = Sampler::for_pixel(pixel, 5);
        let seed = hash_combine(pixel.0, 0);
        let group = |g: u32| sobol_burley::sample_4d(5, 0, hash_combine(seed, g));
        // A light path's start: the light's choice, then four numbers for
        // its point and direction (groups 0 and 1).
        sampler.next_1d();
        sampler.next_2d();
        sampler.next_2d();
        for g in 2..30u32 {
            let numbers = sampler.walk_numbers();
            let expected = group(g);
            assert_eq!(numbers.light, None);
            assert_eq!(numbers.direction, (expected[0], expected[1]), "group {g}");
            assert_eq!((numbers.lobe, numbers.roulette), (expected[2], expected[3]));
        }
    }

    /// The sampler's numbers are the crate's `sample_4d` for the g-th group
    /// it opens, whatever mix of 1D, 2D and vertex starts asks for them.
    #[test]
    fn draws_follow_one_group_after_another() {
        for (pixel, index) in [
            (PixelSeed::new(7, 3, 4), 0u64),
            (PixelSeed::new(1, 0, 9), 70_000),
        ] {
            let mut sampler = Sampler::for_pixel(pixel, index);
            let block = (index / SEQUENCE_LENGTH as u64) as u32;
            let seed = hash_combine(pixel.0, block);
            let i = (index % SEQUENCE_LENGTH as u64) as u32;
            let group = |g: u32| sobol_burley::sample_4d(i, 0, hash_combine(seed, g));
            // A pinhole camera sample, then vertices of light, BSDF and
            // roulette draws, as the path tracer makes them; every third
            // vertex is a mirror's, with no light sample, so vertices start
            // in either of the two groups the sampler makes at a time.
            let (x, y) = sampler.next_2d();
            assert_eq!([x, y], group(0)[..2]);
            let mut next_group = 1;
            // 60 vertices: past the groups whose keys are precomputed.
            for vertex in 0..60u32 {
                sampler.start_vertex();
                if vertex % 3 != 2 {
                    let select = sampler.next_1d();
                    let (u, v) = sampler.next_2d();
                    assert_eq!([select, u, v], group(next_group)[..3], "vertex {vertex}");
                    next_group += 1;
                }
                let (a, b) = sampler.next_2d();
                let (lobe, roulette) = (sampler.next_1d(), sampler.next_1d());
                assert_eq!([a, b, lobe, roulette], group(next_group), "vertex {vertex}");
                next_group += 1;
            }
            assert!(next_group > 64);
        }
    }
}
