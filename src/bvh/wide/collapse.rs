//! Turns the binary SAH BVH into the 8-wide one. Each wide node takes the
//! binary subtrees that the SAH-optimal plan of `plan_lanes` gives it (at
//! most eight), found bottom-up over the whole tree as Ylitie, Karras and
//! Laine (2017) do for their wide BVHs, rather than by greedily opening the
//! widest child until eight lanes are full (Wald, Benthin and Boulos,
//! "Getting Rid of Packets", 2008), which it replaced: the same binary
//! tree, 3–6% less SAH cost and 25–30% fewer nodes (docs/benchmarks.md).
//! Any binary subtree of at most four triangles becomes one leaf block:
//! testing four triangles costs one SIMD test, less than a node. Such a
//! subtree may still be opened for lanes of its own where the builder
//! found that two blocks beat one (`small_split_pays`).

use super::{
    BuildReport, TriangleBlock, WideBvh, WideNode, EMPTY_CHILD, LEAF_BIT, LEAF_COUNT_SHIFT,
    LEAF_INDEX_MASK, WIDTH,
};
use crate::bvh::Node;
use crate::geometry::{Aabb, Triangle};

const EMPTY_BOUNDS: [[f32; WIDTH]; 6] = [
    [f32::INFINITY; WIDTH],
    [f32::INFINITY; WIDTH],
    [f32::INFINITY; WIDTH],
    [f32::NEG_INFINITY; WIDTH],
    [f32::NEG_INFINITY; WIDTH],
    [f32::NEG_INFINITY; WIDTH],
];

/// A node with no children yet: every slot empty.
const EMPTY_NODE: WideNode = WideNode {
    bounds: EMPTY_BOUNDS,
    children: [EMPTY_CHILD; WIDTH],
};

/// Sets child `lane` of `node` to `reference`, with box `b`.
fn set_lane(node: &mut WideNode, lane: usize, reference: u32, b: Aabb) {
    node.children[lane] = reference;
    for axis in 0..3 {
        node.bounds[axis][lane] = b.min[axis];
        node.bounds[3 + axis][lane] = b.max[axis];
    }
}

/// Binary subtrees of at most this many triangles are collapsed as one
/// task: small enough that a big mesh gives every thread many, large
/// enough that the sequential top above them is a few hundred nodes.
const TASK_TRIANGLES: u32 = 4096;

/// Leaf blocks are filled in chunks of this many, a task each.
const BLOCK_CHUNK: usize = 4096;
/// How many blocks ahead the fill asks for triangles: far enough to hide a
/// cache miss behind the blocks in between.
const PREFETCH_BLOCKS: usize = 8;

struct Collapser<'a> {
    binary: &'a [Node],
    /// The caller's triangles, and the binary tree's leaf order of them.
    triangles: &'a [Triangle],
    order: &'a [u32],
    /// Per binary node: (first triangle in leaf order, triangle count) of its subtree.
    ranges: Vec<(u32, u32)>,
    /// Per binary node, the least SAH cost of its subtree in at most 1..=8
    /// lanes (see `plan_lanes`).
    best: Vec<[f32; WIDTH]>,
}

