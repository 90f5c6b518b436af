//! `tracer`: a physically based offline renderer.
//!
//! Follow one sample from a scene file to the film:
//! [`format`](mod@format) reads the scene into a description and [`settings`] →
//! [`scene::build`] builds its triangles, materials, lights and [`bvh`] →
//! [`render`] splits the image into tiles → [`camera`] makes a ray →
//! [`integrator`] traces it through [`bvh`], [`material`] and [`light`] →
//! [`film`] accumulates and writes the image.
//!
//! Modules depend one way: [`color`], [`geometry`], [`sampling`] →
//! [`material`], [`light`], [`bvh`], [`film`], [`camera`] → [`settings`],
//! [`format`](mod@format) → [`scene`] → [`integrator`] → [`render`]. The command line
//! lives in the `tracer` binary, not here.

pub mod bench;
pub mod bvh;
pub mod camera;
pub mod color;
pub mod error;
pub mod files;
pub mod film;
pub mod format;
pub mod geometry;
pub mod huge_pages;
pub mod integrator;
pub mod light;
pub mod material;
pub mod pod_array;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod settings;

pub use error::{Error, Result};
