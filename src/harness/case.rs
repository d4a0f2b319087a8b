//! One case: a scene built by name from `n`, ε and numeric parameters, run with a backend, an
//! accuracy preset and a pruning mode, then diagnosed. Shared by `contactlab sweep` (one CSV
//! row per case) and the tests; `contactlab run` builds its scene the same way.

use crate::energy::mass::lumped_mass;
use crate::energy::{HessianModel, TermKind};
use crate::harness::diagnostics::{
    converged_diagnostics, ConvergedDiagnostics, DiagnosticSettings,
};
use crate::scene::dynamic::DynamicScene;
use crate::scene::Scene;
use crate::solve::dynamics::{
    rest_force, simulate_observed, DynamicLoop, DynamicResult, DynamicSettings, System,
};
use crate::solve::observer::Observer;
use crate::solve::outer::{run, IterationRecord, OuterSettings, Pruning, RunResult, RunStatus};
use crate::solve::settings::{tol_kappa, Accuracy};
use crate::solve::sqp::{Curvature, OuterMethod};
use anyhow::Result;
use contactlab_solvers::{backend_from_name, QpBackend, QpSettings, REFERENCE_BACKEND};
use std::time::Instant;

/// What a case runs with.
#[derive(Clone, Debug)]
pub struct CaseSettings {
    /// Backend name.
    pub backend: String,
    /// Accuracy preset.
    pub accuracy: Accuracy,
    /// Pruning mode.
    pub pruning: Pruning,
    /// Override of the preset's tol_J.
    pub tol_j: Option<f64>,
    /// Maximum outer iterations.
    pub max_outer: usize,
    /// Inner (Newton-type) steps per T(ψ) at most (`None`: the default, 50); 1 gives one QP
    /// per outer step.
    pub max_inner: Option<usize>,
    /// Wall-time limit of the run in seconds (`None`: none); a run that reaches it ends with
    /// status `time_limit` and its last admissible iterate.
    pub time_limit_s: Option<f64>,
    /// The inner steps' Newton model.
    pub newton_model: HessianModel,
    /// The outer method.
    pub outer_method: OuterMethod,
    /// The SQP model's constraint curvature (used by `outer_method` sqp).
    pub sqp_curvature: Curvature,
    /// SQP: `γ` of the active pairs' normal stiffness (finite, ≥ 0; used by `outer_method`
    /// sqp).
    pub sqp_normal_stiffness: f64,
    /// SQP: leave out the rows implied by another row of the same vertex or edge.
    pub sqp_drop_endpoint_rows: bool,
    /// SQP: rows against the extended element where the body turns towards the other side.
    pub sqp_extend_rows: bool,
    /// SQP, 2D: leave out the rows whose closest point is a vertex of the other body.
    pub sqp_drop_vertex_rows: bool,
    /// SQP, 2D: leave out the side rows a corner's row implies.
    pub sqp_drop_side_rows: bool,
    /// SQP: no chain limit for the extended rows against a fixed element.
    pub sqp_extend_fixed: bool,
    /// SQP: add a violated row only where the pair comes within ε + δ on the step's path.
    pub sqp_path_rows: bool,
    /// SQP: add the rows that would imply a violated endpoint or vertex row.
    pub sqp_implying_rows: bool,
    /// SQP: extrapolations of a full step (2, 4, …, 2^k times it; 0: none).
    pub sqp_extrapolate: usize,
    /// SQP: the normal stiffness only on the pairs whose last multiplier is at least this
    /// fraction of the largest (0: every positive one).
    pub sqp_normal_active_rel: f64,
    /// SQP: `interior` keeps surfaces' edge–edge pairs, with this factor on their normal
    /// stiffness (0: left out).
    pub sqp_edge_edge_stiffness: f64,
    /// The second-order check of a `converged` run up to this many free dofs (0: none;
    /// [`OuterSettings::second_order_max_dofs`]).
    pub second_order_max_dofs: usize,
    /// Go on from the lower point where that check finds a saddle
    /// ([`OuterSettings::escape_saddles`]).
    pub escape_saddles: bool,
}

