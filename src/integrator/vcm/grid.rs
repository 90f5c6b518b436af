//! A hash grid over points, for finding every point within a fixed radius
//! of a query (the light vertices a camera vertex merges with).
//!
//! Cells are cubes of twice the radius, so a query's ball touches at most
//! the 2 × 2 × 2 cells around the nearest cell corner. Cells are hashed into
//! twice as many buckets as there are points (rounded up to a power of
//! two), and a counting sort lays the points out bucket by bucket, in their
//! original order within a bucket: the grid, and so every sum over a
//! query's points, is the same whatever the thread count.
//!
//! A query's cost is its cache misses: the grid of a large image holds
//! hundreds of thousands of points. A bit per bucket (a few tens of KB,
//! which stays in cache) says which buckets hold anything, so empty ones
//! cost no trip to memory, and the grid keeps its own copy of each point,
//! small and stored bucket by bucket, so a visited bucket costs one miss.
//! Its buffers are kept from one build to the next.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Something with a position, that a grid can hold.
pub trait Located: Copy + Default + Send + Sync {
    fn position(&self) -> Vec3;
}

/// Points gathered by hashed cell.
pub struct HashGrid<T> {
    /// Cells are found in double precision: a small radius in a large
    /// scene puts cell coordinates beyond what an f32 resolves.
    origin: DVec3,
    /// 1 / cell edge.
    inverse_cell: f64,
    radius2: f32,
    /// Bucket count − 1 (a power of two less one).
    mask: u64,
    /// Bit `b` is set when bucket `b` holds a point.
    occupied: Vec<u64>,
    /// Bucket `b` holds `entries[starts[b] .. starts[b + 1]]`.
    starts: Vec<u32>,
    /// The points, bucket by bucket.
    entries: Vec<T>,
    /// Scratch for a build: each point's bucket, then each bucket's next slot.
    keys: Vec<u32>,
    next: Vec<u32>,
}

impl<T: Located> HashGrid<T> {
    /// An empty grid.
    pub fn new() -> HashGrid<T> {
        HashGrid {
            origin: DVec3::ZERO,
            inverse_cell: 1.0,
            radius2: 0.0,
            mask: 0,
            occupied: Vec::new(),
            starts: vec![0; 2],
            entries: Vec::new(),
            keys: Vec::new(),
            next: Vec::new(),
        }
    }

    /// Replaces the grid's contents with `points`, for queries of `radius`
    /// (> 0). Cell keys are computed in parallel on the current rayon pool.
    pub fn rebuild(&mut self, points: &[T], radius: f32) {
        let n = points.len();
        let origin = points
            .iter()
            .fold(Vec3::splat(f32::INFINITY), |m, p| m.min(p.position()));
        self.origin = if origin.is_finite() {
            origin.as_dvec3()
        } else {
            DVec3::ZERO
        };
        self.inverse_cell = 1.0 / (2.0 * radius as f64);
        self.radius2 = radius * radius;
        let buckets = (2 * n).max(64).next_power_of_two();
        self.mask = buckets as u64 - 1;
        reset(&mut self.occupied, buckets / 64, 0);
        reset(&mut self.starts, buckets + 1, 0);
        let mut keys = std::mem::take(&mut self.keys);
        keys.clear();
        let grid = &*self;
        keys.par_extend(
            points
                .par_iter()
                .with_min_len(4096)
                .map(|p| grid.bucket(grid.cell(p.position()))),
        );
        for &k in &keys {
            self.starts[k as usize + 1] += 1;
            self.occupied[k as usize / 64] |= 1 << (k % 64);
        }
        for b in 0..buckets {
            self.starts[b + 1] += self.starts[b];
        }
        let mut next = std::mem::take(&mut self.next);
        next.clear();
        next.extend_from_slice(&self.starts);
        reset(&mut self.entries, n, T::default());
        for (point, &k) in points.iter().zip(&keys) {
            let slot = &mut next[k as usize];
            self.entries[*slot as usize] = *point;
            *slot += 1;
        }
        self.keys = keys;
        self.next = next;
    }

    /// The cell coordinates of `p`, relative to the grid's origin.
    fn cell_of(&self, p: Vec3) -> DVec3 {
        (p.as_dvec3() - self.origin) * self.inverse_cell
    }

