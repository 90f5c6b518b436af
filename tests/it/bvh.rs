//! The BVH must find exactly what testing every triangle finds.

use crate::common::{self, Rng};
use glam::Vec3;
use tracer::bvh::{BuildOptions, Bvh, Hit, WideBvh};
use tracer::geometry::shapes;
use tracer::geometry::triangle::RayShear;
use tracer::geometry::{Ray, Triangle};

fn brute_force(tris: &[Triangle], ray: &Ray) -> Option<Hit> {
    let shear = RayShear::new(ray.origin, ray.dir);
    let mut best: Option<Hit> = None;
    let mut tmax = ray.tmax;
    for (i, t) in tris.iter().enumerate() {
        if let Some(h) = shear.intersect(t, ray.tmin, tmax) {
            tmax = h.t;
            best = Some(Hit {
                triangle: i as u32,
                t: h.t,
                b1: h.b1,
                b2: h.b2,
            });
        }
    }
    best
}

fn mesh_triangles(mesh: &shapes::MeshData) -> Vec<Triangle> {
    mesh.indices
        .chunks(3)
        .map(|f| {
            let p = |i: usize| mesh.positions[f[i] as usize];
            Triangle::new(p(0), p(1), p(2))
        })
        .collect()
}

fn soup(rng: &mut Rng, n: usize, size: f32) -> Vec<Triangle> {
    (0..n)
        .map(|k| {
            let c = rng.vec3(-10.0, 10.0);
            let a = c + rng.vec3(-size, size);
            let b = c + rng.vec3(-size, size);
            match k % 17 {
                // Degenerate: a repeated vertex, and three collinear points.
                0 => Triangle::new(a, a, b),
                1 => Triangle::new(a, 0.5 * (a + b), b),
                _ => Triangle::new(a, b, c + rng.vec3(-size, size)),
            }
        })
        .collect()
}

fn random_ray(rng: &mut Rng, k: usize) -> Ray {
    let origin = rng.vec3(-12.0, 12.0);
    let mut dir = rng.unit_vector();
    // Every fourth ray is axis-parallel or lies in a coordinate plane, where
    // the slab test divides by zero.
    match k % 8 {
        0 => dir = Vec3::new(0.0, 0.0, dir.z.signum()),
        2 => dir = Vec3::new(dir.x, 0.0, dir.z).normalize(),
        4 => dir = Vec3::new(dir.x.signum(), 0.0, 0.0),
        6 => dir = Vec3::new(0.0, dir.y.signum(), 0.0),
        _ => {}
    }
    Ray::new(origin, dir)
}

/// The scalar binary BVH and the wide BVH over the same triangles: both
/// must answer every query exactly as brute force does.
struct Both {
    binary: Bvh,
    wide: WideBvh,
}

impl Both {
    fn build(tris: &[Triangle]) -> Both {
        Both::build_with(tris, &BuildOptions::default())
    }

    fn build_with(tris: &[Triangle], options: &BuildOptions) -> Both {
        Both {
            binary: Bvh::build_with(tris, options),
            wide: WideBvh::build_with(tris, options),
        }
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let hit = self.binary.intersect(ray);
        let wide = self.wide.intersect(ray);
        assert_eq!(
            hit.map(|h| h.t),
            wide.map(|h| h.t),
            "wide and binary BVH disagree on {ray:?}"
        );
        hit
    }
}

fn assert_same(tris: &[Triangle], bvh: &Both, ray: &Ray) {
    assert_same_in(
        tris,
        |r| bvh.binary.intersect(r),
        |r| bvh.binary.occluded(r),
        ray,
    );
    assert_same_in(
        tris,
        |r| bvh.wide.intersect(r),
        |r| bvh.wide.occluded(r),
        ray,
    );
}

