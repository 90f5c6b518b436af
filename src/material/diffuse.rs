//! Lambertian reflection: f = albedo / π, sampled by cosine-weighted directions.

use crate::color::Rgb;
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// `f · cos θi` for a local direction.
pub fn eval(albedo: Rgb, wi: Vec3) -> Rgb {
    if wi.z <= 0.0 {
        return Rgb::ZERO;
    }
    albedo * (FRAC_1_PI * wi.z)
}

pub fn pdf(wi: Vec3) -> f32 {
    cosine_hemisphere_pdf(wi.z)
}

/// Returns (wi, weight, pdf, delta). With cosine sampling the weight is the albedo.
pub fn sample(albedo: Rgb, u: (f32, f32)) -> Option<(Vec3, Rgb, f32, bool)> {
    let wi = cosine_hemisphere(u.0, u.1);
    let pdf = pdf(wi);
    if pdf <= 0.0 {
        return None;
    }
    Some((wi, albedo, pdf, false))
}
