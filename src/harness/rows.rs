//! The rows the harness writes, one struct per kind of row: the case columns that start every
//! sweep row ([`CaseColumns`]), a static run's columns ([`StaticRow`]), a dynamic run's
//! ([`DynamicRow`]), a row of the scaling experiment ([`ScalingRow`]) and a row of
//! `export-qp`'s `index.csv` ([`QpIndexRow`]). Each is serialized with serde through the `csv`
//! crate, so a CSV's header is the struct's field names in declaration order ([`header`]) and
//! a row is one [`csv_line`]. The columns are documented in docs/sweeps.md and
//! docs/measurements.md.
//!
//! Cell format (unchanged from the hand-written rows these structs replace): floats in their
//! shortest round-trip form, empty when NaN ([`f`], via `serialize_with = "float"` or
//! `"opt_float"`); integers and booleans as Rust prints them; `None` an empty cell (a failed
//! run's row has only its case columns, `status`, `error` and what the spec alone gives).
//!
//! # Adding a column
//! A new column is a new field, at the place in the struct where the column goes, plus the
//! line that computes it. For a static sweep column, e.g. the number of QPs solved:
//!
//! ```ignore
//! // rows.rs, in `StaticRow`, where the column goes:
//! /// QPs solved over the run.
//! pub qps: Option<usize>,
//! // rows.rs, in `StaticRow::of_case`:
//! qps: Some(o.records.iter().map(|r| r.inner_iterations).sum()),
//! ```
//!
//! The header follows by itself (`sweep --resume` then refuses a CSV written before, whose
//! header differs); a dynamic column goes into [`DynamicRow`] and [`DynamicRow::of_metrics`]
//! the same way.

use crate::harness::case::{CaseOutcome, CaseSettings, DynamicMetrics};
use crate::scene::Scene;
use crate::solve::outer::IterationRecord;
use anyhow::Result;
use serde::{Deserialize, Serialize, Serializer};

/// Formats a float for CSV (shortest round-trip form; empty when NaN).
pub fn f(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v:?}")
    }
}

/// `serialize_with` for an `f64` cell: [`f`].
pub fn float<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&f(*v))
}

/// `serialize_with` for an optional `f64` cell: [`f`], empty when `None`.
pub fn opt_float<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => s.serialize_str(&f(*v)),
        None => s.serialize_none(),
    }
}

/// The header of rows of type `T`: its field names, in order (nested structs and tuples of
/// structs contribute their fields in turn).
pub fn header<T: Serialize + Default>() -> Vec<String> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(true)
        .from_writer(Vec::new());
    w.serialize(T::default())
        .expect("a row type serializes to a record");
    let bytes = w.into_inner().expect("writing to memory");
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(bytes.as_slice());
    let mut rec = csv::StringRecord::new();
    r.read_record(&mut rec).expect("the header just written");
    rec.iter().map(String::from).collect()
}

/// One CSV line (with its newline) of `fields`, quoted where needed.
pub fn record_line<I, S>(fields: I) -> Result<Vec<u8>>
where
    I: IntoIterator<Item = S>,
    S: AsRef<[u8]>,
{
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(fields)?;
    w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))
}

/// One CSV line (with its newline) of a row, without header.
pub fn csv_line<T: Serialize>(row: &T) -> Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.serialize(row)?;
    w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))
}

/// The columns that name a sweep run; every sweep row starts with them (the first, `key`, is
/// what `--resume` and `--shard` read).
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct CaseColumns {
    /// Deterministic key of the run.
    pub key: String,
    /// Scene name.
    pub scene: String,
    /// Mesh level.
    pub n: usize,
    /// ε rule label (`0.1*h^1.0`, `fixed:0.001`).
    pub eps_rule: String,
    /// Scene parameters, `k=v;…`.
    pub params: String,
    /// Backend.
    pub backend: String,
    /// Accuracy preset.
    pub accuracy: String,
    /// Pruning mode.
    pub pruning: String,
    /// Outer method (`pantz`, `sqp`).
    pub outer_method: String,
}

