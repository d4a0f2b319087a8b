//! Sparse linear algebra shared by the backends and by the core's diagnostics: an up-looking
//! `LDLᵀ` factorization of a symmetric matrix given by its upper triangle in CSC ([`SparseLdl`],
//! the QDLDL algorithm: elimination tree, column counts, numeric factorization; natural
//! ordering), split into a symbolic phase ([`LdlSymbolic`], which depends on the pattern only)
//! and a numeric phase. Used as a Cholesky factorization: it refuses a non-positive pivot.
//!
//! [`CholeskyTest`] is the other tool here: a verdict of positive definiteness by `faer`'s sparse
//! Cholesky with the AMD ordering, for the Newton model's shift, where the natural order's fill
//! was the larger cost.
//!
//! The Uzawa backend factorizes `P` with it once per solve; the core's diagnostics factorize the
//! H¹ Gram matrix of the mesh to measure the Lemma 5.6 residual in the dual norm H⁻¹. It is a utility, not a backend:
//! the core may import it.

use crate::qp::CscMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Par, Side, Spec};

const NONE: usize = usize::MAX;

/// A test of positive definiteness by sparse Cholesky (`faer`'s `LLᵀ`, supernodal where it
/// pays, AMD ordering) of a symmetric matrix given by its upper triangle: the symbolic phase is
/// computed for one pattern and reused while the matrices tested have it. [`SparseLdl`]
/// factorizes in the natural order, whose fill grows with couplings far apart in the
/// numbering (a contact model's blocks between two bodies); this is the test to use when only
/// the verdict is wanted.
pub struct CholeskyTest {
    /// The pattern (its column pointers and row indices are the ones tested against).
    sym_mat: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    lvals: Vec<f64>,
    buf: MemBuffer,
}

impl std::fmt::Debug for CholeskyTest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskyTest")
            .field("n", &self.sym_mat.ncols())
            .field("nnz", &self.sym_mat.row_idx().len())
            .finish()
    }
}

impl CholeskyTest {
    /// The symbolic phase for the pattern of `a` (square, CSC upper triangle, sorted rows);
    /// `None` when `a` is not square or has an entry below the diagonal.
    pub fn new(a: &CscMatrix) -> Option<CholeskyTest> {
        let n = a.ncols;
        if a.nrows != n || (0..n).any(|j| (a.colptr[j]..a.colptr[j + 1]).any(|p| a.rowval[p] > j)) {
            return None;
        }
        let sym_mat = SymbolicSparseColMat::new_checked(
            n,
            n,
            a.colptr[..=n].to_vec(),
            None,
            a.rowval[..a.colptr[n]].to_vec(),
        );
        let symbolic = factorize_symbolic_cholesky(
            sym_mat.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .ok()?;
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Spec::default());
        let lvals = vec![0.0; symbolic.len_val()];
        Some(CholeskyTest {
            sym_mat,
            symbolic,
            lvals,
            buf: MemBuffer::try_new(req).ok()?,
        })
    }

    /// Whether `a` has exactly the pattern this test was built for (the values are free).
    pub fn matches(&self, a: &CscMatrix) -> bool {
        let (colptr, rowval) = (self.sym_mat.col_ptr(), self.sym_mat.row_idx());
        let n = self.sym_mat.ncols();
        a.nrows == n
            && a.ncols == n
            && a.colptr.get(..=n) == Some(colptr)
            && a.rowval.get(..rowval.len()) == Some(rowval)
    }

    /// Whether `a` (with this test's pattern: false otherwise) is positive definite: every
    /// value finite and the Cholesky factorization meets no non-positive pivot.
    pub fn is_positive_definite(&mut self, a: &CscMatrix) -> bool {
        let nnz = self.sym_mat.row_idx().len();
        if !self.matches(a) || a.nzval[..nnz].iter().any(|v| !v.is_finite()) {
            return false;
        }
        let mat = SparseColMatRef::new(self.sym_mat.as_ref(), &a.nzval[..nnz]);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.lvals,
                mat,
                Side::Upper,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.buf),
                Spec::default(),
            )
            .is_ok()
    }
}

/// Symbolic phase of [`SparseLdl`] for one sparsity pattern: the elimination tree and the column
/// pointers of `L` (from the column counts), together with the pattern (`ncols`, `colptr`,
/// `rowval` of the upper triangle) it was computed for. It depends on the pattern only, never on
/// the values.
#[derive(Clone, Debug, PartialEq)]
pub struct LdlSymbolic {
    n: usize,
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    etree: Vec<usize>,
    lp: Vec<usize>,
}

