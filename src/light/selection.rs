//! Picks which light to sample, with probability proportional to its power,
//! so bright lights get the shadow rays. An alias table makes the choice in
//! constant time, whatever the number of lights (every emissive triangle
//! is one).

use super::Light;
use crate::sampling::AliasTable;

/// Chooses a light with probability proportional to its [`Light::power`].
#[derive(Clone, Debug, Default)]
pub struct LightSelector {
    distribution: Option<AliasTable>,
}

impl LightSelector {
    /// A selector over `lights`, by index into that slice; it selects nothing
    /// when no light has positive power.
    pub fn new(lights: &[Light]) -> LightSelector {
        let powers: Vec<f32> = lights.iter().map(Light::power).collect();
        LightSelector {
            distribution: AliasTable::new(&powers),
        }
    }

    /// A light index and its probability; `None` for a scene that emits nothing.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        self.distribution.as_ref().map(|d| d.sample(u))
    }

    /// Probability of selecting light `light`; zero when nothing can be selected.
    pub fn pmf(&self, light: usize) -> f32 {
        self.distribution.as_ref().map_or(0.0, |d| d.pmf(light))
    }
}
