//! Rays of sixteen independent paths handed over together, one per lane:
//! the path tracer steps sixteen paths at a time (see
//! `integrator/lanes.rs`). The rays are traced one after another, each
//! getting exactly the hit it would get alone; what the path tracer gains
//! is that the processor can overlap sixteen independent traversals,
//! where one path alone waits on each hit before it can shade. BDPT's
//! connections hand over their shadow rays as a run of any length
//! (`shadow_run`). Each call chooses the traversal once and inlines its
//! loop, which spares every ray a function call.
//!
//! Testing each triangle of a flat scene (see `flat.rs`) against all
//! sixteen rays in one AVX-512 step, with the same arithmetic lane for
//! lane, was slower: the Cornell box's `pt` took 1.37 s against 1.30 s
//! one ray at a time (docs/benchmarks.md, "Paths in lanes"). Each ray
//! has its own projection axes, so every triangle costs eighteen blends
//! more than the single-ray test, which already fills sixteen lanes with
//! sixteen triangles.

use super::{Traversal, WideBvh};
use crate::bvh::Hit;
use crate::geometry::Ray;

/// Rays per call.
pub const LANES: usize = 16;

impl WideBvh {
    /// The closest hit of each ray of `rays` whose bit is set in `active`
    /// (bit k for `rays[k]`), into the same lane of `hits`; the other
    /// lanes of `hits` are left as they are.
    pub fn intersect_lanes(
        &self,
        rays: &[Ray; LANES],
        active: u32,
        hits: &mut [Option<Hit>; LANES],
    ) {
        // The traversal is chosen once for all sixteen rays, and its loop
        // is inlined here: called per ray, `intersect` spent about 25 of
        // its 520 instructions on the call and the choice (perf gate's
        // render-cornell-pt: 3.1% fewer instructions inlined).
        match self.traversal {
            Traversal::Tree => for_lanes(active, |lane| {
                hits[lane] = self.closest_hit::<false>(&rays[lane])
            }),
            Traversal::Prefetching => for_lanes(active, |lane| {
                hits[lane] = self.closest_hit::<true>(&rays[lane])
            }),
            Traversal::Flat => for_lanes(active, |lane| {
                hits[lane] = self.closest_hit_flat(&rays[lane])
            }),
        }
    }

    /// A bit mask of the rays of `rays` named in `active` that are blocked.
    pub fn occluded_lanes(&self, rays: &[Ray; LANES], active: u32) -> u32 {
        match self.traversal {
            Traversal::Tree => blocked_lanes(rays, active, |ray| self.any_hit::<false>(ray)),
            Traversal::Prefetching => blocked_lanes(rays, active, |ray| self.any_hit::<true>(ray)),
            Traversal::Flat => blocked_lanes(rays, active, |ray| self.any_hit_flat(ray)),
        }
    }

    /// For each of `items` in turn, `done(item, free)`: `free` is whether
    /// nothing blocks the shadow ray `ray(item)` (`None`: nothing can
    /// block it). The traversal is chosen once for the run and its loop
    /// inlined, as in `intersect_lanes`.
    pub fn shadow_run<T>(
        &self,
        items: &[T],
        ray: impl Fn(&T) -> Option<Ray>,
        done: impl FnMut(&T, bool),
    ) {
        match self.traversal {
            Traversal::Tree => free_each(items, ray, done, |ray| self.any_hit::<false>(ray)),
            Traversal::Prefetching => free_each(items, ray, done, |ray| self.any_hit::<true>(ray)),
            Traversal::Flat => free_each(items, ray, done, |ray| self.any_hit_flat(ray)),
        }
    }
}

/// `WideBvh::shadow_run` with the traversal `occluded`.
#[inline(always)]
fn free_each<T>(
    items: &[T],
    ray: impl Fn(&T) -> Option<Ray>,
    mut done: impl FnMut(&T, bool),
    occluded: impl Fn(&Ray) -> bool,
) {
    for item in items {
        let free = ray(item).is_none_or(|ray| !occluded(&ray));
        done(item, free);
    }
}

