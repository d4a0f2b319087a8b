//! The paper's sub-problem method: Uzawa's algorithm, i.e. projected gradient ascent on the
//! dual, accelerated with Nesterov/FISTA momentum and adaptive restart.
//!
//! # Internal form
//!
//! `P` must be positive definite (the caller adds a proximal term); it is factorized **once per
//! solve** with a sparse up-looking `LDLᵀ` ([`crate::linalg::SparseLdl`], the QDLDL algorithm: elimination
//! tree, column counts, numeric factorization; natural ordering, which suits the banded-ish
//! `P` of contactlab). A failed factorization (`P` not positive definite) returns status
//! `NumericalError`.
//!
//! The symbolic phase ([`crate::linalg::LdlSymbolic`]: elimination tree and column counts, which depend on the
//! pattern of `P` only) is kept by the backend together with the pattern it was computed for,
//! and reused by the next solve whose `P` has exactly that pattern (same `n`, column pointers
//! and row indices; explicit zeros count as entries): only the numeric phase then runs, and its
//! result is bit-identical to a fresh factorization. Any other pattern recomputes the symbolic
//! phase ([`UzawaBackend::symbolic_phases`] counts them). There is no setting to turn this off:
//! it changes no result, only time.
//!
//! Every QP row is turned into one-sided "contact" rows `c_kᵀ x ≥ d_k`: a finite lower bound
//! gives `c_k = a_i, d_k = l_i`; a finite upper bound gives `c_k = −a_i, d_k = −u_i` (so a
//! two-sided row with `l_i < u_i` becomes two rows); an equality row (`l_i = u_i`) gives one row
//! `c_k = a_i, d_k = l_i` whose multiplier is free; rows infinite on both sides are ignored
//! (`y_i = 0`). With multipliers `μ` (`μ_k ≥ 0` on inequality rows) the Lagrangian is
//! `½xᵀPx + qᵀx − μᵀ(Cx − d)`, its minimizer is `x(μ) = P⁻¹(Cᵀμ − q)` and the dual function
//! `D(μ)` is concave with gradient `d − C x(μ)` and Lipschitz constant `λ_max(C P⁻¹ Cᵀ)`.
//! The crate dual is `y_i = −Σ_{k from row i} σ_k μ_k` (`σ_k = ±1` the sign of `c_k`), so that
//! `P x + q + Aᵀ y = 0`.
//!
//! # Equality rows
//!
//! Equality rows are not dual variables of the ascent: `x(μ)` minimizes the Lagrangian of the
//! inequality rows subject to the equality rows `E x = b` exactly, `x = y + W ν` with
//! `y = P⁻¹(C_Iᵀμ_I − q)`, `W = P⁻¹Eᵀ` and `ν = S⁻¹(b − E y)`, `S = E P⁻¹ Eᵀ` (dense, one row
//! and column per equality row: a few, one per gas of the shifted Newton model, whose
//! auxiliary variables they tie to the volume). `ν` is written into the equality entries of
//! `μ`, so the dual value, the duals returned and the stopping test read as before; the ascent,
//! the restart test and the power iteration (on `C_I (P⁻¹ − W S⁻¹ Wᵀ) C_Iᵀ`) run over the
//! inequality rows. As dual variables those rows' multipliers converged slowly: the shifted
//! model scales the gas coefficients down to `1e-6·c`, and on the balloons at n = 12 a QP of
//! the first outer step needed more than 100 000 dual steps (`subproblem_failed`); now that run
//! converges with 9 361 dual steps in all (docs/known-gaps.md). When `S` is not numerically
//! positive definite (dependent equality rows), or there are more than
//! `MAX_ELIMINATED_EQUALITIES` of them, they stay dual variables.
//!
//! # Step rule
//!
//! Uzawa with the optimal constant step plus momentum: `μ⁺ = Π(z − (1/L)(C x(z) − d))` where
//! `Π` clips inequality multipliers at 0, `L = 1.05·λ̂` with `λ̂` from 30 power iterations on
//! `C P⁻¹ Cᵀ`, and `z = μ⁺ + ((t−1)/t⁺)(μ⁺ − μ)` with `t⁺ = (1 + √(1 + 4t²))/2` (FISTA). The
//! momentum is reset (`t = 1`, `z = μ⁺`) when the dual value decreases or when the gradient
//! mapping `μ⁺ − z` makes an obtuse angle with the step `μ⁺ − μ` (O'Donoghue–Candès adaptive
//! restart). As a safeguard, `L` is doubled whenever a momentum-free step decreases `D` (which
//! cannot happen with `L ≥ λ_max`). Since `x(·)` is affine, `x(z)` is the same combination of
//! `x(μ⁺)` and `x(μ)`, so an iteration costs one pair of triangular solves.
//!
//! # Stopping test
//!
//! Stationarity `P x + q − Cᵀμ = 0` holds by construction. With `s = C x(μ) − d`,
//! `τ = eps_abs + eps_rel·max(1, ‖d‖∞)`, the solve stops with `Solved` when the primal violation
//! `max(max_eq |s_k|, max_ineq max(−s_k, 0)) ≤ τ`, the complementarity
//! `max_ineq |μ_k s_k| ≤ τ·max(1, ‖μ‖∞)` and the duality gap `|f(x) − D(μ)| = |μᵀs| ≤
//! τ·max(1, |f(x)|, ‖μ‖∞)` all hold (the gap test keeps the objective accurate when
//! multipliers are large).
//!
//! # Other statuses
//!
//! `PrimalInfeasible` when `‖μ‖∞ > 1e12·max(1, ‖q‖∞)` or when the last step `δ = μ⁺ − μ`,
//! clipped to `δ_ineq ≥ 0` and normalized, is an approximate Farkas certificate
//! (`dᵀδ̂ ≥ 1e-6·max(1, ‖d‖∞)` and `‖Cᵀδ̂‖∞·max(1, ‖x‖₁) ≤ 0.1·dᵀδ̂`) for 10 consecutive
//! iterations; `MaxIterations` at `max_iter` dual steps; `TimeLimit` past `time_limit_s`.
//! `iterations` counts dual steps; `solve_time_s` is wall time. A [`WarmStart`] `y` of the right
//! length is converted to the initial `μ`; its `x` is unused (`x` is a function of `μ`). Lengths
//! are checked as in the other backends (empty = not given, else `n` / `m`).

