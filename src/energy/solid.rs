//! P1 simplicial solids in `D` dimensions (triangles in 2D, tetrahedra in 3D) with a stored
//! energy `W(F)` given by a [`Law`]: the one element engine of the solid models
//! (docs/materials.md). The laws are the compressible neo-Hookean solid
//! ([`super::neo_hookean`], plane strain in 2D and its plane-stress condensation) and the
//! small-strain linear-elastic solid ([`super::linear_elastic`]).
//!
//! An element has `N = D + 1` vertices. With `F = Ds Dm⁻¹` (`Ds = [x1 − x0, …, x_D − x0]`,
//! `Dm` the same in the reference configuration):
//!
//! ```text
//! J(x) = Σ_T |T_ref| W(F_T),     P = ∂W/∂F (first Piola–Kirchhoff),     ∂P_cl/∂F_dn.
//! ```
//!
//! (`|T_ref|` the reference area in 2D, volume in 3D.) `J(x) = +∞` as soon as one element has
//! `W = +∞` (an inverted element of a neo-Hookean solid). Writing
//! `F_kl = Σ_a x_{a,k} G_{a,l}` with `G = [−(B_0 + … + B_{D−1}); B_0; …; B_{D−1}]` (`B = Dm⁻¹`,
//! rows `B_m`), the element gradient is `∂/∂x_{a,c} = |T| Σ_l P_cl G_al` and the
//! `D(D+1) × D(D+1)` element Hessian (6×6 in 2D, 12×12 in 3D) is
//! `|T| Σ_{l,n} ∂P_cl/∂F_dn G_al G_bn` at dofs `(D·a + c, D·b + d)`. With `projected = true`
//! each element Hessian's negative eigenvalues are clamped to zero (symmetric
//! eigendecomposition, `energy::project_psd`), unless the law is convex ([`Law::convex`]: its
//! element Hessians are positive semi-definite by construction and are kept exact).
//!
//! The order of the sums of the Hessian contraction differs per dimension (2D: one running sum
//! over `(l, n)`; 3D: `Σ_n ∂P/∂F G_bn` first, then `Σ_l`), kept from the former separate 2D
//! and 3D neo-Hookean types so that their results stay bit for bit the same.
//!
//! **Reference orientation.** In 2D ([`P1Solid::triangles`]) a triangle listed clockwise in
//! the reference is kept as listed (its `Dm` then has a negative determinant, and `F` is still
//! the identity at the reference); degenerate triangles must not be passed. In 3D
//! ([`P1Solid::tets`]) every tetrahedron is stored positively oriented (`det Dm > 0`): one
//! listed with negative reference volume has its vertices 1 and 2 swapped (the element, its
//! energy and its reference volume are unchanged; only the stored vertex order differs). A
//! degenerate one (`|det Dm| ≤ 10⁻¹²·ℓ³`, `ℓ` its longest reference edge, or a non-finite
//! `det Dm`) cannot be oriented and is rejected with a [`DegenerateTet`] error naming it.
//!
//! **Stress.** [`Energy::element_stress`] gives each element's Cauchy stress
//! ([`Law::cauchy`]), a full 3×3 tensor (in 2D with the out-of-plane component of plane
//! strain or plane stress): the cell data of the VTK frames.

use super::{
    chunked_sum, chunked_triplets, par_scatter, project_psd, push_block, ElementStress, Energy,
    Hessian, TermKind,
};
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimSub, Matrix3, SMatrix, U1};
use thiserror::Error;

/// `∂P_cl/∂F_dn` at `[c][l][d][n]`.
pub type PiolaDerivative<const D: usize> = [[[[f64; D]; D]; D]; D];

/// A stored energy `W(F)` of a P1 solid in `D` dimensions, with its first Piola–Kirchhoff
/// stress, its derivative and its Cauchy stress.
pub trait Law<const D: usize>: Clone + std::fmt::Debug + Send + Sync {
    /// The term's name (display only): `neo_hookean`, `linear_elastic3d`, ….
    fn name(&self) -> &'static str;
    /// `W(F)`; `+∞` where undefined (an inverted element of a neo-Hookean solid).
    fn density(&self, f: &SMatrix<f64, D, D>) -> f64;
    /// `P(F) = ∂W/∂F`; `None` where `W` is undefined.
    fn piola(&self, f: &SMatrix<f64, D, D>) -> Option<SMatrix<f64, D, D>>;
    /// `∂P/∂F`; `None` where `W` is undefined.
    fn tangent(&self, f: &SMatrix<f64, D, D>) -> Option<PiolaDerivative<D>>;
    /// The Cauchy stress as a 3×3 tensor (in 2D the out-of-plane component `σ_zz` of plane
    /// strain or plane stress; `σ_xz = σ_yz = 0`); `None` where `W` is undefined.
    fn cauchy(&self, f: &SMatrix<f64, D, D>) -> Option<Matrix3<f64>>;
    /// Whether `W` is convex in `F` (a quadratic form): element Hessians are then positive
    /// semi-definite by construction and are never projected.
    fn convex(&self) -> bool {
        false
    }
}