/// What every kind of run row can say about itself: how a failed run (an error, a panic)
/// looks, and the status and wall time shown in the progress lines.
pub trait RunRow: Serialize + Default + Send {
    /// The row of a run that failed: `status` (`error`, `panic`) and the message.
    fn failed(status: &str, error: String) -> Self;
    /// The `status` cell.
    fn status(&self) -> &str;
    /// The `wall_time_s` cell.
    fn wall_time_cell(&self) -> String;
}

/// A static run's columns of a sweep row (after [`CaseColumns`]).
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct StaticRow {
    /// Dimension, 2 or 3.
    pub dim: Option<usize>,
    /// Mesh size.
    #[serde(serialize_with = "opt_float")]
    pub h: Option<f64>,
    /// ε.
    #[serde(serialize_with = "opt_float")]
    pub eps: Option<f64>,
    /// The backend's absolute tolerance.
    #[serde(serialize_with = "opt_float")]
    pub qp_tol: Option<f64>,
    /// tol_J used.
    #[serde(serialize_with = "opt_float")]
    pub tol_j: Option<f64>,
    /// Inner steps per T(ψ) at most.
    pub max_inner: Option<usize>,
    /// Run status, or `error` / `panic`.
    pub status: String,
    /// Outer iterations.
    pub outer_iterations: Option<usize>,
    /// Outer steps that were SQP steps (0 for the `pantz` method).
    pub sqp_steps: Option<usize>,
    /// Outer steps where the SQP step collapsed and Pantz's step was taken.
    pub fallback_steps: Option<usize>,
    /// Inner iterations.
    pub inner_iterations: Option<usize>,
    /// Backend iterations.
    pub backend_iterations: Option<usize>,
    /// J at the end.
    #[serde(serialize_with = "opt_float")]
    pub final_energy: Option<f64>,
    /// Smallest distance at the end.
    #[serde(serialize_with = "opt_float")]
    pub min_distance: Option<f64>,
    /// Every iterate passed the exact admissibility check.
    pub all_admissible: Option<bool>,
    /// J never increased.
    pub energy_monotone: Option<bool>,
    /// Lemma 5.6 residual (converged runs).
    #[serde(serialize_with = "opt_float")]
    pub residual_hm1: Option<f64>,
    /// Lemma 5.6 bound.
    #[serde(serialize_with = "opt_float")]
    pub bound: Option<f64>,
    /// residual / bound.
    #[serde(serialize_with = "opt_float")]
    pub ratio: Option<f64>,
    /// ‖λ‖ in the discrete norm.
    #[serde(serialize_with = "opt_float")]
    pub lambda_norm_h: Option<f64>,
    /// C_φ.
    pub c_phi: Option<usize>,
    /// Largest number of edges at a vertex.
    pub max_edges_per_vertex: Option<usize>,
    /// Canonical stationarity relative to the gradient.
    #[serde(serialize_with = "opt_float")]
    pub stationarity_rel: Option<f64>,
    /// The minimality certificate κ at the returned state (every finished run).
    #[serde(serialize_with = "opt_float")]
    pub kappa: Option<f64>,
    /// Pairs of the last iterate.
    pub pairs: Option<usize>,
    /// Active rows (of the diagnostics, else of the last iterate).
    pub active_rows: Option<usize>,
    /// Wall time of the run.
    #[serde(serialize_with = "opt_float")]
    pub wall_time_s: Option<f64>,
    /// Seconds in the pair search.
    #[serde(serialize_with = "opt_float")]
    pub t_pairs_s: Option<f64>,
    /// Seconds in the assembly.
    #[serde(serialize_with = "opt_float")]
    pub t_assembly_s: Option<f64>,
    /// Seconds in the backend.
    #[serde(serialize_with = "opt_float")]
    pub t_solve_s: Option<f64>,
    /// Seconds in the diagnostics.
    #[serde(serialize_with = "opt_float")]
    pub t_diagnostics_s: Option<f64>,
    /// |J − J_ref| / |J_ref| (converged reference only).
    #[serde(serialize_with = "opt_float")]
    pub energy_error: Option<f64>,
    /// H¹ distance to the reference positions (converged reference only).
    #[serde(serialize_with = "opt_float")]
    pub position_error_h1: Option<f64>,
    /// max(ε − smallest distance over the iterates, 0).
    #[serde(serialize_with = "opt_float")]
    pub max_violation: Option<f64>,
    /// J of the reference.
    #[serde(serialize_with = "opt_float")]
    pub reference_energy: Option<f64>,
    /// The error of a failed run.
    pub error: Option<String>,
}

