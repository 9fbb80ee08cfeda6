//! From the parsed file to a render-ready [`Scene`]: validation, transform composition,
//! material and definition resolution, mesh loading, and the acceleration structure.
//!
//! Groups in the object tree are flattened: their transforms compose into each leaf.
//! Named definitions are built once into a shared [`Aggregate`] and placed by reference,
//! so a definition instanced many times is stored once. Meshes are loaded once per file.

use super::error::{SceneError, Source};
use super::format::{self, CameraDesc, NodeDesc, NodeKind, ScaleArg, TransformOp, V3};
use super::{Color, Integrator, Light, LightKind, Material, MaterialModel, Scene, Settings};
use crate::aggregate::Shape;
use crate::aggregate::{Aggregate, Instance, INHERIT};
use crate::camera::{Camera, CameraError, ViewingModel, Window};
use crate::light::AreaLight;
use crate::real::{vec3, Real, Vec2};
use crate::shapes::{Mesh, Triangle};
use crate::suggest::did_you_mean;
use crate::transform::{Affine64, Transform};
use glam::{DMat3, DVec3};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;

fn dv(v: V3) -> DVec3 {
    DVec3::from_array(v.0)
}

fn color(v: V3) -> Color {
    Color::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// The largest image, in pixels: 2²⁷ (for example 16384 × 8192). An image with AOVs and
/// second moments holds 18 floats (72 bytes) per pixel, so the largest needs 9.7 GB.
pub const MAX_PIXELS: u64 = 1 << 27;

/// Bytes an image of `pixels` pixels may need: RGB, the geometry AOVs (Z, N, P, objectId)
/// and the second moments, as 32-bit floats.
pub fn image_bytes(pixels: u64) -> u64 {
    pixels * 18 * 4
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
the image with its AOVs could need {:.1} GB",
                image_bytes(px) as f64 / 1e9
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

    let mut lights = Vec::new();
    let mut light_positions = Vec::new();
    for (k, l) in desc.lights.iter().enumerate() {
        let d = l.get_ref();
        let field = format!("lights[{k}]");
        let err = |f: &str, m: &str| src.key_error(l.span(), f, format!("{field}.{f}"), m);
        let (mut position, mut direction) = (DVec3::ZERO, DVec3::ZERO);
        match d.kind {
            LightKind::Point => {
                let p = d
                    .position
                    .ok_or_else(|| err("position", "a point light needs a position"))?;
                if p.iter().any(|x| !x.is_finite()) {
                    return Err(err("position", "must be finite"));
                }
                position = dv(p);
            }
            LightKind::Directional => {
                let v = dv(d
                    .direction
                    .ok_or_else(|| err("direction", "a directional light needs a direction"))?);
                if !(v.length() > 0.0 && v.is_finite()) {
                    return Err(err("direction", "must be a finite, non-zero vector"));
                }
                direction = v.normalize();
            }
            LightKind::Environment => {}
        }
        light_positions.push(position);
        if d.kind != LightKind::Point && classic {
            return Err(err(
                "type",
                "directional and environment lights need the direct or path integrator",
            ));
        }
        if d.kind != LightKind::Point && d.position.is_some() {
            return Err(err("position", "only point lights have a position"));
        }
        if d.kind != LightKind::Directional && d.direction.is_some() {
            return Err(err("direction", "only directional lights have a direction"));
        }
        if d.color.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(err("color", "components must be finite and ≥ 0"));
        }
        let fade = match (d.fade_distance, d.fade_power) {
            (Some(dist), Some(pow)) if pow > 0.0 => {
                if !(dist > 0.0 && dist.is_finite() && pow.is_finite()) {
                    return Err(err(
                        "fade_distance",
                        "fade_distance must be > 0 and both finite",
                    ));
                }
                Some((dist as Real, pow as Real))
            }
            _ => None,
        };
        lights.push(Light {
            kind: d.kind,
            // World coordinates for now; moved into render space once the origin is known.
            position: vec3(position),
            direction: vec3(direction),
            color: color(d.color),
            fade,
        });
    }

    let mut materials = vec![Material::default()];
    let mut material_index = HashMap::new();
    for (name, m) in &desc.materials {
        let d = m.get_ref();
        let field = format!("materials.{name}");
        let scalars = [
            ("filter", d.filter),
            ("transmit", d.transmit),
            ("ambient", d.ambient),
            ("emission", d.emission),
            ("diffuse", d.diffuse),
            ("brilliance", d.brilliance),
            ("phong", d.phong),
            ("phong_size", d.phong_size),
            ("specular", d.specular),
            ("roughness", d.roughness),
            ("reflection", d.reflection),
            ("ior", d.ior),
        ];
        let err =
            |key: &str, msg: &str| src.key_error(m.span(), key, format!("{field}.{key}"), msg);
        for (key, x) in scalars {
            if !x.is_finite() || x < 0.0 {
                return Err(err(key, "must be finite and ≥ 0"));
            }
        }
        if d.filter + d.transmit > 1.0 {
            return Err(err(
                "transmit",
                &format!(
                    "filter + transmit = {} is more than 1: more light would pass through \
than arrives, and the surface's own colour would count negatively",
                    d.filter + d.transmit
                ),
            ));
        }
        if d.color.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(err("color", "components must be finite and ≥ 0"));
        }
        if d.roughness == 0.0 && d.specular > 0.0 {
            return Err(err("roughness", "must be > 0 when specular is used"));
        }
        if d.ior == 0.0 {
            return Err(err("ior", "must be > 0"));
        }
        if classic != (d.model == MaterialModel::Classic) {
            return Err(err(
                "model",
                if classic {
                    "a physical material needs render.integrator = \"direct\" or \"path\""
                } else {
                    "the direct and path integrators need model = \"diffuse\", \"conductor\" or \"dielectric\""
                },
            ));
        }
        let radiance = d.radiance.unwrap_or_default();
        if radiance.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(err("radiance", "components must be finite and ≥ 0"));
        }
        if classic && d.radiance.is_some() {
            return Err(err(
                "radiance",
                "area lights need the direct or path integrator",
            ));
        }
        material_index.insert(name.clone(), materials.len() as u32);
        materials.push(Material {
            name: name.clone(),
            model: d.model,
            radiance: color(radiance),
            color: color(d.color),
            filter: d.filter as f32,
            transmit: d.transmit as f32,
            ambient: d.ambient as f32,
            emission: d.emission as f32,
            diffuse: d.diffuse as f32,
            brilliance: d.brilliance as f32,
            phong: d.phong as f32,
            phong_size: d.phong_size as f32,
            specular: d.specular as f32,
            roughness: d.roughness as f32,
            reflection: d.reflection as f32,
            ior: d.ior as f32,
        });
    }

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
    })
}

