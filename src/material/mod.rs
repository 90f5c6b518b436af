//! Materials, and the BSDFs they become at a surface point.
//!
//! A [`Material`] is what the scene names; [`Material::bsdf`] resolves its
//! textures at a hit and orients it towards the outgoing direction, giving a
//! [`Bsdf`] the integrators sample and evaluate. Both are enums, so the hot
//! loops dispatch with a `match`, not a virtual call.

mod conductor;
mod dielectric;
mod diffuse;
pub mod microfacet;
mod mirror;
pub mod plastic;
mod rough_dielectric;
pub mod texture;

pub use conductor::{fresnel_conductor, Conductor};
pub use dielectric::fresnel_dielectric;
pub use plastic::Plastic;
pub use rough_dielectric::RoughDielectric;
pub use texture::Texture;

use crate::color::Rgb;
use crate::geometry::{Frame, SurfacePoint};
use glam::Vec3;
use std::sync::Arc;

/// A diffuse albedo: a constant or an image looked up by UV.
#[derive(Clone, Debug)]
pub enum Albedo {
    /// The same reflectance everywhere, each channel in [0, 1].
    Constant(Rgb),
    /// An image looked up at the surface point's UV (shared between materials).
    Texture(Arc<Texture>),
}

impl Albedo {
    /// The reflectance at `surface` (its texture looked up at its UV).
    #[inline]
    pub fn at(&self, surface: &SurfacePoint) -> Rgb {
        match self {
            Albedo::Constant(c) => *c,
            Albedo::Texture(t) => t.lookup(surface.uv),
        }
    }

    /// The mean reflectance over the surface, averaged over RGB (over the
    /// whole image for a texture).
    pub fn mean(&self) -> f32 {
        match self {
            Albedo::Constant(c) => crate::color::average(*c),
            Albedo::Texture(t) => crate::color::average(t.mean()),
        }
    }
}

/// A surface's material, as the scene names it. Indexed by
/// [`crate::scene::TriangleShading::material`].
#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian reflection, from both faces.
    Diffuse {
        /// Fraction of light reflected, per channel.
        albedo: Albedo,
    },
    /// Perfect specular reflection, from both faces.
    Mirror {
        /// Fraction of light reflected per channel, in [0, 1].
        reflectance: Rgb,
    },
    /// Smooth glass: Fresnel reflection and refraction. The geometric normal
    /// points outside (ior 1) and away from the inside (ior `ior`).
    Dielectric {
        /// Index of refraction inside relative to outside (1.5 for glass); > 0.
        ior: f32,
        /// Per-channel factor, in [0, 1], on light each time it refracts;
        /// reflection is untinted.
        transmittance: Rgb,
    },
    /// A metal: GGX microfacet reflection with a complex Fresnel term,
    /// from both faces (Mitsuba 3's `roughconductor`).
    Conductor {
        /// GGX width (not squared); 0 is a smooth mirror.
        alpha: f32,
        /// Real part of the complex index of refraction, per channel
        /// (0, with `k` 1, for Fresnel 1).
        eta: Rgb,
        /// Extinction coefficient, per channel.
        k: Rgb,
        /// Multiplier on reflected light, per channel.
        reflectance: Rgb,
    },
    /// Rough glass: GGX microfacet reflection and refraction (Mitsuba 3's
    /// `roughdielectric`); inside and outside as for [`Material::Dielectric`].
    RoughDielectric {
        /// Index of refraction inside relative to outside; > 0.
        ior: f32,
        /// GGX width (not squared); 0 is smooth glass.
        alpha: f32,
        /// Per-channel factor on light each time it refracts.
        transmittance: Rgb,
    },
    /// A diffuse base under a smooth or GGX-rough dielectric coat, from
    /// both faces (Mitsuba 3's `plastic` and `roughplastic`).
    Plastic {
        /// Reflectance of the base.
        albedo: Albedo,
        /// Index of refraction of the coat; > 0.
        ior: f32,
        /// GGX width of the coat; at most 1e-4 (e.g. 0) is a smooth coat.
        alpha: f32,
        /// The coat's share in choosing a lobe, from the mean albedo.
        specular_weight: f32,
        /// The rough coat's transmittance tables; `None` when smooth.
        tables: Option<&'static plastic::CoatTables>,
    },
}

