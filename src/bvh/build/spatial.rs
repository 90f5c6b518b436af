//! Spatial splits: the SBVH of Stich, Friedrich and Dietrich, "Spatial
//! Splits in Bounding Volume Hierarchies" (HPG 2009).
//!
//! Where the best object split leaves its two children overlapping (large
//! or long thin triangles straddling the plane), the builder also weighs
//! splitting space itself: planes evenly spaced across the node, with each
//! triangle that crosses the chosen plane clipped to either side, so the
//! references on each side are boxed tightly and the children no longer
//! overlap. A triangle cut this way is referenced from both children (a
//! ray that visits both tests it twice; the hit is the same). How many
//! references a build may add is capped by a budget, shared out between a
//! node's children in proportion to their sizes, so the tree depends on
//! the input alone, never on which thread built what.
//!
//! The references travel in vectors that each split hands to its children,
//! rather than the object-split builder's in-place partition, since a
//! spatial split can grow their number.

use super::{
    find_split, half_area, join_subtrees, measure, median_split, partition, split_cost, Binner,
    BuildOptions, PackedBox, Prim, Range, MAX_BINS, MAX_SAH_DEPTH, PARALLEL_MIN, UNSET,
};
use crate::bvh::Node;
use crate::geometry::{Aabb, Triangle};
use glam::Vec3;
use rayon::prelude::*;

/// Candidate planes per axis, evenly spaced across the node's box.
const SPATIAL_BINS: usize = 16;
const _: () = assert!(SPATIAL_BINS <= MAX_BINS, "the sweep holds MAX_BINS planes");

/// Spatial splits are weighed only where the best object split's children
/// overlap by more than this fraction of the root's area (Stich et al.'s
/// α): elsewhere no plane could do much better, and deep in the tree the
/// overlaps are tiny, so the extra sweep is skipped for most nodes.
const MIN_OVERLAP: f32 = 1e-5;

/// Nodes with fewer references than this are split by objects only. Their
/// triangles cross most of the (small) slabs, which makes the spatial sweep
/// costly, and below them it buys little: on Sponza (sponza.obj), skipping
/// them kept the SAH cost at 15.70 (15.69 with them) and took 40% less
/// build time.
const MIN_SPATIAL_REFS: usize = 64;

/// The references of a node still to be built, with their bounds, depth,
/// and how many more references its subtree may add.
struct Task {
    prims: Vec<Prim>,
    range: Range,
    depth: usize,
    budget: usize,
}

enum Outcome {
    Leaf(Vec<Prim>),
    Split(Task, Task),
}

/// One spatial bin along one axis: the box of the triangles' parts that
/// lie in its slab, and how many references start and end in it.
#[derive(Clone, Copy)]
struct SpatialBin {
    bounds: PackedBox,
    entries: u32,
    exits: u32,
}

const EMPTY_SPATIAL_BIN: SpatialBin = SpatialBin {
    bounds: PackedBox::EMPTY,
    entries: 0,
    exits: 0,
};

type SpatialBins = [[SpatialBin; SPATIAL_BINS]; 3];

struct SpatialSplit {
    axis: usize,
    plane: f32,
    cost: f32,
}

struct Builder<'a> {
    triangles: &'a [Triangle],
    options: &'a BuildOptions,
    /// Half the root's surface area, which overlaps are measured against.
    root_area: f32,
}

/// Builds the binary tree over `prims` (one per triangle of `triangles`)
/// with spatial splits; returns its nodes and the leaf order, in which a
/// triangle cut by a split appears once per reference.
pub(super) fn build_tree(
    triangles: &[Triangle],
    prims: Vec<Prim>,
    options: &BuildOptions,
) -> (Vec<Node>, Vec<u32>) {
    let fraction = options.spatial_split_budget.clamp(0.0, 16.0) as f64;
    let budget = (prims.len() as f64 * fraction) as usize;
    let range = measure(&prims, false);
    let builder = Builder {
        triangles,
        options,
        root_area: half_area(range.bounds),
    };
    builder.subtree(Task {
        prims,
        range,
        depth: 0,
        budget,
    })
}

