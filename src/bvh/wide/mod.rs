//! The 8-wide BVH every integrator traces: each node holds its eight
//! children's boxes as structure-of-arrays, so one 8-lane SIMD slab test
//! checks all eight at once, and each leaf is a block of up to four
//! triangles, also as structure-of-arrays, so one 8-lane SIMD test checks
//! the triangles of two blocks. Blocks are stored in leaf order: a hit reads its
//! triangle's data from the block itself.
//!
//! Eight children rather than four: an 8-lane box test costs about what a
//! 4-lane one does (one AVX instruction per step instead of one SSE one),
//! and a random ray makes fewer tests: the SAH cost of the dragon's tree
//! falls from 23.2 to 16.5, with 38% fewer nodes. Measured
//! against the 4-wide tree the same builder collapsed, it was faster on
//! every ray set of the bunny, dragon and Sponza (single rays, one thread),
//! and took 6–9% fewer instructions per sample in the Cornell box renders
//! of the performance gate; see docs/benchmarks.md.
//!
//! The triangle test is the watertight one of Woop, Benthin and Wald (2013),
//! not Möller–Trumbore: measured on our meshes it costs about the same, and
//! Möller–Trumbore's edge tests round differently on the two triangles that
//! share an edge, so rays through shared edges and vertices slip through
//! closed meshes (light leaks, and biased furnace tests).
//!
//! Built by collapsing the binary SAH BVH (see `collapse.rs`). Scenes of
//! at most 32 triangles skip the tree on CPUs with AVX-512: their rays test
//! every triangle, sixteen at a time (see `flat.rs`).

mod collapse;
mod flat;
mod lanes;
mod packet;
mod traverse;

pub use flat::FLAT_MAX_TRIANGLES;
pub use lanes::{for_lanes, LANES};
pub use packet::PACKET_SIZE;

use super::BuildOptions;
use crate::geometry::{Aabb, Triangle};
use crate::pod_array::PodArray;

/// A child reference with this bit set names a leaf block, not a node; the
/// next two bits hold its triangle count minus one, the rest its index.
const LEAF_BIT: u32 = 1 << 31;
const LEAF_COUNT_SHIFT: u32 = 29;
const LEAF_INDEX_MASK: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// An unused child slot.
const EMPTY_CHILD: u32 = u32::MAX;

/// Children per node.
pub const WIDTH: usize = 8;

/// `WIDTH` children's boxes: `bounds[axis]` holds the minima along `axis` for
/// the children, `bounds[3 + axis]` the maxima. Unused slots hold an
/// empty box (min +∞, max −∞), which no ray enters.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(32))]
pub struct WideNode {
    /// Child boxes, one child per lane: minima along x, y, z, then maxima.
    pub bounds: [[f32; WIDTH]; 6],
    /// A node index, `LEAF_BIT | block index`, or `EMPTY_CHILD`.
    pub children: [u32; WIDTH],
}

/// Up to four triangles, one per lane: `v[vertex][axis][lane]`. Unused
/// lanes are zero, with id `u32::MAX`, and masked off by the leaf's count.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(16))]
pub struct TriangleBlock {
    /// Vertex positions: `v[vertex][axis][lane]`, in world space.
    pub v: [[[f32; 4]; 3]; 3],
    /// The caller's triangle index of each lane.
    pub id: [u32; 4],
}

/// What a build produced, for `tracer bench` and `tracer info`.
#[derive(Clone, Debug, Default)]
pub struct BuildReport {
    /// Wall-clock time of the whole build (binary build and collapse), in seconds.
    pub seconds: f64,
    /// SAH cost of the binary BVH before the collapse (one unit per node
    /// visit and per triangle test), comparable with other binary builders.
    pub binary_sah_cost: f32,
    /// SAH cost of the wide BVH: one unit per 8-wide node test and per
    /// 4-triangle leaf test.
    pub sah_cost: f32,
    /// Number of 8-wide inner nodes.
    pub nodes: usize,
    /// Number of leaf blocks (each up to four triangles).
    pub leaves: usize,
    /// Number of triangles built over.
    pub triangles: usize,
    /// Triangle references in the leaves: `triangles`, or more where
    /// spatial splits cut triangles in two.
    pub references: usize,
}