use crate::backend::{QpBackend, QpError, QpSettings, QpSolution, QpStatus, WarmStart};
use crate::linalg::{LdlSymbolic, SparseLdl};
use crate::qp::{CscMatrix, Qp};
use std::time::Instant;

/// The accelerated Uzawa backend. See the module documentation.
#[derive(Clone, Debug)]
pub struct UzawaBackend {
    settings: QpSettings,
    /// Symbolic phase of the last `P` factorized (it carries its pattern).
    symbolic: Option<LdlSymbolic>,
    /// Number of symbolic phases computed so far.
    symbolic_phases: usize,
}

impl UzawaBackend {
    /// A backend using `settings` (validated at each solve).
    pub fn new(settings: QpSettings) -> Self {
        UzawaBackend {
            settings,
            symbolic: None,
            symbolic_phases: 0,
        }
    }

    /// Number of symbolic phases (elimination tree and column counts of `P`) this backend has
    /// computed: one per solve whose `P` pattern differs from the previous one's, so a sequence
    /// of QPs sharing one pattern counts 1.
    pub fn symbolic_phases(&self) -> usize {
        self.symbolic_phases
    }
}

/// The one-sided rows `C x ≥ d` (equality rows `C x = d`) built from a QP.
struct Rows {
    /// Rows of `A` as columns (`Aᵀ`, CSC).
    at: CscMatrix,
    /// Original row of each internal row.
    orig: Vec<usize>,
    /// Sign `σ_k` with `c_k = σ_k a_i`.
    sign: Vec<f64>,
    /// Right-hand side `d_k`.
    d: Vec<f64>,
    /// Whether the multiplier is free (equality row).
    eq: Vec<bool>,
}

