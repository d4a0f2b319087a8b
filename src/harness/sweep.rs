//! `contactlab sweep FILE.toml --out FILE.csv [--jobs N] [--shard K/N] [--resume]`: expands a
//! sweep file into runs, executes them in parallel and writes one CSV row per run, flushed as
//! each run ends (docs/sweeps.md).
//!
//! Guarantees (tested in `tests/sweep.rs`):
//! - a row is written and flushed as soon as its run ends, so an interrupted sweep loses no
//!   finished row; `--resume` reads the CSV back, drops a torn last line, and skips every key
//!   already present;
//! - each run has a deterministic `key` built from everything that defines it; `--shard K/N`
//!   keeps the runs whose key hashes (FNV-1a) to `K−1` mod `N`, so the shards of one sweep are
//!   disjoint, cover it, and do not depend on the machine or on `--jobs`;
//! - a run that fails (an error, or a panic) is a row with status `error`/`panic` and the
//!   message in `error`, never an abort of the sweep;
//! - a sweep that ends with every run present rewrites its CSV in the sweep file's order.

use crate::energy::HessianModel;
use crate::harness::case::{self, CaseSettings};
use crate::harness::diagnostics::h1_distance;
use crate::harness::rows::{
    csv_line, header, record_line, CaseColumns, DynamicRow, RunRow, SecondOrderColumns, StaticRow,
};
use crate::scene::registry::build_scene;
use crate::solve::dynamics::{DynamicSettings, Scheme};
use crate::solve::outer::Pruning;
use crate::solve::settings::{Accuracy, RunSettings};
use crate::solve::sqp::{Curvature, OuterMethod};
use anyhow::{bail, Context, Result};
use contactlab_solvers::{BACKEND_NAMES, DEFAULT_BACKEND, REFERENCE_BACKEND};
use rayon::prelude::*;
use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// Command-line arguments of `contactlab sweep`.
#[derive(clap::Args, Clone, Debug)]
pub struct SweepArgs {
    /// The sweep file (TOML; docs/sweeps.md).
    pub file: PathBuf,
    /// The CSV to write. It must not exist unless --resume is given.
    #[arg(long)]
    pub out: PathBuf,
    /// Runs executed at once (rayon threads; the timing columns are per run, so use 1 for
    /// timing experiments on a loaded machine).
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Run only shard K of N (1-based), e.g. 2/4 in a SLURM array job; the shards' CSVs
    /// concatenate (without their headers) into the table of the whole sweep.
    #[arg(long, value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Keep the rows already in --out and run only the missing ones.
    #[arg(long)]
    pub resume: bool,
    /// Print the expanded runs (key per line) and exit.
    #[arg(long)]
    pub list: bool,
    /// Stop the process abruptly after this many rows have been written (simulates a kill; used
    /// by the resumability test).
    #[arg(long, hide = true)]
    pub stop_after: Option<usize>,
    /// No progress lines.
    #[arg(long)]
    pub quiet: bool,
}

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("--shard {s:?}: expected K/N with 1 ≤ K ≤ N, e.g. 1/2");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let k: usize = k.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// One or several values.
#[derive(Deserialize, Clone, Debug)]
#[serde(untagged)]
pub enum OneOrMany<T> {
    /// A single value.
    One(T),
    /// A list.
    Many(Vec<T>),
}

impl<T: Clone> OneOrMany<T> {
    fn to_vec(&self) -> Vec<T> {
        match self {
            OneOrMany::One(t) => vec![t.clone()],
            OneOrMany::Many(v) => v.clone(),
        }
    }
}

/// An ε rule: `eps = c·h^p` (`c`, `p`; `p` defaults to 1), or a fixed value.
#[derive(Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EpsRule {
    /// Factor of `c·h^p`.
    pub c: Option<f64>,
    /// Power of `c·h^p` (default 1).
    pub p: Option<f64>,
    /// A fixed ε (exclusive with `c`, `p`).
    pub fixed: Option<f64>,
}

impl EpsRule {
    fn check(&self, scene: &str) -> Result<()> {
        match (self.fixed, self.c) {
            (Some(e), None) if self.p.is_none() => {
                if !(e > 0.0 && e.is_finite()) {
                    bail!("scene {scene}: eps fixed = {e} must be finite and > 0");
                }
            }
            (None, Some(c)) => {
                let p = self.p.unwrap_or(1.0);
                if !(c > 0.0 && c.is_finite() && p.is_finite()) {
                    bail!("scene {scene}: eps rule c = {c}, p = {p}: c must be > 0, both finite");
                }
            }
            _ => bail!(
                "scene {scene}: an eps rule is {{ c = .., p = .. }} or {{ fixed = .. }}, got {self:?}"
            ),
        }
        Ok(())
    }

    /// ε at mesh size `h`.
    pub fn eval(&self, h: f64) -> f64 {
        match self.fixed {
            Some(e) => e,
            None => self.c.unwrap_or(1.0) * h.powf(self.p.unwrap_or(1.0)),
        }
    }

    /// The rule as written in keys and the `eps_rule` column, e.g. `0.1*h^1` or `fixed:0.001`.
    pub fn label(&self) -> String {
        match self.fixed {
            Some(e) => format!("fixed:{e:?}"),
            None => format!("{:?}*h^{:?}", self.c.unwrap_or(1.0), self.p.unwrap_or(1.0)),
        }
    }
}

/// The reference run of the speed/accuracy trade-off (one per scene, n, ε and parameters).
#[derive(Deserialize, Clone, Debug)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Backend (default [`REFERENCE_BACKEND`], Clarabel, whatever the runs use).
    #[serde(default = "default_ref_backend")]
    pub backend: String,
    /// Accuracy preset (default high).
    #[serde(default = "default_ref_accuracy")]
    pub accuracy: String,
    /// tol_J of the reference (default 1e-14).
    #[serde(default = "default_ref_tol_j")]
    pub tol_j: f64,
}

fn default_ref_backend() -> String {
    REFERENCE_BACKEND.into()
}
fn default_ref_accuracy() -> String {
    "high".into()
}
fn default_ref_tol_j() -> f64 {
    1e-14
}

/// Settings shared by the scenes of a sweep file; a scene block may override each.
#[derive(Deserialize, Clone, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct Common {
    /// Backends.
    pub backends: Option<Vec<String>>,
    /// Accuracy presets.
    pub accuracy: Option<Vec<String>>,
    /// Pruning mode (lazy, trust-region, all-pairs).
    pub pruning: Option<String>,
    /// Override of the presets' tol_J.
    pub tol_j: Option<f64>,
    /// Maximum outer iterations.
    pub max_outer: Option<usize>,
    /// Inner steps per T(ψ) at most (default 50; 1 = one QP per outer step).
    pub max_inner: Option<usize>,
    /// Wall-time limit per run in seconds (status `time_limit` when reached; static runs only).
    pub time_limit_s: Option<f64>,
    /// The inner steps' Newton model: `shifted` (default) or `projected`.
    pub newton_model: Option<String>,
    /// The outer method: `pantz` or `sqp` (default: [`OuterMethod::default`]).
    pub outer_method: Option<String>,
    /// The SQP model's constraint curvature: `off` (default), `psd`, `full`, `tangent` or
    /// `interior` (with `outer_method = "sqp"` only).
    pub sqp_curvature: Option<String>,
    /// SQP: `γ` of the active pairs' normal stiffness (finite, ≥ 0, default 0; with
    /// `outer_method = "sqp"` only).
    pub sqp_normal_stiffness: Option<f64>,
    /// SQP: leave out the rows implied by another row of the same vertex or edge (default false;
    /// with `outer_method = "sqp"` only).
    pub sqp_drop_endpoint_rows: Option<bool>,
    /// SQP: rows against the extended element where the body turns towards the other side
    /// (default false; with `outer_method = "sqp"` only).
    pub sqp_extend_rows: Option<bool>,
    /// SQP, 2D: leave out the rows whose closest point is a vertex of the other body, implied by
    /// that vertex's row (default false; with `outer_method = "sqp"` only).
    pub sqp_drop_vertex_rows: Option<bool>,
    /// SQP, 2D: leave out a vertex's row against the side of a corner that the corner's row
    /// implies (default false; with `outer_method = "sqp"` only).
    pub sqp_drop_side_rows: Option<bool>,
    /// SQP, with `sqp_extend_rows`: the extended rows against a fixed element without the
    /// chain limit (default false; with `outer_method = "sqp"` only).
    pub sqp_extend_fixed: Option<bool>,
    /// SQP: add a violated row only where the pair comes within ε + δ on the step's straight
    /// path (default false; with `outer_method = "sqp"` only).
    pub sqp_path_rows: Option<bool>,
    /// SQP, 2D: with the endpoint or vertex rows left out, add the rows that would imply a
    /// violated one (default false; with `outer_method = "sqp"` and one of those only).
    pub sqp_implying_rows: Option<bool>,
    /// SQP: after a full step, try 2, 4, …, 2^k times it while J falls and every check passes
    /// (default 0: off; with `outer_method = "sqp"` only).
    pub sqp_extrapolate: Option<usize>,
    /// SQP: the normal stiffness only on the pairs whose last multiplier is at least this
    /// fraction of the largest (default 0: every positive one; with `outer_method = "sqp"`
    /// only).
    pub sqp_normal_active_rel: Option<f64>,
    /// SQP: `interior` keeps surfaces' edge–edge pairs, with this factor on their normal
    /// stiffness (default 0: left out; with `outer_method = "sqp"` only).
    pub sqp_edge_edge_stiffness: Option<f64>,
    /// The second-order check of each `converged` run up to this many free dofs (default 0:
    /// none; `contactlab run`'s default is 1 200): the columns `second_order`,
    /// `min_eigenvalue_rel`, `free_dofs`, `escapes` (static runs only).
    pub second_order_max_dofs: Option<usize>,
    /// Where that check finds a saddle, go on from the lower point it found (default false;
    /// needs `second_order_max_dofs`; the column `escapes`; static runs only).
    pub escape_saddles: Option<bool>,
    /// Reference run for the error columns.
    pub reference: Option<ReferenceSpec>,
}

