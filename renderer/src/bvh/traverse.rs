//! The walks of rays over a [`Bvh`]: one ray at a time, nearest child first for the
//! closest hit or leaves first for any hit (with prefetching for a tree larger than the
//! cache), or a batch of rays in turn; and the steps of one ray's walk, with the orders
//! in which a node's overlapped children are taken and stacked.

use super::build::MAX_DEPTH;
use super::node::{Node, Walk, MAX_WIDTH};
use super::{Bvh, Visit, BATCH};
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec3};
use arrayvec::ArrayVec;

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

/// A child waiting on the traversal stack, with its entry distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u8,
    near: Real,
}

impl<const W: usize> Bvh<W> {
    /// The tree's only leaf, when it is a single one: then traversal visits the leaf
    /// directly, with no walk and no stack, after testing the tree's bounds (which
    /// [`Bvh::traverse`] skips for a leaf of one primitive).
    #[inline]
    fn single_leaf(&self) -> Option<(u32, u8)> {
        let root = &self.nodes[0];
        (self.nodes.len() == 1 && root.lanes == 1 && root.count[0] > 0)
            .then(|| (root.child[0], root.count[0]))
    }

    /// Visits, nearest box first, every primitive whose box the ray overlaps within
    /// `(t_min, t_max)` (a tree of one primitive visits it without testing its box).
    /// `visit(i, t_max)` tests primitive `i` and reports a hit, which shrinks `t_max`.
    /// With `any`, traversal stops at the first hit. Returns whether anything was hit.
    /// (Always inlined: once the search wrote its record in place, the compiler kept this
    /// walk out of line in `Aggregate::intersect_for_shading_into`, its closure's state in
    /// memory: a Whitted frame took 3.4 % more instructions, and the Cornell box and the
    /// mesh scene 2.6–2.8 % more time than inlined.)
    #[inline(always)]
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
        self.walk_one::<false, F>(ray, t_min, t_max, any, false, visit, &|_, _| {})
    }

    /// [`Bvh::traverse_leaves`] for a tree larger than the cache: as soon as a node's
    /// slab test tells which children the ray overlaps, it asks for the memory of all of
    /// them (a prefetch: the child nodes, or the records of the leaves, which start at
    /// `leaf_at(first)`), so their cache misses overlap each other and the work on
    /// the nearest child, instead of following one another. The walk, and so every
    /// result, is the same. A search for any hit starts asking from its first step when
    /// `eager` (the owner's choice: a mesh does when its tree is larger than the cache,
    /// where its shadow rays mostly walk on past their first leaf), else only once a leaf
    /// has failed to end it (`Walk::eager`). (Always inlined: as a call shared by a
    /// mesh's two searches, `Mesh::intersect` and `Mesh::nearest`, it cost the first
    /// +2.2 % instructions on the peers bench's coherent rays.)
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn traverse_leaves_prefetching<F, L>(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        any: bool,
        eager: bool,
        visit: F,
        leaf_at: L,
    ) -> bool
    where
        F: FnMut(u32, u8, Real) -> Visit,
        L: Fn(u32) -> *const u8,
    {
        let ahead = self.ahead(leaf_at);
        self.walk_one::<true, F>(ray, t_min, t_max, any, !any || eager, visit, &ahead)
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

    /// The single-ray walk; `ahead` is given every overlapped child (with `ALL`, from the
    /// first step when `eager`, see `Walk::eager`) or the next child to take.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn walk_one<const ALL: bool, F>(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        any: bool,
        eager: bool,
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
        let mut w = Walk::new(ray, t_min, t_max, eager);
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
        self.traverse_batch_leaves::<false, _, _>(
            rays,
            t_min,
            t_max,
            |r, first, count, t| each(false, &mut |i, t| visit(r, i, t))(first, count, t),
            leaf_at,
        );
    }

    /// [`Bvh::traverse_batch`] a leaf at a time, as [`Bvh::traverse_leaves`]:
    /// `visit(r, first, count, t_max)` tests a leaf against `rays[r]`. For the closest
    /// hit or, with `ANY`, any hit (as [`Bvh::traverse_leaves`] with `any`: leaves first,
    /// each ray's walk ends at its first hit). Returns the mask of the rays that hit
    /// something, bit `r` for `rays[r]`; each ray takes exactly the steps it takes alone,
    /// so the mask is what [`Bvh::traverse_leaves`] returns ray by ray.
    #[inline]
    pub fn traverse_batch_leaves<const ANY: bool, F, L>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        mut visit: F,
        leaf_at: L,
    ) -> u64
    where
        F: FnMut(usize, u32, u8, Real) -> Visit,
        L: Fn(u32) -> *const u8,
    {
        assert!(rays.len() <= BATCH && rays.len() == t_max.len());
        if self.nodes.is_empty() || rays.is_empty() {
            return 0;
        }
        if let Some((first, count)) = self.single_leaf() {
            let mut hits = 0;
            for (r, &t) in t_max.iter().enumerate() {
                if let Visit::Hit(_) = visit(r, first, count, t) {
                    hits |= 1 << r;
                }
            }
            return hits;
        }
        let ahead = self.ahead(leaf_at);
        if self.stack_need <= TINY_STACK {
            self.walk_batch::<TINY_STACK, ANY>(rays, t_min, t_max, &mut visit, &ahead)
        } else if self.stack_need <= SHORT_STACK {
            self.walk_batch::<SHORT_STACK, ANY>(rays, t_min, t_max, &mut visit, &ahead)
        } else {
            self.walk_batch::<LONG_STACK, ANY>(rays, t_min, t_max, &mut visit, &ahead)
        }
    }

    #[inline]
    fn walk_batch<const STACK: usize, const ANY: bool>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        visit: &mut impl FnMut(usize, u32, u8, Real) -> Visit,
        ahead: &impl Fn(u32, u8),
    ) -> u64 {
        // Slots past the last ray start inactive and are never stepped.
        let mut walks: [Walk; BATCH] = std::array::from_fn(|r| {
            let k = r.min(rays.len() - 1);
            Walk::new(&rays[k], t_min, t_max[k], !ANY)
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
                    ANY,
                    &mut |first, count, t| visit(r, first, count, t),
                    ahead,
                ) {
                    active &= !(1u64 << r);
                }
            }
        }
        (0..rays.len()).fold(0, |hits, r| hits | (walks[r].hit as u64) << r)
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

