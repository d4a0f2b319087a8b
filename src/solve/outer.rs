//! The outer loop of §3: `φ_{k+1} = argmin { J(φ) : φ ∈ T(φ_k) }`, stopped when
//! `|J(φ_{k+1}) − J(φ_k)| ≤ max(tol_J · E(φ_{k+1}), 64 u |J(φ_{k+1})|)` (docs/method.md, the
//! stopping rule), with the energy scale of [`energy_scale`]. Where the rule stops the run,
//! the minimality certificate ([`crate::solve::certificate`]) decides the status: `converged`
//! when `κ ≤ tol_κ`, else `fixed_point` (or `line_search_failed` when the last sub-problem
//! stalled in its line search). Every run ends with its certificate.
//!
//! The loop never prints: it emits one [`IterationRecord`] per outer step to an
//! [`Observer`] of [`OuterLoop`] ([`run_observed`]; [`run`] takes a closure), which writes CSV,
//! frames or a progress line.

use crate::contact::continuous::first_contact;
use crate::contact::motion::{point_key, AnyMotionSearch};
use crate::contact::{
    all_movable_pairs, displacements, min_distance, near_pairs, rows_for, ContactPair, PairRows,
};
use crate::contact::{MinDistance, PairSet};
use crate::energy::{HessianModel, Objective};
use crate::scene::mesh::Mesh;
use crate::solve::certificate::{certificate_with, Certificate, CertificateError, CertificatePath};
use crate::solve::h1::{H1Error, H1Norms};
use crate::solve::observer::{Loop, Observer};
use crate::solve::second_order::{second_order, SecondOrder};
use crate::solve::sqp::{
    sqp_step, OuterMethod, SqpContext, SqpSettings, SqpStep, AUTO_CREEP_RATIO,
    AUTO_EDGE_EDGE_STIFFNESS, AUTO_NORMAL_ACTIVE_REL, AUTO_PANTZ_STEPS,
};
use crate::solve::subproblem::row_offsets;
use crate::solve::subproblem::{
    solve_subproblem, DofMap, InnerSettings, ModelShift, RowOracle, SubproblemResult, TrustBox,
};
use contactlab_solvers::{QpBackend, QpError, QpStatus};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;
use thiserror::Error;

/// Which pairs of T(ψ) the sub-problem carries (docs/method.md, pruning).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pruning {
    /// Every pair of disjoint contact elements with a free vertex (the paper-faithful
    /// reference, O(N²) rows): point–edge in 2D, vertex–face and edge–edge in 3D.
    AllPairs,
    /// A working set grown until the sub-problem's solution satisfies every row of the full
    /// T(ψ) (checked through the broad phase with margin ε + 2D): the same iterates as
    /// all-pairs.
    Lazy,
    /// A box `|φ(v) − ψ(v)|∞ ≤ δ` and rows only for pairs closer than `ε + 2√d·δ` (d the
    /// dimension); δ adapts.
    TrustRegion,
}

impl Pruning {
    /// Name used in CSV, JSON and on the command line.
    pub fn as_str(&self) -> &'static str {
        match self {
            Pruning::AllPairs => "all-pairs",
            Pruning::Lazy => "lazy",
            Pruning::TrustRegion => "trust-region",
        }
    }

    /// Parses [`Pruning::as_str`].
    pub fn from_name(s: &str) -> Option<Pruning> {
        match s {
            "all-pairs" => Some(Pruning::AllPairs),
            "lazy" => Some(Pruning::Lazy),
            "trust-region" => Some(Pruning::TrustRegion),
            _ => None,
        }
    }
}

/// Trust-region settings, lengths relative to the median contact edge length `h̄` of ψ_0.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrustSettings {
    /// Initial δ / h̄.
    pub delta0: f64,
    /// Smallest δ / h̄.
    pub delta_min: f64,
    /// Largest δ / h̄.
    pub delta_max: f64,
}

impl Default for TrustSettings {
    fn default() -> Self {
        TrustSettings {
            delta0: 1.0,
            delta_min: 1.0 / 64.0,
            delta_max: 4.0,
        }
    }
}

/// Settings of the outer loop.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OuterSettings {
    /// Relative energy tolerance of the stopping rule (relative to the energy scale of
    /// [`energy_scale`]).
    pub tol_j: f64,
    /// Tolerance of the minimality certificate: a run that meets the stopping rule is
    /// `converged` when `κ ≤ tol_kappa`, else `fixed_point`. The presets use `√tol_J`
    /// (docs/method.md).
    pub tol_kappa: f64,
    /// The backend's tolerance (`eps_abs`): with the row margin δ it sets the certificate's
    /// distance tolerance ([`certificate_active_tol`]).
    pub qp_tol: f64,
    /// Hand the sub-problems' QPs to the backend in the run's own units (energy scale, reference
    /// diameter; [`crate::solve::qp_units`]), so that the backends' absolute tolerances do not
    /// depend on the scene's units. Off by default: it changes the QPs every backend sees, and
    /// with QPs solved to a relative accuracy the creeping runs creep longer
    /// (docs/known-gaps.md).
    pub qp_in_run_units: bool,
    /// Maximum number of outer steps.
    pub max_outer: usize,
    /// The outer method: Pantz's T(ψ) steps, or SQP steps on the linearized true distances
    /// with Pantz's step as their fallback ([`crate::solve::sqp`]).
    pub method: OuterMethod,
    /// Settings of the SQP steps.
    pub sqp: SqpSettings,
    /// Which pairs the sub-problems carry.
    pub pruning: Pruning,
    /// Lazy rows: the initial working set of an outer step holds the pairs closer than
    /// `ε + δ_QP + min(D_prev, lazy_start·h̄)` (`D_prev` the largest vertex displacement of the
    /// previous step, h̄ the median edge length). Any value gives the same iterates; it trades
    /// QP size against re-solves.
    pub lazy_start: f64,
    /// Trust-region settings (used with [`Pruning::TrustRegion`]).
    pub trust: TrustSettings,
    /// Inner loop settings.
    pub inner: InnerSettings,
    /// Wall-time limit of the run in seconds (`None`: no limit). Checked before every outer
    /// step, between inner steps and between lazy rounds (of both methods); a QP in progress,
    /// a pair search and an SQP step's line search are not interrupted, so the run may
    /// overshoot by one QP solve and one pair search, or one SQP line search. On expiry the run stops with
    /// [`RunStatus::TimeLimit`] and returns its last accepted (admissible) iterate.
    pub time_limit_s: Option<f64>,
    /// After convergence, solve the last sub-problem again with its rows at ε itself (no
    /// margin δ), so that the reported state and energy are those of rows at ε, not ε + δ
    /// (docs/method.md, "The row margin"). Not an outer step: `history.csv` ends before it.
    pub polish: bool,
    /// The second-order check of a `converged` run's state ([`crate::solve::second_order`];
    /// [`RunResult::second_order`]) up to this many free dofs (`not_computed` above); 0: no
    /// check (docs/method.md, "The second-order check"). Default 0; `contactlab run` sets it.
    pub second_order_max_dofs: usize,
    /// Where that check finds the state is not a minimum, the run goes on from the lower
    /// admissible point it found, an outer step `escape`, at most [`MAX_ESCAPES`] times.
    /// Default false; `contactlab run` sets it with the `auto` and `sqp` outer methods.
    pub escape_saddles: bool,
    /// The backend of the certificate's dual QP (a name of the backend registry; from
    /// [`crate::solve::certificate::QP_PATH_MIN_GENERATORS`] generators on), `None` for the
    /// registry's `CERTIFICATE_BACKEND` (Clarabel). `contactlab run --certificate-backend`
    /// sets it (docs/method.md, "The minimality certificate").
    pub certificate_backend: Option<String>,
}

