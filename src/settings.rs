//! What one render is asked to do: the camera, the film, the integrator and
//! the rules that stop it. The JSON format, the T-racer importer and the
//! command line all fill this one type, and [`Settings::check`] applies the
//! same limits whichever of them a value came from.

use crate::camera::Camera;
pub use crate::film::tonemap::Tonemap;
use glam::Vec3;
use std::path::PathBuf;

/// The largest image accepted, in pixels (a 16k × 16k render).
pub const MAX_PIXELS: u64 = 1 << 28;

/// The camera as described: where it is, where it looks, its vertical
/// field of view in degrees, and its lens (none for a pinhole).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSettings {
    /// Pinhole position, in world space.
    pub position: Vec3,
    /// A world-space point the camera looks at; differs from `position`.
    pub look_at: Vec3,
    /// Roughly which way is up in the image; need not be unit length or
    /// perpendicular to the view, only not parallel to it.
    pub up: Vec3,
    /// Vertical field of view, in degrees, in (0, 180).
    pub fov: f32,
    /// Radius of the thin lens; 0 for a pinhole.
    pub aperture_radius: f32,
    /// Distance along the view axis to the plane in focus; `None` for the
    /// distance from `position` to `look_at`.
    pub focus_distance: Option<f32>,
}

/// The image: its size, where it is written and how it is tone mapped.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSettings {
    /// Image width, in pixels; > 0.
    pub width: u32,
    /// Image height, in pixels; > 0 (width × height at most [`MAX_PIXELS`]).
    pub height: u32,
    /// The output file; the format follows its extension.
    pub output: PathBuf,
    /// The curve for 8-bit outputs (PNG, TGA); EXR and PFM are written linear.
    pub tonemap: Tonemap,
    /// Stops of exposure applied before tone mapping.
    pub exposure: f32,
}

/// The light transport estimator, by the name the format and the command
/// line use. [`crate::integrator::Integrator`] is the estimator itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorKind {
    /// Path tracing with next-event estimation and MIS.
    Pt,
    /// Light tracing.
    Lt,
    /// Bidirectional path tracing.
    Bdpt,
    /// Vertex connection and merging.
    Vcm,
}

impl IntegratorKind {
    /// Every kind, in the order the command line lists them.
    pub const ALL: [IntegratorKind; 4] = [
        IntegratorKind::Pt,
        IntegratorKind::Lt,
        IntegratorKind::Bdpt,
        IntegratorKind::Vcm,
    ];

    /// The name the scene format and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Pt => "pt",
            IntegratorKind::Lt => "lt",
            IntegratorKind::Bdpt => "bdpt",
            IntegratorKind::Vcm => "vcm",
        }
    }

    /// The kind called `name`, if any.
    pub fn from_name(name: &str) -> Option<IntegratorKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// When a render ends: whichever rule is met first.
#[derive(Clone, Debug, PartialEq)]
pub struct StopRules {
    /// Samples per pixel.
    pub spp: u32,
    /// Seconds; a value too large for the clock means no limit.
    pub time_limit: Option<f64>,
    /// Stop once the estimated mean relative error falls below this.
    pub target_noise: Option<f64>,
    /// With `target_noise`: a tile whose own noise falls below the target
    /// takes no more samples, so the time goes where the noise is, and the
    /// render stops once every tile is below it.
    pub adaptive: bool,
}

/// A rectangle of pixels, `x0 .. x1` by `y0 .. y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    /// Left edge (inclusive), in pixels from the left of the image.
    pub x0: u32,
    /// Top edge (inclusive), in pixels from the top of the image.
    pub y0: u32,
    /// Right edge (exclusive).
    pub x1: u32,
    /// Bottom edge (exclusive).
    pub y1: u32,
}

impl Crop {
    /// The whole `width` × `height` image.
    pub fn full(width: u32, height: u32) -> Crop {
        Crop {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// Width, in pixels.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    /// Height, in pixels.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Whether pixel (`x`, `y`) of the full image is inside.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

/// Display settings that only a T-racer file carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Display {
    /// Write a PFM file.
    Pfm,
    /// Write a TGA file.
    Tga,
    /// Show the image in the preview window (and write an EXR).
    Window,
}

/// Everything one render is asked to do.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Where the pinhole camera is, where it looks, and its field of view.
    pub camera: CameraSettings,
    /// The image and where it goes.
    pub film: FilmSettings,
    /// Which estimator renders the image.
    pub integrator: IntegratorKind,
    /// The most path segments (the camera ray is one; direct light needs two).
    pub max_depth: u32,
    /// VCM's merging radius at the first sample, in scene units; `None`
    /// for a fraction of the scene's size
    /// ([`crate::integrator::DEFAULT_RADIUS_FRACTION`]).
    pub vcm_radius: Option<f32>,
    /// The image is a pure function of the scene, the settings and the seed.
    pub seed: u64,
    /// When to stop sampling: sample count, time or noise.
    pub stop: StopRules,
    /// Render only these pixels; the image covers just them.
    pub crop: Option<Crop>,
    /// Every pixel's samples are numbered from here, so processes given
    /// disjoint ranges take disjoint samples of the same pixels.
    pub sample_offset: u32,
    /// How a T-racer scene asked for its image to be shown.
    pub display: Option<Display>,
}

/// Which setting a check refused, so each source can name it its own way
/// (a key path in a scene file, a flag on the command line).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setting {
    /// The field of view: not in (0°, 180°).
    Fov,
    /// The camera as a whole: `position` equals `look_at`, or `up` is
    /// parallel to the view direction.
    Camera,
    /// The image size: no pixels, or more than [`MAX_PIXELS`].
    ImageSize,
    /// The crop: empty, or not inside the image.
    Crop,
    /// The sample offset plus the samples per pixel do not fit in 32 bits.
    SampleRange,
    /// Adaptive sampling without a target noise.
    Adaptive,
    /// A VCM merging radius that is not a finite number above zero.
    VcmRadius,
}

