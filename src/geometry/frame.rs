//! An orthonormal shading frame around a normal.

use glam::Vec3;

/// An orthonormal, right-handed basis: `s × t = n`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent: the local +x axis, in world space.
    pub s: Vec3,
    /// Second tangent: the local +y axis, in world space.
    pub t: Vec3,
    /// The normal the frame is built around: the local +z axis, in world space.
    pub n: Vec3,
}

impl Frame {
    /// A frame with `n` as its +z axis, by the branchless construction of Duff
    /// et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017).
    pub fn new(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            s: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// World-space `v` in local coordinates (z along `n`, so z is the cosine
    /// to the normal for a unit vector).
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local-space `v` back in world coordinates.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.s + v.y * self.t + v.z * self.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthonormal_for_any_normal() {
        for n in [
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
        ] {
            let f = Frame::new(n);
            assert!((f.s.dot(f.t)).abs() < 1e-6 && (f.s.dot(f.n)).abs() < 1e-6);
            assert!(f.s.cross(f.t).abs_diff_eq(n, 1e-5));
            let v = Vec3::new(0.1, 0.2, 0.3);
            assert!(f.to_world(f.to_local(v)).abs_diff_eq(v, 1e-6));
        }
    }
}
