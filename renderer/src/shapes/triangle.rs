//! The watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2013): permute the axes
//! so the largest direction component is z, shear the vertices into ray space, and test
//! 2D edge functions. An edge function that is exactly zero is recomputed in `f64`, so a
//! ray through a shared edge or vertex hits exactly one of the triangles that share it
//! (or both, at the same t), never neither.

use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3, Vec4};

/// A ray prepared for many triangle tests.
#[derive(Clone, Copy, Debug)]
pub struct WoopRay {
    o: Vec3,
    k: [usize; 3],
    s: [Real; 3],
}

impl WoopRay {
    /// Prepares `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let a = ray.d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if ray.d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = ray.d[kz];
        WoopRay {
            o: ray.o,
            k: [kx, ky, kz],
            s: [ray.d[kx] / dz, ray.d[ky] / dz, 1.0 / dz],
        }
    }

    /// Tests one triangle. Returns `t` and the barycentric weights of p0, p1, p2.
    #[inline]
    pub fn hit(
        &self,
        p0: Vec3,
        p1: Vec3,
        p2: Vec3,
        t_min: Real,
        t_max: Real,
    ) -> Option<(Real, [Real; 3])> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.s;
        let a = p0 - self.o;
        let b = p1 - self.o;
        let c = p2 - self.o;
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as Real;
            v = (ax * cy - ay * cx) as Real;
            w = (bx * ay - by * ax) as Real;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (sz * a[kz], sz * b[kz], sz * c[kz]);
        let t = (u * az + v * bz + w * cz) / det;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let inv = 1.0 / det;
        Some((t, [u * inv, v * inv, w * inv]))
    }
}

/// Four triangles side by side for [`WoopRay::hit4`]: `v[3·k + a]` holds coordinate `a`
/// of vertex `k` of the four triangles, one per lane.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct TriPack {
    pub(crate) v: [[Real; 4]; 9],
    /// A number the owner keeps with each lane's triangle (a mesh: its number as given),
    /// beside the vertices, so that the winner's is read from lines the test just read.
    pub(crate) number: [u32; 4],
}

impl TriPack {
    /// Packs up to four triangles (missing lanes are zero and must be masked off), each
    /// with its number (`u32::MAX` in a missing lane).
    pub fn new(tris: &[[Vec3; 3]], number: [u32; 4]) -> TriPack {
        let mut v = [[0.0; 4]; 9];
        for (lane, t) in tris.iter().enumerate() {
            for k in 0..3 {
                for a in 0..3 {
                    v[3 * k + a][lane] = t[k][a];
                }
            }
        }
        TriPack { v, number }
    }

    /// The vertices of the triangle in `lane`.
    #[inline]
    pub fn triangle(&self, lane: usize) -> [Vec3; 3] {
        let p = |k: usize| {
            Vec3::new(
                self.v[3 * k][lane],
                self.v[3 * k + 1][lane],
                self.v[3 * k + 2][lane],
            )
        };
        [p(0), p(1), p(2)]
    }
}

impl WoopRay {
    /// [`WoopRay::hit`] on the first `lanes` triangles of a pack at once: the lane of the
    /// closest hit with `t_min < t < t_max` (the lowest lane on a tie, as testing them in
    /// order would give), its `t` and barycentrics. Each lane computes exactly what the scalar test
    /// computes, operation for operation; a lane whose edge function is exactly 0 (which
    /// the scalar test redoes in `f64`) is handed to the scalar test. So the result is the
    /// scalar loop's, bit for bit.
    #[inline]
    pub fn hit4(
        &self,
        pack: &TriPack,
        lanes: usize,
        t_min: Real,
        t_max: Real,
    ) -> Option<(usize, Real, [Real; 3])> {
        let Lanes4 {
            u,
            v,
            w,
            det,
            t,
            masked,
            exact,
            ok,
        } = self.lanes4(pack, lanes, t_min, t_max);
        // A lane's barycentrics, as the scalar test computes them.
        let bary = |lane: usize| {
            let (u, v, w) = (u.to_array()[lane], v.to_array()[lane], w.to_array()[lane]);
            let inv = 1.0 / det.to_array()[lane];
            [u * inv, v * inv, w * inv]
        };
        if exact == 0 {
            // The closest accepted lane, the lowest on a tie, without a loop.
            if ok == 0 {
                return None;
            }
            let tmin = masked.min_element();
            let lane = (masked.cmpeq(Vec4::splat(tmin)).bitmask() & ok).trailing_zeros() as usize;
            return Some((lane, tmin, bary(lane)));
        }
        let tl = t.to_array();
        let mut best: Option<(usize, Real, [Real; 3])> = None;
        for lane in 0..lanes {
            let hit = if exact & (1 << lane) != 0 {
                let [p0, p1, p2] = pack.triangle(lane);
                match self.hit(p0, p1, p2, t_min, t_max) {
                    Some((t, b)) => (t, b),
                    None => continue,
                }
            } else if ok & (1 << lane) != 0 {
                (tl[lane], bary(lane))
            } else {
                continue;
            };
            if best.is_none_or(|(_, tb, _)| hit.0 < tb) {
                best = Some((lane, hit.0, hit.1));
            }
        }
        best
    }