/// Escapes from saddles in one run at most ([`OuterSettings::escape_saddles`]).
pub const MAX_ESCAPES: usize = 10;

impl Default for OuterSettings {
    fn default() -> Self {
        OuterSettings {
            tol_j: 1e-10,
            tol_kappa: 1e-5,
            qp_tol: contactlab_solvers::default_settings(contactlab_solvers::DEFAULT_BACKEND)
                .eps_abs,
            qp_in_run_units: false,
            max_outer: 2000,
            method: OuterMethod::default(),
            sqp: SqpSettings::default(),
            pruning: Pruning::Lazy,
            lazy_start: 0.25,
            trust: TrustSettings::default(),
            inner: InnerSettings::default(),
            time_limit_s: None,
            polish: true,
            second_order_max_dofs: 0,
            escape_saddles: false,
            certificate_backend: None,
        }
    }
}

/// Why the outer loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// The stopping rule was met and the minimality certificate holds (`κ ≤ tol_kappa`).
    Converged,
    /// The stopping rule was met at a point whose certificate does not hold (`κ > tol_kappa`):
    /// a fixed point of the outer map that is not a KKT point of problem (3).
    FixedPoint,
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
    /// The wall-time limit ([`OuterSettings::time_limit_s`]) passed.
    TimeLimit,
}

impl RunStatus {
    /// Name used in CSV and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            RunStatus::Converged => "converged",
            RunStatus::FixedPoint => "fixed_point",
            RunStatus::MaxOuterIterations => "max_outer_iterations",
            RunStatus::SubproblemFailed => "subproblem_failed",
            RunStatus::LineSearchFailed => "line_search_failed",
            RunStatus::Inadmissible => "inadmissible",
            RunStatus::EnergyIncreased => "energy_increased",
            RunStatus::TimeLimit => "time_limit",
        }
    }
}

/// What ended a `subproblem_failed` run, for its message and its sweep row: the backend's
/// status on the last QP of outer step `iteration`.
pub fn subproblem_failure(iteration: usize, qp_status: &str) -> String {
    format!("the backend ended {qp_status} on a QP of outer step {iteration}")
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
    /// `min_distance ≥ ε − r`, `r` the round-off allowance of [`roundoff_allowance`].
    pub admissible: bool,
    /// Candidate pairs (pairs given rows).
    pub pairs: usize,
    /// Rows of T(φ_{k-1}) (two per pair in 2D; three or four per pair in 3D).
    pub rows: usize,
    /// Rows active at φ_k (value within the margin of ε).
    pub active_rows: usize,
    /// QP re-solves in this outer step because lazy rows were added.
    pub lazy_rounds: usize,
    /// Trust-region half-width δ used in this step (0 without a trust region).
    pub trust_delta: f64,
    /// Inner steps of this outer step.
    pub inner_iterations: usize,
    /// Backend iterations of this outer step.
    pub backend_iterations: usize,
    /// Last QP status of this outer step.
    pub qp_status: &'static str,
    /// The energy scale `E(φ_k)` of the stopping rule ([`energy_scale`]; NaN at iteration
    /// 0).
    pub energy_scale: f64,
    /// Seconds in pair search and row building.
    pub t_pairs_s: f64,
    /// Seconds assembling gradients, Hessians and QP matrices.
    pub t_assembly_s: f64,
    /// Seconds in the backend.
    pub t_solve_s: f64,
    /// The step taken: `pantz` (a T(ψ) step of the Pantz method), `sqp` (an SQP step),
    /// `fallback` (the SQP step collapsed and Pantz's step was taken; its counts include the
    /// SQP attempt's), `none` (iteration 0).
    pub step: &'static str,
    /// The SQP step's length `t` (NaN for a T(ψ) step; above 1 where the step was
    /// extrapolated, `SqpSettings::extrapolate`).
    pub step_length: f64,
    /// The SQP step's second-order correction QPs.
    pub corrections: usize,
    /// The SQP step's trials rejected by the exact or the continuous check.
    pub rejections: usize,
}

