//! The `ip` backend's stall mode (`ipm` module documentation, "Stalls") on the QP where it was
//! found, and the registry's `ip` handing a QP it does not solve to Clarabel.

use contactlab_solvers::clarabel_backend::ClarabelBackend;
use contactlab_solvers::ipm::IpBackend;
use contactlab_solvers::{backend_from_name, read_qps_file, QpBackend, QpSettings, QpStatus};
use std::path::Path;

fn settings() -> QpSettings {
    QpSettings {
        eps_abs: 1e-10,
        eps_rel: 1e-10,
        ..QpSettings::default()
    }
}

/// A sub-problem QP of `contactlab run drop --dynamic` (implicit Euler, the ring at rest on
/// the floor, as the backend received it after the row presolve): plain Mehrotra cycled with
/// the gap between 0.02 and 0.14 until its 200 iterations; with the stall mode it is solved,
/// to Clarabel's objective.
#[test]
fn ip_leaves_a_mehrotra_cycle_and_solves_the_qp() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/euler_drop_ip_stall.qps");
    let (_, qp) = read_qps_file(&path).unwrap();
    let mut ip = IpBackend::new(settings());
    let sol = ip.solve(&qp, None).unwrap();
    assert_eq!(sol.status, QpStatus::Solved);
    assert_eq!(
        ip.stalls(),
        1,
        "the solve should have entered the stall mode once"
    );
    assert!(sol.iterations < 60, "{} iterations", sol.iterations);
    assert!(
        qp.primal_residual(&sol.x) <= 1e-9,
        "{}",
        qp.primal_residual(&sol.x)
    );
    let reference = ClarabelBackend::new(settings()).solve(&qp, None).unwrap();
    assert_eq!(reference.status, QpStatus::Solved);
    let (j, jr) = (qp.objective(&sol.x), qp.objective(&reference.x));
    assert!(
        (j - jr).abs() <= 1e-8 * jr.abs(),
        "{j} against Clarabel's {jr}"
    );
}

/// `ip` from the registry is the interior point with Clarabel behind it: a QP it does not
/// solve (here: an iteration limit of 3) goes to Clarabel and is counted.
#[test]
fn registry_ip_hands_an_unsolved_qp_to_clarabel() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/euler_drop_ip_stall.qps");
    let (_, qp) = read_qps_file(&path).unwrap();
    let few = QpSettings {
        max_iter: 3,
        ..settings()
    };
    let mut alone = IpBackend::new(few.clone());
    assert_eq!(
        alone.solve(&qp, None).unwrap().status,
        QpStatus::MaxIterations
    );
    let mut b = backend_from_name("ip", &few).unwrap();
    assert_eq!(b.name(), "ip");
    let sol = b.solve(&qp, None).unwrap();
    // Clarabel gets the same settings: 3 iterations are not enough for it either, so its
    // status is what comes back, and the QP is counted as handed on
    assert_eq!(b.fallback_solves(), 1);
    let mut c = ClarabelBackend::new(few);
    assert_eq!(sol.status, c.solve(&qp, None).unwrap().status);
    // with the default iteration limit the QP is solved by `ip` itself
    let mut d = backend_from_name("ip", &settings()).unwrap();
    assert_eq!(d.solve(&qp, None).unwrap().status, QpStatus::Solved);
    assert_eq!(d.fallback_solves(), 0);
}