/// The 8-wide BVH the integrators trace, with its triangles in leaf blocks.
pub struct WideBvh {
    nodes: PodArray<WideNode>,
    blocks: PodArray<TriangleBlock>,
    /// The root: a node, a single leaf block, or `EMPTY_CHILD` for no triangles.
    root: u32,
    bounds: Aabb,
    report: BuildReport,
    /// How rays traverse: see `Traversal`.
    traversal: Traversal,
    /// The triangles in groups of sixteen, for scenes small enough to
    /// trace without the tree (see `flat.rs`); empty otherwise.
    flat: Vec<flat::TriangleGroup>,
}

/// How a BVH's rays find their hits, chosen from its size when it is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Traversal {
    /// Down the tree.
    Tree,
    /// Down the tree, prefetching each child a ray defers (see
    /// `PREFETCH_MIN_BYTES`).
    Prefetching,
    /// Every triangle tested, sixteen at a time (see `flat.rs`).
    Flat,
}

/// Trees at least this large are traversed with prefetches: each child a
/// ray defers is requested from memory when it is pushed, so it is on its
/// way while the ray finishes the nearer subtree. A tree that mostly stays
/// in the caches gains nothing from them and pays their instructions. On
/// this project's machine (32 MiB shared L3), prefetching sped the dragon's
/// tree (55 MB) by 11–33% on every ray set and slowed the Sponza atrium's
/// (3.5 MB) primary any hits by 16–24%; see docs/benchmarks.md.
const PREFETCH_MIN_BYTES: usize = 16 << 20;

impl WideBvh {
    /// Builds over `triangles` with the default [`BuildOptions`]; hits report
    /// indices into this slice.
    pub fn build(triangles: &[Triangle]) -> WideBvh {
        WideBvh::build_with(triangles, &BuildOptions::default())
    }

    /// Builds over `triangles`: a binary SAH build with `options` (leaves of at
    /// most four triangles), collapsed to eight wide.
    pub fn build_with(triangles: &[Triangle], options: &BuildOptions) -> WideBvh {
        let start = std::time::Instant::now();
        // Binary leaves must fit one block of four.
        let options = BuildOptions {
            max_leaf_size: options.max_leaf_size.clamp(1, 4),
            ..options.clone()
        };
        let (binary, order) = super::build::build_tree(triangles, &options);
        let mut wide = WideBvh::collapse(&binary, &order, triangles, options.parallel);
        wide.report.triangles = triangles.len();
        wide.report.seconds = start.elapsed().as_secs_f64();
        wide
    }

    /// Chooses how rays will traverse: flat for the smallest scenes (on
    /// CPUs with AVX-512, where it measured faster), with prefetches for
    /// the largest.
    fn plan_traversal(&mut self) {
        self.set_flat(cfg!(target_feature = "avx512f"));
        if !self.is_flat() && self.memory_bytes() >= PREFETCH_MIN_BYTES {
            self.traversal = Traversal::Prefetching;
        }
    }

    /// Whether rays test every triangle rather than traverse the tree: by
    /// default for scenes of at most [`FLAT_MAX_TRIANGLES`] triangles, on
    /// CPUs with AVX-512.
    pub fn is_flat(&self) -> bool {
        self.traversal == Traversal::Flat
    }

    /// Overrides the rule for tracing flat, for benchmarks and tests: hits
    /// are the same either way (see `flat.rs`). A scene of more than
    /// [`FLAT_MAX_TRIANGLES`] stays with its tree.
    pub fn set_flat(&mut self, on: bool) {
        self.flat = if on {
            flat::groups(&self.blocks)
        } else {
            Vec::new()
        };
        self.traversal = if self.flat.is_empty() {
            Traversal::Tree
        } else {
            Traversal::Flat
        };
    }

