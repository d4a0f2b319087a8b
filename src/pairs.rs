//! Pair search in 2D: the `point_edge` pairs `(x, a)`, vertex `x`, contact edge `a`, `x ∉ a`.
//!
//! This is the paper-faithful all-pairs mode of §4.1.1: every such pair gives two rows of
//! `T(ψ)` (eq. 4). The only pairs left out of the rows are those whose three vertices are all
//! fixed: their rows are constant, so they are checked once at the start
//! ([`fixed_pairs_admissible`]) and never again (SPEC §2).

use crate::geometry::{edge_edge_distance_2d, point_edge_distance};
use crate::mesh::Mesh;

/// A vertex–edge pair: vertex `x`, contact edge index `a` (into [`Mesh::edges`]), `x ∉ a`.
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
            if filter.is_some_and(|f| !f.vertex_edge(x, a)) {
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
    /// 3D: vertex `x` and contact face `t` (vertices `face`).
    VertexTriangle {
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
            ClosestPair::VertexTriangle { x, t, face } => {
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

/// Exact minimum distance of `x` over the disjoint pairs of contact elements: every
/// `point_edge` pair (x ∉ a) in `pairs`, and every pair of disjoint contact edges (crossing
/// edges have distance 0 although their endpoints may be far apart). In 2D this is the distance
/// of every pair of disjoint vertices/edges except the two ends of one edge, which eq. (4) does
/// not constrain either.
pub fn min_distance(mesh: &Mesh, x: &[f64], pairs: &[PointEdgePair]) -> MinDistance {
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

/// Exact admissibility check of `x` over all disjoint pairs (movable and fixed).
pub fn check_admissible(
    mesh: &Mesh,
    x: &[f64],
    movable: &[PointEdgePair],
    fixed: &[PointEdgePair],
) -> MinDistance {
    let a = min_distance(mesh, x, movable);
    let b = min_distance(mesh, x, fixed);
    if b.distance < a.distance {
        b
    } else {
        a
    }
}

/// The once-only check of the all-fixed pairs.
pub fn fixed_pairs_admissible(mesh: &Mesh, x: &[f64], fixed: &[PointEdgePair]) -> MinDistance {
    min_distance(mesh, x, fixed)
}
