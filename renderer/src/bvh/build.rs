//! The binary tree that the binned SAH builds (Wald 2007), the first stage of a [`Bvh`]'s
//! build: the binning, the cheapest split, and the partition of the primitives into leaf
//! order.
//!
//! [`Bvh`]: super::Bvh

use crate::aabb::Aabb;
use crate::real::{Real, Vec3};

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
pub(super) const WIDE_FROM: usize = 1024;
const _: () = assert!(WIDE_BINS % BINS == 0 && (WIDE_BINS / BINS).is_power_of_two());
const MAX_LEAF: usize = 4;
/// Depth past which the SAH stops splitting; keeps the traversal stack bounded.
pub(super) const MAX_DEPTH: usize = 60;
/// Most primitives one leaf can name (counts are bytes). A bigger set that the SAH cannot
/// split (coincident centroids, or the depth limit) is cut in halves by index instead,
/// which adds at most 24 levels below `MAX_DEPTH` for any `u32` count.
const LEAF_LIMIT: usize = u8::MAX as usize;

/// A node of the binary tree the SAH builds. Interior nodes (`count == 0`) have children
/// at `first` and `first + 1`; leaves name the slots `first..first + count`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node2 {
    pub(super) bounds: Aabb,
    pub(super) first: u32,
    pub(super) count: u32,
}

/// Blocks of `B` primitives that `n` fill, the last partly: how the SAH counts a leaf's
/// primitives (`B` = 1: one by one; [`Bvh::build_aligned`](super::Bvh::build_aligned): its records). A constant, so
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
/// than a leaf ([`Bvh::build_spread`](super::Bvh::build_spread)); collapsing gathers them into one node when the
/// set is where a collapse starts, and may share them out with their neighbours below.
pub(super) fn build_binary<const B: usize>(
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

// As the node test's (node.rs, which says why): these run in the f32 build on x86_64.
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;
    use crate::bvh::testing::random_boxes;

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
}