impl StaticRow {
    /// The row of a finished case (the reference columns and `max_violation` empty).
    pub fn of_case(scene: &Scene, o: &CaseOutcome) -> StaticRow {
        let r = &o.res;
        let sum = |g: fn(&IterationRecord) -> f64| o.records.iter().map(g).sum::<f64>();
        let mut row = StaticRow {
            dim: Some(scene.mesh.dim),
            h: Some(scene.h),
            eps: Some(scene.eps),
            qp_tol: Some(o.qp.eps_abs),
            tol_j: Some(o.tol_j),
            max_inner: Some(o.max_inner),
            status: r.status.as_str().to_string(),
            outer_iterations: Some(r.outer_iterations),
            sqp_steps: Some(r.sqp_steps),
            fallback_steps: Some(r.fallback_steps),
            inner_iterations: Some(r.inner_iterations),
            backend_iterations: Some(r.backend_iterations),
            final_energy: Some(r.energy),
            min_distance: Some(r.min_distance.distance),
            all_admissible: Some(o.records.iter().all(|x| x.admissible)),
            energy_monotone: Some(o.records.windows(2).all(|w| w[1].energy <= w[0].energy)),
            pairs: Some(o.records.last().map_or(0, |x| x.pairs)),
            wall_time_s: Some(r.wall_time_s),
            t_pairs_s: Some(sum(|x| x.t_pairs_s)),
            t_assembly_s: Some(sum(|x| x.t_assembly_s)),
            t_solve_s: Some(sum(|x| x.t_solve_s)),
            t_diagnostics_s: Some(o.t_diagnostics_s),
            kappa: Some(r.certificate.kappa),
            ..Default::default()
        };
        if let Some((d, _)) = &o.diagnostics {
            row.residual_hm1 = Some(d.residual_hm1);
            row.bound = Some(d.bound);
            row.ratio = Some(d.ratio);
            row.lambda_norm_h = Some(d.lambda_norm_h);
            row.c_phi = Some(d.c_phi);
            row.max_edges_per_vertex = Some(d.max_edges_per_vertex);
            row.stationarity_rel =
                Some(d.stationarity_canonical / d.gradient_norm.max(f64::MIN_POSITIVE));
            row.active_rows = Some(d.active_rows);
        } else if let Some(last) = o.records.last() {
            row.active_rows = Some(last.active_rows);
        }
        // What failed: the backend's status on the last step's QP.
        if r.status == crate::solve::outer::RunStatus::SubproblemFailed {
            if let Some(last) = o.records.last() {
                row.error = Some(crate::solve::outer::subproblem_failure(
                    last.iteration,
                    last.qp_status,
                ));
            }
        }
        row
    }
}

/// The columns a static sweep adds after [`StaticRow`] where it asks for the second-order
/// check (`second_order_max_dofs`; a sweep without it keeps the published header).
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct SecondOrderColumns {
    /// The check of a `converged` run's state: `minimum`, `degenerate`, `not_minimum`,
    /// `undetermined` or `not_computed` (empty for the other statuses).
    pub second_order: Option<String>,
    /// Its `λ_min / max|λ|` of the restricted Hessian of the Lagrangian.
    #[serde(serialize_with = "opt_float")]
    pub min_eigenvalue_rel: Option<f64>,
    /// Free dofs of the check.
    pub free_dofs: Option<usize>,
    /// Outer steps that left a saddle the check found (`escape_saddles`).
    pub escapes: Option<usize>,
}

