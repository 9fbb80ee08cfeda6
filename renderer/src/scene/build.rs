//! From the parsed file to a render-ready [`Scene`]: validation, transform composition,
//! material and definition resolution, mesh loading, and the acceleration structure.
//!
//! Groups in the object tree are flattened: their transforms compose into each leaf.
//! Named definitions are built once into a shared [`Aggregate`] and placed by reference,
//! so a definition instanced many times is stored once. Meshes are loaded once per file.

use super::camera_desc::build_camera;
use super::definitions::check_definitions;
use super::error::{SceneError, Source};
use super::format;
use super::materials_desc::color;
use super::nodes::Builder;
use super::numbers::check_precision;
use super::origin::render_origin;
use super::scale_check;
use super::{lights_desc, materials_desc};
use super::{Color, Integrator, Scene, Settings};
use crate::aggregate::Aggregate;
use crate::light::AreaLight;
use crate::real::vec3;
use glam::DVec3;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// The largest image, in pixels: 2²⁷ (for example 16384 × 8192). At
/// [`PEAK_BYTES_PER_PIXEL`] the largest could need 22.5 GB.
pub const MAX_PIXELS: u64 = 1 << 27;

/// The most memory a render and its output take per pixel, in bytes, at their peak: the
/// image's RGB and AOVs; the second moments; adaptive sampling's pilot and scores between
/// its passes; the light paths' image; and the EXR writer's copy of every channel. Measured
/// with a counting allocator, the worst case (adaptive, AOVs, moments, EXR) takes 165.6
/// bytes a pixel; a PNG 17 to 64, an EXR with AOVs 88 to 90 (renderer/tests/memory.rs,
/// which fails when a render takes more than this, or much less).
pub const PEAK_BYTES_PER_PIXEL: u64 = 168;

/// The most memory a render takes per row of the image beyond its pixels', in bytes: the
/// rows' slices of the image and its moments, adaptive sampling's sums of whole rows. It
/// counts where an image is a few pixels wide (renderer/tests/memory.rs: 192.0 bytes a
/// row one pixel wide, 165.6 of them the pixel's).
pub const PEAK_BYTES_PER_ROW: u64 = 32;

/// Bytes a render of `width` × `height` pixels may need at its peak
/// ([`PEAK_BYTES_PER_PIXEL`], [`PEAK_BYTES_PER_ROW`]).
pub fn image_bytes(width: u64, height: u64) -> u64 {
    width * height * PEAK_BYTES_PER_PIXEL + height * PEAK_BYTES_PER_ROW
}

/// Checks an image size: each side at least 1, and at most [`MAX_PIXELS`] pixels. The
/// error names `width` or `height` and says why.
pub fn check_size(width: u32, height: u32) -> Result<(), (&'static str, String)> {
    if width == 0 {
        return Err(("width", "must be at least 1".into()));
    }
    if height == 0 {
        return Err(("height", "must be at least 1".into()));
    }
    let px = width as u64 * height as u64;
    if px > MAX_PIXELS {
        let side = if width >= height { "width" } else { "height" };
        return Err((
            side,
            format!(
                "{width} × {height} = {px} pixels is more than the limit of {MAX_PIXELS} (2^27): \
a render could need {:.1} GB",
                image_bytes(width as u64, height as u64) as f64 / 1e9
            ),
        ));
    }
    Ok(())
}

/// The largest `render.max_depth`: POV-Ray's limit for `max_trace_level`. It bounds the
/// classic model's recursion (with [`crate::shading::MAX_PASS_THROUGH`]) and every path.
pub const MAX_DEPTH: u32 = 256;

/// The largest `render.light_paths` (light paths per camera sample): more would take most
/// of a render's time for the caustics alone.
pub const MAX_LIGHT_PATHS: f64 = 16.0;

/// Checks a sample count.
pub fn check_samples(samples: u32) -> Result<(), String> {
    if samples == 0 {
        return Err("must be at least 1".into());
    }
    Ok(())
}

/// Settings given on the command line that replace the scene file's, validated like them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overrides {
    /// Image width and height (`--size WxH`).
    pub size: Option<(u32, u32)>,
    /// Samples per pixel (`--spp N`).
    pub samples: Option<u32>,
    /// Adaptive sampling on (`--adaptive`).
    pub adaptive: bool,
}

impl Overrides {
    /// Validates the overrides on their own, naming the option in the message.
    pub fn check(&self) -> Result<(), String> {
        if let Some((w, h)) = self.size {
            check_size(w, h).map_err(|(side, m)| format!("--size {w}x{h}: the {side} {m}"))?;
        }
        if let Some(n) = self.samples {
            check_samples(n).map_err(|m| format!("--spp {n}: {m}"))?;
        }
        Ok(())
    }
}

/// Parses and builds.
pub fn build(text: &str, file: &Path, base: &Path) -> Result<Scene, SceneError> {
    build_with(text, file, base, &Overrides::default())
}