/// A scene block: `[[scene]]`.
#[derive(Deserialize, Clone, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneBlock {
    /// Scene name.
    pub name: String,
    /// Mesh levels (give `n` or `h`).
    #[serde(default)]
    pub n: Vec<usize>,
    /// Mesh sizes: each becomes the coarsest level `n` whose h is at most the value
    /// ([`crate::scene::registry::n_for_h`]); the row's `h` column holds the scene's actual h.
    #[serde(default)]
    pub h: Vec<f64>,
    /// ε rule(s); default `{ c = 0.1, p = 1 }` (h/10).
    pub eps: Option<OneOrMany<EpsRule>>,
    /// Numeric scene parameters.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// Overrides of the file's defaults.
    #[serde(flatten)]
    pub common: Common,
    /// Time stepping (§6): the block's runs are dynamic runs (a sweep file is all static or
    /// all dynamic: the two kinds of row have different columns).
    #[serde(default)]
    pub dynamic: bool,
    /// Time steps (dynamic; default: the scene's own).
    #[serde(default)]
    pub dt: Vec<f64>,
    /// Number of steps (dynamic; default: the scene's own).
    pub steps: Option<usize>,
    /// Schemes, `euler` and/or `newmark` (dynamic; default `euler`).
    pub scheme: Option<OneOrMany<String>>,
}

/// The time stepping of a dynamic run.
#[derive(Clone, Debug)]
pub struct DynamicSpec {
    /// Δt.
    pub dt: f64,
    /// Steps.
    pub steps: usize,
    /// Scheme.
    pub scheme: Scheme,
}

/// A sweep file.
#[derive(Deserialize, Clone, Debug)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Name (documentation only; accepted so that a file can carry it).
    #[allow(dead_code)]
    pub name: Option<String>,
    /// Free text (documentation only).
    #[allow(dead_code)]
    pub description: Option<String>,
    /// Defaults for every scene block.
    #[serde(default)]
    pub defaults: Common,
    /// Scene blocks.
    pub scene: Vec<SceneBlock>,
}

/// One expanded run.
#[derive(Clone, Debug)]
pub struct RunSpec {
    /// Deterministic key.
    pub key: String,
    /// Scene name.
    pub scene: String,
    /// Mesh level.
    pub n: usize,
    /// Mesh size.
    pub h: f64,
    /// ε rule label.
    pub eps_rule: String,
    /// ε.
    pub eps: f64,
    /// Scene parameters.
    pub params: BTreeMap<String, f64>,
    /// Case settings.
    pub settings: CaseSettings,
    /// Reference run, when the sweep asks for errors.
    pub reference: Option<ReferenceSpec>,
    /// Time stepping, for a dynamic run.
    pub dynamic: Option<DynamicSpec>,
}

impl RunSpec {
    fn params_label(&self) -> String {
        self.params
            .iter()
            .map(|(k, v)| format!("{k}={v:?}"))
            .collect::<Vec<_>>()
            .join(";")
    }

    /// Key of the reference run of this run's group.
    fn group_key(&self) -> String {
        format!(
            "{}|n={}|eps={}|{}",
            self.scene,
            self.n,
            self.eps_rule,
            self.params_label()
        )
    }
}

/// The header of a static sweep's CSV: [`CaseColumns`] then [`StaticRow`].
pub fn header_static() -> Vec<String> {
    header::<(CaseColumns, StaticRow)>()
}

/// The header of a dynamic sweep's CSV: [`CaseColumns`] then [`DynamicRow`].
pub fn header_dynamic() -> Vec<String> {
    header::<(CaseColumns, DynamicRow)>()
}

/// Reads and validates a sweep file, and expands it into runs in file order (scene block, n,
/// ε rule, backend, accuracy). Every name is checked before any run starts.
pub fn load(path: &Path) -> Result<Vec<RunSpec>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading sweep file {path:?}"))?;
    let file: SweepFile =
        toml::from_str(&text).with_context(|| format!("parsing sweep file {path:?}"))?;
    expand(&file).with_context(|| format!("in sweep file {path:?}"))
}

/// Expands a parsed sweep file (see [`load`]).
pub fn expand(file: &SweepFile) -> Result<Vec<RunSpec>> {
    if file.scene.is_empty() {
        bail!("no [[scene]] block");
    }
    check_one_kind(&file.scene)?;
    let mut runs = Vec::new();
    let mut seen = BTreeSet::new();
    for (bi, b) in file.scene.iter().enumerate() {
        let at = format!("scene block {} ({})", bi + 1, b.name);
        let s = BlockSettings::resolve(bi, b, &file.defaults)?;
        let rules = eps_rules(b)?;
        let levels = levels(&at, b)?;
        let schemes = schemes(&at, b)?;
        if b.dynamic && s.reference.is_some() {
            bail!("{at}: a reference run is for static sweeps");
        }
        if levels.is_empty() {
            bail!("{at}: give a list n or a list h");
        }
        for &n in &levels {
            let (h, dyns) = level_variants(&at, b, n, &schemes)?;
            for rule in &rules {
                for dy in &dyns {
                    for be in &s.backends {
                        for acc in &s.accuracy {
                            let spec = s.run(b, n, h, rule, dy, be, *acc);
                            if !seen.insert(spec.key.clone()) {
                                bail!("run {} appears twice in the sweep file", spec.key);
                            }
                            runs.push(spec);
                        }
                    }
                }
            }
        }
    }
    Ok(runs)
}

/// A sweep file is all static or all dynamic (the two kinds of row have different columns).
fn check_one_kind(blocks: &[SceneBlock]) -> Result<()> {
    let dynamic = blocks[0].dynamic;
    if let Some(b) = blocks.iter().find(|b| b.dynamic != dynamic) {
        bail!(
            "scene block {:?} has dynamic = {} but the first block has dynamic = {dynamic}: a \
             sweep file is all static or all dynamic (their CSVs have different columns)",
            b.name,
            b.dynamic
        );
    }
    Ok(())
}

/// The settings of a scene block, its own or the file's defaults, checked.
struct BlockSettings {
    backends: Vec<String>,
    accuracy: Vec<Accuracy>,
    pruning: Pruning,
    tol_j: Option<f64>,
    max_outer: usize,
    max_inner: Option<usize>,
    time_limit_s: Option<f64>,
    newton_model: Option<HessianModel>,
    outer_method: OuterMethod,
    sqp_curvature: Curvature,
    sqp_normal_stiffness: f64,
    sqp_drop_endpoint_rows: bool,
    sqp_extend_rows: bool,
    sqp_drop_vertex_rows: bool,
    sqp_drop_side_rows: bool,
    sqp_extend_fixed: bool,
    sqp_path_rows: bool,
    sqp_implying_rows: bool,
    sqp_extrapolate: usize,
    sqp_normal_active_rel: f64,
    sqp_edge_edge_stiffness: f64,
    second_order_max_dofs: usize,
    escape_saddles: bool,
    reference: Option<ReferenceSpec>,
}

