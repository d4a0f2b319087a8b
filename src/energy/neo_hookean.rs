//! Compressible neo-Hookean energy of P1 simplices in `D` dimensions: triangles in 2D (plane
//! strain) and tetrahedra in 3D, the hyperelastic solid model used for the solid bodies (see
//! Pantz 2008, §7, and e.g. Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §6.4.3).
//!
//! An element has `N = D + 1` vertices. With `F = Ds Dm⁻¹` (`Ds = [x1 − x0, …, x_D − x0]`,
//! `Dm` the same in the reference configuration) and `J = det F`:
//!
//! ```text
//! W(F) = μ/2 (|F|² − D) − μ ln J + λ/2 (ln J)²,        J(x) = Σ_T |T_ref| W(F_T),
//! ```
//!
//! (`|T_ref|` the reference area in 2D, volume in 3D) and `J(x) = +∞` as soon as one element
//! has `det F ≤ 0`. The first Piola–Kirchhoff stress and its derivative are
//!
//! ```text
//! P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ,
//! ∂P_ij/∂F_kl = μ δ_ik δ_jl + (μ − λ ln J) F⁻ᵀ_il F⁻ᵀ_kj + λ F⁻ᵀ_ij F⁻ᵀ_kl.
//! ```
//!
//! Writing `F_kl = Σ_a x_{a,k} G_{a,l}` with `G = [−(B_0 + … + B_{D−1}); B_0; …; B_{D−1}]`
//! (`B = Dm⁻¹`, rows `B_m`), the element gradient is `∂/∂x_{a,c} = |T| Σ_l P_cl G_al` and the
//! `D(D+1) × D(D+1)` element Hessian (6×6 in 2D, 12×12 in 3D) is
//! `|T| Σ_{l,n} ∂P_cl/∂F_dn G_al G_bn` at dofs `(D·a + c, D·b + d)`. With `projected = true`
//! each element Hessian's negative eigenvalues are clamped to zero (symmetric
//! eigendecomposition, `energy::project_psd`); an element Hessian that is already positive
//! semi-definite is kept as is.
//!
//! Everything per element (`F`, `W`, `P`, `∂P/∂F`, `G`, the projection) is one code for both
//! dimensions. The one per-dimension difference is the order of the sums of the Hessian
//! contraction (2D: one running sum over `(l, n)`; 3D: `Σ_n ∂P/∂F G_bn` first, then `Σ_l`),
//! kept from the former separate 2D and 3D types so that the results stay bit for bit the same.
//!
//! **Reference orientation.** In 2D ([`NeoHookean2d::new`]) a triangle listed clockwise in the
//! reference is kept as listed (its `Dm` then has a negative determinant, and `F` is still the
//! identity at the reference); degenerate triangles must not be passed. In 3D
//! ([`NeoHookean3d::new`]) every tetrahedron is stored positively oriented (`det Dm > 0`): one
//! listed with negative reference volume has its vertices 1 and 2 swapped (the element, its
//! energy and its reference volume are unchanged; only the stored vertex order differs). A
//! degenerate one (`|det Dm| ≤ 10⁻¹²·ℓ³`, `ℓ` its longest reference edge, or a non-finite
//! `det Dm`) cannot be oriented and is rejected with a [`DegenerateTet`] error naming it.

use super::{
    chunked_sum, chunked_triplets, par_scatter, project_psd, push_block, Energy, Hessian, TermKind,
};
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimMin, DimSub, SMatrix, U1};
use thiserror::Error;

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

