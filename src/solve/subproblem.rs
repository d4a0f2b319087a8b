//! One outer step: minimize J over the fixed polyhedron T(ψ) (docs/method.md, sub-problems).
//!
//! At an inner iterate `y ∈ T(ψ)` the quadratic model `q(d) = g·d + ½dᵀ(H + ρI)d` is built
//! from the projected (PSD) Hessian `H`; rank-one Hessian terms `c w wᵀ` (the gas term's
//! `C/V² ∇V∇Vᵀ`) enter through one auxiliary variable `s = w·d` and one equality row, so `P`
//! stays sparse. The QP
//!
//! ```text
//!     min q(d)   s.t.   n·(d(p) − d(q)) ≥ ε + δ − n·(y(p) − y(q))   for every row of T(ψ)
//! ```
//!
//! over the free degrees of freedom goes to the backend; then a backtracking (Armijo) line
//! search on J along `d`. Any point of `[y, y + d]` is in T(ψ) by convexity.
//!
//! With a trust region (docs/method.md, pruning) the QP also carries the box
//! `|y(v) + d(v) − ψ(v)|∞ ≤ δ` on every free dof, as rows after the rank-one rows.
//!
//! Two safeguards, both kept out of the reported energy:
//! - the proximal term `ρ = max(rho_abs, rho_rel · max diag H)` makes `P` positive definite (a
//!   slack membrane with |F| < 1 has no stiffness);
//! - the QP rows use `ε + δ`, `δ = margin_rel·ε + margin_abs`, so that a backend's feasibility
//!   tolerance cannot push an iterate below ε. Every accepted point is checked against the
//!   exact rows `≥ ε` of T(ψ).

use crate::contact::{ContactPair, PairRows};
use crate::energy::{HessianModel, Objective};
use crate::scene::mesh::Mesh;
use crate::solve::qp_units::solve_in_units;
use contactlab_solvers::linalg::CholeskyTest;
use contactlab_solvers::{CscMatrix, Qp, QpBackend, QpError, QpStatus, WarmStart};
use std::collections::HashMap;
use std::time::Instant;

/// Lazy rows: after an accepted inner step, a pair the oracle added in this sub-problem is
/// kept while its slack at the new point (row value minus ε) is at most this fraction of ε,
/// and dropped otherwise (docs/method.md, "Lazy rows"). Balloons n = 1600 with `ip`, when
/// the slack allowed was `4·(largest move) + ε`: the QPs of the long steps carried 55 000–
/// 59 000 rows, of which about 7 600 hold a dual.
pub const LAZY_KEEP_SLACK: f64 = 0.1;

/// Settings of the inner (sub-problem) loop.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InnerSettings {
    /// Maximum Newton-type steps per T(ψ).
    pub max_inner: usize,
    /// Stop the inner loop when `J(y) − J(y_new) ≤ tol_inner · E`, `E` the
    /// [`InnerSettings::energy_scale`] (or `max(1, |J|)` without one), and not below the
    /// round-off of J, `64 u |J|`.
    pub tol_inner: f64,
    /// Absolute floor of the proximal weight ρ.
    pub rho_abs: f64,
    /// ρ relative to the largest diagonal entry of H.
    pub rho_rel: f64,
    /// Row margin δ relative to ε.
    pub margin_rel: f64,
    /// Absolute row margin.
    pub margin_abs: f64,
    /// Maximum number of step halvings in the line search.
    pub max_halvings: usize,
    /// Warm-start each QP's duals: from the previous inner QP, through lazy re-solves (new rows
    /// start at 0), and across outer steps by pair identity. Used by OSQP and Uzawa; Clarabel
    /// ignores it. The primal guess is always `d = 0`.
    pub warm_start: bool,
    /// The Hessian of the quadratic model ([`HessianModel`]; [`ModelShift`] for `shifted`).
    pub hessian_model: HessianModel,
    /// The energy scale `E` of the run, set by the outer loop for each step (its stopping
    /// rule's scale, docs/method.md): the inner stopping test and the round-off test of a
    /// failed line search are relative to it, so that they do not depend on the units.
    /// `None`: `max(1, |J|)`.
    #[serde(skip)]
    pub energy_scale: Option<f64>,
    /// The length scale of the run (the reference diameter), set by the outer loop when its
    /// `qp_in_run_units` is on. With both scales the QPs go to the backend in those units
    /// ([`crate::solve::qp_units`]), so that the backend's absolute tolerances do not depend on
    /// the scene's units. `None`: the QPs as built.
    #[serde(skip)]
    pub length_scale: Option<f64>,
}

impl Default for InnerSettings {
    fn default() -> Self {
        InnerSettings {
            max_inner: 50,
            tol_inner: 1e-12,
            rho_abs: 1e-8,
            rho_rel: 1e-8,
            margin_rel: 1e-6,
            margin_abs: 1e-11,
            max_halvings: 40,
            warm_start: true,
            hessian_model: HessianModel::default(),
            energy_scale: None,
            length_scale: None,
        }
    }
}

