//! `edge_edge` pairs in 3D: edges a, b with a ∩ b = ∅. With `n` the unit vector from the
//! closest point of ψ(a) to the closest point of ψ(b) (the deterministic choice of
//! [`edge_edge_distance`] when the edges are parallel: the set P_{a,b} of eq. 12 is then not a
//! singleton), four rows of T(ψ), eq. (6):
//!
//! ```text
//!     n · (φ(b_j) − φ(a_i)) ≥ ε,   i, j = 0, 1.
//! ```
//!
//! Remark 4.3: without these rows two edges can pass through each other while every vertex
//! stays away from every triangle (tested in `tests/lemma42_3d.rs`). In 2D two edges meet only
//! by crossing, which the exact check sees ([`super::admissibility`]); they have no rows of
//! their own (eq. 4 has vertex–edge rows only).

use super::distance::edge_edge_distance;
use super::{p3, Row3};

/// The four rows of the edge–edge pair (a, b) at ψ, with ψ's distance; `None` at distance 0
/// or when the edges share a vertex.
pub fn edge_edge_rows(psi: &[f64], a: [usize; 2], b: [usize; 2]) -> Option<([Row3; 4], f64)> {
    if a.iter().any(|v| b.contains(v)) {
        return None;
    }
    let q = edge_edge_distance(
        &p3(psi, a[0]),
        &p3(psi, a[1]),
        &p3(psi, b[0]),
        &p3(psi, b[1]),
    );
    if q.distance.is_nan() || q.distance <= 0.0 {
        return None;
    }
    let n = (q.pb - q.pa) / q.distance;
    let row = |i: usize, j: usize| Row3 {
        n,
        plus: b[j],
        minus: a[i],
    };
    Some(([row(0, 0), row(0, 1), row(1, 0), row(1, 1)], q.distance))
}
