//! Rows of T(ψ) in 3D, eq. (6), and the exact 3D admissibility check (O(N²) reference form).
//!
//! For a vertex–triangle pair (x, T), x ∉ T, with `n` the unit vector from ψ(x) to the closest
//! point of ψ(T), three rows
//!
//! ```text
//!     n · (φ(t_i) − φ(x)) ≥ ε,   i = 0, 1, 2;
//! ```
//!
//! for an edge–edge pair (a, b), a ∩ b = ∅, with `n` the unit vector from the closest point of
//! ψ(a) to the closest point of ψ(b) (the deterministic choice of
//! [`segment_segment_distance`] when the edges are parallel), four rows
//!
//! ```text
//!     n · (φ(b_j) − φ(a_i)) ≥ ε,   i, j = 0, 1.
//! ```
//!
//! Every row is `n · (φ(p) − φ(q)) ≥ ε` for two vertices `p`, `q` ([`Row3`]). Since a point of
//! φ(T) (of φ(b), φ(a)) is a convex combination of its vertices, the rows give
//! `n · (φ(y) − φ(x)) ≥ ε` for every point y of φ(T) (every pair of points of φ(a), φ(b)), hence
//! dist ≥ ε: the 3D form of Lemma 4.2, tested in `tests/lemma42_3d.rs`. Remark 4.3: without the
//! edge–edge rows two edges can pass through each other while every vertex stays away from
//! every triangle (tested there too).
//!
//! This module is the 3D row builder and the exact check; the 3D pair search, the sub-problem
//! assembly and the outer loop in 3D are not wired to it yet (README, "Known gaps").

use crate::geometry::{point_triangle_distance, segment_segment_distance};
use crate::mesh::ContactFilter;
use nalgebra::Vector3;

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

