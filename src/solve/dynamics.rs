//! The dynamic case (Pantz 2008, §6; docs/method.md): every time step is a problem (3), solved by
//! the same outer loop ([`crate::solve::outer::run`]) with the same backends and pruning.
//!
//! # The step problem
//!
//! §6 writes one step as `min_{φ_{i+1} ∈ A_{h,ε}} ½∫ m |v_{i+1} − v_i|² + J(φ_{i+1})` with
//! `v_{i+1} = (φ_{i+1} − φ_i)/Δt`. With lumped P1 masses `m_v` (per vertex, see
//! [`lumped_mass`], from the energy stage) and `x̃ = x_i + Δt v_i`,
//!
//! ```text
//! ½ m_v |v_{i+1} − v_i|² = ½ m_v |(x − x_i)/Δt − v_i|² = ½ m_v |x − x̃|² / Δt²,
//! ```
//!
//! so each step minimizes over `A_{h,ε}`
//!
//! ```text
//! J_step(x) = (c/2) Σ_v m_v |x_v − x̃_v|² + J(x)                                   (★)
//! ```
//!
//! with a scheme-dependent predictor `x̃` and weight `c`. The [`Inertia`] term is the first
//! part of (★); each step minimises [`WithInertia`], the scene's [`TotalEnergy`] wrapped with
//! that step's inertia term (evaluated last, as if it were `J`'s last term).
//! (★) has units of energy, so the QP duals of the step's rows are forces.
//!
//! * **Implicit Euler** (the paper's example): `x̃ = x_n + Δt v_n`, `c = 1/Δt²`; after the
//!   step `v_{n+1} = (x_{n+1} − x_n)/Δt`. Stationarity of (★) reads
//!   `m (v_{n+1} − v_n)/Δt = −J'(x_{n+1}) + F_c` (`F_c` the contact forces `Σ μ ∇row`).
//! * **Newmark average acceleration** (β = 1/4, γ = 1/2, second order, energy-conserving for
//!   linear problems): `x̃ = x_n + Δt v_n + Δt²/4 a_n`, `c = 4/Δt²`. Stationarity of (★) is
//!   `m c (x_{n+1} − x̃) = −J'(x_{n+1}) + F_c =: m a_{n+1}`, so after the step
//!   `a_{n+1} = (4/Δt²)(x_{n+1} − x̃)` and `v_{n+1} = v_n + Δt/2 (a_n + a_{n+1})`; substituting
//!   `x̃` gives Newmark's `x_{n+1} = x_n + Δt v_n + Δt²/4 (a_n + a_{n+1})`. The initial
//!   acceleration is `a_0 = −M⁻¹ J'(x_0)` on the free vertices (0 on fixed vertices and on
//!   free vertices of zero mass; contact forces at t = 0 are not included).
//!
//! Each step starts the outer loop at `x_n`, which is admissible, so by Lemma 4.2 every outer
//! iterate of every step is in `A_{h,ε}` and `J_step` is non-increasing within the step; the
//! outer loop's exact admissibility check runs on every iterate and is recorded per step
//! ([`StepRecord::admissible`]). Fixed vertices never move (`v = a = 0`, `x̃ = x_n`).
//!
//! # Conservation (what the tests measure)
//!
//! * Momentum: `Σ_v J'(x)_v = 0` for a translation-invariant `J` (elastic terms), and each
//!   row `n·(φ(p) − φ(q))` has gradient `+n` at `p`, `−n` at `q`, so the contact forces sum to
//!   zero: with no fixed vertex and no external force `Σ_v m_v v_v` is conserved by both
//!   schemes up to the step's stationarity residual.
//! * Energy: `E = ½ Σ m |v|² + J(x)`. Comparing (★) at `x_{n+1}` with the admissible `x_n`
//!   only gives `½ m|v_{n+1} − v_n|² + J(x_{n+1}) ≤ ½ m|v_n|² + J(x_n)`; implicit Euler
//!   dissipates `½ m|v_{n+1} − v_n|²` per step for a convex J, and the contact rows, active
//!   at `x_{n+1}` and satisfied at `x_n`, only remove energy. For a non-convex J (neo-Hookean)
//!   `E_{n+1} ≤ E_n` is not a theorem: it is measured.

