//! Scenes of a few dozen triangles, traced without the tree: every triangle
//! is tested, sixteen to a SIMD test (one AVX-512 register per coordinate).
//! Only builds for CPUs with AVX-512 trace flat by default: built for AVX2,
//! where each test takes two registers, it measured slower than the tree
//! for the path and light tracers.
//!
//! In the Cornell box (32 triangles: two groups) a ray through the tree
//! tests one to three nodes and two or three leaf pairs, each node costing
//! about what a group does; the two group tests cost less. Past two groups
//! the tree wins: on Cornell boxes with more boxes added, three groups
//! (42 triangles) ran even with the tree and four (52) 0.88–0.89x of it.
//! See docs/benchmarks.md ("Small scenes traced flat").
//!
//! The test is the tree's, lane for lane (the same watertight arithmetic,
//! see `watertight_test!`), so both report the same distances bit for bit,
//! and the same triangle unless two lie at exactly the same distance (a ray
//! through a shared edge), where each takes the first it tested.

use super::traverse::watertight_lanes_16;
use super::{TriangleBlock, WideBvh};
use crate::bvh::Hit;
use crate::geometry::triangle::RayShear;
use crate::geometry::Ray;
use wide::f32x16;

/// Scenes of at most this many triangles are traced flat.
pub const FLAT_MAX_TRIANGLES: usize = 32;

/// Lanes of one group.
const GROUP: usize = 16;

/// Up to sixteen triangles, one per lane: `v[vertex][axis][lane]`. Unused
/// lanes are zero, and left out by `lanes`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct TriangleGroup {
    v: [[[f32; GROUP]; 3]; 3],
    /// The caller's triangle index of each lane.
    id: [u32; GROUP],
    /// Bit k set for each lane k that holds a triangle.
    lanes: u32,
}

/// The triangles of `blocks` in groups of sixteen, in leaf order, when
/// there are at most `FLAT_MAX_TRIANGLES` of them; none otherwise.
pub(super) fn groups(blocks: &[TriangleBlock]) -> Vec<TriangleGroup> {
    // Every block holds at least one triangle, so a large scene is ruled
    // out by its block count alone, without reading its blocks (a scene
    // from the cache maps them from disk, and would page them all in).
    let used = |b: &TriangleBlock| b.id.iter().filter(|&&id| id != u32::MAX).count();
    if blocks.len() > FLAT_MAX_TRIANGLES
        || blocks.iter().map(used).sum::<usize>() > FLAT_MAX_TRIANGLES
    {
        return Vec::new();
    }
    let mut groups: Vec<TriangleGroup> = Vec::new();
    let triangles = blocks.iter().flat_map(|b| {
        (0..4)
            .filter(|&lane| b.id[lane] != u32::MAX)
            .map(move |lane| (b, lane))
    });
    for (n, (block, lane)) in triangles.enumerate() {
        if n % GROUP == 0 {
            groups.push(TriangleGroup {
                v: [[[0.0; GROUP]; 3]; 3],
                id: [u32::MAX; GROUP],
                lanes: 0,
            });
        }
        let group = groups.last_mut().expect("pushed above");
        let k = n % GROUP;
        for vertex in 0..3 {
            for axis in 0..3 {
                group.v[vertex][axis][k] = block.v[vertex][axis][lane];
            }
        }
        group.id[k] = block.id[lane];
        group.lanes |= 1 << k;
    }
    groups
}

/// The ray's watertight axes and shear, splatted across sixteen lanes.
struct GroupRay {
    k: [usize; 3],
    origin_k: [f32x16; 3],
    shear: [f32x16; 3],
    tmin: f32x16,
}

impl GroupRay {
    #[inline(always)]
    fn new(ray: &Ray) -> GroupRay {
        let o = ray.origin.to_array();
        let (k, s) = RayShear::new(ray.origin, ray.dir).parts();
        GroupRay {
            k,
            origin_k: k.map(|axis| f32x16::splat(o[axis])),
            shear: s.map(f32x16::splat),
            tmin: f32x16::splat(ray.tmin),
        }
    }

