//! Packets: up to eight coherent rays (camera rays through neighbouring
//! pixels) traced together through the 8-wide BVH (Wald, Slusallek, Benthin
//! and Wagner, "Interactive Rendering with Coherent Ray Tracing", 2001). Each
//! node is fetched once for the packet, and each child box is tested against
//! all eight rays in one 8-wide SIMD step; leaves are tested ray by ray with
//! the single-ray triangle test, so every ray gets exactly the hit it would
//! get alone. `tracer bench` measures this against single-ray traversal.

use super::traverse::{leaf, safe_inverse, RayLanes, Stack, EXIT_STRETCH};
use super::{WideBvh, EMPTY_CHILD, LEAF_BIT, WIDTH};
use crate::bvh::Hit;
use crate::geometry::Ray;
use wide::f32x8;

/// The most rays [`WideBvh::intersect_packet`] traces together: one per
/// 8-wide SIMD lane.
pub const PACKET_SIZE: usize = 8;

/// The packet's rays across SIMD lanes. Lanes past the packet's length are
/// never active.
struct PacketLanes {
    origin: [f32x8; 3],
    inv_dir: [f32x8; 3],
    tmin: f32x8,
}

impl PacketLanes {
    fn new(rays: &[Ray]) -> PacketLanes {
        let lane = |f: &dyn Fn(&Ray) -> f32| {
            let mut v = [0.0f32; PACKET_SIZE];
            for (k, r) in rays.iter().enumerate() {
                v[k] = f(r);
            }
            f32x8::new(v)
        };
        PacketLanes {
            origin: [
                lane(&|r| r.origin.x),
                lane(&|r| r.origin.y),
                lane(&|r| r.origin.z),
            ],
            inv_dir: [
                lane(&|r| safe_inverse(r.dir.x)),
                lane(&|r| safe_inverse(r.dir.y)),
                lane(&|r| safe_inverse(r.dir.z)),
            ],
            tmin: lane(&|r| r.tmin),
        }
    }

    /// Which rays enter box `lane` of `bounds` before their own `tmax`, and
    /// the nearest entry distance among them.
    #[inline(always)]
    fn enter(&self, bounds: &[[f32; WIDTH]; 6], lane: usize, tmax: f32x8) -> (u32, f32) {
        let mut near = self.tmin;
        let mut far = tmax;
        for axis in 0..3 {
            let lo = f32x8::splat(bounds[axis][lane]);
            let hi = f32x8::splat(bounds[axis + 3][lane]);
            let t0 = (lo - self.origin[axis]) * self.inv_dir[axis];
            let t1 = (hi - self.origin[axis]) * self.inv_dir[axis];
            near = near.fast_max(t0.fast_min(t1));
            far = far.fast_min(t0.fast_max(t1));
        }
        let hit = near.simd_le(far * f32x8::splat(EXIT_STRETCH));
        let mask = hit.to_bitmask();
        let nearest = hit
            .select(near, f32x8::splat(f32::INFINITY))
            .to_array()
            .into_iter()
            .fold(f32::INFINITY, f32::min);
        (mask, nearest)
    }
}

impl WideBvh {
    /// The closest hit of each of up to eight rays, as `intersect` would
    /// find it for each ray alone. Fastest when the rays are coherent.
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
        // Lanes past the packet repeat its last ray; they are never active.
        let singles: [RayLanes; PACKET_SIZE] =
            std::array::from_fn(|k| RayLanes::new(&rays[k.min(rays.len() - 1)]));
        let mut tmax = [f32::NEG_INFINITY; PACKET_SIZE];
        let mut active = 0u32;
        for (k, r) in rays.iter().enumerate() {
            if singles[k].enters(&self.bounds, r.tmax) {
                tmax[k] = r.tmax;
                active |= 1 << k;
            }
        }
        let mut stack = Stack::<(u32, u32, f32)>::new();
        let mut current = (self.root, active);
        loop {
            let (reference, mask) = current;
            if reference & LEAF_BIT == 0 {
                let node = &self.nodes[reference as usize];
                let tmax_lanes = f32x8::new(tmax);
                let mut entered = [(0u32, 0u32, 0f32); WIDTH];
                let mut count = 0;
                for lane in 0..WIDTH {
                    if node.children[lane] == EMPTY_CHILD {
                        continue;
                    }
                    let (m, near) = lanes.enter(&node.bounds, lane, tmax_lanes);
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
                let (block, count) = leaf(reference);
                let mut m = mask;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let (mut lanes_hit, t, b1, b2) =
                        singles[k].intersect(&self.blocks[block], count, tmax[k]);
                    while lanes_hit != 0 {
                        let lane = lanes_hit.trailing_zeros() as usize;
                        lanes_hit &= lanes_hit - 1;
                        if t[lane] < tmax[k] {
                            tmax[k] = t[lane];
                            hits[k] = Some(Hit {
                                triangle: self.blocks[block].id[lane],
                                t: t[lane],
                                b1: b1[lane],
                                b2: b2[lane],
                            });
                        }
                    }
                }
            }
            // Pop the next entry, skipping it when every ray it holds has
            // since found a hit nearer than the packet's entry distance.
            loop {
                let Some((reference, mask, near)) = stack.pop() else {
                    return hits;
                };
                let mut m = mask;
                let mut farthest = f32::NEG_INFINITY;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    farthest = farthest.max(tmax[k]);
                }
                if near <= farthest * EXIT_STRETCH {
                    current = (reference, mask);
                    break;
                }
            }
        }
    }
}