impl WideBvh {
    /// Collapses the binary tree in parallel without moving a node twice.
    /// The top of the wide tree, down to binary subtrees of at most
    /// `TASK_TRIANGLES`, comes first; each such subtree is a task whose
    /// nodes and blocks follow, task after task. A dry run counts what each
    /// part emits, so every task then writes straight into its own stretch
    /// of the final arrays; the tasks note which binary leaf each block
    /// comes from, and one flat parallel pass fills the blocks. Without
    /// `parallel` the tasks run in order, each appending where the last
    /// ended, which gives the same layout without their dry runs. The
    /// layout depends on the tree alone, never on the thread count.
    pub(in crate::bvh) fn collapse(
        binary: &[Node],
        order: &[u32],
        triangles: &[Triangle],
        parallel: bool,
    ) -> WideBvh {
        let mut c = Collapser {
            binary,
            triangles,
            order,
            ranges: subtree_ranges(binary),
            best: Vec::new(),
        };
        c.best = c.plan_lanes(parallel);
        let (root, nodes, blocks) = if binary.is_empty() {
            (EMPTY_CHILD, Vec::new(), Vec::new())
        } else {
            c.collapse_all(parallel)
        };
        let bounds = binary.first().map_or(Aabb::EMPTY, |n| n.bounds);
        let mut wide = WideBvh {
            root,
            bounds,
            report: BuildReport {
                binary_sah_cost: crate::bvh::sah_cost(binary, parallel),
                nodes: nodes.len(),
                leaves: blocks.len(),
                triangles: order.len(),
                references: order.len(),
                ..BuildReport::default()
            },
            nodes: nodes.into(),
            blocks: blocks.into(),
            traversal: super::Traversal::Tree,
            flat: Vec::new(),
        };
        wide.plan_traversal();
        wide.report.sah_cost = wide.sah_cost(parallel);
        wide
    }

    /// Expected cost of a random ray: area-weighted node and leaf tests
    /// over the root's area (the root's own test included).
    fn sah_cost(&self, parallel: bool) -> f32 {
        let root_area = self.bounds.surface_area();
        if root_area <= 0.0 || self.root == EMPTY_CHILD {
            return 0.0;
        }
        let node_area = |node: &WideNode| {
            let b = &node.bounds;
            (0..WIDTH)
                .filter(|&lane| node.children[lane] != EMPTY_CHILD)
                .map(|lane| {
                    let child = Aabb {
                        min: glam::Vec3::new(b[0][lane], b[1][lane], b[2][lane]),
                        max: glam::Vec3::new(b[3][lane], b[4][lane], b[5][lane]),
                    };
                    child.surface_area() as f64
                })
                .sum::<f64>()
        };
        // The root's own test, then every child's.
        let total = root_area as f64 + crate::bvh::chunked_sum(&self.nodes, parallel, node_area);
        (total / root_area as f64) as f32
    }
}

/// The plan's rows, written from several threads: each thread writes the
/// rows of its own subtrees only, and reads a row only after it or a
/// thread it has joined wrote it.
struct Rows(*mut [f32; WIDTH]);

// SAFETY: see the type's comment; every access goes through `read` and
// `write`, whose callers keep to it.
unsafe impl Sync for Rows {}

impl Rows {
    /// # Safety
    /// Row `i` exists and has been written, by this thread or one it has joined.
    unsafe fn read(&self, i: usize) -> [f32; WIDTH] {
        // SAFETY: the caller's promise.
        unsafe { *self.0.add(i) }
    }

    /// # Safety
    /// Row `i` exists and no other thread reads or writes it meanwhile.
    unsafe fn write(&self, i: usize, row: [f32; WIDTH]) {
        // SAFETY: the caller's promise.
        unsafe { *self.0.add(i) = row }
    }
}

/// For k = 2..=8 (at index k − 1), the least cost of two subtrees whose
/// least costs in 1..=8 lanes are `a` and `b`, in at most k lanes
/// together; index 0 is unused.
#[inline]
fn spread_costs(a: &[f32; WIDTH], b: &[f32; WIDTH]) -> [f32; WIDTH] {
    let mut least = [f32::INFINITY; WIDTH];
    // Costs never grow with more lanes. A subtree that gains nothing from
    // them (a leaf block, most often) is best given one lane, the other
    // the rest: the same sums the full search below would pick, for
    // a seventh of the work.
    if a[0] == a[WIDTH - 1] {
        for k in 1..WIDTH {
            least[k] = a[0] + b[k - 1];
        }
        return least;
    }
    if b[0] == b[WIDTH - 1] {
        for k in 1..WIDTH {
            least[k] = a[k - 1] + b[0];
        }
        return least;
    }
    for i in 0..WIDTH - 1 {
        for j in 0..WIDTH - 1 - i {
            // i + 1 lanes for the first, j + 1 for the second.
            least[i + j + 1] = least[i + j + 1].min(a[i] + b[j]);
        }
    }
    least
}

