//! `contactlab run SCENE --dynamic --dt DT --steps K [--scheme euler|newmark]`: time stepping
//! (§6) and its run directory. SCENE is a built-in scene or a scene file (masses from its
//! bodies' `density`, initial velocities from `velocity`, defaults from `[dynamics]`):
//!
//! - `history.csv`: one row per step ([`StepRecord`]: step, time, kinetic, elastic,
//!   potential, total, momentum_x/y/z, min_distance, admissible, active_contacts,
//!   contact_force, outer_iterations, status, step_energy, wall_time_s);
//! - `contacts.csv`: per step, the active pairs (step, time, kind, first, second, force,
//!   distance);
//! - `frames/frame_NNNNN.vtu` and `frames.pvd` (timestep = the step's time: ParaView plays it
//!   as an animation), with point data `speed`;
//! - `energy.svg` (kinetic, elastic, potential, total against time), `contact_force.svg`
//!   (total contact force against time, and the weight of the free bodies when the scene has
//!   gravity);
//! - `summary.json` (the settings and [`DynamicMetrics`]).

use crate::harness::case::{self, CaseSettings, DynamicMetrics};
use crate::harness::run::{validate_cli, RunArgs};
use crate::output::run_dir::{Contacts, DynamicProgress, Frames, History, RunDir};
use crate::output::svg::write_svg;
use crate::output::timeseries::{timeseries_svg, Line};
use crate::output::write_atomic;
use crate::scene::dynamic::DynamicScene;
use crate::scene::registry;
use crate::solve::dynamics::{DynamicLoop, DynamicSettings, Scheme, StepRecord};
use crate::solve::observer::{EveryK, Fanout, Observer};
use crate::solve::outer::OuterSettings;
use crate::solve::settings::RunSettings;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

#[derive(serde::Serialize)]
struct DynamicSummary {
    scene: String,
    dynamic: bool,
    dim: usize,
    n: Option<usize>,
    h: f64,
    eps: f64,
    dt: f64,
    steps: usize,
    scheme: &'static str,
    density: Vec<f64>,
    backend: String,
    pruning: &'static str,
    accuracy: &'static str,
    qp_tol: f64,
    /// `m g` of the free bodies for the scenes with gravity `g` (drop, drop3d, scene files
    /// with `gravity`).
    weight: Option<f64>,
    metrics: DynamicMetrics,
    params: serde_json::Value,
    settings: OuterSettings,
}

/// Parses `--scheme`.
pub fn parse_scheme(s: &str) -> Result<Scheme> {
    Scheme::from_name(s).with_context(|| format!("--scheme {s:?}: expected one of euler, newmark"))
}

/// `contactlab run … --dynamic` on a built-in scene.
pub fn run_dynamic(a: &RunArgs, rs: &RunSettings) -> Result<()> {
    if !a.perturb.is_empty() || a.heights.is_some() {
        bail!("--perturb and --heights set the balloons' static start; they are not available with --dynamic");
    }
    let scheme = parse_scheme(a.scheme.as_deref().unwrap_or("euler"))?;
    let mut params = registry::parse_params(&a.params)?;
    if let Some(mu) = a.mu {
        params.insert("mu".into(), mu);
    }
    if let Some(c) = a.c {
        if !a.scene.starts_with("balloons") {
            bail!(
                "--c (a gas constant) is an option of the balloons scenes, not of {:?}",
                a.scene
            );
        }
        params.insert("c".into(), c);
    }
    let (ds, params_json) = registry::build_dynamic_scene_json(&a.scene, a.n, a.eps, &params)?;
    let is_dynamic_scene = registry::is_dynamic_only(&a.scene);
    let dt = a.dt.unwrap_or(ds.dt);
    let steps = a.steps.unwrap_or(ds.steps);
    if !is_dynamic_scene && (a.dt.is_none() || a.steps.is_none()) {
        bail!(
            "scene {:?} is static: with --dynamic give --dt and --steps (it runs with density 1 per body and zero initial velocity)",
            a.scene
        );
    }
    let g = params.get("g").copied().unwrap_or(9.81);
    let weight_g = matches!(a.scene.as_str(), "drop" | "drop3d").then_some(g);
    let label = a.scene.clone();
    run_prepared(
        a,
        rs,
        ds,
        params_json,
        DynamicSettings { dt, steps, scheme },
        is_dynamic_scene,
        weight_g,
        &label,
    )
}

