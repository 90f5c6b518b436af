//! What a render records about itself beside its pixels: in an EXR's header
//! as `tracer.*` attributes, and for other formats in a JSON sidecar
//! (`image.png` → `image.png.json`). `tracer merge` reads it back to combine
//! partial renders and to refuse ones that do not belong together.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// In a JSON sidecar the keys are the EXR attributes' names without the
/// `tracer.` prefix (`sceneHash`, `maxSpp`, …); `samples` is a list of
/// `[first, count]` pairs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Metadata {
    /// `tracer` and its version.
    pub program: String,
    /// BLAKE3 of the scene's geometry inputs, camera, materials and lights.
    pub scene_hash: String,
    /// The integrator's name: `pt`, `lt`, `bdpt` or `vcm`.
    pub integrator: String,
    /// VCM's merging radius as set (`vcm_radius`); `None` for the default,
    /// which follows from the scene, and for the other integrators.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vcm_radius: Option<f32>,
    /// The seed every sample was drawn from.
    pub seed: u64,
    /// The most path segments a path could have.
    pub max_depth: u32,
    /// The full image's size; a crop is part of it.
    pub width: u32,
    /// The full image's height, in pixels.
    pub height: u32,
    /// The pixels this image holds: x0, y0, x1, y1 (upper bounds exclusive).
    pub crop: [u32; 4],
    /// Samples per pixel (the fewest any pixel got).
    pub spp: u32,
    /// The most any pixel got: above `spp` when a render was interrupted
    /// in the middle of a pass, or sampled adaptively.
    pub max_spp: u32,
    /// The sample indices every pixel holds, as (first, count) runs: one
    /// run for a render, several for a merge of renders with offsets.
    pub samples: Vec<(u32, u32)>,
    /// Wall-clock seconds spent rendering (summed over the renders merged).
    pub render_seconds: f64,
    /// Progressive passes taken (the most of any render merged).
    pub passes: u32,
    /// What ended the render: `spp`, `time-limit`, `target-noise`,
    /// `interrupted`, `merge`, or `in progress` for a checkpoint.
    pub stopped_by: String,
    /// The last estimate of the mean relative error, if there was one.
    pub noise: Option<f64>,
    /// In a sidecar: BLAKE3 of the image's linear pixels, so a sidecar left
    /// beside an older version of its image is noticed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixels_hash: Option<String>,
}

/// BLAKE3 of an image's size and linear pixels.
pub fn pixels_hash(image: &super::Image) -> String {
    let mut h = blake3::Hasher::new();
    h.update(&image.width.to_le_bytes());
    h.update(&image.height.to_le_bytes());
    for p in &image.pixels {
        for v in p.to_array() {
            h.update(&v.to_le_bytes());
        }
    }
    h.finalize().to_hex().to_string()
}

/// This program's name and version, as [`Metadata::program`] records it.
pub fn program() -> String {
    format!("tracer {}", env!("CARGO_PKG_VERSION"))
}

/// The sidecar that carries the metadata of an image that has no room for it.
pub fn sidecar_path(image: &Path) -> PathBuf {
    let mut name = image.file_name().unwrap_or_default().to_os_string();
    name.push(".json");
    image.with_file_name(name)
}

const PREFIX: &str = "tracer.";

impl Metadata {
    /// `tracer.*` EXR header attributes: numbers as numbers where EXR has
    /// the type, everything else as text.
    pub fn exr_attributes(&self) -> Vec<(String, exr::meta::attribute::AttributeValue)> {
        use exr::meta::attribute::{AttributeValue as A, Text};
        let text = |s: &str| A::Text(Text::new_or_none(s).unwrap_or_else(|| Text::from("?")));
        let mut out = vec![
            ("program", text(&self.program)),
            ("sceneHash", text(&self.scene_hash)),
            ("integrator", text(&self.integrator)),
            ("seed", text(&self.seed.to_string())),
            ("maxDepth", A::I32(self.max_depth as i32)),
            ("width", A::I32(self.width as i32)),
            ("height", A::I32(self.height as i32)),
            (
                "crop",
                text(&format!(
                    "{},{},{},{}",
                    self.crop[0], self.crop[1], self.crop[2], self.crop[3]
                )),
            ),
            ("spp", A::I32(self.spp as i32)),
            ("maxSpp", A::I32(self.max_spp as i32)),
            ("samples", text(&runs_text(&self.samples))),
            ("renderSeconds", A::F64(self.render_seconds)),
            ("passes", A::I32(self.passes as i32)),
            ("stoppedBy", text(&self.stopped_by)),
        ];
        if let Some(n) = self.noise {
            out.push(("noise", A::F64(n)));
        }
        if let Some(r) = self.vcm_radius {
            out.push(("vcmRadius", A::F32(r)));
        }
        out.into_iter()
            .map(|(k, v)| (format!("{PREFIX}{k}"), v))
            .collect()
    }

