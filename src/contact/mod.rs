//! Contact pairs and the rows of T(ψ) in either dimension: the one interface the sub-problem,
//! the outer loop and the diagnostics use.
//!
//! Every row of T(ψ) has the form `n · (φ(plus) − φ(minus)) ≥ ε`, `n` a unit vector frozen at
//! ψ. A pair of disjoint contact elements gives a group of rows with one normal:
//!
//! | pair | dim | rows (`plus`, `minus`) | normal |
//! |---|---|---|---|
//! | `point_edge`: vertex x, edge a | 2 | `(a_i, x)`, i = 0, 1 (eq. 4) | from ψ(x) to the closest point of ψ(a) |
//! | `point_triangle`: vertex x, face T | 3 | `(t_i, x)`, i = 0, 1, 2 (eq. 6) | from ψ(x) to the closest point of ψ(T) |
//! | `edge_edge`: edges a, b | 3 | `(b_j, a_i)`, i, j = 0, 1 (eq. 6) | from the closest point of ψ(a) to that of ψ(b) |
//!
//! By Lemma 4.2 (in 3D with the `edge_edge` rows, Remark 4.3) every φ satisfying the rows is
//! admissible. Each row also carries the barycentric weight of its vertex pair in the closest
//! points (`α_i`, `β_i`, `(1 − s, s)_i·(1 − t, t)_j`); the weights sum to 1 and give the
//! contact force of Lemma 5.6 (computed by the harness's diagnostics).
//!
//! One module per pair kind, named as the kernels of [`distance`]: [`point_edge`],
//! [`point_triangle`], [`edge_edge`], each with its enumeration (the all-pairs mode) and its
//! rows. The broad phase (near-pair searches in both dimensions, the grid, the BVH, the boxes)
//! is [`broad_phase`] and [`bvh`]; the exact admissibility check of every iterate is
//! [`admissibility::min_distance`].
//!
//! The 2D rows are built exactly as [`crate::contact::point_edge_row`] (same floating-point
//! operations), so 2D results do not depend on which interface built them.

pub mod admissibility;
pub mod broad_phase;
pub mod bvh;
pub mod continuous;
pub mod distance;
pub mod edge_edge;
pub mod hessian;
pub mod motion;
pub mod point_edge;
pub mod point_triangle;

pub use admissibility::{
    min_distance, min_distance_brute_force, segment_meets_triangle, Closest3, ClosestPair,
    MinDistance,
};
pub use broad_phase::{near_pairs_3d, NearPairs3};
pub use edge_edge::{edge_edge_pairs, edge_edge_rows};
pub use point_edge::{
    min_slack, point_edge_pairs, point_edge_row, point_edge_rows, PointEdgePair, PointEdgeRow,
};
pub use point_triangle::{point_triangle_pairs, point_triangle_rows};

use self::broad_phase::point_edge_near;
use self::distance::{edge_edge_distance, point_edge_distance, point_triangle_distance};
use crate::scene::mesh::Mesh;
use nalgebra::Vector3;
use rayon::prelude::*;

/// The hasher of the sets of pairs that the pair searches query once per candidate (the lazy
/// oracle's carried pairs, the SQP step's carried and seen pairs): the multiply–rotate hash of
/// rustc's `FxHasher` ([`contactlab_solvers::hash`]), on the pair's kind and indices.
pub use contactlab_solvers::hash::FxHasher as PairHasher;

/// A set of pairs hashed by [`PairHasher`].
pub type PairSet =
    std::collections::HashSet<ContactPair, std::hash::BuildHasherDefault<PairHasher>>;