use crate::contact::{ContactPair, PairRows};
use crate::energy::{Energy, Hessian, HessianModel, Objective, TermKind, TotalEnergy};
// Lumped masses belong to the energy stage (inertia is a kind of energy); re-exported for the
// callers of time stepping.
pub use crate::energy::mass::lumped_mass;
use crate::scene::mesh::Mesh;
use crate::solve::observer::{Loop, Observer};
use crate::solve::outer::{run, IterationRecord, OuterSettings, RunError, RunStatus};
use contactlab_solvers::QpBackend;
use std::time::Instant;
use thiserror::Error;

/// Time-stepping scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// Implicit (backward) Euler, the example of §6 (first order, dissipative).
    Euler,
    /// Newmark average acceleration (β = 1/4, γ = 1/2; second order).
    Newmark,
}

impl Scheme {
    /// Name used on the command line, in CSV and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            Scheme::Euler => "euler",
            Scheme::Newmark => "newmark",
        }
    }

    /// Parses [`Scheme::as_str`].
    pub fn from_name(s: &str) -> Option<Scheme> {
        match s {
            "euler" => Some(Scheme::Euler),
            "newmark" => Some(Scheme::Newmark),
            _ => None,
        }
    }

    /// The weight `c` of (★): `1/Δt²` (Euler) or `4/Δt²` (Newmark).
    pub fn inertia_weight(&self, dt: f64) -> f64 {
        match self {
            Scheme::Euler => 1.0 / (dt * dt),
            Scheme::Newmark => 4.0 / (dt * dt),
        }
    }
}

/// Settings of a dynamic run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicSettings {
    /// Time step Δt (> 0).
    pub dt: f64,
    /// Number of steps (≥ 1).
    pub steps: usize,
    /// Scheme.
    pub scheme: Scheme,
}

impl DynamicSettings {
    /// Checks Δt and the number of steps.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return Err(DynamicsError::BadDt(self.dt));
        }
        if self.steps == 0 {
            return Err(DynamicsError::BadSteps(self.steps));
        }
        Ok(())
    }
}

/// Invalid input to a dynamic run, or a step whose outer loop refused to start.
#[derive(Debug, Error)]
pub enum DynamicsError {
    /// Δt ≤ 0 or not finite.
    #[error("dt must be finite and > 0, got {0}")]
    BadDt(f64),
    /// Zero steps.
    #[error("steps must be >= 1, got {0}")]
    BadSteps(usize),
    /// A vector of the wrong length.
    #[error("{what} has {got} entries, expected {expected}")]
    Length {
        /// Which vector.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The expected length.
        expected: usize,
    },
    /// A mass that is negative or not finite.
    #[error("{what} {index} is {value}: must be finite and >= 0")]
    BadMass {
        /// `mass of vertex` (a bad density is [`crate::energy::mass::MassError`]).
        what: &'static str,
        /// Vertex index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A non-finite initial velocity.
    #[error("initial velocity of dof {dof} is {value}")]
    BadVelocity {
        /// Degree of freedom.
        dof: usize,
        /// The value.
        value: f64,
    },
    /// The outer loop of a step returned an error.
    #[error("step {step}: {source}")]
    Step {
        /// Step number (1-based).
        step: usize,
        /// The outer loop's error.
        source: RunError,
    },
}

/// The inertia term of (★): `(c/2) Σ_v m_v |x_v − x̃_v|²`. Gradient `c m_v (x_v − x̃_v)`,
/// Hessian the diagonal `c m_v` (positive semi-definite: the same projected or not).
#[derive(Clone, Debug)]
pub struct Inertia {
    /// Space dimension.
    pub dim: usize,
    /// Lumped mass per vertex.
    pub mass: Vec<f64>,
    /// The weight `c` (`1/Δt²` or `4/Δt²`).
    pub c: f64,
    /// The predictor `x̃` (flat, `dim` per vertex).
    pub x_tilde: Vec<f64>,
}

impl Energy for Inertia {
    fn name(&self) -> &str {
        "inertia"
    }

    fn kind(&self) -> TermKind {
        TermKind::Inertia
    }