impl BlockSettings {
    /// Block `bi`'s settings, every name and value checked.
    fn resolve(bi: usize, b: &SceneBlock, defaults: &Common) -> Result<BlockSettings> {
        let at = format!("scene block {} ({})", bi + 1, b.name);
        if !b.dynamic && (!b.dt.is_empty() || b.steps.is_some() || b.scheme.is_some()) {
            bail!("{at}: dt, steps and scheme need dynamic = true");
        }
        let pick = |o: &Option<Vec<String>>, d: &Option<Vec<String>>, dflt: &str| {
            o.clone()
                .or_else(|| d.clone())
                .unwrap_or_else(|| vec![dflt.to_string()])
        };
        let c = &b.common;
        let backends = pick(&c.backends, &defaults.backends, DEFAULT_BACKEND);
        let accs = pick(&c.accuracy, &defaults.accuracy, "default");
        let pruning_name = c
            .pruning
            .clone()
            .or_else(|| defaults.pruning.clone())
            .unwrap_or_else(|| "lazy".into());
        let pruning = Pruning::from_name(&pruning_name).with_context(|| {
            format!("{at}: pruning {pruning_name:?}: expected lazy, trust-region or all-pairs")
        })?;
        let tol_j = c.tol_j.or(defaults.tol_j);
        let max_outer = c.max_outer.or(defaults.max_outer).unwrap_or(2000);
        let max_inner = c.max_inner.or(defaults.max_inner);
        let time_limit_s = c.time_limit_s.or(defaults.time_limit_s);
        let newton_model = match c.newton_model.as_ref().or(defaults.newton_model.as_ref()) {
            None => None,
            Some(m) => Some(HessianModel::from_user_name(m).with_context(|| {
                format!(
                    "{at}: newton_model {m:?}: expected one of {}",
                    HessianModel::USER_NAMES
                )
            })?),
        };
        let outer_method = match c.outer_method.as_ref().or(defaults.outer_method.as_ref()) {
            None => OuterMethod::default(),
            Some(m) => OuterMethod::from_name(m).with_context(|| {
                format!(
                    "{at}: outer_method {m:?}: expected one of {}",
                    OuterMethod::names()
                )
            })?,
        };
        let sqp_curvature = match c.sqp_curvature.as_ref().or(defaults.sqp_curvature.as_ref()) {
            None => Curvature::default(),
            Some(m) => Curvature::from_name(m).with_context(|| {
                format!(
                    "{at}: sqp_curvature {m:?}: expected one of {}",
                    Curvature::names()
                )
            })?,
        };
        // a key of the block, else of [defaults], else its default
        macro_rules! key {
            ($k:ident, $default:expr) => {
                c.$k.or(defaults.$k).unwrap_or($default)
            };
        }
        let sqp_normal_stiffness = key!(sqp_normal_stiffness, 0.0);
        let sqp_drop_endpoint_rows = key!(sqp_drop_endpoint_rows, false);
        let sqp_extend_rows = key!(sqp_extend_rows, false);
        let sqp_drop_vertex_rows = key!(sqp_drop_vertex_rows, false);
        let sqp_drop_side_rows = key!(sqp_drop_side_rows, false);
        let sqp_extend_fixed = key!(sqp_extend_fixed, false);
        let sqp_path_rows = key!(sqp_path_rows, false);
        let sqp_implying_rows = key!(sqp_implying_rows, false);
        let sqp_extrapolate = key!(sqp_extrapolate, 0);
        let sqp_normal_active_rel = key!(sqp_normal_active_rel, 0.0);
        let sqp_edge_edge_stiffness = key!(sqp_edge_edge_stiffness, 0.0);
        let second_order_max_dofs = key!(second_order_max_dofs, 0);
        let escape_saddles = key!(escape_saddles, false);
        if b.dynamic && (second_order_max_dofs != 0 || escape_saddles) {
            bail!(
                "{at}: second_order_max_dofs and escape_saddles apply to static runs only (the \
                 check is of a static run's end state)"
            );
        }
        if escape_saddles && second_order_max_dofs == 0 {
            bail!(
                "{at}: escape_saddles set without second_order_max_dofs: it goes on from the \
                 lower point that check finds, and does nothing without it"
            );
        }
        // The run settings of each backend, checked by RunSettings::validate (the keys a sweep
        // file does not set at their defaults).
        for be in backends
            .iter()
            .map(String::as_str)
            .chain(backends.is_empty().then_some(DEFAULT_BACKEND))
        {
            let rs = RunSettings {
                backend: be.to_string(),
                tol_j,
                max_outer,
                max_inner: max_inner.unwrap_or(RunSettings::default().max_inner),
                time_limit_s,
                sqp_normal_stiffness,
                sqp_normal_active_rel,
                sqp_edge_edge_stiffness,
                ..RunSettings::default()
            };
            if let Err(e) = rs.validate() {
                match e.key {
                    "max_outer" | "max_inner" => {
                        bail!("{at}: max_outer and max_inner must be ≥ 1")
                    }
                    "backend" => bail!(
                        "{at}: unknown backend {} (available: {})",
                        e.value,
                        BACKEND_NAMES.join(", ")
                    ),
                    _ => bail!("{at}: {} = {} {}", e.key, e.value, e.rule),
                }
            }
        }
        if outer_method != OuterMethod::Sqp {
            let set: Vec<&str> = [
                ("sqp_curvature", sqp_curvature != Curvature::default()),
                ("sqp_normal_stiffness", sqp_normal_stiffness != 0.0),
                ("sqp_drop_endpoint_rows", sqp_drop_endpoint_rows),
                ("sqp_extend_rows", sqp_extend_rows),
                ("sqp_drop_vertex_rows", sqp_drop_vertex_rows),
                ("sqp_drop_side_rows", sqp_drop_side_rows),
                ("sqp_extend_fixed", sqp_extend_fixed),
                ("sqp_path_rows", sqp_path_rows),
                ("sqp_implying_rows", sqp_implying_rows),
                ("sqp_extrapolate", sqp_extrapolate != 0),
                ("sqp_normal_active_rel", sqp_normal_active_rel != 0.0),
                ("sqp_edge_edge_stiffness", sqp_edge_edge_stiffness != 0.0),
            ]
            .into_iter()
            .filter_map(|(k, set)| set.then_some(k))
            .collect();
            if !set.is_empty() {
                bail!(
                    "{at}: {} set with outer_method = {:?}: sqp_curvature, \
                     sqp_normal_stiffness, sqp_drop_endpoint_rows, sqp_extend_rows, \
                     sqp_drop_vertex_rows, sqp_drop_side_rows, sqp_extend_fixed, sqp_path_rows, \
                     sqp_implying_rows, sqp_extrapolate, sqp_normal_active_rel and \
                     sqp_edge_edge_stiffness apply to outer_method = \"sqp\" only (auto's SQP phase \
                     takes the one command line's)",
                    set.join(" and "),
                    outer_method.as_str()
                );
            }
        }
        if sqp_extend_fixed && !sqp_extend_rows {
            bail!(
                "{at}: sqp_extend_fixed set without sqp_extend_rows: it lifts a limit of the \
                 extended rows, and does nothing without them"
            );
        }
        if sqp_implying_rows && !(sqp_drop_endpoint_rows || sqp_drop_vertex_rows) {
            bail!(
                "{at}: sqp_implying_rows set without sqp_drop_endpoint_rows or \
                 sqp_drop_vertex_rows: it adds the rows that imply the rows those keys leave \
                 out, and does nothing without them"
            );
        }
        if time_limit_s.is_some() && b.dynamic {
            bail!(
                "{at}: time_limit_s applies to static runs only (a dynamic run solves one problem per step)"
            );
        }
        let reference = c.reference.clone().or_else(|| defaults.reference.clone());
        let mut accuracy = Vec::new();
        for a in &accs {
            accuracy.push(Accuracy::from_name(a).with_context(|| {
                format!("{at}: unknown accuracy {a:?} (expected low, default, high)")
            })?);
        }
        if let Some(r) = &reference {
            if !BACKEND_NAMES.contains(&r.backend.as_str()) {
                bail!(
                    "scene block {}: reference backend {:?} unknown",
                    bi + 1,
                    r.backend
                );
            }
            if Accuracy::from_name(&r.accuracy).is_none() {
                bail!(
                    "scene block {}: reference accuracy {:?} unknown",
                    bi + 1,
                    r.accuracy
                );
            }
        }
        Ok(BlockSettings {
            backends,
            accuracy,
            pruning,
            tol_j,
            max_outer,
            max_inner,
            time_limit_s,
            newton_model,
            outer_method,
            sqp_curvature,
            sqp_normal_stiffness,
            sqp_drop_endpoint_rows,
            sqp_extend_rows,
            sqp_drop_vertex_rows,
            sqp_drop_side_rows,
            sqp_extend_fixed,
            sqp_path_rows,
            sqp_implying_rows,
            sqp_extrapolate,
            sqp_normal_active_rel,
            sqp_edge_edge_stiffness,
            second_order_max_dofs,
            escape_saddles,
            reference,
        })
    }