/// The leaf-order triangle range under every binary node: children follow
/// their parents in the array, so one backward pass suffices.
fn subtree_ranges(nodes: &[Node]) -> Vec<(u32, u32)> {
    let mut ranges = vec![(0u32, 0u32); nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        ranges[i] = if n.is_leaf() {
            (n.first, n.count)
        } else {
            let (a, b) = (ranges[n.first as usize], ranges[n.first as usize + 1]);
            (a.0.min(b.0), a.1 + b.1)
        };
    }
    ranges
}

/// Where an emission goes: a dry run that only counts, or a stretch of the
/// final arrays whose first entries are nodes `node_base` and blocks
/// `block_base` overall.
trait Sink {
    /// Appends an inner node with no children yet; returns its global index.
    fn node(&mut self) -> u32;
    /// Sets child `lane` of the node with global index `node`.
    fn set_child(&mut self, node: u32, lane: usize, reference: u32, bounds: Aabb);
    /// Appends a leaf block for binary node `leaf`; returns its global index.
    fn block(&mut self, leaf: usize) -> u32;
}

#[derive(Clone, Copy, Default)]
struct Count {
    nodes: usize,
    blocks: usize,
}

impl Sink for Count {
    fn node(&mut self) -> u32 {
        self.nodes += 1;
        (self.nodes - 1) as u32
    }
    fn set_child(&mut self, _: u32, _: usize, _: u32, _: Aabb) {}
    fn block(&mut self, _: usize) -> u32 {
        self.blocks += 1;
        (self.blocks - 1) as u32
    }
}

struct Stretch<'a> {
    nodes: &'a mut [WideNode],
    /// The binary node each block is made from, in block order.
    leaves: &'a mut [u32],
    node_base: usize,
    block_base: usize,
    next_node: usize,
    next_block: usize,
}

impl<'a> Stretch<'a> {
    fn new(nodes: &'a mut [WideNode], leaves: &'a mut [u32], at: Count) -> Self {
        Stretch {
            nodes,
            leaves,
            node_base: at.nodes,
            block_base: at.blocks,
            next_node: 0,
            next_block: 0,
        }
    }
}

impl Sink for Stretch<'_> {
    fn node(&mut self) -> u32 {
        self.nodes[self.next_node] = EMPTY_NODE;
        self.next_node += 1;
        (self.node_base + self.next_node - 1) as u32
    }
    fn set_child(&mut self, node: u32, lane: usize, reference: u32, b: Aabb) {
        set_lane(
            &mut self.nodes[node as usize - self.node_base],
            lane,
            reference,
            b,
        );
    }
    fn block(&mut self, leaf: usize) -> u32 {
        self.leaves[self.next_block] = leaf as u32;
        self.next_block += 1;
        (self.block_base + self.next_block - 1) as u32
    }
}

/// The end of the final arrays, for the sequential collapse: appends, so
/// it needs no dry run to know where each task's part starts.
struct Grow<'a> {
    nodes: &'a mut Vec<WideNode>,
    leaves: &'a mut Vec<u32>,
}

impl Sink for Grow<'_> {
    fn node(&mut self) -> u32 {
        self.nodes.push(EMPTY_NODE);
        (self.nodes.len() - 1) as u32
    }
    fn set_child(&mut self, node: u32, lane: usize, reference: u32, b: Aabb) {
        set_lane(&mut self.nodes[node as usize], lane, reference, b);
    }
    fn block(&mut self, leaf: usize) -> u32 {
        self.leaves.push(leaf as u32);
        (self.leaves.len() - 1) as u32
    }
}

