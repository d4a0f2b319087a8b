//! A bounding volume hierarchy ([`Bvh`]) over axis-aligned boxes in `D` dimensions, with the
//! same contract as the uniform grid [`AabbGrid`](crate::contact::broad_phase::AabbGrid): items are
//! registered by index, and a query appends the items whose boxes overlap the query box,
//! sorted and without repetition. Unlike the grid, the answer is exact: every box tested
//! against the query box (closed intervals: `lo_i ≤ q.hi` and `q.lo ≤ hi_i` on every axis),
//! never a superset.
//!
//! The tree is binary. A node of more than [`LEAF_SIZE`] (4) items is split at the median of
//! its items' box centroids along the longest axis of the centroids' bounding box (the
//! `⌊m/2⌋` items with the smallest centroid coordinate go left, ties broken by item index,
//! found by `select_nth_unstable_by`: O(m) per node, O(n log n) for the build); a node of at
//! most 4 items is a leaf. Since every split is at the median, the shape of the tree depends
//! only on `n`, so the nodes are laid out in preorder in one flat `Vec` whose size is known in
//! advance, and the two subtrees of a large node are built in parallel (rayon) into disjoint
//! slices of it: the result does not depend on the number of threads. The items (and their
//! boxes, for the exact test) are stored in leaf order, so each leaf is a contiguous run.
//!
//! A query is an iterative depth-first traversal with a fixed stack of node indices.
//!
//! The pair search of [`crate::contact::broad_phase`] uses this tree: the bench `broad_phase/structure`
//! in `benches/pruning.rs` measured it as fast as the grid at 10³ and 10⁴ elements per membrane
//! and 1.4× faster at 10⁵.

use crate::contact::broad_phase::Aabb;

/// Maximum number of items in a leaf.
pub const LEAF_SIZE: usize = 4;

/// Subtrees of at least this many items are built with `rayon::join` (smaller ones serially).
const PAR_MIN_ITEMS: usize = 4096;

/// Capacity of the traversal stack. The depth of a tree of `n ≤ 2³²` items is at most
/// `⌈log₂(n / 4)⌉ ≤ 31`, and the stack never holds more than depth + 1 nodes.
const STACK: usize = 64;

/// One node, in preorder: an internal node's left child is the next node.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node<const D: usize> {
    /// Bounding box of every item below.
    lo: [f64; D],
    hi: [f64; D],
    /// Leaf: position of its first item in [`Bvh::items`]; internal: index of the right child.
    index: u32,
    /// Leaf: number of items (1..=[`LEAF_SIZE`]); internal: 0.
    count: u32,
}

/// An item during the build: the centroid of its box and its index.
#[derive(Clone, Copy)]
struct Entry<const D: usize> {
    centroid: [f64; D],
    item: u32,
}

/// Output length of one part of [`Bvh::dual_reduced`] below which it is not reduced (tiny in
/// the unit tests, so that they reduce in the middle of a part too).
const PART_REDUCE_MIN: usize = if cfg!(test) { 4 } else { 4096 };

/// A bounding volume hierarchy over axis-aligned boxes (module documentation): built by median
/// splits, queried exactly.
#[derive(Clone, Debug)]
pub struct Bvh<const D: usize> {
    nodes: Vec<Node<D>>,
    /// Item indices in leaf order.
    items: Vec<u32>,
    /// `boxes[k]` is the box of `items[k]`.
    boxes: Vec<Aabb<D>>,
}

/// Closed-interval overlap of `[alo, ahi]` and `[blo, bhi]` (false if a bound is NaN).
#[inline]
fn overlaps<const D: usize>(
    alo: &[f64; D],
    ahi: &[f64; D],
    blo: &[f64; D],
    bhi: &[f64; D],
) -> bool {
    (0..D).all(|c| alo[c] <= bhi[c] && blo[c] <= ahi[c])
}