impl SecondOrderColumns {
    /// The columns of a finished run.
    pub fn of_result(r: &crate::solve::outer::RunResult) -> SecondOrderColumns {
        let so = r.second_order.as_ref();
        SecondOrderColumns {
            second_order: so.map(|so| so.status.clone()),
            min_eigenvalue_rel: so.and_then(|so| so.min_eigenvalue_rel),
            free_dofs: so.map(|so| so.free_dofs),
            escapes: Some(r.escapes),
        }
    }
}

impl RunRow for (StaticRow, SecondOrderColumns) {
    fn failed(status: &str, error: String) -> Self {
        (
            StaticRow::failed(status, error),
            SecondOrderColumns::default(),
        )
    }
    fn status(&self) -> &str {
        &self.0.status
    }
    fn wall_time_cell(&self) -> String {
        self.0.wall_time_cell()
    }
}

impl RunRow for StaticRow {
    fn failed(status: &str, error: String) -> Self {
        StaticRow {
            status: status.to_string(),
            error: Some(error),
            ..Default::default()
        }
    }
    fn status(&self) -> &str {
        &self.status
    }
    fn wall_time_cell(&self) -> String {
        self.wall_time_s.map_or(String::new(), f)
    }
}

/// A dynamic run's columns of a sweep row (after [`CaseColumns`]); the quantities are those of
/// [`DynamicMetrics`] (time stepping, §6).
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct DynamicRow {
    /// Dimension, 2 or 3.
    pub dim: Option<usize>,
    /// Mesh size.
    #[serde(serialize_with = "opt_float")]
    pub h: Option<f64>,
    /// ε.
    #[serde(serialize_with = "opt_float")]
    pub eps: Option<f64>,
    /// Δt.
    #[serde(serialize_with = "float")]
    pub dt: f64,
    /// Steps asked for.
    pub steps: usize,
    /// Scheme.
    pub scheme: String,
    /// The backend's absolute tolerance.
    #[serde(serialize_with = "opt_float")]
    pub qp_tol: Option<f64>,
    /// tol_J used.
    #[serde(serialize_with = "opt_float")]
    pub tol_j: Option<f64>,
    /// `completed`, the status that stopped the run, or `error` / `panic`.
    pub status: String,
    /// Steps taken.
    pub steps_taken: Option<usize>,
    /// Steps ended by max_outer.
    pub steps_max_outer: Option<usize>,
    /// Steps that ended where the minimality certificate does not hold (`fixed_point`).
    pub steps_fixed_point: Option<usize>,
    /// The largest certificate κ over the steps.
    #[serde(serialize_with = "opt_float")]
    pub max_kappa: Option<f64>,
    /// Every iterate passed the exact admissibility check.
    pub all_admissible: Option<bool>,
    /// Smallest end-of-step distance.
    #[serde(serialize_with = "opt_float")]
    pub min_distance: Option<f64>,
    /// E_0.
    #[serde(serialize_with = "opt_float")]
    pub initial_energy: Option<f64>,
    /// E at the end.
    #[serde(serialize_with = "opt_float")]
    pub final_energy: Option<f64>,
    /// Kinetic energy at the end.
    #[serde(serialize_with = "opt_float")]
    pub final_kinetic: Option<f64>,
    /// Largest step increase of E.
    #[serde(serialize_with = "opt_float")]
    pub max_energy_increase: Option<f64>,
    /// (E_end − E_0)/|E_0|.
    #[serde(serialize_with = "opt_float")]
    pub energy_drift: Option<f64>,
    /// Momentum error (scenes that conserve momentum).
    #[serde(serialize_with = "opt_float")]
    pub momentum_error: Option<f64>,
    /// Mean contact force over the last steps.
    #[serde(serialize_with = "opt_float")]
    pub force_mean_rest: Option<f64>,
    /// Largest relative jump of the contact force there.
    #[serde(serialize_with = "opt_float")]
    pub force_jump_rest: Option<f64>,
    /// Relative standard deviation of the contact force there.
    #[serde(serialize_with = "opt_float")]
    pub force_std_rest: Option<f64>,
    /// Mean force / weight (drop scenes).
    #[serde(serialize_with = "opt_float")]
    pub weight_ratio_rest: Option<f64>,
    /// Outer iterations over the steps.
    pub outer_iterations: Option<usize>,
    /// Largest outer iterations of one step.
    pub max_outer_per_step: Option<usize>,
    /// Outer iterations that were SQP steps, summed over the steps.
    pub sqp_steps: Option<usize>,
    /// Outer iterations where the SQP step fell back to Pantz's, summed over the steps.
    pub fallback_steps: Option<usize>,
    /// Wall time of the stepping.
    #[serde(serialize_with = "opt_float")]
    pub wall_time_s: Option<f64>,
    /// Wall time of the whole run (scene building included).
    #[serde(serialize_with = "opt_float")]
    pub t_total_s: Option<f64>,
    /// The error of a failed run.
    pub error: Option<String>,
}