impl IterationRecord {
    /// The record of a state no sub-problem produced (`step`: `none` at iteration 0, the
    /// initial state; `escape`, the point the second-order check found): no rows, QP or inner
    /// steps, `t_pairs_s` the time its pair search took.
    fn without_solve(
        iteration: usize,
        energy: f64,
        md: &MinDistance,
        roundoff: f64,
        eps: f64,
        energy_scale: f64,
        step: &'static str,
    ) -> IterationRecord {
        IterationRecord {
            iteration,
            energy,
            min_distance: md.distance,
            admissible: md.distance >= eps - roundoff,
            pairs: 0,
            rows: 0,
            active_rows: 0,
            lazy_rounds: 0,
            trust_delta: 0.0,
            inner_iterations: 0,
            backend_iterations: 0,
            qp_status: "none",
            energy_scale,
            t_pairs_s: 0.0,
            t_assembly_s: 0.0,
            t_solve_s: 0.0,
            step,
            step_length: f64::NAN,
            corrections: 0,
            rejections: 0,
        }
    }
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
    /// The time limit is not > 0.
    #[error("time limit must be > 0 seconds, got {0}")]
    BadTimeLimit(f64),
    /// The H¹ norm of the mesh (for the stopping rule and the certificate) cannot be built.
    #[error("{0}")]
    H1(#[from] H1Error),
    /// The certificate could not be computed (a bug: the point is admissible).
    #[error("minimality certificate: {0}")]
    Certificate(#[from] CertificateError),
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
    /// Rows of the last T(ψ), grouped by pair.
    pub last_rows: Vec<PairRows>,
    /// Multipliers of the last sub-problem (`μ ≥ 0`, one per row of each pair).
    pub multipliers: Vec<[f64; 4]>,
    /// The minimality certificate at φ (the last one computed, at the returned state, whatever
    /// the status).
    pub certificate: Certificate,
    /// How many times the run computed the certificate (the SQP endgame's stopping checks,
    /// the states it compares, and the returned state).
    pub certificate_calls: usize,
    /// The seconds those computations took in all ([`Certificate::seconds`] is the last
    /// one's only).
    pub certificate_seconds: f64,
    /// Wall time of the whole loop (the certificate included).
    pub wall_time_s: f64,
    /// The final polish at ε ([`OuterSettings::polish`]), when it ran.
    pub polish: Option<Polish>,
    /// The ψ of the last sub-problem (the rows of `last_rows` are those of T(ψ)).
    pub psi: Vec<f64>,
    /// Outer steps that were SQP steps ([`OuterMethod::Sqp`]).
    pub sqp_steps: usize,
    /// Outer steps where the SQP step collapsed and Pantz's step was taken.
    pub fallback_steps: usize,
    /// [`OuterMethod::Auto`]: the first outer step of its SQP phase (`None`: Pantz's map
    /// throughout, or another method).
    pub sqp_from: Option<usize>,
    /// The tightest backend tolerance the SQP method set to reach its certificate
    /// ([`SQP_TOLERANCE_RANGE`]); `None` where it kept the run's own. Where a QP failed at it,
    /// the run stopped at the state before that step.
    pub qp_tol_tightened: Option<f64>,
    /// Outer steps that left a saddle ([`OuterSettings::escape_saddles`]).
    pub escapes: usize,
    /// The second-order check at the returned state (`converged` runs with
    /// [`OuterSettings::second_order_max_dofs`] > 0).
    pub second_order: Option<SecondOrder>,
}

/// How far the SQP method tightens the backend's tolerance when its step is stationary for
/// the QP but the certificate does not hold (docs/method.md, "The SQP outer method"): each such
/// step divides the tolerance by 10, down to this fraction of the run's own (two steps). A
/// fraction, not an absolute floor: the backends' tolerances are partly absolute, and a scene
/// in small units (the elastic Hertz case, J ≈ 5e-4, run at 1e-11) needs 1e-13 where the
/// balloons (J ≈ 26, at 1e-9) need 1e-10.
pub const SQP_TOLERANCE_RANGE: f64 = 1e-2;

/// The shortest SQP step (fraction of the QP's step the line search kept) that counts as
/// progress in the SQP method's endgame: shorter steps lower J by round-off-sized amounts for
/// thousands of steps (asymmetric balloons n = 20), so they end the run, or tighten the
/// backend's tolerance first ([`SQP_TOLERANCE_RANGE`]).
pub const SQP_ENDGAME_MIN_STEP: f64 = 1.0 / 1024.0;

/// The outcome of the final polish at ε (docs/method.md, "The row margin").
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Polish {
    /// J after the polish minus J before (≤ 0; 0 when not accepted).
    pub energy_change: f64,
    /// Its inner steps (also counted in the run's total).
    pub inner_iterations: usize,
    /// Whether its iterate was kept: admissible, its QPs solved, J not raised, and (after an
    /// SQP step) certified where the state before it was.
    pub accepted: bool,
    /// After an SQP step: the polished state failed the certificate that the state before
    /// it passed, so the state before it (rows at ε + δ) is returned.
    pub rejected_by_certificate: bool,
}

/// Round-off allowance of the exact admissibility check: `16 u · max(1, max |x_i|)`, `u` the
/// machine epsilon. Lemma 4.2 gives `dist ≥ ε` in exact arithmetic; the distance kernel computes
/// from coordinates of magnitude `max |x_i|`, so it is exact to a few `u` times that (docs/method.md:
/// "≥ ε, to round-off"). Measured case: Uzawa at tolerance 1e-8 (above the row margin δ) put a
/// row exactly at ε and the kernel returned ε − 2.3e-17.
pub fn roundoff_allowance(x: &[f64]) -> f64 {
    16.0 * f64::EPSILON * x.iter().fold(1.0f64, |m, v| m.max(v.abs()))
}

/// The floor of the certificate's scale `S`, relative to `S` at the run's start: `√u`, `u`
/// the machine epsilon. Where every force of the balance vanishes at the end (a time step in
/// free flight: the body at rest shape, the inertia term at its minimum), `κ = ‖r‖/S` is
/// round-off over round-off and reads about 1; measured on `contactlab run collide
/// --dynamic`, whose free-flight steps read κ = 1.0 with `S` about 1e-14 of the forces at the
/// step's start. Below `√u` of the forces a run started from, the end state's forces are not
/// resolved by a double-precision solve, so `S` is floored there. A static scene whose
/// forces stay of the order of its loads never reaches the floor.
pub const CERTIFICATE_SCALE_FLOOR: f64 = 1.490_116_119_384_765_6e-8;

/// `c` with its scale `S` raised to `floor` where it is below (κ and the dual gap rescaled).
fn with_scale_floor(mut c: Certificate, floor: f64) -> Certificate {
    if floor.is_finite() && c.scale < floor {
        c.kappa = c.residual / floor;
        c.dual_gap *= c.scale / floor;
        c.scale = floor;
    }
    c
}

/// The energy scale `E(x) = S·ℓ` of the stopping rule (docs/method.md, the stopping rule):
/// `S = max(‖J'(x)‖_{H⁻¹}, max_t ‖J_t'(x)‖_{H⁻¹})`, the largest force of the balance at `x`
/// (the net force on the free dofs, each term's force with its reactions at the fixed
/// vertices; [`crate::solve::certificate::forces`]), in the unit-free norm of
/// [`crate::solve::h1::H1Norm::scaled`], and `ℓ` the diameter of the reference positions: the work of that
/// force over the size of the scene. It scales with the energy unit, does not depend on the
/// length unit or on an additive constant in J (which `|J|` does: `−C ln V` shifts with the
/// unit of area), and does not vanish at a minimum without contact.
pub fn energy_scale(energy: &dyn Objective, x: &[f64], norms: &H1Norms) -> f64 {
    let (gnorm, term_force, _, _) = crate::solve::certificate::forces(energy, x, norms);
    gnorm.max(term_force) * norms.free.ell
}

/// The distance tolerance of the certificate: a pair is at distance ε when its distance is at
/// most `ε + 2δ + qp_tol·ℓ`, `δ = margin_rel·ε + margin_abs` the sub-problems' row margin (the
/// rows are imposed at `ε + δ`) and `qp_tol·ℓ` what a backend's feasibility tolerance leaves
/// on a row of length scale `ℓ` (the reference diameter).
pub fn certificate_active_tol(settings: &OuterSettings, eps: f64, ell: f64) -> f64 {
    let delta = settings.inner.margin_rel * eps + settings.inner.margin_abs;
    2.0 * delta + settings.qp_tol * ell
}

/// Median length of the contact edges at `x`: the `h̄` of [`TrustSettings`] and of
/// [`OuterSettings::lazy_start`] (the median, not the mean, so that a few long edges, such as
/// the balloons' box, do not set the scale).
pub fn median_edge_length(mesh: &Mesh, x: &[f64]) -> f64 {
    let mut l: Vec<f64> = mesh
        .edges
        .iter()
        .map(|e| {
            if mesh.dim == 2 {
                (Mesh::p2(x, e[0]) - Mesh::p2(x, e[1])).norm()
            } else {
                (mesh.point(x, e[0]) - mesh.point(x, e[1])).norm()
            }
        })
        .collect();
    if l.is_empty() {
        return 0.0;
    }
    let mid = l.len() / 2;
    *l.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The lazy-row oracle at ψ (see [`RowOracle`]): the rows of T(ψ) below `ε + δ` at φ that are
/// not carried yet, found by relative displacement ([`crate::contact::motion::MotionSearch`]: a pair can only be
/// violated when its elements' relative motion since ψ can close its gap at ψ; the trees at ψ
/// are built at the first call and reused for the whole outer step). Of those, per point (or
/// first edge) only the most violated pair is returned.
fn lazy_oracle<'a>(
    mesh: &'a Mesh,
    psi: &'a [f64],
    eps_qp: f64,
) -> impl FnMut(&[f64], &[PairRows]) -> Vec<PairRows> + 'a {
    let mut carried = PairSet::default();
    let mut search: Option<AnyMotionSearch> = None;
    move |phi: &[f64], rows: &[PairRows]| {
        if carried.len() != rows.len() {
            carried = rows.iter().map(|r| r.pair).collect::<PairSet>();
        }
        let search = search.get_or_insert_with(|| AnyMotionSearch::new(mesh, psi));
        // Per point (or first edge), only the most violated pair: the QP solved again with
        // these moves the point, and the oracle is asked again about the next point found.
        // The choice is made inside the traversal, which never holds every violated pair.
        let added =
            search.most_violated_per_point(mesh, psi, phi, eps_qp, &|p| carried.contains(&p));
        carried.extend(added.iter().map(|r| r.pair));
        added
    }
}

/// A sub-problem's multipliers summed per pair: the warm start of the certificate's active
/// set.
fn pair_multipliers(rows: &[PairRows], multipliers: &[[f64; 4]]) -> HashMap<ContactPair, f64> {
    rows.iter()
        .zip(multipliers)
        .map(|(r, m)| (r.pair, m.iter().take(r.len).sum()))
        .collect()
}

/// The indices of the pairs to add to a working set, of `(pair, value)` (values below the
/// row level): per point (the vertex of a point pair, the first edge of an edge–edge pair) the
/// pair of smallest value (the first on ties), in index order.
pub(crate) fn most_violated_per_point(
    violated: impl Iterator<Item = (ContactPair, f64)>,
) -> Vec<usize> {
    let mut best: HashMap<usize, (f64, usize)> = HashMap::new();
    for (i, (pair, v)) in violated.enumerate() {
        let e = best.entry(point_key(pair)).or_insert((v, i));
        if v < e.0 || (v == e.0 && i < e.1) {
            *e = (v, i);
        }
    }
    let mut pick: Vec<usize> = best.into_values().map(|(_, i)| i).collect();
    pick.sort_unstable();
    pick
}

/// What every outer step of one run shares.
struct StepContext<'a> {
    mesh: &'a Mesh,
    energy: &'a dyn Objective,
    eps: f64,
    dofs: &'a DofMap,
    settings: &'a OuterSettings,
    /// The all-pairs mode's pairs (empty otherwise).
    all_pairs: &'a [ContactPair],
    /// Median contact edge length at φ_0.
    hbar: f64,
    roundoff: f64,
    deadline: Option<Instant>,
    /// The H¹ norms of the stopping rule's energy scale.
    norms: &'a H1Norms,
}