/// The adaptive shift of the Newton model [`HessianModel::Shifted`].
///
/// The model's Hessian `H` (element terms projected, the gas and pressure terms exact) can be
/// indefinite; a backend needs `P ⪰ 0`. The shift is the smallest `σ` of the grid
/// `{0} ∪ {σ₀·4ᵏ}` (`σ₀ = 1e-8 · max diag H`) for which `H + ρI + σI` has a Cholesky
/// factorization, searched from a quarter of the previous step's `σ` (so it falls back to
/// 0 where `H` is positive definite near the solution, and the steps become Newton steps).
/// Because `σ ≥ |λ_min(H)|` is set by the most negative mode only, which for a gas is a global
/// mode with curvature `O(C/(V·N))`, the shift does not add the `~C/V` stiffness per vertex of
/// an element-wise projection. The rank-one terms `c wwᵀ` are then weakened to
/// `max(1e-6·c, c − σ/‖w‖²)`, so that along `w` (the direction of the negative mode of a gas
/// term's `−C/V ∇²V`) the model is exact again where the floor does not bind: the
/// model is then `∇²J + σ(I − Σ ŵŵᵀ)` when the `w` have disjoint supports.
///
/// The grid leaves `σ` up to 4 times the smallest shift that makes the model definite, and
/// `σI` stiffens every direction, the soft ones too. [`HessianModel::ShiftedTight`] bisects
/// `σ` in log space between the grid point that failed and the one that passed
/// ([`HessianModel::shift_bisections`] more factorizations), to within a factor `4^(1/64)`.
#[derive(Debug, Default)]
pub struct ModelShift {
    /// The last shift chosen.
    pub sigma: f64,
    /// Largest shift chosen so far.
    pub max_sigma: f64,
    /// Cholesky factorizations tried.
    pub factorizations: usize,
    chol: Option<CholeskyTest>,
}

impl ModelShift {
    /// Chooses the shift for `p` (upper CSC; its leading `nf × nf` block is `H + ρI`, every
    /// diagonal entry present, and no entry couples it to the columns after it) and adds it to
    /// that block's diagonal in place.
    fn apply(
        &mut self,
        p: &mut CscMatrix,
        nf: usize,
        maxdiag: f64,
        bisections: usize,
    ) -> Result<f64, QpError> {
        let end = p.colptr[nf];
        let mut m = CscMatrix {
            nrows: nf,
            ncols: nf,
            colptr: p.colptr[..=nf].to_vec(),
            rowval: p.rowval[..end].to_vec(),
            nzval: p.nzval[..end].to_vec(),
        };
        let diag: Vec<usize> = (0..nf)
            .map(|j| {
                (m.colptr[j]..m.colptr[j + 1])
                    .find(|&k| m.rowval[k] == j)
                    .expect("the proximal term puts every diagonal entry in the pattern")
            })
            .collect();
        let base: Vec<f64> = diag.iter().map(|&k| m.nzval[k]).collect();
        if !self.chol.as_ref().is_some_and(|c| c.matches(&m)) {
            self.chol = CholeskyTest::new(&m);
        }
        let Some(chol) = self.chol.as_mut() else {
            return Err(QpError::NotFinite {
                what: "Newton model (pattern)",
                index: 0,
                value: f64::NAN,
            });
        };
        let floor = 1e-8 * maxdiag.max(f64::MIN_POSITIVE);
        let mut sigma = self.sigma / 4.0;
        if sigma < floor {
            sigma = 0.0;
        }
        // the last shift that failed (None: none failed yet)
        let mut failed: Option<f64> = None;
        for _ in 0..80 {
            for (k, &p) in diag.iter().enumerate() {
                m.nzval[p] = base[k] + sigma;
            }
            self.factorizations += 1;
            if chol.is_positive_definite(&m) {
                if sigma > 0.0 && bisections > 0 {
                    // between the last failure (or σ/4 where the search started at σ) and σ
                    let (mut lo, mut hi) = (failed.unwrap_or(sigma / 4.0), sigma);
                    if lo > 0.0 {
                        for _ in 0..bisections {
                            let mid = (lo * hi).sqrt();
                            for (k, &p) in diag.iter().enumerate() {
                                m.nzval[p] = base[k] + mid;
                            }
                            self.factorizations += 1;
                            if chol.is_positive_definite(&m) {
                                hi = mid;
                            } else {
                                lo = mid;
                            }
                        }
                    }
                    sigma = hi;
                    for (k, &p) in diag.iter().enumerate() {
                        m.nzval[p] = base[k] + sigma;
                    }
                }
                self.sigma = sigma;
                self.max_sigma = self.max_sigma.max(sigma);
                if sigma > 0.0 {
                    for &k in &diag {
                        p.nzval[k] = m.nzval[k];
                    }
                }
                return Ok(sigma);
            }
            failed = Some(sigma);
            sigma = if sigma == 0.0 { floor } else { 4.0 * sigma };
        }
        Err(QpError::NotFinite {
            what: "Newton model shift",
            index: 0,
            value: sigma,
        })
    }
}

