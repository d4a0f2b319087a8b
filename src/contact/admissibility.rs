//! The exact admissibility check: is φ in A_{h,ε}, i.e. is every pair of disjoint contact
//! elements at distance ≥ ε? It returns the minimum distance over those pairs and the closest
//! pair that attains it:
//!
//! | dim | pairs (disjoint) | distance |
//! |---|---|---|
//! | 2 | `point_edge` (x ∉ a) | `dist(φ(x), φ(a))` |
//! | 2 | `edge_edge` (a ∩ b = ∅) | 0 when they cross (otherwise a `point_edge` pair is closer) |
//! | 3 | `point_triangle` (x ∉ T) | `dist(φ(x), φ(T))` |
//! | 3 | `edge_edge` (a ∩ b = ∅) | `dist(φ(a), φ(b))` |
//! | 3 | edge a through face T (a ∩ T = ∅) | 0 ([`segment_meets_triangle`]) |
//!
//! Pairs the contact filter of the mesh ([`Mesh::filter`]) excludes are not checked.
//!
//! Lemma 4.2 (and its 3D form with the rows of eq. 6, Remark 4.3) makes every φ of T(ψ)
//! admissible; the check makes sure of it on every iterate anyway, in floating point, with the
//! round-off allowance of the outer loop. One entry point, [`min_distance`], does it for every
//! iterate of a run (its `skip_fixed = false` form checks the pairs whose vertices are all
//! fixed, once at the start); it runs through the broad phase ([`super::broad_phase`]). The
//! O(N²) form [`min_distance_brute_force`] is the reference the tests hold it to.

use super::broad_phase;
use super::distance::{
    edge_edge_distance, edge_edge_distance_2d, point_edge_distance, point_triangle_distance,
};
use super::p3;
use super::point_edge::{point_edge_pairs, PointEdgePair};
use crate::scene::mesh::{ContactFilter, Mesh};
use nalgebra::Vector3;

/// The pair of disjoint elements that attains the minimum distance.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClosestPair {
    /// Vertex `x` and edge `a` (vertices `a0`, `a1`).
    PointEdge {
        /// Vertex.
        x: usize,
        /// Edge index.
        a: usize,
        /// First vertex of the edge.
        a0: usize,
        /// Second vertex of the edge.
        a1: usize,
    },
    /// Two disjoint edges that cross (distance 0).
    EdgeEdge {
        /// First edge.
        a: usize,
        /// Second edge.
        b: usize,
    },
    /// 3D: vertex `x` and contact face `t` (vertices `face`). Tagged `vertex_triangle` in
    /// summary.json, as before the pair kinds were renamed.
    #[serde(rename = "vertex_triangle")]
    PointTriangle {
        /// Vertex.
        x: usize,
        /// Face index.
        t: usize,
        /// The face's vertices.
        face: [usize; 3],
    },
    /// 3D: two disjoint contact edges.
    Segments {
        /// First edge.
        a: usize,
        /// Second edge.
        b: usize,
        /// First edge's vertices.
        ea: [usize; 2],
        /// Second edge's vertices.
        eb: [usize; 2],
    },
    /// 3D: contact edge `a` passes through contact face `t` (distance 0).
    EdgeThroughFace {
        /// Edge.
        a: usize,
        /// Face.
        t: usize,
    },
    /// The mesh has no disjoint pair.
    None,
}

impl std::fmt::Display for ClosestPair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ClosestPair::PointEdge { x, a, a0, a1 } => {
                write!(f, "vertex {x} and edge {a} = [{a0}, {a1}]")
            }
            ClosestPair::EdgeEdge { a, b } => write!(f, "edges {a} and {b} (they cross)"),
            ClosestPair::PointTriangle { x, t, face } => {
                write!(f, "vertex {x} and face {t} = {face:?}")
            }
            ClosestPair::Segments { a, b, ea, eb } => {
                write!(f, "edge {a} = {ea:?} and edge {b} = {eb:?}")
            }
            ClosestPair::EdgeThroughFace { a, t } => {
                write!(
                    f,
                    "edge {a} and face {t} (the edge passes through the face)"
                )
            }
            ClosestPair::None => write!(f, "no disjoint pair"),
        }
    }
}

