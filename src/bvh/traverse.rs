//! Closest-hit and any-hit traversal of the binary BVH.

use super::{Bvh, Hit, Node};
use crate::geometry::triangle::RayShear;
use crate::geometry::Ray;
use glam::Vec3;

/// The builder bounds the depth at 64 SAH levels plus a median-split tail of
/// at most 32 levels (for up to 2^32 triangles), so this never overflows.
const STACK_SIZE: usize = 128;

struct RayBoxTest {
    origin: Vec3,
    inv_dir: Vec3,
}

impl RayBoxTest {
    fn new(ray: &Ray) -> Self {
        RayBoxTest {
            origin: ray.origin,
            inv_dir: ray.dir.recip(),
        }
    }

    /// Entry distance into the node's box if the ray meets it within (tmin, tmax).
    #[inline]
    fn enter(&self, node: &Node, tmin: f32, tmax: f32) -> Option<f32> {
        let t0 = (node.bounds.min - self.origin) * self.inv_dir;
        let t1 = (node.bounds.max - self.origin) * self.inv_dir;
        // `min`/`max` ignore a NaN (0 × ∞ for a ray in a slab's plane), which
        // treats that axis as not limiting: conservative, never a missed hit.
        let near = t0.min(t1);
        let far = t0.max(t1);
        let enter = near.x.max(near.y).max(near.z).max(tmin);
        let exit = far.x.min(far.y).min(far.z).min(tmax);
        // Slab distances are rounded; widen the exit a little so a hit that
        // lies exactly on a box face is never culled (Ize, "Robust BVH Ray Traversal").
        (enter <= exit * (1.0 + 4.0 * f32::EPSILON)).then_some(enter)
    }
}

impl Bvh {
    /// The closest hit with `ray.tmin < t < ray.tmax`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let boxes = RayBoxTest::new(ray);
        let shear = RayShear::new(ray.origin, ray.dir);
        let mut closest: Option<Hit> = None;
        let mut tmax = ray.tmax;
        let mut stack = [0u32; STACK_SIZE];
        let mut top = 0;
        let mut node = self.nodes.first()?;
        boxes.enter(node, ray.tmin, tmax)?;
        loop {
            if node.is_leaf() {
                let first = node.first as usize;
                for (k, tri) in self.triangles[first..first + node.count as usize]
                    .iter()
                    .enumerate()
                {
                    if let Some(h) = shear.intersect(tri, ray.tmin, tmax) {
                        tmax = h.t;
                        closest = Some(Hit {
                            triangle: (first + k) as u32,
                            t: h.t,
                            b1: h.b1,
                            b2: h.b2,
                        });
                    }
                }
            } else {
                let (a, b) = (node.first as usize, node.first as usize + 1);
                let ta = boxes.enter(&self.nodes[a], ray.tmin, tmax);
                let tb = boxes.enter(&self.nodes[b], ray.tmin, tmax);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far) = if ta <= tb { (a, b) } else { (b, a) };
                        stack[top] = far as u32;
                        top += 1;
                        node = &self.nodes[near];
                        continue;
                    }
                    (Some(_), None) => {
                        node = &self.nodes[a];
                        continue;
                    }
                    (None, Some(_)) => {
                        node = &self.nodes[b];
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop, skipping nodes that a closer hit has since ruled out.
            loop {
                if top == 0 {
                    return closest.map(|h| Hit {
                        triangle: self.original_index[h.triangle as usize],
                        ..h
                    });
                }
                top -= 1;
                let candidate = &self.nodes[stack[top] as usize];
                if boxes.enter(candidate, ray.tmin, tmax).is_some() {
                    node = candidate;
                    break;
                }
            }
        }
    }

    /// Whether anything lies on the ray within (tmin, tmax): for shadow rays,
    /// so it stops at the first hit it finds.
    pub fn occluded(&self, ray: &Ray) -> bool {
        let boxes = RayBoxTest::new(ray);
        let shear = RayShear::new(ray.origin, ray.dir);
        let mut stack = [0u32; STACK_SIZE];
        let mut top = 0;
        let mut index = 0usize;
        if self.nodes.is_empty() {
            return false;
        }
        loop {
            let node = &self.nodes[index];
            if boxes.enter(node, ray.tmin, ray.tmax).is_some() {
                if node.is_leaf() {
                    let first = node.first as usize;
                    let leaf = &self.triangles[first..first + node.count as usize];
                    if leaf
                        .iter()
                        .any(|t| shear.intersect(t, ray.tmin, ray.tmax).is_some())
                    {
                        return true;
                    }
                } else {
                    stack[top] = node.first + 1;
                    top += 1;
                    index = node.first as usize;
                    continue;
                }
            }
            if top == 0 {
                return false;
            }
            top -= 1;
            index = stack[top] as usize;
        }
    }
}