/// Outcome of one sub-problem.
#[derive(Clone, Debug)]
pub struct SubproblemResult {
    /// Final inner iterate (∈ T(ψ)).
    pub y: Vec<f64>,
    /// J(y).
    pub energy: f64,
    /// Inner (Newton-type) steps taken.
    pub inner_iterations: usize,
    /// Backend iterations summed over the inner steps.
    pub backend_iterations: usize,
    /// Status of the last QP solve.
    pub qp_status: QpStatus,
    /// The line search could not decrease J along the last direction, whose slope was above
    /// round-off.
    pub line_search_failed: bool,
    /// The line search could not decrease J along a direction whose slope was at round-off
    /// (`|slope| ≤ max(1e-12·E, 64u|J|)`): the sub-problem stopped there, which is not a proof that it
    /// is solved (the outer loop classifies such a stop with the certificate).
    pub line_search_stalled: bool,
    /// The rows the last QP carried (the given ones, then those a [`RowOracle`] added).
    pub rows: Vec<PairRows>,
    /// Contact multipliers of the last QP, one per row of each pair (`μ = −y_QP ≥ 0`; entries
    /// past the pair's `len` are 0).
    pub multipliers: Vec<[f64; 4]>,
    /// QP re-solves because the oracle added rows (lazy rows).
    pub lazy_rounds: usize,
    /// Seconds spent in the oracle (pair search for lazy rows).
    pub t_pairs_s: f64,
    /// Seconds spent assembling (gradient, Hessian, QP matrices).
    pub t_assembly_s: f64,
    /// Seconds spent in the backend.
    pub t_solve_s: f64,
    /// The deadline passed before the inner loop finished: `y` is the last accepted inner
    /// iterate (in T(ψ), with J no larger than at the start).
    pub timed_out: bool,
}

/// Maps vertex dofs to QP columns (free dofs only).
pub struct DofMap {
    /// `col[dof]` = QP column or `usize::MAX` for a fixed dof.
    pub col: Vec<usize>,
    /// Number of free dofs.
    pub nfree: usize,
}

impl DofMap {
    /// Free dofs of `mesh` ([`Mesh::dof_fixed`]: fixed vertices and supported components are
    /// not free), in dof order.
    pub fn new(mesh: &Mesh) -> Self {
        let mut col = vec![usize::MAX; mesh.x_ref.len()];
        let mut k = 0;
        for (dof, c) in col.iter_mut().enumerate() {
            if !mesh.dof_fixed(dof) {
                *c = k;
                k += 1;
            }
        }
        DofMap { col, nfree: k }
    }
}

/// A trust-region box `|φ(v) − ψ(v)|∞ ≤ delta` around `psi`.
#[derive(Clone, Copy, Debug)]
pub struct TrustBox<'a> {
    /// The centre ψ (the outer iterate).
    pub psi: &'a [f64],
    /// Half-width δ > 0.
    pub delta: f64,
}

/// Smallest row value minus ε over all rows at `phi` (≥ 0 iff φ ∈ T(ψ)).
pub fn min_slack(rows: &[PairRows], phi: &[f64], eps: f64) -> f64 {
    rows.iter()
        .map(|r| r.min_value(phi) - eps)
        .fold(f64::INFINITY, f64::min)
}

/// The QP row index of the first row of each pair (`offsets[r]`), and the total.
pub fn row_offsets(rows: &[PairRows]) -> (Vec<usize>, usize) {
    let mut off = Vec::with_capacity(rows.len());
    let mut k = 0;
    for r in rows {
        off.push(k);
        k += r.len;
    }
    (off, k)
}

/// Builds the QP of one inner step at `y`. Returns the QP (rows: first those of each contact pair,
/// then one equality row per rank-one term, then one box row per free dof when `trust` is
/// given) and the gradient `∇J(y)` it used.
#[allow(clippy::too_many_arguments)]
pub fn build_qp(
    mesh: &Mesh,
    energy: &dyn Objective,
    dofs: &DofMap,
    rows: &[PairRows],
    y: &[f64],
    eps_qp: f64,
    trust: Option<TrustBox>,
    settings: &InnerSettings,
    shift: &mut ModelShift,
) -> Result<(Qp, Vec<f64>), QpError> {
    build_qp_with(
        mesh,
        energy,
        dofs,
        rows,
        y,
        eps_qp,
        trust,
        settings,
        shift,
        &[],
        false,
        &[],
    )
}