/// Compressible neo-Hookean energy of a set of P1 simplices of `N = D + 1` vertices in `D`
/// dimensions: [`NeoHookean2d`] (triangles, plane strain) and [`NeoHookean3d`] (tetrahedra)
/// are this type. (`N` is a parameter of its own because a const generic cannot be written
/// `D + 1`; the constructors only exist for `(2, 3)` and `(3, 4)`.)
#[derive(Clone, Debug)]
pub struct NeoHookean<const D: usize, const N: usize> {
    /// Elements (`N` vertices each); in 3D positively oriented in the reference configuration.
    pub elements: Vec<[usize; N]>,
    /// `Dm⁻¹` per element.
    pub dm_inv: Vec<SMatrix<f64, D, D>>,
    /// Reference measure per element (area in 2D, volume in 3D; positive).
    pub measure: Vec<f64>,
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ`.
    pub lambda: f64,
}

/// Compressible neo-Hookean energy of a set of triangles (2D, plane strain).
pub type NeoHookean2d = NeoHookean<2, 3>;

/// Compressible neo-Hookean energy of a set of tetrahedra (3D).
pub type NeoHookean3d = NeoHookean<3, 4>;

/// `∂P_cl/∂F_dn` at `[c][l][d][n]`.
type PiolaDerivative<const D: usize> = [[[[f64; D]; D]; D]; D];

/// `Ds = [x1 − x0, …, x_D − x0]` of the element with vertices `t` (`D` columns).
fn ds<const D: usize, const N: usize>(x: &[f64], t: &[usize; N]) -> SMatrix<f64, D, D> {
    SMatrix::from_fn(|k, m| x[D * t[m + 1] + k] - x[D * t[0] + k])
}

/// `W(F)`; `+∞` when `det F ≤ 0`.
fn energy_density<const D: usize>(f: &SMatrix<f64, D, D>, mu: f64, lambda: f64) -> f64
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
    let j = f.determinant();
    if j <= 0.0 {
        return f64::INFINITY;
    }
    let lj = j.ln();
    0.5 * mu * (f.norm_squared() - D as f64) - mu * lj + 0.5 * lambda * lj * lj
}

/// The first Piola–Kirchhoff stress `P(F)`; `None` when `det F ≤ 0`.
fn first_piola<const D: usize>(
    f: &SMatrix<f64, D, D>,
    mu: f64,
    lambda: f64,
) -> Option<SMatrix<f64, D, D>>
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
    let j = f.determinant();
    if j <= 0.0 {
        return None;
    }
    let fit = f.try_inverse()?.transpose();
    Some((f - fit) * mu + fit * (lambda * j.ln()))
}

/// `∂P/∂F` at `F`; `None` when `det F ≤ 0`.
fn piola_derivative<const D: usize>(
    f: &SMatrix<f64, D, D>,
    mu: f64,
    lambda: f64,
) -> Option<PiolaDerivative<D>>
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
    let j = f.determinant();
    if j <= 0.0 {
        return None;
    }
    let lj = j.ln();
    let fit = f.try_inverse()?.transpose();
    let mut dp = [[[[0.0; D]; D]; D]; D];
    for (c, dpc) in dp.iter_mut().enumerate() {
        for (l, dpcl) in dpc.iter_mut().enumerate() {
            for (d, dpcld) in dpcl.iter_mut().enumerate() {
                for (n, v) in dpcld.iter_mut().enumerate() {
                    let delta = if c == d && l == n { mu } else { 0.0 };
                    *v = delta
                        + (mu - lambda * lj) * fit[(c, n)] * fit[(d, l)]
                        + lambda * fit[(c, l)] * fit[(d, n)];
                }
            }
        }
    }
    Some(dp)
}

impl NeoHookean2d {
    /// Builds the energy from reference positions `x_ref` (flat, 2D). A triangle listed
    /// clockwise in the reference is handled (its `Dm` then has negative determinant, and
    /// `F` is still the identity at the reference); degenerate triangles must not be passed.
    pub fn new(triangles: Vec<[usize; 3]>, x_ref: &[f64], mu: f64, lambda: f64) -> Self {
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
            mu,
            lambda,
        }
    }
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
            mu,
            lambda,
        })
    }
}

impl<const D: usize, const N: usize> NeoHookean<D, N>
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
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
    fn element_hessian<const K: usize>(&self, x: &[f64], e: usize) -> Option<SMatrix<f64, K, K>> {
        assert_eq!(K, D * N, "element Hessian size");
        let dp = piola_derivative(&self.deformation_gradient(x, e), self.mu, self.lambda)?;
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

    /// Pushes the triplets of the element Hessians (`K = D·N`), each projected if asked.
    fn push_hessians<const K: usize>(&self, x: &[f64], projected: bool, h: &mut Hessian)
    where
        Const<K>: DimSub<U1>,
        DefaultAllocator:
            Allocator<Const<K>, DimDiff<Const<K>, U1>> + Allocator<DimDiff<Const<K>, U1>>,
    {
        chunked_triplets(self.elements.len(), &mut h.triplets, |e, out| {
            let Some(mut he) = self.element_hessian::<K>(x, e) else {
                return;
            };
            if projected {
                project_psd(&mut he);
            }
            push_block(out, D, &self.elements[e], |r, c| he[(r, c)]);
        });
    }
}

impl<const D: usize, const N: usize> Energy for NeoHookean<D, N>
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
    fn name(&self) -> &str {
        if D == 2 {
            "neo_hookean"
        } else {
            "neo_hookean3d"
        }
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        chunked_sum(self.elements.len(), |r| {
            let mut s = 0.0;
            for e in r {
                let w = energy_density(&self.deformation_gradient(x, e), self.mu, self.lambda);
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
                let p = first_piola(&self.deformation_gradient(x, e), self.mu, self.lambda)?;
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
            _ => unreachable!("NeoHookean<{D}, {N}>: only (2, 3) and (3, 4) are built"),
        }
    }
}

#[cfg(test)]
mod tests_2d {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use nalgebra::{DMatrix, Matrix2};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A 3×3-vertex grid (8 triangles, mixed orientations) deformed by a random affine map
    /// with positive determinant plus small random vertex noise.
    fn config(rng: &mut ChaCha8Rng, amp: f64) -> (NeoHookean2d, Vec<f64>) {
        let mut xr = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                xr.push(i as f64 * 0.5 + rng.gen_range(-0.05..0.05));
                xr.push(j as f64 * 0.5 + rng.gen_range(-0.05..0.05));
            }
        }
        let mut tris = Vec::new();
        for j in 0..2 {
            for i in 0..2 {
                let v = 3 * j + i;
                tris.push([v, v + 1, v + 4]);
                tris.push([v, v + 3, v + 4]); // clockwise in the reference
            }
        }
        let nh = NeoHookean2d::new(tris, &xr, rng.gen_range(0.5..2.0), rng.gen_range(0.5..5.0));
        let a = Matrix2::new(
            1.0 + rng.gen_range(-amp..amp),
            rng.gen_range(-amp..amp),
            rng.gen_range(-amp..amp),
            1.0 + rng.gen_range(-amp..amp),
        );
        let mut x = xr.clone();
        for v in 0..9 {
            let p = a * nalgebra::Vector2::new(xr[2 * v], xr[2 * v + 1]);
            x[2 * v] = p.x + rng.gen_range(-0.03..0.03) + 0.2;
            x[2 * v + 1] = p.y + rng.gen_range(-0.03..0.03) - 0.1;
        }
        (nh, x)
    }

    #[test]
    fn energy_neo_hookean_rest_is_zero() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let (nh, _) = config(&mut rng, 0.2);
        let mut xr = vec![0.0; 18];
        // rebuild the reference from F = I: use a rigid rotation + translation of itself
        // (energy and gradient vanish)
        let base = {
            let mut r = ChaCha8Rng::seed_from_u64(6);
            let mut v = Vec::new();
            for j in 0..3 {
                for i in 0..3 {
                    v.push(i as f64 * 0.5 + r.gen_range(-0.05..0.05));
                    v.push(j as f64 * 0.5 + r.gen_range(-0.05..0.05));
                }
            }
            v
        };
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        for v in 0..9 {
            xr[2 * v] = c * base[2 * v] - s * base[2 * v + 1] + 1.0;
            xr[2 * v + 1] = s * base[2 * v] + c * base[2 * v + 1] - 2.0;
        }
        assert!(nh.value(&xr).abs() < 1e-12, "{}", nh.value(&xr));
        let mut g = vec![0.0; 18];
        nh.add_gradient(&xr, &mut g);
        assert!(g.iter().all(|v| v.abs() < 1e-12));
    }

    #[test]
    fn energy_neo_hookean_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..20 {
            let (nh, x) = config(&mut rng, 0.25);
            assert!(nh.value(&x).is_finite());
            let mut g = vec![0.0; x.len()];
            nh.add_gradient(&x, &mut g);
            let gf = fd_gradient(&nh, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-5, "rel {}", rel(&g, &gf));
        }
    }

    #[test]
    fn energy_neo_hookean_hessian_fd_and_projection() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let mut saw_indefinite = false;
        for k in 0..30 {
            let amp = if k < 15 { 0.25 } else { 0.5 };
            let (nh, x) = config(&mut rng, amp);
            if !nh.value(&x).is_finite() {
                continue;
            }
            let n = x.len();
            let mut h = Hessian::default();
            nh.add_hessian(&x, false, &mut h);
            let hd = h.to_dense(n);
            let hf = fd_hessian(&nh, &x, 1e-6);
            let r = rel(hd.as_slice(), hf.as_slice());
            assert!(r <= 1e-5, "rel {r}");
            let mut hp = Hessian::default();
            nh.add_hessian(&x, true, &mut hp);
            let hpd = hp.to_dense(n);
            let scale = hpd.norm().max(1.0);
            assert!(hpd.symmetric_eigenvalues().min() >= -1e-10 * scale);
            // element by element: projected is PSD, and equals the exact one when that is PSD
            for e in 0..nh.elements.len() {
                let he = nh.element_hessian::<6>(&x, e).unwrap();
                let ev = he.symmetric_eigenvalues();
                let mut one = NeoHookean2d {
                    elements: vec![nh.elements[e]],
                    dm_inv: vec![nh.dm_inv[e]],
                    measure: vec![nh.measure[e]],
                    mu: nh.mu,
                    lambda: nh.lambda,
                };
                one.elements[0] = [0, 1, 2];
                let mut xe = vec![0.0; 6];
                for (a, &v) in nh.elements[e].iter().enumerate() {
                    xe[2 * a] = x[2 * v];
                    xe[2 * a + 1] = x[2 * v + 1];
                }
                let mut hpe = Hessian::default();
                one.add_hessian(&xe, true, &mut hpe);
                let hpe = hpe.to_dense(6);
                let s = he.norm().max(1.0);
                assert!(hpe.symmetric_eigenvalues().min() >= -1e-10 * s);
                if ev.min() >= 0.0 {
                    let hed = DMatrix::from_column_slice(6, 6, he.as_slice());
                    assert!((&hpe - hed).norm() <= 1e-12 * s);
                } else {
                    saw_indefinite = true;
                }
            }
        }
        assert!(saw_indefinite, "test set should exercise the projection");
    }

    #[test]
    fn energy_neo_hookean_inverted_is_infinite() {
        let xr = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let nh = NeoHookean2d::new(vec![[0, 1, 2]], &xr, 1.0, 1.0);
        assert!(nh.value(&xr).abs() < 1e-15);
        // reflected
        let x = [0.0, 0.0, 1.0, 0.0, 0.0, -1.0];
        assert_eq!(nh.value(&x), f64::INFINITY);
        // collapsed
        let x = [0.0, 0.0, 1.0, 0.0, 2.0, 0.0];
        assert_eq!(nh.value(&x), f64::INFINITY);
        let mut g = vec![0.0; 6];
        nh.add_gradient(&x, &mut g);
        assert!(g.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn energy_neo_hookean_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        // an m×m grid (2(m−1)² > 4 chunks of triangles, mixed orientations) under a random
        // affine map plus vertex noise; strong enough that some element Hessians are
        // indefinite
        let m = 100;
        assert!(2 * (m - 1) * (m - 1) > 4 * CHUNK);
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let mut xr = Vec::new();
        for j in 0..m {
            for i in 0..m {
                xr.push(i as f64 * 0.5 + rng.gen_range(-0.05..0.05));
                xr.push(j as f64 * 0.5 + rng.gen_range(-0.05..0.05));
            }
        }
        let mut tris = Vec::new();
        for j in 0..m - 1 {
            for i in 0..m - 1 {
                let v = m * j + i;
                if (i + j) % 2 == 0 {
                    tris.push([v, v + 1, v + m + 1]);
                    tris.push([v, v + m, v + m + 1]);
                } else {
                    tris.push([v, v + 1, v + m]);
                    tris.push([v + 1, v + m + 1, v + m]);
                }
            }
        }
        let nh = NeoHookean2d::new(tris, &xr, 1.3, 4.0);
        let a = Matrix2::new(1.4, 0.3, -0.2, 0.6);
        let mut x = xr.clone();
        for v in 0..m * m {
            let p = a * nalgebra::Vector2::new(xr[2 * v], xr[2 * v + 1]);
            x[2 * v] = p.x + rng.gen_range(-0.06..0.06);
            x[2 * v + 1] = p.y + rng.gen_range(-0.06..0.06);
        }
        let bits = assert_thread_independent(|| term_bits(&nh, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
        let indefinite = (0..nh.elements.len())
            .filter(|&e| {
                nh.element_hessian::<6>(&x, e)
                    .unwrap()
                    .symmetric_eigenvalues()
                    .min()
                    < 0.0
            })
            .count();
        assert!(indefinite > 0, "the projection should be exercised");
        // one inverted element: +∞, still thread independent
        let t = nh.elements[3 * CHUNK + 1];
        x.swap(2 * t[1], 2 * t[2]);
        x.swap(2 * t[1] + 1, 2 * t[2] + 1);
        let bits = assert_thread_independent(|| term_bits(&nh, &x));
        assert_eq!(f64::from_bits(bits[0]), f64::INFINITY);
    }
}

#[cfg(test)]
mod tests_3d {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use nalgebra::{DMatrix, Matrix3, Rotation3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The `n×n×n` grid of unit cubes of side `h`, each split into 6 tetrahedra around its
    /// diagonal (Kuhn split; half of them listed with negative orientation), vertices
    /// `v = i + (n+1) j + (n+1)² k`. Returns `(x_ref, tets)`.
    fn cube_grid(n: usize, h: f64) -> (Vec<f64>, Vec<[usize; 4]>) {
        let m = n + 1;
        let mut x = Vec::with_capacity(3 * m * m * m);
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    x.extend([i as f64 * h, j as f64 * h, k as f64 * h]);
                }
            }
        }
        let step = [1, m, m * m];
        let perms = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        let mut tets = Vec::with_capacity(6 * n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let v0 = i + m * j + m * m * k;
                    for p in &perms {
                        let v1 = v0 + step[p[0]];
                        let v2 = v1 + step[p[1]];
                        let v3 = v2 + step[p[2]];
                        tets.push([v0, v1, v2, v3]);
                    }
                }
            }
        }
        (x, tets)
    }

    /// `x ↦ a x + t + noise` on every vertex.
    fn deform(rng: &mut ChaCha8Rng, xr: &[f64], a: &Matrix3<f64>, noise: f64) -> Vec<f64> {
        let t = Vector3::new(0.2, -0.1, 0.3);
        let mut x = xr.to_vec();
        for (p, q) in x.chunks_mut(3).zip(xr.chunks(3)) {
            let y = a * Vector3::new(q[0], q[1], q[2]) + t;
            for k in 0..3 {
                p[k] = y[k] + rng.gen_range(-noise..noise);
            }
        }
        x
    }

    /// A 2×2×2 grid (48 tets, mixed listed orientations), perturbed, under a random affine map
    /// `I + A` (`|A_ij| < amp`), or a stretch (`scale > 1`) / compression (`scale < 1`) of it,
    /// plus small random vertex noise.
    fn config(rng: &mut ChaCha8Rng, amp: f64, scale: f64) -> (NeoHookean3d, Vec<f64>, Vec<f64>) {
        let (mut xr, tets) = cube_grid(2, 0.5);
        for v in xr.iter_mut() {
            *v += rng.gen_range(-0.04..0.04);
        }
        let nh =
            NeoHookean3d::new(tets, &xr, rng.gen_range(0.5..2.0), rng.gen_range(0.5..5.0)).unwrap();
        let a =
            Matrix3::from_fn(|i, j| (if i == j { 1.0 } else { 0.0 }) + rng.gen_range(-amp..amp))
                * scale;
        let x = deform(rng, &xr, &a, 0.02 * scale);
        (nh, xr, x)
    }

    #[test]
    fn energy_neo_hookean3d_reference_orientation_and_volume() {
        // the unit cube split into 6 tets (3 listed negatively): reordered, total volume 1
        let (xr, tets) = cube_grid(1, 1.0);
        let neg = tets
            .iter()
            .filter(|t| ds::<3, 4>(&xr, t).determinant() < 0.0)
            .count();
        assert_eq!(neg, 3);
        let nh = NeoHookean3d::new(tets.clone(), &xr, 1.0, 1.0).unwrap();
        for (e, t) in nh.elements.iter().enumerate() {
            assert!(ds::<3, 4>(&xr, t).determinant() > 0.0);
            let mut a = *t;
            let mut b = tets[e];
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
            assert!((nh.measure[e] - 1.0 / 6.0).abs() < 1e-15);
        }
        let total: f64 = nh.measure.iter().sum();
        assert!((total - 1.0).abs() < 1e-14);
        // uniform dilation by s: J = W(sI) · 1
        let (mu, la, s) = (nh.mu, nh.lambda, 1.3f64);
        let x: Vec<f64> = xr.iter().map(|v| s * v).collect();
        let w =
            0.5 * mu * (3.0 * s * s - 3.0) - 3.0 * mu * s.ln() + 0.5 * la * (3.0 * s.ln()).powi(2);
        assert!((nh.value(&x) - w).abs() < 1e-13, "{} vs {w}", nh.value(&x));
        // a degenerate tet is an error naming it
        let mut flat = xr.clone();
        flat.extend([0.5, 0.5, 0.0]); // vertex 8, in the plane z = 0 of vertices 0, 1, 2
        let mut bad = tets.clone();
        bad.push([0, 1, 3, 8]);
        let err = NeoHookean3d::new(bad, &flat, 1.0, 1.0).unwrap_err();
        assert_eq!(err.index, 6);
        assert_eq!(err.tet, [0, 1, 3, 8]);
        assert!(err.to_string().contains("tetrahedron 6"), "{err}");
    }

    #[test]
    fn energy_neo_hookean3d_rest_is_zero_and_rigid_invariant() {
        let mut rng = ChaCha8Rng::seed_from_u64(30);
        let (nh, xr, x) = config(&mut rng, 0.2, 1.0);
        let rot = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let t = Vector3::new(1.0, -2.0, 0.5);
        let rigid = |x: &[f64]| -> Vec<f64> {
            let mut y = x.to_vec();
            for (p, q) in y.chunks_mut(3).zip(x.chunks(3)) {
                let z = rot * Vector3::new(q[0], q[1], q[2]) + t;
                p.copy_from_slice(z.as_slice());
            }
            y
        };
        // deformed: invariant to 1e-12 relative
        let v0 = nh.value(&x);
        let v1 = nh.value(&rigid(&x));
        assert!(v0 > 0.0 && ((v1 - v0) / v0).abs() < 1e-12, "{v0} {v1}");
        // the reference and a rigid motion of it: zero energy and gradient
        assert!(nh.value(&xr).abs() < 1e-14, "{}", nh.value(&xr));
        let xm = rigid(&xr);
        assert!(nh.value(&xm).abs() < 1e-12, "{}", nh.value(&xm));
        let mut g = vec![0.0; xm.len()];
        nh.add_gradient(&xm, &mut g);
        assert!(g.iter().all(|v| v.abs() < 1e-12));
    }

    #[test]
    fn energy_neo_hookean3d_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5; stretched and compressed
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        for k in 0..12 {
            let scale = [1.0, 1.4, 0.7][k % 3];
            let (nh, _, x) = config(&mut rng, 0.25, scale);
            assert!(nh.value(&x).is_finite());
            let mut g = vec![0.0; x.len()];
            nh.add_gradient(&x, &mut g);
            let gf = fd_gradient(&nh, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-5, "rel {}", rel(&g, &gf));
        }
    }

    #[test]
    fn energy_neo_hookean3d_hessian_fd_and_projection() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(32);
        let (mut saw_indefinite, mut saw_psd) = (false, false);
        for k in 0..12 {
            let scale = [1.0, 1.4, 0.7][k % 3];
            let amp = if k < 6 { 0.25 } else { 0.45 };
            let (nh, _, x) = config(&mut rng, amp, scale);
            if !nh.value(&x).is_finite() {
                continue;
            }
            let n = x.len();
            let mut h = Hessian::default();
            nh.add_hessian(&x, false, &mut h);
            let hd = h.to_dense(n);
            let hf = fd_hessian(&nh, &x, 1e-6);
            let r = rel(hd.as_slice(), hf.as_slice());
            assert!(r <= 1e-5, "rel {r}");
            let mut hp = Hessian::default();
            nh.add_hessian(&x, true, &mut hp);
            let hpd = hp.to_dense(n);
            let scale = hpd.norm().max(1.0);
            assert!(hpd.symmetric_eigenvalues().min() >= -1e-10 * scale);
            // element by element: projected is PSD, and equals the exact one when that is PSD
            for e in 0..nh.elements.len() {
                let he = nh.element_hessian::<12>(&x, e).unwrap();
                let ev = he.symmetric_eigenvalues();
                let one = NeoHookean3d {
                    elements: vec![[0, 1, 2, 3]],
                    dm_inv: vec![nh.dm_inv[e]],
                    measure: vec![nh.measure[e]],
                    mu: nh.mu,
                    lambda: nh.lambda,
                };
                let mut xe = vec![0.0; 12];
                for (a, &v) in nh.elements[e].iter().enumerate() {
                    xe[3 * a..3 * a + 3].copy_from_slice(&x[3 * v..3 * v + 3]);
                }
                let mut hpe = Hessian::default();
                one.add_hessian(&xe, true, &mut hpe);
                let hpe = hpe.to_dense(12);
                let s = he.norm().max(1.0);
                assert!(hpe.symmetric_eigenvalues().min() >= -1e-10 * s);
                if ev.min() >= 0.0 {
                    saw_psd = true;
                    let hed = DMatrix::from_column_slice(12, 12, he.as_slice());
                    assert!((&hpe - hed).norm() <= 1e-12 * s);
                } else {
                    saw_indefinite = true;
                }
            }
        }
        assert!(saw_indefinite, "test set should exercise the projection");
        assert!(saw_psd, "test set should have PSD element Hessians");
    }

    #[test]
    fn energy_neo_hookean3d_inverted_is_infinite() {
        let xr = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let nh = NeoHookean3d::new(vec![[0, 1, 2, 3]], &xr, 1.0, 1.0).unwrap();
        assert!(nh.value(&xr).abs() < 1e-15);
        // reflected
        let mut x = xr;
        x[11] = -1.0;
        assert_eq!(nh.value(&x), f64::INFINITY);
        // flattened
        x[11] = 0.0;
        assert_eq!(nh.value(&x), f64::INFINITY);
        let mut g = vec![0.0; 12];
        nh.add_gradient(&x, &mut g);
        assert_eq!(g, vec![0.0; 12]);
        let mut h = Hessian::default();
        nh.add_hessian(&x, true, &mut h);
        assert!(h.triplets.is_empty());
    }

    #[test]
    fn energy_neo_hookean3d_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        // a 9×9×9 grid (> 1 chunk of tets, mixed listed orientations) under an affine map plus
        // vertex noise; strong enough that some element Hessians are indefinite
        let n = 9;
        let (mut xr, tets) = cube_grid(n, 0.5);
        assert!(tets.len() > CHUNK);
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        for v in xr.iter_mut() {
            *v += rng.gen_range(-0.04..0.04);
        }
        let nh = NeoHookean3d::new(tets, &xr, 1.3, 4.0).unwrap();
        let a = Matrix3::new(1.4, 0.3, 0.1, -0.2, 0.6, 0.2, 0.1, -0.1, 0.9);
        let mut x = deform(&mut rng, &xr, &a, 0.05);
        let bits = assert_thread_independent(|| term_bits(&nh, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
        let (mut h, mut hp) = (Hessian::default(), Hessian::default());
        nh.add_hessian(&x, false, &mut h);
        nh.add_hessian(&x, true, &mut hp);
        assert!(h != hp, "the projection should be exercised");
        // one inverted element: +∞, still thread independent
        let t = nh.elements[CHUNK + 1];
        x.swap(3 * t[1], 3 * t[2]);
        x.swap(3 * t[1] + 1, 3 * t[2] + 1);
        x.swap(3 * t[1] + 2, 3 * t[2] + 2);
        let v = assert_thread_independent(|| nh.value(&x).to_bits());
        assert_eq!(f64::from_bits(v), f64::INFINITY);
    }
}