    fn value(&self, x: &[f64]) -> f64 {
        let mut s = 0.0;
        for (v, &m) in self.mass.iter().enumerate() {
            let mut d2 = 0.0;
            for k in 0..self.dim {
                let d = x[self.dim * v + k] - self.x_tilde[self.dim * v + k];
                d2 += d * d;
            }
            s += m * d2;
        }
        0.5 * self.c * s
    }

    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        for (v, &m) in self.mass.iter().enumerate() {
            for k in 0..self.dim {
                let i = self.dim * v + k;
                g[i] += self.c * m * (x[i] - self.x_tilde[i]);
            }
        }
    }

    fn add_hessian(&self, _x: &[f64], _projected: bool, h: &mut Hessian) {
        for (v, &m) in self.mass.iter().enumerate() {
            if m != 0.0 {
                for k in 0..self.dim {
                    let i = self.dim * v + k;
                    h.triplets.push((i, i, self.c * m));
                }
            }
        }
    }
}

/// The objective of one time step (★): the scene's `J` plus the [`Inertia`] term, evaluated
/// with the inertia term last (as if it were `J`'s last term).
pub struct WithInertia<'a> {
    /// The scene's `J`.
    pub energy: &'a TotalEnergy,
    /// The step's inertia term.
    pub inertia: Inertia,
}

impl Objective for WithInertia<'_> {
    fn value(&self, x: &[f64]) -> f64 {
        self.energy.value(x) + self.inertia.value(x)
    }
    fn gradient(&self, x: &[f64]) -> Vec<f64> {
        let mut g = self.energy.gradient(x);
        self.inertia.add_gradient(x, &mut g);
        g
    }
    fn hessian(&self, x: &[f64], model: HessianModel) -> Hessian {
        let mut h = self.energy.model_hessian(x, model);
        self.inertia
            .add_hessian(x, model.projects(&self.inertia), &mut h);
        h
    }
    fn model_is_psd(&self, model: HessianModel) -> bool {
        // The inertia term is a positive diagonal.
        self.energy.model_is_psd(model)
    }
    fn term_gradients(&self, x: &[f64]) -> Vec<Vec<f64>> {
        let mut gs = self.energy.term_gradients(x);
        let mut g = vec![0.0; x.len()];
        self.inertia.add_gradient(x, &mut g);
        gs.push(g);
        gs
    }
}

/// The contact force of one pair at the end of a step: the sum of its rows' multipliers (QP
/// duals of the step's last sub-problem), the force along the pair's normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairForce {
    /// The pair.
    pub pair: ContactPair,
    /// `Σ μ` of its rows.
    pub force: f64,
    /// Distance of the pair at the end of the step (the distance along its frozen normal: the
    /// smallest row value; exact for the active rows).
    pub distance: f64,
    /// A row of the pair is within the outer loop's activity margin of ε.
    pub active: bool,
}

/// One time step (step 0 is the initial state).
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepRecord {
    /// Step number n.
    pub step: usize,
    /// Time `n Δt`.
    pub time: f64,
    /// `½ Σ m_v |v_v|²`.
    pub kinetic: f64,
    /// The terms of J of kind [`TermKind::Elastic`] (membranes, neo-Hookean solids, gas,
    /// pressure).
    pub elastic: f64,
    /// The terms of J of kind [`TermKind::Potential`] (gravity).
    pub potential: f64,
    /// kinetic + elastic + potential.
    pub total: f64,
    /// `Σ m_v v_v`, x component.
    pub momentum_x: f64,
    /// y component.
    pub momentum_y: f64,
    /// z component (0 in 2D).
    pub momentum_z: f64,
    /// Exact minimum distance over all disjoint pairs at the end of the step.
    pub min_distance: f64,
    /// Every outer iterate of the step passed the exact admissibility check.
    pub admissible: bool,
    /// Pairs with a row within the activity margin of ε at the end of the step.
    pub active_contacts: usize,
    /// Sum of the active pairs' forces.
    pub contact_force: f64,
    /// Outer iterations of the step.
    pub outer_iterations: usize,
    /// Status of the step's outer loop.
    pub status: &'static str,
    /// The minimality certificate κ at the end of the step (docs/method.md, "The minimality
    /// certificate"; NaN for step 0).
    pub kappa: f64,
    /// Outer iterations of the step that were SQP steps (`--outer-method sqp`).
    pub sqp_steps: usize,
    /// Outer iterations of the step where the SQP step collapsed and Pantz's step was taken.
    pub fallback_steps: usize,
    /// `J_step` at the end of the step (★).
    pub step_energy: f64,
    /// Wall time of the step's outer loop, seconds.
    pub wall_time_s: f64,
}

