//! Backend on the OSQP ADMM solver (osqp 0.6 crate, OSQP 0.6 C library).
//!
//! OSQP solves exactly the crate's standard form and uses the same dual sign convention, so `x`
//! and `y` are returned as they are. Infinite bounds are replaced by `±OSQP_INFTY = ±1e30`.
//!
//! # Settings
//!
//! `eps_abs`, `eps_rel`, `max_iter` (saturated at `u32::MAX`), `time_limit` (only when finite),
//! `polish = true`, `verbose = false`, `adaptive_rho = true` with a fixed
//! `adaptive_rho_interval = 25` iterations (OSQP's default 0 chooses the interval from the
//! measured set-up time, which makes the iterates depend on the machine's load). A [`WarmStart`] is used for both
//! `x` and `y` (`osqp_warm_start`); an empty vector means "not given" and starts that part at
//! zero (as a fresh OSQP problem does), any other wrong length is [`QpError::WarmStartLength`]
//! (the rule shared by all backends). `rho = 0.1` (OSQP's default) is set explicitly.
//!
//! # Reuse of the set-up problem
//!
//! The backend keeps the `osqp::Problem` of its last solve. The next solve reuses it when `n`,
//! `m`, the settings and the patterns of `P` (upper triangle) and `A` (column pointers and row
//! indices; explicit zeros count as entries) are exactly the same; it then skips `osqp_setup`
//! (ordering, symbolic factorization, allocations) and updates the data instead, in this order:
//! `update_bounds(l, u)`, `update_lin_cost(q)`, `update_rho(0.1)` when adaptive ρ changed ρ in
//! the previous solve, `update_P_A` (which recomputes the Ruiz scaling from the new `P`, `A`
//! and `q`, as a set-up would, and refactorizes the KKT matrix numerically). Both warm-start
//! vectors are always set (zeros for a part not given), so a reused problem starts from the
//! same point, with the same ρ and scaling, as a fresh one: the results agree with a fresh
//! set-up to the solver tolerance, not bit for bit (the scaled data goes through an unscale /
//! rescale round trip). Two things do differ: the adaptive-ρ interval, which OSQP fixes from
//! timing during the first solve after a set-up, is kept, and `time_limit` counts the update
//! time instead of the set-up time. OSQP checks convexity only at set-up, so on the reuse path a
//! non-convex `P` is reported as `NumericalError` only when the refactorization meets a zero
//! pivot (the problem is then set up afresh) or the iterates diverge. Any other change of
//! pattern or size sets up a new problem ([`OsqpBackend::setups`] counts set-ups). There is no
//! setting to turn reuse off.
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

/// Iterations between ρ adaptations (a multiple of OSQP's termination-check interval, 25).
const ADAPTIVE_RHO_INTERVAL: u32 = 25;

/// The initial ADMM step ρ (OSQP 0.6's default), set at setup and restored before a solve that
/// reuses a problem whose ρ was adapted.
const RHO: f64 = 0.1;

/// The OSQP backend. See the module documentation for the mapping and the reuse of the set-up
/// problem.
pub struct OsqpBackend {
    settings: QpSettings,
    /// The problem set up by an earlier solve, kept while the patterns do not change.
    cache: Option<Cached>,
    /// Number of `osqp_setup` calls so far.
    setups: usize,
}

/// A set-up OSQP problem with what it was set up for.
struct Cached {
    prob: Problem,
    /// The settings it was set up with.
    settings: QpSettings,
    /// `n` and `m`.
    n: usize,
    m: usize,
    /// Patterns of `P` (upper triangle) and `A`: column pointers and row indices.
    p_colptr: Vec<usize>,
    p_rowval: Vec<usize>,
    a_colptr: Vec<usize>,
    a_rowval: Vec<usize>,
    /// Whether the last solve changed ρ (adaptive ρ), so that it must be reset to [`RHO`].
    rho_changed: bool,
}

impl Cached {
    /// Whether `qp`, solved with `settings`, can reuse this problem.
    fn fits(&self, qp: &Qp, settings: &QpSettings) -> bool {
        let same = |m: &crate::qp::CscMatrix, colptr: &[usize], rowval: &[usize]| {
            m.colptr == colptr && m.rowval == rowval
        };
        self.settings == *settings
            && self.n == qp.n()
            && self.m == qp.m()
            && same(&qp.p, &self.p_colptr, &self.p_rowval)
            && same(&qp.a, &self.a_colptr, &self.a_rowval)
    }
}

impl OsqpBackend {
    /// A backend using `settings` (validated at each solve).
    pub fn new(settings: QpSettings) -> Self {
        OsqpBackend {
            settings,
            cache: None,
            setups: 0,
        }
    }

    /// Number of OSQP set-ups (`osqp_setup`: scaling, KKT assembly, ordering, symbolic and
    /// numeric factorization) this backend has done. A solve that reuses the previous problem
    /// does none, so a sequence of QPs sharing their patterns counts 1.
    pub fn setups(&self) -> usize {
        self.setups
    }
}

/// A clone has the settings and the set-up count, not the set-up problem (it sets up its own).
impl Clone for OsqpBackend {
    fn clone(&self) -> Self {
        OsqpBackend {
            settings: self.settings.clone(),
            cache: None,
            setups: self.setups,
        }
    }
}