impl Rows {
    fn new(qp: &Qp) -> Rows {
        let mut r = Rows {
            at: qp.a.transpose(),
            orig: Vec::new(),
            sign: Vec::new(),
            d: Vec::new(),
            eq: Vec::new(),
        };
        for i in 0..qp.m() {
            let (l, u) = (qp.l[i], qp.u[i]);
            if l == u {
                r.push(i, 1.0, l, true);
                continue;
            }
            if l.is_finite() {
                r.push(i, 1.0, l, false);
            }
            if u.is_finite() {
                r.push(i, -1.0, -u, false);
            }
        }
        r
    }

    fn push(&mut self, i: usize, s: f64, d: f64, eq: bool) {
        self.orig.push(i);
        self.sign.push(s);
        self.d.push(d);
        self.eq.push(eq);
    }

    fn len(&self) -> usize {
        self.d.len()
    }

    /// `out = C x`.
    fn mul(&self, x: &[f64], out: &mut [f64]) {
        for (k, o) in out.iter_mut().enumerate() {
            let i = self.orig[k];
            let mut s = 0.0;
            for p in self.at.colptr[i]..self.at.colptr[i + 1] {
                s += self.at.nzval[p] * x[self.at.rowval[p]];
            }
            *o = self.sign[k] * s;
        }
    }

    /// `out += Cᵀ μ`.
    fn tr_mul_add(&self, mu: &[f64], out: &mut [f64]) {
        for (k, &m) in mu.iter().enumerate() {
            if m == 0.0 {
                continue;
            }
            let i = self.orig[k];
            let v = self.sign[k] * m;
            for p in self.at.colptr[i]..self.at.colptr[i + 1] {
                out[self.at.rowval[p]] += self.at.nzval[p] * v;
            }
        }
    }

    /// Projection onto the dual feasible set.
    fn project(&self, mu: &mut [f64]) {
        for (m, &e) in mu.iter_mut().zip(&self.eq) {
            if !e && *m < 0.0 {
                *m = 0.0;
            }
        }
    }
}

/// At most this many equality rows are kept exactly (`W` is dense, `n` by their count, and `S`
/// is factorized densely); a QP with more keeps them as dual variables.
const MAX_ELIMINATED_EQUALITIES: usize = 64;

/// The equality rows kept exactly in the inner minimization (module documentation, "Equality
/// rows"): `W = P⁻¹Eᵀ` (one column per equality row) and the Cholesky factor of the Schur
/// complement `S = E P⁻¹ Eᵀ`.
struct Equalities {
    /// Internal indices of the equality rows.
    rows: Vec<usize>,
    /// `W` by columns.
    w: Vec<Vec<f64>>,
    /// Lower Cholesky factor of `S`, row-major.
    chol: Vec<f64>,
}

impl Equalities {
    /// `None` when there are no equality rows or `S` is not numerically positive definite
    /// (dependent rows): the equality multipliers are then dual variables like the others.
    fn new(rows: &Rows, ldl: &SparseLdl, n: usize) -> Option<Equalities> {
        let idx: Vec<usize> = (0..rows.len()).filter(|&k| rows.eq[k]).collect();
        if idx.is_empty() || idx.len() > MAX_ELIMINATED_EQUALITIES {
            return None;
        }
        let me = idx.len();
        let mut e = vec![0.0; rows.len()];
        let mut w = Vec::with_capacity(me);
        for &k in &idx {
            e[k] = 1.0;
            let mut col = vec![0.0; n];
            rows.tr_mul_add(&e, &mut col);
            ldl.solve_in_place(&mut col);
            e[k] = 0.0;
            w.push(col);
        }
        let mut ew = vec![0.0; rows.len()];
        let mut chol = vec![0.0; me * me];
        for (b, col) in w.iter().enumerate() {
            rows.mul(col, &mut ew);
            for (a, &k) in idx.iter().enumerate() {
                chol[a * me + b] = ew[k];
            }
        }
        let scale = (0..me).map(|a| chol[a * me + a].abs()).fold(0.0, f64::max);
        for j in 0..me {
            let mut d = chol[j * me + j];
            for k in 0..j {
                d -= chol[j * me + k] * chol[j * me + k];
            }
            if d.is_nan() || d <= 1e-12 * scale {
                return None;
            }
            let d = d.sqrt();
            chol[j * me + j] = d;
            for i in j + 1..me {
                let mut v = chol[i * me + j];
                for k in 0..j {
                    v -= chol[i * me + k] * chol[j * me + k];
                }
                chol[i * me + j] = v / d;
            }
        }
        Some(Equalities { rows: idx, w, chol })
    }