impl DynamicRow {
    /// The row of a finished dynamic run of scene `scene` (`dim`, `h`, `ε` of the built scene;
    /// `g` the gravity of a drop scene, for `weight_ratio_rest`). `dt`, `steps`, `scheme` and
    /// `t_total_s` are the caller's.
    pub fn of_metrics(
        dim: usize,
        h: f64,
        eps: f64,
        qp_tol: f64,
        cs: &CaseSettings,
        mt: &DynamicMetrics,
        g: Option<f64>,
    ) -> DynamicRow {
        let mut row = DynamicRow {
            dim: Some(dim),
            h: Some(h),
            eps: Some(eps),
            qp_tol: Some(qp_tol),
            tol_j: Some(cs.tol_j.unwrap_or(cs.accuracy.tol_j())),
            status: mt.status.clone(),
            steps_taken: Some(mt.steps_taken),
            steps_max_outer: Some(mt.steps_max_outer),
            steps_fixed_point: Some(mt.steps_fixed_point),
            max_kappa: Some(mt.max_kappa),
            all_admissible: Some(mt.all_admissible),
            min_distance: Some(mt.min_distance),
            initial_energy: Some(mt.initial_energy),
            final_energy: Some(mt.final_energy),
            final_kinetic: Some(mt.final_kinetic),
            max_energy_increase: Some(mt.max_energy_increase),
            energy_drift: Some(mt.energy_drift),
            momentum_error: mt.momentum_error,
            outer_iterations: Some(mt.outer_iterations),
            max_outer_per_step: Some(mt.max_outer_per_step),
            sqp_steps: Some(mt.sqp_steps),
            fallback_steps: Some(mt.fallback_steps),
            wall_time_s: Some(mt.wall_time_s),
            ..Default::default()
        };
        if let Some(r) = &mt.rest {
            row.force_mean_rest = Some(r.mean);
            row.force_jump_rest = Some(r.max_jump_rel);
            row.force_std_rest = Some(r.std_rel);
            row.weight_ratio_rest = g.map(|g| r.mean / (mt.free_mass * g));
        }
        row
    }
}

impl RunRow for DynamicRow {
    fn failed(status: &str, error: String) -> Self {
        DynamicRow {
            status: status.to_string(),
            error: Some(error),
            ..Default::default()
        }
    }
    fn status(&self) -> &str {
        &self.status
    }
    fn wall_time_cell(&self) -> String {
        self.wall_time_s.map_or(String::new(), f)
    }
}