/// The bits of the lanes of `active` whose rays `occluded` finds blocked.
#[inline(always)]
fn blocked_lanes(rays: &[Ray; LANES], active: u32, occluded: impl Fn(&Ray) -> bool) -> u32 {
    let mut blocked = 0;
    for_lanes(active, |lane| {
        if occluded(&rays[lane]) {
            blocked |= 1 << lane;
        }
    });
    blocked
}

/// Calls `f` with each lane whose bit is set in `mask`, lowest first.
#[inline(always)]
pub fn for_lanes(mut mask: u32, mut f: impl FnMut(usize)) {
    debug_assert!(mask >> LANES == 0, "a lane past the last");
    while mask != 0 {
        // Masked, so the compiler knows each lane indexes a lane array
        // in bounds and drops the checks.
        f(mask.trailing_zeros() as usize & (LANES - 1));
        mask &= mask - 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;
    use glam::Vec3;

    /// A deterministic scatter of `count` triangles and of rays aimed
    /// near them, some bounded, some not.
    fn soup_and_rays(count: usize, rays: usize) -> (Vec<Triangle>, Vec<Ray>) {
        let mut state = 987_654_321u32;
        let mut next = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let mut point = move || Vec3::new(next(), next(), next()) * 4.0 - 2.0;
        let triangles: Vec<Triangle> = (0..count)
            .map(|_| {
                let a = point();
                Triangle::new(a, a + point() * 0.4, a + point() * 0.4)
            })
            .collect();
        let rays = (0..rays)
            .map(|i| {
                let origin = point() * 2.0;
                // Near a triangle's centroid: most rays hit something.
                let aim = &triangles[i * 7 % count];
                let target = (aim.v[0] + aim.v[1] + aim.v[2]) / 3.0 + point() * 0.05;
                let dir = (target - origin).normalize_or(Vec3::X);
                if i % 3 == 0 {
                    Ray::segment(origin, dir, (target - origin).length())
                } else {
                    Ray::new(origin, dir)
                }
            })
            .collect();
        (triangles, rays)
    }

    fn bits(hit: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
        hit.map(|h| (h.triangle, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
    }

    #[test]
    fn lanes_and_runs_find_what_single_rays_find() {
        for count in [12, 300] {
            let (triangles, rays) = soup_and_rays(count, 16 * 20);
            let bvh = WideBvh::build(&triangles);
            let (mut hits_seen, mut blocked_seen) = (0, 0);
            for (batch, rays) in rays.chunks_exact(LANES).enumerate() {
                let rays: [Ray; LANES] = rays.try_into().unwrap();
                // Every lane, then about half of them.
                for active in [
                    u32::MAX >> 16,
                    0x9e37_79b9u32.rotate_left(batch as u32) & 0xffff,
                ] {
                    let mut hits = [None; LANES];
                    bvh.intersect_lanes(&rays, active, &mut hits);
                    let blocked = bvh.occluded_lanes(&rays, active);
                    for (lane, ray) in rays.iter().enumerate() {
                        if active & (1 << lane) == 0 {
                            assert!(hits[lane].is_none(), "an inactive lane is left as it was");
                            assert_eq!(blocked & (1 << lane), 0);
                            continue;
                        }
                        assert_eq!(bits(hits[lane]), bits(bvh.intersect(ray)), "ray {lane}");
                        assert_eq!(blocked & (1 << lane) != 0, bvh.occluded(ray), "ray {lane}");
                        hits_seen += usize::from(hits[lane].is_some());
                        blocked_seen += usize::from(blocked & (1 << lane) != 0);
                    }
                }
                // A run of any length, with rays that nothing can block.
                let items: Vec<(usize, Option<Ray>)> = rays
                    .iter()
                    .enumerate()
                    .map(|(i, ray)| (i, (i % 5 != 4).then_some(*ray)))
                    .collect();
                let mut seen = Vec::new();
                bvh.shadow_run(
                    &items,
                    |&(_, ray)| ray,
                    |&(i, ray), free| {
                        assert_eq!(free, ray.is_none_or(|ray| !bvh.occluded(&ray)), "item {i}");
                        seen.push(i);
                    },
                );
                assert_eq!(seen, (0..LANES).collect::<Vec<_>>(), "every item, in order");
            }
            assert!(
                hits_seen > 200 && blocked_seen > 200,
                "{count}: {hits_seen} hits, {blocked_seen} blocked"
            );
        }
    }
}
