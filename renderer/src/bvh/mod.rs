//! A bounding volume hierarchy: built by binned SAH (Wald 2007) as a binary tree, then
//! collapsed into a `W`-wide tree, 4 or 8 (each node holds the boxes of up to `W` children
//! side by side, so one SIMD slab test covers them all: 4 lanes of SSE, or 8 of AVX). Nodes live in a flat array, 64-byte
//! aligned, and traversal uses a fixed-size stack: it never allocates.
//!
//! The BVH knows nothing about what it bounds. It is built from a list of boxes and its
//! traversal calls a closure with primitive indices, so one implementation serves the
//! instance level and every mesh. The owner stores its primitives in leaf order
//! ([`Bvh::build`] returns them so), and a leaf names a run of consecutive slots.
//!
//! One part a file: `node.rs`, the wide node and its SIMD slab test; `traverse.rs`, the
//! walks of rays over the tree (one ray, a batch, and the steps of one ray's walk);
//! `build.rs`, the binned-SAH build of the binary tree; `collapse.rs`, the binary tree
//! collapsed into `W`-wide nodes by dynamic programming; `testing.rs`, the unit tests'
//! test data. Here: the [`Bvh`] type, its build (the binary tree, then its collapse) and
//! its public items. Imports point one way (tests/architecture.rs checks it):
//! `traverse` uses this module, `node` and `build`; this module uses `node`, `build` and
//! `collapse`; `collapse` uses `node` and `build`.

mod build;
mod collapse;
mod node;
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod testing;
mod traverse;

use crate::aabb::Aabb;
use crate::ray::Ray;
use crate::real::Real;
use build::build_binary;
use collapse::collapse;
use node::{Node, MAX_WIDTH};

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

    /// Bounds of everything.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Number of `W`-wide nodes, for statistics.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of node memory, for statistics and for the owner's choice of
    /// [`Bvh::traverse_batch`].
    pub fn node_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
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

/// The hit mask of a batch asked one ray at a time: bit `r` set when `hit(&rays[r],
/// t_max[r])`. What the batch calls fall back on where the rays are not walked
/// together.
#[inline(always)]
pub(crate) fn mask_ray_by_ray(
    rays: &[Ray],
    t_max: &[Real],
    hit: impl Fn(&Ray, Real) -> bool,
) -> u64 {
    (rays.iter().zip(t_max).enumerate())
        .fold(0, |hits, (r, (ray, &t))| hits | (hit(ray, t) as u64) << r)
}

// As the node test's (node.rs, which says why): these run in the f32 build on x86_64.
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;
    use crate::bvh::build::WIDE_FROM;
    use crate::bvh::testing::u;
    use crate::real::Vec3;

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
}
