//! Bounding volume hierarchy over primitive boxes (the broad phase).
//!
//! **Build.** Primitives are sorted by the 63-bit Morton code of their box centre (21 bits per
//! axis, quantised in the bounding box of all centres), and the tree is built top-down over that
//! order, splitting each range where its highest differing Morton bit changes (the split of a
//! linear BVH, Karras 2012, "Maximizing parallelism in the construction of BVHs, octrees, and k-d
//! trees") or in the middle when all codes in the range are equal. Every leaf holds one primitive.
//! Codes, the sort (keys made unique by the primitive index) and the recursion run in parallel with
//! rayon; the result does not depend on the thread count.
//!
//! **Layout.** The `2n − 1` nodes are stored in depth-first order: the left child of node `i` is
//! `i + 1`, the right child `i + 2·(leaves of the left child)`. Subtrees are therefore contiguous,
//! which lets the build and [`Bvh::refit`] split the node array between threads.
//!
//! **Queries.** [`Bvh::query_aabb`] walks one box down the tree; [`Bvh::self_pairs`] and
//! [`Bvh::pairs_with`] traverse two subtrees simultaneously (each overlapping node pair splits the
//! subtree with more leaves), in parallel above a size threshold. Pair results are sorted and
//! deduplicated, so they are deterministic. For primitives of bounded size and density, the number
//! of box tests grows like `N log N` (tested below).

use rayon::prelude::*;

use super::aabb::Aabb;
use super::GeometryError;

/// Subtrees with more leaves than this are built, refitted and traversed in parallel.
const PARALLEL_LEAVES: usize = 2048;

/// One node: its box, the number of primitives below it, and either the primitive (leaf) or the
/// offset of the right child (internal node; the left child is the next node).
#[derive(Debug, Clone, Copy)]
struct Node {
    aabb: Aabb,
    /// Number of leaves in this subtree (1 for a leaf).
    leaves: usize,
    /// Leaf: primitive index. Internal: offset from this node to its right child.
    index: usize,
}

impl Node {
    #[inline]
    fn is_leaf(&self) -> bool {
        self.leaves == 1
    }
}

/// A bounding volume hierarchy over a fixed list of primitive boxes.
///
/// Primitive `i` is the box `boxes[i]` passed to [`Bvh::build`]; queries report these indices.
/// The tree can be refitted to new boxes of the same primitives with [`Bvh::refit`].
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
}

