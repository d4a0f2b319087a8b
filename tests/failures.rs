//! Failures are recorded, not fatal: a backend that stops at its iteration
//! limit, an infeasible sub-problem and a run that hits its time limit each end the outer loop
//! with a status, and the result is the last accepted iterate, which is admissible and has the
//! lowest J of the run. A scripted backend wraps Clarabel and injects the failure at a chosen
//! solve, so the failure path is exercised deterministically.

use contactlab::contact::min_distance;
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::Scene;
use contactlab::solve::outer::{run, OuterSettings, RunError, RunStatus};
use contactlab_solvers::{
    backend_from_name, default_settings, Qp, QpBackend, QpError, QpSolution, QpStatus, WarmStart,
};
use std::time::Duration;

/// Clarabel, except that solve number `fail_at` (1-based) returns `status` with Clarabel's
/// iterate, and every solve first sleeps `sleep`.
struct Scripted {
    inner: Box<dyn QpBackend>,
    fail_at: usize,
    status: QpStatus,
    sleep: Duration,
    calls: usize,
}

impl Scripted {
    fn new(fail_at: usize, status: QpStatus, sleep: Duration) -> Self {
        Scripted {
            inner: backend_from_name("clarabel", &default_settings("clarabel")).unwrap(),
            fail_at,
            status,
            sleep,
            calls: 0,
        }
    }
}

impl QpBackend for Scripted {
    fn name(&self) -> &'static str {
        "scripted"
    }
    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        self.calls += 1;
        std::thread::sleep(self.sleep);
        let mut sol = self.inner.solve(qp, warm)?;
        if self.calls == self.fail_at {
            sol.status = self.status;
        }
        Ok(sol)
    }
}

fn scene() -> Scene {
    build(&BalloonsParams {
        n: 10,
        ..Default::default()
    })
    .unwrap()
}

struct Outcome {
    status: RunStatus,
    x: Vec<f64>,
    energy: f64,
    outer: usize,
    /// J of every iterate the observer saw (iteration 0 first).
    seen: Vec<f64>,
}

fn run_with(scene: &Scene, backend: &mut dyn QpBackend, settings: &OuterSettings) -> Outcome {
    let mut seen = Vec::new();
    let res = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        backend,
        settings,
        &mut |r, _| seen.push(r.energy),
    )
    .expect("a failure is a status, not an error");
    Outcome {
        status: res.status,
        x: res.x,
        energy: res.energy,
        outer: res.outer_iterations,
        seen,
    }
}

/// The returned state is admissible (exact check over all pairs) and is the lowest-energy
/// iterate of the run.
fn assert_last_admissible(scene: &Scene, o: &Outcome) {
    let md = min_distance(&scene.mesh, &o.x, 2.0 * scene.eps, false);
    assert!(
        md.distance >= scene.eps * (1.0 - 1e-12),
        "returned state at distance {} < eps {}",
        md.distance,
        scene.eps
    );
    assert_eq!(o.energy, scene.energy.value(&o.x));
    let lowest = o.seen.iter().copied().fold(f64::INFINITY, f64::min);
    assert_eq!(
        o.energy, lowest,
        "J of the returned state vs the run's lowest"
    );
}

#[test]
fn backend_iteration_limit_and_infeasible_qp_end_the_run_with_a_status() {
    let scene = scene();
    // The reference run: how many solves and outer steps it takes.
    let mut clean = Scripted::new(usize::MAX, QpStatus::Solved, Duration::ZERO);
    let reference = run_with(&scene, &mut clean, &OuterSettings::default());
    assert_eq!(reference.status, RunStatus::Converged);
    assert!(clean.calls > 6, "{} solves", clean.calls);
    for status in [QpStatus::MaxIterations, QpStatus::PrimalInfeasible] {
        // Fail a solve in the middle of the run.
        let at = clean.calls / 2;
        let mut b = Scripted::new(at, status, Duration::ZERO);
        let o = run_with(&scene, &mut b, &OuterSettings::default());
        assert_eq!(o.status, RunStatus::SubproblemFailed, "{status:?}");
        assert_eq!(b.calls, at, "the run stops at the failing solve");
        assert!(o.outer >= 1 && o.outer <= reference.outer);
        assert!(o.energy >= reference.energy);
        assert_last_admissible(&scene, &o);
    }
}

