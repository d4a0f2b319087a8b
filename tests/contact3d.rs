//! The 3D engine on the 3D scenes: every iterate passes the exact ALL-PAIRS 3D
//! admissibility check (the O(N²) [`min_distance_brute_force`], not the broad phase the loop uses) and J
//! never increases, with lazy rows and with the trust region; the backends' final energies;
//! and a `contactlab run` directory of a 3D scene.

use contactlab::contact::{min_distance_brute_force, MinDistance};
use contactlab::scene::balloons3d::{self, Balloons3dParams};
use contactlab::scene::rod::{self, RodParams};
use contactlab::scene::sheets::{self, SheetsParams};
use contactlab::scene::solids::{self, SolidsParams};
use contactlab::scene::Scene;
use contactlab::solve::outer::{run, OuterSettings, Pruning, RunStatus, TrustSettings};
use contactlab::solve::settings::{tol_kappa, Accuracy};
use contactlab::solve::sqp::OuterMethod;
use contactlab_solvers::backend_from_name;
use std::process::Command;

struct Trace {
    status: RunStatus,
    kappa: f64,
    iterates: usize,
    energy: f64,
    min_distance: f64,
}

/// Runs `scene` and checks every iterate against the exact all-pairs distance and the energy
/// against the previous iterate's.
fn checked_run(
    scene: &Scene,
    backend: &str,
    accuracy: Accuracy,
    pruning: Pruning,
    max_outer: usize,
) -> Trace {
    checked_run_with(
        scene,
        backend,
        accuracy,
        OuterSettings {
            max_outer,
            pruning,
            method: OuterMethod::Pantz,
            ..Default::default()
        },
    )
}

/// [`checked_run`] with the outer settings given (their `tol_j` replaced by the preset's).
fn checked_run_with(
    scene: &Scene,
    backend: &str,
    accuracy: Accuracy,
    settings: OuterSettings,
) -> Trace {
    let mesh = &scene.mesh;
    assert_eq!(mesh.dim, 3);
    let pruning = settings.pruning;
    let settings = OuterSettings {
        tol_j: accuracy.tol_j(),
        tol_kappa: tol_kappa(accuracy.tol_j()),
        qp_tol: accuracy.qp_tol(backend),
        ..settings
    };
    let mut b = backend_from_name(backend, &accuracy.qp_settings(backend)).unwrap();
    let d0 = min_distance_brute_force(mesh, &scene.x0).distance;
    assert!(d0 >= scene.eps, "{}: x0 at {d0} < eps", scene.name);
    let mut j_prev = scene.energy.value(&scene.x0);
    let mut iterates = 0;
    let res = run(
        mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        b.as_mut(),
        &settings,
        &mut |r, x| {
            let MinDistance { distance: d, pair } = min_distance_brute_force(mesh, x);
            assert!(
                d >= scene.eps,
                "{} {backend} {pruning:?}: iterate {} inadmissible: {pair:?} at {d:.6e} < eps {:.6e}",
                scene.name,
                r.iteration,
                scene.eps
            );
            assert!(
                r.energy <= j_prev,
                "{} {backend} {pruning:?}: J increased at iterate {}: {} > {j_prev}",
                scene.name,
                r.iteration,
                r.energy
            );
            j_prev = r.energy;
            iterates += 1;
        },
    )
    .unwrap();
    Trace {
        status: res.status,
        kappa: res.certificate.kappa,
        iterates,
        energy: res.energy,
        min_distance: res.min_distance.distance,
    }
}

fn scenes() -> Vec<Scene> {
    vec![
        rod::build(&RodParams::default()).unwrap(),
        sheets::build(&SheetsParams::default()).unwrap(),
        solids::build(&SolidsParams::default()).unwrap(),
    ]
}

