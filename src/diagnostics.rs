//! Diagnostics of a run: the contact pattern (which bodies touch which).
//!
//! Two bodies touch when some `point_edge` pair between them (vertex of one, edge of the
//! other, x ∉ a) is at distance `< 1.01 ε`. A vertex shared by two bodies (a membrane glued to
//! its support) counts for both.

use crate::geometry::point_edge_distance;
use crate::mesh::Mesh;
use crate::pairs::PointEdgePair;

/// Unordered body pairs `(i, j)`, `i ≤ j`, in contact at `x` (`i = j`: self-contact).
pub fn contact_pattern(
    mesh: &Mesh,
    x: &[f64],
    pairs: &[PointEdgePair],
    eps: f64,
) -> Vec<(usize, usize)> {
    let nbodies = mesh.bodies.len();
    let mut vertex_bodies: Vec<Vec<usize>> = vec![Vec::new(); mesh.nv()];
    for (b, body) in mesh.bodies.iter().enumerate() {
        for &v in &body.vertices {
            vertex_bodies[v].push(b);
        }
    }
    let mut touch = vec![false; nbodies * nbodies];
    for p in pairs {
        let e = mesh.edges[p.a];
        let d =
            point_edge_distance(&Mesh::p2(x, p.x), &Mesh::p2(x, e[0]), &Mesh::p2(x, e[1])).distance;
        if d < 1.01 * eps {
            let be = mesh.edge_body[p.a];
            let vb = &vertex_bodies[p.x];
            for &bv in vb {
                // A glued vertex's own body contact with the edge's body is the glue, not a
                // contact; count self-contact only for a vertex of that body alone.
                if bv == be && vb.len() > 1 {
                    continue;
                }
                let (i, j) = if bv < be { (bv, be) } else { (be, bv) };
                touch[i * nbodies + j] = true;
            }
        }
    }
    let mut out = Vec::new();
    for i in 0..nbodies {
        for j in i..nbodies {
            if touch[i * nbodies + j] {
                out.push((i, j));
            }
        }
    }
    out
}
