//! A primal–dual active-set backend started from the warm start's duals, with the interior
//! point of [`crate::ipm`] behind it: the `active-set` backend.
//!
//! # Why
//!
//! The inner QPs of one sub-problem share their rows, and from one inner step to the next
//! only a few rows change their activity. An interior point starts each QP away from the
//! boundary and needs about ten factorizations whatever the warm start (`ip` on the balloons
//! at n = 1600: 570 iterations for 59 QPs, 34 per inner step). An active-set method started from the previous QP's active rows
//! needs one factorization when they are still the active rows.
//!
//! # Method
//!
//! With the one-sided constraints `g_j·x ≥ h_j` and equality rows `E x = b` of
//! [`crate::ipm`], a working set `W` (the rows with a positive warm dual; none without a warm
//! start) is taken as equalities, and
//!
//! ```text
//!     min ½xᵀPx + qᵀx   subject to   g_j·x = h_j (j ∈ W),   E x = b
//! ```
//!
//! is solved by the method of multipliers with one factorization of the condensed matrix
//! `P + Σ_{j∈W} d_j g_j g_jᵀ` (with `E` as in [`crate::ipm`]), `d_j = PENALTY ·
//! min_c P_cc / |g_j|²`: each round solves for `x` with the current multipliers `z_W` and
//! updates `z_j ← z_j − d_j (g_j·x − h_j)`, until the working rows hold to a tenth of the
//! primal tolerance and the stationarity of the updated multipliers to a tenth of the dual
//! one (at most `MAX_ROUNDS` rounds, each a solve for an increment with two steps of
//! iterative refinement against the unregularized matrix). From the third round on, a round
//! whose primal residual is above half the last one ends the rounds: the working rows cannot
//! all hold (the rows of both sides of one contact at ε + δ), their multipliers drift, and
//! the update below sheds the rows whose multiplier turned negative. The penalty is small
//! (1e2): at 1e4–1e8 it amplified the round-off of `g_j·x − h_j` into a dual residual of
//! 1e-9 on the balloons. Where the working rows are linearly
//! dependent (a vertex's rows against two edges meeting at a vertex) the multipliers are not
//! unique; the rounds keep their component in the null space of `G_Wᵀ` from the warm start,
//! so a warm start's nonnegative split is kept rather than replaced by a minimum-norm one.
//!
//! Then the primal–dual active-set update (Hintermüller, Ito and Kunisch): a working row with
//! `z_j < 0` leaves `W`, a row outside it with `g_j·x < h_j` joins it. The QP is `Solved` when
//! nothing changes: every `z_j ≥ −tol` (those below 0 are set to 0), the primal and dual
//! residuals of the original QP meet the tolerances of
//! [`crate::clarabel_backend::meets_tolerances`] and the complementarity gap
//! `Σ_W z_j |g_j·x − h_j|` meets the interior point's. A working set seen before (a cycle:
//! also where the rounds do not converge and the update changes nothing), `MAX_UPDATES`
//! updates or a failed factorization hand the QP to the interior point with the same warm
//! start; [`ActiveSetBackend::handed_on`] counts them,
//! and [`QpBackend::fallback_solves`] includes them.
//!
//! **Measured** (docs/method.md, "Backends and accuracy presets"): on the balloons it is
//! slower than `ip` (1.44× at n = 640, 1.59× at n = 1600): where a contact front moves it
//! needs 5–12 working sets or hands the QP on; it solves a QP in one working set where the
//! active rows stay. It is kept as an opt-in backend so that the measurement can be repeated.
//!
//! The working set's pattern changes with `W`, so each update builds its matrix (pattern, AMD
//! ordering, symbolic factorization); the last pattern's symbolic factorization is kept and
//! reused when the next QP starts from the same working set.
use crate::backend::{QpBackend, QpError, QpSettings, QpSolution, QpStatus, WarmStart};
use crate::clarabel_backend::meets_tolerances;
use crate::ipm::{p_diagonal, IpBackend, Kkt, Split, SymbolicCache};
use crate::qp::Qp;
use std::collections::HashSet;
use std::time::Instant;

/// `d_j |g_j|²` over the smallest diagonal entry of `P` on the row's columns.
const PENALTY: f64 = 1e2;
/// Multiplier rounds per working set.
const MAX_ROUNDS: usize = 10;
/// Working-set updates per QP before the QP goes to the interior point.
const MAX_UPDATES: usize = 12;
/// Warm duals below this fraction of the largest are taken as 0.
const WARM_DUAL_REL: f64 = 1e-6;

