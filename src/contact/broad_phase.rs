//! Broad phase: the pairs of contact elements closer than a radius, in either dimension,
//! through an index over axis-aligned boxes; the narrow phase (the kernels of
//! [`super::distance`], exact) then sees every such pair. It serves the pair search of the rows
//! of T(ψ) (eq. 4 in 2D, eq. 6 in 3D) and the exact admissibility check of every iterate
//! ([`super::admissibility::min_distance`], implemented here by [`min_distance_2d`] and
//! [`min_distance_3d`]).
//!
//! | dim | search | pairs |
//! |---|---|---|
//! | 2 | [`point_edge_near`] | `point_edge` within `r_x + r_a` (per-vertex and per-edge radii) |
//! | 2 | [`first_crossing`] (in [`super::edge_edge`]) | crossing `edge_edge` pairs |
//! | 3 | [`near_pairs_3d`] | `point_triangle` and `edge_edge` within `r` |
//! | 3 | [`min_distance_3d`] | also an edge through a face |
//!
//! Two structures with one contract (register boxes by index; a query returns the overlapping
//! items sorted, without repetition) exist in any dimension: a uniform grid built by sorting
//! cell keys ([`AabbGrid`]) and a bounding volume hierarchy ([`crate::contact::bvh::Bvh`]). The
//! pair searches use the BVH ([`edge_index`]): on the balloons scene the bench
//! `broad_phase/structure` of `benches/pruning.rs` (build plus one query per vertex) measured
//! them equal at 10³ and 10⁴ elements per membrane and the BVH 1.4× faster at 10⁵. The grid
//! stays for comparison and for scenes where it may win.
//!
//! In 2D every contact edge `a` is registered with its axis-aligned bounding box inflated by a
//! per-edge radius `r_a`; a vertex `x` with radius `r_x` queries the box
//! `[ψ(x) − r_x, ψ(x) + r_x]`. Two boxes that do not overlap cannot hold a pair with
//! `dist(ψ(x), ψ(a)) ≤ r_x + r_a` (the Euclidean distance bounds the L∞ distance), so the narrow
//! phase ([`point_edge_distance`]) sees every such pair. In 3D the triangles and the edges are
//! registered with their boxes, and a vertex or an edge queries its box inflated by `r`.
//!
//! The grid is a sorted vector of `(cell key, item)` entries (no hash map): building it is a
//! parallel sort, a lookup a binary search per run of cells. The cell size defaults to the mean
//! largest side of the registered boxes, so a box spans O(1) cells and a cell holds O(1) boxes
//! on the quasi-uniform meshes of the scenes. The output is sorted (vertex, then element
//! index), so it does not depend on the number of rayon threads.

use super::admissibility::{segment_meets_triangle, Closest3};
pub use super::edge_edge::first_crossing;
use super::p3;
use crate::contact::bvh::Bvh;
use crate::contact::distance::{edge_edge_distance, point_edge_distance, point_triangle_distance};
use crate::contact::{ClosestPair, MinDistance, PointEdgePair};
use crate::scene::mesh::{ContactFilter, Mesh};
use rayon::prelude::*;

/// A `point_edge` pair found by the broad phase, with its exact distance at the queried state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearPair {
    /// The pair.
    pub pair: PointEdgePair,
    /// `dist(ψ(x), ψ(a))` (not squared).
    pub distance: f64,
}

/// A uniform grid over axis-aligned boxes in `D` dimensions. Items are registered by
/// index; a query returns the items of every cell the query box overlaps, sorted, without
/// repetition. A box that would span more than [`MAX_CELLS_PER_BOX`] cells (one vertex moving
/// far in a lazy check) goes to a short list returned by every query instead, so one outlier
/// cannot blow the grid up.
pub struct AabbGrid<const D: usize> {
    cell: f64,
    origin: [f64; D],
    dims: [u64; D],
    keys: Vec<u64>,
    items: Vec<u32>,
    big: Vec<u32>,
}

/// See [`AabbGrid`].
pub const MAX_CELLS_PER_BOX: u64 = 4096;

/// An axis-aligned box `(lo, hi)`.
pub type Aabb<const D: usize> = ([f64; D], [f64; D]);

/// The box of the 2D edge `e` at `x`, inflated by `r`.
pub(crate) fn edge_box(x: &[f64], e: [usize; 2], r: f64) -> Aabb<2> {
    let (a, b) = (Mesh::p2(x, e[0]), Mesh::p2(x, e[1]));
    (
        [a.x.min(b.x) - r, a.y.min(b.y) - r],
        [a.x.max(b.x) + r, a.y.max(b.y) + r],
    )
}