    /// [`WoopRay::hit4`] for a search for any hit: the `t` of a hit among the first
    /// `lanes` triangles of the pack with `t_min < t < t_max`, or `None` when there is
    /// none (exactly when `hit4` finds none). Which hit is left open: the lowest lane
    /// the SIMD test accepts, else the first lane the scalar test hits. It skips the
    /// closest lane's search and the barycentrics, and is inlined into the walk. (On the
    /// peers bench's 1M-triangle mesh, one thread, three alternating pairs against
    /// `hit4`: any hit on coherent primary rays 1.13-1.21x; on shadow and bounce rays,
    /// whose walks wait on memory, 0.96-1.04x.)
    #[inline(always)]
    pub fn hit4_any(&self, pack: &TriPack, lanes: usize, t_min: Real, t_max: Real) -> Option<Real> {
        let l = self.lanes4(pack, lanes, t_min, t_max);
        if l.ok != 0 {
            return Some(l.t.to_array()[l.ok.trailing_zeros() as usize]);
        }
        let mut m = l.exact;
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let [p0, p1, p2] = pack.triangle(lane);
            if let Some((t, _)) = self.hit(p0, p1, p2, t_min, t_max) {
                return Some(t);
            }
        }
        None
    }

    /// The SIMD part of [`WoopRay::hit4`]: each lane's edge functions, determinant and
    /// `t`, the lanes accepted, and the bit masks of the lanes left to the scalar test
    /// (an edge function exactly 0) and of those accepted.
    #[inline(always)]
    fn lanes4(&self, pack: &TriPack, lanes: usize, t_min: Real, t_max: Real) -> Lanes4 {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.s;
        let (sx, sy, sz) = (Vec4::splat(sx), Vec4::splat(sy), Vec4::splat(sz));
        let o = [
            Vec4::splat(self.o[kx]),
            Vec4::splat(self.o[ky]),
            Vec4::splat(self.o[kz]),
        ];
        // Vertex k relative to the origin, in the permuted axes, sheared.
        let rel = |k: usize| {
            let (x, y, z) = (
                Vec4::from_array(pack.v[3 * k + kx]) - o[0],
                Vec4::from_array(pack.v[3 * k + ky]) - o[1],
                Vec4::from_array(pack.v[3 * k + kz]) - o[2],
            );
            (x - sx * z, y - sy * z, z)
        };
        let (ax, ay, az) = rel(0);
        let (bx, by, bz) = rel(1);
        let (cx, cy, cz) = rel(2);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        // The lanes in use, and those whose edge function is exactly 0 (the scalar test
        // redoes them in f64).
        let live = Vec4::new(0.0, 1.0, 2.0, 3.0).cmplt(Vec4::splat(lanes as Real));
        let exact = (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)) & live;
        let neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
        let pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
        let det = u + v + w;
        let t = (u * (sz * az) + v * (sz * bz) + w * (sz * cz)) / det;
        let accepted = !(neg & pos)
            & det.cmpne(zero)
            & t.cmpgt(Vec4::splat(t_min))
            & t.cmplt(Vec4::splat(t_max))
            & live
            & !exact;
        Lanes4 {
            u,
            v,
            w,
            det,
            t,
            masked: Vec4::select(accepted, t, Vec4::INFINITY),
            exact: exact.bitmask(),
            ok: accepted.bitmask(),
        }
    }
}

/// What [`WoopRay::lanes4`] computes for a pack.
struct Lanes4 {
    u: Vec4,
    v: Vec4,
    w: Vec4,
    det: Vec4,
    t: Vec4,
    /// `t` in the accepted lanes, ∞ in the others.
    masked: Vec4,
    exact: u32,
    ok: u32,
}

