//! Rays, and the origin offset that keeps a ray from re-hitting the surface it
//! leaves.

use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    /// Hits count only for `tmin < t < tmax`.
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Ray {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// A segment that stops short of `tmax`, for shadow rays.
    pub fn segment(origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax,
        }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// Moves a surface point off its surface, to the side `toward` lies on, by a
/// few units in the last place of its coordinates.
///
/// This is the method of Wächter and Binder, "A Fast and Robust Method for
/// Avoiding Self-Intersection" (Ray Tracing Gems, ch. 6): the offset scales with
/// the magnitude of the coordinates, so it works at any scene scale without a
/// global epsilon on `t`, and it moves along the geometric normal, so a ray that
/// leaves at a grazing angle still clears the surface.
pub fn offset_origin(p: Vec3, geometric_normal: Vec3, toward: Vec3) -> Vec3 {
    // Below this magnitude integer ULP steps get too small, so add a fixed amount.
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;

    let n = if geometric_normal.dot(toward) < 0.0 {
        -geometric_normal
    } else {
        geometric_normal
    };
    let step = |p: f32, n: f32| -> f32 {
        if p.abs() < ORIGIN {
            return p + FLOAT_SCALE * n;
        }
        let ulps = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = if p < 0.0 { bits - ulps } else { bits + ulps };
        f32::from_bits(moved as u32)
    };
    Vec3::new(step(p.x, n.x), step(p.y, n.y), step(p.z, n.z))
}