/// A reference tetrahedron of (numerically) zero volume: it has no orientation and no `Dm⁻¹`.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("tetrahedron {index} {tet:?} is degenerate (reference volume = {volume:e})")]
pub struct DegenerateTet {
    /// Index of the tetrahedron in the list passed to [`P1Solid::tets`].
    pub index: usize,
    /// Its vertices.
    pub tet: [usize; 4],
    /// Its signed reference volume `det Dm / 6`.
    pub volume: f64,
}

/// A set of P1 simplices of `N = D + 1` vertices in `D` dimensions with the stored energy of
/// the law `L`. (`N` is a parameter of its own because a const generic cannot be written
/// `D + 1`; the constructors only exist for `(2, 3)` and `(3, 4)`.)
#[derive(Clone, Debug)]
pub struct P1Solid<const D: usize, const N: usize, L> {
    /// Elements (`N` vertices each); in 3D positively oriented in the reference configuration.
    pub elements: Vec<[usize; N]>,
    /// `Dm⁻¹` per element.
    pub dm_inv: Vec<SMatrix<f64, D, D>>,
    /// Reference measure per element (area in 2D, volume in 3D; positive).
    pub measure: Vec<f64>,
    /// The stored energy.
    pub law: L,
}

/// `Ds = [x1 − x0, …, x_D − x0]` of the element with vertices `t` (`D` columns).
pub(crate) fn ds<const D: usize, const N: usize>(x: &[f64], t: &[usize; N]) -> SMatrix<f64, D, D> {
    SMatrix::from_fn(|k, m| x[D * t[m + 1] + k] - x[D * t[0] + k])
}

impl<L: Law<2>> P1Solid<2, 3, L> {
    /// The solid of `triangles` on the reference positions `x_ref` (flat, 2D). A triangle
    /// listed clockwise in the reference is handled (its `Dm` then has negative determinant,
    /// and `F` is still the identity at the reference); degenerate triangles must not be
    /// passed.
    pub fn triangles(triangles: Vec<[usize; 3]>, x_ref: &[f64], law: L) -> Self {
        let mut dm_inv = Vec::with_capacity(triangles.len());
        let mut measure = Vec::with_capacity(triangles.len());
        for t in &triangles {
            let dm = ds::<2, 3>(x_ref, t);
            measure.push(0.5 * dm.determinant().abs());
            dm_inv.push(dm.try_inverse().unwrap_or_else(SMatrix::zeros));
        }
        Self {
            elements: triangles,
            dm_inv,
            measure,
            law,
        }
    }
}

impl<L: Law<3>> P1Solid<3, 4, L> {
    /// The solid of `tets` on the reference positions `x_ref` (flat, 3D). Negatively oriented
    /// tetrahedra are reordered (vertices 1 and 2 swapped); a degenerate one is an error.
    pub fn tets(mut tets: Vec<[usize; 4]>, x_ref: &[f64], law: L) -> Result<Self, DegenerateTet> {
        const DIM: usize = 3;
        let mut dm_inv = Vec::with_capacity(tets.len());
        let mut measure = Vec::with_capacity(tets.len());
        for (index, t) in tets.iter_mut().enumerate() {
            let mut dm = ds::<3, 4>(x_ref, t);
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
            measure.push(det.abs() / 6.0);
            dm_inv.push(dm.try_inverse().ok_or(DegenerateTet {
                index,
                tet: *t,
                volume: det / 6.0,
            })?);
        }
        Ok(Self {
            elements: tets,
            dm_inv,
            measure,
            law,
        })
    }
}

impl<const D: usize, const N: usize, L: Law<D>> P1Solid<D, N, L> {
    /// `G` of element `e` (rows `G_a`, `a = 0..N`).
    fn grad_op(&self, e: usize) -> [[f64; D]; N] {
        let b = &self.dm_inv[e];
        let mut g = [[0.0; D]; N];
        for l in 0..D {
            for m in 0..D {
                g[m + 1][l] = b[(m, l)];
            }
            let mut s = b[(0, l)];
            for m in 1..D {
                s += b[(m, l)];
            }
            g[0][l] = -s;
        }
        g
    }

    /// Deformation gradient of element `e`.
    pub fn deformation_gradient(&self, x: &[f64], e: usize) -> SMatrix<f64, D, D> {
        ds(x, &self.elements[e]) * self.dm_inv[e]
    }