/// One outer step: its sub-problem, its record, the exact minimum distance of its iterate, and
/// whether the trust box bound it.
struct Step {
    sub: SubproblemResult,
    record: IterationRecord,
    min_distance: MinDistance,
    box_active: bool,
    /// The energy scale at the step's iterate ([`energy_scale`]).
    energy_scale: f64,
}

impl StepContext<'_> {
    /// The step `k` from ψ = `x`: the sub-problem min J over T(ψ) with rows at `ε + margin`
    /// from the inner start `start` (ψ itself, or a point of T(ψ) for the polish; `delta`: the
    /// trust half-width; `d_prev`: the last step's largest displacement; `warm`: the last
    /// multipliers by pair), checked exactly.
    #[allow(clippy::too_many_arguments)]
    fn step(
        &self,
        x: &[f64],
        start: &[f64],
        k: usize,
        margin: f64,
        delta: f64,
        d_prev: f64,
        e_scale: f64,
        warm: &HashMap<ContactPair, [f64; 4]>,
        backend: &mut dyn QpBackend,
    ) -> Result<Step, RunError> {
        let (mesh, eps, settings) = (self.mesh, self.eps, self.settings);
        let eps_qp = eps + margin;
        // Inside the box |φ − ψ|∞ ≤ δ a vertex moves by at most √d·δ, a row by twice that.
        let box_reach = if mesh.dim == 2 {
            2.0 * std::f64::consts::SQRT_2
        } else {
            2.0 * 3f64.sqrt()
        };
        let tp = Instant::now();
        // The pairs given rows up front (the all-fixed pairs are constant: checked once at the
        // start, never given rows).
        let pairs: Vec<ContactPair> = match settings.pruning {
            Pruning::AllPairs => self.all_pairs.to_vec(),
            // Start from the pairs that the last step's displacement could reach, within
            // `lazy_start·h̄`; the oracle adds whatever else a QP solution violates.
            Pruning::Lazy => {
                let r = eps_qp + d_prev.min(settings.lazy_start * self.hbar);
                near_pairs(mesh, x, r, true)
            }
            // Inside the box a row moves by at most 2√d·δ: farther pairs cannot be violated.
            Pruning::TrustRegion => {
                let r = eps_qp + box_reach * delta * (1.0 + 1e-9);
                near_pairs(mesh, x, r, true)
            }
        };
        let rows0 = rows_for(mesh, x, &pairs).expect("admissible ψ has positive distances");
        let t_pairs_s = tp.elapsed().as_secs_f64();
        let trust =
            (settings.pruning == Pruning::TrustRegion).then_some(TrustBox { psi: x, delta });
        let mut oracle = lazy_oracle(mesh, x, eps_qp);
        let mut inner = settings.inner.clone();
        // The sub-problem's rows are at ε + margin_rel·ε + margin_abs.
        if margin == 0.0 {
            inner.margin_rel = 0.0;
            inner.margin_abs = 0.0;
        }
        inner.energy_scale = Some(e_scale);
        inner.length_scale = settings.qp_in_run_units.then_some(self.norms.free.ell);
        let sub = solve_subproblem(
            mesh,
            self.energy,
            self.dofs,
            rows0,
            start,
            eps,
            trust,
            (settings.pruning == Pruning::Lazy).then_some(&mut oracle as RowOracle),
            Some(warm),
            backend,
            &inner,
            self.deadline,
        )?;
        let box_active = trust.is_some_and(|tb| {
            let dmax = x
                .iter()
                .zip(&sub.y)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            dmax >= (1.0 - 1e-3) * tb.delta
        });
        drop(oracle);
        Ok(self.finish(k, sub, t_pairs_s, delta, box_active, None))
    }

    /// The record of step `k` whose sub-problem (or SQP step) ended at `sub.y`: its exact
    /// minimum distance (`md`, or computed here), energy scale and active rows.
    fn finish(
        &self,
        k: usize,
        sub: SubproblemResult,
        t_pairs_s: f64,
        delta: f64,
        box_active: bool,
        md: Option<MinDistance>,
    ) -> Step {
        let (mesh, eps, settings) = (self.mesh, self.eps, self.settings);
        let tc = Instant::now();
        let md = md.unwrap_or_else(|| min_distance(mesh, &sub.y, 2.0 * eps, true));
        let t_check = tc.elapsed().as_secs_f64();
        let e_new = energy_scale(self.energy, &sub.y, self.norms);
        // Active: within twice the run's margin of ε (the same count with or without it).
        let act = 2.0 * (settings.inner.margin_rel * eps + settings.inner.margin_abs);
        let active_rows = sub
            .rows
            .par_iter()
            .map(|r| {
                r.values(&sub.y)
                    .iter()
                    .take(r.len)
                    .filter(|&&v| v - eps <= act)
                    .count()
            })
            .sum();
        let record = IterationRecord {
            iteration: k,
            energy: sub.energy,
            min_distance: md.distance,
            admissible: md.distance >= eps - self.roundoff,
            pairs: sub.rows.len(),
            rows: row_offsets(&sub.rows).1,
            active_rows,
            lazy_rounds: sub.lazy_rounds,
            trust_delta: if settings.pruning == Pruning::TrustRegion {
                delta
            } else {
                0.0
            },
            inner_iterations: sub.inner_iterations,
            backend_iterations: sub.backend_iterations,
            qp_status: sub.qp_status.as_str(),
            energy_scale: e_new,
            t_pairs_s: t_pairs_s + sub.t_pairs_s + t_check,
            t_assembly_s: sub.t_assembly_s,
            t_solve_s: sub.t_solve_s,
            step: "pantz",
            step_length: f64::NAN,
            corrections: 0,
            rejections: 0,
        };
        Step {
            sub,
            record,
            min_distance: md,
            box_active,
            energy_scale: e_new,
        }
    }

    /// The SQP step `k` from the admissible `x` ([`crate::solve::sqp`]): its [`Step`] when it
    /// was accepted or `x` is stationary for it, and the attempt's counts (charged to the
    /// fallback step when it collapsed).
    #[allow(clippy::too_many_arguments)]
    fn sqp(
        &self,
        x: &[f64],
        jx: f64,
        k: usize,
        d_prev: f64,
        e_scale: f64,
        warm: &HashMap<ContactPair, [f64; 4]>,
        shift: &mut ModelShift,
        backend: &mut dyn QpBackend,
        fine_slope: bool,
    ) -> Result<(Option<Step>, SqpStep), RunError> {
        let settings = self.settings;
        let mut inner = settings.inner.clone();
        inner.energy_scale = Some(e_scale);
        inner.length_scale = settings.qp_in_run_units.then_some(self.norms.free.ell);
        let sctx = SqpContext {
            mesh: self.mesh,
            energy: self.energy,
            eps: self.eps,
            dofs: self.dofs,
            inner: &inner,
            sqp: &settings.sqp,
            roundoff: self.roundoff,
            start_radius: d_prev.min(settings.lazy_start * self.hbar),
            deadline: self.deadline,
            fine_slope,
        };
        let warm_mu: HashMap<ContactPair, f64> =
            warm.iter().map(|(p, m)| (*p, m.iter().sum())).collect();
        let mut s = sqp_step(&sctx, x, jx, &warm_mu, shift, backend)?;
        let (y, energy, md) = match s.accepted.take() {
            Some(a) => a,
            None if s.stationary => (
                x.to_vec(),
                jx,
                min_distance(self.mesh, x, 2.0 * self.eps, true),
            ),
            None => return Ok((None, s)),
        };
        let sub = SubproblemResult {
            y,
            energy,
            inner_iterations: 1,
            backend_iterations: s.backend_iterations,
            qp_status: s.qp_status,
            line_search_failed: false,
            line_search_stalled: false,
            rows: std::mem::take(&mut s.rows),
            multipliers: std::mem::take(&mut s.multipliers),
            lazy_rounds: s.lazy_rounds,
            t_pairs_s: s.t_pairs_s,
            t_assembly_s: s.t_assembly_s,
            t_solve_s: s.t_solve_s,
            timed_out: false,
        };
        let mut step = self.finish(k, sub, 0.0, 0.0, false, Some(md));
        step.record.step = "sqp";
        step.record.step_length = s.step_length;
        step.record.corrections = s.corrections;
        step.record.rejections = s.rejections;
        Ok((Some(step), s))
    }
}