fn aabb_of(p: &Prim) -> Aabb {
    p.aabb()
}

fn intersection(a: Aabb, b: Aabb) -> Aabb {
    Aabb {
        min: a.min.max(b.min),
        max: a.max.min(b.max),
    }
}

/// A triangle seen along one axis: its vertices sorted by that coordinate,
/// so that the cross-section at any plane between the first and the last
/// is the segment between a point on the long edge (first to last) and a
/// point on one of the two short ones.
struct Slices {
    v: [Vec3; 3],
    axis: usize,
    /// The long edge and the two short ones, each divided by its extent
    /// along `axis` (zero for an edge with none): a point at coordinate
    /// `x` lies `x - start` along it.
    long: Vec3,
    short: [Vec3; 2],
    /// A bound on the rounding error of a point computed on an edge, on
    /// the other two axes (the one along `axis` is set exactly).
    pad: Vec3,
}

impl Slices {
    fn new(triangle: &[Vec3; 3], axis: usize) -> Slices {
        let mut v = *triangle;
        // Three compare-and-swaps sort three vertices.
        for (i, j) in [(0, 1), (1, 2), (0, 1)] {
            if v[j][axis] < v[i][axis] {
                v.swap(i, j);
            }
        }
        let per_unit = |p: Vec3, q: Vec3| {
            let d = q[axis] - p[axis];
            if d > 0.0 {
                (q - p) / d
            } else {
                Vec3::ZERO
            }
        };
        let mut pad = v[0].abs().max(v[1].abs()).max(v[2].abs()) * (4.0 * f32::EPSILON);
        pad[axis] = 0.0;
        Slices {
            v,
            axis,
            long: per_unit(v[0], v[2]),
            short: [per_unit(v[0], v[1]), per_unit(v[1], v[2])],
            pad,
        }
    }

    /// A box around the cross-section at `x`: empty unless `x` lies
    /// strictly between the first and last vertex.
    fn section(&self, x: f32) -> Aabb {
        let [p, m, q] = self.v;
        let a = self.axis;
        if !(p[a] < x && x < q[a]) {
            return Aabb::EMPTY;
        }
        let mut long = p + self.long * (x - p[a]);
        let mut short = if x < m[a] {
            p + self.short[0] * (x - p[a])
        } else {
            m + self.short[1] * (x - m[a])
        };
        long[a] = x;
        short[a] = x;
        Aabb {
            min: long.min(short) - self.pad,
            max: long.max(short) + self.pad,
        }
    }

    /// A box around the part of the triangle with `lo ≤ x ≤ hi` along the
    /// axis that also lies in `within`, given the boxes of the
    /// cross-sections at `lo` and `hi`; empty when there is no such part.
    /// The part is convex: its corners are the vertices inside the slab
    /// and the ends of the two cross-sections, so their box holds it, and
    /// the padding keeps rounding from shrinking it.
    fn piece(&self, lo: (f32, Aabb), hi: (f32, Aabb), within: Aabb) -> Aabb {
        let a = self.axis;
        let mut b = lo.1.union(hi.1);
        for p in self.v {
            if lo.0 <= p[a] && p[a] <= hi.0 {
                b = b.grow(p);
            }
        }
        let mut b = intersection(b, within);
        b.min[a] = b.min[a].max(lo.0);
        b.max[a] = b.max[a].min(hi.0);
        b
    }

    /// The part on each side of plane `x`, within `within`.
    fn halves(&self, x: f32, within: Aabb) -> (Aabb, Aabb) {
        let cut = (x, self.section(x));
        (
            self.piece((f32::NEG_INFINITY, Aabb::EMPTY), cut, within),
            self.piece(cut, (f32::INFINITY, Aabb::EMPTY), within),
        )
    }
}

