//! The plain sections of a JSON scene file (`camera`, `film`, `render`) as
//! serde reads them, with their defaults, and how they become [`Settings`].

use super::desc::{Count, Finite, NonNegative, Positive, Seconds, V3};
use crate::settings::{CameraSettings, IntegratorKind, Settings, Tonemap};
use glam::Vec3;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CameraType {
    Perspective,
}

fn default_up() -> V3 {
    V3(Vec3::Y)
}
fn default_fov() -> Positive {
    Positive(40.0)
}

#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    #[serde(rename = "type", default = "default_camera_type")]
    pub kind: CameraType,
    pub position: V3,
    pub look_at: V3,
    #[serde(default = "default_up")]
    pub up: V3,
    #[serde(default = "default_fov")]
    pub fov: Positive,
    #[serde(default)]
    pub aperture_radius: Option<NonNegative>,
    #[serde(default)]
    pub focus_distance: Option<Positive>,
}

fn default_camera_type() -> CameraType {
    CameraType::Perspective
}

fn default_size() -> Count {
    Count(512)
}

#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmDesc {
    #[serde(default = "default_size")]
    pub width: Count,
    #[serde(default = "default_size")]
    pub height: Count,
    #[serde(default)]
    pub output: Option<String>,
    #[serde(default = "default_tonemap")]
    pub tonemap: Tonemap,
    #[serde(default = "default_exposure")]
    pub exposure: Finite,
}

fn default_tonemap() -> Tonemap {
    Tonemap::Srgb
}
fn default_exposure() -> Finite {
    Finite(0.0)
}

impl Default for FilmDesc {
    fn default() -> Self {
        FilmDesc {
            width: default_size(),
            height: default_size(),
            output: None,
            tonemap: Tonemap::Srgb,
            exposure: Finite(0.0),
        }
    }
}

fn default_spp() -> Count {
    Count(16)
}
fn default_max_depth() -> Count {
    Count(16)
}

#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    #[serde(default = "default_integrator")]
    pub integrator: IntegratorKind,
    #[serde(default = "default_spp")]
    pub spp: Count,
    #[serde(default)]
    pub time_limit: Option<Seconds>,
    #[serde(default = "default_max_depth")]
    pub max_depth: Count,
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub vcm_radius: Option<Positive>,
}

fn default_integrator() -> IntegratorKind {
    IntegratorKind::Pt
}

impl Default for RenderDesc {
    fn default() -> Self {
        RenderDesc {
            integrator: IntegratorKind::Pt,
            spp: default_spp(),
            time_limit: None,
            max_depth: default_max_depth(),
            seed: 0,
            vcm_radius: None,
        }
    }
}

/// The settings the three sections describe; `output` is the resolved
/// output path.
pub fn settings(
    camera: &CameraDesc,
    film: &FilmDesc,
    render: &RenderDesc,
    output: PathBuf,
) -> Settings {
    // The one camera type: the pinhole.
    let CameraType::Perspective = camera.kind;
    let mut s = Settings::new(
        CameraSettings {
            position: camera.position.0,
            look_at: camera.look_at.0,
            up: camera.up.0,
            fov: camera.fov.0,
            aperture_radius: camera.aperture_radius.map_or(0.0, |r| r.0),
            focus_distance: camera.focus_distance.map(|d| d.0),
        },
        output,
    );
    s.film.width = film.width.0;
    s.film.height = film.height.0;
    s.film.tonemap = film.tonemap;
    s.film.exposure = film.exposure.0;
    s.integrator = render.integrator;
    s.stop.spp = render.spp.0;
    s.stop.time_limit = render.time_limit.map(|t| t.0);
    s.max_depth = render.max_depth.0;
    s.seed = render.seed;
    s.vcm_radius = render.vcm_radius.map(|r| r.0);
    s
}