/// Which quantity a path carries. Radiance (camera paths) and importance (light
/// paths) scatter differently through refraction: see Veach's thesis, §5.2.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Camera paths (PT, and BDPT's camera subpaths).
    Radiance,
    /// Light paths, traced from the lights (LT, and BDPT's light subpaths):
    /// scattering uses the adjoint BSDF.
    Importance,
}

/// What a [`Bsdf`] scatters with, textures already looked up.
#[derive(Clone, Copy, Debug)]
pub enum BsdfKind {
    /// Lambertian: `f = albedo / π`.
    Diffuse {
        /// Reflectance per channel at this point (from the texture, if any).
        albedo: Rgb,
    },
    /// Perfect specular reflection.
    Mirror {
        /// Fraction reflected per channel, in [0, 1].
        reflectance: Rgb,
    },
    /// `eta` = index on the far side / index on the side of `wo`.
    Dielectric {
        /// Relative index of refraction across the surface, as seen from `wo`.
        eta: f32,
        /// Per-channel factor on refracted light, in [0, 1].
        transmittance: Rgb,
    },
    /// GGX reflection with a complex Fresnel term.
    Conductor(Conductor),
    /// GGX reflection and refraction.
    RoughDielectric(RoughDielectric),
    /// A diffuse base under a dielectric coat.
    Plastic(Plastic),
}

/// A BSDF at one surface point, oriented to the side its outgoing direction is on.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// The lobe and its parameters.
    pub kind: BsdfKind,
    /// Shading frame; its normal is on the side of `wo`.
    frame: Frame,
    /// Geometric normal on the side of `wo`: decides reflection from transmission.
    ng: Vec3,
}

/// A sampled direction and its weight `f · |cos θ| / pdf`.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled incident direction: unit length, world space, pointing away from the surface.
    pub wi: Vec3,
    /// `f · |cos θi| / pdf`; on light paths it includes the shading-normal correction.
    pub weight: Rgb,
    /// Solid-angle density; for a delta lobe, the probability of choosing that lobe.
    pub pdf: f32,
    /// Whether `wi` came from a delta lobe (mirror reflection or smooth
    /// refraction): no other strategy can produce it, and `pdf` is a probability.
    pub delta: bool,
    /// The relative index crossed: the far side's over `wo`'s side for a
    /// refraction, one for a reflection. A radiance weight through such a
    /// crossing carries 1/eta²; Russian roulette multiplies it back out.
    pub eta: f32,
}

impl Material {
    /// A plastic of base `albedo` under a coat of index `ior` and GGX width
    /// `alpha` (0: smooth), with its lobe weights and, for a rough coat,
    /// its tables (computed once per width and index).
    pub fn plastic(albedo: Albedo, ior: f32, alpha: f32) -> Material {
        Material::Plastic {
            specular_weight: plastic::specular_weight(albedo.mean()),
            albedo,
            ior,
            alpha,
            tables: plastic::is_rough(alpha).then(|| plastic::coat_tables(alpha, ior)),
        }
    }

