//! The pinhole camera.
//!
//! Pixel (0, 0) is the top-left of the image; the image's right is
//! `forward × up` (right-handed, as Mitsuba 3's `look_at`). Each sample picks a
//! uniformly random point inside its pixel: a box filter one pixel wide.

use crate::geometry::Ray;
use glam::Vec3;

#[derive(Clone, Debug)]
pub struct Camera {
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// tan(fov / 2): half the image plane's height at distance one.
    tan_half_fov: f32,
    width: u32,
    height: u32,
}

impl Camera {
    /// `None` when `look_at` equals `position` or `up` is parallel to the view direction.
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_degrees: f32,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        let forward = (look_at - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        Some(Camera {
            position,
            forward,
            right,
            up,
            tan_half_fov: (0.5 * fov_degrees.to_radians()).tan(),
            width,
            height,
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The ray through the image point (`x`, `y`) in pixel units, y downwards.
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov * aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov;
        Ray::new(
            self.position,
            (self.forward + sx * self.right + sy * self.up).normalize(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_right_is_forward_cross_up() {
        let c = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0, 100, 100).unwrap();
        assert!(c.ray(50.0, 50.0).dir.abs_diff_eq(Vec3::Z, 1e-6));
        assert!(c.ray(100.0, 50.0).dir.x < 0.0, "right of the image is -x");
        assert!(c.ray(50.0, 0.0).dir.y > 0.0, "top row looks up");
        // 90° vertical fov: the top edge is 45° up.
        assert!((c.ray(50.0, 0.0).dir.angle_between(Vec3::Z).to_degrees() - 45.0).abs() < 1e-3);
    }
}
