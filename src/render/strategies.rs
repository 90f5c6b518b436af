//! `--bdpt-strategies`: one image per BDPT connection strategy (s, t), both
//! as the strategy alone would estimate the image (unweighted) and as it
//! enters the BDPT image (MIS-weighted), for paths up to a few segments. The
//! weighted images of one path length sum to BDPT's image of that length.
//! Shows a user which strategy carries which effect, and why MIS matters.

use super::{pass_size, render_tile, tiles, worker_pool, Progress, RenderOptions, SPLAT_BATCH};
use crate::film::Image;
use crate::integrator::subpath::SplatSink;
use crate::scene::desc::IntegratorKind;
use crate::scene::Scene;
use crate::Result;
use glam::DVec3;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Longest path (in segments) given images of its own: the number of
/// strategies grows with its square, and longer paths are faint.
pub const MAX_STRATEGY_LENGTH: u32 = 5;

/// The images of one strategy: `s` light vertices, `t` camera vertices.
pub struct StrategyImages {
    pub s: u32,
    pub t: u32,
    pub unweighted: Image,
    pub weighted: Image,
}

struct Sums {
    unweighted: Vec<DVec3>,
    weighted: Vec<DVec3>,
}

/// Renders the scene's BDPT with `max_depth` capped at
/// [`MAX_STRATEGY_LENGTH`] and returns the images of every strategy that
/// contributed, ordered by path length, then by `s`.
pub fn render_strategies(scene: &Scene, options: &RenderOptions) -> Result<Vec<StrategyImages>> {
    let mut settings = scene.settings.clone();
    settings.integrator = IntegratorKind::Bdpt;
    settings.max_depth = settings.max_depth.min(MAX_STRATEGY_LENGTH);
    let settings = &settings;
    let pool = worker_pool(options.threads)?;
    let (width, height) = (settings.width, settings.height);
    let pixels = width as usize * height as usize;
    let mut tiles = tiles::split(super::Crop::full(width, height));
    let progress = Progress::new(options.progress, Some(pixels as u64 * settings.spp as u64));
    let mut sums: BTreeMap<(u32, u32), Sums> = BTreeMap::new();
    let (mut spp, mut pass) = (0, 0);
    while spp < settings.spp {
        let count = pass_size(pass).min(settings.spp - spp);
        for batch in tiles.chunks_mut(SPLAT_BATCH) {
            // Every strategy image divides by one sample count: a render
            // cut short cannot be normalised, so it is abandoned.
            if options
                .interrupt
                .as_ref()
                .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
            {
                progress.finish();
                return Err(crate::Error::Interrupted);
            }
            let lists: Vec<_> = pool.install(|| {
                batch
                    .par_iter_mut()
                    .map(|tile| {
                        let sink = || SplatSink {
                            strategies: Some(Vec::new()),
                            ..SplatSink::default()
                        };
                        let mut sinks = [sink(), sink()];
                        render_tile(scene, settings, tile, spp, count, &mut sinks);
                        progress.advance(tile.pixel_count() as u64 * count as u64);
                        let [a, b] = sinks;
                        let mut records = a.strategies.unwrap_or_default();
                        records.extend(b.strategies.unwrap_or_default());
                        records
                    })
                    .collect()
            });
            // Merged in tile order: the same sums for any thread count.
            for record in lists.iter().flatten() {
                let entry = sums.entry((record.s, record.t)).or_insert_with(|| Sums {
                    unweighted: vec![DVec3::ZERO; pixels],
                    weighted: vec![DVec3::ZERO; pixels],
                });
                let value = record.unweighted.as_dvec3();
                entry.unweighted[record.pixel as usize] += value;
                entry.weighted[record.pixel as usize] += value * record.weight as f64;
            }
        }
        spp += count;
        pass += 1;
    }
    progress.finish();

    let to_image = |sums: &[DVec3]| {
        let mut image = Image::new(width, height);
        for (pixel, sum) in image.pixels.iter_mut().zip(sums) {
            *pixel = (*sum / spp.max(1) as f64).as_vec3();
        }
        image
    };
    let mut images: Vec<StrategyImages> = sums
        .iter()
        .map(|(&(s, t), sums)| StrategyImages {
            s,
            t,
            unweighted: to_image(&sums.unweighted),
            weighted: to_image(&sums.weighted),
        })
        .collect();
    images.sort_by_key(|i| (i.s + i.t, i.s));
    Ok(images)
}