/// Refuses numbers that are finite as written (in f64) but not in the renderer's precision
/// (|x| above `Real::MAX`, 3.4e38 in the f32 build): converted, they would become
/// infinite and the image would come out black or with zeroed pixels, silently. Integers
/// too large for an f64 are left to the typed fields, which refuse them.
fn check_precision(
    table: &toml::Spanned<toml::de::DeTable<'_>>,
    src: &Source,
) -> Result<(), SceneError> {
    use toml::de::DeValue;
    /// A number's value, read only when it could be out of range: its digits (before an
    /// exponent) or its exponent are long. Most numbers of a scene are short and skipped.
    fn number(v: &DeValue) -> Option<f64> {
        let text = match v {
            DeValue::Float(f) => f.as_str(),
            DeValue::Integer(i) if i.radix() == 10 => i.as_str(),
            _ => return None,
        };
        // |x| ≤ 3.4e38 whenever the mantissa has at most 38 digits and there is no
        // exponent: skip those without parsing.
        if text.len() < 38 && !text.contains(['e', 'E']) {
            return None;
        }
        text.replace('_', "").parse().ok()
    }
    enum Seg<'k> {
        Key(&'k str),
        Index(usize),
    }
    fn path_of(segs: &[Seg]) -> String {
        let mut p = String::new();
        for s in segs {
            match s {
                Seg::Key(k) if p.is_empty() => p.push_str(k),
                Seg::Key(k) => {
                    p.push('.');
                    p.push_str(k)
                }
                Seg::Index(i) => p.push_str(&format!("[{i}]")),
            }
        }
        p
    }
    fn walk<'k>(
        v: &'k toml::Spanned<DeValue<'k>>,
        segs: &mut Vec<Seg<'k>>,
        src: &Source,
    ) -> Result<(), SceneError> {
        match v.get_ref() {
            DeValue::Table(t) => {
                for (k, val) in t.iter() {
                    segs.push(Seg::Key(k.get_ref()));
                    walk(val, segs, src)?;
                    segs.pop();
                }
            }
            DeValue::Array(a) => {
                for (i, val) in a.iter().enumerate() {
                    segs.push(Seg::Index(i));
                    walk(val, segs, src)?;
                    segs.pop();
                }
            }
            other => {
                if let Some(x) = number(other) {
                    if x.is_finite() && x.abs() > Real::MAX as f64 {
                        return Err(src.error(
                            v.span().start,
                            path_of(segs),
                            format!(
                                "{x:e} is beyond the largest number of the renderer's precision \
({}, largest {:e}); scale the scene down, or use the f64 build",
                                crate::real::PRECISION,
                                Real::MAX
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
    let mut segs = Vec::new();
    for (k, val) in table.get_ref().iter() {
        segs.push(Seg::Key(k.get_ref()));
        walk(val, &mut segs, src)?;
        segs.pop();
    }
    Ok(())
}

/// How deep definitions may place one another (`defs.a` placing `defs.b` placing …), and
/// groups may nest: deeper inputs are refused with a located error (renderer/docs/
/// robustness.md). It bounds the recursion of building and of tracing.
pub const MAX_NESTING: usize = 64;

/// The definitions a node places (its `of`, and its children's), in file order.
fn placed<'n>(node: &'n NodeDesc, out: &mut Vec<&'n Spanned<String>>) {
    if let Some(of) = &node.of {
        out.push(of);
    }
    for c in node.children.iter().flatten() {
        placed(c.get_ref(), out);
    }
}

/// Refuses a definition that places itself, directly or through others (placed anywhere
/// or not), naming the chain, and chains of definitions deeper than [`MAX_NESTING`].
fn check_definitions(
    defs: &BTreeMap<String, Spanned<NodeDesc>>,
    src: &Source,
) -> Result<(), SceneError> {
    // Depth of each definition's chain, once known.
    let mut depth: HashMap<&str, usize> = HashMap::new();
    fn visit<'d>(
        name: &'d str,
        defs: &'d BTreeMap<String, Spanned<NodeDesc>>,
        src: &Source,
        stack: &mut Vec<(&'d str, Option<&'d Spanned<String>>)>,
        depth: &mut HashMap<&'d str, usize>,
    ) -> Result<usize, SceneError> {
        if let Some(&d) = depth.get(name) {
            return Ok(d);
        }
        let Some(node) = defs.get(name) else {
            return Ok(0); // A missing definition is reported where it is placed.
        };
        let mut refs = Vec::new();
        placed(node.get_ref(), &mut refs);
        let mut deepest = 0;
        for of in refs {
            let next = of.get_ref().as_str();
            let chain = |stack: &[(&str, Option<&Spanned<String>>)], last: &str| {
                stack
                    .iter()
                    .map(|(n, _)| format!("defs.{n}"))
                    .chain(std::iter::once(format!("defs.{last}")))
                    .collect::<Vec<_>>()
                    .join(" → ")
            };
            if stack.iter().any(|(n, _)| *n == next) || next == name {
                let mut full = stack.clone();
                full.push((name, None));
                let from = full.iter().position(|(n, _)| *n == next).unwrap_or(0);
                return Err(src.error(
                    of.span().start,
                    format!("defs.{name}.of"),
                    format!(
                        "definition '{next}' contains itself: {}",
                        chain(&full[from..], next)
                    ),
                ));
            }
            if stack.len() + 1 >= MAX_NESTING {
                let mut full = stack.clone();
                full.push((name, None));
                let shown = if full.len() > 6 {
                    format!(
                        "{} → … → {}",
                        chain(&full[..2], full[2].0),
                        chain(&full[full.len() - 2..], next)
                    )
                } else {
                    chain(&full, next)
                };
                return Err(src.error(
                    of.span().start,
                    format!("defs.{name}.of"),
                    format!(
                        "definitions nest deeper than {MAX_NESTING} levels ({shown}); \
flatten the chain"
                    ),
                ));
            }
            stack.push((name, Some(of)));
            let d = visit(next, defs, src, stack, depth)?;
            stack.pop();
            if stack.len() + d + 1 >= MAX_NESTING {
                return Err(src.error(
                    of.span().start,
                    format!("defs.{name}.of"),
                    format!(
                        "definitions nest deeper than {MAX_NESTING} levels (defs.{name} → defs.{next} → … \
{} more); flatten the chain",
                        d
                    ),
                ));
            }
            deepest = deepest.max(d + 1);
        }
        depth.insert(name, deepest);
        Ok(deepest)
    }
    for name in defs.keys() {
        visit(name, defs, src, &mut Vec::new(), &mut depth)?;
    }
    Ok(())
}

/// Where render space's origin goes, in world coordinates: the eye, when the eye is
/// farther from the world origin than twice its distance to every object (then every
/// object is nearer the eye than the world origin is, so moving the origin to the eye
/// makes every coordinate smaller, and so more precise, in the render precision);
/// otherwise the world origin stays (0). A bounded object counts by its box; an unbounded
/// one (a plane) by the point its transform places at its object-space origin.
/// renderer/docs/precision.md measures what it buys.
fn render_origin(root: &Aggregate, eye: DVec3) -> DVec3 {
    let dv = crate::real::dvec3;
    let mut reach: f64 = root.bounded_bounds().map_or(0.0, |b| {
        // The farthest corner of the bounded objects' box from the eye.
        (eye - dv(b.min))
            .abs()
            .max((eye - dv(b.max)).abs())
            .length()
    });
    for inst in root.unbounded_instances() {
        let anchor = inst.xf.map_or(DVec3::ZERO, |x| dv(x.translation()));
        reach = reach.max((eye - anchor).length());
    }
    if eye.length() > 2.0 * reach {
        eye
    } else {
        DVec3::ZERO
    }
}

fn build_camera(
    c: &Spanned<CameraDesc>,
    cols: u32,
    rows: u32,
    src: &Source,
) -> Result<Camera, SceneError> {
    let (form, model) = match c.get_ref() {
        CameraDesc::View {
            vrp,
            vpn,
            vup,
            e,
            window,
        } => (
            "view",
            Ok(ViewingModel {
                vrp: dv(*vrp),
                vpn: dv(*vpn),
                vup: dv(*vup),
                e: *e,
                window: Window {
                    left: window.left,
                    right: window.right,
                    bottom: window.bottom,
                    top: window.top,
                },
                cols,
                rows,
            }),
        ),
        CameraDesc::LookAt {
            from,
            at,
            up,
            fov,
            fov_axis,
        } => (
            "look_at",
            ViewingModel::look_at(dv(*from), dv(*at), dv(*up), *fov, *fov_axis, cols, rows),
        ),
        CameraDesc::Povray {
            location,
            direction,
            right,
            up,
        } => (
            "povray",
            ViewingModel::povray(
                dv(*location),
                dv(*direction),
                dv(*right),
                dv(*up),
                cols,
                rows,
            ),
        ),
    };
    model.and_then(Camera::new).map_err(|e| {
        let field = camera_field(form, &e);
        src.key_error(c.span(), field, format!("camera.{form}.{field}"), e)
    })
}

/// The field of a camera form that a camera error is about.
fn camera_field(form: &str, e: &CameraError) -> &'static str {
    use CameraError::*;
    match (form, e) {
        ("view", ZeroVector(s)) if s.contains("vpn") => "vpn",
        ("view", ZeroVector(_)) => "vup",
        ("view", UpParallel) => "vup",
        ("view", EyeDistance(_)) => "e",
        ("view", EmptyWindow) => "window",
        ("view", NonFinite(s)) if s.contains("window") => "window",
        ("view", NonFinite(_)) => "vrp",
        ("look_at", ZeroVector(s)) if s.contains("at") => "at",
        ("look_at", ZeroVector(_) | UpParallel) => "up",
        ("look_at", FieldOfView(_)) => "fov",
        ("look_at", NonFinite(_)) => "from",
        ("povray", ZeroVector("right")) => "right",
        ("povray", ZeroVector("up") | NotOrthogonal(_)) => "up",
        ("povray", ZeroVector(_) | EyeDistance(_)) => "direction",
        ("povray", NonFinite(_)) => "location",
        (_, EmptyPixelArray) => "width",
        _ => "(camera)",
    }
}

/// The affine map of one transform operation.
pub fn op_affine(op: &TransformOp) -> Result<Affine64, String> {
    Ok(match op {
        TransformOp::Translate(v) => Affine64::translate(dv(*v)),
        TransformOp::Rotate { axis, degrees } => {
            let a = dv(*axis);
            if !(a.length() > 0.0 && a.is_finite()) {
                return Err("the rotation axis is a zero-length or non-finite vector".into());
            }
            if !degrees.is_finite() {
                return Err("the rotation angle is not finite".into());
            }
            Affine64::linear(DMat3::from_axis_angle(a.normalize(), degrees.to_radians()))
        }
        TransformOp::Scale(ScaleArg::Uniform(s)) => {
            Affine64::linear(DMat3::from_diagonal(DVec3::splat(*s)))
        }
        TransformOp::Scale(ScaleArg::PerAxis(s)) => Affine64::linear(DMat3::from_diagonal(dv(*s))),
        TransformOp::Shear(s) => Affine64::linear(DMat3::from_cols(
            DVec3::new(1.0, s.yx, s.zx),
            DVec3::new(s.xy, 1.0, s.zy),
            DVec3::new(s.xz, s.yz, 1.0),
        )),
        TransformOp::Matrix(rows) => Affine64 {
            m: DMat3::from_cols(dv(rows[0]), dv(rows[1]), dv(rows[2])),
            d: dv(rows[3]),
        },
    })
}

struct Builder<'a> {
    src: &'a Source<'a>,
    emissive: Vec<bool>,
    base: PathBuf,
    materials: HashMap<String, u32>,
    defs: &'a BTreeMap<String, Spanned<NodeDesc>>,
    built_defs: HashMap<String, Arc<Aggregate>>,
    in_progress: HashSet<String>,
    meshes: HashMap<PathBuf, Arc<Mesh>>,
    objects: Vec<String>,
    /// The world point at render space's origin.
    origin: DVec3,
}

impl Builder<'_> {
    /// The scene's own objects, flattened, in the render space whose origin is the world
    /// point `origin`: every top-level transform is composed (in `f64`) with a translation
    /// by `−origin` before it is converted to the render precision.
    fn top_level(
        &mut self,
        objects: &[Spanned<NodeDesc>],
        origin: DVec3,
    ) -> Result<Vec<Instance>, SceneError> {
        self.objects.clear();
        self.origin = origin;
        let rebase = Affine64::translate(-origin);
        let mut instances = Vec::new();
        for (k, node) in objects.iter().enumerate() {
            self.node(
                node,
                &format!("objects[{k}]"),
                &rebase,
                0,
                true,
                &mut instances,
            )?;
        }
        Ok(instances)
    }

    /// Flattens `node` into `out`. `numbered`: nodes of the scene's own tree get object ids;
    /// nodes inside definitions inherit the id of the instance that places them.
    fn node(
        &mut self,
        node: &Spanned<NodeDesc>,
        path: &str,
        parent: &Affine64,
        parent_material: u32,
        numbered: bool,
        out: &mut Vec<Instance>,
    ) -> Result<(), SceneError> {
        let d = node.get_ref();
        let span = node.span();
        let err = |field: &str, msg: &dyn std::fmt::Display| {
            self.src
                .key_error(span.clone(), field, format!("{path}.{field}"), msg)
        };
        self.check_fields(d, path, span.clone())?;

        // Compose the local transform, validating each operation on its own line.
        let mut local = Affine64::IDENTITY;
        for (k, op) in d.transform.iter().enumerate() {
            let field = format!("{path}.transform[{k}]");
            let a =
                op_affine(op.get_ref()).map_err(|m| self.src.error(op.span().start, &field, m))?;
            a.inverse()
                .map_err(|e| self.src.error(op.span().start, &field, e))?;
            local = a.compose(&local);
        }
        let mut xf = parent.compose(&local);

        let material = match &d.material {
            Some(m) => *self.materials.get(m.get_ref()).ok_or_else(|| {
                self.src.error(
                    m.span().start,
                    format!("{path}.material"),
                    format!(
                        "no material named '{}'{}",
                        m.get_ref(),
                        did_you_mean(m.get_ref(), self.materials.keys().map(String::as_str))
                    ),
                )
            })?,
            None => parent_material,
        };

        let shape = match d.kind {
            NodeKind::Group => {
                for (k, child) in d.children.iter().flatten().enumerate() {
                    self.node(
                        child,
                        &format!("{path}.children[{k}]"),
                        &xf,
                        material,
                        numbered,
                        out,
                    )?;
                }
                return Ok(());
            }
            NodeKind::Sphere => Shape::Sphere,
            NodeKind::Plane => Shape::Plane,
            NodeKind::Box => Shape::Cube,
            NodeKind::Cylinder => Shape::Cylinder {
                capped: d.capped.unwrap_or(true),
            },
            NodeKind::Cone => Shape::Cone {
                capped: d.capped.unwrap_or(true),
            },
            NodeKind::Disk => Shape::Disk,
            NodeKind::Rectangle => Shape::Rectangle,
            NodeKind::Triangle => {
                let v = d
                    .vertices
                    .as_ref()
                    .ok_or_else(|| err("vertices", &"a triangle needs three vertices"))?;
                // Vertices placed by a pure translation in a rebased scene are world
                // coordinates: move them into render space in f64, so their precision
                // is the render space's, not the world's.
                let shift = if self.origin != DVec3::ZERO && xf.m == DMat3::IDENTITY {
                    std::mem::replace(&mut xf, Affine64::IDENTITY).d
                } else {
                    DVec3::ZERO
                };
                let p = v.get_ref().map(|q| vec3(dv(q) + shift));
                if p.iter().any(|q| !q.is_finite()) {
                    return Err(self.src.error(
                        v.span().start,
                        format!("{path}.vertices"),
                        "must be finite",
                    ));
                }
                let tri = Triangle {
                    p,
                    n: d.normals.as_ref().map(|n| n.get_ref().map(|q| vec3(dv(q)))),
                    uv: d
                        .uvs
                        .map(|u| u.map(|q| Vec2::new(q[0] as Real, q[1] as Real))),
                };
                let n = tri.normal();
                if !(n.is_finite() && n.length_squared().is_finite()) {
                    return Err(self.src.error(
                        v.span().start,
                        format!("{path}.vertices"),
                        format!(
                            "the triangle's normal overflows the renderer's precision ({}): \
its vertices are too large; scale the object down, or use the f64 build",
                            crate::real::PRECISION
                        ),
                    ));
                }
                if !(n.length_squared() > 0.0) {
                    return Err(self.src.error(
                        v.span().start,
                        format!("{path}.vertices"),
                        "the triangle is degenerate (zero area)",
                    ));
                }
                Shape::Triangle(Box::new(tri))
            }
            NodeKind::Mesh => {
                let f = d
                    .file
                    .as_ref()
                    .ok_or_else(|| err("file", &"a mesh needs a file"))?;
                let full = self.base.join(f.get_ref());
                let mesh = match self.meshes.get(&full) {
                    Some(m) => m.clone(),
                    None => {
                        let m = Arc::new(Mesh::load_obj(&full).map_err(|e| {
                            self.src.error(
                                f.span().start,
                                format!("{path}.file"),
                                format!(
                                    "'{}', looked for at {} (relative to the scene file's folder): {e}",
                                    f.get_ref(),
                                    full.display()
                                ),
                            )
                        })?);
                        self.meshes.insert(full, m.clone());
                        m
                    }
                };
                Shape::Mesh(mesh)
            }
            NodeKind::Instance => {
                let of =
                    d.of.as_ref()
                        .ok_or_else(|| err("of", &"an instance needs `of`, a definition's name"))?;
                Shape::Group(self.def(of)?)
            }
        };
        let transform = if xf.is_identity() {
            None
        } else {
            Some(
                Transform::new(&xf)
                    .map_err(|e| err("transform", &format!("composed with its parents: {e}")))?,
            )
        };
        if material != INHERIT && self.emissive[material as usize] {
            if !matches!(shape, Shape::Sphere | Shape::Rectangle) {
                return Err(err(
                    "material",
                    &"an emitting material (radiance) can only be on a sphere or a rectangle",
                ));
            }
            if !numbered {
                return Err(err(
                    "material",
                    &"an emitting material cannot be used inside a definition",
                ));
            }
        }
        let object_id = if numbered {
            self.objects.push(path.to_string());
            self.objects.len() as u32
        } else {
            0
        };
        out.push(Instance {
            shape,
            xf: transform,
            material,
            object_id,
        });
        Ok(())
    }

    /// Builds (once) the aggregate of a named definition.
    fn def(&mut self, of: &Spanned<String>) -> Result<Arc<Aggregate>, SceneError> {
        let name = of.get_ref();
        if let Some(a) = self.built_defs.get(name) {
            return Ok(a.clone());
        }
        let defs = self.defs;
        let Some(node) = defs.get(name) else {
            return Err(self.src.error(
                of.span().start,
                "of",
                format!(
                    "no definition named '{name}'{}",
                    did_you_mean(name, defs.keys().map(String::as_str))
                ),
            ));
        };
        if !self.in_progress.insert(name.clone()) {
            return Err(self.src.error(
                of.span().start,
                "of",
                format!("definition '{name}' contains itself"),
            ));
        }
        let mut inner = Vec::new();
        self.node(
            node,
            &format!("defs.{name}"),
            &Affine64::IDENTITY,
            INHERIT,
            false,
            &mut inner,
        )?;
        self.in_progress.remove(name);
        let agg = Arc::new(Aggregate::new(inner));
        if agg.surface_count().is_none() {
            return Err(self.src.error(
                of.span().start,
                "of",
                format!(
                    "definition '{name}' expands to more than 2^64 - 1 surfaces (its instances \
                     of other definitions multiply); a scene's surfaces must be countable in 64 bits"
                ),
            ));
        }
        self.built_defs.insert(name.clone(), agg.clone());
        Ok(agg)
    }

    /// Rejects fields that do not belong to the node's kind.
    fn check_fields(
        &self,
        d: &NodeDesc,
        path: &str,
        span: std::ops::Range<usize>,
    ) -> Result<(), SceneError> {
        let k = d.kind;
        let wrong = [
            (
                "capped",
                d.capped.is_some() && !matches!(k, NodeKind::Cylinder | NodeKind::Cone),
            ),
            ("vertices", d.vertices.is_some() && k != NodeKind::Triangle),
            ("normals", d.normals.is_some() && k != NodeKind::Triangle),
            ("uvs", d.uvs.is_some() && k != NodeKind::Triangle),
            ("file", d.file.is_some() && k != NodeKind::Mesh),
            ("of", d.of.is_some() && k != NodeKind::Instance),
            ("children", d.children.is_some() && k != NodeKind::Group),
        ];
        for (field, bad) in wrong {
            if bad {
                let kind = format!("{k:?}").to_lowercase();
                return Err(self.src.key_error(
                    span,
                    field,
                    format!("{path}.{field}"),
                    format!("not a field of a {kind}"),
                ));
            }
        }
        Ok(())
    }
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