    /// Whether traversal goes down the tree prefetching deferred children:
    /// by default for trees of at least `PREFETCH_MIN_BYTES`.
    pub fn prefetches(&self) -> bool {
        self.traversal == Traversal::Prefetching
    }

    /// Overrides the rules for prefetching (and for tracing flat), for
    /// benchmarks and tests: hits are the same either way.
    pub fn set_prefetch(&mut self, on: bool) {
        // The groups go with flat tracing: `flat` is empty unless it is chosen.
        self.flat = Vec::new();
        self.traversal = if on {
            Traversal::Prefetching
        } else {
            Traversal::Tree
        };
    }

    /// What the build produced and how long it took.
    pub fn report(&self) -> &BuildReport {
        &self.report
    }

    /// Box around every triangle; [`Aabb::EMPTY`] when there are none.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The inner nodes; children always come after their parent.
    pub fn nodes(&self) -> &[WideNode] {
        &self.nodes
    }

    /// The leaf blocks, in leaf order.
    pub fn blocks(&self) -> &[TriangleBlock] {
        &self.blocks
    }

    /// The root reference: a node, a leaf block, or `u32::MAX` when empty.
    pub fn root(&self) -> u32 {
        self.root
    }

    /// Reassembles a BVH from its parts (the scene cache's sections),
    /// checking that every reference stays in bounds and points forward, as
    /// the collapse lays nodes out, so a damaged tree can neither index out
    /// of range nor loop.
    pub fn from_parts(
        nodes: PodArray<WideNode>,
        blocks: PodArray<TriangleBlock>,
        root: u32,
        bounds: Aabb,
        report: BuildReport,
        triangle_count: usize,
    ) -> Result<WideBvh, String> {
        let check = |reference: u32, parent: Option<usize>| -> Result<(), String> {
            if reference == EMPTY_CHILD {
                return Ok(());
            }
            if reference & LEAF_BIT != 0 {
                let block = (reference & LEAF_INDEX_MASK) as usize;
                let count = ((reference >> LEAF_COUNT_SHIFT) & 3) as usize + 1;
                let Some(b) = blocks.get(block) else {
                    return Err(format!("leaf block {block} of {}", blocks.len()));
                };
                if b.id[..count]
                    .iter()
                    .any(|&id| id as usize >= triangle_count)
                {
                    return Err(format!(
                        "leaf block {block} names a triangle beyond {triangle_count}"
                    ));
                }
                return Ok(());
            }
            let node = reference as usize;
            if node >= nodes.len() || parent.is_some_and(|p| node <= p) {
                return Err(format!("node reference {node} (of {})", nodes.len()));
            }
            Ok(())
        };
        check(root, None)?;
        if nodes.is_empty() != (root == EMPTY_CHILD || root & LEAF_BIT != 0) {
            return Err("the root does not match the node count".into());
        }
        // Children come after their parents, so one forward pass knows
        // every node's depth; traversal's stack holds `WIDTH - 1` entries a level.
        let mut depth = vec![0u32; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            for (lane, &child) in node.children.iter().enumerate() {
                check(child, Some(i))?;
                let b = &node.bounds;
                if child == EMPTY_CHILD && (0..3).any(|a| b[a][lane] <= b[3 + a][lane]) {
                    return Err(format!("node {i} has an empty slot that rays can enter"));
                }
                if child != EMPTY_CHILD && child & LEAF_BIT == 0 {
                    depth[child as usize] = depth[i] + 1;
                }
            }
            if depth[i] as usize > traverse::MAX_DEPTH {
                return Err(format!("deeper than {} levels", traverse::MAX_DEPTH));
            }
        }
        let mut bvh = WideBvh {
            nodes,
            blocks,
            root,
            bounds,
            report,
            traversal: Traversal::Tree,
            flat: Vec::new(),
        };
        bvh.plan_traversal();
        Ok(bvh)
    }

    /// Bytes of nodes and leaf blocks.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
            + self.blocks.len() * std::mem::size_of::<TriangleBlock>()
    }
}