/// A row of `contactlab scaling`'s CSV. The cells are kept as written (the child process
/// prints them as JSON, a timed-out or failed case has only some), so a row read back is
/// written back unchanged; `trust_delta0` and `max_inner` default to `1` and `50` for rows
/// written before those columns existed.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default)]
pub struct ScalingRow {
    /// Elements per membrane.
    pub n: String,
    /// Vertices.
    pub vertices: String,
    /// Pruning mode.
    pub pruning: String,
    /// `one_step` or `full`.
    pub kind: String,
    /// Initial trust-region half-width (relative to the median edge).
    pub trust_delta0: String,
    /// Inner steps per T(ψ) at most.
    pub max_inner: String,
    /// Status.
    pub status: String,
    /// Outer iterations.
    pub outer_iterations: String,
    /// Inner iterations.
    pub inner_iterations: String,
    /// Pairs at the first step.
    pub pairs: String,
    /// Rows at the first step.
    pub rows: String,
    /// Seconds in the pair search of the first outer step.
    #[serde(alias = "t_pairs_s")]
    pub step1_t_pairs_s: String,
    /// Seconds in the assembly of the first outer step.
    #[serde(alias = "t_assembly_s")]
    pub step1_t_assembly_s: String,
    /// Seconds in the backend in the first outer step.
    #[serde(alias = "t_solve_s")]
    pub step1_t_solve_s: String,
    /// Seconds of the first outer step (the sum of the three).
    #[serde(alias = "t_step_s")]
    pub step1_t_step_s: String,
    /// Seconds in the pair search, summed over the run's outer steps.
    pub total_t_pairs_s: String,
    /// Seconds in the assembly, summed over the run's outer steps.
    pub total_t_assembly_s: String,
    /// Seconds in the backend, summed over the run's outer steps.
    pub total_t_solve_s: String,
    /// QP solves of the run (inner steps and lazy re-solves).
    pub qp_solves: String,
    /// Wall time of the whole run.
    pub wall_time_s: String,
    /// Peak resident memory, MiB.
    pub peak_rss_mb: String,
    /// J at the end.
    pub final_energy: String,
    /// Backend.
    pub backend: String,
}

impl Default for ScalingRow {
    fn default() -> Self {
        ScalingRow {
            n: String::new(),
            vertices: String::new(),
            pruning: String::new(),
            kind: String::new(),
            trust_delta0: "1".into(),
            max_inner: "50".into(),
            status: String::new(),
            outer_iterations: String::new(),
            inner_iterations: String::new(),
            pairs: String::new(),
            rows: String::new(),
            step1_t_pairs_s: String::new(),
            step1_t_assembly_s: String::new(),
            step1_t_solve_s: String::new(),
            step1_t_step_s: String::new(),
            total_t_pairs_s: String::new(),
            total_t_assembly_s: String::new(),
            total_t_solve_s: String::new(),
            qp_solves: String::new(),
            wall_time_s: String::new(),
            peak_rss_mb: String::new(),
            final_energy: String::new(),
            backend: String::new(),
        }
    }
}

impl ScalingRow {
    /// A row with every cell empty.
    pub fn empty() -> ScalingRow {
        ScalingRow {
            trust_delta0: String::new(),
            max_inner: String::new(),
            ..Default::default()
        }
    }

    /// The row of the cells a `scaling-case` child printed (column name → cell).
    pub fn from_cells(cells: serde_json::Map<String, serde_json::Value>) -> Result<ScalingRow> {
        Ok(serde_json::from_value(serde_json::Value::Object(cells))?)
    }
}