/// Parses and builds, with command-line overrides of the render settings.
pub fn build_with(
    text: &str,
    file: &Path,
    base: &Path,
    overrides: &Overrides,
) -> Result<Scene, SceneError> {
    let src = Source::new(file, text);
    let table = toml::de::DeTable::parse(text).map_err(|e| {
        src.error(
            e.span().map_or(0, |s| s.start),
            "(syntax)",
            e.message().to_string(),
        )
    })?;
    check_precision(&table, &src)?;
    let mut desc = format::parse_table(table, text).map_err(|(span, path, msg)| {
        let field = if path.is_empty() || path == "." {
            "(syntax)".to_string()
        } else {
            path
        };
        src.error(span.map_or(0, |s| s.start), field, msg)
    })?;
    let render_span = desc.render.span();
    let at_render = |field: &str, msg: &str| {
        src.key_error(render_span.clone(), field, format!("render.{field}"), msg)
    };
    let r = desc.render.get_ref();
    if let Err((side, m)) = check_size(r.width, r.height) {
        return Err(at_render(side, &m));
    }
    if let Err(m) = check_samples(r.samples) {
        return Err(at_render("samples", &m));
    }
    if r.max_depth > MAX_DEPTH {
        return Err(at_render(
            "max_depth",
            &format!(
                "{} is more than the limit of {MAX_DEPTH} (POV-Ray's own limit for max_trace_level); \
it bounds the recursion of the classic model and the length of a path",
                r.max_depth
            ),
        ));
    }
    overrides.check().map_err(|m| SceneError {
        file: src.file.clone(),
        line: 0,
        column: 0,
        field: "(command line)".into(),
        message: m,
    })?;
    let r = desc.render.get_mut();
    if let Some((w, h)) = overrides.size {
        (r.width, r.height) = (w, h);
    }
    if let Some(n) = overrides.samples {
        r.samples = n;
    }
    r.adaptive |= overrides.adaptive;
    let r = desc.render.get_ref();
    for (name, v) in [
        ("background", r.background),
        ("ambient_light", r.ambient_light),
    ] {
        if v.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(at_render(name, "colour components must be finite and ≥ 0"));
        }
    }
    if !(r.adc_bailout.is_finite() && r.adc_bailout >= 0.0) {
        return Err(at_render("adc_bailout", "must be finite and ≥ 0"));
    }
    if !(r.light_paths.is_finite() && (0.0..=MAX_LIGHT_PATHS).contains(&r.light_paths)) {
        return Err(at_render(
            "light_paths",
            &format!(
                "must be a number from 0 to {MAX_LIGHT_PATHS} (light paths per camera sample)"
            ),
        ));
    }
    let settings = Settings {
        width: r.width,
        height: r.height,
        samples: r.samples,
        max_depth: r.max_depth,
        adc_bailout: r.adc_bailout as f32,
        background: color(r.background),
        ambient_light: color(r.ambient_light),
        integrator: r.integrator,
        rr_depth: r.rr_depth,
        sampler: r.sampler,
        adaptive: r.adaptive,
        guides: r.guides,
        light_paths: r.light_paths,
        light_sampling: r.light_sampling,
    };
    let classic = r.integrator == Integrator::Classic;
    let camera = build_camera(&desc.camera, r.width, r.height, &src)?;

    let (mut lights, light_positions) = lights_desc::build_lights(&desc.lights, classic, &src)?;
    let (materials, material_index) =
        materials_desc::build_materials(&desc.materials, classic, &src)?;

    let emissive: Vec<bool> = materials
        .iter()
        .map(|m| m.radiance != Color::ZERO)
        .collect();
    check_definitions(&desc.defs, &src)?;
    let mut b = Builder {
        src: &src,
        emissive,
        base: base.to_path_buf(),
        materials: material_index,
        defs: &desc.defs,
        built_defs: HashMap::new(),
        in_progress: HashSet::new(),
        meshes: HashMap::new(),
        objects: Vec::new(),
        origin: DVec3::ZERO,
        eye: camera.eye64,
        tau: scale_check::tolerance(camera.pixel_angle()),
        notes: Vec::new(),
        mixed: desc.render.get_ref().mixed_precision,
    };
    // Build in world coordinates; then, if the scene lies far from the world origin
    // compared with its own extent, build its objects again in a render space whose
    // origin is the eye (definitions and meshes are reused: they have their own spaces).
    let mut root = Aggregate::new(b.top_level(&desc.objects, DVec3::ZERO)?);
    let origin = render_origin(&root, camera.eye64);
    let camera = if origin == DVec3::ZERO {
        camera
    } else {
        root = Aggregate::new(b.top_level(&desc.objects, origin)?);
        camera.rebased(origin)
    };
    for (l, p) in lights.iter_mut().zip(light_positions) {
        l.position = vec3(p - origin);
    }
    let objects = std::mem::take(&mut b.objects);
    let scale_notes = std::mem::take(&mut b.notes);
    if root.surface_count().is_none() {
        return Err(src.error(
            0,
            "objects",
            "the scene expands to more than 2^64 - 1 surfaces (instances of definitions \
             multiply); a scene's surfaces must be countable in 64 bits",
        ));
    }
    let mut area_lights = Vec::new();
    let mut area_light_of = vec![u32::MAX; objects.len() + 1];
    for inst in root.in_scene_order() {
        if materials[inst.material as usize].radiance != Color::ZERO {
            area_light_of[inst.object_id as usize] = area_lights.len() as u32;
            area_lights.push(AreaLight::new(
                inst,
                materials[inst.material as usize].radiance,
            ));
        }
    }
    Ok(Scene {
        camera,
        settings,
        lights,
        materials,
        root,
        objects,
        area_lights,
        area_light_of,
        scale_notes,
    })
}

impl Scene {
    /// Reads and builds a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with(path, &Overrides::default())
    }

    /// Reads and builds a scene file with command-line overrides of its render settings.
    pub fn load_with(path: &Path, overrides: &Overrides) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            SceneError::unlocated(path, "", format!("cannot read the scene file: {e}"))
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        build_with(&text, path, base, overrides)
    }

    /// Builds a scene from text. `file` names it in errors; meshes resolve against `base`.
    pub fn from_str(text: &str, file: &Path, base: &Path) -> Result<Scene, SceneError> {
        build(text, file, base)
    }
}
