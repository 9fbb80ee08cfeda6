//! Triangle meshes: shared vertex arrays, a BVH of their own, and the watertight test.
//! A mesh is held behind an `Arc`, so a mesh instanced a thousand times is stored once.

use super::triangle::{surface, WoopRay};
use crate::aabb::Aabb;
use crate::bvh::{Bvh, Visit};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{Real, Vec2, Vec3};

/// An indexed triangle mesh in object space.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (same indexing as positions), if the file has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex uvs, if the file has them.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as vertex indices, in BVH leaf order (not file order).
    pub triangles: Vec<[u32; 3]>,
    bvh: Bvh,
}

/// Why a mesh is invalid.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {0} refers to a vertex index out of range")]
    Index(usize),
    /// A coordinate is NaN or infinite.
    #[error("vertex {0} is not finite")]
    NonFinite(usize),
    /// No triangles.
    #[error("the mesh has no triangles")]
    Empty,
    /// The OBJ loader failed.
    #[error("{0}")]
    Obj(String),
}

impl Mesh {
    /// Validates the arrays and builds the BVH. Degenerate (zero-area) triangles are kept:
    /// the watertight test never reports a hit on them.
    pub fn new(
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite(i));
        }
        let nv = positions.len();
        if let Some(i) = triangles
            .iter()
            .position(|t| t.iter().any(|&k| k as usize >= nv))
        {
            return Err(MeshError::Index(i));
        }
        let normals = normals.filter(|n| n.len() == nv && n.iter().all(|v| v.is_finite()));
        let uvs = uvs.filter(|u| u.len() == nv && u.iter().all(|v| v.is_finite()));
        let boxes: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                for &k in t {
                    b.grow(positions[k as usize]);
                }
                b
            })
            .collect();
        let (bvh, triangles) = Bvh::build(triangles, &boxes, 1.0);
        Ok(Mesh {
            positions,
            normals,
            uvs,
            triangles,
            bvh,
        })
    }

    /// Loads a Wavefront OBJ file (all its models merged, triangulated).
    pub fn load_obj(path: &std::path::Path) -> Result<Self, MeshError> {
        let opts = tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let (models, _) = tobj::load_obj(path, &opts).map_err(|e| MeshError::Obj(e.to_string()))?;
        let (mut pos, mut nrm, mut uv, mut tris) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut all_normals = true;
        let mut all_uvs = true;
        for m in &models {
            let mesh = &m.mesh;
            let base = pos.len() as u32;
            let nv = mesh.positions.len() / 3;
            for k in 0..nv {
                let p = &mesh.positions[3 * k..3 * k + 3];
                pos.push(Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real));
            }
            if mesh.normals.len() == 3 * nv {
                for k in 0..nv {
                    let n = &mesh.normals[3 * k..3 * k + 3];
                    nrm.push(Vec3::new(n[0] as Real, n[1] as Real, n[2] as Real));
                }
            } else {
                all_normals = false;
            }
            if mesh.texcoords.len() == 2 * nv {
                for k in 0..nv {
                    uv.push(Vec2::new(
                        mesh.texcoords[2 * k] as Real,
                        mesh.texcoords[2 * k + 1] as Real,
                    ));
                }
            } else {
                all_uvs = false;
            }
            for t in mesh.indices.chunks_exact(3) {
                tris.push([base + t[0], base + t[1], base + t[2]]);
            }
        }
        Mesh::new(pos, all_normals.then_some(nrm), all_uvs.then_some(uv), tris)
    }

    /// Bounds in object space.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// The three vertices of triangle `i`.
    #[inline]
    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        let t = self.triangles[i];
        [
            self.positions[t[0] as usize],
            self.positions[t[1] as usize],
            self.positions[t[2] as usize],
        ]
    }

    /// Closest hit.
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let wr = WoopRay::new(ray);
        let mut best: Option<(Real, [Real; 3], u32)> = None;
        self.bvh.traverse(ray, t_min, t_max, false, |i, tmax| {
            let [p0, p1, p2] = self.vertices(i as usize);
            match wr.hit(p0, p1, p2, t_min, tmax) {
                Some((t, b)) => {
                    best = Some((t, b, i));
                    Visit::Hit(t)
                }
                None => Visit::Miss,
            }
        });
        let (t, b, i) = best?;
        let [p0, p1, p2] = self.vertices(i as usize);
        let tri = self.triangles[i as usize];
        let pick3 = |v: &Vec<Vec3>| [v[tri[0] as usize], v[tri[1] as usize], v[tri[2] as usize]];
        let n = self.normals.as_ref().map(pick3);
        let uv = self
            .uvs
            .as_ref()
            .map(|v| [v[tri[0] as usize], v[tri[1] as usize], v[tri[2] as usize]]);
        Some(surface(
            t,
            b,
            [p0, p1, p2],
            (p1 - p0).cross(p2 - p0),
            n.as_ref(),
            uv.as_ref(),
        ))
    }

    /// Whether any triangle is hit.
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        let wr = WoopRay::new(ray);
        self.bvh.traverse(ray, t_min, t_max, true, |i, tmax| {
            let [p0, p1, p2] = self.vertices(i as usize);
            match wr.hit(p0, p1, p2, t_min, tmax) {
                Some((t, _)) => Visit::Hit(t),
                None => Visit::Miss,
            }
        })
    }
}
