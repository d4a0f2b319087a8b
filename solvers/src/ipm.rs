//! An interior-point backend on the condensed (normal-equations) system, with a sparse
//! `LDLᵀ` from `faer`: the `ip` backend.
//!
//! # Method
//!
//! Each finite side of a row becomes a one-sided constraint `g_j·x ≥ h_j` (`g = a_i`, `h = l_i`
//! for a lower bound; `g = −a_i`, `h = −u_i` for an upper one); rows with `l_i = u_i` are
//! equalities `E x = b`; free rows are dropped. With slacks `s = G x − h ≥ 0`, duals `z ≥ 0`
//! and `y_E`, a Mehrotra predictor–corrector method solves
//!
//! ```text
//!     P x + q − Gᵀz − Eᵀy_E = 0,   G x − h − s = 0,   E x = b,   s ∘ z = σμ e.
//! ```
//!
//! Eliminating `Δs = G Δx + r_p` and `Δz = S⁻¹(r_c − Z Δs)` leaves the quasidefinite system
//!
//! ```text
//!     [ P + Gᵀ D G + ρI   Eᵀ ] [  Δx  ]   [ −r_d + Gᵀ S⁻¹(r_c − Z r_p) ]
//!     [       E          −δI ] [ −Δy_E ] = [ −r_e                       ],   D = S⁻¹Z,
//! ```
//!
//! factorized once per iteration by `faer`'s supernodal sparse `LDLᵀ` (AMD ordering, symbolic
//! phase once per QP pattern: the backend keeps the last one and reuses it while the next
//! QP's condensed matrix has the same pattern; dynamic regularization of the pivots by their expected signs), with
//! `ρ, δ = 1e-10·max(1, max diag)`. Both predictor and corrector use the one factorization;
//! the corrector's direction gets up to two steps of iterative refinement against the
//! unregularized Newton system, each skipped once that system's residual is below
//! `1e-3·eps_abs`; the predictor's (which only sets the centring and the second-order term)
//! gets none. The step is `0.99×` the longest that keeps `s, z > 0`, the same for the primal
//! and dual variables.
//!
//! # Starting point
//!
//! Cold: `min ½xᵀPx + qᵀx + ½|Gx − h|²` subject to `E x = b`, then slacks and duals shifted
//! positive by Mehrotra's heuristic. With a warm start's duals `y` (the previous inner QP's,
//! or the same QP before lazy rows were added, new rows at 0): `z` from `y`, `x` the minimizer
//! of the Lagrangian `½xᵀPx + qᵀx − zᵀ(Gx − h)` plus `½|g_j x − h_j|²` over the rows that hold
//! a dual, `z_j > WARM_DUAL_REL · max z` (an interior-point solution leaves every dual
//! positive, the rows far from binding at about `μ/s_j`), subject to `E x = b` (at an exact
//! solution this is its `x`), then the same shifts. A warm start's `x` is not used.
//!
//! # Constraint reduction
//!
//! Most rows of a contact QP end far from binding (balloons n = 1600: about 7 600 of 54 000
//! rows hold a dual at the solution), yet every row couples its vertices in `K`: rows the
//! lazy oracle added for a long step couple vertices many edges apart, and the factor `L` of
//! the full `K` had 23–25 times the entries of the factor of `P` plus the binding rows alone.
//! So each iteration factorizes a reduced matrix instead, built from the rows whose weight is
//! not negligible, `D_jj |g_j|² ≥ REDUCE_BELOW · min_c P_cc` over the row's columns `c` (a
//! row with a smaller weight moves its vertices' stiffness by less than that fraction). This
//! is the idea of the constraint-reduced interior-point methods (Tits, Absil and Woessner
//! for linear programs; Jung, O'Leary and Tits for convex QPs), with one difference: the
//! direction here is still the Newton direction of the whole QP. The refinement above runs
//! against the full Newton system (every row), with the reduced factorization as its
//! solver, for up to `REDUCED_REFINE` steps until the residual is below `REDUCED_REFINE_REL`
//! of the right-hand side (or `REFINE_BELOW·eps_abs`). If it does not get there (the rows
//! are not yet separated: it stalls or grows), the iteration factorizes the full `K` as
//! before, and so do the next `REDUCE_PAUSE`; a solve that then does not end `Solved` is
//! done again without reduction. Reduction is skipped while more than `REDUCE_MAX_FRACTION`
//! of the rows would be in it, and for a QP whose rows add fewer off-diagonal entries to `K`
//! than `REDUCE_MIN_COUPLING_SHARE` of `P`'s (bounds on single variables add none: `K` then
//! has `P`'s pattern, and a reduced matrix would be another copy of its factorization). A
//! reduced matrix serves again while the wanted rows are among its rows and number at least
//! `1/REUSE_SLACK` of them (its other rows keep their true weights, so it is only closer to
//! the full `K`): as the iterations separate the rows, the
//! wanted set mostly shrinks, and building a matrix (pattern, AMD ordering, symbolic
//! factorization) cost more than factorizing it (balloons n = 1600: 157 builds for 385
//! reduced iterations, against 325 for 404 when every change of the wanted rows built a new
//! one). The reduced matrices' symbolic factorizations are cached like the full one's; the
//! full `K` is only assembled when an iteration needs it. The warm
//! start's first system holds exactly the rows with a dual, so it is reduced already.
//! [`IpBackend::without_reduction`] factorizes the full `K` at every iteration.
//!
//! Unlike the KKT form of a general interior-point code (`n + m` unknowns), this system has
//! `n + m_E` unknowns: for the contact QPs of the sub-problems, whose rows touch two or three
//! vertices each and whose only equality rows are the few rank-one rows of a gas, it is the
//! sparse Hessian plus the contact rows' couplings.
//!
//! # Stalls
//!
//! Mehrotra's corrector adds the second-order term `−Δs_aff∘Δz_aff` to the centring target.
//! On a QP of the `drop` scene at rest (a ring on the floor, 7 rows, two of them trading their
//! activity at every step) that term raised `sᵀz` at every other iteration: the residuals fell
//! to 1e-14 while the gap cycled between 0.02 and 0.14 until the iteration limit (Clarabel:
//! 9 iterations). After `STALL_ITERATIONS` iterations without a new smallest gap, the
//! corrector's right-hand side is the centred one, `−s∘z + σμ`, for the rest of the solve;
//! that QP then ends `Solved` after 22 iterations (8 when the mode is on from the start). A solve
//! that makes progress never enters this mode, so its iterates are those of plain Mehrotra.
//!
//! # Termination and statuses
//!
//! `Solved` when the point meets the common tolerances of
//! [`crate::clarabel_backend::meets_tolerances`] for the original QP (primal and dual
//! residuals, with the duals mapped back: `y_i = z_upper − z_lower`, `y_i = −y_E` on
//! equality rows) and the complementarity gap `sᵀz ≤ eps_abs + eps_rel·max(1, |½xᵀPx + qᵀx|)`;
//! `MaxIterations` after `min(max_iter, 200)` iterations; `TimeLimit`; `NumericalError` when
//! a factorization fails or the step length collapses (an infeasible QP ends there: this
//! backend has no infeasibility certificate). Warm starts are checked, and their duals used.

use crate::backend::{QpBackend, QpError, QpSettings, QpSolution, QpStatus, WarmStart};
use crate::clarabel_backend::meets_tolerances;
use crate::qp::Qp;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side, Spec};
use std::sync::Arc;
use std::time::Instant;

/// A refinement step of the corrector is skipped once the Newton system's residual is below
/// this fraction of `eps_abs`: a thousandth of what the termination tests can see.
const REFINE_BELOW: f64 = 1e-3;

/// Constraint reduction: a row joins the reduced matrix once its weight `d_j |g_j|²` reaches
/// this fraction of the smallest diagonal entry of `P` over its columns.
const REDUCE_BELOW: f64 = 1e-3;

/// Constraint reduction is given up for a QP once more than this fraction of its rows is in
/// the reduced matrix.
const REDUCE_MAX_FRACTION: f64 = 0.5;

