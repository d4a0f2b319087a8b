//! The compressible neo-Hookean solid: P1 triangles in 2D (plane strain, or plane stress by
//! condensation of the out-of-plane stretch) and tetrahedra in 3D (see Pantz 2008, §7, and e.g.
//! Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §6.4.3). The element engine is
//! [`P1Solid`](super::solid::P1Solid); this module gives the laws. docs/materials.md has the
//! formulas and the E/ν conversion.
//!
//! **Plane strain and 3D** ([`NeoHookeanLaw`]). With `J = det F` (`D` = 2 or 3):
//!
//! ```text
//! W(F) = μ/2 (|F|² − D) − μ ln J + λ/2 (ln J)²,    W = +∞ when J ≤ 0,
//! P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ,
//! ∂P_ij/∂F_kl = μ δ_ik δ_jl + (μ − λ ln J) F⁻ᵀ_il F⁻ᵀ_kj + λ F⁻ᵀ_ij F⁻ᵀ_kl,
//! σ = P Fᵀ / J   (2D plane strain: σ_zz = λ ln J / J).
//! ```
//!
//! In 2D this is the 3D law with `F_zz = 1` (plane strain).
//!
//! **Plane stress** ([`NeoHookeanPlaneStress`], 2D only). The out-of-plane stretch `s = F_zz`
//! is the one that makes `σ_zz = 0`: `W_ps(F) = min_{s>0} W₃(F ⊕ s)`, with
//! `W₃(F ⊕ s) = μ/2 (|F|² + s² − 3) − μ ln(J s) + λ/2 (ln(J s))²` (`J = det F`, 2×2). The
//! minimum is the root of `μ (s² − 1) + λ ln(J s) = 0` (increasing in `s`: one root, found by
//! Newton's method in `t = ln s` from the side where the function is positive, monotone since it
//! is convex in `t`). By the envelope theorem `P = μ (F − F⁻ᵀ) + λ ln(J s) F⁻ᵀ`, and with
//! `∂²W₃/∂s² = 2μ + λ/s²` at the root,
//!
//! ```text
//! ∂P/∂F = [μ δ_ik δ_jl + (μ − λ ln(Js)) F⁻ᵀ_il F⁻ᵀ_kj + λ F⁻ᵀ_ij F⁻ᵀ_kl] − λ² F⁻ᵀ_ij F⁻ᵀ_kl / (2μ s² + λ),
//! σ = P Fᵀ / (J s),  σ_zz = 0.
//! ```
//!
//! At small strain its in-plane Lamé constant is `λ − λ²/(2μ + λ) = 2μλ/(λ + 2μ)`, the
//! plane-stress `λ*` of linear elasticity (tested).
//!
//! Each law is a [`Law`]; an inverted element has `W = +∞` and contributes nothing to the
//! gradient or Hessian.

#[cfg(test)]
use super::solid::ds;
pub use super::solid::DegenerateTet;
use super::solid::{embed3, Law, P1Solid, PiolaDerivative};
#[cfg(test)]
use super::{Energy, Hessian};
use nalgebra::{Const, DimMin, Matrix2, Matrix3, SMatrix};

