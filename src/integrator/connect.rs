//! Connections between path vertices: shadow rays between two points, and
//! a light-side point joined to the camera (the t = 1 strategy), with the
//! camera's importance and density for it.

use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::ray::offset_origin;
use crate::geometry::{Ray, SurfacePoint};
use crate::light::IncidentSample;
use crate::sampling::Sampler;
use crate::scene::Scene;
use glam::Vec3;

/// A point a shadow ray can start or end at: a point on a surface, with
/// its geometric normal and its triangle's coordinate magnitude, which set
/// how far it is moved off the surface; or a point on no surface, such as
/// the camera's, which stays where it is.
///
/// Which of the two an end is, is known where the end is made, and the
/// shadow ray's code is inlined there, so the choice costs no branch. (It
/// used to be a zero normal, tested at run time: the test compared the
/// normal's coordinates one by one, and for a box room's axis-aligned
/// walls the coordinate that ended it changed from wall to wall, a branch
/// that mispredicted about four times per BDPT sample in callgrind's
/// model.)
#[derive(Clone, Copy, Debug)]
pub enum Endpoint {
    Surface {
        position: Vec3,
        normal: Vec3,
        magnitude: f32,
    },
    Point(Vec3),
}

impl Endpoint {
    #[inline(always)]
    pub fn surface(s: &SurfacePoint) -> Endpoint {
        Endpoint::Surface {
            position: s.position,
            normal: s.geometric_normal,
            magnitude: s.magnitude,
        }
    }

    #[inline(always)]
    pub fn point(position: Vec3) -> Endpoint {
        Endpoint::Point(position)
    }

    #[inline(always)]
    fn position(&self) -> Vec3 {
        match *self {
            Endpoint::Surface { position, .. } | Endpoint::Point(position) => position,
        }
    }

    /// The position moved off its surface towards `toward`.
    #[inline(always)]
    fn lifted(&self, toward: Vec3) -> Vec3 {
        match *self {
            Endpoint::Surface {
                position,
                normal,
                magnitude,
            } => offset_origin(position, normal, toward, magnitude),
            Endpoint::Point(position) => position,
        }
    }
}

/// Whether the segment between two points is free, each end moved off its surface.
/// Always inlined: the light tracer and BDPT call it in their hot loops, and
/// the compiler stopped inlining it there once the path tracer's lanes
/// came in (perf gate: light tracer +1.7% instructions).
#[inline(always)]
pub fn visible(scene: &Scene, from: Endpoint, to: Endpoint) -> bool {
    segment_ray(from, to).is_none_or(|ray| !scene.occluded(&ray))
}

/// The shadow ray between two points, each end moved off its surface;
/// `None` where the two ends meet, which nothing can block.
#[inline(always)]
pub fn segment_ray(from: Endpoint, to: Endpoint) -> Option<Ray> {
    let dir = to.position() - from.position();
    let origin = from.lifted(dir);
    let target = to.lifted(-dir);
    let d = target - origin;
    let distance = d.length();
    if distance.is_nan() || distance <= 0.0 {
        return None;
    }
    Some(Ray::segment(origin, d / distance, distance))
}

/// The shadow ray from `surface` to the light sample, each end moved off
/// its surface; `None` where the two ends meet, which nothing can block.
/// Always inlined, as `visible`: the compiler stopped inlining it into
/// the path tracer's lanes when BDPT's lanes grew (perf gate's
/// render-cornell-pt +3.5% instructions with this and three more calls
/// left out of line; docs/benchmarks.md).
#[inline(always)]
pub fn shadow_ray(surface: &SurfacePoint, sample: &IncidentSample) -> Option<Ray> {
    let origin = offset_origin(
        surface.position,
        surface.geometric_normal,
        sample.wi,
        surface.magnitude,
    );
    if sample.distance.is_infinite() {
        return Some(Ray::new(origin, sample.wi));
    }
    let target = if sample.normal == Vec3::ZERO {
        sample.point
    } else {
        offset_origin(sample.point, sample.normal, -sample.wi, sample.magnitude)
    };
    let to_target = target - origin;
    let distance = to_target.length();
    if distance.is_nan() || distance <= 0.0 {
        return None;
    }
    Some(Ray::segment(origin, to_target / distance, distance))
}

/// A point on the lens, for a camera path's first ray or for a light
/// path's connections to the camera (one per path). A pinhole draws no
/// random numbers, so pinhole images do not depend on this.
pub(super) fn sample_lens(camera: &Camera, sampler: &mut Sampler) -> Vec3 {
    if camera.is_pinhole() {
        camera.position
    } else {
        camera.lens_point(sampler.next_2d())
    }
}

/// What a light-side point at `position` contributes to the pixel it
/// projects to, given `value` = (light-path weight) × f × cos towards the
/// camera. Returns the pixel and the factor that turns `value` into a splat:
/// the camera's importance over the light path count (report §5.1), and the
/// camera's area density (for MIS, in per-pixel units over the path count).
pub struct CameraConnection {
    pub pixel: u32,
    /// The point on the lens (the pinhole itself for a pinhole camera).
    pub lens: Vec3,
    pub dir_to_camera: Vec3,
    pub distance: f32,
    /// (distance to the image point)² / cos at the camera: solid angle to image area.
    image_to_solid_angle: f32,
}

impl CameraConnection {
    /// The connection of `position` to the lens point `lens` (see
    /// [`Camera::lens_point`]); `None` when it lands outside the image.
    #[inline]
    pub fn new(camera: &Camera, lens: Vec3, position: Vec3) -> Option<CameraConnection> {
        let (x, y) = camera.project_from(lens, position)?;
        let to_camera = lens - position;
        let distance = to_camera.length();
        let dir_to_camera = to_camera / distance;
        let cos_camera = (-dir_to_camera).dot(camera.forward());
        if cos_camera <= 0.0 || distance <= 0.0 {
            return None;
        }
        let image_distance = camera.image_plane_distance() / cos_camera;
        Some(CameraConnection {
            pixel: y as u32 * camera.width() + x as u32,
            lens,
            dir_to_camera,
            distance,
            image_to_solid_angle: image_distance * image_distance / cos_camera,
        })
    }

    /// The camera's density of choosing this point, in area measure at the
    /// point whose surface makes `cos_surface` with the direction to the camera.
    pub fn camera_pdf_area(&self, cos_surface: f32) -> f32 {
        self.image_to_solid_angle * cos_surface / (self.distance * self.distance)
    }

    /// Turns `f · cos` (times the path weight) into the splatted value.
    pub fn splat(&self, value: Rgb, light_paths: f32) -> Rgb {
        value * (self.image_to_solid_angle / (light_paths * self.distance * self.distance))
    }
}