    /// The BSDF for light leaving `surface` towards `wo` (a unit vector).
    // Inlined: see `Light::sample_incident`.
    #[inline(always)]
    pub fn bsdf(&self, surface: &SurfacePoint, wo: Vec3) -> Bsdf {
        let (ns, ng, outside) = facing_normals(surface, wo);
        let kind = match self {
            Material::Diffuse { albedo } => BsdfKind::Diffuse {
                albedo: albedo.at(surface),
            },
            Material::Mirror { reflectance } => BsdfKind::Mirror {
                reflectance: *reflectance,
            },
            Material::Dielectric { ior, transmittance } => BsdfKind::Dielectric {
                eta: if outside { *ior } else { 1.0 / *ior },
                transmittance: *transmittance,
            },
            Material::Conductor {
                alpha,
                eta,
                k,
                reflectance,
            } => BsdfKind::Conductor(Conductor {
                alpha: *alpha,
                eta: *eta,
                k: *k,
                reflectance: *reflectance,
            }),
            Material::RoughDielectric {
                ior,
                alpha,
                transmittance,
            } => BsdfKind::RoughDielectric(RoughDielectric {
                alpha: *alpha,
                eta: if outside { *ior } else { 1.0 / *ior },
                transmittance: *transmittance,
            }),
            Material::Plastic {
                albedo,
                ior,
                alpha,
                specular_weight,
                tables,
            } => BsdfKind::Plastic(Plastic {
                alpha: *alpha,
                eta: *ior,
                albedo: albedo.at(surface),
                specular_weight: *specular_weight,
                tables: *tables,
            }),
        };
        Bsdf::oriented(kind, ns, ng)
    }

    /// Whether the material scatters only into delta lobes (mirror or glass),
    /// so light sampling cannot connect to it.
    pub fn is_delta(&self) -> bool {
        match self {
            Material::Diffuse { .. } | Material::Plastic { .. } => false,
            Material::Mirror { .. } | Material::Dielectric { .. } => true,
            Material::Conductor { alpha, .. } | Material::RoughDielectric { alpha, .. } => {
                *alpha <= microfacet::SMOOTH_ALPHA
            }
        }
    }
}

/// The shading and geometric normals a BSDF at `surface` seen from `wo`
/// takes (see `Material::bsdf`), both on the side of `wo`, and whether
/// `wo` is on the geometric normal's side.
#[inline(always)]
pub fn facing_normals(surface: &SurfacePoint, wo: Vec3) -> (Vec3, Vec3, bool) {
    let outside = wo.dot(surface.geometric_normal) >= 0.0;
    let ng = if outside {
        surface.geometric_normal
    } else {
        -surface.geometric_normal
    };
    let mut ns = if outside {
        surface.shading_normal
    } else {
        -surface.shading_normal
    };
    // An interpolated normal can tilt past `wo`; the geometric one never does.
    if ns.dot(wo) <= 0.0 {
        ns = ng;
    }
    (ns, ng, outside)
}

impl Bsdf {
    /// The Lambertian BSDF of reflectance `albedo` with the shading and
    /// geometric normals `ns` and `ng` from [`facing_normals`]: what
    /// `Material::bsdf` makes of a diffuse material of that reflectance.
    #[inline(always)]
    pub fn lambertian_with(albedo: Rgb, ns: Vec3, ng: Vec3) -> Bsdf {
        Bsdf::oriented(BsdfKind::Diffuse { albedo }, ns, ng)
    }

    /// The lobe `kind` with the shading and geometric normals `ns` and
    /// `ng` from [`facing_normals`].
    #[inline(always)]
    fn oriented(kind: BsdfKind, ns: Vec3, ng: Vec3) -> Bsdf {
        Bsdf {
            kind,
            frame: Frame::new(ns),
            ng,
        }
    }

    /// Whether the BSDF has only delta lobes, so `eval` and `pdf` are always zero.
    pub fn is_delta(&self) -> bool {
        match self.kind {
            BsdfKind::Diffuse { .. } | BsdfKind::Plastic(_) => false,
            BsdfKind::Mirror { .. } | BsdfKind::Dielectric { .. } => true,
            BsdfKind::Conductor(c) => c.is_smooth(),
            BsdfKind::RoughDielectric(r) => r.is_smooth(),
        }
    }

    /// Unit shading normal, flipped to the side of `wo`.
    pub fn shading_normal(&self) -> Vec3 {
        self.frame.n
    }

