//! The continuous check of a straight motion: does any pair of disjoint contact elements come
//! closer than a thickness `η` somewhere on the way (tunnelling)? Conservative advancement on
//! the distance of each candidate pair.
//!
//! Along `φ(τ) = x + τu`, `u = y − x`, `τ ∈ [0, 1]`, the distance `f(τ)` of two elements is
//! Lipschitz with constant
//!
//! ```text
//!     L = max |u(p) − u(q)|,   p a vertex of one element, q of the other:
//! ```
//!
//! for fixed barycentric weights the distance between the two points moves by at most the
//! largest relative displacement of the vertices, and a minimum of L-Lipschitz functions is
//! L-Lipschitz. So `f ≥ η` on `[τ, τ + (f(τ) − η)/L]`, and conservative advancement
//! `τ ← τ + (f(τ) − η)/L` either proves `f ≥ η` on the whole motion or stops where `f` comes
//! within [`HIT_REL`]`·η` of `η` (or after [`MAX_ADVANCES`] steps): that `τ` is reported, a
//! conservative time of contact (the pair may pass a little above `η`; it never passes below
//! unnoticed).
//!
//! **Candidates** are [`AnyMotionSearch::candidates`] at thickness `η`: every other pair has a
//! gap at x above `η + L` and stays farther than `η` all along.
//!
//! **Completeness.** Two disjoint elements (edges in 2D; faces, edges and vertices in 3D) first
//! touch at a vertex–edge contact in 2D, a vertex–triangle or edge–edge contact in 3D, so
//! `point_edge` pairs (2D) and `point_triangle` and `edge_edge` pairs (3D) cover every way one
//! part of the mesh can pass through another; a motion that keeps all of them at least `η`
//! apart (η > 0) passes nothing through anything.

use crate::contact::distance::{edge_edge_distance, point_edge_distance, point_triangle_distance};
use crate::contact::motion::AnyMotionSearch;
use crate::contact::ContactPair;
use crate::scene::mesh::Mesh;
use nalgebra::{Vector2, Vector3};
use rayon::prelude::*;

/// A pair reported within this fraction of `η` above `η` counts as touching (the end of the
/// advancement: its steps shrink like `f − η`).
pub const HIT_REL: f64 = 1e-6;

/// Advancement steps per pair at most; a pair that needs more is reported at the `τ` reached.
pub const MAX_ADVANCES: usize = 10_000;

/// The first pair of a motion to come within the thickness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// The pair.
    pub pair: ContactPair,
    /// The conservative time of contact in `[0, 1]`: the pair is at least `η` apart on
    /// `[0, τ)`.
    pub tau: f64,
    /// Its distance at `τ`.
    pub distance: f64,
}

/// The vertices of the two elements of `pair` (the second list empty past its length).
fn elements(mesh: &Mesh, pair: ContactPair) -> ([usize; 2], usize, [usize; 3], usize) {
    match pair {
        ContactPair::PointEdge { x, a } => ([x, 0], 1, [mesh.edges[a][0], mesh.edges[a][1], 0], 2),
        ContactPair::PointTriangle { x, t } => ([x, 0], 1, mesh.faces[t], 3),
        ContactPair::EdgeEdge { a, b } => {
            (mesh.edges[a], 2, [mesh.edges[b][0], mesh.edges[b][1], 0], 2)
        }
    }
}

/// The distance of `pair` at the positions `at(v)` of its vertices (3D vectors; `z` ignored
/// in 2D), with the kernels of [`crate::contact::distance`].
pub fn pair_distance(mesh: &Mesh, pair: ContactPair, at: impl Fn(usize) -> Vector3<f64>) -> f64 {
    let p2 = |v: usize| {
        let p = at(v);
        Vector2::new(p.x, p.y)
    };
    match pair {
        ContactPair::PointEdge { x, a } => {
            let e = mesh.edges[a];
            point_edge_distance(&p2(x), &p2(e[0]), &p2(e[1])).distance
        }
        ContactPair::PointTriangle { x, t } => {
            let f = mesh.faces[t];
            point_triangle_distance(&at(x), &at(f[0]), &at(f[1]), &at(f[2])).distance
        }
        ContactPair::EdgeEdge { a, b } => {
            let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
            edge_edge_distance(&at(ea[0]), &at(ea[1]), &at(eb[0]), &at(eb[1])).distance
        }
    }
}

