//! Light sampling. An area light's `sample_incident` chooses directions
//! with the solid-angle density it reports, which integrates to one over
//! the triangle as seen from the receiver (chi-square tests over the cap of
//! directions that holds the triangle); delta lights (point, spot,
//! directional) have no density, so their incident light is checked
//! against the closed forms I/d², the spot's falloff, and E. Starting light
//! paths (`sample_emission`) is tested the same way: each light's emitted
//! directions (and the area and directional lights' origins) against the
//! densities they report. The environment's directions, for light
//! sampling and for light paths, are checked the same way.

use crate::common::chi_square::{self, PlaneGrid, SphereGrid};
use glam::{DVec3, Vec2, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;
use tracer::color::Rgb;
use tracer::geometry::{Frame, Triangle};
use tracer::light::{
    AreaLight, DirectionalLight, EnvironmentLight, EnvironmentMap, Light, PointLight, SpotLight,
};

const N: usize = 200_000;

/// A triangle tilted off every axis.
fn triangle() -> Triangle {
    Triangle::new(
        Vec3::new(-0.9, 2.0, -0.4),
        Vec3::new(0.2, 2.5, 1.1),
        Vec3::new(1.1, 1.8, -0.6),
    )
}

fn area_light(two_sided: bool) -> AreaLight {
    AreaLight::new(triangle(), 7, Rgb::new(3.0, 2.0, 1.0), two_sided)
}

/// A point `distance` from the triangle's centroid, on its front side when
/// `side` is 1 and its back side when −1, `tilt` radians off its normal.
fn receiver(light: &AreaLight, distance: f32, tilt: f32, side: f32) -> Vec3 {
    let t = &light.triangle;
    let centroid = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
    let frame = Frame::new(light.normal);
    let dir = side * (tilt.cos() * frame.n + tilt.sin() * frame.s);
    centroid + distance * dir
}

/// Where the ray from `origin` along `dir` meets the triangle, if it does
/// (Möller–Trumbore in double precision; a hair of slack at the edges, so a
/// direction sampled on an edge is not lost to rounding).
fn hit(t: &Triangle, origin: Vec3, dir: Vec3) -> Option<DVec3> {
    let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
    let [a, b, c] = t.v.map(|v| v.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = o - a;
    let b1 = s.dot(p) / det;
    let q = s.cross(e1);
    let b2 = d.dot(q) / det;
    let dist = e2.dot(q) / det;
    const SLACK: f64 = 1e-5;
    (b1 >= -SLACK && b2 >= -SLACK && b1 + b2 <= 1.0 + SLACK && dist > 0.0).then(|| o + dist * d)
}

/// Samples the area light from `receiver` and checks the directions against
/// the density `pdf_incident` gives where each direction meets the triangle
/// (zero where it misses, or meets the back of a one-sided light). The grid
/// is the cap of directions around the one to the centroid that holds the
/// whole triangle, so the triangle covers much of it.
fn check_area_light_sampling(what: &str, light: &AreaLight, receiver: Vec3, seed: u64) {
    let t = &light.triangle;
    let centroid = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
    let frame = Frame::new((centroid - receiver).normalize());
    // The direction farthest from the axis is on the triangle's outline
    // (the projected triangle is less than a hemisphere, and holds the
    // axis): walk the edges, and leave a margin.
    let widest = (0..3 * 256)
        .map(|k| {
            let (edge, s) = (k / 256, (k % 256) as f32 / 256.0);
            let p = t.v[edge].lerp(t.v[(edge + 1) % 3], s);
            frame.n.dot((p - receiver).normalize()) as f64
        })
        .fold(1.0, f64::min);
    let z_min = (widest - 0.05 * (1.0 - widest)).max(-1.0);
    let area = 0.5
        * (t.v[1] - t.v[0])
            .as_dvec3()
            .cross((t.v[2] - t.v[0]).as_dvec3())
            .length();
    let normal = light.normal.as_dvec3();
    let light_enum = Light::Area(light.clone());
    let outcome = chi_square::check(
        what,
        &SphereGrid::band(z_min, 1.0),
        N,
        seed,
        |r| {
            let s = light_enum.sample_incident(receiver, (r.f32(), r.f32()))?;
            assert!(!s.delta);
            assert_eq!(s.value, light.radiance);
            assert_eq!(s.normal, light.normal);
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            let to_point = s.point.as_dvec3() - receiver.as_dvec3();
            let d = to_point.length();
            assert!((s.distance as f64 - d).abs() <= 1e-5 * d);
            assert!(s.wi.as_dvec3().dot(to_point / d) > 1.0 - 1e-6);
            // The point is on the triangle: its plane, within its edges.
            let on = hit(t, receiver, s.wi).expect("the sampled direction misses the light");
            assert!((on - s.point.as_dvec3()).length() <= 1e-4 * d);
            // The density reported: d² / (|cos| · area), as pdf_incident says.
            let closed_form = d * d / ((to_point / d).dot(normal).abs() * area);
            assert!(
                (s.pdf as f64 - closed_form).abs() <= 1e-3 * closed_form,
                "pdf {} against d² / (cos · area) = {closed_form}",
                s.pdf
            );
            let pdf_incident = light.pdf_incident(receiver, s.point);
            assert!((pdf_incident - s.pdf).abs() <= 1e-4 * s.pdf);
            Some((frame.to_local(s.wi), s.pdf as f64))
        },
        |local| {
            let w = frame.to_world(local);
            match hit(t, receiver, w) {
                Some(p) if light.two_sided || w.dot(light.normal) < 0.0 => {
                    light.pdf_incident(receiver, p.as_vec3()) as f64
                }
                _ => 0.0,
            }
        },
    );
    // Every sample reached the triangle, so its density integrates to one.
    assert_eq!(outcome.refused + outcome.outside, 0, "{what}: {outcome:?}");
    assert!(
        (outcome.total - 1.0).abs() < 3e-3,
        "{what}: the density integrates to {}",
        outcome.total
    );
}

#[test]
fn area_light_samples_the_solid_angle_density_it_reports() {
    let light = area_light(false);
    let head_on = receiver(&light, 1.5, 0.0, 1.0);
    check_area_light_sampling("area light, head on", &light, head_on, 41);
    // Close and at 60° from the normal: the density varies across the
    // triangle by distance and cosine.
    let oblique = receiver(&light, 0.6, 60f32.to_radians(), 1.0);
    check_area_light_sampling("area light, close and oblique", &light, oblique, 42);
}

#[test]
fn a_two_sided_area_light_is_sampled_from_behind() {
    let light = area_light(true);
    let behind = receiver(&light, 1.0, 30f32.to_radians(), -1.0);
    check_area_light_sampling("two-sided area light, from behind", &light, behind, 43);
}

#[test]
fn a_one_sided_area_light_sends_nothing_behind_it() {
    let light = Light::Area(area_light(false));
    let Light::Area(area) = &light else {
        unreachable!()
    };
    let behind = receiver(area, 1.0, 30f32.to_radians(), -1.0);
    let mut rng = crate::common::Rng::new(44);
    for _ in 0..1000 {
        assert!(light
            .sample_incident(behind, (rng.f32(), rng.f32()))
            .is_none());
    }
}

/// Delta lights: the same answer whatever the random numbers.
fn incident(light: &Light, receiver: Vec3) -> Option<tracer::light::IncidentSample> {
    let a = light.sample_incident(receiver, (0.1, 0.9));
    let b = light.sample_incident(receiver, (0.7, 0.2));
    assert_eq!(a.map(|s| (s.wi, s.value)), b.map(|s| (s.wi, s.value)));
    if let Some(s) = a {
        assert!(s.delta && s.pdf == 1.0, "{s:?}");
    }
    a
}

/// Asserts that `got` is `expected` within 1e-5 of `scale`: near a spot's
/// rim the falloff is steep, and a direction rounded to single precision
/// moves it by more than 1e-5 of itself, though not of the peak.
fn assert_close(got: Rgb, expected: Rgb, scale: Rgb, what: &str) {
    assert!(
        (got - expected).abs().max_element() <= 1e-5 * scale.max_element(),
        "{what}: {got}, expected {expected}"
    );
}

#[test]
fn a_point_light_delivers_intensity_over_distance_squared() {
    let intensity = Rgb::new(10.0, 5.0, 2.0);
    let position = Vec3::new(1.0, 2.0, 0.5);
    let light = Light::Point(PointLight {
        position,
        intensity,
    });
    for r in [
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.5),
        Vec3::new(-3.0, 7.0, 2.0),
        Vec3::new(1.0, 2.0, 0.6),
    ] {
        let s = incident(&light, r).unwrap();
        let d = position - r;
        assert!(s.wi.abs_diff_eq(d.normalize(), 1e-6), "{r}");
        assert!((s.distance - d.length()).abs() <= 1e-6 * d.length());
        assert_eq!(s.point, position);
        let expected = intensity / d.length_squared();
        assert_close(s.value, expected, expected, &format!("at {r}"));
    }
    // At the light itself there is no direction.
    assert!(light.sample_incident(position, (0.5, 0.5)).is_none());
}

#[test]
fn a_spot_light_delivers_its_falloff_over_distance_squared() {
    let intensity = Rgb::new(20.0, 20.0, 10.0);
    let position = Vec3::new(0.2, 3.0, -0.1);
    let axis = Vec3::new(0.1, -1.0, 0.2).normalize();
    // Full intensity within 20° of the axis, nothing beyond 40°, and a
    // smoothstep in cos θ between them.
    let (cos_cone, cos_start) = (40f32.to_radians().cos(), 20f32.to_radians().cos());
    let light = Light::Spot(SpotLight {
        position,
        axis,
        intensity,
        cos_cone,
        cos_falloff_start: cos_start,
    });
    let frame = Frame::new(axis);
    let mut ramp = 0;
    for degrees in [
        0.0f32, 10.0, 19.5, 20.5, 25.0, 30.0, 35.0, 39.5, 40.5, 60.0, 120.0,
    ] {
        for (distance, turn) in [(1.0f32, 0.0f32), (2.5, 2.0), (0.3, 4.0)] {
            let theta = degrees.to_radians();
            let out =
                theta.cos() * frame.n + theta.sin() * (turn.cos() * frame.s + turn.sin() * frame.t);
            let r = position + distance * out;
            let cos = out.dot(axis);
            let falloff = if cos >= cos_start {
                1.0
            } else if cos <= cos_cone {
                0.0
            } else {
                ramp += 1;
                let x = (cos - cos_cone) / (cos_start - cos_cone);
                x * x * (3.0 - 2.0 * x)
            };
            let what = format!("{degrees}° off the axis, {distance} away");
            match incident(&light, r) {
                Some(s) => {
                    assert!(falloff > 0.0, "{what}: light outside the cone");
                    assert!(s.wi.abs_diff_eq(-out, 1e-5), "{what}");
                    assert!((s.distance - distance).abs() <= 1e-5 * distance, "{what}");
                    assert_eq!(s.point, position);
                    let peak = intensity / (distance * distance);
                    assert_close(s.value, peak * falloff, peak, &what);
                }
                None => assert_eq!(falloff, 0.0, "{what}: no light inside the cone"),
            }
        }
    }
    assert_eq!(ramp, 5 * 3, "the ramp was sampled at five angles");
}

#[test]
fn a_directional_light_delivers_its_irradiance_everywhere() {
    let direction = Vec3::new(0.3, -1.0, 0.2).normalize();
    let irradiance = Rgb::new(2.0, 1.0, 0.5);
    let light = Light::Directional(DirectionalLight {
        direction,
        irradiance,
        scene_center: Vec3::ZERO,
        scene_radius: 5.0,
    });
    for r in [Vec3::ZERO, Vec3::new(3.0, -2.0, 1.0), Vec3::splat(1e4)] {
        let s = incident(&light, r).unwrap();
        assert_eq!(s.wi, -direction);
        assert!(s.distance.is_infinite());
        assert_eq!(s.value, irradiance);
    }
}

// ---------------------------------------------------------------------------
// Starting light paths.

#[test]
fn a_point_light_emits_uniformly_over_the_sphere() {
    let intensity = Rgb::new(1.0, 2.0, 3.0);
    let light = Light::Point(PointLight {
        position: Vec3::new(0.5, 1.0, -2.0),
        intensity,
    });
    chi_square::check(
        "point light emission",
        &SphereGrid::sphere(),
        N,
        51,
        |r| {
            let (u_pos, u_dir) = ((r.f32(), r.f32()), (r.f32(), r.f32()));
            let e = light.sample_emission(u_pos, u_dir)?;
            assert_eq!(e.origin, Vec3::new(0.5, 1.0, -2.0));
            assert_eq!(e.value, intensity);
            Some((e.dir, e.emission_pdf as f64))
        },
        |_| 1.0 / (4.0 * PI),
    );
}

#[test]
fn a_spot_light_emits_uniformly_over_its_cone_weighted_by_its_falloff() {
    let axis = Vec3::new(-0.3, -1.0, 0.4).normalize();
    let (cos_cone, cos_start) = (35f32.to_radians().cos(), 15f32.to_radians().cos());
    let spot = SpotLight {
        position: Vec3::new(0.0, 2.0, 0.0),
        axis,
        intensity: Rgb::splat(4.0),
        cos_cone,
        cos_falloff_start: cos_start,
    };
    let light = Light::Spot(spot.clone());
    let frame = Frame::new(axis);
    let uniform = 1.0 / (2.0 * PI * (1.0 - cos_cone as f64));
    chi_square::check(
        "spot light emission",
        &SphereGrid::band(cos_cone as f64, 1.0),
        N,
        52,
        |r| {
            let (u_pos, u_dir) = ((r.f32(), r.f32()), (r.f32(), r.f32()));
            let e = light.sample_emission(u_pos, u_dir)?;
            let local = frame.to_local(e.dir);
            let falloff = spot.falloff(local.z);
            assert_close(e.value, spot.intensity * falloff, spot.intensity, "value");
            Some((local, e.emission_pdf as f64))
        },
        |w| {
            if w.z >= cos_cone - 1e-6 {
                uniform
            } else {
                0.0
            }
        },
    );
}

/// The directions an area light emits, in the frame of its normal, against
/// cos θ / π on its front (split over both faces when two-sided).
fn check_area_emission(two_sided: bool, seed: u64) {
    let area = area_light(two_sided);
    let light = Light::Area(area.clone());
    let frame = Frame::new(area.normal);
    let sides = if two_sided { 2.0 } else { 1.0 };
    chi_square::check(
        &format!("area light emission (two-sided: {two_sided})"),
        &SphereGrid::sphere(),
        N,
        seed,
        |r| {
            let (u_pos, u_dir) = ((r.f32(), r.f32()), (r.f32(), r.f32()));
            let e = light.sample_emission(u_pos, u_dir)?;
            let local = frame.to_local(e.dir);
            assert!((e.cos_light - local.z.abs()).abs() < 1e-4);
            let expected = area.radiance * local.z.abs();
            assert_close(e.value, expected, area.radiance, "value");
            assert!((e.direct_pdf_area - 1.0 / area.area).abs() <= 1e-6 / area.area);
            // The direction's density: the emission density less the position's.
            Some((local, (e.emission_pdf * area.area) as f64))
        },
        |w| {
            let cos = if two_sided { w.z.abs() } else { w.z.max(0.0) };
            cos as f64 / (PI * sides)
        },
    );
}

#[test]
fn an_area_light_emits_cosine_weighted_directions() {
    check_area_emission(false, 53);
}

#[test]
fn a_two_sided_area_light_emits_from_both_faces() {
    check_area_emission(true, 54);
}

#[test]
fn an_area_light_emits_from_uniform_points() {
    // The origins' barycentrics, on the unit square's lower triangle.
    let area = area_light(false);
    let light = Light::Area(area.clone());
    let t = area.triangle;
    let (e1, e2) = ((t.v[1] - t.v[0]).as_dvec3(), (t.v[2] - t.v[0]).as_dvec3());
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let barycentrics = |p: Vec3| {
        let q = (p - t.v[0]).as_dvec3();
        let (q1, q2) = (q.dot(e1), q.dot(e2));
        let det = d11 * d22 - d12 * d12;
        Vec2::new(
            ((d22 * q1 - d12 * q2) / det) as f32,
            ((d11 * q2 - d12 * q1) / det) as f32,
        )
    };
    chi_square::check(
        "area light emission origins",
        &PlaneGrid::new((0.0, 1.0), (0.0, 1.0), 20),
        N,
        55,
        |r| {
            let (u_pos, u_dir) = ((r.f32(), r.f32()), (r.f32(), r.f32()));
            let e = light.sample_emission(u_pos, u_dir)?;
            let off_plane = (e.origin - t.v[0]).dot(area.normal);
            assert!(
                off_plane.abs() < 1e-5,
                "{} is off the triangle's plane",
                e.origin
            );
            // Uniform by area: density 2 in barycentrics.
            Some((
                barycentrics(e.origin),
                2.0 * e.direct_pdf_area as f64 * area.area as f64,
            ))
        },
        |b| {
            if b.x >= -1e-5 && b.y >= -1e-5 && b.x + b.y <= 1.0 + 1e-5 {
                2.0
            } else {
                0.0
            }
        },
    );
}

#[test]
fn a_directional_light_emits_from_a_uniform_disk_covering_the_scene() {
    let direction = Vec3::new(0.2, -1.0, 0.3).normalize();
    let (center, radius) = (Vec3::new(1.0, 0.5, -1.0), 4.0f32);
    let light = Light::Directional(DirectionalLight {
        direction,
        irradiance: Rgb::ONE,
        scene_center: center,
        scene_radius: radius,
    });
    let frame = Frame::new(direction);
    let disk_center = center - direction * radius;
    chi_square::check(
        "directional light emission origins",
        &PlaneGrid::new((-1.0, 1.0), (-1.0, 1.0), 20),
        N,
        56,
        |r| {
            let (u_pos, u_dir) = ((r.f32(), r.f32()), (r.f32(), r.f32()));
            let e = light.sample_emission(u_pos, u_dir)?;
            assert_eq!(e.dir, direction);
            let local = frame.to_local(e.origin - disk_center) / radius;
            assert!(local.z.abs() < 1e-5, "the origin is off the disk's plane");
            // Density on the unit disk: the emission density times the area scale.
            let reported = e.emission_pdf as f64 * (radius * radius) as f64;
            Some((Vec2::new(local.x, local.y), reported))
        },
        |p: Vec2| {
            if p.length_squared() <= 1.0 + 1e-5 {
                1.0 / PI
            } else {
                0.0
            }
        },
    );
}

// ---------------------------------------------------------------------------
// The environment.

/// A small sky with a gradient, a bright sun and a black patch, turned off
/// every axis.
fn sky() -> EnvironmentLight {
    let (w, h) = (32, 16);
    let texels = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            if (4.0..10.0).contains(&x) && y > 11.0 {
                Rgb::ZERO
            } else if (x, y) == (20.0, 4.0) {
                Rgb::new(300.0, 280.0, 250.0)
            } else {
                Rgb::new(0.3 + x / 32.0, 0.6, 1.2 - y / 16.0)
            }
        })
        .collect();
    let map = EnvironmentMap::new(w, h, texels).unwrap();
    let rotation = glam::Mat3::from_axis_angle(Vec3::new(0.3, 1.0, -0.2).normalize(), 1.1);
    EnvironmentLight::from_map(Arc::new(map), 1.5, rotation, Vec3::ZERO, 2.0)
}