/// The state between steps.
#[derive(Clone, Debug)]
pub struct DynamicState {
    /// Time.
    pub time: f64,
    /// Positions.
    pub x: Vec<f64>,
    /// Velocities.
    pub v: Vec<f64>,
    /// Accelerations (Newmark; zero for Euler).
    pub a: Vec<f64>,
}

/// Outcome of a dynamic run.
#[derive(Clone, Debug)]
pub struct DynamicResult {
    /// Final state.
    pub state: DynamicState,
    /// Records of steps 0..=n (n the steps taken).
    pub records: Vec<StepRecord>,
    /// Steps taken (fewer than asked when a step ended with a status that stops the run).
    pub steps: usize,
    /// The status that stopped the run early (`inadmissible`, `energy_increased`,
    /// `subproblem_failed`), if one did.
    pub stopped_by: Option<RunStatus>,
    /// Wall time of the whole run.
    pub wall_time_s: f64,
}

/// A mechanical system: the scene's mesh, J and ε, and the lumped masses.
pub struct System<'a> {
    /// The mesh.
    pub mesh: &'a Mesh,
    /// The scene's J (without inertia).
    pub energy: &'a mut TotalEnergy,
    /// ε.
    pub eps: f64,
    /// Lumped mass per vertex.
    pub mass: Vec<f64>,
}

impl System<'_> {
    /// `(kinetic, elastic, potential)` at positions `x`, velocities `v`.
    pub fn energies(&self, x: &[f64], v: &[f64]) -> (f64, f64, f64) {
        let d = self.mesh.dim;
        let kinetic = 0.5
            * self
                .mass
                .iter()
                .enumerate()
                .map(|(i, m)| m * (0..d).map(|k| v[d * i + k].powi(2)).sum::<f64>())
                .sum::<f64>();
        let (mut elastic, mut potential) = (0.0, 0.0);
        for t in &self.energy.terms {
            match t.kind() {
                TermKind::Potential => potential += t.value(x),
                // (the step's inertia term is not among the terms when this is called)
                TermKind::Elastic | TermKind::Inertia => elastic += t.value(x),
            }
        }
        (kinetic, elastic, potential)
    }

    /// `Σ_v m_v v_v` (three components; z = 0 in 2D).
    pub fn momentum(&self, v: &[f64]) -> [f64; 3] {
        let d = self.mesh.dim;
        let mut p = [0.0; 3];
        for (i, m) in self.mass.iter().enumerate() {
            for (k, pk) in p.iter_mut().enumerate().take(d) {
                *pk += m * v[d * i + k];
            }
        }
        p
    }

    /// Total mass of the vertices that are not fixed.
    pub fn free_mass(&self) -> f64 {
        self.mass
            .iter()
            .zip(&self.mesh.fixed)
            .filter(|(_, &f)| !f)
            .map(|(m, _)| m)
            .sum()
    }
}

/// The contact forces of a step's last sub-problem at `x` (see [`PairForce`]); `margin` is
/// the outer loop's activity margin (`margin_rel·ε + margin_abs`, active when a row value
/// minus ε is at most twice that, as in [`IterationRecord::active_rows`]).
pub fn pair_forces(
    rows: &[PairRows],
    multipliers: &[[f64; 4]],
    x: &[f64],
    eps: f64,
    margin: f64,
) -> Vec<PairForce> {
    rows.iter()
        .zip(multipliers)
        .map(|(r, mu)| {
            let vals = r.values(x);
            let distance = vals
                .iter()
                .take(r.len)
                .fold(f64::INFINITY, |m, &v| m.min(v));
            PairForce {
                pair: r.pair,
                force: mu.iter().take(r.len).sum(),
                distance,
                active: distance - eps <= 2.0 * margin,
            }
        })
        .collect()
}

/// Time stepping as a [`Loop`]: an event is a step's record, pair forces and state, the
/// outcome the [`DynamicResult`].
pub struct DynamicLoop;

/// One event of time stepping.
pub struct StepEvent<'a> {
    /// The step's record.
    pub record: &'a StepRecord,
    /// The forces of every pair of the step's last sub-problem (empty at step 0).
    pub forces: &'a [PairForce],
    /// The state after the step.
    pub state: &'a DynamicState,
}