impl<const D: usize> AabbGrid<D> {
    /// Registers `boxes[i]` as item `i`. `cell = None` picks the mean largest side of the boxes
    /// (module documentation).
    pub fn build(boxes: &[Aabb<D>], cell: Option<f64>) -> AabbGrid<D> {
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        let mut side_sum = 0.0;
        for (l, h) in boxes {
            let mut side: f64 = 0.0;
            for c in 0..D {
                lo[c] = lo[c].min(l[c]);
                hi[c] = hi[c].max(h[c]);
                side = side.max(h[c] - l[c]);
            }
            side_sum += side;
        }
        let mut grid = AabbGrid {
            cell: 1.0,
            origin: [0.0; D],
            dims: [1; D],
            keys: Vec::new(),
            items: Vec::new(),
            big: Vec::new(),
        };
        if boxes.is_empty() || lo.iter().chain(&hi).any(|v| !v.is_finite()) {
            grid.big = (0..boxes.len() as u32).collect();
            return grid;
        }
        let extent = (0..D)
            .map(|c| hi[c] - lo[c])
            .fold(f64::MIN_POSITIVE, f64::max);
        // At most 2^(62/D) cells a side, so that keys fit in u64.
        let max_side = 2f64.powf(62.0 / D as f64);
        grid.cell = cell
            .unwrap_or(side_sum / boxes.len() as f64)
            .max(extent / max_side)
            .max(f64::MIN_POSITIVE);
        grid.origin = lo;
        for c in 0..D {
            grid.dims[c] = ((hi[c] - lo[c]) / grid.cell).floor() as u64 + 1;
        }
        let cells: Vec<Option<([u64; D], [u64; D])>> = boxes
            .par_iter()
            .map(|(l, h)| {
                let r = grid.cell_range(l, h);
                let count = (0..D).fold(1u64, |n, c| n.saturating_mul(r.1[c] - r.0[c] + 1));
                (count <= MAX_CELLS_PER_BOX).then_some(r)
            })
            .collect();
        grid.big = (0..boxes.len())
            .filter(|&i| cells[i].is_none())
            .map(|i| i as u32)
            .collect();
        let mut entries: Vec<(u64, u32)> = (0..boxes.len())
            .into_par_iter()
            .flat_map_iter(|i| {
                let mut out = Vec::new();
                if let Some((r0, r1)) = cells[i] {
                    grid.for_each_run(&r0, &r1, |k0, k1| {
                        out.extend((k0..=k1).map(|k| (k, i as u32)));
                    });
                }
                out
            })
            .collect();
        entries.par_sort_unstable();
        grid.keys = entries.iter().map(|e| e.0).collect();
        grid.items = entries.iter().map(|e| e.1).collect();
        grid
    }

    /// Inclusive cell index range of the box `[lo, hi]`, clamped to the grid.
    fn cell_range(&self, lo: &[f64; D], hi: &[f64; D]) -> ([u64; D], [u64; D]) {
        let idx = |v: f64, c: usize| -> u64 {
            let k = ((v - self.origin[c]) / self.cell).floor();
            if k.is_nan() || k < 0.0 {
                0
            } else {
                (k as u64).min(self.dims[c] - 1)
            }
        };
        (
            std::array::from_fn(|c| idx(lo[c], c)),
            std::array::from_fn(|c| idx(hi[c].max(lo[c]), c)),
        )
    }

    /// Calls `f(k0, k1)` for each run of consecutive keys of the cell range `[r0, r1]`: the
    /// last coordinate varies fastest, so each choice of the others is one run.
    fn for_each_run(&self, r0: &[u64; D], r1: &[u64; D], mut f: impl FnMut(u64, u64)) {
        let mut idx = *r0;
        loop {
            let mut k0 = 0u64;
            for (i, d) in idx.iter().zip(&self.dims[1..]) {
                k0 = (k0 + i) * d;
            }
            let k1 = k0 + r1[D - 1];
            f(k0 + r0[D - 1], k1);
            // Odometer over the coordinates 0..D-1.
            let mut c = D - 1;
            loop {
                if c == 0 {
                    return;
                }
                c -= 1;
                if idx[c] < r1[c] {
                    idx[c] += 1;
                    break;
                }
                idx[c] = r0[c];
            }
        }
    }