impl std::fmt::Debug for OsqpBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OsqpBackend")
            .field("settings", &self.settings)
            .field("setups", &self.setups)
            .field("problem_kept", &self.cache.is_some())
            .finish()
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

    fn tolerance(&self) -> Option<f64> {
        Some(self.settings.eps_abs)
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.settings.eps_abs = tol;
        self.settings.eps_rel = tol;
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let start = Instant::now();
        self.settings.validate()?;
        qp.validate()?;
        let (n, m) = (qp.n(), qp.m());
        check_warm(warm, n, m)?;

        let l: Vec<f64> = qp.l.iter().map(|&v| v.max(-OSQP_INFTY)).collect();
        let u: Vec<f64> = qp.u.iter().map(|&v| v.min(OSQP_INFTY)).collect();
        let zero = |status, iterations| QpSolution {
            x: vec![0.0; n],
            y: vec![0.0; m],
            status,
            iterations,
            solve_time_s: start.elapsed().as_secs_f64(),
        };

        // Reuse the problem of the previous solve when its patterns, sizes and settings are the
        // same: new values of P and A, q, l and u replace the old ones (no set-up).
        if let Some(c) = self.cache.as_mut().filter(|c| c.fits(qp, &self.settings)) {
            let rho_changed = c.rho_changed;
            let prob = &mut c.prob;
            // The updates panic only when OSQP reports a failure (a zero pivot in the KKT
            // refactorization, i.e. a non-convex P): then set up afresh, which reports it.
            let updated = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                // q, l and u first, P and A last: the update of P and A recomputes the data
                // scaling, and OSQP's cost scaling depends on q, so it is the one a fresh set-up
                // would compute.
                prob.update_bounds(&l, &u);
                prob.update_lin_cost(&qp.q);
                if rho_changed {
                    prob.update_rho(RHO);
                }
                prob.update_P_A(to_osqp(&qp.p), to_osqp(&qp.a));
            }));
            if updated.is_err() {
                self.cache = None;
            }
        } else {
            self.cache = None;
        }
        if self.cache.is_none() {
            let s = &self.settings;
            let mut settings = Settings::default()
                .rho(RHO)
                .eps_abs(s.eps_abs)
                .eps_rel(s.eps_rel)
                .max_iter(
                    u32::try_from(s.max_iter)
                        .unwrap_or(u32::MAX)
                        .min(i32::MAX as u32),
                )
                .polish(true)
                .verbose(false)
                .adaptive_rho(true)
                // a fixed interval: OSQP's default (0 = automatic) times the set-up and adapts
                // ρ after a fraction of that time, so identical runs took different iteration
                // counts (measured: 1925 against 2550 backend iterations on the same case)
                .adaptive_rho_interval(Some(ADAPTIVE_RHO_INTERVAL));
            if s.time_limit_s.is_finite() {
                settings =
                    settings.time_limit(Some(Duration::from_secs_f64(s.time_limit_s.min(1e9))));
            }
            self.setups += 1;
            let prob = match Problem::new(to_osqp(&qp.p), &qp.q, to_osqp(&qp.a), &l, &u, &settings)
            {
                Ok(p) => p,
                // The input was validated, so remaining failures (non-convex P, linear-system
                // set-up, allocation) are numerical.
                Err(_) => return Ok(zero(QpStatus::NumericalError, 0)),
            };
            self.cache = Some(Cached {
                prob,
                settings: self.settings.clone(),
                n,
                m,
                p_colptr: qp.p.colptr.clone(),
                p_rowval: qp.p.rowval.clone(),
                a_colptr: qp.a.colptr.clone(),
                a_rowval: qp.a.rowval.clone(),
                rho_changed: false,
            });
        }
        let cached = self.cache.as_mut().expect("set up above");
        let prob = &mut cached.prob;
        // Always set both starting points, zeros for a part not given: a fresh problem starts
        // at x = 0, y = 0, and a reused one would otherwise start from the previous solution.
        let x0 = match warm {
            Some(w) if !w.x.is_empty() => Cow::Borrowed(&w.x[..]),
            _ => Cow::Owned(vec![0.0; n]),
        };
        let y0 = match warm {
            Some(w) if !w.y.is_empty() => Cow::Borrowed(&w.y[..]),
            _ => Cow::Owned(vec![0.0; m]),
        };
        prob.warm_start(&x0, &y0);
        // The osqp crate panics when a refactorization inside the solve fails (adaptive ρ
        // meeting a zero pivot): a status, never a panic, so report NumericalError and drop
        // the problem.
        let result = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || {
            { prob }.solve()
        })) {
            Ok(r) => r,
            Err(_) => {
                self.cache = None;
                return Ok(zero(QpStatus::NumericalError, 0));
            }
        };
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
        let out = match sol {
            Some(sol) if sol.x().len() == n && sol.y().len() == m => QpSolution {
                x: sol.x().to_vec(),
                y: sol.y().to_vec(),
                status,
                iterations,
                solve_time_s: start.elapsed().as_secs_f64(),
            },
            _ => zero(status, iterations),
        };
        cached.rho_changed = result.rho_updates() > 0;
        Ok(out)
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
