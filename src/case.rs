//! One case: a scene built by name from `n`, ε and numeric parameters, run with a backend, an
//! accuracy preset and a pruning mode, then diagnosed. Shared by `contactlab sweep` (one CSV
//! row per case) and the tests; `contactlab run` builds its scene the same way.

use anyhow::{bail, Result};
use contactlab::diagnostics::{converged_diagnostics, ConvergedDiagnostics, DiagnosticSettings};
use contactlab::dynamics::{
    lumped_mass, rest_force, simulate, DynamicResult, DynamicSettings, DynamicState, PairForce,
    StepRecord, System,
};
use contactlab::energy::TermKind;
use contactlab::outer::{run, IterationRecord, OuterSettings, Pruning, RunResult, RunStatus};
use contactlab::presets::Accuracy;
use contactlab::scene::balloons::{self, BalloonsParams};
use contactlab::scene::balloons3d::{self, Balloons3dParams};
use contactlab::scene::dynamic::{self, CollideParams, Drop3dParams, DropParams, DynamicScene};
use contactlab::scene::ring::{self, RingParams};
use contactlab::scene::rod::{self, RodParams};
use contactlab::scene::sheets::{self, SheetsParams};
use contactlab::scene::solids::{self, SolidsParams};
use contactlab::scene::Scene;
use contactlab_solvers::{backend_from_name, QpBackend, QpSettings};
use std::collections::BTreeMap;
use std::time::Instant;

/// Scenes `contactlab run` and sweeps know: 2D `balloons`, `ring`; 3D `sheets`, `rod`,
/// `solids`, `balloons3d`.
pub const SCENES: [&str; 6] = ["balloons", "ring", "sheets", "rod", "solids", "balloons3d"];

/// Sets the fields of a 3D scene's parameters from `NAME=VALUE` pairs: `fields` lists the
/// numeric fields by name, `flags` the boolean ones (value 0 or 1). Unknown names and
/// non-0/1 flags are errors naming them.
/// A named numeric field of a parameter struct.
type Field<P> = (&'static str, fn(&mut P) -> &mut f64);
/// A named boolean field of a parameter struct.
type Flag<P> = (&'static str, fn(&mut P) -> &mut bool);

fn set_fields<P>(
    scene: &str,
    p: &mut P,
    params: &BTreeMap<String, f64>,
    fields: &[Field<P>],
    flags: &[Flag<P>],
) -> Result<()> {
    for (k, &v) in params {
        if let Some((_, get)) = fields.iter().find(|(n, _)| n == k) {
            *get(p) = v;
        } else if let Some((_, get)) = flags.iter().find(|(n, _)| n == k) {
            *get(p) = match v {
                0.0 => false,
                1.0 => true,
                _ => bail!("scene {scene}: parameter {k:?} = {v} must be 0 or 1"),
            };
        } else {
            let known: Vec<&str> = fields
                .iter()
                .map(|(n, _)| *n)
                .chain(flags.iter().map(|(n, _)| *n))
                .collect();
            bail!(
                "scene {scene}: unknown parameter {k:?} (known: {})",
                known.join(", ")
            );
        }
    }
    Ok(())
}

fn sheets_params(
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<SheetsParams> {
    let mut p = SheetsParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "sheets",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("lambda", |p| &mut p.lambda),
            ("weight", |p| &mut p.weight),
            ("gap", |p| &mut p.gap),
            ("half_size", |p| &mut p.half_size),
            ("angle_deg", |p| &mut p.angle_deg),
            ("stretch_lower", |p| &mut p.stretch_lower),
            ("stretch_upper", |p| &mut p.stretch_upper),
        ],
        &[("lower_fixed", |p| &mut p.lower_fixed)],
    )?;
    Ok(p)
}

fn rod_params(n: usize, eps: Option<f64>, params: &BTreeMap<String, f64>) -> Result<RodParams> {
    let mut p = RodParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "rod",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("weight", |p| &mut p.weight),
            ("height", |p| &mut p.height),
            ("stretch", |p| &mut p.stretch),
            ("slack", |p| &mut p.slack),
            ("swing_deg", |p| &mut p.swing_deg),
        ],
        &[],
    )?;
    Ok(p)
}

fn solids_params(
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<SolidsParams> {
    let mut p = SolidsParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "solids",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("lambda", |p| &mut p.lambda),
            ("angle_deg", |p| &mut p.angle_deg),
            ("upper_size", |p| &mut p.upper_size),
            ("overlap", |p| &mut p.overlap),
            ("gap", |p| &mut p.gap),
            ("contrast", |p| &mut p.contrast),
        ],
        &[],
    )?;
    Ok(p)
}

