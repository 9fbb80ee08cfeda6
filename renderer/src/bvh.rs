//! A bounding volume hierarchy: built by binned SAH (Wald 2007) as a binary tree, then
//! collapsed into a `W`-wide tree, 4 or 8 (each node holds the boxes of up to `W` children
//! side by side, so one SIMD slab test covers them all: 4 lanes of SSE, or 8 of AVX). Nodes live in a flat array, 64-byte
//! aligned, and traversal uses a fixed-size stack: it never allocates.
//!
//! The BVH knows nothing about what it bounds. It is built from a list of boxes and its
//! traversal calls a closure with primitive indices, so one implementation serves the
//! instance level and every mesh. The owner stores its primitives in leaf order
//! ([`Bvh::build`] returns them so), and a leaf names a run of consecutive slots.

use crate::aabb::Aabb;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec3};
use arrayvec::ArrayVec;

/// Bins per axis of the binned SAH for a set of fewer than [`WIDE_FROM`] primitives.
const BINS: usize = 16;
/// Bins per axis for a set of [`WIDE_FROM`] primitives or more: the splits near the root,
/// which every ray pays for, chosen among twice as many candidates. On the peers bench's
/// 1M-triangle mesh, one thread, against 16 bins everywhere (two alternating pairs each):
/// closest hit 1.01-1.04x on coherent rays, 1.04x on shuffled, 1.02-1.11x on shadow and
/// 1.04-1.06x on bounce rays, for a build 4-9 % longer. (32 bins everywhere gained the same
/// and built 21 % longer, the sweeps over the bins of the many small sets; 64 bins from
/// 8,192 primitives gained nothing more.)
const WIDE_BINS: usize = 32;
/// Smallest set binned with [`WIDE_BINS`].
const WIDE_FROM: usize = 1024;
const _: () = assert!(WIDE_BINS % BINS == 0 && (WIDE_BINS / BINS).is_power_of_two());
const MAX_LEAF: usize = 4;
/// Depth past which the SAH stops splitting; keeps the traversal stack bounded.
const MAX_DEPTH: usize = 60;
/// Most primitives one leaf can name (counts are bytes). A bigger set that the SAH cannot
/// split (coincident centroids, or the depth limit) is cut in halves by index instead,
/// which adds at most 24 levels below `MAX_DEPTH` for any `u32` count.
const LEAF_LIMIT: usize = u8::MAX as usize;
/// Widest node the traversal stacks are sized for.
const MAX_WIDTH: usize = 8;
/// Traversal stack for the deepest tree the build can make: a node pushes at most `W − 1`
/// children, once per level, the root's level included.
const LONG_STACK: usize = (MAX_WIDTH - 1) * (MAX_DEPTH + 27);
/// Traversal stack for 8-wide trees of up to 9 levels (depth 8: a mesh of a million
/// triangles in a good tree), or 4-wide ones of up to 21: a smaller array is cheaper to
/// set up for every ray.
const SHORT_STACK: usize = 64;
/// Traversal stack for 8-wide trees of up to 4 levels (a few thousand primitives), or
/// 4-wide ones of up to 10: set up for every ray, so small pays.
const TINY_STACK: usize = 31;

/// A node of the binary tree the SAH builds. Interior nodes (`count == 0`) have children
/// at `first` and `first + 1`; leaves name the slots `first..first + count`.
#[derive(Clone, Copy, Debug)]
struct Node2 {
    bounds: Aabb,
    first: u32,
    count: u32,
}

/// A node of the `W`-wide tree: the boxes of up to `W` children side by side, one array
/// of `W` lanes per axis and side, so that one SIMD slab test covers them all. Per child
/// the node holds either an interior node index (`count == 0`) or a leaf's first slot and
/// count.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
struct Node<const W: usize> {
    /// Per axis `a`, `b[2a]` holds the children's low sides and `b[2a + 1]` their high
    /// sides.
    b: [[Real; W]; 6],
    child: [u32; W],
    count: [u8; W],
    lanes: u8,
    /// Bit `k` set when lane `k` is a leaf (`count[k] > 0`).
    leaves: u8,
}

impl<const W: usize> Node<W> {
    /// A node with no lanes. Every lane's box is empty (low sides +∞, high sides −∞),
    /// and [`Node::set_boxes`] leaves the lanes past the children so: the slab test finds
    /// such a lane's entry at +∞ and its exit at −∞ for any ray (the near side's product
    /// is +∞ and the far side's −∞ whatever the direction's sign, ±0 included), so it
    /// never reports it, with no mask of the lanes in use (which sits on the node's last
    /// cache line).
    const EMPTY: Node<W> = Node {
        b: [
            [Real::INFINITY; W],
            [Real::NEG_INFINITY; W],
            [Real::INFINITY; W],
            [Real::NEG_INFINITY; W],
            [Real::INFINITY; W],
            [Real::NEG_INFINITY; W],
        ],
        child: [0; W],
        count: [0; W],
        lanes: 0,
        leaves: 0,
    };

    /// The slab test of [`Aabb::hit`] on the `W` child boxes at once: each lane's entry
    /// distance, and a bit mask of the lanes whose box the ray overlaps within
    /// `[t_min, t_max]`. The ray's planes are chosen by the sign of its direction (the
    /// near plane of a slab is its low side when the direction is positive). A product
    /// `(plane − o)·(1/d)` is NaN only when `d` is ±0 on that axis and the origin lies on
    /// the plane; such a slab does not constrain the ray, as there: the running bounds
    /// take a product only when it is beyond them (`t0 > near`, `t1 < far`), which a NaN
    /// never is. (That is also the operand order of the processor's `max`/`min`, so the
    /// SIMD test of [`slab`] needs no branch.) The far distance is inflated by
    /// `1 + 2γ(3)`, as there.
    #[inline(always)]
    fn hit(&self, w: &Walk) -> ([Real; W], u32) {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        if W == 4 || (W == 8 && cfg!(target_feature = "avx")) {
            let mut near = [w.t_min; W];
            // SAFETY: the node's boxes are `6 × W` contiguous `f32` (`Real` is `f32`
            // here) and `near` holds `W`; `slab` reads and writes `W` lanes exactly, and
            // it needs AVX only when `W == 8`, which is then enabled at compile time.
            let mask = unsafe { slab::<W>(self.b.as_ptr().cast(), w, near.as_mut_ptr()) };
            return (near, mask);
        }
        self.hit_lanes(w)
    }

    /// [`Node::hit`] as a loop over the lanes: what the SIMD test computes, operation for
    /// operation (and what the f64 build, a build without AVX and other architectures
    /// run; LLVM does not vectorize it well, hence [`slab`]).
    #[inline(always)]
    fn hit_lanes(&self, w: &Walk) -> ([Real; W], u32) {
        let mut near = [w.t_min; W];
        let mut far = [w.t_max; W];
        for a in 0..3 {
            let (n, f) = (&self.b[w.near[a]], &self.b[w.near[a] ^ 1]);
            let (o, inv) = (w.o[a], w.inv_d[a]);
            for k in 0..W {
                let t0 = (n[k] - o) * inv;
                let t1 = (f[k] - o) * inv;
                near[k] = if t0 > near[k] { t0 } else { near[k] };
                far[k] = if t1 < far[k] { t1 } else { far[k] };
            }
        }
        let grow = 1.0 + 2.0 * gamma(3);
        let mut mask = 0u32;
        for k in 0..W {
            mask |= ((near[k] <= far[k] * grow) as u32) << k;
        }
        (near, mask)
    }

    /// Stores the children's boxes (in lane order); the lanes past them get empty boxes.
    fn set_boxes(&mut self, boxes: &[Aabb]) {
        self.lanes = boxes.len() as u8;
        self.b = Node::<W>::EMPTY.b;
        for (k, b) in boxes.iter().enumerate() {
            for a in 0..3 {
                self.b[2 * a][k] = b.min[a];
                self.b[2 * a + 1][k] = b.max[a];
            }
        }
    }
}

/// [`Node::hit`]'s slab test in SIMD registers, for 4 lanes (SSE) or 8 (AVX): the same
/// operations on the same values as its lane loop, so the same bits. `b` points at the
/// node's `6 × W` box planes and `near` receives the `W` entry distances; returns the
/// overlap mask of all `W` lanes. `maxps(t0, near)` is `t0 > near ? t0 : near` and
/// `minps(t1, far)` is `t1 < far ? t1 : far`, which is how a NaN product is ignored.
///
/// # Safety
/// `b` must be valid for reading `6 × W` floats and `near` for writing `W`; `W` must be
/// 4, or 8 with AVX enabled.
#[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
#[inline(always)]
unsafe fn slab<const W: usize>(b: *const f32, w: &Walk, near: *mut f32) -> u32 {
    use std::arch::x86_64::*;
    // The test, written once for both register widths (`$l` lanes).
    macro_rules! lanes {
        ($l:literal, $set1:ident, $load:ident, $store:ident, $sub:ident, $mul:ident,
         $max:ident, $min:ident, $le:expr, $movemask:ident) => {{
            let mut n = $set1(w.t_min);
            let mut f = $set1(w.t_max);
            for a in 0..3 {
                let (o, inv) = ($set1(w.o[a]), $set1(w.inv_d[a]));
                let lo = $load(b.add($l * w.near[a]));
                let hi = $load(b.add($l * (w.near[a] ^ 1)));
                n = $max($mul($sub(lo, o), inv), n);
                f = $min($mul($sub(hi, o), inv), f);
            }
            $store(near, n);
            $movemask($le(n, $mul(f, $set1(1.0 + 2.0 * gamma(3))))) as u32
        }};
    }
    if W == 8 {
        #[cfg(target_feature = "avx")]
        // SAFETY: as the function's contract says; AVX is enabled at compile time.
        return unsafe {
            lanes!(
                8,
                _mm256_set1_ps,
                _mm256_loadu_ps,
                _mm256_storeu_ps,
                _mm256_sub_ps,
                _mm256_mul_ps,
                _mm256_max_ps,
                _mm256_min_ps,
                _mm256_cmp_ps::<_CMP_LE_OQ>,
                _mm256_movemask_ps
            )
        };
        #[cfg(not(target_feature = "avx"))]
        unreachable!("8-wide slabs need AVX");
    }
    assert!(W == 4, "4- or 8-wide nodes only");
    // SAFETY: as the function's contract says (`W == 4`); SSE is part of x86_64.
    unsafe {
        lanes!(
            4,
            _mm_set1_ps,
            _mm_loadu_ps,
            _mm_storeu_ps,
            _mm_sub_ps,
            _mm_mul_ps,
            _mm_max_ps,
            _mm_min_ps,
            _mm_cmple_ps,
            _mm_movemask_ps
        )
    }
}