/// Interleaves the low 21 bits of `x` with two zero bits between each.
#[inline]
fn spread_bits_21(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// 63-bit Morton codes of the box centres, quantised in the bounding box of all finite centres.
/// Boxes with a non-finite centre (unbounded or empty) get `u64::MAX` and sort last.
fn morton_codes(boxes: &[Aabb]) -> Vec<u64> {
    let centers: Vec<_> = boxes.par_iter().map(|b| b.center()).collect();
    let finite = |c: &nalgebra::Vector3<f64>| c.iter().all(|x| x.is_finite());
    let bounds = centers
        .par_iter()
        .filter(|c| finite(c))
        .map(Aabb::from_point)
        .reduce(Aabb::empty, |a, b| a.union(&b));
    const SCALE: f64 = ((1u64 << 21) - 1) as f64;
    let extent = bounds.extent();
    centers
        .par_iter()
        .map(|c| {
            if !finite(c) {
                return u64::MAX;
            }
            let mut code = 0;
            for k in 0..3 {
                let q = if extent[k] > 0.0 {
                    ((c[k] - bounds.min[k]) / extent[k] * SCALE).clamp(0.0, SCALE) as u64
                } else {
                    0
                };
                code |= spread_bits_21(q) << (2 - k);
            }
            code
        })
        .collect()
}

/// Where to split the sorted range: at the first code whose highest differing bit is set, or in
/// the middle when all codes are equal. Always returns a split strictly inside `1..len`.
fn split_point(order: &[(u64, usize)]) -> usize {
    let n = order.len();
    let (first, last) = (order[0].0, order[n - 1].0);
    if first == last {
        return n / 2;
    }
    let bit = 63 - (first ^ last).leading_zeros();
    let mask = 1u64 << bit;
    order.partition_point(|&(c, _)| c & mask == 0)
}

/// Fills `nodes` (exactly `2·order.len() − 1` entries) with the subtree over `order`.
fn build_subtree(nodes: &mut [Node], order: &[(u64, usize)], boxes: &[Aabb]) {
    let n = order.len();
    debug_assert_eq!(nodes.len(), 2 * n - 1);
    if n == 1 {
        let prim = order[0].1;
        nodes[0] = Node {
            aabb: boxes[prim],
            leaves: 1,
            index: prim,
        };
        return;
    }
    let split = split_point(order);
    let (head, rest) = nodes.split_at_mut(1);
    let (left, right) = rest.split_at_mut(2 * split - 1);
    let (order_l, order_r) = order.split_at(split);
    if n > PARALLEL_LEAVES {
        rayon::join(
            || build_subtree(left, order_l, boxes),
            || build_subtree(right, order_r, boxes),
        );
    } else {
        build_subtree(left, order_l, boxes);
        build_subtree(right, order_r, boxes);
    }
    head[0] = Node {
        aabb: left[0].aabb.union(&right[0].aabb),
        leaves: n,
        index: 2 * split,
    };
}

/// Recomputes the boxes of the subtree stored in `nodes` from the primitive boxes.
fn refit_subtree(nodes: &mut [Node], boxes: &[Aabb]) {
    if nodes[0].is_leaf() {
        nodes[0].aabb = boxes[nodes[0].index];
        return;
    }
    let right_offset = nodes[0].index;
    let (head, rest) = nodes.split_at_mut(1);
    let (left, right) = rest.split_at_mut(right_offset - 1);
    if head[0].leaves > PARALLEL_LEAVES {
        rayon::join(|| refit_subtree(left, boxes), || refit_subtree(right, boxes));
    } else {
        refit_subtree(left, boxes);
        refit_subtree(right, boxes);
    }
    head[0].aabb = left[0].aabb.union(&right[0].aabb);
}

/// Pairs found by a traversal and the number of box–box tests it made.
type PairsAndTests = (Vec<(usize, usize)>, u64);

impl Bvh {
    /// Builds the tree over `boxes` (primitive `i` has box `boxes[i]`), in parallel.
    ///
    /// An empty slice gives an empty tree. Non-finite boxes are allowed (e.g.
    /// [`Aabb::everything`]); they are placed last in the Morton order.
    pub fn build(boxes: &[Aabb]) -> Bvh {
        let n = boxes.len();
        if n == 0 {
            return Bvh { nodes: Vec::new() };
        }
        let codes = morton_codes(boxes);
        let mut order: Vec<(u64, usize)> = codes.into_iter().zip(0..n).collect();
        order.par_sort_unstable();
        let mut nodes = vec![
            Node {
                aabb: Aabb::empty(),
                leaves: 0,
                index: 0,
            };
            2 * n - 1
        ];
        build_subtree(&mut nodes, &order, boxes);
        Bvh { nodes }
    }

    /// Number of primitives.
    #[inline]
    pub fn len(&self) -> usize {
        self.nodes.first().map_or(0, |n| n.leaves)
    }

    /// Whether the tree has no primitives.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Box of all primitives ([`Aabb::empty`] for an empty tree).
    #[inline]
    pub fn aabb(&self) -> Aabb {
        self.nodes.first().map_or_else(Aabb::empty, |n| n.aabb)
    }

    /// Updates all node boxes for new primitive boxes, keeping the topology (in parallel).
    ///
    /// Use this between Newton iterations or time steps when primitives move a little; rebuild
    /// when they have moved far, since the tree's quality degrades.
    ///
    /// # Errors
    /// [`GeometryError::LengthMismatch`] if `boxes.len()` differs from [`Bvh::len`].
    pub fn refit(&mut self, boxes: &[Aabb]) -> Result<(), GeometryError> {
        if boxes.len() != self.len() {
            return Err(GeometryError::LengthMismatch {
                what: "Bvh::refit boxes",
                expected: self.len(),
                found: boxes.len(),
            });
        }
        if !self.nodes.is_empty() {
            refit_subtree(&mut self.nodes, boxes);
        }
        Ok(())
    }

    /// Calls `callback(i)` for every primitive whose box intersects `query` (closed boxes:
    /// touching counts). The order is the tree's traversal order, which is deterministic.
    pub fn query_aabb(&self, query: &Aabb, mut callback: impl FnMut(usize)) {
        self.query_aabb_counted(query, &mut callback);
    }

    /// [`Bvh::query_aabb`] collected into a sorted vector.
    pub fn query_aabb_sorted(&self, query: &Aabb) -> Vec<usize> {
        let mut out = Vec::new();
        self.query_aabb(query, |i| out.push(i));
        out.sort_unstable();
        out
    }

    /// The traversal behind [`Bvh::query_aabb`]; returns the number of box tests.
    fn query_aabb_counted(&self, query: &Aabb, callback: &mut impl FnMut(usize)) -> u64 {
        let mut tests = 0;
        if self.nodes.is_empty() {
            return tests;
        }
        let mut stack = Vec::with_capacity(64);
        stack.push(0usize);
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            tests += 1;
            if !node.aabb.intersects(query) {
                continue;
            }
            if node.is_leaf() {
                callback(node.index);
            } else {
                stack.push(i + node.index);
                stack.push(i + 1);
            }
        }
        tests
    }

    /// All pairs `(i, j)`, `i < j`, of primitives whose boxes overlap after each is grown by
    /// `radius` (i.e. are within `2·radius` on every axis), sorted and without duplicates.
    ///
    /// Use `radius = 0` when the boxes were already inflated. Runs in parallel.
    pub fn self_pairs(&self, radius: f64) -> Vec<(usize, usize)> {
        self.self_pairs_counted(radius).0
    }

    /// [`Bvh::self_pairs`] plus the number of box–box tests made (for complexity tests).
    pub(crate) fn self_pairs_counted(&self, radius: f64) -> PairsAndTests {
        if self.nodes.len() < 2 {
            return (Vec::new(), 0);
        }
        let margin = 2.0 * radius.max(0.0);
        let (mut pairs, tests) = self.self_traverse(0, margin);
        pairs.par_sort_unstable();
        pairs.dedup();
        (pairs, tests)
    }

    /// [`Bvh::self_pairs`] restricted to the pairs `keep` accepts, as `u32` indices; the filter
    /// runs before the sort (in a mesh's self pairs most overlapping boxes are neighbours').
    pub fn self_pairs_where(&self, radius: f64, keep: impl Fn(usize, usize) -> bool + Sync) -> Vec<(u32, u32)> {
        if self.nodes.len() < 2 {
            return Vec::new();
        }
        let (pairs, _) = self.self_traverse(0, 2.0 * radius.max(0.0));
        sorted_kept(pairs, keep)
    }

    /// [`Bvh::pairs_with`] restricted to the pairs `keep` accepts, as `u32` indices; the filter
    /// runs before the sort.
    pub fn pairs_with_where(
        &self,
        other: &Bvh,
        radius: f64,
        keep: impl Fn(usize, usize) -> bool + Sync,
    ) -> Vec<(u32, u32)> {
        if self.nodes.is_empty() || other.nodes.is_empty() {
            return Vec::new();
        }
        let (pairs, _) = cross_traverse(self, 0, other, 0, 2.0 * radius.max(0.0), false);
        sorted_kept(pairs, keep)
    }

    /// All pairs `(i, j)` with `i` a primitive of `self` and `j` one of `other` whose boxes overlap
    /// after each is grown by `radius`, sorted by `(i, j)`. Runs in parallel.
    pub fn pairs_with(&self, other: &Bvh, radius: f64) -> Vec<(usize, usize)> {
        self.pairs_with_counted(other, radius).0
    }

    /// [`Bvh::pairs_with`] plus the number of box–box tests made.
    pub(crate) fn pairs_with_counted(&self, other: &Bvh, radius: f64) -> PairsAndTests {
        if self.nodes.is_empty() || other.nodes.is_empty() {
            return (Vec::new(), 0);
        }
        let margin = 2.0 * radius.max(0.0);
        let (mut pairs, tests) = cross_traverse(self, 0, other, 0, margin, false);
        pairs.par_sort_unstable();
        pairs.dedup();
        (pairs, tests)
    }

    /// Pairs within the subtree rooted at `node`: pairs inside each child plus pairs across them.
    fn self_traverse(&self, node: usize, margin: f64) -> PairsAndTests {
        let n = &self.nodes[node];
        if n.is_leaf() {
            return (Vec::new(), 0);
        }
        let (l, r) = (node + 1, node + n.index);
        if n.leaves > PARALLEL_LEAVES {
            let ((a, b), c) = rayon::join(
                || rayon::join(|| self.self_traverse(l, margin), || self.self_traverse(r, margin)),
                || cross_traverse(self, l, self, r, margin, true),
            );
            merge(merge(a, b), c)
        } else {
            let mut out = (Vec::new(), 0);
            self.self_traverse_seq(node, margin, &mut out);
            out
        }
    }

    /// Sequential version of [`Bvh::self_traverse`], appending to `out`: one explicit stack of
    /// node pairs, where `(i, i)` stands for the pairs within subtree `i`.
    fn self_traverse_seq(&self, node: usize, margin: f64, out: &mut PairsAndTests) {
        let mut stack = vec![(node, node)];
        traverse_stack(self, self, &mut stack, margin, true, out);
    }
}