fn balloons3d_params(
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<Balloons3dParams> {
    let mut p = Balloons3dParams {
        n,
        eps,
        ..Default::default()
    };
    set_fields(
        "balloons3d",
        &mut p,
        params,
        &[
            ("mu", |p| &mut p.mu),
            ("lambda", |p| &mut p.lambda),
            ("c", |p| &mut p.c),
            ("radius", |p| &mut p.radius),
            ("pad_gap", |p| &mut p.pad_gap),
            ("twist_deg", |p| &mut p.twist_deg),
        ],
        &[],
    )?;
    Ok(p)
}

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
        "sheets" => Ok(sheets::build(&sheets_params(n, eps, params)?)?),
        "rod" => Ok(rod::build(&rod_params(n, eps, params)?)?),
        "solids" => Ok(solids::build(&solids_params(n, eps, params)?)?),
        "balloons3d" => Ok(balloons3d::build(&balloons3d_params(n, eps, params)?)?),
        other => bail!("unknown scene {other:?} (available: {})", SCENES.join(", ")),
    }
}

/// The default mesh level of scene `name` for `contactlab run` (40 for the 2D scenes, the
/// scene's own default in 3D).
pub fn default_n(name: &str) -> usize {
    match name {
        "sheets" => SheetsParams::default().n,
        "rod" => RodParams::default().n,
        "solids" => SolidsParams::default().n,
        "balloons3d" => Balloons3dParams::default().n,
        _ => 40,
    }
}

/// The full parameter set of a 3D scene built by [`build_scene`] (for summary.json), or
/// `None` for the 2D scenes (whose runs record their own).
pub fn params_json(
    name: &str,
    n: usize,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<Option<serde_json::Value>> {
    Ok(Some(match name {
        "sheets" => serde_json::to_value(sheets_params(n, eps, params)?)?,
        "rod" => serde_json::to_value(rod_params(n, eps, params)?)?,
        "solids" => serde_json::to_value(solids_params(n, eps, params)?)?,
        "balloons3d" => serde_json::to_value(balloons3d_params(n, eps, params)?)?,
        _ => return Ok(None),
    }))
}

/// The smallest `n` in `1..=max_n` with `size(n) ≤ h` (the sizes decrease with n).
fn first_level(h: f64, max_n: usize, size: impl Fn(usize) -> f64) -> Result<usize> {
    (1..=max_n)
        .find(|&n| size(n) <= h)
        .ok_or_else(|| anyhow::anyhow!("h = {h} needs a level above the scene's n ≤ {max_n}"))
}

/// The coarsest mesh level `n` of scene `name` (with parameters `params`, which the 3D
/// scenes' mesh sizes depend on) whose mesh size is at most `h`: balloons `h = 1.6/n`, so
/// `n = ⌈1.6/h⌉`; ring `h = 2 sin(π/n)` with n even, so the smallest even
/// `n ≥ π / asin(h/2)` (at least 6); the 3D scenes: the smallest level whose `mesh_size` is
/// at most `h`.
pub fn n_for_h(name: &str, h: f64, params: &BTreeMap<String, f64>) -> Result<usize> {
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
        "sheets" => {
            let base = sheets_params(1, None, params)?;
            first_level(h, 1000, |n| {
                sheets::mesh_size(&SheetsParams { n, ..base.clone() })
            })?
        }
        "rod" => {
            let base = rod_params(1, None, params)?;
            first_level(h, 100_000, |n| {
                rod::mesh_size(&RodParams { n, ..base.clone() })
            })?
        }
        "solids" => {
            let base = solids_params(1, None, params)?;
            first_level(h, 200, |n| {
                solids::mesh_size(&SolidsParams { n, ..base.clone() })
            })?
        }
        "balloons3d" => {
            let base = balloons3d_params(1, None, params)?;
            first_level(h, 7, |n| {
                balloons3d::mesh_size(&Balloons3dParams { n, ..base.clone() })
            })?
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
    /// Wall-time limit of the run in seconds (`None`: none); a run that reaches it ends with
    /// status `time_limit` and its last admissible iterate.
    pub time_limit_s: Option<f64>,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_builds_by_name_at_its_default_level() {
        for name in SCENES {
            let s = build_scene(name, default_n(name), None, &BTreeMap::new()).unwrap();
            assert_eq!(s.name, name);
            let dim = if ["balloons", "ring"].contains(&name) {
                2
            } else {
                3
            };
            assert_eq!(s.mesh.dim, dim, "{name}");
        }
    }

    #[test]
    fn n_for_h_of_the_3d_scenes_is_the_coarsest_level_fine_enough() {
        let none = BTreeMap::new();
        for name in ["sheets", "rod", "solids", "balloons3d"] {
            for n in 1..=3 {
                let h = build_scene(name, n, None, &none).unwrap().h;
                assert_eq!(n_for_h(name, h, &none).unwrap(), n, "{name} n={n} h={h}");
                // just above h: the same level; just below: a finer one
                assert_eq!(n_for_h(name, h * (1.0 + 1e-9), &none).unwrap(), n);
                assert!(n_for_h(name, h * (1.0 - 1e-9), &none).unwrap() > n);
            }
        }
        // the parameters change h: a sheets stretch makes the elements smaller
        let p: BTreeMap<String, f64> = [("stretch_lower".to_string(), 1.5)].into();
        let h = build_scene("sheets", 2, None, &p).unwrap().h;
        assert!(h < build_scene("sheets", 2, None, &none).unwrap().h);
        assert_eq!(n_for_h("sheets", h, &p).unwrap(), 2);
        assert!(n_for_h("sheets", h, &none).unwrap() > 2);
        let e = n_for_h("balloons3d", 1e-4, &none).unwrap_err().to_string();
        assert!(e.contains("n ≤ 7"), "{e}");
    }

    #[test]
    fn unknown_3d_parameters_and_bad_flags_are_named() {
        let p: BTreeMap<String, f64> = [("weigth".to_string(), 1.0)].into();
        let e = build_scene("sheets", 1, None, &p)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("\"weigth\"") && e.contains("weight"), "{e}");
        let p: BTreeMap<String, f64> = [("lower_fixed".to_string(), 0.5)].into();
        let e = build_scene("sheets", 1, None, &p)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("lower_fixed") && e.contains("0 or 1"), "{e}");
        let p: BTreeMap<String, f64> = [("lower_fixed".to_string(), 1.0)].into();
        let s = build_scene("sheets", 1, None, &p).unwrap();
        assert!(s.mesh.bodies[0].vertices.iter().all(|&v| s.mesh.fixed[v]));
        let e = n_for_h("rod", 0.1, &[("x".to_string(), 1.0)].into())
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"x\""), "{e}");
    }
}

