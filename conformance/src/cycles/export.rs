//! Scene → a Blender scene description (JSON) that `scripts/cycles_refs.py` builds with
//! `bpy` and renders with Cycles. Every number is already in Blender's frame and units;
//! the script only creates what it is told (conformance/docs/cycles.md derives each
//! conversion).
//!
//! **The world map.** The renderer's world is left-handed with y up; Blender's is
//! right-handed with z up. The exporter maps our (x, y, z) to Blender's (x, z, y)
//! ([`WORLD`], a reflection: det −1, its own inverse), so our "up" is Blender's up and our
//! forward (+z) is Blender's front-to-back (+y). Every exported object matrix is
//! `W · M · C`, where M is the instance's `world_from_object` and C places Blender's
//! canonical shape on ours.
//!
//! | renderer | Blender / Cycles |
//! |---|---|
//! | sphere under a similarity | a one-point point cloud of radius 1, which Cycles intersects as an exact sphere (from outside only) |
//! | dielectric sphere, or a sphere under any other map (an ellipsoid) | an icosphere of [`ICOSPHERE_SUBDIVISIONS`] with radial vertex normals (approximate) |
//! | box, rectangle, triangle, mesh | triangle meshes with the same vertices (exact) |
//! | disk | a fan of [`SEGMENTS`] triangles (approximate: the rim is a polygon) |
//! | cylinder (and caps) | [`SEGMENTS`] quads with smooth normals (approximate) |
//! | cone, plane | none: an error (the physical catalog has none) |
//!
//! Cycles takes a face's normal from its winding in object space and maps it by the normal
//! matrix, also under a mirroring transform (the object's negative-scale flag flips it
//! back), so each face is wound so that its object-space cross product is our outward
//! normal.

use glam::{DMat3, DVec3};
use renderer::aggregate::{Instance, Shape};
use renderer::real::dvec3;
use renderer::scene::{Color, Integrator, LightKind, MaterialModel, Scene};
use renderer::transform::Affine64;
use serde_json::{json, Value};

/// Our world → Blender's world: (x, y, z) ↦ (x, z, y).
pub const WORLD: DMat3 = DMat3::from_cols(DVec3::X, DVec3::Z, DVec3::Y);

/// Segments of a tessellated disk or cylinder. The polygon's rim lies within
/// `1 − cos(π/N)` = 4.7e-6 of the radius inside the circle (conformance/docs/cycles.md).
pub const SEGMENTS: usize = 1024;

/// Blender's subdivisions of the icosphere that stands for a dielectric sphere (its count
/// starts at 1, the icosahedron: 9 is 20 · 4⁸ = 1,310,720 triangles with edges of 0.0035
/// to 0.0052 of the radius; a face lies within 4.4e-6 of the radius inside the sphere).
pub const ICOSPHERE_SUBDIVISIONS: u32 = 9;

/// The icosphere's subdivisions for a sphere under a map that is not a similarity (an
/// ellipsoid): 10, 5,242,880 triangles, a face within 1.1e-6 of the radius. The map
/// stretches the faces' sag along its longest axis, and a ray that meets the stretched
/// surface at a grazing angle sees the sag divided by the cosine: at 9 subdivisions one
/// pixel of `mi_ellipsoid` was 2.5e-5 off in distance, beyond the gate's 2e-5.
pub const ELLIPSOID_SUBDIVISIONS: u32 = 10;

/// Why a scene has no Cycles equivalent.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A primitive the exporter does not convert.
    #[error("{0} has no Cycles conversion (conformance/docs/cycles.md)")]
    Unsupported(&'static str),
    /// A classic (POV-Ray) material.
    #[error("material '{0}' is a classic POV-Ray finish; Cycles scenes need diffuse, conductor or dielectric")]
    Classic(String),
    /// The pixels are not square.
    #[error("the pixels are not square (aspect {0}); the export sets Blender's pixel aspect to 1")]
    NonSquarePixels(f64),
    /// A window off the view axis: Blender's shift is not checked here yet.
    #[error("the window is off-centre; the exporter's camera shift is not verified (conformance/docs/cycles.md)")]
    OffCentre,
}