    /// Appends to `out` every item registered in a cell that the box `[lo, hi]` overlaps (and
    /// every oversized item), sorted and without repetition.
    pub fn query(&self, lo: &[f64; D], hi: &[f64; D], out: &mut Vec<u32>) {
        let start = out.len();
        out.extend_from_slice(&self.big);
        if !self.keys.is_empty() {
            let (r0, r1) = self.cell_range(lo, hi);
            self.for_each_run(&r0, &r1, |k0, k1| {
                let p0 = self.keys.partition_point(|&k| k < k0);
                let p1 = self.keys.partition_point(|&k| k <= k1);
                out.extend_from_slice(&self.items[p0..p1]);
            });
        }
        out[start..].sort_unstable();
        let mut w = start;
        for r in start..out.len() {
            if w == start || out[r] != out[w - 1] {
                out[w] = out[r];
                w += 1;
            }
        }
        out.truncate(w);
    }

    /// Number of (cell, item) entries (memory diagnostics).
    pub fn entries(&self) -> usize {
        self.keys.len()
    }
}

/// The index of the contact edges of `mesh` at `x`, edge `a` inflated by `r_edge[a]`: a
/// [`Bvh`], chosen over [`AabbGrid`] by the `broad_phase/structure` bench (module
/// documentation).
pub fn edge_index(mesh: &Mesh, x: &[f64], r_edge: &[f64]) -> Bvh<2> {
    let boxes: Vec<Aabb<2>> = mesh
        .edges
        .par_iter()
        .enumerate()
        .map(|(a, &e)| edge_box(x, e, r_edge[a]))
        .collect();
    Bvh::build(&boxes)
}

/// Every `point_edge` pair `(x, a)`, `x ∉ a`, of contact vertex `x` and contact edge `a` with
/// `dist(x(x), x(a)) ≤ r_vertex[x] + r_edge[a]`, with its exact distance, sorted by vertex then
/// edge. `r_vertex` may be empty (all zero). With `skip_fixed`, pairs whose three vertices are
/// fixed are left out (their rows are constant: checked once, at the start).
pub fn point_edge_near(
    mesh: &Mesh,
    x: &[f64],
    r_vertex: &[f64],
    r_edge: &[f64],
    skip_fixed: bool,
) -> Vec<NearPair> {
    let index = edge_index(mesh, x, r_edge);
    point_edge_near_in(&index, mesh, x, r_vertex, r_edge, skip_fixed)
}

/// [`point_edge_near`] on an edge index already built with the same `r_edge`.
pub fn point_edge_near_in(
    index: &Bvh<2>,
    mesh: &Mesh,
    x: &[f64],
    r_vertex: &[f64],
    r_edge: &[f64],
    skip_fixed: bool,
) -> Vec<NearPair> {
    let verts = mesh.contact_vertices();
    let filter = mesh.filter();
    let per_vertex: Vec<Vec<NearPair>> = verts
        .par_iter()
        .map_init(Vec::new, |buf: &mut Vec<u32>, &v| {
            let rv = if r_vertex.is_empty() {
                0.0
            } else {
                r_vertex[v]
            };
            let p = Mesh::p2(x, v);
            buf.clear();
            index.query(&[p.x - rv, p.y - rv], &[p.x + rv, p.y + rv], buf);
            let mut out = Vec::new();
            for &a in buf.iter() {
                let a = a as usize;
                let e = mesh.edges[a];
                if v == e[0] || v == e[1] {
                    continue;
                }
                if skip_fixed && mesh.fixed[v] && mesh.fixed[e[0]] && mesh.fixed[e[1]] {
                    continue;
                }
                if filter.is_some_and(|f| !f.point_edge(v, a)) {
                    continue;
                }
                let d = point_edge_distance(&p, &Mesh::p2(x, e[0]), &Mesh::p2(x, e[1])).distance;
                if d <= rv + r_edge[a] {
                    out.push(NearPair {
                        pair: PointEdgePair { x: v, a },
                        distance: d,
                    });
                }
            }
            out
        })
        .collect();
    per_vertex.into_iter().flatten().collect()
}