/// A single triangle with optional per-vertex normals and uvs.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3; 3],
    /// Per-vertex shading normals.
    pub n: Option<[Vec3; 3]>,
    /// Per-vertex uvs; the default is (0,0), (1,0), (0,1).
    pub uv: Option<[Vec2; 3]>,
}

impl Triangle {
    /// The geometric normal `(p1 − p0) × (p2 − p0)` (not normalized).
    pub fn normal(&self) -> Vec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in self.p {
            b.grow(p);
        }
        b
    }

    /// Closest hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let (t, bary) = WoopRay::new(ray).hit(self.p[0], self.p[1], self.p[2], t_min, t_max)?;
        Some(surface(
            t,
            bary,
            self.p,
            self.normal(),
            self.n.as_ref(),
            self.uv.as_ref(),
        ))
    }
}

/// Builds the hit record from barycentrics: interpolated shading normal and uv.
#[inline]
pub(crate) fn surface(
    t: Real,
    b: [Real; 3],
    v: [Vec3; 3],
    n_geo: Vec3,
    n: Option<&[Vec3; 3]>,
    uv: Option<&[Vec2; 3]>,
) -> Hit {
    // The point from barycentrics, with pbrt's bound γ(7)·Σ|bᵢ·pᵢ|.
    let (q0, q1, q2) = (v[0] * b[0], v[1] * b[1], v[2] * b[2]);
    let p = q0 + q1 + q2;
    let err = (q0.abs() + q1.abs() + q2.abs()) * gamma(7);
    let n_shade = match n {
        Some(n) => {
            let s = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
            if s.length_squared() > 0.0 {
                s
            } else {
                n_geo
            }
        }
        None => n_geo,
    };
    let uv = match uv {
        Some(uv) => uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2],
        None => Vec2::new(b[1], b[2]),
    };
    Hit::new(t, p, err, n_geo, n_shade, uv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic numbers for the tests' random triangles: the sampler's hash of a
    /// running count.
    struct Rng(u64);
    impl Rng {
        fn f(&mut self) -> Real {
            self.0 += 1;
            crate::sampler::uniform(0x7e57, self.0, 0) as Real
        }
        fn range(&mut self, lo: Real, hi: Real) -> Real {
            lo + (hi - lo) * self.f()
        }
    }

    /// What `hit4` promises to be: the scalar test on each lane in order, keeping a
    /// strictly closer hit (the lowest lane on a tie).
    fn scalar_loop(
        wr: &WoopRay,
        tris: &[[Vec3; 3]],
        t_min: Real,
        t_max: Real,
    ) -> Option<(usize, Real, [Real; 3])> {
        let mut best: Option<(usize, Real, [Real; 3])> = None;
        for (lane, [p0, p1, p2]) in tris.iter().enumerate() {
            if let Some((t, b)) = wr.hit(*p0, *p1, *p2, t_min, t_max) {
                if best.is_none_or(|(_, tb, _)| t < tb) {
                    best = Some((lane, t, b));
                }
            }
        }
        best
    }

    /// `hit4` gives the scalar loop's answer bit for bit (lane, t and barycentrics) for
    /// one to four lanes, on rays through the inside of triangles and on rays exactly
    /// through an edge, where one edge function is exactly 0 in the render precision and
    /// the scalar test recomputes all three in f64 (so the other two, and the
    /// barycentrics, can differ in their last bits from the render-precision values). A
    /// lane with any one edge function exactly 0 must take that fallback, not only a lane
    /// with all three 0. Every third pack repeats a triangle in its last lane: a tie at
    /// the same `t`, which the lower lane must win, as in the loop.
    #[test]
    fn hit4_is_the_scalar_loop_bit_for_bit() {
        let mut rng = Rng(42);
        let (mut hits, mut edge_hits, mut differs, mut ties_won) = (0, 0, 0, 0);
        for case in 0..6000 {
            let lanes = 1 + case % 4;
            // A ray along +z from above the origin: the shear is the identity, and a
            // vertex's coordinates relative to the ray are exact.
            let ray = Ray::new(
                Vec3::new(0.0, 0.0, -3.0),
                Vec3::new(0.0, 0.0, rng.range(0.5, 2.0)),
            );
            let wr = WoopRay::new(&ray);
            let on_edge = case % 2 == 0;
            let mut tris = Vec::new();
            for _ in 0..lanes {
                let mut z = || rng.range(-1.0, 1.0);
                let (z0, z1, z2) = (z(), z(), z());
                let (ax, ay) = (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
                let (cx, cy) = (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
                let tri = if on_edge {
                    // The edge p0 p1 passes exactly through the ray: p1 = −p0/2 (exact),
                    // so its edge function b.x·a.y − b.y·a.x is exactly 0, while the other
                    // two have two non-zero products each.
                    let mut tri = [
                        Vec3::new(ax, ay, z0),
                        Vec3::new(-0.5 * ax, -0.5 * ay, z1),
                        Vec3::new(cx, cy, z2),
                    ];
                    // The zero edge function is then w, u or v.
                    tri.rotate_left(case / 2 % 3);
                    tri
                } else {
                    let (bx, by) = (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
                    [
                        Vec3::new(ax, ay, z0),
                        Vec3::new(bx, by, z1),
                        Vec3::new(cx, cy, z2),
                    ]
                };
                tris.push(tri);
            }
            // Every third case has two lanes with the same triangle, the second its last
            // and the first any other: a tie, which the lower lane wins.
            let tie = (case % 3 == 0 && lanes > 1).then(|| case / 12 % (lanes - 1));
            if let Some(k) = tie {
                tris[lanes - 1] = tris[k];
            }
            let pack = TriPack::new(&tris, [u32::MAX; 4]);
            for (t_min, t_max) in [(0.0, Real::INFINITY), (2.5, 3.5)] {
                let want = scalar_loop(&wr, &tris, t_min, t_max);
                let got = wr.hit4(&pack, lanes, t_min, t_max);
                let bits = |h: Option<(usize, Real, [Real; 3])>| {
                    h.map(|(l, t, b)| (l, t.to_bits(), b.map(Real::to_bits)))
                };
                assert_eq!(
                    bits(got),
                    bits(want),
                    "case {case}, {lanes} lanes, t in ({t_min}, {t_max}): hit4 {got:?}, the \
                     scalar loop {want:?} (renderer/src/shapes/triangle.rs, WoopRay::hit4)"
                );
                // Any hit: some lane's hit exactly when hit4 finds one, with that lane's t.
                let any = wr.hit4_any(&pack, lanes, t_min, t_max);
                let lane_ts: Vec<_> = tris[..lanes]
                    .iter()
                    .filter_map(|[p0, p1, p2]| wr.hit(*p0, *p1, *p2, t_min, t_max))
                    .map(|(t, _)| t.to_bits())
                    .collect();
                assert!(
                    any.is_some() == want.is_some()
                        && any.is_none_or(|t| lane_ts.contains(&t.to_bits())),
                    "case {case}, {lanes} lanes, t in ({t_min}, {t_max}): hit4_any {any:?}, the \
                     lanes' hits at {lane_ts:?} (renderer/src/shapes/triangle.rs, \
                     WoopRay::hit4_any)"
                );
                hits += usize::from(want.is_some());
                ties_won += usize::from(tie.is_some() && want.map(|w| w.0) == tie);
                edge_hits += usize::from(on_edge && want.is_some());
                // How often the render-precision edge functions would have given other
                // barycentrics than the f64 fallback (what the fallback is for).
                if let (true, Some((lane, _, b))) = (on_edge, want) {
                    let [p0, p1, p2] = tris[lane];
                    let (a, bb, c) = (p0 - ray.o, p1 - ray.o, p2 - ray.o);
                    let u = c.x * bb.y - c.y * bb.x;
                    let v = a.x * c.y - a.y * c.x;
                    let w = bb.x * a.y - bb.y * a.x;
                    let inv = 1.0 / (u + v + w);
                    differs += usize::from([u * inv, v * inv, w * inv] != b);
                }
            }
        }
        // Worth something only if both kinds of ray hit often, and (in f32, where the
        // fallback is more precise than the render precision) if the fallback changes bits.
        let needed = if crate::real::PRECISION == "f32" {
            100
        } else {
            0
        };
        assert!(
            hits > 2000 && edge_hits > 1000 && differs >= needed && ties_won > 100,
            "{hits} hits, {edge_hits} on edges, {differs} where the fallback changes bits, \
             {ties_won} won by the lower of two tied lanes"
        );
    }
}
