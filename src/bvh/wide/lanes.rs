//! Rays of sixteen independent paths handed over together, one per lane:
//! the path tracer steps sixteen paths at a time (see
//! `integrator/lanes.rs`). The rays are traced one after another, each
//! getting exactly the hit it would get alone; what the path tracer gains
//! is that the processor can overlap sixteen independent traversals,
//! where one path alone waits on each hit before it can shade.
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
}

impl WideBvh {
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
    while mask != 0 {
        f(mask.trailing_zeros() as usize);
        mask &= mask - 1;
    }
}
