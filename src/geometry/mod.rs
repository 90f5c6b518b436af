//! Triangles, rays and the bounding boxes the BVH is built from.

pub mod aabb;
pub mod ray;
pub mod shapes;
pub mod transform;
pub mod triangle;

pub use aabb::Aabb;
pub use ray::Ray;
pub use triangle::{Triangle, TriangleHit};
