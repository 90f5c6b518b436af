//! Environment light: radiance arriving from infinitely far away, either
//! the same from every direction or read from a latitude–longitude image.
//!
//! The image is looked up exactly as Mitsuba 3's `envmap` does, so that
//! images of the same scene agree: a world direction `d` is rotated into
//! the map's frame, `u = atan2(d.x, −d.z) / 2π` (mod 1) runs left to right
//! and `v = acos(d.y) / π` top to bottom; texel column `j` sits at
//! `u = (j + ½) / W` (the last column blends back into the first) and
//! texel row `i` at `v = i / (H − 1)`, so the top row is the +y pole and
//! the bottom row the −y pole; between texels the radiance is bilinear.
//!
//! Directions are importance-sampled from a piecewise-constant density
//! over the cells between four neighbouring texels, proportional to the cell's mean
//! luminance times its solid angle. Within a cell, directions are uniform
//! in solid angle (uniform in azimuth and in cos θ), so the density is
//! constant over the cell and finite at the poles. A cell whose four
//! corners are black has zero density, and the bilinear radiance there is
//! zero too, so the density covers everything that emits.
//!
//! Light paths leave the environment from a disk as wide as the scene's
//! bounding sphere, perpendicular to the sampled direction (the same way a
//! directional light starts them), which is what LT and BDPT need.

use super::{EmissionSample, IncidentSample, LightPdfs};
use crate::color::{average, luminance, Rgb};
use crate::geometry::Frame;
use crate::sampling::warp::{concentric_disk, uniform_sphere};
use crate::sampling::Distribution1D;
use glam::{Mat3, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// Light from infinitely far away in every direction. Not a delta light:
/// every ray that leaves the scene sees it.
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// The radiance of a constant sky (already scaled); unused with a map.
    constant: Rgb,
    /// The image and its sampling density, if the sky is an image.
    map: Option<Arc<EnvironmentMap>>,
    /// Multiplies the map's texels.
    scale: f32,
    /// World to map frame (the inverse of the light's rotation).
    to_map: Mat3,
    /// Map frame to world.
    to_world: Mat3,
    /// Centre of a sphere that bounds the scene, where light paths aim.
    scene_center: Vec3,
    /// Radius of that sphere.
    scene_radius: f32,
    /// Flux into the scene's bounding disk, averaged over RGB.
    power: f32,
}

/// A latitude–longitude image with its sampling density.
#[derive(Debug)]
pub struct EnvironmentMap {
    width: usize,
    /// Texel rows; at least 2 (a one-row image is repeated).
    height: usize,
    /// Linear RGB, top row first.
    texels: Vec<Rgb>,
    /// Chooses a band of cells between two texel rows; `None` when the map is black.
    bands: Option<Distribution1D>,
    /// Chooses a cell within each band (`None` for a black band); cell `j`
    /// lies between texel columns `j` and `j + 1`.
    cells: Vec<Option<Distribution1D>>,
    /// cos θ at each texel row: `cos(π i / (H − 1))`, decreasing.
    cos_rows: Vec<f32>,
    /// cos θ at a band's top row minus at its bottom row, computed in f64
    /// so that the polar bands of very tall maps keep a non-zero width.
    band_heights: Vec<f32>,
    /// ∫ L dω over the sphere, averaged over RGB, before `scale`.
    integral: f32,
}