    /// Given `x = P⁻¹(Cᵀμ − q)` computed with the equality multipliers at 0, adds `W ν` with
    /// `ν = S⁻¹(b − E x)` so that `E x = b`, and writes `ν` into `mu`'s equality entries.
    /// With `rhs = false` it projects a direction instead (`b = 0`).
    fn correct(&self, rows: &Rows, x: &mut [f64], mu: &mut [f64], rhs: bool) {
        let me = self.rows.len();
        let mut nu: Vec<f64> = self
            .rows
            .iter()
            .map(|&k| {
                let i = rows.orig[k];
                let mut ex = 0.0;
                for p in rows.at.colptr[i]..rows.at.colptr[i + 1] {
                    ex += rows.at.nzval[p] * x[rows.at.rowval[p]];
                }
                (if rhs { rows.d[k] } else { 0.0 }) - rows.sign[k] * ex
            })
            .collect();
        for i in 0..me {
            for k in 0..i {
                nu[i] -= self.chol[i * me + k] * nu[k];
            }
            nu[i] /= self.chol[i * me + i];
        }
        for i in (0..me).rev() {
            for k in i + 1..me {
                nu[i] -= self.chol[k * me + i] * nu[k];
            }
            nu[i] /= self.chol[i * me + i];
        }
        for (a, &k) in self.rows.iter().enumerate() {
            for (xj, wj) in x.iter_mut().zip(&self.w[a]) {
                *xj += nu[a] * wj;
            }
            mu[k] = nu[a];
        }
    }
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl QpBackend for UzawaBackend {
    fn name(&self) -> &'static str {
        "uzawa"
    }

