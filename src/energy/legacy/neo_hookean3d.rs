//! TEMPORARY: the code before the energy/ restructuring, kept (test builds only) for the
//! bit-identity checks of [`super`]; removed when the restructuring is done.
//!
//! Compressible neo-Hookean energy of P1 tetrahedra in 3D (the 3D counterpart of
//! [`super::neo_hookean`]; see Pantz 2008, §7, and e.g. Bonet & Wood, *Nonlinear Continuum
//! Mechanics for FEA*, §6.4.3).
//!
//! With `F = Ds Dm⁻¹` (`Ds = [x1 − x0, x2 − x0, x3 − x0]`, `Dm` the same in the reference
//! configuration) and `J = det F`:
//!
//! ```text
//! W(F) = μ/2 (|F|² − 3) − μ ln J + λ/2 (ln J)²,        J(x) = Σ_T |T_ref| W(F_T),
//! ```
//!
//! and `J(x) = +∞` as soon as one tetrahedron has `det F ≤ 0`. The first Piola–Kirchhoff
//! stress and its derivative are
//!
//! ```text
//! P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ,
//! ∂P_ij/∂F_kl = μ δ_ik δ_jl + (μ − λ ln J) F⁻ᵀ_il F⁻ᵀ_kj + λ F⁻ᵀ_ij F⁻ᵀ_kl.
//! ```
//!
//! Writing `F_kl = Σ_a x_{a,k} G_{a,l}` with `G = [−(B_0+B_1+B_2); B_0; B_1; B_2]`
//! (`B = Dm⁻¹`, rows `B_m`), the element gradient is `∂/∂x_{a,c} = |T| Σ_l P_cl G_al` and the
//! 12×12 element Hessian is `|T| Σ_{l,n} ∂P_cl/∂F_dn G_al G_bn` at dofs `(3a + c, 3b + d)`.
//! With `projected = true` each element Hessian's negative eigenvalues are clamped to zero
//! (symmetric eigendecomposition, [`project_psd`]); an element Hessian that is already
//! positive semi-definite is kept as is.
//!
//! **Reference orientation.** [`NeoHookean3d::new`] stores every tetrahedron positively
//! oriented (`det Dm > 0`): a tetrahedron listed with negative reference volume has its
//! vertices 1 and 2 swapped (the element, its energy and its reference volume are unchanged;
//! only the stored vertex order differs). A degenerate one (`|det Dm| ≤ 10⁻¹²·ℓ³`, `ℓ` its
//! longest reference edge, or a non-finite `det Dm`) cannot be oriented and is rejected with a
//! [`DegenerateTet`] error naming it.

use crate::energy::{
    chunked_sum, chunked_triplets, par_scatter, push_block, Energy, Hessian, TermKind,
};
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimSub, Matrix3, SMatrix, U1};
use thiserror::Error;

const DIM: usize = 3;

/// 12×12 element Hessian (4 vertices × 3 dofs).
pub(crate) type Matrix12 = SMatrix<f64, 12, 12>;

/// A reference tetrahedron of (numerically) zero volume: it has no orientation and no `Dm⁻¹`.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("tetrahedron {index} {tet:?} is degenerate (reference volume = {volume:e})")]
pub struct DegenerateTet {
    /// Index of the tetrahedron in the list passed to [`NeoHookean3d::new`].
    pub index: usize,
    /// Its vertices.
    pub tet: [usize; 4],
    /// Its signed reference volume `det Dm / 6`.
    pub volume: f64,
}