/// Number of leaves of the tree over `m` items: subtrees of `s` and `s + 1` items only occur
/// at each depth, so this counts them level by level (O(log m)).
fn leaf_count(m: usize) -> usize {
    if m == 0 {
        return 0;
    }
    // `a` pending subtrees of `s` items and `b` of `s + 1` items.
    let (mut s, mut a, mut b) = (m, 1usize, 0usize);
    let mut leaves = 0;
    loop {
        if s < LEAF_SIZE {
            return leaves + a + b;
        }
        if s == LEAF_SIZE {
            leaves += a;
            a = 0;
        }
        // A subtree of `k` items splits into `⌊k/2⌋` and `k − ⌊k/2⌋`.
        let h = s / 2;
        (a, b) = if s % 2 == 0 {
            // s = 2h → (h, h); s + 1 = 2h + 1 → (h, h + 1).
            (2 * a + b, b)
        } else {
            // s = 2h + 1 → (h, h + 1); s + 1 = 2h + 2 → (h + 1, h + 1).
            (a, a + 2 * b)
        };
        s = h;
    }
}

/// Number of nodes of the tree over `m` items.
fn tree_size(m: usize) -> usize {
    match m {
        0 => 0,
        _ => 2 * leaf_count(m) - 1,
    }
}

/// Builds the subtree of `entries` into `nodes` (exactly `tree_size(entries.len())` nodes,
/// the first of global index `base`); `first` is the global position of `entries[0]`.
fn build_node<const D: usize>(
    nodes: &mut [Node<D>],
    base: usize,
    entries: &mut [Entry<D>],
    first: usize,
    boxes: &[Aabb<D>],
) {
    debug_assert_eq!(nodes.len(), tree_size(entries.len()));
    let m = entries.len();
    if m <= LEAF_SIZE {
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        for e in entries.iter() {
            let (l, h) = &boxes[e.item as usize];
            for c in 0..D {
                lo[c] = lo[c].min(l[c]);
                hi[c] = hi[c].max(h[c]);
            }
        }
        nodes[0] = Node {
            lo,
            hi,
            index: first as u32,
            count: m as u32,
        };
        return;
    }
    // Longest axis of the centroids' bounds (NaN centroids are ignored by min/max).
    let (mut clo, mut chi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
    for e in entries.iter() {
        for c in 0..D {
            clo[c] = clo[c].min(e.centroid[c]);
            chi[c] = chi[c].max(e.centroid[c]);
        }
    }
    let mut axis = 0;
    for c in 1..D {
        if chi[c] - clo[c] > chi[axis] - clo[axis] {
            axis = c;
        }
    }
    let mid = m / 2;
    entries.select_nth_unstable_by(mid, |p, q| {
        p.centroid[axis]
            .total_cmp(&q.centroid[axis])
            .then(p.item.cmp(&q.item))
    });
    let (left, right) = entries.split_at_mut(mid);
    let (this, rest) = nodes.split_first_mut().expect("m > 0");
    let (lnodes, rnodes) = rest.split_at_mut(tree_size(mid));
    let rbase = base + 1 + lnodes.len();
    if m >= PAR_MIN_ITEMS {
        rayon::join(
            || build_node(lnodes, base + 1, left, first, boxes),
            || build_node(rnodes, rbase, right, first + mid, boxes),
        );
    } else {
        build_node(lnodes, base + 1, left, first, boxes);
        build_node(rnodes, rbase, right, first + mid, boxes);
    }
    let (l, r) = (&lnodes[0], &rnodes[0]);
    *this = Node {
        lo: std::array::from_fn(|c| l.lo[c].min(r.lo[c])),
        hi: std::array::from_fn(|c| l.hi[c].max(r.hi[c])),
        index: rbase as u32,
        count: 0,
    };
}

impl<const D: usize> Bvh<D> {
    /// Registers `boxes[i]` as item `i` (at most `u32::MAX` items).
    pub fn build(boxes: &[Aabb<D>]) -> Bvh<D> {
        assert!(
            boxes.len() <= u32::MAX as usize,
            "Bvh: more than u32::MAX boxes"
        );
        let mut entries: Vec<Entry<D>> = boxes
            .iter()
            .enumerate()
            .map(|(i, (l, h))| Entry {
                centroid: std::array::from_fn(|c| 0.5 * l[c] + 0.5 * h[c]),
                item: i as u32,
            })
            .collect();
        let placeholder = Node {
            lo: [0.0; D],
            hi: [0.0; D],
            index: 0,
            count: 0,
        };
        let mut nodes = vec![placeholder; tree_size(boxes.len())];
        if !boxes.is_empty() {
            build_node(&mut nodes, 0, &mut entries, 0, boxes);
        }
        let items: Vec<u32> = entries.iter().map(|e| e.item).collect();
        let boxes = items.iter().map(|&i| boxes[i as usize]).collect();
        Bvh {
            nodes,
            items,
            boxes,
        }
    }

    /// Appends to `out` every item whose box overlaps the box `[lo, hi]` (closed intervals;
    /// exactly those), sorted and without repetition.
    pub fn query(&self, lo: &[f64; D], hi: &[f64; D], out: &mut Vec<u32>) {
        if self.nodes.is_empty() {
            return;
        }
        let start = out.len();
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let i = stack[top] as usize;
            let node = &self.nodes[i];
            if !overlaps(&node.lo, &node.hi, lo, hi) {
                continue;
            }
            if node.count > 0 {
                let k0 = node.index as usize;
                for k in k0..k0 + node.count as usize {
                    let (l, h) = &self.boxes[k];
                    if overlaps(l, h, lo, hi) {
                        out.push(self.items[k]);
                    }
                }
            } else {
                // Right child below the left one: the left subtree is visited first.
                stack[top] = node.index;
                stack[top + 1] = (i + 1) as u32;
                top += 2;
            }
        }
        // Each item lies in exactly one leaf: sorting is enough for uniqueness.
        out[start..].sort_unstable();
    }

    /// Number of nodes (memory diagnostics).
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// The box of node `i` (preorder index; 0 is the root).
    #[inline]
    pub fn node_box(&self, i: usize) -> ([f64; D], [f64; D]) {
        (self.nodes[i].lo, self.nodes[i].hi)
    }

    /// Per-node boxes of another quantity of the items (e.g. their displacements): node `i`'s
    /// box bounds `item_box(k)` over every item `k` below it. Children follow their parent in
    /// preorder, so one pass from the last node to the first computes them.
    pub fn refit<const E: usize>(&self, item_box: impl Fn(u32) -> Aabb<E>) -> Vec<Aabb<E>> {
        let empty = ([f64::INFINITY; E], [f64::NEG_INFINITY; E]);
        let mut out = vec![empty; self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let node = &self.nodes[i];
            let mut b = empty;
            let mut add = |(l, h): Aabb<E>| {
                for c in 0..E {
                    b.0[c] = b.0[c].min(l[c]);
                    b.1[c] = b.1[c].max(h[c]);
                }
            };
            if node.count > 0 {
                let k0 = node.index as usize;
                for &item in &self.items[k0..k0 + node.count as usize] {
                    add(item_box(item));
                }
            } else {
                add(out[i + 1]);
                add(out[node.index as usize]);
            }
            out[i] = b;
        }
        out
    }

    /// Dual traversal of `self` and `other` (or of `self` with itself when `other` is `None`):
    /// node pairs `(i, j)` (`i` of `self`, `j` of the other tree) for which `keep(i, j)` holds
    /// are refined down to their leaves, and `leaf(a, b, out)` is called for every item pair
    /// of two kept leaves (with itself: every unordered pair of distinct items once). `keep`
    /// must be conservative: false only when no item pair below `(i, j)` is wanted. The work
    /// is split into independent node pairs processed in parallel; the results are
    /// concatenated in a fixed order, so they do not depend on the number of threads.
    pub fn dual<R: Send>(
        &self,
        other: Option<&Bvh<D>>,
        keep: &(dyn Fn(usize, usize) -> bool + Sync),
        leaf: &(dyn Fn(u32, u32, &mut Vec<R>) + Sync),
    ) -> Vec<R> {
        self.dual_reduced(other, keep, leaf, &|_| {})
    }

    /// [`Bvh::dual`], with `part(out)` applied to the output of each independent part of the
    /// traversal before the parts are concatenated, and whenever that output has doubled since
    /// the last call: a reduction that may be applied to any prefix (keep the best item per
    /// key) bounds the memory by the reduced outputs instead of every item found.
    pub fn dual_reduced<R: Send>(
        &self,
        other: Option<&Bvh<D>>,
        keep: &(dyn Fn(usize, usize) -> bool + Sync),
        leaf: &(dyn Fn(u32, u32, &mut Vec<R>) + Sync),
        part: &(dyn Fn(&mut Vec<R>) + Sync),
    ) -> Vec<R> {
        let same = other.is_none();
        let other = other.unwrap_or(self);
        if self.nodes.is_empty() || other.nodes.is_empty() {
            return Vec::new();
        }
        // Node pairs refined breadth-first until there are enough for the threads.
        let mut frontier: Vec<(usize, usize)> = vec![(0, 0)];
        for _ in 0..64 {
            if frontier.len() >= 512 {
                break;
            }
            let mut next = Vec::with_capacity(4 * frontier.len());
            let mut split = false;
            for &(i, j) in &frontier {
                if !keep(i, j) {
                    continue;
                }
                let before = next.len();
                self.children_pairs(other, same, i, j, &mut next);
                if next.len() == before {
                    next.push((i, j));
                } else {
                    split = true;
                }
            }
            frontier = next;
            if !split {
                break;
            }
        }
        use rayon::prelude::*;
        let parts: Vec<Vec<R>> = frontier
            .par_iter()
            .map(|&start| {
                let mut out = Vec::new();
                let mut limit = PART_REDUCE_MIN;
                let mut stack = vec![start];
                let mut kids = Vec::with_capacity(4);
                while let Some((i, j)) = stack.pop() {
                    if out.len() > limit {
                        part(&mut out);
                        limit = (2 * out.len()).max(PART_REDUCE_MIN);
                    }
                    if !keep(i, j) {
                        continue;
                    }
                    kids.clear();
                    self.children_pairs(other, same, i, j, &mut kids);
                    if kids.is_empty() {
                        let (a, b) = (&self.nodes[i], &other.nodes[j]);
                        let (a0, b0) = (a.index as usize, b.index as usize);
                        for ka in a0..a0 + a.count as usize {
                            let kb0 = if same && i == j { ka + 1 } else { b0 };
                            for kb in kb0..b0 + b.count as usize {
                                leaf(self.items[ka], other.items[kb], &mut out);
                            }
                        }
                    } else {
                        // reversed, so that the pairs are visited in the order listed
                        stack.extend(kids.iter().rev());
                    }
                }
                part(&mut out);
                out
            })
            .collect();
        parts.into_iter().flatten().collect()
    }

    /// The node pairs `(i, j)` refines into (none for two leaves): the larger internal node is
    /// split (a leaf against an internal node splits the internal one); with itself, `(i, i)`
    /// gives `(l, l)`, `(l, r)`, `(r, r)`.
    fn children_pairs(
        &self,
        other: &Bvh<D>,
        same: bool,
        i: usize,
        j: usize,
        out: &mut Vec<(usize, usize)>,
    ) {
        let (a, b) = (&self.nodes[i], &other.nodes[j]);
        let (a_leaf, b_leaf) = (a.count > 0, b.count > 0);
        if a_leaf && b_leaf {
            return;
        }
        if same && i == j {
            let (l, r) = (i + 1, a.index as usize);
            out.extend([(l, l), (l, r), (r, r)]);
            return;
        }
        let extent = |n: &Node<D>| (0..D).map(|c| n.hi[c] - n.lo[c]).fold(0.0f64, f64::max);
        let split_a = !a_leaf && (b_leaf || extent(a) >= extent(b));
        if split_a {
            out.extend([(i + 1, j), (a.index as usize, j)]);
        } else {
            out.extend([(i, j + 1), (i, b.index as usize)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::broad_phase::AabbGrid;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute<const D: usize>(boxes: &[Aabb<D>], lo: &[f64; D], hi: &[f64; D]) -> Vec<u32> {
        (0..boxes.len())
            .filter(|&i| (0..D).all(|c| boxes[i].0[c] <= hi[c] && lo[c] <= boxes[i].1[c]))
            .map(|i| i as u32)
            .collect()
    }

    /// `n` boxes in about `[0, 1]^D`: small ones, zero-size ones, duplicates, a few huge ones;
    /// coordinates on a 1/32 lattice with probability 1/2, so that many boxes touch.
    fn random_boxes<const D: usize>(rng: &mut ChaCha8Rng, n: usize) -> Vec<Aabb<D>> {
        let mut boxes: Vec<Aabb<D>> = Vec::with_capacity(n);
        for _ in 0..n {
            let kind = rng.gen_range(0..20);
            if kind == 0 && !boxes.is_empty() {
                let j = rng.gen_range(0..boxes.len());
                boxes.push(boxes[j]);
                continue;
            }
            let snap = rng.gen_bool(0.5);
            let c: [f64; D] = std::array::from_fn(|_| {
                let v = rng.gen_range(0.0..1.0);
                if snap {
                    (v * 32.0f64).round() / 32.0
                } else {
                    v
                }
            });
            let r: [f64; D] = match kind {
                1..=4 => [0.0; D],
                5 => std::array::from_fn(|_| rng.gen_range(0.5..2.0)),
                _ => std::array::from_fn(|_| {
                    let v = rng.gen_range(0.0..0.05);
                    if snap {
                        (v * 32.0f64).round() / 32.0
                    } else {
                        v
                    }
                }),
            };
            boxes.push((
                std::array::from_fn(|k| c[k] - r[k]),
                std::array::from_fn(|k| c[k] + r[k]),
            ));
        }
        boxes
    }

    /// Random query boxes: points, small and large boxes, boxes that touch a registered box.
    fn random_query<const D: usize>(rng: &mut ChaCha8Rng, boxes: &[Aabb<D>]) -> Aabb<D> {
        let kind = rng.gen_range(0..6);
        if kind == 0 && !boxes.is_empty() {
            // Touching a box at a corner: its `hi` as the query's `lo`, or its `lo` as `hi`.
            let b = boxes[rng.gen_range(0..boxes.len())];
            let r = rng.gen_range(0.0..0.1);
            return if rng.gen_bool(0.5) {
                (b.1, b.1.map(|v| v + r))
            } else {
                (b.0.map(|v| v - r), b.0)
            };
        }
        let c: [f64; D] = std::array::from_fn(|_| {
            let v = rng.gen_range(-0.2..1.2);
            if rng.gen_bool(0.3) {
                (v * 32.0f64).round() / 32.0
            } else {
                v
            }
        });
        let r = match kind {
            1 | 2 => 0.0,
            3 => rng.gen_range(0.5..3.0),
            _ => rng.gen_range(0.0..0.1),
        };
        (c.map(|v| v - r), c.map(|v| v + r))
    }

    /// Tree invariants: sizes, leaf sizes, nested boxes, each item once.
    fn check_structure<const D: usize>(bvh: &Bvh<D>, boxes: &[Aabb<D>]) {
        assert_eq!(bvh.nodes.len(), tree_size(boxes.len()));
        let mut seen = vec![false; boxes.len()];
        let contains = |o: &Node<D>, lo: &[f64; D], hi: &[f64; D]| {
            (0..D).all(|c| o.lo[c] <= lo[c] && hi[c] <= o.hi[c])
        };
        for (i, n) in bvh.nodes.iter().enumerate() {
            if n.count > 0 {
                assert!(n.count as usize <= LEAF_SIZE);
                for k in n.index as usize..(n.index + n.count) as usize {
                    let item = bvh.items[k] as usize;
                    assert!(!seen[item], "item {item} twice");
                    seen[item] = true;
                    assert_eq!(bvh.boxes[k], boxes[item]);
                    assert!(contains(n, &boxes[item].0, &boxes[item].1));
                }
            } else {
                let (l, r) = (&bvh.nodes[i + 1], &bvh.nodes[n.index as usize]);
                assert!(n.index as usize > i + 1);
                assert!(contains(n, &l.lo, &l.hi) && contains(n, &r.lo, &r.hi));
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    fn check_against_brute_force<const D: usize>(seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut found = 0;
        let mut touching = 0;
        for n in [0, 1, 2, 3, 4, 5, 7, 8, 9, 17, 64, 100, 333, 1000, 5000] {
            let boxes = random_boxes::<D>(&mut rng, n);
            let bvh = Bvh::build(&boxes);
            check_structure(&bvh, &boxes);
            let grids = [
                AabbGrid::build(&boxes, None),
                AabbGrid::build(&boxes, Some(0.01)),
            ];
            let (mut got, mut coarse) = (Vec::new(), Vec::new());
            for _ in 0..300 {
                let q = random_query(&mut rng, &boxes);
                // The query appends after existing content, which it leaves alone.
                got.clear();
                got.extend([u32::MAX, 7]);
                bvh.query(&q.0, &q.1, &mut got);
                assert_eq!(&got[..2], &[u32::MAX, 7]);
                let want = brute(&boxes, &q.0, &q.1);
                assert_eq!(&got[2..], &want[..], "n {n}, query {q:?}");
                found += want.len();
                touching += want
                    .iter()
                    .filter(|&&i| {
                        let b = &boxes[i as usize];
                        (0..D).any(|c| b.0[c] == q.1[c] || b.1[c] == q.0[c])
                    })
                    .count();
                // The grid returns a superset of the exact answer.
                for grid in &grids {
                    coarse.clear();
                    grid.query(&q.0, &q.1, &mut coarse);
                    for i in &want {
                        assert!(coarse.binary_search(i).is_ok(), "grid misses {i}");
                    }
                }
            }
        }
        assert!(found > 100_000, "too few overlaps tested: {found}");
        assert!(touching > 500, "too few touching boxes tested: {touching}");
    }

    #[test]
    fn bvh_2d_query_matches_brute_force_and_grid_contains_it() {
        check_against_brute_force::<2>(1);
    }

    #[test]
    fn bvh_3d_query_matches_brute_force_and_grid_contains_it() {
        check_against_brute_force::<3>(2);
    }

    #[test]
    fn bvh_empty_input_returns_nothing() {
        let bvh = Bvh::<2>::build(&[]);
        assert_eq!(bvh.nodes(), 0);
        let mut out = vec![3];
        bvh.query(&[f64::NEG_INFINITY; 2], &[f64::INFINITY; 2], &mut out);
        assert_eq!(out, vec![3]);
    }

    #[test]
    fn bvh_all_equal_boxes() {
        // Identical centroids: the median split falls back to item order.
        let boxes = vec![([0.25, 0.5], [0.25, 0.5]); 1000];
        let bvh = Bvh::build(&boxes);
        check_structure(&bvh, &boxes);
        let mut out = Vec::new();
        bvh.query(&[0.25, 0.5], &[0.25, 0.5], &mut out);
        assert_eq!(out, (0..1000).collect::<Vec<u32>>());
        out.clear();
        bvh.query(&[0.0, 0.0], &[0.2, 1.0], &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn bvh_infinite_and_nan_boxes() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut boxes = random_boxes::<2>(&mut rng, 500);
        boxes[10] = ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]);
        boxes[20] = ([0.5, f64::NEG_INFINITY], [0.5, 0.5]);
        boxes[30] = ([f64::NAN, 0.0], [1.0, 1.0]);
        boxes[40] = ([f64::NAN; 2], [f64::NAN; 2]);
        let bvh = Bvh::build(&boxes);
        let mut out = Vec::new();
        for _ in 0..300 {
            let q = random_query(&mut rng, &boxes);
            out.clear();
            bvh.query(&q.0, &q.1, &mut out);
            assert_eq!(out, brute(&boxes, &q.0, &q.1), "query {q:?}");
            assert!(out.binary_search(&10).is_ok());
            assert!(out.binary_search(&30).is_err() && out.binary_search(&40).is_err());
        }
    }

    #[test]
    fn bvh_build_is_independent_of_thread_count() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let boxes = random_boxes::<2>(&mut rng, 6 * PAR_MIN_ITEMS + 123);
        let build = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool")
                .install(|| Bvh::build(&boxes))
        };
        let (a, b) = (build(1), build(4));
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.items, b.items);
        check_structure(&a, &boxes);
    }

    #[test]
    fn tree_size_matches_the_recursive_definition() {
        fn leaves(m: usize) -> usize {
            match m {
                0 => 0,
                1..=LEAF_SIZE => 1,
                _ => leaves(m / 2) + leaves(m - m / 2),
            }
        }
        for m in 0..5000 {
            assert_eq!(leaf_count(m), leaves(m), "m = {m}");
        }
        for m in [65_535, 65_536, 65_537, 1_000_003] {
            assert_eq!(leaf_count(m), leaves(m), "m = {m}");
        }
    }

    /// The dual traversal finds exactly the overlapping item pairs, between two trees and
    /// within one (each unordered pair once), whatever the thread count.
    #[test]
    fn dual_traversal_equals_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for n in [0usize, 1, 3, 5, 40, 700] {
            let a: Vec<Aabb<2>> = random_boxes(&mut rng, n);
            let b: Vec<Aabb<2>> = random_boxes(&mut rng, n / 2 + 3);
            let (ta, tb) = (Bvh::build(&a), Bvh::build(&b));
            let ov = |x: &Aabb<2>, y: &Aabb<2>| overlaps(&x.0, &x.1, &y.0, &y.1);
            let keep_ab = |i: usize, j: usize| {
                let (x, y) = (ta.node_box(i), tb.node_box(j));
                ov(&x, &y)
            };
            let leaf_ab = |p: u32, q: u32, out: &mut Vec<(u32, u32)>| {
                if ov(&a[p as usize], &b[q as usize]) {
                    out.push((p, q));
                }
            };
            let mut got = ta.dual(Some(&tb), &keep_ab, &leaf_ab);
            got.sort_unstable();
            let mut want = Vec::new();
            for (p, bp) in a.iter().enumerate() {
                for (q, bq) in b.iter().enumerate() {
                    if ov(bp, bq) {
                        want.push((p as u32, q as u32));
                    }
                }
            }
            assert_eq!(got, want, "n = {n}");
            let keep_aa = |i: usize, j: usize| ov(&ta.node_box(i), &ta.node_box(j));
            let leaf_aa = |p: u32, q: u32, out: &mut Vec<(u32, u32)>| {
                if ov(&a[p as usize], &a[q as usize]) {
                    out.push((p.min(q), p.max(q)));
                }
            };
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let serial = one.install(|| ta.dual(None, &keep_aa, &leaf_aa));
            let mut got = ta.dual(None, &keep_aa, &leaf_aa);
            assert_eq!(got, serial, "thread-count independent, n = {n}");
            got.sort_unstable();
            let mut want = Vec::new();
            for (p, bp) in a.iter().enumerate() {
                for (q, bq) in a.iter().enumerate().skip(p + 1) {
                    if ov(bp, bq) {
                        want.push((p as u32, q as u32));
                    }
                }
            }
            assert_eq!(got, want, "self, n = {n}");
        }
    }

    /// `refit` bounds every item's box in every node's subtree.
    #[test]
    fn refit_bounds_the_items_below_each_node() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let a: Vec<Aabb<2>> = random_boxes(&mut rng, 300);
        let t = Bvh::build(&a);
        let other: Vec<Aabb<3>> = (0..300)
            .map(|i| {
                let v = [i as f64, -(i as f64), (i % 7) as f64];
                (v, v)
            })
            .collect();
        let fit = t.refit(|k| other[k as usize]);
        assert_eq!(fit.len(), t.nodes());
        // the root bounds everything, tightly
        assert_eq!(fit[0].0, [0.0, -299.0, 0.0]);
        assert_eq!(fit[0].1, [299.0, 0.0, 6.0]);
        // a leaf bounds exactly its own items
        for (i, node) in t.nodes.iter().enumerate() {
            if node.count > 0 {
                let k0 = node.index as usize;
                for &item in &t.items[k0..k0 + node.count as usize] {
                    let (l, h) = other[item as usize];
                    for c in 0..3 {
                        assert!(fit[i].0[c] <= l[c] && h[c] <= fit[i].1[c]);
                    }
                }
            }
        }
    }
}
