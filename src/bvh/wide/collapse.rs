//! Turns the binary SAH BVH into the 4-wide one. Each wide node starts from a
//! binary node's two children and repeatedly opens the child with the largest
//! surface area (the one a random ray is most likely to enter) until it has
//! four, the greedy collapse of Wald, Benthin and Boulos, "Getting Rid of
//! Packets" (2008). Any binary subtree of at most four triangles becomes one
//! leaf block: testing four triangles costs one SIMD test, less than a node.

use super::{
    BuildReport, Node4, TriangleBlock, WideBvh, EMPTY_CHILD, LEAF_BIT, LEAF_COUNT_SHIFT,
    LEAF_INDEX_MASK,
};
use crate::bvh::Node;
use crate::geometry::{Aabb, Triangle};

const EMPTY_BOUNDS: [[f32; 4]; 6] = [
    [f32::INFINITY; 4],
    [f32::INFINITY; 4],
    [f32::INFINITY; 4],
    [f32::NEG_INFINITY; 4],
    [f32::NEG_INFINITY; 4],
    [f32::NEG_INFINITY; 4],
];

struct Collapser<'a> {
    binary: &'a [Node],
    /// The caller's triangles, and the binary tree's leaf order of them.
    triangles: &'a [Triangle],
    order: &'a [u32],
    /// Per binary node: (first triangle in leaf order, triangle count) of its subtree.
    ranges: Vec<(u32, u32)>,
    nodes: Vec<Node4>,
    blocks: Vec<TriangleBlock>,
}

impl WideBvh {
    pub(in crate::bvh) fn collapse(
        binary: &[Node],
        order: &[u32],
        triangles: &[Triangle],
    ) -> WideBvh {
        let mut c = Collapser {
            binary,
            triangles,
            order,
            ranges: subtree_ranges(binary),
            nodes: Vec::with_capacity(binary.len() / 3 + 1),
            blocks: Vec::with_capacity(order.len() / 3 + 1),
        };
        let root = if binary.is_empty() {
            EMPTY_CHILD
        } else {
            c.emit(0)
        };
        let bounds = binary.first().map_or(Aabb::EMPTY, |n| n.bounds);
        let mut wide = WideBvh {
            root,
            bounds,
            report: BuildReport {
                binary_sah_cost: crate::bvh::sah_cost(binary),
                nodes: c.nodes.len(),
                leaves: c.blocks.len(),
                triangles: order.len(),
                ..BuildReport::default()
            },
            nodes: c.nodes.into(),
            blocks: c.blocks.into(),
        };
        wide.report.sah_cost = wide.sah_cost();
        wide
    }

    /// Expected cost of a random ray: area-weighted node and leaf tests
    /// over the root's area (the root's own test included).
    fn sah_cost(&self) -> f32 {
        let root_area = self.bounds.surface_area();
        if root_area <= 0.0 || self.root == EMPTY_CHILD {
            return 0.0;
        }
        let mut total = root_area; // the root's test
        for node in &self.nodes {
            for lane in 0..4 {
                if node.children[lane] == EMPTY_CHILD {
                    continue;
                }
                let b = &node.bounds;
                let child = Aabb {
                    min: glam::Vec3::new(b[0][lane], b[1][lane], b[2][lane]),
                    max: glam::Vec3::new(b[3][lane], b[4][lane], b[5][lane]),
                };
                total += child.surface_area();
            }
        }
        total / root_area
    }
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

impl Collapser<'_> {
    fn is_leaf(&self, node: usize) -> bool {
        self.binary[node].is_leaf() || self.ranges[node].1 <= 4
    }

    /// Emits the subtree under binary node `node`; returns its child reference.
    fn emit(&mut self, node: usize) -> u32 {
        if self.is_leaf(node) {
            return self.emit_leaf(node);
        }
        let nodes = self.binary;
        let first = nodes[node].first as usize;
        let mut children = [first, first + 1, 0, 0];
        let mut count = 2;
        while count < 4 {
            let mut widest = None;
            let mut widest_area = f32::NEG_INFINITY;
            for (k, &c) in children[..count].iter().enumerate() {
                let area = nodes[c].bounds.surface_area();
                if !self.is_leaf(c) && area > widest_area {
                    (widest, widest_area) = (Some(k), area);
                }
            }
            let Some(k) = widest else { break };
            let opened = nodes[children[k]].first as usize;
            children[k] = opened;
            children[count] = opened + 1;
            count += 1;
        }
        let children = &children[..count];
        let index = self.nodes.len();
        self.nodes.push(Node4 {
            bounds: EMPTY_BOUNDS,
            children: [EMPTY_CHILD; 4],
        });
        for (lane, &child) in children.iter().enumerate() {
            let reference = self.emit(child);
            let b = nodes[child].bounds;
            let n = &mut self.nodes[index];
            n.children[lane] = reference;
            for axis in 0..3 {
                n.bounds[axis][lane] = b.min[axis];
                n.bounds[3 + axis][lane] = b.max[axis];
            }
        }
        index as u32
    }

    fn emit_leaf(&mut self, node: usize) -> u32 {
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
        let index = self.blocks.len() as u32;
        assert!(
            index <= LEAF_INDEX_MASK,
            "too many leaves for a 29-bit index"
        );
        self.blocks.push(block);
        LEAF_BIT | (count - 1) << LEAF_COUNT_SHIFT | index
    }
}
