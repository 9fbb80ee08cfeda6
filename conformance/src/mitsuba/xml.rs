//! Scene → Mitsuba 3 XML (scene format 3.0.0).
//!
//! **Handedness is converted here and nowhere else.** The renderer's world is left-handed
//! and Mitsuba's is right-handed, so the exporter mirrors the whole world by
//! `F = diag(−1, 1, 1)` ([`MIRROR`]). Each primitive's canonical space in Mitsuba is mapped
//! onto the renderer's by a fixed rigid map C. Every exported `to_world` is therefore
//! `F · M · C`, where M is the instance's `world_from_object`.
//!
//! | renderer | Mitsuba | C (Mitsuba canonical → renderer canonical) |
//! |---|---|---|
//! | sphere | `sphere` | identity |
//! | box | `cube` | identity |
//! | rectangle (y = 0, normal +y) | `rectangle` (z = 0, normal +z) | rotation −90° about x |
//! | disk | `disk` | rotation −90° about x |
//! | cylinder, y ∈ [−1, 1] | `cylinder`, z ∈ [0, 1], open | rotation −90° about x after z ↦ 2z − 1 |
//! | cylinder caps | two `disk`s | as the disk, moved to y = ±1 |
//! | triangle, mesh | `obj` files written beside the XML | identity (winding reversed when det M > 0, see [`write_obj`]) |
//! | cone, plane | none: an error (the Mitsuba catalog uses rectangles for floors) | |
//!
//! Mitsuba's `sphere` accepts only a uniform scale (plus rotation and translation), and
//! `disk` and `cylinder` only a uniform scale across their cross-section. Any other
//! transform is exported as a `shapegroup` placed by an `instance`, which takes any
//! affine map.

use glam::{DMat3, DMat4, DVec3};
use renderer::aggregate::Instance;
use renderer::aggregate::Shape;
use renderer::real::dvec3;
use renderer::scene::Integrator;
use renderer::scene::{Color, LightKind, Material, MaterialModel, Scene};
use renderer::shapes::Mesh;
use renderer::transform::Affine64;
use std::fmt::Write;
use std::path::Path;

/// The world mirror between the renderer's left-handed and Mitsuba's right-handed frame.
pub const MIRROR: DMat3 = DMat3::from_cols(DVec3::NEG_X, DVec3::Y, DVec3::Z);

/// Why a scene has no Mitsuba equivalent.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A primitive Mitsuba lacks.
    #[error("{0} has no Mitsuba equivalent")]
    Unsupported(&'static str),
    /// Mitsuba's sensor cannot express non-square pixels.
    #[error(
        "the pixels are not square (aspect {0}); Mitsuba refuses scale in a camera's to_world"
    )]
    NonSquarePixels(f64),
    /// A classic (POV-Ray) material.
    #[error("material '{0}' is a classic POV-Ray finish; Mitsuba scenes need diffuse, conductor or dielectric")]
    Classic(String),
    /// An emitter that Mitsuba cannot place.
    #[error("an emitting sphere must be a similarity (Mitsuba cannot instance emitters)")]
    EmitterTransform,
    /// Writing a mesh file failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// The exported scene: XML text plus the mesh files it references (name, contents).
pub struct Export {
    /// The XML document.
    pub xml: String,
    /// OBJ files to write beside it.
    pub meshes: Vec<(String, String)>,
}

impl Export {
    /// Writes the XML to `path` and the meshes beside it.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        for (name, text) in &self.meshes {
            std::fs::write(dir.join(name), text)?;
        }
        std::fs::write(path, &self.xml)
    }
}

fn f(x: f64) -> String {
    format!("{}", x as f32 as f64)
}

fn rgb(c: Color) -> String {
    format!("{}, {}, {}", f(c.x as f64), f(c.y as f64), f(c.z as f64))
}

