//! Packets: up to eight rays traced together through the 8-wide BVH, one
//! ray per SIMD lane (Wald, Slusallek, Benthin and Wagner, "Interactive
//! Rendering with Coherent Ray Tracing", 2001). Each node is fetched once
//! for the packet and each child box tested against all eight rays in one
//! 8-wide step; each triangle of a leaf is tested against all eight rays in
//! one 8-wide watertight test, which computes for every lane exactly what
//! the single-ray test computes for that ray, so a ray's hit distance is
//! the same bit for bit either way.
//!
//! The packet visits the union of the nodes its rays would visit alone,
//! so it pays where the rays share most of their nodes: coherent rays
//! (camera rays through neighbouring pixels). Rays that go their own ways
//! lose, even in the Cornell box's three-node tree, where eight of them
//! visit nearly every leaf (docs/benchmarks.md, "Ray packets").

use super::traverse::{leaf, safe_inverse, stack_storage, watertight_lanes, Stack, EXIT_STRETCH};
use super::{TriangleBlock, WideBvh, EMPTY_CHILD, LEAF_BIT, WIDTH};
use crate::bvh::Hit;
use crate::geometry::triangle::RayShear;
use crate::geometry::{Aabb, Ray};
use wide::{f32x8, u32x8};

/// The most rays [`WideBvh::intersect_packet`] traces together: one per
/// 8-wide SIMD lane.
pub const PACKET_SIZE: usize = 8;

/// The packet's rays across SIMD lanes. Lanes past the packet's length
/// repeat its last ray, and their answers are dropped.
struct PacketLanes {
    origin: [f32x8; 3],
    inv_dir: [f32x8; 3],
    tmin: f32x8,
    tmax: f32x8,
    /// The watertight test's axes of each lane's ray: `axis_is_x[k]` holds
    /// the lanes whose k-th axis (`kx`, `ky`, `kz`) is x, `axis_is_y[k]`
    /// those whose is y; the rest are z.
    axis_is_x: [f32x8; 3],
    axis_is_y: [f32x8; 3],
    /// The shear constants `sx`, `sy`, `sz` of each lane's ray.
    shear: [f32x8; 3],
}

impl PacketLanes {
    fn new(rays: &[Ray]) -> PacketLanes {
        let mut origin = [[0.0f32; PACKET_SIZE]; 3];
        let mut inv_dir = [[0.0f32; PACKET_SIZE]; 3];
        let mut axis = [[0.0f32; PACKET_SIZE]; 3];
        let mut shear = [[0.0f32; PACKET_SIZE]; 3];
        let (mut tmin, mut tmax) = ([0.0f32; PACKET_SIZE], [0.0f32; PACKET_SIZE]);
        for k in 0..PACKET_SIZE {
            let ray = &rays[k.min(rays.len() - 1)];
            let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
            let (axes, s) = RayShear::new(ray.origin, ray.dir).parts();
            for a in 0..3 {
                origin[a][k] = o[a];
                inv_dir[a][k] = safe_inverse(d[a]);
                axis[a][k] = axes[a] as f32;
                shear[a][k] = s[a];
            }
            (tmin[k], tmax[k]) = (ray.tmin, ray.tmax);
        }
        let axis = axis.map(f32x8::new);
        PacketLanes {
            origin: origin.map(f32x8::new),
            inv_dir: inv_dir.map(f32x8::new),
            tmin: f32x8::new(tmin),
            tmax: f32x8::new(tmax),
            axis_is_x: axis.map(|a| a.simd_eq(f32x8::ZERO)),
            axis_is_y: axis.map(|a| a.simd_eq(f32x8::ONE)),
            shear: shear.map(f32x8::new),
        }
    }

    /// Which rays enter box `lane` of `bounds` before their own `tmax`, and
    /// the nearest entry distance among them.
    #[inline(always)]
    fn enter(&self, bounds: &[[f32; WIDTH]; 6], lane: usize, tmax: f32x8) -> (u32, f32) {
        let lo = [0, 1, 2].map(|a| bounds[a][lane]);
        let hi = [0, 1, 2].map(|a| bounds[a + 3][lane]);
        let (hit, near) = self.enter_box(lo, hi, tmax);
        let mask = hit.to_bitmask();
        let nearest = hit
            .select(near, f32x8::splat(f32::INFINITY))
            .to_array()
            .into_iter()
            .fold(f32::INFINITY, f32::min);
        (mask, nearest)
    }