/// A finished case.
pub struct CaseOutcome {
    /// The run.
    pub res: RunResult,
    /// Every iteration record.
    pub records: Vec<IterationRecord>,
    /// Diagnostics of a run that stopped on the stopping rule (`converged` or `fixed_point`),
    /// with the tolerance of the canonical-dual QP.
    pub diagnostics: Option<(ConvergedDiagnostics, f64)>,
    /// The backend settings used.
    pub qp: QpSettings,
    /// tol_J used.
    pub tol_j: f64,
    /// Inner steps per T(ψ) at most, as used.
    pub max_inner: usize,
    /// Seconds in the diagnostics.
    pub t_diagnostics_s: f64,
}

/// The canonical-dual QP of the diagnostics is solved by Clarabel at the first of these
/// tolerances at which it reports `solved` (measured: at n = 20 on the balloons, 1e-12 ended
/// `numerical_error`).
pub const DIAG_QP_TOLS: [f64; 3] = [1e-12, 1e-10, 1e-9];

/// Lemma 5.4 / 5.6 diagnostics of a converged run (Clarabel at the first tolerance of
/// [`DIAG_QP_TOLS`] that solves the canonical-dual QP), and that tolerance.
pub fn lemma_diagnostics(scene: &Scene, res: &RunResult) -> Result<(ConvergedDiagnostics, f64)> {
    lemma_diagnostics_with(scene, res, &DiagnosticSettings::for_eps(scene.eps))
}

/// [`lemma_diagnostics`] with other [`DiagnosticSettings`] (`contactlab run` counts the rows
/// its last sub-problem's duals hold as active, `raw_dual_rel`).
pub fn lemma_diagnostics_with(
    scene: &Scene,
    res: &RunResult,
    settings: &DiagnosticSettings,
) -> Result<(ConvergedDiagnostics, f64)> {
    let mut last = None;
    for tol in DIAG_QP_TOLS {
        let st = QpSettings {
            eps_abs: tol,
            eps_rel: tol,
            ..Default::default()
        };
        let mut b = backend_from_name(REFERENCE_BACKEND, &st)?;
        let d = converged_diagnostics(
            &scene.mesh,
            &scene.energy,
            &res.x,
            &res.psi,
            scene.eps,
            scene.h,
            &res.last_rows,
            &res.multipliers,
            b.as_mut(),
            settings,
        )?;
        let solved = d.dual_qp_status == "solved";
        last = Some((d, tol));
        if solved {
            break;
        }
    }
    Ok(last.expect("DIAG_QP_TOLS is not empty"))
}

/// The outer-loop settings of a case, static or dynamic: the preset's tol_J unless overridden
/// (and the certificate's tolerance √tol_J), the backend's tolerance, max_outer, pruning,
/// max_inner, the Newton model, the outer method and the SQP model's curvature and normal
/// stiffness (the time limit is a static run's, set by [`execute_with`]).
pub fn outer_settings(cs: &CaseSettings) -> OuterSettings {
    let tol_j = cs.tol_j.unwrap_or(cs.accuracy.tol_j());
    let mut settings = OuterSettings {
        tol_j,
        tol_kappa: tol_kappa(tol_j),
        qp_tol: cs.accuracy.qp_tol(&cs.backend),
        max_outer: cs.max_outer,
        pruning: cs.pruning,
        ..Default::default()
    };
    if let Some(k) = cs.max_inner {
        settings.inner.max_inner = k;
    }
    settings.inner.hessian_model = cs.newton_model;
    settings.method = cs.outer_method;
    settings.sqp.curvature = cs.sqp_curvature;
    settings.sqp.normal_stiffness = cs.sqp_normal_stiffness;
    settings.sqp.drop_endpoint_rows = cs.sqp_drop_endpoint_rows;
    settings.sqp.extend_rows = cs.sqp_extend_rows;
    settings.sqp.drop_vertex_rows = cs.sqp_drop_vertex_rows;
    settings.sqp.drop_side_rows = cs.sqp_drop_side_rows;
    settings.sqp.extend_fixed = cs.sqp_extend_fixed;
    settings.sqp.path_rows = cs.sqp_path_rows;
    settings.sqp.implying_rows = cs.sqp_implying_rows;
    settings.sqp.extrapolate = cs.sqp_extrapolate;
    settings.sqp.normal_active_rel = cs.sqp_normal_active_rel;
    settings.sqp.edge_edge_stiffness = cs.sqp_edge_edge_stiffness;
    settings.second_order_max_dofs = cs.second_order_max_dofs;
    settings.escape_saddles = cs.escape_saddles;
    settings
}