/// A 4×4 matrix (column-vector convention) as Mitsuba's row-major `matrix` value.
fn matrix(m: &DMat4) -> String {
    let r = m.transpose().to_cols_array();
    r.iter().map(|v| f(*v)).collect::<Vec<_>>().join(" ")
}

fn affine4(a: &Affine64) -> DMat4 {
    DMat4::from_cols(
        a.m.x_axis.extend(0.0),
        a.m.y_axis.extend(0.0),
        a.m.z_axis.extend(0.0),
        a.d.extend(1.0),
    )
}

/// C for the flat primitives: Mitsuba's z = 0 plane onto the renderer's y = 0 plane.
fn flat_c() -> Affine64 {
    Affine64::linear(DMat3::from_rotation_x(-std::f64::consts::FRAC_PI_2))
}

/// Whether a linear map is a similarity on the span of `axes` (equal lengths, orthogonal).
fn similar_on(m: &DMat3, axes: &[DVec3]) -> bool {
    let v: Vec<DVec3> = axes.iter().map(|a| *m * *a).collect();
    let l0 = v[0].length_squared();
    v.iter()
        .all(|x| ((x.length_squared() - l0) / l0).abs() < 1e-9)
        && (0..v.len()).all(|i| (i + 1..v.len()).all(|j| (v[i].dot(v[j]) / l0).abs() < 1e-9))
}

struct Exporter<'a> {
    scene: &'a Scene,
    body: String,
    meshes: Vec<(String, String)>,
    mesh_files: Vec<(usize, bool, String)>,
    groups: usize,
}

/// Exports a physical scene as Mitsuba XML. `spp` goes into the sampler; `moment` wraps the
/// integrator in Mitsuba's `moment` integrator (mean and second moment per pixel).
pub fn export(scene: &Scene, spp: u32, moment: bool) -> Result<Export, ExportError> {
    let mut e = Exporter {
        scene,
        body: String::new(),
        meshes: Vec::new(),
        mesh_files: Vec::new(),
        groups: 0,
    };
    let mut xml = String::from("<scene version=\"3.0.0\">\n");
    xml.push_str(&e.integrator(moment));
    xml.push_str(&e.sensor(spp)?);
    for l in &scene.lights {
        xml.push_str(&e.light(l.kind, l.position, l.direction, l.color));
    }
    let root = &scene.root;
    // Top-level objects go from render space back to the scene's own coordinates.
    crate::placement::each_leaf(
        root,
        &Affine64::translate(scene.origin()),
        None,
        &mut |inst, world, material| e.leaf(inst, *world, material),
    )?;
    xml.push_str(&e.body);
    xml.push_str("</scene>\n");
    Ok(Export {
        xml,
        meshes: e.meshes,
    })
}

