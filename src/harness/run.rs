//! `contactlab run SCENE` for a static run: builds the scene (built-in by name, or a scene
//! file), runs the outer loop with the chosen backend and writes the run directory
//! (`docs/run-directory.md`). With `--dynamic` it hands over to [`super::dynamic_run`].
//!
//! Exit codes of the command line: 0 a run converged (or a command succeeded), 1 a run
//! finished with a failure status (its directory written, [`RunFinished`]), 2 an error (bad
//! input, inadmissible start, a violated guarantee), 101 a panic.

use crate::contact::near_pairs;
use crate::energy::HessianModel;
use crate::harness::diagnostics::{
    contact_pattern, ConvergedDiagnostics, DiagnosticSettings, PairMultiplier,
};
use crate::harness::scene_file::{self, load_scene_file};
use crate::harness::{case, contact_output, dynamic_run, restart};
use crate::output::run_dir::{Frames, History, RunDir, StaticProgress};
use crate::output::svg::{projection_svg, shapes_and_energy_svg, write_svg, Shape, Shape3};
use crate::output::vtk::write_vtu_with;
use crate::output::write_atomic;
use crate::scene::balloons::{self, BalloonsParams};
use crate::scene::registry;
use crate::scene::ring::{self, RingParams};
use crate::scene::Scene;
use crate::solve::certificate::Certificate;
use crate::solve::observer::{EveryK, Fanout, Observer};
use crate::solve::outer::{run_observed, OuterEvent, OuterLoop, OuterSettings, Pruning, RunStatus};
use crate::solve::second_order::{SecondOrder, SECOND_ORDER_MAX_DOFS};
use crate::solve::settings::{Accuracy, RunSettings};
use crate::solve::sqp::{Curvature, OuterMethod};
use anyhow::{anyhow, bail, Result};
use contactlab_solvers::{backend_from_name, QpError};
use std::path::PathBuf;