/// A child waiting on the traversal stack, with its entry distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u8,
    near: Real,
}

/// A BVH over primitives given by their boxes, with nodes `W` wide (4 or 8).
#[derive(Clone, Debug)]
pub struct Bvh<const W: usize = 8> {
    /// The root is `nodes[0]`; empty when there are no primitives.
    nodes: Vec<Node<W>>,
    bounds: Aabb,
    /// Most stack entries a traversal can need: `W − 1` per level, the root's included
    /// (a walk holds the unvisited siblings of every node on its path).
    stack_need: usize,
}

impl<const W: usize> Default for Bvh<W> {
    fn default() -> Self {
        Bvh {
            nodes: Vec::new(),
            bounds: Aabb::default(),
            stack_need: 0,
        }
    }
}

/// What the traversal closure says about a primitive.
pub enum Visit {
    /// No hit (or a hit no closer than the current bound).
    Miss,
    /// A hit at this distance: the search interval shrinks to it.
    Hit(Real),
}

impl<const W: usize> Bvh<W> {
    /// Builds a BVH over `items`, whose boxes (all finite) are `boxes`, and returns it with
    /// the items permuted into leaf order: a leaf's primitives then sit side by side in
    /// memory, and traversal reads them with no index array in between.
    /// `traversal_cost` is the cost of one binary node visit in units of one primitive
    /// test, for the SAH.
    pub fn build<T>(items: Vec<T>, boxes: &[Aabb], traversal_cost: Real) -> (Bvh<W>, Vec<T>) {
        Bvh::build_with::<T, 1>(items, boxes, traversal_cost, false)
    }

    /// [`Bvh::build`] that may also spread a set of at most `W` primitives over one node,
    /// a leaf of one per lane, when the SAH finds that cheaper than a leaf of them all:
    /// the node's box test then spares a ray the primitives whose boxes it misses. The
    /// binary SAH cannot see that gain when the boxes are thin and far apart, as the walls
    /// of a room are (any two of them span the whole room, so every binary split looks as
    /// dear as the leaf). For instances, whose tests (a ray transform and a shape) cost far
    /// more than a lane of a node's test; a mesh's packs of four triangles are tested
    /// together and use [`Bvh::build_aligned`].
    pub fn build_spread<T>(
        items: Vec<T>,
        boxes: &[Aabb],
        traversal_cost: Real,
    ) -> (Bvh<W>, Vec<T>) {
        Bvh::build_with::<T, 1>(items, boxes, traversal_cost, true)
    }

    fn build_with<T, const B: usize>(
        items: Vec<T>,
        boxes: &[Aabb],
        traversal_cost: Real,
        spread: bool,
    ) -> (Bvh<W>, Vec<T>) {
        const {
            assert!(
                W == 4 || W == MAX_WIDTH,
                "nodes are 4 or 8 wide (bvh::slab)"
            )
        };
        assert_eq!(items.len(), boxes.len(), "one box per item");
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let bvh = if boxes.is_empty() {
            Bvh::default()
        } else {
            let binary = build_binary::<B>(
                &mut order,
                boxes,
                traversal_cost,
                if spread { W } else { 0 },
            );
            let (nodes, depth) = collapse::<W>(&binary);
            Bvh {
                nodes: crate::pages::on_huge_pages(nodes),
                bounds: binary[0].bounds,
                stack_need: (W - 1) * (depth + 1),
            }
        };
        let mut slots: Vec<Option<T>> = items.into_iter().map(Some).collect();
        let ordered = order
            .iter()
            .map(|&i| {
                slots[i as usize]
                    .take()
                    .expect("the BVH references each primitive once")
            })
            .collect();
        (bvh, ordered)
    }

    /// [`Bvh::build`] with every leaf starting at a slot that is a multiple of `ALIGN`:
    /// the leaf-ordered items come back with `None` in the padding slots, and a leaf still
    /// counts only its items. An owner that packs `ALIGN` primitives per SIMD record can
    /// then test a leaf as whole records.
    ///
    /// The SAH prices what such an owner pays: a leaf costs its number of records
    /// (`count.div_ceil(ALIGN)`, in the binned splits' sums too), and `traversal_cost` is
    /// in units of one record's test; a leaf may hold two records. Priced by primitives
    /// instead, the SAH split four triangles into leaves of one to three: the 1M-triangle
    /// benchmark mesh filled its packs of four to 43 % (579,426 packs, 180,224 nodes);
    /// priced by records, to 95 % (264,627 packs, 64,467 nodes), and one thread traced
    /// closest hits 1.17–1.36× faster (any hit: 1.33–1.36× on shadow and bounce rays, no
    /// change on primary rays; renderer/docs/performance.md).
    pub fn build_aligned<T, const ALIGN: usize>(
        items: Vec<T>,
        boxes: &[Aabb],
        traversal_cost: Real,
    ) -> (Bvh<W>, Vec<Option<T>>) {
        const { assert!(ALIGN > 0, "records of at least one primitive") };
        let (mut bvh, ordered) = Bvh::build_with::<T, ALIGN>(items, boxes, traversal_cost, false);
        // Every leaf lane, in slot order (leaves cover the slots once, side by side).
        let mut leaves: Vec<(u32, usize, usize)> = Vec::new();
        for (n, node) in bvh.nodes.iter().enumerate() {
            for lane in 0..node.lanes as usize {
                if node.count[lane] > 0 {
                    leaves.push((node.child[lane], n, lane));
                }
            }
        }
        leaves.sort_unstable();
        let mut ordered = ordered.into_iter();
        let mut out: Vec<Option<T>> = Vec::with_capacity(boxes.len() + ALIGN * leaves.len());
        for (_, n, lane) in leaves {
            let count = bvh.nodes[n].count[lane] as usize;
            bvh.nodes[n].child[lane] = out.len() as u32;
            out.extend(ordered.by_ref().take(count).map(Some));
            out.resize_with(out.len().next_multiple_of(ALIGN), || None);
        }
        (bvh, out)
    }

    /// The tree's only leaf, when it is a single one: then traversal visits the leaf
    /// directly, with no walk and no stack, after testing the tree's bounds (which
    /// [`Bvh::traverse`] skips for a leaf of one primitive).
    #[inline]
    fn single_leaf(&self) -> Option<(u32, u8)> {
        let root = &self.nodes[0];
        (self.nodes.len() == 1 && root.lanes == 1 && root.count[0] > 0)
            .then(|| (root.child[0], root.count[0]))
    }

    /// Bounds of everything.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Number of `W`-wide nodes, for statistics.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Visits, nearest box first, every primitive whose box the ray overlaps within
    /// `(t_min, t_max)` (a tree of one primitive visits it without testing its box).
    /// `visit(i, t_max)` tests primitive `i` and reports a hit, which shrinks `t_max`.
    /// With `any`, traversal stops at the first hit. Returns whether anything was hit.
    #[inline]
    pub fn traverse<F>(&self, ray: &Ray, t_min: Real, t_max: Real, any: bool, mut visit: F) -> bool
    where
        F: FnMut(u32, Real) -> Visit,
    {
        let mut leaves = each(any, &mut visit);
        // A tree of one node (a scene of up to `W` instances): its leaves in the walk's
        // order, without the walk's stack. Only here, for instances: in the walk itself
        // (which meshes use too) the test made the 1M-triangle mesh's walks slower (any
        // hit on coherent rays about 0.85×), where it is never taken.
        if self.nodes.len() == 1 {
            return match self.single_leaf() {
                // One primitive alone (a scene of one mesh or one definition, which
                // test their own root first; or of one shape, whose own test costs
                // about what a box test does): visited without the tree's box test,
                // which would only repeat it (in a one-mesh scene, 12 instructions a ray
                // for the closest hit, 43 for any hit). Without a box test a search can
                // only find more, never less; all 122 catalog scenes gave the same bits.
                Some((first, 1)) => matches!(leaves(first, 1, t_max), Visit::Hit(_)),
                // A leaf of several: its box test, then the leaf. (The walk below, spelled
                // out here: falling through to it instead cost the count gate's frames
                // 0.4 to 0.8 % instructions, the compiler's layout.)
                Some(_) => self.traverse_leaves(ray, t_min, t_max, any, leaves),
                None => {
                    Walk::new(ray, t_min, t_max, !any).root_only(&self.nodes[0], any, &mut leaves)
                }
            };
        }
        self.traverse_leaves(ray, t_min, t_max, any, leaves)
    }

    /// [`Bvh::traverse`] a leaf at a time: `visit(first, count, t_max)` tests the
    /// primitives in slots `first..first + count` together and reports the closest hit
    /// among them (with `any`, any hit), which shrinks `t_max`.
    #[inline]
    pub fn traverse_leaves<F>(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        any: bool,
        visit: F,
    ) -> bool
    where
        F: FnMut(u32, u8, Real) -> Visit,
    {
        self.walk_one::<false, F>(ray, t_min, t_max, any, visit, &|_, _| {})
    }