impl Exporter<'_> {
    fn integrator(&self, moment: bool) -> String {
        let s = &self.scene.settings;
        let inner = match s.integrator {
            Integrator::Path => format!(
                "<integrator type=\"path\"><integer name=\"max_depth\" value=\"{}\"/><integer name=\"rr_depth\" value=\"{}\"/></integrator>",
                s.max_depth, s.rr_depth
            ),
            _ => "<integrator type=\"direct\"/>".into(),
        };
        if moment {
            format!("  <integrator type=\"moment\">{inner}</integrator>\n")
        } else {
            format!("  {inner}\n")
        }
    }

    /// The viewing model as a perspective sensor (see shared notes: verified to 1e-7).
    fn sensor(&self, spp: u32) -> Result<String, ExportError> {
        let cam = &self.scene.camera;
        let m = cam.model;
        let w = m.window;
        let (du, dv) = (
            (w.right - w.left) / m.cols as f64,
            (w.top - w.bottom) / m.rows as f64,
        );
        if ((du - dv) / du).abs() > 1e-9 {
            return Err(ExportError::NonSquarePixels(du / dv));
        }
        let [u, v, n] = cam.basis64;
        let frame = DMat3::from_cols(MIRROR * -u, MIRROR * v, MIRROR * n);
        let eye = MIRROR * cam.eye64;
        let to_world = DMat4::from_cols(
            frame.x_axis.extend(0.0),
            frame.y_axis.extend(0.0),
            frame.z_axis.extend(0.0),
            eye.extend(1.0),
        );
        let fov = 2.0 * ((w.right - w.left) / (2.0 * m.e)).atan().to_degrees();
        let ppx = 0.5 * (w.left + w.right) / (w.right - w.left);
        let ppy = -0.5 * (w.bottom + w.top) / (w.top - w.bottom);
        Ok(format!(
            "  <sensor type=\"perspective\">\n    <float name=\"fov\" value=\"{}\"/>\n    <string name=\"fov_axis\" value=\"x\"/>\n    <float name=\"principal_point_offset_x\" value=\"{}\"/>\n    <float name=\"principal_point_offset_y\" value=\"{}\"/>\n    <transform name=\"to_world\"><matrix value=\"{}\"/></transform>\n    <sampler type=\"independent\"><integer name=\"sample_count\" value=\"{spp}\"/></sampler>\n    <film type=\"hdrfilm\"><integer name=\"width\" value=\"{}\"/><integer name=\"height\" value=\"{}\"/><rfilter type=\"box\"/><string name=\"pixel_format\" value=\"rgb\"/></film>\n  </sensor>\n",
            fov,
            ppx,
            ppy,
            // The frame is exact in f64; print it at full precision.
            to_world.transpose().to_cols_array().iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(" "),
            m.cols,
            m.rows
        ))
    }

    fn light(
        &self,
        kind: LightKind,
        position: renderer::Vec3,
        direction: renderer::Vec3,
        color: Color,
    ) -> String {
        match kind {
            LightKind::Point => {
                let p = MIRROR * (dvec3(position) + self.scene.origin());
                format!(
                    "  <emitter type=\"point\"><point name=\"position\" x=\"{}\" y=\"{}\" z=\"{}\"/><rgb name=\"intensity\" value=\"{}\"/></emitter>\n",
                    f(p.x),
                    f(p.y),
                    f(p.z),
                    rgb(color)
                )
            }
            LightKind::Directional => {
                let d = MIRROR * dvec3(direction);
                format!(
                    "  <emitter type=\"directional\"><vector name=\"direction\" x=\"{}\" y=\"{}\" z=\"{}\"/><rgb name=\"irradiance\" value=\"{}\"/></emitter>\n",
                    f(d.x),
                    f(d.y),
                    f(d.z),
                    rgb(color)
                )
            }
            LightKind::Environment => format!(
                "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"{}\"/></emitter>\n",
                rgb(color)
            ),
        }
    }

    fn bsdf(&self, m: &Material) -> Result<String, ExportError> {
        Ok(match m.model {
            MaterialModel::Diffuse => format!(
                "<bsdf type=\"twosided\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"{}\"/></bsdf></bsdf>",
                rgb(m.color)
            ),
            MaterialModel::Conductor => format!(
                "<bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/><rgb name=\"specular_reflectance\" value=\"{}\"/></bsdf>",
                rgb(m.color)
            ),
            MaterialModel::Dielectric => format!(
                "<bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"{}\"/><float name=\"ext_ior\" value=\"1\"/></bsdf>",
                f(m.ior as f64)
            ),
            MaterialModel::Classic => return Err(ExportError::Classic(m.name.clone())),
        })
    }

    /// Writes one leaf shape of the scene, placed by `world`, of material `material`
    /// ([`crate::placement::each_leaf`] walks the instances to it).
    fn leaf(&mut self, inst: &Instance, world: Affine64, material: u32) -> Result<(), ExportError> {
        let m = self.scene.material(material).clone();
        let bsdf = self.bsdf(&m)?;
        let emitter = if m.radiance != Color::ZERO {
            format!(
                "<emitter type=\"area\"><rgb name=\"radiance\" value=\"{}\"/></emitter>",
                rgb(m.radiance)
            )
        } else {
            String::new()
        };
        let mirrored = Affine64::linear(MIRROR).compose(&world);
        let body = format!("{bsdf}{emitter}");
        match &inst.shape {
            Shape::Sphere => {
                if similar_on(&mirrored.m, &[DVec3::X, DVec3::Y, DVec3::Z]) {
                    self.shape("sphere", &mirrored, &body);
                } else if emitter.is_empty() {
                    self.grouped("sphere", &mirrored, &bsdf);
                } else {
                    return Err(ExportError::EmitterTransform);
                }
            }
            Shape::Cube => self.shape("cube", &mirrored, &body),
            Shape::Rectangle => self.shape("rectangle", &mirrored.compose(&flat_c()), &body),
            Shape::Disk => {
                let t = mirrored.compose(&flat_c());
                if similar_on(&t.m, &[DVec3::X, DVec3::Y]) {
                    self.shape("disk", &t, &body);
                } else {
                    self.grouped("disk", &t, &bsdf);
                }
            }
            Shape::Cylinder { capped } => {
                // Mitsuba: radius 1, z ∈ [0, 1]. z ↦ 2z − 1, then onto the y axis.
                let stretch = Affine64 {
                    m: DMat3::from_diagonal(DVec3::new(1.0, 1.0, 2.0)),
                    d: DVec3::new(0.0, 0.0, -1.0),
                };
                let t = mirrored.compose(&flat_c()).compose(&stretch);
                let ok = similar_on(&t.m, &[DVec3::X, DVec3::Y])
                    && t.m.x_axis.dot(t.m.z_axis).abs() < 1e-9 * t.m.z_axis.length_squared()
                    && t.m.y_axis.dot(t.m.z_axis).abs() < 1e-9 * t.m.z_axis.length_squared();
                if ok {
                    self.shape("cylinder", &t, &body);
                } else {
                    self.grouped("cylinder", &t, &bsdf);
                }
                if *capped {
                    for (y, angle) in [
                        (1.0, -std::f64::consts::FRAC_PI_2),
                        (-1.0, std::f64::consts::FRAC_PI_2),
                    ] {
                        let cap = Affine64 {
                            m: DMat3::from_rotation_x(angle),
                            d: DVec3::new(0.0, y, 0.0),
                        };
                        let t = mirrored.compose(&cap);
                        if similar_on(&t.m, &[DVec3::X, DVec3::Y]) {
                            self.shape("disk", &t, &bsdf);
                        } else {
                            self.grouped("disk", &t, &bsdf);
                        }
                    }
                }
            }
            Shape::Triangle(tri) => {
                let mesh = Mesh::new(
                    tri.p.to_vec(),
                    tri.n.map(|n| n.to_vec()),
                    None,
                    vec![[0, 1, 2]],
                )
                .expect("a valid triangle");
                let name = self.mesh_file(
                    &mesh,
                    world.m.determinant() > 0.0,
                    std::ptr::from_ref(tri.as_ref()) as usize,
                );
                self.obj(&name, &mirrored, &body, mesh.normals.is_none());
            }
            Shape::Mesh(mesh) => {
                let name = self.mesh_file(
                    mesh,
                    world.m.determinant() > 0.0,
                    std::sync::Arc::as_ptr(mesh) as usize,
                );
                self.obj(&name, &mirrored, &body, mesh.normals.is_none());
            }
            Shape::Cone { .. } => return Err(ExportError::Unsupported("the cone")),
            Shape::Plane => return Err(ExportError::Unsupported("the infinite plane")),
            Shape::Group(_) => unreachable!("placement::each_leaf walks groups through"),
            Shape::Anchored(_) => unreachable!("written as the scene placed it (unanchored)"),
        }
        Ok(())
    }

    fn shape(&mut self, kind: &str, to_world: &Affine64, body: &str) {
        let to_world = &keep_orientation(to_world);
        writeln!(
            self.body,
            "  <shape type=\"{kind}\"><transform name=\"to_world\"><matrix value=\"{}\"/></transform>{body}</shape>",
            matrix(&affine4(to_world))
        )
        .unwrap();
    }

    fn grouped(&mut self, kind: &str, to_world: &Affine64, bsdf: &str) {
        let to_world = &keep_orientation(to_world);
        let id = format!("group{}", self.groups);
        self.groups += 1;
        writeln!(
            self.body,
            "  <shape type=\"shapegroup\" id=\"{id}\"><shape type=\"{kind}\">{bsdf}</shape></shape>\n  <shape type=\"instance\"><ref id=\"{id}\"/><transform name=\"to_world\"><matrix value=\"{}\"/></transform></shape>",
            matrix(&affine4(to_world))
        )
        .unwrap();
    }

    fn obj(&mut self, file: &str, to_world: &Affine64, body: &str, flat: bool) {
        writeln!(
            self.body,
            "  <shape type=\"obj\"><string name=\"filename\" value=\"{file}\"/><boolean name=\"face_normals\" value=\"{flat}\"/><transform name=\"to_world\"><matrix value=\"{}\"/></transform>{body}</shape>",
            matrix(&affine4(to_world))
        )
        .unwrap();
    }

    /// The OBJ file of a mesh, written once per (mesh, winding).
    fn mesh_file(&mut self, mesh: &Mesh, reverse: bool, key: usize) -> String {
        if let Some((_, _, name)) = self
            .mesh_files
            .iter()
            .find(|(k, r, _)| *k == key && *r == reverse)
        {
            return name.clone();
        }
        let name = format!(
            "mesh{}{}.obj",
            self.mesh_files.len(),
            if reverse { "r" } else { "" }
        );
        self.meshes.push((name.clone(), write_obj(mesh, reverse)));
        self.mesh_files.push((key, reverse, name.clone()));
        name
    }
}

