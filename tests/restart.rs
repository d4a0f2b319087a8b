//! `contactlab run … --start-from FILE [--start-perturb A]`: a run started from a perturbed
//! copy of a certified end state returns to the same energy, and bad starts are refused by
//! name (src/harness/restart.rs).
//!
//! The return is tested with the SQP method: from the same perturbed start (balloons n = 20,
//! A = 0.05) Pantz's method creeps for 711 outer steps to a fixed point 9.8e-5 above the
//! minimum (κ 6.2e-4), the SQP method is back within 1e-9 in 11 steps (docs/method.md).

use std::path::{Path, PathBuf};
use std::process::Command;

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("contactlab_restart_{tag}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn run(args: &[&str], out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args([
            "run",
            "balloons",
            "--n",
            "20",
            "--quiet",
            "--frame-every",
            "1000",
        ])
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn a_perturbed_certified_end_state_returns_to_the_same_energy() {
    let first = dir("first");
    let o = run(&[], &first);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s0 = summary(&first);
    assert_eq!(s0["status"], "converged");
    let j0 = s0["final_energy"].as_f64().unwrap();
    let again = dir("again");
    let start = first.join("final.vtu");
    let o = run(
        &[
            "--start-from",
            start.to_str().unwrap(),
            "--start-perturb",
            "0.05",
            "--outer-method",
            "sqp",
        ],
        &again,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s1 = summary(&again);
    assert_eq!(s1["status"], "converged");
    let a = s1["params"]["start_perturb"].as_f64().unwrap();
    assert!(a > 0.0 && a <= 0.05, "amplitude used {a}");
    // the start was perturbed: its energy is above the end state's
    let j_start = s1["initial_energy"].as_f64().unwrap();
    assert!(j_start > j0, "start J {j_start} vs end J {j0}");
    let j1 = s1["final_energy"].as_f64().unwrap();
    assert!(
        (j1 - j0).abs() <= 1e-8 * j0.abs(),
        "restart ends at {j1}, the first run at {j0}"
    );
}

#[test]
fn bad_starts_are_refused_by_name() {
    let out = dir("bad");
    let o = run(&["--start-perturb", "0.1"], &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--start-from"));
    let missing = out.join("nowhere.vtu");
    let o = run(&["--start-from", missing.to_str().unwrap()], &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nowhere.vtu"));
    // a state of another level
    let other = dir("other");
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["run", "balloons", "--n", "8", "--quiet", "--out"])
        .arg(&other)
        .output()
        .unwrap();
    assert!(o.status.success());
    let f = other.join("final.vtu");
    let o = run(&["--start-from", f.to_str().unwrap()], &out);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("points, but the scene"), "{err}");
}