/// Whether the outer loop keeps an SQP step `s` that produced a point (accepted, or `x` itself
/// when stationary) and lowered J by `decrease`: always when `x` is stationary for the
/// linearized problem or no safeguard cut the step; a step that a safeguard (the exact or
/// the continuous check, a failed correction) cut and that lowered J by at most the stopping
/// rule's `tol` is no evidence of a fixed point, and Pantz's step is taken instead.
pub(crate) fn keep_sqp_step(s: &SqpStep, decrease: f64, tol: f64) -> bool {
    s.stationary || !(s.limited && decrease <= tol)
}

/// A Pantz step taken because the SQP attempt `s` collapsed: the attempt's QP solves, backend
/// iterations and times are charged to it.
fn charge_fallback(step: &mut Step, s: &SqpStep) {
    step.sub.inner_iterations += 1;
    step.sub.backend_iterations += s.backend_iterations;
    let r = &mut step.record;
    r.step = "fallback";
    r.inner_iterations += 1;
    r.lazy_rounds += s.lazy_rounds;
    r.backend_iterations += s.backend_iterations;
    r.corrections = s.corrections;
    r.rejections = s.rejections;
    r.t_pairs_s += s.t_pairs_s;
    r.t_assembly_s += s.t_assembly_s;
    r.t_solve_s += s.t_solve_s;
}

/// The outer loop as a [`Loop`]: an event is an iterate and its record, the outcome the
/// [`RunResult`].
pub struct OuterLoop;

/// One event of the outer loop.
pub struct OuterEvent<'a> {
    /// The step's record.
    pub record: &'a IterationRecord,
    /// The step's iterate (the sub-problem's solution, admissible or not).
    pub x: &'a [f64],
    /// The rows of the step's last QP (empty at iteration 0).
    pub rows: &'a [PairRows],
    /// Their multipliers (`μ ≥ 0`, one per row of each pair; empty at iteration 0).
    pub multipliers: &'a [[f64; 4]],
}

impl Loop for OuterLoop {
    type Event<'a> = OuterEvent<'a>;
    type Outcome = RunResult;
    fn index(event: &OuterEvent<'_>) -> usize {
        event.record.iteration
    }
}

/// A closure `(record, iterate)` as an observer of the outer loop.
struct FnOuter<'f>(&'f mut dyn FnMut(&IterationRecord, &[f64]));

impl Observer<OuterLoop> for FnOuter<'_> {
    fn iteration(&mut self, event: &OuterEvent<'_>) {
        (self.0)(event.record, event.x)
    }
}

/// Whether the polish step `step` from a state of energy `jx` is kept: admissible, solved, not
/// above `jx`.
fn polish_accepted(step: &Step, jx: f64) -> bool {
    let sub = &step.sub;
    step.record.admissible
        && sub.energy <= jx
        && sub.qp_status == QpStatus::Solved
        && !sub.line_search_failed
        && !sub.timed_out
}

/// [`OuterMethod::Auto`]'s SQP phase: the run's settings with [`SqpSettings::one_line`], the
/// normal stiffness on the pairs in contact only ([`AUTO_NORMAL_ACTIVE_REL`]), surfaces'
/// edge–edge pairs in `interior` ([`AUTO_EDGE_EDGE_STIFFNESS`]) and, where the run's Newton
/// model is `shifted` (the default), `shifted-tight` (the one command line's; docs/method.md,
/// "The contact terms from the pairs in contact").
fn auto_sqp_settings(settings: &OuterSettings) -> OuterSettings {
    let mut s = settings.clone();
    s.method = OuterMethod::Sqp;
    s.sqp = SqpSettings {
        normal_active_rel: AUTO_NORMAL_ACTIVE_REL,
        edge_edge_stiffness: AUTO_EDGE_EDGE_STIFFNESS,
        ..SqpSettings::one_line()
    };
    if s.inner.hessian_model == HessianModel::Shifted {
        s.inner.hessian_model = HessianModel::ShiftedTight;
    }
    s
}