#[test]
fn time_limit_ends_the_run_with_its_last_admissible_iterate() {
    let scene = scene();
    // 20 ms per solve: the clean run makes more than 6 solves (above), so at least 0.12 s; a
    // 0.05 s limit stops it after two or three solves at most, wherever the machine is slow.
    let mut b = Scripted::new(usize::MAX, QpStatus::Solved, Duration::from_millis(20));
    let settings = OuterSettings {
        time_limit_s: Some(0.05),
        ..Default::default()
    };
    let o = run_with(&scene, &mut b, &settings);
    assert_eq!(o.status, RunStatus::TimeLimit);
    // Checked between inner steps: 0.05 s allows at most 3 solves of 20 ms, plus the lazy
    // re-solves of one inner step (3 at most on this scene). Checked only between outer steps,
    // the first step would run to its end: 21 solves (18 inner steps, 3 lazy re-solves).
    assert!(
        b.calls <= 6,
        "{} solves before the time limit stopped the run",
        b.calls
    );
    assert!(
        o.seen.len() >= 2,
        "the step under way is recorded: {:?}",
        o.seen
    );
    assert_last_admissible(&scene, &o);
    // J did not go up from the start. (Not `<`: on a loaded machine the set-up before the
    // first solve can use most of the 0.05 s, and the limit then stops the run before its
    // first step is accepted; measured once while two test suites shared the two cores.)
    assert!(o.energy <= o.seen[0]);

    // A limit that has passed before the first step: the initial state, status time_limit.
    let mut b = Scripted::new(usize::MAX, QpStatus::Solved, Duration::ZERO);
    let settings = OuterSettings {
        time_limit_s: Some(1e-12),
        ..Default::default()
    };
    let o = run_with(&scene, &mut b, &settings);
    assert_eq!(o.status, RunStatus::TimeLimit);
    assert_eq!(o.outer, 0);
    assert_eq!(o.x, scene.x0);
    assert_eq!(b.calls, 0);
}

#[test]
fn a_time_limit_that_is_not_positive_is_an_error() {
    let scene = scene();
    for t in [0.0, -1.0, f64::NAN] {
        let mut b = Scripted::new(usize::MAX, QpStatus::Solved, Duration::ZERO);
        let settings = OuterSettings {
            time_limit_s: Some(t),
            ..Default::default()
        };
        let err = run(
            &scene.mesh,
            &scene.energy,
            scene.eps,
            &scene.x0,
            &mut b,
            &settings,
            &mut |_, _| {},
        )
        .unwrap_err();
        assert!(matches!(err, RunError::BadTimeLimit(_)), "{t}: {err}");
        assert!(err.to_string().contains("time limit"), "{err}");
    }
}

