//! `point_edge` pairs in 2D: vertex `x`, contact edge `a`, `x ∉ a`. Their enumeration (the
//! paper-faithful all-pairs mode of §4.1.1) and their rows of T(ψ), eq. (4):
//!
//! ```text
//!     n_{a,x}(ψ) · (φ(a_i) − φ(x)) ≥ ε,   i = 0, 1,
//! ```
//!
//! with `n_{a,x}(ψ)` the unit vector from ψ(x) to the closest point of ψ(a) (eq. 5). Both rows
//! are linear in φ, so T(ψ) is a convex polyhedron; it contains ψ when ψ is admissible, and by
//! Lemma 4.2 it lies inside A_{h,ε}. The only pairs left out of the rows are those whose three
//! vertices are all fixed: their rows are constant, so they are checked once at the start
//! ([`super::admissibility::min_distance`] with `skip_fixed = false`) and never again.

use super::distance::point_edge_distance;
use crate::scene::mesh::Mesh;
use nalgebra::Vector2;
use rayon::prelude::*;

/// A point–edge pair: vertex `x`, contact edge index `a` (into [`Mesh::edges`]), `x ∉ a`.
/// Ordered by vertex, then edge (the order of the broad phase's output).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PointEdgePair {
    /// Vertex.
    pub x: usize,
    /// Edge index.
    pub a: usize,
}

/// All `point_edge` pairs of the mesh that the contact filter ([`Mesh::contact_filter`])
/// allows, split into those with at least one free vertex (they
/// get rows) and those whose vertices are all fixed (checked once).
pub fn point_edge_pairs(mesh: &Mesh) -> (Vec<PointEdgePair>, Vec<PointEdgePair>) {
    let verts = mesh.contact_vertices();
    let filter = mesh.filter();
    let mut movable = Vec::new();
    let mut fixed = Vec::new();
    for (a, e) in mesh.edges.iter().enumerate() {
        for &x in &verts {
            if x == e[0] || x == e[1] {
                continue;
            }
            if filter.is_some_and(|f| !f.point_edge(x, a)) {
                continue;
            }
            let pair = PointEdgePair { x, a };
            if mesh.fixed[x] && mesh.fixed[e[0]] && mesh.fixed[e[1]] {
                fixed.push(pair);
            } else {
                movable.push(pair);
            }
        }
    }
    (movable, fixed)
}

/// The two rows of one `point_edge` pair, frozen at ψ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEdgeRow {
    /// The pair.
    pub pair: PointEdgePair,
    /// Edge vertices `[a0, a1]`.
    pub edge: [usize; 2],
    /// Unit normal `n_{a,x}(ψ)`, from ψ(x) towards ψ(a).
    pub n: Vector2<f64>,
    /// `dist(ψ(x), ψ(a))`.
    pub distance: f64,
    /// Barycentric coordinates of the closest point of ψ(a).
    pub alpha: [f64; 2],
}

impl PointEdgeRow {
    /// Values `n·(φ(a_i) − φ(x))` of the two rows at `phi`.
    #[inline]
    pub fn values(&self, phi: &[f64]) -> [f64; 2] {
        let px = Mesh::p2(phi, self.pair.x);
        [
            self.n.dot(&(Mesh::p2(phi, self.edge[0]) - px)),
            self.n.dot(&(Mesh::p2(phi, self.edge[1]) - px)),
        ]
    }
}

/// The rows of one pair at ψ; `None` at distance 0 (no normal).
pub fn point_edge_row(mesh: &Mesh, psi: &[f64], pair: PointEdgePair) -> Option<PointEdgeRow> {
    let edge = mesh.edges[pair.a];
    let px = Mesh::p2(psi, pair.x);
    let q = point_edge_distance(&px, &Mesh::p2(psi, edge[0]), &Mesh::p2(psi, edge[1]));
    if q.distance <= 0.0 {
        return None;
    }
    Some(PointEdgeRow {
        pair,
        edge,
        n: (q.closest - px) / q.distance,
        distance: q.distance,
        alpha: q.alpha,
    })
}

/// Builds the rows of T(ψ) for `pairs` (rayon-parallel, in the order of `pairs`). A pair at
/// distance 0 (ψ not admissible) has no normal; the caller has checked admissibility first, so
/// this returns `None` then.
pub fn point_edge_rows(
    mesh: &Mesh,
    psi: &[f64],
    pairs: &[PointEdgePair],
) -> Option<Vec<PointEdgeRow>> {
    pairs
        .par_iter()
        .map(|&pair| point_edge_row(mesh, psi, pair))
        .collect()
}

/// Smallest row value minus ε over all rows at `phi` (≥ 0 iff φ ∈ T(ψ)).
pub fn min_slack(rows: &[PointEdgeRow], phi: &[f64], eps: f64) -> f64 {
    rows.iter()
        .map(|r| {
            let v = r.values(phi);
            v[0].min(v[1]) - eps
        })
        .fold(f64::INFINITY, f64::min)
}
