//! The perspective camera: a pinhole, or a thin lens.
//!
//! Pixel (0, 0) is the top-left of the image; the image's right is
//! `forward × up` (right-handed, as Mitsuba 3's `look_at`). Each sample picks a
//! uniformly random point inside its pixel: a box filter one pixel wide.
//!
//! A thin lens is a disk of radius `lens_radius` around `position`, facing
//! `forward`; every ray through an image point passes through the same
//! point of the plane in focus, `focus_distance` along the view axis. Seen
//! from any one lens point the image maps to directions exactly as for the
//! pinhole, so the importance and direction densities of the pinhole hold at
//! every lens point, and the lens point itself (uniform on the disk) is
//! sampled alike by camera paths and by light paths connecting to the
//! camera: its density cancels from every MIS weight.

use crate::geometry::Ray;
use glam::Vec3;

/// A pinhole camera looking at an image of `width` × `height` pixels.
#[derive(Clone, Debug)]
pub struct Camera {
    /// The pinhole, or the lens's centre, in world space.
    pub position: Vec3,
    /// Radius of the lens disk; 0 for a pinhole.
    lens_radius: f32,
    /// Distance along `forward` from the lens to the plane in focus.
    focus_distance: f32,
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
            lens_radius: 0.0,
            focus_distance: (look_at - position).length(),
            forward,
            right,
            up,
            tan_half_fov: (0.5 * fov_degrees.to_radians()).tan(),
            width,
            height,
        })
    }

    /// The same camera with a thin lens of `radius` (0: a pinhole) focused
    /// `focus_distance` along the view axis (> 0).
    pub fn with_lens(mut self, radius: f32, focus_distance: f32) -> Camera {
        self.lens_radius = radius;
        self.focus_distance = focus_distance;
        self
    }

    /// Whether all rays start at `position` (no lens to sample).
    pub fn is_pinhole(&self) -> bool {
        self.lens_radius <= 0.0
    }

    /// A point on the lens, uniform on its disk, from two uniform numbers.
    pub fn lens_point(&self, u: (f32, f32)) -> Vec3 {
        if self.is_pinhole() {
            return self.position;
        }
        let d = crate::sampling::warp::concentric_disk(u.0, u.1) * self.lens_radius;
        self.position + d.x * self.right + d.y * self.up
    }

    /// Image width, in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height, in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Unit view direction: through the image's centre.
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The image's right and up directions (unit, orthogonal to `forward`).
    pub fn right_up(&self) -> (Vec3, Vec3) {
        (self.right, self.up)
    }

    /// Distance along `forward` from the lens to the plane in focus.
    pub fn focus_distance(&self) -> f32 {
        self.focus_distance
    }

    /// Distance from the pinhole to an image plane whose pixels are one unit
    /// wide. Densities on that plane are "per pixel", which makes the box
    /// filter of the contract and light-tracing splats agree (Georgiev 2012, §5.1).
    pub fn image_plane_distance(&self) -> f32 {
        self.height as f32 / (2.0 * self.tan_half_fov)
    }

    /// Solid-angle density of the camera choosing direction `dir` when each
    /// pixel's point is uniform in the pixel: (distance to the image point)² / cos.
    pub fn direction_pdf(&self, dir: Vec3) -> f32 {
        let cos = dir.dot(self.forward);
        if cos <= 0.0 {
            return 0.0;
        }
        let d = self.image_plane_distance() / cos;
        d * d / cos
    }

    /// The image point that a ray from the lens point `lens` through `p`
    /// comes from: where the ray meets the plane in focus, projected through
    /// the lens's centre. For a pinhole, [`Camera::project`].
    pub fn project_from(&self, lens: Vec3, p: Vec3) -> Option<(f32, f32)> {
        if self.is_pinhole() {
            return self.project(p);
        }
        let d = p - lens;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        self.project(lens + d * (self.focus_distance / z))
    }

    /// The image point (pixels, y downwards) that `p` projects to, if it is in
    /// front of the camera and inside the image.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let scale = self.image_plane_distance() / z;
        let x = 0.5 * self.width as f32 + d.dot(self.right) * scale;
        let y = 0.5 * self.height as f32 - d.dot(self.up) * scale;
        let inside =
            (0.0..self.width as f32).contains(&x) && (0.0..self.height as f32).contains(&y);
        inside.then_some((x, y))
    }

    /// The ray through the image point (`x`, `y`) in pixel units, y
    /// downwards, from the pinhole.
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        Ray::new(self.position, self.pinhole_direction(x, y))
    }

    /// The ray through the image point (`x`, `y`) from the lens point
    /// `lens` (see [`Camera::lens_point`]): towards where the pinhole ray
    /// meets the plane in focus.
    pub fn ray_from(&self, lens: Vec3, x: f32, y: f32) -> Ray {
        let dir = self.pinhole_direction(x, y);
        if self.is_pinhole() {
            return Ray::new(self.position, dir);
        }
        let focus = self.position + dir * (self.focus_distance / dir.dot(self.forward));
        Ray::new(lens, (focus - lens).normalize())
    }

    fn pinhole_direction(&self, x: f32, y: f32) -> Vec3 {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov * aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov;
        (self.forward + sx * self.right + sy * self.up).normalize()
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

    #[test]
    fn projection_inverts_camera_rays() {
        let c = Camera::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, 1.5, 7.0),
            Vec3::Y,
            50.0,
            64,
            48,
        )
        .unwrap();
        for (x, y) in [(0.5, 0.5), (63.2, 10.0), (32.0, 24.0), (5.0, 47.9)] {
            let ray = c.ray(x, y);
            let (px, py) = c.project(ray.at(3.7)).unwrap();
            assert!(
                (px - x).abs() < 1e-3 && (py - y).abs() < 1e-3,
                "({x}, {y}) -> ({px}, {py})"
            );
        }
        assert!(
            c.project(c.position - c.forward()).is_none(),
            "behind the camera"
        );
    }

    /// The direction pdf integrates to the image's pixel count over the
    /// frustum: one unit of density per pixel.
    #[test]
    fn thin_lens_focuses_on_its_plane() {
        let pinhole = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 50.0, 64, 48).unwrap();
        let lens = pinhole.clone().with_lens(0.5, 4.0);
        assert!(pinhole.is_pinhole() && !lens.is_pinhole());
        let (x, y) = (20.25, 30.5);
        let focus_point = {
            let r = pinhole.ray(x, y);
            r.origin + r.dir * (4.0 / r.dir.z)
        };
        for u in [(0.1, 0.2), (0.9, 0.5), (0.5, 0.5), (0.3, 0.95)] {
            let p = lens.lens_point(u);
            assert!(p.z.abs() < 1e-6 && p.length() <= 0.5 + 1e-6);
            // Every lens ray through an image point meets the same point in focus...
            let r = lens.ray_from(p, x, y);
            let hit = r.origin + r.dir * ((4.0 - r.origin.z) / r.dir.z);
            assert!(hit.abs_diff_eq(focus_point, 1e-4), "{hit} vs {focus_point}");
            // ...and projecting back from that lens point finds the image point.
            let (px, py) = lens.project_from(p, focus_point + r.dir * 3.0).unwrap();
            assert!(
                (px - x).abs() < 1e-3 && (py - y).abs() < 1e-3,
                "({px}, {py})"
            );
        }
    }

    #[test]
    fn direction_pdf_counts_pixels() {
        let c = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0, 40, 30).unwrap();
        let n = 400;
        let mut integral = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (
                    40.0 * (i as f32 + 0.5) / n as f32,
                    30.0 * (j as f32 + 0.5) / n as f32,
                );
                let dir = c.ray(x, y).dir;
                // Solid angle of this little image cell: area × cos / dist² on the image plane.
                let cos = dir.dot(c.forward());
                let dist = c.image_plane_distance() / cos;
                let cell = (40.0 / n as f32) * (30.0 / n as f32) * cos / (dist * dist);
                integral += (c.direction_pdf(dir) * cell) as f64;
            }
        }
        assert!((integral - 1200.0).abs() < 1.0, "{integral}");
    }
}