/// The exact check of [`crate::contact::admissibility::min_distance`] in 2D: the crossing test
/// ([`first_crossing`]), then the `point_edge` pairs within a radius `r` (starting at `r0`,
/// multiplied by 4 until some pair is found, so the minimum found is the global one). With
/// `skip_fixed`, pairs whose vertices are all fixed are not checked (they were checked once at
/// the start).
pub fn min_distance_2d(mesh: &Mesh, x: &[f64], r0: f64, skip_fixed: bool) -> MinDistance {
    let mut best = MinDistance {
        distance: f64::INFINITY,
        pair: ClosestPair::None,
    };
    if let Some((a, b)) = first_crossing(mesh, x, skip_fixed) {
        return MinDistance {
            distance: 0.0,
            pair: ClosestPair::EdgeEdge { a, b },
        };
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in mesh.contact_vertices() {
        for c in 0..2 {
            lo[c] = lo[c].min(x[2 * v + c]);
            hi[c] = hi[c].max(x[2 * v + c]);
        }
    }
    let diam = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt();
    let mut r = if r0 > 0.0 && r0.is_finite() { r0 } else { diam };
    loop {
        let re = vec![r; mesh.edges.len()];
        let near = point_edge_near(mesh, x, &[], &re, skip_fixed);
        for np in &near {
            if np.distance < best.distance {
                let e = mesh.edges[np.pair.a];
                best = MinDistance {
                    distance: np.distance,
                    pair: ClosestPair::PointEdge {
                        x: np.pair.x,
                        a: np.pair.a,
                        a0: e[0],
                        a1: e[1],
                    },
                };
            }
        }
        if !(near.is_empty() && r > 0.0 && r <= diam) {
            return best;
        }
        r *= 4.0;
    }
}

/// Disjoint element pairs closer than a radius, found through the BVH of
/// [`crate::contact::bvh::Bvh`]: the 3D broad phase. Sorted, so the result does not depend on the
/// thread count.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NearPairs3 {
    /// `(vertex, triangle index, distance)`, sorted by vertex then triangle.
    pub point_triangle: Vec<(usize, usize, f64)>,
    /// `(edge a, edge b, distance)` with `a < b`, sorted.
    pub edge_edge: Vec<(usize, usize, f64)>,
}

/// The box of the vertices `vs` at `x`, inflated by `r`.
fn bbox(x: &[f64], vs: &[usize], r: f64) -> Aabb<3> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in vs {
        for c in 0..3 {
            lo[c] = lo[c].min(x[3 * v + c] - r);
            hi[c] = hi[c].max(x[3 * v + c] + r);
        }
    }
    (lo, hi)
}

/// Every disjoint `point_triangle` pair (`vertices` × `triangles`, x ∉ T) and `edge_edge` pair
/// (a ∩ b = ∅) at distance `< r` that `filter` allows (`None`: all pairs; an excluded pair is
/// dropped before its distance is computed), through a BVH over the triangles' and the edges'
/// boxes.
pub fn near_pairs_3d(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    r: f64,
    filter: Option<&ContactFilter>,
) -> NearPairs3 {
    let mut out = NearPairs3::default();
    let mut hits = Vec::new();
    let tbox: Vec<_> = triangles.iter().map(|t| bbox(x, t, 0.0)).collect();
    let tb = Bvh::<3>::build(&tbox);
    for &v in vertices {
        let (lo, hi) = bbox(x, &[v], r);
        hits.clear();
        tb.query(&lo, &hi, &mut hits);
        for &ti in &hits {
            let t = triangles[ti as usize];
            if t.contains(&v) || filter.is_some_and(|f| !f.point_triangle(v, ti as usize)) {
                continue;
            }
            let d = point_triangle_distance(&p3(x, v), &p3(x, t[0]), &p3(x, t[1]), &p3(x, t[2]))
                .distance;
            if d < r {
                out.point_triangle.push((v, ti as usize, d));
            }
        }
    }
    let ebox: Vec<_> = edges.iter().map(|e| bbox(x, e, 0.0)).collect();
    let eb = Bvh::<3>::build(&ebox);
    for (ai, a) in edges.iter().enumerate() {
        let (lo, hi) = bbox(x, a, r);
        hits.clear();
        eb.query(&lo, &hi, &mut hits);
        for &bi in &hits {
            let bi = bi as usize;
            let b = edges[bi];
            if bi <= ai
                || a.iter().any(|v| b.contains(v))
                || filter.is_some_and(|f| !f.edge_edge(ai, bi))
            {
                continue;
            }
            let d =
                edge_edge_distance(&p3(x, a[0]), &p3(x, a[1]), &p3(x, b[0]), &p3(x, b[1])).distance;
            if d < r {
                out.edge_edge.push((ai, bi, d));
            }
        }
    }
    out.point_triangle.sort_by_key(|p| (p.0, p.1));
    out.edge_edge.sort_by_key(|p| (p.0, p.1));
    out
}

