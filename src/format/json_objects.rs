//! The `objects` section of a JSON scene: shapes, their transforms,
//! materials and emission.

use super::desc::*;
use super::json::Ctx;
use super::resolve;
use crate::geometry::transform::Transform;
use crate::Result;
use glam::Vec3;
use serde::Deserialize;
use serde_json::{Map, Value};

/// The largest icosphere level accepted: 20 × 4^10 ≈ 21 M triangles.
pub const MAX_SUBDIVISIONS: u32 = 10;

// The own keys of each object type.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Mesh {
    file: String,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Empty {}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Sphere {
    #[serde(default)]
    center: Option<V3>,
    #[serde(default)]
    radius: Option<Positive>,
    #[serde(default)]
    subdivisions: Option<u32>,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Triangles {
    positions: Vec<V3>,
    #[serde(default)]
    indices: Option<Vec<u32>>,
    #[serde(default)]
    normals: Option<Vec<V3>>,
    #[serde(default)]
    uvs: Option<Vec<V2>>,
}

impl Ctx<'_> {
    pub(super) fn object(&self, value: &Value, path: &str) -> Result<ObjectDesc> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Common {
            #[serde(default)]
            material: Option<String>,
            #[serde(default)]
            transform: Option<Value>,
            #[serde(default)]
            emission: Option<Color>,
            #[serde(default)]
            two_sided: bool,
        }
        const COMMON: [&str; 4] = ["material", "transform", "emission", "two_sided"];

        let (kind, mut map) = self.tagged(
            value,
            path,
            &["mesh", "quad", "cube", "sphere", "triangles"],
        )?;
        let mut common_map = Map::new();
        for key in COMMON {
            if let Some(v) = map.remove(key) {
                common_map.insert(key.to_string(), v);
            }
        }
        let common: Common = self.typed(Value::Object(common_map), path)?;
        let own_keys: &[&str] = match kind.as_str() {
            "mesh" => &["file"],
            "sphere" => &["center", "radius", "subdivisions"],
            "triangles" => &["positions", "indices", "normals", "uvs"],
            _ => &[],
        };
        if let Some(unknown) = map.keys().find(|k| !own_keys.contains(&k.as_str())) {
            let allowed: Vec<&str> = own_keys.iter().chain(COMMON.iter()).copied().collect();
            return Err(self.err(
                &format!("{path}.{unknown}"),
                format!("unknown key, a {kind} takes: {}", allowed.join(", ")),
            ));
        }
        let shape = self.shape(&kind, Value::Object(map), path)?;
        let transform = match common.transform {
            None => Transform::IDENTITY,
            Some(v) => self.transform(v, &format!("{path}.transform"))?,
        };
        Ok(ObjectDesc {
            key_path: path.to_string(),
            shape,
            material: common.material,
            transform,
            emission: common.emission.map(|c| c.0),
            two_sided: common.two_sided,
        })
    }

    /// The shape of an object of type `kind`, from its own keys (`rest`).
    fn shape(&self, kind: &str, rest: Value, path: &str) -> Result<ShapeDesc> {
        Ok(match kind {
            "mesh" => {
                let m: Mesh = self.typed(rest, path)?;
                ShapeDesc::Mesh {
                    file: resolve(self.file, &m.file),
                    mtl_override: None,
                }
            }
            "quad" => {
                self.typed::<Empty>(rest, path)?;
                ShapeDesc::Quad
            }
            "cube" => {
                self.typed::<Empty>(rest, path)?;
                ShapeDesc::Cube
            }
            "sphere" => {
                let s: Sphere = self.typed(rest, path)?;
                let subdivisions = s.subdivisions.unwrap_or(4);
                if subdivisions > MAX_SUBDIVISIONS {
                    return Err(self.err(
                    &format!("{path}.subdivisions"),
                    format!("expected at most {MAX_SUBDIVISIONS} (20 × 4^{MAX_SUBDIVISIONS} triangles), found {subdivisions}"),
                ));
                }
                ShapeDesc::Sphere {
                    center: s.center.map_or(Vec3::ZERO, |c| c.0),
                    radius: s.radius.map_or(1.0, |r| r.0),
                    subdivisions,
                }
            }
            _ => {
                let t: Triangles = self.typed(rest, path)?;
                self.check_triangles(&t.positions, &t.indices, &t.normals, &t.uvs, path)?;
                ShapeDesc::Triangles {
                    positions: t.positions.into_iter().map(|p| p.0).collect(),
                    indices: t.indices,
                    normals: t.normals.map(|n| n.into_iter().map(|n| n.0).collect()),
                    uvs: t.uvs.map(|u| u.into_iter().map(|u| u.0).collect()),
                }
            }
        })
    }

    fn check_triangles(
        &self,
        positions: &[V3],
        indices: &Option<Vec<u32>>,
        normals: &Option<Vec<V3>>,
        uvs: &Option<Vec<V2>>,
        path: &str,
    ) -> Result<()> {
        let n = positions.len();
        let count = indices.as_ref().map_or(n, Vec::len);
        if count == 0 || !count.is_multiple_of(3) {
            let key = if indices.is_some() {
                "indices"
            } else {
                "positions"
            };
            return Err(self.err(
                &format!("{path}.{key}"),
                format!(
                    "expected a non-empty multiple of 3 entries (whole triangles), found {count}"
                ),
            ));
        }
        if let Some(idx) = indices {
            if let Some((i, &bad)) = idx.iter().enumerate().find(|(_, &k)| k as usize >= n) {
                return Err(self.err(
                    &format!("{path}.indices[{i}]"),
                    format!("index {bad} is out of range: there are {n} positions"),
                ));
            }
        }
        if let Some(normals) = normals {
            if normals.len() != n {
                return Err(self.err(
                    &format!("{path}.normals"),
                    format!(
                        "expected one normal per position ({n}), found {}",
                        normals.len()
                    ),
                ));
            }
        }
        if let Some(uvs) = uvs {
            if uvs.len() != n {
                return Err(self.err(
                    &format!("{path}.uvs"),
                    format!("expected one UV per position ({n}), found {}", uvs.len()),
                ));
            }
        }
        Ok(())
    }

    pub(super) fn transform(&self, value: Value, path: &str) -> Result<Transform> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct TransformFile {
            #[serde(default)]
            matrix: Option<[Finite; 16]>,
            #[serde(default)]
            scale: Option<Value>,
            #[serde(default)]
            rotate: Option<[Finite; 4]>,
            #[serde(default)]
            translate: Option<V3>,
        }
        let t: TransformFile = self.typed(value, path)?;
        let singular = || {
            self.err(
                path,
                "the transform is singular (it flattens the object to zero volume)",
            )
        };
        if let Some(m) = t.matrix {
            if t.scale.is_some() || t.rotate.is_some() || t.translate.is_some() {
                return Err(self.err(
                    path,
                    "give either \"matrix\" or scale/rotate/translate, not both",
                ));
            }
            let rows: Vec<f32> = m.iter().map(|x| x.0).collect();
            let matrix = glam::Mat4::from_cols_slice(&rows).transpose();
            let bottom = matrix.row(3);
            if bottom != glam::Vec4::new(0.0, 0.0, 0.0, 1.0) {
                return Err(self.err(
                    &format!("{path}.matrix"),
                    "expected an affine matrix: the last row must be [0, 0, 0, 1]",
                ));
            }
            return Transform::new(matrix).ok_or_else(singular);
        }
        let scale = match t.scale {
            None => Vec3::ONE,
            Some(Value::Array(a)) => {
                self.typed::<V3>(Value::Array(a), &format!("{path}.scale"))?
                    .0
            }
            Some(v) => Vec3::splat(self.typed::<Finite>(v, &format!("{path}.scale"))?.0),
        };
        if scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0 {
            return Err(self.err(&format!("{path}.scale"), "expected non-zero scale factors"));
        }
        let rotation = match t.rotate {
            None => None,
            Some([x, y, z, deg]) => {
                let axis = Vec3::new(x.0, y.0, z.0);
                if axis.length_squared() == 0.0 {
                    return Err(self.err(
                        &format!("{path}.rotate"),
                        "expected a non-zero rotation axis",
                    ));
                }
                Some((axis, deg.0))
            }
        };
        Transform::from_srt(scale, rotation, t.translate.map_or(Vec3::ZERO, |v| v.0))
            .ok_or_else(singular)
    }
}
