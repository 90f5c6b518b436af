//! BDPT's light vertices on Lambertian surfaces, shaded eight lanes at a
//! time, as its camera vertices are (`bdpt_diffuse.rs`).
//!
//! While the light lanes take a step (`bdpt_lanes.rs`), each lane whose
//! walk reached a Lambertian surface keeps its vertex for the camera walks
//! and stages the surface, the walk and its numbers. One SIMD pass per
//! half of the lanes then joins each vertex to the camera (t = 1: where it
//! lands on the image, the BSDF's value towards the lens with the shading
//! correction of importance, the splat and its weight, and the shadow
//! ray), samples the next direction and follows the walk: its MIS
//! quantities, its throughput and Russian roulette. Every operation is
//! the scalar code's (`light_vertex`, `camera_splat_unshadowed`,
//! `camera_splat_weight`, `Walk::follow`) in its order, so each sample
//! stays bit for bit what it is alone (`tests/it/determinism.rs`).

use super::bdpt_diffuse::{FollowedWalks, StagedWalks};
use super::simd::{
    diffuse_eval, eights_with, get3, lane_mask, load, load3, offset_origin, set3, set_bits,
    shading_correction, store, store3, Lanes, Lanes3, StagedLights, StagedVertices, V3,
};
use super::walk::{MergeWeights, Walk};
use super::LIGHT_ROULETTE_START;
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::{Ray, SurfacePoint};
use crate::light::AreaLight;
use crate::sampling::VertexNumbers;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;
use wide::f32x8;

/// The staged inputs of a step's diffuse light vertices, and their results.
#[derive(Default)]
pub(super) struct DiffuseLightLanes {
    vertices: StagedVertices,
    /// Each lane's lens point, which its splats aim at.
    lens: Lanes3,
    walks: StagedWalks,
    /// Lanes whose walks look for a further vertex (and drew its numbers).
    goes_on: u32,
    out: Splatted,
}

/// What the SIMD pass hands back, per lane.
#[derive(Default)]
struct Splatted {
    /// t = 1: the lanes whose vertex lands on the image and reflects
    /// something towards the lens, and of those the ones with a shadow ray.
    splat_some: u32,
    splat_ray: u32,
    /// The image point, and the splat with its MIS weight.
    x: Lanes,
    y: Lanes,
    splat: Lanes3,
    ray_origin: Lanes3,
    ray_dir: Lanes3,
    ray_tmax: Lanes,
    next: FollowedWalks,
}

/// What the pass reads of the camera: its frame, the projection's
/// constants, and the light paths per pass that splats are divided by.
pub(super) struct SplatCamera {
    pinhole: bool,
    position: V3,
    forward: V3,
    right: V3,
    up: V3,
    focus_distance: f32x8,
    image_plane_distance: f32x8,
    half_width: f32x8,
    half_height: f32x8,
    width: f32x8,
    height: f32x8,
    light_paths: f32x8,
}

impl SplatCamera {
    pub fn new(camera: &Camera, light_paths: f32) -> SplatCamera {
        let splat = |v: Vec3| V3 {
            x: f32x8::splat(v.x),
            y: f32x8::splat(v.y),
            z: f32x8::splat(v.z),
        };
        let (right, up) = camera.right_up();
        let (width, height) = (camera.width() as f32, camera.height() as f32);
        SplatCamera {
            pinhole: camera.is_pinhole(),
            position: splat(camera.position),
            forward: splat(camera.forward()),
            right: splat(right),
            up: splat(up),
            focus_distance: f32x8::splat(camera.focus_distance()),
            image_plane_distance: f32x8::splat(camera.image_plane_distance()),
            half_width: f32x8::splat(0.5 * width),
            half_height: f32x8::splat(0.5 * height),
            width: f32x8::splat(width),
            height: f32x8::splat(height),
            light_paths: f32x8::splat(light_paths),
        }
    }

