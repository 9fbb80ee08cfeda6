//! Scenes: the file format ([`format`]), its errors ([`error`]) and the built, render-ready
//! [`Scene`] ([`build`]).

pub mod build;
pub mod error;
pub mod format;

use crate::aggregate::Aggregate;
use crate::camera::Camera;
use crate::real::{Real, Vec3};
pub use error::SceneError;
use std::path::Path;

/// Colours are `f32` RGB in both precisions (as in POV-Ray).
pub type Color = glam::Vec3;

/// Render settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Pixel columns.
    pub width: u32,
    /// Pixel rows.
    pub height: u32,
    /// Samples per pixel.
    pub samples: u32,
    /// Maximum trace depth: a path hits at most this many surfaces.
    pub max_depth: u32,
    /// Rays whose weight falls below this are not traced.
    pub adc_bailout: f32,
    /// Colour of rays that hit nothing.
    pub background: Color,
    /// Global ambient light.
    pub ambient_light: Color,
    /// Light transport.
    pub integrator: crate::physical::Integrator,
    /// Depth from which the path integrator plays Russian roulette.
    pub rr_depth: u32,
    /// Sample placement.
    pub sampler: crate::sampler::SamplerKind,
}

pub use format::LightKind;

/// A light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Kind.
    pub kind: LightKind,
    /// Position (point lights; zero otherwise).
    pub position: Vec3,
    /// Unit direction the light travels (directional lights; zero otherwise).
    pub direction: Vec3,
    /// Colour.
    pub color: Color,
    /// Fade distance and power, when fading is on.
    pub fade: Option<(Real, Real)>,
}

/// Which reflectance model a material uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialModel {
    /// POV-Ray's pigment and finish (the classic integrator).
    #[default]
    Classic,
    /// Lambertian: `color` is the reflectance.
    Diffuse,
    /// A perfect mirror: `color` is the specular reflectance.
    Conductor,
    /// A smooth dielectric with Fresnel reflection and refraction; `ior` inside, 1 outside.
    Dielectric,
}

/// A material: POV-Ray's pigment and finish, parameter for parameter, or a physical model.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// Reflectance model.
    pub model: MaterialModel,
    /// Emitted radiance (area lights; zero when not emitting).
    pub radiance: Color,
    /// Pigment colour.
    pub color: Color,
    /// Filtered transparency.
    pub filter: f32,
    /// Unfiltered transparency.
    pub transmit: f32,
    /// Ambient coefficient.
    pub ambient: f32,
    /// Emission coefficient.
    pub emission: f32,
    /// Diffuse coefficient.
    pub diffuse: f32,
    /// Diffuse exponent.
    pub brilliance: f32,
    /// Phong amount.
    pub phong: f32,
    /// Phong exponent.
    pub phong_size: f32,
    /// Specular amount.
    pub specular: f32,
    /// Specular roughness.
    pub roughness: f32,
    /// Reflection amount.
    pub reflection: f32,
    /// Interior index of refraction.
    pub ior: f32,
}

impl Default for Material {
    /// White pigment with POV-Ray's default finish.
    fn default() -> Self {
        Material {
            name: "default".into(),
            model: MaterialModel::Classic,
            radiance: Color::ZERO,
            color: Color::ONE,
            filter: 0.0,
            transmit: 0.0,
            ambient: 0.1,
            emission: 0.0,
            diffuse: 0.6,
            brilliance: 1.0,
            phong: 0.0,
            phong_size: 40.0,
            specular: 0.0,
            roughness: 0.05,
            reflection: 0.0,
            ior: 1.0,
        }
    }
}

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
    pub area_lights: Vec<crate::physical::AreaLight>,
    /// For each object id, the index of its area light, or `u32::MAX`.
    pub area_light_of: Vec<u32>,
}

impl Scene {
    /// Reads and builds a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.display().to_string(),
            line: 0,
            column: 0,
            field: "(file)".into(),
            message: format!("cannot read: {e}"),
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        Scene::from_str(&text, path, base)
    }

    /// Builds a scene from text. `file` names it in errors; meshes resolve against `base`.
    pub fn from_str(text: &str, file: &Path, base: &Path) -> Result<Scene, SceneError> {
        build::build(text, file, base)
    }

    /// The material of a hit.
    #[inline]
    pub fn material(&self, index: u32) -> &Material {
        self.materials
            .get(index as usize)
            .unwrap_or(&self.materials[0])
    }
}