/// Directions towards an image sky follow the density the light reports
/// (luminance × solid angle, cell by cell), over a grid finer than the map's.
#[test]
fn an_image_sky_is_sampled_by_its_luminance() {
    let environment = sky();
    let light = Light::Environment(environment.clone());
    let receiver = Vec3::new(0.3, -0.2, 1.0);
    chi_square::check(
        "image sky sampling",
        &SphereGrid {
            z: (-1.0, 1.0),
            z_bins: 24,
            phi_bins: 48,
        },
        N,
        61,
        |r| {
            let s = light.sample_incident(receiver, (r.f32(), r.f32()))?;
            assert!(!s.delta && s.distance.is_infinite());
            let want = environment.radiance(s.wi);
            assert!((s.value - want).abs().max_element() <= 1e-4 * want.max_element());
            Some((s.wi, s.pdf as f64))
        },
        |w| environment.pdf_direction(w) as f64,
    );
}

/// Light paths from the sky leave from a disk across the scene's bounding
/// sphere, perpendicular to their direction, with directions drawn as
/// light sampling draws them (the density reported is direction × position).
#[test]
fn an_image_sky_emits_from_a_disk_across_the_scene() {
    let environment = sky();
    let light = Light::Environment(environment.clone());
    let disk_area = PI * 2.0 * 2.0;
    chi_square::check(
        "image sky emission",
        &SphereGrid {
            z: (-1.0, 1.0),
            z_bins: 24,
            phi_bins: 48,
        },
        N,
        62,
        |r| {
            let e = light.sample_emission((r.f32(), r.f32()), (r.f32(), r.f32()))?;
            let to_sky = -e.dir;
            // On the plane tangent to the sphere of radius 2, within the disk.
            assert!((e.origin.dot(to_sky) - 2.0).abs() < 1e-4);
            assert!((e.origin - to_sky * 2.0).length() <= 2.0 + 1e-4);
            assert!(
                (e.direct_pdf_area - environment.pdf_direction(to_sky)).abs()
                    <= 1e-4 * e.direct_pdf_area
            );
            Some((to_sky, e.emission_pdf as f64 * disk_area))
        },
        |w| environment.pdf_direction(w) as f64,
    );
}