/// `contactlab run FILE.toml --dynamic`: the scene file's masses (`density`), initial
/// velocities (`velocity`) and `[dynamics]` defaults; `--dt`, `--steps`, `--scheme` override
/// them, and Δt and the number of steps must come from one or the other.
pub fn run_dynamic_file(
    a: &RunArgs,
    rs: &RunSettings,
    file: crate::scene::file::SceneFile,
    params_json: serde_json::Value,
) -> Result<()> {
    let spec = file.dynamics.clone();
    let path = file.path.display().to_string();
    let scheme = parse_scheme(
        a.scheme
            .as_deref()
            .or(spec.scheme.as_deref())
            .unwrap_or("euler"),
    )?;
    let dt = a.dt.or(spec.dt).with_context(|| {
        format!("{path}: --dynamic needs a time step: give --dt or `dt` in the file's [dynamics]")
    })?;
    let steps = a.steps.or(spec.steps).with_context(|| {
        format!(
            "{path}: --dynamic needs a number of steps: give --steps or `steps` in the file's [dynamics]"
        )
    })?;
    let weight_g = file
        .gravity
        .as_ref()
        .map(|g| g.iter().map(|c| c * c).sum::<f64>().sqrt());
    let ds = file.into_dynamic()?;
    let label = ds.scene.name.clone();
    run_prepared(
        a,
        rs,
        ds,
        params_json,
        DynamicSettings { dt, steps, scheme },
        true,
        weight_g,
        &label,
    )
}