/// The exact check of [`crate::contact::admissibility::min_distance`] in 3D, over the pairs of
/// contact elements the mesh's contact filter allows: an edge through a triangle among
/// overlapping boxes (distance 0), then the near pairs ([`near_pairs_3d`]) within a radius that
/// starts at `r0` (> 0) and grows ×4 until a pair is found. Returns the closest pair by index.
pub fn min_distance_3d(mesh: &Mesh, x: &[f64], r0: f64) -> (f64, Closest3) {
    let (vertices, edges, triangles) = (&mesh.contact_vertices(), &mesh.edges, &mesh.faces);
    let filter = mesh.filter();
    let tbox: Vec<_> = triangles.iter().map(|t| bbox(x, t, 0.0)).collect();
    let tb = Bvh::<3>::build(&tbox);
    let mut hits = Vec::new();
    for (ai, e) in edges.iter().enumerate() {
        let (lo, hi) = bbox(x, e, 0.0);
        hits.clear();
        tb.query(&lo, &hi, &mut hits);
        for &ti in &hits {
            let t = triangles[ti as usize];
            if e.iter().any(|v| t.contains(v))
                || filter.is_some_and(|f| !f.edge_face(ai, ti as usize))
            {
                continue;
            }
            if segment_meets_triangle(
                &p3(x, e[0]),
                &p3(x, e[1]),
                &p3(x, t[0]),
                &p3(x, t[1]),
                &p3(x, t[2]),
            ) {
                return (
                    0.0,
                    Closest3::EdgeThroughTriangle {
                        a: ai,
                        t: ti as usize,
                    },
                );
            }
        }
    }
    // the diameter of the configuration bounds every distance
    let all: Vec<usize> = (0..x.len() / 3).collect();
    let (lo, hi) = bbox(x, &all, 0.0);
    let diam = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt();
    let mut r = r0.max(f64::MIN_POSITIVE);
    loop {
        let near = near_pairs_3d(x, vertices, edges, triangles, r, filter);
        let mut best = (f64::INFINITY, Closest3::None);
        for &(v, t, d) in &near.point_triangle {
            if d < best.0 {
                best = (d, Closest3::PointTriangle { x: v, t });
            }
        }
        for &(a, b, d) in &near.edge_edge {
            if d < best.0 {
                best = (d, Closest3::EdgeEdge { a, b });
            }
        }
        if best.0.is_finite() || r > 2.0 * diam + 1.0 {
            return best;
        }
        r *= 4.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::min_distance_brute_force;
    use crate::scene::mesh::{Body, BodyKind};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Random polylines (some closed) with a few fixed vertices.
    fn random_mesh(rng: &mut ChaCha8Rng, curves: usize, per: usize) -> Mesh {
        let mut x = Vec::new();
        let mut edges = Vec::new();
        let mut edge_body = Vec::new();
        let mut bodies = Vec::new();
        for b in 0..curves {
            let first = x.len() / 2;
            let (cx, cy) = (rng.gen_range(0.0..1.0), rng.gen_range(0.0..1.0));
            for _ in 0..per {
                x.push(cx + rng.gen_range(-0.3..0.3));
                x.push(cy + rng.gen_range(-0.3..0.3));
            }
            let closed = b % 2 == 0;
            let ne = if closed { per } else { per - 1 };
            let mut be = Vec::new();
            for i in 0..ne {
                edges.push([first + i, first + (i + 1) % per]);
                edge_body.push(b);
                be.push(edges.len() - 1);
            }
            bodies.push(Body {
                name: format!("c{b}"),
                kind: BodyKind::Curve,
                h: 0.1,
                vertices: (first..first + per).collect(),
                edges: be,
                triangles: vec![],
                ..Default::default()
            });
        }
        let nv = x.len() / 2;
        let fixed = (0..nv).map(|_| rng.gen_bool(0.3)).collect();
        Mesh {
            dim: 2,
            x_ref: x,
            fixed,
            edges,
            edge_body,
            triangles: vec![],
            bodies,
            ..Default::default()
        }
    }

    /// Brute force: every pair with `d ≤ r_x + r_a`, by direct enumeration.
    fn brute(mesh: &Mesh, x: &[f64], rv: &[f64], re: &[f64], skip_fixed: bool) -> Vec<NearPair> {
        let mut out = Vec::new();
        let filter = mesh.filter();
        for v in mesh.contact_vertices() {
            for (a, e) in mesh.edges.iter().enumerate() {
                if v == e[0] || v == e[1] {
                    continue;
                }
                if skip_fixed && mesh.fixed[v] && mesh.fixed[e[0]] && mesh.fixed[e[1]] {
                    continue;
                }
                if filter.is_some_and(|f| !f.point_edge(v, a)) {
                    continue;
                }
                let d =
                    point_edge_distance(&Mesh::p2(x, v), &Mesh::p2(x, e[0]), &Mesh::p2(x, e[1]))
                        .distance;
                if d <= rv[v] + re[a] {
                    out.push(NearPair {
                        pair: PointEdgePair { x: v, a },
                        distance: d,
                    });
                }
            }
        }
        out
    }

    #[test]
    fn point_edge_near_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut found = 0;
        for trial in 0..60 {
            let per = rng.gen_range(3..12);
            let mesh = random_mesh(&mut rng, 4, per);
            let x = mesh.x_ref.clone();
            let nv = mesh.nv();
            let scale = [0.0, 0.01, 0.1, 0.5][trial % 4];
            let rv: Vec<f64> = (0..nv).map(|_| rng.gen_range(0.0..=scale)).collect();
            let re: Vec<f64> = (0..mesh.edges.len())
                .map(|_| rng.gen_range(0.0..=scale))
                .collect();
            for skip in [false, true] {
                let got = point_edge_near(&mesh, &x, &rv, &re, skip);
                let want = brute(&mesh, &x, &rv, &re, skip);
                assert_eq!(got, want, "trial {trial} skip_fixed {skip}");
                found += got.len();
            }
        }
        assert!(found > 500, "the test barely exercises the grid: {found}");
    }

    #[test]
    fn min_distance_2d_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut crossings = 0;
        for _ in 0..100 {
            let per = rng.gen_range(3..8);
            let mesh = random_mesh(&mut rng, 3, per);
            let x = mesh.x_ref.clone();
            let want = min_distance_brute_force(&mesh, &x);
            let got = min_distance_2d(&mesh, &x, 1e-3, false);
            assert_eq!(got.distance, want.distance);
            if want.distance == 0.0 {
                crossings += 1;
                assert!(matches!(got.pair, ClosestPair::EdgeEdge { .. }));
            } else if let ClosestPair::PointEdge { x: v, a0, a1, .. } = got.pair {
                // Ties may name another pair: check that the named pair attains the minimum.
                let d = point_edge_distance(&Mesh::p2(&x, v), &Mesh::p2(&x, a0), &Mesh::p2(&x, a1))
                    .distance;
                assert_eq!(d, want.distance);
            } else {
                panic!("no pair named: {:?}", got.pair);
            }
        }
        assert!(crossings > 10, "too few crossing cases: {crossings}");
    }

    #[test]
    fn aabb_grid_3d_query_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let boxes: Vec<Aabb<3>> = (0..400)
            .map(|i| {
                let c: [f64; 3] = std::array::from_fn(|_| rng.gen_range(0.0..1.0));
                // A few oversized boxes exercise the `big` list.
                let r = if i % 97 == 0 {
                    0.9
                } else {
                    rng.gen_range(0.0..0.05)
                };
                (c.map(|v| v - r), c.map(|v| v + r))
            })
            .collect();
        let grid = AabbGrid::build(&boxes, Some(0.01));
        assert!(!grid.big.is_empty(), "no oversized box in the test");
        let overlap =
            |a: &Aabb<3>, b: &Aabb<3>| (0..3).all(|c| a.0[c] <= b.1[c] && b.0[c] <= a.1[c]);
        let mut found = 0;
        for _ in 0..200 {
            let c: [f64; 3] = std::array::from_fn(|_| rng.gen_range(-0.1..1.1));
            let r = rng.gen_range(0.0..0.1);
            let q = (c.map(|v| v - r), c.map(|v| v + r));
            let mut got = Vec::new();
            grid.query(&q.0, &q.1, &mut got);
            // Every overlapping box is returned (the grid may return more: same cells).
            for (i, b) in boxes.iter().enumerate() {
                if overlap(b, &q) {
                    assert!(got.binary_search(&(i as u32)).is_ok(), "box {i} missed");
                    found += 1;
                }
            }
            assert!(got.windows(2).all(|w| w[0] < w[1]), "not sorted/unique");
        }
        assert!(found > 200, "too few overlaps tested: {found}");
    }
}