/// A refused setting and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// Which setting was refused.
    pub setting: Setting,
    /// Why, for a person: says what was expected and what was found.
    pub message: String,
}

impl Settings {
    /// Default settings for a camera: 512 × 512, sRGB, path tracing, 16
    /// samples per pixel, 16 segments, seed 0, written to `output`.
    pub fn new(camera: CameraSettings, output: PathBuf) -> Settings {
        Settings {
            camera,
            film: FilmSettings {
                width: 512,
                height: 512,
                output,
                tonemap: Tonemap::Srgb,
                exposure: 0.0,
            },
            integrator: IntegratorKind::Pt,
            max_depth: 16,
            vcm_radius: None,
            seed: 0,
            stop: StopRules {
                spp: 16,
                time_limit: None,
                target_noise: None,
                adaptive: false,
            },
            crop: None,
            sample_offset: 0,
            display: None,
        }
    }

    /// The limits every source of settings shares: a field of view in
    /// (0°, 180°), a camera with a direction, an image that fits in memory,
    /// a crop inside it, sample indices that fit in 32 bits, adaptive
    /// sampling only with a target.
    pub fn check(&self) -> Result<(), Invalid> {
        let invalid = |setting, message: String| Err(Invalid { setting, message });
        let fov = self.camera.fov;
        // Written so that NaN fails too.
        if fov.is_nan() || fov <= 0.0 {
            return invalid(
                Setting::Fov,
                format!("expected a number greater than zero, found {fov}"),
            );
        }
        if fov >= 180.0 {
            return invalid(
                Setting::Fov,
                format!("expected less than 180 degrees, found {fov}"),
            );
        }
        let lens = (self.camera.aperture_radius, self.camera.focus_distance);
        if !(lens.0 >= 0.0 && lens.0.is_finite()) {
            return invalid(
                Setting::Camera,
                format!(
                    "aperture_radius: expected a number zero or greater, found {}",
                    lens.0
                ),
            );
        }
        if lens.1.is_some_and(|d| !(d > 0.0 && d.is_finite())) {
            return invalid(
                Setting::Camera,
                format!(
                    "focus_distance: expected a number greater than zero, found {:?}",
                    lens.1
                ),
            );
        }
        if self.camera().is_none() {
            return invalid(
                Setting::Camera,
                "position and look_at must differ, and up must not be parallel to the view direction".into(),
            );
        }
        let (w, h) = (self.film.width, self.film.height);
        if w == 0 || h == 0 {
            return invalid(Setting::ImageSize, format!("{w} x {h} has no pixels"));
        }
        if w as u64 * h as u64 > MAX_PIXELS {
            return invalid(
                Setting::ImageSize,
                format!("{w} x {h} is too large (at most {MAX_PIXELS} pixels)"),
            );
        }
        if let Some(c) = self.crop {
            if c.x0 >= c.x1 || c.y0 >= c.y1 || c.x1 > w || c.y1 > h {
                return invalid(
                    Setting::Crop,
                    format!(
                        "crop {},{},{},{} is not a non-empty part of the {w}x{h} image",
                        c.x0, c.y0, c.x1, c.y1
                    ),
                );
            }
        }
        if self.sample_offset.checked_add(self.stop.spp).is_none() {
            return invalid(
                Setting::SampleRange,
                format!(
                    "sample offset {} plus {} samples per pixel exceeds 2^32",
                    self.sample_offset, self.stop.spp
                ),
            );
        }
        if self.stop.adaptive && self.stop.target_noise.is_none() {
            return invalid(
                Setting::Adaptive,
                "adaptive sampling needs a target noise".into(),
            );
        }
        if let Some(r) = self.vcm_radius {
            if !(r > 0.0 && r.is_finite()) {
                return invalid(
                    Setting::VcmRadius,
                    format!("expected a number greater than zero, found {r}"),
                );
            }
            let paths = self.film.width as f32 * self.film.height as f32;
            let (lowest, highest) = crate::integrator::radius_limits(paths);
            if !(lowest..=highest).contains(&r) {
                return invalid(
                    Setting::VcmRadius,
                    format!(
                        "{r} is outside {lowest:e} to {highest:e}, the radii whose merges a {} x {} image can normalise",
                        self.film.width, self.film.height
                    ),
                );
            }
        }
        Ok(())
    }

    /// The camera at the film's resolution; `None` when it has no direction.
    pub fn camera(&self) -> Option<Camera> {
        let c = &self.camera;
        let focus = c
            .focus_distance
            .unwrap_or_else(|| (c.look_at - c.position).length());
        Camera::new(
            c.position,
            c.look_at,
            c.up,
            c.fov,
            self.film.width,
            self.film.height,
        )
        .map(|camera| camera.with_lens(c.aperture_radius, focus))
    }

    /// The pixels rendered: the crop, or the whole image.
    pub fn crop_or_full(&self) -> Crop {
        self.crop
            .unwrap_or(Crop::full(self.film.width, self.film.height))
    }
}