/// The three scenes stop on the stopping rule at fixed points of Pantz's iteration whose
/// certificate does not hold (measured at the default preset, lazy rows: κ = 3.5e-3 rod,
/// 2.8e-3 sheets, 9.1e-2 solids; the trust region: 3.6e-3, 2.8e-3, 9.6e-2): the outer
/// iteration creeps there (docs/known-gaps.md). They were reported `converged` before the
/// certificate.
fn assert_fixed_point(t: &Trace, name: &str) {
    assert_eq!(t.status, RunStatus::FixedPoint, "{name}");
    assert!(t.kappa >= 1e-3, "{name}: κ = {:e}", t.kappa);
}

#[test]
fn every_3d_iterate_is_admissible_and_j_never_increases_lazy() {
    for scene in scenes() {
        let t = checked_run(&scene, "clarabel", Accuracy::Default, Pruning::Lazy, 200);
        if scene.name == "sheets" {
            // The sheets creep under the outer map of §3 (J falling by about 1/k per step;
            // docs/known-gaps.md): whether the stopping rule fires within 200 steps depends on
            // how exactly each QP is solved. What is checked here, every iterate admissible
            // and J never increasing, holds along the whole run whichever way it ends; where
            // it stops it is not a minimum.
            assert!(
                matches!(
                    t.status,
                    RunStatus::FixedPoint | RunStatus::MaxOuterIterations
                ),
                "sheets: {:?}",
                t.status
            );
            assert!(t.kappa >= 1e-3, "sheets: κ = {:e}", t.kappa);
        } else {
            assert_fixed_point(&t, &scene.name);
        }
        assert!(t.iterates >= 2, "{}: {} iterates", scene.name, t.iterates);
        // the bodies end in contact: some pair at ε
        assert!(
            t.min_distance < 1.001 * scene.eps,
            "{}: min distance {} vs eps {}",
            scene.name,
            t.min_distance,
            scene.eps
        );
    }
}

#[test]
fn every_balloons3d_iterate_is_admissible_and_j_never_increases() {
    // The first 40 of its ~150 outer steps (the whole run takes ~12 s here): the balloons
    // inflate against the box and each other within them.
    let scene = balloons3d::build(&Balloons3dParams::default()).unwrap();
    let t = checked_run(&scene, "clarabel", Accuracy::Default, Pruning::Lazy, 40);
    assert_eq!(t.iterates, 41); // x0 and 40 steps
    assert!(t.min_distance < 1.001 * scene.eps, "{}", t.min_distance);
}

#[test]
fn trust_region_3d_iterates_pass_the_all_pairs_check() {
    // δ0 = h̄/10: the default δ0 = h̄ reaches 2√3·h̄ in 3D, nearly every pair of these small
    // meshes (the solids' first step: 61 209 pairs, 21 s of Clarabel). Where the runs stop is
    // measured in docs/measurements.md, not asserted here: the trust region ends the solids at a J
    // 2.5e-3 above the lazy rows' (both fixed points whose certificate does not hold).
    for scene in scenes() {
        let t = checked_run_with(
            &scene,
            "clarabel",
            Accuracy::Default,
            OuterSettings {
                pruning: Pruning::TrustRegion,
                trust: TrustSettings {
                    delta0: 0.1,
                    ..Default::default()
                },
                max_outer: 100,
                method: OuterMethod::Pantz,
                ..Default::default()
            },
        );
        assert_fixed_point(&t, &scene.name);
        assert!(t.iterates >= 3, "{}: {} iterates", scene.name, t.iterates);
    }
}