fn assert_same_in(
    tris: &[Triangle],
    intersect: impl Fn(&Ray) -> Option<Hit>,
    occluded: impl Fn(&Ray) -> bool,
    ray: &Ray,
) {
    let expected = brute_force(tris, ray);
    let found = intersect(ray);
    match (expected, found) {
        (None, None) => {}
        (Some(e), Some(f)) => {
            assert_eq!(e.t, f.t, "distance differs for {ray:?}");
            if e.triangle != f.triangle {
                // Two triangles at exactly the same distance: either is right,
                // but the BVH's must really be hit there.
                let shear = RayShear::new(ray.origin, ray.dir);
                let h = shear
                    .intersect(&tris[f.triangle as usize], ray.tmin, ray.tmax)
                    .unwrap();
                assert_eq!(h.t, e.t, "BVH reported triangle {} for {ray:?}", f.triangle);
            }
        }
        (e, f) => panic!("brute force {e:?} but BVH {f:?} for {ray:?}"),
    }
    assert_eq!(
        occluded(ray),
        expected.is_some(),
        "any-hit disagrees for {ray:?}"
    );
}

#[test]
fn random_soups_match_brute_force() {
    let mut rng = Rng::new(7);
    for (n, size) in [(1, 3.0), (10, 3.0), (300, 2.0), (3000, 0.7)] {
        let tris = soup(&mut rng, n, size);
        for options in [
            BuildOptions::default(),
            BuildOptions {
                bins: 4,
                max_leaf_size: 1,
                parallel: false,
                spatial_split_budget: 0.0,
            },
            BuildOptions {
                spatial_split_budget: 1.0,
                ..BuildOptions::default()
            },
        ] {
            let bvh = Both::build_with(&tris, &options);
            for k in 0..2000 {
                let mut ray = random_ray(&mut rng, k);
                if k % 5 == 0 {
                    ray.tmax = rng.range(0.0, 20.0);
                }
                if k % 7 == 0 {
                    ray.tmin = rng.range(0.0, 5.0);
                }
                assert_same(&tris, &bvh, &ray);
            }
        }
    }
}

#[test]
fn rays_aimed_at_triangles_match_brute_force() {
    // Random rays mostly miss a sparse soup; aim at vertices and edges too.
    let mut rng = Rng::new(11);
    let tris = soup(&mut rng, 500, 1.5);
    let bvh = Both::build(&tris);
    for k in 0..5000 {
        let t = tris[k % tris.len()];
        let target = match k % 3 {
            0 => t.v[k % 3],
            1 => 0.5 * (t.v[0] + t.v[1]),
            _ => t.point(rng.f32() * 0.5, rng.f32() * 0.5),
        };
        let origin = rng.vec3(-15.0, 15.0);
        let ray = Ray::new(origin, (target - origin).normalize());
        assert_same(&tris, &bvh, &ray);
    }
}

#[test]
fn coplanar_grid_and_extreme_coordinates() {
    let mut rng = Rng::new(3);
    for scale in [1e-4f32, 1.0, 1e5] {
        // A grid of triangles all in the plane y = 0.
        let mut tris = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let p = |a: f32, b: f32| Vec3::new(a, 0.0, b) * scale;
                let (x, z) = (i as f32, j as f32);
                tris.push(Triangle::new(p(x, z), p(x, z + 1.0), p(x + 1.0, z + 1.0)));
                tris.push(Triangle::new(p(x, z), p(x + 1.0, z + 1.0), p(x + 1.0, z)));
            }
        }
        let bvh = Both::build(&tris);
        for k in 0..2000 {
            let origin = (rng.vec3(-2.0, 22.0) * Vec3::new(1.0, 0.0, 1.0)
                + Vec3::Y * rng.range(0.5, 5.0))
                * scale;
            let target = Vec3::new(rng.range(0.0, 20.0), 0.0, rng.range(0.0, 20.0)) * scale;
            let ray = Ray::new(origin, (target - origin).normalize());
            assert_same(&tris, &bvh, &ray);
            // Rays through the grid's vertices and edges must hit (watertight).
            let vertex = Vec3::new((k % 19 + 1) as f32, 0.0, (k / 19 % 19 + 1) as f32) * scale;
            let ray = Ray::new(origin, (vertex - origin).normalize());
            assert!(
                bvh.intersect(&ray).is_some(),
                "ray through a shared vertex at scale {scale} missed"
            );
            assert_same(&tris, &bvh, &ray);
        }
    }
}