/// The outer-loop settings of a dynamic case whose backend has the settings `qp` (a
/// `--qp-tol` included): [`outer_settings`] with the backend's tolerance, which sets the
/// certificate's distance tolerance ([`crate::solve::outer::certificate_active_tol`]).
pub fn dynamic_outer_settings(cs: &CaseSettings, qp: &QpSettings) -> OuterSettings {
    let mut settings = outer_settings(cs);
    settings.qp_tol = qp.eps_abs;
    settings
}

/// Runs `scene` with `cs`, calling `observer` on every iterate, then diagnoses a run that
/// stopped on the stopping rule (`converged` or `fixed_point`).
pub fn execute(
    scene: &Scene,
    cs: &CaseSettings,
    observer: &mut dyn FnMut(&IterationRecord, &[f64]),
) -> Result<CaseOutcome> {
    let qp = cs.accuracy.qp_settings(&cs.backend);
    let mut backend = backend_from_name(&cs.backend, &qp)?;
    execute_with(scene, cs, backend.as_mut(), observer)
}

/// [`execute`] with a backend built by the caller (e.g. one that records the QPs); `cs.backend`
/// names it in outputs.
pub fn execute_with(
    scene: &Scene,
    cs: &CaseSettings,
    backend: &mut dyn QpBackend,
    observer: &mut dyn FnMut(&IterationRecord, &[f64]),
) -> Result<CaseOutcome> {
    let qp = cs.accuracy.qp_settings(&cs.backend);
    let mut settings = outer_settings(cs);
    let tol_j = settings.tol_j;
    settings.time_limit_s = cs.time_limit_s;
    let mut records = Vec::new();
    let res = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        backend,
        &settings,
        &mut |r, x| {
            records.push(r.clone());
            observer(r, x)
        },
    )?;
    let t = Instant::now();
    let diagnostics = if matches!(res.status, RunStatus::Converged | RunStatus::FixedPoint) {
        Some(lemma_diagnostics(scene, &res)?)
    } else {
        None
    };
    Ok(CaseOutcome {
        res,
        records,
        diagnostics,
        qp,
        tol_j,
        max_inner: settings.inner.max_inner,
        t_diagnostics_s: t.elapsed().as_secs_f64(),
    })
}

/// What a dynamic run measured (summary.json and the dynamic sweep rows).
#[derive(Clone, Debug, serde::Serialize)]
pub struct DynamicMetrics {
    /// Steps taken.
    pub steps_taken: usize,
    /// `completed`, or the outer-loop status that stopped the run.
    pub status: String,
    /// Steps whose outer loop ended `max_outer_iterations` (accepted, not converged).
    pub steps_max_outer: usize,
    /// Steps whose outer loop ended `line_search_failed` (accepted).
    pub steps_line_search_failed: usize,
    /// Steps whose outer loop stopped where the minimality certificate does not hold
    /// (`fixed_point`: accepted, not certified).
    pub steps_fixed_point: usize,
    /// The largest certificate κ over the steps (NaN when no step was taken).
    pub max_kappa: f64,
    /// Outer iterations that were SQP steps, summed over the steps.
    pub sqp_steps: usize,
    /// Outer iterations where the SQP step collapsed and Pantz's was taken, summed.
    pub fallback_steps: usize,
    /// Every outer iterate of every step passed the exact admissibility check.
    pub all_admissible: bool,
    /// Smallest end-of-step distance.
    pub min_distance: f64,
    /// E_0.
    pub initial_energy: f64,
    /// E at the end.
    pub final_energy: f64,
    /// Kinetic energy at the end.
    pub final_kinetic: f64,
    /// `max_n (E_n − E_(n−1))` (negative: E decreased at every step).
    pub max_energy_increase: f64,
    /// `(E_end − E_0)/|E_0|`.
    pub energy_drift: f64,
    /// `max_n |P_n − P_0|` when the scene has no fixed vertex and no potential (external)
    /// energy — then momentum is conserved and this is its error; `None` otherwise.
    pub momentum_error: Option<f64>,
    /// Total mass of the free vertices.
    pub free_mass: f64,
    /// Contact force statistics over the last quarter of the steps.
    pub rest: Option<crate::solve::dynamics::RestForce>,
    /// Outer iterations summed over the steps.
    pub outer_iterations: usize,
    /// The largest number of outer iterations of one step.
    pub max_outer_per_step: usize,
    /// QPs the backend did not solve and handed to the one behind it (`ip`: Clarabel;
    /// `contactlab_solvers::fallback`).
    pub qp_fallbacks: usize,
    /// Wall time of the stepping.
    pub wall_time_s: f64,
}