    /// The slab test of one box against every lane: which lanes enter it
    /// within (tmin, `tmax`), and where.
    #[inline(always)]
    fn enter_box(&self, lo: [f32; 3], hi: [f32; 3], tmax: f32x8) -> (f32x8, f32x8) {
        let mut near = self.tmin;
        let mut far = tmax;
        for axis in 0..3 {
            let t0 = (f32x8::splat(lo[axis]) - self.origin[axis]) * self.inv_dir[axis];
            let t1 = (f32x8::splat(hi[axis]) - self.origin[axis]) * self.inv_dir[axis];
            near = near.fast_max(t0.fast_min(t1));
            far = far.fast_min(t0.fast_max(t1));
        }
        (near.simd_le(far * f32x8::splat(EXIT_STRETCH)), near)
    }

    /// The lanes that meet the root's own box.
    fn enter_root(&self, bounds: &Aabb) -> u32 {
        let (hit, _) = self.enter_box(bounds.min.to_array(), bounds.max.to_array(), self.tmax);
        hit.to_bitmask()
    }

    /// `p[kx]`, `p[ky]`, `p[kz]` of each lane's ray.
    #[inline(always)]
    fn permute(&self, p: [f32x8; 3]) -> [f32x8; 3] {
        [0, 1, 2].map(|k| self.axis_is_x[k].select(p[0], self.axis_is_y[k].select(p[1], p[2])))
    }

    /// The watertight test of triangle `j` of `block` against every lane's
    /// ray, the arithmetic of `RayLanes::intersect` lane for lane: which
    /// lanes hit it within (tmin, `tmax`), their distances, and the
    /// barycentrics of vertices 1 and 2.
    #[inline(always)]
    fn intersect(
        &self,
        block: &TriangleBlock,
        j: usize,
        tmax: f32x8,
    ) -> (f32x8, f32x8, f32x8, f32x8) {
        let [sx, sy, sz] = self.shear;
        // Vertex positions relative to each ray's origin, sheared so that
        // ray runs along +z.
        let project = |v: usize| {
            let relative = [0, 1, 2].map(|a| f32x8::splat(block.v[v][a][j]) - self.origin[a]);
            let [x, y, z] = self.permute(relative);
            (x - sx * z, y - sy * z, z)
        };
        watertight_lanes(
            [project(0), project(1), project(2)],
            sz,
            0xff,
            self.tmin,
            tmax,
        )
    }
}

