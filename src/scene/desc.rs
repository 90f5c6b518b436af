//! The scene as described, before anything is loaded: what the JSON format
//! (`format.rs`) and the T-racer importer (`trs.rs`) both produce, and what
//! `load.rs` turns into a renderable [`super::Scene`].
//!
//! Value types here validate themselves while deserialising (finite numbers,
//! non-negative colours, positive sizes), so a bad value is reported at the
//! exact key path by `serde_path_to_error`.

use crate::color::Rgb;
use crate::geometry::transform::Transform;
use glam::{Vec2, Vec3};
use serde::de::{Deserialize, Deserializer, Error as _};
use std::path::PathBuf;

/// A finite number that fits in an `f32`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Finite(pub f32);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f64::deserialize(d)?;
        if !x.is_finite() || x.abs() > f32::MAX as f64 {
            return Err(D::Error::custom(format!(
                "expected a finite number that fits in 32 bits, found {x:e}"
            )));
        }
        Ok(Finite(x as f32))
    }
}

/// A number as a person would write it: exponent notation when very large or small.
fn short(x: f32) -> String {
    if x != 0.0 && !(1e-4..1e7).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A number greater than zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Positive(pub f32);

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(x) = Finite::deserialize(d)?;
        if x <= 0.0 {
            return Err(D::Error::custom(format!(
                "expected a number greater than zero, found {}",
                short(x)
            )));
        }
        Ok(Positive(x))
    }
}

/// An integer greater than zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Count(pub u32);

impl<'de> Deserialize<'de> for Count {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = i64::deserialize(d)?;
        if x <= 0 || x > u32::MAX as i64 {
            return Err(D::Error::custom(format!(
                "expected a whole number greater than zero, found {x}"
            )));
        }
        Ok(Count(x as u32))
    }
}

/// Three finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3(pub Vec3);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y, z] = <[Finite; 3]>::deserialize(d)?;
        Ok(V3(Vec3::new(x.0, y.0, z.0)))
    }
}

/// Two finite numbers (a texture coordinate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V2(pub Vec2);

impl<'de> Deserialize<'de> for V2 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y] = <[Finite; 2]>::deserialize(d)?;
        Ok(V2(Vec2::new(x.0, y.0)))
    }
}

/// A linear RGB colour with no negative channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Color(pub Rgb);

impl<'de> Deserialize<'de> for Color {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let V3(c) = V3::deserialize(d)?;
        if c.min_element() < 0.0 {
            return Err(D::Error::custom(format!(
                "expected a colour with no negative channel, found [{}, {}, {}]",
                c.x, c.y, c.z
            )));
        }
        Ok(Color(c))
    }
}

/// A reflectance: every channel in [0, 1], so a surface never creates energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reflectance(pub Rgb);

impl<'de> Deserialize<'de> for Reflectance {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Color(c) = Color::deserialize(d)?;
        if c.max_element() > 1.0 {
            return Err(D::Error::custom(format!(
                "expected a reflectance with channels between 0 and 1, found [{}, {}, {}]",
                c.x, c.y, c.z
            )));
        }
        Ok(Reflectance(c))
    }
}

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
}

fn default_camera_type() -> CameraType {
    CameraType::Perspective
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorKind {
    /// Path tracing with next-event estimation and MIS.
    Pt,
    /// Light tracing.
    Lt,
    /// Bidirectional path tracing.
    Bdpt,
}

impl IntegratorKind {
    /// The name the scene format and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Pt => "pt",
            IntegratorKind::Lt => "lt",
            IntegratorKind::Bdpt => "bdpt",
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
    pub time_limit: Option<Positive>,
    #[serde(default = "default_max_depth")]
    pub max_depth: Count,
    #[serde(default)]
    pub seed: u64,
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
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum AlbedoDesc {
    Constant(Rgb),
    /// A texture file, resolved against the scene's folder.
    Texture(PathBuf),
}

#[derive(Clone, Debug, PartialEq)]
pub enum MaterialDesc {
    Diffuse { albedo: AlbedoDesc },
    Mirror { reflectance: Rgb },
    Dielectric { ior: f32, transmittance: Rgb },
}

/// How T-racer's "Mesh Material" rewrites every MTL material of a mesh,
/// keeping the MTL's `Kd` as the colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialOverride {
    Diffuse,
    Mirror,
    Glass,
}

#[derive(Clone, Debug)]
pub enum ShapeDesc {
    Mesh {
        file: PathBuf,
        mtl_override: Option<MaterialOverride>,
    },
    Quad,
    Cube,
    Sphere {
        center: Vec3,
        radius: f32,
        subdivisions: u32,
    },
    Triangles {
        positions: Vec<Vec3>,
        indices: Option<Vec<u32>>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
    },
}

#[derive(Clone, Debug)]
pub struct ObjectDesc {
    /// Where this object is described, e.g. `objects[3]`, for error messages.
    pub key_path: String,
    pub shape: ShapeDesc,
    pub material: Option<String>,
    pub transform: Transform,
    pub emission: Option<Rgb>,
    pub two_sided: bool,
}

#[derive(Clone, Debug)]
pub enum LightDesc {
    Point {
        position: Vec3,
        intensity: Rgb,
    },
    Spot {
        position: Vec3,
        look_at: Vec3,
        intensity: Rgb,
        cone_angle: f32,
        falloff_start: f32,
    },
    Directional {
        direction: Vec3,
        irradiance: Rgb,
    },
}

/// Display settings that only a T-racer file carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Display {
    Pfm,
    Tga,
    Window,
}

#[derive(Clone, Debug)]
pub struct SceneDesc {
    /// The file the description came from; relative paths resolve against its folder.
    pub file: PathBuf,
    pub name: String,
    pub camera: CameraDesc,
    pub film: FilmDesc,
    pub render: RenderDesc,
    pub materials: Vec<(String, MaterialDesc)>,
    pub objects: Vec<ObjectDesc>,
    pub lights: Vec<(String, LightDesc)>,
    pub display: Option<Display>,
}