impl Builder<'_> {
    fn subtree(&self, task: Task) -> (Vec<Node>, Vec<u32>) {
        if !self.options.parallel || task.prims.len() < PARALLEL_MIN {
            return self.sequential(task);
        }
        let bounds = task.range.bounds;
        let ((left, left_order), (right, right_order)) = match self.split(task) {
            Outcome::Leaf(prims) => {
                let order = prims.iter().map(Prim::index).collect();
                return (vec![leaf(bounds, 0, &prims)], order);
            }
            Outcome::Split(l, r) => rayon::join(|| self.subtree(l), || self.subtree(r)),
        };
        let nodes = join_subtrees(bounds, &left, &right, left_order.len() as u32);
        let mut order = left_order;
        order.extend(right_order);
        (nodes, order)
    }

    fn sequential(&self, task: Task) -> (Vec<Node>, Vec<u32>) {
        let mut nodes = vec![UNSET];
        let mut order = Vec::with_capacity(task.prims.len());
        // Left before right, so every subtree's triangles are contiguous
        // in the leaf order.
        let mut work = vec![(0usize, task)];
        while let Some((node, task)) = work.pop() {
            let bounds = task.range.bounds;
            match self.split(task) {
                Outcome::Leaf(prims) => {
                    nodes[node] = leaf(bounds, order.len(), &prims);
                    order.extend(prims.iter().map(Prim::index));
                }
                Outcome::Split(l, r) => {
                    let left = nodes.len();
                    nodes.push(UNSET);
                    nodes.push(UNSET);
                    nodes[node] = Node {
                        bounds,
                        first: left as u32,
                        count: 0,
                    };
                    work.push((left + 1, r));
                    work.push((left, l));
                }
            }
        }
        (nodes, order)
    }

    fn split(&self, task: Task) -> Outcome {
        let Task {
            mut prims,
            range,
            depth,
            budget,
        } = task;
        let count = prims.len();
        if count <= self.options.max_leaf_size {
            return Outcome::Leaf(prims);
        }
        if depth >= MAX_SAH_DEPTH || range.centroids.extent().max_element() <= 0.0 {
            let (mid, left, right) = median_split(&mut prims, range);
            return object_children(prims, mid, left, right, depth, budget);
        }
        let bins = self.options.bins.min(count.max(4));
        let object = find_split(&prims, range, bins, self.options.parallel);
        let overlap = half_area(intersection(object.left, object.right));
        if budget > 0 && overlap > MIN_OVERLAP * self.root_area && count >= MIN_SPATIAL_REFS {
            if let Some(spatial) = self.find_spatial_split(&prims, range.bounds) {
                if spatial.cost < object.cost {
                    if let Some(outcome) = self.spatial_partition(&prims, &spatial, depth, budget) {
                        return outcome;
                    }
                }
            }
        }
        let binner = Binner::new(range.centroids, bins);
        let (axis, bin) = (object.axis, object.bin);
        let (mid, left_centroids, right_centroids) =
            partition(&mut prims, |p| binner.below(p.centroid2_lanes(), axis, bin));
        if mid == 0 || mid == count {
            let (mid, left, right) = median_split(&mut prims, range);
            return object_children(prims, mid, left, right, depth, budget);
        }
        let left = Range {
            bounds: object.left,
            centroids: left_centroids,
        };
        let right = Range {
            bounds: object.right,
            centroids: right_centroids,
        };
        object_children(prims, mid, left, right, depth, budget)
    }

    /// Bins the parts of every reference into `SPATIAL_BINS` slabs along
    /// each axis of `bounds`, then sweeps each axis for the cheapest plane.
    fn find_spatial_split(&self, prims: &[Prim], bounds: Aabb) -> Option<SpatialSplit> {
        let extent = bounds.extent();
        let bin_all = |prims: &[Prim]| {
            let mut bins = [[EMPTY_SPATIAL_BIN; SPATIAL_BINS]; 3];
            for p in prims {
                self.bin_reference(p, bounds, &mut bins);
            }
            bins
        };
        let bins: SpatialBins = if self.options.parallel && prims.len() >= 4 * PARALLEL_MIN {
            prims.par_chunks(PARALLEL_MIN).map(bin_all).reduce(
                || [[EMPTY_SPATIAL_BIN; SPATIAL_BINS]; 3],
                |mut a, b| {
                    for (a, b) in a.iter_mut().flatten().zip(b.iter().flatten()) {
                        a.bounds = a.bounds.union(b.bounds);
                        a.entries += b.entries;
                        a.exits += b.exits;
                    }
                    a
                },
            )
        } else {
            bin_all(prims)
        };
        let parent_area = half_area(bounds).max(f32::MIN_POSITIVE);
        let mut best: Option<SpatialSplit> = None;
        for (axis, bins) in bins.iter().enumerate() {
            if extent[axis] <= 0.0 {
                continue;
            }
            let counted = |k: usize| (bins[k].bounds, bins[k].entries, bins[k].exits);
            if let Some((k, cost, _)) = sweep(SPATIAL_BINS, counted, parent_area) {
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(SpatialSplit {
                        axis,
                        plane: plane(bounds, axis, k),
                        cost,
                    });
                }
            }
        }
        best
    }

    /// Adds reference `p` to the bins along each axis: whole to the one bin
    /// it lies in, or clipped to each slab it crosses.
    fn bin_reference(&self, p: &Prim, bounds: Aabb, bins: &mut SpatialBins) {
        let b = aabb_of(p);
        let extent = bounds.extent();
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let scale = SPATIAL_BINS as f32 / extent[axis];
            let bin_of =
                |x: f32| (((x - bounds.min[axis]) * scale).max(0.0) as usize).min(SPATIAL_BINS - 1);
            let first = bin_of(b.min[axis]);
            let last = bin_of(b.max[axis]).max(first);
            let bins = &mut bins[axis];
            if first == last {
                bins[first].bounds.grow(p);
            } else {
                // Read only here: most references lie in one bin, and the
                // triangles, in the caller's order, are a cache miss each.
                let slices = Slices::new(&self.triangles[p.index() as usize].v, axis);
                // Each plane's cross-section serves the slabs on both sides.
                let at = |k: usize| {
                    let x = plane(bounds, axis, k);
                    (x, slices.section(x))
                };
                let mut lo = at(first);
                for (k, bin) in bins.iter_mut().enumerate().take(last + 1).skip(first) {
                    let hi = at(k + 1);
                    let part = slices.piece(lo, hi, b);
                    if !part.is_empty() {
                        bin.bounds = bin.bounds.union(PackedBox::of(part));
                    }
                    lo = hi;
                }
            }
            bins[first].entries += 1;
            bins[last].exits += 1;
        }
    }

    /// Splits the references at `split`'s plane, cutting those that cross
    /// it; `None` when one side would be empty.
    fn spatial_partition(
        &self,
        prims: &[Prim],
        split: &SpatialSplit,
        depth: usize,
        budget: usize,
    ) -> Option<Outcome> {
        let (axis, plane) = (split.axis, split.plane);
        let mut left = Vec::with_capacity(prims.len());
        let mut right = Vec::with_capacity(prims.len());
        let mut added = 0;
        for p in prims {
            let b = aabb_of(p);
            if b.max[axis] <= plane {
                left.push(*p);
            } else if b.min[axis] >= plane {
                right.push(*p);
            } else {
                let slices = Slices::new(&self.triangles[p.index() as usize].v, axis);
                let (l, r) = slices.halves(plane, b);
                let index = p.index() as usize;
                match (l.is_empty(), r.is_empty()) {
                    (false, false) => {
                        left.push(Prim::new(l, index));
                        right.push(Prim::new(r, index));
                        added += 1;
                    }
                    (false, true) => left.push(Prim::new(l, index)),
                    (true, false) => right.push(Prim::new(r, index)),
                    // Only rounding could leave no part on either side:
                    // keep the reference whole.
                    (true, true) => left.push(*p),
                }
            }
        }
        if left.is_empty() || right.is_empty() {
            return None;
        }
        let (left_range, right_range) = (measure(&left, false), measure(&right, false));
        let (left_budget, right_budget) =
            share(budget.saturating_sub(added), left.len(), right.len());
        Some(Outcome::Split(
            Task {
                prims: left,
                range: left_range,
                depth: depth + 1,
                budget: left_budget,
            },
            Task {
                prims: right,
                range: right_range,
                depth: depth + 1,
                budget: right_budget,
            },
        ))
    }
}

