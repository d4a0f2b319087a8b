//! Backend on the OSQP ADMM solver (osqp 0.6 crate, OSQP 0.6 C library).
//!
//! OSQP solves exactly the crate's standard form and uses the same dual sign convention, so `x`
//! and `y` are returned as they are. Infinite bounds are replaced by `±OSQP_INFTY = ±1e30`.
//!
//! # Settings
//!
//! `eps_abs`, `eps_rel`, `max_iter` (saturated at `u32::MAX`), `time_limit` (only when finite),
//! `polish = true`, `verbose = false`, `adaptive_rho = true`. A [`WarmStart`] is used for both
//! `x` and `y` (`warm_start_x` / `warm_start_y`); an empty vector means "not given", any other
//! wrong length is [`QpError::WarmStartLength`] (the rule shared by all backends).
//!
//! # Status mapping
//!
//! `Solved → Solved`; `SolvedInaccurate → NumericalError` (it did not meet the requested
//! tolerances; the point is still returned); `MaxIterationsReached → MaxIterations`;
//! `TimeLimitReached → TimeLimit`; `PrimalInfeasible(Inaccurate) → PrimalInfeasible`;
//! `DualInfeasible(Inaccurate) → DualInfeasible`; anything else (non-convex, setup failure not
//! caused by the input) `NumericalError` with zero vectors. Setup failures caused by the input
//! are impossible after [`Qp::validate`], except a non-convex `P`, reported as `NumericalError`.

use crate::backend::{QpBackend, QpError, QpSettings, QpSolution, QpStatus, WarmStart};
use crate::qp::Qp;
use osqp::{CscMatrix as OsCsc, Problem, Settings, Status};
use std::borrow::Cow;
use std::time::{Duration, Instant};

/// OSQP's infinity (`OSQP_INFTY` in OSQP 0.6).
pub const OSQP_INFTY: f64 = 1e30;

/// The OSQP backend. See the module documentation for the mapping.
#[derive(Clone, Debug)]
pub struct OsqpBackend {
    settings: QpSettings,
}

impl OsqpBackend {
    /// A backend using `settings` (validated at each solve).
    pub fn new(settings: QpSettings) -> Self {
        OsqpBackend { settings }
    }
}

/// Checks a warm start against `n` and `m`, the rule shared by every backend: each of `x` and
/// `y` is either empty (not given) or of the right length with finite entries.
pub(crate) fn check_warm(warm: Option<&WarmStart>, n: usize, m: usize) -> Result<(), QpError> {
    if let Some(w) = warm {
        if !w.x.is_empty() && w.x.len() != n {
            return Err(QpError::WarmStartLength {
                what: "x",
                expected: n,
                found: w.x.len(),
            });
        }
        if !w.y.is_empty() && w.y.len() != m {
            return Err(QpError::WarmStartLength {
                what: "y",
                expected: m,
                found: w.y.len(),
            });
        }
        for (i, v) in w.x.iter().enumerate() {
            if !v.is_finite() {
                return Err(QpError::NotFinite {
                    what: "warm start x",
                    index: i,
                    value: *v,
                });
            }
        }
        for (i, v) in w.y.iter().enumerate() {
            if !v.is_finite() {
                return Err(QpError::NotFinite {
                    what: "warm start y",
                    index: i,
                    value: *v,
                });
            }
        }
    }
    Ok(())
}

fn to_osqp(m: &crate::qp::CscMatrix) -> OsCsc<'_> {
    OsCsc {
        nrows: m.nrows,
        ncols: m.ncols,
        indptr: Cow::Borrowed(&m.colptr),
        indices: Cow::Borrowed(&m.rowval),
        data: Cow::Borrowed(&m.nzval),
    }
}

impl QpBackend for OsqpBackend {
    fn name(&self) -> &'static str {
        "osqp"
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let start = Instant::now();
        self.settings.validate()?;
        qp.validate()?;
        let (n, m) = (qp.n(), qp.m());
        check_warm(warm, n, m)?;

