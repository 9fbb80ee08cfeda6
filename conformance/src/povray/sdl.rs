//! Scene → POV-Ray 3.7 SDL.
//!
//! The exporter works from the built [`Scene`], so POV-Ray renders exactly the geometry the
//! renderer renders: every number is written as the exact decimal value of its `f32`
//! (printed through `f64`), transforms as `matrix`, and the camera as
//! explicit location/direction/right/up, which reproduces the viewing model's window
//! exactly (see renderer/docs/scene-format.md, `[camera.povray]`).
//!
//! | primitive | POV-Ray |
//! |---|---|
//! | sphere | `sphere { <0,0,0>, 1 }` |
//! | plane | `plane { y, 0 }` |
//! | box | `box { <-1,-1,-1>, <1,1,1> }` |
//! | cylinder | `cylinder { <0,-1,0>, <0,1,0>, 1 [open] }` |
//! | cone | `cone { <0,-1,0>, 1, <0,1,0>, 0 [open] }` |
//! | disk | `disc { <0,0,0>, y, 1 }` |
//! | rectangle | `polygon { 5, <-1,0,-1>, <1,0,-1>, <1,0,1>, <-1,0,1>, <-1,0,-1> }` |
//! | triangle | `triangle` or `smooth_triangle` |
//! | mesh | `mesh2` (declared once) |
//! | definition | `union` (declared once), placed with `object` |

use renderer::aggregate::Shape;
use renderer::aggregate::{Aggregate, Instance, INHERIT};
use renderer::real::Real;
use renderer::scene::{Color, Material, Scene};
use renderer::transform::Transform;
use std::collections::HashMap;
use std::fmt::Write;

/// A number as the exact decimal of its `f32` value. Both builds export the same text (the
/// f32 scene), so one set of references serves the f32 and the f64 renderer; the f64 build
/// renders geometry that differs from it by about 1e-7 relative, far below the
/// comparison's half-float tolerance.
fn num(x: Real) -> String {
    let x = x as f32 as f64;
    if x == 0.0 {
        return "0".into();
    }
    format!("{x}")
}

fn f(x: f32) -> String {
    num(x as Real)
}

fn vec(v: renderer::Vec3) -> String {
    format!("<{}, {}, {}>", num(v.x), num(v.y), num(v.z))
}

fn vec64(v: glam::DVec3) -> String {
    format!("<{}, {}, {}>", v.x, v.y, v.z)
}

fn rgb(c: Color) -> String {
    format!("<{}, {}, {}>", f(c.x), f(c.y), f(c.z))
}

/// A render-space point in world coordinates: as [`vec`] when the scene was not moved
/// (`origin` 0, the text both builds share), else render space plus the origin, in f64.
fn world(p: renderer::Vec3, origin: glam::DVec3) -> String {
    if origin == glam::DVec3::ZERO {
        vec(p)
    } else {
        vec64(renderer::real::dvec3(p) + origin)
    }
}

/// POV-Ray's `matrix`: rows of the row-vector convention, i.e. the columns of the stored
/// column-vector matrix, then the translation. `origin` moves a top-level object from
/// render space back to the scene's own coordinates (0 inside definitions).
fn matrix(t: &Transform, origin: glam::DVec3) -> String {
    let m = t.matrix();
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let mut s = String::from("matrix <");
    for c in cols {
        write!(s, "{}, {}, {}, ", num(c.x), num(c.y), num(c.z)).unwrap();
    }
    let d = world(t.translation(), origin);
    write!(s, "{}>", &d[1..d.len() - 1]).unwrap();
    s
}

fn texture_name(m: &Material, index: u32) -> String {
    let clean: String = m
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("M{index}_{clean}")
}

struct Exporter<'a> {
    scene: &'a Scene,
    out: String,
    meshes: HashMap<usize, String>,
    defs: HashMap<usize, String>,
}

/// Exports a scene as POV-Ray SDL.
pub fn export(scene: &Scene, title: &str) -> String {
    let mut e = Exporter {
        scene,
        out: String::new(),
        meshes: HashMap::new(),
        defs: HashMap::new(),
    };
    e.header(title);
    let body = e.aggregate_body(&scene.root, true);
    e.out.push_str(&body);
    e.out
}

