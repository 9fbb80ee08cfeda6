//! The binary tree collapsed into a `W`-wide one: which binary nodes become wide ones,
//! chosen by dynamic programming for the least total node area.

use super::build::Node2;
use super::node::{Node, MAX_WIDTH};
use crate::aabb::Aabb;

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
pub(super) fn collapse<const W: usize>(bin: &[Node2]) -> (Vec<Node<W>>, usize) {
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

// As the node test's (node.rs, which says why): these run in the f32 build on x86_64.
#[cfg(all(test, target_arch = "x86_64", not(feature = "f64")))]
mod tests {
    use super::*;
    use crate::bvh::build::build_binary;
    use crate::bvh::testing::random_boxes;
    use crate::real::Vec3;

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
}