/// The primal–dual active-set method with the interior point behind it.
pub struct ActiveSetBackend {
    settings: QpSettings,
    ip: IpBackend,
    cache: Option<SymbolicCache>,
    handed_on: usize,
}

impl ActiveSetBackend {
    /// A backend with `settings` (validated at each solve); the interior point behind it has
    /// the same.
    pub fn new(settings: QpSettings) -> Self {
        ActiveSetBackend {
            ip: IpBackend::new(settings.clone()),
            settings,
            cache: None,
            handed_on: 0,
        }
    }

    /// QPs handed to the interior point since the backend was made.
    pub fn handed_on(&self) -> usize {
        self.handed_on
    }

    /// The active-set method alone: `Some` solution when it ends `Solved`, `None` to hand the
    /// QP on. `iters` counts its working sets.
    fn try_solve(
        &mut self,
        qp: &Qp,
        warm: Option<&WarmStart>,
        iters: &mut usize,
    ) -> Option<QpSolution> {
        let s = &self.settings;
        let (n, m) = (qp.n(), qp.m());
        let split = Split::new(qp);
        let mi = split.ineq.len();
        let pdiag = p_diagonal(qp);
        let maxdiag = pdiag.iter().fold(1.0f64, |a, b| a.max(b.abs()));
        let reg = 1e-10 * maxdiag;
        let pen: Vec<f64> = (0..mi)
            .map(|j| {
                let (cs, vs) = split.g_row(j);
                let g2: f64 = vs.iter().map(|v| v * v).sum();
                let pmin = cs.iter().map(|&c| pdiag[c]).fold(f64::INFINITY, f64::min);
                if g2 > 0.0 && pmin.is_finite() && pmin > 0.0 {
                    PENALTY * pmin / g2
                } else {
                    PENALTY * maxdiag
                }
            })
            .collect();
        // z from the warm start (the sign convention of QpSolution::y)
        let mut z: Vec<f64> = match warm.filter(|w| w.y.len() == m) {
            Some(w) => split
                .ineq
                .iter()
                .map(|&(i, sg)| (-sg * w.y[i]).max(0.0))
                .collect(),
            None => vec![0.0; mi],
        };
        // an interior-point solution leaves every dual positive: the rows that hold one are
        // those above a millionth of the largest (as for the interior point's warm start)
        let floor = WARM_DUAL_REL * z.iter().copied().fold(0.0, f64::max);
        for v in z.iter_mut() {
            if *v <= floor {
                *v = 0.0;
            }
        }
        let mut in_w: Vec<bool> = z.iter().map(|&v| v > 0.0).collect();
        let mut seen: HashSet<Vec<usize>> = HashSet::new();
        let mut gx = vec![0.0; mi];
        let mut x = vec![0.0; n];
        let mut ye = vec![0.0; split.eq.len()];
        for _ in 0..MAX_UPDATES {
            let keep: Vec<usize> = (0..mi).filter(|&j| in_w[j]).collect();
            if !seen.insert(keep.clone()) {
                return None;
            }
            *iters += 1;
            let sub = split.subset(&keep);
            let mut k = Kkt::new(qp, &sub, &mut self.cache)?;
            let d: Vec<f64> = keep.iter().map(|&j| pen[j]).collect();
            let vals_true = k.values(qp, &d, 0.0, 0.0);
            let vals = k.values(qp, &d, reg, reg);
            if !k.factor(&vals, reg) {
                return None;
            }
            // method of multipliers on the working rows
            let mut zw: Vec<f64> = keep.iter().map(|&j| z[j]).collect();
            let hw: Vec<f64> = keep.iter().map(|&j| split.h[j]).collect();
            let tol_p = 0.1 * (s.eps_abs + s.eps_rel);
            let mut held = false;
            let mut gw = vec![0.0; keep.len()];
            let mut ex = vec![0.0; split.eq.len()];
            let mut last_worst = f64::INFINITY;
            for round in 0..MAX_ROUNDS {
                // the residual of the augmented Lagrangian's stationarity at x, solved for an
                // increment (round-off relative to the residual, not to the penalty's terms)
                sub.g_mul(&x, &mut gw);
                let zt: Vec<f64> = (0..keep.len())
                    .map(|a| zw[a] - d[a] * (gw[a] - hw[a]))
                    .collect();
                let mut rhs = vec![0.0; n + split.eq.len()];
                qp.p.sym_upper_mul_add(-1.0, &x, &mut rhs[..n]);
                for (r, qv) in rhs.iter_mut().zip(&qp.q) {
                    *r -= qv;
                }
                sub.gt_mul_add(&zt, &mut rhs[..n]);
                split.et_mul_add(&ye, &mut rhs[..n]);
                split.e_mul(&x, &mut ex);
                for (kk, bv) in split.b.iter().enumerate() {
                    rhs[n + kk] = bv - ex[kk];
                }
                let sol = k.solve_refined(&vals_true, &rhs);
                if sol.iter().any(|v| !v.is_finite()) {
                    return None;
                }
                for (xi, dx) in x.iter_mut().zip(&sol[..n]) {
                    *xi += dx;
                }
                for (e, v) in ye.iter_mut().zip(&sol[n..]) {
                    *e -= v;
                }
                sub.g_mul(&x, &mut gw);
                let mut worst = 0.0f64;
                for ((zj, dj), (g, h)) in zw.iter_mut().zip(&d).zip(gw.iter().zip(&hw)) {
                    let r = g - h;
                    worst = worst.max(r.abs());
                    *zj -= dj * r;
                }
                let scale = 1.0 + gw.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                // stationarity with the updated multipliers (the solve's round-off is relative
                // to the penalty's terms: a long first increment leaves it above tolerance)
                let mut rd = vec![0.0; n];
                qp.p.sym_upper_mul_add(1.0, &x, &mut rd);
                let pscale = rd.iter().chain(&qp.q).fold(1.0f64, |a, b| a.max(b.abs()));
                for (r, qv) in rd.iter_mut().zip(&qp.q) {
                    *r += qv;
                }
                let mzw: Vec<f64> = zw.iter().map(|v| -v).collect();
                sub.gt_mul_add(&mzw, &mut rd);
                let mye: Vec<f64> = ye.iter().map(|v| -v).collect();
                split.et_mul_add(&mye, &mut rd);
                let stat = rd.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                if round >= 2 && worst > 0.5 * last_worst {
                    // the working rows cannot all hold (their multipliers drift): update
                    break;
                }
                last_worst = worst;
                if worst <= tol_p * scale && stat <= 0.1 * (s.eps_abs + s.eps_rel * pscale) {
                    held = true;
                    break;
                }
            }
            for (&j, &v) in keep.iter().zip(&zw) {
                z[j] = v;
            }
            split.g_mul(&x, &mut gx);
            // the update
            let mut changed = false;
            let ztol = 1e-3 * s.eps_abs;
            for j in 0..mi {
                if in_w[j] {
                    if z[j] < -ztol {
                        in_w[j] = false;
                        z[j] = 0.0;
                        changed = true;
                    } else if z[j] < 0.0 {
                        z[j] = 0.0;
                    }
                } else if gx[j] < split.h[j] {
                    let pri_tol = s.eps_abs + s.eps_rel * gx[j].abs().max(1.0);
                    if gx[j] < split.h[j] - 0.1 * pri_tol {
                        in_w[j] = true;
                        changed = true;
                    }
                }
            }
            if changed || !held {
                continue;
            }
            let y = split.duals(m, &z, &ye);
            let obj = qp.objective(&x);
            let gap: f64 = (0..mi)
                .filter(|&j| in_w[j])
                .map(|j| z[j] * (gx[j] - split.h[j]).abs())
                .sum();
            if gap <= s.eps_abs + s.eps_rel * obj.abs().max(1.0) && meets_tolerances(qp, &x, &y, s)
            {
                return Some(QpSolution {
                    x,
                    y,
                    status: QpStatus::Solved,
                    iterations: 0,
                    solve_time_s: 0.0,
                });
            }
            return None;
        }
        None
    }
}