/// Cache lines a prefetch of a child asks for: a node is four (256 bytes at 8 lanes), a
/// mesh leaf of two packs five or six (320 bytes in `f32`, at a multiple of 32: six when
/// the first pack starts 32 bytes into a line, and then the sixth, the second pack's
/// last 32 bytes, is not asked for; a sixth line for every child measured no better), of
/// one pack three, and the instance records of a leaf (32 bytes each) one or two. As
/// many whatever the child is, so that the walk does not branch on it (`Bvh::ahead`).
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
/// written into the first places of `lanes`, and how many there are. (Into the caller's
/// array: an array returned was copied out with wide loads of the lanes just written one
/// by one, which the processor cannot forward from its store buffer.)
#[inline(always)]
fn sorted_lanes<const W: usize>(mask: u32, key: &[Real; W], lanes: &mut [usize; W]) -> usize {
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
    k
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
        let mut lanes = [0; W];
        let k = sorted_lanes(mask, &key, &mut lanes);
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
        let mut lanes = [0; W];
        let k = sorted_lanes(mask, key, &mut lanes);
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
    pub(super) fn new(ray: &Ray, t_min: Real, t_max: Real, eager: bool) -> Self {
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
        // An empty lane's child is no node (`Node::EMPTY`): only a ray with a NaN can
        // overlap an empty lane (the slab test ignores a NaN product), and there the walk
        // moves on to the next child on the stack, as from a leaf that holds nothing. (So
        // such a ray walks the tree and finds what the shapes' own tests report, where node
        // 0 as the empty lanes' child made it cycle through the root until the stack
        // overflowed.)
        if let (0, Some(n)) = (self.count, nodes.get(self.child as usize)) {
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
                let first = mask.trailing_zeros() as usize;
                let rest = mask & (mask - 1);
                let next = if rest == 0 {
                    first
                } else if rest & (rest - 1) == 0 {
                    let second = rest.trailing_zeros() as usize;
                    let nearer = near[second] < near[first];
                    // For any hit, a leaf goes before a node, two leaves in lane order,
                    // two nodes nearer first: the second lane goes first when it alone
                    // is a leaf, or when neither is and it is nearer. (Read from the
                    // node's leaf bits, with no copy of the entry distances with −∞ for
                    // the leaves, which compiled to a branch a lane: −13 % instructions
                    // for shadow rays' any hit, the same time.)
                    let second_first = if any {
                        let leaves = n.leaves as u32;
                        let (lf, ls) = ((leaves >> first) & 1, (leaves >> second) & 1);
                        ls > lf || (ls | lf == 0 && nearer)
                    } else {
                        nearer
                    };
                    let (a, b) = if second_first {
                        (second, first)
                    } else {
                        (first, second)
                    };
                    Walk::push(stack, n, b, near[b]);
                    a
                } else if any {
                    Walk::push_unsorted(stack, n, mask, &near)
                } else if rest.count_ones() == 2 {
                    Walk::push_few::<N, W, 3>(stack, n, mask, &near, &near)
                } else {
                    Walk::push_sorted(stack, n, mask, &near, &near)
                };
                (self.child, self.count) = (n.child[next], n.count[next]);
                if !ALL {
                    ahead(self.child, self.count);
                }
                return true;
            }
        } else if self.count != 0 {
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

// As the node test's (node.rs, which says why): these run in the f32 build on x86_64.
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;
    use crate::bvh::testing::u;

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
                let mut lanes = [0; 8];
                let k = sorted_lanes(mask, &key, &mut lanes);
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
}
