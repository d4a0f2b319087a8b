//! The QP standard form `min ½xᵀPx + qᵀx, l ≤ Ax ≤ u` and a minimal CSC matrix.

use crate::backend::QpError;

/// A sparse matrix in compressed sparse column form. Row indices within a column are sorted
/// and unique.
#[derive(Clone, Debug, PartialEq)]
pub struct CscMatrix {
    /// Number of rows.
    pub nrows: usize,
    /// Number of columns.
    pub ncols: usize,
    /// Column pointers, length `ncols + 1`.
    pub colptr: Vec<usize>,
    /// Row index of each stored entry.
    pub rowval: Vec<usize>,
    /// Value of each stored entry.
    pub nzval: Vec<f64>,
}

impl CscMatrix {
    /// An all-zero `nrows × ncols` matrix.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        CscMatrix {
            nrows,
            ncols,
            colptr: vec![0; ncols + 1],
            rowval: Vec::new(),
            nzval: Vec::new(),
        }
    }

    /// Builds a matrix from `(row, col, value)` triplets; duplicates are summed, explicit zeros
    /// kept (the sparsity pattern then does not depend on values). Errors name the first
    /// out-of-range or non-finite triplet.
    pub fn from_triplets(
        nrows: usize,
        ncols: usize,
        triplets: &[(usize, usize, f64)],
    ) -> Result<Self, QpError> {
        for (k, &(i, j, v)) in triplets.iter().enumerate() {
            if i >= nrows || j >= ncols {
                return Err(QpError::IndexOutOfRange {
                    what: "triplet",
                    index: k,
                    row: i,
                    col: j,
                    nrows,
                    ncols,
                });
            }
            if !v.is_finite() {
                return Err(QpError::NotFinite {
                    what: "matrix triplet",
                    index: k,
                    value: v,
                });
            }
        }
        let mut count = vec![0usize; ncols + 1];
        for &(_, j, _) in triplets {
            count[j + 1] += 1;
        }
        for j in 0..ncols {
            count[j + 1] += count[j];
        }
        let mut next = count.clone();
        let mut rows = vec![0usize; triplets.len()];
        let mut vals = vec![0f64; triplets.len()];
        for &(i, j, v) in triplets {
            let p = next[j];
            rows[p] = i;
            vals[p] = v;
            next[j] += 1;
        }
        let mut colptr = Vec::with_capacity(ncols + 1);
        let mut rowval = Vec::with_capacity(triplets.len());
        let mut nzval = Vec::with_capacity(triplets.len());
        colptr.push(0);
        let mut perm: Vec<usize> = Vec::new();
        for j in 0..ncols {
            perm.clear();
            perm.extend(count[j]..count[j + 1]);
            perm.sort_by_key(|&p| rows[p]);
            for &p in &perm {
                if rowval.len() > colptr[j] && *rowval.last().unwrap() == rows[p] {
                    *nzval.last_mut().unwrap() += vals[p];
                } else {
                    rowval.push(rows[p]);
                    nzval.push(vals[p]);
                }
            }
            colptr.push(rowval.len());
        }
        Ok(CscMatrix {
            nrows,
            ncols,
            colptr,
            rowval,
            nzval,
        })
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.nzval.len()
    }

    /// `y += alpha · M x`.
    pub fn mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        for j in 0..self.ncols {
            let xj = alpha * x[j];
            if xj != 0.0 {
                for p in self.colptr[j]..self.colptr[j + 1] {
                    y[self.rowval[p]] += self.nzval[p] * xj;
                }
            }
        }
    }

    /// `y += alpha · Mᵀ x`.
    pub fn tr_mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        for j in 0..self.ncols {
            let mut s = 0.0;
            for p in self.colptr[j]..self.colptr[j + 1] {
                s += self.nzval[p] * x[self.rowval[p]];
            }
            y[j] += alpha * s;
        }
    }

    /// `y += alpha · S x` where `self` holds the upper triangle of the symmetric matrix `S`.
    pub fn sym_upper_mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        for j in 0..self.ncols {
            for p in self.colptr[j]..self.colptr[j + 1] {
                let i = self.rowval[p];
                let v = alpha * self.nzval[p];
                y[i] += v * x[j];
                if i != j {
                    y[j] += v * x[i];
                }
            }
        }
    }

    /// The transpose, in CSC.
    pub fn transpose(&self) -> CscMatrix {
        let mut t: Vec<(usize, usize, f64)> = Vec::with_capacity(self.nnz());
        for j in 0..self.ncols {
            for p in self.colptr[j]..self.colptr[j + 1] {
                t.push((j, self.rowval[p], self.nzval[p]));
            }
        }
        CscMatrix::from_triplets(self.ncols, self.nrows, &t).expect("transpose of a valid matrix")
    }

    /// Dense copy (row-major `nrows × ncols`), for tests and small problems.
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.ncols]; self.nrows];
        for j in 0..self.ncols {
            for p in self.colptr[j]..self.colptr[j + 1] {
                d[self.rowval[p]][j] += self.nzval[p];
            }
        }
        d
    }
}

