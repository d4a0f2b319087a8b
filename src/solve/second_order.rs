//! The second-order check: whether a certified KKT point is a local minimum of problem (3)
//! (docs/method.md, "The second-order check").
//!
//! The certificate κ ([`crate::solve::certificate`]) says that `J'(φ_h) = Σ μ_k ∇d_k` with
//! `μ ≥ 0`: a KKT point, which can be a minimum, a saddle or a maximum along the contact set.
//! With the certificate's multipliers, the Hessian of the Lagrangian
//!
//! ```text
//!     L = ∇²J(φ_h) − Σ_k μ_k ∇²d_k        (the exact Hessian of J; ∇²d_k of each pair's distance)
//! ```
//!
//! is restricted to `Z`, the free directions that keep every strongly active distance fixed to
//! first order (`∇d_k · v = 0` for `μ_k > 1e-6 max μ`), and its smallest eigenvalue `λ_min` is
//! compared with the largest `|λ|` of the restricted matrix:
//!
//! * `minimum`: `λ_min > 1e-8 max|λ|`. The second-order sufficient condition holds on `Z`,
//!   which contains the critical cone (the weakly active distances only shrink it), so φ_h is
//!   a strict local minimum (for these multipliers; no constraint qualification is needed).
//! * `degenerate`: no eigenvalue below `−1e-8 max|λ|`, some within `1e-8 max|λ|` of zero
//!   (a frictionless block free to slide, a slack string's vertex): the second-order
//!   necessary condition holds on `Z`; the flat directions are not decided.
//! * `not_minimum`: negative curvature, and an admissible point with lower J was found along
//!   the lowest mode: from φ_h, `±t v`, then least-norm corrections along the active
//!   gradients back to the strongly active distances' values (the weakly active ones kept at
//!   least at theirs), the exact admissibility check passed, J lower at `t`, `t/2` and `t/4`
//!   by decreases that shrink like `t²` (`t = h/4, h/8, …`): a descent the mode explains,
//!   not a far basin. The step and the decrease are reported.
//! * `undetermined`: negative curvature on `Z` and no such point (a weakly active distance,
//!   not in `Z`'s constraints, can forbid the mode: the critical cone is smaller than `Z`), or
//!   a pair whose distance has no Hessian (parallel edges). The reason says which.
//! * `not_computed`: more free dofs than the bound, [`SECOND_ORDER_MAX_DOFS`] by default (the
//!   check is dense).
//!
//! The signs of the eigenvalues of a restriction to a subspace do not depend on the basis
//! chosen (Sylvester's law of inertia), so the classification does not depend on the inner
//! product (their sizes, `min_eigenvalue_rel`, do); the Euclidean one of the free dofs is used.
//! The distances are piecewise smooth: where a closest point is on an element's boundary the
//! Hessian is that of the distance to the lower-dimensional feature
//! ([`crate::contact::hessian::hessian_of_distance`]), one side of a kink.

use crate::contact::hessian::pair_hessian;
use crate::contact::min_distance;
use crate::energy::{HessianModel, Objective};
use crate::scene::mesh::Mesh;
use crate::solve::certificate::{ActiveGenerator, Certificate};
use crate::solve::outer::roundoff_allowance;
use faer::linalg::solvers::Solve;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

/// Free dofs above which `contactlab run` does not compute the check: it is dense (eigenvalues
/// of an `n × n` matrix), 0.03–0.22 s at 525–632 free dofs, 0.14–0.21 s at 954–1 053,
/// 0.27–0.69 s at 1 272–1 350 (`results/second_order.csv`; docs/method.md, "The
/// second-order check");
/// `contactlab run --second-order-max-dofs N` sets another bound.
pub const SECOND_ORDER_MAX_DOFS: usize = 1200;
/// A multiplier above this fraction of the largest makes its distance strongly active.
const STRONG_REL: f64 = 1e-6;
/// Eigenvalues within this fraction of the largest `|λ|` count as zero.
const EIG_REL: f64 = 1e-8;
/// A gradient whose norm falls below this fraction of its own under Gram–Schmidt is dependent.
const RANK_REL: f64 = 1e-8;