/// The compressible neo-Hookean law in `D` dimensions (2D: plane strain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeoHookeanLaw {
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ`.
    pub lambda: f64,
}

/// Compressible neo-Hookean energy of P1 simplices in `D` dimensions: [`NeoHookean2d`]
/// (triangles, plane strain) and [`NeoHookean3d`] (tetrahedra).
pub type NeoHookean<const D: usize, const N: usize> = P1Solid<D, N, NeoHookeanLaw>;

/// Compressible neo-Hookean energy of a set of triangles (2D, plane strain).
pub type NeoHookean2d = NeoHookean<2, 3>;

/// Compressible neo-Hookean energy of a set of tetrahedra (3D).
pub type NeoHookean3d = NeoHookean<3, 4>;

/// Compressible neo-Hookean energy of a set of triangles in plane stress.
pub type NeoHookeanPlaneStress2d = P1Solid<2, 3, NeoHookeanPlaneStress>;

impl NeoHookean2d {
    /// Builds the energy from reference positions `x_ref` (flat, 2D); see
    /// [`P1Solid::triangles`].
    pub fn new(triangles: Vec<[usize; 3]>, x_ref: &[f64], mu: f64, lambda: f64) -> Self {
        Self::triangles(triangles, x_ref, NeoHookeanLaw { mu, lambda })
    }
}

impl NeoHookean3d {
    /// Builds the energy from reference positions `x_ref` (flat, 3D); see [`P1Solid::tets`].
    pub fn new(
        tets: Vec<[usize; 4]>,
        x_ref: &[f64],
        mu: f64,
        lambda: f64,
    ) -> Result<Self, DegenerateTet> {
        Self::tets(tets, x_ref, NeoHookeanLaw { mu, lambda })
    }
}

impl NeoHookeanPlaneStress2d {
    /// Builds the plane-stress energy from reference positions `x_ref` (flat, 2D).
    pub fn new(triangles: Vec<[usize; 3]>, x_ref: &[f64], mu: f64, lambda: f64) -> Self {
        Self::triangles(triangles, x_ref, NeoHookeanPlaneStress { mu, lambda })
    }
}

/// `∂P/∂F` of the neo-Hookean form with `ln J` replaced by `lj` (plane strain and 3D:
/// `lj = ln det F`; plane stress: `ln(det F · s)`).
fn nh_tangent<const D: usize>(
    fit: &SMatrix<f64, D, D>,
    mu: f64,
    lambda: f64,
    lj: f64,
) -> PiolaDerivative<D> {
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
    dp
}

impl<const D: usize> Law<D> for NeoHookeanLaw
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
    fn name(&self) -> &'static str {
        if D == 2 {
            "neo_hookean"
        } else {
            "neo_hookean3d"
        }
    }

    fn density(&self, f: &SMatrix<f64, D, D>) -> f64 {
        let j = f.determinant();
        if j <= 0.0 {
            return f64::INFINITY;
        }
        let lj = j.ln();
        0.5 * self.mu * (f.norm_squared() - D as f64) - self.mu * lj + 0.5 * self.lambda * lj * lj
    }

    fn piola(&self, f: &SMatrix<f64, D, D>) -> Option<SMatrix<f64, D, D>> {
        let j = f.determinant();
        if j <= 0.0 {
            return None;
        }
        let fit = f.try_inverse()?.transpose();
        Some((f - fit) * self.mu + fit * (self.lambda * j.ln()))
    }

    fn tangent(&self, f: &SMatrix<f64, D, D>) -> Option<PiolaDerivative<D>> {
        let j = f.determinant();
        if j <= 0.0 {
            return None;
        }
        let fit = f.try_inverse()?.transpose();
        Some(nh_tangent(&fit, self.mu, self.lambda, j.ln()))
    }

    fn cauchy(&self, f: &SMatrix<f64, D, D>) -> Option<Matrix3<f64>> {
        let p = self.piola(f)?;
        let j = f.determinant();
        let mut s = embed3(&((p * f.transpose()) / j));
        // plane strain: P_zz = μ (1 − 1) + λ ln J (F_zz = 1)
        s[(2, 2)] = if D == 2 {
            self.lambda * j.ln() / j
        } else {
            s[(2, 2)]
        };
        Some(s)
    }
}

/// The compressible neo-Hookean law in plane stress (2D): the out-of-plane stretch
/// minimizes the 3D energy (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeoHookeanPlaneStress {
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ` (of the 3D material).
    pub lambda: f64,
}

impl NeoHookeanPlaneStress {
    /// The out-of-plane stretch `s` of `J = det F > 0`: the root of
    /// `μ (s² − 1) + λ ln(J s) = 0`.
    pub fn stretch(&self, j: f64) -> f64 {
        let (mu, la) = (self.mu, self.lambda);
        if la == 0.0 {
            return 1.0;
        }
        let lj = j.ln();
        // g(t) = μ (e^{2t} − 1) + λ (ln J + t), increasing and convex in t = ln s
        let g = |t: f64| mu * ((2.0 * t).exp() - 1.0) + la * (lj + t);
        // start where g ≥ 0 (Newton then decreases monotonically to the root): t = 0 if
        // ln J ≥ 0, else t = −ln J (g = μ(J⁻² − 1) ≥ 0 there)
        let mut t = if lj >= 0.0 { 0.0 } else { -lj };
        for _ in 0..100 {
            let gt = g(t);
            let dg = 2.0 * mu * (2.0 * t).exp() + la;
            let step = gt / dg;
            t -= step;
            if step.abs() <= 1e-15 * (1.0 + t.abs()) {
                break;
            }
        }
        t.exp()
    }
}

