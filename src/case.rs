//! One case: a scene built by name from `n`, ε and numeric parameters, run with a backend, an
//! accuracy preset and a pruning mode, then diagnosed. Shared by `contactlab sweep` (one CSV
//! row per case) and the tests; `contactlab run` builds its scene the same way.

use anyhow::{bail, Result};
use contactlab::diagnostics::{converged_diagnostics, ConvergedDiagnostics, DiagnosticSettings};
use contactlab::outer::{run, IterationRecord, OuterSettings, Pruning, RunResult, RunStatus};
use contactlab::presets::Accuracy;
use contactlab::scene::balloons::{self, BalloonsParams};
use contactlab::scene::ring::{self, RingParams};
use contactlab::scene::Scene;
use contactlab_solvers::{backend_from_name, QpBackend, QpSettings};
use std::collections::BTreeMap;
use std::time::Instant;

/// Scenes `contactlab run` and sweeps know.
pub const SCENES: [&str; 2] = ["balloons", "ring"];

/// Builds scene `name` at mesh level `n` with ε (`None`: the scene's default, h/10) and numeric
/// parameters. Unknown scene or parameter names are errors naming them.
pub fn build_scene(
    name: &str,
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<Scene> {
    match name {
        "balloons" => {
            let mut p = BalloonsParams {
                n,
                eps,
                ..Default::default()
            };
            for (k, &v) in params {
                match k.as_str() {
                    "c" => p.c = v,
                    "mu" => p.mu = v,
                    "perturb0" => p.perturb[0] = v,
                    "perturb1" => p.perturb[1] = v,
                    "perturb2" => p.perturb[2] = v,
                    "perturb3" => p.perturb[3] = v,
                    other => bail!(
                        "scene balloons: unknown parameter {other:?} (known: c, mu, perturb0..perturb3)"
                    ),
                }
            }
            Ok(balloons::build(&p)?)
        }
        "ring" => {
            let mut p = RingParams {
                n,
                eps,
                ..Default::default()
            };
            for (k, &v) in params {
                match k.as_str() {
                    "mu" => p.mu = v,
                    "p" => p.p = v,
                    "aspect" => p.aspect = v,
                    "half_span" => p.half_span = v,
                    other => bail!(
                        "scene ring: unknown parameter {other:?} (known: mu, p, aspect, half_span)"
                    ),
                }
            }
            Ok(ring::build(&p)?)
        }
        other => bail!("unknown scene {other:?} (available: {})", SCENES.join(", ")),
    }
}

/// The coarsest mesh level `n` of scene `name` whose mesh size is at most `h`: balloons
/// `h = 1.6/n`, so `n = ⌈1.6/h⌉`; ring `h = 2 sin(π/n)` with n even, so the smallest even
/// `n ≥ π / asin(h/2)` (at least 6).
pub fn n_for_h(name: &str, h: f64) -> Result<usize> {
    if !(h.is_finite() && h > 0.0) {
        bail!("h = {h}: a mesh size must be finite and > 0");
    }
    let n = match name {
        "balloons" => {
            let mut n = (1.6 / h).ceil().max(1.0) as usize;
            // guard the rounding of 1.6/h
            while n > 1 && 1.6 / ((n - 1) as f64) <= h {
                n -= 1;
            }
            n
        }
        "ring" => {
            if h >= 2.0 {
                6
            } else {
                let mut n = ((std::f64::consts::PI / (h / 2.0).asin()).ceil() as usize).max(6);
                n += n % 2;
                while n > 6 && ring::mesh_size(n - 2) <= h {
                    n -= 2;
                }
                while ring::mesh_size(n) > h {
                    n += 2;
                }
                n
            }
        }
        other => bail!("unknown scene {other:?} (available: {})", SCENES.join(", ")),
    };
    if n > 10_000_000 {
        bail!("h = {h} needs n = {n} elements: too fine");
    }
    Ok(n)
}

/// Parses `NAME=VALUE` scene parameters (`--param`, repeatable); the error names the argument.
pub fn parse_params(args: &[String]) -> Result<BTreeMap<String, f64>> {
    let mut params = BTreeMap::new();
    for p in args {
        let Some((k, v)) = p.split_once('=') else {
            bail!("--param {p:?}: expected NAME=VALUE");
        };
        let Ok(v) = v.trim().parse::<f64>() else {
            bail!("--param {p:?}: value {v:?} is not a number");
        };
        params.insert(k.trim().to_string(), v);
    }
    Ok(params)
}

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
}