impl WideBvh {
    /// The closest hit of each of up to eight rays: for each ray the
    /// distance `intersect` finds for it alone, bit for bit, and the same
    /// triangle unless two lie at exactly that distance.
    pub fn intersect_packet(&self, rays: &[Ray]) -> [Option<Hit>; PACKET_SIZE] {
        assert!(
            rays.len() <= PACKET_SIZE,
            "at most {PACKET_SIZE} rays per packet"
        );
        let mut hits = [None; PACKET_SIZE];
        if self.root == EMPTY_CHILD || rays.is_empty() {
            return hits;
        }
        let lanes = PacketLanes::new(rays);
        let real = (1u32 << rays.len()) - 1;
        let active = lanes.enter_root(&self.bounds) & real;
        let mut tmax = lanes.tmax;
        let mut triangle = u32x8::splat(u32::MAX);
        let (mut b1, mut b2) = (f32x8::ZERO, f32x8::ZERO);
        let mut storage = stack_storage();
        let mut stack = Stack::<(u32, u32, f32)>::new(&mut storage);
        let mut current = (self.root, active);
        while current.1 != 0 {
            let (reference, mask) = current;
            if reference & LEAF_BIT == 0 {
                let node = &self.nodes[reference as usize];
                let mut entered = [(0u32, 0u32, 0f32); WIDTH];
                let mut count = 0;
                for lane in 0..WIDTH {
                    if node.children[lane] == EMPTY_CHILD {
                        continue;
                    }
                    let (m, near) = lanes.enter(&node.bounds, lane, tmax);
                    let m = m & mask;
                    if m != 0 {
                        // Nearest first, by the packet's nearest entry.
                        let mut k = count;
                        while k > 0 && entered[k - 1].2 > near {
                            entered[k] = entered[k - 1];
                            k -= 1;
                        }
                        entered[k] = (node.children[lane], m, near);
                        count += 1;
                    }
                }
                if count > 0 {
                    for &entry in entered[1..count].iter().rev() {
                        stack.push(entry);
                    }
                    current = (entered[0].0, entered[0].1);
                    continue;
                }
            } else {
                // Every lane is tested, not only those that entered the
                // leaf's box: a hit is a hit, wherever the ray's traversal
                // stands, and masking would cost more than it saves.
                let (block, count) = leaf(reference);
                let block = &self.blocks[block];
                for j in 0..count as usize {
                    let (hit, t, v, w) = lanes.intersect(block, j, tmax);
                    if hit.to_bitmask() & real == 0 {
                        continue;
                    }
                    tmax = hit.select(t, tmax);
                    b1 = hit.select(v, b1);
                    b2 = hit.select(w, b2);
                    triangle = hit.select(u32x8::splat(block.id[j]), triangle);
                }
            }
            current = (0, 0);
            // Pop the next entry, skipping it when every ray it holds has
            // since found a hit nearer than the packet's entry distance.
            while let Some((reference, mask, near)) = stack.pop() {
                let reach = f32x8::splat(near).simd_le(tmax * f32x8::splat(EXIT_STRETCH));
                if reach.to_bitmask() & mask != 0 {
                    current = (reference, mask);
                    break;
                }
            }
        }
        let (t, b1, b2, triangle) = (
            tmax.to_array(),
            b1.to_array(),
            b2.to_array(),
            triangle.to_array(),
        );
        for k in 0..rays.len() {
            if triangle[k] != u32::MAX {
                hits[k] = Some(Hit {
                    triangle: triangle[k],
                    t: t[k],
                    b1: b1[k],
                    b2: b2[k],
                });
            }
        }
        hits
    }

    /// Which of up to eight rays are blocked within (tmin, tmax), as
    /// `occluded` answers for each ray alone: bit k for ray k.
    pub fn occluded_packet(&self, rays: &[Ray]) -> u32 {
        assert!(
            rays.len() <= PACKET_SIZE,
            "at most {PACKET_SIZE} rays per packet"
        );
        if self.root == EMPTY_CHILD || rays.is_empty() {
            return 0;
        }
        let lanes = PacketLanes::new(rays);
        let real = (1u32 << rays.len()) - 1;
        let mut open = lanes.enter_root(&self.bounds) & real;
        let mut blocked = 0u32;
        let mut storage = stack_storage();
        let mut stack = Stack::<(u32, u32)>::new(&mut storage);
        let mut current = (self.root, open);
        loop {
            let (reference, mask) = current;
            if reference & LEAF_BIT == 0 {
                let node = &self.nodes[reference as usize];
                for lane in 0..WIDTH {
                    if node.children[lane] == EMPTY_CHILD {
                        continue;
                    }
                    let lo = [0, 1, 2].map(|a| node.bounds[a][lane]);
                    let hi = [0, 1, 2].map(|a| node.bounds[a + 3][lane]);
                    let m = lanes.enter_box(lo, hi, lanes.tmax).0.to_bitmask() & mask;
                    if m != 0 {
                        stack.push((node.children[lane], m));
                    }
                }
            } else {
                let (block, count) = leaf(reference);
                let block = &self.blocks[block];
                for j in 0..count as usize {
                    blocked |= lanes.intersect(block, j, lanes.tmax).0.to_bitmask() & real;
                }
                open &= !blocked;
                if open == 0 {
                    return blocked;
                }
            }
            // The next entry with a ray still open.
            loop {
                let Some((reference, mask)) = stack.pop() else {
                    return blocked;
                };
                if mask & open != 0 {
                    current = (reference, mask & open);
                    break;
                }
            }
        }
    }
}