impl QpBackend for ActiveSetBackend {
    fn name(&self) -> &'static str {
        "active-set"
    }

    fn tolerance(&self) -> Option<f64> {
        Some(self.settings.eps_abs)
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.settings.eps_abs = tol;
        self.settings.eps_rel = tol;
        self.ip.set_tolerance(tol);
    }

    fn fallback_solves(&self) -> usize {
        self.handed_on
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let start = Instant::now();
        self.settings.validate()?;
        qp.validate()?;
        crate::osqp_backend::check_warm(warm, qp.n(), qp.m())?;
        let mut iters = 0;
        if let Some(mut sol) = self.try_solve(qp, warm, &mut iters) {
            sol.iterations = iters;
            sol.solve_time_s = start.elapsed().as_secs_f64();
            return Ok(sol);
        }
        self.handed_on += 1;
        let mut sol = self.ip.solve(qp, warm)?;
        sol.iterations += iters;
        sol.solve_time_s = start.elapsed().as_secs_f64();
        Ok(sol)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clarabel_backend::ClarabelBackend;
    use crate::ipm::tests::{chain_qp, tight};
    use crate::qp::CscMatrix;

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    }

    /// Cold (the working set empty at first) and warm from the solution's duals, on a
    /// contact-like QP whose rows come in duplicates: the method itself solves it (nothing
    /// handed on), to Clarabel's solution; from the solution's duals in one working set.
    #[test]
    fn solves_a_contact_like_qp_cold_and_in_one_working_set_from_its_duals() {
        let qp = chain_qp(60);
        let cl = ClarabelBackend::new(tight()).solve(&qp, None).unwrap();
        assert_eq!(cl.status, QpStatus::Solved);
        let mut b = ActiveSetBackend::new(tight());
        let cold = b.solve(&qp, None).unwrap();
        assert_eq!(cold.status, QpStatus::Solved);
        assert_eq!(b.handed_on(), 0, "cold solve handed on");
        let (ja, jc) = (qp.objective(&cold.x), qp.objective(&cl.x));
        assert!((ja - jc).abs() <= 1e-8 * jc.abs().max(1.0), "{ja} vs {jc}");
        assert!(max_diff(&cold.x, &cl.x) < 1e-6);
        assert!(qp.primal_residual(&cold.x) < 1e-9);
        assert!(qp.dual_residual(&cold.x, &cold.y) < 1e-8);
        assert!(cold.y.iter().any(|&y| y < -1e-6), "no lower row active");
        assert!(
            cold.iterations >= 2,
            "cold: {} working sets",
            cold.iterations
        );
        let warm = WarmStart {
            x: Vec::new(),
            y: cl.y.clone(),
        };
        let w = b.solve(&qp, Some(&warm)).unwrap();
        assert_eq!(w.status, QpStatus::Solved);
        assert_eq!(w.iterations, 1, "working sets from the solution's duals");
        assert_eq!(b.handed_on(), 0);
        assert!(max_diff(&w.x, &cl.x) < 1e-6);
    }

    /// A warm start whose positive duals make an inconsistent working set (x = 1 and
    /// x = 0.5): the rounds stall, the second row's multiplier turns negative, it leaves.
    #[test]
    fn an_inconsistent_working_set_is_shed() {
        let qp = Qp {
            p: CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap(),
            q: vec![0.0],
            a: CscMatrix::from_triplets(2, 1, &[(0, 0, 1.0), (1, 0, 1.0)]).unwrap(),
            l: vec![1.0, 0.5],
            u: vec![f64::INFINITY; 2],
        };
        let mut b = ActiveSetBackend::new(tight());
        let warm = WarmStart {
            x: Vec::new(),
            y: vec![-1.0, -1.0],
        };
        let s = b.solve(&qp, Some(&warm)).unwrap();
        assert_eq!(s.status, QpStatus::Solved);
        assert_eq!(b.handed_on(), 0);
        assert!((s.x[0] - 1.0).abs() < 1e-9, "x = {}", s.x[0]);
        assert!(
            (s.y[0] + 1.0).abs() < 1e-8 && s.y[1].abs() < 1e-12,
            "y = {:?}",
            s.y
        );
    }

    /// An infeasible QP: no working set solves it; it goes to the interior point, which
    /// does not solve it either.
    #[test]
    fn an_infeasible_qp_is_handed_on() {
        let qp = Qp {
            p: CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap(),
            q: vec![0.0],
            a: CscMatrix::from_triplets(2, 1, &[(0, 0, 1.0), (1, 0, 1.0)]).unwrap(),
            l: vec![1.0, f64::NEG_INFINITY],
            u: vec![f64::INFINITY, -1.0],
        };
        let mut b = ActiveSetBackend::new(tight());
        let s = b.solve(&qp, None).unwrap();
        assert_ne!(s.status, QpStatus::Solved);
        assert_eq!(b.handed_on(), 1);
        assert_eq!(b.fallback_solves(), 1);
    }
}
