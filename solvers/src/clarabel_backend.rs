//! Backend on the Clarabel interior-point solver (clarabel 0.11).
//!
//! # Conversion to Clarabel's conic form
//!
//! Clarabel solves `min ½xᵀPx + qᵀx  s.t.  A_c x + s = b, s ∈ K`. Each row `i` of the QP becomes
//!
//! * an equality row (`l_i = u_i`): one `ZeroCone` row `a_i x + s = l_i`;
//! * a finite upper bound: one `NonnegativeCone` row `a_i x + s = u_i`;
//! * a finite lower bound: one `NonnegativeCone` row `−a_i x + s = −l_i`;
//! * infinite bounds are dropped (a free row gets `y_i = 0`).
//!
//! Clarabel's duals `z` satisfy `P x + q + A_cᵀ z = 0` with `z ≥ 0` on the nonnegative cone, so
//! the crate dual is `y_i = z_upper − z_lower` (equality rows: `y_i = z_eq`), which gives
//! `P x + q + Aᵀ y = 0`, `y_i ≤ 0` at an active lower bound and `y_i ≥ 0` at an active upper
//! bound.
//!
//! # Settings
//!
//! `tol_gap_abs = tol_feas = eps_abs`, `tol_gap_rel = eps_rel` (floored at `1e-16` since Clarabel
//! needs a positive value), `max_iter`, `time_limit` (seconds, `∞` kept), `verbose = false`.
//!
//! # Status mapping
//!
//! `Solved → Solved`; `AlmostSolved → Solved` only when the returned point meets
//! [`meets_tolerances`], else `NumericalError`; `MaxIterations → MaxIterations`;
//! `MaxTime → TimeLimit`; `(Almost)PrimalInfeasible → PrimalInfeasible`;
//! `(Almost)DualInfeasible → DualInfeasible`; everything else `NumericalError`.
//!
//! **Warm start is ignored**: Clarabel (an interior-point method) does not support it. Its
//! lengths are still checked like in the other backends, so bad input is an error everywhere.

use crate::backend::{QpBackend, QpError, QpSettings, QpSolution, QpStatus, WarmStart};
use crate::qp::Qp;
use clarabel::algebra::CscMatrix as ClCsc;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
    ZeroConeT,
};
use std::time::Instant;

/// The Clarabel interior-point backend. See the module documentation for the mapping.
#[derive(Clone, Debug)]
pub struct ClarabelBackend {
    settings: QpSettings,
}

impl ClarabelBackend {
    /// A backend using `settings` (validated at each solve).
    pub fn new(settings: QpSettings) -> Self {
        ClarabelBackend { settings }
    }
}

/// `‖v‖∞` (0 for an empty vector).
fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// True when `x` and `y` meet the common tolerances: the primal residual (see
/// [`Qp::primal_residual`]) is at most `eps_abs + eps_rel·max(1, ‖Ax‖∞)` and the dual residual
/// ([`Qp::dual_residual`]) at most `eps_abs + eps_rel·max(1, ‖Px‖∞, ‖q‖∞, ‖Aᵀy‖∞)`. Non-finite
/// values fail.
pub fn meets_tolerances(qp: &Qp, x: &[f64], y: &[f64], settings: &QpSettings) -> bool {
    if x.len() != qp.n() || y.len() != qp.m() || x.iter().chain(y).any(|v| !v.is_finite()) {
        return false;
    }
    let mut ax = vec![0.0; qp.m()];
    qp.a.mul_add(1.0, x, &mut ax);
    let mut px = vec![0.0; qp.n()];
    qp.p.sym_upper_mul_add(1.0, x, &mut px);
    let mut aty = vec![0.0; qp.n()];
    qp.a.tr_mul_add(1.0, y, &mut aty);
    let pri_tol = settings.eps_abs + settings.eps_rel * inf_norm(&ax).max(1.0);
    let dua_tol = settings.eps_abs
        + settings.eps_rel
            * inf_norm(&px)
                .max(inf_norm(&qp.q))
                .max(inf_norm(&aty))
                .max(1.0);
    qp.primal_residual(x) <= pri_tol && qp.dual_residual(x, y) <= dua_tol
}

/// Where the conic rows of one QP row live.
#[derive(Clone, Copy, Debug)]
enum RowMap {
    /// Dropped (both bounds infinite).
    Free,
    /// Equality row at conic index.
    Eq(usize),
    /// Optional upper and lower conic indices.
    Ineq(Option<usize>, Option<usize>),
}

impl QpBackend for ClarabelBackend {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let start = Instant::now();
        self.settings.validate()?;
        qp.validate()?;
        let (n, m) = (qp.n(), qp.m());
        // Checked for a uniform interface, then ignored.
        crate::osqp_backend::check_warm(warm, n, m)?;

