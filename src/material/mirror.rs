//! Perfect specular reflection.

use super::reflect_local;
use crate::color::Rgb;
use glam::Vec3;

/// Returns (wi, weight, pdf, delta): the one reflected direction, chosen with probability one.
pub fn sample(reflectance: Rgb, wo: Vec3) -> (Vec3, Rgb, f32, bool) {
    (reflect_local(wo), reflectance, 1.0, true)
}