impl Law<2> for NeoHookeanPlaneStress {
    fn name(&self) -> &'static str {
        "neo_hookean_plane_stress"
    }

    fn density(&self, f: &Matrix2<f64>) -> f64 {
        let j = f.determinant();
        if j <= 0.0 {
            return f64::INFINITY;
        }
        let s = self.stretch(j);
        let ljs = (j * s).ln();
        0.5 * self.mu * (f.norm_squared() + s * s - 3.0) - self.mu * ljs
            + 0.5 * self.lambda * ljs * ljs
    }

    fn piola(&self, f: &Matrix2<f64>) -> Option<Matrix2<f64>> {
        let j = f.determinant();
        if j <= 0.0 {
            return None;
        }
        let s = self.stretch(j);
        let fit = f.try_inverse()?.transpose();
        Some((f - fit) * self.mu + fit * (self.lambda * (j * s).ln()))
    }

    fn tangent(&self, f: &Matrix2<f64>) -> Option<PiolaDerivative<2>> {
        let j = f.determinant();
        if j <= 0.0 {
            return None;
        }
        let s = self.stretch(j);
        let fit = f.try_inverse()?.transpose();
        let mut dp = nh_tangent(&fit, self.mu, self.lambda, (j * s).ln());
        let c = self.lambda * self.lambda / (2.0 * self.mu * s * s + self.lambda);
        for (a, dpa) in dp.iter_mut().enumerate() {
            for (b, dpab) in dpa.iter_mut().enumerate() {
                for (k, dpabk) in dpab.iter_mut().enumerate() {
                    for (l, v) in dpabk.iter_mut().enumerate() {
                        *v -= c * fit[(a, b)] * fit[(k, l)];
                    }
                }
            }
        }
        Some(dp)
    }

    fn cauchy(&self, f: &Matrix2<f64>) -> Option<Matrix3<f64>> {
        let p = self.piola(f)?;
        let j = f.determinant();
        let s = self.stretch(j);
        let mut m = embed3(&((p * f.transpose()) / (j * s)));
        m[(2, 2)] = 0.0;
        Some(m)
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
                    law: nh.law,
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
pub(crate) mod tests_3d {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use nalgebra::{DMatrix, Matrix3, Rotation3, Vector3};
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
        let (mu, la, s) = (nh.law.mu, nh.law.lambda, 1.3f64);
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
                    law: nh.law,
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

#[cfg(test)]
mod tests_plane_stress {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use crate::energy::material::{Elasticity, Plane};
    use crate::energy::LinearElastic2d;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A jittered 3×3-vertex grid (8 triangles) and an affine deformation of it with noise.
    fn config(rng: &mut ChaCha8Rng, amp: f64) -> (Vec<f64>, Vec<[usize; 3]>, Vec<f64>) {
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
                tris.push([v, v + 4, v + 3]);
            }
        }
        let a = Matrix2::new(
            1.0 + rng.gen_range(-amp..amp),
            rng.gen_range(-amp..amp),
            rng.gen_range(-amp..amp),
            1.0 + rng.gen_range(-amp..amp),
        );
        let mut x = xr.clone();
        for v in 0..9 {
            let p = a * nalgebra::Vector2::new(xr[2 * v], xr[2 * v + 1]);
            x[2 * v] = p.x + rng.gen_range(-0.02..0.02);
            x[2 * v + 1] = p.y + rng.gen_range(-0.02..0.02);
        }
        (xr, tris, x)
    }

    #[test]
    fn energy_neo_hookean_plane_stress_fd_and_projection() {
        let mut rng = ChaCha8Rng::seed_from_u64(61);
        for k in 0..16 {
            let (xr, tris, x) = config(&mut rng, if k < 8 { 0.2 } else { 0.4 });
            let nh = NeoHookeanPlaneStress2d::new(
                tris,
                &xr,
                rng.gen_range(0.5..2.0),
                rng.gen_range(0.0..5.0),
            );
            if !nh.value(&x).is_finite() {
                continue;
            }
            let mut g = vec![0.0; x.len()];
            nh.add_gradient(&x, &mut g);
            assert!(rel(&g, &fd_gradient(&nh, &x, 1e-6)) <= 1e-6);
            let mut h = Hessian::default();
            nh.add_hessian(&x, false, &mut h);
            let hd = h.to_dense(x.len());
            let r = rel(hd.as_slice(), fd_hessian(&nh, &x, 1e-6).as_slice());
            assert!(r <= 1e-5, "rel {r}");
            let mut hp = Hessian::default();
            nh.add_hessian(&x, true, &mut hp);
            let hp = hp.to_dense(x.len());
            assert!(hp.symmetric_eigenvalues().min() >= -1e-10 * hp.norm().max(1.0));
        }
    }

    #[test]
    fn energy_neo_hookean_plane_stress_zero_sigma_zz_rigid_invariant_small_strain() {
        let law = NeoHookeanPlaneStress {
            mu: 1.3,
            lambda: 2.9,
        };
        // the stretch makes the 3D P_zz = μ (s − 1/s) + λ ln(J s)/s vanish
        for j in [0.3, 0.9, 1.0, 1.2, 4.0] {
            let s = law.stretch(j);
            let pzz = law.mu * (s - 1.0 / s) + law.lambda * (j * s).ln() / s;
            assert!(pzz.abs() <= 1e-13, "J = {j}: P_zz = {pzz}");
        }
        // rigid motions: zero energy and force
        let mut rng = ChaCha8Rng::seed_from_u64(62);
        let (xr, tris, x) = config(&mut rng, 0.2);
        let nh = NeoHookeanPlaneStress2d::triangles(tris.clone(), &xr, law);
        let (c, sn) = (0.8f64.cos(), 0.8f64.sin());
        let rigid = |y: &[f64]| -> Vec<f64> {
            y.chunks(2)
                .flat_map(|p| [c * p[0] - sn * p[1] + 2.0, sn * p[0] + c * p[1] - 1.0])
                .collect()
        };
        assert!(nh.value(&rigid(&xr)).abs() < 1e-13);
        let v0 = nh.value(&x);
        assert!(((nh.value(&rigid(&x)) - v0) / v0).abs() < 1e-12);
        let mut g = vec![0.0; 18];
        nh.add_gradient(&rigid(&xr), &mut g);
        assert!(g.iter().all(|v| v.abs() < 1e-12));
        // small strain: the linear plane-stress solid (λ* = 2μλ/(λ + 2μ)), σ_zz = 0
        let xs: Vec<f64> = xr.iter().map(|v| v + rng.gen_range(-1e-6..1e-6)).collect();
        let lin = LinearElastic2d::new(tris, &xr, law.mu, law.lambda, Plane::Stress);
        let (mut gn, mut gl) = (vec![0.0; 18], vec![0.0; 18]);
        nh.add_gradient(&xs, &mut gn);
        lin.add_gradient(&xs, &mut gl);
        assert!(rel(&gn, &gl) < 1e-4, "{}", rel(&gn, &gl));
        let st = nh.element_stress(&x).unwrap();
        assert!(st.sigma.iter().all(|s| s[(2, 2)] == 0.0));
        let m = Elasticity {
            mu: law.mu,
            lambda: law.lambda,
        };
        assert!((m.plane_stress_lambda() - lin.law.lambda).abs() < 1e-15);
    }

    #[test]
    fn energy_neo_hookean_cauchy_stress_of_a_uniform_stretch() {
        // plane strain, F = diag(a, b): σ = (μ(F Fᵀ − I) + λ ln J I)/J, σ_zz = λ ln J / J
        let law = NeoHookeanLaw {
            mu: 1.5,
            lambda: 0.7,
        };
        let (a, b) = (1.2, 0.9);
        let f = Matrix2::new(a, 0.0, 0.0, b);
        let s = Law::<2>::cauchy(&law, &f).unwrap();
        let j: f64 = a * b;
        let sxx = (law.mu * (a * a - 1.0) + law.lambda * j.ln()) / j;
        let syy = (law.mu * (b * b - 1.0) + law.lambda * j.ln()) / j;
        assert!((s[(0, 0)] - sxx).abs() < 1e-14 && (s[(1, 1)] - syy).abs() < 1e-14);
        assert!((s[(2, 2)] - law.lambda * j.ln() / j).abs() < 1e-14);
        assert_eq!(s[(0, 1)], 0.0);
    }
}
