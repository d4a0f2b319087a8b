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

use super::{chunked_sum, chunked_triplets, par_scatter, push_block, Energy, Hessian, TermKind};
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use nalgebra::{DMatrix, Rotation3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The `n×n×n` grid of unit cubes of side `h`, each split into 6 tetrahedra around its
    /// diagonal (Kuhn split; half of them listed with negative orientation), vertices
    /// `v = i + (n+1) j + (n+1)² k`. Returns `(x_ref, tets)`.
    pub(crate) fn cube_grid(n: usize, h: f64) -> (Vec<f64>, Vec<[usize; 4]>) {
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
            .filter(|t| ds(&xr, t).determinant() < 0.0)
            .count();
        assert_eq!(neg, 3);
        let nh = NeoHookean3d::new(tets.clone(), &xr, 1.0, 1.0).unwrap();
        for (e, t) in nh.tets.iter().enumerate() {
            assert!(ds(&xr, t).determinant() > 0.0);
            let mut a = *t;
            let mut b = tets[e];
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
            assert!((nh.volume[e] - 1.0 / 6.0).abs() < 1e-15);
        }
        let total: f64 = nh.volume.iter().sum();
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
            for e in 0..nh.tets.len() {
                let he = nh.element_hessian(&x, e).unwrap();
                let ev = he.symmetric_eigenvalues();
                let one = NeoHookean3d {
                    tets: vec![[0, 1, 2, 3]],
                    dm_inv: vec![nh.dm_inv[e]],
                    volume: vec![nh.volume[e]],
                    mu: nh.mu,
                    lambda: nh.lambda,
                };
                let mut xe = vec![0.0; 12];
                for (a, &v) in nh.tets[e].iter().enumerate() {
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
        let t = nh.tets[CHUNK + 1];
        x.swap(3 * t[1], 3 * t[2]);
        x.swap(3 * t[1] + 1, 3 * t[2] + 1);
        x.swap(3 * t[1] + 2, 3 * t[2] + 2);
        let v = assert_thread_independent(|| nh.value(&x).to_bits());
        assert_eq!(f64::from_bits(v), f64::INFINITY);
    }
}