/// A pair of disjoint contact elements. Ordered (kind, then indices), hashable: the key of
/// the warm-start duals across outer steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ContactPair {
    /// 2D: vertex `x`, contact edge `a` (index into [`Mesh::edges`]), `x ∉ a`.
    PointEdge {
        /// Vertex.
        x: usize,
        /// Edge index.
        a: usize,
    },
    /// 3D: vertex `x`, contact face `t` (index into [`Mesh::faces`]), `x ∉ t`.
    PointTriangle {
        /// Vertex.
        x: usize,
        /// Face index.
        t: usize,
    },
    /// 3D: contact edges `a < b` (indices into [`Mesh::edges`]), `a ∩ b = ∅`.
    EdgeEdge {
        /// First edge.
        a: usize,
        /// Second edge.
        b: usize,
    },
}

impl ContactPair {
    /// `point_edge`, `vertex_triangle` or `edge_edge`: the pair kind in contacts.csv and
    /// multipliers.csv (`PointTriangle` keeps the name the files had before the renaming).
    pub fn kind(&self) -> &'static str {
        match self {
            ContactPair::PointEdge { .. } => "point_edge",
            ContactPair::PointTriangle { .. } => "vertex_triangle",
            ContactPair::EdgeEdge { .. } => "edge_edge",
        }
    }

    /// The two element indices: (vertex, edge), (vertex, face) or (edge a, edge b).
    pub fn indices(&self) -> (usize, usize) {
        match *self {
            ContactPair::PointEdge { x, a } => (x, a),
            ContactPair::PointTriangle { x, t } => (x, t),
            ContactPair::EdgeEdge { a, b } => (a, b),
        }
    }
}

impl From<PointEdgePair> for ContactPair {
    fn from(p: PointEdgePair) -> Self {
        ContactPair::PointEdge { x: p.x, a: p.a }
    }
}

/// The rows of one contact pair, frozen at ψ: `n · (φ(plus[i]) − φ(minus[i])) ≥ ε` for
/// `i < len`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairRows {
    /// The pair.
    pub pair: ContactPair,
    /// Unit normal at ψ (`z = 0` in 2D).
    pub n: Vector3<f64>,
    /// Far-side vertex of each row.
    pub plus: [usize; 4],
    /// Near-side vertex of each row.
    pub minus: [usize; 4],
    /// Number of rows: 2 (`point_edge`), 3 (`point_triangle`) or 4 (`edge_edge`).
    pub len: usize,
    /// `dist` of the pair at ψ.
    pub distance: f64,
    /// Barycentric weight of each row's vertex pair in the closest points (sum 1).
    pub weight: [f64; 4],
    /// Space dimension.
    pub dim: usize,
}

impl PairRows {
    /// Row values `n · (φ(plus[i]) − φ(minus[i]))`, `i < len` (the rest `+∞`).
    #[inline]
    pub fn values(&self, phi: &[f64]) -> [f64; 4] {
        let mut v = [f64::INFINITY; 4];
        let d = self.dim;
        for (i, vi) in v.iter_mut().enumerate().take(self.len) {
            let (p, m) = (self.plus[i], self.minus[i]);
            let mut s = 0.0;
            // the 2D order of operations of `PointEdgeRow::values` (n.x·dx + n.y·dy)
            for c in 0..d {
                s += self.n[c] * (phi[d * p + c] - phi[d * m + c]);
            }
            *vi = s;
        }
        v
    }

    /// The smallest row value at `phi`.
    #[inline]
    pub fn min_value(&self, phi: &[f64]) -> f64 {
        self.values(phi).into_iter().fold(f64::INFINITY, f64::min)
    }
}