/// Constraint reduction is skipped for a QP whose rows' couplings (`Σ_j l_j(l_j − 1)/2`, the
/// off-diagonal entries they add to `K`, over rows of `l_j` entries) are fewer than this share
/// of `P`'s stored entries: `K` then has about `P`'s pattern, and each reduced matrix would be
/// another copy of it (balloons at 4·10⁵ vertices with the trust region, whose box rows have
/// one entry each: 8 reduced matrices built in two QPs).
const REDUCE_MIN_COUPLING_SHARE: f64 = 0.01;

/// After a reduced matrix that was not enough, this many iterations use the full one.
const REDUCE_PAUSE: usize = 2;
/// A reduced matrix is kept while the wanted rows are among its rows and number at least
/// `1/REUSE_SLACK` of them (its rows beyond the wanted ones keep their true weights).
const REUSE_SLACK: f64 = 2.0;

/// Refinement steps of the predictor's and the corrector's direction with the reduced matrix.
const REDUCED_REFINE_PREDICTOR: usize = 2;
const REDUCED_REFINE: usize = 8;

/// With the reduced matrix, the corrector's direction is accepted once the Newton system's
/// residual is below this fraction of its right-hand side (or below `REFINE_BELOW·eps_abs`),
/// and refinement stops when a step reduces the residual by less than `REDUCED_STALL`.
const REDUCED_REFINE_REL: f64 = 1e-7;
const REDUCED_STALL: f64 = 0.5;

/// A warm start's dual counts as held when above this fraction of the largest.
const WARM_DUAL_REL: f64 = 1e-6;

/// Most interior-point iterations, whatever `max_iter` allows.
const MAX_IP_ITERATIONS: usize = 200;

/// After this many iterations without a new smallest complementarity gap, the corrector drops
/// Mehrotra's second-order term for the rest of the solve (module documentation, "Stalls").
const STALL_ITERATIONS: usize = 10;

/// The interior-point backend (module documentation).
#[derive(Debug)]
pub struct IpBackend {
    settings: QpSettings,
    /// The last QP's pattern and symbolic factorization (module documentation).
    symbolic: Option<SymbolicCache>,
    /// The same for the reduced matrices (module documentation, "Constraint reduction").
    symbolic_reduced: Option<SymbolicCache>,
    /// Constraint reduction on (the default) or off.
    reduction: bool,
    /// Iterations that factorized a reduced matrix, and those of them whose reduced matrix
    /// did not give the Newton direction (the full one was factorized instead), since the
    /// backend was made.
    reduced_iterations: usize,
    reduction_fallbacks: usize,
    /// Solves done again without reduction (their first attempt did not end `Solved`).
    reduction_retries: usize,
    /// Reduced matrices built (pattern and symbolic factorization).
    reduced_builds: usize,
    /// Solves whose corrector dropped Mehrotra's second-order term after a stall (module
    /// documentation, "Stalls").
    stalls: usize,
}

impl IpBackend {
    /// A backend with `settings` (validated at each solve).
    pub fn new(settings: QpSettings) -> Self {
        IpBackend {
            settings,
            symbolic: None,
            symbolic_reduced: None,
            reduction: true,
            reduced_iterations: 0,
            reduction_fallbacks: 0,
            reduction_retries: 0,
            reduced_builds: 0,
            stalls: 0,
        }
    }

    /// The backend without constraint reduction (every iteration factorizes the full
    /// condensed matrix).
    pub fn without_reduction(settings: QpSettings) -> Self {
        let mut b = IpBackend::new(settings);
        b.reduction = false;
        b
    }

    /// Since the backend was made: iterations that factorized a reduced matrix, those of
    /// them whose reduced matrix was not enough (the full one was factorized too), and
    /// solves done again without reduction.
    pub fn reduction_counts(&self) -> (usize, usize, usize) {
        (
            self.reduced_iterations,
            self.reduction_fallbacks,
            self.reduction_retries,
        )
    }

    /// Reduced matrices built (pattern, ordering and symbolic factorization) since the backend
    /// was made: at most one per iteration that factorized one, fewer where a reduced matrix
    /// served again for a subset of its rows.
    pub fn reduced_builds(&self) -> usize {
        self.reduced_builds
    }

    /// Solves so far whose corrector dropped Mehrotra's second-order term after a stall
    /// (module documentation, "Stalls").
    pub fn stalls(&self) -> usize {
        self.stalls
    }

    /// Solves so far that reused the previous QP's symbolic factorization.
    pub fn symbolic_reuses(&self) -> usize {
        self.symbolic.as_ref().map_or(0, |c| c.hits)
    }
}

/// The constraints in one-sided form.
pub(crate) struct Split {
    /// Inequality constraints `g_j·x ≥ h_j`: (row of `A`, sign ±1), and `h_j`.
    pub(crate) ineq: Vec<(usize, f64)>,
    pub(crate) h: Vec<f64>,
    /// Equality rows of `A` and their right-hand sides.
    pub(crate) eq: Vec<usize>,
    pub(crate) b: Vec<f64>,
    /// `G` by rows (CSR, the sign folded in).
    g_ptr: Vec<usize>,
    g_col: Vec<usize>,
    g_val: Vec<f64>,
    /// `E` by rows (CSR).
    e_ptr: Vec<usize>,
    e_col: Vec<usize>,
    e_val: Vec<f64>,
}

/// The diagonal of `P` (0 where it has no entry).
pub(crate) fn p_diagonal(qp: &Qp) -> Vec<f64> {
    let mut pdiag = vec![0.0; qp.n()];
    for (j, pd) in pdiag.iter_mut().enumerate() {
        for p in qp.p.colptr[j]..qp.p.colptr[j + 1] {
            if qp.p.rowval[p] == j {
                *pd = qp.p.nzval[p];
            }
        }
    }
    pdiag
}

/// `out_j = row_j · x` for a CSR matrix.
#[inline]
fn csr_mul(ptr: &[usize], col: &[usize], val: &[f64], x: &[f64], out: &mut [f64]) {
    for (j, o) in out.iter_mut().enumerate() {
        let mut acc = 0.0;
        for p in ptr[j]..ptr[j + 1] {
            acc += val[p] * x[col[p]];
        }
        *o = acc;
    }
}

/// `out += Mᵀ w` for a CSR matrix.
#[inline]
fn csr_tr_mul_add(ptr: &[usize], col: &[usize], val: &[f64], w: &[f64], out: &mut [f64]) {
    for (j, &wj) in w.iter().enumerate() {
        if wj != 0.0 {
            for p in ptr[j]..ptr[j + 1] {
                out[col[p]] += val[p] * wj;
            }
        }
    }
}

impl Split {
    pub(crate) fn new(qp: &Qp) -> Split {
        let (n, m) = (qp.n(), qp.m());
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m];
        for j in 0..n {
            for p in qp.a.colptr[j]..qp.a.colptr[j + 1] {
                rows[qp.a.rowval[p]].push((j, qp.a.nzval[p]));
            }
        }
        let (mut ineq, mut h, mut eq, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..m {
            if qp.l[i] == qp.u[i] {
                eq.push(i);
                b.push(qp.l[i]);
                continue;
            }
            if qp.l[i].is_finite() {
                ineq.push((i, 1.0));
                h.push(qp.l[i]);
            }
            if qp.u[i].is_finite() {
                ineq.push((i, -1.0));
                h.push(-qp.u[i]);
            }
        }
        let (mut g_ptr, mut g_col, mut g_val) = (vec![0], Vec::new(), Vec::new());
        for &(i, sg) in &ineq {
            for &(c, v) in &rows[i] {
                g_col.push(c);
                g_val.push(sg * v);
            }
            g_ptr.push(g_col.len());
        }
        let (mut e_ptr, mut e_col, mut e_val) = (vec![0], Vec::new(), Vec::new());
        for &i in &eq {
            for &(c, v) in &rows[i] {
                e_col.push(c);
                e_val.push(v);
            }
            e_ptr.push(e_col.len());
        }
        Split {
            ineq,
            h,
            eq,
            b,
            g_ptr,
            g_col,
            g_val,
            e_ptr,
            e_col,
            e_val,
        }
    }