/// A row of `export-qp`'s `index.csv`: one sub-problem QP.
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct QpIndexRow {
    /// Index of the QP in the run.
    pub k: usize,
    /// Its QPS file.
    pub file: String,
    /// Variables.
    pub variables: usize,
    /// Constraint rows.
    pub rows: usize,
    /// Non-zeros of P.
    pub nnz_p: usize,
    /// Non-zeros of A.
    pub nnz_a: usize,
    /// The backend's status, or `error: …`.
    pub status: String,
    /// The backend's iterations.
    pub iterations: usize,
    /// Objective at the backend's solution (empty on error).
    #[serde(serialize_with = "float")]
    pub objective: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The headers as they were written by hand before the rows were structs: a changed
    /// header breaks `--resume` on every committed CSV.
    #[test]
    fn headers_are_the_published_ones() {
        let case = "key,scene,n,eps_rule,params,backend,accuracy,pruning,outer_method";
        let stat = "dim,h,eps,qp_tol,tol_j,max_inner,status,outer_iterations,sqp_steps,\
                    fallback_steps,inner_iterations,backend_iterations,final_energy,min_distance,all_admissible,energy_monotone,\
                    residual_hm1,bound,ratio,lambda_norm_h,c_phi,max_edges_per_vertex,\
                    stationarity_rel,kappa,pairs,active_rows,wall_time_s,t_pairs_s,t_assembly_s,\
                    t_solve_s,t_diagnostics_s,energy_error,position_error_h1,max_violation,\
                    reference_energy,error";
        let dynamic = "dim,h,eps,dt,steps,scheme,qp_tol,tol_j,status,steps_taken,\
                       steps_max_outer,steps_fixed_point,max_kappa,all_admissible,min_distance,\
                       initial_energy,final_energy,final_kinetic,max_energy_increase,\
                       energy_drift,momentum_error,force_mean_rest,force_jump_rest,\
                       force_std_rest,weight_ratio_rest,outer_iterations,max_outer_per_step,\
                       sqp_steps,fallback_steps,wall_time_s,t_total_s,error";
        let scaling = "n,vertices,pruning,kind,trust_delta0,max_inner,status,outer_iterations,\
                       inner_iterations,pairs,rows,step1_t_pairs_s,step1_t_assembly_s,\
                       step1_t_solve_s,step1_t_step_s,total_t_pairs_s,total_t_assembly_s,\
                       total_t_solve_s,qp_solves,wall_time_s,peak_rss_mb,final_energy,backend";
        let index = "k,file,variables,rows,nnz_p,nnz_a,status,iterations,objective";
        assert_eq!(
            header::<(CaseColumns, (StaticRow, SecondOrderColumns))>().join(","),
            format!("{case},{stat},second_order,min_eigenvalue_rel,free_dofs,escapes")
        );
        assert_eq!(header::<CaseColumns>().join(","), case);
        assert_eq!(
            header::<(CaseColumns, StaticRow)>().join(","),
            format!("{case},{stat}")
        );
        assert_eq!(
            header::<(CaseColumns, DynamicRow)>().join(","),
            format!("{case},{dynamic}")
        );
        assert_eq!(header::<ScalingRow>().join(","), scaling);
        assert_eq!(header::<QpIndexRow>().join(","), index);
    }

    /// A scaling CSV written before the first-step columns were renamed is read under the new
    /// names (so a resumed experiment keeps its rows).
    #[test]
    fn scaling_rows_read_the_old_first_step_columns() {
        let old = "n,vertices,pruning,kind,status,t_pairs_s,t_assembly_s,t_solve_s,t_step_s,\
                   wall_time_s\n25,104,lazy,one_step,one_step_done,0.1,0.2,0.3,0.6,1.5\n";
        let mut rd = csv::Reader::from_reader(old.as_bytes());
        let row: ScalingRow = rd.deserialize().next().unwrap().unwrap();
        assert_eq!(row.step1_t_pairs_s, "0.1");
        assert_eq!(row.step1_t_step_s, "0.6");
        assert_eq!(row.total_t_solve_s, "");
        assert_eq!(row.wall_time_s, "1.5");
    }

    #[test]
    fn cells_keep_their_format() {
        let row = (
            CaseColumns {
                key: "a|b,c".into(),
                n: 20,
                ..Default::default()
            },
            StaticRow {
                h: Some(0.1),
                eps: Some(f64::NAN),
                tol_j: Some(1e-10),
                status: "error".into(),
                all_admissible: Some(true),
                error: Some("bad \"x\"".into()),
                ..Default::default()
            },
        );
        let line = String::from_utf8(csv_line(&row).unwrap()).unwrap();
        assert!(
            line.starts_with("\"a|b,c\",,20,,,,,,,,0.1,,,1e-10,,error,"),
            "{line}"
        );
        assert!(
            line.ends_with(",true,,,,,,,,,,,,,,,,,,,,,\"bad \"\"x\"\"\"\n"),
            "{line}"
        );
        assert_eq!(f(f64::NAN), "");
        assert_eq!(f(2.0), "2.0");
    }
}