impl LdlSymbolic {
    /// Elimination tree and column counts of the symmetric matrix whose upper triangle is `a`
    /// (square, CSC, sorted rows). Returns `None` when `a` is not square or has an entry below
    /// the diagonal.
    pub fn new(a: &CscMatrix) -> Option<LdlSymbolic> {
        let n = a.ncols;
        if a.nrows != n {
            return None;
        }
        let mut work = vec![NONE; n];
        let mut lnz = vec![0usize; n];
        let mut etree = vec![NONE; n];
        for j in 0..n {
            work[j] = j;
            for p in a.colptr[j]..a.colptr[j + 1] {
                let mut i = a.rowval[p];
                if i > j {
                    return None;
                }
                while work[i] != j {
                    if etree[i] == NONE {
                        etree[i] = j;
                    }
                    lnz[i] += 1;
                    work[i] = j;
                    i = etree[i];
                    if i == NONE {
                        break;
                    }
                }
            }
        }
        let mut lp = vec![0usize; n + 1];
        for i in 0..n {
            lp[i + 1] = lp[i] + lnz[i];
        }
        Some(LdlSymbolic {
            n,
            colptr: a.colptr[..=n].to_vec(),
            rowval: a.rowval[..a.colptr[n]].to_vec(),
            etree,
            lp,
        })
    }

    /// Whether `a` has exactly the pattern this symbolic phase was computed for (same shape,
    /// column pointers and row indices; the values are free).
    pub fn matches(&self, a: &CscMatrix) -> bool {
        a.nrows == self.n
            && a.ncols == self.n
            && a.colptr.len() == self.n + 1
            && a.colptr == self.colptr
            && a.rowval.get(..self.colptr[self.n]) == Some(&self.rowval[..])
    }

    /// Number of entries of `L` below the diagonal.
    pub fn nnz_l(&self) -> usize {
        self.lp[self.n]
    }
}

/// Sparse `LDLᵀ` factorization of a symmetric matrix given by its upper triangle (QDLDL
/// algorithm, natural ordering). Used as a Cholesky: it fails unless every pivot is positive.
#[derive(Clone, Debug)]
pub struct SparseLdl {
    n: usize,
    lp: Vec<usize>,
    li: Vec<usize>,
    lx: Vec<f64>,
    dinv: Vec<f64>,
}

impl SparseLdl {
    /// Factorizes the matrix whose upper triangle is `a` (square, CSC, sorted rows). Returns
    /// `None` when `a` is not square, has an entry below the diagonal, or a pivot is not
    /// positive (relative to the largest diagonal entry) or not finite. Same as
    /// [`LdlSymbolic::new`] followed by [`SparseLdl::numeric`].
    pub fn factor(a: &CscMatrix) -> Option<SparseLdl> {
        SparseLdl::numeric(a, &LdlSymbolic::new(a)?)
    }

    /// Numeric phase: factorizes `a` with the symbolic phase `sym` of its pattern, skipping the
    /// elimination tree and column counts. The result is bit-identical to [`SparseLdl::factor`]
    /// of `a`. Returns `None` when `a` does not have the pattern of `sym`
    /// ([`LdlSymbolic::matches`]) or a pivot is not positive (relative to the largest diagonal
    /// entry) or not finite.
    pub fn numeric(a: &CscMatrix, sym: &LdlSymbolic) -> Option<SparseLdl> {
        if !sym.matches(a) {
            return None;
        }
        let n = sym.n;
        let etree = &sym.etree;
        let lp = sym.lp.clone();
        let nnz = lp[n];
        let mut li = vec![0usize; nnz];
        let mut lx = vec![0.0; nnz];
        let mut d = vec![0.0; n];
        let mut dinv = vec![0.0; n];
        let mut y_markers = vec![false; n];
        let mut y_idx = vec![0usize; n];
        let mut elim = vec![0usize; n];
        let mut next_space = lp[..n].to_vec();
        let mut y_vals = vec![0.0; n];
        let max_diag = (0..n)
            .flat_map(|j| (a.colptr[j]..a.colptr[j + 1]).filter(move |&p| a.rowval[p] == j))
            .fold(0.0f64, |m, p| m.max(a.nzval[p].abs()));
        let pivot_tol = 1e-14 * max_diag.max(f64::MIN_POSITIVE);
        for k in 0..n {
            let mut nnz_y = 0;
            d[k] = 0.0;
            for p in a.colptr[k]..a.colptr[k + 1] {
                let b = a.rowval[p];
                if b == k {
                    d[k] += a.nzval[p];
                    continue;
                }
                y_vals[b] = a.nzval[p];
                if !y_markers[b] {
                    y_markers[b] = true;
                    elim[0] = b;
                    let mut nnz_e = 1;
                    let mut next = etree[b];
                    while next != NONE && next < k {
                        if y_markers[next] {
                            break;
                        }
                        y_markers[next] = true;
                        elim[nnz_e] = next;
                        nnz_e += 1;
                        next = etree[next];
                    }
                    while nnz_e > 0 {
                        nnz_e -= 1;
                        y_idx[nnz_y] = elim[nnz_e];
                        nnz_y += 1;
                    }
                }
            }
            for i in (0..nnz_y).rev() {
                let c = y_idx[i];
                let tmp = next_space[c];
                let yc = y_vals[c];
                for j in lp[c]..tmp {
                    y_vals[li[j]] -= lx[j] * yc;
                }
                li[tmp] = k;
                lx[tmp] = yc * dinv[c];
                d[k] -= yc * lx[tmp];
                next_space[c] += 1;
                y_vals[c] = 0.0;
                y_markers[c] = false;
            }
            if !(d[k].is_finite() && d[k] > pivot_tol) {
                return None;
            }
            dinv[k] = 1.0 / d[k];
        }
        Some(SparseLdl {
            n,
            lp,
            li,
            lx,
            dinv,
        })
    }