// The field docs are the command line's help texts (clap prints them as written), not
// rustdoc: `[dynamics]` names a scene-file table and `<scene>` a placeholder.
#[derive(clap::Args, Clone)]
#[allow(
    missing_docs,
    rustdoc::broken_intra_doc_links,
    rustdoc::invalid_html_tags
)]
pub struct RunArgs {
    /// Scene name: balloons, ring (2D); sheets, rod, solids, balloons3d (3D); with --dynamic
    /// also drop, collide (2D), drop3d (3D); or a scene file `path/to/scene.toml` (docs/scene-files.md), whose `[solver]` settings apply unless the corresponding flag is given.
    #[arg(default_value = "balloons")]
    pub scene: String,
    /// Sub-problem backend (the backend registry, `contactlab_solvers::registry`).
    #[arg(long, default_value = contactlab_solvers::DEFAULT_BACKEND, help = backend_help())]
    pub backend: String,
    /// Mesh level: elements per membrane (balloons), edges of the ring (both default 40), or
    /// the 3D scene's level (default: the scene's own, docs/scenes.md).
    #[arg(long)]
    pub n: Option<usize>,
    /// A scene parameter NAME=VALUE (ring: p, aspect, half_span; the 3D scenes: docs/scenes.md
    /// "3D"); repeatable.
    #[arg(long = "param")]
    pub params: Vec<String>,
    /// Gas constant C (balloons: default 50; balloons3d: default 30).
    #[arg(long)]
    pub c: Option<f64>,
    /// Elasticity coefficient μ (default 1).
    #[arg(long)]
    pub mu: Option<f64>,
    /// ε (default h/10).
    #[arg(long)]
    pub eps: Option<f64>,
    /// Relative perturbation of one C_i, as BALLOON:VALUE (e.g. 0:1e-3); repeatable.
    #[arg(long = "perturb", value_parser = parse_perturb)]
    pub perturb: Vec<(usize, f64)>,
    /// Initial heights of the four balloons, comma-separated (e.g. 0.9,0.2,0.9,0.2).
    #[arg(long, value_delimiter = ',')]
    pub heights: Option<Vec<f64>>,
    /// Which pairs of T(ψ) the sub-problems carry: lazy (default), trust-region, all-pairs.
    #[arg(long, default_value = "lazy", value_parser = parse_pruning)]
    pub pruning: Pruning,
    /// Lazy rows: initial working-set radius cap relative to the median edge length (lazy only).
    #[arg(long, default_value_t = 0.25)]
    pub lazy_start: f64,
    /// Initial trust-region half-width δ0 relative to the median edge length (trust-region only).
    #[arg(long, default_value_t = 1.0)]
    pub trust_delta0: f64,
    /// Inner (Newton-type) steps per T(ψ) at most; 1 gives inexact sub-problems.
    #[arg(long, default_value_t = 50)]
    pub max_inner: usize,
    /// Do not warm-start the QP duals (OSQP, Uzawa; Clarabel never warm-starts).
    #[arg(long)]
    pub no_warm_start: bool,
    /// Hessian of the inner steps' quadratic model: shifted (element terms projected, gas and
    /// pressure exact, an adaptive shift; the default), shifted-tight (the same, its shift
    /// bisected to within 2% of the smallest that makes the model definite) or projected
    /// (every element block projected, the previous model). docs/method.md, "The Newton model".
    #[arg(long, default_value = "shifted", value_parser = parse_newton_model)]
    pub newton_model: HessianModel,
    /// The outer method: auto (Pantz's map while it converges, then sqp with the one command
    /// line's settings and --sqp-normal-active-rel 0.001 --sqp-edge-edge-stiffness 100 once it
    /// creeps or stops uncertified; docs/method.md, "Pantz's map, then SQP"), pantz (the
    /// paper's T(ψ) steps throughout) or sqp (steps on the linearized true distances, with a
    /// correction, an exact and a continuous check, Pantz's step as the fallback;
    /// docs/method.md, "The SQP outer method").
    #[arg(long, default_value_t = OuterMethod::default(), value_parser = parse_outer_method)]
    pub outer_method: OuterMethod,
    /// With --outer-method sqp: the constraints' curvature −Σ μ_k ∇²d_k in the QP's Hessian:
    /// off, psd (each pair's block projected to its PSD part), full (the model's shift keeps
    /// it convex), tangent (each block on its pair's tangent space, then projected), interior
    /// (full, for the pairs whose closest points are inside both elements only) or auto
    /// (interior, with --sqp-normal-stiffness and --sqp-extrapolate, where the energy's Newton
    /// model is indefinite — a gas or a pressure load — and none of the three elsewhere).
    /// docs/method.md, "The SQP outer method".
    #[arg(long, default_value_t = Curvature::default().as_str().to_string(), value_parser = parse_curvature)]
    pub sqp_curvature: String,
    /// With --outer-method sqp: γ ≥ 0, the model gets γ·max diag(H)·∇d∇dᵀ for each pair with a
    /// positive multiplier at the last step (0: none). docs/method.md, "The SQP outer method".
    #[arg(long, default_value_t = 0.0, value_parser = parse_normal_stiffness)]
    pub sqp_normal_stiffness: f64,
    /// With --outer-method sqp: leave out of the QP a row whose closest point is on the
    /// boundary of one of its elements (an edge's endpoint; a face's edge or vertex) when the
    /// same vertex or edge has an interior row against another element containing that point
    /// (implied in the true geometry; linearized, it cuts the sliding). docs/method.md, "Rows
    /// implied by another row". `--sqp-drop-endpoint-rows false` turns off a scene file's
    /// `sqp_drop_endpoint_rows = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_drop_endpoint_rows: bool,
    /// SQP: take a row whose closest point is on an element's boundary against the element
    /// extended past it (the line through an edge; in 3D the line–line distance of two curve
    /// edges) where the body turns towards the other side there, so that the row does not cut
    /// a slide past the boundary (2D and 3D curves; docs/method.md, "Rows against the extended
    /// element"). `--sqp-extend-rows false` turns off a scene file's `sqp_extend_rows = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_extend_rows: bool,
    /// SQP, 2D: leave out a vertex's row whose closest point is a vertex of the other body when
    /// that vertex's row against an edge at the first is in the QP (implied; docs/method.md,
    /// "Rows implied by another row"). `--sqp-drop-vertex-rows false` turns off a scene file's
    /// `sqp_drop_vertex_rows = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_drop_vertex_rows: bool,
    /// SQP, 2D: leave out a vertex's row against an edge of the other body (closest point
    /// inside the edge) when one endpoint's row against an edge at the vertex is in the QP and
    /// the other endpoint lies farther from that edge's line: the side of a corner passing over
    /// the vertex (docs/method.md, "Rows against the side of a corner"). `--sqp-drop-side-rows
    /// false` turns off a scene file's `sqp_drop_side_rows = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_drop_side_rows: bool,
    /// SQP, with --sqp-extend-rows: against an element whose vertices are all fixed, take the
    /// extended row however far past the boundary the chain test has to walk (otherwise at
    /// most 4 edges): a fixed element's line does not move, so its row is exact at any
    /// distance (docs/method.md, "Rows against the extended element"). `--sqp-extend-fixed
    /// false` turns off a scene file's `sqp_extend_fixed = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_extend_fixed: bool,
    /// SQP: add a row the QP's solution violates only where the pair's exact distance comes
    /// within ε + δ on the straight motion to that solution (docs/method.md, "Rows by the
    /// step's path"). `--sqp-path-rows false` turns off a scene file's `sqp_path_rows = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_path_rows: bool,
    /// SQP, 2D, with --sqp-drop-endpoint-rows or --sqp-drop-vertex-rows: where a violated row
    /// would be left out if a row implying it were in the QP, add that row (interior, or
    /// extended with --sqp-extend-rows) in the lazy round (docs/method.md, "Adding the implying
    /// rows"). `--sqp-implying-rows false` turns off a scene file's `sqp_implying_rows = true`.
    #[arg(long, num_args = 0..=1, default_missing_value = "true", default_value_t = false,
          action = clap::ArgAction::Set)]
    pub sqp_implying_rows: bool,
    /// SQP: after a full step is accepted, try 2, 4, …, 2^K times it while each trial passes
    /// every test of the line search and lowers J further; the last accepted is kept
    /// (docs/method.md, "Extrapolating a full step"; 0: off).
    #[arg(long, default_value_t = 0)]
    pub sqp_extrapolate: usize,
    /// SQP: the normal stiffness (--sqp-normal-stiffness) only on the pairs whose multiplier at
    /// the last step is at least this fraction of the largest, in [0, 1] (0: every pair with a
    /// positive multiplier, which with an interior-point backend is every pair of the last
    /// QP). docs/method.md, "The contact terms from the pairs in contact".
    #[arg(long, default_value_t = 0.0)]
    pub sqp_normal_active_rel: f64,
    /// SQP: with --sqp-curvature interior, keep the edge–edge pairs of surfaces' and solids'
    /// edges and give them F times the normal stiffness (0: left out). docs/method.md, "The
    /// contact terms from the pairs in contact".
    #[arg(long, default_value_t = 0.0)]
    pub sqp_edge_edge_stiffness: f64,
    /// Accuracy preset: low, default or high (QP tolerance per backend and tol_J; docs/method.md,
    /// "Accuracy presets"). --qp-tol and --tol-j override its values.
    #[arg(long, default_value = "default", value_parser = parse_accuracy)]
    pub accuracy: Accuracy,
    /// Relative energy tolerance of the outer stopping rule (default: the preset's).
    #[arg(long)]
    pub tol_j: Option<f64>,
    /// Maximum outer iterations.
    #[arg(long, default_value_t = 2000)]
    pub max_outer: usize,
    /// Wall-time limit in seconds: the run then ends with status time_limit and its last
    /// admissible iterate (checked between inner steps; a QP under way is finished first).
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Backend tolerance (eps_abs = eps_rel); default: the preset's (default preset: 1e-9
    /// clarabel, 1e-8 uzawa, 1e-6 osqp).
    #[arg(long)]
    pub qp_tol: Option<f64>,
    /// Run directory (default runs/<scene>-default).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Start from the positions of a saved state of the same scene (a run directory's
    /// `final.vtu` or a frame) instead of the scene's φ_0 (static runs; docs/cli.md).
    #[arg(long)]
    pub start_from: Option<PathBuf>,
    /// With --start-from: move every free dof by A·h·u, u uniform in [−1, 1] (fixed seed),
    /// halving A until the start is admissible; the A used is in summary.json's params.
    #[arg(long, default_value_t = 0.0)]
    pub start_perturb: f64,
    /// Write a VTK frame every K outer iterations (the last is always written).
    #[arg(long, default_value_t = 1)]
    pub frame_every: usize,
    /// The second-order check of a converged static run (summary.json `second_order`;
    /// docs/method.md, "The second-order check") up to this many free dofs (`not_computed`
    /// above); 0: no check.
    #[arg(long, default_value_t = SECOND_ORDER_MAX_DOFS)]
    pub second_order_max_dofs: usize,
    /// The backend of the minimality certificate's dual QP, used from 3 000 generators on
    /// (default: the registry's, Clarabel). `ip` is the one for large 3D states
    /// (docs/method.md, "The minimality certificate").
    #[arg(long, value_name = "BACKEND")]
    pub certificate_backend: Option<String>,
    /// Where that check finds a converged state is not a minimum (a saddle of the contact
    /// set), go on from the lower admissible point it found (an outer step `escape`, at most
    /// 10; docs/method.md, "The second-order check"). The default of static runs with the
    /// `auto` and `sqp` outer methods; with `pantz` only when given (an error with --dynamic).
    #[arg(long, conflicts_with = "no_escape_saddles")]
    pub escape_saddles: bool,
    /// Stop at a certified state even where the second-order check finds it is not a minimum
    /// (the check is still reported).
    #[arg(long)]
    pub no_escape_saddles: bool,
    /// No progress line.
    #[arg(long)]
    pub quiet: bool,
    /// Time stepping (§6): each step minimizes ½∫m|v_(i+1) − v_i|² + J over A_(h,ε) with the
    /// same outer loop (docs/method.md).
    #[arg(long)]
    pub dynamic: bool,
    /// Time step (--dynamic; default: the dynamic scene's, or the scene file's [dynamics]).
    #[arg(long)]
    pub dt: Option<f64>,
    /// Number of time steps (--dynamic; default: the dynamic scene's, or the scene file's
    /// [dynamics]).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Time-stepping scheme: euler (implicit Euler, default) or newmark (average
    /// acceleration).
    #[arg(long)]
    pub scheme: Option<String>,
}

