//! Triangles, rays and the bounding boxes the BVH is built from; surface
//! points and the shading frame around a normal.

pub mod aabb;
mod frame;
pub mod ray;
pub mod shapes;
mod surface;
pub mod transform;
pub mod triangle;

pub use aabb::Aabb;
pub use frame::Frame;
pub use ray::Ray;
pub use surface::SurfacePoint;
pub use triangle::{Triangle, TriangleHit};