/// The cheapest of the planes between `bins` bins along one axis, where
/// plane `k` puts bins `0..k` on the left: its index, SAH cost and left
/// box. `bin(k)` gives bin `k`'s box and the references it adds to the
/// left side when below the plane and to the right side when above it
/// (those starting in it on the left, those ending in it on the right).
/// One sweep from the right, then one from the left, costs each plane
/// once; ties go to the lowest plane. `find_split` sweeps whole references
/// the same way, written out.
#[inline(always)]
fn sweep(
    bins: usize,
    bin: impl Fn(usize) -> (PackedBox, u32, u32),
    parent_area: f32,
) -> Option<(usize, f32, Aabb)> {
    let mut right = [(0f32, 0u32); MAX_BINS];
    let (mut acc, mut n) = (PackedBox::EMPTY, 0);
    for k in (1..bins).rev() {
        let (bounds, _, count) = bin(k);
        acc = acc.union(bounds);
        n += count;
        right[k] = (acc.half_area(), n);
    }
    let mut best: Option<(usize, f32, Aabb)> = None;
    let (mut acc, mut n) = (PackedBox::EMPTY, 0);
    for (k, &(right_area, right_count)) in right.iter().enumerate().take(bins).skip(1) {
        let (bounds, count, _) = bin(k - 1);
        acc = acc.union(bounds);
        n += count;
        if n == 0 || right_count == 0 {
            continue;
        }
        let cost = split_cost(acc.half_area(), n, right_area, right_count, parent_area);
        if best.is_none_or(|(_, c, _)| cost < c) {
            best = Some((k, cost, acc.aabb()));
        }
    }
    best
}

