//! Closest-hit and any-hit traversal of the 8-wide BVH: one SIMD slab test
//! for a node's eight children, nearest child first, and one SIMD watertight
//! test (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection",
//! 2013) for a leaf's four triangles. The triangle test computes exactly what
//! the scalar `RayShear` computes, lane by lane, so both BVHs report the
//! same distances bit for bit.

use super::{
    Traversal, TriangleBlock, WideBvh, WideNode, EMPTY_CHILD, LEAF_BIT, LEAF_COUNT_SHIFT,
    LEAF_INDEX_MASK, WIDTH,
};
use crate::bvh::Hit;
use crate::geometry::triangle::RayShear;
use crate::geometry::Ray;
use std::mem::MaybeUninit;
use wide::{f32x16, f32x4, f32x8};

/// A leaf reference's block index and triangle count.
#[inline(always)]
pub(super) fn leaf(reference: u32) -> (usize, u32) {
    (
        (reference & LEAF_INDEX_MASK) as usize,
        ((reference & !LEAF_BIT) >> LEAF_COUNT_SHIFT) + 1,
    )
}

/// The deepest tree the traversal stack holds: each node visit pushes at
/// most `WIDTH - 1` children, and the builder's trees are at most 96 deep (64 SAH
/// levels plus a median tail of at most 32).
pub(super) const MAX_DEPTH: usize = 96;
const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH + 4;

/// Room for a traversal stack, left uninitialised: zeroing two kilobytes
/// on every ray cost more than the traversal itself in small scenes.
pub(super) type StackStorage<T> = [MaybeUninit<T>; STACK_SIZE];

/// Uninitialised room for a [`Stack`].
#[inline(always)]
pub(super) fn stack_storage<T: Copy>() -> StackStorage<T> {
    [const { MaybeUninit::uninit() }; STACK_SIZE]
}

/// The traversal stack. Its entries live in storage of their own, apart
/// from `top`: when both shared one struct, the compiler could not tell a
/// write to an entry from a write to `top`, so it kept `top` in memory and
/// every push and pop went through a store and a reload.
pub(super) struct Stack<'a, T: Copy> {
    entries: &'a mut StackStorage<T>,
    top: usize,
}

impl<'a, T: Copy> Stack<'a, T> {
    #[inline(always)]
    pub(super) fn new(entries: &'a mut StackStorage<T>) -> Self {
        Stack { entries, top: 0 }
    }

    #[inline(always)]
    pub(super) fn push(&mut self, entry: T) {
        // Bounds-checked: an overflow panics rather than corrupting memory.
        self.entries[self.top].write(entry);
        self.top += 1;
    }

    /// The entry `pop` would return, left in place.
    #[inline(always)]
    pub(super) fn peek(&self) -> Option<T> {
        // SAFETY: every entry below `top` was written by `push`.
        (self.top > 0).then(|| unsafe { self.entries[self.top - 1].assume_init() })
    }

    /// How many entries the stack holds.
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        self.top
    }

    /// The entries from `base` up to the top.
    #[inline(always)]
    pub(super) fn above(&self, base: usize) -> &[T] {
        let entries = &self.entries[base.min(self.top)..self.top];
        // SAFETY: every entry below `top` was written by `push`, and
        // `MaybeUninit<T>` has the layout of `T`.
        unsafe { std::slice::from_raw_parts(entries.as_ptr().cast(), entries.len()) }
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if self.top == 0 {
            return None;
        }
        self.top -= 1;
        // SAFETY: every entry below `top` was written by `push`.
        Some(unsafe { self.entries[self.top].assume_init() })
    }
}

impl Stack<'_, (u32, f32)> {
    /// Pushes `entry` (a child and its entry distance) among the entries
    /// above `base`, which stay ordered with the nearest on top; of equal
    /// distances, the one pushed first stays above, as a stable sort by
    /// distance would leave them.
    #[inline(always)]
    pub(super) fn push_ordered(&mut self, base: usize, entry: (u32, f32)) {
        let mut k = self.top;
        while k > base {
            // SAFETY: every entry below `top` was written by `push`.
            let below = unsafe { self.entries[k - 1].assume_init() };
            if below.1 >= entry.1 {
                break;
            }
            // Bounds-checked, as in `push`.
            self.entries[k].write(below);
            k -= 1;
        }
        self.entries[k].write(entry);
        self.top += 1;
    }
}

