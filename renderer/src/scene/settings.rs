//! Render settings: image size, sampling, trace depth and the light-transport model.

use crate::material::Color;

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
    pub integrator: Integrator,
    /// Depth from which the path integrator plays Russian roulette.
    pub rr_depth: u32,
    /// Sample placement.
    pub sampler: crate::sampler::SamplerKind,
    /// Share the samples out by the noise around each pixel (adaptive.rs): `samples` is
    /// then the average a pixel.
    pub adaptive: bool,
    /// Physical model: aim some continuation directions at specular objects (guide.rs).
    pub guides: bool,
    /// Path integrator: light paths traced per camera sample for the caustics seen
    /// directly (light_paths.rs); 0 turns them off.
    pub light_paths: f64,
    /// Physical model: how next-event estimation picks lights.
    pub light_sampling: LightSampling,
}

/// How the physical integrators' next-event estimation picks lights at a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LightSampling {
    /// Every light once: a shadow ray each, less noise a sample.
    #[default]
    All,
    /// One light, chosen uniformly among all of them, weighted by their number: one
    /// shadow ray, as Mitsuba 3's emitter sampling does.
    One,
}

/// Light transport.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// POV-Ray 3.7's classic model (shading.rs).
    #[default]
    Classic,
    /// Mitsuba's `direct`.
    Direct,
    /// Mitsuba's `path`.
    Path,
}