    /// A Lambertian BSDF's reflectance, shading normal and geometric normal
    /// (both on the side of `wo`), for code that evaluates it in SIMD
    /// lanes; `None` for every other lobe.
    #[inline(always)]
    pub fn lambertian(&self) -> Option<(Rgb, Vec3, Vec3)> {
        match self.kind {
            BsdfKind::Diffuse { albedo } => Some((albedo, self.frame.n, self.ng)),
            _ => None,
        }
    }

    /// `f(wo, wi) · |cos θi|` for radiance, with θi measured from the
    /// shading normal; zero for delta lobes, and where the shading and
    /// geometric normals disagree on which side `wi` is.
    // Inlined, with `eval_local`: left out of line, the path tracer's light
    // sample paid two calls per vertex (see `integrator::connect::shadow_ray`).
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.eval_local(wo, wi, Transport::Radiance)
    }

    /// Whether `wi` is reflected (on `wo`'s geometric side); `None` when
    /// the shading normal puts it on the other side than the geometry does.
    #[inline]
    fn side(&self, wi: Vec3) -> Option<bool> {
        let reflected = wi.dot(self.ng) > 0.0;
        ((wi.dot(self.frame.n) > 0.0) == reflected).then_some(reflected)
    }

    #[inline(always)]
    fn eval_local(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Rgb {
        let Some(reflected) = self.side(wi) else {
            return Rgb::ZERO;
        };
        match &self.kind {
            BsdfKind::Diffuse { albedo } if reflected => {
                diffuse::eval(*albedo, self.frame.to_local(wi))
            }
            BsdfKind::Conductor(_) | BsdfKind::RoughDielectric(_) | BsdfKind::Plastic(_) => {
                self.eval_microfacet(wo, wi, reflected, mode)
            }
            _ => Rgb::ZERO,
        }
    }

    // The microfacet lobes stay out of line, so the diffuse path above
    // inlines into the integrators' loops.
    #[inline(never)]
    fn eval_microfacet(&self, wo: Vec3, wi: Vec3, reflected: bool, mode: Transport) -> Rgb {
        let (wo, wi_local) = (self.frame.to_local(wo), self.frame.to_local(wi));
        match &self.kind {
            BsdfKind::Conductor(c) if reflected => c.eval(wo, wi_local),
            BsdfKind::RoughDielectric(r) => r.eval(wo, wi_local, mode),
            BsdfKind::Plastic(p) if reflected => p.eval(wo, wi_local),
            _ => Rgb::ZERO,
        }
    }

    #[inline(never)]
    fn microfacet_pdfs(&self, wo: Vec3, wi: Vec3, reflected: bool) -> (f32, f32) {
        let (wo, wi_local) = (self.frame.to_local(wo), self.frame.to_local(wi));
        match &self.kind {
            BsdfKind::Conductor(c) if reflected => (c.pdf(wo, wi_local), c.pdf(wi_local, wo)),
            BsdfKind::RoughDielectric(r) => (r.pdf(wo, wi_local), r.reverse_pdf(wo, wi_local)),
            BsdfKind::Plastic(p) if reflected => (p.pdf(wo, wi_local), p.pdf(wi_local, wo)),
            _ => (0.0, 0.0),
        }
    }

    /// Solid-angle density with which [`Bsdf::sample`] picks `wi`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdfs(wo, wi).0
    }

    /// Densities of sampling `wi` given `wo`, and of `wo` given `wi` (the
    /// reverse direction that BDPT's MIS weights need); zero for delta lobes.
    #[inline]
    pub fn pdfs(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
        let Some(reflected) = self.side(wi) else {
            return (0.0, 0.0);
        };
        match &self.kind {
            BsdfKind::Diffuse { .. } if reflected => (
                diffuse::pdf(self.frame.to_local(wi)),
                diffuse::pdf(self.frame.to_local(wo)),
            ),
            BsdfKind::Conductor(_) | BsdfKind::RoughDielectric(_) | BsdfKind::Plastic(_) => {
                self.microfacet_pdfs(wo, wi, reflected)
            }
            _ => (0.0, 0.0),
        }
    }

    /// [`Bsdf::eval_mode`] and [`Bsdf::pdfs`] at once, for the connections
    /// that need all three: the side of `wi` and its local coordinates are
    /// then worked out once rather than three times. Returns f · |cos θi|,
    /// the density of `wi` given `wo`, and of `wo` given `wi`, each the
    /// same number the separate calls give.
    #[inline]
    pub fn eval_pdfs(&self, wo: Vec3, wi: Vec3, mode: Transport) -> (Rgb, f32, f32) {
        let Some(reflected) = self.side(wi) else {
            return (Rgb::ZERO, 0.0, 0.0);
        };
        let (value, pdf, reverse_pdf) = match &self.kind {
            BsdfKind::Diffuse { albedo } if reflected => {
                let wi_local = self.frame.to_local(wi);
                (
                    diffuse::eval(*albedo, wi_local),
                    diffuse::pdf(wi_local),
                    diffuse::pdf(self.frame.to_local(wo)),
                )
            }
            BsdfKind::Conductor(_) | BsdfKind::RoughDielectric(_) | BsdfKind::Plastic(_) => {
                let value = self.eval_microfacet(wo, wi, reflected, mode);
                let (pdf, reverse_pdf) = self.microfacet_pdfs(wo, wi, reflected);
                (value, pdf, reverse_pdf)
            }
            _ => return (Rgb::ZERO, 0.0, 0.0),
        };
        let value = match mode {
            Transport::Radiance => value,
            Transport::Importance => value * self.shading_correction(wo, wi),
        };
        (value, pdf, reverse_pdf)
    }

    /// Like [`Bsdf::eval`], for light flowing from `wi` to `wo` (radiance) or
    /// from `wo` to `wi` (importance, on light paths). For importance the
    /// cosine factor carries the correction that keeps shading normals
    /// consistent in the adjoint direction: f · |wo·ns| |wi·ng| / |wo·ng|
    /// (Veach's thesis, eq. 5.19), and refraction is not scaled by 1/eta².
    pub fn eval_mode(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Rgb {
        let value = self.eval_local(wo, wi, mode);
        match mode {
            Transport::Radiance => value,
            Transport::Importance => value * self.shading_correction(wo, wi),
        }
    }

    /// |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|): one unless the normals differ.
    fn shading_correction(&self, wo: Vec3, wi: Vec3) -> f32 {
        // Flat shading: numerator and denominator are the same product d,
        // so the general form below gives one, or zero where d is zero, or
        // NaN where d is NaN; this says so without its two dot products
        // and its division.
        if self.frame.n == self.ng {
            let d = wo.dot(self.ng).abs() * wi.dot(self.ng).abs();
            return if d > 0.0 {
                1.0
            } else if d <= 0.0 {
                0.0
            } else {
                f32::NAN
            };
        }
        let denominator = wo.dot(self.ng).abs() * wi.dot(self.frame.n).abs();
        if denominator <= 0.0 {
            return 0.0;
        }
        wo.dot(self.frame.n).abs() * wi.dot(self.ng).abs() / denominator
    }

    /// Samples an incident direction; `u` picks the direction, `u_lobe` the lobe.
    /// On light paths (`Transport::Importance`) the weight includes the
    /// shading-normal correction of [`Bsdf::eval_mode`].
    // Inlined: see `Light::sample_incident`.
    #[inline(always)]
    pub fn sample(
        &self,
        wo: Vec3,
        u: (f32, f32),
        u_lobe: f32,
        mode: Transport,
    ) -> Option<BsdfSample> {
        // Not needed by the diffuse lobe, whose directions ignore `wo`.
        let wo_local = || self.frame.to_local(wo);
        let (wi_local, weight, pdf, delta) = match self.kind {
            BsdfKind::Diffuse { albedo } => diffuse::sample(albedo, u)?,
            BsdfKind::Mirror { reflectance } => mirror::sample(reflectance, wo_local()),
            BsdfKind::Dielectric { eta, transmittance } => {
                dielectric::sample(eta, transmittance, wo_local(), u_lobe, mode)?
            }
            BsdfKind::Conductor(ref c) => c.sample(wo_local(), u)?,
            BsdfKind::RoughDielectric(ref r) => r.sample(wo_local(), u, u_lobe, mode)?,
            BsdfKind::Plastic(ref p) => p.sample(wo_local(), u, u_lobe)?,
        };
        let wi = self.frame.to_world(wi_local);
        // Shading normals can send a "reflected" direction through the surface
        // (or a refracted one back out): such a path would leak light, so end it.
        let reflected = wi_local.z > 0.0;
        if (wi.dot(self.ng) > 0.0) != reflected {
            return None;
        }
        let weight = match mode {
            Transport::Radiance => weight,
            Transport::Importance => weight * self.shading_correction(wo, wi),
        };
        let eta = match self.kind {
            BsdfKind::Dielectric { eta, .. } if !reflected => eta,
            BsdfKind::RoughDielectric(ref r) if !reflected => r.eta,
            _ => 1.0,
        };
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta,
            eta,
        })
    }
}