/// Slab distances are rounded; stretching the exit distance by a few ULPs
/// keeps a hit that lies exactly on a box face from being culled (Ize,
/// "Robust BVH Ray Traversal", 2013).
pub(super) const EXIT_STRETCH: f32 = 1.0 + 4.0 * f32::EPSILON;

/// 1/c for a slab test. A zero component would give 0 × ∞ = NaN for a ray
/// lying in a slab plane; a tiny stand-in keeps every distance a number of
/// the right sign.
#[inline(always)]
pub(super) fn safe_inverse(c: f32) -> f32 {
    1.0 / if c.abs() < 1e-20 {
        1e-20f32.copysign(c)
    } else {
        c
    }
}

/// [`safe_inverse`] of the three components at once: one vector division
/// rather than three scalar ones, and no branch (the same numbers, as
/// division rounds alike in both). Also returns the inverses' sign bits
/// (bit a for axis a), which the slab test's row choice reads.
#[inline(always)]
fn safe_inverses(d: [f32; 3]) -> ([f32; 3], u32) {
    let c = f32x4::new([d[0], d[1], d[2], 1.0]);
    let tiny = f32x4::splat(1e-20);
    let stand_in = (c & f32x4::splat(-0.0)) | tiny;
    let c = c.abs().simd_lt(tiny).select(stand_in, c);
    let inverses = f32x4::ONE / c;
    let [x, y, z, _] = inverses.to_array();
    ([x, y, z], inverses.to_bitmask())
}

/// The edge functions `u`, `v`, `w` of the watertight test, recomputed in
/// double precision for the lanes in `lanes` (bit k for lane k), where
/// single precision gave an exact zero: an edge passes (nearly) through
/// the ray there, and the scalar test decides such lanes exactly too.
/// `xy` holds the projected vertices' coordinates `ax, ay, bx, by, cx, cy`.
/// Rare.
pub(super) fn exact_edges<const N: usize>(
    lanes: u32,
    xy: [[f32; N]; 6],
    uvw: [[f32; N]; 3],
) -> [[f32; N]; 3] {
    let [ax, ay, bx, by, cx, cy] = xy;
    let [mut u, mut v, mut w] = uvw;
    let d = |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
    let mut m = lanes;
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        u[l] = d(cx[l], by[l], cy[l], bx[l]);
        v[l] = d(ax[l], cy[l], ay[l], cx[l]);
        w[l] = d(bx[l], ay[l], by[l], ax[l]);
    }
    [u, v, w]
}

/// The ray, splatted across lanes, with what every test reuses. Every
/// field is read at a fixed position (the per-ray axis choices index the
/// node and the block, never this struct), so the compiler can keep it in
/// registers rather than on the stack.
pub(super) struct RayLanes {
    origin: [f32x8; 3],
    /// The direction's inverses, negated: the slab distance (plane −
    /// origin) × inverse is computed as (origin − plane) × −inverse, the
    /// same value (negation is exact, and subtraction and multiplication
    /// round symmetrically; only a zero may change sign, which no
    /// comparison sees), so that the plane, the operand read from the
    /// node, comes second, where the instruction can take it straight from
    /// memory: one load fewer per slab, six per node.
    neg_inv_dir: [f32x8; 3],
    /// `neg_inv_dir` stretched by `EXIT_STRETCH`, for the exit distances:
    /// the stretch then costs no multiplication on the path from a node's
    /// load to the choice of the next node.
    neg_inv_dir_exit: [f32x8; 3],
    /// Per axis, which row of `WideNode::bounds` holds the near plane (the
    /// minimum for a positive direction, the maximum for a negative one),
    /// and which the far one.
    near_row: [usize; 3],
    far_row: [usize; 3],
    tmin: f32,
    /// The watertight test's axes: `kx`, `ky`, then the dominant `kz`
    /// (see `RayShear`).
    k: [usize; 3],
    /// The origin's coordinates along `kx`, `ky` and `kz`.
    origin_k: [f32x8; 3],
    /// The shear constants `sx`, `sy`, `sz`.
    shear: [f32x8; 3],
}

