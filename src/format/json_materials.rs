//! The `materials` section of a JSON scene: each material by its `type`.

use super::desc::*;
use super::json::kind_of;
use super::json::Ctx;
use super::resolve;
use crate::Result;
use glam::Vec3;
use serde::Deserialize;
use serde_json::Value;

impl Ctx<'_> {
    pub(super) fn material(&self, value: &Value, path: &str) -> Result<MaterialDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Diffuse {
            #[serde(default)]
            albedo: Option<Value>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Mirror {
            #[serde(default)]
            reflectance: Option<Reflectance>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Dielectric {
            #[serde(default)]
            ior: Option<Positive>,
            #[serde(default)]
            transmittance: Option<Reflectance>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Conductor {
            #[serde(default)]
            alpha: Option<NonNegative>,
            #[serde(default)]
            eta: Option<Color>,
            #[serde(default)]
            k: Option<Color>,
            #[serde(default)]
            reflectance: Option<Reflectance>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct RoughDielectric {
            #[serde(default)]
            ior: Option<Positive>,
            #[serde(default)]
            alpha: Option<NonNegative>,
            #[serde(default)]
            transmittance: Option<Reflectance>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Plastic {
            #[serde(default)]
            albedo: Option<Value>,
            #[serde(default)]
            ior: Option<Positive>,
            #[serde(default)]
            alpha: Option<NonNegative>,
        }
        let (kind, map) = self.tagged(
            value,
            path,
            &[
                "diffuse",
                "mirror",
                "dielectric",
                "conductor",
                "rough_dielectric",
                "plastic",
            ],
        )?;
        let map = Value::Object(map);
        Ok(match kind.as_str() {
            "diffuse" => {
                let d: Diffuse = self.typed(map, path)?;
                let albedo = match d.albedo {
                    None => AlbedoDesc::Constant(glam::Vec3::splat(0.5)),
                    Some(v) => self.albedo(v, &format!("{path}.albedo"))?,
                };
                MaterialDesc::Diffuse { albedo }
            }
            "mirror" => {
                let m: Mirror = self.typed(map, path)?;
                MaterialDesc::Mirror {
                    reflectance: m.reflectance.map_or(Vec3::ONE, |r| r.0),
                }
            }
            "dielectric" => {
                let d: Dielectric = self.typed(map, path)?;
                MaterialDesc::Dielectric {
                    ior: d.ior.map_or(1.5, |x| x.0),
                    transmittance: d.transmittance.map_or(Vec3::ONE, |r| r.0),
                }
            }
            "conductor" => {
                let c: Conductor = self.typed(map, path)?;
                let ior = match (c.eta, c.k) {
                    (Some(eta), Some(k)) => Some((eta.0, k.0)),
                    (None, None) => None,
                    (eta, _) => {
                        let missing = if eta.is_some() { "k" } else { "eta" };
                        return Err(self.err(
                            &format!("{path}.{missing}"),
                            "missing: give both `eta` and `k` (or neither, for Fresnel 1)",
                        ));
                    }
                };
                MaterialDesc::Conductor {
                    alpha: c.alpha.map_or(0.1, |a| a.0),
                    ior,
                    reflectance: c.reflectance.map_or(Vec3::ONE, |r| r.0),
                }
            }
            "plastic" => {
                let p: Plastic = self.typed(map, path)?;
                let albedo = match p.albedo {
                    None => AlbedoDesc::Constant(glam::Vec3::splat(0.5)),
                    Some(v) => self.albedo(v, &format!("{path}.albedo"))?,
                };
                MaterialDesc::Plastic {
                    albedo,
                    ior: p.ior.map_or(1.5, |x| x.0),
                    alpha: p.alpha.map_or(0.1, |a| a.0),
                }
            }
            _ => {
                let d: RoughDielectric = self.typed(map, path)?;
                MaterialDesc::RoughDielectric {
                    ior: d.ior.map_or(1.5, |x| x.0),
                    alpha: d.alpha.map_or(0.1, |a| a.0),
                    transmittance: d.transmittance.map_or(Vec3::ONE, |r| r.0),
                }
            }
        })
    }

    fn albedo(&self, value: Value, path: &str) -> Result<AlbedoDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct TextureRef {
            texture: String,
        }
        match value {
            Value::Object(_) => {
                let t: TextureRef = self.typed(value, path)?;
                Ok(AlbedoDesc::Texture(resolve(self.file, &t.texture)))
            }
            Value::Array(_) => Ok(AlbedoDesc::Constant(
                self.typed::<Reflectance>(value, path)?.0,
            )),
            other => Err(self.err(
                path,
                format!(
                    "expected an RGB colour or {{\"texture\": file}}, found {}",
                    kind_of(&other)
                ),
            )),
        }
    }
}