/// A QP in standard form `min ½xᵀPx + qᵀx  s.t.  l ≤ Ax ≤ u`.
#[derive(Clone, Debug, PartialEq)]
pub struct Qp {
    /// Upper triangle (with diagonal) of the symmetric PSD matrix `P`, `n × n`.
    pub p: CscMatrix,
    /// Linear cost, length `n`.
    pub q: Vec<f64>,
    /// Constraint matrix, `m × n`.
    pub a: CscMatrix,
    /// Lower bounds, length `m` (`f64::NEG_INFINITY` for none).
    pub l: Vec<f64>,
    /// Upper bounds, length `m` (`f64::INFINITY` for none).
    pub u: Vec<f64>,
}

impl Qp {
    /// Number of variables `n`.
    pub fn n(&self) -> usize {
        self.q.len()
    }

    /// Number of rows `m`.
    pub fn m(&self) -> usize {
        self.l.len()
    }

    /// Checks dimensions, finiteness, `l ≤ u`, and that `p` is upper triangular. The error names
    /// the offending row, column or entry.
    pub fn validate(&self) -> Result<(), QpError> {
        let n = self.q.len();
        let m = self.l.len();
        if self.p.nrows != n || self.p.ncols != n {
            return Err(QpError::DimensionMismatch {
                what: "P",
                expected: (n, n),
                found: (self.p.nrows, self.p.ncols),
            });
        }
        if self.a.ncols != n || self.a.nrows != m {
            return Err(QpError::DimensionMismatch {
                what: "A",
                expected: (m, n),
                found: (self.a.nrows, self.a.ncols),
            });
        }
        if self.u.len() != m {
            return Err(QpError::DimensionMismatch {
                what: "u",
                expected: (m, 1),
                found: (self.u.len(), 1),
            });
        }
        for (i, v) in self.q.iter().enumerate() {
            if !v.is_finite() {
                return Err(QpError::NotFinite {
                    what: "q",
                    index: i,
                    value: *v,
                });
            }
        }
        for (k, v) in self.p.nzval.iter().chain(self.a.nzval.iter()).enumerate() {
            if !v.is_finite() {
                return Err(QpError::NotFinite {
                    what: "P or A entry",
                    index: k,
                    value: *v,
                });
            }
        }
        for j in 0..n {
            for p in self.p.colptr[j]..self.p.colptr[j + 1] {
                if self.p.rowval[p] > j {
                    return Err(QpError::NotUpperTriangular {
                        row: self.p.rowval[p],
                        col: j,
                    });
                }
            }
        }
        for i in 0..m {
            let (l, u) = (self.l[i], self.u[i]);
            if l.is_nan() || u.is_nan() || l > u || l == f64::INFINITY || u == f64::NEG_INFINITY {
                return Err(QpError::InvalidBounds { row: i, l, u });
            }
        }
        Ok(())
    }

    /// Objective value `½xᵀPx + qᵀx`.
    pub fn objective(&self, x: &[f64]) -> f64 {
        let mut px = vec![0.0; x.len()];
        self.p.sym_upper_mul_add(1.0, x, &mut px);
        x.iter().zip(&px).map(|(a, b)| 0.5 * a * b).sum::<f64>()
            + x.iter().zip(&self.q).map(|(a, b)| a * b).sum::<f64>()
    }

    /// Largest bound violation `max_i max(l_i − (Ax)_i, (Ax)_i − u_i, 0)`.
    pub fn primal_residual(&self, x: &[f64]) -> f64 {
        let mut ax = vec![0.0; self.m()];
        self.a.mul_add(1.0, x, &mut ax);
        ax.iter()
            .zip(self.l.iter().zip(&self.u))
            .map(|(v, (l, u))| (l - v).max(v - u).max(0.0))
            .fold(0.0, f64::max)
    }