    /// [`Bvh::traverse_leaves`] for a tree larger than the cache: as soon as a node's
    /// slab test tells which children the ray overlaps, it asks for the memory of all of
    /// them (a prefetch: the child nodes, or the records of the leaves, which start at
    /// `leaf_at(first)`), so their cache misses overlap each other and the work on
    /// the nearest child, instead of following one another. The walk, and so every
    /// result, is the same. A search for any hit starts asking only once a leaf has failed
    /// to end it (`Walk::eager`).
    #[inline]
    pub fn traverse_leaves_prefetching<F, L>(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        any: bool,
        visit: F,
        leaf_at: L,
    ) -> bool
    where
        F: FnMut(u32, u8, Real) -> Visit,
        L: Fn(u32) -> *const u8,
    {
        self.walk_one::<true, F>(ray, t_min, t_max, any, visit, &self.ahead(leaf_at))
    }

    /// The prefetch of a child: [`AHEAD_LINES`] cache lines from its node, or from its
    /// leaf's first record, `leaf_at(first)`. The address is chosen by a select, not a
    /// branch (whether the next child is a node or a leaf follows no pattern a predictor
    /// learns), and the lines are as many whatever it is.
    #[inline(always)]
    fn ahead<'a>(&'a self, leaf_at: impl Fn(u32) -> *const u8 + 'a) -> impl Fn(u32, u8) + 'a {
        let nodes = self.nodes.as_ptr();
        move |child: u32, count: u8| {
            let node = nodes.wrapping_add(child as usize).cast::<u8>();
            let leaf = leaf_at(child);
            prefetch_lines(if count == 0 { node } else { leaf });
        }
    }

    /// The single-ray walk; `ahead` is given every overlapped child (with `ALL`) or the
    /// next child to take.
    #[inline(always)]
    fn walk_one<const ALL: bool, F>(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        any: bool,
        mut visit: F,
        ahead: &impl Fn(u32, u8),
    ) -> bool
    where
        F: FnMut(u32, u8, Real) -> Visit,
    {
        if self.nodes.is_empty() {
            return false;
        }
        if let Some((first, count)) = self.single_leaf() {
            // The leaf's box (the tree's bounds) still rejects the rays that miss it, as
            // cheaply as the root's slab test would, without a walk or a stack.
            if self
                .bounds
                .hit(ray.o, Vec3::ONE / ray.d, t_min, t_max)
                .is_none()
            {
                return false;
            }
            return matches!(visit(first, count, t_max), Visit::Hit(_));
        }
        let mut w = Walk::new(ray, t_min, t_max, !any);
        if self.stack_need <= TINY_STACK {
            let mut stack = ArrayVec::<Entry, TINY_STACK>::new();
            while w.step::<_, _, _, ALL>(&mut stack, &self.nodes, any, &mut visit, ahead) {}
        } else if self.stack_need <= SHORT_STACK {
            let mut stack = ArrayVec::<Entry, SHORT_STACK>::new();
            while w.step::<_, _, _, ALL>(&mut stack, &self.nodes, any, &mut visit, ahead) {}
        } else {
            let mut stack = ArrayVec::<Entry, LONG_STACK>::new();
            while w.step::<_, _, _, ALL>(&mut stack, &self.nodes, any, &mut visit, ahead) {}
        }
        w.hit
    }

    /// [`Bvh::traverse`] (closest hit) for up to [`BATCH`] rays at once. The rays are
    /// walked in turn, one step each, and every step asks for the memory of the ray's
    /// next step ahead of time (a prefetch: the next node, or the records of the next leaf,
    /// which start at `leaf_at(first)`). While one ray waits on
    /// memory the others work, so a tree much larger than the cache costs fewer stalls.
    /// Each ray takes exactly the steps it would take alone, so every result is the same
    /// as from [`Bvh::traverse`]. `visit(r, i, t_max)` tests primitive `i` against
    /// `rays[r]`.
    #[inline]
    pub fn traverse_batch<F, L>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        mut visit: F,
        leaf_at: L,
    ) where
        F: FnMut(usize, u32, Real) -> Visit,
        L: Fn(u32) -> *const u8,
    {
        self.traverse_batch_leaves(
            rays,
            t_min,
            t_max,
            |r, first, count, t| each(false, &mut |i, t| visit(r, i, t))(first, count, t),
            leaf_at,
        )
    }

    /// [`Bvh::traverse_batch`] a leaf at a time, as [`Bvh::traverse_leaves`]:
    /// `visit(r, first, count, t_max)` tests a leaf against `rays[r]`.
    #[inline]
    pub fn traverse_batch_leaves<F, L>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        mut visit: F,
        leaf_at: L,
    ) where
        F: FnMut(usize, u32, u8, Real) -> Visit,
        L: Fn(u32) -> *const u8,
    {
        assert!(rays.len() <= BATCH && rays.len() == t_max.len());
        if self.nodes.is_empty() || rays.is_empty() {
            return;
        }
        if let Some((first, count)) = self.single_leaf() {
            for (r, &t) in t_max.iter().enumerate() {
                visit(r, first, count, t);
            }
            return;
        }
        let ahead = self.ahead(leaf_at);
        if self.stack_need <= TINY_STACK {
            self.walk_batch::<TINY_STACK>(rays, t_min, t_max, &mut visit, &ahead);
        } else if self.stack_need <= SHORT_STACK {
            self.walk_batch::<SHORT_STACK>(rays, t_min, t_max, &mut visit, &ahead);
        } else {
            self.walk_batch::<LONG_STACK>(rays, t_min, t_max, &mut visit, &ahead);
        }
    }

    #[inline]
    fn walk_batch<const STACK: usize>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        visit: &mut impl FnMut(usize, u32, u8, Real) -> Visit,
        ahead: &impl Fn(u32, u8),
    ) {
        // Slots past the last ray start inactive and are never stepped.
        let mut walks: [Walk; BATCH] = std::array::from_fn(|r| {
            let k = r.min(rays.len() - 1);
            Walk::new(&rays[k], t_min, t_max[k], true)
        });
        let mut stacks: [ArrayVec<Entry, STACK>; BATCH] = std::array::from_fn(|_| ArrayVec::new());
        let mut active: u64 = (1u64 << rays.len()) - 1;
        // Each round steps the active rays in order, taken from the mask's bits (a test
        // per slot mispredicts once rays finish at different steps).
        while active != 0 {
            let mut round = active;
            while round != 0 {
                let r = round.trailing_zeros() as usize;
                round &= round - 1;
                if !walks[r].step::<_, _, _, false>(
                    &mut stacks[r],
                    &self.nodes,
                    false,
                    &mut |first, count, t| visit(r, first, count, t),
                    ahead,
                ) {
                    active &= !(1u64 << r);
                }
            }
        }
    }

    /// Bytes of node memory, for statistics and for the owner's choice of
    /// [`Bvh::traverse_batch`].
    pub fn node_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
    }
}

/// A leaf visitor (for [`Bvh::traverse_leaves`]) that tests the leaf's primitives one by
/// one with `visit(i, t_max)`, in slot order, shrinking `t_max` at each hit: the closest
/// hit of the leaf, the earlier slot on a tie (or, with `any`, the first hit).
#[inline(always)]
fn each<F: FnMut(u32, Real) -> Visit>(
    any: bool,
    visit: &mut F,
) -> impl FnMut(u32, u8, Real) -> Visit + '_ {
    move |first, count, mut t_max| {
        let mut hit = false;
        for i in first..first + count as u32 {
            if let Visit::Hit(t) = visit(i, t_max) {
                hit = true;
                t_max = t;
                if any {
                    break;
                }
            }
        }
        if hit {
            Visit::Hit(t_max)
        } else {
            Visit::Miss
        }
    }
}

/// Size of a tree and the records its leaves name (in bytes) above which its owner
/// walks rays together ([`Bvh::traverse_batch`]): `Aggregate::intersect_many` counts its
/// nodes and leads, `Mesh::intersect_batch` its nodes and triangle packs. Below it the tree stays in the L2 cache (1 MiB per core on the
/// development machine), and one ray at a time is faster: at 10⁴ spheres (0.5 MB)
/// interleaving took 3.87 ms against 3.71 ms, at 10⁵ (5.4 MB) 4.67 ms against 7.11 ms.
pub const INTERLEAVE_ABOVE: usize = 1 << 20;

/// Rays [`Bvh::traverse_batch`] walks together. Measured on the 10⁶-sphere benchmark
/// scene (renderer/docs/performance.md): 4 rays took 6.1 ms, 8 took 5.7 ms and 16 took
/// 5.0 ms, against 10.1 ms one ray at a time, in one run.
pub const BATCH: usize = 16;

/// Cache lines a prefetch of a child asks for: a node is four (256 bytes at 8 lanes), a
/// mesh leaf of two packs five or six (288 bytes at a multiple of 16: six when the first
/// pack starts 48 bytes into a line, and then the sixth, the second pack's last 16
/// bytes, is not asked for), of one pack three, and the instance records of a leaf (32
/// bytes each) one or two. As many whatever the child is, so that the walk does not
/// branch on it (`Bvh::ahead`).
const AHEAD_LINES: usize = 5;