/// The fraction of the steps (the last ones) over which [`DynamicMetrics::rest`] is taken.
pub const REST_FRACTION: f64 = 0.25;

/// Runs `ds` for `dyn_settings` with the case's backend, accuracy and pruning, calling
/// `observer` per step.
pub fn execute_dynamic(
    ds: &mut DynamicScene,
    cs: &CaseSettings,
    dyn_settings: &DynamicSettings,
    qp: &QpSettings,
    observer: &mut dyn Observer<DynamicLoop>,
) -> Result<(DynamicResult, DynamicMetrics)> {
    let mut backend = backend_from_name(&cs.backend, qp)?;
    let settings = dynamic_outer_settings(cs, qp);
    let mass = lumped_mass(&ds.scene.mesh, &ds.scene.mesh.x_ref, &ds.density)?;
    let mut system = System {
        mesh: &ds.scene.mesh,
        energy: &mut ds.scene.energy,
        eps: ds.scene.eps,
        mass,
    };
    let res = simulate_observed(
        &mut system,
        &ds.scene.x0,
        &ds.v0,
        backend.as_mut(),
        &settings,
        dyn_settings,
        observer,
    )?;
    let free_mass = system.free_mass();
    let has_potential = system
        .energy
        .terms
        .iter()
        .any(|t| t.kind() == TermKind::Potential);
    let conserves = !has_potential && !ds.scene.mesh.fixed.iter().any(|&f| f);
    let mut m = dynamic_metrics(&res, free_mass, conserves);
    m.qp_fallbacks = backend.fallback_solves();
    Ok((res, m))
}

/// [`DynamicMetrics`] of a finished run.
pub fn dynamic_metrics(res: &DynamicResult, free_mass: f64, conserves: bool) -> DynamicMetrics {
    let r = &res.records;
    let (e0, last) = (r[0].total, r.last().expect("step 0 is recorded"));
    let p0 = [r[0].momentum_x, r[0].momentum_y, r[0].momentum_z];
    let steps = &r[1..];
    DynamicMetrics {
        steps_taken: res.steps,
        status: res
            .stopped_by
            .map_or("completed".to_string(), |s| s.as_str().to_string()),
        steps_max_outer: steps
            .iter()
            .filter(|s| s.status == "max_outer_iterations")
            .count(),
        steps_line_search_failed: steps
            .iter()
            .filter(|s| s.status == "line_search_failed")
            .count(),
        steps_fixed_point: steps.iter().filter(|s| s.status == "fixed_point").count(),
        max_kappa: steps
            .iter()
            .map(|s| s.kappa)
            .reduce(f64::max)
            .unwrap_or(f64::NAN),
        sqp_steps: steps.iter().map(|s| s.sqp_steps).sum(),
        fallback_steps: steps.iter().map(|s| s.fallback_steps).sum(),
        all_admissible: r.iter().all(|s| s.admissible),
        min_distance: r
            .iter()
            .map(|s| s.min_distance)
            .fold(f64::INFINITY, f64::min),
        initial_energy: e0,
        final_energy: last.total,
        final_kinetic: last.kinetic,
        max_energy_increase: r
            .windows(2)
            .map(|w| w[1].total - w[0].total)
            .fold(f64::NEG_INFINITY, f64::max),
        energy_drift: (last.total - e0) / e0.abs().max(f64::MIN_POSITIVE),
        momentum_error: conserves.then(|| {
            r.iter()
                .map(|s| {
                    ((s.momentum_x - p0[0]).powi(2)
                        + (s.momentum_y - p0[1]).powi(2)
                        + (s.momentum_z - p0[2]).powi(2))
                    .sqrt()
                })
                .fold(0.0, f64::max)
        }),
        free_mass,
        rest: rest_force(r, REST_FRACTION),
        outer_iterations: steps.iter().map(|s| s.outer_iterations).sum(),
        max_outer_per_step: steps.iter().map(|s| s.outer_iterations).max().unwrap_or(0),
        qp_fallbacks: 0,
        wall_time_s: res.wall_time_s,
    }
}