    /// The run of block `b` at level `n` (mesh size `h`) with ε rule `rule`, time stepping
    /// `dy`, backend `be` and accuracy `acc`, with its key.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        b: &SceneBlock,
        n: usize,
        h: f64,
        rule: &EpsRule,
        dy: &Option<DynamicSpec>,
        be: &str,
        acc: Accuracy,
    ) -> RunSpec {
        let settings = CaseSettings {
            backend: be.to_string(),
            accuracy: acc,
            pruning: self.pruning,
            tol_j: self.tol_j,
            max_outer: self.max_outer,
            max_inner: self.max_inner,
            time_limit_s: self.time_limit_s,
            newton_model: self.newton_model.unwrap_or_default(),
            outer_method: self.outer_method,
            sqp_curvature: self.sqp_curvature,
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
            second_order_max_dofs: self.second_order_max_dofs,
            escape_saddles: self.escape_saddles,
        };
        let mut spec = RunSpec {
            key: String::new(),
            scene: b.name.clone(),
            n,
            h,
            eps_rule: rule.label(),
            eps: rule.eval(h),
            params: b.params.clone(),
            settings,
            reference: self.reference.clone(),
            dynamic: dy.clone(),
        };
        spec.key = run_key(&spec);
        spec
    }
}

/// The key of a run: everything that defines it. The group key, the time stepping (dynamic),
/// backend, accuracy, pruning, tol_J, max_outer, then max_inner, the time limit, a Newton
/// model other than the default, an outer method other than `pantz`, an SQP curvature other
/// than `off`, an SQP normal stiffness other than 0 and the SQP's row options (dropped
/// endpoint rows, extended rows, extended rows against fixed elements, dropped vertex rows,
/// dropped side rows, path rows, implying rows,
/// extrapolation) only when set, so that the keys of
/// sweeps without them (and of every run made before the SQP method) stay as they were.
fn run_key(spec: &RunSpec) -> String {
    let s = &spec.settings;
    format!(
        "{}{}|{}|{}|{}|tolj={}|max={}{}{}{}{}{}{}{}{}{}{}{}{}{}{}{}{}{}{}",
        spec.group_key(),
        spec.dynamic.as_ref().map_or(String::new(), |d| format!(
            "|dt={:?}|steps={}|{}",
            d.dt,
            d.steps,
            d.scheme.as_str()
        )),
        s.backend,
        s.accuracy.as_str(),
        s.pruning.as_str(),
        s.tol_j.map_or("preset".into(), |t| format!("{t:?}")),
        s.max_outer,
        s.max_inner.map_or(String::new(), |k| format!("|inner={k}")),
        s.time_limit_s
            .map_or(String::new(), |t| format!("|limit={t:?}s")),
        if s.newton_model == HessianModel::default() {
            String::new()
        } else {
            format!("|model={}", s.newton_model.as_str())
        },
        if s.outer_method == OuterMethod::Pantz {
            String::new()
        } else {
            format!("|method={}", s.outer_method.as_str())
        },
        if s.sqp_curvature == Curvature::default() {
            String::new()
        } else {
            format!("|curvature={}", s.sqp_curvature.as_str())
        },
        if s.sqp_normal_stiffness == 0.0 {
            String::new()
        } else {
            format!("|gamma={:?}", s.sqp_normal_stiffness)
        },
        if s.sqp_drop_endpoint_rows {
            "|drop-endpoint-rows"
        } else {
            ""
        },
        if s.sqp_extend_rows {
            "|extend-rows"
        } else {
            ""
        },
        if s.sqp_extend_fixed {
            "|extend-fixed"
        } else {
            ""
        },
        if s.sqp_drop_vertex_rows {
            "|drop-vertex-rows"
        } else {
            ""
        },
        if s.sqp_drop_side_rows {
            "|drop-side-rows"
        } else {
            ""
        },
        if s.sqp_path_rows { "|path-rows" } else { "" },
        if s.sqp_implying_rows {
            "|implying-rows"
        } else {
            ""
        },
        if s.sqp_extrapolate == 0 {
            String::new()
        } else {
            format!("|extrapolate={}", s.sqp_extrapolate)
        },
        if s.sqp_normal_active_rel == 0.0 {
            String::new()
        } else {
            format!("|normal-active={:?}", s.sqp_normal_active_rel)
        },
        if s.sqp_edge_edge_stiffness == 0.0 {
            String::new()
        } else {
            format!("|edge-edge={:?}", s.sqp_edge_edge_stiffness)
        },
        if s.second_order_max_dofs == 0 {
            String::new()
        } else {
            format!("|second-order={}", s.second_order_max_dofs)
        },
        if s.escape_saddles { "|escape" } else { "" }
    )
}

/// The block's ε rules (default `{ c = 0.1, p = 1 }`), checked.
fn eps_rules(b: &SceneBlock) -> Result<Vec<EpsRule>> {
    let rules = b.eps.as_ref().map(|e| e.to_vec()).unwrap_or_else(|| {
        vec![EpsRule {
            c: Some(0.1),
            p: Some(1.0),
            fixed: None,
        }]
    });
    for r in &rules {
        r.check(&b.name)?;
    }
    Ok(rules)
}

/// The block's mesh levels: its `n` list, then one level per `h`.
fn levels(at: &str, b: &SceneBlock) -> Result<Vec<usize>> {
    let mut levels = b.n.clone();
    for &h in &b.h {
        let n = if b.dynamic {
            crate::scene::registry::dynamic_n_for_h(&b.name, h, &b.params)
        } else {
            crate::scene::registry::n_for_h(&b.name, h, &b.params)
        };
        levels.push(n.with_context(|| at.to_string())?);
    }
    Ok(levels)
}

/// The block's time-stepping schemes (default euler).
fn schemes(at: &str, b: &SceneBlock) -> Result<Vec<Scheme>> {
    b.scheme
        .as_ref()
        .map(|s| s.to_vec())
        .unwrap_or_else(|| vec!["euler".into()])
        .iter()
        .map(|s| {
            Scheme::from_name(s)
                .with_context(|| format!("{at}: scheme {s:?}: expected euler or newmark"))
        })
        .collect()
}

/// The mesh size of level `n` of block `b` and its time steppings (`[None]` for a static
/// block). Building the scene checks its name and parameters and gives `h`.
fn level_variants(
    at: &str,
    b: &SceneBlock,
    n: usize,
    schemes: &[Scheme],
) -> Result<(f64, Vec<Option<DynamicSpec>>)> {
    if !b.dynamic {
        let h = build_scene(&b.name, n, None, &b.params)
            .with_context(|| format!("{at}, n = {n}"))?
            .h;
        return Ok((h, vec![None]));
    }
    let ds = crate::scene::registry::build_dynamic_scene(&b.name, Some(n), None, &b.params)
        .with_context(|| format!("{at}, n = {n}"))?;
    let dts = if b.dt.is_empty() {
        vec![ds.dt]
    } else {
        b.dt.clone()
    };
    let steps = b.steps.unwrap_or(ds.steps);
    let mut dyns = Vec::new();
    for &dt in &dts {
        for &scheme in schemes {
            let d = DynamicSettings { dt, steps, scheme };
            d.validate().map_err(|e| anyhow::anyhow!("{at}: {e}"))?;
            dyns.push(Some(DynamicSpec { dt, steps, scheme }));
        }
    }
    Ok((ds.scene.h, dyns))
}

