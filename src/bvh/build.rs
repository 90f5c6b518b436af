//! Top-down binned SAH construction (Wald, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies", 2007): centroids are binned along each axis,
//! and the split plane between bins with the lowest SAH cost wins.
//!
//! Speed comes from memory order: each triangle's box and index live in one
//! 32-byte record, and the records themselves are partitioned, so every pass
//! reads memory front to back. One pass bins all three axes; the winning
//! split's bin sweep already gives both children's bounds; and the partition
//! pass computes both children's centroid bounds. Big subtrees are built in
//! parallel with `rayon::join`, each into its own array, and `assemble`
//! copies them into the final one in a single parallel pass.

mod assemble;
mod spatial;

use super::{Bvh, Node, INTERSECTION_COST, TRAVERSAL_COST};
use crate::geometry::{Aabb, Triangle};
use assemble::{assemble, Part};
use glam::Vec3;
use rayon::prelude::*;
use wide::{f32x4, f32x8};

/// How the binned SAH build splits.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Bins per axis (2 to 16). 16 is within a few per cent of a full sweep's
    /// SAH cost. Small nodes use fewer: one per triangle at most.
    pub bins: usize,
    /// Ranges of at most this many triangles become leaves, larger ones are
    /// always split. Four matches the wide BVH's leaves, which test four
    /// triangles at once.
    pub max_leaf_size: usize,
    /// Build independent subtrees on the rayon pool the call runs in.
    pub parallel: bool,
    /// Spatial splits (see `spatial.rs`): how many triangle references the
    /// build may add by cutting triangles at split planes, as a fraction of
    /// the triangle count. Zero builds over whole triangles only.
    pub spatial_split_budget: f32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            bins: 16,
            max_leaf_size: 4,
            parallel: true,
            spatial_split_budget: 0.0,
        }
    }
}

const MAX_BINS: usize = 16;

/// Ranges of at least this many prims are binned as two sets (see
/// `Bins::of`). Below it, clearing and adding up the second set (1.7 KB)
/// outweighs the few updates it overlaps. One-thread builds (`tracer
/// bench`, medians of rounds in turn) with 16, 64 and 256: dragon 0.380,
/// 0.387 and 0.393 s, bunny 0.025, 0.025 and 0.026 s, Sponza 0.022, 0.023
/// and 0.024 s, differences inside the spread between rounds of one
/// binary; 16 counts 1.7% more instructions than 64 (perf gate's `bvh-build`).
const TWO_BIN_SETS_MIN: usize = 64;

/// Below this many triangles a subtree is built on the calling thread: the
/// fork costs more than it saves, and big subtrees already keep every thread busy.
const PARALLEL_MIN: usize = 16 * 1024;

/// Depth after which splits fall back to the object median: past it the SAH
/// is peeling off a few triangles at a time (exponentially spaced
/// centroids), and the median bounds the depth, and with it the traversal stack.
const MAX_SAH_DEPTH: usize = 64;

/// A triangle's bounds and index, in one 32-byte record that the build
/// moves around: a [`PackedBox`] whose unused fourth lane holds the index.
#[derive(Clone, Copy, Debug)]
struct Prim {
    bounds: PackedBox,
}

impl Prim {
    fn new(bounds: Aabb, index: usize) -> Prim {
        let mut lanes = PackedBox::of(bounds).lanes.to_array();
        lanes[3] = f32::from_bits(index as u32);
        Prim {
            bounds: PackedBox {
                lanes: f32x8::new(lanes),
            },
        }
    }

    fn index(&self) -> u32 {
        self.bounds.lanes.to_array()[3].to_bits()
    }

    fn aabb(&self) -> Aabb {
        self.bounds.aabb()
    }

    /// Twice the centroid: the factor of two cancels in every comparison.
    #[inline(always)]
    fn centroid2(&self) -> Vec3 {
        let [x, y, z, _] = self.centroid2_lanes().to_array();
        Vec3::new(x, y, z)
    }

