//! The scene as described, before anything is built: what the JSON format
//! (`json.rs`) and the T-racer importer (`trs.rs`) both produce, and what
//! [`crate::scene::build`] turns into a renderable [`crate::scene::Scene`].
//!
//! Value types here validate themselves while deserialising (finite numbers,
//! non-negative colours, positive sizes), so a bad value is reported at the
//! exact key path by `serde_path_to_error`.

use crate::color::Rgb;
use crate::geometry::transform::Transform;
use crate::settings::Settings;
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

/// A JSON object read with its keys in file order, refusing a key that
/// appears twice (which JSON parsers otherwise resolve silently, last one
/// wins), sorted by key once read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UniqueMap(pub Vec<(String, serde_json::Value)>);

impl<'de> Deserialize<'de> for UniqueMap {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = UniqueMap;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<UniqueMap, A::Error> {
                let mut entries: Vec<(String, serde_json::Value)> = Vec::new();
                let mut seen = std::collections::HashSet::new();
                while let Some(key) = map.next_key::<String>()? {
                    if !seen.insert(key.clone()) {
                        return Err(A::Error::custom(format!(
                            "the name \"{}\" is given twice",
                            crate::error::clip(key)
                        )));
                    }
                    let value = map.next_value()?;
                    entries.push((key, value));
                }
                entries.sort_by(|a, b| a.0.cmp(&b.0));
                Ok(UniqueMap(entries))
            }
        }
        d.deserialize_map(Visitor)
    }
}

/// A duration in seconds: any finite number greater than zero, in double
/// precision (a value too large for the clock means no limit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seconds(pub f64);

impl<'de> Deserialize<'de> for Seconds {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f64::deserialize(d)?;
        if !(x.is_finite() && x > 0.0) {
            return Err(D::Error::custom(format!(
                "expected a positive number of seconds, found {x:e}"
            )));
        }
        Ok(Seconds(x))
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

/// A number zero or greater.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonNegative(pub f32);

impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Finite(x) = Finite::deserialize(d)?;
        if x < 0.0 {
            return Err(D::Error::custom(format!(
                "expected a number zero or greater, found {}",
                short(x)
            )));
        }
        Ok(NonNegative(x))
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

/// Where a diffuse material's albedo comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum AlbedoDesc {
    /// One reflectance everywhere, each channel in [0, 1].
    Constant(Rgb),
    /// A texture file, resolved against the scene's folder.
    Texture(PathBuf),
}

/// A material as described; [`crate::scene::build`] makes a
/// [`crate::material::Material`] of it.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialDesc {
    /// Lambertian reflection.
    Diffuse {
        /// The albedo (JSON default: 0.5 grey).
        albedo: AlbedoDesc,
    },
    /// Perfect specular reflection.
    Mirror {
        /// Fraction reflected per channel, in [0, 1] (JSON default: 1).
        reflectance: Rgb,
    },
    /// Smooth glass.
    Dielectric {
        /// Index of refraction inside relative to outside; > 0 (JSON default: 1.5).
        ior: f32,
        /// Per-channel factor on refracted light, in [0, 1] (JSON default: 1).
        transmittance: Rgb,
    },
    /// A GGX conductor (format 2).
    Conductor {
        /// GGX width, ≥ 0 (JSON default: 0.1).
        alpha: f32,
        /// Complex index of refraction (`eta`, `k`); `None` for Fresnel 1.
        ior: Option<(Rgb, Rgb)>,
        /// Multiplier on reflected light, in [0, 1] (JSON default: 1).
        reflectance: Rgb,
    },
    /// GGX rough glass (format 2).
    RoughDielectric {
        /// Index of refraction inside relative to outside; > 0 (JSON default: 1.5).
        ior: f32,
        /// GGX width, ≥ 0 (JSON default: 0.1).
        alpha: f32,
        /// Per-channel factor on refracted light, in [0, 1] (JSON default: 1).
        transmittance: Rgb,
    },
    /// A diffuse base under a dielectric coat (format 2).
    Plastic {
        /// The base's albedo (JSON default: 0.5 grey).
        albedo: AlbedoDesc,
        /// Index of refraction of the coat; > 0 (JSON default: 1.5).
        ior: f32,
        /// GGX width of the coat, ≥ 0 (JSON default: 0.1); 0 is a smooth coat.
        alpha: f32,
    },
}

/// How T-racer's "Mesh Material" rewrites every MTL material of a mesh,
/// keeping the MTL's `Kd` as the colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialOverride {
    /// Diffuse, with albedo `Kd`.
    Diffuse,
    /// Mirror, with reflectance `Kd`.
    Mirror,
    /// Dielectric, with transmittance `Kd` and the MTL's `Ni` as the index when
    /// it is above 1 (else 1.5).
    Glass,
}

