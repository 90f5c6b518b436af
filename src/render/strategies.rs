//! `--bdpt-strategies`: one image per BDPT connection strategy (s, t), both
//! as the strategy alone would estimate the image (unweighted) and as it
//! enters the BDPT image (MIS-weighted), for paths up to a few segments. The
//! weighted images of one path length sum to BDPT's image of that length.
//! Shows a user which strategy carries which effect, and why MIS matters.

use crate::film::Image;
use crate::integrator::StrategySample;
use glam::DVec3;
use std::collections::BTreeMap;

/// Longest path (in segments) given images of its own: the number of
/// strategies grows with its square, and longer paths are faint.
pub const MAX_STRATEGY_LENGTH: u32 = 5;

/// The images of one strategy: `s` light vertices, `t` camera vertices.
pub struct StrategyImages {
    /// Light subpath vertices, the light's own point included (0: the camera
    /// path hit a light).
    pub s: u32,
    /// Camera subpath vertices, the pinhole included (1: the light path was
    /// projected onto the image).
    pub t: u32,
    /// The image as this strategy alone would estimate it (full image size).
    pub unweighted: Image,
    /// This strategy's MIS-weighted share of BDPT's image.
    pub weighted: Image,
}

struct Sums {
    unweighted: Vec<DVec3>,
    weighted: Vec<DVec3>,
}

/// Per strategy, the sums of its samples over the whole image.
pub(super) struct StrategySums {
    pixels: usize,
    sums: BTreeMap<(u32, u32), Sums>,
}

impl StrategySums {
    pub fn new(pixels: usize) -> StrategySums {
        StrategySums {
            pixels,
            sums: BTreeMap::new(),
        }
    }

    /// Adds records in the order given (tile order: the same sums for any
    /// thread count).
    pub fn add(&mut self, records: &[StrategySample]) {
        for record in records {
            let pixels = self.pixels;
            let entry = self
                .sums
                .entry((record.s, record.t))
                .or_insert_with(|| Sums {
                    unweighted: vec![DVec3::ZERO; pixels],
                    weighted: vec![DVec3::ZERO; pixels],
                });
            let value = record.unweighted.as_dvec3();
            entry.unweighted[record.pixel as usize] += value;
            entry.weighted[record.pixel as usize] += value * record.weight as f64;
        }
    }

    /// The images of every strategy that contributed, each pixel divided by
    /// `spp`, ordered by path length, then by `s`.
    pub fn images(&self, width: u32, height: u32, spp: u32) -> Vec<StrategyImages> {
        let to_image = |sums: &[DVec3]| {
            let mut image = Image::new(width, height);
            for (pixel, sum) in image.pixels.iter_mut().zip(sums) {
                *pixel = (*sum / spp.max(1) as f64).as_vec3();
            }
            image
        };
        let mut images: Vec<StrategyImages> = self
            .sums
            .iter()
            .map(|(&(s, t), sums)| StrategyImages {
                s,
                t,
                unweighted: to_image(&sums.unweighted),
                weighted: to_image(&sums.weighted),
            })
            .collect();
        images.sort_by_key(|i| (i.s + i.t, i.s));
        images
    }
}
