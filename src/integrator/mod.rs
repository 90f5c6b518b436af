//! Light transport estimators. Each returns, for one camera sample, an
//! unbiased estimate of the radiance arriving along the camera ray.

pub mod bdpt;
pub mod lt;
pub mod mis;
pub mod pt;
pub mod subpath;

/// Paths at least this many segments long are continued by Russian roulette.
/// Short paths carry most of the image and always continue, so roulette adds
/// little variance; it only trims the long tail.
pub const ROULETTE_START: u32 = 4;
