//! The minimality certificate κ: whether a configuration φ_h is a KKT point of problem (3)
//! itself, with its true non-linear constraints `dist(φ(T1), φ(T2)) ≥ ε` (Lemma 5.1 in 2D,
//! Lemma 5.3 in 3D), and not only a fixed point of the outer map (Lemma 5.4)
//! (docs/method.md, "The minimality certificate").
//!
//! ```text
//!     κ = min_{μ ≥ 0} ‖J'(φ_h) − Σ_k μ_k ∇d_k‖_{H⁻¹} / S,
//!     S = max(‖J'(φ_h)‖_{H⁻¹}, max_t ‖J_t'(φ_h)‖_{H⁻¹})
//! ```
//!
//! * `d_k` is the distance of a pair `k` of disjoint contact elements whose distance is
//!   within `active_tol` of ε, or that the last sub-problem held with a multiplier above
//!   `1e-4` of the largest (a backend leaves an active row within its own tolerance of
//!   ε + δ, which can exceed `active_tol`: on Hertz 2D at `qp_tol = 1e-11`, 1e-9 above),
//!   and `∇d_k` its gradient on the free dofs. With `n` the unit
//!   vector from the closest point of the first element to that of the second and the
//!   closest points' barycentric weights (eq. 8, 12, 13):
//!   - `point_edge` (2D): `−n` at x, `α_i n` at a_i;
//!   - `point_triangle`: `−n` at x, `β_i n` at t_i;
//!   - `edge_edge`: `−(1 − s, s)_i n` at a_i, `(1 − t, t)_j n` at b_j. When the edges are
//!     parallel the closest pair is not unique (eq. 12's `P_{a,b}`) and the distance is not
//!     differentiable; the extreme points of its subdifferential are the gradients of the
//!     distances from the edges' endpoints to the other edge, which are constraints of
//!     `A_{h,ε}` themselves (a vertex and an edge it does not belong to). Those within the
//!     tolerance are generators too.
//!
//!   This is `Σ_i w_i ∇row_i` over the pair's rows of T(φ_h) (rows built at φ_h itself) with
//!   their weights `w_i`: the gradient of Lemma 5.6's residual.
//! * `‖·‖_{H⁻¹}` is the dual norm of the H¹ Gram matrix on the reference mesh scaled to unit
//!   diameter ([`H1Norm::scaled`]): the numerator over the free dofs (the KKT conditions are
//!   on the free dofs), each term's force `J_t'` over all dofs (with the reactions at the
//!   fixed vertices).
//! * The scale `S`: with contact, `J'(φ_h)` is the force the contacts hold; at a minimum
//!   without contact it vanishes, and a ratio to it alone would read 1 (noise over noise). The
//!   forces of J's terms (elastic, gas, gravity, inertia; and the reactions at fixed vertices)
//!   do not vanish there: they are what balances. So κ is the unbalanced force relative to
//!   the largest force in the balance, a number in `[0, 1]` that does not depend on the units
//!   of length or energy (tested).
//!
//! The non-negative least-squares problem is solved by the Lawson–Hanson active-set method on
//! the `G⁻¹`-weighted normal equations `Q = Bᵀ G⁻¹ B`, `c = Bᵀ G⁻¹ J'` (B the generators as
//! columns), with a Cholesky factor of `Q` on the passive set updated column by column (append:
//! a triangular solve; removal: a rank-one update). It is exact on degenerate problems: a
//! column enters the passive set only if it lowers the residual, which (in exact arithmetic)
//! makes it independent of the columns already there, so `Q` on the passive set stays
//! definite however many contacts are nearly parallel; a column whose pivot is below
//! `1e-12` of its diagonal is numerically dependent and is left out. The passive set starts
//! from the pairs the last sub-problem gave a positive multiplier, at those multipliers. The
//! method stops when no generator makes an angle with the residual (in the `G⁻¹` inner
//! product) whose cosine exceeds `1e-10`, up to round-off; the reported residual is then
//! recomputed from the multipliers, so it is an upper bound of the minimum attained by
//! non-negative multipliers.
//!
//! That method forms `Q` on the passive set densely and costs like its cube: from
//! [`QP_PATH_MIN_GENERATORS`] distinct generators on, the problem is solved by its dual, a
//! sparse QP in the backends' standard form ([`nnls_dual_qp`]: `min ½wᵀGw − J'ᵀw` s.t.
//! `Bᵀw ≤ 0`, whose row multipliers are μ), by the registry's [`CERTIFICATE_BACKEND`] at
//! [`CERTIFICATE_TOL`], with refinement rounds (skipped where weak duality already puts the
//! first QP within [`REFINE_GAP`] of the minimum); nothing `k × k` is formed. Its residual
//! too is recomputed from the multipliers clipped to `≥ 0`, so it is an upper bound of the minimum
//! whatever the backend returned. `dual_gap` reports, for either path, how far the residual
//! can be above the minimum by weak duality.

use crate::contact::distance::edge_edge_distance;
use crate::contact::{near_pairs, p3, pair_rows, ContactPair};
use crate::energy::Objective;
use crate::scene::mesh::Mesh;
use crate::solve::h1::{dot, H1Norm, H1Norms};
use contactlab_solvers::{
    backend_from_name, CscMatrix, Qp, QpSettings, QpStatus, CERTIFICATE_BACKEND, CERTIFICATE_TOL,
};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;
use thiserror::Error;

/// Cosine below which a generator is not worth adding (the stopping test).
const DUAL_TOL: f64 = 1e-10;
/// Relative pivot below which a generator is dependent on the passive set (the squared sine
/// of its angle with the passive set's span).
const PIVOT_TOL: f64 = 1e-12;
/// The same for the warm start, which takes columns without asking whether they lower the
/// residual: nearly parallel contacts would otherwise enter together and make `Q` on the
/// passive set ill-conditioned (its condition number squares that of the columns).
const WARM_PIVOT_TOL: f64 = 1e-6;

/// Refinement rounds of [`nnls_dual_qp`] at most.
const REFINE_ROUNDS: usize = 3;
/// The proximal weight on the correction of the multipliers in a refinement round (in the
/// round's units): small enough not to bias the correction (with `ip`, the degenerate cone of
/// the tests stopped at 2.5e-8 of ‖g‖ with `1e-10`, at 9.0e-9 with `1e-13` and `1e-16`).
const PROX: f64 = 1e-13;

/// [`nnls_dual_qp`] skips its refinement rounds when weak duality ([`dual_gap`]) puts the
/// first QP's residual within this fraction of the minimum: κ is then an upper bound at most
/// that far above the least one (its `dual_gap` says how far). Measured on balloons3d n = 4
/// (3 204 generators, docs/method.md, "The minimality certificate"): one refinement QP took
/// 468 s to lower the residual by 3e-5 of itself, where the gap allowed 4.6%.
pub const REFINE_GAP: f64 = 0.1;

/// Distinct generators from which [`certificate`] solves the sparse dual QP instead of the
/// dense active set (measured: docs/method.md, "The minimality certificate").
pub const QP_PATH_MIN_GENERATORS: usize = 3000;

/// A pair whose multiplier in the last sub-problem exceeds this fraction of the largest one is
/// a generator whatever its gap (the diagnostics' `raw_dual_rel`).
const HELD_REL: f64 = 1e-4;

/// Why the certificate could not be computed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CertificateError {
    /// A contact pair is at distance 0: no normal, φ_h is not admissible.
    #[error("contact pair {0:?} is at distance 0: no constraint gradient")]
    ZeroDistance(ContactPair),
}