/// A finished case.
pub struct CaseOutcome {
    /// The run.
    pub res: RunResult,
    /// Every iteration record.
    pub records: Vec<IterationRecord>,
    /// Diagnostics of a converged run, with the tolerance of the canonical-dual QP.
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
    let mut last = None;
    for tol in DIAG_QP_TOLS {
        let st = QpSettings {
            eps_abs: tol,
            eps_rel: tol,
            ..Default::default()
        };
        let mut b = backend_from_name("clarabel", &st)?;
        let d = converged_diagnostics(
            &scene.mesh,
            &scene.energy,
            &res.x,
            scene.eps,
            scene.h,
            &res.last_rows,
            &res.multipliers,
            b.as_mut(),
            &DiagnosticSettings::for_eps(scene.eps),
        )?;
        let solved = d.dual_qp_status == "solved";
        last = Some((d, tol));
        if solved {
            break;
        }
    }
    Ok(last.expect("DIAG_QP_TOLS is not empty"))
}

/// Runs `scene` with `cs`, calling `observer` on every iterate, then diagnoses a converged
/// run.
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
    let tol_j = cs.tol_j.unwrap_or(cs.accuracy.tol_j());
    let mut settings = OuterSettings {
        tol_j,
        max_outer: cs.max_outer,
        pruning: cs.pruning,
        ..Default::default()
    };
    if let Some(k) = cs.max_inner {
        settings.inner.max_inner = k;
    }
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
    let diagnostics = if res.status == RunStatus::Converged {
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

/// The per-run columns of a sweep row (after the case's own columns), as documented in the
/// README ("Sweeps").
pub const RUN_COLUMNS: [&str; 33] = [
    "dim",
    "h",
    "eps",
    "qp_tol",
    "tol_j",
    "max_inner",
    "status",
    "outer_iterations",
    "inner_iterations",
    "backend_iterations",
    "final_energy",
    "min_distance",
    "all_admissible",
    "energy_monotone",
    "residual_hm1",
    "bound",
    "ratio",
    "lambda_norm_h",
    "c_phi",
    "max_edges_per_vertex",
    "stationarity_rel",
    "pairs",
    "active_rows",
    "wall_time_s",
    "t_pairs_s",
    "t_assembly_s",
    "t_solve_s",
    "t_diagnostics_s",
    "energy_error",
    "position_error_h1",
    "max_violation",
    "reference_energy",
    "error",
];

/// Formats a float for CSV (shortest round-trip form; empty when NaN).
pub fn f(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v:?}")
    }
}

/// The run columns of a finished case ([`RUN_COLUMNS`]; the error columns empty).
pub fn row_values(scene: &Scene, o: &CaseOutcome) -> BTreeMap<&'static str, String> {
    let mut m = BTreeMap::new();
    let r = &o.res;
    let sum = |g: fn(&IterationRecord) -> f64| o.records.iter().map(g).sum::<f64>();
    m.insert("dim", scene.mesh.dim.to_string());
    m.insert("h", f(scene.h));
    m.insert("eps", f(scene.eps));
    m.insert("qp_tol", f(o.qp.eps_abs));
    m.insert("tol_j", f(o.tol_j));
    m.insert("max_inner", o.max_inner.to_string());
    m.insert("status", r.status.as_str().to_string());
    m.insert("outer_iterations", r.outer_iterations.to_string());
    m.insert("inner_iterations", r.inner_iterations.to_string());
    m.insert("backend_iterations", r.backend_iterations.to_string());
    m.insert("final_energy", f(r.energy));
    m.insert("min_distance", f(r.min_distance.distance));
    m.insert(
        "all_admissible",
        o.records.iter().all(|x| x.admissible).to_string(),
    );
    m.insert(
        "energy_monotone",
        o.records
            .windows(2)
            .all(|w| w[1].energy <= w[0].energy)
            .to_string(),
    );
    if let Some((d, _)) = &o.diagnostics {
        m.insert("residual_hm1", f(d.residual_hm1));
        m.insert("bound", f(d.bound));
        m.insert("ratio", f(d.ratio));
        m.insert("lambda_norm_h", f(d.lambda_norm_h));
        m.insert("c_phi", d.c_phi.to_string());
        m.insert("max_edges_per_vertex", d.max_edges_per_vertex.to_string());
        m.insert(
            "stationarity_rel",
            f(d.stationarity_canonical / d.gradient_norm.max(f64::MIN_POSITIVE)),
        );
        m.insert("active_rows", d.active_rows.to_string());
    } else if let Some(last) = o.records.last() {
        m.insert("active_rows", last.active_rows.to_string());
    }
    m.insert("pairs", o.records.last().map_or(0, |x| x.pairs).to_string());
    m.insert("wall_time_s", f(r.wall_time_s));
    m.insert("t_pairs_s", f(sum(|x| x.t_pairs_s)));
    m.insert("t_assembly_s", f(sum(|x| x.t_assembly_s)));
    m.insert("t_solve_s", f(sum(|x| x.t_solve_s)));
    m.insert("t_diagnostics_s", f(o.t_diagnostics_s));
    m
}