/// FNV-1a hash of a key (stable across platforms and Rust versions).
pub fn key_hash(key: &str) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for b in key.as_bytes() {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

/// Whether run `key` belongs to shard `k` of `n` (1-based).
pub fn in_shard(key: &str, shard: Option<(usize, usize)>) -> bool {
    match shard {
        None => true,
        Some((k, n)) => key_hash(key) % n as u64 == (k - 1) as u64,
    }
}

/// The reference of a group: energy and positions.
struct Reference {
    energy: f64,
    x: Vec<f64>,
    status: String,
}

/// Reads the rows already in `path` (for --resume): the keys, after dropping a torn last line
/// (one without its newline, left by a kill during a write). Errors when the header differs.
fn existing_keys(path: &Path, want: &[String]) -> Result<BTreeSet<String>> {
    let mut bytes = std::fs::read(path).with_context(|| format!("reading {path:?}"))?;
    if let Some(end) = bytes.iter().rposition(|&b| b == b'\n') {
        if end + 1 < bytes.len() {
            eprintln!(
                "sweep: {path:?}: dropping a torn last line ({} bytes, no newline)",
                bytes.len() - end - 1
            );
            bytes.truncate(end + 1);
            std::fs::write(path, &bytes).with_context(|| format!("truncating {path:?}"))?;
        }
    } else {
        bytes.clear();
        std::fs::write(path, &bytes)?;
    }
    let mut keys = BTreeSet::new();
    if bytes.is_empty() {
        return Ok(keys);
    }
    let mut rdr = csv::Reader::from_reader(bytes.as_slice());
    let h: Vec<String> = rdr.headers()?.iter().map(|s| s.to_string()).collect();
    if h != want {
        bail!(
            "{path:?}: its header is not this version's sweep header; move it away or write to \
             another --out (first difference at column {})",
            h.iter()
                .zip(want)
                .position(|(a, b)| a != b)
                .unwrap_or(h.len().min(want.len()))
                + 1
        );
    }
    for (i, rec) in rdr.records().enumerate() {
        let rec = rec.with_context(|| format!("{path:?}: row {}", i + 2))?;
        keys.insert(rec.get(0).unwrap_or_default().to_string());
    }
    Ok(keys)
}

/// The row of a run: `run`'s row, or an `error` or `panic` row with the message (a panic is
/// caught, so one bad run never aborts the sweep).
fn catch_row<R: RunRow>(run: impl FnOnce() -> Result<R>) -> R {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)) {
        Ok(Ok(row)) => row,
        Ok(Err(e)) => R::failed("error", format!("{e:#}")),
        Err(p) => R::failed(
            "panic",
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "panic".into()),
        ),
    }
}

/// Runs one static spec into its row (never panics: a panic becomes a `panic` row).
fn run_one(spec: &RunSpec, reference: Option<&Reference>) -> StaticRow {
    run_one_checked(spec, reference).0
}

/// [`run_one`], with the second-order check's columns of the run (a sweep file that asks for
/// the check writes them after the row).
fn run_one_checked(
    spec: &RunSpec,
    reference: Option<&Reference>,
) -> (StaticRow, SecondOrderColumns) {
    let t = Instant::now();
    let (mut row, cols) = catch_row(|| -> Result<_> {
        let scene = build_scene(&spec.scene, spec.n, Some(spec.eps), &spec.params)?;
        let o = case::execute(&scene, &spec.settings, &mut |_, _| {})?;
        let mut row = StaticRow::of_case(&scene, &o);
        if let Some(r) = reference {
            row.reference_energy = Some(r.energy);
            if r.status == "converged" || r.status == "fixed_point" {
                row.energy_error =
                    Some((o.res.energy - r.energy).abs() / r.energy.abs().max(f64::MIN_POSITIVE));
                row.position_error_h1 = Some(h1_distance(&scene.mesh, &o.res.x, &r.x));
            }
        }
        let worst = o
            .records
            .iter()
            .map(|r| r.min_distance)
            .fold(f64::INFINITY, f64::min);
        row.max_violation = Some((scene.eps - worst).max(0.0));
        Ok((row, SecondOrderColumns::of_result(&o.res)))
    });
    row.h.get_or_insert(spec.h);
    row.eps.get_or_insert(spec.eps);
    row.wall_time_s.get_or_insert(t.elapsed().as_secs_f64());
    (row, cols)
}

/// Runs one dynamic spec into its row (never panics: a panic becomes a `panic` row).
fn run_one_dynamic(spec: &RunSpec) -> DynamicRow {
    let t = Instant::now();
    let d = spec.dynamic.as_ref().expect("a dynamic spec");
    let mut row = catch_row(|| -> Result<_> {
        let mut ds = crate::scene::registry::build_dynamic_scene(
            &spec.scene,
            Some(spec.n),
            Some(spec.eps),
            &spec.params,
        )?;
        let qp = spec.settings.accuracy.qp_settings(&spec.settings.backend);
        let dyn_settings = DynamicSettings {
            dt: d.dt,
            steps: d.steps,
            scheme: d.scheme,
        };
        let (_, mt) = case::execute_dynamic(&mut ds, &spec.settings, &dyn_settings, &qp, &mut ())?;
        let g = matches!(spec.scene.as_str(), "drop" | "drop3d")
            .then(|| spec.params.get("g").copied().unwrap_or(9.81));
        Ok(DynamicRow::of_metrics(
            ds.scene.mesh.dim,
            ds.scene.h,
            ds.scene.eps,
            qp.eps_abs,
            &spec.settings,
            &mt,
            g,
        ))
    });
    row.dt = d.dt;
    row.steps = d.steps;
    row.scheme = d.scheme.as_str().to_string();
    row.h.get_or_insert(spec.h);
    row.eps.get_or_insert(spec.eps);
    row.t_total_s = Some(t.elapsed().as_secs_f64());
    row
}

/// Solves the reference of a group.
fn solve_reference(spec: &RunSpec, r: &ReferenceSpec) -> Result<Reference> {
    let scene = build_scene(&spec.scene, spec.n, Some(spec.eps), &spec.params)?;
    let cs = CaseSettings {
        backend: r.backend.clone(),
        accuracy: Accuracy::from_name(&r.accuracy).expect("checked in expand"),
        pruning: spec.settings.pruning,
        tol_j: Some(r.tol_j),
        max_outer: spec.settings.max_outer.max(10_000),
        max_inner: None,
        newton_model: Default::default(),
        outer_method: spec.settings.outer_method,
        // the default SQP model, as the default Newton model: a reference is solved once per
        // group, whichever model its group's runs use
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
        // no second-order check: the reference's J is what the error columns read
        second_order_max_dofs: 0,
        escape_saddles: false,
        // the block's limit: a reference that reaches it is not converged, and the rows of its
        // group then get no error columns
        time_limit_s: spec.settings.time_limit_s,
    };
    let o = case::execute(&scene, &cs, &mut |_, _| {})?;
    Ok(Reference {
        energy: o.res.energy,
        x: o.res.x,
        status: o.res.status.as_str().to_string(),
    })
}

impl RunSpec {
    /// The case columns of this run's row.
    fn case_columns(&self) -> CaseColumns {
        CaseColumns {
            key: self.key.clone(),
            scene: self.scene.clone(),
            n: self.n,
            eps_rule: self.eps_rule.clone(),
            params: self.params_label(),
            backend: self.settings.backend.clone(),
            accuracy: self.settings.accuracy.as_str().to_string(),
            pruning: self.settings.pruning.as_str().to_string(),
            outer_method: self.settings.outer_method.as_str().to_string(),
        }
    }
}

/// `contactlab sweep`.
pub fn cmd_sweep(a: &SweepArgs) -> Result<()> {
    if a.jobs == 0 {
        bail!("--jobs 0: need at least one job");
    }
    let runs = load(&a.file)?;
    if a.list {
        for r in &runs {
            if in_shard(&r.key, a.shard) {
                println!("{}", r.key);
            }
        }
        return Ok(());
    }
    if runs.first().is_some_and(|r| r.dynamic.is_some()) {
        sweep_rows(a, &runs, |r, _| run_one_dynamic(r))
    } else if runs.iter().any(|r| r.settings.second_order_max_dofs > 0) {
        // the check's columns after the published ones, only where the file asks for it
        sweep_rows(a, &runs, run_one_checked)
    } else {
        sweep_rows(a, &runs, run_one)
    }
}

