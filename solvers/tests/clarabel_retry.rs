//! Clarabel's retry without equilibration (`clarabel_backend` module documentation, "Retry
//! without equilibration") on the QP where it was found.

use contactlab_solvers::clarabel_backend::ClarabelBackend;
use contactlab_solvers::ipm::IpBackend;
use contactlab_solvers::{read_qps_file, QpBackend, QpSettings, QpStatus};
use std::path::Path;

/// A sub-problem QP of `contactlab run drop --dynamic --scheme newmark` (step 264, as the
/// backend received it after the row presolve): Clarabel with its equilibration stops with
/// `InsufficientProgress` at a duality gap of 2.8e-2; the retry solves it, to the objective
/// of the `ip` backend.
#[test]
fn clarabel_retries_without_equilibration_where_it_stalls() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/newmark_drop_insufficient_progress.qps");
    let (_, qp) = read_qps_file(&path).unwrap();
    let settings = QpSettings {
        eps_abs: 1e-9,
        eps_rel: 1e-9,
        ..QpSettings::default()
    };
    let mut clarabel = ClarabelBackend::new(settings.clone());
    let sol = clarabel.solve(&qp, None).unwrap();
    // the first solve stalled (a retry happens only then), the retry solved
    assert_eq!(clarabel.retries(), 1);
    assert_eq!(sol.status, QpStatus::Solved);
    assert!(
        qp.primal_residual(&sol.x) <= 1e-9,
        "{}",
        qp.primal_residual(&sol.x)
    );
    let reference = IpBackend::new(settings).solve(&qp, None).unwrap();
    assert_eq!(reference.status, QpStatus::Solved);
    let (j, jr) = (qp.objective(&sol.x), qp.objective(&reference.x));
    assert!(
        (j - jr).abs() <= 1e-7 * jr.abs().max(1e-3),
        "{j} against ip's {jr}"
    );
    // a QP Clarabel solves at once is not retried
    let mut easy = qp.clone();
    easy.a = contactlab_solvers::CscMatrix::from_triplets(0, qp.n(), &[]).unwrap();
    easy.l.clear();
    easy.u.clear();
    let mut fresh = ClarabelBackend::new(QpSettings::default());
    assert_eq!(fresh.solve(&easy, None).unwrap().status, QpStatus::Solved);
    assert_eq!(fresh.retries(), 0);
}