    /// The box around `centroid2` alone: the lanes minus the lanes with
    /// their halves swapped give min + max in the first half and its
    /// negation in the second.
    #[inline(always)]
    fn centroid2_box(&self) -> PackedBox {
        let l = self.bounds.lanes.to_array();
        let swapped = f32x8::new([l[4], l[5], l[6], l[7], l[0], l[1], l[2], l[3]]);
        PackedBox {
            lanes: self.bounds.lanes - swapped,
        }
    }

    /// `centroid2` in the first three lanes; the fourth is meaningless.
    #[inline(always)]
    fn centroid2_lanes(&self) -> f32x4 {
        let (min, negated_max) = self.bounds.halves();
        min - negated_max
    }
}

/// A box in one 8-lane vector: the minima in lanes 0-2 and the negated
/// maxima in lanes 4-6 (lanes 3 and 7 are ignored). With the maxima negated,
/// the union of two boxes is a single lane-wise minimum, which halves the
/// work of binning, where every triangle grows three bins.
#[derive(Clone, Copy, Debug)]
struct PackedBox {
    lanes: f32x8,
}

impl PackedBox {
    const EMPTY: PackedBox = PackedBox {
        lanes: f32x8::splat(f32::INFINITY),
    };

    fn of(b: Aabb) -> PackedBox {
        PackedBox {
            lanes: f32x8::new([
                b.min.x, b.min.y, b.min.z, 0.0, -b.max.x, -b.max.y, -b.max.z, 0.0,
            ]),
        }
    }

    /// The minima and the negated maxima.
    #[inline(always)]
    fn halves(self) -> (f32x4, f32x4) {
        let l = self.lanes.to_array();
        (
            f32x4::new([l[0], l[1], l[2], l[3]]),
            f32x4::new([l[4], l[5], l[6], l[7]]),
        )
    }

    #[inline(always)]
    fn grow(&mut self, p: &Prim) {
        *self = self.union(p.bounds);
    }

    #[inline(always)]
    fn union(self, o: PackedBox) -> PackedBox {
        PackedBox {
            lanes: self.lanes.fast_min(o.lanes),
        }
    }

    fn aabb(self) -> Aabb {
        let l = self.lanes.to_array();
        Aabb {
            min: Vec3::new(l[0], l[1], l[2]),
            max: -Vec3::new(l[4], l[5], l[6]),
        }
    }

    #[inline(always)]
    fn half_area(self) -> f32 {
        let (min, negated_max) = self.halves();
        let [x, y, z, _] = (-(min + negated_max)).fast_max(f32x4::ZERO).to_array();
        x * y + y * z + z * x
    }
}

/// A range of prims with its bounds and the bounds of its (doubled) centroids.
#[derive(Clone, Copy)]
struct Range {
    bounds: Aabb,
    centroids: Aabb,
}

