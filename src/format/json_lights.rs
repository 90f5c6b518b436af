//! The `lights` section of a JSON scene: point, spot, directional and
//! environment lights.

use super::desc::*;
use super::json::Ctx;
use super::resolve;
use crate::Result;
use serde::Deserialize;
use serde_json::Value;

impl Ctx<'_> {
    pub(super) fn light(&self, value: &Value, path: &str) -> Result<LightDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Point {
            position: V3,
            intensity: Color,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Spot {
            position: V3,
            look_at: V3,
            intensity: Color,
            #[serde(default)]
            cone_angle: Option<Positive>,
            #[serde(default)]
            falloff_start: Option<Finite>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Directional {
            direction: V3,
            irradiance: Color,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Environment {
            #[serde(default)]
            radiance: Option<Color>,
            #[serde(default)]
            file: Option<String>,
            #[serde(default)]
            scale: Option<NonNegative>,
            #[serde(default)]
            transform: Option<Value>,
        }
        let (kind, map) = self.tagged(
            value,
            path,
            &["point", "spot", "directional", "environment"],
        )?;
        let map = Value::Object(map);
        Ok(match kind.as_str() {
            "point" => {
                let p: Point = self.typed(map, path)?;
                LightDesc::Point {
                    position: p.position.0,
                    intensity: p.intensity.0,
                }
            }
            "spot" => {
                let s: Spot = self.typed(map, path)?;
                let cone = s.cone_angle.map_or(30.0, |c| c.0);
                if cone > 180.0 {
                    return Err(self.err(
                        &format!("{path}.cone_angle"),
                        format!("expected at most 180 degrees, found {cone}"),
                    ));
                }
                let start = s.falloff_start.map_or(cone, |f| f.0);
                if !(0.0..=cone).contains(&start) {
                    return Err(self.err(
                        &format!("{path}.falloff_start"),
                        format!(
                            "expected between 0 and cone_angle ({cone}) degrees, found {start}"
                        ),
                    ));
                }
                if (s.look_at.0 - s.position.0).length_squared() == 0.0 {
                    return Err(self.err(&format!("{path}.look_at"), "must differ from position"));
                }
                LightDesc::Spot {
                    position: s.position.0,
                    look_at: s.look_at.0,
                    intensity: s.intensity.0,
                    cone_angle: cone,
                    falloff_start: start,
                }
            }
            "environment" => {
                let e: Environment = self.typed(map, path)?;
                let sky = match (e.radiance, e.file) {
                    (Some(c), None) => SkyDesc::Constant(c.0),
                    (None, Some(f)) => SkyDesc::Image(resolve(self.file, &f)),
                    (Some(_), Some(_)) => {
                        return Err(self.err(
                            path,
                            "give either \"radiance\" (a constant sky) or \"file\" (an image), not both",
                        ))
                    }
                    (None, None) => {
                        return Err(self.err(
                            path,
                            "missing required key (one of: radiance, file)",
                        ))
                    }
                };
                let rotation = match e.transform {
                    None => glam::Mat3::IDENTITY,
                    Some(t) => self.rotation(t, &format!("{path}.transform"))?,
                };
                LightDesc::Environment {
                    sky,
                    scale: e.scale.map_or(1.0, |s| s.0),
                    rotation,
                }
            }
            _ => {
                let d: Directional = self.typed(map, path)?;
                if d.direction.0.length_squared() == 0.0 {
                    return Err(self.err(
                        &format!("{path}.direction"),
                        "expected a non-zero direction",
                    ));
                }
                LightDesc::Directional {
                    direction: d.direction.0,
                    irradiance: d.irradiance.0,
                }
            }
        })
    }
}

impl Ctx<'_> {
    /// A transform that may only turn things: the environment is infinitely
    /// far away, so moving or scaling it would mean nothing.
    fn rotation(&self, value: Value, path: &str) -> Result<glam::Mat3> {
        let t = self.transform(value, path)?;
        let m = glam::Mat3::from_mat4(t.matrix);
        let translation = t.matrix.w_axis.truncate();
        let orthonormal = (m.transpose() * m).abs_diff_eq(glam::Mat3::IDENTITY, 1e-4);
        if translation != glam::Vec3::ZERO || !orthonormal || m.determinant() < 0.0 {
            return Err(self.err(
                path,
                "expected a rotation only (an environment is infinitely far away: \
                 it cannot be moved, scaled or mirrored)",
            ));
        }
        // Make it exactly orthonormal, so its transpose is its inverse.
        let x = m.x_axis.normalize();
        let y = (m.y_axis - x * x.dot(m.y_axis)).normalize();
        Ok(glam::Mat3::from_cols(x, y, x.cross(y)))
    }
}