/// The minimality certificate of a configuration (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Certificate {
    /// `κ = ‖r‖ / S`, in `[0, 1]`.
    pub kappa: f64,
    /// `‖r‖_{H⁻¹}`, `r = J'(φ_h) − Σ μ_k ∇d_k` with the non-negative least-squares
    /// multipliers.
    pub residual: f64,
    /// `‖J'(φ_h)‖_{H⁻¹}` on the free dofs.
    pub gradient: f64,
    /// `max_t ‖J_t'(φ_h)‖_{H⁻¹}` over J's terms, on all dofs.
    pub term_force: f64,
    /// `S = max(gradient, term_force)`; the outer loop floors it at
    /// [`crate::solve::outer::CERTIFICATE_SCALE_FLOOR`] times `S` at the run's start (a state
    /// where every force of the balance vanishes to round-off).
    pub scale: f64,
    /// Pairs at distance ε (within `active_tol`) or held by the last sub-problem (a multiplier
    /// above `1e-4` of the largest).
    pub pairs: usize,
    /// Constraint gradients (the pairs', and the endpoint distances of parallel edges).
    pub generators: usize,
    /// Generators with a positive multiplier (`qp`: an interior point's, all of them where
    /// every generator is nearly active).
    pub positive: usize,
    /// The distance tolerance: pairs with `d_k ≤ ε + active_tol` count.
    pub active_tol: f64,
    /// Which solver gave the multipliers: `active_set` (Lawson–Hanson, exact) or `qp` (the
    /// dual QP with [`CERTIFICATE_BACKEND`]), see [`CertificatePath`].
    pub method: String,
    /// `active_set`: columns added (the warm start's included). `qp`: the backend's
    /// iterations.
    pub iterations: usize,
    /// `active_set`: generators left out as numerically dependent that still had a positive
    /// cosine with the residual at the end (0 when the method met its optimality test).
    /// `qp`: 1 when the backend did not report `solved` (the residual is then still an upper
    /// bound of the minimum, from whatever multipliers it returned), else 0.
    pub unresolved: usize,
    /// How far `residual` can be above the minimum over `μ ≥ 0`, relative to `S`: `‖r‖ − lb`
    /// with `lb` the weak-duality lower bound at `w = G⁻¹r` (`nnls`' `dual_gap`; a bound when
    /// `Bᵀw ≤ 0`, an estimate when round-off leaves some `b_jᵀw` positive). Either method.
    pub dual_gap: f64,
    /// Seconds spent.
    pub seconds: f64,
    /// The generators (distinct columns) with their multipliers: what the second-order check
    /// ([`crate::solve::second_order`]) takes. Not serialized.
    #[serde(skip)]
    pub active: Vec<ActiveGenerator>,
}

/// One distinct constraint gradient of the certificate with its non-negative multiplier.
#[derive(Clone, Debug, PartialEq)]
pub struct ActiveGenerator {
    /// The pair of its first generator (identical gradients of other pairs are merged in).
    pub pair: ContactPair,
    /// 0: the pair's distance; 1..=4: an endpoint distance of a parallel edge–edge pair.
    pub part: u8,
    /// `μ ≥ 0`.
    pub mu: f64,
    /// `∇d` on the free-dof columns.
    pub gradient: Vec<(usize, f64)>,
}

/// Which solver of the non-negative least-squares problem [`certificate_with`] uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CertificatePath<'a> {
    /// The active set below [`QP_PATH_MIN_GENERATORS`] distinct generators, the dual QP with
    /// [`CERTIFICATE_BACKEND`] at [`CERTIFICATE_TOL`] from there (what [`certificate`] does).
    Auto,
    /// [`CertificatePath::Auto`] with another backend of the registry for the dual QP (at
    /// [`CERTIFICATE_TOL`]).
    AutoWith {
        /// A name of the backend registry.
        backend: &'a str,
    },
    /// Lawson–Hanson on the dense normal equations (exact to round-off; `O(k³)`).
    ActiveSet,
    /// The sparse dual QP with a registered backend at a tolerance (`eps_abs = eps_rel`).
    Qp {
        /// A name of the backend registry.
        backend: &'a str,
        /// Its tolerance.
        tol: f64,
    },
}

/// One constraint gradient: `(free-dof column, value)` entries.
struct Generator {
    pair: ContactPair,
    /// 0: the pair's distance; 1..=4: an endpoint distance of an edge–edge pair.
    part: u8,
    entries: Vec<(usize, f64)>,
}

fn sp_dot(b: &[(usize, f64)], v: &[f64]) -> f64 {
    b.iter().map(|&(k, x)| x * v[k]).sum()
}

/// `aᵀb` with four partial sums (the dense triangular solves' inner loop; a fixed order, so
/// deterministic).
fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a4, b4) = (a[..n].chunks_exact(4), b[..n].chunks_exact(4));
    let (ra, rb) = (a4.remainder(), b4.remainder());
    let mut s = [0.0f64; 4];
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// Entries `(col, value)` of `Σ coef·n` at each vertex, merged and restricted to free dofs.
pub(crate) fn gradient_entries(
    dim: usize,
    col: &[usize],
    parts: &[(usize, f64)],
    n: &[f64],
) -> Vec<(usize, f64)> {
    let mut e: Vec<(usize, f64)> = Vec::with_capacity(parts.len() * dim);
    for &(v, coef) in parts {
        if coef == 0.0 {
            continue;
        }
        for c in 0..dim {
            let k = col[dim * v + c];
            if k != usize::MAX {
                e.push((k, coef * n[c]));
            }
        }
    }
    e.sort_by_key(|t| t.0);
    let mut out: Vec<(usize, f64)> = Vec::with_capacity(e.len());
    for (k, v) in e {
        match out.last_mut() {
            Some(last) if last.0 == k => last.1 += v,
            _ => out.push((k, v)),
        }
    }
    out.retain(|t| t.1 != 0.0);
    out
}

/// The constraint gradients at `x` of the pairs within `eps + active_tol`, and of the pairs
/// in `held` (the pairs the last sub-problem held, whatever their gap), in the order of the
/// broad phase (deterministic), with the count of pairs.
fn generators(
    mesh: &Mesh,
    x: &[f64],
    eps: f64,
    active_tol: f64,
    held: &HashMap<ContactPair, f64>,
    col: &[usize],
) -> Result<(Vec<Generator>, usize), CertificateError> {
    let reach = eps + active_tol;
    let mut near = near_pairs(mesh, x, reach * (1.0 + 1e-9), true);
    let known: std::collections::HashSet<ContactPair> = near.iter().copied().collect();
    let mut extra: Vec<ContactPair> = held
        .keys()
        .filter(|p| !known.contains(p))
        .copied()
        .collect();
    extra.sort_unstable();
    near.extend(extra);
    let dim = mesh.dim;
    let mut out = Vec::new();
    let mut pairs = 0;
    for p in near {
        let r = pair_rows(mesh, x, p).ok_or(CertificateError::ZeroDistance(p))?;
        if r.distance > reach && !held.contains_key(&p) {
            continue;
        }
        pairs += 1;
        let n = [r.n.x, r.n.y, r.n.z];
        let mut parts: Vec<(usize, f64)> = Vec::with_capacity(2 * r.len);
        for i in 0..r.len {
            parts.push((r.plus[i], r.weight[i]));
            parts.push((r.minus[i], -r.weight[i]));
        }
        out.push(Generator {
            pair: p,
            part: 0,
            entries: gradient_entries(dim, col, &parts, &n),
        });
        if let ContactPair::EdgeEdge { a, b } = p {
            let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
            let ends = [(ea[0], eb), (ea[1], eb), (eb[0], ea), (eb[1], ea)];
            for (k, &(v, seg)) in ends.iter().enumerate() {
                let pv = p3(x, v);
                let q = edge_edge_distance(&pv, &pv, &p3(x, seg[0]), &p3(x, seg[1]));
                if q.distance > reach {
                    continue;
                }
                if q.distance.is_nan() || q.distance <= 0.0 {
                    return Err(CertificateError::ZeroDistance(p));
                }
                let nv = (q.pb - q.pa) / q.distance;
                let parts = [(v, -1.0), (seg[0], 1.0 - q.t), (seg[1], q.t)];
                out.push(Generator {
                    pair: p,
                    part: k as u8 + 1,
                    entries: gradient_entries(dim, col, &parts, &[nv.x, nv.y, nv.z]),
                });
            }
        }
    }
    out.retain(|g| !g.entries.is_empty());
    Ok((out, pairs))
}

/// A dense lower-triangular Cholesky factor `L Lᵀ = Q_PP`, row `i` holding `i + 1` entries.
#[derive(Default)]
struct Chol {
    rows: Vec<Vec<f64>>,
}

impl Chol {
    /// `L y = b`.
    fn forward(&self, b: &[f64]) -> Vec<f64> {
        let mut y = b.to_vec();
        for (i, row) in self.rows.iter().enumerate() {
            let s = dot4(&row[..i], &y[..i]);
            y[i] = (y[i] - s) / row[i];
        }
        y
    }

