//! Linear RGB colours. A colour is a `glam::Vec3`; these helpers name what the
//! renderer asks of one.

use glam::Vec3;

/// Linear RGB radiance, reflectance or weight.
pub type Rgb = Vec3;

/// Rec. 709 luminance of a linear RGB colour.
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Mean of the three channels: used for power-proportional light selection so
/// that a light with any non-zero channel can be picked.
pub fn average(c: Rgb) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Whether every channel is exactly zero.
pub fn is_black(c: Rgb) -> bool {
    c.x == 0.0 && c.y == 0.0 && c.z == 0.0
}

/// Whether no channel is NaN or infinite.
pub fn is_finite(c: Rgb) -> bool {
    c.x.is_finite() && c.y.is_finite() && c.z.is_finite()
}
