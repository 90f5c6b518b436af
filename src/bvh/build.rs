//! Top-down binned SAH construction (Wald, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies", 2007): centroids are binned along each axis,
//! and the split plane between bins with the lowest SAH cost wins.

use super::{Bvh, Node, INTERSECTION_COST, TRAVERSAL_COST};
use crate::geometry::{Aabb, Triangle};
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Bins per axis (2 to 32). 16 is within a few per cent of a full sweep's SAH cost.
    pub bins: usize,
    /// A node with more triangles than this is always split. Four matches the
    /// wide BVH's leaves, which test four triangles at once.
    pub max_leaf_size: usize,
    /// Build independent subtrees on the rayon pool the call runs in.
    pub parallel: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            bins: 16,
            max_leaf_size: 4,
            parallel: true,
        }
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    count: 0,
};

const MAX_BINS: usize = 32;

/// Below this many triangles a subtree is built on the calling thread: the
/// fork costs more than it saves, and big subtrees already keep every thread busy.
const PARALLEL_MIN: usize = 16 * 1024;

struct Split {
    axis: usize,
    /// Triangles in bins `< bin` go left.
    bin: usize,
    cost: f32,
}

/// What every subtree's construction reads.
struct Context<'a> {
    boxes: &'a [Aabb],
    centroids: &'a [Vec3],
    bins: usize,
    options: &'a BuildOptions,
}

const UNSET: Node = Node {
    bounds: Aabb::EMPTY,
    first: 0,
    count: 0,
};

impl Bvh {
    pub fn build_with(triangles: &[Triangle], options: &BuildOptions) -> Bvh {
        let boxes: Vec<Aabb> = if options.parallel {
            triangles
                .par_iter()
                .map(|t| Aabb::from_points(&t.v))
                .collect()
        } else {
            triangles.iter().map(|t| Aabb::from_points(&t.v)).collect()
        };
        let centroids: Vec<Vec3> = boxes.iter().map(|b| b.center()).collect();
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let context = Context {
            boxes: &boxes,
            centroids: &centroids,
            bins: options.bins.clamp(2, MAX_BINS),
            options,
        };
        // No root at all for no triangles: traversal checks for this and reports no hit.
        let nodes = if triangles.is_empty() {
            Vec::new()
        } else {
            build_subtree(&context, &mut order, 0, 0)
        };
        Bvh {
            triangles: order.iter().map(|&i| triangles[i as usize]).collect(),
            original_index: order,
            nodes,
        }
    }
}

/// Bounds of a range, and where to split it (0 for a leaf).
fn decide(context: &Context, range: &mut [u32], depth: usize) -> (Aabb, usize) {
    let (boxes, centroids) = (context.boxes, context.centroids);
    let bounds = range
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
    let centroid_bounds = range
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.grow(centroids[i as usize]));
    let count = range.len();
    let max_leaf = context.options.max_leaf_size.max(1);
    let leaf_cost = count as f32 * INTERSECTION_COST;
    let bins = context.bins;
    let split = find_split(range, boxes, centroids, centroid_bounds, bins, bounds);
    let mid = match split {
        // Past this depth the SAH is peeling off a few triangles at a time
        // (exponentially spaced centroids): split at the median to bound the
        // depth, and with it the traversal stack.
        _ if depth >= MAX_SAH_DEPTH && count > max_leaf => {
            median_split(range, centroids, centroid_bounds)
        }
        Some(s) if s.cost < leaf_cost || count > max_leaf => partition(range, |i| {
            bin_of(centroids[i as usize], centroid_bounds, s.axis, bins) < s.bin
        }),
        // All centroids coincide: no plane separates them, so halve by index.
        None if count > max_leaf => median_split(range, centroids, centroid_bounds),
        _ => 0,
    };
    (bounds, if mid == count { 0 } else { mid })
}