    fn tolerance(&self) -> Option<f64> {
        Some(self.settings.eps_abs)
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.settings.eps_abs = tol;
        self.settings.eps_rel = tol;
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let start = Instant::now();
        let st = self.settings.clone();
        st.validate()?;
        qp.validate()?;
        let (n, m) = (qp.n(), qp.m());
        crate::osqp_backend::check_warm(warm, n, m)?;
        let finish = |x: Vec<f64>, y: Vec<f64>, status: QpStatus, iterations: usize| QpSolution {
            x,
            y,
            status,
            iterations,
            solve_time_s: start.elapsed().as_secs_f64(),
        };
        // Symbolic phase only when the pattern of P changed since the last solve.
        if !self.symbolic.as_ref().is_some_and(|sym| sym.matches(&qp.p)) {
            self.symbolic = LdlSymbolic::new(&qp.p);
            self.symbolic_phases += 1;
        }
        let Some(ldl) = self
            .symbolic
            .as_ref()
            .and_then(|sym| SparseLdl::numeric(&qp.p, sym))
        else {
            return Ok(finish(
                vec![0.0; n],
                vec![0.0; m],
                QpStatus::NumericalError,
                0,
            ));
        };
        let rows = Rows::new(qp);
        let mi = rows.len();
        let eqs = Equalities::new(&rows, &ldl, n);
        // x(μ) = P⁻¹(Cᵀμ − q); with the equality rows eliminated, the minimizer subject to
        // them, whose multipliers are written into μ's equality entries.
        let x_of = |mu: &mut [f64], x: &mut [f64]| {
            for (xi, qi) in x.iter_mut().zip(&qp.q) {
                *xi = -qi;
            }
            if let Some(e) = &eqs {
                for &k in &e.rows {
                    mu[k] = 0.0;
                }
            }
            rows.tr_mul_add(mu, x);
            ldl.solve_in_place(x);
            if let Some(e) = &eqs {
                e.correct(&rows, x, mu, true);
            }
        };
        let to_y = |mu: &[f64]| {
            let mut y = vec![0.0; m];
            for k in 0..mi {
                y[rows.orig[k]] -= rows.sign[k] * mu[k];
            }
            y
        };

        // Initial multipliers.
        let mut mu = vec![0.0; mi];
        if let Some(w) = warm.filter(|w| !w.y.is_empty()) {
            for k in 0..mi {
                let yi = w.y[rows.orig[k]];
                mu[k] = -rows.sign[k] * yi;
            }
            rows.project(&mut mu);
        }
        let mut x = vec![0.0; n];
        x_of(&mut mu, &mut x);
        if mi == 0 {
            let y = to_y(&mu);
            return Ok(finish(x, y, QpStatus::Solved, 0));
        }

        // Lipschitz constant of the dual gradient: 30 power iterations on C P⁻¹ Cᵀ.
        let mut v: Vec<f64> = (0..mi)
            .map(|k| 1.0 + 0.1 * ((k * 7919) % 13) as f64)
            .collect();
        let mut w = vec![0.0; n];
        let mut cv = vec![0.0; mi];
        let mut lam = 0.0;
        for _ in 0..30 {
            let nv = inf_norm(&v).max(f64::MIN_POSITIVE);
            v.iter_mut().for_each(|e| *e /= nv);
            w.iter_mut().for_each(|e| *e = 0.0);
            if let Some(e) = &eqs {
                for &k in &e.rows {
                    v[k] = 0.0;
                }
            }
            rows.tr_mul_add(&v, &mut w);
            ldl.solve_in_place(&mut w);
            if let Some(e) = &eqs {
                let mut scratch = vec![0.0; mi];
                e.correct(&rows, &mut w, &mut scratch, false);
            }
            rows.mul(&w, &mut cv);
            if let Some(e) = &eqs {
                for &k in &e.rows {
                    cv[k] = 0.0;
                }
            }
            let n2v = dot(&v, &v).sqrt();
            lam = dot(&cv, &cv).sqrt() / n2v.max(f64::MIN_POSITIVE);
            if !(lam.is_finite() && lam > 0.0) {
                break;
            }
            std::mem::swap(&mut v, &mut cv);
        }
        let mut big_l = if lam.is_finite() && lam > 0.0 {
            1.05 * lam
        } else {
            // Power iteration broke down: fall back to the safe bound trace(C P⁻¹ Cᵀ).
            let mut tr = 0.0;
            let mut e = vec![0.0; mi];
            for k in 0..mi {
                e[k] = 1.0;
                w.iter_mut().for_each(|v| *v = 0.0);
                rows.tr_mul_add(&e, &mut w);
                let cw = w.clone();
                ldl.solve_in_place(&mut w);
                tr += dot(&cw, &w);
                e[k] = 0.0;
            }
            if tr.is_finite() && tr > 0.0 {
                tr
            } else {
                1.0
            }
        };
        let mut step = 1.0 / big_l;

        let d_norm = inf_norm(
            &rows
                .d
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect::<Vec<_>>(),
        );
        let tol = st.eps_abs + st.eps_rel * d_norm.max(1.0);
        let q_norm = inf_norm(&qp.q).max(1.0);
        let cert_tol = 1e-6 * d_norm.max(1.0);

        let mut z = mu.clone();
        let mut xz = x.clone();
        let mut t = 1.0f64;
        let mut s = vec![0.0; mi];
        let mut mu_new = vec![0.0; mi];
        let mut x_new = vec![0.0; n];
        let mut delta = vec![0.0; mi];
        let mut ctd = vec![0.0; n];
        // Dual value D(μ) = ½ μᵀd − ½ μᵀ s + ½ qᵀ x with s = C x − d.
        rows.mul(&x, &mut s);
        s.iter_mut().zip(&rows.d).for_each(|(a, b)| *a -= b);
        let mut dual_val = 0.5 * (dot(&mu, &rows.d) - dot(&mu, &s) + dot(&qp.q, &x));
        let mut cert_count = 0;
        // Whether z = μ (no momentum) at the current step.
        let mut plain = true;
        let mut iterations = 0;
        let status = loop {
            if iterations >= st.max_iter {
                break QpStatus::MaxIterations;
            }
            if iterations % 32 == 0 && start.elapsed().as_secs_f64() > st.time_limit_s {
                break QpStatus::TimeLimit;
            }
            iterations += 1;
            // Gradient step from z.
            rows.mul(&xz, &mut s);
            for k in 0..mi {
                mu_new[k] = z[k] - step * (s[k] - rows.d[k]);
            }
            rows.project(&mut mu_new);
            x_of(&mut mu_new, &mut x_new);
            rows.mul(&x_new, &mut s);
            s.iter_mut().zip(&rows.d).for_each(|(a, b)| *a -= b);
            if x_new.iter().any(|v| !v.is_finite()) {
                break QpStatus::NumericalError;
            }

            // Stopping test at (μ⁺, x(μ⁺)).
            let mut viol = 0.0f64;
            let mut comp = 0.0f64;
            for k in 0..mi {
                if rows.eq[k] {
                    viol = viol.max(s[k].abs());
                } else {
                    viol = viol.max(-s[k]);
                    comp = comp.max((mu_new[k] * s[k]).abs());
                }
            }
            let mu_norm = inf_norm(&mu_new);
            let new_val = 0.5 * (dot(&mu_new, &rows.d) - dot(&mu_new, &s) + dot(&qp.q, &x_new));
            // Duality gap f(x(μ)) − D(μ) = μᵀs (stationarity is exact).
            let gap = dot(&mu_new, &s).abs();
            let f_val = new_val + dot(&mu_new, &s);
            if viol <= tol
                && comp <= tol * mu_norm.max(1.0)
                && gap <= tol * f_val.abs().max(mu_norm).max(1.0)
            {
                std::mem::swap(&mut mu, &mut mu_new);
                std::mem::swap(&mut x, &mut x_new);
                break QpStatus::Solved;
            }

            // Primal infeasibility: exploding multipliers or a Farkas-like step direction.
            if mu_norm > 1e12 * q_norm {
                std::mem::swap(&mut mu, &mut mu_new);
                std::mem::swap(&mut x, &mut x_new);
                break QpStatus::PrimalInfeasible;
            }
            for k in 0..mi {
                let dk = mu_new[k] - mu[k];
                delta[k] = if rows.eq[k] { dk } else { dk.max(0.0) };
            }
            let dn = inf_norm(&delta);
            let mut farkas = false;
            if dn > 0.0 {
                delta.iter_mut().for_each(|e| *e /= dn);
                let dd = dot(&delta, &rows.d);
                if dd >= cert_tol {
                    ctd.iter_mut().for_each(|e| *e = 0.0);
                    rows.tr_mul_add(&delta, &mut ctd);
                    let x1: f64 = x_new.iter().map(|v| v.abs()).sum();
                    farkas = inf_norm(&ctd) * x1.max(1.0) <= 0.1 * dd;
                }
            }
            cert_count = if farkas { cert_count + 1 } else { 0 };
            if cert_count >= 10 {
                std::mem::swap(&mut mu, &mut mu_new);
                std::mem::swap(&mut x, &mut x_new);
                break QpStatus::PrimalInfeasible;
            }

            // Momentum with adaptive restart.
            // Decreases at the rounding level of D are ignored.
            let decreased = dual_val - new_val > 1e-12 * dual_val.abs().max(1.0);
            if decreased && plain {
                // A plain projected gradient step with step 1/L ≥ 1/λ_max never decreases D:
                // the power-iteration estimate was too small.
                big_l *= 2.0;
                step = 1.0 / big_l;
            }
            let mut restart = decreased;
            if !restart {
                let mut g = 0.0;
                for k in 0..mi {
                    if eqs.is_none() || !rows.eq[k] {
                        g += (mu_new[k] - z[k]) * (mu_new[k] - mu[k]);
                    }
                }
                restart = g < 0.0;
            }
            plain = restart;
            let beta = if restart {
                t = 1.0;
                0.0
            } else {
                let t_new = 0.5 * (1.0 + (1.0 + 4.0 * t * t).sqrt());
                let b = (t - 1.0) / t_new;
                t = t_new;
                b
            };
            for k in 0..mi {
                z[k] = mu_new[k] + beta * (mu_new[k] - mu[k]);
            }
            // x(z) by the same affine combination (z is not projected, as in FISTA).
            for j in 0..n {
                xz[j] = x_new[j] + beta * (x_new[j] - x[j]);
            }
            std::mem::swap(&mut mu, &mut mu_new);
            std::mem::swap(&mut x, &mut x_new);
            dual_val = new_val;
        };
        let y = to_y(&mu);
        Ok(finish(x, y, status, iterations))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::qp::tests::{assert_solves_small_qp, small_qp};

    #[test]
    fn solves_small_qp_with_crate_dual_signs() {
        let qp = small_qp();
        let mut b = UzawaBackend::new(QpSettings::default());
        let s = assert_solves_small_qp(&mut b, 1e-9);
        // Warm start from the solution converges at once.
        let w = WarmStart {
            x: vec![],
            y: s.y.clone(),
        };
        let s2 = b.solve(&qp, Some(&w)).unwrap();
        assert_eq!(s2.status, QpStatus::Solved);
        assert!(s2.iterations <= 2, "{}", s2.iterations);
        let bad = WarmStart {
            x: vec![],
            y: vec![0.0],
        };
        assert!(matches!(
            b.solve(&qp, Some(&bad)),
            Err(QpError::WarmStartLength { what: "y", .. })
        ));
    }

    #[test]
    fn infeasible_and_not_positive_definite() {
        let mut qp = small_qp();
        qp.l[2] = 0.3;
        qp.u[2] = 0.3;
        qp.l[1] = 0.9;
        let s = UzawaBackend::new(QpSettings::default())
            .solve(&qp, None)
            .unwrap();
        assert_eq!(s.status, QpStatus::PrimalInfeasible);
        let mut qp = small_qp();
        qp.p = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0)]).unwrap();
        let s = UzawaBackend::new(QpSettings::default())
            .solve(&qp, None)
            .unwrap();
        assert_eq!(s.status, QpStatus::NumericalError);
    }

    #[test]
    fn iteration_limit_is_a_status() {
        let qp = small_qp();
        let st = QpSettings {
            max_iter: 1,
            ..QpSettings::default()
        };
        let s = UzawaBackend::new(st).solve(&qp, None).unwrap();
        assert_eq!(s.status, QpStatus::MaxIterations);
        assert_eq!(s.iterations, 1);
        assert_eq!((s.x.len(), s.y.len()), (2, 3));
    }

    #[test]
    fn an_ill_scaled_equality_row_is_kept_exactly() {
        // min ½|x|² + (1e-4 − 1)x₀ s.t. 1e-4·x₀ = 1e-4 (an equality row scaled as the gas rows
        // of the shifted Newton model) and x₁ ≥ 1: x = (1, 1), y = (−1, −1). As a dual variable
        // the equality multiplier has curvature 1e-8 against 1 for the other row.
        let p = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(2, 2, &[(0, 0, 1e-4), (1, 1, 1.0)]).unwrap();
        let qp = Qp {
            p,
            q: vec![1e-4 - 1.0, 0.0],
            a,
            l: vec![1e-4, 1.0],
            u: vec![1e-4, f64::INFINITY],
        };
        let sol = UzawaBackend::new(QpSettings::default())
            .solve(&qp, None)
            .unwrap();
        assert_eq!(sol.status, QpStatus::Solved);
        assert!(sol.iterations <= 10, "{} dual steps", sol.iterations);
        assert!(
            (sol.x[0] - 1.0).abs() < 1e-9 && (sol.x[1] - 1.0).abs() < 1e-8,
            "{:?}",
            sol.x
        );
        assert!(
            (sol.y[0] + 1.0).abs() < 1e-6 && (sol.y[1] + 1.0).abs() < 1e-8,
            "{:?}",
            sol.y
        );
    }
}