    /// The duals of the `m` rows of the QP from the inequality duals `z` and the equality
    /// duals `ye` (the sign convention of [`QpSolution::y`]): `y_i = z_upper − z_lower`,
    /// `y_i = −y_E` on equality rows.
    pub(crate) fn duals(&self, m: usize, z: &[f64], ye: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; m];
        for (&(i, sg), &zj) in self.ineq.iter().zip(z) {
            y[i] -= sg * zj;
        }
        for (&i, &v) in self.eq.iter().zip(ye) {
            y[i] = -v;
        }
        y
    }

    /// The same equality rows and the inequality constraints `keep` only (in that order).
    pub(crate) fn subset(&self, keep: &[usize]) -> Split {
        let (mut g_ptr, mut g_col, mut g_val) = (vec![0], Vec::new(), Vec::new());
        for &j in keep {
            let (cs, vs) = self.g_row(j);
            g_col.extend_from_slice(cs);
            g_val.extend_from_slice(vs);
            g_ptr.push(g_col.len());
        }
        Split {
            ineq: keep.iter().map(|&j| self.ineq[j]).collect(),
            h: keep.iter().map(|&j| self.h[j]).collect(),
            eq: self.eq.clone(),
            b: self.b.clone(),
            g_ptr,
            g_col,
            g_val,
            e_ptr: self.e_ptr.clone(),
            e_col: self.e_col.clone(),
            e_val: self.e_val.clone(),
        }
    }

    /// The entries of inequality constraint `j`: (columns, values with the sign).
    pub(crate) fn g_row(&self, j: usize) -> (&[usize], &[f64]) {
        let r = self.g_ptr[j]..self.g_ptr[j + 1];
        (&self.g_col[r.clone()], &self.g_val[r])
    }

    /// `G x` into `out`.
    pub(crate) fn g_mul(&self, x: &[f64], out: &mut [f64]) {
        csr_mul(&self.g_ptr, &self.g_col, &self.g_val, x, out);
    }

    /// `out += Gᵀ w`.
    pub(crate) fn gt_mul_add(&self, w: &[f64], out: &mut [f64]) {
        csr_tr_mul_add(&self.g_ptr, &self.g_col, &self.g_val, w, out);
    }

    /// `E x` into `out`.
    pub(crate) fn e_mul(&self, x: &[f64], out: &mut [f64]) {
        csr_mul(&self.e_ptr, &self.e_col, &self.e_val, x, out);
    }

    /// `out += Eᵀ w`.
    pub(crate) fn et_mul_add(&self, w: &[f64], out: &mut [f64]) {
        csr_tr_mul_add(&self.e_ptr, &self.e_col, &self.e_val, w, out);
    }
}

/// The pattern of the last QP's condensed matrix and its symbolic factorization (AMD
/// ordering, elimination tree), kept by the backend between solves.
#[derive(Debug)]
pub(crate) struct SymbolicCache {
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    symbolic: Arc<SymbolicCholesky<usize>>,
    /// Solves that reused a cached factorization, since the backend was made.
    hits: usize,
}

/// The condensed matrix `K` (upper triangle, CSC, `n + m_E` columns): its pattern, where each
/// contribution goes, its factorization.
pub(crate) struct Kkt {
    n: usize,
    dim: usize,
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    /// The value positions of `P`'s entries, in `P`'s order.
    p_pos: Vec<usize>,
    /// The value positions of the diagonal entries.
    diag_pos: Vec<usize>,
    /// Per inequality constraint `j`, `g_pos[g_ptr[j]..g_ptr[j+1]]`: (value position,
    /// g_a·g_b) over its entry pairs `a ≤ b`.
    g_ptr: Vec<usize>,
    g_pos: Vec<(usize, f64)>,
    /// The value positions of `E`'s entries and their values.
    e_pos: Vec<(usize, f64)>,
    symbolic: Arc<SymbolicCholesky<usize>>,
    sym_mat: SymbolicSparseColMat<usize>,
    signs: Vec<i8>,
    lvals: Vec<f64>,
    buf: MemBuffer,
}

impl Kkt {
    /// `cache`: the last QP's pattern and symbolic factorization, reused when this QP's
    /// pattern is the same (and replaced otherwise).
    pub(crate) fn new(qp: &Qp, split: &Split, cache: &mut Option<SymbolicCache>) -> Option<Kkt> {
        let n = qp.n();
        let me = split.eq.len();
        let dim = n + me;
        // the pattern as sorted column sets (upper: row ≤ column): every contribution, counted
        // per column, placed, then each column sorted and deduplicated in place
        let mut count = vec![1usize; dim];
        for (j, c) in count.iter_mut().enumerate().take(n) {
            *c += qp.p.colptr[j + 1] - qp.p.colptr[j];
        }
        for j in 0..split.ineq.len() {
            let (cs, _) = split.g_row(j);
            for &a in cs {
                for &b in cs {
                    if a <= b {
                        count[b] += 1;
                    }
                }
            }
        }
        for k in 0..me {
            count[n + k] += split.e_ptr[k + 1] - split.e_ptr[k];
        }
        let mut next = Vec::with_capacity(dim + 1);
        next.push(0usize);
        for c in &count {
            next.push(next.last().copied().unwrap_or(0) + c);
        }
        let mut raw = vec![0usize; *next.last().unwrap_or(&0)];
        let mut fill = next[..dim].to_vec();
        let mut put = |r: usize, c: usize| {
            raw[fill[c]] = r;
            fill[c] += 1;
        };
        for j in 0..dim {
            put(j, j);
        }
        for j in 0..n {
            for p in qp.p.colptr[j]..qp.p.colptr[j + 1] {
                put(qp.p.rowval[p], j);
            }
        }
        for j in 0..split.ineq.len() {
            let (cs, _) = split.g_row(j);
            for &a in cs {
                for &b in cs {
                    if a <= b {
                        put(a, b);
                    }
                }
            }
        }
        for k in 0..me {
            for &c in &split.e_col[split.e_ptr[k]..split.e_ptr[k + 1]] {
                put(c, n + k);
            }
        }
        let mut colptr = Vec::with_capacity(dim + 1);
        let mut rowval = Vec::with_capacity(raw.len());
        colptr.push(0);
        for c in 0..dim {
            let seg = &mut raw[next[c]..next[c + 1]];
            seg.sort_unstable();
            let mut last = usize::MAX;
            for &r in seg.iter() {
                if r != last {
                    rowval.push(r);
                    last = r;
                }
            }
            colptr.push(rowval.len());
        }
        let pos = |r: usize, c: usize| -> usize {
            let s = &rowval[colptr[c]..colptr[c + 1]];
            colptr[c] + s.binary_search(&r).expect("entry in the pattern")
        };
        let mut p_pos = Vec::with_capacity(qp.p.nnz());
        for j in 0..n {
            for p in qp.p.colptr[j]..qp.p.colptr[j + 1] {
                p_pos.push(pos(qp.p.rowval[p], j));
            }
        }
        let diag_pos = (0..dim).map(|j| pos(j, j)).collect();
        let mut g_ptr = vec![0];
        let mut g_pos = Vec::new();
        for j in 0..split.ineq.len() {
            let (cs, vs) = split.g_row(j);
            for (&a, &va) in cs.iter().zip(vs) {
                for (&b, &vb) in cs.iter().zip(vs) {
                    if a <= b {
                        // (g gᵀ)_ab, stored once in the upper triangle
                        g_pos.push((pos(a, b), va * vb));
                    }
                }
            }
            g_ptr.push(g_pos.len());
        }
        let e_pos = (0..split.eq.len())
            .flat_map(|k| {
                let r = split.e_ptr[k]..split.e_ptr[k + 1];
                split.e_col[r.clone()]
                    .iter()
                    .zip(&split.e_val[r])
                    .map(move |(&c, &v)| (c, k, v))
            })
            .map(|(c, k, v)| (pos(c, n + k), v))
            .collect();
        let sym_mat =
            SymbolicSparseColMat::new_checked(dim, dim, colptr.clone(), None, rowval.clone());
        let symbolic = match cache {
            Some(c) if c.colptr == colptr && c.rowval == rowval => {
                c.hits += 1;
                Arc::clone(&c.symbolic)
            }
            _ => {
                let symbolic = Arc::new(
                    factorize_symbolic_cholesky(
                        sym_mat.as_ref(),
                        Side::Upper,
                        SymmetricOrdering::Amd,
                        CholeskySymbolicParams::default(),
                    )
                    .ok()?,
                );
                *cache = Some(SymbolicCache {
                    colptr: colptr.clone(),
                    rowval: rowval.clone(),
                    symbolic: Arc::clone(&symbolic),
                    hits: cache.as_ref().map_or(0, |c| c.hits),
                });
                symbolic
            }
        };
        let mut signs = vec![1i8; dim];
        for s in signs.iter_mut().skip(n) {
            *s = -1;
        }
        let req = symbolic
            .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Spec::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let lvals = vec![0.0; symbolic.len_val()];
        Some(Kkt {
            n,
            dim,
            colptr,
            rowval,
            p_pos,
            diag_pos,
            g_ptr,
            g_pos,
            e_pos,
            symbolic,
            sym_mat,
            signs,
            lvals,
            buf: MemBuffer::try_new(req).ok()?,
        })
    }