impl EnvironmentMap {
    /// A map from `width × height` linear texels, top row first. Negative
    /// components count as zero; non-finite ones are refused.
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<Rgb>,
    ) -> std::result::Result<EnvironmentMap, String> {
        assert!(width > 0 && height > 0 && texels.len() == width * height);
        if let Some(k) = texels.iter().position(|t| !t.is_finite()) {
            return Err(format!(
                "texel ({}, {}) is not a finite colour",
                k % width,
                k / width
            ));
        }
        let mut texels: Vec<Rgb> = texels.into_iter().map(|t| t.max(Rgb::ZERO)).collect();
        let height = if height == 1 {
            texels.extend_from_within(..);
            2
        } else {
            height
        };
        let cos_rows_f64: Vec<f64> = (0..height)
            .map(|i| (std::f64::consts::PI * i as f64 / (height - 1) as f64).cos())
            .collect();
        let cos_rows: Vec<f32> = cos_rows_f64.iter().map(|&c| c as f32).collect();
        let band_heights: Vec<f32> = cos_rows_f64
            .windows(2)
            .map(|w| (w[0] - w[1]) as f32)
            .collect();
        let texel = |i: usize, j: usize| texels[i * width + j % width];
        let mut band_weights = Vec::with_capacity(height - 1);
        let mut cells = Vec::with_capacity(height - 1);
        let mut integral = 0.0f64;
        for (i, &band_height) in band_heights.iter().enumerate() {
            let band_solid_angle = 2.0 * PI * band_height / width as f32;
            let mut weights = Vec::with_capacity(width);
            for j in 0..width {
                let corners = texel(i, j) + texel(i, j + 1) + texel(i + 1, j) + texel(i + 1, j + 1);
                weights.push(luminance(corners) * 0.25);
                integral += (average(corners) * 0.25 * band_solid_angle) as f64;
            }
            let band_luminance: f32 = weights.iter().sum();
            band_weights.push(band_luminance * band_height);
            cells.push(Distribution1D::new(&weights));
        }
        Ok(EnvironmentMap {
            width,
            height,
            bands: Distribution1D::new(&band_weights),
            cells,
            cos_rows,
            band_heights,
            texels,
            integral: integral as f32,
        })
    }

    /// Bilinear radiance at image point (`u`, `v`), both in [0, 1].
    fn lookup(&self, u: f32, v: f32) -> Rgb {
        let x = u * self.width as f32 - 0.5;
        let floor = x.floor();
        let fx = (x - floor).clamp(0.0, 1.0);
        let x0 = (floor as i64).rem_euclid(self.width as i64) as usize;
        let x1 = (x0 + 1) % self.width;
        let y = v * (self.height - 1) as f32;
        let y0 = (y.floor().max(0.0) as usize).min(self.height - 2);
        let fy = (y - y0 as f32).clamp(0.0, 1.0);
        let row = |i: usize| {
            let r = &self.texels[i * self.width..(i + 1) * self.width];
            r[x0] * (1.0 - fx) + r[x1] * fx
        };
        row(y0) * (1.0 - fy) + row(y0 + 1) * fy
    }

    /// The cell holding image point (`u`, `v`): (band, column).
    fn cell(&self, u: f32, v: f32) -> (usize, usize) {
        let band = ((v * (self.height - 1) as f32).max(0.0) as usize).min(self.height - 2);
        let x = (u * self.width as f32 - 0.5).floor() as i64;
        let column = x.rem_euclid(self.width as i64) as usize;
        (band, column)
    }

    /// Solid-angle density of a direction in `cell`.
    fn cell_pdf(&self, (band, column): (usize, usize)) -> f32 {
        let Some(bands) = &self.bands else {
            return 0.0;
        };
        let Some(cells) = &self.cells[band] else {
            return 0.0;
        };
        let cell_solid_angle = 2.0 * PI * self.band_heights[band] / self.width as f32;
        if cell_solid_angle <= 0.0 {
            return 0.0;
        }
        bands.pmf(band) * cells.pmf(column) / cell_solid_angle
    }

    /// A direction in the map's frame, drawn from the cells' density.
    fn sample(&self, u: (f32, f32)) -> Option<Vec3> {
        let (band, _, within_band) = self.bands.as_ref()?.sample_remapped(u.1);
        let (column, _, within_cell) = self.cells[band].as_ref()?.sample_remapped(u.0);
        let cos_theta = self.cos_rows[band] - self.band_heights[band] * within_band;
        let u = (column as f32 + 0.5 + within_cell) / self.width as f32;
        Some(from_image_point(u, cos_theta))
    }
}