/// [`build_qp`] with `extra`, symmetric triplets on dofs (both triangles) added to the model
/// Hessian before the shift (the SQP model's constraint curvature), and `indefinite`: `extra`
/// may make the model indefinite, so the shift is applied even where J's model is PSD.
#[allow(clippy::too_many_arguments)]
pub fn build_qp_with(
    mesh: &Mesh,
    energy: &dyn Objective,
    dofs: &DofMap,
    rows: &[PairRows],
    y: &[f64],
    eps_qp: f64,
    trust: Option<TrustBox>,
    settings: &InnerSettings,
    shift: &mut ModelShift,
    extra: &[(usize, usize, f64)],
    indefinite: bool,
    normal: &[(usize, usize, f64)],
) -> Result<(Qp, Vec<f64>), QpError> {
    let g = energy.gradient(y);
    let mut h = energy.hessian(y, settings.hessian_model);
    h.triplets.extend_from_slice(extra);
    let nf = dofs.nfree;
    let naux = h.rank_one.len();
    let n = nf + naux;
    let mut ptrip: Vec<(usize, usize, f64)> = Vec::with_capacity(h.triplets.len() / 2 + n);
    let mut maxdiag: f64 = 0.0;
    for &(i, j, v) in &h.triplets {
        let (ci, cj) = (dofs.col[i], dofs.col[j]);
        if ci == usize::MAX || cj == usize::MAX || ci > cj {
            continue;
        }
        if ci == cj {
            maxdiag = maxdiag.max(v);
        }
        ptrip.push((ci, cj, v));
    }
    for &(i, j, v) in normal {
        let (ci, cj) = (dofs.col[i], dofs.col[j]);
        if ci == usize::MAX || cj == usize::MAX || ci > cj {
            continue;
        }
        ptrip.push((ci, cj, v * maxdiag));
    }
    let rho = settings.rho_abs.max(settings.rho_rel * maxdiag);
    for c in 0..nf {
        ptrip.push((c, c, rho));
    }
    for (k, r) in h.rank_one.iter().enumerate() {
        ptrip.push((nf + k, nf + k, r.coef));
    }
    let mut p = CscMatrix::from_triplets(n, n, &ptrip)?;
    if indefinite || !energy.model_is_psd(settings.hessian_model) {
        let sigma = shift.apply(
            &mut p,
            nf,
            maxdiag,
            settings.hessian_model.shift_bisections(),
        )?;
        if sigma > 0.0 {
            for (k, r) in h.rank_one.iter().enumerate() {
                let ww: f64 =
                    r.w.iter()
                        .filter(|(dof, _)| dofs.col[*dof] != usize::MAX)
                        .map(|(_, w)| w * w)
                        .sum();
                if ww > 0.0 {
                    // The auxiliary column holds its diagonal entry only. Kept positive so
                    // that P stays definite (Uzawa factorizes it).
                    p.nzval[p.colptr[nf + k]] = (r.coef - sigma / ww).max(1e-6 * r.coef);
                }
            }
        }
    }
    let mut q = vec![0.0; n];
    for (dof, &c) in dofs.col.iter().enumerate() {
        if c != usize::MAX {
            q[c] = g[dof];
        }
    }
    let nbox = if trust.is_some() { nf } else { 0 };
    let (offsets, ncontact) = row_offsets(rows);
    let m = ncontact + naux + nbox;
    let dim = mesh.dim;
    let mut atrip: Vec<(usize, usize, f64)> = Vec::with_capacity(2 * dim * ncontact + nbox);
    let mut l = vec![0.0; m];
    let mut u = vec![f64::INFINITY; m];
    for v in u.iter_mut().skip(ncontact).take(naux) {
        *v = 0.0;
    }
    #[allow(clippy::needless_range_loop)] // i indexes the values and the row's vertices
    for (row, &off) in rows.iter().zip(&offsets) {
        let vals = row.values(y);
        for i in 0..row.len {
            let ri = off + i;
            l[ri] = eps_qp - vals[i];
            for c in 0..dim {
                let cm = dofs.col[dim * row.minus[i] + c];
                if cm != usize::MAX {
                    atrip.push((ri, cm, -row.n[c]));
                }
                let cp = dofs.col[dim * row.plus[i] + c];
                if cp != usize::MAX {
                    atrip.push((ri, cp, row.n[c]));
                }
            }
        }
    }
    for (k, r) in h.rank_one.iter().enumerate() {
        let ri = ncontact + k;
        atrip.push((ri, nf + k, 1.0));
        for &(dof, w) in &r.w {
            let c = dofs.col[dof];
            if c != usize::MAX {
                atrip.push((ri, c, -w));
            }
        }
    }
    if let Some(tb) = trust {
        let base = ncontact + naux;
        for (dof, &c) in dofs.col.iter().enumerate() {
            if c != usize::MAX {
                let off = tb.psi[dof] - y[dof];
                atrip.push((base + c, c, 1.0));
                l[base + c] = off - tb.delta;
                u[base + c] = off + tb.delta;
            }
        }
    }
    let a = CscMatrix::from_triplets(m, n, &atrip)?;
    Ok((Qp { p, q, a, l, u }, g))
}

/// The outcome of one inner step's line search.
enum Step {
    /// The QP step is zero up to round-off (non-negative slope).
    Optimal,
    /// The accepted point and its energy.
    Accepted(Vec<f64>, f64),
    /// No step length decreased J enough; the slope of the direction.
    Failed(f64),
}