/// `--backend`'s help: the names of the backend registry.
fn backend_help() -> String {
    format!(
        "Sub-problem backend: {}",
        contactlab_solvers::registry::backend_list_help()
    )
}

fn parse_accuracy(s: &str) -> Result<Accuracy, String> {
    Accuracy::from_name(s)
        .ok_or_else(|| format!("--accuracy {s:?}: expected one of low, default, high"))
}

fn parse_newton_model(s: &str) -> Result<HessianModel, String> {
    HessianModel::from_user_name(s).ok_or_else(|| {
        format!(
            "--newton-model {s:?}: expected one of {}",
            HessianModel::USER_NAMES
        )
    })
}

fn parse_normal_stiffness(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!(
            "--sqp-normal-stiffness {s:?}: expected a finite number ≥ 0"
        )),
    }
}

fn parse_curvature(s: &str) -> Result<String, String> {
    Curvature::from_name(s)
        .map(|c| c.as_str().to_string())
        .ok_or_else(|| {
            format!(
                "--sqp-curvature {s:?}: expected one of {}",
                Curvature::names()
            )
        })
}

fn parse_outer_method(s: &str) -> Result<OuterMethod, String> {
    OuterMethod::from_name(s).ok_or_else(|| {
        format!(
            "--outer-method {s:?}: expected one of {}",
            OuterMethod::names()
        )
    })
}

fn parse_pruning(s: &str) -> Result<Pruning, String> {
    Pruning::from_name(s)
        .ok_or_else(|| format!("--pruning {s:?}: expected one of lazy, trust-region, all-pairs"))
}

fn parse_perturb(s: &str) -> Result<(usize, f64), String> {
    let (i, v) = s
        .split_once(':')
        .ok_or_else(|| format!("--perturb {s:?}: expected BALLOON:VALUE, e.g. 0:1e-3"))?;
    let i: usize = i
        .parse()
        .map_err(|_| format!("--perturb {s:?}: balloon index {i:?} is not an integer 0..3"))?;
    if i > 3 {
        return Err(format!(
            "--perturb {s:?}: balloon index {i} out of range 0..3"
        ));
    }
    let v: f64 = v
        .parse()
        .map_err(|_| format!("--perturb {s:?}: value {v:?} is not a number"))?;
    Ok((i, v))
}

#[derive(serde::Serialize)]
struct Summary {
    /// Lemma 5.4 / 5.6 diagnostics (runs stopped by the stopping rule: `converged`,
    /// `fixed_point`).
    diagnostics: Option<DiagSummary>,
    /// The minimality certificate at the returned state (every run).
    certificate: Certificate,
    /// Certificates the run computed (the endgame's checks and the returned state's) and
    /// their seconds in all: `certificate.seconds` is the last one's only.
    certificate_calls: usize,
    certificate_seconds: f64,
    /// The second-order check at the returned state (`converged` runs: a KKT point;
    /// docs/method.md, "The second-order check").
    second_order: Option<SecondOrder>,
    /// Outer steps that left a saddle the second-order check found.
    escapes: usize,
    /// Whether the run escaped saddles (`false` with `--no-escape-saddles`).
    escape_saddles: bool,
    /// The bound of the second-order check in free dofs (`--second-order-max-dofs`; 0: off).
    second_order_max_dofs: usize,
    scene: String,
    dim: usize,
    n: usize,
    h: f64,
    eps: f64,
    backend: String,
    pruning: &'static str,
    /// The outer method (`pantz`, `sqp`, `auto`).
    outer_method: &'static str,
    status: &'static str,
    outer_iterations: usize,
    /// Outer steps that were SQP steps (0 for `pantz`).
    sqp_steps: usize,
    /// Outer steps where the SQP step collapsed and Pantz's step was taken (0 for `pantz`).
    fallback_steps: usize,
    /// `auto`: the first outer step of its SQP phase (`null`: Pantz's map throughout, or
    /// another method).
    sqp_from: Option<usize>,
    /// The backend tolerance the SQP method tightened to for its certificate (`null` where it
    /// kept `qp_tol`).
    qp_tol_tightened: Option<f64>,
    inner_iterations: usize,
    backend_iterations: usize,
    /// QPs the backend did not solve and handed to the one behind it (`ip`: Clarabel).
    qp_fallbacks: usize,
    initial_energy: f64,
    final_energy: f64,
    /// The final polish at ε (docs/method.md, "The row margin"), when it ran.
    polish: Option<crate::solve::outer::Polish>,
    min_distance: f64,
    closest_pair: String,
    wall_time_s: f64,
    contact_pattern: Vec<[String; 2]>,
    state: String,
    energy_monotone: bool,
    all_iterates_admissible: bool,
    params: serde_json::Value,
    settings: OuterSettings,
    qp_tol: f64,
    accuracy: &'static str,
    /// Loads, reactions and contact forces of the returned state.
    contact: contact_output::ContactSummary,
}