    /// A bit mask of the group's lanes hit within (tmin, `tmax`), their
    /// distances, and the barycentrics of vertices 1 and 2.
    #[inline(always)]
    fn test(
        &self,
        group: &TriangleGroup,
        tmax: f32,
    ) -> (u32, [f32; GROUP], [f32; GROUP], [f32; GROUP]) {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let [ox, oy, oz] = self.origin_k;
        let project = |vertex: usize| {
            let v = &group.v[vertex];
            let x = f32x16::new(v[kx]) - ox;
            let y = f32x16::new(v[ky]) - oy;
            let z = f32x16::new(v[kz]) - oz;
            (x - sx * z, y - sy * z, z)
        };
        let (hit, t, b1, b2) = watertight_lanes_16(
            [project(0), project(1), project(2)],
            sz,
            group.lanes,
            self.tmin,
            f32x16::splat(tmax),
        );
        (
            hit.to_bitmask() & group.lanes,
            t.to_array(),
            b1.to_array(),
            b2.to_array(),
        )
    }
}

impl WideBvh {
    /// `intersect` over the flat groups. Out of line, and marked cold so
    /// that the compiler lays `intersect` out for the tree as before:
    /// otherwise the tree's rays paid a few instructions each for the
    /// choice (perf gate's ray workloads, +1.5%).
    #[cold]
    #[inline(never)]
    pub(super) fn closest_hit_flat(&self, ray: &Ray) -> Option<Hit> {
        let setup = GroupRay::new(ray);
        let mut tmax = ray.tmax;
        let mut closest: Option<(usize, usize, f32, f32)> = None;
        for (g, group) in self.flat.iter().enumerate() {
            let (mut mask, t, b1, b2) = setup.test(group, tmax);
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if t[lane] < tmax {
                    tmax = t[lane];
                    closest = Some((g, lane, b1[lane], b2[lane]));
                }
            }
        }
        closest.map(|(g, lane, b1, b2)| Hit {
            triangle: self.flat[g].id[lane],
            t: tmax,
            b1,
            b2,
        })
    }

    /// `occluded` over the flat groups; out of line and cold as `closest_hit_flat`.
    #[cold]
    #[inline(never)]
    pub(super) fn any_hit_flat(&self, ray: &Ray) -> bool {
        let setup = GroupRay::new(ray);
        self.flat
            .iter()
            .any(|group| setup.test(group, ray.tmax).0 != 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;
    use glam::Vec3;

    /// A small random-looking soup, deterministic: a linear congruential
    /// sequence is enough to scatter triangles.
    fn soup(count: usize) -> Vec<Triangle> {
        let mut state = 12345u32;
        let mut next = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let mut point = move || Vec3::new(next(), next(), next()) * 4.0 - 2.0;
        (0..count)
            .map(|_| {
                let a = point();
                Triangle::new(a, a + (point() * 0.5), a + (point() * 0.5))
            })
            .collect()
    }

    #[test]
    fn flat_and_tree_traversals_agree_bit_for_bit() {
        for count in [1, 5, 16, 17, 32] {
            let triangles = soup(count);
            let mut bvh = WideBvh::build(&triangles);
            assert_eq!(bvh.is_flat(), cfg!(target_feature = "avx512f"));
            let mut hits = 0;
            for i in 0..4000u32 {
                let f = |k: u32| ((i.wrapping_mul(2_654_435_761) >> k) & 0xff) as f32 / 255.0;
                let origin = Vec3::new(f(0), f(8), f(16)) * 6.0 - 3.0;
                // Aimed near a triangle's centroid, so that most rays hit
                // something and some pass close to edges.
                let aim = &triangles[i as usize % count];
                let target = (aim.v[0] + aim.v[1] + aim.v[2]) / 3.0
                    + (Vec3::new(f(3), f(11), f(19)) - 0.5) * 0.3;
                let dir = (target - origin).normalize_or(Vec3::X);
                let ray = if i % 2 == 0 {
                    Ray::new(origin, dir)
                } else {
                    Ray::segment(origin, dir, (target - origin).length())
                };
                bvh.set_flat(true);
                let (flat_hit, flat_any) = (bvh.intersect(&ray), bvh.occluded(&ray));
                bvh.set_flat(false);
                let (tree_hit, tree_any) = (bvh.intersect(&ray), bvh.occluded(&ray));
                let bits = |h: Option<Hit>| {
                    h.map(|h| (h.triangle, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
                };
                assert_eq!(bits(flat_hit), bits(tree_hit), "{count} triangles, ray {i}");
                assert_eq!(flat_any, tree_any, "{count} triangles, ray {i}");
                hits += usize::from(flat_hit.is_some());
            }
            assert!(hits > 800, "{count} triangles: only {hits} hits");
        }
        let mut larger = WideBvh::build(&soup(FLAT_MAX_TRIANGLES + 1));
        larger.set_flat(true);
        assert!(!larger.is_flat(), "past the size limit the tree stays");
    }
}
