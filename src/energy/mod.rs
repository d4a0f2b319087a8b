//! Energies `J`: value, gradient and a sparse Hessian (optionally projected to be positive
//! semi-definite, element by element).
//!
//! All functions take the flat position vector `x` (`dim` coordinates per vertex) and use the
//! degree-of-freedom numbering `dim*v + k` of [`crate::mesh`].

#[cfg(test)]
mod fd_test;
pub mod gas;
pub mod gravity;
pub mod membrane;
pub mod neo_hookean;

pub use gas::GasEnergy;
pub use gravity::Gravity;
pub use membrane::MembraneEnergy;
pub use neo_hookean::NeoHookean2d;

/// A rank-one Hessian term `coef · w wᵀ` (`coef ≥ 0`), kept out of the sparse block so that
/// `P` stays sparse: the QP assembly turns it into one auxiliary variable `s = w·d` and one
/// equality row (SPEC §2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RankOne {
    /// Non-negative coefficient.
    pub coef: f64,
    /// Sparse vector `w` as `(dof, value)` pairs.
    pub w: Vec<(usize, f64)>,
}

/// A Hessian being assembled: sparse triplets (BOTH triangles, duplicates summed by the
/// consumer) plus rank-one terms. The represented matrix is
/// `Σ triplets + Σ_k coef_k w_k w_kᵀ`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hessian {
    /// `(row dof, col dof, value)`, symmetric: `(i, j, v)` and `(j, i, v)` both present for
    /// `i ≠ j`.
    pub triplets: Vec<(usize, usize, f64)>,
    /// Rank-one terms.
    pub rank_one: Vec<RankOne>,
}

impl Hessian {
    /// Adds the symmetric block `m` (size `k·dim`) coupling the listed vertices.
    pub fn add_block(&mut self, dim: usize, vertices: &[usize], m: &nalgebra::DMatrix<f64>) {
        for (a, &va) in vertices.iter().enumerate() {
            for (b, &vb) in vertices.iter().enumerate() {
                for i in 0..dim {
                    for j in 0..dim {
                        let v = m[(dim * a + i, dim * b + j)];
                        if v != 0.0 {
                            self.triplets.push((dim * va + i, dim * vb + j, v));
                        }
                    }
                }
            }
        }
    }

    /// Dense `n × n` matrix (tests and small problems).
    pub fn to_dense(&self, n: usize) -> nalgebra::DMatrix<f64> {
        let mut h = nalgebra::DMatrix::zeros(n, n);
        for &(i, j, v) in &self.triplets {
            h[(i, j)] += v;
        }
        for r in &self.rank_one {
            for &(i, a) in &r.w {
                for &(j, b) in &r.w {
                    h[(i, j)] += r.coef * a * b;
                }
            }
        }
        h
    }
}

/// One term of the total energy.
pub trait Energy: Send + Sync {
    /// Short name used in outputs.
    fn name(&self) -> &str;
    /// `J(x)`; `f64::INFINITY` where undefined (inverted triangle, non-positive gas area).
    fn value(&self, x: &[f64]) -> f64;
    /// `g += ∇J(x)`.
    fn add_gradient(&self, x: &[f64], g: &mut [f64]);
    /// Adds the Hessian at `x`. With `projected = false` the exact Hessian (for tests); with
    /// `projected = true` every element's contribution is replaced by its positive
    /// semi-definite part (what the QP uses).
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian);
}

/// Sum of energy terms.
#[derive(Default)]
pub struct TotalEnergy {
    /// The terms.
    pub terms: Vec<Box<dyn Energy>>,
}

impl TotalEnergy {
    /// `J(x) = Σ terms`.
    pub fn value(&self, x: &[f64]) -> f64 {
        self.terms.iter().map(|t| t.value(x)).sum()
    }
    /// `∇J(x)`.
    pub fn gradient(&self, x: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; x.len()];
        for t in &self.terms {
            t.add_gradient(x, &mut g);
        }
        g
    }
    /// The (projected) Hessian.
    pub fn hessian(&self, x: &[f64], projected: bool) -> Hessian {
        let mut h = Hessian::default();
        for t in &self.terms {
            t.add_hessian(x, projected, &mut h);
        }
        h
    }
}