    /// Reads the attributes [`Metadata::exr_attributes`] wrote; `Err` names
    /// the first one missing or malformed.
    pub fn from_exr_attributes(
        attributes: &std::collections::HashMap<
            exr::meta::attribute::Text,
            exr::meta::attribute::AttributeValue,
        >,
    ) -> Result<Metadata, String> {
        use exr::meta::attribute::AttributeValue as A;
        let get = |k: &str| {
            attributes
                .get(format!("{PREFIX}{k}").as_bytes())
                .ok_or_else(|| format!("no {PREFIX}{k} attribute (not written by tracer?)"))
        };
        let text = |k: &str| -> Result<String, String> {
            match get(k)? {
                A::Text(t) => Ok(t.to_string()),
                _ => Err(format!("{PREFIX}{k} is not text")),
            }
        };
        let int = |k: &str| -> Result<u32, String> {
            match get(k)? {
                A::I32(v) if *v >= 0 => Ok(*v as u32),
                _ => Err(format!("{PREFIX}{k} is not a non-negative integer")),
            }
        };
        let float = |k: &str| -> Result<f64, String> {
            match get(k)? {
                A::F64(v) => Ok(*v),
                A::F32(v) => Ok(*v as f64),
                _ => Err(format!("{PREFIX}{k} is not a number")),
            }
        };
        let crop = text("crop")?;
        let crop: Vec<u32> = crop
            .split(',')
            .map(|v| v.trim().parse())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("{PREFIX}crop is not four integers"))?;
        let crop: [u32; 4] = crop
            .try_into()
            .map_err(|_| format!("{PREFIX}crop is not four integers"))?;
        Ok(Metadata {
            program: text("program")?,
            scene_hash: text("sceneHash")?,
            integrator: text("integrator")?,
            vcm_radius: match get("vcmRadius") {
                Ok(A::F32(r)) => Some(*r),
                Ok(_) => return Err(format!("{PREFIX}vcmRadius is not a number")),
                Err(_) => None,
            },
            seed: text("seed")?
                .parse()
                .map_err(|_| format!("{PREFIX}seed is not an integer"))?,
            max_depth: int("maxDepth")?,
            width: int("width")?,
            height: int("height")?,
            crop,
            spp: int("spp")?,
            max_spp: int("maxSpp")?,
            samples: parse_runs(&text("samples")?)
                .ok_or_else(|| format!("{PREFIX}samples is malformed"))?,
            render_seconds: float("renderSeconds")?,
            passes: int("passes")?,
            stopped_by: text("stoppedBy")?,
            noise: get("noise").ok().and_then(|_| float("noise").ok()),
            pixels_hash: None,
        })
    }
}

/// `0+16,32+16`: runs of sample indices.
fn runs_text(runs: &[(u32, u32)]) -> String {
    runs.iter()
        .map(|(first, count)| format!("{first}+{count}"))
        .collect::<Vec<_>>()
        .join(",")
}

fn parse_runs(s: &str) -> Option<Vec<(u32, u32)>> {
    if s.is_empty() {
        return Some(Vec::new());
    }
    s.split(',')
        .map(|run| {
            let (a, b) = run.split_once('+')?;
            Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
        })
        .collect()
}

/// Sorts runs and joins those that touch or overlap.
pub fn normalize_runs(runs: &[(u32, u32)]) -> Vec<(u32, u32)> {
    let mut sorted: Vec<(u64, u64)> = runs
        .iter()
        .filter(|r| r.1 > 0)
        .map(|&(a, n)| (a as u64, a as u64 + n as u64))
        .collect();
    sorted.sort();
    let mut out: Vec<(u64, u64)> = Vec::new();
    for (a, b) in sorted {
        match out.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => out.push((a, b)),
        }
    }
    out.into_iter()
        .map(|(a, b)| (a as u32, (b - a) as u32))
        .collect()
}

/// Whether two sets of runs share a sample index.
pub fn runs_overlap(a: &[(u32, u32)], b: &[(u32, u32)]) -> bool {
    a.iter().any(|&(a0, an)| {
        b.iter().any(|&(b0, bn)| {
            let (a1, b1) = (a0 as u64 + an as u64, b0 as u64 + bn as u64);
            (a0 as u64) < b1 && (b0 as u64) < a1
        })
    })
}