#[test]
fn backends_agree_on_the_3d_final_energies() {
    // Measured (docs/measurements.md, results/backends.csv): the rod and the solids agree to relative
    // 1e-6 at the default preset; the sheets and balloons3d do not (see there). All three
    // backends stop at the same fixed point above the minimum, and agree on its certificate
    // (measured κ: rod 3.512e-3, 3.512e-3, 3.511e-3; solids 9.128e-2, 9.127e-2, 9.127e-2).
    for scene in [
        rod::build(&RodParams::default()).unwrap(),
        solids::build(&SolidsParams::default()).unwrap(),
    ] {
        let mut kappas = Vec::new();
        let e: Vec<(&str, f64)> = ["clarabel", "osqp", "uzawa"]
            .into_iter()
            .map(|b| {
                let t = checked_run(&scene, b, Accuracy::Default, Pruning::Lazy, 200);
                assert_fixed_point(&t, &format!("{} {b}", scene.name));
                kappas.push(t.kappa);
                (b, t.energy)
            })
            .collect();
        let (klo, khi) = kappas
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &k| (a.min(k), b.max(k)));
        assert!(khi - klo <= 1e-2 * klo, "{}: κ {kappas:?}", scene.name);
        let lo = e.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let hi = e.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        assert!(
            (hi - lo) / lo.abs() < 1e-6,
            "{}: final energies {e:?} spread {:.2e}",
            scene.name,
            (hi - lo) / lo.abs()
        );
    }
}

#[test]
fn run_directory_of_a_3d_scene() {
    let dir = std::env::temp_dir().join(format!("contactlab-3d-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for (scene, cells) in [("solids", "10"), ("rod", "3")] {
        let out = dir.join(scene);
        let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .args(["run", scene, "--outer-method", "pantz", "--quiet", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        // both stop at a fixed point whose certificate does not hold: exit code 1, the run
        // directory written
        assert_eq!(
            o.status.code(),
            Some(1),
            "{scene}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(String::from_utf8_lossy(&o.stderr).contains("fixed_point"));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["dim"], 3, "{scene}");
        assert_eq!(summary["scene"], scene);
        assert_eq!(summary["status"], "fixed_point");
        let kappa = summary["certificate"]["kappa"].as_f64().unwrap();
        assert!(kappa >= 1e-3, "{scene}: κ = {kappa}");
        assert_eq!(summary["all_iterates_admissible"], true);
        assert_eq!(summary["energy_monotone"], true);
        assert!(
            summary["diagnostics"]["residual_hm1"].is_number(),
            "{scene}"
        );
        let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
        let k = summary["outer_iterations"].as_u64().unwrap() as usize;
        assert_eq!(
            hist.lines().count(),
            k + 2,
            "{scene}: header + iterates 0..=k"
        );
        let last = std::fs::read_to_string(out.join(format!("frames/frame_{k:05}.vtu"))).unwrap();
        // the cell types: VTK_TETRA (10) for the solids, VTK_LINE (3) for the rod's curve
        let types = last
            .split("Name=\"types\"")
            .nth(1)
            .and_then(|s| s.split('>').nth(1))
            .and_then(|s| s.split('<').next())
            .unwrap();
        assert!(
            types.split_whitespace().any(|t| t == cells),
            "{scene}: no cell of type {cells}"
        );
        let pvd = std::fs::read_to_string(out.join("frames.pvd")).unwrap();
        assert!(pvd.contains(&format!("frames/frame_{k:05}.vtu")));
        let svg = std::fs::read_to_string(out.join("shapes.svg")).unwrap();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"));
        if scene == "solids" {
            assert!(svg.contains("<polygon"), "solids: no face drawn");
        } else {
            assert!(svg.contains("<line"), "rod: no edge drawn");
        }
        let mult = std::fs::read_to_string(out.join("multipliers.csv")).unwrap();
        assert!(mult.starts_with("kind,first,second,rows,distance,w0,w1,w2,w3"));
        assert!(
            mult.lines().count() > 1,
            "{scene}: no pair in multipliers.csv"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_rejects_options_of_other_scenes_by_name() {
    for (args, needle) in [
        (vec!["run", "solids", "--c", "3"], "--c"),
        (vec!["run", "rod", "--param", "bogus=1"], "bogus"),
        (vec!["run", "sheets", "--heights", "1,1,1,1"], "--heights"),
        (
            vec!["run", "sheets", "--param", "lower_fixed=2"],
            "lower_fixed",
        ),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .args(&args)
            .args(["--quiet", "--out", "/nonexistent/never-written"])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}