/// Asks the processor to start loading the [`AHEAD_LINES`] cache lines from the one that
/// holds `p`, without waiting for them. A hint only: it changes no value, only when memory
/// arrives, and it cannot fault, so `p` need not be a valid address.
#[inline(always)]
fn prefetch_lines(p: *const u8) {
    for line in 0..AHEAD_LINES {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `_mm_prefetch` reads nothing into the program and cannot fault (it is
        // a hint, ignored for an invalid address); the address is computed with
        // `wrapping_add`. SSE, which it needs, is part of the x86_64 baseline.
        unsafe {
            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                p.wrapping_add(64 * line).cast(),
            );
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (p, line);
    }
}

/// One ray's traversal state, apart from its stack.
#[derive(Clone, Copy)]
struct Walk {
    o: [Real; 3],
    inv_d: [Real; 3],
    /// Per axis `a`, the index in [`Node::b`] of the slab's near side: `2a` (low) when the
    /// direction is positive, `2a + 1` (high) when negative (its sign bit: −0 counts).
    near: [usize; 3],
    t_min: Real,
    t_max: Real,
    /// The child to take next: an interior node (`count == 0`) or a leaf's slots.
    child: u32,
    count: u8,
    hit: bool,
    /// Whether a prefetching walk (`ALL`) asks for every overlapped child yet. A search
    /// for the closest hit does from the start; a search for any hit only once a leaf has
    /// failed to end it: when the first leaf tested (leaves go first, and a large
    /// occluder such as a ground quad sits near the root) ends the search, as it does for
    /// most rays aimed at such a surface, prefetches would be wasted.
    eager: bool,
}

/// Each lane's rank among the lanes of `mask` ordered by ascending key, ties in lane
/// order (what [`sorted_lanes`] computes, as positions): lane `i`'s rank counts the lanes
/// `j` of `mask` with `key[j] < key[i]`, or `key[j] == key[i]` and `j < i`; and the mask
/// of lanes of rank 0; and the mask of lanes whose key is NaN. Lanes outside `mask` take
/// NaN keys, which no comparison counts (their own ranks are meaningless). When no key
/// of `mask` is NaN, its lanes' ranks are `0..k` for its `k` lanes, one each: by key,
/// then by lane, is a strict total order on them. Eight broadcasts of a key and three
/// compares each, with no branch.
///
/// # Safety
/// `key` must be valid for reading 8 `f32`, and AVX2 available.
#[cfg(all(target_arch = "x86_64", not(feature = "f64"), target_feature = "avx2"))]
#[inline(always)]
unsafe fn ranks8(key: *const f32, mask: u32) -> ([u32; 8], u32, u32) {
    use std::arch::x86_64::*;
    // SAFETY: as the function's contract says.
    unsafe {
        let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let active = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask as i32), bit), bit);
        let given = _mm256_loadu_ps(key);
        let nan = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_UNORD_Q>(given, given)) as u32;
        let k = _mm256_blendv_ps(_mm256_set1_ps(f32::NAN), given, _mm256_castsi256_ps(active));
        let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mut rank = _mm256_setzero_si256();
        for j in 0..8 {
            let kj = _mm256_permutevar8x32_ps(k, _mm256_set1_epi32(j));
            let less = _mm256_cmp_ps::<_CMP_LT_OQ>(kj, k);
            let tie = _mm256_cmp_ps::<_CMP_EQ_OQ>(kj, k);
            let later = _mm256_castsi256_ps(_mm256_cmpgt_epi32(lane, _mm256_set1_epi32(j)));
            let before = _mm256_or_ps(less, _mm256_and_ps(tie, later));
            // A true comparison is all ones: −1 as an integer.
            rank = _mm256_sub_epi32(rank, _mm256_castps_si256(before));
        }
        let first = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
            rank,
            _mm256_setzero_si256(),
        ))) as u32;
        let mut out = [0u32; 8];
        _mm256_storeu_si256(out.as_mut_ptr().cast(), rank);
        (out, first, nan)
    }
}

/// The lanes whose bits are set in `mask`, lowest first.
#[inline(always)]
fn lanes_of(mask: u32) -> impl Iterator<Item = usize> {
    let mut m = mask;
    std::iter::from_fn(move || {
        (m != 0).then(|| {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            lane
        })
    })
}

/// The lanes of `mask` by ascending `key`, ties in lane order (an insertion sort, stable),
/// and how many there are.
#[inline(always)]
fn sorted_lanes<const W: usize>(mask: u32, key: &[Real; W]) -> ([usize; W], usize) {
    let mut lanes = [0usize; W];
    let mut k = 0;
    for lane in lanes_of(mask) {
        let mut j = k;
        while j > 0 && key[lanes[j - 1]] > key[lane] {
            lanes[j] = lanes[j - 1];
            j -= 1;
        }
        lanes[j] = lane;
        k += 1;
    }
    (lanes, k)
}

impl Walk {
    /// [`Walk::step`]'s whole walk for a tree of one node, whose lanes are all leaves (a
    /// scene of up to `W` instances, a small mesh): the node's test, then its leaves in
    /// the order the walk takes them (the nearest first for a closest hit, ties in lane
    /// order; lane order for any hit, which takes leaves first and they all are), each
    /// after the first only while its box still reaches the shrinking interval. The
    /// same visits with the same intervals as the general walk, without its stack.
    /// (Prefetch hints are skipped: a tree of one node is in cache.)
    #[inline(always)]
    fn root_only<const W: usize, F>(&self, n: &Node<W>, any: bool, visit: &mut F) -> bool
    where
        F: FnMut(u32, u8, Real) -> Visit,
    {
        let (near, mask) = n.hit(self);
        if mask == 0 {
            return false;
        }
        // The step's keys: an any-hit search puts leaves first, and all lanes are leaves,
        // so they tie and keep lane order.
        let key = if any { [Real::NEG_INFINITY; W] } else { near };
        let (lanes, k) = sorted_lanes(mask, &key);
        let grow = 1.0 + 2.0 * gamma(3);
        let (mut t_max, mut hit) = (self.t_max, false);
        for (i, &lane) in lanes[..k].iter().enumerate() {
            if i > 0 && !(near[lane] <= t_max * grow) {
                continue;
            }
            if let Visit::Hit(t) = visit(n.child[lane], n.count[lane], t_max) {
                hit = true;
                if any {
                    return true;
                }
                t_max = t;
            }
        }
        hit
    }

    /// Pushes lane `lane` of node `n`, entered at `near`.
    #[inline(always)]
    fn push<const N: usize, const W: usize>(
        stack: &mut ArrayVec<Entry, N>,
        n: &Node<W>,
        lane: usize,
        near: Real,
    ) {
        // The stack holds `W − 1` entries per level, the root's included (`stack_need`),
        // which is what a traversal can push, so it never overflows.
        stack.push(Entry {
            child: n.child[lane],
            count: n.count[lane],
            near,
        });
    }

    /// Of the lanes of `mask` (two or more, whose keys are not NaN, as no overlapped
    /// lane's entry distance is), returns the first by ascending `key` (ties in lane
    /// order) and pushes the others, entered at `near`, so that they pop in that order.
    /// With AVX2 and 8 lanes, each lane's place in the order comes from [`ranks8`] and
    /// the lanes are written straight to their slots; elsewhere, an insertion sort
    /// ([`sorted_lanes`]). The same order either way. Only the search for the closest hit
    /// calls it. (On the peers bench's 1M-triangle mesh, one thread, four alternating
    /// pairs of `peers mesh --quick` against the inline insertion sort: closest hit
    /// 1.09x on coherent rays, 1.05-1.07x on bounce rays; the sort's data-dependent loops
    /// mispredict. Out of line, as here: inlined into the step, an earlier version of the
    /// ranks gained nothing. For any hit, whose leaves all tie at −∞, the ranks made
    /// coherent rays 0.89x; that search now does not sort, [`Walk::push_unsorted`].)
    #[inline(never)]
    fn push_sorted<const N: usize, const W: usize>(
        stack: &mut ArrayVec<Entry, N>,
        n: &Node<W>,
        mask: u32,
        key: &[Real; W],
        near: &[Real; W],
    ) -> usize {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64"), target_feature = "avx2"))]
        if W == 8 {
            // SAFETY: `key` holds `W` = 8 `f32` (`Real` is `f32` here); AVX2 is enabled
            // at compile time.
            let (rank, firsts, nan) = unsafe { ranks8(key.as_ptr().cast(), mask) };
            // An overlapped lane's entry distance is never NaN (`Node::hit`); the slots
            // below rely on it, so it is checked here, not assumed.
            assert!(nan & mask == 0, "a NaN key among the lanes to order");
            let next = (firsts & mask).trailing_zeros() as usize;
            let k = mask.count_ones() as usize;
            let base = stack.len();
            // The same bound as `Walk::push`'s (`stack_need`: `W − 1` a level), checked.
            assert!(base + k - 1 <= N, "traversal stack overflow");
            let slots = stack.as_mut_ptr();
            for lane in lanes_of(mask & !(1u32 << next)) {
                // The ranks of the lanes of `mask` are 0..k, one each (no key is NaN,
                // asserted above), and `next` has rank 0: the others land on
                // `base..base + k − 1`, each once, the farthest at the bottom.
                let slot = base + k - 1 - rank[lane] as usize;
                debug_assert!((base..base + k - 1).contains(&slot));
                // SAFETY: `base ≤ slot < base + k − 1 ≤ N`, the stack's capacity (both
                // checked above: the bound, and the keys that make the ranks 0..k).
                unsafe {
                    slots.add(slot).write(Entry {
                        child: n.child[lane],
                        count: n.count[lane],
                        near: near[lane],
                    })
                };
            }
            // SAFETY: slots `base..base + k − 1` were all written just above (`Entry` is
            // `Copy`, so nothing is dropped).
            unsafe { stack.set_len(base + k - 1) };
            return next;
        }
        Walk::push_by_sort(stack, n, mask, key, near)
    }