/// Result of the exact admissibility check.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MinDistance {
    /// `min dist(φ(T1), φ(T2))` over the checked disjoint pairs (`+∞` if none).
    pub distance: f64,
    /// The pair attaining it.
    pub pair: ClosestPair,
}

/// The exact admissibility check of `x`, through the broad phase: the minimum distance over
/// every pair of disjoint contact elements the contact filter allows (module documentation),
/// and the closest pair. 2D: [`broad_phase::min_distance_2d`]; with `skip_fixed`, the pairs
/// whose vertices are all fixed (constant: checked once, at the start, with `skip_fixed =
/// false`) are left out. 3D: [`broad_phase::min_distance_3d`] over every pair (`skip_fixed`
/// is ignored: the constant pairs are checked every time). `r0 > 0` is the initial search
/// radius; the result does not depend on it. Equal to [`min_distance_brute_force`] (tested;
/// where several pairs attain the minimum, the two may name different ones).
pub fn min_distance(mesh: &Mesh, x: &[f64], r0: f64, skip_fixed: bool) -> MinDistance {
    if mesh.dim == 2 {
        return broad_phase::min_distance_2d(mesh, x, r0, skip_fixed);
    }
    let (distance, c) = broad_phase::min_distance_3d(mesh, x, r0);
    MinDistance {
        distance,
        pair: closest_pair(mesh, c),
    }
}

/// The [`ClosestPair`] (element indices and vertices) of a 3D [`Closest3`].
fn closest_pair(mesh: &Mesh, c: Closest3) -> ClosestPair {
    match c {
        Closest3::PointTriangle { x, t } => ClosestPair::PointTriangle {
            x,
            t,
            face: mesh.faces[t],
        },
        Closest3::EdgeEdge { a, b } => ClosestPair::Segments {
            a,
            b,
            ea: mesh.edges[a],
            eb: mesh.edges[b],
        },
        Closest3::EdgeThroughTriangle { a, t } => ClosestPair::EdgeThroughFace { a, t },
        Closest3::None => ClosestPair::None,
    }
}

/// The same check as [`min_distance`] over every pair, by direct enumeration, O(N²): the
/// reference of the tests. 2D: every `point_edge` pair of [`point_edge_pairs`] (those with a
/// free vertex first, then the all-fixed ones; the first wins a tie) and every pair of disjoint
/// edges for crossings; 3D: every `point_triangle`, edge-through-face and `edge_edge` pair.
pub fn min_distance_brute_force(mesh: &Mesh, x: &[f64]) -> MinDistance {
    if mesh.dim == 2 {
        let (movable, fixed) = point_edge_pairs(mesh);
        let a = min_distance_of_pairs(mesh, x, &movable);
        let b = min_distance_of_pairs(mesh, x, &fixed);
        return if b.distance < a.distance { b } else { a };
    }
    let (distance, c) = min_distance_3d_brute_force(
        x,
        &mesh.contact_vertices(),
        &mesh.edges,
        &mesh.faces,
        mesh.filter(),
    );
    MinDistance {
        distance,
        pair: closest_pair(mesh, c),
    }
}

/// [`min_distance_brute_force`] in 2D over the given `point_edge` pairs: every
/// `point_edge` pair (x ∉ a) in `pairs`, and every pair of disjoint contact edges (crossing
/// edges have distance 0 although their endpoints may be far apart). In 2D this is the distance
/// of every pair of disjoint vertices/edges except the two ends of one edge, which eq. (4) does
/// not constrain either.
fn min_distance_of_pairs(mesh: &Mesh, x: &[f64], pairs: &[PointEdgePair]) -> MinDistance {
    let mut best = MinDistance {
        distance: f64::INFINITY,
        pair: ClosestPair::None,
    };
    for p in pairs {
        let e = mesh.edges[p.a];
        let d =
            point_edge_distance(&Mesh::p2(x, p.x), &Mesh::p2(x, e[0]), &Mesh::p2(x, e[1])).distance;
        if d < best.distance {
            best = MinDistance {
                distance: d,
                pair: ClosestPair::PointEdge {
                    x: p.x,
                    a: p.a,
                    a0: e[0],
                    a1: e[1],
                },
            };
        }
    }
    // Crossings: only a crossing can make two disjoint edges closer than their endpoint pairs.
    let filter = mesh.filter();
    for (a, ea) in mesh.edges.iter().enumerate() {
        for (b, eb) in mesh.edges.iter().enumerate().skip(a + 1) {
            if ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1] {
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
            if d == 0.0 && d < best.distance {
                best = MinDistance {
                    distance: 0.0,
                    pair: ClosestPair::EdgeEdge { a, b },
                };
            }
        }
    }
    best
}