#[test]
fn closed_mesh_is_watertight_from_inside() {
    let mesh = shapes::sphere(Vec3::new(0.3, -0.2, 0.1), 2.0, 3);
    let tris = mesh_triangles(&mesh);
    let bvh = Both::build(&tris);
    let mut rng = Rng::new(5);
    let center = Vec3::new(0.3, -0.2, 0.1);
    for k in 0..20000 {
        // Through vertices (shared by 5-6 triangles) and edge midpoints.
        let f = &mesh.indices[(k % (mesh.indices.len() / 3)) * 3..][..3];
        let p = |i: usize| mesh.positions[f[i] as usize];
        let target = if k % 2 == 0 {
            p(0)
        } else {
            0.5 * (p(1) + p(2))
        };
        let origin = center + rng.vec3(-0.5, 0.5);
        let ray = Ray::new(origin, (target - origin).normalize());
        assert!(
            bvh.intersect(&ray).is_some(),
            "ray {k} escaped the closed sphere"
        );
    }
}

#[test]
fn empty_and_single_triangle_scenes() {
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    let empty = Both::build(&[]);
    for (hit, occluded) in [
        (empty.binary.intersect(&ray), empty.binary.occluded(&ray)),
        (empty.wide.intersect(&ray), empty.wide.occluded(&ray)),
    ] {
        assert!(hit.is_none() && !occluded);
    }

    let one = [Triangle::new(
        Vec3::new(-1.0, -1.0, 5.0),
        Vec3::new(1.0, -1.0, 5.0),
        Vec3::new(0.0, 1.0, 5.0),
    )];
    let bvh = Both::build(&one);
    let hit = bvh.intersect(&ray).unwrap();
    assert_eq!((hit.triangle, hit.t), (0, 5.0));
    // tmax just short of the triangle, and tmin just past it.
    assert!(bvh.intersect(&Ray { tmax: 4.999, ..ray }).is_none());
    assert!(bvh.intersect(&Ray { tmin: 5.0, ..ray }).is_none());
    // A hit just beyond tmin is kept: the box tests honour the ray's own
    // tmin, with no fixed epsilon that would lose near hits.
    for tmin in [4.999, 4.99999] {
        assert!(
            bvh.intersect(&Ray { tmin, ..ray }).is_some(),
            "hit lost with tmin {tmin}"
        );
    }
    let near = Ray::new(Vec3::new(0.0, 0.0, 5.0 - 1e-5), Vec3::Z);
    assert_eq!(
        bvh.intersect(&near).map(|h| h.triangle),
        Some(0),
        "a hit 1e-5 away was lost"
    );
}

#[test]
fn sah_cost_is_reported_and_sensible() {
    let mut rng = Rng::new(1);
    let tris = soup(&mut rng, 5000, 0.3);
    let bvh = Both::build(&tris);
    let cost = bvh.binary.sah_cost();
    // A flat list would cost 5000 triangle tests; a good tree a few dozen.
    assert!(cost > 1.0 && cost < 100.0, "SAH cost {cost}");
    assert_eq!(bvh.binary.triangle_count(), 5000);
    // Four children and four triangles per test: fewer tests than binary.
    let report = bvh.wide.report();
    assert!(
        report.sah_cost > 1.0 && report.sah_cost < 0.7 * cost,
        "wide SAH cost {}",
        report.sah_cost
    );
    assert_eq!(report.triangles, 5000);
    assert_eq!(report.binary_sah_cost, cost);
    let blocks = bvh.wide.blocks();
    let ids: std::collections::BTreeSet<u32> = blocks
        .iter()
        .flat_map(|b| b.id)
        .filter(|&i| i != u32::MAX)
        .collect();
    assert_eq!(ids.len(), 5000, "every triangle in exactly one leaf");
}

/// Two wide BVHs with the same nodes and leaf blocks, in the same places.
fn assert_same_layout(a: &WideBvh, b: &WideBvh) {
    assert_eq!(a.nodes().len(), b.nodes().len());
    for (a, b) in a.nodes().iter().zip(b.nodes()) {
        assert_eq!((a.children, a.bounds), (b.children, b.bounds));
    }
    assert_eq!(a.blocks().len(), b.blocks().len());
    for (a, b) in a.blocks().iter().zip(b.blocks()) {
        assert_eq!((a.id, a.v), (b.id, b.v));
    }
}