    /// [`Walk::push_sorted`] for exactly `K` lanes: the compare-and-swaps of a bubble sort
    /// (a swap only on a strictly smaller key, so ties keep lane order, as there), branch
    /// free. The step uses it for three lanes: of the nodes a coherent primary ray of the
    /// peers bench's 1M-triangle mesh overlaps in three lanes or more, 79 % have three,
    /// where [`Walk::push_sorted`]'s ranks cost 64 instructions a call. This cut a
    /// closest-hit ray's instructions by 4.6 %, and one thread traced coherent rays
    /// 0.98-1.03x (median 1.03x) and shuffled ones 1.03-1.04x (one slow pair 0.91x) in
    /// four alternating pairs. Used for four lanes too, it saved another 0.9 % of the
    /// instructions and no time (coherent rays 0.97-1.01x).
    #[inline(always)]
    fn push_few<const N: usize, const W: usize, const K: usize>(
        stack: &mut ArrayVec<Entry, N>,
        n: &Node<W>,
        mask: u32,
        key: &[Real; W],
        near: &[Real; W],
    ) -> usize {
        let mut lanes = lanes_of(mask);
        let mut l = [0usize; K];
        for x in &mut l {
            *x = lanes.next().unwrap_or_default();
        }
        let mut k = l.map(|lane| key[lane]);
        for pass in (1..K).rev() {
            for i in 0..pass {
                let swap = k[i + 1] < k[i];
                (l[i], l[i + 1]) = if swap {
                    (l[i + 1], l[i])
                } else {
                    (l[i], l[i + 1])
                };
                (k[i], k[i + 1]) = if swap {
                    (k[i + 1], k[i])
                } else {
                    (k[i], k[i + 1])
                };
            }
        }
        Walk::take_first(stack, n, &l, near)
    }

    /// For a search for any hit, of the lanes of `mask` (three or more): returns the
    /// first leaf in lane order (the first lane when none is a leaf) and pushes the others
    /// without ordering them by distance: the interior nodes, then the leaves, each in
    /// lane order, so that the leaves pop first (the highest lane first). A ray that
    /// nothing occludes visits every overlapped child whatever the order, and sorting them
    /// mispredicts: on the peers bench's 1M-triangle mesh, one thread, three alternating
    /// pairs against the insertion sort by entry distance (leaves first): any hit on
    /// coherent rays 1.32-1.36x, on shadow rays 1.04-1.05x (1.27x in a slow pair), on
    /// bounce rays 1.00-1.05x. (Interior nodes popping in ascending lane order instead
    /// gained nothing: 0.97-1.02x.)
    #[inline(always)]
    fn push_unsorted<const N: usize, const W: usize>(
        stack: &mut ArrayVec<Entry, N>,
        n: &Node<W>,
        mask: u32,
        near: &[Real; W],
    ) -> usize {
        let leaves = n.leaves as u32 & mask;
        let next = if leaves != 0 { leaves } else { mask }.trailing_zeros() as usize;
        let taken = !(1u32 << next);
        for m in [mask & !leaves & taken, leaves & taken] {
            for lane in lanes_of(m) {
                Walk::push(stack, n, lane, near[lane]);
            }
        }
        next
    }

    /// [`Walk::push_sorted`] by an insertion sort ([`sorted_lanes`]).
    #[inline(always)]
    fn push_by_sort<const N: usize, const W: usize>(
        stack: &mut ArrayVec<Entry, N>,
        n: &Node<W>,
        mask: u32,
        key: &[Real; W],
        near: &[Real; W],
    ) -> usize {
        let (lanes, k) = sorted_lanes(mask, key);
        Walk::take_first(stack, n, &lanes[..k], near)
    }

    /// Of `sorted` (lanes of `n` in the order to take them, at least one), returns the
    /// first and pushes the others, entered at `near`, the last first, so that they pop
    /// in that order.
    #[inline(always)]
    fn take_first<const N: usize, const W: usize>(
        stack: &mut ArrayVec<Entry, N>,
        n: &Node<W>,
        sorted: &[usize],
        near: &[Real; W],
    ) -> usize {
        for &lane in sorted[1..].iter().rev() {
            Walk::push(stack, n, lane, near[lane]);
        }
        sorted[0]
    }

    /// A walk of `ray` over `(t_min, t_max)`; `eager` as [`Walk::eager`] starts: true for
    /// a search for the closest hit, false for any hit.
    #[inline]
    fn new(ray: &Ray, t_min: Real, t_max: Real, eager: bool) -> Self {
        let inv = Vec3::ONE / ray.d;
        Walk {
            near: [
                ray.d.x.is_sign_negative() as usize,
                2 + ray.d.y.is_sign_negative() as usize,
                4 + ray.d.z.is_sign_negative() as usize,
            ],
            o: ray.o.to_array(),
            inv_d: inv.to_array(),
            t_min,
            t_max,
            child: 0,
            count: 0,
            hit: false,
            eager,
        }
    }

    /// Tests the current node or visits the current leaf, then moves to the next child
    /// to take, and passes it to `ahead` (with `ALL`, passes every child the node's test
    /// found instead). Returns false once the traversal is over.
    #[inline(always)]
    fn step<const N: usize, const W: usize, F, const ALL: bool>(
        &mut self,
        stack: &mut ArrayVec<Entry, N>,
        nodes: &[Node<W>],
        any: bool,
        visit: &mut F,
        ahead: &impl Fn(u32, u8),
    ) -> bool
    where
        F: FnMut(u32, u8, Real) -> Visit,
    {
        if self.count == 0 {
            let n = &nodes[self.child as usize];
            let (near, mask) = n.hit(self);
            if ALL && self.eager {
                for lane in lanes_of(mask) {
                    ahead(n.child[lane], n.count[lane]);
                }
            }
            if mask != 0 {
                // Take the nearest overlapped lane next and push the others, farthest
                // first, so they pop nearest first. Ties keep lane order (a stable
                // order), so the result never depends on anything else. One and two
                // lanes, the common cases, take no loop.
                //
                // A search for any hit (a shadow ray) may take the lanes in any order, and
                // takes leaves first: a leaf is one test that can end the search, where a
                // node is a descent. (Large primitives, such as a ground quad, sit in
                // leaves near the root; a shadow ray that crosses one needs nothing else.)
                // The stack keeps each lane's entry distance either way.
                // (The copy is always written: made only under `if any`, it cost the
                // sphere walk +8.6 % instructions in the count gate, as the compiler laid
                // the step out otherwise; unused, the closest-hit walk drops it.)
                let mut leaves_first = near;
                let key = if any {
                    for (k, c) in leaves_first.iter_mut().zip(n.count) {
                        if c > 0 {
                            *k = Real::NEG_INFINITY;
                        }
                    }
                    &leaves_first
                } else {
                    &near
                };
                let first = mask.trailing_zeros() as usize;
                let rest = mask & (mask - 1);
                let next = if rest == 0 {
                    first
                } else if rest & (rest - 1) == 0 {
                    let second = rest.trailing_zeros() as usize;
                    let (a, b) = if key[second] < key[first] {
                        (second, first)
                    } else {
                        (first, second)
                    };
                    Walk::push(stack, n, b, near[b]);
                    a
                } else if any {
                    Walk::push_unsorted(stack, n, mask, &near)
                } else if rest.count_ones() == 2 {
                    Walk::push_few::<N, W, 3>(stack, n, mask, key, &near)
                } else {
                    Walk::push_sorted(stack, n, mask, key, &near)
                };
                (self.child, self.count) = (n.child[next], n.count[next]);
                if !ALL {
                    ahead(self.child, self.count);
                }
                return true;
            }
        } else {
            if let Visit::Hit(t) = visit(self.child, self.count, self.t_max) {
                self.hit = true;
                if any {
                    return false;
                }
                self.t_max = t;
            } else {
                self.eager = true;
            }
        }
        // Pop the next child whose box the (possibly shrunk) interval still reaches.
        let grow = 1.0 + 2.0 * gamma(3);
        while let Some(e) = stack.pop() {
            if e.near <= self.t_max * grow {
                (self.child, self.count) = (e.child, e.count);
                if !ALL {
                    ahead(self.child, self.count);
                }
                return true;
            }
        }
        false
    }
}

/// Blocks of `B` primitives that `n` fill, the last partly: how the SAH counts a leaf's
/// primitives (`B` = 1: one by one; [`Bvh::build_aligned`]: its records). A constant, so
/// that it is a shift, or nothing, in the binned splits' inner loop.
#[inline(always)]
fn blocks<const B: usize>(n: usize) -> Real {
    n.div_ceil(B) as Real
}

/// The binary SAH tree over `order` (primitive indices, permuted in place into leaf
/// order); the root is node 0. Leaves are priced by blocks of `B` primitives ([`blocks`])
/// and hold at most `MAX_LEAF` primitives or two blocks, whichever is more (but for sets
/// cut by halves: coincident centroids, or the depth limit, up to `LEAF_LIMIT`). A set of at
/// most `spread` primitives (0: never) is split
/// down to leaves of one when one node over them all, a lane each, costs less by the SAH
/// than a leaf ([`Bvh::build_spread`]); collapsing gathers them into one node when the
/// set is where a collapse starts, and may share them out with their neighbours below.
fn build_binary<const B: usize>(
    order: &mut [u32],
    boxes: &[Aabb],
    traversal_cost: Real,
    spread: usize,
) -> Vec<Node2> {
    let centroids: Vec<Vec3> = boxes.iter().map(|b| b.centroid()).collect();
    let mut nodes = Vec::with_capacity(2 * order.len());
    nodes.push(Node2 {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    });
    // Work list of (node, start, end, depth, split down to leaves of one).
    let mut work = vec![(0usize, 0usize, order.len(), 0usize, false)];
    while let Some((node, start, end, depth, mut single)) = work.pop() {
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &i in &order[start..end] {
            bounds = bounds.union(&boxes[i as usize]);
            cbounds.grow(centroids[i as usize]);
        }
        let count = end - start;
        nodes[node] = Node2 {
            bounds,
            first: start as u32,
            count: count as u32,
        };
        let split = if count <= 1 || depth >= MAX_DEPTH {
            None
        } else {
            let set = Set {
                idx: &order[start..end],
                boxes,
                centroids: &centroids,
                cb: &cbounds,
                parent: &bounds,
                traversal_cost,
            };
            let best = if count >= WIDE_FROM {
                best_split::<B, WIDE_BINS>(&set)
            } else {
                best_split::<B, BINS>(&set)
            };
            if !single && count <= spread {
                // No tree over these primitives costs less by the SAH than one node with
                // a lane each: every tree has a node, and a primitive is tested when a
                // box that holds its own is hit. So this is against the leaf alone (on a
                // tie, the leaf: no node to walk).
                let area = bounds.area().max(Real::MIN_POSITIVE);
                let lanes: Real = order[start..end]
                    .iter()
                    .map(|&i| boxes[i as usize].area() / area)
                    .sum();
                single = traversal_cost + lanes < count as Real;
            }
            let (too_many, leaf_cost) = (count > MAX_LEAF.max(2 * B), blocks::<B>(count));
            best.filter(|&(_, _, cost)| single || too_many || cost < leaf_cost)
                .map(|(axis, split_pos, _)| {
                    // Partition in place by bin (of `WIDE_BINS`, as `best_split` gives it).
                    let slice = &mut order[start..end];
                    let mut mid = 0;
                    for k in 0..slice.len() {
                        if bin_of::<WIDE_BINS>(centroids[slice[k] as usize][axis], &cbounds, axis)
                            < split_pos
                        {
                            slice.swap(k, mid);
                            mid += 1;
                        }
                    }
                    mid
                })
                .filter(|&mid| mid > 0 && mid < count)
        };
        let mid = match split {
            Some(mid) => mid,
            None if count > LEAF_LIMIT || (single && count > 1 && depth < MAX_DEPTH) => count / 2,
            None => continue,
        };
        let left = nodes.len();
        nodes.extend([nodes[node]; 2]);
        nodes[node].first = left as u32;
        nodes[node].count = 0;
        work.push((left + 1, start + mid, end, depth + 1, single));
        work.push((left, start, start + mid, depth + 1, single));
    }
    nodes
}