/// The rows of `pair` at ψ; `None` at distance 0 (or NaN: no normal).
pub fn pair_rows(mesh: &Mesh, psi: &[f64], pair: ContactPair) -> Option<PairRows> {
    match pair {
        ContactPair::PointEdge { x, a } => {
            let edge = mesh.edges[a];
            let px = Mesh::p2(psi, x);
            let q = point_edge_distance(&px, &Mesh::p2(psi, edge[0]), &Mesh::p2(psi, edge[1]));
            if q.distance.is_nan() || q.distance <= 0.0 {
                return None;
            }
            let n = (q.closest - px) / q.distance;
            Some(PairRows {
                pair,
                n: Vector3::new(n.x, n.y, 0.0),
                plus: [edge[0], edge[1], 0, 0],
                minus: [x, x, 0, 0],
                len: 2,
                distance: q.distance,
                weight: [q.alpha[0], q.alpha[1], 0.0, 0.0],
                dim: 2,
            })
        }
        ContactPair::PointTriangle { x, t } => {
            let f = mesh.faces[t];
            let px = p3(psi, x);
            let q = point_triangle_distance(&px, &p3(psi, f[0]), &p3(psi, f[1]), &p3(psi, f[2]));
            if q.distance.is_nan() || q.distance <= 0.0 {
                return None;
            }
            Some(PairRows {
                pair,
                n: (q.closest - px) / q.distance,
                plus: [f[0], f[1], f[2], 0],
                minus: [x, x, x, 0],
                len: 3,
                distance: q.distance,
                weight: [q.beta[0], q.beta[1], q.beta[2], 0.0],
                dim: 3,
            })
        }
        ContactPair::EdgeEdge { a, b } => {
            let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
            let q = edge_edge_distance(
                &p3(psi, ea[0]),
                &p3(psi, ea[1]),
                &p3(psi, eb[0]),
                &p3(psi, eb[1]),
            );
            if q.distance.is_nan() || q.distance <= 0.0 {
                return None;
            }
            let wa = [1.0 - q.s, q.s];
            let wb = [1.0 - q.t, q.t];
            Some(PairRows {
                pair,
                n: (q.pb - q.pa) / q.distance,
                plus: [eb[0], eb[1], eb[0], eb[1]],
                minus: [ea[0], ea[0], ea[1], ea[1]],
                len: 4,
                distance: q.distance,
                weight: [wa[0] * wb[0], wa[0] * wb[1], wa[1] * wb[0], wa[1] * wb[1]],
                dim: 3,
            })
        }
    }
}

/// The rows of `pairs` at ψ (rayon-parallel, in the order of `pairs`); `None` when a pair is
/// at distance 0 (the caller has checked admissibility first).
pub fn rows_for(mesh: &Mesh, psi: &[f64], pairs: &[ContactPair]) -> Option<Vec<PairRows>> {
    pairs.par_iter().map(|&p| pair_rows(mesh, psi, p)).collect()
}

/// Whether every vertex of the pair is fixed (its rows are constant: checked once, never
/// given rows).
pub fn all_fixed(mesh: &Mesh, pair: ContactPair) -> bool {
    let f = &mesh.fixed;
    match pair {
        ContactPair::PointEdge { x, a } => {
            let e = mesh.edges[a];
            f[x] && f[e[0]] && f[e[1]]
        }
        ContactPair::PointTriangle { x, t } => f[x] && mesh.faces[t].iter().all(|&v| f[v]),
        ContactPair::EdgeEdge { a, b } => {
            mesh.edges[a].iter().all(|&v| f[v]) && mesh.edges[b].iter().all(|&v| f[v])
        }
    }
}

/// Every pair of disjoint contact elements with a free vertex that the contact filter allows
/// (the all-pairs mode, O(N²)): 2D [`point_edge_pairs`]; 3D [`point_triangle_pairs`], then
/// [`edge_edge_pairs`].
pub fn all_movable_pairs(mesh: &Mesh) -> Vec<ContactPair> {
    if mesh.dim == 2 {
        return point_edge_pairs(mesh)
            .0
            .into_iter()
            .map(Into::into)
            .collect();
    }
    let mut out = point_triangle_pairs(mesh);
    out.extend(edge_edge_pairs(mesh));
    out.retain(|&p| !all_fixed(mesh, p));
    out
}