    /// The values of `K` for the weights `d` (`D`), with `reg` added to the `x` block's
    /// diagonal and `−reg_e` to the equality block's.
    pub(crate) fn values(&self, qp: &Qp, d: &[f64], reg: f64, reg_e: f64) -> Vec<f64> {
        let mut v = vec![0.0; self.rowval.len()];
        for (&p, &val) in self.p_pos.iter().zip(&qp.p.nzval) {
            v[p] += val;
        }
        for (j, &dj) in d.iter().enumerate() {
            for &(p, gg) in &self.g_pos[self.g_ptr[j]..self.g_ptr[j + 1]] {
                v[p] += dj * gg;
            }
        }
        for &(p, e) in &self.e_pos {
            v[p] += e;
        }
        for (j, &p) in self.diag_pos.iter().enumerate() {
            v[p] += if j < self.n { reg } else { -reg_e };
        }
        v
    }

    /// `K v` (upper-triangle storage, symmetric product).
    pub(crate) fn mul(&self, vals: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.dim];
        for j in 0..self.dim {
            for p in self.colptr[j]..self.colptr[j + 1] {
                let i = self.rowval[p];
                y[i] += vals[p] * x[j];
                if i != j {
                    y[j] += vals[p] * x[i];
                }
            }
        }
        y
    }

    /// Factorizes `vals`; false when the factorization fails.
    pub(crate) fn factor(&mut self, vals: &[f64], delta: f64) -> bool {
        let mat = SparseColMatRef::new(self.sym_mat.as_ref(), vals);
        let reg = LdltRegularization {
            dynamic_regularization_signs: Some(&self.signs),
            dynamic_regularization_delta: delta,
            dynamic_regularization_epsilon: delta * 1e-3,
        };
        self.symbolic
            .factorize_numeric_ldlt(
                &mut self.lvals,
                mat,
                Side::Upper,
                reg,
                Par::Seq,
                MemStack::new(&mut self.buf),
                Spec::default(),
            )
            .is_ok()
    }

    /// Solves with the factorization in place.
    pub(crate) fn solve(&mut self, rhs: &mut [f64]) {
        let ldlt = faer::sparse::linalg::cholesky::LdltRef::new(&self.symbolic, &self.lvals);
        let n = rhs.len();
        let mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        ldlt.solve_in_place_with_conj(Conj::No, mat, Par::Seq, MemStack::new(&mut self.buf));
    }

    /// Solves `K_true Δ = rhs` with the factorization of the regularized `K` and two steps of
    /// iterative refinement against `K_true` (`vals_true`).
    pub(crate) fn solve_refined(&mut self, vals_true: &[f64], rhs: &[f64]) -> Vec<f64> {
        let mut x = rhs.to_vec();
        self.solve(&mut x);
        for _ in 0..2 {
            let kx = self.mul(vals_true, &x);
            let mut r: Vec<f64> = rhs.iter().zip(&kx).map(|(a, b)| a - b).collect();
            self.solve(&mut r);
            for (xi, ri) in x.iter_mut().zip(&r) {
                *xi += ri;
            }
        }
        x
    }
}

/// The full condensed matrix (built on first use, with `cache`) factorized for the weights
/// `d`; `None` when it cannot be built or factorized.
fn factor_full<'a>(
    kkt: &'a mut Option<Kkt>,
    qp: &Qp,
    split: &Split,
    cache: &mut Option<SymbolicCache>,
    d: &[f64],
    reg: f64,
) -> Option<&'a mut Kkt> {
    if kkt.is_none() {
        *kkt = Kkt::new(qp, split, cache);
    }
    let k = kkt.as_mut()?;
    let vals = k.values(qp, d, reg, reg);
    k.factor(&vals, reg).then_some(k)
}

/// Whether the reduced matrix of the rows `keep` can serve for the wanted rows `in_q` (`n_q`
/// of them): it holds all of them, and at most `REUSE_SLACK` times as many.
fn covers(keep: &[usize], in_q: &[bool], n_q: usize) -> bool {
    keep.len() as f64 <= REUSE_SLACK * n_q as f64
        && keep.iter().filter(|&&j| in_q[j]).count() == n_q
}

/// The longest `α ∈ (0, 1]` keeping `v + α·dv > 0` (and `1` when nothing limits it).
fn max_step(v: &[f64], dv: &[f64]) -> f64 {
    v.iter()
        .zip(dv)
        .filter(|(_, d)| **d < 0.0)
        .map(|(a, d)| -a / d)
        .fold(1.0, f64::min)
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

impl QpBackend for IpBackend {
    fn name(&self) -> &'static str {
        "ip"
    }

    fn tolerance(&self) -> Option<f64> {
        Some(self.settings.eps_abs)
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.settings.eps_abs = tol;
        self.settings.eps_rel = tol;
    }

    /// With constraint reduction, a solve that ends other than `Solved` (or at the time
    /// limit) after factorizing a reduced matrix is done again without reduction.
    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let before = self.reduced_iterations;
        let sol = self.solve_with(qp, warm, self.reduction)?;
        if self.reduced_iterations > before
            && !matches!(sol.status, QpStatus::Solved | QpStatus::TimeLimit)
        {
            self.reduction_retries += 1;
            let again = self.solve_with(qp, warm, false)?;
            return Ok(QpSolution {
                iterations: sol.iterations + again.iterations,
                solve_time_s: sol.solve_time_s + again.solve_time_s,
                ..again
            });
        }
        Ok(sol)
    }
}

