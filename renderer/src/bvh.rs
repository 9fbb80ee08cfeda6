//! A bounding volume hierarchy built by binned SAH (Wald 2007), stored as a flat node
//! array, and traversed with a fixed-size stack: traversal never allocates.
//!
//! The BVH knows nothing about what it bounds. It is built from a list of boxes and its
//! traversal calls a closure with primitive indices, so one implementation serves the
//! instance level and every mesh.

use crate::aabb::Aabb;
use crate::ray::Ray;
use crate::real::{Real, Vec3};

const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Depth past which a node becomes a leaf; keeps the traversal stack bounded.
const MAX_DEPTH: usize = 60;
const STACK: usize = 64;
/// Cost of one traversal step relative to one primitive test, for the SAH.
const TRAVERSAL_COST: Real = 1.0;

/// One node. Interior nodes (`count == 0`) have children at `first` and `first + 1`;
/// leaves hold `indices[first..first + count]`.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// First child, or first primitive slot.
    pub first: u32,
    /// Number of primitives; 0 for an interior node.
    pub count: u32,
}

/// A BVH over primitives given by their boxes.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes; the root is `nodes[0]`.
    pub nodes: Vec<Node>,
    /// Primitive indices referenced by leaves.
    pub indices: Vec<u32>,
}

/// What the traversal closure says about a primitive.
pub enum Visit {
    /// No hit (or a hit no closer than the current bound).
    Miss,
    /// A hit at this distance: the search interval shrinks to it.
    Hit(Real),
}