    /// Exact element Hessian (`K = D·N`: 6 in 2D, 12 in 3D), or `None` if inverted.
    pub(crate) fn element_hessian<const K: usize>(
        &self,
        x: &[f64],
        e: usize,
    ) -> Option<SMatrix<f64, K, K>> {
        assert_eq!(K, D * N, "element Hessian size");
        let dp = self.law.tangent(&self.deformation_gradient(x, e))?;
        let g = self.grad_op(e);
        let mut h = SMatrix::<f64, K, K>::zeros();
        if D == 2 {
            // one running sum over (l, n) per entry (the order of the former 2D type)
            for a in 0..N {
                for c in 0..D {
                    for b in 0..N {
                        for d in 0..D {
                            let mut s = 0.0;
                            for l in 0..D {
                                for n in 0..D {
                                    s += dp[c][l][d][n] * g[a][l] * g[b][n];
                                }
                            }
                            h[(D * a + c, D * b + d)] = self.measure[e] * s;
                        }
                    }
                }
            }
        } else {
            // t[c][l][b][d] = Σ_n ∂P_cl/∂F_dn G_bn, then Σ_l G_al t[c][l][b][d] (the order of
            // the former 3D type)
            let mut t = [[[[0.0; D]; N]; D]; D];
            for (c, tc) in t.iter_mut().enumerate() {
                for (l, tcl) in tc.iter_mut().enumerate() {
                    for (b, tclb) in tcl.iter_mut().enumerate() {
                        for (d, v) in tclb.iter_mut().enumerate() {
                            *v = (0..D).map(|n| dp[c][l][d][n] * g[b][n]).sum();
                        }
                    }
                }
            }
            for a in 0..N {
                for c in 0..D {
                    for b in 0..N {
                        for d in 0..D {
                            let s: f64 = (0..D).map(|l| g[a][l] * t[c][l][b][d]).sum();
                            h[(D * a + c, D * b + d)] = self.measure[e] * s;
                        }
                    }
                }
            }
        }
        Some((h + h.transpose()) * 0.5)
    }

    /// Pushes the triplets of the element Hessians (`K = D·N`), each projected if asked (and
    /// the law is not convex).
    fn push_hessians<const K: usize>(&self, x: &[f64], projected: bool, h: &mut Hessian)
    where
        Const<K>: DimSub<U1>,
        DefaultAllocator:
            Allocator<Const<K>, DimDiff<Const<K>, U1>> + Allocator<DimDiff<Const<K>, U1>>,
    {
        let project = projected && !self.law.convex();
        chunked_triplets(self.elements.len(), &mut h.triplets, |e, out| {
            let Some(mut he) = self.element_hessian::<K>(x, e) else {
                return;
            };
            if project {
                project_psd(&mut he);
            }
            push_block(out, D, &self.elements[e], |r, c| he[(r, c)]);
        });
    }
}

impl<const D: usize, const N: usize, L: Law<D>> Energy for P1Solid<D, N, L> {
    fn name(&self) -> &str {
        self.law.name()
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        chunked_sum(self.elements.len(), |r| {
            let mut s = 0.0;
            for e in r {
                let w = self.law.density(&self.deformation_gradient(x, e));
                if w == f64::INFINITY {
                    return f64::INFINITY;
                }
                s += self.measure[e] * w;
            }
            s
        })
    }

    /// Inverted elements (energy `+∞`) contribute nothing.
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        par_scatter(
            self.elements.len(),
            g,
            |e| {
                let p = self.law.piola(&self.deformation_gradient(x, e))?;
                let gop = self.grad_op(e);
                let mut ge = [[0.0; D]; N];
                for (a, gea) in ge.iter_mut().enumerate() {
                    for (c, gac) in gea.iter_mut().enumerate() {
                        let s: f64 = (0..D).map(|l| p[(c, l)] * gop[a][l]).sum();
                        *gac = self.measure[e] * s;
                    }
                }
                Some(ge)
            },
            |e, ge, g| {
                for (a, &v) in self.elements[e].iter().enumerate() {
                    for c in 0..D {
                        g[D * v + c] += ge[a][c];
                    }
                }
            },
        );
    }

    /// Inverted elements contribute nothing.
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        // the element Hessian is a static K×K matrix, K = D·N (a const generic cannot be
        // computed from D and N, hence the match)
        match (D, N) {
            (2, 3) => self.push_hessians::<6>(x, projected, h),
            (3, 4) => self.push_hessians::<12>(x, projected, h),
            _ => unreachable!("P1Solid<{D}, {N}>: only (2, 3) and (3, 4) are built"),
        }
    }

    fn element_stress(&self, x: &[f64]) -> Option<ElementStress> {
        let mut elements = Vec::with_capacity(self.elements.len());
        let mut sigma = Vec::with_capacity(self.elements.len());
        for (e, t) in self.elements.iter().enumerate() {
            let mut v = [usize::MAX; 4];
            v[..N].copy_from_slice(t);
            elements.push(v);
            let s = self
                .law
                .cauchy(&self.deformation_gradient(x, e))
                .unwrap_or_else(|| Matrix3::from_element(f64::NAN));
            sigma.push(s);
        }
        Some(ElementStress { elements, sigma })
    }
}

/// `F` as a 3×3 matrix (`F_zz = 1` in 2D).
pub(crate) fn embed3<const D: usize>(f: &SMatrix<f64, D, D>) -> Matrix3<f64> {
    let mut m = Matrix3::identity();
    for i in 0..D {
        for j in 0..D {
            m[(i, j)] = f[(i, j)];
        }
    }
    m
}
