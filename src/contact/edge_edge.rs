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
//! stays away from every triangle (tested in `tests/lemma42_3d.rs`).
//!
//! In 2D two disjoint edges meet only by crossing: they have no rows of their own (eq. 4 has
//! `point_edge` rows only, and Lemma 4.2 shows they suffice), but the exact admissibility check
//! ([`super::admissibility`]) looks for crossings ([`first_crossing`]), since a crossing is
//! the only way two disjoint edges get closer than their `point_edge` pairs.

use super::broad_phase::{edge_box, edge_index};
use super::distance::{edge_edge_distance, edge_edge_distance_2d};
use super::{p3, ContactPair, Row3};
use crate::scene::mesh::Mesh;
use rayon::prelude::*;

/// Every 3D `edge_edge` pair `a < b` of disjoint contact edges that the contact filter allows,
/// sorted (all pairs, O(N²): the all-pairs mode).
pub fn edge_edge_pairs(mesh: &Mesh) -> Vec<ContactPair> {
    let mut out = Vec::new();
    let filter = mesh.filter();
    for (a, ea) in mesh.edges.iter().enumerate() {
        for (b, eb) in mesh.edges.iter().enumerate().skip(a + 1) {
            if !ea.iter().any(|v| eb.contains(v)) && filter.is_none_or(|fl| fl.edge_edge(a, b)) {
                out.push(ContactPair::EdgeEdge { a, b });
            }
        }
    }
    out
}

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

/// The first pair (smallest `(a, b)`, `a < b`) of disjoint contact edges that intersect at `x`
/// (distance 0), if any. Only a crossing can make two disjoint edges closer than their
/// `point_edge` pairs, so this completes the exact admissibility check.
///
/// With `skip_fixed`, pairs of edges whose four vertices are fixed are not tested.
pub fn first_crossing(mesh: &Mesh, x: &[f64], skip_fixed: bool) -> Option<(usize, usize)> {
    let index = edge_index(mesh, x, &vec![0.0; mesh.edges.len()]);
    let filter = mesh.filter();
    (0..mesh.edges.len())
        .into_par_iter()
        .map_init(Vec::new, |buf: &mut Vec<u32>, a| {
            let ea = mesh.edges[a];
            let (lo, hi) = edge_box(x, ea, 0.0);
            buf.clear();
            index.query(&lo, &hi, buf);
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
                if filter.is_some_and(|f| !f.edge_edge(a, b)) {
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

#[cfg(test)]
mod tests {
    use super::*;

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
            ..Default::default()
        };
        assert_eq!(first_crossing(&mesh, &x, false), Some((0, 1)));
        let mut y = x.clone();
        y[7] = 2.0; // vertex 3 moved to (1, 2): edge [2, 3] parallel to edge [0, 1]
        assert_eq!(first_crossing(&mesh, &y, false), None);
    }
}
