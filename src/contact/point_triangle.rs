//! `point_triangle` pairs in 3D: vertex `x`, contact triangle `T = [t0, t1, t2]`, `x ∉ T`.
//! With `n` the unit vector from ψ(x) to the closest point of ψ(T), three rows of T(ψ),
//! eq. (6):
//!
//! ```text
//!     n · (φ(t_i) − φ(x)) ≥ ε,   i = 0, 1, 2.
//! ```
//!
//! A point of φ(T) is a convex combination of its vertices, so the rows give
//! `n · (φ(y) − φ(x)) ≥ ε` for every point y of φ(T), hence dist ≥ ε: the 3D form of
//! Lemma 4.2, tested in `tests/lemma42_3d.rs`.

use super::distance::point_triangle_distance;
use super::{p3, ContactPair, Row3};
use crate::scene::mesh::Mesh;

/// Every `point_triangle` pair (contact vertex x, contact face t, x ∉ t) that the contact
/// filter allows, sorted by vertex then face (all pairs, O(N²): the all-pairs mode).
pub fn point_triangle_pairs(mesh: &Mesh) -> Vec<ContactPair> {
    let mut out = Vec::new();
    let filter = mesh.filter();
    for &x in &mesh.contact_vertices() {
        for (t, f) in mesh.faces.iter().enumerate() {
            if !f.contains(&x) && filter.is_none_or(|fl| fl.point_triangle(x, t)) {
                out.push(ContactPair::PointTriangle { x, t });
            }
        }
    }
    out
}

/// The three rows of the `point_triangle` pair (x, t) at ψ, with ψ's distance; `None` at
/// distance 0 (no normal) or when x is a vertex of t.
pub fn point_triangle_rows(psi: &[f64], x: usize, t: [usize; 3]) -> Option<([Row3; 3], f64)> {
    if t.contains(&x) {
        return None;
    }
    let px = p3(psi, x);
    let q = point_triangle_distance(&px, &p3(psi, t[0]), &p3(psi, t[1]), &p3(psi, t[2]));
    if q.distance.is_nan() || q.distance <= 0.0 {
        return None;
    }
    let n = (q.closest - px) / q.distance;
    let row = |i: usize| Row3 {
        n,
        plus: t[i],
        minus: x,
    };
    Some(([row(0), row(1), row(2)], q.distance))
}
