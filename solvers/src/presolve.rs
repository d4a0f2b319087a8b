//! Row presolve: rows of `A` that are zero, or positive multiples of an earlier row, are
//! removed before a backend sees the QP, and the duals are mapped back to every original row.
//!
//! The contact QPs carry many such rows: two pairs of T(ψ) whose closest points are the same
//! vertex give the same row `n·(φ(p) − φ(q))` twice, bit for bit, and only the tighter bound
//! can bind. Parallel copies make the active rows rank-deficient, which interior-point, ADMM
//! and dual methods all handle worse than a smaller, equivalent QP.
//!
//! # What is merged
//!
//! Row `j` is merged into an earlier row `i` when both have the same sparsity pattern and
//! `a_j = c·a_i` with `c > 0`, tested exactly: each row is normalized by the absolute value of
//! its first entry and the normalized values are compared bit for bit (positive multiples that
//! round differently stay apart, which is safe). The merged row keeps `a_i` as it is (rows are
//! never rescaled, so a QP without such rows reaches the backend unchanged) with the bounds
//! `max(l_i, l_j/c) ≤ a_i x ≤ min(u_i, u_j/c)`. A zero row is dropped when `l ≤ 0 ≤ u` (an
//! infeasible zero row is kept, so that the backend reports the infeasibility), and a row whose
//! bounds would cross those of its group is kept apart, for the same reason.
//!
//! # Duals
//!
//! For the merged row's dual `ŷ` (`P x + q + Aᵀ y = 0`; `ŷ < 0` at the active lower bound,
//! `ŷ > 0` at the upper one) the original row whose bound is the binding one (the first such in
//! row order) gets `ŷ / c`, the other rows of the group 0, and a dropped zero row 0:
//! stationarity, sign and complementarity hold for the original QP exactly as for the reduced
//! one. A warm start is mapped the other way: the reduced row gets `Σ c_j y_j` over its group.

use crate::backend::{QpBackend, QpError, QpSolution, WarmStart};
use crate::qp::{CscMatrix, Qp};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use crate::hash::FxHasher as KeyHasher;

/// What happened to one original row.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Fate {
    /// This row is `scale ×` row `r` of the reduced QP.
    Row { r: usize, scale: f64 },
    /// A zero row, dropped.
    Zero,
}

/// The map from a QP to its presolved form ([`Presolve::new`]) and back.
#[derive(Clone, Debug)]
pub struct Presolve {
    fate: Vec<Fate>,
    /// Per reduced row: the original row giving its lower and its upper bound.
    lower_from: Vec<usize>,
    upper_from: Vec<usize>,
    /// The reduced QP.
    qp: Qp,
}

