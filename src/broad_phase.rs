//! Broad phase in 2D: a uniform grid over the contact edges, built by sorting cell keys.
//!
//! Every contact edge `a` is registered in each grid cell that its axis-aligned bounding box,
//! inflated by a per-edge radius `r_a`, overlaps; a vertex `x` with radius `r_x` looks up the
//! cells its box `[ψ(x) − r_x, ψ(x) + r_x]` overlaps. Two boxes that do not overlap cannot hold a
//! pair with `dist(ψ(x), ψ(a)) ≤ r_x + r_a` (the Euclidean distance bounds the L∞ distance), so
//! the narrow phase ([`point_edge_distance`], exact) sees every such pair.
//!
//! The grid is a sorted vector of `(cell key, edge)` entries (no hash map): building it is a
//! parallel sort, a lookup a binary search, and the output order (vertex, then edge index) does
//! not depend on the number of rayon threads. The cell size defaults to the larger of the mean
//! edge length and twice the mean edge radius, so an edge spans O(1) cells and a cell holds
//! O(1) edges on the quasi-uniform meshes of the scenes.
//!
//! The same names run through the layers: `point_edge` pairs here, in [`crate::pairs`], in the
//! rows of T(ψ) ([`crate::rows`]) and in the diagnostics.

use crate::geometry::{edge_edge_distance_2d, point_edge_distance};
use crate::mesh::Mesh;
use crate::pairs::{ClosestPair, MinDistance, PointEdgePair};
use rayon::prelude::*;

/// A `point_edge` pair found by the broad phase, with its exact distance at the queried state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearPair {
    /// The pair.
    pub pair: PointEdgePair,
    /// `dist(ψ(x), ψ(a))` (not squared).
    pub distance: f64,
}

/// Uniform grid over the (inflated) contact edges at one state. See the module documentation.
pub struct EdgeGrid {
    cell: f64,
    origin: [f64; 2],
    nx: u64,
    ny: u64,
    keys: Vec<u64>,
    edges: Vec<u32>,
}

fn edge_box(x: &[f64], e: [usize; 2], r: f64) -> ([f64; 2], [f64; 2]) {
    let (a, b) = (Mesh::p2(x, e[0]), Mesh::p2(x, e[1]));
    (
        [a.x.min(b.x) - r, a.y.min(b.y) - r],
        [a.x.max(b.x) + r, a.y.max(b.y) + r],
    )
}

impl EdgeGrid {
    /// Registers every contact edge `a` of `mesh` at state `x`, inflated by `r_edge[a]`.
    /// `cell = None` picks the default cell size (module documentation).
    pub fn build(mesh: &Mesh, x: &[f64], r_edge: &[f64], cell: Option<f64>) -> EdgeGrid {
        let ne = mesh.edges.len();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut len_sum = 0.0;
        let mut r_sum = 0.0;
        for (a, &e) in mesh.edges.iter().enumerate() {
            let (l, h) = edge_box(x, e, r_edge[a]);
            for c in 0..2 {
                lo[c] = lo[c].min(l[c]);
                hi[c] = hi[c].max(h[c]);
            }
            len_sum += (Mesh::p2(x, e[0]) - Mesh::p2(x, e[1])).norm();
            r_sum += r_edge[a];
        }
        if ne == 0 {
            return EdgeGrid {
                cell: 1.0,
                origin: [0.0; 2],
                nx: 1,
                ny: 1,
                keys: Vec::new(),
                edges: Vec::new(),
            };
        }
        let nef = ne as f64;
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
        let mut cell = cell.unwrap_or((len_sum / nef).max(2.0 * r_sum / nef));
        // Keep the key space in u64 and the grid at most ~4·10⁶ cells a side.
        cell = cell.max(extent / 4.0e6).max(f64::MIN_POSITIVE);
        let nx = ((hi[0] - lo[0]) / cell).floor() as u64 + 1;
        let ny = ((hi[1] - lo[1]) / cell).floor() as u64 + 1;
        let mut grid = EdgeGrid {
            cell,
            origin: lo,
            nx,
            ny,
            keys: Vec::new(),
            edges: Vec::new(),
        };
        let mut entries: Vec<(u64, u32)> = (0..ne)
            .into_par_iter()
            .flat_map_iter(|a| {
                let (l, h) = edge_box(x, mesh.edges[a], r_edge[a]);
                let (i0, i1, j0, j1) = grid.cell_range(l, h);
                let ny = grid.ny;
                (i0..=i1).flat_map(move |i| (j0..=j1).map(move |j| (i * ny + j, a as u32)))
            })
            .collect();
        entries.par_sort_unstable();
        grid.keys = entries.iter().map(|e| e.0).collect();
        grid.edges = entries.iter().map(|e| e.1).collect();
        grid
    }