#[test]
fn the_binary_exits_1_on_a_failure_status_with_its_outputs_written() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("failure_exit");
    for (args, status) in [
        (&["--max-outer", "1"][..], "max_outer_iterations"),
        (&["--time-limit", "1e-9"][..], "time_limit"),
    ] {
        let _ = std::fs::remove_dir_all(&dir);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .args(["run", "balloons", "--n", "20", "--quiet", "--out"])
            .arg(&dir)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(status), "{err}");
        let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        assert!(
            summary.contains(&format!("\"status\": \"{status}\"")),
            "{summary}"
        );
        assert!(dir.join("final.vtu").exists() && dir.join("history.csv").exists());
    }
    // `subproblem_failed` names the backend's status and the outer step: Uzawa asked for
    // 1e-13 (its preset is 1e-8) on the balloons n = 12 needs more than its 100 000 dual steps
    // for a QP of outer step 2
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args([
            "run",
            "balloons",
            "--n",
            "12",
            "--backend",
            "uzawa",
            "--qp-tol",
            "1e-13",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "status subproblem_failed; the backend ended max_iterations on a QP of outer step 2"
        ),
        "{err}"
    );
    // bad input stays exit 2
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["run", "balloons", "--time-limit", "-1", "--quiet", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// Clarabel that fails (`NumericalError`) at every solve once its tolerance is set below the
/// preset's: the SQP endgame's tightening meets a backend at its limit.
struct FailsWhenTightened {
    inner: Box<dyn QpBackend>,
    tol0: f64,
    /// Fail with an error (the run ends with it) instead of a failed status.
    error: bool,
}

impl QpBackend for FailsWhenTightened {
    fn name(&self) -> &'static str {
        "fails-when-tightened"
    }
    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        let mut sol = self.inner.solve(qp, warm)?;
        if self.inner.tolerance().is_some_and(|t| t < self.tol0) {
            if self.error {
                return Err(QpError::NotFinite {
                    what: "test: a value at the tightened tolerance",
                    index: 0,
                    value: f64::NAN,
                });
            }
            sol.status = QpStatus::NumericalError;
        }
        Ok(sol)
    }
    fn tolerance(&self) -> Option<f64> {
        self.inner.tolerance()
    }
    fn set_tolerance(&mut self, tol: f64) {
        self.inner.set_tolerance(tol);
    }
}

/// The solids, the SQP method, and Clarabel failing once tightened (`error`: with an error).
fn sqp_solids_failing_when_tightened(
    error: bool,
) -> (contactlab::scene::Scene, FailsWhenTightened, OuterSettings) {
    use contactlab::scene::solids::{build, SolidsParams};
    use contactlab::solve::sqp::OuterMethod;
    let scene = build(&SolidsParams::default()).unwrap();
    let inner = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
    let tol0 = inner.tolerance().unwrap();
    let settings = OuterSettings {
        method: OuterMethod::Sqp,
        ..Default::default()
    };
    (scene, FailsWhenTightened { inner, tol0, error }, settings)
}

/// The solids with the SQP method tighten the tolerance once (tests/sqp.rs); when the backend
/// then fails, the run does not end `subproblem_failed`: it stops at the state where the
/// stopping rule held, with the run's tolerance back, admissible, its status the
/// certificate's (here `fixed_point`: that state's κ is above tol_κ).
#[test]
fn a_backend_failing_at_the_tightened_tolerance_ends_the_sqp_run_at_its_last_state() {
    let (scene, mut b, settings) = sqp_solids_failing_when_tightened(false);
    let tol0 = b.tol0;
    let mut last = f64::INFINITY;
    let res = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        &mut b,
        &settings,
        &mut |r, _| last = r.energy,
    )
    .unwrap();
    assert!(
        res.qp_tol_tightened.is_some(),
        "the endgame did not tighten"
    );
    assert_eq!(
        res.status,
        RunStatus::FixedPoint,
        "κ {:e}",
        res.certificate.kappa
    );
    assert_eq!(b.tolerance(), Some(tol0));
    assert!(res.energy <= last);
    let d = min_distance(&scene.mesh, &res.x, 2.0 * scene.eps, true).distance;
    assert!(d >= scene.eps * (1.0 - 1e-12), "distance {d:e}");
}

/// A run that ends with an error after the SQP endgame tightened the backend's tolerance
/// still gives the caller the backend back at its own tolerance.
#[test]
fn the_backend_tolerance_is_restored_when_the_run_ends_with_an_error() {
    let (scene, mut b, settings) = sqp_solids_failing_when_tightened(true);
    let tol0 = b.tol0;
    let err = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        &mut b,
        &settings,
        &mut |_, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("tightened tolerance"), "{err}");
    assert_eq!(b.tolerance(), Some(tol0));
}