impl Presolve {
    /// Presolves `qp` (which must be valid: [`Qp::validate`]).
    pub fn new(qp: &Qp) -> Presolve {
        let (n, m) = (qp.n(), qp.m());
        // The rows, as (column, value) lists in column order (CSR: row i is
        // `rows[ptr[i]..ptr[i + 1]]`).
        let mut ptr = vec![0usize; m + 1];
        for (&r, &v) in qp.a.rowval.iter().zip(&qp.a.nzval) {
            if v != 0.0 {
                ptr[r + 1] += 1;
            }
        }
        for i in 0..m {
            ptr[i + 1] += ptr[i];
        }
        let mut rows = vec![(0usize, 0.0f64); ptr[m]];
        let mut fill = ptr[..m].to_vec();
        for j in 0..n {
            for p in qp.a.colptr[j]..qp.a.colptr[j + 1] {
                if qp.a.nzval[p] != 0.0 {
                    let r = qp.a.rowval[p];
                    rows[fill[r]] = (j, qp.a.nzval[p]);
                    fill[r] += 1;
                }
            }
        }
        let row = |i: usize| &rows[ptr[i]..ptr[i + 1]];
        // The groups by key (the columns and the bits of the values over the first entry's
        // absolute value): a hash of the key to the first reduced row of that hash, and per
        // reduced row the next one of the same hash; a reduced row is in these chains only
        // when no earlier one has its key.
        let key_hash = |r: &[(usize, f64)], s: f64| {
            let mut h = KeyHasher::default();
            for &(j, v) in r {
                h.write_u64(j as u64);
                h.write_u64((v / s).to_bits());
            }
            h.finish()
        };
        let same_key = |a: &[(usize, f64)], sa: f64, b: &[(usize, f64)], sb: f64| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| x.0 == y.0 && (x.1 / sa).to_bits() == (y.1 / sb).to_bits())
        };
        let mut fate = Vec::with_capacity(m);
        let mut heads: HashMap<u64, usize, BuildHasherDefault<KeyHasher>> = HashMap::default();
        let mut next_same: Vec<usize> = Vec::new();
        let (mut l, mut u) = (Vec::new(), Vec::new());
        let (mut lower_from, mut upper_from) = (Vec::new(), Vec::new());
        // The first row of each reduced row, and the absolute value of its first entry.
        let mut first: Vec<(usize, f64)> = Vec::new();
        for i in 0..m {
            let ri = row(i);
            if ri.is_empty() && qp.l[i] <= 0.0 && 0.0 <= qp.u[i] {
                fate.push(Fate::Zero);
                continue;
            }
            let s = ri.first().map_or(1.0, |e| e.1.abs());
            let hash = key_hash(ri, s);
            let mut group = heads.get(&hash).copied();
            while let Some(r) = group {
                if same_key(row(first[r].0), first[r].1, ri, s) {
                    break;
                }
                group = (next_same[r] != usize::MAX).then_some(next_same[r]);
            }
            // a_i = c·a_first with c = s / s_first: the bounds of a_first x are l_i/c, u_i/c.
            let merged = group.and_then(|r| {
                let c = s / first[r].1;
                let (li, ui) = (qp.l[i] / c, qp.u[i] / c);
                // rows whose bounds would cross stay apart: the backend reports infeasibility
                (li.max(l[r]) <= ui.min(u[r])).then_some((r, c, li, ui))
            });
            match merged {
                Some((r, c, li, ui)) => {
                    if li > l[r] {
                        l[r] = li;
                        lower_from[r] = i;
                    }
                    if ui < u[r] {
                        u[r] = ui;
                        upper_from[r] = i;
                    }
                    fate.push(Fate::Row { r, scale: c });
                }
                None => {
                    let r = first.len();
                    next_same.push(usize::MAX);
                    if group.is_none() {
                        // first of its key: at the head of its hash's chain
                        if let Some(h) = heads.insert(hash, r) {
                            next_same[r] = h;
                        }
                    }
                    first.push((i, s));
                    l.push(qp.l[i]);
                    u.push(qp.u[i]);
                    lower_from.push(i);
                    upper_from.push(i);
                    fate.push(Fate::Row { r, scale: 1.0 });
                }
            }
        }
        // The reduced A: row r is its first row, unscaled.
        let mr = first.len();
        let mut trip = Vec::new();
        for (r, &(i, _)) in first.iter().enumerate() {
            for &(j, v) in row(i) {
                trip.push((r, j, v));
            }
        }
        let a = CscMatrix::from_triplets(mr, n, &trip).expect("indices of a valid QP");
        Presolve {
            fate,
            lower_from,
            upper_from,
            qp: Qp {
                p: qp.p.clone(),
                q: qp.q.clone(),
                a,
                l,
                u,
            },
        }
    }

    /// The reduced QP.
    pub fn qp(&self) -> &Qp {
        &self.qp
    }

    /// Rows removed (merged or zero).
    pub fn removed(&self) -> usize {
        self.fate.len() - self.qp.m()
    }

    /// A warm start of the original QP as one of the reduced QP.
    ///
    /// A QP without zero or parallel rows is passed on as it is.
    pub fn reduce_warm(&self, warm: &WarmStart) -> WarmStart {
        let y = if warm.y.len() == self.fate.len() {
            let mut y = vec![0.0; self.qp.m()];
            for (i, f) in self.fate.iter().enumerate() {
                if let Fate::Row { r, scale } = *f {
                    y[r] += scale * warm.y[i];
                }
            }
            y
        } else {
            // a wrong length is passed on for the backend to report
            warm.y.clone()
        };
        WarmStart {
            x: warm.x.clone(),
            y,
        }
    }

    /// The solution of the reduced QP as one of the original QP (module documentation).
    pub fn restore(&self, mut sol: QpSolution) -> QpSolution {
        let mut y = vec![0.0; self.fate.len()];
        for (i, f) in self.fate.iter().enumerate() {
            if let Fate::Row { r, scale } = *f {
                let yr = sol.y[r];
                let from = if yr < 0.0 {
                    self.lower_from[r]
                } else {
                    self.upper_from[r]
                };
                if from == i && yr != 0.0 {
                    y[i] = yr / scale;
                }
            }
        }
        sol.y = y;
        sol
    }
}

