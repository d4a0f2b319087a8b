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

use super::{chunked_sum, chunked_triplets, par_scatter, push_block, Energy, Hessian, TermKind};
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use nalgebra::DMatrix;
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
            for e in 0..nh.triangles.len() {
                let he = nh.element_hessian(&x, e).unwrap();
                let ev = he.symmetric_eigenvalues();
                let mut one = NeoHookean2d {
                    triangles: vec![nh.triangles[e]],
                    dm_inv: vec![nh.dm_inv[e]],
                    area: vec![nh.area[e]],
                    mu: nh.mu,
                    lambda: nh.lambda,
                };
                one.triangles[0] = [0, 1, 2];
                let mut xe = vec![0.0; 6];
                for (a, &v) in nh.triangles[e].iter().enumerate() {
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
        let indefinite = (0..nh.triangles.len())
            .filter(|&e| {
                nh.element_hessian(&x, e)
                    .unwrap()
                    .symmetric_eigenvalues()
                    .min()
                    < 0.0
            })
            .count();
        assert!(indefinite > 0, "the projection should be exercised");
        // one inverted element: +∞, still thread independent
        let t = nh.triangles[3 * CHUNK + 1];
        x.swap(2 * t[1], 2 * t[2]);
        x.swap(2 * t[1] + 1, 2 * t[2] + 1);
        let bits = assert_thread_independent(|| term_bits(&nh, &x));
        assert_eq!(f64::from_bits(bits[0]), f64::INFINITY);
    }
}