        let l: Vec<f64> = qp.l.iter().map(|&v| v.max(-OSQP_INFTY)).collect();
        let u: Vec<f64> = qp.u.iter().map(|&v| v.min(OSQP_INFTY)).collect();
        let s = &self.settings;
        let mut settings = Settings::default()
            .eps_abs(s.eps_abs)
            .eps_rel(s.eps_rel)
            .max_iter(
                u32::try_from(s.max_iter)
                    .unwrap_or(u32::MAX)
                    .min(i32::MAX as u32),
            )
            .polish(true)
            .verbose(false)
            .adaptive_rho(true);
        if s.time_limit_s.is_finite() {
            settings = settings.time_limit(Some(Duration::from_secs_f64(s.time_limit_s.min(1e9))));
        }
        let zero = |status, iterations| QpSolution {
            x: vec![0.0; n],
            y: vec![0.0; m],
            status,
            iterations,
            solve_time_s: start.elapsed().as_secs_f64(),
        };
        let mut prob = match Problem::new(to_osqp(&qp.p), &qp.q, to_osqp(&qp.a), &l, &u, &settings)
        {
            Ok(p) => p,
            // The input was validated, so remaining failures (non-convex P, linear-system
            // set-up, allocation) are numerical.
            Err(_) => return Ok(zero(QpStatus::NumericalError, 0)),
        };
        if let Some(w) = warm {
            if !w.x.is_empty() {
                prob.warm_start_x(&w.x);
            }
            if !w.y.is_empty() {
                prob.warm_start_y(&w.y);
            }
        }
        let result = prob.solve();
        let iterations = result.iter() as usize;
        let status = match &result {
            Status::Solved(_) => QpStatus::Solved,
            Status::SolvedInaccurate(_) => QpStatus::NumericalError,
            Status::MaxIterationsReached(_) => QpStatus::MaxIterations,
            Status::TimeLimitReached(_) => QpStatus::TimeLimit,
            Status::PrimalInfeasible(_) | Status::PrimalInfeasibleInaccurate(_) => {
                QpStatus::PrimalInfeasible
            }
            Status::DualInfeasible(_) | Status::DualInfeasibleInaccurate(_) => {
                QpStatus::DualInfeasible
            }
            _ => QpStatus::NumericalError,
        };
        let sol = match &result {
            Status::Solved(s)
            | Status::SolvedInaccurate(s)
            | Status::MaxIterationsReached(s)
            | Status::TimeLimitReached(s) => Some(s.clone()),
            _ => None,
        };
        match sol {
            Some(sol) if sol.x().len() == n && sol.y().len() == m => Ok(QpSolution {
                x: sol.x().to_vec(),
                y: sol.y().to_vec(),
                status,
                iterations,
                solve_time_s: start.elapsed().as_secs_f64(),
            }),
            _ => Ok(zero(status, iterations)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::qp::tests::small_qp;

    #[test]
    fn solves_small_qp_with_crate_dual_signs() {
        let qp = small_qp();
        let s = OsqpBackend::new(QpSettings::default())
            .solve(&qp, None)
            .unwrap();
        assert_eq!(s.status, QpStatus::Solved);
        assert!(
            (s.x[0] - 0.8).abs() < 1e-7 && (s.x[1] - 0.2).abs() < 1e-7,
            "{:?}",
            s.x
        );
        assert!(qp.dual_residual(&s.x, &s.y) < 1e-7);
        assert!(s.y[0] > 0.0 && s.y[1] < 0.0, "{:?}", s.y);
    }

    #[test]
    fn warm_start_is_used_and_checked() {
        let qp = small_qp();
        let mut b = OsqpBackend::new(QpSettings::default());
        let s = b.solve(&qp, None).unwrap();
        let w = WarmStart {
            x: s.x.clone(),
            y: s.y.clone(),
        };
        let s2 = b.solve(&qp, Some(&w)).unwrap();
        assert_eq!(s2.status, QpStatus::Solved);
        assert!(s2.iterations <= s.iterations);
        let bad = WarmStart {
            x: vec![0.0; 2],
            y: vec![0.0; 2],
        };
        let e = b.solve(&qp, Some(&bad)).unwrap_err();
        assert_eq!(
            e,
            QpError::WarmStartLength {
                what: "y",
                expected: 3,
                found: 2
            }
        );
    }

    #[test]
    fn infeasible_is_a_status() {
        let mut qp = small_qp();
        qp.l[2] = 0.3;
        qp.u[2] = 0.3;
        qp.l[1] = 0.9;
        let s = OsqpBackend::new(QpSettings::default())
            .solve(&qp, None)
            .unwrap();
        assert_ne!(s.status, QpStatus::Solved);
    }
}