impl Loop for DynamicLoop {
    type Event<'a> = StepEvent<'a>;
    type Outcome = DynamicResult;
    fn index(event: &StepEvent<'_>) -> usize {
        event.record.step
    }
}

/// The records, collected.
impl Observer<DynamicLoop> for Vec<StepRecord> {
    fn iteration(&mut self, event: &StepEvent<'_>) {
        self.push(event.record.clone());
    }
}

/// A closure `(record, forces, state)` as an observer of time stepping.
struct FnSteps<'f>(&'f mut dyn FnMut(&StepRecord, &[PairForce], &DynamicState));

impl Observer<DynamicLoop> for FnSteps<'_> {
    fn iteration(&mut self, event: &StepEvent<'_>) {
        (self.0)(event.record, event.forces, event.state)
    }
}

/// Runs `settings.steps` time steps from `x0` with initial velocity `v0`, calling `observer`
/// after each step (and once for step 0) with the record, the forces of every pair of the
/// step's last sub-problem (empty at step 0) and the state ([`simulate_observed`]).
pub fn simulate(
    system: &mut System,
    x0: &[f64],
    v0: &[f64],
    backend: &mut dyn QpBackend,
    outer: &OuterSettings,
    settings: &DynamicSettings,
    observer: &mut dyn FnMut(&StepRecord, &[PairForce], &DynamicState),
) -> Result<DynamicResult, DynamicsError> {
    simulate_observed(
        system,
        x0,
        v0,
        backend,
        outer,
        settings,
        &mut FnSteps(observer),
    )
}

