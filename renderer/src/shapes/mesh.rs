//! Triangle meshes: shared vertex arrays, a BVH of their own, and the watertight test.
//! A mesh is held behind an `Arc`, so a mesh instanced a thousand times is stored once.

use super::triangle::{surface, TriPack, WoopRay};
use crate::aabb::Aabb;
use crate::bvh::{mask_ray_by_ray, Bvh, Visit, BATCH, INTERLEAVE_ABOVE};
use crate::hit::{Hit, RayHit};
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
    bvh: Bvh<8>,
    /// The triangles' vertices, four per pack, in the BVH's slot order: every leaf starts
    /// a pack, so a leaf is tested a pack (four triangles) at a time with no index array
    /// in between. Each lane also holds its triangle's number in the order it was given
    /// (the file's; `u32::MAX` for padding): the hit's `prim`, read once a search from
    /// the winner's pack, whose lines the test just read (in an array of its own it was a
    /// cache miss a ray), and what [`Mesh::triangles_as_given`] undoes. (40 bytes per
    /// triangle in `f32`, plus the padding of partly filled packs.)
    packs: Vec<TriPack>,
    /// For each pack lane, its triangle's index in `triangles` (`u32::MAX` for padding):
    /// read for the winner's normals and uvs only.
    pack_tris: Vec<[u32; 4]>,
}

/// The closest hit so far in a mesh search: the triangle (its pack and lane), `t` and the
/// barycentrics. The search reads nothing but the tree and the packs; the triangle's
/// index (for its normals and uvs) is looked up once, for the winner.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    pack: u32,
    lane: u8,
    t: Real,
    b: [Real; 3],
}

/// A triangle's geometric normal, `(p₁ − p₀) × (p₂ − p₀)` (not normalized): the hit
/// record's and the [`RayHit`]'s.
#[inline(always)]
fn geometric_normal([p0, p1, p2]: &[Vec3; 3]) -> Vec3 {
    (*p1 - *p0).cross(*p2 - *p0)
}