/// Lazy rows: given a trial point and the rows carried so far, returns the rows of T(ψ) that
/// the trial point violates (value below the QP level `ε + δ`) and that are not carried yet.
pub type RowOracle<'a> = &'a mut dyn FnMut(&[f64], &[PairRows]) -> Vec<PairRows>;

/// Minimizes J over the rows `rows` of T(ψ) (and the box `trust`, if given) starting from
/// `start`, which must satisfy every row of T(ψ) (`≥ ε`) and the box.
///
/// With an `oracle` (lazy rows), every QP solution `y + d` is checked against the whole of T(ψ)
/// and the QP is solved again with violated rows added until none is: each inner QP then has
/// the solution of the all-pairs QP (it is strictly convex), so the inner path, and the outer
/// iterates, are those of the all-pairs mode. Pairs the oracle added that are far from binding
/// after an accepted step are dropped again (the next QP's check brings back any it needs).
#[allow(clippy::too_many_arguments)]
pub fn solve_subproblem(
    mesh: &Mesh,
    energy: &dyn Objective,
    dofs: &DofMap,
    rows: Vec<PairRows>,
    start: &[f64],
    eps: f64,
    trust: Option<TrustBox>,
    mut oracle: Option<RowOracle>,
    warm_pairs: Option<&HashMap<ContactPair, [f64; 4]>>,
    backend: &mut dyn QpBackend,
    settings: &InnerSettings,
    deadline: Option<Instant>,
) -> Result<SubproblemResult, QpError> {
    let mut rows = rows;
    // Which carried pairs the oracle added in this sub-problem (the only ones ever dropped).
    let mut added_here = vec![false; rows.len()];
    let warm_pairs = warm_pairs.filter(|_| settings.warm_start);
    let eps_qp = eps + settings.margin_rel * eps + settings.margin_abs;
    let mut y = start.to_vec();
    let mut jy = energy.value(&y);
    let mut res = SubproblemResult {
        y: Vec::new(),
        energy: jy,
        inner_iterations: 0,
        backend_iterations: 0,
        qp_status: QpStatus::Solved,
        line_search_failed: false,
        line_search_stalled: false,
        rows: Vec::new(),
        multipliers: Vec::new(),
        lazy_rounds: 0,
        t_assembly_s: 0.0,
        t_pairs_s: 0.0,
        t_solve_s: 0.0,
        timed_out: false,
    };
    let mut warm: Option<WarmStart> = None;
    let mut shift = ModelShift::default();
    'inner: for _ in 0..settings.max_inner {
        // Checked between inner steps and between lazy rounds (a QP in progress and the
        // oracle's search are not interrupted): the time limit overshoots by up to one QP solve
        // and one pair search.
        if deadline.is_some_and(|d| Instant::now() >= d) {
            res.timed_out = true;
            break;
        }
        res.inner_iterations += 1;
        // Solve the QP over the carried rows and ask the oracle about the full step `y + d`:
        // rows of T(ψ) it violates are added and the QP solved again from the same `y` (rows
        // only grow within this loop, so it ends). A QP solution that violates no row of T(ψ)
        // is the all-pairs QP's solution (a convex QP). Then the line search on J.
        let (sol, qp, step) = loop {
            let t0 = Instant::now();
            let (qp, g) = build_qp(
                mesh, energy, dofs, &rows, &y, eps_qp, trust, settings, &mut shift,
            )?;
            res.t_assembly_s += t0.elapsed().as_secs_f64();
            if warm.is_none() && res.inner_iterations == 1 && res.lazy_rounds == 0 {
                // First QP of the outer step: the last step's multipliers, by pair.
                warm = warm_pairs.map(|map| {
                    let mut yw = vec![0.0; qp.m()];
                    let (offsets, _) = row_offsets(&rows);
                    for (row, &off) in rows.iter().zip(&offsets) {
                        if let Some(mu) = map.get(&row.pair) {
                            for i in 0..row.len {
                                yw[off + i] = -mu[i];
                            }
                        }
                    }
                    WarmStart {
                        x: Vec::new(),
                        y: yw,
                    }
                });
            }
            let t1 = Instant::now();
            let sol = match (settings.energy_scale, settings.length_scale) {
                (Some(e), Some(l)) => solve_in_units(backend, &qp, warm.as_ref(), e, l)?,
                _ => backend.solve(&qp, warm.as_ref())?,
            };
            res.t_solve_s += t1.elapsed().as_secs_f64();
            res.backend_iterations += sol.iterations;
            res.qp_status = sol.status;
            if sol.status != QpStatus::Solved {
                break 'inner;
            }
            let mut d = vec![0.0; y.len()];
            for (dof, &c) in dofs.col.iter().enumerate() {
                if c != usize::MAX {
                    d[dof] = sol.x[c];
                    // The backend meets the box to its tolerance; the box is exact (the pairs
                    // left out of the rows rely on it), so clamp into it.
                    if let Some(tb) = trust {
                        let off = tb.psi[dof] - y[dof];
                        d[dof] = d[dof].clamp(off - tb.delta, off + tb.delta);
                    }
                }
            }
            if let Some(oracle) = oracle.as_mut() {
                let tp = Instant::now();
                let full: Vec<f64> = y.iter().zip(&d).map(|(a, b)| a + b).collect();
                let added = oracle(&full, &rows);
                res.t_pairs_s += tp.elapsed().as_secs_f64();
                if !added.is_empty() {
                    if deadline.is_some_and(|d| Instant::now() >= d) {
                        // The QP must be solved again before its step can be taken: stop at
                        // the last accepted iterate `y` (in T(ψ)) instead.
                        res.timed_out = true;
                        break 'inner;
                    }
                    // Keep this QP's duals for the carried rows; the new rows start at 0.
                    let old = row_offsets(&rows).1;
                    added_here.resize(rows.len() + added.len(), true);
                    rows.extend(added);
                    res.lazy_rounds += 1;
                    warm = settings.warm_start.then(|| {
                        let mut yw = sol.y[..old].to_vec();
                        yw.resize(row_offsets(&rows).1, 0.0);
                        yw.extend_from_slice(&sol.y[old..]);
                        WarmStart {
                            x: Vec::new(),
                            y: yw,
                        }
                    });
                    continue;
                }
            }
            let slope: f64 = g.iter().zip(&d).map(|(a, b)| a * b).sum();
            let step = if slope >= 0.0 {
                // d = 0 up to round-off: y is optimal for the model.
                Step::Optimal
            } else {
                // y and y + d both lie in T(ψ) (the oracle checked y + d against all of it),
                // so the segment does; the line search still checks the carried rows exactly.
                // Where the rows carry no margin (the polish at ε), the backend's tolerance can
                // leave rows of the full step just below ε: the step is then cut where the
                // first of them reaches ε (rows are linear in the step length).
                let mut t: f64 = 1.0;
                if eps_qp == eps {
                    let full: Vec<f64> = y.iter().zip(&d).map(|(a, b)| a + b).collect();
                    for r in &rows {
                        let (v0, v1) = (r.values(&y), r.values(&full));
                        for i in 0..r.len {
                            if v1[i] < eps && v0[i] > v1[i] {
                                // a millionth of the slack left, above the round-off of the
                                // row values, so that the exact check below passes
                                t = t.min((v0[i] - eps) * (1.0 - 1e-6) / (v0[i] - v1[i]));
                            }
                        }
                    }
                    t = t.max(0.0);
                }
                let mut accepted = None;
                for _ in 0..=settings.max_halvings {
                    let trial: Vec<f64> = y.iter().zip(&d).map(|(a, b)| a + t * b).collect();
                    let jt = energy.value(&trial);
                    if jt.is_finite()
                        && jt <= jy + 1e-4 * t * slope
                        && min_slack(&rows, &trial, eps) >= 0.0
                    {
                        accepted = Some((trial, jt));
                        break;
                    }
                    t *= 0.5;
                }
                match accepted {
                    Some((trial, jt)) => Step::Accepted(trial, jt),
                    None => Step::Failed(slope),
                }
            };
            break (sol, qp, step);
        };
        let (offsets, _) = row_offsets(&rows);
        res.multipliers = rows
            .iter()
            .zip(&offsets)
            .map(|(row, &off)| {
                let mut mu = [0.0; 4];
                for (i, m) in mu.iter_mut().enumerate().take(row.len) {
                    *m = -sol.y[off + i];
                }
                mu
            })
            .collect();
        match step {
            Step::Optimal => break,
            Step::Accepted(trial, jt) => {
                let dec = jy - jt;
                y = trial;
                jy = jt;
                let mut ysol = sol.y.clone();
                if oracle.is_some() {
                    // Lazy rows: forget the pairs the oracle added that are not nearly binding
                    // at the new point (slack above LAZY_KEEP_SLACK·ε); the oracle brings any
                    // back that a later point violates.
                    let thr = LAZY_KEEP_SLACK * eps;
                    let (offsets, ncontact) = row_offsets(&rows);
                    let keep: Vec<bool> = rows
                        .iter()
                        .zip(&added_here)
                        .map(|(r, &added)| !added || r.min_value(&y) - eps <= thr)
                        .collect();
                    if keep.iter().any(|k| !k) {
                        let mut kept_y = Vec::with_capacity(ysol.len());
                        for ((r, &off), &k) in rows.iter().zip(&offsets).zip(&keep) {
                            if k {
                                kept_y.extend_from_slice(&ysol[off..off + r.len]);
                            }
                        }
                        kept_y.extend_from_slice(&ysol[ncontact..]);
                        ysol = kept_y;
                        let mut it = keep.iter();
                        rows.retain(|_| *it.next().unwrap());
                        let mut it = keep.iter();
                        res.multipliers.retain(|_| *it.next().unwrap());
                        let mut it = keep.iter();
                        added_here.retain(|_| *it.next().unwrap());
                    }
                }
                warm = settings.warm_start.then(|| WarmStart {
                    x: vec![0.0; qp.n()],
                    y: ysol,
                });
                let scale = settings.energy_scale.unwrap_or(jy.abs().max(1.0));
                if dec <= (settings.tol_inner * scale).max(64.0 * f64::EPSILON * jy.abs()) {
                    break;
                }
            }
            Step::Failed(slope) => {
                // A predicted decrease at round-off level is a stall, not a failure; whether
                // the point is optimal is for the certificate to say.
                let scale = settings.energy_scale.unwrap_or(jy.abs().max(1.0));
                res.line_search_stalled =
                    -slope <= (1e-12 * scale).max(64.0 * f64::EPSILON * jy.abs());
                res.line_search_failed = !res.line_search_stalled;
                break;
            }
        }
    }
    if res.multipliers.len() != rows.len() {
        res.multipliers = vec![[0.0; 4]; rows.len()];
    }
    res.rows = rows;
    res.y = y;
    res.energy = jy;
    Ok(res)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Hessian;
    use std::time::Duration;

    /// Upper triplets of the 1D Laplacian-like tridiagonal `a` on the diagonal, `b` off it.
    fn tridiagonal(n: usize, a: f64, b: f64) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, a));
            if i + 1 < n {
                t.push((i, i + 1, b));
            }
        }
        t
    }

    /// `½|x₀ − (0, −1)|²` for vertex 0: pulls it through the edge below it.
    struct PullDown;

    impl Objective for PullDown {
        fn value(&self, x: &[f64]) -> f64 {
            0.5 * (x[0] * x[0] + (x[1] + 1.0) * (x[1] + 1.0))
        }
        fn gradient(&self, x: &[f64]) -> Vec<f64> {
            let mut g = vec![0.0; x.len()];
            g[0] = x[0];
            g[1] = x[1] + 1.0;
            g
        }
        fn hessian(&self, _x: &[f64], _model: HessianModel) -> Hessian {
            Hessian {
                triplets: vec![(0, 0, 1.0), (1, 1, 1.0)],
                rank_one: Vec::new(),
            }
        }
        fn model_is_psd(&self, _model: HessianModel) -> bool {
            true
        }
    }

    /// A free vertex at (0, 1) above a fixed edge from (−1, 0) to (1, 0).
    fn vertex_over_edge() -> Mesh {
        use crate::scene::mesh::{Body, BodyKind};
        Mesh {
            dim: 2,
            x_ref: vec![0.0, 1.0, -1.0, 0.0, 1.0, 0.0],
            fixed: vec![false, true, true],
            edges: vec![[1, 2]],
            edge_body: vec![1],
            bodies: vec![
                Body {
                    name: "point".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![0],
                    ..Default::default()
                },
                Body {
                    name: "edge".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![1, 2],
                    edges: vec![0],
                    ..Default::default()
                },
            ],
            ..Default::default()
        }
    }

    /// The lazy rows of the vertex over the edge from no rows: the first QP's step crosses the
    /// edge, the oracle (after `wait`) adds the pair's row, the next QP stops at ε. Returns
    /// the result and how often the oracle was asked.
    fn lazy_vertex_over_edge(wait: Option<Duration>) -> (SubproblemResult, usize) {
        let mesh = vertex_over_edge();
        let dofs = DofMap::new(&mesh);
        let x0 = mesh.x_ref.clone();
        let pair = ContactPair::PointEdge { x: 0, a: 0 };
        let row = crate::contact::pair_rows(&mesh, &x0, pair).unwrap();
        let mut calls = 0;
        let mut oracle = |phi: &[f64], carried: &[PairRows]| {
            calls += 1;
            if let Some(w) = wait {
                std::thread::sleep(w);
            }
            let violated = phi[1] < 0.1 && carried.iter().all(|r| r.pair != pair);
            if violated {
                vec![row]
            } else {
                Vec::new()
            }
        };
        let st = contactlab_solvers::QpSettings::default();
        let mut backend = contactlab_solvers::backend_from_name("clarabel", &st).unwrap();
        let deadline = wait.map(|w| Instant::now() + w / 2);
        let res = solve_subproblem(
            &mesh,
            &PullDown,
            &dofs,
            Vec::new(),
            &x0,
            0.1,
            None,
            Some(&mut oracle as RowOracle),
            None,
            backend.as_mut(),
            &InnerSettings::default(),
            deadline,
        )
        .unwrap();
        (res, calls)
    }

    #[test]
    fn lazy_rows_stop_at_the_vertex_over_the_edge_at_eps() {
        let (res, calls) = lazy_vertex_over_edge(None);
        assert!(!res.timed_out);
        assert_eq!(res.lazy_rounds, 1);
        assert!(
            calls >= 2,
            "the oracle checks the re-solved QP too: {calls}"
        );
        assert!((res.y[1] - 0.1).abs() < 1e-5, "y = {:?}", &res.y[..2]);
        assert!(
            res.y[1] >= 0.1 && res.y[0].abs() < 1e-6,
            "y = {:?}",
            &res.y[..2]
        );
    }

    #[test]
    fn the_deadline_is_checked_between_lazy_rounds() {
        // The deadline passes while the oracle searches after the first QP: the QP is not
        // solved again, the sub-problem ends at its start (the last accepted iterate).
        let (res, calls) = lazy_vertex_over_edge(Some(Duration::from_millis(40)));
        assert!(res.timed_out);
        assert_eq!(calls, 1);
        assert_eq!((res.inner_iterations, res.lazy_rounds), (1, 0));
        assert_eq!(&res.y[..2], &[0.0, 1.0]);
        assert_eq!(res.multipliers.len(), res.rows.len());
    }

    #[test]
    fn model_shift_is_zero_on_a_positive_definite_model() {
        // eigenvalues 2 − 2cos(kπ/(n+1)) > 0
        let mut m = CscMatrix::from_triplets(10, 10, &tridiagonal(10, 2.0, -1.0)).unwrap();
        let before = m.nzval.clone();
        let mut shift = ModelShift::default();
        assert_eq!(shift.apply(&mut m, 10, 2.0, 0).unwrap(), 0.0);
        assert_eq!(m.nzval, before);
        assert_eq!(shift.factorizations, 1);
    }

    #[test]
    fn the_tight_shift_is_within_a_factor_4_to_the_64th_of_the_smallest() {
        // the same model as below: λ_min = 1 − 2cos(π/11) ≈ −0.919
        let n = 10;
        let t = CscMatrix::from_triplets(n, n, &tridiagonal(n, 1.0, -1.0)).unwrap();
        let lambda_min = 1.0 - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        let bisections = HessianModel::ShiftedTight.shift_bisections();
        assert_eq!(bisections, 6);
        let mut grid = ModelShift::default();
        let coarse = grid.apply(&mut t.clone(), n, 1.0, 0).unwrap();
        let mut shift = ModelShift::default();
        let sigma = shift.apply(&mut t.clone(), n, 1.0, bisections).unwrap();
        assert!(sigma > -lambda_min, "σ = {sigma}, λ_min = {lambda_min}");
        let bound = 4f64.powf(1.0 / 64.0) * -lambda_min;
        assert!(sigma <= bound, "σ = {sigma} above {bound}");
        assert!(sigma < coarse, "σ = {sigma}, the grid's {coarse}");
        assert_eq!(shift.factorizations, grid.factorizations + bisections);
        // from the next step's start σ/4 (which fails) it bisects again to a σ as tight
        let again = shift.apply(&mut t.clone(), n, 1.0, bisections).unwrap();
        assert!(again > -lambda_min && again <= bound, "σ = {again}");
        // a definite model is not shifted
        let pd = CscMatrix::from_triplets(n, n, &tridiagonal(n, 3.0, -1.0)).unwrap();
        let mut fresh = ModelShift::default();
        assert_eq!(
            fresh.apply(&mut pd.clone(), n, 3.0, bisections).unwrap(),
            0.0
        );
    }

    #[test]
    fn model_shift_makes_an_indefinite_model_definite_within_a_factor_4() {
        // eigenvalues a + 2b·cos(kπ/(n+1)); with a = 1, b = −1 the smallest is
        // 1 − 2cos(π/11) ≈ −0.919
        let n = 10;
        let t = CscMatrix::from_triplets(n, n, &tridiagonal(n, 1.0, -1.0)).unwrap();
        let lambda_min = 1.0 - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        let mut shift = ModelShift::default();
        let mut m = t.clone();
        let sigma = shift.apply(&mut m, n, 1.0, 0).unwrap();
        assert!(
            sigma > -lambda_min,
            "σ = {sigma} does not cover λ_min = {lambda_min}"
        );
        assert!(
            sigma <= 4.0 * -lambda_min,
            "σ = {sigma} more than 4·|λ_min|"
        );
        // the shift is on the diagonal of the matrix, nowhere else
        for j in 0..n {
            for k in t.colptr[j]..t.colptr[j + 1] {
                let add = if t.rowval[k] == j { sigma } else { 0.0 };
                assert_eq!(m.nzval[k], t.nzval[k] + add);
            }
        }
        // the next step starts from σ/4, which fails, and climbs back to the same σ
        let again = shift.apply(&mut t.clone(), n, 1.0, 0).unwrap();
        assert_eq!(again, sigma);
        // a model that became definite brings the shift back to 0 within a few steps
        let pd = CscMatrix::from_triplets(n, n, &tridiagonal(n, 3.0, -1.0)).unwrap();
        let mut steps = 0;
        while shift.apply(&mut pd.clone(), n, 3.0, 0).unwrap() > 0.0 {
            steps += 1;
            assert!(steps < 40, "the shift does not fall back to 0");
        }
        assert_eq!(shift.max_sigma, sigma);
    }
}