/// Concatenates two partial results.
fn merge(mut a: PairsAndTests, b: PairsAndTests) -> PairsAndTests {
    a.0.extend(b.0);
    (a.0, a.1 + b.1)
}

/// Pairs between subtree `a` of tree `ta` and subtree `b` of tree `tb`; in parallel for large
/// subtrees. With `ordered`, pairs are reported as `(min, max)` (self-collision).
fn cross_traverse(ta: &Bvh, a: usize, tb: &Bvh, b: usize, margin: f64, ordered: bool) -> PairsAndTests {
    let (na, nb) = (&ta.nodes[a], &tb.nodes[b]);
    if na.leaves + nb.leaves <= PARALLEL_LEAVES {
        let mut out = (Vec::new(), 0);
        cross_traverse_seq(ta, a, tb, b, margin, ordered, &mut out);
        return out;
    }
    if !na.aabb.intersects_within(&nb.aabb, margin) {
        return (Vec::new(), 1);
    }
    let (x, y) = if !na.is_leaf() && (nb.is_leaf() || na.leaves >= nb.leaves) {
        rayon::join(
            || cross_traverse(ta, a + 1, tb, b, margin, ordered),
            || cross_traverse(ta, a + na.index, tb, b, margin, ordered),
        )
    } else {
        rayon::join(
            || cross_traverse(ta, a, tb, b + 1, margin, ordered),
            || cross_traverse(ta, a, tb, b + nb.index, margin, ordered),
        )
    };
    let (pairs, tests) = merge(x, y);
    (pairs, tests + 1)
}

