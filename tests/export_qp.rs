//! `contactlab export-qp`: every QPS file it writes is read back by the project's reader and
//! equals, bit for bit, the QP the run solved (captured in-process by the same deterministic
//! run). Both the export and the in-process run go through the library (`harness::export`,
//! `harness::case`), so the test runs the command's own code, not a copy of its settings.

use contactlab::harness::capture::Capture;
use contactlab::harness::case::{execute_with, CaseSettings};
use contactlab::harness::export::{cmd_export, ExportArgs};
use contactlab::scene::registry::build_scene;
use contactlab::solve::outer::Pruning;
use contactlab::solve::settings::Accuracy;
use contactlab_solvers::qps::read_qps_file;
use contactlab_solvers::{backend_from_name, Qp, QpError, QpSolution};
use std::path::Path;

#[test]
fn exported_qps_files_read_back_to_the_solved_qps() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("export_qp");
    let _ = std::fs::remove_dir_all(&dir);
    cmd_export(&ExportArgs {
        scene: "ring".into(),
        n: 20,
        eps: None,
        params: Vec::new(),
        backend: "clarabel".into(),
        accuracy: "default".into(),
        pruning: "lazy".into(),
        max_outer: 2000,
        out: dir.clone(),
    })
    .unwrap();

    // the same run in-process, with the settings export-qp uses (clarabel, default, lazy)
    let scene = build_scene("ring", 20, None, &Default::default()).unwrap();
    let acc = Accuracy::Default;
    let cs = CaseSettings {
        backend: "clarabel".into(),
        accuracy: acc,
        pruning: Pruning::Lazy,
        tol_j: None,
        max_outer: 2000,
        max_inner: None,
        newton_model: Default::default(),
        outer_method: Default::default(),
        sqp_curvature: Default::default(),
        sqp_normal_stiffness: 0.0,
        sqp_drop_endpoint_rows: false,
        sqp_extend_rows: false,
        sqp_drop_vertex_rows: false,
        sqp_drop_side_rows: false,
        sqp_extend_fixed: false,
        sqp_path_rows: false,
        sqp_implying_rows: false,
        sqp_extrapolate: 0,
        sqp_normal_active_rel: 0.0,
        sqp_edge_edge_stiffness: 0.0,
        second_order_max_dofs: 0,
        escape_saddles: false,
        time_limit_s: None,
    };
    let mut inner = backend_from_name("clarabel", &acc.qp_settings("clarabel")).unwrap();
    let mut captured: Vec<Qp> = Vec::new();
    let mut sink = |_: usize, qp: &Qp, _: &Result<QpSolution, QpError>| captured.push(qp.clone());
    {
        let mut cap = Capture::new(inner.as_mut(), &mut sink);
        execute_with(&scene, &cs, &mut cap, &mut |_, _| {}).unwrap();
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