/// The pairs of disjoint contact elements closer than `r` at `x` (broad phase, sorted; with
/// `skip_fixed`, the all-fixed pairs are left out). 2D: [`point_edge_near`]; 3D:
/// [`near_pairs_3d`].
pub fn near_pairs(mesh: &Mesh, x: &[f64], r: f64, skip_fixed: bool) -> Vec<ContactPair> {
    if mesh.dim == 2 {
        return point_edge_near(mesh, x, &[], &vec![r; mesh.edges.len()], skip_fixed)
            .into_iter()
            .map(|p| p.pair.into())
            .collect();
    }
    let near = near_pairs_3d(
        x,
        &mesh.contact_vertices(),
        &mesh.edges,
        &mesh.faces,
        r,
        mesh.filter(),
    );
    let mut out: Vec<ContactPair> = near
        .point_triangle
        .iter()
        .map(|&(x, t, _)| ContactPair::PointTriangle { x, t })
        .chain(
            near.edge_edge
                .iter()
                .map(|&(a, b, _)| ContactPair::EdgeEdge { a, b }),
        )
        .collect();
    if skip_fixed {
        out.retain(|&p| !all_fixed(mesh, p));
    }
    out
}

/// Per-vertex Euclidean displacement `|y(v) − x(v)|` in dimension `dim`.
pub fn displacements(dim: usize, x: &[f64], y: &[f64]) -> Vec<f64> {
    if dim == 2 {
        return x
            .chunks(2)
            .zip(y.chunks(2))
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .collect();
    }
    x.chunks(dim)
        .zip(y.chunks(dim))
        .map(|(a, b)| {
            a.iter()
                .zip(b)
                .map(|(p, q)| (p - q) * (p - q))
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// One row `n · (φ(plus) − φ(minus)) ≥ ε`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row3 {
    /// Unit normal, frozen at ψ.
    pub n: Vector3<f64>,
    /// The vertex on the far side (a triangle's or edge b's vertex).
    pub plus: usize,
    /// The vertex on the near side (the vertex x, or edge a's vertex).
    pub minus: usize,
}

impl Row3 {
    /// `n · (φ(plus) − φ(minus))`.
    #[inline]
    pub fn value(&self, phi: &[f64]) -> f64 {
        (p3(phi, self.plus) - p3(phi, self.minus)).dot(&self.n)
    }
}

/// Position of vertex `v` in a flat 3D array.
#[inline]
pub fn p3(x: &[f64], v: usize) -> Vector3<f64> {
    Vector3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2])
}

