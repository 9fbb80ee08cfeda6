//! Scenes: the file format ([`format`]), its errors ([`error`]), the render settings
//! ([`settings`]) and the built, render-ready [`Scene`] ([`build`] reads and builds it).
//! Lights and materials are scene data in their own modules (`crate::light`,
//! `crate::material`); the integrators read the scene, and nothing here reads them.

pub mod build;
mod camera_desc;
mod definitions;
pub mod error;
pub mod format;
mod lights_desc;
mod materials_desc;
mod nodes;
mod numbers;
mod origin;
pub mod scale_check;
pub mod settings;
mod transform_ops;

use crate::aggregate::Aggregate;
use crate::camera::Camera;
pub use crate::light::{AreaLight, Light, LightKind};
pub use crate::material::{Color, Material, MaterialModel};
pub use error::SceneError;
pub use settings::{Integrator, Settings};

/// A render-ready scene.
#[derive(Debug)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Render settings.
    pub settings: Settings,
    /// Lights.
    pub lights: Vec<Light>,
    /// Materials; index 0 is the default material.
    pub materials: Vec<Material>,
    /// The object tree, flattened into instances under a BVH.
    pub root: Aggregate,
    /// Scene-file path of each object id (id k is at index k − 1).
    pub objects: Vec<String>,
    /// Area lights (emissive spheres and rectangles).
    pub area_lights: Vec<AreaLight>,
    /// For each object id, the index of its area light, or `u32::MAX`.
    pub area_light_of: Vec<u32>,
    /// The scene's objects whose own size is too large next to the distances the camera
    /// sees for the build's precision, each moved to mixed precision or warned about
    /// (`scale_check`, renderer/docs/precision.md).
    pub scale_notes: Vec<scale_check::ScaleNote>,
}

impl Scene {
    /// The world point at render space's origin: 0, or the eye when the scene was moved
    /// there for precision (scene/origin.rs, `render_origin`). Hit points, lights and the
    /// camera are in render space; add this to report world coordinates.
    pub fn origin(&self) -> glam::DVec3 {
        self.camera.origin()
    }

    /// The material of a hit.
    #[inline]
    pub fn material(&self, index: u32) -> &Material {
        self.materials
            .get(index as usize)
            .unwrap_or(&self.materials[0])
    }
}