    /// `Camera::project_from`, lane by lane: the image point of `p` seen
    /// from `lens`, and the lanes where it is in front and on the image.
    #[inline(always)]
    fn project_from(&self, lens: V3, p: V3) -> (f32x8, f32x8, f32x8) {
        let zero = f32x8::ZERO;
        let (p, lens_front) = if self.pinhole {
            (p, f32x8::splat(f32::from_bits(u32::MAX)))
        } else {
            let d = p - lens;
            let z = d.dot(self.forward);
            (lens + d.scale(self.focus_distance / z), !z.simd_le(zero))
        };
        // `Camera::project`.
        let d = p - self.position;
        let z = d.dot(self.forward);
        let scale = self.image_plane_distance / z;
        let x = self.half_width + d.dot(self.right) * scale;
        let y = self.half_height - d.dot(self.up) * scale;
        let inside =
            zero.simd_le(x) & x.simd_lt(self.width) & zero.simd_le(y) & y.simd_lt(self.height);
        (x, y, lens_front & !z.simd_le(zero) & inside)
    }
}

impl DiffuseLightLanes {
    /// Forgets the previous step's lanes.
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.goes_on = 0;
    }

    /// Lanes staged this step.
    pub fn staged(&self) -> u32 {
        self.vertices.staged
    }

    /// Stages lane `lane`'s vertex at `surface` (reflectance `albedo`, the
    /// walk arriving along `-wo`) on `walk`, its splat aimed at `lens`,
    /// with the numbers of its next direction and roulette where the walk
    /// looks further (`None`: it ends here after its splat).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn stage(
        &mut self,
        lane: usize,
        surface: &SurfacePoint,
        wo: Vec3,
        albedo: Rgb,
        walk: &Walk,
        lens: Vec3,
        numbers: Option<VertexNumbers>,
    ) {
        let (direction, roulette) = match numbers {
            Some(n) => {
                self.goes_on |= 1 << lane;
                (n.direction, n.roulette)
            }
            // Numbers for a sample nobody reads.
            None => ((0.5, 0.5), 0.0),
        };
        self.vertices.stage(
            lane,
            surface,
            wo,
            albedo,
            walk.throughput,
            direction,
            roulette,
            walk.length >= LIGHT_ROULETTE_START,
        );
        set3(&mut self.lens, lane, lens);
        self.walks.stage(lane, walk);
    }

    /// Shades every staged lane.
    pub fn shade(&mut self, camera: &SplatCamera) {
        for base in self.vertices.halves() {
            self.shade_half(camera, base);
        }
    }

    /// Lane `lane`'s splat: its pixel in an image `width` wide, its value
    /// with its weight, and its shadow ray; `None` where it adds nothing.
    #[inline(always)]
    pub fn splat(&self, lane: usize, width: u32) -> Option<(u32, Rgb, Option<Ray>)> {
        let (bit, out) = (1u32 << lane, &self.out);
        if out.splat_some & bit == 0 {
            return None;
        }
        let pixel = out.y[lane] as u32 * width + out.x[lane] as u32;
        let ray = (out.splat_ray & bit != 0).then(|| {
            Ray::segment(
                get3(&out.ray_origin, lane),
                get3(&out.ray_dir, lane),
                out.ray_tmax[lane],
            )
        });
        Some((pixel, get3(&out.splat, lane), ray))
    }

    /// Follows lane `lane`'s walk as `light_vertex` would after its visit;
    /// returns whether it goes on.
    #[inline(always)]
    pub fn follow(&self, lane: usize, walk: &mut Walk) -> bool {
        self.goes_on >> lane & 1 != 0 && self.out.next.apply(lane, walk)
    }

    /// The SIMD pass over lanes `base .. base + 8`.
    fn shade_half(&mut self, camera: &SplatCamera, base: usize) {
        let (zero, one) = (f32x8::ZERO, f32x8::ONE);
        let mis = |x: f32x8| x * x;
        let v = self.vertices.vertices(base);
        let (d_vcm, d_vc, vm) = self.walks.weights(base);

        // t = 1 (`camera_splat_unshadowed`): `CameraConnection::new` ...
        let lens = load3(&self.lens, base);
        let (x, y, on_image) = camera.project_from(lens, v.position);
        let to_camera = lens - v.position;
        let distance = to_camera.dot(to_camera).sqrt();
        let dir = to_camera.div(distance);
        let cos_camera = (-dir).dot(camera.forward);
        let image_distance = camera.image_plane_distance / cos_camera;
        let image_to_solid_angle = image_distance * image_distance / cos_camera;
        // ... the BSDF towards the lens (`Bsdf::eval_mode` for importance) ...
        let (f, _) = diffuse_eval(v.albedo, v.frame.n, v.ng, dir);
        let f = f.scale(shading_correction(v.wo, dir, v.frame.n, v.ng));
        let some = lane_mask(self.vertices.staged >> base)
            & on_image
            & !cos_camera.simd_le(zero)
            & !distance.simd_le(zero)
            & !f.is_zero();
        // ... the shadow ray to the lens point (`segment_ray`) ...
        let origin = offset_origin(v.position, v.normal, to_camera, v.magnitude);
        let to_lens = lens - origin;
        let length = to_lens.dot(to_lens).sqrt();
        let has_ray = !(length.is_nan() | length.simd_le(zero));
        // ... the splat (`CameraConnection::splat`) and its weight
        // (`camera_splat_weight`, report eq. 44).
        let splat = (v.throughput * f)
            .scale(image_to_solid_angle / (camera.light_paths * distance * distance));
        let reflected = dir.dot(v.ng).simd_gt(zero);
        let lobe = reflected & !(dir.dot(v.frame.n).simd_gt(zero) ^ reflected);
        let reverse_pdf = v.wo.dot(v.frame.n).max(zero) * f32x8::splat(FRAC_1_PI);
        let reverse_pdf = lobe.select(reverse_pdf, zero);
        let cos_surface = dir.dot(v.normal).abs();
        let camera_pdf_area = image_to_solid_angle * cos_surface / (distance * distance);
        let w_light =
            mis(camera_pdf_area / camera.light_paths) * (vm + d_vcm + d_vc * mis(reverse_pdf));
        let weight = one / (w_light + one);
        let out = &mut self.out;
        set_bits(&mut out.splat_some, some, base);
        set_bits(&mut out.splat_ray, has_ray, base);
        store(x, &mut out.x, base);
        store(y, &mut out.y, base);
        store3(splat.scale(weight), &mut out.splat, base);
        store3(origin, &mut out.ray_origin, base);
        store3(to_lens.div(length), &mut out.ray_dir, base);
        store(length, &mut out.ray_tmax, base);

        // `Walk::follow` for importance: the MIS quantities, the throughput
        // times the sample's weight (the reflectance times the shading
        // correction), the next ray and roulette.
        if (self.goes_on >> base) & 0xff != 0 {
            let weight = v
                .albedo
                .scale(shading_correction(v.wo, v.wi, v.frame.n, v.ng));
            self.walks.follow(&v, weight, base, &mut out.next);
        }
    }
}