/// The stepping and the run directory, shared by the built-in scenes and the scene files.
/// `weight_g`: `|g|` when the contact-force plot gets the free bodies' weight `m g`.
// The flags (`a`: output, frames, progress) and the run settings (`rs`: a scene file's
// `[solver]` already merged) are both needed.
#[allow(clippy::too_many_arguments)]
fn run_prepared(
    a: &RunArgs,
    rs: &RunSettings,
    mut ds: DynamicScene,
    params_json: serde_json::Value,
    dyn_settings: DynamicSettings,
    is_dynamic_scene: bool,
    weight_g: Option<f64>,
    label: &str,
) -> Result<()> {
    let DynamicSettings { dt, steps, scheme } = dyn_settings.clone();
    dyn_settings
        .validate()
        .map_err(|e| anyhow::anyhow!("--dt/--steps: {e}"))?;
    validate_cli(rs)?;
    let cs = CaseSettings {
        backend: rs.backend.clone(),
        accuracy: rs.accuracy,
        pruning: rs.pruning,
        tol_j: rs.tol_j,
        max_outer: rs.max_outer,
        max_inner: Some(rs.max_inner),
        time_limit_s: None,
        newton_model: rs.hessian_model,
        outer_method: rs.outer_method,
        sqp_curvature: rs.sqp_curvature,
        sqp_normal_stiffness: rs.sqp_normal_stiffness,
        sqp_drop_endpoint_rows: rs.sqp_drop_endpoint_rows,
        sqp_extend_rows: rs.sqp_extend_rows,
        sqp_drop_vertex_rows: rs.sqp_drop_vertex_rows,
        sqp_drop_side_rows: rs.sqp_drop_side_rows,
        sqp_extend_fixed: rs.sqp_extend_fixed,
        sqp_path_rows: rs.sqp_path_rows,
        sqp_implying_rows: rs.sqp_implying_rows,
        sqp_extrapolate: rs.sqp_extrapolate,
        sqp_normal_active_rel: rs.sqp_normal_active_rel,
        sqp_edge_edge_stiffness: rs.sqp_edge_edge_stiffness,
        second_order_max_dofs: 0,
        escape_saddles: false,
    };
    let qps = rs.qp_settings();
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("runs/{label}-dynamic-{}", scheme.as_str())));
    let mesh = ds.scene.mesh.clone();
    let dim = mesh.dim;
    let eps = ds.scene.eps;
    let mut frames = EveryK {
        k: a.frame_every,
        last: Some(steps),
        inner: Frames::create(&out, &mesh)?,
    };
    let mut hist = History::create(&out.join("history.csv"))?;
    let mut contacts = Contacts::create(&out.join("contacts.csv"))?;
    let mut records: Vec<StepRecord> = Vec::new();
    let mut progress = DynamicProgress {
        scheme: scheme.as_str(),
        backend: rs.backend.clone(),
        steps,
        eps,
    };
    let mut files = RunDir::<DynamicLoop>::new(vec![&mut hist, &mut contacts, &mut frames]);
    let mut observers: Vec<&mut dyn Observer<DynamicLoop>> = vec![&mut records, &mut files];
    if !a.quiet {
        observers.push(&mut progress);
    }
    let (res, metrics) =
        case::execute_dynamic(&mut ds, &cs, &dyn_settings, &qps, &mut Fanout(observers))?;
    files.into_result()?;
    let weight = weight_g.map(|g| metrics.free_mass * g);
    // pictures
    let series = |f: fn(&StepRecord) -> f64| -> Vec<(f64, f64)> {
        records.iter().map(|r| (r.time, f(r))).collect()
    };
    let title = format!(
        "{} {} dt={} steps={} backend={}",
        label,
        scheme.as_str(),
        dt,
        res.steps,
        rs.backend
    );
    let energy = timeseries_svg(
        &[
            Line {
                label: "total".into(),
                points: series(|r| r.total),
                dashed: false,
            },
            Line {
                label: "kinetic".into(),
                points: series(|r| r.kinetic),
                dashed: false,
            },
            Line {
                label: "elastic".into(),
                points: series(|r| r.elastic),
                dashed: false,
            },
            Line {
                label: "potential".into(),
                points: series(|r| r.potential),
                dashed: false,
            },
        ],
        &title,
        "time",
        "energy",
    );
    write_svg(&out.join("energy.svg"), &energy)?;
    let mut lines = vec![Line {
        label: "total contact force Σμ".into(),
        points: series(|r| r.contact_force),
        dashed: false,
    }];
    if let Some(w) = weight {
        let t1 = records.last().map_or(0.0, |r| r.time);
        lines.push(Line {
            label: "weight m g".into(),
            points: vec![(0.0, w), (t1, w)],
            dashed: true,
        });
    }
    write_svg(
        &out.join("contact_force.svg"),
        &timeseries_svg(&lines, &title, "time", "force"),
    )?;
    let summary = DynamicSummary {
        scene: ds.scene.name.clone(),
        dynamic: is_dynamic_scene,
        dim,
        n: a.n,
        h: ds.scene.h,
        eps,
        dt,
        steps,
        scheme: scheme.as_str(),
        density: ds.density.clone(),
        backend: rs.backend.clone(),
        pruning: rs.pruning.as_str(),
        accuracy: rs.accuracy.as_str(),
        qp_tol: qps.eps_abs,
        weight,
        metrics: metrics.clone(),
        params: params_json,
        settings: case::dynamic_outer_settings(&cs, &qps),
    };
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    println!(
        "{} {}: {} of {steps} steps ({}), E {:.10e} -> {:.10e}, K_end = {:.3e}, all admissible = {}, {} steps not converged (max outer), {} not certified (fixed point, max kappa {:.3e}), {:.1} s -> {}",
        label,
        scheme.as_str(),
        metrics.steps_taken,
        metrics.status,
        metrics.initial_energy,
        metrics.final_energy,
        metrics.final_kinetic,
        metrics.all_admissible,
        metrics.steps_max_outer,
        metrics.steps_fixed_point,
        metrics.max_kappa,
        metrics.wall_time_s,
        out.display()
    );
    if !metrics.all_admissible {
        bail!(
            "dynamic run violated a guarantee: all_admissible = false, status = {}",
            metrics.status
        );
    }
    if metrics.status != "completed" {
        return Err(crate::harness::run::RunFinished {
            status: metrics.status.to_string(),
        }
        .into());
    }
    Ok(())
}
