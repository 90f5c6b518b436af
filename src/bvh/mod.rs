//! Bounding volume hierarchy over triangles.
//!
//! A binary BVH built top-down with the binned surface area heuristic, stored
//! as a flat array with siblings adjacent. The BVH keeps its own copy of the
//! triangles in leaf order, so a leaf's triangles are contiguous in memory;
//! hits report the caller's original triangle index.

mod build;
mod traverse;
pub mod wide;

pub use build::BuildOptions;
pub use wide::{for_lanes, WideBvh, LANES};

use crate::geometry::{Aabb, Triangle};

/// A node of the binary BVH: a leaf when `count > 0`, else an inner node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Box around every triangle below the node.
    pub bounds: Aabb,
    /// Inner node: index of the first of its two adjacent children.
    /// Leaf: index of its first triangle in leaf order.
    pub first: u32,
    /// Number of triangles; zero marks an inner node.
    pub count: u32,
}

impl Node {
    /// Whether the node holds triangles rather than children.
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A closest hit: the caller's triangle index, distance and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The caller's index of the triangle hit.
    pub triangle: u32,
    /// Ray parameter of the hit: a distance when the ray direction is unit length.
    pub t: f32,
    /// Barycentric weight of the triangle's vertex 1.
    pub b1: f32,
    /// Barycentric weight of vertex 2 (vertex 0's is `1 - b1 - b2`).
    pub b2: f32,
}

/// A binary SAH BVH with its own copy of the triangles, in leaf order.
/// The integrators trace [`WideBvh`], collapsed from the same build; this
/// one serves as a reference in tests.
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangles in leaf order.
    triangles: Vec<Triangle>,
    /// Leaf order → the caller's triangle index.
    original_index: Vec<u32>,
}

/// Traversal and intersection costs the SAH weighs, relative to each other.
pub const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one ray–triangle test, relative to [`TRAVERSAL_COST`].
pub const INTERSECTION_COST: f32 = 1.0;

/// What the node a split adds costs a ray, relative to one leaf-block test.
/// A wide node's test takes about half the instructions of a block test
/// and stands for about three binary levels, which puts a binary node's
/// share near 0.15; 0.3 keeps nearly all of the gain in the Cornell box
/// (12.5% fewer instructions per sample rendered, against 13.1% at 0.15)
/// and adds 0.5–1.4% to the scanned meshes' memory rather than 3–6%.
pub(crate) const SPLIT_NODE_SHARE: f32 = 0.3;

/// Whether a range small enough for one leaf block is better split into
/// two blocks with boxes `left` and `right`: the SAH weighs one block test
/// for a ray entering `parent` against a node's share plus one block test
/// for each child box the ray enters. Four triangles from different parts
/// of a scene (two walls of a room) have a large common box that most rays
/// enter; split, each small box is entered only by the rays that come
/// near its triangles.
pub(crate) fn small_split_pays(parent: Aabb, left: Aabb, right: Aabb) -> bool {
    let parent_area = parent.surface_area();
    parent_area > 0.0
        && SPLIT_NODE_SHARE * parent_area + left.surface_area() + right.surface_area() < parent_area
}

impl Bvh {
    /// Builds over `triangles` with the default [`BuildOptions`]; hits report
    /// indices into this slice.
    pub fn build(triangles: &[Triangle]) -> Bvh {
        Bvh::build_with(triangles, &BuildOptions::default())
    }

    /// The nodes, root first; an inner node's two children are adjacent.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Number of triangles built over.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Box around every triangle; [`Aabb::EMPTY`] when there are none.
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }

    /// Expected cost of a random ray under the SAH, in units of one triangle test.
    pub fn sah_cost(&self) -> f32 {
        sah_cost(&self.nodes, false)
    }

    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }

    /// Bytes of nodes, triangles and index map (the heap the BVH uses).
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.triangles.len() * (std::mem::size_of::<Triangle>() + 4)
    }
}

/// Expected cost of a random ray through a binary tree under the SAH, in
/// units of one triangle test.
pub(crate) fn sah_cost(nodes: &[Node], parallel: bool) -> f32 {
    let Some(root) = nodes.first() else {
        return 0.0;
    };
    let root_area = root.bounds.surface_area();
    if root_area <= 0.0 {
        return 0.0;
    }
    let total = chunked_sum(nodes, parallel, |n| {
        let cost = if n.is_leaf() {
            n.count as f32 * INTERSECTION_COST
        } else {
            TRAVERSAL_COST
        };
        (n.bounds.surface_area() * cost) as f64
    });
    (total / root_area as f64) as f32
}

/// The sum of `term` over `items`, added up in fixed chunks (on the rayon
/// pool when `parallel`) and the chunks' sums in order, so the result is the
/// same bits whatever the thread count. For build reports over the whole
/// tree, which a single thread took several milliseconds to add up.
pub(crate) fn chunked_sum<T: Sync>(
    items: &[T],
    parallel: bool,
    term: impl Fn(&T) -> f64 + Sync,
) -> f64 {
    const CHUNK: usize = 8192;
    let chunk_sum = |chunk: &[T]| chunk.iter().map(&term).sum::<f64>();
    let sums: Vec<f64> = if parallel {
        use rayon::prelude::*;
        items.par_chunks(CHUNK).map(chunk_sum).collect()
    } else {
        items.chunks(CHUNK).map(chunk_sum).collect()
    };
    sums.iter().sum()
}
