//! Diagnostics of a run: the contact pattern (which bodies touch which), and the Lemma 5.4
//! multipliers and Lemma 5.6 residual of a converged run.
//!
//! Two bodies touch when some pair of disjoint contact elements between them (2D: vertex of
//! one, edge of the other; 3D: vertex–face or edge–edge) is at distance `< 1.01 ε`. A vertex
//! shared by two bodies (a membrane glued to its support) counts for both.

use crate::contact::{near_pairs, pair_rows, rows_for, ContactPair, PairRows};
use crate::scene::mesh::Mesh;
use crate::solve::h1::h1_gram;

/// Unordered body pairs `(i, j)`, `i ≤ j`, in contact at `x` (`i = j`: self-contact), among
/// `pairs` (e.g. [`near_pairs`] within `1.01 ε`).
pub fn contact_pattern(
    mesh: &Mesh,
    x: &[f64],
    pairs: &[ContactPair],
    eps: f64,
) -> Vec<(usize, usize)> {
    let nbodies = mesh.bodies.len();
    let mut vertex_bodies: Vec<Vec<usize>> = vec![Vec::new(); mesh.nv()];
    for (b, body) in mesh.bodies.iter().enumerate() {
        for &v in &body.vertices {
            vertex_bodies[v].push(b);
        }
    }
    let mut touch = vec![false; nbodies * nbodies];
    let mut mark = |i: usize, j: usize| {
        let (i, j) = if i < j { (i, j) } else { (j, i) };
        touch[i * nbodies + j] = true;
    };
    for &p in pairs {
        let d = pair_rows(mesh, x, p).map_or(0.0, |r| r.distance);
        if d >= 1.01 * eps {
            continue;
        }
        match p {
            ContactPair::PointEdge { x: v, a } | ContactPair::PointTriangle { x: v, t: a } => {
                let be = if matches!(p, ContactPair::PointEdge { .. }) {
                    mesh.edge_body[a]
                } else {
                    mesh.face_body[a]
                };
                let vb = &vertex_bodies[v];
                for &bv in vb {
                    // A glued vertex's own body contact with the element's body is the glue,
                    // not a contact; count self-contact only for a vertex of that body alone.
                    if bv == be && vb.len() > 1 {
                        continue;
                    }
                    mark(bv, be);
                }
            }
            ContactPair::EdgeEdge { a, b } => mark(mesh.edge_body[a], mesh.edge_body[b]),
        }
    }
    let mut out = Vec::new();
    for i in 0..nbodies {
        for j in i..nbodies {
            if touch[i * nbodies + j] {
                out.push((i, j));
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Lemma 5.4 multipliers and the Lemma 5.6 residual of a converged run (docs/method.md, "Diagnostics of a converged run").
// ---------------------------------------------------------------------------------------------

use crate::energy::TotalEnergy;
use contactlab_solvers::linalg::SparseLdl;
use contactlab_solvers::{CscMatrix, Qp, QpBackend, QpError, QpStatus};
use std::collections::{BTreeMap, HashMap};

/// Settings of [`converged_diagnostics`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DiagnosticSettings {
    /// A row `n·(φ(p) − φ(q)) ≥ ε` of T(φ_h) is active when its value is at most
    /// `ε + active_tol`. Default `2·(1e-6·ε + 1e-11)`: twice the sub-problems' row margin
    /// (`InnerSettings::margin_rel`, `margin_abs`), the count the outer loop reports.
    pub active_tol: f64,
    /// Tikhonov weight τ of the canonical-dual problem, relative to the largest diagonal entry
    /// of `A Aᵀ` (see [`converged_diagnostics`]). Default `1e-10`.
    pub tikhonov_rel: f64,
    /// With `Some(r)`, a row whose raw dual (the last sub-problem's) exceeds `r` times the
    /// largest raw dual is active whatever its gap: a backend leaves an active row within its
    /// own tolerance of `ε + δ`, far more than `active_tol` at small ε/h. `None` (the default
    /// of [`DiagnosticSettings::for_eps`], what sweeps use, so that their committed columns do
    /// not move): the gap alone decides. `contactlab run` uses `Some(1e-4)` for its
    /// `multipliers.csv` and summary.
    pub raw_dual_rel: Option<f64>,
}

impl DiagnosticSettings {
    /// The defaults for a run with minimal distance `eps`.
    pub fn for_eps(eps: f64) -> Self {
        DiagnosticSettings {
            active_tol: 2.0 * (1e-6 * eps + 1e-11),
            tikhonov_rel: 1e-10,
            raw_dual_rel: None,
        }
    }
}

/// One contact pair at the fixed point: its rows, canonical duals and per-length (2D) or
/// per-area (3D) multiplier.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PairMultiplier {
    /// `point_edge`, `vertex_triangle` or `edge_edge`.
    pub kind: &'static str,
    /// First element: the vertex x (point–edge, vertex–triangle) or edge a (edge–edge).
    pub first: usize,
    /// Second element: the edge a (point–edge), face T (vertex–triangle) or edge b.
    pub second: usize,
    /// Number of rows of the pair (2, 3 or 4).
    pub rows: usize,
    /// The pair's distance at φ_h.
    pub distance: f64,
    /// Barycentric weight of each row in the closest points (2D: `(α⁰, α¹)` of `p_{a,x}`).
    pub weight: [f64; 4],
    /// Whether each row is active.
    pub active: [bool; 4],
    /// Canonical duals of the rows, QP scaling (`h^{d−1}·λ` per row; eq. 9 and 14).
    pub mu: [f64; 4],
    /// The pair's local size: the reference tributary measure of its point (vertex–edge,
    /// vertex–triangle) projected normal to the pair's normal
    /// ([`ContactAdjacency::projected`](crate::harness::contact_output::ContactAdjacency::projected)),
    /// or the weighted mean of those of edge `a`'s ends (edge–edge, weights the closest
    /// point's `(1 − s, s)`): a length in 2D, an area in 3D.
    pub local_size: f64,
    /// `λ = Σ μ / local_size`: per length in 2D (eq. 14 with the local element size in place
    /// of the uniform h), per area in 3D.
    pub lambda: f64,
}

/// Lemma 5.4 and Lemma 5.6 quantities at a converged configuration φ_h.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ConvergedDiagnostics {
    /// Mesh size h used for the scalings.
    pub h: f64,
    /// Pairs of T(φ_h) with at least one active row.
    pub active_pairs: usize,
    /// Active rows of T(φ_h).
    pub active_rows: usize,
    /// `‖J'(φ_h) − Σ μ ∇row‖_∞` over the free dofs with the canonical duals (Lemma 5.4
    /// stationarity; 0 at an exact fixed point).
    pub stationarity_canonical: f64,
    /// The same with the raw duals of the last sub-problem (rows built at the previous
    /// iterate), as returned by the backend.
    pub stationarity_raw: f64,
    /// `‖J'(φ_h)‖_∞` over the free dofs, the scale of the two stationarity residuals.
    pub gradient_norm: f64,
    /// Complementarity of the raw duals: `max μ_r·|value_r(φ_h) − ε|` over the last
    /// sub-problem's rows.
    pub complementarity_raw: f64,
    /// Most negative raw dual (0 when all are ≥ 0).
    pub min_raw_dual: f64,
    /// `‖λ‖_h = (Σ h^{d−1} λ²)^{1/2}` over the active pairs.
    pub lambda_norm_h: f64,
    /// `C(φ_h)`: 2D, `max_a #{x : (a, x) active}` (Lemma 5.6); 3D, the largest number of
    /// active pairs sharing one contact element (a face, or an edge of an edge–edge pair).
    pub c_phi: usize,
    /// `max_x #{a : (a, x) active}` (Remark 5.2: at most six in 2D); 3D: faces per vertex.
    pub max_edges_per_vertex: usize,
    /// `‖R‖_{H⁻¹} = (rᵀ G⁻¹ r)^{1/2}`, Lemma 5.6 residual with the canonical duals.
    pub residual_hm1: f64,
    /// `B = √C(φ_h)·‖λ‖_h·h`.
    pub bound: f64,
    /// `‖R‖ / B` (NaN when B = 0).
    pub ratio: f64,
    /// Status of the canonical-dual QP (`solved` or the backend's status).
    pub dual_qp_status: &'static str,
    /// The active pairs.
    pub pairs: Vec<PairMultiplier>,
}

/// Errors of [`converged_diagnostics`].
#[derive(Debug, thiserror::Error)]
pub enum DiagnosticsError {
    /// The configuration has a pair at distance 0 (no normal).
    #[error("the configuration has a contact pair at distance 0: no rows of T(φ_h)")]
    ZeroDistance,
    /// The H¹ Gram matrix on the free dofs could not be factorized.
    #[error("the H1 Gram matrix on the free dofs is not positive definite (a free vertex belongs to no element?)")]
    Gram,
    /// The canonical-dual QP was rejected.
    #[error("canonical-dual QP rejected: {0}")]
    Qp(#[from] QpError),
}

/// Free dof numbering: `col[dof]`, `usize::MAX` for a prescribed dof (a fixed vertex or a
/// supported component), the numbering of the sub-problem's QP.
fn free_cols(mesh: &Mesh) -> (Vec<usize>, usize) {
    let d = crate::solve::subproblem::DofMap::new(mesh);
    (d.col, d.nfree)
}

/// The H¹ norm `√(dᵀ G d)` of `d = x − y` on the free dofs, `G` = [`h1_gram`] (on the scene's
/// own reference positions) (the fixed dofs
/// are equal in any two configurations of one scene). The position error of the speed/accuracy
/// trade-off.
pub fn h1_distance(mesh: &Mesh, x: &[f64], y: &[f64]) -> f64 {
    let (col, nfree) = free_cols(mesh);
    let mut d = vec![0.0; nfree];
    for (k, &c) in col.iter().enumerate() {
        if c != usize::MAX {
            d[c] = x[k] - y[k];
        }
    }
    let g = h1_gram(mesh);
    let mut gd = vec![0.0; nfree];
    g.sym_upper_mul_add(1.0, &d, &mut gd);
    d.iter()
        .zip(&gd)
        .map(|(a, b)| a * b)
        .sum::<f64>()
        .max(0.0)
        .sqrt()
}

/// The gradient of row `i` of a pair, `n·(φ(p) − φ(q))`, as `(dof, value)` entries on the free
/// dofs.
fn row_gradient(r: &PairRows, i: usize, col: &[usize], out: &mut Vec<(usize, f64)>) {
    out.clear();
    let d = r.dim;
    for c in 0..d {
        let cp = col[d * r.plus[i] + c];
        if cp != usize::MAX {
            out.push((cp, r.n[c]));
        }
        let cm = col[d * r.minus[i] + c];
        if cm != usize::MAX {
            out.push((cm, -r.n[c]));
        }
    }
}

/// `g − Σ_r μ_r ∇row_r` on the free dofs.
fn stationarity_vector(g: &[f64], rows: &[PairRows], mu: &[[f64; 4]], col: &[usize]) -> Vec<f64> {
    let mut s = g.to_vec();
    let mut buf = Vec::new();
    for (r, m) in rows.iter().zip(mu) {
        for (i, &mi) in m.iter().enumerate().take(r.len) {
            if mi != 0.0 {
                row_gradient(r, i, col, &mut buf);
                for &(k, v) in &buf {
                    s[k] -= mi * v;
                }
            }
        }
    }
    s
}

/// `‖J'(x) − Σ_r μ_r ∇row_r‖_∞` over the free dofs: the Lemma 5.4 stationarity residual of
/// duals `mu` (one per row of each pair) with the sign of docs/method.md (the opposite of the paper's printed (9) and (15)).
pub fn stationarity_residual(
    mesh: &Mesh,
    energy: &TotalEnergy,
    x: &[f64],
    rows: &[PairRows],
    mu: &[[f64; 4]],
) -> f64 {
    let (col, nfree) = free_cols(mesh);
    let gfull = energy.gradient(x);
    let mut g = vec![0.0; nfree];
    for (dof, &c) in col.iter().enumerate() {
        if c != usize::MAX {
            g[c] = gfull[dof];
        }
    }
    max_abs(&stationarity_vector(&g, rows, mu, &col))
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Lemma 5.4 / 5.6 diagnostics at a converged configuration `x` (= φ_h) of a run whose last
/// sub-problem had rows `last_rows` and duals `last_mult` (docs/method.md, "Diagnostics of a converged run").
///
/// * **Rows** of T(ψ), `psi` the last sub-problem's ψ (`RunResult::psi`; φ_h ≈ ψ at a fixed
///   point): every contact pair closer than `ε + active_tol + 1e-9·ε` at φ_h; a row is active
///   when its value at φ_h is at most `ε + active_tol`. Built at ψ rather than at φ_h because
///   after the polish at ε (docs/method.md, "The row margin") these are the rows φ_h meets
///   with equality: at a contact on a polygon's vertex the normal at φ_h turns by about
///   displacement/ε, so rows rebuilt at φ_h move by (h/ε)·δ and fall out of the active band.
/// * **Canonical duals** (docs/method.md, canonical duals): with `A` the active rows' gradients and
///   `g = J'(φ_h)` on the free dofs, the duals minimize `½|Aᵀμ − g|² + ½τ|μ|²` over `μ ≥ 0`,
///   `τ = tikhonov_rel · max diag(AAᵀ)`: a non-negative least-squares problem whose solution
///   tends to the minimum-norm one of the stationarity set as τ → 0. It is solved as a QP by
///   `backend` (the caller picks it and its tolerance). Inactive rows get 0, so complementary
///   slackness holds by construction; the raw duals' complementarity is reported apart.
/// * **Lemma 5.6**: `r = g − Σ_pairs (Σ_i μ_i)(Σ_i w_i ∇row_i)`, `w` the rows' barycentric
///   weights, the nodal vector of `⟨R, φ̂⟩ = ⟨J'(φ_h), φ̂⟩ − Σ h^{d−1}λ n·(φ̂(p) − φ̂(q))` with
///   `p`, `q` the pair's closest points, and `‖R‖ = (rᵀG⁻¹r)^{1/2}` with the H¹ Gram matrix `G`
///   ([`h1_gram`], factorized by the sparse `LDLᵀ` also used by the Uzawa backend). In 3D the
///   same quantities with per-area λ; the paper proves the bound in 2D only.
#[allow(clippy::too_many_arguments)] // the run's state, its last sub-problem and the QP solver
pub fn converged_diagnostics(
    mesh: &Mesh,
    energy: &TotalEnergy,
    x: &[f64],
    psi: &[f64],
    eps: f64,
    h: f64,
    last_rows: &[PairRows],
    last_mult: &[[f64; 4]],
    backend: &mut dyn QpBackend,
    settings: &DiagnosticSettings,
) -> Result<ConvergedDiagnostics, DiagnosticsError> {
    let (col, nfree) = free_cols(mesh);
    let gfull = energy.gradient(x);
    let mut g = vec![0.0; nfree];
    for (dof, &c) in col.iter().enumerate() {
        if c != usize::MAX {
            g[c] = gfull[dof];
        }
    }
    let gradient_norm = max_abs(&g);

    // Raw duals: stationarity against the last rows, complementarity at φ_h.
    let stationarity_raw = max_abs(&stationarity_vector(&g, last_rows, last_mult, &col));
    let mut complementarity_raw = 0.0f64;
    let mut min_raw_dual = 0.0f64;
    for (r, m) in last_rows.iter().zip(last_mult) {
        let v = r.values(x);
        for i in 0..r.len {
            complementarity_raw = complementarity_raw.max(m[i] * (v[i] - eps).abs());
            min_raw_dual = min_raw_dual.min(m[i]);
        }
    }

    // Rows of T(ψ) near contact at φ_h, ψ the last sub-problem's (φ_h ≈ ψ at a fixed point;
    // after the polish at ε, the rows φ_h satisfies with equality); and (with `raw_dual_rel`)
    // the rows the last sub-problem's duals hold: a backend leaves an active row within its
    // own tolerance of ε + δ, which at small ε/h is far more than `active_tol`, so a row whose
    // raw dual is above `raw_dual_rel` of the largest (an interior-point backend leaves small
    // positive duals on inactive rows, far below 1e-4 of it) counts as active whatever its gap.
    let reach = eps + settings.active_tol + 1e-9 * eps;
    let mut near = near_pairs(mesh, x, reach, true);
    let max_raw = last_mult
        .iter()
        .flat_map(|m| m.iter())
        .fold(0.0f64, |a, &b| a.max(b));
    let mut raw_active: HashMap<(ContactPair, usize), ()> = HashMap::new();
    for (r, m) in last_rows.iter().zip(last_mult) {
        for (i, &mu) in m.iter().enumerate().take(r.len) {
            if settings
                .raw_dual_rel
                .is_some_and(|r| max_raw > 0.0 && mu > r * max_raw)
            {
                raw_active.insert((r.pair, i), ());
            }
        }
    }
    let mut extra: Vec<ContactPair> = raw_active.keys().map(|(p, _)| *p).collect();
    extra.sort_unstable();
    extra.dedup();
    let listed: std::collections::HashSet<ContactPair> = near.iter().copied().collect();
    near.extend(extra.into_iter().filter(|p| !listed.contains(p)));
    let rows = rows_for(mesh, psi, &near).ok_or(DiagnosticsError::ZeroDistance)?;
    let mut active_idx: Vec<(usize, usize)> = Vec::new(); // (pair index, row)
    let mut active_flags = vec![[false; 4]; rows.len()];
    for (k, r) in rows.iter().enumerate() {
        let v = r.values(x);
        for i in 0..r.len {
            if v[i] - eps <= settings.active_tol || raw_active.contains_key(&(r.pair, i)) {
                active_idx.push((k, i));
                active_flags[k][i] = true;
            }
        }
    }

    // Canonical duals: min ½|Aᵀμ − g|² + ½τ|μ|², μ ≥ 0, as a QP in μ.
    let m = active_idx.len();
    let mut mu = vec![[0.0f64; 4]; rows.len()];
    let mut dual_qp_status = "solved";
    if m > 0 {
        // Column lists of Aᵀ: for each free dof, the active rows touching it.
        let mut grads: Vec<Vec<(usize, f64)>> = Vec::with_capacity(m);
        let mut buf = Vec::new();
        for &(k, i) in &active_idx {
            row_gradient(&rows[k], i, &col, &mut buf);
            grads.push(buf.clone());
        }
        let mut by_dof: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
        for (j, gr) in grads.iter().enumerate() {
            for &(d, v) in gr {
                by_dof.entry(d).or_default().push((j, v));
            }
        }
        let mut ptrip: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        for list in by_dof.values() {
            for &(j1, v1) in list {
                for &(j2, v2) in list {
                    if j1 <= j2 {
                        *ptrip.entry((j1, j2)).or_insert(0.0) += v1 * v2;
                    }
                }
            }
        }
        let dmax = (0..m)
            .map(|j| ptrip.get(&(j, j)).copied().unwrap_or(0.0))
            .fold(0.0f64, f64::max);
        let tau = settings.tikhonov_rel * dmax.max(1.0);
        for j in 0..m {
            *ptrip.entry((j, j)).or_insert(0.0) += tau;
        }
        let mut pt: Vec<(usize, usize, f64)> =
            ptrip.into_iter().map(|((i, j), v)| (i, j, v)).collect();
        pt.sort_by_key(|t| (t.1, t.0));
        let q: Vec<f64> = grads
            .iter()
            .map(|gr| -gr.iter().map(|&(d, v)| v * g[d]).sum::<f64>())
            .collect();
        let ident: Vec<(usize, usize, f64)> = (0..m).map(|j| (j, j, 1.0)).collect();
        let qp = Qp {
            p: CscMatrix::from_triplets(m, m, &pt)?,
            q,
            a: CscMatrix::from_triplets(m, m, &ident)?,
            l: vec![0.0; m],
            u: vec![f64::INFINITY; m],
        };
        let sol = backend.solve(&qp, None)?;
        if sol.status != QpStatus::Solved {
            dual_qp_status = sol.status.as_str();
        }
        for (j, &(k, i)) in active_idx.iter().enumerate() {
            mu[k][i] = sol.x[j].max(0.0);
        }
    }
    let stationarity_canonical = max_abs(&stationarity_vector(&g, &rows, &mu, &col));

    // Pairs, λ, counts.
    let mut pairs = Vec::new();
    // per contact element (0: edge, 1: face) and per vertex
    let mut per_element: HashMap<(u8, usize), usize> = HashMap::new();
    let mut per_vertex: HashMap<usize, usize> = HashMap::new();
    let mut lambda_sq = 0.0;
    // h^{d−1}: λ per length in 2D, per area in 3D (eq. 14), for ‖λ‖_h and the bound; the
    // pairs' λ divide by their local size
    let hd = if mesh.dim == 2 { h } else { h * h };
    let adj = crate::harness::contact_output::ContactAdjacency::new(mesh);
    for (k, r) in rows.iter().enumerate() {
        if !active_flags[k].iter().any(|&a| a) {
            continue;
        }
        match r.pair {
            ContactPair::PointEdge { x, a } => {
                *per_element.entry((0, a)).or_insert(0) += 1;
                *per_vertex.entry(x).or_insert(0) += 1;
            }
            ContactPair::PointTriangle { x, t } => {
                *per_element.entry((1, t)).or_insert(0) += 1;
                *per_vertex.entry(x).or_insert(0) += 1;
            }
            ContactPair::EdgeEdge { a, b } => {
                *per_element.entry((0, a)).or_insert(0) += 1;
                *per_element.entry((0, b)).or_insert(0) += 1;
            }
        }
        let total = mu[k].iter().take(r.len).fold(0.0, |s, m| s + m);
        let lambda_h = total / hd;
        lambda_sq += hd * lambda_h * lambda_h;
        let n = [r.n.x, r.n.y, r.n.z];
        let trib = |v: usize| adj.projected(mesh, &mesh.x_ref, v, n);
        let local_size = match r.pair {
            ContactPair::PointEdge { x, .. } | ContactPair::PointTriangle { x, .. } => trib(x),
            ContactPair::EdgeEdge { a, .. } => {
                let [a0, a1] = mesh.edges[a];
                (r.weight[0] + r.weight[1]) * trib(a0) + (r.weight[2] + r.weight[3]) * trib(a1)
            }
        };
        let lambda = if local_size > 0.0 {
            total / local_size
        } else {
            lambda_h
        };
        let (first, second) = r.pair.indices();
        pairs.push(PairMultiplier {
            kind: r.pair.kind(),
            first,
            second,
            rows: r.len,
            distance: pair_rows(mesh, x, r.pair).map_or(0.0, |q| q.distance),
            weight: r.weight,
            active: active_flags[k],
            mu: mu[k],
            local_size,
            lambda,
        });
    }
    let c_phi = per_element.values().copied().max().unwrap_or(0);
    let max_edges_per_vertex = per_vertex.values().copied().max().unwrap_or(0);
    let lambda_norm_h = lambda_sq.sqrt();

    // Lemma 5.6 residual: r = g − Σ (Σ_i μ_i)(Σ_i w_i ∇row_i).
    let mut rvec = g.clone();
    let mut buf = Vec::new();
    for (k, r) in rows.iter().enumerate() {
        let s = mu[k].iter().take(r.len).fold(0.0, |s, m| s + m);
        if s == 0.0 {
            continue;
        }
        for i in 0..r.len {
            row_gradient(r, i, &col, &mut buf);
            for &(d, v) in &buf {
                rvec[d] -= s * r.weight[i] * v;
            }
        }
    }
    let residual_hm1 = if nfree == 0 {
        0.0
    } else {
        let gram = h1_gram(mesh);
        let ldl = SparseLdl::factor(&gram).ok_or(DiagnosticsError::Gram)?;
        let mut z = rvec.clone();
        ldl.solve_in_place(&mut z);
        rvec.iter()
            .zip(&z)
            .map(|(a, b)| a * b)
            .sum::<f64>()
            .max(0.0)
            .sqrt()
    };
    let bound = (c_phi as f64).sqrt() * lambda_norm_h * h;
    let ratio = if bound > 0.0 {
        residual_hm1 / bound
    } else {
        f64::NAN
    };
    Ok(ConvergedDiagnostics {
        h,
        active_pairs: pairs.len(),
        active_rows: m,
        stationarity_canonical,
        stationarity_raw,
        gradient_norm,
        complementarity_raw,
        min_raw_dual,
        lambda_norm_h,
        c_phi,
        max_edges_per_vertex,
        residual_hm1,
        bound,
        ratio,
        dual_qp_status,
        pairs,
    })
}
