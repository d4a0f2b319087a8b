//! The exact Hessian `∇²d` of a pair's distance `d = dist(T1, T2)` (point–edge in 2D,
//! point–triangle and edge–edge in 3D) with respect to the positions of the pair's vertices:
//! the constraints' curvature of the SQP model (docs/method.md, "The SQP outer method").
//!
//! **One formula for every kind.** The closest points are `p = Σ_{i∈near} w_i y_i` and
//! `q = Σ_{j∈far} w_j y_j` (barycentric weights, sum 1 on each side), `r = q − p`, `d = |r|`.
//! Write `c_i` for the signed weights (`+w_j` on the far side, `−w_i` on the near side), so
//! that `r = Σ_i c_i y_i`. The weights that are positive span the faces of the two elements
//! the closest points lie in (a vertex, an edge or a triangle); on each side, with `i₀` the
//! first vertex of the face, `λ_a` the weight of each other vertex `a`, the point is
//! `y_{i₀} + Σ_a λ_a (y_a − y_{i₀})`, and `r` is affine in `λ`: `∂r/∂λ_a = T_a = Σ_i e_{a,i} y_i`
//! (`e_a = ±(δ_a − δ_{i₀})`, `+` far, `−` near). With the face fixed (the closest points in the
//! relative interior of their faces, so `λ` is a smooth interior minimizer),
//! `φ(y) = min_λ ½|r(y, λ)|²` has (Schur complement of `λ`, `f_λ = Tᵀr = 0` at the minimizer)
//!
//! ```text
//!     ∇φ = c ⊗ r,     ∇²φ = ccᵀ ⊗ I − Mᵀ (TᵀT)⁻¹ M,     M_{a,(i,·)} = c_i T_a + e_{a,i} r,
//! ```
//!
//! and `d = √(2φ)`: `∇²d = ∇²φ / d − ∇φ ∇φᵀ / d³`. At a vertex–vertex closest pair (no `λ`)
//! this is `ccᵀ ⊗ (I − nnᵀ)/d`, the Hessian of `|x − a|`; for a 2D point in an edge's interior
//! it is the Hessian of `n·(x − a₀)` with `n` turning with the edge. On the boundary between two
//! faces (a weight exactly 0 or a point at the end of an edge) the distance is `C¹` but not
//! `C²`, and this is the one-sided Hessian of the face the kernel chose.
//!
//! **Where there is none.** `d = 0`, a face whose `TᵀT` is singular or nearly so (parallel
//! edges, whose closest pair is not unique and whose distance is not twice differentiable;
//! a degenerate triangle): `None`, and the caller leaves the pair's curvature out.
//!
//! Every kind is checked against second differences of the distance kernels (tests below).

use super::distance::{edge_edge_distance, point_edge_distance, point_triangle_distance};
use super::{p3, ContactPair};
use crate::scene::mesh::Mesh;

/// The Hessian of one pair's distance on its vertices' coordinates.
#[derive(Clone, Debug)]
pub struct PairHessian {
    /// The pair's vertices (`nv` of them): near side first, then far side.
    pub vertices: [usize; 4],
    /// Number of vertices: 3 (point–edge), 4 (point–triangle, edge–edge).
    pub nv: usize,
    /// Space dimension.
    pub dim: usize,
    /// The distance.
    pub distance: f64,
    /// `∇²d`, row-major, `(nv·dim)²` entries, local index `i·dim + c` (vertex `i`, coordinate
    /// `c`).
    pub h: Vec<f64>,
    /// `∇d = c ⊗ n` on the same local indices.
    pub grad: Vec<f64>,
}

/// `TᵀT` is treated as singular when its smallest Cholesky pivot is below this fraction of its
/// diagonal entry (for two columns, `sin²` of their angle: parallel edges, thin triangles).
const SINGULAR: f64 = 1e-10;