    /// Solves `S x = b` in place.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        for i in 0..self.n {
            let xi = x[i];
            for j in self.lp[i]..self.lp[i + 1] {
                x[self.li[j]] -= self.lx[j] * xi;
            }
        }
        for i in 0..self.n {
            x[i] *= self.dinv[i];
        }
        for i in (0..self.n).rev() {
            let mut s = x[i];
            for j in self.lp[i]..self.lp[i + 1] {
                s -= self.lx[j] * x[self.li[j]];
            }
            x[i] = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ldl_solves_a_banded_system() {
        // Tridiagonal SPD with an extra corner entry.
        let n = 6;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 4.0));
            if i + 1 < n {
                t.push((i, i + 1, -1.0));
            }
        }
        t.push((0, n - 1, 0.5));
        let s = CscMatrix::from_triplets(n, n, &t).unwrap();
        let f = SparseLdl::factor(&s).unwrap();
        let b: Vec<f64> = (0..n).map(|i| i as f64 - 2.0).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x);
        let mut r = vec![0.0; n];
        s.sym_upper_mul_add(1.0, &x, &mut r);
        for i in 0..n {
            assert!((r[i] - b[i]).abs() < 1e-12);
        }
        // Indefinite → None.
        let bad = CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (0, 1, 2.0), (1, 1, 1.0)]).unwrap();
        assert!(SparseLdl::factor(&bad).is_none());
    }

    /// The Cholesky test gives `SparseLdl`'s verdict on a path-graph matrix with couplings
    /// between far-apart vertices (a contact model's shape) shifted by `−f·λ_min` (`λ_min`
    /// bisected on the LDL's verdict): definite for `f < 1`, not for `f > 1`, away from the
    /// threshold; and it refuses another pattern, a value that is not finite and a matrix
    /// that is not an upper triangle.
    #[test]
    fn cholesky_test_agrees_with_the_ldl_on_definite_and_indefinite_matrices() {
        let n = 40;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 2.0));
            if i + 1 < n {
                t.push((i, i + 1, -1.0));
            }
        }
        // far couplings: (i, n − 1 − i) with a weight that keeps the matrix symmetric
        for i in 0..n / 4 {
            t.push((i, n - 1 - i, -0.3));
            t.push((i, i, 0.3));
            t.push((n - 1 - i, n - 1 - i, 0.3));
        }
        let base = CscMatrix::from_triplets(n, n, &t).unwrap();
        let mut test = CholeskyTest::new(&base).unwrap();
        // the smallest eigenvalue of `base`, by the LDL's verdict bisected on the shift
        let pd_ldl = |shift: f64| {
            let mut m = base.clone();
            for j in 0..n {
                for p in m.colptr[j]..m.colptr[j + 1] {
                    if m.rowval[p] == j {
                        m.nzval[p] -= shift;
                    }
                }
            }
            (SparseLdl::factor(&m).is_some(), m)
        };
        let (mut lo, mut hi) = (0.0, 4.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if pd_ldl(mid).0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let lmin = 0.5 * (lo + hi);
        assert!(lmin > 0.0 && lmin < 1.0, "{lmin}");
        for f in [0.0, 0.5, 0.9, 0.99, 1.01, 1.1, 1.5, 3.0] {
            let (ldl, m) = pd_ldl(f * lmin);
            assert_eq!(ldl, f < 1.0, "shift {f}·λ_min");
            assert_eq!(test.is_positive_definite(&m), ldl, "shift {f}·λ_min");
        }
        let mut nan = base.clone();
        nan.nzval[0] = f64::NAN;
        assert!(!test.is_positive_definite(&nan));
        let other = CscMatrix::from_triplets(n, n, &[(0, 0, 1.0)]).unwrap();
        assert!(!test.matches(&other) && !test.is_positive_definite(&other));
        // below the diagonal: not an upper triangle
        let lower =
            CscMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 0, 0.5), (1, 1, 1.0)]).unwrap();
        assert!(CholeskyTest::new(&lower).is_none());
    }
}