    /// Cell index range `(i0, i1, j0, j1)` (inclusive) of the box `[lo, hi]`, clamped to the grid.
    fn cell_range(&self, lo: [f64; 2], hi: [f64; 2]) -> (u64, u64, u64, u64) {
        let idx = |v: f64, o: f64, n: u64| -> u64 {
            let k = ((v - o) / self.cell).floor();
            if k.is_nan() || k < 0.0 {
                0
            } else {
                (k as u64).min(n - 1)
            }
        };
        (
            idx(lo[0], self.origin[0], self.nx),
            idx(hi[0], self.origin[0], self.nx),
            idx(lo[1], self.origin[1], self.ny),
            idx(hi[1], self.origin[1], self.ny),
        )
    }

    /// Appends to `out` every edge registered in a cell that the box `[lo, hi]` overlaps,
    /// sorted and without repetition.
    pub fn edges_in_box(&self, lo: [f64; 2], hi: [f64; 2], out: &mut Vec<u32>) {
        let start = out.len();
        let (i0, i1, j0, j1) = self.cell_range(lo, hi);
        for i in i0..=i1 {
            // Cells (i, j0..=j1) have consecutive keys.
            let k0 = i * self.ny + j0;
            let k1 = i * self.ny + j1;
            let p0 = self.keys.partition_point(|&k| k < k0);
            let p1 = self.keys.partition_point(|&k| k <= k1);
            out.extend_from_slice(&self.edges[p0..p1]);
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

    /// Number of (cell, edge) entries (memory diagnostics).
    pub fn entries(&self) -> usize {
        self.keys.len()
    }
}

/// Every `point_edge` pair `(x, a)`, `x ∉ a`, of contact vertex `x` and contact edge `a` with
/// `dist(x(x), x(a)) ≤ r_vertex[x] + r_edge[a]`, with its exact distance, sorted by vertex then
/// edge. `r_vertex` may be empty (all zero). With `skip_fixed`, pairs whose three vertices are
/// fixed are left out (their rows are constant: SPEC §2).
pub fn point_edge_near(
    mesh: &Mesh,
    x: &[f64],
    r_vertex: &[f64],
    r_edge: &[f64],
    skip_fixed: bool,
) -> Vec<NearPair> {
    let grid = EdgeGrid::build(mesh, x, r_edge, None);
    point_edge_near_in(&grid, mesh, x, r_vertex, r_edge, skip_fixed)
}

/// [`point_edge_near`] on a grid already built with the same `r_edge`.
pub fn point_edge_near_in(
    grid: &EdgeGrid,
    mesh: &Mesh,
    x: &[f64],
    r_vertex: &[f64],
    r_edge: &[f64],
    skip_fixed: bool,
) -> Vec<NearPair> {
    let verts = mesh.contact_vertices();
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
            grid.edges_in_box([p.x - rv, p.y - rv], [p.x + rv, p.y + rv], buf);
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

/// The first pair (smallest `(a, b)`, `a < b`) of disjoint contact edges that intersect at `x`
/// (distance 0), if any. Only a crossing can make two disjoint edges closer than their
/// `point_edge` pairs, so this completes the exact admissibility check.
///
/// With `skip_fixed`, pairs of edges whose four vertices are fixed are not tested.
pub fn first_crossing(mesh: &Mesh, x: &[f64], skip_fixed: bool) -> Option<(usize, usize)> {
    let zero = vec![0.0; mesh.edges.len()];
    let grid = EdgeGrid::build(mesh, x, &zero, None);
    (0..mesh.edges.len())
        .into_par_iter()
        .map_init(Vec::new, |buf: &mut Vec<u32>, a| {
            let ea = mesh.edges[a];
            let (lo, hi) = edge_box(x, ea, 0.0);
            buf.clear();
            grid.edges_in_box(lo, hi, buf);
            for &b in buf.iter() {
                let b = b as usize;
                if b <= a {
                    continue;
                }
                let eb = mesh.edges[b];
                if ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1] {
                    continue;
                }
                if skip_fixed && [ea[0], ea[1], eb[0], eb[1]].iter().all(|&v| mesh.fixed[v]) {
                    continue;
                }
                let d = edge_edge_distance_2d(
                    &Mesh::p2(x, ea[0]),
                    &Mesh::p2(x, ea[1]),
                    &Mesh::p2(x, eb[0]),
                    &Mesh::p2(x, eb[1]),
                );
                if d == 0.0 {
                    return Some((a, b));
                }
            }
            None
        })
        .flatten()
        .min()
}

/// Exact minimum distance over the disjoint pairs of contact elements at `x`, through the broad
/// phase: the `point_edge` pairs within a radius `r` (starting at `r0`, multiplied by 4 until
/// some pair is found, so the minimum found is the global one) and the crossing test. With
/// `skip_fixed`, pairs whose vertices are all fixed are not checked (they were checked once at
/// the start). The same value as [`crate::pairs::check_admissible`] over the same pairs.
pub fn min_distance_near(mesh: &Mesh, x: &[f64], r0: f64, skip_fixed: bool) -> MinDistance {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Body, BodyKind};
    use crate::pairs::{check_admissible, point_edge_pairs};
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
        }
    }

    /// Brute force: every pair with `d ≤ r_x + r_a`, by direct enumeration.
    fn brute(mesh: &Mesh, x: &[f64], rv: &[f64], re: &[f64], skip_fixed: bool) -> Vec<NearPair> {
        let mut out = Vec::new();
        for v in mesh.contact_vertices() {
            for (a, e) in mesh.edges.iter().enumerate() {
                if v == e[0] || v == e[1] {
                    continue;
                }
                if skip_fixed && mesh.fixed[v] && mesh.fixed[e[0]] && mesh.fixed[e[1]] {
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
    fn min_distance_near_matches_all_pairs_check() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut crossings = 0;
        for _ in 0..100 {
            let per = rng.gen_range(3..8);
            let mesh = random_mesh(&mut rng, 3, per);
            let x = mesh.x_ref.clone();
            let (movable, fixed) = point_edge_pairs(&mesh);
            let want = check_admissible(&mesh, &x, &movable, &fixed);
            let got = min_distance_near(&mesh, &x, 1e-3, false);
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
    fn first_crossing_finds_a_planted_crossing_and_ignores_shared_vertices() {
        // Two edges forming an X, plus a V sharing a vertex.
        let x = vec![
            0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 2.0, 0.0, 3.0, 1.0, 4.0, 0.0,
        ];
        let mesh = Mesh {
            dim: 2,
            x_ref: x.clone(),
            fixed: vec![false; 7],
            edges: vec![[0, 1], [2, 3], [4, 5], [5, 6]],
            edge_body: vec![0, 1, 2, 2],
            triangles: vec![],
            bodies: vec![],
        };
        assert_eq!(first_crossing(&mesh, &x, false), Some((0, 1)));
        let mut y = x.clone();
        y[7] = 2.0; // vertex 3 moved to (1, 2): edge [2, 3] parallel to edge [0, 1]
        assert_eq!(first_crossing(&mesh, &y, false), None);
    }
}
