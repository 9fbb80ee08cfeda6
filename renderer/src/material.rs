//! Materials: POV-Ray's pigment and finish, parameter for parameter, or one of the physical
//! models. Scene data, read by both integrators.

/// Colours are `f32` RGB in both precisions (as in POV-Ray).
pub type Color = glam::Vec3;

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