/// The dynamic scenes (§6; `contactlab run NAME --dynamic`): 2D `drop`, `collide`; 3D
/// `drop3d`. The static scenes of [`SCENES`] also run with `--dynamic`, with density 1 per
/// body, zero initial velocity and no default Δt or number of steps.
pub const DYNAMIC_SCENES: [&str; 3] = ["drop", "collide", "drop3d"];

/// A dynamic scene by name: the dynamic scenes with their parameters (`--param`), or a static
/// scene of [`SCENES`] wrapped with density 1 per body and zero velocity (its Δt and steps
/// then have no default: 0 and 0, which [`DynamicSettings::validate`] refuses).
pub fn build_dynamic_scene(
    name: &str,
    n: Option<usize>,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<DynamicScene> {
    Ok(build_dynamic_scene_json(name, n, eps, params)?.0)
}

/// [`build_dynamic_scene`], and the scene's full parameter set as JSON (summary.json): the
/// dynamic scenes' parameter structs, or `{n, eps, params}` for a wrapped static scene.
pub fn build_dynamic_scene_json(
    name: &str,
    n: Option<usize>,
    eps: Option<f64>,
    params: &BTreeMap<String, f64>,
) -> Result<(DynamicScene, serde_json::Value)> {
    match name {
        "drop" => {
            let mut p = DropParams {
                eps,
                ..Default::default()
            };
            if let Some(n) = n {
                p.ring.n = n;
            }
            let mut layers = p.ring.layers as f64;
            let mut floor_edges = p.floor_edges as f64;
            set_fields(
                "drop",
                &mut (&mut p, &mut layers, &mut floor_edges),
                params,
                &[
                    ("mu", |p| &mut p.0.ring.mu),
                    ("lambda", |p| &mut p.0.ring.lambda),
                    ("radius", |p| &mut p.0.ring.radius),
                    ("inner", |p| &mut p.0.ring.inner),
                    ("layers", |p| &mut *p.1),
                    ("density", |p| &mut p.0.density),
                    ("g", |p| &mut p.0.g),
                    ("height", |p| &mut p.0.height),
                    ("floor_half_width", |p| &mut p.0.floor_half_width),
                    ("floor_edges", |p| &mut *p.2),
                ],
                &[],
            )?;
            p.ring.layers = count("drop", "layers", layers)?;
            p.floor_edges = count("drop", "floor_edges", floor_edges)?;
            Ok((dynamic::drop(&p)?, serde_json::to_value(&p)?))
        }
        "collide" => {
            let mut p = CollideParams {
                eps,
                ..Default::default()
            };
            if let Some(n) = n {
                p.ring.n = n;
            }
            let mut layers = p.ring.layers as f64;
            set_fields(
                "collide",
                &mut (&mut p, &mut layers),
                params,
                &[
                    ("mu", |p| &mut p.0.ring.mu),
                    ("lambda", |p| &mut p.0.ring.lambda),
                    ("radius", |p| &mut p.0.ring.radius),
                    ("inner", |p| &mut p.0.ring.inner),
                    ("layers", |p| &mut *p.1),
                    ("density", |p| &mut p.0.density),
                    ("density_ratio", |p| &mut p.0.density_ratio),
                    ("gap", |p| &mut p.0.gap),
                    ("speed", |p| &mut p.0.speed),
                    ("offset_cells", |p| &mut p.0.offset_cells),
                ],
                &[],
            )?;
            p.ring.layers = count("collide", "layers", layers)?;
            Ok((dynamic::collide(&p)?, serde_json::to_value(&p)?))
        }
        "drop3d" => {
            let mut p = Drop3dParams {
                eps,
                ..Default::default()
            };
            if let Some(n) = n {
                p.n = n;
            }
            set_fields(
                "drop3d",
                &mut p,
                params,
                &[
                    ("half_size", |p| &mut p.half_size),
                    ("angle_deg", |p| &mut p.angle_deg),
                    ("tilt_deg", |p| &mut p.tilt_deg),
                    ("height", |p| &mut p.height),
                    ("obstacle_half_size", |p| &mut p.obstacle_half_size),
                    ("mu", |p| &mut p.mu),
                    ("lambda", |p| &mut p.lambda),
                    ("density", |p| &mut p.density),
                    ("g", |p| &mut p.g),
                ],
                &[],
            )?;
            Ok((dynamic::drop3d(&p)?, serde_json::to_value(&p)?))
        }
        other if SCENES.contains(&other) => {
            let n = n.unwrap_or_else(|| default_n(other));
            let scene = build_scene(other, n, eps, params)?;
            let density = vec![1.0; scene.mesh.bodies.len()];
            let v0 = vec![0.0; scene.x0.len()];
            let json = match params_json(other, n, eps, params)? {
                Some(j) => j,
                None => serde_json::json!({ "n": n, "eps": eps, "params": params }),
            };
            Ok((
                DynamicScene {
                    scene,
                    density,
                    v0,
                    dt: 0.0,
                    steps: 0,
                },
                json,
            ))
        }
        other => bail!(
            "unknown scene {other:?} (dynamic: {}; static, with --dynamic: {})",
            DYNAMIC_SCENES.join(", "),
            SCENES.join(", ")
        ),
    }
}

/// A non-negative integer parameter given as a number.
fn count(scene: &str, name: &str, v: f64) -> Result<usize> {
    if v >= 0.0 && v.fract() == 0.0 && v <= 1e9 {
        Ok(v as usize)
    } else {
        bail!("scene {scene}: parameter {name:?} = {v} must be a non-negative integer")
    }
}

/// The smallest mesh level of dynamic scene `name` whose h is at most `h` (drop, collide: the
/// ring's cells around; drop3d: its level; the static scenes: [`n_for_h`]).
pub fn dynamic_n_for_h(name: &str, h: f64, params: &BTreeMap<String, f64>) -> Result<usize> {
    if !DYNAMIC_SCENES.contains(&name) {
        return n_for_h(name, h, params);
    }
    if !(h.is_finite() && h > 0.0) {
        bail!("h = {h}: a mesh size must be finite and > 0");
    }
    let size =
        |n: usize| -> Result<f64> { Ok(build_dynamic_scene(name, Some(n), None, params)?.scene.h) };
    let start = if name == "drop3d" { 1 } else { 8 };
    for n in start..=400 {
        if size(n)? <= h {
            return Ok(n);
        }
    }
    bail!("h = {h} needs a level above the scene's n ≤ 400")
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
    pub rest: Option<contactlab::dynamics::RestForce>,
    /// Outer iterations summed over the steps.
    pub outer_iterations: usize,
    /// The largest number of outer iterations of one step.
    pub max_outer_per_step: usize,
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
    observer: &mut dyn FnMut(&StepRecord, &[PairForce], &DynamicState),
) -> Result<(DynamicResult, DynamicMetrics)> {
    let mut backend = backend_from_name(&cs.backend, qp)?;
    let mut settings = OuterSettings {
        tol_j: cs.tol_j.unwrap_or(cs.accuracy.tol_j()),
        max_outer: cs.max_outer,
        pruning: cs.pruning,
        ..Default::default()
    };
    if let Some(k) = cs.max_inner {
        settings.inner.max_inner = k;
    }
    let mass = lumped_mass(&ds.scene.mesh, &ds.scene.mesh.x_ref, &ds.density)?;
    let mut system = System {
        mesh: &ds.scene.mesh,
        energy: &mut ds.scene.energy,
        eps: ds.scene.eps,
        mass,
    };
    let res = simulate(
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
    let m = dynamic_metrics(&res, free_mass, conserves);
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
        wall_time_s: res.wall_time_s,
    }
}