/// Builds the subtree over `order`, whose first entry is triangle `offset`
/// in leaf order. Returns its nodes with the root first and siblings adjacent.
fn build_subtree(context: &Context, order: &mut [u32], offset: usize, depth: usize) -> Vec<Node> {
    if !context.options.parallel || order.len() < PARALLEL_MIN {
        return build_sequential(context, order, offset, depth);
    }
    let (bounds, mid) = decide(context, order, depth);
    if mid == 0 {
        return vec![Node {
            bounds,
            first: offset as u32,
            count: order.len() as u32,
        }];
    }
    let (left_order, right_order) = order.split_at_mut(mid);
    let (left, right) = rayon::join(
        || build_subtree(context, left_order, offset, depth + 1),
        || build_subtree(context, right_order, offset + mid, depth + 1),
    );
    // Layout: [root, left root, right root, rest of left, rest of right].
    let left_index = |i: u32| if i == 0 { 1 } else { i + 2 };
    let right_shift = left.len() as u32 + 1;
    let right_index = |i: u32| if i == 0 { 2 } else { i + right_shift };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node {
        bounds,
        first: 1,
        count: 0,
    });
    let relink = |n: &Node, map: &dyn Fn(u32) -> u32| {
        if n.is_leaf() {
            *n
        } else {
            Node {
                first: map(n.first),
                ..*n
            }
        }
    };
    nodes.push(relink(&left[0], &left_index));
    nodes.push(relink(&right[0], &right_index));
    nodes.extend(left[1..].iter().map(|n| relink(n, &left_index)));
    nodes.extend(right[1..].iter().map(|n| relink(n, &right_index)));
    nodes
}

fn build_sequential(
    context: &Context,
    order: &mut [u32],
    offset: usize,
    depth: usize,
) -> Vec<Node> {
    let mut nodes = Vec::with_capacity(order.len() / 2 + 1);
    nodes.push(UNSET);
    // Work list of (node, first, end, depth) ranges into `order`; an explicit
    // stack keeps deep, unbalanced trees from overflowing the call stack.
    let mut work = vec![(0usize, 0usize, order.len(), depth)];
    while let Some((node, first, end, depth)) = work.pop() {
        let range = &mut order[first..end];
        let (bounds, mid) = decide(context, range, depth);
        if mid == 0 {
            nodes[node] = Node {
                bounds,
                first: (offset + first) as u32,
                count: (end - first) as u32,
            };
            continue;
        }
        let left = nodes.len();
        nodes.push(UNSET);
        nodes.push(UNSET);
        nodes[node] = Node {
            bounds,
            first: left as u32,
            count: 0,
        };
        work.push((left + 1, first + mid, end, depth + 1));
        work.push((left, first, first + mid, depth + 1));
    }
    nodes
}

/// Depth after which splits fall back to the object median; see `build_with`.
const MAX_SAH_DEPTH: usize = 64;

/// Splits at the median centroid along the widest centroid axis (by index if all coincide).
fn median_split(range: &mut [u32], centroids: &[Vec3], centroid_bounds: Aabb) -> usize {
    let e = centroid_bounds.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = range.len() / 2;
    range.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
    });
    mid
}

fn bin_of(c: Vec3, centroid_bounds: Aabb, axis: usize, bins: usize) -> usize {
    let lo = centroid_bounds.min[axis];
    let extent = centroid_bounds.max[axis] - lo;
    let b = ((c[axis] - lo) / extent * bins as f32) as usize;
    b.min(bins - 1)
}

fn find_split(
    range: &[u32],
    boxes: &[Aabb],
    centroids: &[Vec3],
    centroid_bounds: Aabb,
    bins: usize,
    bounds: Aabb,
) -> Option<Split> {
    let parent_area = bounds.surface_area();
    let mut best: Option<Split> = None;
    let mut bin = [EMPTY_BIN; MAX_BINS];
    let mut right_area = [0.0f32; MAX_BINS];
    let mut right_count = [0u32; MAX_BINS];
    for axis in 0..3 {
        if centroid_bounds.extent()[axis] <= 0.0 {
            continue;
        }
        bin[..bins].fill(EMPTY_BIN);
        for &i in range {
            let b = &mut bin[bin_of(centroids[i as usize], centroid_bounds, axis, bins)];
            b.bounds = b.bounds.union(boxes[i as usize]);
            b.count += 1;
        }
        // Sweep from the right, then from the left, evaluating each plane once.
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for k in (1..bins).rev() {
            acc = acc.union(bin[k].bounds);
            n += bin[k].count;
            right_area[k] = acc.surface_area();
            right_count[k] = n;
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for k in 1..bins {
            acc = acc.union(bin[k - 1].bounds);
            n += bin[k - 1].count;
            if n == 0 || right_count[k] == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST
                + INTERSECTION_COST
                    * (acc.surface_area() * n as f32 + right_area[k] * right_count[k] as f32)
                    / parent_area.max(f32::MIN_POSITIVE);
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split { axis, bin: k, cost });
            }
        }
    }
    best
}

/// Moves the elements for which `goes_left` holds to the front; returns how many.
fn partition(range: &mut [u32], goes_left: impl Fn(u32) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..range.len() {
        if goes_left(range[i]) {
            range.swap(i, mid);
            mid += 1;
        }
    }
    mid
}