impl Exporter<'_> {
    fn header(&mut self, title: &str) {
        let s = &self.scene.settings;
        let o = &mut self.out;
        writeln!(
            o,
            "// {title}: exported by the verified-tracer conformance harness."
        )
        .unwrap();
        writeln!(o, "#version 3.7;").unwrap();
        writeln!(
            o,
            "global_settings {{ assumed_gamma 1.0 max_trace_level {} adc_bailout {} ambient_light rgb {} }}",
            s.max_depth,
            f(s.adc_bailout),
            rgb(s.ambient_light)
        )
        .unwrap();
        writeln!(o, "background {{ rgb {} }}", rgb(s.background)).unwrap();
        let [loc, dir, right, up] = self
            .scene
            .camera
            .model
            .to_povray()
            .expect("a built camera converts to POV-Ray vectors");
        writeln!(
            o,
            "camera {{ perspective location {} direction {} right {} up {} }}",
            vec64(loc),
            vec64(dir),
            vec64(right),
            vec64(up)
        )
        .unwrap();
        for l in &self.scene.lights {
            write!(
                o,
                "light_source {{ {} color rgb {}",
                world(l.position, self.scene.origin()),
                rgb(l.color)
            )
            .unwrap();
            if let Some((d, p)) = l.fade {
                write!(o, " fade_distance {} fade_power {}", num(d), num(p)).unwrap();
            }
            writeln!(o, " }}").unwrap();
        }
        for (k, m) in self.scene.materials.iter().enumerate() {
            writeln!(
                o,
                "#declare {} = texture {{ pigment {{ rgbft <{}, {}, {}, {}, {}> }} finish {{ ambient {} emission {} diffuse {} brilliance {} phong {} phong_size {} specular {} roughness {} reflection {} }} }}",
                texture_name(m, k as u32),
                f(m.color.x),
                f(m.color.y),
                f(m.color.z),
                f(m.filter),
                f(m.transmit),
                f(m.ambient),
                f(m.emission),
                f(m.diffuse),
                f(m.brilliance),
                f(m.phong),
                f(m.phong_size),
                f(m.specular),
                f(m.roughness),
                f(m.reflection),
            )
            .unwrap();
        }
    }

    /// The objects of an aggregate, one per line. At the top level every object gets its
    /// material; inside a definition only objects with their own material do.
    fn aggregate_body(&mut self, agg: &Aggregate, top: bool) -> String {
        let mut s = String::new();
        for inst in agg.in_scene_order() {
            let line = self.instance(inst, top);
            s.push_str(&line);
            s.push('\n');
        }
        s
    }

    fn instance(&mut self, inst: &Instance, top: bool) -> String {
        // A shape in mixed precision is written as the scene placed it.
        let inst = &*inst.unanchored();
        let shape = self.shape(&inst.shape);
        let mut mods = String::new();
        // A top-level object goes from render space back to the scene's own coordinates.
        let origin = if top {
            self.scene.origin()
        } else {
            glam::DVec3::ZERO
        };
        match &inst.xf {
            Some(t) => write!(mods, " {}", matrix(t, origin)).unwrap(),
            None if origin != glam::DVec3::ZERO => {
                write!(mods, " translate {}", vec64(origin)).unwrap()
            }
            None => {}
        }
        let material = if inst.material == INHERIT && top {
            0
        } else {
            inst.material
        };
        if material != INHERIT {
            let m = self.scene.material(material);
            write!(
                mods,
                " texture {{ {} }} interior {{ ior {} }}",
                texture_name(m, material),
                f(m.ior)
            )
            .unwrap();
        }
        format!("object {{ {shape}{mods} }}")
    }

    fn shape(&mut self, shape: &Shape) -> String {
        match shape {
            Shape::Sphere => "sphere { <0, 0, 0>, 1 }".into(),
            Shape::Plane => "plane { y, 0 }".into(),
            Shape::Cube => "box { <-1, -1, -1>, <1, 1, 1> }".into(),
            Shape::Cylinder { capped } => format!(
                "cylinder {{ <0, -1, 0>, <0, 1, 0>, 1{} }}",
                if *capped { "" } else { " open" }
            ),
            Shape::Cone { capped } => format!(
                "cone {{ <0, -1, 0>, 1, <0, 1, 0>, 0{} }}",
                if *capped { "" } else { " open" }
            ),
            Shape::Disk => "disc { <0, 0, 0>, y, 1 }".into(),
            Shape::Rectangle => {
                "polygon { 5, <-1, 0, -1>, <1, 0, -1>, <1, 0, 1>, <-1, 0, 1>, <-1, 0, -1> }".into()
            }
            Shape::Triangle(t) => match &t.n {
                Some(n) => format!(
                    "smooth_triangle {{ {}, {}, {}, {}, {}, {} }}",
                    vec(t.p[0]),
                    vec(n[0]),
                    vec(t.p[1]),
                    vec(n[1]),
                    vec(t.p[2]),
                    vec(n[2])
                ),
                None => format!(
                    "triangle {{ {}, {}, {} }}",
                    vec(t.p[0]),
                    vec(t.p[1]),
                    vec(t.p[2])
                ),
            },
            Shape::Mesh(m) => {
                let key = std::sync::Arc::as_ptr(m) as usize;
                if let Some(name) = self.meshes.get(&key) {
                    return name.clone();
                }
                let name = format!("Mesh{}", self.meshes.len());
                let mut d = format!(
                    "#declare {name} = mesh2 {{\n  vertex_vectors {{ {}",
                    m.positions.len()
                );
                for p in &m.positions {
                    write!(d, ", {}", vec(*p)).unwrap();
                }
                d.push_str(" }\n");
                if let Some(n) = &m.normals {
                    write!(d, "  normal_vectors {{ {}", n.len()).unwrap();
                    for v in n {
                        write!(d, ", {}", vec(*v)).unwrap();
                    }
                    d.push_str(" }\n");
                }
                write!(d, "  face_indices {{ {}", m.triangles.len()).unwrap();
                for t in &m.triangles_as_given() {
                    write!(d, ", <{}, {}, {}>", t[0], t[1], t[2]).unwrap();
                }
                d.push_str(" }\n}\n");
                self.out.push_str(&d);
                self.meshes.insert(key, name.clone());
                name
            }
            Shape::Anchored(_) => unreachable!("written as the scene placed it (unanchored)"),
            Shape::Group(g) => {
                let key = std::sync::Arc::as_ptr(g) as usize;
                if let Some(name) = self.defs.get(&key) {
                    return name.clone();
                }
                let name = format!("Def{}", self.defs.len());
                let body = self.aggregate_body(g, false);
                let wrapper = if g.instances.len() > 1 {
                    "union"
                } else {
                    "object"
                };
                let d = format!("#declare {name} = {wrapper} {{\n{body}}}\n");
                self.out.push_str(&d);
                self.defs.insert(key, name.clone());
                name
            }
        }
    }
}
