//! The outer loop of §3: `φ_{k+1} = argmin { J(φ) : φ ∈ T(φ_k) }`, stopped when
//! `|J(φ_{k+1}) − J(φ_k)| ≤ tol_J · max(1, |J(φ_k)|)` (SPEC §2).
//!
//! The loop never prints: it emits one [`IterationRecord`] per outer step to an observer
//! callback, which writes CSV, frames or a progress line.

use crate::energy::TotalEnergy;
use crate::mesh::Mesh;
use crate::pairs::{check_admissible, point_edge_pairs, MinDistance, PointEdgePair};
use crate::rows::{point_edge_rows, PointEdgeRow};
use crate::subproblem::{solve_subproblem, DofMap, InnerSettings};
use contactlab_solvers::{QpBackend, QpError, QpStatus};
use std::time::Instant;
use thiserror::Error;

/// Settings of the outer loop.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OuterSettings {
    /// Relative energy tolerance of the stopping rule.
    pub tol_j: f64,
    /// Maximum number of outer steps.
    pub max_outer: usize,
    /// Inner loop settings.
    pub inner: InnerSettings,
}

impl Default for OuterSettings {
    fn default() -> Self {
        OuterSettings {
            tol_j: 1e-10,
            max_outer: 2000,
            inner: InnerSettings::default(),
        }
    }
}

/// Why the outer loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// The stopping rule was met.
    Converged,
    /// `max_outer` steps without meeting the stopping rule.
    MaxOuterIterations,
    /// A sub-problem's QP did not solve (its status is in the record).
    SubproblemFailed,
    /// The line search could not decrease J along a QP direction.
    LineSearchFailed,
    /// An iterate failed the exact admissibility check (a bug: Lemma 4.2 forbids it).
    Inadmissible,
    /// J increased from one outer iterate to the next (a bug).
    EnergyIncreased,
}

impl RunStatus {
    /// Name used in CSV and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            RunStatus::Converged => "converged",
            RunStatus::MaxOuterIterations => "max_outer_iterations",
            RunStatus::SubproblemFailed => "subproblem_failed",
            RunStatus::LineSearchFailed => "line_search_failed",
            RunStatus::Inadmissible => "inadmissible",
            RunStatus::EnergyIncreased => "energy_increased",
        }
    }
}

/// One outer step, as emitted to observers (iteration 0 is the initial state).
#[derive(Clone, Debug, serde::Serialize)]
pub struct IterationRecord {
    /// Outer iteration k (0 = initial state).
    pub iteration: usize,
    /// J(φ_k).
    pub energy: f64,
    /// Exact minimum distance over all disjoint pairs at φ_k.
    pub min_distance: f64,
    /// Candidate pairs (pairs given rows).
    pub pairs: usize,
    /// Rows of T(φ_{k-1}) (two per pair).
    pub rows: usize,
    /// Rows active at φ_k (value within the margin of ε).
    pub active_rows: usize,
    /// Inner steps of this outer step.
    pub inner_iterations: usize,
    /// Backend iterations of this outer step.
    pub backend_iterations: usize,
    /// Last QP status of this outer step.
    pub qp_status: &'static str,
    /// Seconds in pair search and row building.
    pub t_pairs_s: f64,
    /// Seconds assembling gradients, Hessians and QP matrices.
    pub t_assembly_s: f64,
    /// Seconds in the backend.
    pub t_solve_s: f64,
}

/// Invalid input to a run.
#[derive(Debug, Error)]
pub enum RunError {
    /// φ_0 is not admissible.
    #[error("initial configuration is not admissible: {pair} are at distance {distance:.6e} < eps = {eps:.6e}")]
    InadmissibleStart {
        /// The closest pair, described.
        pair: String,
        /// Its distance.
        distance: f64,
        /// ε.
        eps: f64,
    },
    /// ε ≤ 0 or not finite.
    #[error("eps must be finite and > 0, got {0}")]
    BadEps(f64),
    /// A QP was malformed (a bug in the problem builder, reported, not a panic).
    #[error("QP rejected by the backend: {0}")]
    Qp(#[from] QpError),
    /// J(φ_0) is not finite.
    #[error("initial energy is not finite ({0})")]
    BadInitialEnergy(f64),
}

/// Final state of a run.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Final configuration φ (the last admissible iterate).
    pub x: Vec<f64>,
    /// Why the loop stopped.
    pub status: RunStatus,
    /// Outer steps taken.
    pub outer_iterations: usize,
    /// Inner steps summed.
    pub inner_iterations: usize,
    /// Backend iterations summed.
    pub backend_iterations: usize,
    /// J(φ).
    pub energy: f64,
    /// Exact minimum distance at φ.
    pub min_distance: MinDistance,
    /// Rows of the last T(ψ) and their multipliers (`μ ≥ 0`, two per pair).
    pub last_rows: Vec<PointEdgeRow>,
    /// Multipliers of the last sub-problem.
    pub multipliers: Vec<[f64; 2]>,
    /// Wall time of the whole loop.
    pub wall_time_s: f64,
}