/// Runs the pending runs of `runs` (this shard's, not yet in `--out`) and appends one row of
/// type `R` each, built by `run_one` from the spec and its group's reference.
fn sweep_rows<R: RunRow>(
    a: &SweepArgs,
    runs: &[RunSpec],
    run_one: impl Fn(&RunSpec, Option<&Reference>) -> R + Sync,
) -> Result<()> {
    let hdr_cols = header::<(CaseColumns, R)>();
    let done = if a.out.exists() {
        if !a.resume {
            bail!(
                "{:?} exists: pass --resume to keep its rows and run the missing ones, or remove it",
                a.out
            );
        }
        existing_keys(&a.out, &hdr_cols)?
    } else {
        BTreeSet::new()
    };
    if let Some(dir) = a.out.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {dir:?}"))?;
        }
    }
    let mine: Vec<&RunSpec> = runs.iter().filter(|r| in_shard(&r.key, a.shard)).collect();
    let todo: Vec<&RunSpec> = mine
        .iter()
        .copied()
        .filter(|r| !done.contains(&r.key))
        .collect();
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&a.out)
        .with_context(|| format!("opening {:?}", a.out))?;
    if file.metadata()?.len() == 0 {
        file.write_all(&record_line(&hdr_cols)?)?;
        file.flush()?;
    }
    let name = a.file.display().to_string();
    if !a.quiet {
        eprintln!(
            "sweep {name}: {} runs{}, {} already in {:?}, {} to run with {} job(s)",
            mine.len(),
            a.shard
                .map(|(k, n)| format!(" in shard {k}/{n}"))
                .unwrap_or_default(),
            mine.len() - todo.len(),
            a.out,
            todo.len(),
            a.jobs
        );
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.jobs)
        .build()
        .context("building the thread pool")?;
    let refs = solve_references(a, &pool, &todo);
    let t0 = Instant::now();
    let writer = Mutex::new((file, 0usize));
    let total = todo.len();
    let result: Result<()> = pool.install(|| {
        todo.par_iter().try_for_each(|r| -> Result<()> {
            let row = run_one(r, refs.get(&r.group_key()));
            let line = csv_line(&(r.case_columns(), &row))?;
            let mut g = writer.lock().unwrap_or_else(|e| e.into_inner());
            g.0.write_all(&line)?;
            g.0.flush()?;
            g.1 += 1;
            if !a.quiet {
                eprintln!(
                    "[{}/{} {:.0}s] {} {} {} s",
                    g.1,
                    total,
                    t0.elapsed().as_secs_f64(),
                    r.key,
                    row.status(),
                    row.wall_time_cell(),
                );
            }
            if a.stop_after == Some(g.1) {
                g.0.sync_all()?;
                std::process::exit(3);
            }
            Ok(())
        })
    });
    result?;
    drop(writer);
    // complete: rewrite in the sweep file's order
    let present = existing_keys(&a.out, &hdr_cols)?;
    if mine.iter().all(|r| present.contains(&r.key)) {
        sort_csv(&a.out, &mine)?;
    }
    if !a.quiet {
        eprintln!("sweep {name}: done, {:?}", a.out);
    }
    Ok(())
}

/// The references: one per group with pending runs that asks for one, solved first (in
/// parallel); a failed reference leaves its group's error columns empty.
fn solve_references(
    a: &SweepArgs,
    pool: &rayon::ThreadPool,
    todo: &[&RunSpec],
) -> HashMap<String, Reference> {
    let mut groups: BTreeMap<String, &RunSpec> = BTreeMap::new();
    for r in todo {
        if r.reference.is_some() {
            groups.entry(r.group_key()).or_insert(r);
        }
    }
    pool.install(|| {
        groups
            .par_iter()
            .filter_map(|(g, r)| {
                let spec = r.reference.as_ref().expect("filtered");
                let t = Instant::now();
                match solve_reference(r, spec) {
                    Ok(x) => {
                        if !a.quiet {
                            eprintln!(
                                "sweep: reference {g}: {} J={:.12e} ({:.2}s)",
                                x.status,
                                x.energy,
                                t.elapsed().as_secs_f64()
                            );
                        }
                        Some((g.clone(), x))
                    }
                    Err(e) => {
                        eprintln!("sweep: reference {g} failed: {e:#}; error columns left empty");
                        None
                    }
                }
            })
            .collect()
    })
}

