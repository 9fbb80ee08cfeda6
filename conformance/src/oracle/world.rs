//! The oracle's own scene: every primitive of the built scene flattened to one list, each
//! with its `world_from_object` map and inverse in `f64`, its material and its interior.
//!
//! It reads the numbers POV-Ray reads: the exporter (`povray/sdl.rs`) writes every number as
//! its `f32` value, so each is taken here as `f32` widened to `f64`, in both builds. The
//! nested transforms of definitions are composed here in `f64`, as POV-Ray composes the
//! `matrix` of an `object` with those of its children. The scene is read from the renderer's
//! parsed and built [`Scene`] (its parser, transform-operation composition and material
//! inheritance); nothing of its intersection, shading, camera or BVH code is used.
//!
//! The oracle declines a scene with anything it does not model, naming it: the physical
//! integrators, more than one sample a pixel, lights other than points, area lights, and
//! a scene moved to a render-space origin.

use super::shapes::Primitive;
use glam::{DMat3, DVec3};
use renderer::aggregate::{Aggregate, Shape, INHERIT};
use renderer::light::LightKind;
use renderer::scene::{Integrator, Scene};
use renderer::transform::Transform;

/// A `world_from_object` affine map and its inverse.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    /// Linear part.
    pub m: DMat3,
    /// Translation.
    pub t: DVec3,
    /// Inverse of the linear part.
    pub inv: DMat3,
}

impl Affine {
    const IDENTITY: Affine = Affine {
        m: DMat3::IDENTITY,
        t: DVec3::ZERO,
        inv: DMat3::IDENTITY,
    };

    fn new(m: DMat3, t: DVec3) -> Affine {
        Affine {
            m,
            t,
            inv: m.inverse(),
        }
    }

    /// `self ∘ inner`.
    fn then_inner(&self, inner: &Affine) -> Affine {
        Affine::new(self.m * inner.m, self.m * inner.t + self.t)
    }
}

/// One primitive placed in the world.
#[derive(Clone, Debug)]
pub struct Object {
    /// What it is, in object space.
    pub prim: Primitive,
    /// `world_from_object`.
    pub xf: Affine,
    /// Index into [`World::materials`].
    pub material: usize,
    /// The interior it belongs to (POV-Ray's `interior` block: every child of a
    /// definition placed with a material shares the placement's).
    pub interior: usize,
}

/// A point light.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position.
    pub position: DVec3,
    /// Colour.
    pub color: DVec3,
    /// `fade_distance`, `fade_power`.
    pub fade: Option<(f64, f64)>,
}

/// A POV-Ray texture and interior, in `f64`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Finish {
    /// Pigment colour.
    pub color: DVec3,
    /// Pigment filter.
    pub filter: f64,
    /// Pigment transmit.
    pub transmit: f64,
    /// Finish terms.
    pub ambient: f64,
    /// `emission`.
    pub emission: f64,
    /// `diffuse`.
    pub diffuse: f64,
    /// `brilliance`.
    pub brilliance: f64,
    /// `phong`.
    pub phong: f64,
    /// `phong_size`.
    pub phong_size: f64,
    /// `specular`.
    pub specular: f64,
    /// `roughness`.
    pub roughness: f64,
    /// `reflection`.
    pub reflection: f64,
    /// Interior `ior`.
    pub ior: f64,
}

/// Everything the oracle traces.
#[derive(Clone, Debug)]
pub struct World {
    /// Every primitive.
    pub objects: Vec<Object>,
    /// Point lights.
    pub lights: Vec<PointLight>,
    /// Materials, by the scene's index.
    pub materials: Vec<Finish>,
    /// `background`.
    pub background: DVec3,
    /// `ambient_light`.
    pub ambient_light: DVec3,
    /// `max_trace_level`.
    pub max_trace_level: u32,
    /// `adc_bailout`.
    pub adc_bailout: f64,
    /// Number of interiors.
    pub interiors: usize,
}

/// A number as POV-Ray reads it from the export: its `f32` value.
fn wide(x: impl Into<f64>) -> f64 {
    x.into() as f32 as f64
}

fn wide3(v: renderer::Vec3) -> DVec3 {
    DVec3::new(wide(v.x), wide(v.y), wide(v.z))
}

fn colour(c: renderer::scene::Color) -> DVec3 {
    DVec3::new(c.x as f64, c.y as f64, c.z as f64)
}

fn affine(t: &Transform) -> Affine {
    let m = t.matrix();
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(wide3);
    Affine::new(
        DMat3::from_cols(cols[0], cols[1], cols[2]),
        wide3(t.translation()),
    )
}