/// Runs the outer loop from `x0`.
pub fn run(
    mesh: &Mesh,
    energy: &TotalEnergy,
    eps: f64,
    x0: &[f64],
    backend: &mut dyn QpBackend,
    settings: &OuterSettings,
    observer: &mut dyn FnMut(&IterationRecord, &[f64]),
) -> Result<RunResult, RunError> {
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(RunError::BadEps(eps));
    }
    let start = Instant::now();
    let t0 = Instant::now();
    let (pairs, fixed_pairs): (Vec<PointEdgePair>, Vec<PointEdgePair>) = point_edge_pairs(mesh);
    let md0 = check_admissible(mesh, x0, &pairs, &fixed_pairs);
    if md0.distance < eps {
        return Err(RunError::InadmissibleStart {
            pair: md0.pair.to_string(),
            distance: md0.distance,
            eps,
        });
    }
    let dofs = DofMap::new(mesh);
    let mut x = x0.to_vec();
    let mut jx = energy.value(&x);
    if !jx.is_finite() {
        return Err(RunError::BadInitialEnergy(jx));
    }
    let t_pairs0 = t0.elapsed().as_secs_f64();
    observer(
        &IterationRecord {
            iteration: 0,
            energy: jx,
            min_distance: md0.distance,
            pairs: pairs.len(),
            rows: 0,
            active_rows: 0,
            inner_iterations: 0,
            backend_iterations: 0,
            qp_status: "none",
            t_pairs_s: t_pairs0,
            t_assembly_s: 0.0,
            t_solve_s: 0.0,
        },
        &x,
    );
    let mut result = RunResult {
        x: Vec::new(),
        status: RunStatus::MaxOuterIterations,
        outer_iterations: 0,
        inner_iterations: 0,
        backend_iterations: 0,
        energy: jx,
        min_distance: md0,
        last_rows: Vec::new(),
        multipliers: Vec::new(),
        wall_time_s: 0.0,
    };
    let margin = settings.inner.margin_rel * eps + settings.inner.margin_abs;
    for k in 1..=settings.max_outer {
        let tp = Instant::now();
        // The all-fixed pairs are constant: checked once above, never given rows.
        let rows = point_edge_rows(mesh, &x, &pairs).expect("admissible ψ has positive distances");
        let t_pairs = tp.elapsed().as_secs_f64();
        let sub = solve_subproblem(
            mesh,
            energy,
            &dofs,
            &rows,
            &x,
            eps,
            backend,
            &settings.inner,
        )?;
        result.outer_iterations = k;
        result.inner_iterations += sub.inner_iterations;
        result.backend_iterations += sub.backend_iterations;
        let tc = Instant::now();
        let md = check_admissible(mesh, &sub.y, &pairs, &fixed_pairs);
        let t_check = tc.elapsed().as_secs_f64();
        let active_rows = rows
            .iter()
            .map(|r| {
                r.values(&sub.y)
                    .iter()
                    .filter(|&&v| v - eps <= 2.0 * margin)
                    .count()
            })
            .sum();
        observer(
            &IterationRecord {
                iteration: k,
                energy: sub.energy,
                min_distance: md.distance,
                pairs: pairs.len(),
                rows: 2 * rows.len(),
                active_rows,
                inner_iterations: sub.inner_iterations,
                backend_iterations: sub.backend_iterations,
                qp_status: sub.qp_status.as_str(),
                t_pairs_s: t_pairs + t_check,
                t_assembly_s: sub.t_assembly_s,
                t_solve_s: sub.t_solve_s,
            },
            &sub.y,
        );
        if md.distance < eps {
            result.status = RunStatus::Inadmissible;
            result.min_distance = md;
            break;
        }
        if sub.energy > jx {
            result.status = RunStatus::EnergyIncreased;
            break;
        }
        let jprev = jx;
        x = sub.y;
        jx = sub.energy;
        result.energy = jx;
        result.min_distance = md;
        result.last_rows = rows;
        result.multipliers = sub.multipliers;
        if sub.qp_status != QpStatus::Solved {
            result.status = RunStatus::SubproblemFailed;
            break;
        }
        if sub.line_search_failed {
            result.status = RunStatus::LineSearchFailed;
            break;
        }
        if (jprev - jx).abs() <= settings.tol_j * jprev.abs().max(1.0) {
            result.status = RunStatus::Converged;
            break;
        }
    }
    result.x = x;
    result.wall_time_s = start.elapsed().as_secs_f64();
    Ok(result)
}