/// Rewrites `path` with its rows in the order of `order` (atomic: a temporary file renamed).
fn sort_csv(path: &Path, order: &[&RunSpec]) -> Result<()> {
    let rank: HashMap<&str, usize> = order
        .iter()
        .enumerate()
        .map(|(i, r)| (r.key.as_str(), i))
        .collect();
    let mut rdr = csv::Reader::from_path(path)?;
    let hdr = rdr.headers()?.clone();
    let mut rows: Vec<csv::StringRecord> = rdr.records().collect::<Result<_, _>>()?;
    rows.sort_by_key(|r| {
        rank.get(r.get(0).unwrap_or(""))
            .copied()
            .unwrap_or(usize::MAX)
    });
    let tmp = path.with_extension("csv.tmp");
    {
        let mut w = csv::Writer::from_path(&tmp)?;
        w.write_record(&hdr)?;
        for r in &rows {
            w.write_record(r)?;
        }
        w.flush()?;
    }
    std::fs::rename(&tmp, path)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Vec<RunSpec>> {
        expand(&toml::from_str(s)?)
    }

    #[test]
    fn sweep_expands_in_order_with_unique_keys() {
        let runs = parse(
            r#"
            [defaults]
            backends = ["clarabel", "uzawa"]
            [[scene]]
            name = "balloons"
            n = [20, 40]
            eps = [{ c = 0.1 }, { fixed = 0.001 }]
            "#,
        )
        .unwrap();
        assert_eq!(runs.len(), 2 * 2 * 2);
        assert_eq!(runs[0].n, 20);
        assert_eq!(runs[0].eps_rule, "0.1*h^1.0");
        assert!((runs[0].eps - 0.1 * runs[0].h).abs() < 1e-15);
        assert_eq!(runs[2].eps_rule, "fixed:0.001");
        assert_eq!(runs[2].eps, 0.001);
        assert_eq!(runs[1].settings.backend, "uzawa");
        assert_eq!(runs[4].n, 40);
        let keys: BTreeSet<_> = runs.iter().map(|r| r.key.clone()).collect();
        assert_eq!(keys.len(), runs.len());
        assert!(runs
            .iter()
            .all(|r| r.settings.max_inner.is_none() && !r.key.contains("inner=")));
        // max_inner enters the settings and the key only when given
        let runs = parse("[[scene]]\nname = \"ring\"\nn = [20]\nmax_inner = 1").unwrap();
        assert_eq!(runs[0].settings.max_inner, Some(1));
        assert!(
            runs[0].key.ends_with("|inner=1|method=auto"),
            "{}",
            runs[0].key
        );
        assert!(runs[0].settings.time_limit_s.is_none() && !runs[0].key.contains("limit="));
        // so does time_limit_s; a bad one, or one on a dynamic block, is an error naming it
        let runs = parse("[[scene]]\nname = \"ring\"\nn = [20]\ntime_limit_s = 2.5").unwrap();
        assert_eq!(runs[0].settings.time_limit_s, Some(2.5));
        assert!(runs[0].key.contains("|limit=2.5s|"), "{}", runs[0].key);
        let err = |s: &str| format!("{:#}", parse(s).expect_err("should fail"));
        let m = err("[[scene]]\nname = \"ring\"\nn = [20]\ntime_limit_s = 0");
        assert!(m.contains("time_limit_s = 0 must be > 0"), "{m}");
        let m = err("[[scene]]\nname = \"drop\"\ndynamic = true\ntime_limit_s = 5");
        assert!(m.contains("static runs only"), "{m}");
        // outer_method: auto (the default) and sqp are named in the key, pantz leaves the key
        // as it was, a block overrides the defaults, an unknown name is an error naming the
        // choices
        assert!(runs[0].settings.outer_method == OuterMethod::Auto);
        assert!(runs[0].key.ends_with("|method=auto"), "{}", runs[0].key);
        let runs = parse(
            "[defaults]\nouter_method = \"sqp\"\n[[scene]]\nname = \"ring\"\nn = [20]\n\
             [[scene]]\nname = \"ring\"\nn = [20]\nouter_method = \"pantz\"",
        )
        .unwrap();
        assert_eq!(runs[0].settings.outer_method, OuterMethod::Sqp);
        assert!(runs[0].key.ends_with("|method=sqp"), "{}", runs[0].key);
        assert_eq!(runs[0].case_columns().outer_method, "sqp");
        assert_eq!(runs[1].settings.outer_method, OuterMethod::Pantz);
        assert!(!runs[1].key.contains("method="), "{}", runs[1].key);
        let runs = parse("[[scene]]\nname = \"ring\"\nn = [20]\nouter_method = \"auto\"").unwrap();
        assert_eq!(runs[0].settings.outer_method, OuterMethod::Auto);
        assert!(runs[0].key.ends_with("|method=auto"), "{}", runs[0].key);
        let m = err(
            "[[scene]]\nname = \"ring\"\nn = [20]\nouter_method = \"auto\"\nsqp_extrapolate = 3",
        );
        assert!(
            m.contains("sqp_extrapolate set with outer_method = \"auto\""),
            "{m}"
        );
        let m = err("[[scene]]\nname = \"ring\"\nn = [20]\nouter_method = \"newton\"");
        assert!(
            m.contains("outer_method \"newton\"") && m.contains("pantz, sqp"),
            "{m}"
        );
    }

    #[test]
    fn sweep_sqp_model_keys_reach_the_settings_and_the_key_only_when_set() {
        let ring = |extra: &str| parse(&format!("[[scene]]\nname = \"ring\"\nn = [20]\n{extra}"));
        let plain =
            format!("ring|n=20|eps=0.1*h^1.0||{DEFAULT_BACKEND}|default|lazy|tolj=preset|max=2000");
        // unset, or set to the defaults: the settings' defaults and the key as it was
        for extra in [
            "",
            "outer_method = \"sqp\"",
            "outer_method = \"sqp\"\nsqp_curvature = \"off\"\nsqp_normal_stiffness = 0.0",
            "sqp_curvature = \"off\"\nsqp_normal_stiffness = 0",
        ] {
            let runs = ring(extra).unwrap();
            let s = &runs[0].settings;
            assert_eq!(
                (s.sqp_curvature, s.sqp_normal_stiffness),
                (Curvature::Off, 0.0)
            );
            // a block without outer_method runs auto, the default, named in the key (a key
            // without a method names Pantz's run, as before auto became the default)
            let want = if extra.contains("sqp\"") {
                format!("{plain}|method=sqp")
            } else {
                format!("{plain}|method=auto")
            };
            assert_eq!(runs[0].key, want, "{extra:?}");
            let o = case::outer_settings(s);
            assert_eq!(
                (o.sqp.curvature, o.sqp.normal_stiffness),
                (Curvature::Off, 0.0)
            );
        }
        // set: in the settings, the outer settings and the key (after the method)
        let runs =
            ring("outer_method = \"sqp\"\nsqp_curvature = \"psd\"\nsqp_normal_stiffness = 0.01")
                .unwrap();
        let s = &runs[0].settings;
        assert_eq!(
            (s.sqp_curvature, s.sqp_normal_stiffness),
            (Curvature::Psd, 0.01)
        );
        let o = case::outer_settings(s);
        assert_eq!(
            (o.sqp.curvature, o.sqp.normal_stiffness),
            (Curvature::Psd, 0.01)
        );
        assert_eq!(
            runs[0].key,
            format!("{plain}|method=sqp|curvature=psd|gamma=0.01")
        );
        let runs = ring("outer_method = \"sqp\"\nsqp_normal_stiffness = 1").unwrap();
        assert_eq!(runs[0].key, format!("{plain}|method=sqp|gamma=1.0"));
        // the row options: in the outer settings and the key, in a fixed order
        let runs = ring(
            "outer_method = \"sqp\"\nsqp_path_rows = true\nsqp_drop_vertex_rows = true\n\
             sqp_extend_rows = true\nsqp_drop_endpoint_rows = true",
        )
        .unwrap();
        let o = case::outer_settings(&runs[0].settings);
        assert!(o.sqp.path_rows && o.sqp.extend_rows);
        assert!(o.sqp.drop_vertex_rows && o.sqp.drop_endpoint_rows);
        assert_eq!(
            runs[0].key,
            format!("{plain}|method=sqp|drop-endpoint-rows|extend-rows|drop-vertex-rows|path-rows")
        );
        let runs = ring("outer_method = \"sqp\"\nsqp_path_rows = true").unwrap();
        assert!(case::outer_settings(&runs[0].settings).sqp.path_rows);
        assert_eq!(runs[0].key, format!("{plain}|method=sqp|path-rows"));
        let runs =
            ring("outer_method = \"sqp\"\nsqp_drop_vertex_rows = true\nsqp_implying_rows = true")
                .unwrap();
        assert!(case::outer_settings(&runs[0].settings).sqp.implying_rows);
        assert_eq!(
            runs[0].key,
            format!("{plain}|method=sqp|drop-vertex-rows|implying-rows")
        );
        let runs = ring(
            "outer_method = \"sqp\"\nsqp_normal_active_rel = 0.001\nsqp_edge_edge_stiffness = 100",
        )
        .unwrap();
        let o = case::outer_settings(&runs[0].settings);
        assert_eq!(
            (o.sqp.normal_active_rel, o.sqp.edge_edge_stiffness),
            (0.001, 100.0)
        );
        assert_eq!(
            runs[0].key,
            format!("{plain}|method=sqp|normal-active=0.001|edge-edge=100.0")
        );
        let err = ring("sqp_edge_edge_stiffness = 100")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("sqp_edge_edge_stiffness set with outer_method = \"auto\""),
            "{err}"
        );
        let err = ring("outer_method = \"sqp\"\nsqp_normal_active_rel = 2")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("sqp_normal_active_rel = 2 must be in [0, 1]"),
            "{err}"
        );
        let runs = ring("outer_method = \"sqp\"\nsqp_extend_rows = true\nsqp_extend_fixed = true")
            .unwrap();
        assert!(case::outer_settings(&runs[0].settings).sqp.extend_fixed);
        assert_eq!(
            runs[0].key,
            format!("{plain}|method=sqp|extend-rows|extend-fixed")
        );
        let err = ring("outer_method = \"sqp\"\nsqp_extend_fixed = true")
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("sqp_extend_fixed set without sqp_extend_rows"),
            "{err}"
        );
        let runs = ring("outer_method = \"sqp\"\nsqp_drop_side_rows = true").unwrap();
        assert!(case::outer_settings(&runs[0].settings).sqp.drop_side_rows);
        assert_eq!(runs[0].key, format!("{plain}|method=sqp|drop-side-rows"));
        let err = ring("sqp_drop_side_rows = true").err().unwrap().to_string();
        assert!(
            err.contains("sqp_drop_side_rows set with outer_method = \"auto\""),
            "{err}"
        );
        let err = ring("outer_method = \"sqp\"\nsqp_implying_rows = true")
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("sqp_implying_rows set without sqp_drop_endpoint_rows"),
            "{err}"
        );
        let err = ring("sqp_path_rows = true").err().unwrap().to_string();
        assert!(
            err.contains("sqp_path_rows set with outer_method = \"auto\""),
            "{err}"
        );
        // the extrapolation: in the outer settings and the key (after the row options)
        let runs =
            ring("outer_method = \"sqp\"\nsqp_path_rows = true\nsqp_extrapolate = 3").unwrap();
        assert_eq!(case::outer_settings(&runs[0].settings).sqp.extrapolate, 3);
        assert_eq!(
            runs[0].key,
            format!("{plain}|method=sqp|path-rows|extrapolate=3")
        );
        let runs = ring("outer_method = \"sqp\"\nsqp_extrapolate = 0").unwrap();
        assert_eq!(runs[0].key, format!("{plain}|method=sqp"));
        let err = ring("sqp_extrapolate = 2").err().unwrap().to_string();
        assert!(
            err.contains("sqp_extrapolate set with outer_method = \"auto\""),
            "{err}"
        );
        // a block overrides the defaults, key by key
        let runs = parse(
            "[defaults]\nouter_method = \"sqp\"\nsqp_curvature = \"full\"\n\
             sqp_normal_stiffness = 0.5\n\
             [[scene]]\nname = \"ring\"\nn = [20]\n\
             [[scene]]\nname = \"ring\"\nn = [24]\nsqp_curvature = \"tangent\"\n\
             [[scene]]\nname = \"ring\"\nn = [28]\nsqp_curvature = \"off\"\n\
             sqp_normal_stiffness = 0.0\n",
        )
        .unwrap();
        let got: Vec<(Curvature, f64)> = runs
            .iter()
            .map(|r| (r.settings.sqp_curvature, r.settings.sqp_normal_stiffness))
            .collect();
        assert_eq!(
            got,
            [
                (Curvature::Full, 0.5),
                (Curvature::Tangent, 0.5),
                (Curvature::Off, 0.0)
            ]
        );
        assert!(runs[0]
            .key
            .ends_with("|method=sqp|curvature=full|gamma=0.5"));
        assert!(runs[1]
            .key
            .ends_with("|method=sqp|curvature=tangent|gamma=0.5"));
        assert!(
            runs[2].key.ends_with("|max=2000|method=sqp"),
            "{}",
            runs[2].key
        );
        // dynamic blocks take them too
        let runs = parse(
            "[[scene]]\nname = \"collide\"\ndynamic = true\nn = [16]\nsteps = 2\n\
             outer_method = \"sqp\"\nsqp_curvature = \"interior\"\n",
        )
        .unwrap();
        assert_eq!(runs[0].settings.sqp_curvature, Curvature::Interior);
        assert!(
            runs[0].key.ends_with("|method=sqp|curvature=interior"),
            "{}",
            runs[0].key
        );
        // bad values name the block and the key
        let err = |extra: &str| format!("{:#}", ring(extra).expect_err(extra));
        let m = err("outer_method = \"sqp\"\nsqp_curvature = \"hessian\"");
        assert!(
            m.contains("scene block 1 (ring): sqp_curvature \"hessian\"")
                && m.contains("off, psd, full, tangent, interior, auto"),
            "{m}"
        );
        let m = parse(
            "[defaults]\nouter_method = \"sqp\"\nsqp_curvature = \"PSD\"\n\
             [[scene]]\nname = \"ring\"\nn = [20]",
        )
        .map(|_| ())
        .unwrap_err();
        assert!(format!("{m:#}").contains("scene block 1 (ring): sqp_curvature \"PSD\""));
        for (g, shown) in [("-0.5", "-0.5"), ("nan", "NaN"), ("inf", "inf")] {
            let m = err(&format!(
                "outer_method = \"sqp\"\nsqp_normal_stiffness = {g}"
            ));
            assert!(
                m.contains(&format!(
                    "scene block 1 (ring): sqp_normal_stiffness = {shown} must be finite and ≥ 0"
                )),
                "{m}"
            );
        }
        // with pantz or auto (given, or the default) they are an error naming the key and sqp
        for (extra, method) in [
            ("outer_method = \"pantz\"\nsqp_curvature = \"psd\"", "pantz"),
            ("sqp_curvature = \"psd\"", "auto"),
        ] {
            let m = err(extra);
            assert!(
                m.contains(&format!(
                    "scene block 1 (ring): sqp_curvature set with outer_method = \"{method}\""
                )) && m.contains("apply to outer_method = \"sqp\" only"),
                "{m}"
            );
        }
        let m = err("sqp_normal_stiffness = 0.01");
        assert!(
            m.contains("sqp_normal_stiffness set with outer_method = \"auto\""),
            "{m}"
        );
        // the defaults' sqp settings with a block that goes back to pantz
        let m = parse(
            "[defaults]\nouter_method = \"sqp\"\nsqp_curvature = \"psd\"\n\
             sqp_normal_stiffness = 0.1\n[[scene]]\nname = \"ring\"\nn = [20]\n\
             [[scene]]\nname = \"ring\"\nn = [24]\nouter_method = \"pantz\"",
        )
        .map(|_| ())
        .unwrap_err();
        let m = format!("{m:#}");
        assert!(
            m.contains(
                "scene block 2 (ring): sqp_curvature and sqp_normal_stiffness set with outer_method = \"pantz\""
            ),
            "{m}"
        );
    }

    #[test]
    fn sweep_bad_files_name_the_problem() {
        let e = |s: &str| format!("{:#}", parse(s).expect_err("should fail"));
        assert!(e("[[scene]]\nname = \"nope\"\nn = [20]").contains("unknown scene \"nope\""));
        assert!(
            e("[[scene]]\nname = \"balloons\"\nn = [20]\nbackends = [\"gurobi\"]")
                .contains("unknown backend \"gurobi\"")
        );
        assert!(
            e("[[scene]]\nname = \"balloons\"\nn = [20]\naccuracy = [\"max\"]")
                .contains("unknown accuracy \"max\"")
        );
        assert!(
            e("[[scene]]\nname = \"balloons\"\nn = [20]\nparams = { zeta = 1.0 }")
                .contains("unknown parameter \"zeta\"")
        );
        assert!(
            e("[[scene]]\nname = \"balloons\"\nn = [20]\neps = { c = -1.0 }")
                .contains("c must be > 0")
        );
        assert!(
            e("[[scene]]\nname = \"balloons\"\nn = [20]\neps = { fixed = 1.0, c = 1.0 }")
                .contains("eps rule")
        );
        assert!(
            toml::from_str::<SweepFile>("[[scene]]\nname = \"balloons\"\nn = [20]\nbogus = 1")
                .err()
                .unwrap()
                .to_string()
                .contains("bogus")
        );
        assert!(e("[[scene]]\nname = \"balloons\"\nn = [20, 20]").contains("twice"));
    }

    #[test]
    fn sweep_h_lists_become_levels() {
        let runs = parse("[[scene]]\nname = \"balloons\"\nh = [0.08, 0.05]\n[[scene]]\nname = \"ring\"\nh = [0.1]").unwrap();
        let ns: Vec<usize> = runs.iter().map(|r| r.n).collect();
        assert_eq!(ns, vec![20, 32, 64]);
        assert!((runs[0].h - 0.08).abs() < 1e-15 && runs[1].h <= 0.05 && runs[2].h <= 0.1);
        // the ring's level is the coarsest even n with h ≤ 0.1
        let coarser = crate::scene::registry::build_scene("ring", 62, None, &Default::default())
            .unwrap()
            .h;
        assert!(coarser > 0.1, "{coarser}");
        let e = format!(
            "{:#}",
            parse("[[scene]]\nname = \"ring\"\nh = [-1.0]").unwrap_err()
        );
        assert!(e.contains("h = -1"), "{e}");
        assert!(
            format!("{:#}", parse("[[scene]]\nname = \"ring\"").unwrap_err())
                .contains("list n or a list h")
        );
    }

    #[test]
    fn sweep_shards_partition_the_runs() {
        let runs = parse(
            "[defaults]\nbackends = [\"clarabel\", \"osqp\", \"uzawa\"]\naccuracy = [\"low\", \"default\", \"high\"]\n[[scene]]\nname = \"balloons\"\nn = [20, 40, 80]",
        )
        .unwrap();
        for n in 1..=4 {
            let mut count = 0;
            for r in &runs {
                let owners = (1..=n).filter(|&k| in_shard(&r.key, Some((k, n)))).count();
                assert_eq!(owners, 1, "{} in {owners} of {n} shards", r.key);
                count += 1;
            }
            assert_eq!(count, runs.len());
        }
        // both shards of 2 are used by 27 runs
        let s1 = runs
            .iter()
            .filter(|r| in_shard(&r.key, Some((1, 2))))
            .count();
        assert!(
            s1 > 0 && s1 < runs.len(),
            "shard 1/2 has {s1} of {}",
            runs.len()
        );
        assert!(
            parse_shard("0/2").is_err() && parse_shard("3/2").is_err() && parse_shard("x").is_err()
        );
        assert_eq!(parse_shard("2/3"), Ok((2, 3)));
    }

    #[test]
    fn sweep_dynamic_blocks_expand_with_their_own_keys_and_reject_bad_input() {
        let runs = parse(
            r#"
            [[scene]]
            name = "collide"
            dynamic = true
            n = [16]
            dt = [0.01, 0.005]
            steps = 4
            scheme = ["euler", "newmark"]
            "#,
        )
        .unwrap();
        assert_eq!(runs.len(), 4);
        assert_eq!(
            runs[0].key,
            format!(
                "collide|n=16|eps=0.1*h^1.0||dt=0.01|steps=4|euler|{DEFAULT_BACKEND}|default|lazy|tolj=preset|max=2000|method=auto"
            )
        );
        assert!(runs.iter().all(|r| r.dynamic.is_some()));
        assert_eq!(runs[3].dynamic.as_ref().unwrap().scheme, Scheme::Newmark);
        // the scene's own dt and steps by default; h picks the ring's level
        let runs = parse("[[scene]]\nname = \"drop\"\ndynamic = true\nh = [0.2]\n").unwrap();
        let d = runs[0].dynamic.as_ref().unwrap();
        assert_eq!((d.dt, d.steps, d.scheme), (0.02, 300, Scheme::Euler));
        assert!(runs[0].h <= 0.2);
        let err = |t: &str| parse(t).unwrap_err().to_string();
        let e = err("[[scene]]\nname = \"collide\"\ndynamic = true\nn = [16]\ndt = [0.0]\n");
        assert!(e.contains("dt must be finite and > 0, got 0"), "{e}");
        let e = err("[[scene]]\nname = \"collide\"\ndynamic = true\nn = [16]\nscheme = \"rk4\"\n");
        assert!(e.contains("\"rk4\""), "{e}");
        let e = err("[[scene]]\nname = \"ring\"\nn = [20]\ndt = [0.1]\n");
        assert!(e.contains("need dynamic = true"), "{e}");
        let e = err(
            "[[scene]]\nname = \"ring\"\nn = [20]\n[[scene]]\nname = \"collide\"\ndynamic = true\nn = [16]\n",
        );
        assert!(e.contains("all static or all dynamic"), "{e}");
        // a static scene run dynamically needs dt and steps (no defaults)
        let e = err("[[scene]]\nname = \"ring\"\ndynamic = true\nn = [20]\n");
        assert!(e.contains("dt must be finite and > 0, got 0"), "{e}");
        assert_ne!(header_dynamic(), header_static());
        let case = header::<CaseColumns>();
        assert_eq!(&header_dynamic()[..case.len()], &case[..]);
    }
}
