//! Where a sample puts what is not its own pixel's estimate: splats into
//! other pixels (light tracing, BDPT's t = 1 strategy), and, when asked,
//! each strategy's share for `--bdpt-strategies`.

use crate::color::{is_black, is_finite, Rgb};
use crate::film::Splat;

/// One strategy's share of one sample, kept only for `--bdpt-strategies`.
/// A path of `s` light vertices (the light's own point included) joined to
/// `t` camera vertices (the pinhole included).
#[derive(Clone, Copy, Debug)]
pub struct StrategySample {
    /// Light subpath vertices, the light's own point included.
    pub s: u32,
    /// Camera subpath vertices, the pinhole included.
    pub t: u32,
    /// The pixel it lands in: row-major index into the full image.
    pub pixel: u32,
    /// The strategy's estimate alone, as if it were the only one.
    pub unweighted: Rgb,
    /// Its MIS weight: `unweighted × weight` is what enters the image.
    pub weight: f32,
}

/// What the light side of a sample produces besides the camera pixel's own
/// estimate: splats to other pixels, discarded splats, and optionally
/// per-strategy records.
#[derive(Default)]
pub struct SampleSink {
    /// Contributions to other pixels, in the order they were made.
    pub splats: Vec<Splat>,
    /// Splats dropped for being NaN or infinite.
    pub discarded: u64,
    /// Per-strategy records; `None` unless `--bdpt-strategies` asked for them.
    pub strategies: Option<Vec<StrategySample>>,
}

impl SampleSink {
    /// Adds `value` to `pixel` (a row-major index into the full image); a NaN
    /// or infinite value is counted in `discarded` instead.
    pub fn emit(&mut self, pixel: u32, value: Rgb) {
        if is_finite(value) {
            self.splats.push(Splat { pixel, value });
        } else {
            self.discarded += 1;
        }
    }

    /// Records a strategy's contribution when strategies are being kept.
    pub fn record(&mut self, s: u32, t: u32, pixel: u32, unweighted: Rgb, weight: f32) {
        if let Some(list) = self.strategies.as_mut() {
            if weight > 0.0 && is_finite(unweighted) && !is_black(unweighted) {
                list.push(StrategySample {
                    s,
                    t,
                    pixel,
                    unweighted,
                    weight,
                });
            }
        }
    }
}
