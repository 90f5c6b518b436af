//! Picks which light to sample, with probability proportional to its power,
//! so bright lights get the shadow rays.

use super::Light;
use crate::sampling::Distribution1D;

#[derive(Clone, Debug, Default)]
pub struct LightSelector {
    distribution: Option<Distribution1D>,
}

impl LightSelector {
    pub fn new(lights: &[Light]) -> LightSelector {
        let powers: Vec<f32> = lights.iter().map(Light::power).collect();
        LightSelector {
            distribution: Distribution1D::new(&powers),
        }
    }

    /// A light index and its probability; `None` for a scene that emits nothing.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        self.distribution.as_ref().map(|d| d.sample(u))
    }

    pub fn pmf(&self, light: usize) -> f32 {
        self.distribution.as_ref().map_or(0.0, |d| d.pmf(light))
    }
}
