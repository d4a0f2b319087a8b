//! TEMPORARY: the code before the energy/ restructuring, kept (test builds only) for the
//! bit-identity checks of [`super`]; removed when the restructuring is done.
//!
//! Compressible neo-Hookean energy of P1 triangles in 2D (the hyperelastic solid model used
//! for the solid bodies; see Pantz 2008, §7, and e.g. Bonet & Wood, *Nonlinear Continuum
//! Mechanics for FEA*, §6.4.3).
//!
//! With `F = Ds Dm⁻¹` (`Ds = [x1 − x0, x2 − x0]`, `Dm` the same in the reference
//! configuration) and `J = det F`:
//!
//! ```text
//! W(F) = μ/2 (|F|² − 2) − μ ln J + λ/2 (ln J)²,        J(x) = Σ_T |T_ref| W(F_T),
//! ```
//!
//! and `J(x) = +∞` as soon as one triangle has `det F ≤ 0`. The first Piola–Kirchhoff stress
//! and its derivative are
//!
//! ```text
//! P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ,
//! ∂P_ij/∂F_kl = μ δ_ik δ_jl + (μ − λ ln J) F⁻ᵀ_il F⁻ᵀ_kj + λ F⁻ᵀ_ij F⁻ᵀ_kl.
//! ```
//!
//! Writing `F_kl = Σ_a x_{a,k} G_{a,l}` with `G = [−(B_0+B_1); B_0; B_1]` (`B = Dm⁻¹`, rows
//! `B_m`), the element gradient is `∂/∂x_{a,c} = |T| Σ_l P_cl G_al` and the 6×6 element
//! Hessian is `|T| Σ_{l,n} ∂P_cl/∂F_dn G_al G_bn` at dofs `(2a + c, 2b + d)`. With
//! `projected = true` each element Hessian's negative eigenvalues are clamped to zero
//! (symmetric eigendecomposition).

use crate::energy::{
    chunked_sum, chunked_triplets, par_scatter, push_block, Energy, Hessian, TermKind,
};
use nalgebra::{Matrix2, Matrix6};

const DIM: usize = 2;

