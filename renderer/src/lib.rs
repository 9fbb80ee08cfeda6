//! A verified classic ray tracer.
//!
//! See ARCHITECTURE.md at the repository root for the bird's-eye view and invariants.

pub mod aabb;
pub mod aggregate;
pub mod bvh;
pub mod camera;
pub mod hit;
pub mod light;
pub mod material;
pub mod output;
pub mod physical;
pub mod ray;
pub mod real;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod shading;
pub mod shapes;
pub mod spawn;
pub mod transform;

pub use aggregate::Shape;
pub use aggregate::{Aggregate, Instance};
pub use camera::{Camera, ViewingModel, Window};
pub use hit::Hit;
pub use ray::Ray;
pub use real::{Real, Vec3};
pub use transform::{Affine64, Transform};