    /// `L Lᵀ s = b`.
    fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut y = self.forward(b);
        for i in (0..self.rows.len()).rev() {
            let row = &self.rows[i];
            y[i] /= row[i];
            let yi = y[i];
            for (k, l) in row[..i].iter().enumerate() {
                y[k] -= l * yi;
            }
        }
        y
    }

    /// Appends a column with `Q_{P,j} = q` and `Q_jj = d`; false (nothing changed) when its
    /// pivot is below `tol·d` (numerically dependent).
    fn push(&mut self, q: &[f64], d: f64, tol: f64) -> bool {
        let mut l = self.forward(q);
        let piv = d - dot4(&l, &l);
        if piv.is_nan() || piv <= tol * d {
            return false;
        }
        l.push(piv.sqrt());
        self.rows.push(l);
        true
    }

    /// Removes row and column `k` (a rank-one update of the trailing block).
    fn remove(&mut self, k: usize) {
        self.rows.remove(k);
        let mut x: Vec<f64> = self.rows[k..].iter_mut().map(|r| r.remove(k)).collect();
        for jj in 0..x.len() {
            let j = k + jj;
            let ljj = self.rows[j][j];
            let r = ljj.hypot(x[jj]);
            let (c, s) = (r / ljj, x[jj] / ljj);
            self.rows[j][j] = r;
            for (ii, xi) in x.iter_mut().enumerate().skip(jj + 1) {
                let row = &mut self.rows[k + ii];
                row[j] = (row[j] + s * *xi) / c;
                *xi = c * *xi - s * row[j];
            }
        }
    }
}

/// The forces at `x`: `(‖J'(x)‖_{H⁻¹}` on the free dofs, `max_t ‖J_t'(x)‖_{H⁻¹}` over J's
/// terms on all dofs`)`, and `G⁻¹J'` on the free dofs. `S = max` of the two is the scale of
/// κ and, times the reference diameter, the energy scale of the outer stopping rule.
pub fn forces(
    energy: &dyn Objective,
    x: &[f64],
    norms: &H1Norms,
) -> (f64, f64, Vec<f64>, Vec<f64>) {
    let (free, all) = (&norms.free, &norms.all);
    let g = free.restrict(&energy.gradient(x));
    let mut vg = g.clone();
    free.solve_in_place(&mut vg);
    let gnorm = dot(&g, &vg).max(0.0).sqrt();
    let term_force = energy
        .term_gradients(x)
        .iter()
        .map(|gt| all.norm(&all.restrict(gt)))
        .fold(0.0f64, f64::max);
    (gnorm, term_force, g, vg)
}

/// The certificate at `x` (see the module documentation). `norms` are the scaled H¹ norms
/// over the free dofs and over all dofs; `warm` the multiplier of each pair in the last
/// sub-problem (the passive set starts from the positive ones); pairs within
/// `eps + active_tol` of contact count.
pub fn certificate(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    eps: f64,
    active_tol: f64,
    norms: &H1Norms,
    warm: &HashMap<ContactPair, f64>,
) -> Result<Certificate, CertificateError> {
    certificate_with(
        mesh,
        energy,
        x,
        eps,
        active_tol,
        norms,
        warm,
        CertificatePath::Auto,
    )
}

/// [`certificate`] with the solver of its least-squares problem chosen by `path`.
#[allow(clippy::too_many_arguments)]
pub fn certificate_with(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    eps: f64,
    active_tol: f64,
    norms: &H1Norms,
    warm: &HashMap<ContactPair, f64>,
    path: CertificatePath,
) -> Result<Certificate, CertificateError> {
    let t0 = Instant::now();
    let free: &H1Norm = &norms.free;
    let (gnorm, term_force, g, _) = forces(energy, x, norms);
    let scale = gnorm.max(term_force);
    // A pair the last sub-problem held with a multiplier above HELD_REL of the largest counts
    // as active whatever its gap (as in the diagnostics): a backend leaves an active row
    // within its own tolerance of ε + δ, which can exceed `active_tol`.
    let wmax = warm.values().fold(0.0f64, |m, &v| m.max(v));
    let held: HashMap<ContactPair, f64> = warm
        .iter()
        .filter(|(_, &v)| wmax > 0.0 && v > HELD_REL * wmax)
        .map(|(&p, &v)| (p, v))
        .collect();
    let (gens, pairs) = generators(mesh, x, eps, active_tol, &held, &free.col)?;
    let warm: Vec<f64> = gens
        .iter()
        .map(|b| {
            if b.part == 0 {
                warm.get(&b.pair).copied().unwrap_or(0.0)
            } else {
                0.0
            }
        })
        .collect();
    // Identical gradients (a vertex whose closest point is a vertex shared by two edges, in
    // two pairs) are one column, with the sum of their warm multipliers.
    let mut index: HashMap<Vec<(usize, u64)>, usize> = HashMap::new();
    let mut cols: Vec<Vec<(usize, f64)>> = Vec::new();
    let mut owner: Vec<(ContactPair, u8)> = Vec::new();
    let mut warm_cols: Vec<f64> = Vec::new();
    for (b, w) in gens.into_iter().zip(warm) {
        let key: Vec<(usize, u64)> = b.entries.iter().map(|&(k, v)| (k, v.to_bits())).collect();
        match index.get(&key) {
            Some(&j) => warm_cols[j] += w,
            None => {
                index.insert(key, cols.len());
                cols.push(b.entries);
                owner.push((b.pair, b.part));
                warm_cols.push(w);
            }
        }
    }
    let qp = match path {
        CertificatePath::Auto if cols.len() >= QP_PATH_MIN_GENERATORS => {
            Some((CERTIFICATE_BACKEND, CERTIFICATE_TOL))
        }
        CertificatePath::AutoWith { backend } if cols.len() >= QP_PATH_MIN_GENERATORS => {
            Some((backend, CERTIFICATE_TOL))
        }
        CertificatePath::Auto | CertificatePath::AutoWith { .. } | CertificatePath::ActiveSet => {
            None
        }
        CertificatePath::Qp { backend, tol } => Some((backend, tol)),
    };
    let solve = |v: &mut [f64]| free.solve_in_place(v);
    let (sol, method) = match qp {
        None => (nnls(&g, &cols, &solve, &warm_cols), "active_set"),
        Some((backend, tol)) => (
            nnls_dual_qp(&g, &cols, &free.gram, &solve, backend, tol),
            "qp",
        ),
    };
    Ok(Certificate {
        kappa: if scale > 0.0 {
            sol.residual / scale
        } else {
            0.0
        },
        residual: sol.residual,
        gradient: gnorm,
        term_force,
        scale,
        pairs,
        generators: cols.len(),
        positive: sol.mu.iter().filter(|&&v| v > 0.0).count(),
        active_tol,
        method: method.into(),
        iterations: sol.iterations,
        unresolved: sol.unresolved,
        dual_gap: if scale > 0.0 {
            // computed already where the dual QP's refinement was skipped (the same g, cols, μ)
            sol.skip_gap
                .unwrap_or_else(|| dual_gap(&g, &cols, &sol.mu, &solve))
                / scale
        } else {
            0.0
        },
        seconds: t0.elapsed().as_secs_f64(),
        active: owner
            .into_iter()
            .zip(cols)
            .zip(&sol.mu)
            .map(|(((pair, part), gradient), &mu)| ActiveGenerator {
                pair,
                part,
                mu,
                gradient,
            })
            .collect(),
    })
}