impl IpBackend {
    /// One solve, with constraint reduction or without.
    fn solve_with(
        &mut self,
        qp: &Qp,
        warm: Option<&WarmStart>,
        reduction: bool,
    ) -> Result<QpSolution, QpError> {
        let start = Instant::now();
        self.settings.validate()?;
        qp.validate()?;
        let (n, m) = (qp.n(), qp.m());
        crate::osqp_backend::check_warm(warm, n, m)?;
        let s = &self.settings;
        let split = Split::new(qp);
        let (mi, me) = (split.ineq.len(), split.eq.len());
        let mut out = QpSolution {
            x: vec![0.0; n],
            y: vec![0.0; m],
            status: QpStatus::NumericalError,
            iterations: 0,
            solve_time_s: 0.0,
        };
        // The full condensed matrix, built when first needed (module documentation,
        // "Constraint reduction").
        let mut kkt: Option<Kkt> = None;
        // the duals of the original rows: y_i = z_upper − z_lower, −y_E on equality rows
        let map_y = |z: &[f64], ye: &[f64]| split.duals(m, z, ye);
        let maxdiag = (0..n)
            .filter_map(|j| {
                (qp.p.colptr[j]..qp.p.colptr[j + 1])
                    .find(|&p| qp.p.rowval[p] == j)
                    .map(|p| qp.p.nzval[p].abs())
            })
            .fold(1.0f64, f64::max);
        let reg = 1e-10 * maxdiag;
        let dim = n + me;

        // Initial point (module documentation, "Starting point").
        let warm_z: Option<Vec<f64>> = warm.filter(|w| !w.y.is_empty()).map(|w| {
            split
                .ineq
                .iter()
                .map(|&(i, sg)| (-sg * w.y[i]).max(0.0))
                .collect()
        });
        let weights: Vec<f64> = match &warm_z {
            Some(wz) => {
                // the rows that hold a dual: above a millionth of the largest (an
                // interior-point solution leaves every dual positive)
                let floor = WARM_DUAL_REL * wz.iter().copied().fold(0.0, f64::max);
                wz.iter()
                    .map(|&v| if v > floor && v > 0.0 { 1.0 } else { 0.0 })
                    .collect()
            }
            None => vec![1.0; mi],
        };
        let mut rhs = vec![0.0; dim];
        for (r, qv) in rhs.iter_mut().zip(&qp.q) {
            *r = -qv;
        }
        match &warm_z {
            Some(wz) => {
                // −q + Gᵀz + Σ_{z_j > 0} g_j h_j
                let t: Vec<f64> = wz
                    .iter()
                    .zip(&weights)
                    .zip(&split.h)
                    .map(|((z, w), h)| z + w * h)
                    .collect();
                split.gt_mul_add(&t, &mut rhs[..n]);
            }
            None => split.gt_mul_add(&split.h, &mut rhs[..n]),
        }
        for (k, bv) in split.b.iter().enumerate() {
            rhs[n + k] = *bv;
        }
        // Constraint reduction: per inequality, |g_j|² and the smallest diagonal entry of P
        // over its columns (not needed without reduction); the rows in the reduced matrix
        // (those of a warm start's duals at first).
        // (none where the rows add few entries to `K`: REDUCE_MIN_COUPLING_SHARE)
        let row_couplings: usize = (0..mi)
            .map(|j| {
                let l = split.g_row(j).0.len();
                l * l.saturating_sub(1) / 2
            })
            .sum();
        let mut reduce = reduction
            && mi > 0
            && row_couplings as f64 >= REDUCE_MIN_COUPLING_SHARE * qp.p.nnz() as f64;
        let (mut gnorm2, mut pmin) = (Vec::new(), Vec::new());
        if reduce {
            let pdiag = p_diagonal(qp);
            for j in 0..mi {
                let (cs, vs) = split.g_row(j);
                gnorm2.push(vs.iter().map(|v| v * v).sum::<f64>());
                pmin.push(
                    cs.iter()
                        .map(|&c| pdiag[c])
                        .fold(f64::INFINITY, f64::min)
                        .max(reg),
                );
            }
        }
        let mut in_q: Vec<bool> = weights.iter().map(|&w| w > 0.0).collect();
        let n_q = in_q.iter().filter(|&&b| b).count();
        // no reduced matrix before this iteration (after one that was not enough)
        let mut pause_until = 0usize;
        let mut reduced: Option<(Vec<usize>, Kkt)> = None;
        // The starting point's system: reduced when a warm start holds few enough duals
        // (its rows of weight 0 are not in it, so the reduced matrix is exact).
        let start_rows: Option<Vec<usize>> =
            (reduce && warm_z.is_some() && n_q as f64 <= REDUCE_MAX_FRACTION * mi as f64)
                .then(|| (0..mi).filter(|&j| in_q[j]).collect());
        let sub = start_rows.as_ref().map(|keep| split.subset(keep));
        let (start_split, start_weights, cache) = match (&sub, &start_rows) {
            (Some(sub), Some(keep)) => (sub, vec![1.0; keep.len()], &mut self.symbolic_reduced),
            _ => (&split, weights.clone(), &mut self.symbolic),
        };
        let Some(mut k) = Kkt::new(qp, start_split, cache) else {
            out.solve_time_s = start.elapsed().as_secs_f64();
            return Ok(out);
        };
        let vals_true = k.values(qp, &start_weights, 0.0, 0.0);
        let vals = k.values(qp, &start_weights, reg, reg);
        if !k.factor(&vals, reg) {
            out.solve_time_s = start.elapsed().as_secs_f64();
            return Ok(out);
        }
        let sol = k.solve_refined(&vals_true, &rhs);
        match start_rows {
            Some(keep) => reduced = Some((keep, k)),
            None => kkt = Some(k),
        }
        let mut x = sol[..n].to_vec();
        let mut ye: Vec<f64> = sol[n..].iter().map(|v| -v).collect();
        let mut gx = vec![0.0; mi];
        split.g_mul(&x, &mut gx);
        let r: Vec<f64> = gx.iter().zip(&split.h).map(|(a, b)| a - b).collect();
        let mut sl = r.clone();
        let mut z: Vec<f64> = match warm_z {
            Some(wz) => wz,
            None => r.iter().map(|v| -v).collect(),
        };
        if mi > 0 {
            let ds = (-1.5 * sl.iter().copied().fold(f64::INFINITY, f64::min)).max(0.0);
            let dz = (-1.5 * z.iter().copied().fold(f64::INFINITY, f64::min)).max(0.0);
            sl.iter_mut().for_each(|v| *v += ds);
            z.iter_mut().for_each(|v| *v += dz);
            let sz: f64 = sl.iter().zip(&z).map(|(a, b)| a * b).sum();
            let (ssum, zsum) = (sl.iter().sum::<f64>(), z.iter().sum::<f64>());
            let ds2 = if zsum > 0.0 { 0.5 * sz / zsum } else { 1.0 };
            let dz2 = if ssum > 0.0 { 0.5 * sz / ssum } else { 1.0 };
            let floor = 1e-8 * (1.0 + inf_norm(&r));
            sl.iter_mut().for_each(|v| *v = (*v + ds2).max(floor));
            z.iter_mut().for_each(|v| *v = (*v + dz2).max(floor));
        }

        let max_it = s.max_iter.min(MAX_IP_ITERATIONS);
        // the smallest complementarity gap so far and its iteration (module documentation,
        // "Stalls")
        let (mut best_gap, mut best_it) = (f64::INFINITY, 0);
        let mut safeguarded = false;
        let mut px = vec![0.0; n];
        let mut ex = vec![0.0; me];
        for it in 0..=max_it {
            // residuals
            px.iter_mut().for_each(|v| *v = 0.0);
            qp.p.sym_upper_mul_add(1.0, &x, &mut px);
            let mut rd: Vec<f64> = px.iter().zip(&qp.q).map(|(a, b)| a + b).collect();
            let mz: Vec<f64> = z.iter().map(|v| -v).collect();
            split.gt_mul_add(&mz, &mut rd);
            let mye: Vec<f64> = ye.iter().map(|v| -v).collect();
            split.et_mul_add(&mye, &mut rd);
            split.g_mul(&x, &mut gx);
            let rp: Vec<f64> = (0..mi).map(|j| gx[j] - split.h[j] - sl[j]).collect();
            split.e_mul(&x, &mut ex);
            let re: Vec<f64> = ex.iter().zip(&split.b).map(|(a, b)| a - b).collect();
            let gap: f64 = sl.iter().zip(&z).map(|(a, b)| a * b).sum();
            let obj = 0.5 * x.iter().zip(&px).map(|(a, b)| a * b).sum::<f64>()
                + x.iter().zip(&qp.q).map(|(a, b)| a * b).sum::<f64>();
            out.iterations = it;
            let y = map_y(&z, &ye);

            if gap <= s.eps_abs + s.eps_rel * obj.abs().max(1.0) && meets_tolerances(qp, &x, &y, s)
            {
                out.x = x;
                out.y = y;
                out.status = QpStatus::Solved;
                out.solve_time_s = start.elapsed().as_secs_f64();
                return Ok(out);
            }
            out.x = x.clone();
            out.y = y;
            if it == max_it {
                out.status = QpStatus::MaxIterations;
                break;
            }
            if start.elapsed().as_secs_f64() > s.time_limit_s {
                out.status = QpStatus::TimeLimit;
                break;
            }
            let mu = if mi > 0 { gap / mi as f64 } else { 0.0 };
            if gap < best_gap {
                (best_gap, best_it) = (gap, it);
            } else if it - best_it >= STALL_ITERATIONS && !safeguarded {
                safeguarded = true;
                self.stalls += 1;
            }
            // the matrix of this iteration
            let d: Vec<f64> = sl.iter().zip(&z).map(|(a, b)| b / a).collect();
            // Constraint reduction (module documentation): this iteration's rows are those
            // whose weight is not negligible; a new reduced matrix when they change.
            let mut full = !reduce || it < pause_until;
            if !full {
                let mut changed = false;
                let mut n_q = 0;
                for j in 0..mi {
                    let want = d[j] * gnorm2[j] >= REDUCE_BELOW * pmin[j];
                    changed |= want != in_q[j];
                    in_q[j] = want;
                    n_q += want as usize;
                }
                if n_q as f64 > REDUCE_MAX_FRACTION * mi as f64 {
                    full = true;
                    reduced = None;
                } else if reduced.is_none()
                    || (changed
                        && !reduced
                            .as_ref()
                            .is_some_and(|(keep, _)| covers(keep, &in_q, n_q)))
                {
                    self.reduced_builds += 1;
                    let keep: Vec<usize> = (0..mi).filter(|&j| in_q[j]).collect();
                    match Kkt::new(qp, &split.subset(&keep), &mut self.symbolic_reduced) {
                        Some(k) => reduced = Some((keep, k)),
                        None => {
                            reduce = false;
                            full = true;
                            reduced = None;
                        }
                    }
                }
            }
            if !full {
                self.reduced_iterations += 1;
                let (keep, rk) = reduced.as_mut().expect("built above");
                let dq: Vec<f64> = keep.iter().map(|&j| d[j]).collect();
                let vals = rk.values(qp, &dq, reg, reg);
                if !rk.factor(&vals, reg) {
                    reduce = false;
                    full = true;
                    reduced = None;
                }
            }
            if full && factor_full(&mut kkt, qp, &split, &mut self.symbolic, &d, reg).is_none() {
                out.status = QpStatus::NumericalError;
                break;
            }
            // Δ for a complementarity right-hand side rc, with the factorization `f`: the
            // condensed system, then up to `refine` steps of iterative refinement on the full
            // Newton system (equations (a), (c); (b) and (d) hold by construction), which also
            // absorbs the regularization and, with the reduced matrix, the rows left out of
            // it; a step is skipped once the residual is below `refine_below` (or, with the
            // reduced matrix, below `REDUCED_REFINE_REL` of the right-hand side). Also returns
            // whether the residual got there.
            let refine_below = REFINE_BELOW * s.eps_abs;
            let direction = |f: &mut Kkt,
                             rc: &[f64],
                             refine: usize,
                             relative: bool|
             -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, bool) {
                // w = S⁻¹(rc − Z rp)
                let w: Vec<f64> = (0..mi).map(|j| (rc[j] - z[j] * rp[j]) / sl[j]).collect();
                let mut rhs = vec![0.0; dim];
                for (r, v) in rhs.iter_mut().zip(&rd) {
                    *r = -v;
                }
                split.gt_mul_add(&w, &mut rhs[..n]);
                for (k, v) in re.iter().enumerate() {
                    rhs[n + k] = -v;
                }
                let below = if relative {
                    refine_below.max(REDUCED_REFINE_REL * inf_norm(&rhs))
                } else {
                    refine_below
                };
                let mut last = f64::INFINITY;
                f.solve(&mut rhs);
                let mut dx = rhs[..n].to_vec();
                let mut dye: Vec<f64> = rhs[n..].iter().map(|v| -v).collect();
                let mut gdx = vec![0.0; mi];
                split.g_mul(&dx, &mut gdx);
                let mut ds: Vec<f64> = (0..mi).map(|j| gdx[j] + rp[j]).collect();
                let mut dz: Vec<f64> = (0..mi).map(|j| (rc[j] - z[j] * ds[j]) / sl[j]).collect();
                let mut converged = false;
                // Gᵀ Δz, kept up to date by the row pass below (one pass over G per step)
                let mut gtdz = vec![0.0; n];
                if refine > 0 {
                    split.gt_mul_add(&dz, &mut gtdz);
                }
                for k in 0..=refine {
                    if refine == 0 {
                        break;
                    }
                    // ρ_a = −r_d − (P Δx − Gᵀ Δz − Eᵀ Δy), ρ_c = −r_e − E Δx
                    let mut ra: Vec<f64> = rd.iter().map(|v| -v).collect();
                    let mut pdx = vec![0.0; n];
                    qp.p.sym_upper_mul_add(1.0, &dx, &mut pdx);
                    for ((r, v), g) in ra.iter_mut().zip(&pdx).zip(&gtdz) {
                        *r += g - v;
                    }
                    split.et_mul_add(&dye, &mut ra);
                    let mut edx = vec![0.0; me];
                    split.e_mul(&dx, &mut edx);
                    let mut corr = ra;
                    corr.extend(re.iter().zip(&edx).map(|(a, b)| -a - b));
                    let res = inf_norm(&corr);
                    if res <= below {
                        converged = true;
                        break;
                    }
                    // the last step, or (with the reduced matrix) refinement that stalls
                    if k == refine || (relative && res > REDUCED_STALL * last) {
                        break;
                    }
                    last = res;
                    f.solve(&mut corr);
                    for (v, c) in dx.iter_mut().zip(&corr[..n]) {
                        *v += c;
                    }
                    for (v, c) in dye.iter_mut().zip(&corr[n..]) {
                        *v -= c;
                    }
                    // per row j: g_j·corr, then Δs, Δz and Gᵀ Δz updated from the same row
                    for j in 0..mi {
                        let (cs, vs) = split.g_row(j);
                        let gd: f64 = cs.iter().zip(vs).map(|(&c, &v)| v * corr[c]).sum();
                        ds[j] += gd;
                        let ddz = -z[j] * gd / sl[j];
                        dz[j] += ddz;
                        if ddz != 0.0 {
                            for (&c, &v) in cs.iter().zip(vs) {
                                gtdz[c] += v * ddz;
                            }
                        }
                    }
                }
                (dx, dye, ds, dz, converged)
            };
            let rc_aff: Vec<f64> = (0..mi).map(|j| -sl[j] * z[j]).collect();
            let predictor_corrector = |f: &mut Kkt, is_reduced: bool| {
                // predictor
                let (_, _, ds_a, dz_a, _) = direction(
                    f,
                    &rc_aff,
                    if is_reduced {
                        REDUCED_REFINE_PREDICTOR
                    } else {
                        0
                    },
                    is_reduced,
                );
                let a_aff = max_step(&sl, &ds_a).min(max_step(&z, &dz_a));
                let mu_aff = if mi > 0 {
                    (0..mi)
                        .map(|j| (sl[j] + a_aff * ds_a[j]) * (z[j] + a_aff * dz_a[j]))
                        .sum::<f64>()
                        / mi as f64
                } else {
                    0.0
                };
                let sigma = if mu > 0.0 {
                    (mu_aff / mu).powi(3).min(1.0)
                } else {
                    0.0
                };
                // corrector; after a stall without Mehrotra's second-order term (module
                // documentation, "Stalls")
                let second = if safeguarded { 0.0 } else { 1.0 };
                let rc: Vec<f64> = (0..mi)
                    .map(|j| -sl[j] * z[j] - second * ds_a[j] * dz_a[j] + sigma * mu)
                    .collect();
                direction(
                    f,
                    &rc,
                    if is_reduced { REDUCED_REFINE } else { 2 },
                    is_reduced,
                )
            };
            let (dx, dye, ds, dz) = if full {
                let k = kkt.as_mut().expect("factorized above");
                let (dx, dye, ds, dz, _) = predictor_corrector(k, false);
                (dx, dye, ds, dz)
            } else {
                let (_, rk) = reduced.as_mut().expect("factorized above");
                let (dx, dye, ds, dz, ok) = predictor_corrector(rk, true);
                if ok {
                    (dx, dye, ds, dz)
                } else {
                    // The reduced matrix did not give the Newton direction (its rows are not
                    // yet separated): the full matrix, for this iteration and the next
                    // `REDUCE_PAUSE`.
                    self.reduction_fallbacks += 1;
                    pause_until = it + 1 + REDUCE_PAUSE;
                    let Some(k) = factor_full(&mut kkt, qp, &split, &mut self.symbolic, &d, reg)
                    else {
                        out.status = QpStatus::NumericalError;
                        break;
                    };
                    let (dx, dye, ds, dz, _) = predictor_corrector(k, false);
                    (dx, dye, ds, dz)
                }
            };
            let alpha = (0.99 * max_step(&sl, &ds).min(max_step(&z, &dz))).min(1.0);
            if alpha.is_nan() || alpha <= 1e-12 || dx.iter().any(|v| !v.is_finite()) {
                out.status = QpStatus::NumericalError;
                break;
            }
            for (v, d) in x.iter_mut().zip(&dx) {
                *v += alpha * d;
            }
            for (v, d) in ye.iter_mut().zip(&dye) {
                *v += alpha * d;
            }
            for j in 0..mi {
                sl[j] = (sl[j] + alpha * ds[j]).max(f64::MIN_POSITIVE);
                z[j] = (z[j] + alpha * dz[j]).max(f64::MIN_POSITIVE);
            }
        }
        out.solve_time_s = start.elapsed().as_secs_f64();
        Ok(out)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::clarabel_backend::ClarabelBackend;
    use crate::qp::tests::{
        assert_bad_bounds_rejected, assert_equality_and_infeasible, assert_solves_small_qp,
    };
    use crate::qp::CscMatrix;

