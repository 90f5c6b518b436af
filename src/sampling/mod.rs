//! Random numbers for the integrators, and the warps that turn them into
//! directions and points.

pub mod alias;
pub mod distribution;
pub mod sampler;
pub mod warp;

pub use alias::AliasTable;
pub use distribution::Distribution1D;
pub use sampler::{PixelSeed, Sampler, VertexNumbers};