        // Build the conic rows: equalities first (ZeroCone), then inequalities (NonnegativeCone).
        let at = qp.a.transpose(); // n × m: column i holds row i of A.
        let at = &at;
        let row =
            |i: usize| (at.colptr[i]..at.colptr[i + 1]).map(move |p| (at.rowval[p], at.nzval[p]));
        let mut map = vec![RowMap::Free; m];
        let (mut ti, mut tj, mut tv) = (Vec::new(), Vec::new(), Vec::new());
        let mut b = Vec::new();
        for i in 0..m {
            if qp.l[i] == qp.u[i] {
                let k = b.len();
                for (j, v) in row(i) {
                    ti.push(k);
                    tj.push(j);
                    tv.push(v);
                }
                b.push(qp.l[i]);
                map[i] = RowMap::Eq(k);
            }
        }
        let n_eq = b.len();
        for i in 0..m {
            if qp.l[i] == qp.u[i] {
                continue;
            }
            let mut up = None;
            let mut lo = None;
            if qp.u[i].is_finite() {
                let k = b.len();
                for (j, v) in row(i) {
                    ti.push(k);
                    tj.push(j);
                    tv.push(v);
                }
                b.push(qp.u[i]);
                up = Some(k);
            }
            if qp.l[i].is_finite() {
                let k = b.len();
                for (j, v) in row(i) {
                    ti.push(k);
                    tj.push(j);
                    tv.push(-v);
                }
                b.push(-qp.l[i]);
                lo = Some(k);
            }
            if up.is_some() || lo.is_some() {
                map[i] = RowMap::Ineq(up, lo);
            }
        }
        let mc = b.len();
        let a_c = ClCsc::new_from_triplets(mc, n, ti, tj, tv);
        let p_c = ClCsc::new(
            n,
            n,
            qp.p.colptr.clone(),
            qp.p.rowval.clone(),
            qp.p.nzval.clone(),
        );
        let mut cones: Vec<SupportedConeT<f64>> = Vec::new();
        if n_eq > 0 {
            cones.push(ZeroConeT(n_eq));
        }
        if mc > n_eq {
            cones.push(NonnegativeConeT(mc - n_eq));
        }

        let s = &self.settings;
        let settings = DefaultSettings::<f64> {
            max_iter: u32::try_from(s.max_iter).unwrap_or(u32::MAX),
            time_limit: s.time_limit_s,
            verbose: false,
            tol_gap_abs: s.eps_abs,
            tol_gap_rel: s.eps_rel.max(1e-16),
            tol_feas: s.eps_abs,
            ..DefaultSettings::default()
        };

        let failed = |iterations: usize| QpSolution {
            x: vec![0.0; n],
            y: vec![0.0; m],
            status: QpStatus::NumericalError,
            iterations,
            solve_time_s: start.elapsed().as_secs_f64(),
        };
        let mut solver = match DefaultSolver::new(&p_c, &qp.q, &a_c, &b, &cones, settings) {
            Ok(solver) => solver,
            Err(_) => return Ok(failed(0)),
        };
        solver.solve();
        let sol = &solver.solution;
        let iterations = sol.iterations as usize;
        if sol.x.len() != n || sol.z.len() != mc {
            return Ok(failed(iterations));
        }
        let x = sol.x.clone();
        let z = &sol.z;
        let y: Vec<f64> = map
            .iter()
            .map(|r| match *r {
                RowMap::Free => 0.0,
                RowMap::Eq(k) => z[k],
                RowMap::Ineq(up, lo) => up.map_or(0.0, |k| z[k]) - lo.map_or(0.0, |k| z[k]),
            })
            .collect();
        let status = match sol.status {
            SolverStatus::Solved => QpStatus::Solved,
            SolverStatus::AlmostSolved => {
                if meets_tolerances(qp, &x, &y, &self.settings) {
                    QpStatus::Solved
                } else {
                    QpStatus::NumericalError
                }
            }
            SolverStatus::MaxIterations => QpStatus::MaxIterations,
            SolverStatus::MaxTime => QpStatus::TimeLimit,
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                QpStatus::PrimalInfeasible
            }
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
                QpStatus::DualInfeasible
            }
            _ => QpStatus::NumericalError,
        };
        Ok(QpSolution {
            x,
            y,
            status,
            iterations,
            solve_time_s: start.elapsed().as_secs_f64(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::qp::tests::small_qp;

    #[test]
    fn solves_small_qp_with_crate_dual_signs() {
        let qp = small_qp();
        let mut b = ClarabelBackend::new(QpSettings::default());
        let s = b.solve(&qp, None).unwrap();
        assert_eq!(s.status, QpStatus::Solved);
        // Optimum: x0 = 0.8 would not be forced; unconstrained optimum (1,1) violates x0+x1 ≤ 1 →
        // x = (0.5, 0.5) violates x0 ≥ 0.8 → x = (0.8, 0.2).
        assert!(
            (s.x[0] - 0.8).abs() < 1e-7 && (s.x[1] - 0.2).abs() < 1e-7,
            "{:?}",
            s.x
        );
        assert!(qp.dual_residual(&s.x, &s.y) < 1e-7);
        assert!(s.y[0] > 0.0, "upper bound active → y ≥ 0: {:?}", s.y);
        assert!(s.y[1] < 0.0, "lower bound active → y ≤ 0: {:?}", s.y);
        assert_eq!(s.y[2], 0.0);
    }

    #[test]
    fn equality_and_infeasible() {
        let mut qp = small_qp();
        qp.l[2] = 0.1;
        qp.u[2] = 0.1;
        let mut b = ClarabelBackend::new(QpSettings::default());
        let s = b.solve(&qp, None).unwrap();
        assert_eq!(s.status, QpStatus::Solved);
        assert!(
            (s.x[0] - 0.9).abs() < 1e-7 && (s.x[1] - 0.1).abs() < 1e-7,
            "{:?}",
            s.x
        );
        assert!(qp.dual_residual(&s.x, &s.y) < 1e-7);
        // x0 ≥ 0.95 and x0 + x1 ≤ 1 with x1 = 0.1 → infeasible.
        qp.l[1] = 0.95;
        let s = b.solve(&qp, None).unwrap();
        assert_ne!(s.status, QpStatus::Solved);
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut qp = small_qp();
        qp.l[1] = 6.0;
        let e = ClarabelBackend::new(QpSettings::default())
            .solve(&qp, None)
            .unwrap_err();
        assert_eq!(
            e,
            QpError::InvalidBounds {
                row: 1,
                l: 6.0,
                u: 5.0
            }
        );
    }
}