    #[test]
    fn solves_small_qp_with_crate_dual_signs() {
        assert_solves_small_qp(&mut IpBackend::new(QpSettings::default()), 1e-7);
    }

    #[test]
    fn equality_rows_and_an_infeasible_qp() {
        assert_equality_and_infeasible(&mut IpBackend::new(QpSettings::default()));
    }

    #[test]
    fn bad_input_is_an_error() {
        assert_bad_bounds_rejected(&mut IpBackend::new(QpSettings::default()));
    }

    /// A chain of points in 2D pressed down onto a line by a linear load, springs between
    /// neighbours (a tridiagonal `P` per component), two-point contact rows `x_{2i+1} ≥ −1`,
    /// duplicated rows and rows coupling neighbours: the structure of the contact QPs. Clarabel
    /// and `ip` must agree on the objective and the solution.
    pub(crate) fn chain_qp(n: usize) -> Qp {
        let dim = 2 * n;
        let mut pt = Vec::new();
        for c in 0..2 {
            for i in 0..n {
                let k = 2 * i + c;
                pt.push((k, k, 2.0 + 0.01 * i as f64));
                if i + 1 < n {
                    pt.push((k, k + 2, -1.0));
                }
            }
        }
        let p = CscMatrix::from_triplets(dim, dim, &pt).unwrap();
        let q: Vec<f64> = (0..dim)
            .map(|k| if k % 2 == 1 { 0.3 } else { -0.05 })
            .collect();
        let mut at = Vec::new();
        let (mut l, mut u) = (Vec::new(), Vec::new());
        let mut row = 0;
        for i in 0..n {
            // y_i ≥ −1 − 0.01 i, twice (a duplicate), and a row coupling x_i and y_i.
            for _ in 0..2 {
                at.push((row, 2 * i + 1, 1.0));
                l.push(-1.0 - 0.01 * i as f64);
                u.push(f64::INFINITY);
                row += 1;
            }
            at.push((row, 2 * i, 0.2));
            at.push((row, 2 * i + 1, 1.0));
            l.push(-1.5);
            u.push(2.0);
            row += 1;
        }
        let a = CscMatrix::from_triplets(row, dim, &at).unwrap();
        Qp { p, q, a, l, u }
    }