/// Loads a scene file and applies its `[solver]` settings to `settings` for the keys whose
/// flag was not given explicitly (a flag on the command line wins over the file).
fn scene_from_file(
    a: &RunArgs,
    settings: &mut RunSettings,
    explicit: &dyn Fn(&str) -> bool,
) -> Result<(crate::scene::file::SceneFile, serde_json::Value)> {
    for (flag, given) in [
        ("--n", a.n.is_some()),
        ("--param", !a.params.is_empty()),
        ("--c", a.c.is_some()),
        ("--mu", a.mu.is_some()),
        ("--eps", a.eps.is_some()),
        ("--perturb", !a.perturb.is_empty()),
        ("--heights", a.heights.is_some()),
    ] {
        if given {
            bail!(
                "{flag} is an option of the built-in scenes; a scene file sets its own values ({})",
                a.scene
            );
        }
    }
    let f = load_scene_file(std::path::Path::new(&a.scene))?;
    let s = &f.solver;
    // `$id`: the flag's clap id; `$field`: the key of `[solver]` and of RunSettings.
    macro_rules! from_file {
        ($id:literal, $field:ident) => {
            from_file!($id, $field, |v| Ok::<_, anyhow::Error>(v))
        };
        ($id:literal, $field:ident, $convert:expr) => {
            if !explicit($id) {
                if let Some(v) = s.$field.clone() {
                    settings.$field = $convert(v)?;
                }
            }
        };
    }
    from_file!("backend", backend);
    from_file!("pruning", pruning, |v| Ok::<_, anyhow::Error>(
        scene_file::pruning(v)
    ));
    from_file!("max_outer", max_outer);
    from_file!("max_inner", max_inner);
    from_file!("lazy_start", lazy_start);
    from_file!("trust_delta0", trust_delta0);
    from_file!("tol_j", tol_j, |v| Ok::<_, anyhow::Error>(Some(v)));
    from_file!("qp_tol", qp_tol, |v| Ok::<_, anyhow::Error>(Some(v)));
    from_file!("accuracy", accuracy, |v: String| parse_accuracy(&v)
        .map_err(anyhow::Error::msg));
    from_file!("no_warm_start", warm_start);
    if !explicit("outer_method") {
        if let Some(m) = &s.outer_method {
            settings.outer_method = parse_outer_method(m).map_err(anyhow::Error::msg)?;
        }
    }
    if !explicit("newton_model") {
        if let Some(m) = &s.newton_model {
            settings.hessian_model = parse_newton_model(m).map_err(anyhow::Error::msg)?;
        }
    }
    if !explicit("sqp_curvature") {
        if let Some(c) = &s.sqp_curvature {
            settings.sqp_curvature = Curvature::from_name(c).ok_or_else(|| {
                anyhow!(
                    "{}: solver.sqp_curvature {c:?}: expected one of {}",
                    a.scene,
                    Curvature::names()
                )
            })?;
        }
    }
    from_file!("sqp_normal_stiffness", sqp_normal_stiffness);
    from_file!("sqp_drop_endpoint_rows", sqp_drop_endpoint_rows);
    from_file!("sqp_extend_rows", sqp_extend_rows);
    from_file!("sqp_drop_vertex_rows", sqp_drop_vertex_rows);
    from_file!("sqp_drop_side_rows", sqp_drop_side_rows);
    from_file!("sqp_extend_fixed", sqp_extend_fixed);
    from_file!("sqp_path_rows", sqp_path_rows);
    from_file!("sqp_implying_rows", sqp_implying_rows);
    from_file!("sqp_extrapolate", sqp_extrapolate);
    from_file!("sqp_normal_active_rel", sqp_normal_active_rel);
    from_file!("sqp_edge_edge_stiffness", sqp_edge_edge_stiffness);
    let params = serde_json::json!({
        "scene_file": a.scene,
        "bodies": f.body_names,
        "solver": f.solver,
        "dynamics": f.dynamics,
    });
    Ok((f, params))
}

impl RunArgs {
    /// The run settings the flags give (before a scene file's `[solver]`).
    pub fn settings(&self) -> RunSettings {
        RunSettings {
            backend: self.backend.clone(),
            accuracy: self.accuracy,
            pruning: self.pruning,
            tol_j: self.tol_j,
            qp_tol: self.qp_tol,
            max_outer: self.max_outer,
            max_inner: self.max_inner,
            lazy_start: self.lazy_start,
            trust_delta0: self.trust_delta0,
            warm_start: !self.no_warm_start,
            time_limit_s: self.time_limit,
            hessian_model: self.newton_model,
            outer_method: self.outer_method,
            sqp_curvature: Curvature::from_name(&self.sqp_curvature).unwrap_or_default(),
            sqp_normal_stiffness: self.sqp_normal_stiffness,
            sqp_drop_endpoint_rows: self.sqp_drop_endpoint_rows,
            sqp_extend_rows: self.sqp_extend_rows,
            sqp_drop_vertex_rows: self.sqp_drop_vertex_rows,
            sqp_drop_side_rows: self.sqp_drop_side_rows,
            sqp_extend_fixed: self.sqp_extend_fixed,
            sqp_path_rows: self.sqp_path_rows,
            sqp_implying_rows: self.sqp_implying_rows,
            sqp_extrapolate: self.sqp_extrapolate,
            sqp_normal_active_rel: self.sqp_normal_active_rel,
            sqp_edge_edge_stiffness: self.sqp_edge_edge_stiffness,
        }
    }
}