/// Plane `k` of the `SPATIAL_BINS + 1` evenly spaced across `bounds` along
/// `axis`; the first and last are the box's own faces, exactly.
fn plane(bounds: Aabb, axis: usize, k: usize) -> f32 {
    if k >= SPATIAL_BINS {
        return bounds.max[axis];
    }
    let (lo, hi) = (bounds.min[axis], bounds.max[axis]);
    lo + (hi - lo) * (k as f32 / SPATIAL_BINS as f32)
}

/// Splits `budget` between two children in proportion to their sizes.
fn share(budget: usize, left: usize, right: usize) -> (usize, usize) {
    let l = (budget as u128 * left as u128 / (left + right).max(1) as u128) as usize;
    (l, budget - l)
}

/// The two children of an object split: the first `mid` references go left.
fn object_children(
    mut prims: Vec<Prim>,
    mid: usize,
    left: Range,
    right: Range,
    depth: usize,
    budget: usize,
) -> Outcome {
    let right_prims = prims.split_off(mid);
    let (left_budget, right_budget) = share(budget, prims.len(), right_prims.len());
    Outcome::Split(
        Task {
            prims,
            range: left,
            depth: depth + 1,
            budget: left_budget,
        },
        Task {
            prims: right_prims,
            range: right,
            depth: depth + 1,
            budget: right_budget,
        },
    )
}

/// A leaf over `prims` whose first triangle sits at `first` in leaf order.
fn leaf(bounds: Aabb, first: usize, prims: &[Prim]) -> Node {
    Node {
        bounds,
        first: first as u32,
        count: prims.len() as u32,
    }
}