/// Reflects `w` about the +z axis of a local frame.
pub(crate) fn reflect_local(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// Reflects `w` about the unit normal `n`, given `cos = w·n`.
pub(crate) fn reflect(w: Vec3, n: Vec3, cos: f32) -> Vec3 {
    2.0 * cos * n - w
}

/// Refracts `w` through a surface with unit normal `n` on `w`'s side
/// (`cos = w·n > 0`) into a medium `eta` times denser, by Snell's law;
/// the caller has ruled out total internal reflection.
pub(crate) fn refract(w: Vec3, n: Vec3, cos: f32, eta: f32) -> Vec3 {
    let sin2_t = (1.0 - cos * cos) / (eta * eta);
    let cos_t = safe_sqrt(1.0 - sin2_t);
    (-w / eta + (cos / eta - cos_t) * n).normalize()
}

pub(crate) fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn a_lambertian_bsdf_from_its_parts_is_the_materials() {
        let material = Material::Diffuse {
            albedo: Albedo::Constant(Rgb::new(0.7, 0.4, 0.2)),
        };
        let ng = Vec3::Z;
        // Shading normals flat, tilted, and tilted past some of the `wo`.
        let shading = [
            ng,
            Vec3::new(0.3, 0.0, 1.0).normalize(),
            Vec3::new(0.0, -0.9, 0.2).normalize(),
        ];
        for ns in shading {
            let surface = SurfacePoint {
                position: Vec3::new(1.0, 2.0, 3.0),
                geometric_normal: ng,
                shading_normal: ns,
                uv: Vec2::ZERO,
                magnitude: 3.0,
            };
            for wo in [
                Vec3::new(0.2, 0.1, 0.97),
                Vec3::new(-0.5, 0.6, -0.62),
                Vec3::new(0.0, 0.995, 0.1),
            ] {
                let wo = wo.normalize();
                let whole = material.bsdf(&surface, wo);
                let (albedo, lobe_ns, lobe_ng) = whole.lambertian().expect("diffuse");
                let (ns, ng, _) = facing_normals(&surface, wo);
                assert_eq!((lobe_ns, lobe_ng), (ns, ng));
                let parts = Bsdf::lambertian_with(albedo, ns, ng);
                // Debug prints each float exactly (shortest round trip).
                assert_eq!(
                    format!("{whole:?}"),
                    format!("{parts:?}"),
                    "ns {ns}, wo {wo}"
                );
            }
        }
    }
}