/// Checks `settings` ([`RunSettings::validate`]) in the command line's words: the flag and the
/// value (a bad backend name or QP tolerance in the backends' own words).
///
/// Also refuses the SQP model's settings with the Pantz outer method (as sweep files do):
/// they would be ignored. This is checked once the command line and a scene file's `[solver]`
/// are merged, since either may give the method.
pub(crate) fn validate_cli(settings: &RunSettings) -> Result<()> {
    if settings.outer_method != OuterMethod::Sqp {
        let set: Vec<String> = [
            (
                "--sqp-curvature",
                settings.sqp_curvature != Curvature::default(),
                settings.sqp_curvature.as_str().to_string(),
            ),
            (
                "--sqp-normal-stiffness",
                settings.sqp_normal_stiffness != 0.0,
                settings.sqp_normal_stiffness.to_string(),
            ),
            (
                "--sqp-drop-endpoint-rows",
                settings.sqp_drop_endpoint_rows,
                String::new(),
            ),
            ("--sqp-extend-rows", settings.sqp_extend_rows, String::new()),
            (
                "--sqp-extend-fixed",
                settings.sqp_extend_fixed,
                String::new(),
            ),
            (
                "--sqp-drop-vertex-rows",
                settings.sqp_drop_vertex_rows,
                String::new(),
            ),
            (
                "--sqp-drop-side-rows",
                settings.sqp_drop_side_rows,
                String::new(),
            ),
            ("--sqp-path-rows", settings.sqp_path_rows, String::new()),
            (
                "--sqp-implying-rows",
                settings.sqp_implying_rows,
                String::new(),
            ),
            (
                "--sqp-extrapolate",
                settings.sqp_extrapolate != 0,
                settings.sqp_extrapolate.to_string(),
            ),
            (
                "--sqp-normal-active-rel",
                settings.sqp_normal_active_rel != 0.0,
                settings.sqp_normal_active_rel.to_string(),
            ),
            (
                "--sqp-edge-edge-stiffness",
                settings.sqp_edge_edge_stiffness != 0.0,
                settings.sqp_edge_edge_stiffness.to_string(),
            ),
        ]
        .into_iter()
        .filter_map(|(flag, set, v)| set.then(|| format!("{flag} {v}").trim_end().to_string()))
        .collect();
        if !set.is_empty() {
            bail!(
                "{} set with the {} outer method: the SQP model's settings (--sqp-curvature, \
                 --sqp-normal-stiffness, --sqp-drop-endpoint-rows, --sqp-extend-rows, --sqp-extend-fixed, \
                 --sqp-drop-vertex-rows, --sqp-drop-side-rows, --sqp-path-rows, --sqp-implying-rows, --sqp-extrapolate, \
                 --sqp-normal-active-rel, --sqp-edge-edge-stiffness, or the same keys with underscores in a scene file's [solver]) apply to --outer-method sqp only \
                 (auto's SQP phase takes the one command line's, docs/method.md)",
                set.join(" and "),
                settings.outer_method.as_str()
            );
        }
    }
    if settings.sqp_extend_fixed && !settings.sqp_extend_rows {
        bail!(
            "--sqp-extend-fixed set without --sqp-extend-rows (or the same keys in a scene \
             file's [solver]): it lifts a limit of the extended rows, and does nothing \
             without them"
        );
    }
    if settings.sqp_implying_rows
        && !(settings.sqp_drop_endpoint_rows || settings.sqp_drop_vertex_rows)
    {
        bail!(
            "--sqp-implying-rows set without --sqp-drop-endpoint-rows or --sqp-drop-vertex-rows \
             (or the same keys in a scene file's [solver]): it adds the rows that imply the rows \
             those options leave out, and does nothing without them"
        );
    }
    let Err(e) = settings.validate() else {
        return Ok(());
    };
    let v = &e.value;
    Err(match e.key {
        "backend" => QpError::UnknownBackend(settings.backend.clone()).into(),
        "qp_tol" => QpError::InvalidSetting {
            name: "eps_abs",
            value: v.clone(),
            reason: "must be finite and > 0",
        }
        .into(),
        "max_outer" => anyhow!("--max-outer must be >= 1, got {v}"),
        "max_inner" => anyhow!("--max-inner must be >= 1, got {v}"),
        "lazy_start" => anyhow!("--lazy-start must be finite and >= 0, got {v}"),
        "trust_delta0" => anyhow!("--trust-delta0 must be finite and > 0, got {v}"),
        "time_limit_s" => anyhow!("--time-limit must be > 0 seconds, got {v}"),
        "tol_j" => anyhow!("--tol-j must be > 0, got {v}"),
        "sqp_normal_stiffness" => {
            anyhow!("--sqp-normal-stiffness must be finite and >= 0, got {v}")
        }
        "sqp_normal_active_rel" => {
            anyhow!("--sqp-normal-active-rel must be in [0, 1], got {v}")
        }
        "sqp_edge_edge_stiffness" => {
            anyhow!("--sqp-edge-edge-stiffness must be finite and >= 0, got {v}")
        }
        _ => e.into(),
    })
}