/// Collapses a binary tree into a `W`-wide one with the least total surface area of its
/// wide nodes, the one part of the SAH cost a collapse can change: the leaves are the
/// binary tree's, and each is tested when its own box, in its parent's node, is hit, so
/// their part is the same however the interior is grouped, while a node is tested when
/// its parent's lane for it is hit, so each node costs its area. Dynamic programming over
/// the binary tree, after Ylitie, Karras and Laine ("Efficient incoherent ray traversal on
/// GPUs through compressed wide BVHs", 2017): [`Forests`] holds, for every binary node
/// and every k ≤ `W`, the least area of a forest of at most k roots (leaves, or wide
/// nodes with their subtrees) that covers the node's subtree. Opening the child with the
/// largest area until a node had `W` children, as this did before, left the peers bench
/// mesh's 8-wide nodes half full (65,618 nodes, 3.98 children each: a binary node over
/// two leaves became a node of two lanes); this gives 37,923 nodes of 6.15 children
/// (renderer/docs/performance.md has what that bought).
/// Interior children are stored side by side, depth first; a node's lanes follow the
/// binary tree's left-to-right order.
/// Returns the nodes and the number of levels below the root.
fn collapse<const W: usize>(bin: &[Node2]) -> (Vec<Node<W>>, usize) {
    let forests = Forests::<W>::new(bin);
    let mut out = vec![Node::EMPTY];
    let mut depth = 0;
    let mut work = vec![(0usize, 0usize, 0usize)];
    let mut kids = Vec::with_capacity(W);
    while let Some((b, o, level)) = work.pop() {
        depth = depth.max(level);
        kids.clear();
        if bin[b].count == 0 {
            forests.children(b, &mut kids);
        } else {
            kids.push(b);
        }
        let mut node = Node::EMPTY;
        let boxes: Vec<Aabb> = kids.iter().map(|&kid| bin[kid].bounds).collect();
        node.set_boxes(&boxes);
        let mut interior = Vec::new();
        for (lane, &kid) in kids.iter().enumerate() {
            let n = &bin[kid];
            if n.count == 0 {
                node.child[lane] = (out.len() + interior.len()) as u32;
                interior.push(kid);
            } else {
                node.child[lane] = n.first;
                node.count[lane] = n.count as u8;
                node.leaves |= 1 << lane;
            }
        }
        out[o] = node;
        let base = out.len();
        out.extend(std::iter::repeat_n(Node::EMPTY, interior.len()));
        for (j, &kid) in interior.iter().enumerate().rev() {
            work.push((kid, base + j, level + 1));
        }
    }
    (out, depth)
}

/// A box's surface area in `f64`, from its sides in `f64`: finite for every finite box
/// (in `f32`, sides past about 10¹⁹ overflow the products, and every node above such a
/// box would cost the same +∞, leaving [`collapse`] nothing to choose by).
fn area_f64(b: &Aabb) -> f64 {
    if b.is_empty() {
        return 0.0;
    }
    let e = |a: usize| b.max[a] as f64 - b.min[a] as f64;
    2.0 * (e(0) * e(1) + e(1) * e(2) + e(2) * e(0))
}

/// The costs of [`collapse`]'s dynamic programme: `cost[n][k - 1]`, the least total area
/// of the wide nodes of a forest of at most `k` roots that covers binary node `n`'s
/// subtree (0 for a leaf, which is a root of its own).
struct Forests<'a, const W: usize> {
    bin: &'a [Node2],
    cost: Vec<[f64; W]>,
}

impl<'a, const W: usize> Forests<'a, W> {
    fn new(bin: &'a [Node2]) -> Self {
        let mut cost = vec![[0.0; W]; bin.len()];
        // Children come after their parent in `bin` (build_binary appends them).
        for n in (0..bin.len()).rev() {
            if bin[n].count > 0 {
                continue;
            }
            let split = Self::splits(&cost, bin[n].first as usize);
            let own = area_f64(&bin[n].bounds) + split[W];
            cost[n][0] = own;
            for k in 2..=W {
                cost[n][k - 1] = own.min(split[k]);
            }
        }
        Forests { bin, cost }
    }

    /// For the children `l` and `l + 1` of a node: `[k]`, the least cost of at most `a`
    /// roots over the left and `b` over the right with `a + b = k` (k ≥ 2). That is also
    /// the least with `a + b ≤ k`: a cost never rises with the budget (a leaf's is 0 for
    /// any, and a node's is the least of its own and these, which by induction fall with
    /// k), so a larger share of the same split costs no more.
    fn splits(cost: &[[f64; W]], l: usize) -> [f64; MAX_WIDTH + 1] {
        let mut best = [f64::INFINITY; MAX_WIDTH + 1];
        for a in 1..W {
            for b in 1..=W - a {
                let c = cost[l][a - 1] + cost[l + 1][b - 1];
                if c < best[a + b] {
                    best[a + b] = c;
                }
            }
        }
        best
    }

    /// The children of a wide node at interior binary node `n`, left to right.
    fn children(&self, n: usize, out: &mut Vec<usize>) {
        self.share(self.bin[n].first as usize, W, out);
    }

    /// The roots of the cheapest forest of at most `k` over the children `l` and `l + 1`
    /// of a node (the first (a, b) in order that reaches the least cost).
    fn share(&self, l: usize, k: usize, out: &mut Vec<usize>) {
        let best = Self::splits(&self.cost, l)[k];
        for a in 1..k {
            for b in 1..=k - a {
                if self.cost[l][a - 1] + self.cost[l + 1][b - 1] == best {
                    self.roots(l, a, out);
                    self.roots(l + 1, b, out);
                    return;
                }
            }
        }
        // Not reached: the least cost is one of the sums it was taken from, computed the
        // same way. Were it not, the two children are a forest within any budget.
        out.extend([l, l + 1]);
    }

    /// The roots of the cheapest forest of at most `k` over binary node `n`: `n` itself
    /// (a leaf, or a wide node) unless splitting it between its children costs less.
    fn roots(&self, n: usize, k: usize, out: &mut Vec<usize>) {
        let node = &self.bin[n];
        if node.count > 0 || k == 1 || self.cost[n][k - 1] == self.cost[n][0] {
            out.push(n);
        } else {
            self.share(node.first as usize, k, out);
        }
    }
}

#[inline]
fn bin_of<const N: usize>(c: Real, cb: &Aabb, axis: usize) -> usize {
    let lo = cb.min[axis];
    let ext = cb.max[axis] - lo;
    if ext <= 0.0 {
        return 0;
    }
    (((c - lo) / ext * N as Real) as usize).min(N - 1)
}

/// A set of primitives that [`best_split`] splits: their indices, every primitive's box
/// and centroid, the bounds of the set's centroids and of its boxes, and the SAH's
/// traversal cost.
#[derive(Clone, Copy)]
struct Set<'a> {
    idx: &'a [u32],
    boxes: &'a [Aabb],
    centroids: &'a [Vec3],
    cb: &'a Aabb,
    parent: &'a Aabb,
    traversal_cost: Real,
}

/// The cheapest split among `N` bins per axis: (axis, first bin of the right side
/// counted in [`WIDE_BINS`] bins, SAH cost in units of tests of one block of `B`, each
/// side's count rounded up to whole blocks). `None` when all centroids coincide. A bin
/// boundary `k` of `N` is boundary `k·WIDE_BINS/N` of `WIDE_BINS` exactly: the bin
/// index is the floor of the same quotient times a power of two, and scaling by a power of
/// two rounds nothing, so [`bin_of`]`::<WIDE_BINS>` partitions every set by either.
fn best_split<const B: usize, const N: usize>(set: &Set) -> Option<(usize, usize, Real)> {
    let Set {
        idx,
        boxes,
        centroids,
        cb,
        parent,
        traversal_cost,
    } = *set;
    let mut best: Option<(usize, usize, Real)> = None;
    let parent_area = parent.area().max(Real::MIN_POSITIVE);
    for axis in 0..3 {
        if cb.max[axis] - cb.min[axis] <= 0.0 {
            continue;
        }
        let mut bb = [Aabb::EMPTY; N];
        let mut cnt = [0usize; N];
        for &i in idx {
            let b = bin_of::<N>(centroids[i as usize][axis], cb, axis);
            bb[b] = bb[b].union(&boxes[i as usize]);
            cnt[b] += 1;
        }
        // Sweep from the right to get suffix areas and counts.
        let mut right_area = [0.0 as Real; N];
        let mut right_cnt = [0usize; N];
        let mut acc = Aabb::EMPTY;
        let mut c = 0;
        for k in (1..N).rev() {
            acc = acc.union(&bb[k]);
            c += cnt[k];
            right_area[k] = acc.area();
            right_cnt[k] = c;
        }
        let mut left = Aabb::EMPTY;
        let mut lc = 0;
        for k in 1..N {
            left = left.union(&bb[k - 1]);
            lc += cnt[k - 1];
            if lc == 0 || right_cnt[k] == 0 {
                continue;
            }
            let cost = traversal_cost
                + (left.area() * blocks::<B>(lc) + right_area[k] * blocks::<B>(right_cnt[k]))
                    / parent_area;
            if best.is_none_or(|(_, _, b)| cost < b) {
                best = Some((axis, k * (WIDE_BINS / N), cost));
            }
        }
    }
    best
}