/// The outcome of the second-order check (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SecondOrder {
    /// `minimum`, `not_minimum`, `undetermined` or `not_computed`.
    pub status: String,
    /// Why `undetermined` or `not_computed` (empty otherwise).
    pub reason: String,
    /// `λ_min / max|λ|` of the restricted Hessian of the Lagrangian (`null` when not computed).
    pub min_eigenvalue_rel: Option<f64>,
    /// Free dofs.
    pub free_dofs: usize,
    /// Distances with `μ > 1e-6 max μ`.
    pub strongly_active: usize,
    /// The other generators of the certificate (distances within its tolerance of ε).
    pub weakly_active: usize,
    /// Rank of the strongly active gradients (the dimension of `Z` is `free_dofs` minus it).
    pub rank: usize,
    /// Eigenvalues of the restriction below `−1e-8 max|λ|`.
    pub negative_modes: usize,
    /// Eigenvalues of the restriction within `1e-8 max|λ|` of zero (flat directions: a
    /// frictionless block free to slide, a slack string's vertex).
    pub zero_modes: usize,
    /// `not_minimum`: the step `t` (a length: the mode is a unit vector of the free dofs)
    /// along the negative mode at which the lower admissible point was found.
    pub descent_step: Option<f64>,
    /// `not_minimum`: `J(φ_h) − J` at that point (> 0).
    pub descent_decrease: Option<f64>,
    /// `not_minimum`: that point (all dofs). Not serialized.
    #[serde(skip)]
    pub point: Option<Vec<f64>>,
    /// Seconds spent.
    pub seconds: f64,
}

impl SecondOrder {
    fn new(status: &str, reason: String) -> SecondOrder {
        SecondOrder {
            status: status.into(),
            reason,
            ..SecondOrder::default()
        }
    }
}

/// Orthonormal basis (Gram–Schmidt, twice) of the span of the given vectors; a vector whose
/// norm falls below `RANK_REL` of its own once projected is dependent and left out.
fn orthonormal(vectors: &[DVector<f64>]) -> Vec<DVector<f64>> {
    let mut q: Vec<DVector<f64>> = Vec::new();
    for v in vectors {
        let n0 = v.norm();
        let mut w = v.clone();
        for _ in 0..2 {
            for qi in &q {
                let c = qi.dot(&w);
                w.axpy(-c, qi, 1.0);
            }
        }
        let n = w.norm();
        if n0 > 0.0 && n > RANK_REL * n0 {
            q.push(w / n);
        }
    }
    q
}

/// A dense gradient on `nf` free columns.
fn dense(g: &ActiveGenerator, nf: usize) -> DVector<f64> {
    let mut v = DVector::zeros(nf);
    for &(c, a) in &g.gradient {
        v[c] += a;
    }
    v
}

/// The second-order check at `x` with the certificate's multipliers (`cert.active`); `col`
/// maps each dof to its free column (`usize::MAX`: fixed), as the certificate's; `h` is the
/// mesh size (the scale of the steps tried), `max_dofs` the bound above which it is
/// `not_computed`.
#[allow(clippy::too_many_arguments)]
pub fn second_order(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    col: &[usize],
    cert: &Certificate,
    eps: f64,
    h: f64,
    max_dofs: usize,
) -> SecondOrder {
    let t0 = Instant::now();
    let nf = col.iter().filter(|&&c| c != usize::MAX).count();
    // A fault in the check must not cost the run its outputs: it is reported instead.
    let mut out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        check(mesh, energy, x, col, nf, cert, eps, h, max_dofs)
    }))
    .unwrap_or_else(|_| SecondOrder::new("undetermined", "the check failed (a panic)".into()));
    out.free_dofs = nf;
    out.seconds = t0.elapsed().as_secs_f64();
    out
}