impl RayLanes {
    pub(super) fn new(ray: &Ray) -> RayLanes {
        let d = ray.dir.to_array();
        let o = ray.origin.to_array();
        let (inv, signs) = safe_inverses(d);
        let (k, s) = RayShear::new(ray.origin, ray.dir).parts();
        // For a finite direction the inverses are never zero or NaN, so a
        // set sign bit is exactly a negative inverse.
        let negative = [0, 1, 2].map(|a| (signs >> a) as usize & 1);
        let near_row = [0, 1, 2].map(|a| a + 3 * negative[a]);
        RayLanes {
            origin: o.map(f32x8::splat),
            neg_inv_dir: inv.map(|i| f32x8::splat(-i)),
            neg_inv_dir_exit: inv.map(|i| f32x8::splat(-(i * EXIT_STRETCH))),
            near_row,
            far_row: [0, 1, 2].map(|a| a + 3 - 3 * negative[a]),
            tmin: ray.tmin,
            k,
            origin_k: k.map(|axis| f32x8::splat(o[axis])),
            shear: s.map(f32x8::splat),
        }
    }

    /// Entry distances into the node's child boxes, and a bit mask of those
    /// the ray enters before `tmax`.
    ///
    /// The exit distances are stretched (see `EXIT_STRETCH`) through
    /// `neg_inv_dir_exit`, and the three axes' distances are combined as a tree
    /// (two maxima, then one), not a chain: both shorten the dependency
    /// chain from loading a node to knowing which child comes next. The
    /// minima and maxima are exact and no distance is NaN (the inverses are
    /// finite and non-zero), so the order of combining changes nothing.
    #[inline(always)]
    fn enter(&self, node: &WideNode, tmax: f32) -> (f32x8, u32) {
        let entry = |axis: usize| {
            (self.origin[axis] - f32x8::new(node.bounds[self.near_row[axis]]))
                * self.neg_inv_dir[axis]
        };
        let exit = |axis: usize| {
            (self.origin[axis] - f32x8::new(node.bounds[self.far_row[axis]]))
                * self.neg_inv_dir_exit[axis]
        };
        let near = entry(0)
            .fast_max(entry(1))
            .fast_max(entry(2).fast_max(f32x8::splat(self.tmin)));
        let far = exit(0)
            .fast_min(exit(1))
            .fast_min(exit(2).fast_min(f32x8::splat(tmax * EXIT_STRETCH)));
        (near, near.simd_le(far).to_bitmask())
    }

    /// The watertight test on two blocks at once, in the eight lanes of one
    /// AVX register: the first `count_a` triangles of `a` in lanes 0-3 and
    /// the first `count_b` of `b` in lanes 4-7 (`count_b` = 0 tests `a`
    /// alone, at the same cost). Returns a bit mask of lanes hit within
    /// (tmin, tmax), their distances, and the barycentrics of vertices 1
    /// and 2. A node's children that are leaves tend to be entered together;
    /// testing two per call halves what their triangles cost.
    #[inline(always)]
    pub(super) fn intersect(
        &self,
        a: &TriangleBlock,
        count_a: u32,
        b: &TriangleBlock,
        count_b: u32,
        tmax: f32,
    ) -> (u32, [f32; 8], [f32; 8], [f32; 8]) {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        // Vertex positions relative to the origin, sheared so the ray runs along +z.
        let [ox, oy, oz] = self.origin_k;
        let both = |p: &[f32; 4], q: &[f32; 4]| {
            f32x8::new([p[0], p[1], p[2], p[3], q[0], q[1], q[2], q[3]])
        };
        let project = |vertex: usize| {
            let (p, q) = (&a.v[vertex], &b.v[vertex]);
            let x = both(&p[kx], &q[kx]) - ox;
            let y = both(&p[ky], &q[ky]) - oy;
            let z = both(&p[kz], &q[kz]) - oz;
            (x - sx * z, y - sy * z, z)
        };
        let lanes = ((1u32 << count_a) - 1) | (((1u32 << count_b) - 1) << 4);
        let (hit, t, b1, b2) = watertight_lanes(
            [project(0), project(1), project(2)],
            sz,
            lanes,
            f32x8::splat(self.tmin),
            f32x8::splat(tmax),
        );
        (
            hit.to_bitmask() & lanes,
            t.to_array(),
            b1.to_array(),
            b2.to_array(),
        )
    }
}