// Where the node test has no SIMD form (the f64 build, another architecture; at 8 lanes
// a build without AVX), `hit` is `hit_lanes` and there is nothing to compare.
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;

    /// Test numbers: the sampler's hash of (test, case, dimension), in [0, 1).
    fn u(case: u64, dim: u64) -> Real {
        crate::sampler::uniform(0xb7b, case, dim) as Real
    }

    /// `Walk::push_sorted` (by ranks on an AVX2 build), and `Walk::push_few` on three
    /// lanes, take and stack the lanes in the insertion sort's order: on every mask of two
    /// or more of 8 lanes, 80 draws each of keys from a few values (ties in every pattern,
    /// ±∞ among them; NaN in lanes outside the mask, which must not count), the next lane
    /// and the stacked lanes, with their children, counts and entry distances, are the
    /// same.
    #[test]
    fn pushed_lanes_pop_in_the_sorted_order() {
        let values = [
            Real::NEG_INFINITY,
            0.0,
            0.5,
            0.5000001,
            1.0,
            7.0,
            Real::INFINITY,
        ];
        let mut node = Node::<8>::EMPTY;
        for k in 0..8 {
            node.child[k] = 100 + k as u32;
            node.count[k] = k as u8;
        }
        let mut ties = 0;
        for mask in (0u32..256).filter(|m| m.count_ones() >= 2) {
            for draw in 0..80u64 {
                let case = u64::from(mask) * 80 + draw;
                let key: [Real; 8] = std::array::from_fn(|k| {
                    if mask & (1 << k) == 0 && draw % 2 == 1 {
                        Real::NAN
                    } else {
                        values[(u(case, 1 + k as u64) * values.len() as Real) as usize]
                    }
                });
                let near: [Real; 8] = std::array::from_fn(|k| k as Real + u(case, 20 + k as u64));
                let (lanes, k) = sorted_lanes(mask, &key);
                type Push =
                    fn(&mut ArrayVec<Entry, 16>, &Node<8>, u32, &[Real; 8], &[Real; 8]) -> usize;
                let mut pushes: Vec<(&str, Push)> =
                    vec![("push_sorted (bvh::ranks8)", Walk::push_sorted)];
                if k == 3 {
                    pushes.push(("push_few::<3>", Walk::push_few::<16, 8, 3>));
                }
                for (name, push) in pushes {
                    let mut stack = ArrayVec::<Entry, 16>::new();
                    stack.push(Entry {
                        child: 1,
                        count: 0,
                        near: -1.0,
                    });
                    let next = push(&mut stack, &node, mask, &key, &near);
                    assert_eq!(
                        next, lanes[0],
                        "mask {mask:#010b}, keys {key:?}: Walk::{name} takes the wrong first lane"
                    );
                    let popped: Vec<(u32, u8, Real)> = stack
                        .iter()
                        .rev()
                        .map(|e| (e.child, e.count, e.near))
                        .collect();
                    let sorted: Vec<(u32, u8, Real)> = lanes[1..k]
                        .iter()
                        .map(|&l| (100 + l as u32, l as u8, near[l]))
                        .chain([(1, 0, -1.0)])
                        .collect();
                    assert_eq!(
                        popped, sorted,
                        "mask {mask:#010b}, keys {key:?}: Walk::{name} stacks the lanes out of \
                         the insertion sort's order"
                    );
                }
                ties += (1..k).any(|i| key[lanes[i]] == key[lanes[i - 1]]) as usize;
            }
        }
        assert!(ties > 5000, "the cases must include ties: {ties}");
    }

    /// `n` boxes in a 10-unit cube, each up to 1 unit a side, from test numbers
    /// `first..first + n`.
    fn random_boxes(first: u64, n: usize) -> Vec<Aabb> {
        (first..first + n as u64)
            .map(|k| {
                let c = Vec3::new(u(k, 1), u(k, 2), u(k, 3)) * 10.0;
                Aabb {
                    min: c,
                    max: c + Vec3::new(u(k, 4), u(k, 5), u(k, 6)),
                }
            })
            .collect()
    }

    /// `area_f64` is a box's surface area (`Aabb::area`'s, to `f32` rounding) and 0 for
    /// an empty box; in the `f32` build it stays finite where `Aabb::area` overflows.
    #[test]
    fn node_areas_are_surface_areas() {
        for (k, b) in random_boxes(9000, 50).iter().enumerate() {
            let (got, area) = (area_f64(b), b.area() as f64);
            assert!(
                (got - area).abs() <= 1e-6 * area,
                "box {k}: area_f64 {got}, Aabb::area {area}"
            );
        }
        assert_eq!(area_f64(&Aabb::EMPTY), 0.0);
        // (The module's tests run in the f32 build only.)
        let big = Aabb {
            min: Vec3::splat(-1e30),
            max: Vec3::new(1e30, 1e30, -1e30 + 1e24),
        };
        assert!(big.area().is_infinite(), "the f32 area overflows");
        let got = area_f64(&big);
        let want = 2.0 * (4e60 + 2.0 * 2e30 * 1e24);
        assert!(
            (got - want).abs() <= 1e-6 * want,
            "area_f64 {got}, want {want}"
        );
    }

    /// The wide nodes' total area (what [`collapse`] minimizes): each node's box is the
    /// union of its lanes' boxes.
    fn wide_area<const W: usize>(nodes: &[Node<W>]) -> f64 {
        nodes
            .iter()
            .map(|n| {
                let mut b = Aabb::EMPTY;
                for k in 0..n.lanes as usize {
                    b = b.union(&Aabb {
                        min: Vec3::new(n.b[0][k], n.b[2][k], n.b[4][k]),
                        max: Vec3::new(n.b[1][k], n.b[3][k], n.b[5][k]),
                    });
                }
                area_f64(&b)
            })
            .sum()
    }

    /// The least total area of a `W`-wide tree over the binary tree `bin`, by trying every
    /// set of binary interior nodes (the root always among them) as the wide nodes, and
    /// keeping the sets whose nodes have at most `W` children each.
    fn least_area_by_search<const W: usize>(bin: &[Node2]) -> f64 {
        let interior: Vec<usize> = (1..bin.len()).filter(|&n| bin[n].count == 0).collect();
        let mut best = f64::INFINITY;
        for set in 0u32..1 << interior.len() {
            let wide = |n: usize| {
                n == 0
                    || interior
                        .iter()
                        .position(|&m| m == n)
                        .is_some_and(|k| set >> k & 1 == 1)
            };
            // A wide node's children: its binary subtree, cut at wide nodes and leaves.
            let children = |n: usize| {
                let (mut stack, mut count) =
                    (vec![bin[n].first as usize, bin[n].first as usize + 1], 0);
                while let Some(m) = stack.pop() {
                    if bin[m].count > 0 || wide(m) {
                        count += 1;
                    } else {
                        stack.extend([bin[m].first as usize, bin[m].first as usize + 1]);
                    }
                }
                count
            };
            let nodes: Vec<usize> = (0..bin.len())
                .filter(|&n| bin[n].count == 0 && wide(n))
                .collect();
            if nodes.iter().all(|&n| children(n) <= W) {
                best = best.min(nodes.iter().map(|&n| area_f64(&bin[n].bounds)).sum());
            }
        }
        best
    }

    /// `collapse` finds the least total area of wide nodes over the binary tree (as an
    /// exhaustive search over which binary nodes become wide ones finds it), and covers
    /// every primitive once, on 4-wide trees over 6 to 20 random boxes, where most
    /// groupings leave some node with more than four children. Collapsing by opening the
    /// largest child until a node is full, as before, missed the least area in 7 of these
    /// 60 cases (by up to 3.4 %; on the 10⁶-triangle bench mesh its 8-wide nodes held 3.98
    /// children on average, against 6.15 now).
    #[test]
    fn the_collapse_has_the_least_node_area() {
        for case in 0..60u64 {
            let n = 6 + (case as usize * 7) % 15;
            let boxes = random_boxes(7000 + case * 100, n);
            let mut order: Vec<u32> = (0..n as u32).collect();
            // Leaves of one box: every binary node over two or more is interior.
            let bin = build_binary::<1>(&mut order, &boxes, 0.0, n);
            assert!(
                bin.iter().all(|b| b.count <= 1),
                "case {case}: a leaf of more than one box"
            );
            let interior = bin.iter().filter(|b| b.count == 0).count();
            assert!(
                interior <= 22,
                "case {case}: {interior} interior nodes, too many to search"
            );
            let (nodes, _) = collapse::<4>(&bin);
            let (got, least) = (wide_area(&nodes), least_area_by_search::<4>(&bin));
            assert!(
                (got - least).abs() <= 1e-9 * least,
                "case {case}: the collapse's nodes have area {got}, the least is {least}"
            );
            let mut slots: Vec<u32> = nodes
                .iter()
                .flat_map(|n| {
                    (0..n.lanes as usize)
                        .filter(|&k| n.count[k] > 0)
                        .map(|k| n.child[k])
                })
                .collect();
            slots.sort_unstable();
            assert_eq!(
                slots,
                (0..n as u32).collect::<Vec<_>>(),
                "case {case}: leaves cover each slot once"
            );
            assert!(
                nodes.iter().all(|n| (1..=4).contains(&(n.lanes as usize))),
                "case {case}: lanes"
            );
        }
    }

    /// The split `best_split` finds among 16 bins (and among 32) partitions the set by
    /// `bin_of::<WIDE_BINS>` into the two sides it priced: the SAH cost of the sides that
    /// partition makes is the cost it returned.
    #[test]
    fn a_split_partitions_the_set_it_priced() {
        let mut checked = 0;
        for case in 0..200u64 {
            let n = 8 + (case as usize * 37) % 300;
            let boxes = random_boxes(case * 1000, n);
            let centroids: Vec<Vec3> = boxes.iter().map(|b| b.centroid()).collect();
            let idx: Vec<u32> = (0..n as u32).collect();
            let (mut cb, mut parent) = (Aabb::EMPTY, Aabb::EMPTY);
            for (b, c) in boxes.iter().zip(&centroids) {
                parent = parent.union(b);
                cb.grow(*c);
            }
            let set = Set {
                idx: &idx,
                boxes: &boxes,
                centroids: &centroids,
                cb: &cb,
                parent: &parent,
                traversal_cost: 1.0,
            };
            for (bins, best) in [
                (BINS, best_split::<1, BINS>(&set)),
                (WIDE_BINS, best_split::<1, WIDE_BINS>(&set)),
            ] {
                let (axis, pos, cost) = best.expect("distinct centroids");
                let (mut l, mut r, mut nl) = (Aabb::EMPTY, Aabb::EMPTY, 0);
                for (b, c) in boxes.iter().zip(&centroids) {
                    if bin_of::<WIDE_BINS>(c[axis], &cb, axis) < pos {
                        l = l.union(b);
                        nl += 1;
                    } else {
                        r = r.union(b);
                    }
                }
                let got =
                    1.0 + (l.area() * nl as Real + r.area() * (n - nl) as Real) / parent.area();
                assert!(
                    (got - cost).abs() <= 1e-5 * cost,
                    "case {case}, {bins} bins: the split at bin {pos} of {WIDE_BINS} on axis \
                     {axis} was priced {cost} but partitions into sides that cost {got} \
                     (bvh::best_split's bin in WIDE_BINS, bvh::bin_of)"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 400);
    }

    /// Every node's leaf mask marks exactly its leaf lanes, on a tree large enough for
    /// the top splits' wider binning (`WIDE_BINS`).
    #[test]
    fn leaf_masks_mark_the_leaf_lanes() {
        let n = 4 * WIDE_FROM;
        let boxes: Vec<Aabb> = (0..n as u64)
            .map(|i| {
                let c = Vec3::new(u(i, 1), u(i, 2), u(i, 3)) * 100.0;
                Aabb {
                    min: c,
                    max: c + Vec3::new(u(i, 4), u(i, 5), u(i, 6)),
                }
            })
            .collect();
        let (bvh, _) = Bvh::<8>::build((0..n).collect::<Vec<_>>(), &boxes, 1.0);
        assert!(bvh.nodes.len() > 100, "{} nodes", bvh.nodes.len());
        for (i, node) in bvh.nodes.iter().enumerate() {
            let expect = (0..node.lanes as usize)
                .filter(|&k| node.count[k] > 0)
                .fold(0u8, |m, k| m | 1 << k);
            assert_eq!(
                node.leaves, expect,
                "node {i}: the leaf mask (bvh::collapse)"
            );
        }
    }

    /// A search for any hit takes a leaf first (the first in lane order) and stacks the
    /// other overlapped lanes so that the leaves pop before the interior nodes, each lane
    /// once with its entry distance.
    #[test]
    fn any_hit_takes_and_pops_leaves_first() {
        let near: [Real; 8] = std::array::from_fn(|k| 10.0 - k as Real);
        for leaves in 0u32..256 {
            let mut node = Node::<8>::EMPTY;
            for k in 0..8 {
                node.child[k] = 100 + k as u32;
                if leaves & (1 << k) != 0 {
                    node.count[k] = 1 + k as u8;
                    node.leaves |= 1 << k;
                }
            }
            for mask in (0u32..256).filter(|m| m.count_ones() >= 3) {
                let mut stack = ArrayVec::<Entry, 16>::new();
                let next = Walk::push_unsorted(&mut stack, &node, mask, &near);
                let in_mask = |m: u32| (0..8).filter(move |k| m & (1 << k) != 0);
                let expect_next = in_mask(mask & leaves)
                    .next()
                    .unwrap_or(mask.trailing_zeros() as usize);
                assert_eq!(
                    next, expect_next,
                    "mask {mask:#010b}, leaves {leaves:#010b}: the lane taken"
                );
                let popped: Vec<usize> = stack
                    .iter()
                    .rev()
                    .map(|e| (e.child - 100) as usize)
                    .collect();
                let mut expect: Vec<usize> = in_mask(mask & leaves)
                    .filter(|&l| l != next)
                    .rev()
                    .collect();
                expect.extend(in_mask(mask & !leaves).filter(|&l| l != next).rev());
                assert_eq!(
                    popped, expect,
                    "mask {mask:#010b}, leaves {leaves:#010b}: Walk::push_unsorted must pop the \
                     leaves first, then the interior nodes"
                );
                for e in &stack {
                    let l = (e.child - 100) as usize;
                    assert_eq!(
                        (e.count, e.near),
                        (node.count[l], near[l]),
                        "lane {l}'s entry"
                    );
                }
            }
        }
    }

    /// A NaN key among the lanes to order (which `Node::hit` never gives an overlapped
    /// lane) stops `Walk::push_sorted` before it writes the stack: on the AVX2 build its
    /// slots rely on the keys being ordered.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64"), target_feature = "avx2"))]
    #[test]
    #[should_panic(expected = "a NaN key among the lanes to order")]
    fn a_nan_key_stops_push_sorted() {
        let key = [0.5, Real::NAN, 0.25, 1.0, 0.0, 0.0, 0.0, 0.0];
        let mut stack = ArrayVec::<Entry, 16>::new();
        Walk::push_sorted(&mut stack, &Node::<8>::EMPTY, 0b1111, &key, &key);
    }

    /// The node test in SIMD lanes (SSE at 4, AVX at 8) gives the bits of the lane loop,
    /// on rays that cross boxes, miss them, run along a box's plane with a zero direction
    /// component (the NaN products the test must ignore), start on a plane, or pass
    /// through a corner; and neither reports a lane past the node's children.
    fn simd_matches_lanes<const W: usize>() {
        let mut seen = [0usize; 3];
        for case in 0..4000u64 {
            let mut node = Node::<W>::EMPTY;
            let boxes: Vec<Aabb> = (0..W)
                .map(|k| {
                    let c = Vec3::new(u(case, 6 * k as u64), u(case, 6 * k as u64 + 1), 0.0) * 4.0
                        - 2.0;
                    let h = Vec3::new(u(case, 6 * k as u64 + 2), u(case, 6 * k as u64 + 3), 0.5);
                    Aabb {
                        min: c - h,
                        max: c + h,
                    }
                })
                .collect();
            let lanes = 1 + (case as usize % W);
            node.set_boxes(&boxes[..lanes]);
            let mut o = Vec3::new(u(case, 100), u(case, 101), u(case, 102)) * 6.0 - 3.0;
            let mut d = Vec3::new(u(case, 103), u(case, 104), u(case, 105)) * 2.0 - 1.0;
            match case % 6 {
                // A zero (or negative zero) direction component, the origin on a plane.
                1 => {
                    d.x = if case % 8 == 1 { 0.0 } else { -0.0 };
                    o.x = boxes[0].min.x;
                }
                2 => {
                    d.y = 0.0;
                    o.y = boxes[0].max.y;
                    d.z = -0.0;
                }
                3 => o = boxes[0].centroid(),
                // Through a corner: entry and exit meet there, up to rounding, which the
                // far distance's inflation must absorb in both tests.
                4 => d = Vec3::new(boxes[0].max.x, boxes[0].min.y, boxes[0].max.z) - o,
                // Through the world's origin, where a lane left zeroed would have a box.
                5 => d = -o,
                _ => {}
            }
            let w = Walk::new(&Ray::new(o, d), 0.0, 4.0 * u(case, 106) + 0.5, true);
            let (simd, lanes_loop) = (node.hit(&w), node.hit_lanes(&w));
            assert_eq!(
                simd.1, lanes_loop.1,
                "case {case}: the SIMD node test (bvh::slab) and the lane loop \
                 (Node::hit_lanes) disagree on which of {W} boxes the ray overlaps"
            );
            for k in 0..lanes {
                assert_eq!(
                    simd.0[k].to_bits(),
                    lanes_loop.0[k].to_bits(),
                    "case {case}, lane {k}: entry distances differ between bvh::slab and \
                     Node::hit_lanes"
                );
            }
            assert_eq!(
                simd.1 >> lanes,
                0,
                "case {case}: the node test reports a lane past the node's {lanes} children \
                 (their empty boxes, Node::EMPTY, must never be overlapped)"
            );
            seen[(simd.1 != 0) as usize] += 1;
            seen[2] += (simd.1 != 0 && simd.1 != (1 << lanes) - 1) as usize;
        }
        assert!(
            seen.iter().all(|&n| n > 100),
            "the cases must include hits, misses and partial masks: {seen:?}"
        );
    }

    #[test]
    fn simd_node_test_matches_the_lane_loop_at_4_lanes() {
        simd_matches_lanes::<4>();
    }

    #[test]
    #[cfg(target_feature = "avx")]
    fn simd_node_test_matches_the_lane_loop_at_8_lanes() {
        simd_matches_lanes::<8>();
    }
}
