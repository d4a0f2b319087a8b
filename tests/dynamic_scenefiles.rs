//! `contactlab run FILE.toml --dynamic`: a scene file runs through the same stepping as the
//! built-in dynamic scenes, with masses from its bodies' `density`, initial velocities from
//! `velocity`, and `[dynamics]` defaults that the command line overrides; a moving body
//! without a density is refused with its name; `drop` written as a scene file takes the same
//! time steps as the built-in `drop`.

use contactlab::scene::dynamic::{drop, DropParams, DynamicScene};
use contactlab::scene::file;
use contactlab::solve::dynamics::{
    lumped_mass, simulate, DynamicResult, DynamicSettings, Scheme, System,
};
use contactlab::solve::outer::OuterSettings;
use contactlab_solvers::{backend_from_name, default_settings};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(name)
}

fn contactlab(args: &[&str], out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(args)
        .args(["--quiet", "--out"])
        .arg(out)
        .output()
        .unwrap()
}

/// history.csv as (header, rows of fields).
fn history(dir: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

fn column<'a>(header: &[String], rows: &'a [Vec<String>], name: &str) -> Vec<&'a str> {
    let k = header
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("column {name} missing from {header:?}"));
    rows.iter().map(|r| r[k].as_str()).collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn dynamic_scenefile_string_dropped_on_a_fixed_floor_runs_through_the_binary() {
    let file = data("tests/data/dynamic_string.toml");
    let file = file.to_str().unwrap();
    let tmp = std::env::temp_dir().join(format!("contactlab_dyn_file_{}", std::process::id()));
    // the command line overrides [dynamics] (5 steps, newmark)
    let dir = tmp.join("euler");
    let o = contactlab(
        &[
            "run",
            file,
            "--dynamic",
            "--steps",
            "20",
            "--scheme",
            "euler",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let (header, rows) = history(&dir);
    assert_eq!(rows.len(), 21, "step 0 and 20 steps");
    for col in [
        "kinetic",
        "elastic",
        "potential",
        "total",
        "momentum_x",
        "momentum_y",
    ] {
        assert!(header.iter().any(|c| c == col), "{col} missing: {header:?}");
    }
    assert!(column(&header, &rows, "admissible")
        .iter()
        .all(|&a| a == "true"));
    // the string lands: some step has an active contact with a positive force
    let active: Vec<usize> = column(&header, &rows, "active_contacts")
        .iter()
        .map(|a| a.parse().unwrap())
        .collect();
    let first = active
        .iter()
        .position(|&a| a > 0)
        .expect("no contact in 20 steps");
    let force: f64 = column(&header, &rows, "contact_force")[first]
        .parse()
        .unwrap();
    assert!(force > 0.0, "step {first}: force {force}");
    // velocity = [0, -1] on a string of length 0.9 and density 1: P_0 = (0, -0.9)
    let p = |c: &str| -> f64 { column(&header, &rows, c)[0].parse().unwrap() };
    assert_eq!(p("momentum_x"), 0.0);
    assert!(
        (p("momentum_y") + 0.9).abs() <= 1e-15,
        "{}",
        p("momentum_y")
    );
    assert!((p("kinetic") - 0.45).abs() <= 1e-15, "{}", p("kinetic"));
    let s = summary(&dir);
    assert_eq!(s["scene"], "dynamic_string");
    assert_eq!(s["steps"], 20);
    assert_eq!(s["scheme"], "euler");
    assert_eq!(s["dt"], 0.01);
    assert_eq!(s["density"], serde_json::json!([0.0, 1.0]));
    assert_eq!(s["metrics"]["all_admissible"], true);
    // without flags: the file's [dynamics] (5 steps of Newmark)
    let dir = tmp.join("file");
    let o = contactlab(&["run", file, "--dynamic"], &dir);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (_, rows) = history(&dir);
    assert_eq!(rows.len(), 6);
    let s = summary(&dir);
    assert_eq!(
        (s["steps"].as_u64(), s["scheme"].as_str()),
        (Some(5), Some("newmark"))
    );
    let _ = std::fs::remove_dir_all(&tmp);
}

#[test]
fn dynamic_scenefile_moving_body_without_density_is_refused() {
    let file = data("tests/data/dynamic_no_density.toml");
    let file = file.to_str().unwrap();
    let good = data("tests/data/dynamic_string.toml");
    let good = good.to_str().unwrap();
    let dir = std::env::temp_dir().join(format!("contactlab_dyn_nodens_{}", std::process::id()));
    for (args, needles) in [
        (
            vec!["run", file, "--dynamic", "--dt", "0.01", "--steps", "3"],
            vec![
                "dynamic_no_density.toml:14",
                "body[1].density = (missing)",
                "body \"string\" has free vertices",
            ],
        ),
        (
            vec!["run", file, "--dynamic", "--steps", "3"],
            vec!["dynamic_no_density.toml", "--dt", "[dynamics]"],
        ),
        (
            vec!["run", file, "--dynamic", "--dt", "0.01"],
            vec!["dynamic_no_density.toml", "--steps", "[dynamics]"],
        ),
        (
            vec!["run", good, "--dynamic", "--dt", "0", "--steps", "3"],
            vec!["dt must be finite and > 0, got 0"],
        ),
        (
            vec!["run", good, "--dynamic", "--scheme", "rk4"],
            vec!["--scheme \"rk4\""],
        ),
    ] {
        let o = contactlab(&args, &dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n:?} missing from {err}");
        }
    }
    // the same file runs statically: no mass is needed there
    let o = contactlab(&["run", file], &dir);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn steps(ds: &mut DynamicScene, steps: usize) -> DynamicResult {
    let mut b = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
    let mass = lumped_mass(&ds.scene.mesh, &ds.scene.mesh.x_ref, &ds.density).unwrap();
    let mut system = System {
        mesh: &ds.scene.mesh,
        energy: &mut ds.scene.energy,
        eps: ds.scene.eps,
        mass,
    };
    let settings = DynamicSettings {
        dt: ds.dt,
        steps,
        scheme: Scheme::Euler,
    };
    simulate(
        &mut system,
        &ds.scene.x0,
        &ds.v0,
        b.as_mut(),
        &OuterSettings::default(),
        &settings,
        &mut |_, _, _| {},
    )
    .unwrap()
}

/// `experiments/scenes/drop.toml` (written by `export_scenes`) against the built-in `drop`:
/// the same masses, Δt and steps, and the first 15 steps (the impact is at step 10) with the
/// same outer iterations per step and the same energies and positions to round-off.
#[test]
fn dynamic_scenefile_drop_twin_takes_the_same_steps() {
    let mut f = file::load(&data("experiments/scenes/drop.toml"))
        .unwrap()
        .into_dynamic()
        .unwrap();
    let mut b = drop(&DropParams::default()).unwrap();
    assert_eq!(f.scene.mesh.x_ref, b.scene.mesh.x_ref);
    assert_eq!(f.scene.mesh.fixed, b.scene.mesh.fixed);
    assert_eq!((f.dt, f.steps), (b.dt, b.steps));
    assert_eq!(f.density, b.density);
    assert_eq!(f.v0, b.v0);
    let (mf, mb) = (
        lumped_mass(&f.scene.mesh, &f.scene.mesh.x_ref, &f.density).unwrap(),
        lumped_mass(&b.scene.mesh, &b.scene.mesh.x_ref, &b.density).unwrap(),
    );
    for (p, q) in mf.iter().zip(&mb) {
        assert!(
            (p - q).abs() <= 1e-15 * q.abs().max(1e-300),
            "mass {p} vs {q}"
        );
    }
    let (rf, rb) = (steps(&mut f, 15), steps(&mut b, 15));
    assert_eq!(rf.steps, 15);
    assert_eq!(rb.steps, 15);
    assert!(
        rb.records.iter().any(|r| r.active_contacts > 0),
        "no impact in 15 steps"
    );
    for (p, q) in rf.records.iter().zip(&rb.records) {
        assert_eq!(p.outer_iterations, q.outer_iterations, "step {}", q.step);
        assert_eq!(p.status, q.status, "step {}", q.step);
        assert_eq!(p.active_contacts, q.active_contacts, "step {}", q.step);
        assert!(
            (p.total - q.total).abs() <= 1e-12 * q.total.abs(),
            "step {}: E {} vs {}",
            q.step,
            p.total,
            q.total
        );
    }
    let scale = rb.state.x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (p, q) in rf.state.x.iter().zip(&rb.state.x) {
        assert!((p - q).abs() <= 1e-12 * scale, "x {p} vs {q}");
    }
}
