//! `tracer`: a physically based offline renderer.
//!
//! Follow one sample from the command line to the film:
//! [`cli`] parses flags → [`scene::load`] reads the scene and builds the [`bvh`] →
//! [`render`] splits the image into tiles → [`camera`] makes a ray →
//! [`integrator`] traces it through [`bvh`], [`material`] and [`light`] →
//! [`film`] accumulates and writes the image.

pub mod bench;
pub mod bvh;
pub mod camera;
pub mod cli;
pub mod color;
pub mod error;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod pod_array;
pub mod preview;
pub mod render;
pub mod sampling;
pub mod scene;

pub use error::{Error, Result};