/// Runs the outer loop from `x0`, calling `observer` with every record and iterate.
pub fn run(
    mesh: &Mesh,
    energy: &dyn Objective,
    eps: f64,
    x0: &[f64],
    backend: &mut dyn QpBackend,
    settings: &OuterSettings,
    observer: &mut dyn FnMut(&IterationRecord, &[f64]),
) -> Result<RunResult, RunError> {
    run_observed(
        mesh,
        energy,
        eps,
        x0,
        backend,
        settings,
        &mut FnOuter(observer),
    )
}

/// Runs the outer loop from `x0`, reporting to `observer` ([`Observer::init`] once the start
/// is checked, [`Observer::finish`] with the result). The backend's tolerance, which the SQP
/// endgame may tighten, is the caller's again afterwards, however the run ended.
pub fn run_observed(
    mesh: &Mesh,
    energy: &dyn Objective,
    eps: f64,
    x0: &[f64],
    backend: &mut dyn QpBackend,
    settings: &OuterSettings,
    observer: &mut dyn Observer<OuterLoop>,
) -> Result<RunResult, RunError> {
    let tolerance0 = backend.tolerance();
    let res = outer_loop(mesh, energy, eps, x0, backend, settings, observer);
    if let Some(t) = tolerance0 {
        backend.set_tolerance(t);
    }
    res
}