/// The image point of a direction in the map's frame.
fn image_point(d: Vec3) -> (f32, f32) {
    let u = d.x.atan2(-d.z) / (2.0 * PI);
    (u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The direction in the map's frame at horizontal image coordinate `u`
/// and polar cosine `cos_theta` (the inverse of [`image_point`]).
fn from_image_point(u: f32, cos_theta: f32) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (sin_phi, cos_phi) = (2.0 * PI * u).sin_cos();
    Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
}

impl EnvironmentLight {
    /// A sky of the same `radiance` in every direction, around a scene
    /// bounded by the sphere (`scene_center`, `scene_radius`).
    pub fn constant(radiance: Rgb, scene_center: Vec3, scene_radius: f32) -> EnvironmentLight {
        let mut light = EnvironmentLight {
            constant: radiance,
            map: None,
            scale: 1.0,
            to_map: Mat3::IDENTITY,
            to_world: Mat3::IDENTITY,
            scene_center,
            scene_radius,
            power: 0.0,
        };
        light.power = light.disk_area() * 4.0 * PI * average(radiance);
        light
    }

    /// A sky from `map` times `scale`, turned by `rotation` (map frame to world).
    pub fn from_map(
        map: Arc<EnvironmentMap>,
        scale: f32,
        rotation: Mat3,
        scene_center: Vec3,
        scene_radius: f32,
    ) -> EnvironmentLight {
        let mut light = EnvironmentLight {
            constant: Rgb::ZERO,
            scale,
            to_map: rotation.transpose(),
            to_world: rotation,
            scene_center,
            scene_radius,
            power: 0.0,
            map: None,
        };
        light.power = light.disk_area() * scale * map.integral;
        light.map = Some(map);
        light
    }

    /// Flux through the disk that covers the scene, averaged over RGB.
    pub fn power(&self) -> f32 {
        self.power
    }

    /// Radiance arriving from direction `dir` (unit, pointing away from the scene).
    pub fn radiance(&self, dir: Vec3) -> Rgb {
        match &self.map {
            None => self.constant,
            Some(map) => {
                let (u, v) = image_point(self.to_map * dir);
                map.lookup(u, v) * self.scale
            }
        }
    }

    /// Solid-angle density with which light sampling chooses `dir`.
    pub fn pdf_direction(&self, dir: Vec3) -> f32 {
        match &self.map {
            None => 1.0 / (4.0 * PI),
            Some(map) => {
                let (u, v) = image_point(self.to_map * dir);
                map.cell_pdf(map.cell(u, v))
            }
        }
    }

    /// A world direction towards the sky, its radiance and solid-angle density.
    fn sample_direction(&self, u: (f32, f32)) -> Option<(Vec3, Rgb, f32)> {
        match &self.map {
            None => {
                let d = uniform_sphere(u.0, u.1);
                Some((d, self.constant, 1.0 / (4.0 * PI)))
            }
            Some(map) => {
                // Radiance and density are taken at the world direction, so
                // they are exactly what `radiance` and `pdf_direction` give
                // for it (a point on a cell's edge counts in one cell only).
                let d = (self.to_world * map.sample(u)?).normalize();
                let (iu, iv) = image_point(self.to_map * d);
                let pdf = map.cell_pdf(map.cell(iu, iv));
                let radiance = map.lookup(iu, iv) * self.scale;
                (pdf > 0.0).then_some((d, radiance, pdf))
            }
        }
    }

    /// Light arriving at `receiver` from a sampled direction.
    pub fn sample_incident(&self, receiver: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        let (wi, value, pdf) = self.sample_direction(u)?;
        Some(IncidentSample {
            wi,
            distance: f32::INFINITY,
            // Unused at an infinite distance (shadow rays go along `wi`).
            point: receiver + wi,
            normal: Vec3::ZERO,
            magnitude: 0.0,
            value,
            pdf,
            delta: false,
        })
    }

    /// Starts a light path: a direction from the sky and a point on the disk
    /// across the scene's bounding sphere, perpendicular to it.
    pub fn sample_emission(&self, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmissionSample> {
        let (to_sky, value, pdf) = self.sample_direction(u_dir)?;
        let frame = Frame::new(to_sky);
        let d = concentric_disk(u_pos.0, u_pos.1) * self.scene_radius;
        let origin = self.scene_center + to_sky * self.scene_radius + frame.s * d.x + frame.t * d.y;
        Some(EmissionSample {
            origin,
            dir: -to_sky,
            value,
            emission_pdf: pdf / self.disk_area(),
            // Light sampling chooses a direction, not a point: its density
            // stays in solid angle, which is what the MIS ratios need.
            direct_pdf_area: pdf,
            cos_light: 1.0,
            normal: Vec3::ZERO,
            magnitude: 0.0,
        })
    }

    /// Densities of the light-side strategies for the sky seen along `dir`
    /// (pointing away from the scene).
    pub fn pdfs_for_direction(&self, dir: Vec3) -> LightPdfs {
        let direct = self.pdf_direction(dir);
        LightPdfs {
            direct,
            emission: direct / self.disk_area(),
            cos_light: 1.0,
        }
    }

    fn disk_area(&self) -> f32 {
        PI * self.scene_radius * self.scene_radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient_map(width: usize, height: usize) -> EnvironmentMap {
        let texels = (0..width * height)
            .map(|k| {
                let (x, y) = (k % width, k / width);
                // A bright spot, a colour gradient and a black corner.
                let spot = if (x, y) == (width / 3, height / 4) {
                    40.0
                } else {
                    0.0
                };
                let black = x < width / 4 && y > height * 3 / 4;
                if black {
                    Rgb::ZERO
                } else {
                    Rgb::new(
                        0.2 + x as f32 / width as f32,
                        0.5,
                        1.0 - y as f32 / height as f32,
                    ) + Rgb::splat(spot)
                }
            })
            .collect();
        EnvironmentMap::new(width, height, texels).unwrap()
    }

    /// The mapping of Mitsuba's `envmap`: −z is the left edge and the
    /// middle column is +z, +y the top row.
    #[test]
    fn image_points_follow_the_latitude_longitude_convention() {
        let close =
            |a: (f32, f32), b: (f32, f32)| (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6;
        assert!(close(image_point(Vec3::Y), (0.0, 0.0)) || image_point(Vec3::Y).1 < 1e-6);
        assert!(close(image_point(Vec3::NEG_Z), (0.0, 0.5)));
        assert!(close(image_point(Vec3::X), (0.25, 0.5)));
        assert!(close(image_point(Vec3::Z), (0.5, 0.5)));
        assert!(close(image_point(Vec3::NEG_X), (0.75, 0.5)));
        for &(u, c) in &[(0.1, 0.3), (0.6, -0.9), (0.95, 0.99)] {
            let (u2, v2) = image_point(from_image_point(u, c));
            assert!((u2 - u).abs() < 1e-5 && ((PI * v2).cos() - c).abs() < 1e-5);
        }
    }

    #[test]
    fn texels_sit_at_column_and_row_positions() {
        let map = gradient_map(8, 5);
        for (i, j) in [(0, 0), (2, 3), (4, 7)] {
            let u = (j as f32 + 0.5) / 8.0;
            let v = i as f32 / 4.0;
            let got = map.lookup(u, v);
            assert!((got - map.texels[i * 8 + j]).abs().max_element() < 1e-5);
        }
        // Halfway past the last column blends with the first.
        let mid = map.lookup(0.0, 0.25);
        let want = (map.texels[8 + 7] + map.texels[8]) * 0.5;
        assert!((mid - want).abs().max_element() < 1e-5);
    }

    #[test]
    fn black_cells_are_never_sampled_and_a_black_map_has_no_power() {
        let map = gradient_map(16, 8);
        let light = EnvironmentLight::from_map(Arc::new(map), 1.0, Mat3::IDENTITY, Vec3::ZERO, 1.0);
        for k in 0..20_000 {
            let u = (
                (k % 200) as f32 / 200.0 + 1.37e-3,
                (k / 200) as f32 / 100.0 + 3.1e-3,
            );
            let (d, l, pdf) = light.sample_direction(u).unwrap();
            assert!(l.max_element() > 0.0, "sampled a black direction {d:?}");
            assert!((pdf - light.pdf_direction(d)).abs() <= 1e-3 * pdf);
        }
        let black = EnvironmentMap::new(4, 2, vec![Rgb::ZERO; 8]).unwrap();
        let light =
            EnvironmentLight::from_map(Arc::new(black), 1.0, Mat3::IDENTITY, Vec3::ZERO, 1.0);
        assert_eq!(light.power(), 0.0);
        assert!(light.sample_direction((0.3, 0.6)).is_none());
    }

    #[test]
    fn non_finite_texels_are_refused() {
        let mut texels = vec![Rgb::ONE; 6];
        texels[4] = Rgb::new(f32::NAN, 0.0, 0.0);
        let e = EnvironmentMap::new(3, 2, texels).unwrap_err();
        assert!(e.contains("(1, 1)"), "{e}");
    }
}