/// The Hessian of `d = |Σ_i c_i y_i|` minimized over the faces (module documentation).
/// `y`: the local vertices' positions (`dim` coordinates used); `near`, `far`: each side's
/// (local vertex, barycentric weight). Returns `(d, ∇²d)` row-major on `(i·dim + c)`.
pub fn hessian_of_distance(
    dim: usize,
    y: &[[f64; 3]],
    near: &[(usize, f64)],
    far: &[(usize, f64)],
) -> Option<(f64, Vec<f64>)> {
    let nv = y.len();
    let nd = nv * dim;
    let mut c = vec![0.0f64; nv];
    for &(i, w) in far {
        c[i] += w;
    }
    for &(i, w) in near {
        c[i] -= w;
    }
    let mut r = [0.0f64; 3];
    for (i, yi) in y.iter().enumerate() {
        for k in 0..dim {
            r[k] += c[i] * yi[k];
        }
    }
    let d = r[..dim].iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(d.is_finite() && d > 0.0) {
        return None;
    }
    // The free parameters: on each side, the weights of the face's vertices after the first.
    let mut e: Vec<Vec<f64>> = Vec::new();
    for (side, sign) in [(far, 1.0f64), (near, -1.0f64)] {
        let support: Vec<usize> = side
            .iter()
            .filter(|(_, w)| *w > 0.0)
            .map(|(i, _)| *i)
            .collect();
        if support.is_empty() {
            return None;
        }
        for &a in &support[1..] {
            let mut ea = vec![0.0; nv];
            ea[a] += sign;
            ea[support[0]] -= sign;
            e.push(ea);
        }
    }
    let m = e.len();
    let t: Vec<[f64; 3]> = e
        .iter()
        .map(|ea| {
            let mut ta = [0.0; 3];
            for (i, yi) in y.iter().enumerate() {
                for k in 0..dim {
                    ta[k] += ea[i] * yi[k];
                }
            }
            ta
        })
        .collect();
    // Cholesky of G = TᵀT (m ≤ 3).
    let mut l = [[0.0f64; 3]; 3];
    for a in 0..m {
        for b in 0..=a {
            let gab: f64 = (0..dim).map(|k| t[a][k] * t[b][k]).sum();
            let s = gab - (0..b).map(|q| l[a][q] * l[b][q]).sum::<f64>();
            if a == b {
                if s.is_nan() || s <= SINGULAR * gab {
                    return None;
                }
                l[a][a] = s.sqrt();
            } else {
                l[a][b] = s / l[b][b];
            }
        }
    }
    // M (m × nd) and L⁻¹M, so that Mᵀ G⁻¹ M = (L⁻¹M)ᵀ (L⁻¹M).
    let mut lm = vec![vec![0.0f64; nd]; m];
    for a in 0..m {
        for i in 0..nv {
            for k in 0..dim {
                lm[a][i * dim + k] = c[i] * t[a][k] + e[a][i] * r[k];
            }
        }
    }
    for a in 0..m {
        for b in 0..a {
            let lab = l[a][b];
            let (lo, hi) = lm.split_at_mut(a);
            for (x, &v) in hi[0].iter_mut().zip(&lo[b]) {
                *x -= lab * v;
            }
        }
        let laa = l[a][a];
        for x in lm[a].iter_mut() {
            *x /= laa;
        }
    }
    let mut h = vec![0.0f64; nd * nd];
    let (d1, d3) = (1.0 / d, 1.0 / (d * d * d));
    for i in 0..nv {
        for k in 0..dim {
            let p = i * dim + k;
            let gp = c[i] * r[k];
            for j in 0..nv {
                for (kk, &rkk) in r.iter().enumerate().take(dim) {
                    let q = j * dim + kk;
                    let mut hphi = if k == kk { c[i] * c[j] } else { 0.0 };
                    for row in &lm {
                        hphi -= row[p] * row[q];
                    }
                    h[p * nd + q] = hphi * d1 - gp * c[j] * rkk * d3;
                }
            }
        }
    }
    Some((d, h))
}