/// Subtrees built in parallel are laid out exactly as the sequential builder
/// lays them out: the tree is a function of the triangles, not of the threads.
#[test]
fn parallel_build_equals_sequential_build() {
    let _guard = common::heavy();
    let mut rng = Rng::new(11);
    let tris = soup(&mut rng, 60_000, 0.05);
    let parallel = Bvh::build(&tris);
    let sequential = Bvh::build_with(
        &tris,
        &BuildOptions {
            parallel: false,
            ..BuildOptions::default()
        },
    );
    assert_eq!(parallel.nodes().len(), sequential.nodes().len());
    assert!(parallel.nodes() == sequential.nodes());
    // The wide BVH too: the collapse's tasks land in the same places
    // whether they run in parallel or one after another.
    let wide = WideBvh::build(&tris);
    let wide_sequential = WideBvh::build_with(
        &tris,
        &BuildOptions {
            parallel: false,
            ..BuildOptions::default()
        },
    );
    assert_same_layout(&wide, &wide_sequential);
    let both = Both {
        binary: parallel,
        wide,
    };
    for k in 0..2000 {
        assert_same(&tris, &both, &random_ray(&mut rng, k));
    }
}

/// Packets return, ray for ray, what single-ray traversal returns (closest
/// and any hits): coherent
/// packets (neighbouring camera rays), incoherent ones, partial packets, and
/// rays with their own tmin and tmax.
#[test]
fn packets_match_single_rays() {
    let mut rng = Rng::new(21);
    let mesh = shapes::sphere(Vec3::ZERO, 2.0, 4);
    let mut tris = mesh_triangles(&mesh);
    tris.extend(soup(&mut rng, 2000, 0.5));
    let bvh = WideBvh::build(&tris);
    let check = |rays: &[Ray]| {
        let packet = bvh.intersect_packet(rays);
        for (k, ray) in rays.iter().enumerate() {
            let single = bvh.intersect(ray);
            assert_eq!(
                packet[k].map(|h| (h.t, h.triangle)),
                single.map(|h| (h.t, h.triangle)),
                "ray {k} of a packet of {}: {ray:?}",
                rays.len()
            );
        }
        for hit in &packet[rays.len()..] {
            assert!(hit.is_none(), "a lane past the packet reported a hit");
        }
        let blocked = bvh.occluded_packet(rays);
        for (k, ray) in rays.iter().enumerate() {
            assert_eq!(
                blocked & (1 << k) != 0,
                bvh.occluded(ray),
                "any hit, ray {k} of a packet of {}: {ray:?}",
                rays.len()
            );
        }
        assert_eq!(
            blocked >> rays.len(),
            0,
            "a lane past the packet is blocked"
        );
    };
    for p in 0..500 {
        let origin = rng.vec3(-12.0, 12.0);
        let target = rng.vec3(-3.0, 3.0);
        let n = 1 + p % 8;
        let coherent: Vec<Ray> = (0..n)
            .map(|k| {
                let t = target + Vec3::new(0.05 * k as f32, 0.03 * (k % 3) as f32, 0.0);
                let mut ray = Ray::new(origin, (t - origin).normalize());
                if p % 5 == 0 {
                    ray.tmax = rng.range(5.0, 20.0);
                }
                if p % 7 == 0 {
                    ray.tmin = rng.range(0.0, 10.0);
                }
                ray
            })
            .collect();
        check(&coherent);
        let incoherent: Vec<Ray> = (0..n).map(|k| random_ray(&mut rng, p * 8 + k)).collect();
        check(&incoherent);
    }
    let empty = WideBvh::build(&[]);
    assert!(empty.intersect_packet(&[Ray::new(Vec3::ZERO, Vec3::Z)])[0].is_none());
    assert_eq!(empty.occluded_packet(&[Ray::new(Vec3::ZERO, Vec3::Z)]), 0);
}

#[test]
fn the_wide_bvh_bounds_are_exactly_the_triangles_bounds() {
    // The scene takes its bounds from the BVH instead of a pass over the
    // triangles, so the two must agree to the bit.
    use tracer::geometry::Aabb;
    for triangles in [
        tracer::bench::meshes::displaced_sphere(4),
        tracer::bench::meshes::city(9),
        Vec::new(),
    ] {
        let union = triangles
            .iter()
            .fold(Aabb::EMPTY, |a, t| a.union(Aabb::from_points(&t.v)));
        let bounds = tracer::bvh::WideBvh::build(&triangles).bounds();
        assert_eq!((bounds.min, bounds.max), (union.min, union.max));
    }
}

