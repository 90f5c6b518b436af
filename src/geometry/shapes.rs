//! The contract's built-in shapes, as indexed triangle meshes in object space.

use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// An indexed triangle mesh before it is transformed into the scene.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertex positions, in object space.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, if the shape has smooth normals.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the shape has them; `None` maps
    /// every vertex to (0, 0).
    pub uvs: Option<Vec<Vec2>>,
    /// Three indices per triangle, counter-clockwise seen from the front.
    pub indices: Vec<u32>,
}

/// Unit square in the xz-plane centred at the origin, facing +y.
pub fn quad() -> MeshData {
    MeshData {
        positions: vec![
            Vec3::new(-0.5, 0.0, -0.5),
            Vec3::new(-0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, -0.5),
        ],
        normals: None,
        // u along +x, v along −z: seen from the front (+y), the texture is upright, not mirrored.
        uvs: Some(vec![
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
        ]),
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// Unit cube centred at the origin, faces pointing outwards, flat shaded.
pub fn cube() -> MeshData {
    let mut mesh = MeshData {
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    // Each face: its outward normal and two in-plane axes whose cross product is that normal.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    for (n, a, b) in faces {
        debug_assert!(a.cross(b).abs_diff_eq(n, 1e-6));
        let base = mesh.positions.len() as u32;
        for (s, t) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
            mesh.positions.push(0.5 * n + s * a + t * b);
            mesh.uvs.as_mut().unwrap().push(Vec2::new(s + 0.5, t + 0.5));
        }
        mesh.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    mesh
}

/// Icosphere: an icosahedron subdivided `level` times and projected onto the
/// sphere, with smooth normals and a latitude–longitude UV mapping.
pub fn sphere(center: Vec3, radius: f32, level: u32) -> MeshData {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut dirs: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, dirs: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *midpoints.entry(key).or_insert_with(|| {
                dirs.push((dirs[a as usize] + dirs[b as usize]).normalize());
                dirs.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut dirs);
            let bc = midpoint(b, c, &mut dirs);
            let ca = midpoint(c, a, &mut dirs);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    // Longitude–latitude UVs: v = 1 at the north pole, u increasing eastwards
    // as seen from outside, so the texture is upright and not mirrored.
    let uv_of = |d: Vec3| {
        Vec2::new(
            0.5 + (-d.z).atan2(d.x) / (2.0 * std::f32::consts::PI),
            0.5 + d.y.clamp(-1.0, 1.0).asin() / std::f32::consts::PI,
        )
    };
    let mut uvs: Vec<Vec2> = dirs.iter().map(|&d| uv_of(d)).collect();
    // Triangles that straddle the u = 0/1 seam would interpolate u across the
    // whole texture: give them copies of their low-u vertices with u + 1.
    let mut seam_copies: HashMap<u32, u32> = HashMap::new();
    for f in faces.iter_mut() {
        let us = f.map(|i| uvs[i as usize].x);
        let (lo, hi) = (
            us.iter().cloned().fold(1.0, f32::min),
            us.iter().cloned().fold(0.0, f32::max),
        );
        if hi - lo <= 0.5 {
            continue;
        }
        for i in f.iter_mut() {
            if uvs[*i as usize].x < 0.5 {
                *i = *seam_copies.entry(*i).or_insert_with(|| {
                    dirs.push(dirs[*i as usize]);
                    uvs.push(uvs[*i as usize] + Vec2::X);
                    dirs.len() as u32 - 1
                });
            }
        }
    }
    MeshData {
        positions: dirs.iter().map(|&d| center + radius * d).collect(),
        normals: Some(dirs),
        uvs: Some(uvs),
        indices: faces.into_iter().flatten().collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face_normals(m: &MeshData) -> Vec<(Vec3, Vec3)> {
        m.indices
            .chunks(3)
            .map(|f| {
                let p = |i: u32| m.positions[i as usize];
                let n = (p(f[1]) - p(f[0])).cross(p(f[2]) - p(f[0]));
                (n, (p(f[0]) + p(f[1]) + p(f[2])) / 3.0)
            })
            .collect()
    }

    #[test]
    fn quad_faces_up() {
        for (n, _) in face_normals(&quad()) {
            assert!(n.normalize().abs_diff_eq(Vec3::Y, 1e-6));
        }
    }

    /// Seen from the front, +u must point right and +v up (not mirrored):
    /// the UV axes' cross product points along the face normal.
    #[test]
    fn textures_are_upright_and_seamless() {
        for mesh in [quad(), cube(), sphere(Vec3::ZERO, 1.0, 3)] {
            let uv = mesh.uvs.as_ref().unwrap();
            for f in mesh.indices.chunks(3) {
                let (p, t) = (
                    |i: usize| mesh.positions[f[i] as usize],
                    |i: usize| uv[f[i] as usize],
                );
                let (e1, e2) = (p(1) - p(0), p(2) - p(0));
                let (d1, d2) = (t(1) - t(0), t(2) - t(0));
                let det = d1.x * d2.y - d1.y * d2.x;
                let du = (e1 * d2.y - e2 * d1.y) / det;
                let dv = (e2 * d1.x - e1 * d2.x) / det;
                assert!(du.cross(dv).dot(e1.cross(e2)) > 0.0, "mirrored texture");
            }
        }
        let s = sphere(Vec3::ZERO, 1.0, 3);
        let uv = s.uvs.as_ref().unwrap();
        for f in s.indices.chunks(3) {
            // Near the poles longitude changes fast; elsewhere a wide u range
            // means the triangle interpolates across the seam.
            let polar = f.iter().any(|&i| s.positions[i as usize].y.abs() > 0.9);
            let us = [0, 1, 2].map(|k| uv[f[k] as usize].x);
            let spread = us.iter().cloned().fold(f32::MIN, f32::max)
                - us.iter().cloned().fold(f32::MAX, f32::min);
            assert!(polar || spread < 0.5, "triangle spans the seam: u = {us:?}");
        }
        let top = s
            .positions
            .iter()
            .zip(s.uvs.unwrap())
            .max_by(|a, b| a.0.y.total_cmp(&b.0.y))
            .unwrap();
        assert!(top.1.y > 0.8, "north pole at the top of the texture");
    }

    #[test]
    fn cube_and_sphere_face_outwards() {
        for (n, c) in face_normals(&cube())
            .into_iter()
            .chain(face_normals(&sphere(Vec3::ZERO, 1.0, 2)))
        {
            assert!(n.dot(c) > 0.0, "inward face at {c}");
        }
        assert_eq!(sphere(Vec3::ZERO, 1.0, 2).indices.len(), 20 * 16 * 3);
    }
}