/// `contactlab run`: a static run (or, with `--dynamic`, a dynamic one) and its run
/// directory. `explicit(id)` tells whether the flag `id` was given on the command line (it
/// then wins over a scene file's `[solver]`).
pub fn run_cmd(a: RunArgs, explicit: &dyn Fn(&str) -> bool) -> Result<()> {
    let from_file = a.scene.ends_with(".toml");
    let mut rs = a.settings();
    if a.dynamic && a.escape_saddles {
        bail!("--escape-saddles is an option of static runs, not of --dynamic");
    }
    if a.dynamic && a.certificate_backend.is_some() {
        bail!("--certificate-backend is an option of static runs, not of --dynamic");
    }
    if a.dynamic && (a.start_from.is_some() || a.start_perturb != 0.0) {
        bail!("--start-from and --start-perturb are options of static runs, not of --dynamic");
    }
    if a.dynamic {
        if from_file {
            let (f, params) = scene_from_file(&a, &mut rs, explicit)?;
            return dynamic_run::run_dynamic_file(&a, &rs, f, params);
        }
        return dynamic_run::run_dynamic(&a, &rs);
    }
    if a.dt.is_some() || a.steps.is_some() || a.scheme.is_some() {
        bail!("--dt, --steps and --scheme are options of a dynamic run: add --dynamic");
    }
    if registry::is_dynamic_only(&a.scene) {
        bail!(
            "scene {:?} is a dynamic scene: run it with --dynamic [--dt DT --steps K --scheme euler|newmark]",
            a.scene
        );
    }
    let n = if from_file {
        0
    } else {
        a.n.unwrap_or_else(|| registry::default_n(&a.scene))
    };
    let (scene, params) = match a.scene.as_str() {
        _ if from_file => {
            let (f, params) = scene_from_file(&a, &mut rs, explicit)?;
            (f.scene, params)
        }
        "balloons" => {
            let mut params = BalloonsParams {
                n,
                c: a.c.unwrap_or(50.0),
                mu: a.mu.unwrap_or(1.0),
                eps: a.eps,
                ..Default::default()
            };
            for (i, v) in &a.perturb {
                params.perturb[*i] = *v;
            }
            if let Some(hs) = &a.heights {
                if hs.len() != 4 {
                    bail!(
                        "--heights takes 4 values (one per balloon), got {}",
                        hs.len()
                    );
                }
                params.heights.copy_from_slice(hs);
            }
            for (k, v) in registry::parse_params(&a.params)? {
                match k.as_str() {
                    "n_ratio" => params.n_ratio = v,
                    other => bail!(
                        "--param {other}: the balloons take --param n_ratio=R only (and --c, --mu, --perturb, --heights)"
                    ),
                }
            }
            (balloons::build(&params)?, serde_json::to_value(&params)?)
        }
        "ring" => {
            if !a.perturb.is_empty() || a.heights.is_some() || a.c.is_some() {
                bail!("--c, --perturb and --heights are balloons options; the ring takes --mu and --param p=..,aspect=..,half_span=..");
            }
            let mut params = RingParams {
                n,
                mu: a.mu.unwrap_or(1.0),
                eps: a.eps,
                ..Default::default()
            };
            for (k, v) in registry::parse_params(&a.params)? {
                match k.as_str() {
                    "p" => params.p = v,
                    "aspect" => params.aspect = v,
                    "half_span" => params.half_span = v,
                    other => bail!("--param {other:?}: the ring knows p, aspect, half_span (and --mu, --eps, --n)"),
                }
            }
            (ring::build(&params)?, serde_json::to_value(&params)?)
        }
        name => {
            if !a.perturb.is_empty() || a.heights.is_some() {
                bail!("--perturb and --heights are options of the 2D balloons, not of {name:?}");
            }
            let mut p = registry::parse_params(&a.params)?;
            if let Some(mu) = a.mu {
                p.insert("mu".into(), mu);
            }
            if let Some(c) = a.c {
                if name != "balloons3d" {
                    bail!(
                        "--c (a gas constant) is an option of the balloons scenes, not of {name:?}"
                    );
                }
                p.insert("c".into(), c);
            }
            let scene = registry::build_scene(name, n, a.eps, &p)?;
            let json = registry::params_json(name, n, a.eps, &p)?.unwrap_or_default();
            (scene, json)
        }
    };
    let (scene, params) = match &a.start_from {
        Some(path) => {
            let st = restart::start_state(&scene, path, a.start_perturb)?;
            let mut params = params;
            if let Some(m) = params.as_object_mut() {
                m.insert("start_from".into(), path.display().to_string().into());
                m.insert("start_perturb".into(), st.amplitude.into());
                m.insert("start_unperturbed_vertices".into(), st.unperturbed.into());
            }
            (Scene { x0: st.x, ..scene }, params)
        }
        None if a.start_perturb != 0.0 => {
            bail!("--start-perturb perturbs the state of --start-from FILE: give that too")
        }
        None => (scene, params),
    };
    validate_cli(&rs)?;
    let qps = rs.qp_settings();
    let mut backend = backend_from_name(&rs.backend, &qps)?;
    let mut settings = rs.outer_settings();
    settings.second_order_max_dofs = a.second_order_max_dofs;
    if let Some(b) = &a.certificate_backend {
        if let Err(e) = backend_from_name(b, &qps) {
            bail!("--certificate-backend {b:?}: {e}");
        }
        settings.certificate_backend = Some(b.clone());
    }
    let method = settings.method;
    // Pantz's map stays the paper's method unless asked: it escapes only with the flag.
    settings.escape_saddles =
        a.escape_saddles || (!a.no_escape_saddles && method != OuterMethod::Pantz);
    // a scene file's n: its number of vertices
    let n = if from_file { scene.mesh.nv() } else { n };
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("runs/{}-default", scene.name)));
    let mesh = &scene.mesh;
    let (energy, eps) = (&scene.energy, scene.eps);
    let mut frames = EveryK {
        k: a.frame_every,
        last: None,
        inner: Frames::create(&out, mesh)?.with_fields(Box::new(move |x, rows, mult| {
            contact_output::frame_fields(mesh, energy, x, eps, rows, mult)
        })),
    };
    let mut contacts =
        contact_output::StaticContacts::create(&out.join("contacts.csv"), mesh, energy, eps)?;
    let mut hist = History::create(&out.join("history.csv"))?;
    let mut trace = Trace::default();
    let mut progress = StaticProgress {
        backend: rs.backend.clone(),
        pruning: rs.pruning.as_str(),
        eps: scene.eps,
    };
    let mut files = RunDir::<OuterLoop>::new(vec![&mut hist, &mut contacts, &mut frames]);
    let mut observers: Vec<&mut dyn Observer<OuterLoop>> = vec![&mut trace, &mut files];
    if !a.quiet {
        observers.push(&mut progress);
    }
    let res = run_observed(
        mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        backend.as_mut(),
        &settings,
        &mut Fanout(observers),
    )?;
    files.into_result()?;
    let Trace {
        energies,
        snapshots,
        monotone,
        admissible,
        last_qp,
    } = trace;
    // The state the run returns, its last admissible iterate, whatever the status (after an
    // inadmissible or energy-increasing step the last frame is that step's iterate).
    let final_fields =
        contact_output::frame_fields(mesh, energy, &res.x, eps, &res.last_rows, &res.multipliers);
    write_vtu_with(
        &out.join("final.vtu"),
        mesh.dim,
        &res.x,
        &mesh.edges,
        vtk_triangles(mesh),
        &mesh.tets,
        &final_fields.fields(),
    )?;
    let contact_summary =
        contact_output::write_reactions(&out.join("reactions.csv"), &scene, &res)?;
    let near = near_pairs(mesh, &res.x, 1.01 * scene.eps, false);
    let pattern = contact_pattern(mesh, &res.x, &near, scene.eps);
    let names: Vec<[String; 2]> = pattern
        .iter()
        .map(|&(i, j)| [mesh.bodies[i].name.clone(), mesh.bodies[j].name.clone()])
        .collect();
    let state = registry::classify_state(&scene.name, mesh, &res.x, scene.eps, &pattern)
        .unwrap_or_else(|| contact_state(&names));
    // Picture: initial, an intermediate and the final shapes, J beside them.
    let mid = snapshots.len() / 2;
    let panels = [
        ("initial (k=0)".to_string(), &snapshots[0].1),
        (
            format!("intermediate (k={})", snapshots[mid].0),
            &snapshots[mid].1,
        ),
        (format!("final (k={})", res.outer_iterations), &res.x),
    ];
    let title = format!(
        "{} n={} backend={} state={} J={:.10e}",
        scene.name, n, rs.backend, state, res.energy
    );
    let svg = if mesh.dim == 3 {
        let faces = drawn_faces(mesh);
        let shapes: Vec<Shape3> = panels
            .iter()
            .map(|(label, x)| Shape3 {
                label: label.clone(),
                x,
                edges: &mesh.edges,
                faces: &faces,
            })
            .collect();
        projection_svg(&shapes, &energies, &title)
    } else {
        let shapes: Vec<Shape> = panels
            .iter()
            .map(|(label, x)| Shape {
                label: label.clone(),
                x,
                edges: &mesh.edges,
                triangles: &mesh.triangles,
            })
            .collect();
        shapes_and_energy_svg(&shapes, &energies, &title)
    };
    write_svg(&out.join("shapes.svg"), &svg)?;
    // multipliers.csv whatever the status (the canonical duals at the returned iterate); the
    // summary's diagnostics for the runs at a fixed point only (converged, fixed_point)
    let diag_settings = DiagnosticSettings {
        raw_dual_rel: Some(1e-4),
        ..DiagnosticSettings::for_eps(scene.eps)
    };
    let at_fixed_point = matches!(res.status, RunStatus::Converged | RunStatus::FixedPoint);
    let diagnostics = match case::lemma_diagnostics_with(&scene, &res, &diag_settings) {
        Ok((diag, tol)) => {
            let mut w = csv::Writer::from_writer(Vec::new());
            for p in &diag.pairs {
                w.serialize(PairRow::from(p))?;
            }
            write_atomic(&out.join("multipliers.csv"), &w.into_inner()?)?;
            at_fixed_point.then_some((diag, tol))
        }
        Err(e) if at_fixed_point => return Err(e),
        Err(e) => {
            eprintln!("multipliers.csv not written: {e:#}");
            None
        }
    };
    let summary = Summary {
        certificate: res.certificate.clone(),
        certificate_calls: res.certificate_calls,
        certificate_seconds: res.certificate_seconds,
        second_order: res.second_order.clone(),
        escapes: res.escapes,
        escape_saddles: settings.escape_saddles,
        second_order_max_dofs: settings.second_order_max_dofs,
        diagnostics: diagnostics
            .as_ref()
            .map(|(d, tol)| DiagSummary::new(d, *tol)),
        scene: scene.name.clone(),
        dim: mesh.dim,
        n,
        h: scene.h,
        eps: scene.eps,
        backend: rs.backend.clone(),
        pruning: settings.pruning.as_str(),
        outer_method: method.as_str(),
        status: res.status.as_str(),
        outer_iterations: res.outer_iterations,
        sqp_steps: res.sqp_steps,
        fallback_steps: res.fallback_steps,
        sqp_from: res.sqp_from,
        qp_tol_tightened: res.qp_tol_tightened,
        inner_iterations: res.inner_iterations,
        backend_iterations: res.backend_iterations,
        qp_fallbacks: backend.fallback_solves(),
        initial_energy: energies[0].1,
        final_energy: res.energy,
        polish: res.polish,
        min_distance: res.min_distance.distance,
        closest_pair: res.min_distance.pair.to_string(),
        wall_time_s: res.wall_time_s,
        contact_pattern: names,
        state: state.clone(),
        energy_monotone: monotone,
        all_iterates_admissible: admissible,
        params,
        settings,
        qp_tol: qps.eps_abs,
        accuracy: rs.accuracy.as_str(),
        contact: contact_summary,
    };
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    println!(
        "{}: status {} after {} outer iterations{}, J = {:.12e}, kappa = {:.3e}{}, state {}, min distance / eps = {:.6}, {:.1} s -> {}",
        rs.backend,
        res.status.as_str(),
        res.outer_iterations,
        if method.uses_sqp() {
            format!(
                " ({}{} sqp, {} pantz fallback)",
                res.sqp_from
                    .map_or(String::new(), |k| format!("sqp from step {k}: ")),
                res.sqp_steps,
                res.fallback_steps
            )
        } else {
            String::new()
        },
        res.energy,
        res.certificate.kappa,
        // the second-order check where it was computed, and the saddles left
        match (&res.second_order, res.escapes) {
            (Some(so), 0) if so.status != "not_computed" => format!(", second order {}", so.status),
            (Some(so), k) if k > 0 => format!(", second order {} after {k} escape(s)", so.status),
            _ => String::new(),
        },
        state,
        res.min_distance.distance / scene.eps,
        res.wall_time_s,
        out.display()
    );
    if !monotone || !admissible {
        bail!("run violated a guarantee: energy_monotone = {monotone}, all_iterates_admissible = {admissible}");
    }
    if res.status != RunStatus::Converged {
        let mut status = res.status.as_str().to_string();
        if res.status == RunStatus::SubproblemFailed {
            // which backend status ended it, as a sweep row's `error` says
            status += "; ";
            status += &crate::solve::outer::subproblem_failure(last_qp.0, last_qp.1);
        }
        return Err(RunFinished { status }.into());
    }
    Ok(())
}

