//! Procedural meshes for benchmarks, so that every machine can measure the
//! same geometry without downloading anything.

use crate::geometry::shapes;
use crate::geometry::Triangle;
use crate::sampling::sampler::hash;
use glam::Vec3;

/// An icosphere of `20 · 4^level` triangles (level 8: 1.3 M), its radius
/// displaced by a sum of waves, so that neighbouring triangles differ in
/// orientation and size as on a scanned model.
pub fn displaced_sphere(level: u32) -> Vec<Triangle> {
    let mesh = shapes::sphere(Vec3::ZERO, 1.0, level);
    let displace = |p: Vec3| {
        let bumps = (7.0 * p.x).sin() * (5.0 * p.y).cos() * 0.08
            + (23.0 * p.z + 3.0 * p.x).sin() * 0.02
            + (61.0 * p.y - 17.0 * p.z).sin() * 0.005;
        p * (1.0 + bumps)
    };
    let positions: Vec<Vec3> = mesh.positions.iter().map(|&p| displace(p)).collect();
    mesh.indices
        .chunks_exact(3)
        .map(|f| {
            Triangle::new(
                positions[f[0] as usize],
                positions[f[1] as usize],
                positions[f[2] as usize],
            )
        })
        .collect()
}

/// A city: `blocks × blocks` lots, each with a box building of random
/// footprint and a heavy-tailed random height, on a ground plane. Many
/// long, thin, overlapping boxes: a hard case for a BVH.
pub fn city(blocks: u32) -> Vec<Triangle> {
    let mut state = 7u32;
    let mut next = || {
        state = hash(state.wrapping_add(0x9e37_79b9));
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut tris = Vec::with_capacity(blocks as usize * blocks as usize * 12 + 2);
    let size = blocks as f32;
    quad(
        &mut tris,
        Vec3::ZERO,
        Vec3::new(size, 0.0, 0.0),
        Vec3::new(0.0, 0.0, size),
    );
    for i in 0..blocks {
        for j in 0..blocks {
            let w = 0.3 + 0.6 * next();
            let d = 0.3 + 0.6 * next();
            let h = 0.2 + 4.0 * next().powi(4) * 10.0;
            let x = i as f32 + (1.0 - w) * next();
            let z = j as f32 + (1.0 - d) * next();
            boxed(&mut tris, Vec3::new(x, 0.0, z), Vec3::new(x + w, h, z + d));
        }
    }
    tris
}

fn quad(tris: &mut Vec<Triangle>, corner: Vec3, a: Vec3, b: Vec3) {
    tris.push(Triangle::new(corner, corner + a, corner + a + b));
    tris.push(Triangle::new(corner, corner + a + b, corner + b));
}

/// The six faces of an axis-aligned box.
fn boxed(tris: &mut Vec<Triangle>, lo: Vec3, hi: Vec3) {
    let e = hi - lo;
    let (x, y, z) = (Vec3::X * e.x, Vec3::Y * e.y, Vec3::Z * e.z);
    quad(tris, lo, z, x);
    quad(tris, lo + y, x, z);
    quad(tris, lo, x, y);
    quad(tris, lo + z, y, x);
    quad(tris, lo, y, z);
    quad(tris, lo + x, z, y);
}

/// The triangles of an OBJ file, all groups together.
pub fn obj_triangles(path: &std::path::Path) -> Result<Vec<Triangle>, String> {
    let obj = crate::format::obj::load_obj(path, None)?;
    Ok(obj
        .groups
        .iter()
        .flat_map(|g| {
            let m = &g.mesh;
            m.indices.chunks_exact(3).map(move |f| {
                Triangle::new(
                    m.positions[f[0] as usize],
                    m.positions[f[1] as usize],
                    m.positions[f[2] as usize],
                )
            })
        })
        .collect())
}
