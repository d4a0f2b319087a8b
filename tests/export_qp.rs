//! `contactlab export-qp`: every QPS file it writes is read back by the project's reader and
//! equals, bit for bit, the QP the run solved (captured in-process by the same deterministic
//! run).

use contactlab::harness::capture::Capture;
use contactlab::scene::ring::{build, RingParams};
use contactlab::solve::outer::{run, OuterSettings, Pruning};
use contactlab::solve::settings::Accuracy;
use contactlab_solvers::qps::read_qps_file;
use contactlab_solvers::{backend_from_name, Qp, QpError, QpSolution};
use std::path::Path;
use std::process::Command;

#[test]
fn exported_qps_files_read_back_to_the_solved_qps() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("export_qp");
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["export-qp", "ring", "--n", "20", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // the same run in-process, with the settings export-qp uses (clarabel, default, lazy)
    let scene = build(&RingParams {
        n: 20,
        ..Default::default()
    })
    .unwrap();
    let acc = Accuracy::Default;
    let mut inner = backend_from_name("clarabel", &acc.qp_settings("clarabel")).unwrap();
    let mut captured: Vec<Qp> = Vec::new();
    let mut sink = |_: usize, qp: &Qp, _: &Result<QpSolution, QpError>| captured.push(qp.clone());
    {
        let mut cap = Capture::new(inner.as_mut(), &mut sink);
        let settings = OuterSettings {
            tol_j: acc.tol_j(),
            max_outer: 2000,
            pruning: Pruning::Lazy,
            ..Default::default()
        };
        run(
            &scene.mesh,
            &scene.energy,
            scene.eps,
            &scene.x0,
            &mut cap,
            &settings,
            &mut |_, _| {},
        )
        .unwrap();
    }
    let index = std::fs::read_to_string(dir.join("index.csv")).unwrap();
    let files: Vec<String> = index
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().to_string())
        .collect();
    assert_eq!(files.len(), captured.len(), "index.csv rows vs QPs solved");
    assert!(captured.len() >= 5, "only {} QPs", captured.len());
    let mut with_rows = 0;
    for (k, (file, qp)) in files.iter().zip(&captured).enumerate() {
        let (name, back) = read_qps_file(&dir.join(file)).unwrap();
        assert_eq!(name, file.trim_end_matches(".qps"));
        back.validate().unwrap();
        assert_eq!(&back, qp, "QP {k} ({file}) differs after the round trip");
        if back.m() > 0 {
            with_rows += 1;
        }
    }
    assert!(with_rows > 0, "no exported QP has contact rows");
}