/// Compressible neo-Hookean energy of a set of triangles (2D, plane strain).
#[derive(Clone, Debug)]
pub struct NeoHookean2d {
    /// Triangles `[v0, v1, v2]`.
    pub triangles: Vec<[usize; 3]>,
    /// `Dm⁻¹` per triangle.
    pub dm_inv: Vec<Matrix2<f64>>,
    /// Reference area per triangle (positive).
    pub area: Vec<f64>,
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ`.
    pub lambda: f64,
}

impl NeoHookean2d {
    /// Builds the energy from reference positions `x_ref` (flat, 2D). A triangle listed
    /// clockwise in the reference is handled (its `Dm` then has negative determinant, and
    /// `F` is still the identity at the reference); degenerate triangles must not be passed.
    pub fn new(triangles: Vec<[usize; 3]>, x_ref: &[f64], mu: f64, lambda: f64) -> Self {
        let mut dm_inv = Vec::with_capacity(triangles.len());
        let mut area = Vec::with_capacity(triangles.len());
        for t in &triangles {
            let dm = ds(x_ref, t);
            area.push(0.5 * dm.determinant().abs());
            dm_inv.push(dm.try_inverse().unwrap_or_else(Matrix2::zeros));
        }
        Self {
            triangles,
            dm_inv,
            area,
            mu,
            lambda,
        }
    }

    fn grad_op(&self, e: usize) -> [[f64; 2]; 3] {
        let b = &self.dm_inv[e];
        [
            [-(b[(0, 0)] + b[(1, 0)]), -(b[(0, 1)] + b[(1, 1)])],
            [b[(0, 0)], b[(0, 1)]],
            [b[(1, 0)], b[(1, 1)]],
        ]
    }

    /// Deformation gradient of element `e`.
    pub fn deformation_gradient(&self, x: &[f64], e: usize) -> Matrix2<f64> {
        ds(x, &self.triangles[e]) * self.dm_inv[e]
    }

    fn energy_density(&self, f: &Matrix2<f64>) -> f64 {
        let j = f.determinant();
        if j <= 0.0 {
            return f64::INFINITY;
        }
        let lj = j.ln();
        0.5 * self.mu * (f.norm_squared() - 2.0) - self.mu * lj + 0.5 * self.lambda * lj * lj
    }

    /// Exact 6×6 element Hessian, or `None` if inverted.
    fn element_hessian(&self, x: &[f64], e: usize) -> Option<Matrix6<f64>> {
        let f = self.deformation_gradient(x, e);
        let j = f.determinant();
        if j <= 0.0 {
            return None;
        }
        let lj = j.ln();
        let fit = f.try_inverse()?.transpose();
        let (mu, la) = (self.mu, self.lambda);
        let dp = |i: usize, jj: usize, k: usize, l: usize| -> f64 {
            let d = if i == k && jj == l { mu } else { 0.0 };
            d + (mu - la * lj) * fit[(i, l)] * fit[(k, jj)] + la * fit[(i, jj)] * fit[(k, l)]
        };
        let g = self.grad_op(e);
        let mut h = Matrix6::zeros();
        for a in 0..3 {
            for c in 0..DIM {
                for b in 0..3 {
                    for d in 0..DIM {
                        let mut s = 0.0;
                        for l in 0..DIM {
                            for n in 0..DIM {
                                s += dp(c, l, d, n) * g[a][l] * g[b][n];
                            }
                        }
                        h[(DIM * a + c, DIM * b + d)] = self.area[e] * s;
                    }
                }
            }
        }
        Some((h + h.transpose()) * 0.5)
    }
}

fn ds(x: &[f64], t: &[usize; 3]) -> Matrix2<f64> {
    let p = |v: usize, k: usize| x[DIM * v + k];
    Matrix2::new(
        p(t[1], 0) - p(t[0], 0),
        p(t[2], 0) - p(t[0], 0),
        p(t[1], 1) - p(t[0], 1),
        p(t[2], 1) - p(t[0], 1),
    )
}

impl Energy for NeoHookean2d {
    fn name(&self) -> &str {
        "neo_hookean"
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        chunked_sum(self.triangles.len(), |r| {
            let mut s = 0.0;
            for e in r {
                let w = self.energy_density(&self.deformation_gradient(x, e));
                if w == f64::INFINITY {
                    return f64::INFINITY;
                }
                s += self.area[e] * w;
            }
            s
        })
    }

    /// Inverted elements (energy `+∞`) contribute nothing.
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        par_scatter(
            self.triangles.len(),
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
                let mut ge = [[0.0; DIM]; 3];
                for (a, gea) in ge.iter_mut().enumerate() {
                    for (c, gac) in gea.iter_mut().enumerate() {
                        let s: f64 = (0..DIM).map(|l| p[(c, l)] * gop[a][l]).sum();
                        *gac = self.area[e] * s;
                    }
                }
                Some(ge)
            },
            |e, ge, g| {
                for (a, &v) in self.triangles[e].iter().enumerate() {
                    for c in 0..DIM {
                        g[DIM * v + c] += ge[a][c];
                    }
                }
            },
        );
    }

    /// Inverted elements contribute nothing.
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        chunked_triplets(self.triangles.len(), &mut h.triplets, |e, out| {
            let Some(mut he) = self.element_hessian(x, e) else {
                return;
            };
            if projected {
                let eig = he.symmetric_eigen();
                if eig.eigenvalues.min() < 0.0 {
                    let d = eig.eigenvalues.map(|v| v.max(0.0));
                    he = eig.eigenvectors
                        * Matrix6::from_diagonal(&d)
                        * eig.eigenvectors.transpose();
                    he = (he + he.transpose()) * 0.5;
                }
            }
            push_block(out, DIM, &self.triangles[e], |r, c| he[(r, c)]);
        });
    }
}