/// The values of a per-vertex array at a triangle's three vertices.
#[inline]
fn pick3<T: Copy>(v: &[T], tri: [u32; 3]) -> [T; 3] {
    tri.map(|k| v[k as usize])
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

/// The largest OBJ file a scene may name: 4 GiB (about 80 million triangles).
pub const MAX_OBJ_BYTES: u64 = 4 << 30;

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
        let numbered: Vec<(u32, [u32; 3])> = (0..).zip(triangles).collect();
        let (bvh, slots) = Bvh::<8>::build_aligned::<_, 4>(numbered, &boxes, 1.0);
        let mut triangles = Vec::with_capacity(boxes.len());
        let mut packs = crate::pages::huge_with_capacity(slots.len() / 4);
        let advised = packs.as_ptr();
        let mut pack_tris = Vec::with_capacity(slots.len() / 4);
        for chunk in slots.chunks(4) {
            let mut verts = Vec::with_capacity(4);
            let (mut ids, mut numbers) = ([u32::MAX; 4], [u32::MAX; 4]);
            for (lane, t) in chunk.iter().enumerate() {
                if let Some((g, t)) = t {
                    ids[lane] = triangles.len() as u32;
                    numbers[lane] = *g;
                    verts.push(t.map(|k| positions[k as usize]));
                    triangles.push(*t);
                }
            }
            packs.push(TriPack::new(&verts, numbers));
            pack_tris.push(ids);
        }
        debug_assert_eq!(
            packs.as_ptr(),
            advised,
            "the packs outgrew their advised memory (one per four slots)"
        );
        Ok(Mesh {
            positions,
            normals,
            uvs,
            triangles,
            bvh,
            packs,
            pack_tris,
        })
    }

    /// Loads a Wavefront OBJ file (all its models merged, triangulated).
    pub fn load_obj(path: &std::path::Path) -> Result<Self, MeshError> {
        // Only a regular file of bounded size: a device or a pipe (/dev/zero) would be read
        // without end.
        let meta = std::fs::metadata(path).map_err(|e| MeshError::Obj(e.to_string()))?;
        if !meta.is_file() {
            return Err(MeshError::Obj(
                "not a regular file (a mesh must be an OBJ file on disk)".into(),
            ));
        }
        if meta.len() > MAX_OBJ_BYTES {
            return Err(MeshError::Obj(format!(
                "{} bytes is more than the limit of {MAX_OBJ_BYTES} (4 GiB)",
                meta.len()
            )));
        }
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

    /// The triangles in the order they were given (the file's), not the BVH's: what an
    /// exporter writes, so that an export, and the hash of it that a reference records,
    /// does not change with the tree.
    pub fn triangles_as_given(&self) -> Vec<[u32; 3]> {
        let mut out = vec![[0; 3]; self.triangles.len()];
        for (ids, pack) in self.pack_tris.iter().zip(&self.packs) {
            for (&i, &g) in ids.iter().zip(&pack.number).filter(|(&i, _)| i != u32::MAX) {
                out[g as usize] = self.triangles[i as usize];
            }
        }
        out
    }

    /// Bounds in object space.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// The three vertices of triangle `i`.
    #[inline]
    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        pick3(&self.positions, self.triangles[i])
    }

    /// Closest hit. The search keeps only the closest `t` and its triangle; the hit
    /// record (point, normals, uv) is built once, for the winner.
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        self.search(ray, t_min, t_max).map(|c| self.finish(c))
    }

    /// [`Mesh::intersect`] written into `out` (left alone when there is no hit): the
    /// caller's record, so that it does not copy the one returned (aggregate/mod.rs's
    /// `Best`).
    pub fn intersect_into(&self, ray: &Ray, t_min: Real, t_max: Real, out: &mut Hit) -> bool {
        match self.search(ray, t_min, t_max) {
            Some(c) => {
                *out = self.finish(c);
                true
            }
            None => false,
        }
    }

    /// The closest hit as a [`RayHit`]: the search of [`Mesh::intersect`], and of its
    /// winner only the geometric normal, the barycentrics and the number, which the record
    /// computes the same way (the point, its error bound and the shading normal are left
    /// out).
    pub fn nearest(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<RayHit> {
        let c = self.search(ray, t_min, t_max)?;
        let (pack, lane) = (c.pack as usize, c.lane as usize);
        Some(RayHit {
            t: c.t,
            n_geo: geometric_normal(&self.packs[pack].triangle(lane)),
            b: Vec2::new(c.b[1], c.b[2]),
            surface: 0,
            prim: self.packs[pack].number[lane],
        })
    }

    /// The search for the closest hit: the winning triangle, its `t` and barycentrics.
    #[inline(always)]
    fn search(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Candidate> {
        let wr = WoopRay::new(ray);
        let mut best: Option<Candidate> = None;
        self.bvh.traverse_leaves_prefetching(
            ray,
            t_min,
            t_max,
            false,
            true,
            |first, count, tmax| self.visit_leaf(&wr, first, count, t_min, tmax, &mut best),
            |first| self.leaf_at(first),
        );
        best
    }

    /// [`Mesh::intersect`] for up to [`BATCH`] rays, each with its own `t_max`. When the
    /// mesh's tree and triangles are larger than [`INTERLEAVE_ABOVE`], the rays walk it
    /// together ([`Bvh::traverse_batch_leaves`], each step prefetching the next node or
    /// the next leaf's packs), so one ray's cache misses overlap the others' work; each
    /// ray takes exactly the steps it takes alone.
    pub fn intersect_batch(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        out: &mut [Option<Hit>],
    ) {
        if !self.interleaves() {
            for ((r, &tm), o) in rays.iter().zip(t_max).zip(out.iter_mut()) {
                *o = self.intersect(r, t_min, tm);
            }
            return;
        }
        let mut wrs = [WoopRay::new(&Ray::new(Vec3::ZERO, Vec3::ONE)); BATCH];
        for (w, r) in wrs.iter_mut().zip(rays) {
            *w = WoopRay::new(r);
        }
        let mut best: [Option<Candidate>; BATCH] = [None; BATCH];
        self.bvh.traverse_batch_leaves::<false, _, _>(
            rays,
            t_min,
            t_max,
            |r, first, count, tmax| {
                self.visit_leaf(&wrs[r], first, count, t_min, tmax, &mut best[r])
            },
            |first| self.leaf_at(first),
        );
        for (o, b) in out.iter_mut().zip(best) {
            *o = b.map(|c| self.finish(c));
        }
    }

    /// Where the packs of the leaf at slots `first..` start, for the walk's prefetch
    /// ahead of its test (a leaf has one or two packs of 160 bytes in `f32`; the
    /// prefetch's five lines cover them but for the second pack's last 32 bytes, its
    /// last coordinate row and its numbers, when the first starts 32 bytes into a line;
    /// the rare larger leaf, of coincident centroids or past the depth limit,
    /// gets about its first two).
    #[inline(always)]
    fn leaf_at(&self, first: u32) -> *const u8 {
        self.packs.as_ptr().wrapping_add(first as usize / 4).cast()
    }

    /// Whether [`Mesh::intersect_batch`] walks rays together: whether the tree and the
    /// packs take more than [`INTERLEAVE_ABOVE`] bytes.
    pub fn interleaves(&self) -> bool {
        self.bvh.node_bytes() + std::mem::size_of_val(self.packs.as_slice()) > INTERLEAVE_ABOVE
    }

    /// The packs of a leaf (slots `first..first + count`, starting a pack): each pack's
    /// index, the pack, and how many of its lanes the leaf fills.
    #[inline(always)]
    fn leaf_packs(&self, first: u32, count: u8) -> impl Iterator<Item = (usize, &TriPack, usize)> {
        let (first, count) = (first as usize / 4, count as usize);
        self.packs[first..first + count.div_ceil(4)]
            .iter()
            .enumerate()
            .map(move |(k, pack)| (first + k, pack, (count - 4 * k).min(4)))
    }

    /// Tests a leaf (slots `first..first + count`, starting a pack) pack by pack, keeping
    /// a closer hit in `best` as (triangle, t).
    #[inline(always)]
    fn visit_leaf(
        &self,
        wr: &WoopRay,
        first: u32,
        count: u8,
        t_min: Real,
        mut t_max: Real,
        best: &mut Option<Candidate>,
    ) -> Visit {
        let mut hit = false;
        for (index, pack, lanes) in self.leaf_packs(first, count) {
            if let Some((lane, t, b)) = wr.hit4(pack, lanes, t_min, t_max) {
                *best = Some(Candidate {
                    pack: index as u32,
                    lane: lane as u8,
                    t,
                    b,
                });
                t_max = t;
                hit = true;
            }
        }
        if hit {
            Visit::Hit(t_max)
        } else {
            Visit::Miss
        }
    }

    /// The hit record of the winning candidate (built once per ray, for the closest hit
    /// only). The vertices come from the pack the search just read (the same values as
    /// `positions`, copied); the triangle's vertex indices are read only for normals or
    /// uvs, its number as given always (the hit's `prim`).
    #[inline]
    fn finish(&self, c: Candidate) -> Hit {
        let (t, b) = (c.t, c.b);
        let (pack, lane) = (c.pack as usize, c.lane as usize);
        let [p0, p1, p2] = self.packs[pack].triangle(lane);
        let tri = (self.normals.is_some() || self.uvs.is_some())
            .then(|| self.triangles[self.pack_tris[pack][lane] as usize]);
        let n = self.normals.as_deref().zip(tri).map(|(v, t)| pick3(v, t));
        let uv = self.uvs.as_deref().zip(tri).map(|(v, t)| pick3(v, t));
        let n_geo = geometric_normal(&[p0, p1, p2]);
        let mut hit = surface(t, b, [p0, p1, p2], n_geo, n.as_ref(), uv.as_ref());
        hit.prim = self.packs[pack].number[lane];
        hit
    }

    /// Whether any triangle is hit. A mesh larger than the cache ([`Mesh::interleaves`])
    /// asks for the overlapped children's memory from the walk's first step, as the
    /// closest hit does: most shadow rays walk on past their first leaf there (on the
    /// peers bench's 1M-triangle mesh, shadow rays 1.01–1.04×, bounce rays 1.07×, against
    /// asking only once a leaf has failed; performance.md, 2026-11-29). A smaller mesh,
    /// in the cache, asks only then.
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        let wr = WoopRay::new(ray);
        self.bvh.traverse_leaves_prefetching(
            ray,
            t_min,
            t_max,
            true,
            self.interleaves(),
            |first, count, tmax| self.any_in_leaf(&wr, first, count, t_min, tmax),
            |first| self.leaf_at(first),
        )
    }

    /// [`Mesh::occluded`] for up to [`BATCH`] rays, each with its own `t_max`: bit `r` of
    /// the result for `rays[r]`. When the mesh interleaves ([`Mesh::interleaves`]) the rays
    /// walk its tree together ([`Bvh::traverse_batch_leaves`] with `ANY`), each taking exactly
    /// the steps it takes alone; otherwise one at a time.
    pub fn occluded_batch(&self, rays: &[Ray], t_min: Real, t_max: &[Real]) -> u64 {
        if !self.interleaves() {
            return mask_ray_by_ray(rays, t_max, |ray, t| self.occluded(ray, t_min, t));
        }
        let mut wrs = [WoopRay::new(&Ray::new(Vec3::ZERO, Vec3::ONE)); BATCH];
        for (w, r) in wrs.iter_mut().zip(rays) {
            *w = WoopRay::new(r);
        }
        self.bvh.traverse_batch_leaves::<true, _, _>(
            rays,
            t_min,
            t_max,
            |r, first, count, tmax| self.any_in_leaf(&wrs[r], first, count, t_min, tmax),
            |first| self.leaf_at(first),
        )
    }

    /// Tests a leaf (slots `first..first + count`, starting a pack) pack by pack, and
    /// stops at the first pack with a hit.
    #[inline(always)]
    fn any_in_leaf(&self, wr: &WoopRay, first: u32, count: u8, t_min: Real, t_max: Real) -> Visit {
        for (_, pack, lanes) in self.leaf_packs(first, count) {
            if let Some(t) = wr.hit4_any(pack, lanes, t_min, t_max) {
                return Visit::Hit(t);
            }
        }
        Visit::Miss
    }
}