/// Compressible neo-Hookean energy of a set of tetrahedra (3D).
#[derive(Clone, Debug)]
pub struct NeoHookean3d {
    /// Tetrahedra `[v0, v1, v2, v3]`, positively oriented in the reference configuration.
    pub tets: Vec<[usize; 4]>,
    /// `Dm⁻¹` per tetrahedron.
    pub dm_inv: Vec<Matrix3<f64>>,
    /// Reference volume per tetrahedron (positive).
    pub volume: Vec<f64>,
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ`.
    pub lambda: f64,
}

impl NeoHookean3d {
    /// Builds the energy from reference positions `x_ref` (flat, 3D). Negatively oriented
    /// tetrahedra are reordered (vertices 1 and 2 swapped); a degenerate one is an error.
    pub fn new(
        mut tets: Vec<[usize; 4]>,
        x_ref: &[f64],
        mu: f64,
        lambda: f64,
    ) -> Result<Self, DegenerateTet> {
        let mut dm_inv = Vec::with_capacity(tets.len());
        let mut volume = Vec::with_capacity(tets.len());
        for (index, t) in tets.iter_mut().enumerate() {
            let mut dm = ds(x_ref, t);
            let det = dm.determinant();
            let l = (0..4)
                .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
                .map(|(a, b)| {
                    (0..DIM)
                        .map(|k| (x_ref[DIM * t[b] + k] - x_ref[DIM * t[a] + k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max);
            if !det.is_finite() || det.abs() <= 1e-12 * l * l * l {
                return Err(DegenerateTet {
                    index,
                    tet: *t,
                    volume: det / 6.0,
                });
            }
            if det < 0.0 {
                t.swap(1, 2);
                dm.swap_columns(0, 1);
            }
            volume.push(det.abs() / 6.0);
            dm_inv.push(dm.try_inverse().ok_or(DegenerateTet {
                index,
                tet: *t,
                volume: det / 6.0,
            })?);
        }
        Ok(Self {
            tets,
            dm_inv,
            volume,
            mu,
            lambda,
        })
    }

    fn grad_op(&self, e: usize) -> [[f64; 3]; 4] {
        let b = &self.dm_inv[e];
        let mut g = [[0.0; 3]; 4];
        for l in 0..DIM {
            for m in 0..DIM {
                g[m + 1][l] = b[(m, l)];
            }
            g[0][l] = -(b[(0, l)] + b[(1, l)] + b[(2, l)]);
        }
        g
    }

    /// Deformation gradient of element `e`.
    pub fn deformation_gradient(&self, x: &[f64], e: usize) -> Matrix3<f64> {
        ds(x, &self.tets[e]) * self.dm_inv[e]
    }

    fn energy_density(&self, f: &Matrix3<f64>) -> f64 {
        let j = f.determinant();
        if j <= 0.0 {
            return f64::INFINITY;
        }
        let lj = j.ln();
        0.5 * self.mu * (f.norm_squared() - 3.0) - self.mu * lj + 0.5 * self.lambda * lj * lj
    }

    /// Exact 12×12 element Hessian, or `None` if inverted.
    fn element_hessian(&self, x: &[f64], e: usize) -> Option<Matrix12> {
        let f = self.deformation_gradient(x, e);
        let j = f.determinant();
        if j <= 0.0 {
            return None;
        }
        let lj = j.ln();
        let fit = f.try_inverse()?.transpose();
        let (mu, la) = (self.mu, self.lambda);
        // ∂P_cl/∂F_dn at [DIM·c + l][DIM·d + n]
        let mut dp = [[0.0; DIM * DIM]; DIM * DIM];
        for c in 0..DIM {
            for l in 0..DIM {
                for d in 0..DIM {
                    for n in 0..DIM {
                        let delta = if c == d && l == n { mu } else { 0.0 };
                        dp[DIM * c + l][DIM * d + n] = delta
                            + (mu - la * lj) * fit[(c, n)] * fit[(d, l)]
                            + la * fit[(c, l)] * fit[(d, n)];
                    }
                }
            }
        }
        let g = self.grad_op(e);
        // t[DIM·c + l][DIM·b + d] = Σ_n ∂P_cl/∂F_dn G_bn
        let mut t = [[0.0; 4 * DIM]; DIM * DIM];
        for (cl, trow) in t.iter_mut().enumerate() {
            for b in 0..4 {
                for d in 0..DIM {
                    trow[DIM * b + d] = (0..DIM).map(|n| dp[cl][DIM * d + n] * g[b][n]).sum();
                }
            }
        }
        let mut h = Matrix12::zeros();
        for a in 0..4 {
            for c in 0..DIM {
                for bd in 0..4 * DIM {
                    let s: f64 = (0..DIM).map(|l| g[a][l] * t[DIM * c + l][bd]).sum();
                    h[(DIM * a + c, bd)] = self.volume[e] * s;
                }
            }
        }
        Some((h + h.transpose()) * 0.5)
    }
}

fn ds(x: &[f64], t: &[usize; 4]) -> Matrix3<f64> {
    Matrix3::from_fn(|k, m| x[DIM * t[m + 1] + k] - x[DIM * t[0] + k])
}

/// Replaces the symmetric matrix `m` by its positive semi-definite part when it has a negative
/// eigenvalue (eigendecomposition `m = Q Λ Qᵀ`, then `Q max(Λ, 0) Qᵀ`, symmetrized); leaves it
/// untouched otherwise. Shared by the 3D energies.
pub(crate) fn project_psd<const N: usize>(m: &mut SMatrix<f64, N, N>)
where
    Const<N>: DimSub<U1>,
    DefaultAllocator: Allocator<Const<N>, DimDiff<Const<N>, U1>> + Allocator<DimDiff<Const<N>, U1>>,
{
    let eig = m.symmetric_eigen();
    if eig.eigenvalues.min() < 0.0 {
        let d = eig.eigenvalues.map(|v| v.max(0.0));
        let p = eig.eigenvectors
            * SMatrix::<f64, N, N>::from_diagonal(&d)
            * eig.eigenvectors.transpose();
        *m = (p + p.transpose()) * 0.5;
    }
}

impl Energy for NeoHookean3d {
    fn name(&self) -> &str {
        "neo_hookean3d"
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        chunked_sum(self.tets.len(), |r| {
            let mut s = 0.0;
            for e in r {
                let w = self.energy_density(&self.deformation_gradient(x, e));
                if w == f64::INFINITY {
                    return f64::INFINITY;
                }
                s += self.volume[e] * w;
            }
            s
        })
    }

    /// Inverted elements (energy `+∞`) contribute nothing.
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        par_scatter(
            self.tets.len(),
            g,
            |e| {
                let f = self.deformation_gradient(x, e);
                let j = f.determinant();
                if j <= 0.0 {
                    return None;
                }
                let fit = f.try_inverse()?.transpose();
                let p = (f - fit) * self.mu + fit * (self.lambda * j.ln());
                let gop = self.grad_op(e);
                let mut ge = [[0.0; DIM]; 4];
                for (a, gea) in ge.iter_mut().enumerate() {
                    for (c, gac) in gea.iter_mut().enumerate() {
                        let s: f64 = (0..DIM).map(|l| p[(c, l)] * gop[a][l]).sum();
                        *gac = self.volume[e] * s;
                    }
                }
                Some(ge)
            },
            |e, ge, g| {
                for (a, &v) in self.tets[e].iter().enumerate() {
                    for c in 0..DIM {
                        g[DIM * v + c] += ge[a][c];
                    }
                }
            },
        );
    }

    /// Inverted elements contribute nothing.
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        chunked_triplets(self.tets.len(), &mut h.triplets, |e, out| {
            let Some(mut he) = self.element_hessian(x, e) else {
                return;
            };
            if projected {
                project_psd(&mut he);
            }
            push_block(out, DIM, &self.tets[e], |r, c| he[(r, c)]);
        });
    }
}