fn f(x: f64) -> Value {
    json!(x as f32 as f64)
}

fn rgb(c: Color) -> [f64; 3] {
    [c.x as f64, c.y as f64, c.z as f64].map(|x| x as f32 as f64)
}

/// A 4×4 affine matrix, row-major (Blender's `Matrix` rows), values rounded to f32.
fn matrix(a: &Affine64) -> Value {
    let m = a.m;
    let rows = [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x, a.d.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y, a.d.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z, a.d.z],
        [0.0, 0.0, 0.0, 1.0],
    ];
    Value::Array(rows.iter().flatten().map(|x| f(*x)).collect())
}

/// A light's colour as Blender's (colour, energy): the colour scaled to a largest
/// component of 1, the energy `scale` times that component.
fn color_energy(c: Color, scale: f64) -> (Value, Value) {
    let c = rgb(c);
    let max = c.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return (json!([0.0, 0.0, 0.0]), json!(0.0));
    }
    (json!(c.map(|x| x / max)), f(scale * max))
}

/// Cycles' `max_bounces` for our integrator: `direct` is 0 (direct light at the first hit,
/// emitters met by its BSDF ray included), `path` with `max_depth` D counts D − 2
/// (D vertices after the camera: the first hit, its direct light, then D − 2 bounces).
pub fn max_bounces(scene: &Scene) -> u32 {
    match scene.settings.integrator {
        Integrator::Path => scene.settings.max_depth.saturating_sub(2),
        _ => 0,
    }
}

/// Exports a physical scene.
pub fn export(scene: &Scene) -> Result<Value, ExportError> {
    let mut e = Exporter {
        scene,
        materials: Vec::new(),
        objects: Vec::new(),
    };
    let camera = e.camera()?;
    crate::placement::each_leaf(
        &scene.root,
        &Affine64::translate(scene.origin()),
        None,
        &mut |inst, world, material| e.leaf(inst, *world, material),
    )?;
    let lights = e.lights();
    let m = scene.camera.model;
    Ok(json!({
        "width": m.cols,
        "height": m.rows,
        "camera": camera,
        "max_bounces": max_bounces(scene),
        "materials": e.materials.into_iter().map(|(_, v)| v).collect::<Vec<_>>(),
        "objects": e.objects,
        "lights": lights,
    }))
}

struct Exporter<'a> {
    scene: &'a Scene,
    /// Exported materials, by the scene's material index.
    materials: Vec<(u32, Value)>,
    objects: Vec<Value>,
}

