//! A backend that hands the QPs it does not solve to a second backend: the `ip` entry of the
//! registry is the interior point of [`crate::ipm`] with Clarabel behind it.
//!
//! Each QP goes to the first backend; when it ends with any status but `Solved` (an iteration
//! limit, a numerical breakdown; `ip` has no infeasibility certificate, so an infeasible QP ends
//! there too), the same QP goes to the second, cold, and its answer is returned whatever its
//! status, with the iterations and times of both summed. [`QpBackend::fallback_solves`] counts
//! those QPs. Invalid input is refused by the first backend and never reaches the second.
use crate::backend::{QpBackend, QpError, QpSolution, QpStatus, WarmStart};
use crate::qp::Qp;

/// `first`, then `second` for the QPs `first` does not solve.
pub struct Fallback {
    first: Box<dyn QpBackend>,
    second: Box<dyn QpBackend>,
    handed_on: usize,
}

impl Fallback {
    /// `first` with `second` behind it.
    pub fn new(first: Box<dyn QpBackend>, second: Box<dyn QpBackend>) -> Fallback {
        Fallback {
            first,
            second,
            handed_on: 0,
        }
    }
}

impl QpBackend for Fallback {
    fn name(&self) -> &'static str {
        self.first.name()
    }

    fn tolerance(&self) -> Option<f64> {
        self.first.tolerance()
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.first.set_tolerance(tol);
        self.second.set_tolerance(tol);
    }

    fn fallback_solves(&self) -> usize {
        self.handed_on + self.first.fallback_solves() + self.second.fallback_solves()
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let a = self.first.solve(qp, warm)?;
        if a.status == QpStatus::Solved {
            return Ok(a);
        }
        self.handed_on += 1;
        let mut b = self.second.solve(qp, None)?;
        b.iterations += a.iterations;
        b.solve_time_s += a.solve_time_s;
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::QpSettings;
    use crate::clarabel_backend::ClarabelBackend;
    use crate::ipm::IpBackend;
    use crate::qp::CscMatrix;

    /// min ½|x|² − x₀ s.t. x₀ + x₁ ≤ 0.5, x₀ ≥ −1: the solution is x = (0.75, −0.25).
    fn small() -> Qp {
        let p = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0)]).unwrap();
        Qp {
            p,
            q: vec![-1.0, 0.0],
            a,
            l: vec![f64::NEG_INFINITY, -1.0],
            u: vec![0.5, f64::INFINITY],
        }
    }

    #[test]
    fn a_solved_qp_stays_with_the_first_backend() {
        let s = QpSettings::default();
        let mut b = Fallback::new(
            Box::new(IpBackend::new(s.clone())),
            Box::new(ClarabelBackend::new(s)),
        );
        let sol = b.solve(&small(), None).unwrap();
        assert_eq!(sol.status, QpStatus::Solved);
        assert!(
            (sol.x[0] - 0.75).abs() < 1e-7 && (sol.x[1] + 0.25).abs() < 1e-7,
            "{:?}",
            sol.x
        );
        assert_eq!(b.fallback_solves(), 0);
        assert_eq!(b.name(), "ip");
    }

    #[test]
    fn an_unsolved_qp_goes_to_the_second_backend() {
        // one interior-point iteration cannot reach 1e-9; Clarabel, given the same settings
        // but its own iteration limit, solves it
        let tight = QpSettings {
            max_iter: 1,
            ..QpSettings::default()
        };
        let mut alone = IpBackend::new(tight.clone());
        let first = alone.solve(&small(), None).unwrap();
        assert_eq!(first.status, QpStatus::MaxIterations);
        let mut b = Fallback::new(
            Box::new(IpBackend::new(tight)),
            Box::new(ClarabelBackend::new(QpSettings::default())),
        );
        let sol = b.solve(&small(), None).unwrap();
        assert_eq!(sol.status, QpStatus::Solved);
        assert!((sol.x[0] - 0.75).abs() < 1e-7, "{:?}", sol.x);
        assert_eq!(b.fallback_solves(), 1);
        assert!(sol.iterations > first.iterations);
        // bad input is refused before any hand-over
        let mut bad = small();
        bad.q[0] = f64::NAN;
        assert!(b.solve(&bad, None).is_err());
        assert_eq!(b.fallback_solves(), 1);
    }

    #[test]
    fn an_infeasible_qp_gets_clarabels_certificate() {
        // x₀ ≤ 0 and x₀ ≥ 1: `ip` has no infeasibility certificate, Clarabel has
        let p = CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(2, 1, &[(0, 0, 1.0), (1, 0, 1.0)]).unwrap();
        let qp = Qp {
            p,
            q: vec![0.0],
            a,
            l: vec![f64::NEG_INFINITY, 1.0],
            u: vec![0.0, f64::INFINITY],
        };
        let s = QpSettings::default();
        let ip_alone = IpBackend::new(s.clone()).solve(&qp, None).unwrap().status;
        assert_ne!(ip_alone, QpStatus::Solved);
        assert_ne!(ip_alone, QpStatus::PrimalInfeasible);
        let mut b = Fallback::new(
            Box::new(IpBackend::new(s.clone())),
            Box::new(ClarabelBackend::new(s)),
        );
        assert_eq!(
            b.solve(&qp, None).unwrap().status,
            QpStatus::PrimalInfeasible
        );
        assert_eq!(b.fallback_solves(), 1);
    }
}
