//! A point on a surface, as shading and light transport see it.

use glam::{Vec2, Vec3};

/// What the integrator knows about a surface point.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// World-space position, interpolated in double precision so it lies on the triangle.
    pub position: Vec3,
    /// Unit geometric normal by counter-clockwise winding (the front side).
    pub geometric_normal: Vec3,
    /// Unit interpolated shading normal, on the same side as the geometric normal.
    pub shading_normal: Vec3,
    /// Interpolated texture coordinate; (0, 0) on meshes without UVs.
    pub uv: Vec2,
    /// Largest coordinate magnitude of the surface's triangle, for ray offsets.
    pub magnitude: f32,
}