/// What an object is made of, in object space (before its transform).
#[derive(Clone, Debug)]
pub enum ShapeDesc {
    /// The triangles of an OBJ file, with its MTL materials.
    Mesh {
        /// The OBJ file, already resolved against the scene's folder.
        file: PathBuf,
        /// T-racer's "Mesh Material"; `None` converts each MTL material as the
        /// scene format says.
        mtl_override: Option<MaterialOverride>,
    },
    /// Unit square in the xz-plane, centred at the origin, facing +y.
    Quad,
    /// Unit cube centred at the origin, faces pointing outwards.
    Cube,
    /// An icosphere with smooth normals.
    Sphere {
        /// Centre, in object space.
        center: Vec3,
        /// Radius, in object-space units; > 0.
        radius: f32,
        /// Times the icosahedron is subdivided: 20 × 4^n triangles, at most
        /// [`crate::format::json::MAX_SUBDIVISIONS`].
        subdivisions: u32,
    },
    /// Triangles given inline.
    Triangles {
        /// Vertex positions, in object space.
        positions: Vec<Vec3>,
        /// Three indices into `positions` per triangle, counter-clockwise seen from
        /// the front; `None`: every three consecutive positions form a triangle.
        indices: Option<Vec<u32>>,
        /// One shading normal per position; `None` shades flat.
        normals: Option<Vec<Vec3>>,
        /// One texture coordinate per position; `None` maps all to (0, 0).
        uvs: Option<Vec<Vec2>>,
    },
}

/// One object of the scene: a shape, its material, and where it is.
#[derive(Clone, Debug)]
pub struct ObjectDesc {
    /// Where this object is described, e.g. `objects[3]`, for error messages.
    pub key_path: String,
    /// What the object is made of.
    pub shape: ShapeDesc,
    /// Name of one of [`SceneDesc::materials`]. `None`: a mesh keeps its MTL
    /// materials; anything else (or a mesh part without one) gets the material
    /// named `default`, or a built-in 0.5 grey diffuse when there is none.
    pub material: Option<String>,
    /// Object-to-world transform, applied to every vertex and normal.
    pub transform: Transform,
    /// Radiance emitted by every triangle, making each an area light. `None`
    /// (or black): not emissive, except where a mesh's MTL gives `Ke`.
    pub emission: Option<Rgb>,
    /// Whether an emissive object emits from its back faces too (materials
    /// are two-sided regardless).
    pub two_sided: bool,
}

/// A light that is not an emissive object.
#[derive(Clone, Debug)]
pub enum LightDesc {
    /// Isotropic point light.
    Point {
        /// Position, in world space.
        position: Vec3,
        /// Radiant intensity, W/sr per channel.
        intensity: Rgb,
    },
    /// Spot light: a point light limited to a cone.
    Spot {
        /// Position, in world space.
        position: Vec3,
        /// A world-space point on the cone's axis; differs from `position`.
        look_at: Vec3,
        /// Radiant intensity along the axis, W/sr per channel.
        intensity: Rgb,
        /// Angle from the axis to the cone's edge, in degrees, in (0, 180].
        cone_angle: f32,
        /// Angle from the axis where the falloff to zero begins, in degrees, in
        /// [0, `cone_angle`]; equal to `cone_angle` for a hard edge.
        falloff_start: f32,
    },
    /// Parallel light from infinitely far away.
    Directional {
        /// Direction the light travels in (not towards the light); non-zero,
        /// not necessarily unit length.
        direction: Vec3,
        /// Irradiance on a surface facing the light, per channel.
        irradiance: Rgb,
    },
    /// Light from infinitely far away in every direction (format 2).
    Environment {
        /// What the sky looks like: one colour, or an image.
        sky: SkyDesc,
        /// Multiplies the radiance; non-negative.
        scale: f32,
        /// Turns the sky from its own frame into the world's (a rotation).
        rotation: glam::Mat3,
    },
}

/// The radiance of an environment light.
#[derive(Clone, Debug)]
pub enum SkyDesc {
    /// The same radiance from every direction.
    Constant(Rgb),
    /// A latitude–longitude image (resolved path).
    Image(PathBuf),
}

/// A scene as read from its file: everything [`crate::scene::build`] needs.
#[derive(Clone, Debug)]
pub struct SceneDesc {
    /// The file the description came from; relative paths resolve against its folder.
    pub file: PathBuf,
    /// The scene's name: its `name` key, or the file name without extension.
    pub name: String,
    /// What the file asks one render to do.
    pub settings: Settings,
    /// Named materials in material-index order (a JSON file's, sorted by name).
    pub materials: Vec<(String, MaterialDesc)>,
    /// The objects, in file order.
    pub objects: Vec<ObjectDesc>,
    /// Lights that are not emissive objects, each with its key path (e.g.
    /// `lights[0]`) for messages.
    pub lights: Vec<(String, LightDesc)>,
}
