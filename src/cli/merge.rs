//! `tracer merge`: combines partial renders of one scene — crops of the
//! image, disjoint sample ranges of the same pixels (`--sample-offset`), or
//! both — into one image. Each pixel is the mean of the inputs that cover
//! it, weighted by their samples per pixel, which is exactly the estimate
//! one render of all those samples makes.

use clap::Args;
use glam::DVec3;
use std::path::{Path, PathBuf};
use tracer::film::metadata::{normalize_runs, program, runs_overlap, Metadata};
use tracer::film::read::read_with_metadata;
use tracer::film::tonemap::Tonemap;
use tracer::film::write::write_image_with;
use tracer::film::Image;
use tracer::{Error, Result};

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Partial renders: EXR (or PFM with its JSON sidecar) written by `tracer render`.
    #[arg(required = true, num_args = 1..)]
    pub inputs: Vec<PathBuf>,
    /// The merged image (.exr keeps the metadata in its header; other
    /// formats get a JSON sidecar).
    #[arg(short, long)]
    pub output: PathBuf,
}

struct Part {
    path: PathBuf,
    image: Image,
    meta: Metadata,
}

fn refuse(path: &Path, message: String) -> Error {
    Error::Image {
        path: path.to_path_buf(),
        message,
    }
}

pub fn run_merge(args: &MergeArgs) -> Result<i32> {
    let mut parts = Vec::new();
    for path in &args.inputs {
        let (image, meta) = read_with_metadata(path)?;
        parts.push(Part {
            path: path.clone(),
            image,
            meta,
        });
    }
    let (image, meta) = merge(&parts)?;
    write_image_with(&args.output, &image, Tonemap::Srgb, 0.0, Some(&meta))?;
    eprintln!(
        "merged {} renders into {}: {}x{}, {} spp",
        parts.len(),
        args.output.display(),
        image.width,
        image.height,
        meta.spp
    );
    Ok(0)
}

fn merge(parts: &[Part]) -> Result<(Image, Metadata)> {
    let first = &parts[0];
    let m0 = &first.meta;
    for p in parts {
        check_part(p, first)?;
    }
    check_disjoint(parts)?;
    let (w, h) = (m0.width, m0.height);
    let mut sums = vec![DVec3::ZERO; w as usize * h as usize];
    let mut counts = vec![0u64; w as usize * h as usize];
    for p in parts {
        let [x0, y0, x1, y1] = p.meta.crop;
        let spp = p.meta.spp as u64;
        for y in y0..y1 {
            for x in x0..x1 {
                let k = (y * w + x) as usize;
                sums[k] += p.image.get(x - x0, y - y0).as_dvec3() * spp as f64;
                counts[k] += spp;
            }
        }
    }
    if let Some(k) = counts.iter().position(|&c| c == 0) {
        return Err(Error::Merge(format!(
            "the inputs leave pixel ({}, {}) uncovered: merge needs crops that cover the {w}x{h} image",
            k as u32 % w,
            k as u32 / w
        )));
    }
    if counts.iter().any(|&c| c != counts[0]) {
        return Err(Error::Merge(
            "the inputs give different pixels different sample counts: merge crops of equal samples, or equal crops of disjoint samples".into(),
        ));
    }
    let mut image = Image::new(w, h);
    for (k, p) in image.pixels.iter_mut().enumerate() {
        *p = (sums[k] / counts[k] as f64).as_vec3();
    }
    let samples: Vec<(u32, u32)> = normalize_runs(
        &parts
            .iter()
            .flat_map(|p| p.meta.samples.iter().copied())
            .collect::<Vec<_>>(),
    );
    let meta = Metadata {
        program: program(),
        crop: [0, 0, w, h],
        spp: counts[0] as u32,
        max_spp: counts[0] as u32,
        samples,
        render_seconds: parts.iter().map(|p| p.meta.render_seconds).sum(),
        passes: parts.iter().map(|p| p.meta.passes).max().unwrap_or(0),
        stopped_by: "merge".into(),
        noise: None,
        pixels_hash: None,
        ..m0.clone()
    };
    Ok((image, meta))
}

/// Refuses a part that is not of the same render as `first`, or whose
/// metadata does not describe its own pixels.
fn check_part(p: &Part, first: &Part) -> Result<()> {
    let m0 = &first.meta;
    let m = &p.meta;
    let differs = |what: &str, a: String, b: String| {
        refuse(
            &p.path,
            format!(
                "{what} is {a}, but {} has {b}: not parts of the same render",
                first.path.display()
            ),
        )
    };
    if m.scene_hash != m0.scene_hash {
        return Err(differs(
            "the scene",
            m.scene_hash.clone(),
            m0.scene_hash.clone(),
        ));
    }
    for (what, a, b) in [
        (
            "the integrator",
            m.integrator.clone(),
            m0.integrator.clone(),
        ),
        ("the seed", m.seed.to_string(), m0.seed.to_string()),
        (
            "the VCM radius",
            format!("{:?}", m.vcm_radius),
            format!("{:?}", m0.vcm_radius),
        ),
        (
            "the maximum depth",
            m.max_depth.to_string(),
            m0.max_depth.to_string(),
        ),
        (
            "the image size",
            format!("{}x{}", m.width, m.height),
            format!("{}x{}", m0.width, m0.height),
        ),
        ("the program", m.program.clone(), m0.program.clone()),
    ] {
        if a != b {
            return Err(differs(what, a, b));
        }
    }
    if m.scene_hash.len() != 64 {
        return Err(refuse(
            &p.path,
            format!(
                "has no scene hash ({:?}): nothing to check it against",
                m.scene_hash
            ),
        ));
    }
    if p.image.pixels.iter().any(|c| !c.is_finite()) {
        return Err(refuse(&p.path, "holds NaN or infinite pixels".into()));
    }
    if m.max_spp != m.spp {
        return Err(refuse(
            &p.path,
            format!(
                "holds {} to {} samples per pixel (an interrupted or adaptive render): its pixels cannot be weighted alike",
                m.spp, m.max_spp
            ),
        ));
    }
    let [x0, y0, x1, y1] = m.crop;
    let (cw, ch) = (x1.saturating_sub(x0), y1.saturating_sub(y0));
    if x1 > m.width || y1 > m.height || (cw, ch) != (p.image.width, p.image.height) {
        return Err(refuse(
            &p.path,
            format!(
                "is {}x{}, but its metadata says crop {x0},{y0},{x1},{y1} of {}x{}",
                p.image.width, p.image.height, m.width, m.height
            ),
        ));
    }
    let ranges: u32 = m.samples.iter().map(|r| r.1).sum();
    if ranges != m.spp || m.spp == 0 {
        return Err(refuse(
            &p.path,
            format!(
                "holds {} samples per pixel but sample ranges of {ranges}",
                m.spp
            ),
        ));
    }
    Ok(())
}

/// Refuses parts that share samples of the same pixels.
fn check_disjoint(parts: &[Part]) -> Result<()> {
    // The same sample of the same pixel twice would count it double.
    for (i, a) in parts.iter().enumerate() {
        for b in &parts[i + 1..] {
            if crops_overlap(a.meta.crop, b.meta.crop)
                && runs_overlap(&a.meta.samples, &b.meta.samples)
            {
                return Err(refuse(
                    &b.path,
                    format!(
                        "holds some of the same samples of the same pixels as {} (give each process its own --sample-offset)",
                        a.path.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn crops_overlap(a: [u32; 4], b: [u32; 4]) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}