/// Mitsuba flips a sphere's normals inward, and a built-in mesh's geometric normals, under
/// a `to_world` with negative determinant (measured with 3.9.1). The world mirror makes
/// that the common case. Every built-in primitive (sphere, cube, rectangle, disk,
/// cylinder) is symmetric under x ↦ −x in its own canonical space, so composing with that
/// mirror gives the same surface with a positive determinant.
fn keep_orientation(t: &Affine64) -> Affine64 {
    if t.m.determinant() < 0.0 {
        t.compose(&Affine64::linear(DMat3::from_diagonal(DVec3::new(
            -1.0, 1.0, 1.0,
        ))))
    } else {
        *t
    }
}

/// A mesh as OBJ text, with its vertex normals when it has them (the renderer then shades
/// with interpolated normals, and so does Mitsuba). Mitsuba computes face normals from the winding in its own
/// right-handed world. The world mirror F flips that once more, so a mesh whose transform
/// keeps orientation (det M > 0) is written with reversed winding. The renderer's outward
/// normal `M⁻ᵀ·n` and Mitsuba's face normal then agree.
pub fn write_obj(mesh: &Mesh, reverse: bool) -> String {
    let mut s = String::from("# exported by the verified-tracer conformance harness\n");
    for p in &mesh.positions {
        writeln!(s, "v {} {} {}", f(p.x as f64), f(p.y as f64), f(p.z as f64)).unwrap();
    }
    for t in &mesh.triangles_as_given() {
        let (a, b, c) = if reverse {
            (t[0], t[2], t[1])
        } else {
            (t[0], t[1], t[2])
        };
        writeln!(s, "f {} {} {}", a + 1, b + 1, c + 1).unwrap();
    }
    s
}

/// Maps a Mitsuba world point or vector back to the renderer's world.
pub fn to_renderer(v: DVec3) -> DVec3 {
    MIRROR * v
}