impl Exporter<'_> {
    /// The viewing model as a Blender perspective camera: horizontal sensor fit, so that
    /// `lens / sensor_width = e / (right − left)`; the camera's local axes are our u, v
    /// and −n mapped by [`WORLD`] (Blender's camera looks down its local −z).
    fn camera(&self) -> Result<Value, ExportError> {
        let cam = &self.scene.camera;
        let m = cam.model;
        let w = m.window;
        let (width, height) = (w.right - w.left, w.top - w.bottom);
        let (du, dv) = (width / m.cols as f64, height / m.rows as f64);
        if ((du - dv) / du).abs() > 1e-9 {
            return Err(ExportError::NonSquarePixels(du / dv));
        }
        if (w.left + w.right).abs() > 1e-12 * width || (w.bottom + w.top).abs() > 1e-12 * height {
            return Err(ExportError::OffCentre);
        }
        let [u, v, n] = cam.basis64;
        let frame = DMat3::from_cols(WORLD * u, WORLD * v, WORLD * -n);
        let to_world = Affine64 {
            m: frame,
            d: WORLD * cam.eye64,
        };
        const SENSOR: f64 = 36.0;
        // Near and far clipping: far enough apart for every catalog scene, and the near
        // plane well inside the nearest surface (Cycles starts camera rays on it).
        Ok(json!({
            "matrix": matrix(&to_world),
            "sensor_width": SENSOR,
            "lens": SENSOR * m.e / width,
            "shift_x": 0.0,
            "shift_y": 0.0,
            "clip_start": 1e-4,
            "clip_end": 1e6,
        }))
    }

    fn lights(&self) -> Vec<Value> {
        let mut out = Vec::new();
        for l in &self.scene.lights {
            match l.kind {
                LightKind::Point => {
                    // Radiant intensity I = energy · colour / (4π) W/sr.
                    let (color, energy) = color_energy(l.color, 4.0 * std::f64::consts::PI);
                    let p = WORLD * (dvec3(l.position) + self.scene.origin());
                    out.push(json!({
                        "type": "point", "color": color, "energy": energy,
                        "matrix": matrix(&Affine64::translate(DVec3::new(
                            p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64))),
                    }));
                }
                LightKind::Directional => {
                    // A sun shines down its local −z; its strength is irradiance (W/m²).
                    let (color, energy) = color_energy(l.color, 1.0);
                    let d = (WORLD * dvec3(l.direction).as_vec3().as_dvec3()).normalize();
                    let z = -d;
                    let helper = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
                    let x = helper.cross(z).normalize();
                    let y = z.cross(x);
                    out.push(json!({
                        "type": "sun", "color": color, "energy": energy,
                        "matrix": matrix(&Affine64::linear(DMat3::from_cols(x, y, z))),
                    }));
                }
                LightKind::Environment => {
                    out.push(json!({ "type": "world", "radiance": rgb(l.color) }));
                }
            }
        }
        out
    }

    fn material(&mut self, index: u32) -> Result<usize, ExportError> {
        if let Some(k) = self.materials.iter().position(|(i, _)| *i == index) {
            return Ok(k);
        }
        let m = self.scene.material(index);
        let mut v = match m.model {
            MaterialModel::Diffuse => json!({ "type": "diffuse", "color": rgb(m.color) }),
            MaterialModel::Conductor => json!({ "type": "mirror", "color": rgb(m.color) }),
            MaterialModel::Dielectric => json!({ "type": "glass", "ior": f(m.ior as f64) }),
            MaterialModel::Classic => return Err(ExportError::Classic(m.name.clone())),
        };
        if m.radiance != Color::ZERO {
            v["emission"] = json!(rgb(m.radiance));
        }
        self.materials.push((index, v));
        Ok(self.materials.len() - 1)
    }

    /// Writes one leaf shape of the scene, placed by `world`, of material `material`
    /// ([`crate::placement::each_leaf`] walks the instances to it).
    fn leaf(&mut self, inst: &Instance, world: Affine64, material: u32) -> Result<(), ExportError> {
        let mat = self.material(material)?;
        let placed = Affine64::linear(WORLD).compose(&world);
        match &inst.shape {
            Shape::Sphere => {
                // A sphere is symmetric under x ↦ −x: keep the determinant positive.
                let m = if placed.m.determinant() < 0.0 {
                    placed.compose(&Affine64::linear(DMat3::from_diagonal(DVec3::new(
                        -1.0, 1.0, 1.0,
                    ))))
                } else {
                    placed
                };
                // Cycles culls a point's back face (kernel/geom/point_intersect.h:
                // "Always back-face culling for now"), so a ray inside never leaves a
                // point-cloud sphere; and it bakes a one-user point's transform into a
                // sphere, while an instanced point's normal comes out by M, not M⁻ᵀ
                // (conformance/docs/cycles.md, "A point under a non-similarity"). A
                // dielectric sphere, and a sphere under any map but a similarity (an
                // ellipsoid), is an icosphere mesh instead, its vertex normals the radial
                // directions, which Cycles maps as a mesh's: by M⁻ᵀ.
                let ellipsoid = !similar(&m.m);
                if self.scene.material(material).model == MaterialModel::Dielectric || ellipsoid {
                    let subdivisions = if ellipsoid {
                        ELLIPSOID_SUBDIVISIONS
                    } else {
                        ICOSPHERE_SUBDIVISIONS
                    };
                    self.objects.push(json!({
                        "shape": "icosphere", "subdivisions": subdivisions,
                        "matrix": matrix(&m), "material": mat, "aov_normal": "shading",
                    }));
                    return Ok(());
                }
                self.objects.push(json!({
                    "shape": "sphere", "matrix": matrix(&m), "material": mat,
                }));
            }
            Shape::Cube => self.mesh(&placed, mat, &box_mesh(), None),
            Shape::Rectangle => self.mesh(&placed, mat, &rectangle_mesh(), None),
            Shape::Disk => self.mesh(&placed, mat, &disk_mesh(0.0, 1.0), None),
            Shape::Cylinder { capped } => {
                let (p, t, n) = cylinder_mesh();
                self.mesh(&placed, mat, &(p, t), Some(&n));
                // Our normal AOV is the exact cylinder's; the interpolated normal of a
                // chord point equals the radial direction there (conformance/docs/cycles.md).
                self.objects.last_mut().expect("just pushed")["aov_normal"] = json!("shading");
                if *capped {
                    self.mesh(&placed, mat, &disk_mesh(1.0, 1.0), None);
                    self.mesh(&placed, mat, &disk_mesh(-1.0, -1.0), None);
                }
            }
            Shape::Triangle(tri) => {
                let p = tri.p.map(|v| dvec3(v)).to_vec();
                let n = tri.n.map(|n| n.map(|v| dvec3(v)).to_vec());
                self.mesh(&placed, mat, &(p, vec![[0, 1, 2]]), n.as_deref());
            }
            Shape::Mesh(mesh) => {
                let p: Vec<DVec3> = mesh.positions.iter().map(|v| dvec3(*v)).collect();
                let n: Option<Vec<DVec3>> = mesh
                    .normals
                    .as_ref()
                    .map(|n| n.iter().map(|v| dvec3(*v)).collect());
                self.mesh(&placed, mat, &(p, mesh.triangles_as_given()), n.as_deref());
            }
            Shape::Cone { .. } => return Err(ExportError::Unsupported("the cone")),
            Shape::Plane => return Err(ExportError::Unsupported("the infinite plane")),
            Shape::Group(_) => unreachable!("placement::each_leaf walks groups through"),
            Shape::Anchored(_) => unreachable!("written as the scene placed it (unanchored)"),
        }
        Ok(())
    }

    /// A triangle mesh in the shape's own coordinates, placed by `to_world`. With vertex
    /// normals it is shaded smooth (its normal AOV is then the interpolated normal, see
    /// `scripts/cycles_refs.py`), otherwise flat.
    fn mesh(
        &mut self,
        to_world: &Affine64,
        material: usize,
        (p, t): &(Vec<DVec3>, Vec<[u32; 3]>),
        normals: Option<&[DVec3]>,
    ) {
        let flat =
            |v: &[DVec3]| Value::Array(v.iter().flat_map(|x| [f(x.x), f(x.y), f(x.z)]).collect());
        self.objects.push(json!({
            "shape": "mesh",
            "matrix": matrix(to_world),
            "material": material,
            "positions": flat(p),
            "triangles": t.iter().flatten().collect::<Vec<_>>(),
            "normals": normals.map(flat),
        }));
    }
}