    fn cell(&self, p: Vec3) -> [i64; 3] {
        let c = self.cell_of(p).floor();
        // `as` saturates: a point absurdly far from the rest still gets a cell.
        [c.x as i64, c.y as i64, c.z as i64]
    }

    fn bucket(&self, [x, y, z]: [i64; 3]) -> u32 {
        // Three large odd multipliers spread neighbouring cells over the table.
        let h = (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
            ^ (y as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
            ^ (z as u64).wrapping_mul(0x1656_67b1_9e37_79f9);
        ((h ^ (h >> 29)) & self.mask) as u32
    }

    /// Calls `visit` with every point within the radius of `p` (distance ≤
    /// radius), each exactly once, in a fixed order.
    #[inline]
    pub fn for_each_near(&self, p: Vec3, mut visit: impl FnMut(&T)) {
        if self.entries.is_empty() {
            return;
        }
        let rel = self.cell_of(p);
        let c = rel.floor();
        let frac = rel - c;
        let base = [c.x as i64, c.y as i64, c.z as i64];
        // Towards the nearer neighbour along each axis.
        let step = [frac.x, frac.y, frac.z].map(|f| if f < 0.5 { -1 } else { 1 });
        let mut seen = [u32::MAX; 8];
        for corner in 0..8usize {
            let cell = [0, 1, 2]
                .map(|a| base[a].wrapping_add(if corner >> a & 1 == 1 { step[a] } else { 0 }));
            let b = self.bucket(cell);
            // Two cells may share a bucket: visit its points once.
            if self.occupied[b as usize / 64] & (1 << (b % 64)) == 0 || seen[..corner].contains(&b)
            {
                continue;
            }
            seen[corner] = b;
            let (start, end) = (self.starts[b as usize], self.starts[b as usize + 1]);
            for e in &self.entries[start as usize..end as usize] {
                if (e.position() - p).length_squared() <= self.radius2 {
                    visit(e);
                }
            }
        }
    }

    /// Points in the grid.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the grid holds no points.
    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

impl<T: Located> Default for HashGrid<T> {
    fn default() -> Self {
        HashGrid::new()
    }
}

/// Makes `v` hold `n` copies of `value`, keeping its allocation.
fn reset<T: Clone>(v: &mut Vec<T>, n: usize, value: T) {
    v.clear();
    v.resize(n, value);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Default)]
    struct Point(Vec3, u32);

    impl Located for Point {
        fn position(&self) -> Vec3 {
            self.0
        }
    }

    fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Every query finds exactly the points a brute-force search finds,
    /// each once, with points clustered so that buckets collide.
    #[test]
    fn finds_exactly_the_points_within_the_radius() {
        let mut s = 7u64;
        let mut points: Vec<Vec3> = (0..3000)
            .map(|_| Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 4.0 - 2.0)
            .collect();
        // A dense cluster and exact duplicates.
        points.extend((0..200).map(|i| Vec3::splat(0.3) + Vec3::X * (i % 7) as f32 * 1e-3));
        let indexed: Vec<Point> = points
            .iter()
            .enumerate()
            .map(|(i, p)| Point(*p, i as u32))
            .collect();
        // One grid rebuilt for every radius, as the renderer reuses its grid.
        let mut grid = HashGrid::new();
        for radius in [0.01, 0.07, 0.3, 5.0] {
            grid.rebuild(&indexed, radius);
            assert_eq!(grid.len(), points.len());
            for q in 0..300 {
                let p = if q % 3 == 0 {
                    points[q * 7]
                } else {
                    Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 4.4 - 2.2
                };
                let mut found = Vec::new();
                grid.for_each_near(p, |point| found.push(point.1));
                let mut expected: Vec<u32> = (0..points.len() as u32)
                    .filter(|&i| (points[i as usize] - p).length_squared() <= radius * radius)
                    .collect();
                found.sort_unstable();
                expected.sort_unstable();
                assert_eq!(found, expected, "radius {radius}, query {p}");
            }
        }
    }

    #[test]
    fn an_empty_grid_finds_nothing() {
        let mut grid = HashGrid::<Point>::new();
        grid.for_each_near(Vec3::ZERO, |_| panic!("found a point in a new grid"));
        grid.rebuild(&[], 0.1);
        assert!(grid.is_empty());
        grid.for_each_near(Vec3::ZERO, |_| panic!("found a point in an empty grid"));
    }
}