/// Runs `settings.steps` time steps from `x0` with initial velocity `v0`, reporting each step
/// (and step 0) to `observer` ([`Observer::init`] before step 0, [`Observer::finish`] with the
/// result). A step whose outer loop ends `converged`, `max_outer_iterations` or
/// `line_search_failed` is accepted (its status is recorded); `inadmissible`,
/// `energy_increased` or `subproblem_failed` stop the run. Each step minimises
/// [`WithInertia`]: `system.energy` is left as it is.
pub fn simulate_observed(
    system: &mut System,
    x0: &[f64],
    v0: &[f64],
    backend: &mut dyn QpBackend,
    outer: &OuterSettings,
    settings: &DynamicSettings,
    observer: &mut dyn Observer<DynamicLoop>,
) -> Result<DynamicResult, DynamicsError> {
    settings.validate()?;
    let mesh = system.mesh;
    let n = mesh.x_ref.len();
    let d = mesh.dim;
    for (what, got) in [("x0", x0.len()), ("v0", v0.len())] {
        if got != n {
            return Err(DynamicsError::Length {
                what,
                got,
                expected: n,
            });
        }
    }
    if system.mass.len() != mesh.nv() {
        return Err(DynamicsError::Length {
            what: "mass (one per vertex)",
            got: system.mass.len(),
            expected: mesh.nv(),
        });
    }
    for (index, &value) in system.mass.iter().enumerate() {
        if !(value >= 0.0 && value.is_finite()) {
            return Err(DynamicsError::BadMass {
                what: "mass of vertex",
                index,
                value,
            });
        }
    }
    if let Some((dof, &value)) = v0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::BadVelocity { dof, value });
    }
    let start = Instant::now();
    let free = |i: usize| !mesh.dof_fixed(i);
    let mut v: Vec<f64> = (0..n).map(|i| if free(i) { v0[i] } else { 0.0 }).collect();
    let mut a = vec![0.0; n];
    if settings.scheme == Scheme::Newmark {
        let g = system.energy.gradient(x0);
        for i in 0..n {
            let m = system.mass[i / d];
            if free(i) && m > 0.0 {
                a[i] = -g[i] / m;
            }
        }
    }
    let mut state = DynamicState {
        time: 0.0,
        x: x0.to_vec(),
        v: v.clone(),
        a: a.clone(),
    };
    let record = |system: &System, step: usize, state: &DynamicState| {
        let (kinetic, elastic, potential) = system.energies(&state.x, &state.v);
        let p = system.momentum(&state.v);
        StepRecord {
            step,
            time: state.time,
            kinetic,
            elastic,
            potential,
            total: kinetic + elastic + potential,
            momentum_x: p[0],
            momentum_y: p[1],
            momentum_z: p[2],
            min_distance: f64::NAN,
            admissible: true,
            active_contacts: 0,
            contact_force: 0.0,
            outer_iterations: 0,
            status: "initial",
            kappa: f64::NAN,
            sqp_steps: 0,
            fallback_steps: 0,
            step_energy: f64::NAN,
            wall_time_s: 0.0,
        }
    };
    let mut records = Vec::with_capacity(settings.steps + 1);
    let mut r0 = record(system, 0, &state);
    r0.min_distance = crate::contact::min_distance(mesh, x0, 2.0 * system.eps, false).distance;
    observer.init();
    observer.iteration(&StepEvent {
        record: &r0,
        forces: &[],
        state: &state,
    });
    records.push(r0);
    let dt = settings.dt;
    let c = settings.scheme.inertia_weight(dt);
    let margin = outer.inner.margin_rel * system.eps + outer.inner.margin_abs;
    let mut stopped_by = None;
    let mut steps = 0;
    let out = (|| -> Result<(), DynamicsError> {
        for step in 1..=settings.steps {
            let x_n = state.x.clone();
            let x_tilde: Vec<f64> = (0..n)
                .map(|i| {
                    if !free(i) {
                        x_n[i]
                    } else {
                        match settings.scheme {
                            Scheme::Euler => x_n[i] + dt * v[i],
                            Scheme::Newmark => x_n[i] + dt * v[i] + 0.25 * dt * dt * a[i],
                        }
                    }
                })
                .collect();
            let objective = WithInertia {
                energy: system.energy,
                inertia: Inertia {
                    dim: d,
                    mass: system.mass.clone(),
                    c,
                    x_tilde: x_tilde.clone(),
                },
            };
            let mut admissible = true;
            let res = run(
                mesh,
                &objective,
                system.eps,
                &x_n,
                backend,
                outer,
                &mut |r: &IterationRecord, _| admissible &= r.admissible,
            )
            .map_err(|source| DynamicsError::Step { step, source })?;
            let x = res.x;
            for i in 0..n {
                if !free(i) {
                    continue;
                }
                match settings.scheme {
                    Scheme::Euler => v[i] = (x[i] - x_n[i]) / dt,
                    Scheme::Newmark => {
                        let a_new = c * (x[i] - x_tilde[i]);
                        v[i] += 0.5 * dt * (a[i] + a_new);
                        a[i] = a_new;
                    }
                }
            }
            state = DynamicState {
                time: step as f64 * dt,
                x,
                v: v.clone(),
                a: a.clone(),
            };
            let forces = pair_forces(
                &res.last_rows,
                &res.multipliers,
                &state.x,
                system.eps,
                margin,
            );
            let mut rec = record(system, step, &state);
            rec.step_energy = res.energy;
            rec.min_distance = res.min_distance.distance;
            rec.admissible = admissible;
            rec.active_contacts = forces.iter().filter(|f| f.active).count();
            rec.contact_force = forces
                .iter()
                .filter(|f| f.active)
                .fold(0.0, |s, f| s + f.force);
            rec.outer_iterations = res.outer_iterations;
            rec.status = res.status.as_str();
            rec.kappa = res.certificate.kappa;
            rec.sqp_steps = res.sqp_steps;
            rec.fallback_steps = res.fallback_steps;
            rec.wall_time_s = res.wall_time_s;
            observer.iteration(&StepEvent {
                record: &rec,
                forces: &forces,
                state: &state,
            });
            records.push(rec);
            steps = step;
            if matches!(
                res.status,
                RunStatus::Inadmissible | RunStatus::EnergyIncreased | RunStatus::SubproblemFailed
            ) {
                stopped_by = Some(res.status);
                break;
            }
        }
        Ok(())
    })();
    out?;
    let result = DynamicResult {
        state,
        records,
        steps,
        stopped_by,
        wall_time_s: start.elapsed().as_secs_f64(),
    };
    observer.finish(&result);
    Ok(result)
}