impl World {
    /// The oracle's scene, or the reason it declines it.
    pub fn new(scene: &Scene) -> Result<World, String> {
        let s = &scene.settings;
        if s.integrator != Integrator::Classic {
            return Err(
                "a physically based integrator (the oracle models POV-Ray's classic model)".into(),
            );
        }
        if s.samples > 1 {
            return Err(format!(
                "{} samples a pixel (the oracle traces pixel centres)",
                s.samples
            ));
        }
        if scene.origin() != DVec3::ZERO {
            return Err("a render-space origin (render.origin)".into());
        }
        if !scene.area_lights.is_empty() {
            return Err("area lights".into());
        }
        let mut lights = Vec::new();
        for l in &scene.lights {
            if l.kind != LightKind::Point {
                return Err(format!(
                    "a {:?} light (the oracle knows point lights)",
                    l.kind
                ));
            }
            lights.push(PointLight {
                position: wide3(l.position),
                color: colour(l.color),
                fade: l.fade.map(|(d, p)| (wide(d), wide(p))),
            });
        }
        let materials = scene
            .materials
            .iter()
            .map(|m| Finish {
                color: colour(m.color),
                filter: m.filter as f64,
                transmit: m.transmit as f64,
                ambient: m.ambient as f64,
                emission: m.emission as f64,
                diffuse: m.diffuse as f64,
                brilliance: m.brilliance as f64,
                phong: m.phong as f64,
                phong_size: m.phong_size as f64,
                specular: m.specular as f64,
                roughness: m.roughness as f64,
                reflection: m.reflection as f64,
                ior: m.ior as f64,
            })
            .collect();
        let mut w = World {
            objects: Vec::new(),
            lights,
            materials,
            background: colour(s.background),
            ambient_light: colour(s.ambient_light),
            max_trace_level: s.max_depth,
            adc_bailout: s.adc_bailout as f64,
            interiors: 0,
        };
        w.flatten(&scene.root, &Affine::IDENTITY, None)?;
        Ok(w)
    }

    /// Adds the primitives of `agg` placed by `outer`; `inherited` is the material and
    /// interior of the enclosing placement (`None` at the top level).
    fn flatten(
        &mut self,
        agg: &Aggregate,
        outer: &Affine,
        inherited: Option<(usize, usize)>,
    ) -> Result<(), String> {
        for inst in agg.in_scene_order() {
            // A shape in mixed precision is taken as the scene placed it.
            let inst = &*inst.unanchored();
            let xf = match &inst.xf {
                Some(t) => outer.then_inner(&affine(t)),
                None => *outer,
            };
            // A top-level object without a material takes the first (as the exporter
            // writes it); an object with its own material gets its own interior.
            let own = match (inst.material, inherited) {
                (INHERIT, Some(m)) => m,
                (INHERIT, None) => (0, self.new_interior()),
                (k, _) => (k as usize, self.new_interior()),
            };
            let prim = match &inst.shape {
                Shape::Sphere => Primitive::Sphere,
                Shape::Plane => Primitive::Plane,
                Shape::Cube => Primitive::Cube,
                Shape::Cylinder { capped } => Primitive::Cylinder { capped: *capped },
                Shape::Cone { capped } => Primitive::Cone { capped: *capped },
                Shape::Disk => Primitive::Disk,
                Shape::Rectangle => Primitive::Rectangle,
                Shape::Triangle(t) => {
                    Primitive::Triangle(t.p.map(wide3), t.n.map(|n| n.map(wide3)))
                }
                Shape::Mesh(m) => {
                    for t in m.triangles_as_given() {
                        let at = |k: usize| t[k] as usize;
                        let p = [0, 1, 2].map(|k| wide3(m.positions[at(k)]));
                        let n = m
                            .normals
                            .as_ref()
                            .map(|n| [0, 1, 2].map(|k| wide3(n[at(k)])));
                        self.objects.push(Object {
                            prim: Primitive::Triangle(p, n),
                            xf,
                            material: own.0,
                            interior: own.1,
                        });
                    }
                    continue;
                }
                Shape::Group(g) => {
                    self.flatten(g, &xf, Some(own))?;
                    continue;
                }
                Shape::Anchored(_) => unreachable!("taken as the scene placed it (unanchored)"),
            };
            self.objects.push(Object {
                prim,
                xf,
                material: own.0,
                interior: own.1,
            });
        }
        Ok(())
    }

    fn new_interior(&mut self) -> usize {
        self.interiors += 1;
        self.interiors - 1
    }
}
