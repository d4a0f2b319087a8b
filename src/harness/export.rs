//! `contactlab export-qp SCENE [--n N] [--eps EPS] [--param K=V]… [--backend B] [--accuracy A]
//! [--pruning P] --out DIR`: runs a scene and writes every sub-problem QP it solves as a QPS
//! file (free MPS with a QUADOBJ section, the Maros–Meszaros convention), plus `index.csv`
//! (one row per QP: file, variables, rows, non-zeros, the backend's status, iterations and
//! objective) and `run.json` (scene, settings, final status). An external QP solver can then be
//! run on contact QPs; `contactlab_solvers::qps::read_qps_file` reads them back.

use crate::harness::capture::Capture;
use crate::harness::case::{execute_with, CaseSettings};
use crate::harness::rows::{csv_line, header, record_line, QpIndexRow};
use crate::output::write_atomic;
use crate::scene::registry::{build_scene, parse_params};
use crate::solve::outer::Pruning;
use crate::solve::settings::Accuracy;
use anyhow::{bail, Context, Result};
use contactlab_solvers::qps::write_qps_file;
use contactlab_solvers::{backend_from_name, Qp, QpError, QpSolution};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `contactlab export-qp`.
#[derive(clap::Args, Clone, Debug)]
pub struct ExportArgs {
    /// Built-in scene name (balloons, ring, sheets, rod, solids, balloons3d; docs/scenes.md).
    pub scene: String,
    /// Mesh level (elements per membrane for the balloons, edges for the ring).
    #[arg(long, default_value_t = 20)]
    pub n: usize,
    /// ε (default: the scene's, h/10).
    #[arg(long)]
    pub eps: Option<f64>,
    /// A numeric scene parameter K=V (repeatable), as in a sweep file's `params`.
    #[arg(long = "param")]
    pub params: Vec<String>,
    /// Backend that solves the QPs during the run.
    #[arg(long, default_value = contactlab_solvers::DEFAULT_BACKEND)]
    pub backend: String,
    /// Accuracy preset: low, default or high.
    #[arg(long, default_value = "default")]
    pub accuracy: String,
    /// Pruning mode: lazy, trust-region or all-pairs.
    #[arg(long, default_value = "lazy")]
    pub pruning: String,
    /// Maximum outer iterations.
    #[arg(long, default_value_t = 2000)]
    pub max_outer: usize,
    /// Output directory (created; QPS files already in it are overwritten).
    #[arg(long)]
    pub out: PathBuf,
}

/// `contactlab export-qp`.
pub fn cmd_export(a: &ExportArgs) -> Result<()> {
    let params = parse_params(&a.params)?;
    let accuracy = Accuracy::from_name(&a.accuracy)
        .with_context(|| format!("--accuracy {:?}: expected low, default or high", a.accuracy))?;
    let pruning = Pruning::from_name(&a.pruning).with_context(|| {
        format!(
            "--pruning {:?}: expected lazy, trust-region or all-pairs",
            a.pruning
        )
    })?;
    let scene = build_scene(&a.scene, a.n, a.eps, &params)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {:?}", a.out))?;
    let cs = CaseSettings {
        backend: a.backend.clone(),
        accuracy,
        pruning,
        tol_j: None,
        max_outer: a.max_outer,
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
    let qp_settings = accuracy.qp_settings(&a.backend);
    let mut inner = backend_from_name(&a.backend, &qp_settings)?;
    let index_path = a.out.join("index.csv");
    let mut index =
        std::fs::File::create(&index_path).with_context(|| format!("creating {index_path:?}"))?;
    index.write_all(&record_line(header::<QpIndexRow>())?)?;
    let mut failure: Option<anyhow::Error> = None;
    let out_dir = a.out.clone();
    let stem = format!("{}_n{}", a.scene, a.n);
    let mut sink = |k: usize, qp: &Qp, r: &Result<QpSolution, QpError>| {
        if failure.is_some() {
            return;
        }
        let file = format!("{stem}_{k:05}.qps");
        let name = format!("{stem}_{k:05}");
        let res = write_qps_file(qp, &name, &out_dir.join(&file))
            .with_context(|| format!("writing {file}"))
            .and_then(|()| {
                let (status, it, obj) = match r {
                    Ok(s) => (
                        s.status.as_str().to_string(),
                        s.iterations,
                        qp.objective(&s.x),
                    ),
                    Err(e) => (format!("error: {e}").replace(',', ";"), 0, f64::NAN),
                };
                let row = QpIndexRow {
                    k,
                    variables: qp.n(),
                    rows: qp.m(),
                    nnz_p: qp.p.nnz(),
                    nnz_a: qp.a.nnz(),
                    file,
                    status,
                    iterations: it,
                    objective: obj,
                };
                csv_line(&row)
                    .and_then(|line| Ok(index.write_all(&line)?))
                    .and_then(|()| Ok(index.flush()?))
                    .context("writing index.csv")
            });
        if let Err(e) = res {
            failure = Some(e);
        }
    };
    let (status, count, energy) = {
        let mut cap = Capture::new(inner.as_mut(), &mut sink);
        let o = execute_with(&scene, &cs, &mut cap, &mut |_, _| {})?;
        (o.res.status, cap.count(), o.res.energy)
    };
    if let Some(e) = failure {
        return Err(e);
    }
    if count == 0 {
        bail!("the run solved no QP (status {})", status.as_str());
    }
    let summary = serde_json::json!({
        "scene": a.scene, "n": a.n, "h": scene.h, "eps": scene.eps, "params": params,
        "backend": a.backend, "accuracy": accuracy.as_str(), "pruning": pruning.as_str(),
        "status": status.as_str(), "final_energy": energy, "qps": count,
        "format": "free MPS with QUADOBJ (objective 1/2 x'Px + q'x; every variable free, FR)",
    });
    write_atomic(
        &a.out.join("run.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    eprintln!(
        "export-qp: {count} QPs of a {} run ({}) written to {:?}",
        a.scene,
        status.as_str(),
        a.out
    );
    Ok(())
}