/// A backend that solves the presolved QP with `inner` ([`Presolve`]); its name, iterations
/// and statuses are the inner backend's.
pub struct Presolved {
    inner: Box<dyn QpBackend>,
    /// Rows removed over all solves.
    pub removed_rows: usize,
}

impl Presolved {
    /// Wraps `inner`.
    pub fn new(inner: Box<dyn QpBackend>) -> Presolved {
        Presolved {
            inner,
            removed_rows: 0,
        }
    }
}

impl QpBackend for Presolved {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn tolerance(&self) -> Option<f64> {
        self.inner.tolerance()
    }

    fn set_tolerance(&mut self, tol: f64) {
        self.inner.set_tolerance(tol);
    }

    fn fallback_solves(&self) -> usize {
        self.inner.fallback_solves()
    }

    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError> {
        qp.validate()?;
        let pre = Presolve::new(qp);
        self.removed_rows += pre.removed();
        let warm = warm.map(|w| pre.reduce_warm(w));
        let sol = self.inner.solve(pre.qp(), warm.as_ref())?;
        Ok(pre.restore(sol))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{QpSettings, QpStatus};
    use crate::clarabel_backend::ClarabelBackend;

    /// min ½|x|² − x₀ − x₁ s.t. the rows below: x₀ + x₁ ≤ 1 three times (once scaled by 2, once
    /// with a looser bound), a zero row, and x₀ ≥ 0.2 (also as 3x₀ ≥ 0.9, tighter).
    fn example() -> Qp {
        let p = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(
            6,
            2,
            &[
                (0, 0, 1.0),
                (0, 1, 1.0),
                (1, 0, 2.0),
                (1, 1, 2.0),
                (2, 0, 1.0),
                (2, 1, 1.0),
                (4, 0, 1.0),
                (5, 0, 3.0),
            ],
        )
        .unwrap();
        Qp {
            p,
            q: vec![-1.0, -1.0],
            a,
            l: vec![
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
                -1.0,
                0.2,
                0.9,
            ],
            u: vec![1.0, 2.0, 5.0, 1.0, f64::INFINITY, f64::INFINITY],
        }
    }

    #[test]
    fn presolve_merges_parallel_rows_and_drops_zero_rows() {
        let qp = example();
        let pre = Presolve::new(&qp);
        assert_eq!(pre.qp().m(), 2);
        assert_eq!(pre.removed(), 4);
        // x₀ + x₁ ≤ min(1, 2/2, 5) = 1; x₀ ≥ max(0.2, 0.9/3) = 0.3
        assert_eq!(pre.qp().u[0], 1.0);
        assert!((pre.qp().l[1] - 0.3).abs() < 1e-15);
        // the rows are not rescaled
        assert_eq!(pre.qp().a.to_dense(), vec![vec![1.0, 1.0], vec![1.0, 0.0]]);
    }

    #[test]
    fn presolved_solution_meets_the_original_kkt_conditions() {
        let qp = example();
        let s = QpSettings {
            eps_abs: 1e-10,
            eps_rel: 1e-10,
            ..Default::default()
        };
        let mut b = Presolved::new(Box::new(ClarabelBackend::new(s.clone())));
        let sol = b.solve(&qp, None).unwrap();
        assert_eq!(sol.status, QpStatus::Solved);
        // the solution: x = (0.5, 0.5) with x₀ ≥ 0.3 inactive and x₀ + x₁ ≤ 1 active
        assert!((sol.x[0] - 0.5).abs() < 1e-8 && (sol.x[1] - 0.5).abs() < 1e-8);
        assert!(qp.dual_residual(&sol.x, &sol.y) < 1e-8);
        assert!(qp.primal_residual(&sol.x) < 1e-8);
        // one of the parallel rows carries the dual (the first of the tied bounds), the
        // looser ones and the zero row nothing; signs: y ≥ 0 at an upper bound
        assert!(sol.y[0] > 0.4);
        assert_eq!(sol.y[1], 0.0);
        assert_eq!(sol.y[2], 0.0);
        assert_eq!(sol.y[3], 0.0);
        // the same objective as the unreduced QP
        let full = ClarabelBackend::new(s).solve(&qp, None).unwrap();
        assert!((qp.objective(&sol.x) - qp.objective(&full.x)).abs() < 1e-9);
    }

    #[test]
    fn presolve_maps_the_binding_lower_bound_back_with_its_scale() {
        // min ½x² + 2x s.t. x ≥ 0.2, 3x ≥ 0.9 (the binding one): x = 0.3, dual on row 1
        let p = CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(2, 1, &[(0, 0, 1.0), (1, 0, 3.0)]).unwrap();
        let qp = Qp {
            p,
            q: vec![2.0],
            a,
            l: vec![0.2, 0.9],
            u: vec![f64::INFINITY; 2],
        };
        let s = QpSettings {
            eps_abs: 1e-10,
            eps_rel: 1e-10,
            ..Default::default()
        };
        let sol = Presolved::new(Box::new(ClarabelBackend::new(s)))
            .solve(&qp, None)
            .unwrap();
        assert!((sol.x[0] - 0.3).abs() < 1e-8);
        assert_eq!(sol.y[0], 0.0);
        // P x + q + 3 y₁ = 0 → y₁ = −(0.3 + 2)/3
        assert!((sol.y[1] + 2.3 / 3.0).abs() < 1e-8);
        assert!(qp.dual_residual(&sol.x, &sol.y) < 1e-8);
    }

    #[test]
    fn presolve_keeps_an_infeasible_zero_row_for_the_backend() {
        let p = CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(2, 1, &[(0, 0, 1.0)]).unwrap();
        let qp = Qp {
            p,
            q: vec![0.0],
            a,
            l: vec![0.0, 1.0],
            u: vec![1.0, 2.0],
        };
        let pre = Presolve::new(&qp);
        assert_eq!(pre.qp().m(), 2);
        let sol = Presolved::new(Box::new(ClarabelBackend::new(QpSettings::default())))
            .solve(&qp, None)
            .unwrap();
        assert_eq!(sol.status, QpStatus::PrimalInfeasible);
    }

    #[test]
    fn presolve_keeps_crossing_copies_apart_and_merges_later_ones_into_the_first() {
        // x₀ − x₁ in [0, 1]; 2x₀ − 2x₁ in [4, 6] (crosses: kept apart); x₀ − x₁ in [0.5, 3]
        // (merges into the first row); x₀ + x₁ in [0, 1] (another key); 3x₀ + 3x₁ ≤ 9
        let p = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
        let a = CscMatrix::from_triplets(
            5,
            2,
            &[
                (0, 0, 1.0),
                (0, 1, -1.0),
                (1, 0, 2.0),
                (1, 1, -2.0),
                (2, 0, 1.0),
                (2, 1, -1.0),
                (3, 0, 1.0),
                (3, 1, 1.0),
                (4, 0, 3.0),
                (4, 1, 3.0),
            ],
        )
        .unwrap();
        let qp = Qp {
            p,
            q: vec![0.0, 0.0],
            a,
            l: vec![0.0, 4.0, 0.5, 0.0, -1e20],
            u: vec![1.0, 6.0, 3.0, 1.0, 9.0],
        };
        let pre = Presolve::new(&qp);
        assert_eq!(pre.qp().m(), 3);
        assert_eq!(
            pre.fate,
            vec![
                Fate::Row { r: 0, scale: 1.0 },
                Fate::Row { r: 1, scale: 1.0 },
                Fate::Row { r: 0, scale: 1.0 },
                Fate::Row { r: 2, scale: 1.0 },
                Fate::Row { r: 2, scale: 3.0 },
            ]
        );
        assert_eq!((pre.qp().l[0], pre.qp().u[0]), (0.5, 1.0));
        assert_eq!((pre.qp().l[1], pre.qp().u[1]), (4.0, 6.0));
        assert_eq!((pre.qp().l[2], pre.qp().u[2]), (0.0, 1.0));
    }

    #[test]
    fn presolve_maps_warm_starts_to_the_reduced_rows() {
        let qp = example();
        let pre = Presolve::new(&qp);
        let w = pre.reduce_warm(&WarmStart {
            x: vec![],
            y: vec![1.0, 0.5, 0.0, 7.0, -1.0, -2.0],
        });
        // row 0 gets 1·1 + 2·0.5 + 1·0; row 1 gets 1·(−1) + 3·(−2)
        assert_eq!(w.y, vec![2.0, -7.0]);
    }
}
