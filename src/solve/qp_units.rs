//! The sub-problem QP in the run's own units (docs/method.md, "The outer loop").
//!
//! The backends' tolerances are partly absolute (Clarabel's `tol_gap_abs` and `tol_feas`, the
//! `max(1, ·)` of every backend's residual test), so the same QP written in other units of
//! energy and length is solved to another relative accuracy, and a run takes other steps. The
//! sub-problem therefore hands the backend the QP in units where energies are measured by the
//! run's energy scale `E` and lengths by the reference diameter `ℓ` (both rounded to powers of
//! two, so that the change of units is exact in floating point): with `x = ℓ x'`,
//!
//! ```text
//!     P' = P ℓ²/E,   q' = q ℓ/E,   A' = A,   l' = l/ℓ,   u' = u/ℓ,   y = y' E/ℓ.
//! ```
//!
//! Every variable of the QP is a length or, for a rank-one term's auxiliary variable `s = w·d`,
//! homogeneous in the displacement `d` (its equality row `s − w·d = 0` has zero bounds), so one
//! length unit serves all of them.

use contactlab_solvers::{Qp, QpBackend, QpError, QpSolution, WarmStart};

/// `2^round(log2 v)` (`v > 0` finite), else 1.
fn power_of_two(v: f64) -> f64 {
    if v > 0.0 && v.is_finite() {
        2f64.powi(v.log2().round() as i32)
    } else {
        1.0
    }
}

/// Solves `qp` with `backend` in the units `(energy, length)` (rounded to powers of two; see
/// the module documentation) and returns the solution in the QP's own units.
pub fn solve_in_units(
    backend: &mut dyn QpBackend,
    qp: &Qp,
    warm: Option<&WarmStart>,
    energy: f64,
    length: f64,
) -> Result<QpSolution, QpError> {
    let (e, l) = (power_of_two(energy), power_of_two(length));
    if e == 1.0 && l == 1.0 {
        return backend.solve(qp, warm);
    }
    let (fp, fq) = (l * l / e, l / e);
    let mut s = qp.clone();
    s.p.nzval.iter_mut().for_each(|v| *v *= fp);
    s.q.iter_mut().for_each(|v| *v *= fq);
    s.l.iter_mut().for_each(|v| *v /= l);
    s.u.iter_mut().for_each(|v| *v /= l);
    let w = warm.map(|w| WarmStart {
        x: w.x.iter().map(|v| v / l).collect(),
        y: w.y.iter().map(|v| v * fq).collect(),
    });
    let mut sol = backend.solve(&s, w.as_ref())?;
    sol.x.iter_mut().for_each(|v| *v *= l);
    sol.y.iter_mut().for_each(|v| *v /= fq);
    Ok(sol)
}

#[cfg(test)]
mod tests {
    use super::*;
    use contactlab_solvers::{backend_from_name, CscMatrix, QpSettings};

    #[test]
    fn qp_units_give_the_solution_in_the_qps_own_units() {
        // min ½(x0² + 2 x1²) − x0 − x1 s.t. x0 + x1 ≥ 2: x0 − 1 = 2 x1 − 1 = λ, x0 + x1 = 2,
        // so x = (4/3, 2/3), λ = 1/3 (y = −λ).
        let qp = Qp {
            p: CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 2.0)]).unwrap(),
            q: vec![-1.0, -1.0],
            a: CscMatrix::from_triplets(1, 2, &[(0, 0, 1.0), (0, 1, 1.0)]).unwrap(),
            l: vec![2.0],
            u: vec![f64::INFINITY],
        };
        let st = QpSettings {
            eps_abs: 1e-12,
            eps_rel: 1e-12,
            ..Default::default()
        };
        let mut b = backend_from_name("clarabel", &st).unwrap();
        let plain = b.solve(&qp, None).unwrap();
        assert!((plain.x[0] - 4.0 / 3.0).abs() < 1e-9 && (plain.x[1] - 2.0 / 3.0).abs() < 1e-9);
        assert!((plain.y[0] + 1.0 / 3.0).abs() < 1e-9);
        for (e, l) in [(1e-6, 1e-3), (16.0, 4.0), (1.0, 1.0)] {
            let s = solve_in_units(b.as_mut(), &qp, None, e, l).unwrap();
            for k in 0..2 {
                assert!((s.x[k] - plain.x[k]).abs() < 1e-9, "E {e} L {l}: {:?}", s.x);
            }
            assert!((s.y[0] - plain.y[0]).abs() < 1e-9, "E {e} L {l}: {:?}", s.y);
        }
    }
}
