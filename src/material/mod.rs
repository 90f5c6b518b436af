//! Materials, and the BSDFs they become at a surface point.
//!
//! A [`Material`] is what the scene names; [`Material::bsdf`] resolves its
//! textures at a hit and orients it towards the outgoing direction, giving a
//! [`Bsdf`] the integrators sample and evaluate. Both are enums, so the hot
//! loops dispatch with a `match`, not a virtual call.

mod dielectric;
mod diffuse;
mod mirror;
pub mod texture;

pub use dielectric::fresnel_dielectric;
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
}

impl Material {
    /// The BSDF for light leaving `surface` towards `wo` (a unit vector).
    pub fn bsdf(&self, surface: &SurfacePoint, wo: Vec3) -> Bsdf {
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
        let kind = match self {
            Material::Diffuse { albedo } => BsdfKind::Diffuse {
                albedo: match albedo {
                    Albedo::Constant(c) => *c,
                    Albedo::Texture(t) => t.lookup(surface.uv),
                },
            },
            Material::Mirror { reflectance } => BsdfKind::Mirror {
                reflectance: *reflectance,
            },
            Material::Dielectric { ior, transmittance } => BsdfKind::Dielectric {
                eta: if outside { *ior } else { 1.0 / *ior },
                transmittance: *transmittance,
            },
        };
        Bsdf {
            kind,
            frame: Frame::new(ns),
            ng,
        }
    }

    /// Whether the material scatters only into delta lobes (mirror or glass),
    /// so light sampling cannot connect to it.
    pub fn is_delta(&self) -> bool {
        !matches!(self, Material::Diffuse { .. })
    }
}

impl Bsdf {
    /// Whether the BSDF has only delta lobes, so `eval` and `pdf` are always zero.
    pub fn is_delta(&self) -> bool {
        !matches!(self.kind, BsdfKind::Diffuse { .. })
    }

    /// Unit shading normal, flipped to the side of `wo`.
    pub fn shading_normal(&self) -> Vec3 {
        self.frame.n
    }

    /// `f(wo, wi) · |cos θi|` with θi measured from the shading normal; zero for
    /// delta lobes and for directions on the wrong geometric side.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self.kind {
            BsdfKind::Diffuse { albedo } => {
                if wi.dot(self.ng) <= 0.0 {
                    return Rgb::ZERO;
                }
                diffuse::eval(albedo, self.frame.to_local(wi))
            }
            _ => {
                let _ = wo;
                Rgb::ZERO
            }
        }
    }

    /// Solid-angle density with which [`Bsdf::sample`] picks `wi`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdfs(wo, wi).0
    }

    /// Densities of sampling `wi` given `wo`, and of `wo` given `wi` (the
    /// reverse direction that BDPT's MIS weights need); zero for delta lobes.
    pub fn pdfs(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
        match self.kind {
            BsdfKind::Diffuse { .. } if wi.dot(self.ng) > 0.0 => (
                diffuse::pdf(self.frame.to_local(wi)),
                diffuse::pdf(self.frame.to_local(wo)),
            ),
            _ => (0.0, 0.0),
        }
    }

    /// Like [`Bsdf::eval`], for light flowing from `wi` to `wo` (radiance) or
    /// from `wo` to `wi` (importance, on light paths). For importance the
    /// cosine factor carries the correction that keeps shading normals
    /// consistent in the adjoint direction: f · |wo·ns| |wi·ng| / |wo·ng|
    /// (Veach's thesis, eq. 5.19).
    pub fn eval_mode(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Rgb {
        let value = self.eval(wo, wi);
        match mode {
            Transport::Radiance => value,
            Transport::Importance => value * self.shading_correction(wo, wi),
        }
    }

    /// |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|): one unless the normals differ.
    fn shading_correction(&self, wo: Vec3, wi: Vec3) -> f32 {
        let denominator = wo.dot(self.ng).abs() * wi.dot(self.frame.n).abs();
        if denominator <= 0.0 {
            return 0.0;
        }
        wo.dot(self.frame.n).abs() * wi.dot(self.ng).abs() / denominator
    }

    /// Samples an incident direction; `u` picks the direction, `u_lobe` the lobe.
    /// On light paths (`Transport::Importance`) the weight includes the
    /// shading-normal correction of [`Bsdf::eval_mode`].
    pub fn sample(
        &self,
        wo: Vec3,
        u: (f32, f32),
        u_lobe: f32,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let wo_local = self.frame.to_local(wo);
        let (wi_local, weight, pdf, delta) = match self.kind {
            BsdfKind::Diffuse { albedo } => diffuse::sample(albedo, u)?,
            BsdfKind::Mirror { reflectance } => mirror::sample(reflectance, wo_local),
            BsdfKind::Dielectric { eta, transmittance } => {
                dielectric::sample(eta, transmittance, wo_local, u_lobe, mode)?
            }
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
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta,
        })
    }
}

/// Reflects `w` about the +z axis of a local frame.
pub(crate) fn reflect_local(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

pub(crate) fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}
