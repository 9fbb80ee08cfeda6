//! The object tree flattened into instances: transforms composed in f64, materials and
//! definitions resolved, meshes loaded once per file, each node validated where it is
//! written.

use super::error::{SceneError, Source};
use super::format::dv;
use super::format::{NodeDesc, NodeKind};
use super::scale_check::{self, ScaleNote, BUILD_BITS, MIXED_BITS};
use super::transform_ops::op_affine;
use crate::aggregate::{Aggregate, Instance, Shape, INHERIT};
use crate::real::{dvec3, vec3, Real, Vec2};
use crate::shapes::{Mesh, Triangle};
use crate::suggest::did_you_mean;
use crate::transform::{Affine64, Transform};
use glam::{DMat3, DVec3};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::PathBuf;
use std::sync::Arc;
use toml::Spanned;

pub(super) struct Builder<'a> {
    pub(super) src: &'a Source<'a>,
    pub(super) emissive: Vec<bool>,
    pub(super) base: PathBuf,
    pub(super) materials: HashMap<String, u32>,
    pub(super) defs: &'a BTreeMap<String, Spanned<NodeDesc>>,
    pub(super) built_defs: HashMap<String, Arc<Aggregate>>,
    pub(super) in_progress: HashSet<String>,
    pub(super) meshes: HashMap<PathBuf, Arc<Mesh>>,
    pub(super) objects: Vec<String>,
    /// The world point at render space's origin.
    pub(super) origin: DVec3,
    /// The eye, in world coordinates, and the relative depth the camera resolves
    /// ([`scale_check::tolerance`]).
    pub(super) eye: DVec3,
    pub(super) tau: f64,
    /// Instances of the scene's own tree that the build's precision cannot resolve.
    pub(super) notes: Vec<ScaleNote>,
    /// Whether such instances go to mixed precision (`render.mixed_precision`).
    pub(super) mixed: bool,
}

impl Builder<'_> {
    /// The scene's own objects, flattened, in the render space whose origin is the world
    /// point `origin`: every top-level transform is composed (in `f64`) with a translation
    /// by `−origin` before it is converted to the render precision.
    pub(super) fn top_level(
        &mut self,
        objects: &[Spanned<NodeDesc>],
        origin: DVec3,
    ) -> Result<Vec<Instance>, SceneError> {
        self.objects.clear();
        self.notes.clear();
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

        let mut shape = match d.kind {
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
                // Normals and uvs are checked as the vertices are, where they are
                // written (an OBJ file's are refused by the mesh loader).
                let n = d.normals.as_ref().map(|n| n.get_ref().map(|q| vec3(dv(q))));
                if let (Some(at), Some(n)) = (&d.normals, &n) {
                    if n.iter().any(|q| !q.is_finite()) {
                        return Err(self.src.error(
                            at.span().start,
                            format!("{path}.normals"),
                            format!(
                                "must be finite in the renderer's precision ({})",
                                crate::real::PRECISION
                            ),
                        ));
                    }
                }
                let uv = d
                    .uvs
                    .as_ref()
                    .map(|u| u.get_ref().map(|q| Vec2::new(q[0] as Real, q[1] as Real)));
                if let (Some(at), Some(uv)) = (&d.uvs, &uv) {
                    if uv.iter().any(|q| !q.is_finite()) {
                        return Err(self.src.error(
                            at.span().start,
                            format!("{path}.uvs"),
                            format!(
                                "must be finite in the renderer's precision ({})",
                                crate::real::PRECISION
                            ),
                        ));
                    }
                }
                let tri = Triangle { p, n, uv };
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
        let placed = |xf: &Affine64| {
            Transform::new(xf)
                .map_err(|e| err("transform", &format!("composed with its parents: {e}")))
        };
        let mut transform = if xf.is_identity() {
            None
        } else {
            Some(placed(&xf)?)
        };
        if numbered {
            let inv = transform.map_or(DMat3::IDENTITY, |t| {
                let m = t.inverse_matrix();
                DMat3::from_cols(dvec3(m.x_axis), dvec3(m.y_axis), dvec3(m.z_axis))
            });
            if let Some(moved) = self.check_scale(&mut shape, &xf, &inv, material, span.start, path)
            {
                transform = Some(placed(&moved)?);
            }
        }
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

    /// The scale check of renderer/docs/precision.md ("Scale against view") for an
    /// instance of the scene's own tree: when the build's precision cannot resolve it, a
    /// note, and the instance moved to mixed precision where its shape allows (not an
    /// emitter: area lights sample the canonical shape).
    /// Returns the instance's new transform when it moved. `inv`: the linear part of the
    /// transform's inverse as stored (the build's precision is enough for an estimate).
    fn check_scale(
        &mut self,
        shape: &mut Shape,
        xf: &Affine64,
        inv: &DMat3,
        material: u32,
        at: usize,
        path: &str,
    ) -> Option<Affine64> {
        let eye = self.eye - self.origin;
        let need = scale_check::need(shape, xf, inv, eye, self.tau);
        // (A NaN estimate, which a finite transform should never give, counts as fine.)
        if !(need.bits > BUILD_BITS) {
            return None;
        }
        let emits = material != INHERIT && self.emissive[material as usize];
        let moved = (self.mixed && need.bits <= MIXED_BITS && !emits)
            .then(|| scale_check::anchored(shape, xf, need.anchor))
            .flatten()
            .map(|(s, x)| {
                *shape = s;
                x
            });
        let mixed = moved.is_some();
        let (line, column) = self.src.line_col(at);
        self.notes.push(ScaleNote {
            file: self.src.file.clone(),
            line,
            column,
            field: path.to_string(),
            bits: need.bits,
            ratio: need.ratio,
            mixed,
            mixed_off: !self.mixed,
        });
        moved
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