    /// The settings of the tests below: both tolerances at 1e-10.
    pub(crate) fn tight() -> QpSettings {
        QpSettings {
            eps_abs: 1e-10,
            eps_rel: 1e-10,
            ..QpSettings::default()
        }
    }

    #[test]
    fn agrees_with_clarabel_on_a_contact_like_qp() {
        let qp = chain_qp(60);
        let settings = tight();
        let ip = IpBackend::new(settings.clone()).solve(&qp, None).unwrap();
        let cl = ClarabelBackend::new(settings).solve(&qp, None).unwrap();
        assert_eq!(ip.status, QpStatus::Solved);
        assert_eq!(cl.status, QpStatus::Solved);
        let (ji, jc) = (qp.objective(&ip.x), qp.objective(&cl.x));
        assert!(
            (ji - jc).abs() <= 1e-8 * jc.abs().max(1.0),
            "objective ip {ji} clarabel {jc}"
        );
        let dx =
            ip.x.iter()
                .zip(&cl.x)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(dx < 1e-6, "max |x_ip − x_clarabel| = {dx}");
        assert!(qp.primal_residual(&ip.x) < 1e-9);
        assert!(qp.dual_residual(&ip.x, &ip.y) < 1e-8);
        // Some contact rows bind (the load pushes the chain down).
        assert!(ip.y.iter().any(|&y| y < -1e-6), "no lower row active");
    }

    /// A warm start from a solution's duals (a lazy re-solve: the same QP with rows added,
    /// their duals 0) reaches the cold solve's solution in fewer iterations; duals that are
    /// nonsense (wrong signs, huge) still reach it.
    #[test]
    fn warm_start_duals_are_used_and_safe() {
        let settings = tight();
        let full = chain_qp(60);
        // the QP without its coupling rows (every third), as before the oracle added them
        let keep: Vec<usize> = (0..full.m()).filter(|r| r % 3 != 2).collect();
        let mut at = Vec::new();
        for (k, &r) in keep.iter().enumerate() {
            for j in 0..full.n() {
                for p in full.a.colptr[j]..full.a.colptr[j + 1] {
                    if full.a.rowval[p] == r {
                        at.push((k, j, full.a.nzval[p]));
                    }
                }
            }
        }
        let part = Qp {
            p: full.p.clone(),
            q: full.q.clone(),
            a: CscMatrix::from_triplets(keep.len(), full.n(), &at).unwrap(),
            l: keep.iter().map(|&r| full.l[r]).collect(),
            u: keep.iter().map(|&r| full.u[r]).collect(),
        };
        let mut ip = IpBackend::new(settings);
        let first = ip.solve(&part, None).unwrap();
        assert_eq!(first.status, QpStatus::Solved);
        let mut y = vec![0.0; full.m()];
        for (k, &r) in keep.iter().enumerate() {
            y[r] = first.y[k];
        }
        let cold = ip.solve(&full, None).unwrap();
        let warm = ip
            .solve(
                &full,
                Some(&WarmStart {
                    x: Vec::new(),
                    y: y.clone(),
                }),
            )
            .unwrap();
        let junk = ip
            .solve(
                &full,
                Some(&WarmStart {
                    x: Vec::new(),
                    y: y.iter().map(|v| -1e6 * v + 3.0).collect(),
                }),
            )
            .unwrap();
        let jc = full.objective(&cold.x);
        for (name, sol) in [("warm", &warm), ("junk", &junk)] {
            assert_eq!(sol.status, QpStatus::Solved, "{name}");
            let j = full.objective(&sol.x);
            assert!(
                (j - jc).abs() <= 1e-8 * jc.abs().max(1.0),
                "{name}: {j} against {jc}"
            );
            assert!(full.primal_residual(&sol.x) < 1e-9, "{name}");
        }
        assert!(
            warm.iterations < cold.iterations,
            "warm {} cold {}",
            warm.iterations,
            cold.iterations
        );
    }