/// How far `‖r‖_{G⁻¹}`, `r = g − Σ μ_j b_j` (`μ ≥ 0`), can be above the minimum over
/// `μ ≥ 0`, by weak duality at `w = G⁻¹r`: for every `μ* ≥ 0`,
///
/// ```text
///     ½‖g − Bμ*‖²_{G⁻¹} ≥ gᵀw − ½wᵀGw − μ*ᵀBᵀw = ½‖r‖² + μᵀBᵀw − μ*ᵀBᵀw,
/// ```
///
/// so with `v = max_j (b_jᵀw)⁺` the minimum is at least `lb = (‖r‖² + 2μᵀBᵀw − 2‖μ*‖₁v)^{1/2}`.
/// Returns `‖r‖ − lb` with `‖μ*‖₁` estimated by `‖μ‖₁`: a bound when `Bᵀw ≤ 0` (`v = 0`), an
/// estimate otherwise (round-off makes `v` positive, if tiny, at any computed solution).
fn dual_gap(
    g: &[f64],
    cols: &[Vec<(usize, f64)>],
    mu: &[f64],
    solve: &(dyn Fn(&mut [f64]) + Sync),
) -> f64 {
    let mut r = g.to_vec();
    for (b, &mk) in cols.iter().zip(mu) {
        for &(d, v) in b {
            r[d] -= mk * v;
        }
    }
    let mut w = r.clone();
    solve(&mut w);
    let r2 = dot(&r, &w).max(0.0);
    let bw: Vec<f64> = cols.par_iter().map(|b| sp_dot(b, &w)).collect();
    let comp: f64 = mu.iter().zip(&bw).map(|(m, b)| m * b).sum();
    let viol = bw.iter().fold(0.0f64, |a, &b| a.max(b));
    let l1: f64 = mu.iter().sum();
    let lb2 = r2 + 2.0 * comp - 2.0 * l1 * viol;
    r2.sqrt() - lb2.max(0.0).sqrt()
}

/// The solution of [`nnls`].
pub(crate) struct Nnls {
    /// The multiplier of each column (≥ 0).
    pub mu: Vec<f64>,
    /// `‖g − Σ μ_j b_j‖_{G⁻¹}`, recomputed from `mu`.
    pub residual: f64,
    /// Columns added (the warm start's included).
    pub iterations: usize,
    /// Columns left out as dependent whose cosine with the residual exceeds `100·DUAL_TOL`,
    /// or 1 when the iteration cap was reached ([`nnls_dual_qp`]: 1 when the backend did not
    /// solve).
    pub unresolved: usize,
    /// [`nnls_dual_qp`] only: the weak-duality gap at `mu` where it was computed to skip the
    /// refinement (then within [`REFINE_GAP`] of `residual`); `None` where the refinement ran
    /// or was not needed.
    pub skip_gap: Option<f64>,
}

/// The same least-squares problem as [`nnls`] by its dual, a sparse QP in the standard form
/// of the backends:
///
/// ```text
///     ½‖r‖²_{G⁻¹} = max_w wᵀr − ½wᵀGw,
///     min_{μ ≥ 0} ½‖g − Bμ‖²_{G⁻¹} = max_{Bᵀw ≤ 0} gᵀw − ½wᵀGw
/// ```
///
/// (for fixed w, `min_{μ ≥ 0} −μᵀBᵀw` is bounded only if `Bᵀw ≤ 0`; the problem is convex
/// with linear constraints, so there is no duality gap). The QP `min ½wᵀGw − gᵀw` s.t.
/// `Bᵀw ≤ 0` has the NNLS multipliers as its row multipliers and `w* = G⁻¹(g − Bμ*)`. It is
/// solved in units where `‖g‖_∞ = 1` and with each row `b_j` divided by its Euclidean norm
/// (the backends' tolerances are absolute, or relative to `max(1, ·)`), by the registered
/// backend `backend` at `tol`, then refined by at most [`REFINE_ROUNDS`] rounds (in the body:
/// the first QP's residual is accurate to about `√tol·‖g‖` only), unless [`dual_gap`] already
/// puts that residual within [`REFINE_GAP`] of the minimum. Nothing `k × k` is formed: the QPs
/// hold `G` and `B`.
///
/// The multipliers are then clipped to `≥ 0` (a NaN to 0), and the residual is recomputed
/// from them with the factor of `G`: whatever the backend returned, it is the residual of
/// non-negative multipliers, an upper bound of the minimum.
pub(crate) fn nnls_dual_qp(
    g: &[f64],
    cols: &[Vec<(usize, f64)>],
    gram: &CscMatrix,
    solve: &(dyn Fn(&mut [f64]) + Sync),
    backend: &str,
    tol: f64,
) -> Nnls {
    let (n, m) = (g.len(), cols.len());
    // An interior point that has not converged in 200 iterations will not (the refinement's
    // QPs on balloons n = 1600 with `ip`: 200 iterations, 4 s, no progress).
    let settings = QpSettings {
        eps_abs: tol,
        eps_rel: tol,
        max_iter: 200,
        ..QpSettings::default()
    };
    let solve_qp =
        |qp: &Qp| backend_from_name(backend, &settings).and_then(|mut b| b.solve(qp, None));
    let residual_of = |mu: &[f64]| {
        let mut r = g.to_vec();
        for (b, &mk) in cols.iter().zip(mu) {
            if mk > 0.0 {
                for &(d, v) in b {
                    r[d] -= mk * v;
                }
            }
        }
        let mut t = r.clone();
        solve(&mut t);
        let rn = dot(&r, &t).max(0.0).sqrt();
        (r, rn)
    };
    let inf_norm = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let gscale = inf_norm(g);
    if m == 0 || gscale == 0.0 || !gscale.is_finite() {
        let mu = vec![0.0; m];
        let residual = residual_of(&mu).1;
        return Nnls {
            mu,
            residual,
            iterations: 0,
            unresolved: 0,
            skip_gap: None,
        };
    }
    // Row j of the QPs is `b_j / ‖b_j‖₂`.
    let rscale: Vec<f64> = cols
        .iter()
        .map(|b| {
            let nb = b.iter().map(|e| e.1 * e.1).sum::<f64>().sqrt();
            if nb > 0.0 {
                1.0 / nb
            } else {
                1.0
            }
        })
        .collect();
    let trip: Vec<(usize, usize, f64)> = cols
        .iter()
        .zip(&rscale)
        .enumerate()
        .flat_map(|(j, (b, &c))| b.iter().map(move |&(k, v)| (j, k, c * v)))
        .collect();
    let dual = Qp {
        p: gram.clone(),
        q: g.iter().map(|v| -v / gscale).collect(),
        a: CscMatrix::from_triplets(m, n, &trip).expect("generator entries in range, finite"),
        l: vec![f64::NEG_INFINITY; m],
        u: vec![0.0; m],
    };
    let (mut mu, mut iterations, solved) = match solve_qp(&dual) {
        Ok(s) => {
            // An interior point leaves the multipliers of inactive rows at about its
            // tolerance: below `tol` of the largest they are taken as 0.
            let ymax = s.y.iter().fold(0.0f64, |a, &y| a.max(y));
            let cut = tol * ymax;
            let mu: Vec<f64> =
                s.y.iter()
                    .zip(&rscale)
                    .map(|(&y, &c)| if y > cut { y * c * gscale } else { 0.0 })
                    .collect();
            (mu, s.iterations, s.status == QpStatus::Solved)
        }
        Err(_) => (vec![0.0; m], 0, false),
    };
    drop(dual);
    let (mut r, mut residual) = residual_of(&mu);
    // Refinement. The QP's optimal value is ½‖r‖² and its tolerance is absolute in units of
    // ‖g‖, so ‖r‖ is accurate to about √tol·‖g‖ only (1e-5 of ‖g‖ where the minimum is 0).
    // Each round solves for the correction ν of the multipliers in the primal form, in units
    // of the current residual r₀ = g − Bμ₀:
    //     min ½tᵀGt  s.t.  Gt + Bν = r₀,  ν ≥ −μ₀
    // (t = G⁻¹(r₀ − Bν), the new residual), so its error is √tol of ‖r₀‖. A round is kept
    // only if it lowers the residual recomputed from the clipped multipliers; the rounds stop
    // when one does not halve it.
    let skip_gap = (residual > 0.0)
        .then(|| dual_gap(g, cols, &mu, solve))
        .filter(|&gap| gap <= REFINE_GAP * residual);
    if residual > 0.0 && skip_gap.is_none() {
        let mut gfull: Vec<(usize, usize, f64)> = Vec::with_capacity(2 * gram.nnz() + trip.len());
        for j in 0..gram.ncols {
            for p in gram.colptr[j]..gram.colptr[j + 1] {
                let (i, v) = (gram.rowval[p], gram.nzval[p]);
                gfull.push((i, j, v));
                if i != j {
                    gfull.push((j, i, v));
                }
            }
        }
        // [G B; 0 I] over (t, ν), rows: the n equalities, then the m bounds.
        let mut rows = gfull;
        rows.extend(trip.iter().map(|&(j, k, v)| (k, n + j, v)));
        rows.extend((0..m).map(|j| (n + j, n + j, 1.0)));
        let a = CscMatrix::from_triplets(n + m, n + m, &rows).expect("in range, finite");
        // A proximal term `½ PROX·‖ν‖²`: duplicate and parallel generators leave directions of
        // ν that the equalities do not fix (measured: without it `ip` ends in a numerical
        // error on the degenerate cone of the tests).
        let mut ptrip: Vec<(usize, usize, f64)> = Vec::with_capacity(gram.nnz() + m);
        for j in 0..gram.ncols {
            for q in gram.colptr[j]..gram.colptr[j + 1] {
                ptrip.push((gram.rowval[q], j, gram.nzval[q]));
            }
        }
        ptrip.extend((0..m).map(|j| (n + j, n + j, PROX)));
        let p = CscMatrix::from_triplets(n + m, n + m, &ptrip).expect("in range, finite");
        for _ in 0..REFINE_ROUNDS {
            let s0 = inf_norm(&r);
            if !(s0 > 0.0 && s0.is_finite()) {
                break;
            }
            let mut l: Vec<f64> = r.iter().map(|v| v / s0).collect();
            let mut u = l.clone();
            l.extend(mu.iter().zip(&rscale).map(|(&mk, &c)| -mk / (c * s0)));
            u.extend(std::iter::repeat_n(f64::INFINITY, m));
            let qp = Qp {
                p: p.clone(),
                q: vec![0.0; n + m],
                a: a.clone(),
                l,
                u,
            };
            let Ok(sol) = solve_qp(&qp) else { break };
            iterations += sol.iterations;
            let cand: Vec<f64> = mu
                .iter()
                .zip(&rscale)
                .zip(&sol.x[n..])
                .map(|((&mk, &c), &nu)| {
                    let v = mk + nu * c * s0;
                    if v > 0.0 {
                        v
                    } else {
                        0.0
                    }
                })
                .collect();
            let (rc, rnc) = residual_of(&cand);
            // (a NaN residual is not lower either)
            if rnc.partial_cmp(&residual) != Some(std::cmp::Ordering::Less) {
                break;
            }
            let halved = rnc <= 0.5 * residual;
            (mu, r, residual) = (cand, rc, rnc);
            if !halved {
                break;
            }
        }
    }
    Nnls {
        mu,
        residual,
        iterations,
        unresolved: usize::from(!solved),
        skip_gap,
    }
}