#[allow(clippy::too_many_arguments)]
fn check(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    col: &[usize],
    nf: usize,
    cert: &Certificate,
    eps: f64,
    hmesh: f64,
    max_dofs: usize,
) -> SecondOrder {
    if nf > max_dofs {
        return SecondOrder::new(
            "not_computed",
            format!("{nf} free dofs, above {max_dofs} (--second-order-max-dofs)"),
        );
    }
    if nf == 0 {
        return SecondOrder::new("undetermined", "no free dofs".into());
    }
    // ∇²J on the free columns
    let hj = energy.hessian(x, HessianModel::Exact);
    let mut h = DMatrix::<f64>::zeros(nf, nf);
    for &(i, j, v) in &hj.triplets {
        let (ci, cj) = (col[i], col[j]);
        if ci != usize::MAX && cj != usize::MAX {
            h[(ci, cj)] += v;
        }
    }
    for r in &hj.rank_one {
        let w: Vec<(usize, f64)> =
            r.w.iter()
                .filter(|(i, _)| col[*i] != usize::MAX)
                .map(|&(i, a)| (col[i], a))
                .collect();
        for &(ci, a) in &w {
            for &(cj, b) in &w {
                h[(ci, cj)] += r.coef * a * b;
            }
        }
    }
    // − Σ μ_k ∇²d_k
    let mu_max = cert.active.iter().fold(0.0f64, |m, g| m.max(g.mu));
    let strong: Vec<&ActiveGenerator> = cert
        .active
        .iter()
        .filter(|g| mu_max > 0.0 && g.mu > STRONG_REL * mu_max)
        .collect();
    let weak: Vec<&ActiveGenerator> = cert
        .active
        .iter()
        .filter(|g| !(mu_max > 0.0 && g.mu > STRONG_REL * mu_max))
        .collect();
    let dim = mesh.dim;
    for g in cert.active.iter().filter(|g| g.mu > 0.0) {
        let ph = match (g.part, pair_hessian(mesh, x, g.pair)) {
            (0, Some(ph)) => ph,
            _ => {
                return SecondOrder::new(
                    "undetermined",
                    format!("no Hessian of the distance of {:?}", g.pair),
                )
            }
        };
        let nd = ph.nv * dim;
        for p in 0..nd {
            let cp = col[dim * ph.vertices[p / dim] + p % dim];
            if cp == usize::MAX {
                continue;
            }
            for q in 0..nd {
                let cq = col[dim * ph.vertices[q / dim] + q % dim];
                if cq != usize::MAX {
                    h[(cp, cq)] -= g.mu * ph.h[p * nd + q];
                }
            }
        }
    }
    let h = (&h + h.transpose()) * 0.5;
    // Z: the orthogonal complement of the strongly active gradients
    let sg: Vec<DVector<f64>> = strong.iter().map(|g| dense(g, nf)).collect();
    let q = orthonormal(&sg);
    let r = q.len();
    let mut out = SecondOrder {
        strongly_active: strong.len(),
        weakly_active: weak.len(),
        rank: r,
        ..SecondOrder::default()
    };
    if r == nf {
        out.status = "minimum".into();
        out.reason = "the active gradients span every free direction".into();
        return out;
    }
    // M = P H P + c (I − P), P = I − Q Qᵀ: its spectrum is that of H on Z and c (r times).
    let qm = if r == 0 {
        DMatrix::zeros(nf, 0)
    } else {
        DMatrix::from_columns(&q)
    };
    let hq = &h * &qm;
    let qhq = qm.transpose() * &hq;
    let c = 1.0
        + (0..nf)
            .map(|i| h.row(i).iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
    let m = &h - &qm * hq.transpose() - &hq * qm.transpose()
        + &qm * (qhq + DMatrix::identity(r, r) * c) * qm.transpose();
    // The dense eigenvalues and the Cholesky factor below are faer's (blocked; 4.6–5.1×
    // faster than nalgebra's at 1 300–2 000 dofs, docs/method.md, "The second-order check").
    let m = faer::Mat::<f64>::from_fn(nf, nf, |i, j| 0.5 * (m[(i, j)] + m[(j, i)]));
    let Ok(mut eig) = m.self_adjoint_eigenvalues(faer::Side::Lower) else {
        return SecondOrder::new("undetermined", "the eigenvalue solver failed".into());
    };
    eig.sort_by(f64::total_cmp);
    let reduced = &eig[..nf - r];
    let lmin = reduced[0];
    let scale = reduced.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    if scale == 0.0 {
        out.status = "degenerate".into();
        out.zero_modes = nf - r;
        out.min_eigenvalue_rel = Some(0.0);
        out.reason =
            "the restricted Hessian vanishes: every direction is flat to second order".into();
        return out;
    }
    let rel = lmin / scale;
    out.min_eigenvalue_rel = Some(rel);
    out.negative_modes = reduced.iter().filter(|&&l| l < -EIG_REL * scale).count();
    out.zero_modes = reduced
        .iter()
        .filter(|&&l| l.abs() <= EIG_REL * scale)
        .count();
    if rel > EIG_REL {
        out.status = "minimum".into();
        return out;
    }
    if rel >= -EIG_REL {
        out.status = "degenerate".into();
        out.reason = format!(
            "no negative curvature; {} flat direction(s) that second order does not decide",
            out.zero_modes
        );
        return out;
    }
    // The eigenvector of λ_min: inverse iteration on M − sI, s just below λ_min.
    let s = lmin - 1e-3 * (scale * EIG_REL).max(lmin.abs());
    let shifted =
        faer::Mat::<f64>::from_fn(nf, nf, |i, j| m[(i, j)] - if i == j { s } else { 0.0 });
    let Ok(chol) = shifted.llt(faer::Side::Lower) else {
        out.status = "undetermined".into();
        out.reason = "inverse iteration failed".into();
        return out;
    };
    let mut v = DVector::from_element(nf, 1.0 / (nf as f64).sqrt());
    for _ in 0..4 {
        let y = chol.solve(faer::Col::<f64>::from_fn(nf, |i| v[i]));
        v = DVector::from_fn(nf, |i, _| y[i]);
        // keep it in Z
        for qi in &q {
            let c = qi.dot(&v);
            v.axpy(-c, qi, 1.0);
        }
        let n = v.norm();
        if n == 0.0 {
            break;
        }
        v /= n;
    }
    match descent(mesh, energy, x, col, cert, &v, eps, hmesh) {
        Some((t, dj, z)) => {
            out.status = "not_minimum".into();
            out.descent_step = Some(t);
            out.descent_decrease = Some(dj);
            out.point = Some(z);
        }
        None => {
            out.status = "undetermined".into();
            out.reason = format!(
                "{} negative mode(s), and no lower admissible point was found along the lowest",
                out.negative_modes
            );
        }
    }
    out
}

/// Along the unit free-dof direction `±v` (a negative mode of the restricted Hessian): the
/// largest `t = h/4, h/8, …, h/2²⁰` such that the points at `t`, `t/2` and `t/4`, each brought
/// back to the strongly active distances' values at x (and the weakly active ones to at least
/// theirs; both within the exact check's tolerance of ε) by
/// least-norm corrections along their gradients, pass the exact admissibility check and have
/// J below J(x) by more than round-off, by decreases that shrink like `t²` (the decrease at
/// `t` is 4 to 64 times that at `t/4`). Returns `t`, the decrease of J at `t` and the point.
#[allow(clippy::too_many_arguments)]
fn descent(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    col: &[usize],
    cert: &Certificate,
    v: &DVector<f64>,
    eps: f64,
    h: f64,
) -> Option<(f64, f64, Vec<f64>)> {
    let jx = energy.value(x);
    let round = 64.0 * f64::EPSILON * jx.abs().max(f64::MIN_POSITIVE);
    let mu_max = cert.active.iter().fold(0.0f64, |m, g| m.max(g.mu));
    // each distance's level: its value at x (not ε: bringing a distance from ε + 1e-12 down
    // to ε would lower J by μ·1e-12 at any t, a decrease that is not the mode's)
    let mut gens: Vec<(&ActiveGenerator, bool, f64)> = Vec::new();
    for g in cert.active.iter().filter(|g| g.part == 0) {
        let d = crate::contact::pair_rows(mesh, x, g.pair)?.distance;
        gens.push((g, mu_max > 0.0 && g.mu > STRONG_REL * mu_max, d));
    }
    let mut free_dof = vec![0usize; v.len()];
    for (dof, &c) in col.iter().enumerate() {
        if c != usize::MAX {
            free_dof[c] = dof;
        }
    }
    let lower = |t: f64| -> Option<(f64, Vec<f64>)> {
        let mut z: Vec<f64> = x
            .iter()
            .zip(col)
            .map(|(&xi, &c)| if c == usize::MAX { xi } else { xi + t * v[c] })
            .collect();
        let tol = 1e-14 * eps.max(f64::MIN_POSITIVE);
        for round_k in 0..=10 {
            // the distances to bring back: strong ones to their level, weak ones up to it
            let mut rows: Vec<(&ActiveGenerator, f64)> = Vec::new();
            let mut worst = 0.0f64;
            for &(g, strong, level) in &gens {
                let d = crate::contact::pair_rows(mesh, &z, g.pair)?.distance;
                if strong || d < level {
                    worst = worst.max((level - d).abs());
                    rows.push((g, level - d));
                }
            }
            if worst <= tol {
                break;
            }
            if round_k == 10 {
                return None;
            }
            // least norm along the gradients (sparse: a pair's touches at most 4 vertices),
            // regularized by 1e-12 of the mean diagonal (dependent rows: parallel copies of
            // one gradient); the next round corrects what that leaves
            let k = rows.len();
            let mut dense_g = vec![0.0; v.len()];
            let mut aat = faer::Mat::<f64>::zeros(k, k);
            for (i, (gi, _)) in rows.iter().enumerate() {
                for &(c, w) in &gi.gradient {
                    dense_g[c] += w;
                }
                for (j, (gj, _)) in rows.iter().enumerate().skip(i) {
                    let d: f64 = gj.gradient.iter().map(|&(c, w)| dense_g[c] * w).sum();
                    aat[(i, j)] = d;
                    aat[(j, i)] = d;
                }
                for &(c, _) in &gi.gradient {
                    dense_g[c] = 0.0;
                }
            }
            let reg = 1e-12 * (0..k).map(|i| aat[(i, i)]).sum::<f64>() / k as f64;
            for i in 0..k {
                aat[(i, i)] += reg;
            }
            let r = faer::Col::<f64>::from_fn(k, |i| rows[i].1);
            let alpha = aat.llt(faer::Side::Lower).ok()?.solve(r);
            for ((g, _), a) in rows.iter().zip(alpha.iter()) {
                for &(c, w) in &g.gradient {
                    let dof = free_dof[c];
                    z[dof] += a * w;
                }
            }
        }
        let md = min_distance(mesh, &z, 2.0 * eps, true);
        if md.distance < eps - roundoff_allowance(&z) {
            return None;
        }
        let jz = energy.value(&z);
        (jz.is_finite() && jz < jx - round).then_some((jx - jz, z))
    };
    for k in 2..=20 {
        let t = h / f64::from(1u32 << k);
        for sign in [1.0, -1.0] {
            // lower at t, t/2 and t/4, by a decrease that shrinks like t² (a ratio of 16
            // over the factor 4; 4 … 64 accepted): the mode's, not another basin's
            let Some((d1, z)) = lower(sign * t) else {
                continue;
            };
            if lower(sign * t / 2.0).is_none() {
                continue;
            }
            if let Some((d4, _)) = lower(sign * t / 4.0) {
                if (4.0..=64.0).contains(&(d1 / d4)) {
                    return Some((t, d1, z));
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Hessian;
    use crate::scene::mesh::{Body, BodyKind};
    use crate::solve::certificate::certificate;
    use crate::solve::h1::H1Norms;
    use std::collections::HashMap;

    /// `½ k |x₀ − target|²` for vertex 0 (with `kx = 0`: its x coordinate free of charge).
    struct Pull {
        target: [f64; 2],
        kx: f64,
    }

    impl Objective for Pull {
        fn value(&self, x: &[f64]) -> f64 {
            let (a, b) = (x[0] - self.target[0], x[1] - self.target[1]);
            0.5 * (self.kx * a * a + b * b)
        }
        fn gradient(&self, x: &[f64]) -> Vec<f64> {
            let mut g = vec![0.0; x.len()];
            g[0] = self.kx * (x[0] - self.target[0]);
            g[1] = x[1] - self.target[1];
            g
        }
        fn hessian(&self, _x: &[f64], _model: HessianModel) -> Hessian {
            Hessian {
                triplets: vec![(0, 0, self.kx), (1, 1, 1.0)],
                rank_one: Vec::new(),
            }
        }
        fn model_is_psd(&self, _model: HessianModel) -> bool {
            true
        }
    }

    /// Vertex 0 free, on a string [0, 3] to a fixed vertex 3 above it; the fixed obstacle edge
    /// [1, 2]. `x` holds the four positions.
    fn mesh(x: &[f64]) -> Mesh {
        Mesh {
            dim: 2,
            x_ref: x.to_vec(),
            fixed: vec![false, true, true, true],
            edges: vec![[1, 2], [0, 3]],
            edge_body: vec![1, 0],
            bodies: vec![
                Body {
                    name: "string".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![0, 3],
                    edges: vec![1],
                    ..Default::default()
                },
                Body {
                    name: "obstacle".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![1, 2],
                    edges: vec![0],
                    ..Default::default()
                },
            ],
            ..Default::default()
        }
    }

    const EPS: f64 = 0.01;

    /// The check at `x` (a KKT point of `energy` with vertex 0 at distance ε of the obstacle),
    /// with the certificate's multipliers.
    fn check_at(x: &[f64], energy: &Pull) -> (Certificate, SecondOrder) {
        let m = mesh(x);
        let norms = H1Norms::scaled(&m).unwrap();
        let cert = certificate(&m, energy, x, EPS, 1e-12, &norms, &HashMap::new()).unwrap();
        let so = second_order(
            &m,
            energy,
            x,
            &norms.free.col,
            &cert,
            EPS,
            0.1,
            SECOND_ORDER_MAX_DOFS,
        );
        (cert, so)
    }

    #[test]
    fn second_order_flat_obstacle_is_a_minimum() {
        // pulled through a flat edge towards (0.3, −1): the KKT point (0.3, ε) is the minimum;
        // on the tangent the Hessian is the pull's, the edge has no curvature
        let x = [0.3, EPS, -1.0, 0.0, 1.0, 0.0, 0.3, 5.0];
        let (cert, so) = check_at(
            &x,
            &Pull {
                target: [0.3, -1.0],
                kx: 1.0,
            },
        );
        assert!(cert.kappa < 1e-12, "{cert:?}");
        assert_eq!(so.status, "minimum", "{so:?}");
        assert_eq!((so.free_dofs, so.strongly_active, so.rank), (2, 1, 1));
        assert!(
            (so.min_eigenvalue_rel.unwrap() - 1.0).abs() < 1e-12,
            "{so:?}"
        );
        // without a pull along the edge the tangent is flat: second order does not decide
        let (_, so) = check_at(
            &x,
            &Pull {
                target: [0.3, -1.0],
                kx: 0.0,
            },
        );
        assert_eq!(so.status, "degenerate", "{so:?}");
        assert_eq!((so.zero_modes, so.negative_modes), (1, 0));
        // no contact: the pull's own minimum, every direction free
        let x = [0.3, 0.5, -1.0, 0.0, 1.0, 0.0, 0.3, 5.0];
        let (cert, so) = check_at(
            &x,
            &Pull {
                target: [0.3, 0.5],
                kx: 1.0,
            },
        );
        assert_eq!(cert.active.len(), 0);
        assert_eq!(so.status, "minimum", "{so:?}");
        assert_eq!((so.strongly_active, so.rank), (0, 0));
    }

    #[test]
    fn second_order_vertex_obstacle_is_not_a_minimum() {
        // the obstacle edge ends at the origin; the vertex sits at distance ε straight above
        // that end, pulled straight down: a KKT point (μ = 1 + ε) at the top of the circle of
        // radius ε round the end, where J is largest: on the tangent L = 1 − μ/ε < 0, and
        // sliding round the end lowers J
        let x = [0.0, EPS, -1.0, -1.0, 0.0, 0.0, 0.0, 5.0];
        let energy = Pull {
            target: [0.0, -1.0],
            kx: 1.0,
        };
        let (cert, so) = check_at(&x, &energy);
        assert!(cert.kappa < 1e-12, "{cert:?}");
        assert_eq!(so.status, "not_minimum", "{so:?}");
        assert_eq!(so.negative_modes, 1);
        let rel = so.min_eigenvalue_rel.unwrap();
        let mu = 1.0 + EPS;
        let lam = 1.0 - mu / EPS;
        assert!((rel - lam / lam.abs()).abs() < 1e-9, "{so:?}");
        // the lower point: t along the tangent, then back to the circle along the gradient at
        // x (vertical): (t, √(ε² − t²)), where J is lower by ε − √(ε² − t²)
        let t = so.descent_step.unwrap();
        let dj = so.descent_decrease.unwrap();
        assert!(dj > 0.0 && t < EPS, "{so:?}");
        let expect = EPS - (EPS * EPS - t * t).sqrt();
        assert!((dj - expect).abs() < 1e-6 * expect, "{dj} against {expect}");
    }

    #[test]
    fn second_order_is_not_computed_above_its_size() {
        let x = [0.3, EPS, -1.0, 0.0, 1.0, 0.0, 0.3, 5.0];
        let m = mesh(&x);
        let energy = Pull {
            target: [0.3, -1.0],
            kx: 1.0,
        };
        let norms = H1Norms::scaled(&m).unwrap();
        let cert = certificate(&m, &energy, &x, EPS, 1e-12, &norms, &HashMap::new()).unwrap();
        // 2 free dofs: above a bound of 1, and of 0 (off)
        for bound in [1, 0] {
            let so = second_order(&m, &energy, &x, &norms.free.col, &cert, EPS, 0.1, bound);
            assert_eq!(so.status, "not_computed");
            assert!(so.reason.contains("--second-order-max-dofs"), "{so:?}");
            assert!(so.min_eigenvalue_rel.is_none());
        }
        let so = second_order(&m, &energy, &x, &norms.free.col, &cert, EPS, 0.1, 2);
        assert_eq!(so.status, "minimum");
    }
}