/// Conservative advancement of one pair along `x + τu`: `None` when its distance stays at
/// least `eta` on `[0, 1]`, else the [`Contact`] where it stops (module documentation).
pub fn advance(mesh: &Mesh, pair: ContactPair, x: &[f64], u: &[f64], eta: f64) -> Option<Contact> {
    let d = mesh.dim;
    let at = |v: usize, tau: f64| {
        let mut p = Vector3::zeros();
        for c in 0..d {
            p[c] = x[d * v + c] + tau * u[d * v + c];
        }
        p
    };
    let (a, na, b, nb) = elements(mesh, pair);
    let mut lip = 0.0f64;
    for &p in &a[..na] {
        for &q in &b[..nb] {
            let mut s = 0.0;
            for c in 0..d {
                let w = u[d * p + c] - u[d * q + c];
                s += w * w;
            }
            lip = lip.max(s);
        }
    }
    let lip = lip.sqrt();
    let mut tau = 0.0f64;
    for _ in 0..MAX_ADVANCES {
        let f = pair_distance(mesh, pair, |v| at(v, tau));
        if f.is_nan() || f - eta <= HIT_REL * eta {
            return Some(Contact {
                pair,
                tau,
                distance: f,
            });
        }
        if lip == 0.0 {
            return None;
        }
        let step = (f - eta) / lip;
        if tau + step >= 1.0 {
            return None;
        }
        tau += step;
    }
    let f = pair_distance(mesh, pair, |v| at(v, tau));
    Some(Contact {
        pair,
        tau,
        distance: f,
    })
}

/// The first pair of disjoint contact elements (with a free vertex, allowed by the contact
/// filter) whose distance comes within `eta` on the straight motion from `x` to `y`, `None`
/// when every pair stays at least `eta` apart. `search` holds the trees at `x`. The earliest
/// `τ` wins, ties by pair order, so the answer does not depend on the thread count.
pub fn first_contact(
    mesh: &Mesh,
    search: &AnyMotionSearch,
    x: &[f64],
    y: &[f64],
    eta: f64,
) -> Option<Contact> {
    let u: Vec<f64> = y.iter().zip(x).map(|(a, b)| a - b).collect();
    let cands = search.candidates(mesh, x, y, eta);
    cands
        .par_iter()
        .map(|&p| advance(mesh, p, x, &u, eta))
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .fold(None, |best: Option<Contact>, c| match best {
            Some(b) if b.tau <= c.tau => Some(b),
            _ => Some(c),
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::{Body, BodyKind};

    /// Two horizontal segments in 2D: `[0, 1] × {0}` (fixed) and a free one at height `h`.
    fn two_segments(h: f64) -> (Mesh, Vec<f64>) {
        let x = vec![0.0, 0.0, 1.0, 0.0, 0.3, h, 0.7, h];
        let mesh = Mesh {
            dim: 2,
            x_ref: x.clone(),
            fixed: vec![true, true, false, false],
            edges: vec![[0, 1], [2, 3]],
            edge_body: vec![0, 1],
            bodies: vec![
                Body {
                    name: "low".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![0, 1],
                    ..Default::default()
                },
                Body {
                    name: "up".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![2, 3],
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        (mesh, x)
    }

    #[test]
    fn continuous_check_catches_a_pass_through_that_both_ends_hide() {
        // the upper segment jumps from 0.1 above to 0.1 below: both ends are admissible for
        // ε = 0.05, the motion passes through the lower segment
        let (mesh, x) = two_segments(0.1);
        let mut y = x.clone();
        y[5] = -0.1;
        y[7] = -0.1;
        assert!(crate::contact::min_distance(&mesh, &y, 0.1, false).distance >= 0.1 - 1e-15);
        let search = AnyMotionSearch::new(&mesh, &x);
        let c = first_contact(&mesh, &search, &x, &y, 0.025).expect("the motion tunnels");
        // the segments come within η = 0.025 at τ = (0.1 − 0.025) / 0.2 = 0.375
        assert!(
            (c.tau - 0.375).abs() < 1e-6,
            "contact at τ = {} ({:?})",
            c.tau,
            c.pair
        );
        assert!(
            c.distance >= 0.025 * (1.0 - 1e-12) && c.distance < 0.025 * (1.0 + 2.0 * HIT_REL),
            "{c:?}"
        );
        // the same motion stopped short of the lower segment is clear
        let mut z = x.clone();
        z[5] = 0.03;
        z[7] = 0.03;
        assert_eq!(first_contact(&mesh, &search, &x, &z, 0.025), None);
    }

    #[test]
    fn continuous_check_passes_a_motion_that_slides_along() {
        // sliding by 0.5 along the lower segment at constant height 0.05: η = 0.025 is never
        // reached, nor a distance below 0.05
        let (mesh, x) = two_segments(0.05);
        let mut y = x.clone();
        y[4] += 0.5;
        y[6] += 0.5;
        let search = AnyMotionSearch::new(&mesh, &x);
        assert_eq!(first_contact(&mesh, &search, &x, &y, 0.025), None);
        // at η just below the height it is reported, at once
        let c = first_contact(&mesh, &search, &x, &y, 0.05).expect("touching");
        assert_eq!(c.tau, 0.0);
    }
}