/// `min_{μ ≥ 0} ‖g − Σ_j μ_j b_j‖_{G⁻¹}` by the Lawson–Hanson active-set method on the normal
/// equations `Q = Bᵀ G⁻¹ B` (module documentation). `cols` are the sparse columns `b_j`,
/// `solve` computes `G⁻¹ v` in place, and a column with `warm[j] > 0` starts in the passive
/// set at `μ_j = warm[j]`.
pub(crate) fn nnls(
    g: &[f64],
    cols: &[Vec<(usize, f64)>],
    solve: &(dyn Fn(&mut [f64]) + Sync),
    warm: &[f64],
) -> Nnls {
    let m = cols.len();
    let mut lh = ActiveSet::new(g, cols, solve);
    let mut iterations = 0;
    // Warm start: the given positive multipliers.
    for (j, &w) in warm.iter().enumerate() {
        if w > 0.0 && lh.add(j, w, WARM_PIVOT_TOL) {
            iterations += 1;
        }
    }
    if !lh.pset.is_empty() {
        lh.settle(false);
    }
    let cap = 10 * m + 100;
    let unresolved;
    loop {
        let (t, rn) = lh.residual();
        // w_j = b_jᵀ G⁻¹ r: the decrease of ½‖r‖² per unit of μ_j; cos_j = w_j / ‖b_j‖ is
        // ‖r‖ times the cosine of the angle between r and b_j. The round-off of w_j is about
        // u·‖b_j‖·(‖g‖ + ‖Bμ‖) ≤ u·‖b_j‖·(2‖g‖ + ‖r‖).
        let floor = 128.0 * f64::EPSILON * (2.0 * lh.gnorm + rn);
        let cos = lh.cosines(&t);
        let best = (0..m)
            .filter(|&j| !lh.in_p[j] && !lh.excluded[j])
            .map(|j| (cos[j], j))
            .filter(|&(cj, _)| cj > DUAL_TOL * rn + floor)
            .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
        let Some((_, j)) = best else {
            if lh.dirty {
                // Optimal with a factor updated by removals: build it afresh on the passive
                // set, solve again from there, and test again.
                lh.rebuild();
                continue;
            }
            unresolved = (0..m)
                .filter(|&j| lh.excluded[j] && cos[j] > 100.0 * DUAL_TOL * rn + floor)
                .count();
            break;
        };
        if iterations >= cap {
            unresolved = 1;
            break;
        }
        iterations += 1;
        if lh.add(j, 0.0, PIVOT_TOL) {
            lh.settle(true);
        } else {
            lh.excluded[j] = true;
        }
    }
    let (_, residual) = lh.residual();
    let mut mu = vec![0.0; m];
    for (&k, &mk) in lh.pset.iter().zip(&lh.mu) {
        mu[k] = mk;
    }
    Nnls {
        mu,
        residual,
        iterations,
        unresolved,
        skip_gap: None,
    }
}

/// The state of the Lawson–Hanson method: the passive set `pset` with its multipliers `mu`
/// and the Cholesky factor of `Q` on it.
struct ActiveSet<'a> {
    g: &'a [f64],
    cols: &'a [Vec<(usize, f64)>],
    solve: &'a (dyn Fn(&mut [f64]) + Sync),
    /// `‖g‖_{G⁻¹}`.
    gnorm: f64,
    /// `c_j = b_jᵀ G⁻¹ g`.
    c: Vec<f64>,
    /// `‖b_j‖_{G⁻¹}`, NaN until needed (one solve each).
    bnorm: Vec<f64>,
    chol: Chol,
    pset: Vec<usize>,
    mu: Vec<f64>,
    in_p: Vec<bool>,
    /// Columns found dependent on the passive set (forgotten at the next removal).
    excluded: Vec<bool>,
    /// Removals update the factor by rotations, which keeps the rounding errors of the
    /// columns removed: the factor has seen one since it was last built afresh.
    dirty: bool,
}

impl<'a> ActiveSet<'a> {
    fn new(
        g: &'a [f64],
        cols: &'a [Vec<(usize, f64)>],
        solve: &'a (dyn Fn(&mut [f64]) + Sync),
    ) -> Self {
        let m = cols.len();
        let mut vg = g.to_vec();
        solve(&mut vg);
        ActiveSet {
            g,
            cols,
            solve,
            gnorm: dot(g, &vg).max(0.0).sqrt(),
            c: cols.iter().map(|b| sp_dot(b, &vg)).collect(),
            bnorm: vec![f64::NAN; m],
            chol: Chol::default(),
            pset: Vec::new(),
            mu: Vec::new(),
            in_p: vec![false; m],
            excluded: vec![false; m],
            dirty: false,
        }
    }

    /// `G⁻¹ b_j`.
    fn solve_col(&self, j: usize) -> Vec<f64> {
        let mut z = vec![0.0; self.g.len()];
        for &(k, v) in &self.cols[j] {
            z[k] += v;
        }
        (self.solve)(&mut z);
        z
    }

    /// Adds column j to the passive set at `μ_j = mu0`; false (nothing changed) when it is
    /// zero or its pivot is below `tol` of its diagonal (dependent).
    fn add(&mut self, j: usize, mu0: f64, tol: f64) -> bool {
        let z = self.solve_col(j);
        let d = sp_dot(&self.cols[j], &z);
        self.bnorm[j] = d.max(0.0).sqrt();
        let q: Vec<f64> = self
            .pset
            .iter()
            .map(|&k| sp_dot(&self.cols[k], &z))
            .collect();
        if !(d > 0.0 && self.chol.push(&q, d, tol)) {
            return false;
        }
        self.pset.push(j);
        self.mu.push(mu0);
        self.in_p[j] = true;
        true
    }