/// One range's centroids binned along all three axes: each bin's box and
/// triangle count. Boxes and counts are kept apart, so the empty bins are
/// 1.7 KB to clear rather than 2.3 KB of padded records, and the bins are
/// filled in place: clearing and copying them had taken a tenth of the
/// build's instructions, most ranges being a few dozen triangles.
struct Bins {
    bounds: [[PackedBox; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    const EMPTY: Bins = Bins {
        bounds: [[PackedBox::EMPTY; MAX_BINS]; 3],
        counts: [[0; MAX_BINS]; 3],
    };

    #[inline(always)]
    fn add(&mut self, binner: &Binner, prims: &[Prim]) {
        for p in prims {
            self.add_one(binner, p);
        }
    }

    #[inline(always)]
    fn add_one(&mut self, binner: &Binner, p: &Prim) {
        let b = binner.bins_of(p.centroid2_lanes());
        for ((bounds, counts), &k) in self.bounds.iter_mut().zip(&mut self.counts).zip(&b) {
            // `bins_of` is already below MAX_BINS; the mask says so to
            // the compiler, which then drops the bounds check.
            let k = k & (MAX_BINS - 1);
            bounds[k].grow(p);
            counts[k] += 1;
        }
    }

    /// The bins of `prims`, filled as two sets that take alternate prims
    /// and are added up at the end. Neighbouring prims lie close together
    /// (a mesh's triangles, and every range after a partition), so they
    /// mostly fall in the same bins; with one set, each update of a bin
    /// waits for the previous one's store, a chain through memory. Two sets
    /// make two chains, each half as long, that the core runs side by side.
    fn of(binner: &Binner, prims: &[Prim]) -> Bins {
        let mut even = Bins::EMPTY;
        if prims.len() < TWO_BIN_SETS_MIN {
            even.add(binner, prims);
            return even;
        }
        let mut odd = Bins::EMPTY;
        let (pairs, rest) = prims.as_chunks::<2>();
        for [a, b] in pairs {
            even.add_one(binner, a);
            odd.add_one(binner, b);
        }
        even.add(binner, rest);
        even.merge(&odd)
    }

    fn merge(mut self, other: &Bins) -> Bins {
        for axis in 0..3 {
            for k in 0..MAX_BINS {
                self.bounds[axis][k] = self.bounds[axis][k].union(other.bounds[axis][k]);
                self.counts[axis][k] += other.counts[axis][k];
            }
        }
        self
    }
}

/// The best plane found: prims in bins `< bin` along `axis` go left.
struct Split {
    axis: usize,
    bin: usize,
    cost: f32,
    left: Aabb,
    right: Aabb,
}

/// Maps doubled centroids to bins along each axis.
/// Origin and scale hold x, y, z in their first three lanes (the fourth zero).
struct Binner {
    origin4: f32x4,
    scale4: f32x4,
    last_bin: f32x4,
}

impl Binner {
    fn new(centroids: Aabb, bins: usize) -> Binner {
        let extent = centroids.extent();
        // Slightly under bins/extent so the largest centroid lands in the last bin.
        let scale = Vec3::select(
            extent.cmpgt(Vec3::ZERO),
            Vec3::splat(bins as f32 * (1.0 - 1e-6)) / extent,
            Vec3::ZERO,
        );
        let origin = centroids.min;
        Binner {
            origin4: f32x4::new(origin.extend(0.0).to_array()),
            scale4: f32x4::new(scale.extend(0.0).to_array()),
            last_bin: f32x4::splat((bins - 1) as f32),
        }
    }

    /// Whether centroid `c` falls in a bin below `bin` (at least 1) along
    /// `axis`: `bins_of(c)[axis] < bin` for every finite centroid, as one
    /// comparison.
    #[inline(always)]
    fn below(&self, c: f32x4, axis: usize, bin: usize) -> bool {
        // All three axes in one vector: picking the axis's lane out of the
        // comparison's mask is cheaper than picking its coordinate out of `c`.
        let x = (c - self.origin4) * self.scale4;
        (x.simd_lt(f32x4::splat(bin as f32)).to_bitmask() >> axis) & 1 != 0
    }

    /// The bin of centroid `c` along each axis. Clamped to the bins while
    /// still floating point (a NaN becomes bin 0, as `max` returns its second
    /// operand), so the truncation is one instruction with no overflow
    /// check: float-to-integer casts that saturate were a seventh of the
    /// build's instructions.
    #[inline(always)]
    fn bins_of(&self, c: f32x4) -> [usize; 3] {
        let x = (c - self.origin4) * self.scale4;
        let b = x
            .fast_max(f32x4::ZERO)
            .fast_min(self.last_bin)
            .fast_trunc_int()
            .to_array();
        [b[0] as usize, b[1] as usize, b[2] as usize]
    }
}

impl Bvh {
    /// Builds over `triangles` with `options`; hits report indices into this slice.
    pub fn build_with(triangles: &[Triangle], options: &BuildOptions) -> Bvh {
        let (nodes, original_index) = build_tree(triangles, options);
        Bvh {
            triangles: original_index
                .iter()
                .map(|&i| triangles[i as usize])
                .collect(),
            original_index,
            nodes,
        }
    }
}

/// The binary tree's nodes and the leaf order of the triangles (the
/// caller's index of each), without gathering the triangles themselves.
pub(super) fn build_tree(triangles: &[Triangle], options: &BuildOptions) -> (Vec<Node>, Vec<u32>) {
    let make = |(i, t): (usize, &Triangle)| Prim::new(Aabb::from_points(&t.v), i);
    let mut prims: Vec<Prim> = if options.parallel {
        triangles.par_iter().enumerate().map(make).collect()
    } else {
        triangles.iter().enumerate().map(make).collect()
    };
    let options = BuildOptions {
        bins: options.bins.clamp(2, MAX_BINS),
        max_leaf_size: options.max_leaf_size.max(1),
        parallel: options.parallel,
        spatial_split_budget: options.spatial_split_budget,
    };
    if options.spatial_split_budget > 0.0 && !prims.is_empty() {
        return spatial::build_tree(triangles, prims, &options);
    }
    // No root at all for no triangles: traversal checks for this and reports no hit.
    let nodes = if prims.is_empty() {
        Vec::new()
    } else {
        let range = measure(&prims, options.parallel);
        assemble(
            build_subtree(&options, &mut prims, range, 0, 0),
            options.parallel,
        )
    };
    let order = if options.parallel {
        prims.par_iter().map(Prim::index).collect()
    } else {
        prims.iter().map(Prim::index).collect()
    };
    (nodes, order)
}

/// The bounds and centroid bounds of `prims`, in chunks on the rayon pool
/// when `parallel` and there are many (minima and maxima are exact, so the
/// chunking changes nothing).
fn measure(prims: &[Prim], parallel: bool) -> Range {
    let one = |prims: &[Prim]| {
        let mut bounds = PackedBox::EMPTY;
        let mut centroids = Aabb::EMPTY;
        for p in prims {
            bounds.grow(p);
            centroids = centroids.grow(p.centroid2());
        }
        (bounds, centroids)
    };
    let (bounds, centroids) = if parallel && prims.len() >= 4 * PARALLEL_MIN {
        prims.par_chunks(PARALLEL_MIN).map(one).reduce(
            || (PackedBox::EMPTY, Aabb::EMPTY),
            |a, b| (a.0.union(b.0), a.1.union(b.1)),
        )
    } else {
        one(prims)
    };
    Range {
        bounds: bounds.aabb(),
        centroids,
    }
}

/// Where to split a range: `None` makes it a leaf; otherwise the count
/// going left and both children's ranges. Reorders `prims` accordingly.
fn split(
    options: &BuildOptions,
    prims: &mut [Prim],
    range: Range,
    depth: usize,
) -> Option<(usize, Range, Range)> {
    let count = prims.len();
    // A range that fits a leaf becomes one unless its best split into two
    // blocks pays for the node it adds (see `small_split_pays`); the
    // collapse asks the same question of the same boxes, so it keeps
    // exactly these splits.
    if count <= options.max_leaf_size {
        if count < 2 || depth >= MAX_SAH_DEPTH {
            return None;
        }
        return small_split(prims, range);
    }
    // Anything larger is split, by the SAH's best plane where there is one.
    if depth >= MAX_SAH_DEPTH || range.centroids.extent().max_element() <= 0.0 {
        // Too deep, or all centroids coincide and no plane separates them.
        return Some(median_split(prims, range));
    }
    // More bins than triangles only adds empty planes to sweep.
    let bins = options.bins.min(count.max(4));
    let best = find_split(prims, range, bins, options.parallel);
    let binner = Binner::new(range.centroids, bins);
    let (axis, bin) = (best.axis, best.bin);
    let goes_left = |p: &Prim| binner.below(p.centroid2_lanes(), axis, bin);
    let (mid, left_centroids, right_centroids) = partition(prims, goes_left);
    if mid == 0 || mid == count {
        // Cannot happen with a proper centroid extent, but never loop forever.
        return Some(median_split(prims, range));
    }
    Some((
        mid,
        Range {
            bounds: best.left,
            centroids: left_centroids,
        },
        Range {
            bounds: best.right,
            centroids: right_centroids,
        },
    ))
}

/// Bins every prim along all three axes in one pass, then sweeps each axis
/// for the cheapest plane.
fn find_split(prims: &[Prim], range: Range, bins: usize, parallel: bool) -> Split {
    let binner = Binner::new(range.centroids, bins);
    // The top levels' binning would otherwise run on one thread while the
    // others wait: bin chunks in parallel and add the bins up.
    let binned = if parallel && prims.len() >= 4 * PARALLEL_MIN {
        prims
            .par_chunks(PARALLEL_MIN)
            .map(|chunk| Bins::of(&binner, chunk))
            .reduce(|| Bins::EMPTY, |a, b| a.merge(&b))
    } else {
        Bins::of(&binner, prims)
    };
    let parent_area = half_area(range.bounds).max(f32::MIN_POSITIVE);
    let mut best = Split {
        axis: 0,
        bin: 0,
        cost: f32::INFINITY,
        left: Aabb::EMPTY,
        right: Aabb::EMPTY,
    };
    let extent = range.centroids.extent();
    for (axis, (boxes, counts)) in binned.bounds.iter().zip(&binned.counts).enumerate() {
        if extent[axis] <= 0.0 {
            continue;
        }
        // Sweep from the right, then from the left, evaluating each plane
        // once. (`spatial::sweep` does the same for spatial bins; written out
        // here, the object-only build took 10% fewer instructions.)
        let mut right = [(0f32, 0u32); MAX_BINS];
        let (mut acc, mut n) = (PackedBox::EMPTY, 0);
        for k in (1..bins).rev() {
            acc = acc.union(boxes[k]);
            n += counts[k];
            right[k] = (acc.half_area(), n);
        }
        let (mut acc, mut n) = (PackedBox::EMPTY, 0);
        for k in 1..bins {
            acc = acc.union(boxes[k - 1]);
            n += counts[k - 1];
            let (right_area, right_count) = right[k];
            if n == 0 || right_count == 0 {
                continue;
            }
            let cost = split_cost(acc.half_area(), n, right_area, right_count, parent_area);
            if cost < best.cost {
                best = Split {
                    axis,
                    bin: k,
                    cost,
                    left: acc.aabb(),
                    right: Aabb::EMPTY,
                };
            }
        }
    }
    if best.cost.is_finite() {
        best.right = binned.bounds[best.axis][best.bin..bins]
            .iter()
            .fold(PackedBox::EMPTY, |b, &bin| b.union(bin))
            .aabb();
    }
    best
}

/// The split of a range of two to four triangles
/// into two blocks with the least total box area, where it pays for its
/// node (`small_split_pays`); `None` keeps the range one leaf. Tries every
/// cut of the triangles sorted by centroid along the axis where centroids
/// spread most. A third of the build's ranges are this small: weighing
/// them this way adds about 6% to the build's instructions (the perf
/// gate's `bvh-build`), where binning them on three axes added 11%.
fn small_split(prims: &mut [Prim], range: Range) -> Option<(usize, Range, Range)> {
    let count = prims.len();
    debug_assert!((2..=4).contains(&count));
    let axis = range.centroids.extent().max_position();
    // Sort by centroid along `axis` (insertion sort of at most four).
    let mut sorted = [prims[0]; 4];
    sorted[..count].copy_from_slice(prims);
    let key = |p: &Prim| p.centroid2()[axis];
    for i in 1..count {
        let mut j = i;
        while j > 0 && key(&sorted[j - 1]) > key(&sorted[j]) {
            sorted.swap(j - 1, j);
            j -= 1;
        }
    }
    let mut right = [PackedBox::EMPTY; 4];
    let mut acc = PackedBox::EMPTY;
    for k in (1..count).rev() {
        acc.grow(&sorted[k]);
        right[k] = acc;
    }
    let (mut best_area, mut best_cut) = (f32::INFINITY, 0);
    let mut left = PackedBox::EMPTY;
    let mut lefts = [PackedBox::EMPTY; 4];
    for cut in 1..count {
        left.grow(&sorted[cut - 1]);
        lefts[cut] = left;
        let area = left.half_area() + right[cut].half_area();
        if area < best_area {
            (best_area, best_cut) = (area, cut);
        }
    }
    let (left, right) = (lefts[best_cut].aabb(), right[best_cut].aabb());
    if !super::small_split_pays(range.bounds, left, right) {
        return None;
    }
    prims.copy_from_slice(&sorted[..count]);
    let centroids_of =
        |prims: &[Prim]| prims.iter().fold(Aabb::EMPTY, |c, p| c.grow(p.centroid2()));
    Some((
        best_cut,
        Range {
            bounds: left,
            centroids: centroids_of(&prims[..best_cut]),
        },
        Range {
            bounds: right,
            centroids: centroids_of(&prims[best_cut..]),
        },
    ))
}

/// The SAH cost of a split into children of the given half areas and
/// triangle counts, under a parent of half area `parent_area`. Triangles are
/// tested four at a time: a side costs one test per block of four, which
/// steers splits towards full leaves.
#[inline(always)]
fn split_cost(left_area: f32, left: u32, right_area: f32, right: u32, parent_area: f32) -> f32 {
    let blocks = |n: u32| n.div_ceil(4) as f32;
    TRAVERSAL_COST
        + INTERSECTION_COST * (left_area * blocks(left) + right_area * blocks(right)) / parent_area
}

/// Half the surface area of `b` (zero for an empty box).
fn half_area(b: Aabb) -> f32 {
    let e = b.extent();
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// Moves the prims for which `goes_left` holds to the front; returns their
/// count and the centroid bounds of both sides.
///
/// Without branches on the side (Lomuto's scheme, each prim swapped with
/// the first one of the right side whichever side it takes): which side a
/// prim takes is a coin toss to the branch predictor, and its misses had
/// been a third of the build's.
fn partition(prims: &mut [Prim], goes_left: impl Fn(&Prim) -> bool) -> (usize, Aabb, Aabb) {
    // The sides' centroid bounds, grown in registers: each side takes the
    // centroid or, on the other side, an empty box. Indexing an array of the
    // two by the side kept them in memory, so that each prim's update waited
    // on the previous one's store.
    let empty = PackedBox::EMPTY.lanes;
    let (mut left_box, mut right_box) = (empty, empty);
    let mut left_count = 0;
    for i in 0..prims.len() {
        let prim = prims[i];
        let left = goes_left(&prim);
        let centroid = prim.centroid2_box().lanes;
        let mask = f32x8::splat(f32::from_bits(0u32.wrapping_sub(left as u32)));
        left_box = left_box.fast_min(mask.select(centroid, empty));
        right_box = right_box.fast_min(mask.select(empty, centroid));
        prims[i] = prims[left_count];
        prims[left_count] = prim;
        left_count += left as usize;
    }
    let aabb = |lanes| PackedBox { lanes }.aabb();
    (left_count, aabb(left_box), aabb(right_box))
}

/// Splits at the median centroid along the widest centroid axis (by index
/// when all centroids coincide).
fn median_split(prims: &mut [Prim], range: Range) -> (usize, Range, Range) {
    let e = range.centroids.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        a.centroid2()[axis]
            .total_cmp(&b.centroid2()[axis])
            .then(a.index().cmp(&b.index()))
    });
    let (l, r) = prims.split_at(mid);
    (mid, measure(l, false), measure(r, false))
}

/// Builds the subtree over `prims`, whose first entry is triangle `offset`
/// in leaf order: ranges of at least `PARALLEL_MIN` are split here (their
/// halves built in parallel when `options.parallel`), smaller ones built
/// whole by `build_sequential`. The parts are the same either way.
fn build_subtree(
    options: &BuildOptions,
    prims: &mut [Prim],
    range: Range,
    offset: usize,
    depth: usize,
) -> Part {
    if prims.len() < PARALLEL_MIN {
        return Part::Whole(build_sequential(options, prims, range, offset, depth));
    }
    let Some((mid, left_range, right_range)) = split(options, prims, range, depth) else {
        return Part::Whole(vec![Node {
            bounds: range.bounds,
            first: offset as u32,
            count: prims.len() as u32,
        }]);
    };
    let (left_prims, right_prims) = prims.split_at_mut(mid);
    let mut left = move || build_subtree(options, left_prims, left_range, offset, depth + 1);
    let mut right =
        move || build_subtree(options, right_prims, right_range, offset + mid, depth + 1);
    let children = if options.parallel {
        rayon::join(left, right)
    } else {
        (left(), right())
    };
    Part::Split {
        bounds: range.bounds,
        children: Box::new([children.0, children.1]),
    }
}

/// The nodes of a subtree with root box `bounds` whose two children were
/// built apart (each root first): [root, left root, right root, rest of
/// left, rest of right], exactly what the sequential builders produce.
/// The right subtree's leaves move `right_leaf_shift` further along the
/// leaf order.
fn join_subtrees(bounds: Aabb, left: &[Node], right: &[Node], right_leaf_shift: u32) -> Vec<Node> {
    let left_index = |i: u32| if i == 0 { 1 } else { i + 2 };
    let right_shift = left.len() as u32 + 1;
    let right_index = |i: u32| if i == 0 { 2 } else { i + right_shift };
    let relink = |n: &Node, map: &dyn Fn(u32) -> u32, leaf_shift: u32| {
        let first = if n.is_leaf() {
            n.first + leaf_shift
        } else {
            map(n.first)
        };
        Node { first, ..*n }
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node {
        bounds,
        first: 1,
        count: 0,
    });
    nodes.push(relink(&left[0], &left_index, 0));
    nodes.push(relink(&right[0], &right_index, right_leaf_shift));
    nodes.extend(left[1..].iter().map(|n| relink(n, &left_index, 0)));
    nodes.extend(
        right[1..]
            .iter()
            .map(|n| relink(n, &right_index, right_leaf_shift)),
    );
    nodes
}

const UNSET: Node = Node {
    bounds: Aabb::EMPTY,
    first: 0,
    count: 0,
};

fn build_sequential(
    options: &BuildOptions,
    prims: &mut [Prim],
    range: Range,
    offset: usize,
    depth: usize,
) -> Vec<Node> {
    let mut nodes = Vec::with_capacity(prims.len() / 2 + 1);
    nodes.push(UNSET);
    // Work list of (node, first, end, range, depth); an explicit stack keeps
    // deep, unbalanced trees from overflowing the call stack.
    let mut work = vec![(0usize, 0usize, prims.len(), range, depth)];
    while let Some((node, first, end, range, depth)) = work.pop() {
        let Some((mid, left_range, right_range)) =
            split(options, &mut prims[first..end], range, depth)
        else {
            nodes[node] = Node {
                bounds: range.bounds,
                first: (offset + first) as u32,
                count: (end - first) as u32,
            };
            continue;
        };
        let left = nodes.len();
        nodes.push(UNSET);
        nodes.push(UNSET);
        nodes[node] = Node {
            bounds: range.bounds,
            first: left as u32,
            count: 0,
        };
        work.push((left + 1, first + mid, end, right_range, depth + 1));
        work.push((left, first, first + mid, left_range, depth + 1));
    }
    nodes
}