/// Defines `$name`, the watertight test on the lanes of `$lanes`, from
/// each lane's three vertices already made relative to its ray's origin
/// and sheared (x, y, and the unscaled z): the edge functions, decided in
/// double precision where single precision gives an exact zero in a lane
/// of `lanes`, then a mask of the lanes hit within (`tmin`, `tmax`), their
/// distances, and the barycentrics of vertices 1 and 2. One body for both
/// widths, so the eight-lane and sixteen-lane tests compute the same
/// numbers lane by lane.
macro_rules! watertight_test {
    ($(#[$doc:meta])* $name:ident, $lanes:ty) => {
        $(#[$doc])*
        #[inline(always)]
        pub(super) fn $name(
            vertices: [($lanes, $lanes, $lanes); 3],
            sz: $lanes,
            lanes: u32,
            tmin: $lanes,
            tmax: $lanes,
        ) -> ($lanes, $lanes, $lanes, $lanes) {
            let [(ax, ay, az), (bx, by, bz), (cx, cy, cz)] = vertices;
            let mut u = cx * by - cy * bx;
            let mut v = ax * cy - ay * cx;
            let mut w = bx * ay - by * ax;
            let zero = <$lanes>::ZERO;
            let on_edge =
                (u.simd_eq(zero) | v.simd_eq(zero) | w.simd_eq(zero)).to_bitmask() & lanes;
            if on_edge != 0 {
                let xy = [ax, ay, bx, by, cx, cy].map(|c| c.to_array());
                let [ua, va, wa] = exact_edges(on_edge, xy, [u, v, w].map(|c| c.to_array()));
                (u, v, w) = (<$lanes>::new(ua), <$lanes>::new(va), <$lanes>::new(wa));
            }
            let outside = (u.simd_lt(zero) | v.simd_lt(zero) | w.simd_lt(zero))
                & (u.simd_gt(zero) | v.simd_gt(zero) | w.simd_gt(zero));
            let det = u + v + w;
            let t_scaled = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
            let inv_det = <$lanes>::ONE / det;
            let t = t_scaled * inv_det;
            // Comparisons with NaN are false, so a zero determinant (0 × ∞) never hits.
            let hit = !outside & det.simd_ne(zero) & t.simd_gt(tmin) & t.simd_lt(tmax);
            (hit, t, v * inv_det, w * inv_det)
        }
    };
}

watertight_test!(
    /// The watertight test on eight lanes: for the single-ray test (eight
    /// triangles, one ray) and the packet test (one triangle, eight rays).
    watertight_lanes,
    f32x8
);

watertight_test!(
    /// The watertight test on sixteen lanes: for the flat scenes' groups
    /// of sixteen triangles (see `flat.rs`).
    watertight_lanes_16,
    f32x16
);

impl WideBvh {
    /// Asks the cache for the node or leaf block `reference` names, which
    /// the traversal will visit soon: its first lines are then on the way
    /// while the current node's other children are handled.
    #[inline(always)]
    fn prefetch_reference(&self, reference: u32) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let (address, bytes): (*const u8, usize) = if reference & LEAF_BIT == 0 {
                (
                    self.nodes.as_ptr().wrapping_add(reference as usize).cast(),
                    std::mem::size_of::<WideNode>(),
                )
            } else {
                (
                    self.blocks
                        .as_ptr()
                        .wrapping_add((reference & LEAF_INDEX_MASK) as usize)
                        .cast(),
                    std::mem::size_of::<TriangleBlock>(),
                )
            };
            for offset in (0..bytes).step_by(64) {
                // SAFETY: a prefetch is a hint; it reads nothing, and an
                // address past the end only fetches a line in vain.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(address.wrapping_add(offset).cast()) };
            }
        }
    }

    /// The closest hit with `ray.tmin < t < ray.tmax`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        // The tree first: the choice costs its rays one test and branch
        // (the perf gate's ray workloads: 0.4-0.8% more instructions).
        if self.traversal == Traversal::Tree {
            self.closest_hit::<false>(ray)
        } else if self.traversal == Traversal::Flat {
            self.closest_hit_flat(ray)
        } else {
            self.closest_hit::<true>(ray)
        }
    }

    /// Whether anything lies on the ray within (tmin, tmax): for shadow
    /// rays, so it stops at the first hit it finds, in whatever order.
    pub fn occluded(&self, ray: &Ray) -> bool {
        // The tree first, as in `intersect`.
        if self.traversal == Traversal::Tree {
            self.any_hit::<false>(ray)
        } else if self.traversal == Traversal::Flat {
            self.any_hit_flat(ray)
        } else {
            self.any_hit::<true>(ray)
        }
    }

    /// `intersect`, prefetching the children it puts on the stack when
    /// `PREFETCH` is set.
    #[inline(always)]
    pub(super) fn closest_hit<const PREFETCH: bool>(&self, ray: &Ray) -> Option<Hit> {
        if self.root == EMPTY_CHILD {
            return None;
        }
        // No test of the root's own box first: the root node's test of its
        // children's boxes rejects a ray that misses everything at about the
        // same cost, and a ray that hits (most of them, in a closed scene)
        // would pay for both.
        let lanes = RayLanes::new(ray);
        let mut tmax = ray.tmax;
        let mut closest: Option<(u32, usize, f32, f32)> = None;
        let mut storage = stack_storage();
        let mut stack = Stack::<(u32, f32)>::new(&mut storage);
        let mut current = self.root;
        loop {
            if current & LEAF_BIT == 0 {
                let node = &self.nodes[current as usize];
                let (near, mut mask) = lanes.enter(node, tmax);
                let near = near.to_array();
                // One or two entered children are handled
                // without the sort below, so the next node's address is
                // known a few steps sooner; the order is the sort's.
                if mask != 0 {
                    let a = mask.trailing_zeros() as usize;
                    let rest = mask & (mask - 1);
                    if rest == 0 {
                        current = node.children[a];
                        continue;
                    }
                    if rest & (rest - 1) == 0 {
                        let b = rest.trailing_zeros() as usize;
                        let (first, second) = if near[b] < near[a] { (b, a) } else { (a, b) };
                        let deferred = (node.children[second], near[second]);
                        if PREFETCH {
                            self.prefetch_reference(deferred.0);
                        }
                        stack.push(deferred);
                        current = node.children[first];
                        continue;
                    }
                    // Three or more: sorted straight onto the stack,
                    // nearest on top, then the nearest taken off as the
                    // next node.
                    let base = stack.len();
                    while mask != 0 {
                        let lane = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack.push_ordered(base, (node.children[lane], near[lane]));
                    }
                    if let Some((child, _)) = stack.pop() {
                        if PREFETCH {
                            for &(deferred, _) in stack.above(base) {
                                self.prefetch_reference(deferred);
                            }
                        }
                        current = child;
                        continue;
                    }
                }
            } else {
                let (block, count) = leaf(current);
                // The next child in line joins the test when it is a leaf
                // the ray still reaches.
                let (partner, partner_count) = match stack.peek() {
                    Some((next, near)) if next & LEAF_BIT != 0 && near <= tmax * EXIT_STRETCH => {
                        stack.pop();
                        leaf(next)
                    }
                    _ => (block, 0),
                };
                let (mut mask, t, b1, b2) = lanes.intersect(
                    &self.blocks[block],
                    count,
                    &self.blocks[partner],
                    partner_count,
                    tmax,
                );
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if t[lane] < tmax {
                        tmax = t[lane];
                        let owner = if lane < 4 { block } else { partner };
                        closest = Some((owner as u32, lane % 4, b1[lane], b2[lane]));
                    }
                }
            }
            // Pop the next child, skipping those a closer hit has ruled out.
            loop {
                let Some((child, near)) = stack.pop() else {
                    return closest.map(|(block, lane, b1, b2)| Hit {
                        triangle: self.blocks[block as usize].id[lane],
                        t: tmax,
                        b1,
                        b2,
                    });
                };
                if near <= tmax * EXIT_STRETCH {
                    current = child;
                    break;
                }
            }
        }
    }

    /// `occluded`, prefetching as `closest_hit` does.
    #[inline(always)]
    pub(super) fn any_hit<const PREFETCH: bool>(&self, ray: &Ray) -> bool {
        if self.root == EMPTY_CHILD {
            return false;
        }
        // No test of the root's own box first (see `intersect`).
        let lanes = RayLanes::new(ray);
        let mut storage = stack_storage();
        let mut stack = Stack::<u32>::new(&mut storage);
        let mut current = self.root;
        loop {
            if current & LEAF_BIT == 0 {
                let node = &self.nodes[current as usize];
                let (_, mut mask) = lanes.enter(node, ray.tmax);
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if PREFETCH {
                        self.prefetch_reference(node.children[lane]);
                    }
                    stack.push(node.children[lane]);
                }
            } else {
                // One block at a time: pairing leaves here as `closest_hit`
                // does costs more than it saves (callgrind, perf gate's
                // rays-shadow-any +3.4%), as a hit in the first block often
                // makes the second's test wasted work.
                let (block, count) = leaf(current);
                let block = &self.blocks[block];
                if lanes.intersect(block, count, block, 0, ray.tmax).0 != 0 {
                    return true;
                }
            }
            match stack.pop() {
                Some(next) => current = next,
                None => return false,
            }
        }
    }
}