    /// Largest entry of `|Px + q + Aᵀy|`.
    pub fn dual_residual(&self, x: &[f64], y: &[f64]) -> f64 {
        let mut r = self.q.clone();
        self.p.sym_upper_mul_add(1.0, x, &mut r);
        self.a.tr_mul_add(1.0, y, &mut r);
        r.iter().fold(0.0, |m, v| m.max(v.abs()))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// min ½(x0² + x1²) − x0 − x1  s.t.  x0 + x1 ≤ 1, 0.8 ≤ x0 ≤ 5, and a free row on x1
    /// (shared by the backends' unit tests).
    pub(crate) fn small_qp() -> Qp {
        let p = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
        let a =
            CscMatrix::from_triplets(3, 2, &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0), (2, 1, 1.0)])
                .unwrap();
        Qp {
            p,
            q: vec![-1.0, -1.0],
            a,
            l: vec![f64::NEG_INFINITY, 0.8, f64::NEG_INFINITY],
            u: vec![1.0, 5.0, f64::INFINITY],
        }
    }

    /// `b` solves [`small_qp`]: x = (0.8, 0.2), the crate's dual signs (upper bound active →
    /// y ≥ 0, lower → y ≤ 0, a free row 0), dual residual below `dual_tol`. Returns the
    /// solution (shared by the backends' unit tests).
    pub(crate) fn assert_solves_small_qp(
        b: &mut dyn crate::backend::QpBackend,
        dual_tol: f64,
    ) -> crate::backend::QpSolution {
        let qp = small_qp();
        let s = b.solve(&qp, None).unwrap();
        assert_eq!(s.status, crate::backend::QpStatus::Solved);
        // The unconstrained optimum (1, 1) violates x0 + x1 ≤ 1; (0.5, 0.5) violates x0 ≥ 0.8.
        assert!(
            (s.x[0] - 0.8).abs() < 1e-7 && (s.x[1] - 0.2).abs() < 1e-7,
            "{:?}",
            s.x
        );
        assert!(qp.dual_residual(&s.x, &s.y) < dual_tol);
        assert!(s.y[0] > 0.0, "upper bound active → y ≥ 0: {:?}", s.y);
        assert!(s.y[1] < 0.0, "lower bound active → y ≤ 0: {:?}", s.y);
        assert_eq!(s.y[2], 0.0);
        s
    }

    /// `b` solves [`small_qp`] with row 2 an equality (x1 = 0.1: x = (0.9, 0.1)), and does not
    /// call the QP solved once x0 ≥ 0.95 makes it infeasible.
    pub(crate) fn assert_equality_and_infeasible(b: &mut dyn crate::backend::QpBackend) {
        use crate::backend::QpStatus;
        let mut qp = small_qp();
        qp.l[2] = 0.1;
        qp.u[2] = 0.1;
        let s = b.solve(&qp, None).unwrap();
        assert_eq!(s.status, QpStatus::Solved);
        assert!(
            (s.x[0] - 0.9).abs() < 1e-7 && (s.x[1] - 0.1).abs() < 1e-7,
            "{:?}",
            s.x
        );
        assert!(qp.dual_residual(&s.x, &s.y) < 1e-7);
        qp.l[1] = 0.95;
        let s = b.solve(&qp, None).unwrap();
        assert_ne!(s.status, QpStatus::Solved);
    }

    /// `b` rejects `l > u` with the named error.
    pub(crate) fn assert_bad_bounds_rejected(b: &mut dyn crate::backend::QpBackend) {
        let mut qp = small_qp();
        qp.l[1] = 6.0;
        assert_eq!(
            b.solve(&qp, None).unwrap_err(),
            QpError::InvalidBounds {
                row: 1,
                l: 6.0,
                u: 5.0
            }
        );
    }

    #[test]
    fn triplets_sum_duplicates_and_sort() {
        let m =
            CscMatrix::from_triplets(3, 2, &[(2, 0, 1.0), (0, 0, 2.0), (2, 0, 3.0), (1, 1, -1.0)])
                .unwrap();
        assert_eq!(m.colptr, vec![0, 2, 3]);
        assert_eq!(m.rowval, vec![0, 2, 1]);
        assert_eq!(m.nzval, vec![2.0, 4.0, -1.0]);
        let mut y = vec![0.0; 3];
        m.mul_add(1.0, &[1.0, 2.0], &mut y);
        assert_eq!(y, vec![2.0, -2.0, 4.0]);
        let mut z = vec![0.0; 2];
        m.tr_mul_add(1.0, &[1.0, 1.0, 1.0], &mut z);
        assert_eq!(z, vec![6.0, -1.0]);
    }

    #[test]
    fn out_of_range_triplet_is_named() {
        let e = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (2, 1, 1.0)]).unwrap_err();
        assert!(e.to_string().contains("triplet 1"), "{e}");
    }

    #[test]
    fn symmetric_upper_product_matches_dense() {
        // S = [[2, 1], [1, 3]] stored as its upper triangle.
        let s = CscMatrix::from_triplets(2, 2, &[(0, 0, 2.0), (0, 1, 1.0), (1, 1, 3.0)]).unwrap();
        let mut y = vec![0.0; 2];
        s.sym_upper_mul_add(1.0, &[1.0, -1.0], &mut y);
        assert_eq!(y, vec![1.0, -2.0]);
    }
}
