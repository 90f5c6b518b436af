//! Affine transforms of points and normals.

use glam::{Mat3, Mat4, Vec3};

/// An invertible affine transform from object space to world space.
#[derive(Clone, Copy, Debug)]
pub struct Transform {
    /// The object-to-world matrix, applied to column vectors.
    pub matrix: Mat4,
    /// Inverse transpose of the upper 3x3, which carries normals.
    normal_matrix: Mat3,
}

impl Transform {
    /// The transform that leaves everything where it is.
    pub const IDENTITY: Transform = Transform {
        matrix: Mat4::IDENTITY,
        normal_matrix: Mat3::IDENTITY,
    };

    /// `None` when the matrix is singular (it would flatten the object).
    pub fn new(matrix: Mat4) -> Option<Transform> {
        let m3 = Mat3::from_mat4(matrix);
        let det = m3.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return None;
        }
        Some(Transform {
            matrix,
            normal_matrix: m3.inverse().transpose(),
        })
    }

    /// Scale, then rotate (about `axis` by `degrees`), then translate.
    pub fn from_srt(
        scale: Vec3,
        rotation: Option<(Vec3, f32)>,
        translate: Vec3,
    ) -> Option<Transform> {
        let r = match rotation {
            Some((axis, deg)) => Mat4::from_axis_angle(axis.normalize(), deg.to_radians()),
            None => Mat4::IDENTITY,
        };
        Transform::new(Mat4::from_translation(translate) * r * Mat4::from_scale(scale))
    }

    /// `p` transformed as a point (translation applies).
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.matrix.transform_point3(p)
    }

    /// `n` transformed as a normal (by the inverse transpose) and normalised;
    /// zero for a zero `n`.
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal_matrix * n).normalize_or_zero()
    }
}