/// The Hessian of `pair`'s distance at `x` (`None`: distance 0, or no Hessian, module
/// documentation).
pub fn pair_hessian(mesh: &Mesh, x: &[f64], pair: ContactPair) -> Option<PairHessian> {
    let dim = mesh.dim;
    let pos = |v: usize| -> [f64; 3] {
        if dim == 2 {
            [x[2 * v], x[2 * v + 1], 0.0]
        } else {
            let p = p3(x, v);
            [p.x, p.y, p.z]
        }
    };
    // (vertices, their number, the near side's and the far side's weights)
    type Parts = ([usize; 4], usize, Vec<(usize, f64)>, Vec<(usize, f64)>);
    let (vertices, nv, near, far): Parts = match pair {
        ContactPair::PointEdge { x: v, a } => {
            let ed = mesh.edges[a];
            let q = point_edge_distance(&Mesh::p2(x, v), &Mesh::p2(x, ed[0]), &Mesh::p2(x, ed[1]));
            (
                [v, ed[0], ed[1], 0],
                3,
                vec![(0, 1.0)],
                vec![(1, q.alpha[0]), (2, q.alpha[1])],
            )
        }
        ContactPair::PointTriangle { x: v, t } => {
            let f = mesh.faces[t];
            let q = point_triangle_distance(&p3(x, v), &p3(x, f[0]), &p3(x, f[1]), &p3(x, f[2]));
            (
                [v, f[0], f[1], f[2]],
                4,
                vec![(0, 1.0)],
                vec![(1, q.beta[0]), (2, q.beta[1]), (3, q.beta[2])],
            )
        }
        ContactPair::EdgeEdge { a, b } => {
            let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
            let q = edge_edge_distance(&p3(x, ea[0]), &p3(x, ea[1]), &p3(x, eb[0]), &p3(x, eb[1]));
            (
                [ea[0], ea[1], eb[0], eb[1]],
                4,
                vec![(0, 1.0 - q.s), (1, q.s)],
                vec![(2, 1.0 - q.t), (3, q.t)],
            )
        }
    };
    let y: Vec<[f64; 3]> = vertices[..nv].iter().map(|&v| pos(v)).collect();
    let (distance, h) = hessian_of_distance(dim, &y, &near, &far)?;
    // ∇d = c ⊗ r / d
    let mut c = [0.0f64; 4];
    for &(i, w) in &far {
        c[i] += w;
    }
    for &(i, w) in &near {
        c[i] -= w;
    }
    let mut r = [0.0f64; 3];
    for i in 0..nv {
        for k in 0..dim {
            r[k] += c[i] * y[i][k];
        }
    }
    let grad = (0..nv * dim)
        .map(|p| c[p / dim] * r[p % dim] / distance)
        .collect();
    Some(PairHessian {
        vertices,
        nv,
        dim,
        distance,
        h,
        grad,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    /// The distance of each kind from local positions (the kernels the rows use).
    #[derive(Clone, Copy, Debug)]
    enum Kind {
        PointEdge,
        PointTriangle,
        EdgeEdge,
    }

    fn dist(kind: Kind, y: &[[f64; 3]]) -> f64 {
        let v2 = |p: [f64; 3]| Vector2::new(p[0], p[1]);
        let v3 = |p: [f64; 3]| Vector3::new(p[0], p[1], p[2]);
        match kind {
            Kind::PointEdge => point_edge_distance(&v2(y[0]), &v2(y[1]), &v2(y[2])).distance,
            Kind::PointTriangle => {
                point_triangle_distance(&v3(y[0]), &v3(y[1]), &v3(y[2]), &v3(y[3])).distance
            }
            Kind::EdgeEdge => {
                edge_edge_distance(&v3(y[0]), &v3(y[1]), &v3(y[2]), &v3(y[3])).distance
            }
        }
    }

    /// The analytic Hessian through the kernels' weights (as `pair_hessian`).
    fn analytic(kind: Kind, y: &[[f64; 3]]) -> Option<(f64, Vec<f64>)> {
        let v2 = |p: [f64; 3]| Vector2::new(p[0], p[1]);
        let v3 = |p: [f64; 3]| Vector3::new(p[0], p[1], p[2]);
        match kind {
            Kind::PointEdge => {
                let q = point_edge_distance(&v2(y[0]), &v2(y[1]), &v2(y[2]));
                hessian_of_distance(2, y, &[(0, 1.0)], &[(1, q.alpha[0]), (2, q.alpha[1])])
            }
            Kind::PointTriangle => {
                let q = point_triangle_distance(&v3(y[0]), &v3(y[1]), &v3(y[2]), &v3(y[3]));
                hessian_of_distance(
                    3,
                    y,
                    &[(0, 1.0)],
                    &[(1, q.beta[0]), (2, q.beta[1]), (3, q.beta[2])],
                )
            }
            Kind::EdgeEdge => {
                let q = edge_edge_distance(&v3(y[0]), &v3(y[1]), &v3(y[2]), &v3(y[3]));
                hessian_of_distance(
                    3,
                    y,
                    &[(0, 1.0 - q.s), (1, q.s)],
                    &[(2, 1.0 - q.t), (3, q.t)],
                )
            }
        }
    }

    /// Central second differences of the distance, step `h`.
    fn fd_hessian(kind: Kind, dim: usize, y: &[[f64; 3]], h: f64) -> Vec<f64> {
        let nd = y.len() * dim;
        let at = |moves: &[(usize, f64)]| {
            let mut z = y.to_vec();
            for &(p, s) in moves {
                z[p / dim][p % dim] += s;
            }
            dist(kind, &z)
        };
        let mut out = vec![0.0; nd * nd];
        for p in 0..nd {
            for q in 0..nd {
                out[p * nd + q] =
                    (at(&[(p, h), (q, h)]) - at(&[(p, h), (q, -h)]) - at(&[(p, -h), (q, h)])
                        + at(&[(p, -h), (q, -h)]))
                        / (4.0 * h * h);
            }
        }
        out
    }

    /// Checks the Hessian of `kind` at `y` against second differences; returns its largest
    /// entry (so that a caller can see the case is not trivial).
    fn check(kind: Kind, y: &[[f64; 3]], what: &str) -> f64 {
        let dim = match kind {
            Kind::PointEdge => 2,
            _ => 3,
        };
        let (d, h) = analytic(kind, y).unwrap_or_else(|| panic!("{what}: no Hessian"));
        assert!(
            (d - dist(kind, y)).abs() <= 1e-14 * d.max(1.0),
            "{what}: distance"
        );
        // the step: small against the distance and the distance to a face boundary
        let step = 1e-5 * d.min(1.0);
        let fd = fd_hessian(kind, dim, y, step);
        let scale = h.iter().fold(1.0 / d, |a: f64, v| a.max(v.abs()));
        for (p, (a, b)) in h.iter().zip(&fd).enumerate() {
            assert!(
                (a - b).abs() <= 2e-4 * scale,
                "{what} ({kind:?}): entry {p}: analytic {a:e}, second differences {b:e} (scale {scale:e})"
            );
        }
        // symmetric
        let nd = y.len() * dim;
        for p in 0..nd {
            for q in 0..nd {
                assert!((h[p * nd + q] - h[q * nd + p]).abs() <= 1e-12 * scale);
            }
        }
        scale
    }

    #[test]
    fn point_edge_interior_and_vertices() {
        // interior: the point above the middle of a tilted edge
        check(
            Kind::PointEdge,
            &[[0.3, 0.9, 0.0], [-0.7, 0.1, 0.0], [1.1, 0.4, 0.0]],
            "interior",
        );
        // closest point the first endpoint, then the second (d = |x − a|)
        check(
            Kind::PointEdge,
            &[[-1.0, 0.5, 0.0], [0.0, 0.0, 0.0], [1.0, 0.2, 0.0]],
            "vertex a0",
        );
        check(
            Kind::PointEdge,
            &[[1.6, -0.4, 0.0], [0.0, 0.0, 0.0], [1.0, 0.2, 0.0]],
            "vertex a1",
        );
        // nearly degenerate: close to the edge (d = 1e-3 of its length), near an endpoint
        check(
            Kind::PointEdge,
            &[[0.02, 1e-3, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            "close, near an end",
        );
    }

    #[test]
    fn point_edge_vertex_case_is_the_projector() {
        // d = |x − a0|: ∇²d = ccᵀ ⊗ (I − nnᵀ)/d, c = (−1, 1, 0)
        let y = [[-3.0, 4.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let (d, h) = analytic(Kind::PointEdge, &y).unwrap();
        assert!((d - 5.0).abs() < 1e-15);
        let n = [3.0 / 5.0, -4.0 / 5.0];
        let c = [-1.0, 1.0, 0.0];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..2 {
                    for kk in 0..2 {
                        let proj = if k == kk { 1.0 } else { 0.0 } - n[k] * n[kk];
                        let want = c[i] * c[j] * proj / d;
                        let got = h[(i * 2 + k) * 6 + j * 2 + kk];
                        assert!((got - want).abs() < 1e-15, "{i} {j} {k} {kk}");
                    }
                }
            }
        }
    }

    #[test]
    fn point_triangle_face_edge_vertex() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.1, 0.2], [0.2, 1.0, -0.1]];
        let with = |p: [f64; 3]| [p, t[0], t[1], t[2]];
        check(Kind::PointTriangle, &with([0.3, 0.3, 0.8]), "face");
        check(Kind::PointTriangle, &with([0.3, 0.3, -0.6]), "face, below");
        check(Kind::PointTriangle, &with([0.5, -0.6, 0.3]), "edge t0t1");
        check(Kind::PointTriangle, &with([0.9, 0.9, 0.2]), "edge t1t2");
        check(Kind::PointTriangle, &with([-0.5, -0.4, 0.1]), "vertex t0");
        check(Kind::PointTriangle, &with([1.6, 0.0, 0.5]), "vertex t1");
        // nearly degenerate: very close to the face (1e-3 of its size)
        check(
            Kind::PointTriangle,
            &with([0.3, 0.3, 0.06 + 1e-3]),
            "close to the face",
        );
        // a thin (but not degenerate) triangle
        let thin = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-2, 0.0]];
        check(
            Kind::PointTriangle,
            &[[0.5, 0.004, 0.3], thin[0], thin[1], thin[2]],
            "thin triangle, face",
        );
    }

    #[test]
    fn edge_edge_interior_end_and_ends() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.2, 0.1]];
        let ee = |b0: [f64; 3], b1: [f64; 3]| [a[0], a[1], b0, b1];
        check(
            Kind::EdgeEdge,
            &ee([0.5, -0.5, 0.6], [0.4, 0.8, 0.5]),
            "interior",
        );
        check(
            Kind::EdgeEdge,
            &ee([1.5, -0.5, 0.6], [1.4, 0.8, 0.5]),
            "s = 1, t interior",
        );
        check(
            Kind::EdgeEdge,
            &ee([-0.4, -0.5, 0.6], [-1.4, -1.8, 0.5]),
            "ends",
        );
        check(
            Kind::EdgeEdge,
            &ee([0.5, 0.5, 0.6], [0.5, 1.5, 0.9]),
            "t = 0, s interior",
        );
        // nearly parallel (sin of the angle 1e-3)
        check(
            Kind::EdgeEdge,
            &ee([0.3, 0.06, 0.5], [1.3, 0.26 + 1e-3, 0.6]),
            "nearly parallel",
        );
    }

    #[test]
    fn random_configurations_of_every_kind() {
        // deterministic pseudo-random points (an LCG), every kind, whatever face is closest
        let mut s: u64 = 0x9e3779b97f4a7c15;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut checked = 0;
        for kind in [Kind::PointEdge, Kind::PointTriangle, Kind::EdgeEdge] {
            for case in 0..60 {
                let mut y = [[0.0; 3]; 4];
                for p in y.iter_mut() {
                    for v in p.iter_mut() {
                        *v = rnd();
                    }
                }
                let nv = match kind {
                    Kind::PointEdge => {
                        for p in y.iter_mut() {
                            p[2] = 0.0;
                        }
                        3
                    }
                    _ => 4,
                };
                let y = &y[..nv];
                let d = dist(kind, y);
                // skip configurations within the second differences' reach of a face boundary
                // (there the distance is C¹ only) or too close to touching
                if d < 0.05 || near_face_boundary(kind, y, 1e-3) {
                    continue;
                }
                check(kind, y, &format!("random {case}"));
                checked += 1;
            }
        }
        assert!(checked >= 100, "only {checked} random cases");
    }

    /// Whether the closest points' weights change face within a move of `r` of any coordinate
    /// (sampled at ± r along each coordinate).
    fn near_face_boundary(kind: Kind, y: &[[f64; 3]], r: f64) -> bool {
        let faces = |z: &[[f64; 3]]| -> Vec<bool> {
            let v2 = |p: [f64; 3]| Vector2::new(p[0], p[1]);
            let v3 = |p: [f64; 3]| Vector3::new(p[0], p[1], p[2]);
            match kind {
                Kind::PointEdge => {
                    let q = point_edge_distance(&v2(z[0]), &v2(z[1]), &v2(z[2]));
                    q.alpha.iter().map(|w| *w > 0.0).collect()
                }
                Kind::PointTriangle => {
                    let q = point_triangle_distance(&v3(z[0]), &v3(z[1]), &v3(z[2]), &v3(z[3]));
                    q.beta.iter().map(|w| *w > 0.0).collect()
                }
                Kind::EdgeEdge => {
                    let q = edge_edge_distance(&v3(z[0]), &v3(z[1]), &v3(z[2]), &v3(z[3]));
                    vec![q.s > 0.0, q.s < 1.0, q.t > 0.0, q.t < 1.0]
                }
            }
        };
        let f0 = faces(y);
        for i in 0..y.len() {
            for k in 0..3 {
                for s in [-r, r] {
                    let mut z = y.to_vec();
                    z[i][k] += s;
                    if faces(&z) != f0 {
                        return true;
                    }
                }
            }
        }
        false
    }

    #[test]
    fn parallel_edges_and_touching_have_none() {
        let y = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.2, 0.5, 0.0],
            [1.2, 0.5, 0.0],
        ];
        assert!(analytic(Kind::EdgeEdge, &y).is_none());
        let touching = [[0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        assert!(analytic(Kind::PointEdge, &touching).is_none());
    }
}