impl Bvh {
    /// Builds a BVH over `boxes`, which must all be finite.
    pub fn build(boxes: &[Aabb]) -> Bvh {
        let n = boxes.len();
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * n.max(1)),
            indices: (0..n as u32).collect(),
        };
        if n == 0 {
            bvh.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: 0,
                count: 0,
            });
            return bvh;
        }
        let centroids: Vec<Vec3> = boxes.iter().map(|b| b.centroid()).collect();
        bvh.nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: n as u32,
        });
        // Work list of (node, start, end, depth).
        let mut work = vec![(0usize, 0usize, n, 0usize)];
        while let Some((node, start, end, depth)) = work.pop() {
            let mut bounds = Aabb::EMPTY;
            let mut cbounds = Aabb::EMPTY;
            for &i in &bvh.indices[start..end] {
                bounds = bounds.union(&boxes[i as usize]);
                cbounds.grow(centroids[i as usize]);
            }
            bvh.nodes[node].bounds = bounds;
            let count = end - start;
            let leaf = |bvh: &mut Bvh| {
                bvh.nodes[node].first = start as u32;
                bvh.nodes[node].count = count as u32;
            };
            if count <= 1 || depth >= MAX_DEPTH {
                leaf(&mut bvh);
                continue;
            }
            let Some((axis, split_pos, cost)) =
                best_split(&bvh.indices[start..end], boxes, &centroids, &cbounds)
            else {
                leaf(&mut bvh);
                continue;
            };
            let leaf_cost = count as Real;
            if count <= MAX_LEAF && cost >= leaf_cost {
                leaf(&mut bvh);
                continue;
            }
            // Partition in place by bin.
            let slice = &mut bvh.indices[start..end];
            let mut mid = 0;
            for k in 0..slice.len() {
                if bin_of(centroids[slice[k] as usize][axis], &cbounds, axis) < split_pos {
                    slice.swap(k, mid);
                    mid += 1;
                }
            }
            if mid == 0 || mid == count {
                leaf(&mut bvh);
                continue;
            }
            let left = bvh.nodes.len();
            for _ in 0..2 {
                bvh.nodes.push(Node {
                    bounds: Aabb::EMPTY,
                    first: 0,
                    count: 0,
                });
            }
            bvh.nodes[node].first = left as u32;
            bvh.nodes[node].count = 0;
            work.push((left + 1, start + mid, end, depth + 1));
            work.push((left, start, start + mid, depth + 1));
        }
        bvh
    }

    /// Permutes `items` (one per box given to [`Bvh::build`]) into leaf order and makes the
    /// index array the identity, so that a leaf's primitives sit side by side in memory
    /// and traversal reads them without an indirection into scattered storage.
    pub fn reorder<T>(&mut self, items: Vec<T>) -> Vec<T> {
        assert_eq!(items.len(), self.indices.len(), "one item per box");
        let mut slots: Vec<Option<T>> = items.into_iter().map(Some).collect();
        let ordered = self
            .indices
            .iter()
            .map(|&i| {
                slots[i as usize]
                    .take()
                    .expect("the BVH references each primitive once")
            })
            .collect();
        for (k, i) in self.indices.iter_mut().enumerate() {
            *i = k as u32;
        }
        ordered
    }

    /// Bounds of everything.
    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bounds
    }

    /// Visits, nearest box first, every primitive whose box the ray overlaps within
    /// `(t_min, t_max)`. `visit(i, t_max)` tests primitive `i` and reports a hit, which
    /// shrinks `t_max`. With `any`, traversal stops at the first hit. Returns whether
    /// anything was hit.
    #[inline]
    pub fn traverse<F>(
        &self,
        ray: &Ray,
        t_min: Real,
        mut t_max: Real,
        any: bool,
        mut visit: F,
    ) -> bool
    where
        F: FnMut(u32, Real) -> Visit,
    {
        let inv_d = Vec3::ONE / ray.d;
        let mut stack = [0u32; STACK];
        let mut sp = 0usize;
        let mut hit = false;
        let root = &self.nodes[0];
        if root.bounds.hit(ray.o, inv_d, t_min, t_max).is_none() {
            return false;
        }
        let mut node = 0u32;
        loop {
            let n = &self.nodes[node as usize];
            if n.count > 0 {
                for &i in &self.indices[n.first as usize..(n.first + n.count) as usize] {
                    if let Visit::Hit(t) = visit(i, t_max) {
                        hit = true;
                        if any {
                            return true;
                        }
                        t_max = t;
                    }
                }
            } else {
                let (a, b) = (n.first, n.first + 1);
                let ta = self.nodes[a as usize]
                    .bounds
                    .hit(ray.o, inv_d, t_min, t_max);
                let tb = self.nodes[b as usize]
                    .bounds
                    .hit(ray.o, inv_d, t_min, t_max);
                match (ta, tb) {
                    (Some(x), Some(y)) => {
                        let (near, far) = if x <= y { (a, b) } else { (b, a) };
                        stack[sp] = far;
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node that still overlaps the (possibly shrunk) interval.
            loop {
                if sp == 0 {
                    return hit;
                }
                sp -= 1;
                node = stack[sp];
                if self.nodes[node as usize]
                    .bounds
                    .hit(ray.o, inv_d, t_min, t_max)
                    .is_some()
                {
                    break;
                }
            }
        }
    }
}

#[inline]
fn bin_of(c: Real, cb: &Aabb, axis: usize) -> usize {
    let lo = cb.min[axis];
    let ext = cb.max[axis] - lo;
    if ext <= 0.0 {
        return 0;
    }
    (((c - lo) / ext * BINS as Real) as usize).min(BINS - 1)
}

/// The cheapest binned split: (axis, first bin of the right side, SAH cost in units of
/// primitive tests). `None` when all centroids coincide.
fn best_split(
    idx: &[u32],
    boxes: &[Aabb],
    centroids: &[Vec3],
    cb: &Aabb,
) -> Option<(usize, usize, Real)> {
    let mut best: Option<(usize, usize, Real)> = None;
    let mut parent = Aabb::EMPTY;
    for &i in idx {
        parent = parent.union(&boxes[i as usize]);
    }
    let parent_area = parent.area().max(Real::MIN_POSITIVE);
    for axis in 0..3 {
        if cb.max[axis] - cb.min[axis] <= 0.0 {
            continue;
        }
        let mut bb = [Aabb::EMPTY; BINS];
        let mut cnt = [0usize; BINS];
        for &i in idx {
            let b = bin_of(centroids[i as usize][axis], cb, axis);
            bb[b] = bb[b].union(&boxes[i as usize]);
            cnt[b] += 1;
        }
        // Sweep from the right to get suffix areas and counts.
        let mut right_area = [0.0 as Real; BINS];
        let mut right_cnt = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut c = 0;
        for k in (1..BINS).rev() {
            acc = acc.union(&bb[k]);
            c += cnt[k];
            right_area[k] = acc.area();
            right_cnt[k] = c;
        }
        let mut left = Aabb::EMPTY;
        let mut lc = 0;
        for k in 1..BINS {
            left = left.union(&bb[k - 1]);
            lc += cnt[k - 1];
            if lc == 0 || right_cnt[k] == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST
                + (left.area() * lc as Real + right_area[k] * right_cnt[k] as Real) / parent_area;
            if best.is_none_or(|(_, _, b)| cost < b) {
                best = Some((axis, k, cost));
            }
        }
    }
    best
}