    /// Moves μ towards the least-squares solution on the passive set, dropping the columns
    /// that reach 0, until that solution is positive. `fresh`: the last column was just added
    /// (at μ = 0); if the solution does not make it positive it cannot lower the residual
    /// (round-off), and it is taken out again and excluded.
    fn settle(&mut self, mut fresh: bool) {
        loop {
            let cp: Vec<f64> = self.pset.iter().map(|&k| self.c[k]).collect();
            let s = self.chol.solve(&cp);
            if fresh && s[s.len() - 1].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                let j = self.pset.pop().expect("a column was just added");
                self.mu.pop();
                self.chol.rows.pop();
                self.in_p[j] = false;
                self.excluded[j] = true;
                return;
            }
            fresh = false;
            if s.iter().all(|&v| v > 0.0) {
                self.mu = s;
                return;
            }
            let mut alpha = f64::INFINITY;
            let mut hit = 0;
            for (k, (&sk, &mk)) in s.iter().zip(&self.mu).enumerate() {
                if sk <= 0.0 {
                    let a = mk / (mk - sk);
                    if a < alpha {
                        alpha = a;
                        hit = k;
                    }
                }
            }
            for (mk, sk) in self.mu.iter_mut().zip(&s) {
                *mk += alpha * (sk - *mk);
            }
            self.mu[hit] = 0.0;
            // drop every column at 0, from the end so that the indices stay valid
            for k in (0..self.pset.len()).rev() {
                if self.mu[k].is_nan() || self.mu[k] <= 0.0 {
                    self.in_p[self.pset[k]] = false;
                    self.pset.remove(k);
                    self.mu.remove(k);
                    self.chol.remove(k);
                }
            }
            // a removal can make an excluded column independent again
            self.excluded.iter_mut().for_each(|e| *e = false);
            self.dirty = true;
            if self.pset.is_empty() {
                return;
            }
        }
    }

    /// Builds the factor afresh on the passive set (columns now dependent leave it), and
    /// settles from the current multipliers.
    fn rebuild(&mut self) {
        self.dirty = false;
        self.chol = Chol::default();
        let (old_p, old_mu) = (std::mem::take(&mut self.pset), std::mem::take(&mut self.mu));
        for (&k, &mk) in old_p.iter().zip(&old_mu) {
            self.in_p[k] = false;
            self.add(k, mk, PIVOT_TOL);
        }
        if !self.pset.is_empty() {
            self.settle(false);
        }
    }

    /// `(G⁻¹ r, ‖r‖_{G⁻¹})`, `r = g − Σ μ_k b_k`.
    fn residual(&self) -> (Vec<f64>, f64) {
        let mut r = self.g.to_vec();
        for (&k, &mk) in self.pset.iter().zip(&self.mu) {
            for &(d, v) in &self.cols[k] {
                r[d] -= mk * v;
            }
        }
        let mut t = r.clone();
        (self.solve)(&mut t);
        let rn = dot(&r, &t).max(0.0).sqrt();
        (t, rn)
    }

    /// `w_j / ‖b_j‖` where `w_j = b_jᵀ t > 0`, else 0 (the norms computed where needed).
    fn cosines(&mut self, t: &[f64]) -> Vec<f64> {
        let w: Vec<f64> = self.cols.par_iter().map(|b| sp_dot(b, t)).collect();
        let need: Vec<usize> = (0..w.len())
            .filter(|&j| w[j] > 0.0 && self.bnorm[j].is_nan())
            .collect();
        let norms: Vec<f64> = need
            .par_iter()
            .map(|&j| sp_dot(&self.cols[j], &self.solve_col(j)).max(0.0).sqrt())
            .collect();
        for (&j, &b) in need.iter().zip(&norms) {
            self.bnorm[j] = b;
        }
        w.iter()
            .zip(&self.bnorm)
            .map(|(&wj, &bj)| if wj > 0.0 && bj > 0.0 { wj / bj } else { 0.0 })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::{Body, BodyKind};
    use nalgebra::{DMatrix, DVector};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random SPD matrix `M Mᵀ + I` of size n and its solver.
    fn spd(n: usize, rng: &mut ChaCha8Rng) -> DMatrix<f64> {
        let m = DMatrix::from_fn(n, n, |_, _| rng.gen_range(-1.0..1.0));
        &m * m.transpose() + DMatrix::identity(n, n)
    }

    fn dense(b: &[(usize, f64)], n: usize) -> DVector<f64> {
        let mut v = DVector::zeros(n);
        for &(k, x) in b {
            v[k] += x;
        }
        v
    }

    /// `‖v‖_{G⁻¹}`.
    fn hm1(gm: &DMatrix<f64>, v: &DVector<f64>) -> f64 {
        let z = gm.clone().cholesky().unwrap().solve(v);
        v.dot(&z).max(0.0).sqrt()
    }

    /// The NNLS optimum by enumeration: every subset of columns with a definite normal
    /// matrix whose least-squares multipliers are ≥ 0 (an optimal solution with linearly
    /// independent support exists, Carathéodory), the smallest residual.
    fn brute_force(gm: &DMatrix<f64>, g: &DVector<f64>, cols: &[DVector<f64>]) -> f64 {
        let m = cols.len();
        let ginv = gm.clone().try_inverse().unwrap();
        let mut best = hm1(gm, g);
        for mask in 1u32..(1 << m) {
            let idx: Vec<usize> = (0..m).filter(|&j| mask >> j & 1 == 1).collect();
            let b = DMatrix::from_fn(g.len(), idx.len(), |i, k| cols[idx[k]][i]);
            let q = b.transpose() * &ginv * &b;
            let c = b.transpose() * &ginv * g;
            let Some(ch) = q.clone().cholesky() else {
                continue;
            };
            if q.symmetric_eigenvalues().min() < 1e-9 * q.diagonal().max() {
                continue;
            }
            let mu = ch.solve(&c);
            if mu.iter().all(|&v| v >= 0.0) {
                best = best.min(hm1(gm, &(g - &b * mu)));
            }
        }
        best
    }

    fn run_nnls(
        gm: &DMatrix<f64>,
        g: &DVector<f64>,
        cols: &[Vec<(usize, f64)>],
        warm: &[f64],
    ) -> Nnls {
        let ch = gm.clone().cholesky().unwrap();
        let solve = move |v: &mut [f64]| {
            let z = ch.solve(&DVector::from_column_slice(v));
            v.copy_from_slice(z.as_slice());
        };
        nnls(g.as_slice(), cols, &solve, warm)
    }

    /// NNLS optimality: μ ≥ 0, `w = Bᵀ G⁻¹ r ≤ tol` for every column and `|w_j| ≤ tol` where
    /// `μ_j > 0` (a convex problem: these certify the minimum).
    fn assert_kkt(gm: &DMatrix<f64>, g: &DVector<f64>, cols: &[Vec<(usize, f64)>], s: &Nnls) {
        let n = g.len();
        let mut r = g.clone();
        for (b, &mu) in cols.iter().zip(&s.mu) {
            assert!(mu >= 0.0, "negative multiplier {mu}");
            r -= dense(b, n) * mu;
        }
        let t = gm.clone().cholesky().unwrap().solve(&r);
        let rn = r.dot(&t).sqrt();
        assert!(
            (rn - s.residual).abs() <= 1e-12 * hm1(gm, g),
            "{rn} vs {}",
            s.residual
        );
        for (j, (b, &mu)) in cols.iter().zip(&s.mu).enumerate() {
            let bd = dense(b, n);
            let w = bd.dot(&t) / hm1(gm, &bd);
            let tol = 1e-8 * rn + 1e-12 * hm1(gm, g);
            assert!(w <= tol, "column {j}: cosine·‖r‖ {w:e} > {tol:e}");
            if mu > 0.0 {
                assert!(w.abs() <= tol, "column {j} in the passive set: {w:e}");
            }
        }
    }

    /// Forty random least-squares problems (seeded) with their minimum by enumeration; every
    /// third has a duplicate column (the same gradient from two pairs).
    #[allow(clippy::type_complexity)]
    fn random_problems() -> Vec<(DMatrix<f64>, DVector<f64>, Vec<Vec<(usize, f64)>>, f64)> {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        (0..40)
            .map(|trial| {
                let n = rng.gen_range(2..7);
                let m = rng.gen_range(1..10);
                let gm = spd(n, &mut rng);
                let g = DVector::from_fn(n, |_, _| rng.gen_range(-1.0..1.0));
                let mut cols: Vec<Vec<(usize, f64)>> = (0..m)
                    .map(|_| {
                        (0..rng.gen_range(1..4))
                            .map(|_| (rng.gen_range(0..n), rng.gen_range(-1.0..1.0)))
                            .collect()
                    })
                    .collect();
                if trial % 3 == 0 {
                    cols.push(cols[0].clone());
                }
                let dcols: Vec<DVector<f64>> = cols.iter().map(|b| dense(b, n)).collect();
                let brute = brute_force(&gm, &g, &dcols);
                (gm, g, cols, brute)
            })
            .collect()
    }

    #[test]
    fn certificate_nnls_matches_enumeration_on_random_problems() {
        for (trial, (gm, g, cols, brute)) in random_problems().into_iter().enumerate() {
            for warm in [vec![0.0; cols.len()], vec![1.0; cols.len()]] {
                let s = run_nnls(&gm, &g, &cols, &warm);
                assert_kkt(&gm, &g, &cols, &s);
                assert!(
                    (s.residual - brute).abs() <= 1e-9 * hm1(&gm, &g),
                    "trial {trial}: nnls {} vs enumeration {brute}",
                    s.residual
                );
                assert_eq!(s.unresolved, 0, "trial {trial}");
            }
        }
    }

    /// `g` in the cone of two columns b1, b2; the columns: each of b1, b2 thirty times, as
    /// exact positive multiples and as copies turned by 1e-6 to 1e-3, plus columns pointing
    /// away. The minimum of the least-squares problem is 0.
    #[allow(clippy::type_complexity)]
    fn degenerate_cone() -> (DMatrix<f64>, DVector<f64>, Vec<Vec<(usize, f64)>>) {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 8;
        let gm = spd(n, &mut rng);
        let b1: Vec<(usize, f64)> = vec![(0, 1.0), (3, -0.5), (5, 0.25)];
        let b2: Vec<(usize, f64)> = vec![(1, 1.0), (3, 0.5), (6, -1.0)];
        let g = dense(&b1, n) * 2.0 + dense(&b2, n) * 0.7;
        let mut cols = Vec::new();
        for k in 0..30 {
            for b in [&b1, &b2] {
                let mut c: Vec<(usize, f64)> = b
                    .iter()
                    .map(|&(i, v)| (i, v * (1.0 + 0.1 * k as f64)))
                    .collect();
                if k % 2 == 1 {
                    let turn = 10f64.powi(-6 + (k % 4));
                    c.push((rng.gen_range(0..n), turn * rng.gen_range(-1.0..1.0)));
                }
                cols.push(c);
            }
            cols.push(vec![(rng.gen_range(0..n), -rng.gen_range(0.1..1.0))]);
        }
        (gm, g, cols)
    }

    #[test]
    fn certificate_nnls_is_exact_on_degenerate_cones() {
        // g in the cone of two columns b1, b2. The columns: each of b1, b2 thirty times, as
        // exact positive multiples (the same gradient from several pairs) and as copies turned
        // by 1e-6 to 1e-3 (nearly parallel contacts), plus columns pointing away. The
        // minimum is 0; the method reaches it to round-off from a cold start and from a warm
        // start on every column.
        let (gm, g, cols) = degenerate_cone();
        for warm in [vec![0.0; cols.len()], vec![1.0; cols.len()]] {
            let s = run_nnls(&gm, &g, &cols, &warm);
            assert_kkt(&gm, &g, &cols, &s);
            assert!(
                s.residual <= 1e-12 * hm1(&gm, &g),
                "warm {}: residual {:e} of {:e}",
                warm[0],
                s.residual,
                hm1(&gm, &g)
            );
            assert_eq!(s.unresolved, 0);
        }
    }

    /// The upper triangle of `gm` in CSC.
    fn upper_csc(gm: &DMatrix<f64>) -> CscMatrix {
        let n = gm.nrows();
        let t: Vec<(usize, usize, f64)> = (0..n)
            .flat_map(|j| (0..=j).map(move |i| (i, j)))
            .map(|(i, j)| (i, j, gm[(i, j)]))
            .collect();
        CscMatrix::from_triplets(n, n, &t).unwrap()
    }

    fn run_dual_qp(gm: &DMatrix<f64>, g: &DVector<f64>, cols: &[Vec<(usize, f64)>]) -> Nnls {
        let ch = gm.clone().cholesky().unwrap();
        let solve = move |v: &mut [f64]| {
            let z = ch.solve(&DVector::from_column_slice(v));
            v.copy_from_slice(z.as_slice());
        };
        nnls_dual_qp(
            g.as_slice(),
            cols,
            &upper_csc(gm),
            &solve,
            CERTIFICATE_BACKEND,
            CERTIFICATE_TOL,
        )
    }

    #[test]
    fn certificate_dual_qp_is_an_upper_bound_close_to_the_minimum() {
        // The sparse path on the random problems of the enumeration test: its residual,
        // recomputed from non-negative multipliers, is never below the minimum (round-off
        // aside) and close to it: refined, at most 1e-10 ‖g‖ above (measured 9.5e-12 before
        // the refinement could be skipped); where it is farther, the refinement was skipped,
        // so the weak-duality gap at its multipliers is at most `REFINE_GAP` of the residual,
        // and the residual is above the minimum by no more than that gap.
        let (mut worst, mut skipped) = (0.0f64, 0);
        for (trial, (gm, g, cols, brute)) in random_problems().into_iter().enumerate() {
            let s = run_dual_qp(&gm, &g, &cols);
            let gn = hm1(&gm, &g);
            assert!(s.mu.iter().all(|&v| v >= 0.0));
            assert!(
                s.residual >= brute - 1e-12 * gn,
                "trial {trial}: {} below the minimum {brute}",
                s.residual
            );
            if let Some(reported) = s.skip_gap {
                skipped += 1;
                let ch = gm.clone().cholesky().unwrap();
                let solve = move |v: &mut [f64]| {
                    let z = ch.solve(&DVector::from_column_slice(v));
                    v.copy_from_slice(z.as_slice());
                };
                let gap = dual_gap(g.as_slice(), &cols, &s.mu, &solve);
                assert_eq!(
                    gap, reported,
                    "trial {trial}: the gap reported for the skip"
                );
                assert!(
                    gap <= REFINE_GAP * s.residual,
                    "trial {trial}: {} above the minimum {brute} with a gap {gap:e}",
                    s.residual
                );
                assert!(
                    s.residual - brute <= gap + 1e-12 * gn,
                    "trial {trial}: {} above the minimum {brute} by more than its gap {gap:e}",
                    s.residual
                );
            } else {
                assert!(
                    s.residual <= brute + 1e-10 * gn,
                    "trial {trial}: refined dual QP {} vs enumeration {brute}",
                    s.residual
                );
            }
            assert_eq!(s.unresolved, 0, "trial {trial}");
            worst = worst.max((s.residual - brute) / gn);
        }
        eprintln!(
            "dual QP above the minimum by at most {worst:e} of ||g||; refinement skipped in \
             {skipped} trials, each within its duality gap"
        );
    }

    #[test]
    fn certificate_dual_qp_reaches_zero_on_degenerate_cones() {
        // The degenerate cone of `certificate_nnls_is_exact_on_degenerate_cones` (each column
        // 30 times, exact multiples and copies turned by 1e-6 to 1e-3): the minimum is 0. The
        // first QP leaves 6.4e-6 of ‖g‖ (√tol, see `nnls_dual_qp`), the refinement 1.2e-8
        // (the active set: below 1e-12).
        let (gm, g, cols) = degenerate_cone();
        let s = run_dual_qp(&gm, &g, &cols);
        assert!(
            s.residual <= 3e-8 * hm1(&gm, &g),
            "residual {:e} of {:e}",
            s.residual,
            hm1(&gm, &g)
        );
        assert_eq!(s.unresolved, 0);
    }

    #[test]
    fn certificate_paths_agree_on_parallel_rods_at_rest() {
        // Rod b = [(0.4, 0.1, 0), (1.6, 0.1, 0)] with unit masses under gravity −y, resting on
        // the fixed rod a = [(0, 0, 0), (1, 0, 0)] at ε = 0.1: parallel edges, so the pair's
        // gradient and the endpoint distances of b0 and a1 are parallel generators (the pair's
        // one a convex combination of the two others); a1 under b's centre of mass holds the
        // weight exactly. The minimum is 0: both paths reach it to round-off.
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, //
            0.4, 0.1, 0.0, 1.6, 0.1, 0.0,
        ];
        let mesh = two_edges(3, &x, vec![true, true, false, false]);
        let energy = crate::energy::TotalEnergy {
            terms: vec![Box::new(crate::energy::Gravity::<3>::new(
                vec![0.0, 0.0, 1.0, 1.0],
                [0.0, -1.0, 0.0],
            ))],
        };
        let norms = H1Norms::scaled(&mesh).unwrap();
        let none = HashMap::new();
        let cert =
            |path| certificate_with(&mesh, &energy, &x, 0.1, 1e-9, &norms, &none, path).unwrap();
        let exact = cert(CertificatePath::ActiveSet);
        let qp = cert(CertificatePath::Qp {
            backend: CERTIFICATE_BACKEND,
            tol: CERTIFICATE_TOL,
        });
        let auto = cert(CertificatePath::Auto);
        // another backend for the dual QP changes nothing below QP_PATH_MIN_GENERATORS
        let with_ip = cert(CertificatePath::AutoWith { backend: "ip" });
        assert_eq!(with_ip.method, "active_set");
        assert_eq!(with_ip.kappa.to_bits(), auto.kappa.to_bits());
        assert_eq!(exact.generators, 3);
        assert_eq!(
            (exact.method.as_str(), qp.method.as_str()),
            ("active_set", "qp")
        );
        assert_eq!(auto.method, "active_set");
        assert!(exact.kappa <= 1e-14, "{exact:?}");
        // the first QP leaves 3.6e-6, the refinement 2.6e-16
        assert!(qp.kappa <= 1e-14, "{qp:?}");
        assert_eq!((exact.unresolved, qp.unresolved), (0, 0));
        assert!(exact.gradient > 0.1, "{exact:?}");
    }

    fn curve(name: &str, vertices: Vec<usize>, edges: Vec<usize>) -> Body {
        Body {
            name: name.into(),
            kind: BodyKind::Curve,
            vertices,
            edges,
            ..Default::default()
        }
    }

    /// Two curves of one edge each, `[0, 1]` and `[2, 3]`, in dimension `dim`.
    fn two_edges(dim: usize, x: &[f64], fixed: Vec<bool>) -> Mesh {
        Mesh {
            dim,
            x_ref: x.to_vec(),
            fixed,
            edges: vec![[0, 1], [2, 3]],
            edge_body: vec![0, 1],
            bodies: vec![
                curve("a", vec![0, 1], vec![0]),
                curve("b", vec![2, 3], vec![1]),
            ],
            ..Default::default()
        }
    }

    /// The distance whose gradient a generator is: the pair's (part 0) or an endpoint's
    /// distance to the other edge (edge–edge parts 1–4).
    fn distance(mesh: &Mesh, x: &[f64], pair: ContactPair, part: u8) -> f64 {
        if part == 0 {
            return pair_rows(mesh, x, pair).unwrap().distance;
        }
        let ContactPair::EdgeEdge { a, b } = pair else {
            unreachable!()
        };
        let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
        let (v, seg) = [(ea[0], eb), (ea[1], eb), (eb[0], ea), (eb[1], ea)][part as usize - 1];
        let pv = p3(x, v);
        edge_edge_distance(&pv, &pv, &p3(x, seg[0]), &p3(x, seg[1])).distance
    }

    /// Every generator at `x` against central differences of its distance (step 1e-6;
    /// the distances are smooth there, so the error is O(1e-12)).
    fn check_generators(mesh: &Mesh, x: &[f64], skip_part0: bool) -> usize {
        let (col, _) = crate::solve::h1::dof_columns(mesh, true);
        let (gens, _) = generators(mesh, x, 0.0, 10.0, &HashMap::new(), &col).unwrap();
        let mut checked = 0;
        for gen in &gens {
            if skip_part0 && gen.part == 0 {
                continue;
            }
            for (dof, &c) in col.iter().enumerate() {
                if c == usize::MAX {
                    continue;
                }
                let h = 1e-6;
                let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
                xp[dof] += h;
                xm[dof] -= h;
                let fd = (distance(mesh, &xp, gen.pair, gen.part)
                    - distance(mesh, &xm, gen.pair, gen.part))
                    / (2.0 * h);
                let an = gen.entries.iter().find(|e| e.0 == c).map_or(0.0, |e| e.1);
                assert!(
                    (fd - an).abs() <= 1e-7,
                    "{:?} part {} dof {dof}: analytic {an} vs finite difference {fd}",
                    gen.pair,
                    gen.part
                );
            }
            checked += 1;
        }
        checked
    }

    #[test]
    fn certificate_point_edge_gradients_match_finite_differences() {
        // Edge [0, 1] and edge [2, 3] of two curves; vertex 3 projects inside edge [0, 1],
        // vertex 2 onto its end 1 (an endpoint gradient), 0 and 1 onto edge [2, 3].
        let x = vec![0.0, 0.0, 1.0, 0.2, 1.3, 0.9, 0.4, 0.5];
        let mesh = two_edges(2, &x, vec![false, true, false, false]);
        assert_eq!(check_generators(&mesh, &x, false), 4);
    }

    #[test]
    fn certificate_3d_gradients_match_finite_differences() {
        // Two triangles (surfaces) one above the other, the upper one rotated: vertex–face and
        // edge–edge pairs in general position.
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, //
            0.3, -0.2, 0.5, 0.9, 0.6, 0.55, -0.1, 0.7, 0.45,
        ];
        let faces = vec![[0, 1, 2], [3, 4, 5]];
        let surface = |name: &str, vertices: Vec<usize>, edges: Vec<usize>, f: usize| Body {
            name: name.into(),
            kind: BodyKind::Surface,
            vertices,
            edges,
            triangles: vec![f],
            faces: vec![f],
            ..Default::default()
        };
        let mesh = Mesh {
            dim: 3,
            x_ref: x.clone(),
            fixed: vec![true, false, false, false, false, false],
            edges: vec![[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3]],
            edge_body: vec![0, 0, 0, 1, 1, 1],
            triangles: faces.clone(),
            faces,
            face_body: vec![0, 1],
            bodies: vec![
                surface("low", vec![0, 1, 2], vec![0, 1, 2], 0),
                surface("up", vec![3, 4, 5], vec![3, 4, 5], 1),
            ],
            ..Default::default()
        };
        let n = check_generators(&mesh, &x, false);
        assert!(n >= 6 + 9, "{n} generators checked");
    }

    #[test]
    fn certificate_parallel_edges_add_their_endpoint_distances() {
        // Two parallel edges in space (rods), overlapping along their middle: the distance of
        // the pair is not differentiable (eq. 12), the four endpoint distances are, and the
        // two whose endpoint projects inside the other edge are at the pair's distance.
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, //
            0.4, 0.1, 0.0, 1.6, 0.1, 0.0,
        ];
        let mesh = two_edges(3, &x, vec![false; 4]);
        let (col, _) = crate::solve::h1::dof_columns(&mesh, true);
        let (gens, pairs) = generators(&mesh, &x, 0.1, 1e-9, &HashMap::new(), &col).unwrap();
        assert_eq!(pairs, 1);
        let parts: Vec<u8> = gens.iter().map(|g| g.part).collect();
        // a1 = (1, 0, 0) projects inside b, b0 = (0.4, 0.1, 0) inside a: parts 2 and 3
        assert_eq!(parts, vec![0, 2, 3]);
        assert_eq!(check_generators(&mesh, &x, true), 4);
    }

    #[test]
    fn certificate_counts_a_pair_the_sub_problem_held_beyond_the_tolerance() {
        // The same rods 1e-9 farther apart than ε + active_tol: not a generator by its gap,
        // a generator when the last sub-problem held it.
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, //
            0.4, 0.1, 0.0, 1.6, 0.1, 0.0,
        ];
        let mesh = two_edges(3, &x, vec![false; 4]);
        let (col, _) = crate::solve::h1::dof_columns(&mesh, true);
        let eps = 0.1 - 2e-9;
        let (gens, pairs) = generators(&mesh, &x, eps, 1e-9, &HashMap::new(), &col).unwrap();
        assert_eq!((gens.len(), pairs), (0, 0));
        let pair = near_pairs(&mesh, &x, 0.2, true)[0];
        let held = HashMap::from([(pair, 1.0)]);
        let (gens, pairs) = generators(&mesh, &x, eps, 1e-9, &held, &col).unwrap();
        assert_eq!(pairs, 1);
        assert_eq!(gens[0].pair, pair);
    }
}