/// The state of a 3D run: the pairs of bodies in contact (`lower-upper;…`), or
/// `no-contact`.
fn contact_state(pairs: &[[String; 2]]) -> String {
    if pairs.is_empty() {
        "no-contact".into()
    } else {
        pairs
            .iter()
            .map(|[a, b]| format!("{a}-{b}"))
            .collect::<Vec<_>>()
            .join(";")
    }
}

/// The faces the 3D picture fills: those of bodies with a free vertex. A body whose vertices
/// are all fixed (the box of balloons3d, an obstacle sheet) is drawn by its edges alone, so
/// it does not hide what it holds.
fn drawn_faces(mesh: &crate::scene::mesh::Mesh) -> Vec<[usize; 3]> {
    mesh.bodies
        .iter()
        .filter(|b| b.vertices.iter().any(|&v| !mesh.fixed[v]))
        .flat_map(|b| b.faces.iter().map(|&f| mesh.faces[f]))
        .collect()
}

/// What a static run keeps of its iterates for the summary and the figures.
struct Trace {
    /// `(iteration, J)` per record.
    energies: Vec<(usize, f64)>,
    /// `(iteration, iterate)` per record.
    snapshots: Vec<(usize, Vec<f64>)>,
    /// No record's J above the one before.
    monotone: bool,
    /// Every record admissible.
    admissible: bool,
    /// The last record's outer step and its last QP's status.
    last_qp: (usize, &'static str),
}

impl Default for Trace {
    fn default() -> Self {
        Self {
            energies: Vec::new(),
            snapshots: Vec::new(),
            monotone: true,
            admissible: true,
            last_qp: (0, "none"),
        }
    }
}

impl Observer<OuterLoop> for Trace {
    fn iteration(&mut self, event: &OuterEvent<'_>) {
        let rec = event.record;
        if let Some(&(_, jprev)) = self.energies.last() {
            self.monotone &= rec.energy <= jprev;
        }
        self.admissible &= rec.admissible;
        self.last_qp = (rec.iteration, rec.qp_status);
        self.energies.push((rec.iteration, rec.energy));
        self.snapshots.push((rec.iteration, event.x.to_vec()));
    }
}

/// The triangles a VTK frame shows: the solid elements in 2D, the contact faces in 3D (the
/// surfaces' triangles and the solids' boundary).
fn vtk_triangles(mesh: &crate::scene::mesh::Mesh) -> &[[usize; 3]] {
    if mesh.dim == 3 {
        &mesh.faces
    } else {
        &mesh.triangles
    }
}

/// One row of `multipliers.csv`: an active pair at the fixed point. Unused row slots (a
/// point–edge pair has 2 rows, vertex–triangle 3, edge–edge 4) are empty.
#[derive(serde::Serialize)]
struct PairRow {
    kind: &'static str,
    first: usize,
    second: usize,
    rows: usize,
    distance: f64,
    w0: Option<f64>,
    w1: Option<f64>,
    w2: Option<f64>,
    w3: Option<f64>,
    active0: Option<bool>,
    active1: Option<bool>,
    active2: Option<bool>,
    active3: Option<bool>,
    mu0: Option<f64>,
    mu1: Option<f64>,
    mu2: Option<f64>,
    mu3: Option<f64>,
    local_size: f64,
    lambda: f64,
}

impl From<&PairMultiplier> for PairRow {
    fn from(p: &PairMultiplier) -> Self {
        let n = p.rows;
        let w = |i: usize| (i < n).then_some(p.weight[i]);
        let a = |i: usize| (i < n).then_some(p.active[i]);
        let m = |i: usize| (i < n).then_some(p.mu[i]);
        PairRow {
            kind: p.kind,
            first: p.first,
            second: p.second,
            rows: n,
            distance: p.distance,
            w0: w(0),
            w1: w(1),
            w2: w(2),
            w3: w(3),
            active0: a(0),
            active1: a(1),
            active2: a(2),
            active3: a(3),
            mu0: m(0),
            mu1: m(1),
            mu2: m(2),
            mu3: m(3),
            local_size: p.local_size,
            lambda: p.lambda,
        }
    }
}

/// The scalar part of [`ConvergedDiagnostics`] (the pairs go to `multipliers.csv`).
#[derive(serde::Serialize)]
struct DiagSummary {
    h: f64,
    active_pairs: usize,
    active_rows: usize,
    stationarity_canonical: f64,
    stationarity_raw: f64,
    gradient_norm: f64,
    complementarity_raw: f64,
    min_raw_dual: f64,
    lambda_norm_h: f64,
    c_phi: usize,
    max_edges_per_vertex: usize,
    residual_hm1: f64,
    bound: f64,
    ratio: f64,
    dual_qp_status: &'static str,
    dual_qp_tol: f64,
}

impl DiagSummary {
    fn new(d: &ConvergedDiagnostics, dual_qp_tol: f64) -> Self {
        DiagSummary {
            dual_qp_tol,
            h: d.h,
            active_pairs: d.active_pairs,
            active_rows: d.active_rows,
            stationarity_canonical: d.stationarity_canonical,
            stationarity_raw: d.stationarity_raw,
            gradient_norm: d.gradient_norm,
            complementarity_raw: d.complementarity_raw,
            min_raw_dual: d.min_raw_dual,
            lambda_norm_h: d.lambda_norm_h,
            c_phi: d.c_phi,
            max_edges_per_vertex: d.max_edges_per_vertex,
            residual_hm1: d.residual_hm1,
            bound: d.bound,
            ratio: d.ratio,
            dual_qp_status: d.dual_qp_status,
        }
    }
}

/// A run that finished and wrote its outputs, but with a failure status (exit code 1).
#[derive(Debug)]
pub struct RunFinished {
    /// The status (`max_outer_iterations`, `subproblem_failed`, …).
    pub status: String,
}

impl std::fmt::Display for RunFinished {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the run finished with status {} (its outputs are written)",
            self.status
        )
    }
}

impl std::error::Error for RunFinished {}
