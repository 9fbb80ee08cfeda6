//! The `W`-wide node: the boxes of up to `W` children side by side, and the slab test
//! that covers them all at once (SIMD, or the same operations as a lane loop). Also
//! [`Walk`], one ray's walk state, whose ray part is what the slab test reads: it is
//! declared here so that the traversal (`traverse.rs`, where its methods are) uses this
//! module and never the other way round.

use crate::aabb::Aabb;
use crate::real::{gamma, Real};

/// Widest node the traversal stacks are sized for.
pub(super) const MAX_WIDTH: usize = 8;

/// A node of the `W`-wide tree: the boxes of up to `W` children side by side, one array
/// of `W` lanes per axis and side, so that one SIMD slab test covers them all. Per child
/// the node holds either an interior node index (`count == 0`) or a leaf's first slot and
/// count.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub(super) struct Node<const W: usize> {
    /// Per axis `a`, `b[2a]` holds the children's low sides and `b[2a + 1]` their high
    /// sides.
    pub(super) b: [[Real; W]; 6],
    pub(super) child: [u32; W],
    pub(super) count: [u8; W],
    pub(super) lanes: u8,
    /// Bit `k` set when lane `k` is a leaf (`count[k] > 0`).
    pub(super) leaves: u8,
}

/// The child of an empty lane: no node (an index past every tree's nodes).
pub(super) const NO_NODE: u32 = u32::MAX;

impl<const W: usize> Node<W> {
    /// A node with no lanes. Every lane's box is empty (low sides +∞, high sides −∞),
    /// and [`Node::set_boxes`] leaves the lanes past the children so: the slab test finds
    /// such a lane's entry at +∞ and its exit at −∞ for any ray (the near side's product
    /// is +∞ and the far side's −∞ whatever the direction's sign, ±0 included), so it
    /// never reports it, with no mask of the lanes in use (which sits on the node's last
    /// cache line). The exception is a ray with a NaN in its origin or direction, whose
    /// NaN products the test ignores: on such an axis nothing bounds it, and it may
    /// overlap an empty lane, so an empty lane's child is [`NO_NODE`], which the walk
    /// skips (bvh/traverse.rs, `Walk::step`).
    pub(super) const EMPTY: Node<W> = Node {
        b: [
            [Real::INFINITY; W],
            [Real::NEG_INFINITY; W],
            [Real::INFINITY; W],
            [Real::NEG_INFINITY; W],
            [Real::INFINITY; W],
            [Real::NEG_INFINITY; W],
        ],
        child: [NO_NODE; W],
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
    pub(super) fn hit(&self, w: &Walk) -> ([Real; W], u32) {
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
    pub(super) fn set_boxes(&mut self, boxes: &[Aabb]) {
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

/// One ray's traversal state, apart from its stack.
#[derive(Clone, Copy)]
pub(super) struct Walk {
    pub(super) o: [Real; 3],
    pub(super) inv_d: [Real; 3],
    /// Per axis `a`, the index in [`Node::b`] of the slab's near side: `2a` (low) when the
    /// direction is positive, `2a + 1` (high) when negative (its sign bit: −0 counts).
    pub(super) near: [usize; 3],
    pub(super) t_min: Real,
    pub(super) t_max: Real,
    /// The child to take next: an interior node (`count == 0`) or a leaf's slots.
    pub(super) child: u32,
    pub(super) count: u8,
    pub(super) hit: bool,
    /// Whether a prefetching walk (`ALL`) asks for every overlapped child yet. A search
    /// for the closest hit does from the start, and so does a search for any hit in a
    /// tree its owner says is larger than the cache (a mesh past `INTERLEAVE_ABOVE`:
    /// there most shadow rays walk on past their first leaf, and the children passed on
    /// the way down would otherwise be missed one after another). Otherwise a search for
    /// any hit asks only once a leaf has failed to end it: when the first leaf tested
    /// (leaves go first, and a large occluder such as a ground quad sits near the root)
    /// ends the search, as it does for most rays aimed at such a surface, prefetches
    /// would be wasted.
    pub(super) eager: bool,
}

// Where the node test has no SIMD form (the f64 build, another architecture; at 8 lanes
// a build without AVX), `hit` is `hit_lanes` and there is nothing to compare.
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;
    use crate::bvh::testing::u;
    use crate::ray::Ray;
    use crate::real::Vec3;

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