/// The light walks' starts on emissive triangles, made eight lanes at a
/// time (`start_light_walk` with `AreaLight::sample_emission`): each lane
/// stages its light, chosen with its numbers drawn, and one pass per eight
/// lanes samples the point and direction and begins the walk.
#[derive(Default)]
pub(super) struct LightStarts {
    lights: StagedLights,
    direction: [Lanes; 2],
    vc: Lanes,
    out: Started,
}

/// What the pass hands back, per lane.
#[derive(Default)]
struct Started {
    /// Lanes whose light emits along the sampled direction.
    some: u32,
    origin: Lanes3,
    dir: Lanes3,
    throughput: Lanes3,
    roulette_scale: Lanes,
    d_vcm: Lanes,
    d_vc: Lanes,
    d_vm: Lanes,
}

impl LightStarts {
    /// Forgets the previous batch's lanes.
    pub fn clear(&mut self) {
        self.lights.clear();
    }

    /// Lanes staged.
    pub fn staged(&self) -> u32 {
        self.lights.lit
    }

    /// Stages lane `lane`'s start on `light`, chosen with probability
    /// `pick`, with the numbers of its point and direction, for a walk
    /// with the merging constants `merging`.
    #[inline(always)]
    pub fn stage(
        &mut self,
        lane: usize,
        light: &AreaLight,
        pick: f32,
        (u_point, u_direction): ((f32, f32), (f32, f32)),
        merging: MergeWeights,
    ) {
        self.lights.stage(lane, light, pick, u_point);
        self.direction[0][lane] = u_direction.0;
        self.direction[1][lane] = u_direction.1;
        self.vc[lane] = merging.vc;
    }