/// All rows of T(ψ) for the given elements (every disjoint point–triangle pair and every
/// disjoint edge–edge pair, all pairs); `None` when some pair is at distance 0. With
/// `edge_edge = false`, the point–triangle rows only (the master/slave simplification of
/// Remark 4.3, kept to show what it misses).
pub fn all_rows_3d(
    psi: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    edge_edge: bool,
) -> Option<Vec<Row3>> {
    let mut rows = Vec::new();
    for t in triangles {
        for &v in vertices {
            if t.contains(&v) {
                continue;
            }
            rows.extend_from_slice(&point_triangle_rows(psi, v, *t)?.0);
        }
    }
    if edge_edge {
        for (ai, a) in edges.iter().enumerate() {
            for b in edges.iter().skip(ai + 1) {
                if a.iter().any(|v| b.contains(v)) {
                    continue;
                }
                rows.extend_from_slice(&edge_edge_rows(psi, *a, *b)?.0);
            }
        }
    }
    Some(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::point_edge_row;
    use crate::scene::mesh::{Body, BodyKind};

    fn two_sheets() -> (Mesh, Vec<f64>) {
        // two triangles stacked at heights 0 and 0.5, the upper one rotated
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, //
            0.3, -0.2, 0.5, 0.9, 0.6, 0.5, -0.1, 0.7, 0.5,
        ];
        let faces = vec![[0, 1, 2], [3, 4, 5]];
        let edges = vec![[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3]];
        let mesh = Mesh {
            dim: 3,
            x_ref: x.clone(),
            fixed: vec![true, true, true, false, false, false],
            edge_body: vec![0, 0, 0, 1, 1, 1],
            edges,
            face_body: vec![0, 1],
            triangles: faces.clone(),
            faces,
            bodies: vec![
                Body {
                    name: "low".into(),
                    kind: BodyKind::Surface,
                    vertices: vec![0, 1, 2],
                    ..Default::default()
                },
                Body {
                    name: "up".into(),
                    kind: BodyKind::Surface,
                    vertices: vec![3, 4, 5],
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        (mesh, x)
    }

    #[test]
    fn contact_2d_rows_equal_point_edge_rows_bit_for_bit() {
        let x = vec![0.0, 0.0, 1.0, 0.1, 0.3, 0.7, 0.2, -0.5];
        let mesh = Mesh {
            dim: 2,
            x_ref: x.clone(),
            fixed: vec![false; 4],
            edges: vec![[0, 1], [2, 3]],
            edge_body: vec![0, 1],
            ..Default::default()
        };
        let phi = vec![0.01, 0.02, 1.0, 0.13, 0.31, 0.66, 0.2, -0.45];
        for (xv, a) in [(2, 0), (3, 0), (0, 1), (1, 1)] {
            let old = point_edge_row(&mesh, &x, PointEdgePair { x: xv, a }).unwrap();
            let new = pair_rows(&mesh, &x, ContactPair::PointEdge { x: xv, a }).unwrap();
            assert_eq!(old.values(&phi)[0].to_bits(), new.values(&phi)[0].to_bits());
            assert_eq!(old.values(&phi)[1].to_bits(), new.values(&phi)[1].to_bits());
            assert_eq!(new.values(&phi)[2], f64::INFINITY);
            assert_eq!(old.alpha, [new.weight[0], new.weight[1]]);
        }
    }

    #[test]
    fn contact_3d_rows_at_psi_bound_the_distance_and_weights_sum_to_one() {
        let (mesh, x) = two_sheets();
        let pairs = all_movable_pairs(&mesh);
        // 3 upper vertices × lower face, 3 lower vertices × upper face, 9 edge–edge pairs
        // (the all-fixed pairs of the lower sheet alone do not exist: it has one face)
        assert_eq!(pairs.len(), 3 + 3 + 9);
        let rows = rows_for(&mesh, &x, &pairs).unwrap();
        for r in &rows {
            let v = r.values(&x);
            for &vi in v.iter().take(r.len) {
                assert!(vi >= r.distance - 1e-14, "{r:?}");
            }
            let ws: f64 = r.weight.iter().take(r.len).sum();
            assert!((ws - 1.0).abs() < 1e-14);
            // the weighted rows give n·(closest_b − closest_a) = the distance
            let wv: f64 = (0..r.len).map(|i| r.weight[i] * v[i]).sum();
            assert!((wv - r.distance).abs() < 1e-12, "{wv} {}", r.distance);
        }
        let md = min_distance(&mesh, &x, 0.1, false);
        let m = rows
            .iter()
            .map(|r| r.distance)
            .fold(f64::INFINITY, f64::min);
        assert_eq!(md.distance, m);
        // near pairs within the minimum + a bit: exactly the closest ones
        let near = near_pairs(&mesh, &x, m * 1.000001, true);
        assert!(!near.is_empty());
        for p in near {
            assert!(rows
                .iter()
                .any(|r| r.pair == p && r.distance < m * 1.000001));
        }
    }

    #[test]
    fn contact_displacements_match_in_both_dimensions() {
        let d = displacements(
            3,
            &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            &[3.0, 4.0, 0.0, 1.0, 1.0, 3.0],
        );
        assert_eq!(d, vec![5.0, 2.0]);
        let d = displacements(2, &[0.0, 0.0], &[3.0, 4.0]);
        assert_eq!(d, vec![5.0]);
    }
}