/// The three rows of the vertex–triangle pair (x, t) at ψ, with ψ's distance; `None` at
/// distance 0 (no normal) or when x is a vertex of t.
pub fn vertex_triangle_rows(psi: &[f64], x: usize, t: [usize; 3]) -> Option<([Row3; 3], f64)> {
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

/// The four rows of the edge–edge pair (a, b) at ψ, with ψ's distance; `None` at distance 0
/// or when the edges share a vertex.
pub fn edge_edge_rows(psi: &[f64], a: [usize; 2], b: [usize; 2]) -> Option<([Row3; 4], f64)> {
    if a.iter().any(|v| b.contains(v)) {
        return None;
    }
    let q = segment_segment_distance(
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

/// Whether the segment `[a0, a1]` meets the triangle `(t0, t1, t2)` (closed sets), by exact
/// orientation signs of the floating-point inputs (the determinants are computed in f64, so
/// "exact" means: up to their rounding). Coplanar segments are reported as not meeting; their
/// contact shows as a zero vertex–triangle or edge–edge distance instead.
pub fn segment_meets_triangle(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> bool {
    let orient = |p: &Vector3<f64>, q: &Vector3<f64>, r: &Vector3<f64>, s: &Vector3<f64>| {
        (q - p).cross(&(r - p)).dot(&(s - p))
    };
    let s0 = orient(t0, t1, t2, a0);
    let s1 = orient(t0, t1, t2, a1);
    if (s0 > 0.0 && s1 > 0.0) || (s0 < 0.0 && s1 < 0.0) {
        return false;
    }
    // Coplanar up to rounding: an orientation of two points within rounding of the plane is
    // noise, and its sign says nothing. A segment lying in the plane meets the triangle only
    // through an edge or an endpoint, which the vertex–triangle and edge–edge distances
    // already report, so it does not count as passing through.
    let n = (t1 - t0).cross(&(t2 - t0)).norm();
    let scale = [t1 - t0, t2 - t0, a0 - t0, a1 - t0]
        .iter()
        .map(|v| v.norm())
        .fold(0.0_f64, f64::max);
    let tol = 64.0 * f64::EPSILON * n * scale;
    if s0.abs() <= tol && s1.abs() <= tol {
        return false;
    }
    // the line a0→a1 passes the three edges of the triangle on the same side
    let e0 = orient(a0, a1, t0, t1);
    let e1 = orient(a0, a1, t1, t2);
    let e2 = orient(a0, a1, t2, t0);
    (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0)
}

/// The closest pair of disjoint elements found by [`min_distance_3d`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Closest3 {
    /// Vertex `x` and triangle `t` (index).
    VertexTriangle {
        /// Vertex.
        x: usize,
        /// Triangle index.
        t: usize,
    },
    /// Edges `a` and `b` (indices).
    EdgeEdge {
        /// First edge.
        a: usize,
        /// Second edge.
        b: usize,
    },
    /// Edge `a` passes through triangle `t` (distance 0).
    EdgeThroughTriangle {
        /// Edge index.
        a: usize,
        /// Triangle index.
        t: usize,
    },
    /// No disjoint pair.
    None,
}

/// The exact minimum distance over all disjoint element pairs of a 3D mesh (all pairs, O(N²):
/// the reference the pruned check of the 2D engine is tested against): vertex–triangle pairs
/// (`vertices` × `triangles`, x ∉ T), edge–edge pairs (a ∩ b = ∅), and 0 when an edge passes
/// through a triangle it does not touch.
pub fn min_distance_3d(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
) -> (f64, Closest3) {
    min_distance_3d_filtered(x, vertices, edges, triangles, None)
}

/// [`min_distance_3d`] over the pairs a contact filter allows (`None`: all pairs; `edges` and
/// `triangles` must then be the mesh's contact edges and faces the filter was built for).
pub fn min_distance_3d_filtered(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    filter: Option<&ContactFilter>,
) -> (f64, Closest3) {
    let mut best = (f64::INFINITY, Closest3::None);
    for (ti, t) in triangles.iter().enumerate() {
        let (t0, t1, t2) = (p3(x, t[0]), p3(x, t[1]), p3(x, t[2]));
        for &v in vertices {
            if t.contains(&v) || filter.is_some_and(|f| !f.vertex_face(v, ti)) {
                continue;
            }
            let d = point_triangle_distance(&p3(x, v), &t0, &t1, &t2).distance;
            if d < best.0 {
                best = (d, Closest3::VertexTriangle { x: v, t: ti });
            }
        }
        for (ai, e) in edges.iter().enumerate() {
            if e.iter().any(|v| t.contains(v)) || filter.is_some_and(|f| !f.edge_face(ai, ti)) {
                continue;
            }
            if segment_meets_triangle(&p3(x, e[0]), &p3(x, e[1]), &t0, &t1, &t2) {
                return (0.0, Closest3::EdgeThroughTriangle { a: ai, t: ti });
            }
        }
    }
    for (ai, a) in edges.iter().enumerate() {
        for (bi, b) in edges.iter().enumerate().skip(ai + 1) {
            if a.iter().any(|v| b.contains(v)) || filter.is_some_and(|f| !f.edge_edge(ai, bi)) {
                continue;
            }
            let d =
                segment_segment_distance(&p3(x, a[0]), &p3(x, a[1]), &p3(x, b[0]), &p3(x, b[1]))
                    .distance;
            if d < best.0 {
                best = (d, Closest3::EdgeEdge { a: ai, b: bi });
            }
        }
    }
    best
}

/// All rows of T(ψ) for the given elements (every disjoint vertex–triangle pair and every
/// disjoint edge–edge pair, all pairs); `None` when some pair is at distance 0. With
/// `edge_edge = false`, the vertex–triangle rows only (the master/slave simplification of
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
            rows.extend_from_slice(&vertex_triangle_rows(psi, v, *t)?.0);
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

    #[test]
    fn rows3d_values_at_psi_are_at_least_the_distance() {
        // x above the triangle's interior: the three rows equal the distance at ψ
        let psi = [0.2, 0.2, 0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let (rows, d) = vertex_triangle_rows(&psi, 0, [1, 2, 3]).unwrap();
        assert!((d - 0.5).abs() < 1e-15);
        for r in rows {
            assert!((r.value(&psi) - 0.5).abs() < 1e-15, "{}", r.value(&psi));
        }
        // skew edges at distance 1
        let psi = [-1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 1.0, 1.0];
        let (rows, d) = edge_edge_rows(&psi, [0, 1], [2, 3]).unwrap();
        assert!((d - 1.0).abs() < 1e-15);
        for r in rows {
            assert!(r.value(&psi) >= 1.0 - 1e-15);
        }
        assert!(vertex_triangle_rows(&psi, 0, [0, 2, 3]).is_none());
        assert!(edge_edge_rows(&psi, [0, 1], [1, 3]).is_none());
    }

    #[test]
    fn rows3d_segment_through_triangle() {
        let t = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let hit = |a: [f64; 3], b: [f64; 3]| {
            segment_meets_triangle(&Vector3::from(a), &Vector3::from(b), &t[0], &t[1], &t[2])
        };
        assert!(hit([0.2, 0.2, -1.0], [0.2, 0.2, 1.0]));
        assert!(!hit([0.8, 0.8, -1.0], [0.8, 0.8, 1.0])); // passes beside the hypotenuse
        assert!(!hit([0.2, 0.2, 0.1], [0.2, 0.2, 1.0])); // stops above
        assert!(hit([0.2, 0.2, 0.0], [0.2, 0.2, 1.0])); // touches the face
        assert!(hit([0.0, 0.0, -1.0], [0.0, 0.0, 1.0])); // through a vertex
        assert!(!hit([0.1, 0.1, 0.0], [0.3, 0.1, 0.0])); // coplanar: not this test's case
    }

    #[test]
    fn rows3d_coplanar_segment_beside_a_rotated_triangle_does_not_cross() {
        // A coplanar, disjoint segment (the cube faces of the solids scene) rotated and moved
        // so that the orientations are rounding noise of either sign: never a crossing.
        // A segment that does pierce the triangle, moved the same way, still does.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut noisy = 0;
        for _ in 0..2000 {
            let axis = Vector3::new(rng.gen(), rng.gen(), rng.gen::<f64>()) - Vector3::repeat(0.5);
            let rot = nalgebra::Rotation3::new(axis.normalize() * rng.gen_range(0.0..3.0));
            let shift = Vector3::new(rng.gen(), rng.gen(), rng.gen::<f64>()) * 3.0;
            let m = |p: [f64; 3]| rot * Vector3::from(p) * 0.1 + shift;
            let t = [m([0.0, 0.0, 0.0]), m([1.0, 0.0, 0.0]), m([0.0, 1.0, 0.0])];
            let (a, b) = (m([1.0, 1.0, 0.0]), m([2.0, 0.5, 0.0]));
            let o = |p: &Vector3<f64>| (t[1] - t[0]).cross(&(t[2] - t[0])).dot(&(p - t[0]));
            if o(&a) * o(&b) < 0.0 {
                noisy += 1;
            }
            assert!(!segment_meets_triangle(&a, &b, &t[0], &t[1], &t[2]));
            let (c, d) = (m([0.2, 0.2, -1.0]), m([0.3, 0.2, 1.0]));
            assert!(segment_meets_triangle(&c, &d, &t[0], &t[1], &t[2]));
        }
        // the case is real: rounding gives opposite signs in a good share of the samples
        assert!(
            noisy > 100,
            "only {noisy} samples had opposite-sign orientations"
        );
    }
}

/// Disjoint element pairs closer than a radius, found through the BVH of
/// [`crate::bvh::Bvh`]: the 3D broad phase. Sorted, so the result does not depend on the
/// thread count.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NearPairs3 {
    /// `(vertex, triangle index, distance)`, sorted by vertex then triangle.
    pub vertex_triangle: Vec<(usize, usize, f64)>,
    /// `(edge a, edge b, distance)` with `a < b`, sorted.
    pub edge_edge: Vec<(usize, usize, f64)>,
}

fn bbox(x: &[f64], vs: &[usize], r: f64) -> crate::broad_phase::Aabb<3> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in vs {
        for c in 0..3 {
            lo[c] = lo[c].min(x[3 * v + c] - r);
            hi[c] = hi[c].max(x[3 * v + c] + r);
        }
    }
    (lo, hi)
}

/// Every disjoint vertex–triangle pair (`vertices` × `triangles`, x ∉ T) and edge–edge pair
/// (a ∩ b = ∅) at distance `< r`, through a BVH over the triangles' and the edges' boxes.
pub fn near_pairs_3d(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    r: f64,
) -> NearPairs3 {
    near_pairs_3d_filtered(x, vertices, edges, triangles, r, None)
}

/// [`near_pairs_3d`] over the pairs a contact filter allows (`None`: all pairs). An excluded
/// pair is dropped before its distance is computed.
pub fn near_pairs_3d_filtered(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    r: f64,
    filter: Option<&ContactFilter>,
) -> NearPairs3 {
    use crate::bvh::Bvh;
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
            if t.contains(&v) || filter.is_some_and(|f| !f.vertex_face(v, ti as usize)) {
                continue;
            }
            let d = point_triangle_distance(&p3(x, v), &p3(x, t[0]), &p3(x, t[1]), &p3(x, t[2]))
                .distance;
            if d < r {
                out.vertex_triangle.push((v, ti as usize, d));
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
                segment_segment_distance(&p3(x, a[0]), &p3(x, a[1]), &p3(x, b[0]), &p3(x, b[1]))
                    .distance;
            if d < r {
                out.edge_edge.push((ai, bi, d));
            }
        }
    }
    out.vertex_triangle.sort_by_key(|p| (p.0, p.1));
    out.edge_edge.sort_by_key(|p| (p.0, p.1));
    out
}

/// [`min_distance_3d`] through the BVH: edges through triangles among overlapping boxes, then
/// the near pairs within a radius that starts at `r0` (> 0) and grows ×4 until a pair is found.
/// Gives the same distance as the O(N²) form (tested).
pub fn min_distance_3d_bvh(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    r0: f64,
) -> (f64, Closest3) {
    min_distance_3d_bvh_filtered(x, vertices, edges, triangles, r0, None)
}

/// [`min_distance_3d_bvh`] over the pairs a contact filter allows (`None`: all pairs).
pub fn min_distance_3d_bvh_filtered(
    x: &[f64],
    vertices: &[usize],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    r0: f64,
    filter: Option<&ContactFilter>,
) -> (f64, Closest3) {
    use crate::bvh::Bvh;
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
        let near = near_pairs_3d_filtered(x, vertices, edges, triangles, r, filter);
        let mut best = (f64::INFINITY, Closest3::None);
        for &(v, t, d) in &near.vertex_triangle {
            if d < best.0 {
                best = (d, Closest3::VertexTriangle { x: v, t });
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