/// The pairs `keep` accepts, sorted by `(i, j)` without duplicates (sorted as one `u64` key
/// each: indices fit in 32 bits, primitives are counted in `u32` elsewhere too).
fn sorted_kept(pairs: Vec<(usize, usize)>, keep: impl Fn(usize, usize) -> bool + Sync) -> Vec<(u32, u32)> {
    let mut keys: Vec<u64> = pairs
        .into_par_iter()
        .filter(|&(i, j)| keep(i, j))
        .map(|(i, j)| ((i as u64) << 32) | j as u64)
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    keys.into_iter().map(|k| ((k >> 32) as u32, k as u32)).collect()
}

/// Sequential simultaneous traversal of subtree `a` of `ta` and subtree `b` of `tb`.
fn cross_traverse_seq(ta: &Bvh, a: usize, tb: &Bvh, b: usize, margin: f64, ordered: bool, out: &mut PairsAndTests) {
    let mut stack = vec![(a, b)];
    traverse_stack(ta, tb, &mut stack, margin, ordered, out);
}

/// Runs the node pairs on `stack` until it is empty: overlapping pairs split the subtree with
/// more leaves, overlapping leaves are reported. A pair `(i, i)` (only when `ta` and `tb` are one
/// tree) stands for the pairs within subtree `i`: those of each child and those across them.
fn traverse_stack(
    ta: &Bvh,
    tb: &Bvh,
    stack: &mut Vec<(usize, usize)>,
    margin: f64,
    ordered: bool,
    out: &mut PairsAndTests,
) {
    let same_tree = std::ptr::eq(ta, tb);
    while let Some((a, b)) = stack.pop() {
        let (na, nb) = (&ta.nodes[a], &tb.nodes[b]);
        if same_tree && a == b {
            if !na.is_leaf() {
                let (l, r) = (a + 1, a + na.index);
                stack.push((l, r));
                stack.push((r, r));
                stack.push((l, l));
            }
            continue;
        }
        out.1 += 1;
        if !na.aabb.intersects_within(&nb.aabb, margin) {
            continue;
        }
        match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                let (i, j) = (na.index, nb.index);
                out.0.push(if ordered && j < i { (j, i) } else { (i, j) });
            }
            (false, true) => {
                stack.push((a + na.index, b));
                stack.push((a + 1, b));
            }
            (true, false) => {
                stack.push((a, b + nb.index));
                stack.push((a, b + 1));
            }
            (false, false) => {
                if na.leaves >= nb.leaves {
                    stack.push((a + na.index, b));
                    stack.push((a + 1, b));
                } else {
                    stack.push((a, b + nb.index));
                    stack.push((a, b + 1));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::aabb::triangle_aabb;
    use nalgebra::Vector3;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn random_boxes(rng: &mut StdRng, n: usize, size: f64) -> Vec<Aabb> {
        (0..n)
            .map(|_| {
                let c = Vector3::new(rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>());
                let h = Vector3::new(
                    rng.random_range(0.0..size),
                    rng.random_range(0.0..size),
                    rng.random_range(0.0..size),
                );
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    fn brute_self_pairs(boxes: &[Aabb], radius: f64) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if boxes[i].intersects_within(&boxes[j], 2.0 * radius) {
                    out.push((i, j));
                }
            }
        }
        out
    }

    fn brute_cross_pairs(a: &[Aabb], b: &[Aabb], radius: f64) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                if x.intersects_within(y, 2.0 * radius) {
                    out.push((i, j));
                }
            }
        }
        out
    }

    /// Checks the structural invariants: every primitive in exactly one leaf, parent boxes contain
    /// child boxes, leaf counts add up.
    fn check_tree(bvh: &Bvh, boxes: &[Aabb]) {
        assert_eq!(bvh.len(), boxes.len());
        assert_eq!(bvh.nodes.len(), (2 * boxes.len()).saturating_sub(1));
        let mut seen = vec![false; boxes.len()];
        for (i, n) in bvh.nodes.iter().enumerate() {
            if n.is_leaf() {
                assert!(!seen[n.index]);
                seen[n.index] = true;
                assert_eq!(n.aabb, boxes[n.index]);
            } else {
                let (l, r) = (&bvh.nodes[i + 1], &bvh.nodes[i + n.index]);
                assert_eq!(l.leaves + r.leaves, n.leaves);
                assert!(n.aabb.contains(&l.aabb) && n.aabb.contains(&r.aabb));
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn matches_brute_force_on_random_scenes() {
        let mut rng = StdRng::seed_from_u64(10);
        for &(n, size) in &[(1usize, 0.1), (2, 0.5), (17, 0.2), (300, 0.05), (3000, 0.01)] {
            let boxes = random_boxes(&mut rng, n, size);
            let bvh = Bvh::build(&boxes);
            check_tree(&bvh, &boxes);
            for &r in &[0.0, 0.01] {
                assert_eq!(bvh.self_pairs(r), brute_self_pairs(&boxes, r), "n = {n}, r = {r}");
            }
            let others = random_boxes(&mut rng, n / 2 + 1, size);
            let other = Bvh::build(&others);
            assert_eq!(bvh.pairs_with(&other, 0.005), brute_cross_pairs(&boxes, &others, 0.005));
            for _ in 0..20 {
                let q = random_boxes(&mut rng, 1, 0.2)[0];
                let expected: Vec<usize> = (0..n).filter(|&i| boxes[i].intersects(&q)).collect();
                assert_eq!(bvh.query_aabb_sorted(&q), expected);
            }
        }
    }

    #[test]
    fn refit_follows_moved_boxes() {
        let mut rng = StdRng::seed_from_u64(11);
        let boxes = random_boxes(&mut rng, 5000, 0.01);
        let mut bvh = Bvh::build(&boxes);
        let shift = Vector3::new(0.3, -0.2, 0.1);
        let moved: Vec<Aabb> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let s = if i % 3 == 0 { shift } else { Vector3::zeros() };
                Aabb::new(b.min + s, b.max + s)
            })
            .collect();
        bvh.refit(&moved).unwrap();
        check_tree(&bvh, &moved);
        assert_eq!(bvh.self_pairs(0.0), brute_self_pairs(&moved, 0.0));
        assert!(matches!(
            bvh.refit(&moved[1..]),
            Err(GeometryError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn degenerate_inputs() {
        // Empty tree.
        let empty = Bvh::build(&[]);
        assert!(empty.is_empty());
        assert_eq!(empty.len(), 0);
        assert!(empty.self_pairs(1.0).is_empty());
        assert!(empty.aabb().is_empty());
        empty.query_aabb(&Aabb::everything(), |_| panic!("no primitives"));
        // All boxes identical: every pair overlaps.
        let b = Aabb::new(Vector3::zeros(), Vector3::repeat(1.0));
        let same = vec![b; 50];
        let bvh = Bvh::build(&same);
        check_tree(&bvh, &same);
        assert_eq!(bvh.self_pairs(0.0).len(), 50 * 49 / 2);
        assert_eq!(bvh.pairs_with(&empty, 0.0), vec![]);
        // Non-finite boxes (from NaN vertices) overlap everything but the empty box.
        let mut boxes = random_boxes(&mut StdRng::seed_from_u64(12), 40, 0.05);
        boxes[7] = Aabb::everything();
        boxes[8] = Aabb::empty();
        let bvh = Bvh::build(&boxes);
        check_tree(&bvh, &boxes);
        let pairs = bvh.self_pairs(0.0);
        assert_eq!(pairs, brute_self_pairs(&boxes, 0.0));
        assert!(pairs.contains(&(7, 39)) && !pairs.iter().any(|&(i, j)| i == 8 || j == 8));
    }

    #[test]
    fn deterministic_across_thread_counts() {
        let boxes = random_boxes(&mut StdRng::seed_from_u64(13), 20_000, 0.004);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let (p1, t1) = one.install(|| Bvh::build(&boxes).self_pairs_counted(0.0));
        let (p2, t2) = Bvh::build(&boxes).self_pairs_counted(0.0);
        assert_eq!(p1, p2);
        assert_eq!(t1, t2);
    }

    /// A flat `n × n` grid of unit squares, two triangles each, in the z = 0 plane.
    fn grid_triangle_boxes(n: usize, radius: f64) -> Vec<Aabb> {
        let x = |i: usize, j: usize| Vector3::new(i as f64, j as f64, 0.0);
        let mut out = Vec::with_capacity(2 * n * n);
        for i in 0..n {
            for j in 0..n {
                out.push(triangle_aabb(&x(i, j), &x(i + 1, j), &x(i + 1, j + 1), radius));
                out.push(triangle_aabb(&x(i, j), &x(i + 1, j + 1), &x(i, j + 1), radius));
            }
        }
        out
    }

    #[test]
    fn box_tests_grow_like_n_log_n() {
        // N = 2·64² = 8192 and 4N = 32768 triangles.
        let count = |n: usize| {
            let boxes = grid_triangle_boxes(n, 0.1);
            let bvh = Bvh::build(&boxes);
            let (pairs, tests) = bvh.self_pairs_counted(0.0);
            (boxes.len(), pairs.len(), tests)
        };
        let (n1, p1, t1) = count(64);
        let (n4, p4, t4) = count(128);
        let ratio = t4 as f64 / t1 as f64;
        println!("N = {n1}: {t1} box tests, {p1} pairs; 4N = {n4}: {t4} box tests, {p4} pairs; ratio {ratio:.2}");
        // Output-sensitive: pairs grow linearly, box tests like N log N (ratio ≈ 4.6); quadratic
        // behaviour would give 16.
        assert!(ratio < 6.0, "ratio {ratio}");
        // And per primitive the work stays small.
        assert!((t4 as f64) < 200.0 * n4 as f64);
    }
}