/// Whether the segment `[a0, a1]` meets the triangle `(t0, t1, t2)` (closed sets), by exact
/// orientation signs of the floating-point inputs (the determinants are computed in f64, so
/// "exact" means: up to their rounding). Coplanar segments are reported as not meeting; their
/// contact shows as a zero point–triangle or edge–edge distance instead.
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
    // through an edge or an endpoint, which the point–triangle and edge–edge distances
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

/// The closest pair of disjoint elements of a 3D mesh, by element index: what
/// [`broad_phase::min_distance_3d`] finds.
///
/// `Debug` is written out: its text reaches the built-in 3D scenes' error messages
/// (`InadmissibleStart`), which keep the variant names they had before the renaming
/// (`VertexTriangle`).
#[derive(Clone, Copy, PartialEq)]
pub enum Closest3 {
    /// Vertex `x` and triangle `t` (index).
    PointTriangle {
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

impl std::fmt::Debug for Closest3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Closest3::PointTriangle { x, t } => f
                .debug_struct("VertexTriangle")
                .field("x", &x)
                .field("t", &t)
                .finish(),
            Closest3::EdgeEdge { a, b } => f
                .debug_struct("EdgeEdge")
                .field("a", &a)
                .field("b", &b)
                .finish(),
            Closest3::EdgeThroughTriangle { a, t } => f
                .debug_struct("EdgeThroughTriangle")
                .field("a", &a)
                .field("t", &t)
                .finish(),
            Closest3::None => write!(f, "None"),
        }
    }
}

/// [`min_distance_brute_force`] in 3D over `vertices` × `triangles` (x ∉ T), the pairs of
/// disjoint `edges` and the edges through triangles they do not touch, skipping the pairs
/// `filter` excludes (`edges` and `triangles` are then the mesh's contact edges and faces).
fn min_distance_3d_brute_force(
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
            if t.contains(&v) || filter.is_some_and(|f| !f.point_triangle(v, ti)) {
                continue;
            }
            let d = point_triangle_distance(&p3(x, v), &t0, &t1, &t2).distance;
            if d < best.0 {
                best = (d, Closest3::PointTriangle { x: v, t: ti });
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
                edge_edge_distance(&p3(x, a[0]), &p3(x, a[1]), &p3(x, b[0]), &p3(x, b[1])).distance;
            if d < best.0 {
                best = (d, Closest3::EdgeEdge { a: ai, b: bi });
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::super::{edge_edge_rows, point_triangle_rows};
    use super::*;

    #[test]
    fn rows3d_values_at_psi_are_at_least_the_distance() {
        // x above the triangle's interior: the three rows equal the distance at ψ
        let psi = [0.2, 0.2, 0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let (rows, d) = point_triangle_rows(&psi, 0, [1, 2, 3]).unwrap();
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
        assert!(point_triangle_rows(&psi, 0, [0, 2, 3]).is_none());
        assert!(edge_edge_rows(&psi, [0, 1], [1, 3]).is_none());
    }

    #[test]
    fn point_triangle_keeps_its_output_text() {
        // summary.json, contacts.csv and the scenes' error messages predate the renaming
        let c = ClosestPair::PointTriangle {
            x: 1,
            t: 2,
            face: [3, 4, 5],
        };
        let j = serde_json::to_value(c).unwrap();
        assert_eq!(j["kind"], "vertex_triangle");
        assert_eq!(c.to_string(), "vertex 1 and face 2 = [3, 4, 5]");
        let c3 = Closest3::PointTriangle { x: 1, t: 2 };
        assert_eq!(format!("{c3:?}"), "VertexTriangle { x: 1, t: 2 }");
        let c3 = Closest3::EdgeThroughTriangle { a: 1, t: 2 };
        assert_eq!(format!("{c3:?}"), "EdgeThroughTriangle { a: 1, t: 2 }");
        assert_eq!(format!("{:?}", Closest3::None), "None");
        let p = crate::contact::ContactPair::PointTriangle { x: 1, t: 2 };
        assert_eq!(p.kind(), "vertex_triangle");
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