    /// Starts every staged lane, eight at a time.
    pub fn start(&mut self) {
        for base in eights_with(self.lights.lit) {
            self.start_eight(base);
        }
    }

    /// Lane `lane`'s walk as `start_light_walk` begins it, for merging
    /// constants `merging`; `None` where its light emits nothing along the
    /// sampled direction.
    #[inline(always)]
    pub fn walk(&self, lane: usize, merging: MergeWeights) -> Option<Walk> {
        let out = &self.out;
        (out.some >> lane & 1 != 0).then(|| Walk {
            origin: get3(&out.origin, lane),
            dir: get3(&out.dir, lane),
            throughput: get3(&out.throughput, lane),
            roulette_scale: out.roulette_scale[lane],
            length: 1,
            d_vcm: out.d_vcm[lane],
            d_vc: out.d_vc[lane],
            d_vm: out.d_vm[lane],
            merging,
            finite_start: true,
            weighted: true,
        })
    }

    /// The SIMD pass over lanes `base .. base + 8`.
    fn start_eight(&mut self, base: usize) {
        let (zero, one) = (f32x8::ZERO, f32x8::ONE);
        let mis = |x: f32x8| x * x;
        let (u, v) = (
            load(&self.direction[0], base),
            load(&self.direction[1], base),
        );
        let e = self.lights.emission(base, u, v);
        let emission_pdf = e.emission_pdf * e.pick;
        let direct_pdf = e.direct_pdf_area * e.pick;
        // An area light is finite and not a delta: the cosine counts.
        let d_vc = mis(e.cos_light / emission_pdf);
        let throughput = e.value.div(emission_pdf);
        // `roulette_scale`.
        let scale = one / throughput.max_element();
        let usable = !(scale.is_nan() | scale.is_inf()) & scale.simd_gt(zero);
        let out = &mut self.out;
        set_bits(&mut out.some, e.some, base);
        store3(
            offset_origin(e.point, e.normal, e.dir, e.magnitude),
            &mut out.origin,
            base,
        );
        store3(e.dir, &mut out.dir, base);
        store3(throughput, &mut out.throughput, base);
        store(usable.select(scale, one), &mut out.roulette_scale, base);
        store(mis(direct_pdf / emission_pdf), &mut out.d_vcm, base);
        store(d_vc, &mut out.d_vc, base);
        store(d_vc * load(&self.vc, base), &mut out.d_vm, base);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::LANES;
    use crate::geometry::Triangle;

    /// Every lane a batch stages is started, whatever the lane count: each
    /// lane's walk leaves along the light's own scalar emission sample.
    #[test]
    fn every_staged_lane_starts_as_its_scalar_emission_sample() {
        let triangle = Triangle::new(
            Vec3::new(-1.0, 3.0, 0.5),
            Vec3::new(2.0, 3.5, -0.25),
            Vec3::new(0.5, 2.0, 1.5),
        );
        let light = AreaLight::new(triangle, 0, Vec3::new(4.0, 2.5, 1.0), true);
        let number = |k: usize, d: usize| ((k * 7 + d * 3) % 29) as f32 / 29.0 + 0.01;
        let mut starts = LightStarts::default();
        starts.clear();
        for k in 0..LANES {
            let u = ((number(k, 0), number(k, 1)), (number(k, 2), number(k, 3)));
            starts.stage(k, &light, 0.5, u, MergeWeights::NONE);
        }
        starts.start();
        let mut started = 0;
        for k in 0..LANES {
            let scalar =
                light.sample_emission((number(k, 0), number(k, 1)), (number(k, 2), number(k, 3)));
            let walk = starts.walk(k, MergeWeights::NONE);
            assert_eq!(walk.is_some(), scalar.is_some(), "lane {k}");
            if let (Some(walk), Some(scalar)) = (walk, scalar) {
                // The walk leaves from just off the light (its ray offset).
                assert!(walk.origin.distance(scalar.origin) < 1e-3, "lane {k}");
                assert_eq!(walk.dir, scalar.dir, "lane {k}");
                started += 1;
            }
        }
        assert!(started > LANES / 2, "only {started} of {LANES} lanes emit");
    }
}