/// Whether a linear map is a similarity (orthogonal columns of equal length).
fn similar(m: &DMat3) -> bool {
    let c = [m.x_axis, m.y_axis, m.z_axis];
    let l0 = c[0].length_squared();
    c.iter()
        .all(|x| ((x.length_squared() - l0) / l0).abs() < 1e-9)
        && (0..3).all(|i| (i + 1..3).all(|j| (c[i].dot(c[j]) / l0).abs() < 1e-9))
}

type TriMesh = (Vec<DVec3>, Vec<[u32; 3]>);

/// Orders a triangle so that its (right-handed formula) cross product points along `n`.
fn wound(p: &[DVec3], t: [u32; 3], n: DVec3) -> [u32; 3] {
    let [a, b, c] = t.map(|i| p[i as usize]);
    if (b - a).cross(c - a).dot(n) < 0.0 {
        [t[0], t[2], t[1]]
    } else {
        t
    }
}

/// The renderer's box: [−1, 1]³, outward normals.
fn box_mesh() -> TriMesh {
    let p: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let mut t = Vec::new();
    for axis in 0..3 {
        for side in [0u32, 1] {
            let corners: Vec<u32> = (0..8u32).filter(|i| (i >> axis) & 1 == side).collect();
            let mut n = DVec3::ZERO;
            n[axis] = if side == 1 { 1.0 } else { -1.0 };
            // corners in bit order form a quad a, b, c, d with a–d the diagonal.
            let (a, b, c, d) = (corners[0], corners[1], corners[2], corners[3]);
            t.push(wound(&p, [a, b, d], n));
            t.push(wound(&p, [a, d, c], n));
        }
    }
    (p, t)
}

