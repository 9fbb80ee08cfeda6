//! The physically based model: radiometric, in linear RGB, following Mitsuba 3's
//! definitions so that the same numbers mean the same image
//! (renderer/docs/physical.md cites the Mitsuba source for each).
//!
//! - BSDFs: Lambertian `diffuse` (reflectance/π, two-sided), smooth `conductor` (a perfect
//!   mirror scaled by its specular reflectance), smooth `dielectric` (Fresnel reflection
//!   and refraction, interior ior over exterior 1).
//! - Lights: `point` (intensity, W/sr), `directional` (irradiance), area lights (emissive
//!   spheres and rectangles, radiance on the side of their normal), and a constant
//!   `environment` (radiance).
//! - Integrators: `direct` (emitters seen directly or through one BSDF sample, plus light
//!   sampling at the first hit, combined by multiple importance sampling) and `path`
//!   (unidirectional path tracing with next-event estimation, MIS, `max_depth` and Russian
//!   roulette from `rr_depth`).
//!
//! `bsdf.rs` holds the BSDFs and the surface record, `vertex.rs` what a path vertex asks
//! of the scene, `integrator.rs` the integrators, `guide.rs` the specular guides, and
//! `light_paths.rs` the light paths for the caustics seen directly. Imports point one
//! way: the integrator uses the light paths, which use neither it nor this module.

mod bsdf;
pub mod guide;
mod integrator;
mod light_paths;
mod vertex;

pub use integrator::{Fault, PhysicalIntegrator};
pub(crate) use light_paths::fold as fold_light_image;
