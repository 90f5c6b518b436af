//! Maps linear radiance to 8-bit display values.

use crate::color::Rgb;

/// The curve that turns linear radiance into 8-bit PNG and TGA pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tonemap {
    /// x^(1/2.2)
    Gamma,
    /// The sRGB transfer curve.
    Srgb,
    /// ACES filmic curve (Narkowicz's fit), then sRGB.
    Aces,
    /// Clamp to [0, 1], no curve: linear values in 8 bits.
    Clamp,
}

impl Tonemap {
    /// Every curve, in the order the documentation lists them.
    pub const ALL: [Tonemap; 4] = [Tonemap::Gamma, Tonemap::Srgb, Tonemap::Aces, Tonemap::Clamp];

    /// The name the scene format uses.
    pub fn name(self) -> &'static str {
        match self {
            Tonemap::Gamma => "gamma",
            Tonemap::Srgb => "srgb",
            Tonemap::Aces => "aces",
            Tonemap::Clamp => "clamp",
        }
    }
}

/// The display value in [0, 1] of one linear channel, after `exposure` stops.
pub fn map_channel(x: f32, tonemap: Tonemap, exposure: f32) -> f32 {
    let x = (x * exposure.exp2()).max(0.0);
    let x = if x.is_nan() { 0.0 } else { x };
    let y = match tonemap {
        Tonemap::Gamma => x.powf(1.0 / 2.2),
        Tonemap::Srgb => srgb_encode(x),
        Tonemap::Aces => srgb_encode(aces_filmic(x)),
        Tonemap::Clamp => x,
    };
    y.clamp(0.0, 1.0)
}

/// The 8-bit display value of a linear colour, by [`map_channel`], rounded
/// to nearest.
pub fn to_8bit(c: Rgb, tonemap: Tonemap, exposure: f32) -> [u8; 3] {
    let q = |x: f32| (map_channel(x, tonemap, exposure) * 255.0 + 0.5) as u8;
    [q(c.x), q(c.y), q(c.z)]
}

/// The sRGB transfer function (IEC 61966-2-1).
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Narkowicz's fit of the ACES filmic reference curve ("ACES Filmic Tone
/// Mapping Curve", 2015): rolls highlights off smoothly instead of clipping.
pub fn aces_filmic(x: f32) -> f32 {
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_hit_known_points() {
        assert_eq!(map_channel(0.0, Tonemap::Srgb, 0.0), 0.0);
        assert!((map_channel(1.0, Tonemap::Srgb, 0.0) - 1.0).abs() < 1e-6);
        assert!((map_channel(0.214_041, Tonemap::Srgb, 0.0) - 0.5).abs() < 1e-3);
        assert!((map_channel(0.5, Tonemap::Gamma, 0.0) - 0.5f32.powf(1.0 / 2.2)).abs() < 1e-6);
        assert_eq!(
            map_channel(0.25, Tonemap::Clamp, 1.0),
            0.5,
            "one stop doubles"
        );
        assert_eq!(map_channel(7.0, Tonemap::Clamp, 0.0), 1.0);
        assert!(map_channel(100.0, Tonemap::Aces, 0.0) > 0.99);
        assert_eq!(
            to_8bit(Rgb::new(f32::NAN, -1.0, 2.0), Tonemap::Srgb, 0.0),
            [0, 0, 255]
        );
    }
}
