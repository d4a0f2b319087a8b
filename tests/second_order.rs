//! The second-order check in `summary.json` (docs/method.md, "The second-order check"): the
//! asymmetric balloons' certified state is a strict local minimum; the rod's certified state
//! under the default method is not a minimum: the check finds a lower admissible point along
//! its negative mode, and by default the run goes on from that point to a strict minimum; a
//! sweep file that asks for the check gets its columns (the check's own construction is
//! tested against a closed form in `src/solve/second_order.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("contactlab-second-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `contactlab run ARGS --quiet --out DIR` and returns summary.json.
fn run(args: &[&str], dir: &Path) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .arg("run")
        .args(args)
        .args(["--quiet", "--frame-every", "1000000", "--out"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        o.status.code().is_some(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn second_order_asymmetric_balloons_end_at_a_strict_minimum() {
    let d = tmp("balloons");
    let s = run(
        &["balloons", "--n", "40", "--heights", "0.9,0.2,0.9,0.2"],
        &d,
    );
    assert_eq!(s["status"], "converged");
    let so = &s["second_order"];
    assert_eq!(so["status"], "minimum", "{so}");
    assert!(so["min_eigenvalue_rel"].as_f64().unwrap() > 1e-8, "{so}");
    assert_eq!(so["negative_modes"], 0);
    assert!(so["strongly_active"].as_u64().unwrap() > 0);
}

#[test]
fn second_order_rod_certified_state_is_not_a_minimum() {
    // measured: κ 1.4e-7 (converged), one negative mode of the restricted Hessian, and an
    // admissible point h̄/4 (0.0088) away along it whose J is 2.3e-6 lower
    let d = tmp("rod");
    let s = run(&["rod", "--n", "8", "--no-escape-saddles"], &d);
    assert_eq!(s["status"], "converged");
    let so = &s["second_order"];
    assert_eq!(so["status"], "not_minimum", "{so}");
    assert!(so["min_eigenvalue_rel"].as_f64().unwrap() < -1e-8, "{so}");
    assert!(so["negative_modes"].as_u64().unwrap() >= 1);
    let dj = so["descent_decrease"].as_f64().unwrap();
    let t = so["descent_step"].as_f64().unwrap();
    let h = s["h"].as_f64().unwrap();
    assert!(dj > 0.0 && t > 0.0 && t <= 0.5 * h, "{so}");
    // the decrease is far above J's round-off
    let j = s["final_energy"].as_f64().unwrap();
    assert!(dj > 1e-9 * j.abs(), "{dj} against J = {j}");
    assert_eq!(s["escapes"], 0);
    assert_eq!(s["escape_saddles"], false);

    // by default the run goes on from the lower point, to a certified strict minimum below
    // the saddle (measured: one escape, J 3.0e-4 lower); `--escape-saddles` says the same
    let d = tmp("rod-escape");
    let e = run(&["rod", "--n", "8"], &d);
    assert_eq!(e["escape_saddles"], true);
    assert_eq!(e["second_order_max_dofs"], 1200);
    assert_eq!(e["status"], "converged");
    assert!(e["escapes"].as_u64().unwrap() >= 1);
    assert_eq!(
        e["second_order"]["status"], "minimum",
        "{}",
        e["second_order"]
    );
    let je = e["final_energy"].as_f64().unwrap();
    assert!(je < j - dj, "{je} against the saddle's {j} − {dj}");
    assert_eq!(e["energy_monotone"], true);
    assert_eq!(e["all_iterates_admissible"], true);
    let hist = std::fs::read_to_string(d.join("history.csv")).unwrap();
    let escape_rows = hist.lines().filter(|l| l.contains(",escape,")).count();
    assert_eq!(escape_rows as u64, e["escapes"].as_u64().unwrap());
    // every certificate the run computed is counted, at the saddle and at the end at least,
    // and `certificate.seconds` is the last one's share of their total
    let calls = e["certificate_calls"].as_u64().unwrap();
    assert!(
        calls > e["escapes"].as_u64().unwrap(),
        "{calls} certificates"
    );
    let total = e["certificate_seconds"].as_f64().unwrap();
    assert!(
        total >= e["certificate"]["seconds"].as_f64().unwrap(),
        "{total} s"
    );
}

#[test]
fn second_order_not_computed_for_large_runs_and_absent_without_a_fixed_point() {
    // hertz2d_elastic has 3491 free dofs: above the dense check's size
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments/scenes/benchmarks/hertz2d_elastic.toml");
    let d = tmp("hertz");
    let s = run(&[scene.to_str().unwrap()], &d);
    assert_eq!(s["second_order"]["status"], "not_computed");
    assert_eq!(s["second_order"]["free_dofs"], 3491);
    // and the rod n = 8 below a bound of 100: not computed, so no escape either (it stops
    // at the saddle, 15 outer steps, as with --no-escape-saddles)
    let d = tmp("bound");
    let s = run(&["rod", "--n", "8", "--second-order-max-dofs", "100"], &d);
    assert_eq!(s["second_order"]["status"], "not_computed");
    assert_eq!(s["second_order"]["free_dofs"], 525);
    assert_eq!(s["escapes"], 0);
    // --escape-saddles and --no-escape-saddles together: refused
    refused(
        &["rod", "--escape-saddles", "--no-escape-saddles"],
        "--no-escape-saddles",
    );
    // a run stopped by its outer-step limit is at no fixed point: no check
    let d = tmp("limit");
    let s = run(
        &[
            "balloons",
            "--n",
            "40",
            "--heights",
            "0.9,0.2,0.9,0.2",
            "--max-outer",
            "2",
        ],
        &d,
    );
    assert_eq!(s["status"], "max_outer_iterations");
    assert!(s["second_order"].is_null(), "{}", s["second_order"]);
    // the escape is an option of static runs: refused by name with --dynamic
    refused(
        &["drop", "--dynamic", "--escape-saddles"],
        "--escape-saddles is an option of static runs",
    );
}

/// `contactlab run ARGS` exits with the usage-error code 2 and a message that contains `want`.
fn refused(args: &[&str], want: &str) {
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .arg("run")
        .args(args)
        .args(["--quiet", "--out"])
        .arg(tmp("refused"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(want), "{err}");
}

const SWEEP: &str = r#"
name = "second order"
[defaults]
backends = ["ip"]
accuracy = ["default"]
outer_method = "auto"
second_order_max_dofs = 1200
escape_saddles = true
[[scene]]
name = "rod"
n = [8]
[[scene]]
name = "rod"
n = [8]
escape_saddles = false
"#;

fn sweep_file(d: &Path, text: &str) -> std::process::Output {
    std::fs::write(d.join("s.toml"), text).unwrap();
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args([
            "sweep", "s.toml", "--quiet", "--jobs", "1", "--out", "s.csv",
        ])
        .current_dir(d)
        .output()
        .unwrap()
}

#[test]
fn second_order_in_sweep_rows() {
    // a sweep that asks for the check has its columns after the published ones, and escapes
    // where escape_saddles says so: the rod n = 8 as `contactlab run` (measured: 26 outer
    // steps, one escape, a strict minimum; without the escape 15 steps at the saddle)
    let d = tmp("sweep");
    std::fs::create_dir_all(&d).unwrap();
    let o = sweep_file(&d, SWEEP);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut r = csv::Reader::from_path(d.join("s.csv")).unwrap();
    let hdr: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        &hdr[hdr.len() - 4..],
        ["second_order", "min_eigenvalue_rel", "free_dofs", "escapes"]
    );
    let col = |name: &str| hdr.iter().position(|h| h == name).unwrap();
    let recs: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(recs.len(), 2);
    let (esc, stay) = if recs[0].get(0).unwrap().ends_with("|escape") {
        (&recs[0], &recs[1])
    } else {
        (&recs[1], &recs[0])
    };
    for rec in [esc, stay] {
        assert_eq!(&rec[col("status")], "converged");
        assert_eq!(&rec[col("free_dofs")], "525");
    }
    assert_eq!(&stay[col("second_order")], "not_minimum");
    assert_eq!(&stay[col("escapes")], "0");
    assert_eq!(&esc[col("second_order")], "minimum");
    assert_eq!(&esc[col("escapes")], "1");
    let j = |rec: &csv::StringRecord| rec[col("final_energy")].parse::<f64>().unwrap();
    assert!(j(esc) < j(stay), "{} against {}", j(esc), j(stay));
    let lam: f64 = esc[col("min_eigenvalue_rel")].parse().unwrap();
    assert!(lam > 1e-8, "{lam}");

    // escape_saddles without the check, and the check on a dynamic block: refused by name
    for (text, want) in [
        (
            "name = \"x\"\n[[scene]]\nname = \"rod\"\nn = [8]\nescape_saddles = true\n",
            "escape_saddles set without second_order_max_dofs",
        ),
        (
            "name = \"x\"\n[[scene]]\nname = \"drop\"\nn = [4]\ndynamic = true\ndt = [0.1]\n\
             steps = 2\nsecond_order_max_dofs = 100\n",
            "apply to static runs only",
        ),
    ] {
        let _ = std::fs::remove_file(d.join("s.csv"));
        let o = sweep_file(&d, text);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{err}");
    }
}