/// The top part's binary subtrees left to tasks, in emission order, and
/// each one's reference once the tasks are placed: `None` on the dry run,
/// which lists the subtrees.
#[derive(Default)]
struct Deferred {
    subtrees: Vec<usize>,
    roots: Option<Vec<u32>>,
    next: usize,
}

impl Collapser<'_> {
    /// Whether the subtree under binary node `node` becomes one leaf block
    /// when it is a child of a wide node.
    fn is_leaf(&self, node: usize) -> bool {
        self.binary[node].is_leaf() || self.ranges[node].1 <= 4
    }

    /// Whether the collapse may open binary node `node` to put its
    /// children in lanes of their own: any inner node above four
    /// triangles, and a smaller one where the builder's criterion says two
    /// blocks beat one (the builder only leaves such nodes where it does,
    /// but a tree built with smaller leaves has others).
    fn openable(&self, node: usize) -> bool {
        let n = &self.binary[node];
        if n.is_leaf() {
            return false;
        }
        if self.ranges[node].1 > 4 {
            return true;
        }
        let first = n.first as usize;
        crate::bvh::small_split_pays(
            n.bounds,
            self.binary[first].bounds,
            self.binary[first + 1].bounds,
        )
    }

    fn collapse_all(&self, parallel: bool) -> (u32, Vec<WideNode>, Vec<TriangleBlock>) {
        let (root, nodes, leaves) = if parallel {
            self.place_parallel()
        } else {
            self.place_sequential()
        };
        assert!(
            leaves.len() <= LEAF_INDEX_MASK as usize + 1,
            "too many leaves for a 29-bit index"
        );
        // The blocks last, in one flat pass: gathering each leaf's
        // triangles reads all over the caller's array, and a plain loop
        // (on every thread) keeps many of those reads in flight.
        let mut blocks: Vec<TriangleBlock> = bytemuck::zeroed_vec(leaves.len());
        let fill = |(out, leaves): (&mut [TriangleBlock], &[u32])| {
            for (k, (block, &n)) in out.iter_mut().zip(leaves).enumerate() {
                if let Some(&ahead) = leaves.get(k + PREFETCH_BLOCKS) {
                    self.prefetch_leaf(ahead as usize);
                }
                *block = self.leaf_block(n as usize);
            }
        };
        if parallel {
            use rayon::prelude::*;
            blocks
                .par_chunks_mut(BLOCK_CHUNK)
                .zip(leaves.par_chunks(BLOCK_CHUNK))
                .for_each(fill);
        } else {
            blocks
                .chunks_mut(BLOCK_CHUNK)
                .zip(leaves.chunks(BLOCK_CHUNK))
                .for_each(fill);
        }
        (root, nodes, blocks)
    }

    /// A dry run of the top of the wide tree: the binary subtrees it leaves
    /// to tasks, what the top itself emits, and whether the root is a task
    /// (then the top is empty).
    fn plan_top(&self) -> (Deferred, Count, bool) {
        let mut deferred = Deferred::default();
        let mut top = Count::default();
        let root_is_task = !self.is_leaf(0) && self.ranges[0].1 <= TASK_TRIANGLES;
        if root_is_task {
            deferred.subtrees.push(0);
        } else {
            self.emit(0, &mut top, Some(&mut deferred));
        }
        (deferred, top, root_is_task)
    }

    /// The sequential collapse: the same layout as the parallel one (the
    /// top, then task after task), but each task is appended where the
    /// last one ended, so only the top needs a dry run.
    fn place_sequential(&self) -> (u32, Vec<WideNode>, Vec<u32>) {
        let (mut deferred, top, root_is_task) = self.plan_top();
        let mut nodes: Vec<WideNode> = bytemuck::zeroed_vec(top.nodes);
        let mut leaves = vec![0u32; top.blocks];
        let mut roots = Vec::with_capacity(deferred.subtrees.len());
        for &subtree in &deferred.subtrees {
            let mut out = Grow {
                nodes: &mut nodes,
                leaves: &mut leaves,
            };
            roots.push(self.emit(subtree, &mut out, None));
        }
        let root = if root_is_task {
            roots[0]
        } else {
            deferred.roots = Some(roots);
            let mut out = Stretch::new(
                &mut nodes[..top.nodes],
                &mut leaves[..top.blocks],
                Count::default(),
            );
            self.emit(0, &mut out, Some(&mut deferred))
        };
        (root, nodes, leaves)
    }

    /// The parallel collapse: dry runs size every task's part, then the
    /// tasks write their parts at once.
    fn place_parallel(&self) -> (u32, Vec<WideNode>, Vec<u32>) {
        // Dry runs: the top, which lists the tasks, then every task.
        let (mut deferred, top, root_is_task) = self.plan_top();
        let count = |&subtree: &usize| {
            let mut n = Count::default();
            self.emit(subtree, &mut n, None);
            n
        };
        let counts: Vec<Count> = {
            use rayon::prelude::*;
            deferred.subtrees.par_iter().map(count).collect()
        };
        // Each task's place; its root is its first node.
        let mut at = top;
        let mut starts = Vec::with_capacity(counts.len());
        let mut roots = Vec::with_capacity(counts.len());
        for n in &counts {
            starts.push(at);
            roots.push(at.nodes as u32);
            at.nodes += n.nodes;
            at.blocks += n.blocks;
        }
        // Filled on every thread: the allocator hands back recycled memory
        // (the build freed bigger arrays), which zeroing on one thread took
        // 3 ms of the dragon's build.
        let mut nodes: Vec<WideNode> = Vec::with_capacity(at.nodes);
        let mut leaves: Vec<u32> = Vec::with_capacity(at.blocks);
        {
            use rayon::prelude::*;
            nodes.par_extend(rayon::iter::repeat_n(EMPTY_NODE, at.nodes));
            leaves.par_extend(rayon::iter::repeat_n(0, at.blocks));
        }
        let (top_nodes, mut rest_nodes) = nodes.split_at_mut(top.nodes);
        let (top_blocks, mut rest_blocks) = leaves.split_at_mut(top.blocks);
        let root = if root_is_task {
            roots[0]
        } else {
            deferred.roots = Some(roots);
            let mut out = Stretch::new(top_nodes, top_blocks, Count::default());
            self.emit(0, &mut out, Some(&mut deferred))
        };
        let mut tasks = Vec::with_capacity(counts.len());
        for ((&subtree, n), &start) in deferred.subtrees.iter().zip(&counts).zip(&starts) {
            let (task_nodes, more_nodes) = std::mem::take(&mut rest_nodes).split_at_mut(n.nodes);
            let (task_blocks, more_blocks) =
                std::mem::take(&mut rest_blocks).split_at_mut(n.blocks);
            (rest_nodes, rest_blocks) = (more_nodes, more_blocks);
            tasks.push((subtree, Stretch::new(task_nodes, task_blocks, start)));
        }
        let run = |(subtree, mut out): (usize, Stretch)| {
            self.emit(subtree, &mut out, None);
        };
        {
            use rayon::prelude::*;
            tasks.into_par_iter().for_each(run);
        }
        (root, nodes, leaves)
    }

    /// Emits the subtree under binary node `node`; returns its child
    /// reference. With `deferred`, non-leaf subtrees of at most
    /// `TASK_TRIANGLES` are left to tasks: listed on a dry run, referred
    /// to by their placed roots on the real one.
    fn emit<S: Sink>(&self, node: usize, out: &mut S, mut deferred: Option<&mut Deferred>) -> u32 {
        if self.is_leaf(node) {
            let (_, count) = self.ranges[node];
            return LEAF_BIT | (count - 1) << LEAF_COUNT_SHIFT | out.block(node);
        }
        let nodes = self.binary;
        // The binary nodes the plan dissolves into this node's lanes.
        let mut opened = [node; WIDTH - 1];
        let mut opened_count = 0;
        self.spread(node, WIDTH, &mut opened, &mut opened_count);
        let opened = &opened[..opened_count];
        // Lanes in the order the greedy collapse gives them (each opened
        // node's first child takes its lane, the second the next free
        // one, widest opened first): any-hit queries visit the lanes from
        // the last, and this order measured faster for them than the
        // binary tree's left-to-right order or any order by area.
        let first = nodes[node].first as usize;
        let mut children = [0; WIDTH];
        let area = |c: usize| {
            if opened[1..].contains(&c) {
                nodes[c].bounds.surface_area()
            } else {
                f32::NEG_INFINITY
            }
        };
        let mut areas = [f32::NEG_INFINITY; WIDTH];
        (children[0], children[1]) = (first, first + 1);
        (areas[0], areas[1]) = (area(first), area(first + 1));
        let mut count = 2;
        while count < WIDTH {
            let mut widest = None;
            let mut widest_area = f32::NEG_INFINITY;
            for (k, &a) in areas[..count].iter().enumerate() {
                if a > widest_area {
                    (widest, widest_area) = (Some(k), a);
                }
            }
            let Some(k) = widest else { break };
            let next = nodes[children[k]].first as usize;
            (children[k], areas[k]) = (next, area(next));
            (children[count], areas[count]) = (next + 1, area(next + 1));
            count += 1;
        }
        let index = out.node();
        for (lane, &child) in children[..count].iter().enumerate() {
            let reference = match deferred.as_deref_mut() {
                Some(d) if !self.is_leaf(child) && self.ranges[child].1 <= TASK_TRIANGLES => {
                    match &d.roots {
                        None => {
                            d.subtrees.push(child);
                            EMPTY_CHILD
                        }
                        Some(roots) => {
                            d.next += 1;
                            roots[d.next - 1]
                        }
                    }
                }
                _ => self.emit(child, out, deferred.as_deref_mut()),
            };
            out.set_child(index, lane, reference, nodes[child].bounds);
        }
        index
    }

    /// The SAH-optimal collapse (Ylitie, Karras and Laine, "Efficient
    /// Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs",
    /// 2017): for every binary node and every k from 1 to 8, the least
    /// cost of its subtree when it may take at most k lanes of its
    /// parent, in one pass from the leaves up (children follow their
    /// parents in the array). In one lane the subtree is a leaf block or
    /// a wide node; in more, an openable node may instead spread its two
    /// children over them. The cost is the wide tree's SAH cost, every
    /// node and block test weighing its box's area, so the tree this
    /// gives has the least SAH cost of all the collapses of the binary
    /// tree: 3% below the greedy collapse's on the bunny, 2.5% on the
    /// dragon and 6% on Sponza, whose long thin triangles leave many
    /// overlapping boxes for the order of opening to matter.
    ///
    /// With `parallel`, subtrees of more than `TASK_TRIANGLES` are planned
    /// on the rayon pool, two at a time: planning the dragon took 7 ms, on
    /// one thread the whole of a two-thread build's last 4%.
    fn plan_lanes(&self, parallel: bool) -> Vec<[f32; WIDTH]> {
        let mut best = vec![[0.0f32; WIDTH]; self.binary.len()];
        if !self.binary.is_empty() {
            let rows = Rows(best.as_mut_ptr());
            self.plan_subtree(0, &rows, parallel);
        }
        best
    }

    /// Plans binary node `node`'s subtree, children first.
    fn plan_subtree(&self, node: usize, rows: &Rows, parallel: bool) {
        let n = &self.binary[node];
        let area = n.bounds.surface_area();
        let mut row = [area; WIDTH];
        if !n.is_leaf() {
            let first = n.first as usize;
            if parallel && self.ranges[node].1 > TASK_TRIANGLES {
                rayon::join(
                    || self.plan_subtree(first, rows, parallel),
                    || self.plan_subtree(first + 1, rows, parallel),
                );
            } else {
                self.plan_subtree(first, rows, false);
                self.plan_subtree(first + 1, rows, false);
            }
            let leaf = self.is_leaf(node);
            if !leaf || self.openable(node) {
                // SAFETY: both children's rows were written above, on this
                // thread or on one `rayon::join` has waited for.
                let (a, b) = unsafe { (rows.read(first), rows.read(first + 1)) };
                let spread = spread_costs(&a, &b);
                if !leaf {
                    row[0] = area + spread[WIDTH - 1];
                }
                for k in 1..WIDTH {
                    row[k] = row[0].min(spread[k]);
                }
            }
        }
        // SAFETY: each node is planned once, by the one call that owns its
        // subtree, so no other thread touches this row.
        unsafe { rows.write(node, row) };
    }

    /// The least cost of binary node `node`'s two children in at most
    /// `lanes` lanes (at least two), and how many the first one takes; of
    /// equal costs, the fewest for the first.
    #[inline]
    fn spread_cost(&self, best: &[[f32; WIDTH]], node: usize, lanes: usize) -> (f32, usize) {
        let first = self.binary[node].first as usize;
        let (a, b) = (&best[first], &best[first + 1]);
        let mut least = (f32::INFINITY, 1);
        for k in 1..lanes {
            let cost = a[k - 1] + b[lanes - k - 1];
            if cost < least.0 {
                least = (cost, k);
            }
        }
        least
    }

    /// Lists in `opened` binary node `node` and the nodes below it that
    /// are dissolved when its two children take at most `lanes` lanes, as
    /// `plan_lanes` found cheapest.
    fn spread(
        &self,
        node: usize,
        lanes: usize,
        opened: &mut [usize; WIDTH - 1],
        count: &mut usize,
    ) {
        opened[*count] = node;
        *count += 1;
        let first = self.binary[node].first as usize;
        let (_, k) = self.spread_cost(&self.best, node, lanes);
        for (child, lanes) in [(first, k), (first + 1, lanes - k)] {
            let row = &self.best[child];
            if lanes >= 2 && row[lanes - 1] < row[0] {
                self.spread(child, lanes, opened, count);
            }
        }
    }

    /// Asks the cache for the triangles `leaf_block(node)` will read.
    #[inline(always)]
    fn prefetch_leaf(&self, node: usize) {
        #[cfg(target_arch = "x86_64")]
        {
            let (first, count) = self.ranges[node];
            for &id in &self.order[first as usize..(first + count) as usize] {
                let t: *const Triangle = &self.triangles[id as usize];
                // SAFETY: a prefetch is a hint; it reads nothing.
                unsafe {
                    std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(t.cast())
                };
            }
        }
    }

    /// The block of the (up to four) triangles under binary node `node`.
    fn leaf_block(&self, node: usize) -> TriangleBlock {
        let (first, count) = self.ranges[node];
        let mut block = TriangleBlock {
            v: [[[0.0; 4]; 3]; 3],
            id: [u32::MAX; 4],
        };
        assert!(
            (1..=4).contains(&count),
            "a leaf holds one to four triangles"
        );
        for lane in 0..count as usize {
            let k = first as usize + lane;
            let id = self.order[k];
            let t: &Triangle = &self.triangles[id as usize];
            for (vertex, p) in t.v.iter().enumerate() {
                for axis in 0..3 {
                    block.v[vertex][axis][lane] = p[axis];
                }
            }
            block.id[lane] = id;
        }
        block
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::build::build_tree;
    use crate::bvh::BuildOptions;
    use glam::Vec3;

    /// `n` small random triangles, some long and thin, from a fixed seed.
    fn triangles(n: usize, seed: u32) -> Vec<Triangle> {
        let mut state = seed;
        let mut next = || {
            state = crate::sampling::sampler::hash(state.wrapping_add(0x9e37_79b9));
            state as f32 / u32::MAX as f32
        };
        (0..n)
            .map(|k| {
                let c = Vec3::new(next(), next(), next()) * 20.0;
                let size = if k % 5 == 0 { 6.0 } else { 0.8 };
                let mut corner = || c + (Vec3::new(next(), next(), next()) - 0.5) * size;
                Triangle::new(corner(), corner(), corner())
            })
            .collect()
    }

    fn collapser<'a>(binary: &'a [Node], order: &'a [u32], tris: &'a [Triangle]) -> Collapser<'a> {
        let mut c = Collapser {
            binary,
            triangles: tris,
            order,
            ranges: subtree_ranges(binary),
            best: Vec::new(),
        };
        c.best = c.plan_lanes(true);
        c
    }

    /// Every way of laying out binary node `node`'s subtree in at most
    /// `lanes` lanes, found by listing the sets of subtrees its children
    /// can become (each kept whole, or an openable one dissolved into its
    /// own children's sets) and costing each set: the same question as
    /// `plan_lanes` answers, by enumeration rather than by lane counts.
    fn least_by_enumeration(c: &Collapser, node: usize, lanes: usize) -> f32 {
        fn cuts(c: &Collapser, node: usize, limit: usize) -> Vec<Vec<usize>> {
            let mut all = vec![vec![node]];
            // Opening a node takes at least two lanes.
            if limit >= 2 && c.openable(node) {
                let first = c.binary[node].first as usize;
                for a in cuts(c, first, limit - 1) {
                    for b in cuts(c, first + 1, limit - a.len()) {
                        all.push([a.clone(), b].concat());
                    }
                }
            }
            all.retain(|cut| cut.len() <= limit);
            all
        }
        fn whole(c: &Collapser, node: usize) -> f32 {
            let area = c.binary[node].bounds.surface_area();
            if c.is_leaf(node) {
                area
            } else {
                area + least_by_enumeration(c, node, WIDTH)
            }
        }
        let first = c.binary[node].first as usize;
        let mut least = f32::INFINITY;
        for a in cuts(c, first, lanes - 1) {
            for b in cuts(c, first + 1, lanes - a.len()) {
                let cost: f64 = a.iter().chain(&b).map(|&n| whole(c, n) as f64).sum();
                least = least.min(cost as f32);
            }
        }
        least
    }

    #[test]
    fn the_plan_is_the_least_cost_of_every_collapse() {
        for (n, seed) in [(9, 1), (24, 2), (40, 3), (48, 4)] {
            let tris = triangles(n, seed);
            let (binary, order) = build_tree(&tris, &BuildOptions::default());
            let c = collapser(&binary, &order, &tris);
            let planned = c.best[0][0];
            let root = binary[0].bounds.surface_area();
            let enumerated = root + least_by_enumeration(&c, 0, WIDTH);
            assert!(
                (planned - enumerated).abs() <= 1e-4 * enumerated,
                "{n} triangles: planned {planned}, least of all collapses {enumerated}"
            );
        }
    }

    #[test]
    fn the_tree_built_has_the_planned_cost() {
        for (n, seed) in [(5, 5), (300, 6), (5000, 7)] {
            let tris = triangles(n, seed);
            let (binary, order) = build_tree(&tris, &BuildOptions::default());
            let c = collapser(&binary, &order, &tris);
            let planned = c.best[0][0] / binary[0].bounds.surface_area();
            for parallel in [false, true] {
                let wide = WideBvh::collapse(&binary, &order, &tris, parallel);
                let built = wide.report.sah_cost;
                assert!(
                    (built - planned).abs() <= 1e-4 * planned,
                    "{n} triangles: built {built}, planned {planned}"
                );
            }
        }
    }
}