/// The "no chatter" measurement over a rest window: the total contact force `F_k` of the
/// steps in the window, its mean, its largest step-to-step change and its standard deviation
/// (both relative to the mean).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RestForce {
    /// First step of the window.
    pub first_step: usize,
    /// Steps in the window.
    pub steps: usize,
    /// Mean of `F_k`.
    pub mean: f64,
    /// `max_k |F_k − F_{k−1}| / mean` over consecutive steps of the window.
    pub max_jump_rel: f64,
    /// Standard deviation of `F_k` / mean.
    pub std_rel: f64,
    /// Largest kinetic energy in the window.
    pub max_kinetic: f64,
    /// Smallest number of active contacts in the window.
    pub min_active: usize,
    /// Largest number of active contacts in the window.
    pub max_active: usize,
}

/// [`RestForce`] over the last `fraction` (in (0, 1]) of the steps `1..` of `records`
/// (at least 2 steps); `None` when there are fewer than 2 steps.
pub fn rest_force(records: &[StepRecord], fraction: f64) -> Option<RestForce> {
    let steps = records.iter().filter(|r| r.step > 0).count();
    let w = ((steps as f64 * fraction).ceil() as usize).clamp(2, steps.max(2));
    if steps < 2 {
        return None;
    }
    let win = &records[records.len() - w..];
    let f: Vec<f64> = win.iter().map(|r| r.contact_force).collect();
    let mean = f.iter().sum::<f64>() / w as f64;
    let var = f.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / w as f64;
    let jump = f
        .windows(2)
        .map(|p| (p[1] - p[0]).abs())
        .fold(0.0, f64::max);
    Some(RestForce {
        first_step: win[0].step,
        steps: w,
        mean,
        max_jump_rel: jump / mean.abs().max(f64::MIN_POSITIVE),
        std_rel: var.sqrt() / mean.abs().max(f64::MIN_POSITIVE),
        max_kinetic: win.iter().map(|r| r.kinetic).fold(0.0, f64::max),
        min_active: win.iter().map(|r| r.active_contacts).min().unwrap_or(0),
        max_active: win.iter().map(|r| r.active_contacts).max().unwrap_or(0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn inertia_value_gradient_hessian_match_finite_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(61);
        for dim in [2, 3] {
            let nv = 5;
            let inertia = Inertia {
                dim,
                mass: (0..nv).map(|_| rng.gen_range(0.1..2.0)).collect(),
                c: 1.0 / 0.01f64.powi(2),
                x_tilde: (0..dim * nv).map(|_| rng.gen_range(-1.0..1.0)).collect(),
            };
            let x: Vec<f64> = (0..dim * nv).map(|_| rng.gen_range(-1.0..1.0)).collect();
            // value: the defining sum, written out
            let mut s = 0.0;
            for v in 0..nv {
                for k in 0..dim {
                    s += inertia.mass[v] * (x[dim * v + k] - inertia.x_tilde[dim * v + k]).powi(2);
                }
            }
            assert!((inertia.value(&x) - 0.5 * inertia.c * s).abs() <= 1e-12 * inertia.value(&x));
            let mut g = vec![0.0; x.len()];
            inertia.add_gradient(&x, &mut g);
            assert!(rel(&fd_gradient(&inertia, &x, 1e-6), &g) < 1e-8);
            for projected in [false, true] {
                let mut h = Hessian::default();
                inertia.add_hessian(&x, projected, &mut h);
                let hd = h.to_dense(x.len());
                let fd = fd_hessian(&inertia, &x, 1e-6);
                assert!((&hd - &fd).norm() <= 1e-6 * fd.norm(), "dim {dim}");
                // diagonal
                for i in 0..x.len() {
                    for j in 0..x.len() {
                        if i != j {
                            assert_eq!(hd[(i, j)], 0.0);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn bad_dynamic_settings_are_named() {
        let s = |dt, steps| DynamicSettings {
            dt,
            steps,
            scheme: Scheme::Euler,
        };
        assert!(s(0.01, 1).validate().is_ok());
        assert_eq!(
            s(0.0, 1).validate().unwrap_err().to_string(),
            "dt must be finite and > 0, got 0"
        );
        assert!(s(f64::NAN, 1).validate().is_err());
        assert_eq!(
            s(0.1, 0).validate().unwrap_err().to_string(),
            "steps must be >= 1, got 0"
        );
        assert_eq!(Scheme::from_name("newmark"), Some(Scheme::Newmark));
        assert_eq!(Scheme::from_name("rk4"), None);
    }
}