/// Long thin triangles crossing one another, in every orientation: where
/// spatial splits pay.
fn slivers(rng: &mut Rng, n: usize) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let a = rng.vec3(-10.0, 10.0);
            let b = a + rng.vec3(-8.0, 8.0);
            let c = a + rng.vec3(-0.3, 0.3);
            Triangle::new(a, b, c)
        })
        .collect()
}

/// Spatial splits cut triangles, and a cut triangle is found through
/// either of its references exactly as brute force finds it: closest hits,
/// any hits, both BVHs, rays in every direction and aimed at vertices and
/// edges, where a clipped box that rounding had shrunk would lose hits.
#[test]
fn spatial_splits_find_exactly_what_brute_force_finds() {
    let mut rng = Rng::new(23);
    // A city's ground plane and tall thin buildings, crossed by slivers.
    let mut tris: Vec<Triangle> = tracer::bench::meshes::city(16)
        .iter()
        .map(|t| {
            Triangle::new(
                t.v[0] - Vec3::new(8.0, 2.0, 8.0),
                t.v[1] - Vec3::new(8.0, 2.0, 8.0),
                t.v[2] - Vec3::new(8.0, 2.0, 8.0),
            )
        })
        .collect();
    tris.extend(slivers(&mut rng, 300));
    let plain = WideBvh::build(&tris);
    let options = BuildOptions {
        spatial_split_budget: 0.5,
        ..BuildOptions::default()
    };
    let bvh = Both::build_with(&tris, &options);
    let report = bvh.wide.report();
    assert_eq!(report.triangles, tris.len());
    assert!(
        report.references > tris.len() + tris.len() / 20,
        "spatial splits added only {} references",
        report.references - tris.len()
    );
    assert!(report.references <= tris.len() + tris.len() / 2);
    assert!(
        report.sah_cost < 0.95 * plain.report().sah_cost,
        "SAH cost {} with spatial splits, {} without",
        report.sah_cost,
        plain.report().sah_cost
    );
    for k in 0..4000 {
        let ray = if k % 2 == 0 {
            random_ray(&mut rng, k)
        } else {
            let t = tris[k % tris.len()];
            let target = match k % 3 {
                0 => t.v[k % 3],
                1 => 0.5 * (t.v[0] + t.v[1]),
                _ => t.point(rng.f32() * 0.5, rng.f32() * 0.5),
            };
            let origin = rng.vec3(-15.0, 15.0);
            Ray::new(origin, (target - origin).normalize())
        };
        bvh.intersect(&ray);
        assert_same(&tris, &bvh, &ray);
    }
}

/// With spatial splits too, the tree is a function of the triangles: built
/// on many threads or one, node for node the same.
#[test]
fn spatial_split_builds_do_not_depend_on_threads() {
    let _guard = common::heavy();
    let mut rng = Rng::new(5);
    let mut tris = slivers(&mut rng, 40_000);
    tris.extend(soup(&mut rng, 40_000, 0.05));
    let options = |parallel| BuildOptions {
        parallel,
        spatial_split_budget: 0.3,
        ..BuildOptions::default()
    };
    let parallel = Bvh::build_with(&tris, &options(true));
    let sequential = Bvh::build_with(&tris, &options(false));
    assert!(parallel.triangle_count() > tris.len());
    assert!(parallel.nodes() == sequential.nodes());
    let wide = WideBvh::build_with(&tris, &options(true));
    let wide_sequential = WideBvh::build_with(&tris, &options(false));
    assert_same_layout(&wide, &wide_sequential);
    let both = Both {
        binary: parallel,
        wide,
    };
    for k in 0..1000 {
        assert_same(&tris, &both, &random_ray(&mut rng, k));
    }
}

/// Big trees are traversed with prefetches of the children a ray defers;
/// the hits are the same with and without them.
#[test]
fn prefetching_traversal_finds_the_same_hits() {
    let mut rng = Rng::new(31);
    let tris = soup(&mut rng, 3000, 0.7);
    let mut bvh = Both::build(&tris);
    assert!(!bvh.wide.prefetches(), "a small tree stays in the caches");
    bvh.wide.set_prefetch(true);
    for k in 0..3000 {
        let mut ray = random_ray(&mut rng, k);
        if k % 5 == 0 {
            ray.tmax = rng.range(0.0, 20.0);
        }
        assert_same(&tris, &bvh, &ray);
    }
}