/// [`run_observed`] without the restoring of the backend's tolerance.
fn outer_loop(
    mesh: &Mesh,
    energy: &dyn Objective,
    eps: f64,
    x0: &[f64],
    backend: &mut dyn QpBackend,
    settings: &OuterSettings,
    observer: &mut dyn Observer<OuterLoop>,
) -> Result<RunResult, RunError> {
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(RunError::BadEps(eps));
    }
    if let Some(t) = settings.time_limit_s {
        if t.is_nan() || t <= 0.0 {
            return Err(RunError::BadTimeLimit(t));
        }
    }
    let start = Instant::now();
    // A limit too large for an Instant (e.g. 1e300 s) is no limit.
    let deadline = settings
        .time_limit_s
        .and_then(|t| std::time::Duration::try_from_secs_f64(t).ok())
        .and_then(|d| start.checked_add(d));
    let t0 = Instant::now();
    // The start is checked over every disjoint pair, the all-fixed ones included (once).
    let md0 = min_distance(mesh, x0, 2.0 * eps, false);
    // Admissible as the loop's iterates are (within the round-off allowance of the exact
    // check): a time step starts from the last one's end state, which may sit an ulp below ε.
    if md0.distance < eps - roundoff_allowance(x0) {
        return Err(RunError::InadmissibleStart {
            pair: md0.pair.to_string(),
            distance: md0.distance,
            eps,
        });
    }
    let all_pairs: Vec<ContactPair> = if settings.pruning == Pruning::AllPairs {
        all_movable_pairs(mesh)
    } else {
        Vec::new()
    };
    let dofs = DofMap::new(mesh);
    let mut x = x0.to_vec();
    let mut jx = energy.value(&x);
    if !jx.is_finite() {
        return Err(RunError::BadInitialEnergy(jx));
    }
    let norms = H1Norms::scaled(mesh)?;
    let mut e_scale = energy_scale(energy, &x, &norms);
    let scale_floor = CERTIFICATE_SCALE_FLOOR * e_scale / norms.free.ell;
    // The certificate at a state, from the multipliers by pair of its last sub-problem.
    let active_tol = certificate_active_tol(settings, eps, norms.free.ell);
    let cert_time = std::cell::Cell::new((0usize, 0.0f64));
    let certify = |x: &[f64], warm: &HashMap<ContactPair, f64>| {
        let t = Instant::now();
        let path = match settings.certificate_backend.as_deref() {
            Some(backend) => CertificatePath::AutoWith { backend },
            None => CertificatePath::Auto,
        };
        let c = certificate_with(mesh, energy, x, eps, active_tol, &norms, warm, path);
        let (calls, seconds) = cert_time.get();
        cert_time.set((calls + 1, seconds + t.elapsed().as_secs_f64()));
        c.map(|c| with_scale_floor(c, scale_floor))
    };
    let hbar = median_edge_length(mesh, x0);
    let roundoff = roundoff_allowance(x0);
    let mut delta = settings.trust.delta0 * hbar;
    let mut d_prev = hbar;
    let t_pairs0 = t0.elapsed().as_secs_f64();
    observer.init();
    observer.iteration(&OuterEvent {
        record: &IterationRecord {
            // the start was checked admissible above
            admissible: true,
            pairs: all_pairs.len(),
            t_pairs_s: t_pairs0,
            ..IterationRecord::without_solve(0, jx, &md0, roundoff, eps, e_scale, "none")
        },
        x: &x,
        rows: &[],
        multipliers: &[],
    });
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
        certificate: Certificate::default(),
        certificate_calls: 0,
        certificate_seconds: 0.0,
        wall_time_s: 0.0,
        polish: None,
        psi: Vec::new(),
        sqp_steps: 0,
        fallback_steps: 0,
        sqp_from: None,
        qp_tol_tightened: None,
        escapes: 0,
        second_order: None,
    };
    let tolerance0 = backend.tolerance();
    // The rule stopped the run (`converged` or `fixed_point` by the certificate), and the
    // last sub-problem stalled in its line search.
    let mut stopped_by_rule = false;
    let mut stalled = false;
    // The certificate at x, where the SQP endgame computed it since x last changed (the end of
    // the run then reuses it instead of computing it again).
    let mut cert_at_x: Option<Certificate> = None;
    let margin = settings.inner.margin_rel * eps + settings.inner.margin_abs;
    // The last sub-problem's multipliers by pair: the next step's warm start.
    let mut last_mult: HashMap<ContactPair, [f64; 4]> = HashMap::new();
    let ctx = StepContext {
        mesh,
        energy,
        eps,
        dofs: &dofs,
        settings,
        all_pairs: &all_pairs,
        hbar,
        roundoff,
        deadline,
        norms: &norms,
    };
    // `auto`: the SQP phase's settings (the one command line's) and its step context.
    let auto = settings.method == OuterMethod::Auto;
    let line_settings = auto.then(|| auto_sqp_settings(settings));
    let ctx_line = line_settings
        .as_ref()
        .map(|s| StepContext { settings: s, ..ctx });
    // The method of the next step, and the context it is taken in (`auto`: Pantz's, then the
    // line's once the SQP phase has begun; its fallbacks and polish included).
    let mut method = if auto {
        OuterMethod::Pantz
    } else {
        settings.method
    };
    let mut cur = &ctx;
    // The decreases of J of the last two steps (NaN before them: no comparison holds).
    let mut decreases = [f64::NAN; 2];
    // The steps taken so far that the trust region's box did not cut (all of them without it).
    let mut free_steps = 0;
    // `auto`: the polish and certificate computed where Pantz's map stopped at a certified
    // state (the end of the run reuses both).
    let mut early_polish: Option<(Step, Certificate)> = None;
    // The SQP endgame's last resort: the stationarity test without its energy-scale floor.
    let mut fine_slope = false;
    // The ψ of the last accepted step.
    let mut psi = x.clone();
    // The last step was an SQP step (its polish is about T(x) at the final x), and the
    // Newton model's shift carried from one SQP step to the next.
    let mut last_sqp = false;
    let mut shift = ModelShift::default();
    // The outer steps before this pass: a pass ends where the run stops, and another begins
    // where the run escapes a saddle (`escape_saddles`).
    let mut k0 = 0;
    'escape: loop {
        for k in (k0 + 1)..=settings.max_outer {
            if deadline.is_some_and(|d| Instant::now() >= d) {
                result.status = RunStatus::TimeLimit;
                break;
            }
            let creeps = decreases[1] > AUTO_CREEP_RATIO * decreases[0];
            if auto && method == OuterMethod::Pantz && (free_steps >= AUTO_PANTZ_STEPS || creeps) {
                // Pantz's map did not stop within its steps, or its decrease of J shrinks too
                // slowly: it creeps; the SQP method goes on.
                method = OuterMethod::Sqp;
                result.sqp_from = Some(k);
                cur = ctx_line.as_ref().unwrap_or(&ctx);
            }
            let step = match method {
                OuterMethod::Pantz | OuterMethod::Auto => cur.step(
                    &x, &x, k, margin, delta, d_prev, e_scale, &last_mult, backend,
                )?,
                OuterMethod::Sqp => {
                    let (step, attempt) = cur.sqp(
                        &x, jx, k, d_prev, e_scale, &last_mult, &mut shift, backend, fine_slope,
                    )?;
                    if attempt.timed_out {
                        // stopped between lazy rounds: x is the last accepted iterate
                        result.status = RunStatus::TimeLimit;
                        break;
                    }
                    // A step that a safeguard cut and that moved J by less than the stopping
                    // rule's tolerance is no evidence of a fixed point: take Pantz's step.
                    let tol = (settings.tol_j * e_scale).max(64.0 * f64::EPSILON * jx.abs());
                    match step {
                        Some(st) if keep_sqp_step(&attempt, jx - st.sub.energy, tol) => {
                            result.sqp_steps += 1;
                            st
                        }
                        _ => {
                            let mut st = cur.step(
                                &x, &x, k, margin, delta, d_prev, e_scale, &last_mult, backend,
                            )?;
                            charge_fallback(&mut st, &attempt);
                            result.fallback_steps += 1;
                            st
                        }
                    }
                }
            };
            // A QP that fails at a tolerance the endgame tightened is the backend's limit, not the
            // run's: the tolerance goes back to the run's own, the step is dropped, and the run
            // stops at x (where the stopping rule held), its status by the certificate.
            if result.qp_tol_tightened.is_some() && step.sub.qp_status != QpStatus::Solved {
                if let Some(t) = tolerance0 {
                    backend.set_tolerance(t);
                }
                stopped_by_rule = true;
                break;
            }
            last_sqp = step.record.step == "sqp";
            let sub = step.sub;
            result.outer_iterations = k;
            result.inner_iterations += sub.inner_iterations;
            result.backend_iterations += sub.backend_iterations;
            observer.iteration(&OuterEvent {
                record: &step.record,
                x: &sub.y,
                rows: &sub.rows,
                multipliers: &sub.multipliers,
            });
            if !step.record.admissible {
                result.status = RunStatus::Inadmissible;
                result.min_distance = step.min_distance;
                break;
            }
            if sub.energy > jx {
                result.status = RunStatus::EnergyIncreased;
                break;
            }
            let jprev = jx;
            // A step the trust region's box cut is no evidence of creep: neither it nor the one
            // before it is compared, and it does not count towards AUTO_PANTZ_STEPS.
            if step.box_active {
                decreases = [f64::NAN; 2];
            } else {
                decreases = [decreases[1], jprev - sub.energy];
                free_steps += 1;
            }
            d_prev = displacements(mesh.dim, &x, &sub.y)
                .into_iter()
                .fold(0.0, f64::max)
                .max(1e-3 * hbar);
            psi = std::mem::replace(&mut x, sub.y);
            cert_at_x = None;
            jx = sub.energy;
            e_scale = step.energy_scale;
            result.energy = jx;
            result.min_distance = step.min_distance;
            last_mult = sub
                .rows
                .iter()
                .zip(&sub.multipliers)
                .map(|(r, m)| (r.pair, *m))
                .collect();
            result.last_rows = sub.rows;
            result.multipliers = sub.multipliers;
            if sub.qp_status != QpStatus::Solved {
                result.status = RunStatus::SubproblemFailed;
                break;
            }
            if sub.line_search_failed {
                result.status = RunStatus::LineSearchFailed;
                break;
            }
            if sub.timed_out {
                result.status = RunStatus::TimeLimit;
                break;
            }
            if settings.pruning == Pruning::TrustRegion {
                // Grow δ while the box binds; shrink it when the step stays well inside.
                let t = &settings.trust;
                if step.box_active {
                    delta = (2.0 * delta).min(t.delta_max * hbar);
                } else if d_prev < 0.25 * delta {
                    delta = (0.5 * delta).max(t.delta_min * hbar);
                }
            }
            // With a binding box the step is not argmin over T(ψ): do not stop on it. Below
            // 64u|J| an energy difference is round-off.
            let round = 64.0 * f64::EPSILON * jx.abs();
            let tol = (settings.tol_j * e_scale).max(round);
            if !step.box_active && (jprev - jx).abs() <= tol {
                if auto && method == OuterMethod::Pantz {
                    // Pantz's map stopped: its state is the result if the certificate holds there
                    // (after the polish, as at the end of the run), else the SQP method goes on
                    // from x (the polish's work is counted, its state dropped).
                    let polish = if settings.polish {
                        Some(cur.step(
                            &psi, &x, k, 0.0, delta, d_prev, e_scale, &last_mult, backend,
                        )?)
                    } else {
                        None
                    };
                    let c = match polish.as_ref().filter(|p| polish_accepted(p, jx)) {
                        Some(p) => {
                            certify(&p.sub.y, &pair_multipliers(&p.sub.rows, &p.sub.multipliers))?
                        }
                        None => certify(
                            &x,
                            &pair_multipliers(&result.last_rows, &result.multipliers),
                        )?,
                    };
                    if c.kappa <= settings.tol_kappa {
                        match polish {
                            Some(p) => early_polish = Some((p, c)),
                            None => cert_at_x = Some(c),
                        }
                        stopped_by_rule = true;
                        stalled = sub.line_search_stalled;
                        break;
                    }
                    if let Some(p) = polish {
                        result.inner_iterations += p.sub.inner_iterations;
                        result.backend_iterations += p.sub.backend_iterations;
                    }
                    method = OuterMethod::Sqp;
                    result.sqp_from = Some(k + 1);
                    cur = ctx_line.as_ref().unwrap_or(&ctx);
                    continue;
                }
                // The SQP method does not creep (docs/method.md): where its step still lowers J
                // above round-off with a step the line search did not cut below
                // SQP_ENDGAME_MIN_STEP, or is stationary only to the backend's tolerance, and the
                // certificate does not hold, it goes on, in the second case (and where the line
                // search cut the step that short) with the backend's tolerance divided by 10
                // (down to SQP_TOLERANCE_RANGE times the run's own).
                let progress =
                    (jprev - jx).abs() > round && step.record.step_length >= SQP_ENDGAME_MIN_STEP;
                let tighter = backend.tolerance().and_then(|now| {
                    let t = (0.1 * now).max(tolerance0.unwrap_or(now) * SQP_TOLERANCE_RANGE);
                    (t < now * (1.0 - 1e-9)).then_some(t)
                });
                if last_sqp && (progress || tighter.is_some() || !fine_slope) {
                    let c = certify(
                        &x,
                        &pair_multipliers(&result.last_rows, &result.multipliers),
                    )?;
                    let kappa = c.kappa;
                    cert_at_x = Some(c);
                    if kappa > settings.tol_kappa {
                        if !progress {
                            match tighter {
                                Some(t) => {
                                    backend.set_tolerance(t);
                                    result.qp_tol_tightened = Some(t);
                                }
                                // At the tightest tolerance: the stationarity test drops its floor
                                // of the energy scale, once (docs/method.md, "The SQP outer
                                // method", the endgame).
                                None => fine_slope = true,
                            }
                        }
                        continue;
                    }
                }
                stopped_by_rule = true;
                stalled = sub.line_search_stalled;
                break;
            }
        }
        // The polish (docs/method.md, "The row margin"): where the stopping rule stopped the run,
        // the last sub-problem, min J over T(ψ) of the last ψ, is solved again from the final
        // state with its rows at ε itself, so that the reported state and energy carry no bias
        // from the margin δ. Kept only if admissible, solved, and not above J.
        // After an SQP step, the state before an accepted polish (x, J, distance, rows,
        // multipliers): returned instead where only it is certified.
        let mut unpolished = None;
        if settings.polish && stopped_by_rule {
            let k = result.outer_iterations;
            // After an SQP step the natural neighbourhood is T(x) at the final x: at a KKT point
            // of (3) (rows at ε + δ) x is a KKT point of min J over T(x) too (the weighted sum of
            // a pair's rows is its distance's linearization), so the polish moves by O(δ).
            if last_sqp {
                psi = x.clone();
            }
            let (step, early_cert) = match early_polish.take() {
                Some((st, c)) => (st, Some(c)),
                None => (
                    cur.step(
                        &psi, &x, k, 0.0, delta, d_prev, e_scale, &last_mult, backend,
                    )?,
                    None,
                ),
            };
            let accepted = polish_accepted(&step, jx);
            let sub = step.sub;
            result.inner_iterations += sub.inner_iterations;
            result.backend_iterations += sub.backend_iterations;
            result.polish = Some(Polish {
                energy_change: if accepted { sub.energy - jx } else { 0.0 },
                inner_iterations: sub.inner_iterations,
                accepted,
                rejected_by_certificate: false,
            });
            if accepted {
                if last_sqp {
                    unpolished = Some((
                        x.clone(),
                        jx,
                        result.min_distance,
                        std::mem::take(&mut result.last_rows),
                        std::mem::take(&mut result.multipliers),
                        cert_at_x.take(),
                    ));
                }
                x = sub.y;
                cert_at_x = None;
                result.energy = sub.energy;
                result.min_distance = step.min_distance;
                result.last_rows = sub.rows;
                result.multipliers = sub.multipliers;
            }
            if early_cert.is_some() {
                cert_at_x = early_cert;
            }
        }
        result.psi = psi;
        // The certificate at the returned point, with the last sub-problem's multipliers (summed
        // per pair) as the warm start of its active set (the SQP endgame's, where it computed it
        // at that point).
        result.certificate = match cert_at_x {
            Some(c) => c,
            None => certify(
                &x,
                &pair_multipliers(&result.last_rows, &result.multipliers),
            )?,
        };
        if let Some((x0, j0, md0, rows0, mult0, cert0)) = unpolished {
            // The polish is a step of Pantz's map from the SQP end state; where it leaves a state
            // that the certificate does not pass while the state before it does, the latter is
            // the result (its rows at ε + δ, so J keeps the margin's bias).
            if result.certificate.kappa > settings.tol_kappa {
                let c0 = match cert0 {
                    Some(c) => c,
                    None => certify(&x0, &pair_multipliers(&rows0, &mult0))?,
                };
                if c0.kappa <= settings.tol_kappa {
                    x = x0;
                    result.energy = j0;
                    result.min_distance = md0;
                    result.last_rows = rows0;
                    result.multipliers = mult0;
                    result.certificate = c0;
                    if let Some(p) = result.polish.as_mut() {
                        p.energy_change = 0.0;
                        p.accepted = false;
                        p.rejected_by_certificate = true;
                    }
                }
            }
        }
        if stopped_by_rule {
            result.status = if result.certificate.kappa <= settings.tol_kappa {
                RunStatus::Converged
            } else if stalled {
                RunStatus::LineSearchFailed
            } else {
                RunStatus::FixedPoint
            };
        }
        // The second-order check of a certified state; where it is not a minimum and the run
        // escapes saddles, the run goes on from the lower admissible point the check found, if
        // nothing lies between (the continuous check).
        if result.status == RunStatus::Converged && settings.second_order_max_dofs > 0 {
            let so = second_order(
                mesh,
                energy,
                &x,
                &norms.free.col,
                &result.certificate,
                eps,
                hbar,
                settings.second_order_max_dofs,
            );
            let escape = settings.escape_saddles
                && result.escapes < MAX_ESCAPES
                && result.outer_iterations < settings.max_outer;
            let z = so
                .point
                .clone()
                .filter(|_| escape && so.status == "not_minimum");
            let clear = z.as_ref().is_some_and(|z| {
                let search = AnyMotionSearch::new(mesh, &x);
                let eta = settings.sqp.ccd_thickness * eps;
                first_contact(mesh, &search, &x, z, eta.min(eps - roundoff)).is_none()
            });
            if let (Some(z), true) = (z, clear) {
                let k = result.outer_iterations + 1;
                let jz = energy.value(&z);
                let md = min_distance(mesh, &z, 2.0 * eps, true);
                e_scale = energy_scale(energy, &z, &norms);
                let record =
                    IterationRecord::without_solve(k, jz, &md, roundoff, eps, e_scale, "escape");
                observer.iteration(&OuterEvent {
                    record: &record,
                    x: &z,
                    rows: &[],
                    multipliers: &[],
                });
                result.outer_iterations = k;
                result.escapes += 1;
                result.energy = jz;
                result.min_distance = md;
                result.polish = None;
                result.status = RunStatus::MaxOuterIterations;
                k0 = k;
                psi = z.clone();
                x = z;
                jx = jz;
                cert_at_x = None;
                stopped_by_rule = false;
                stalled = false;
                fine_slope = false;
                last_sqp = false;
                decreases = [f64::NAN; 2];
                if let Some(t) = tolerance0 {
                    backend.set_tolerance(t);
                }
                if auto {
                    // the SQP phase goes on (or begins) from the lower point
                    if method == OuterMethod::Pantz {
                        result.sqp_from = Some(k + 1);
                    }
                    method = OuterMethod::Sqp;
                    cur = ctx_line.as_ref().unwrap_or(&ctx);
                }
                continue 'escape;
            }
            result.second_order = Some(so);
        }
        break 'escape;
    }
    result.x = x;
    (result.certificate_calls, result.certificate_seconds) = cert_time.get();
    result.wall_time_s = start.elapsed().as_secs_f64();
    observer.finish(&result);
    Ok(result)
}