/// The renderer's rectangle: y = 0, x and z in [−1, 1], normal +y.
fn rectangle_mesh() -> TriMesh {
    let p = vec![
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(1.0, 0.0, -1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(-1.0, 0.0, 1.0),
    ];
    let t = vec![
        wound(&p, [0, 1, 2], DVec3::Y),
        wound(&p, [0, 2, 3], DVec3::Y),
    ];
    (p, t)
}

fn rim(k: usize, y: f64) -> DVec3 {
    let a = 2.0 * std::f64::consts::PI * k as f64 / SEGMENTS as f64;
    DVec3::new(a.cos(), y, a.sin())
}

/// A disk of radius 1 in the plane y = `y`, facing `sign` · y.
fn disk_mesh(y: f64, sign: f64) -> TriMesh {
    let mut p = vec![DVec3::new(0.0, y, 0.0)];
    p.extend((0..SEGMENTS).map(|k| rim(k, y)));
    let n = DVec3::new(0.0, sign, 0.0);
    let t = (0..SEGMENTS as u32)
        .map(|k| wound(&p, [0, 1 + k, 1 + (k + 1) % SEGMENTS as u32], n))
        .collect();
    (p, t)
}

/// The open cylinder of radius 1, y ∈ [−1, 1], with outward vertex normals.
fn cylinder_mesh() -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<DVec3>) {
    let mut p = Vec::with_capacity(2 * SEGMENTS);
    let mut n = Vec::with_capacity(2 * SEGMENTS);
    for k in 0..SEGMENTS {
        for y in [-1.0, 1.0] {
            let r = rim(k, y);
            p.push(r);
            n.push(DVec3::new(r.x, 0.0, r.z));
        }
    }
    let s = SEGMENTS as u32;
    let mut t = Vec::with_capacity(2 * SEGMENTS);
    for k in 0..s {
        let (a, b) = (2 * k, 2 * ((k + 1) % s));
        let out = n[a as usize] + n[b as usize];
        t.push(wound(&p, [a, b, a + 1], out));
        t.push(wound(&p, [b, b + 1, a + 1], out));
    }
    (p, t, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_world_map_is_a_reflection_and_its_own_inverse() {
        assert_eq!(WORLD.determinant(), -1.0);
        assert_eq!(WORLD * WORLD, DMat3::IDENTITY);
    }

    #[test]
    fn canonical_meshes_face_outward() {
        for (name, (p, t)) in [("box", box_mesh()), ("rectangle", rectangle_mesh())] {
            for tri in &t {
                let [a, b, c] = tri.map(|i| p[i as usize]);
                let n = (b - a).cross(c - a);
                let centre = (a + b + c) / 3.0;
                let out = if name == "box" { centre } else { DVec3::Y };
                assert!(n.dot(out) > 0.0, "{name}: triangle {tri:?} faces inward");
            }
        }
        assert_eq!(box_mesh().1.len(), 12);
        let (p, t, _) = cylinder_mesh();
        for tri in &t {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let centre = (a + b + c) / 3.0;
            assert!(
                (b - a)
                    .cross(c - a)
                    .dot(DVec3::new(centre.x, 0.0, centre.z))
                    > 0.0
            );
        }
    }
}