    /// `covers`: a reduced matrix serves for the wanted rows when it holds every one of them
    /// and at most `REUSE_SLACK` times as many.
    #[test]
    fn a_reduced_matrix_covers_a_subset_of_its_rows_not_too_much_smaller() {
        let keep = [1, 3, 4, 7];
        let want = |rows: &[usize]| {
            let mut w = vec![false; 9];
            rows.iter().for_each(|&j| w[j] = true);
            w
        };
        assert!(covers(&keep, &want(&[1, 3, 4, 7]), 4));
        assert!(covers(&keep, &want(&[3, 7]), 2));
        // a wanted row outside the matrix
        assert!(!covers(&keep, &want(&[3, 5]), 2));
        // more than REUSE_SLACK = 2 times as many rows as wanted
        assert!(!covers(&keep, &want(&[4]), 1));
    }

    /// Rows that add no off-diagonal entry to `K` (bounds on single variables, as a trust
    /// box's) give no reason for a reduced matrix, however many there are: none is built, and
    /// the solution is Clarabel's.
    #[test]
    fn no_reduction_where_the_rows_couple_nothing() {
        let base = chain_qp(60);
        let n = base.n();
        // −1 ≤ x_k ≤ 1 on every variable: one entry per row
        let at: Vec<(usize, usize, f64)> = (0..n).map(|k| (k, k, 1.0)).collect();
        let qp = Qp {
            p: base.p.clone(),
            q: base.q.iter().map(|v| 40.0 * v).collect(),
            a: CscMatrix::from_triplets(n, n, &at).unwrap(),
            l: vec![-1.0; n],
            u: vec![1.0; n],
        };
        let mut ip = IpBackend::new(tight());
        let s = ip.solve(&qp, None).unwrap();
        assert_eq!(s.status, QpStatus::Solved);
        // some bounds bind, so the solve is not trivial
        assert!(
            s.x.iter().any(|v| (v.abs() - 1.0).abs() < 1e-6),
            "{:?}",
            s.x
        );
        // warm-started too (where a reduced matrix would start from the rows with a dual)
        let w = WarmStart {
            x: Vec::new(),
            y: s.y.clone(),
        };
        assert_eq!(ip.solve(&qp, Some(&w)).unwrap().status, QpStatus::Solved);
        assert_eq!(ip.reduced_builds(), 0);
        assert_eq!(ip.reduction_counts().0, 0);
        let c = ClarabelBackend::new(tight()).solve(&qp, None).unwrap();
        let obj = |x: &[f64]| {
            let mut px = vec![0.0; n];
            qp.p.sym_upper_mul_add(1.0, x, &mut px);
            0.5 * x.iter().zip(&px).map(|(a, b)| a * b).sum::<f64>()
                + x.iter().zip(&qp.q).map(|(a, b)| a * b).sum::<f64>()
        };
        assert!((obj(&s.x) - obj(&c.x)).abs() <= 1e-8 * obj(&c.x).abs().max(1.0));
    }

    /// Constraint reduction: with many rows far from binding that couple distant variables
    /// (as the lazy oracle's rows for a long step do), a warm-started solve factorizes
    /// reduced matrices and reaches the solution of the backend that factorizes the full
    /// matrix at every iteration; without reduction no reduced matrix is factorized.
    #[test]
    fn constraint_reduction_reaches_the_full_solution() {
        let settings = tight();
        let base = chain_qp(80);
        let (n, m0) = (base.n(), base.m());
        // rows x_i − x_{i+17} ≥ −50 and y_i + y_{i+29} ≥ −60: never binding
        let mut at = Vec::new();
        for j in 0..n {
            for p in base.a.colptr[j]..base.a.colptr[j + 1] {
                at.push((base.a.rowval[p], j, base.a.nzval[p]));
            }
        }
        let (mut l, mut u) = (base.l.clone(), base.u.clone());
        let mut row = m0;
        for i in 0..80 {
            if i + 17 < 80 {
                at.push((row, 2 * i, 1.0));
                at.push((row, 2 * (i + 17), -1.0));
                l.push(-50.0);
                u.push(f64::INFINITY);
                row += 1;
            }
            if i + 29 < 80 {
                at.push((row, 2 * i + 1, 1.0));
                at.push((row, 2 * (i + 29) + 1, 1.0));
                l.push(-60.0);
                u.push(f64::INFINITY);
                row += 1;
            }
        }
        let qp = Qp {
            p: base.p.clone(),
            q: base.q.clone(),
            a: CscMatrix::from_triplets(row, n, &at).unwrap(),
            l,
            u,
        };
        let mut full = IpBackend::without_reduction(settings.clone());
        let cold = full.solve(&qp, None).unwrap();
        assert_eq!(cold.status, QpStatus::Solved);
        // a warm start from a nearby QP's solution (the linear term moved)
        let mut moved = qp.clone();
        moved.q.iter_mut().for_each(|v| *v *= 1.05);
        let warm = WarmStart {
            x: Vec::new(),
            y: cold.y.clone(),
        };
        let reference = full.solve(&moved, Some(&warm)).unwrap();
        let mut reduced = IpBackend::new(settings);
        let sol = reduced.solve(&moved, Some(&warm)).unwrap();
        assert_eq!(reference.status, QpStatus::Solved);
        assert_eq!(sol.status, QpStatus::Solved);
        let (jr, js) = (moved.objective(&reference.x), moved.objective(&sol.x));
        assert!(
            (jr - js).abs() <= 1e-8 * jr.abs().max(1.0),
            "{js} against {jr}"
        );
        assert!(moved.primal_residual(&sol.x) < 1e-9);
        let (iters, fallbacks, retries) = reduced.reduction_counts();
        assert!(iters > 0, "no reduced matrix was factorized");
        assert!(fallbacks <= iters);
        assert_eq!(retries, 0);
        // the wanted rows shrink as the iterations go: a reduced matrix serves again for a
        // subset of its rows (6 builds for the 8 iterations without that, 2 with it)
        assert!(
            reduced.reduced_builds() < iters,
            "{} reduced matrices built for {iters} iterations",
            reduced.reduced_builds()
        );
        assert_eq!(full.reduction_counts(), (0, 0, 0));
    }

    /// The symbolic factorization is reused when the next QP has the same pattern (other
    /// values), with the same answer as a fresh backend, bit for bit; a QP of another pattern
    /// gets its own.
    #[test]
    fn symbolic_factorization_reused_for_the_same_pattern() {
        let settings = tight();
        let a = chain_qp(40);
        let mut b = chain_qp(40);
        b.q.iter_mut().for_each(|v| *v *= 1.5);
        b.l.iter_mut().for_each(|v| *v -= 0.01);
        let mut ip = IpBackend::new(settings.clone());
        let sa = ip.solve(&a, None).unwrap();
        assert_eq!(ip.symbolic_reuses(), 0);
        let sb = ip.solve(&b, None).unwrap();
        assert_eq!(ip.symbolic_reuses(), 1);
        let fresh = IpBackend::new(settings.clone()).solve(&b, None).unwrap();
        assert_eq!(sb.status, QpStatus::Solved);
        assert_eq!(sb.x, fresh.x);
        assert_eq!(sb.iterations, fresh.iterations);
        assert_ne!(sa.x, sb.x);
        ip.solve(&chain_qp(41), None).unwrap();
        assert_eq!(ip.symbolic_reuses(), 1, "another pattern reused the cache");
        ip.solve(&chain_qp(41), None).unwrap();
        assert_eq!(ip.symbolic_reuses(), 2);
    }
}
