//! Hyperelastic membrane of P1 triangles in 3D (a surface in space): St Venant–Kirchhoff
//! membrane model (e.g. Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §6.4.1, written
//! on the tangent plane of the surface).
//!
//! Each triangle `(X0, X1, X2)` gets a reference 2D frame in its own plane: the orthonormal
//! basis `e1 = (X1 − X0)/|X1 − X0|`, `e2 = n × e1` (`n` the unit normal), in which the reference
//! edge matrix is `Dm = [[e1·(X1 − X0), e1·(X2 − X0)], [e2·(X1 − X0), e2·(X2 − X0)]]` (2×2,
//! upper triangular, `det Dm = 2 |T_ref| > 0`). With the deformed edges
//! `Ds = [x1 − x0, x2 − x0]` (3×2):
//!
//! ```text
//! F = Ds Dm⁻¹ (3×2),   E = ½ (FᵀF − I) (2×2, Green strain),
//! W(F) = μ |E|² + λ/2 (tr E)²,        J(x) = Σ_T |T_ref| W(F_T).
//! ```
//!
//! `W` only sees the metric `FᵀF` of the deformed triangle, so `J` is invariant under rigid
//! motions (and reflections) and vanishes at the reference. The first Piola–Kirchhoff stress
//! (3×2) and its derivative are, with `S = 2μ E + λ tr(E) I` the second one,
//!
//! ```text
//! P = F S,
//! ∂P_ij/∂F_cd = δ_ic S_dj + μ (F_id F_cj + (F Fᵀ)_ic δ_jd) + λ F_ij F_cd.
//! ```
//!
//! Writing `F_kl = Σ_a x_{a,k} G_{a,l}` with `G = [−(B_0+B_1); B_0; B_1]` (`B = Dm⁻¹`, rows
//! `B_m`), the element gradient is `∂/∂x_{a,c} = |T| Σ_l P_cl G_al` and the 9×9 element
//! Hessian is `|T| Σ_{l,n} ∂P_cl/∂F_dn G_al G_bn` at dofs `(3a + c, 3b + d)`. It is indefinite
//! in compression (a compressed membrane buckles: `S` has a negative eigenvalue); with
//! `projected = true` each element Hessian's negative eigenvalues are clamped to zero
//! (symmetric eigendecomposition, `energy::project_psd`), an element Hessian
//! that is already positive semi-definite being kept as is.
//!
//! The energy is finite everywhere (St Venant–Kirchhoff does not prevent a triangle from
//! collapsing or flipping).

use super::{
    chunked_sum, chunked_triplets, par_scatter, project_psd, push_block, Energy, Hessian, TermKind,
};
use nalgebra::{Matrix2, Matrix3x2, SMatrix, Vector3};

const DIM: usize = 3;

/// 9×9 element Hessian (3 vertices × 3 dofs).
pub(crate) type Matrix9 = SMatrix<f64, 9, 9>;

/// St Venant–Kirchhoff membrane energy of a set of triangles in 3D.
#[derive(Clone, Debug)]
pub struct Membrane3dEnergy {
    /// Triangles `[v0, v1, v2]`.
    pub triangles: Vec<[usize; 3]>,
    /// `Dm⁻¹` per triangle (in the triangle's reference 2D frame).
    pub dm_inv: Vec<Matrix2<f64>>,
    /// Reference area per triangle (positive).
    pub area: Vec<f64>,
    /// Shear modulus `μ`.
    pub mu: f64,
    /// Lamé's first parameter `λ` of the membrane's 2D law. (`μ` and `λ` are per unit
    /// reference area, the thickness folded in; for a thin sheet of a 3D material `(μ, λ₃)`
    /// the plane-stress value is `λ = 2μλ₃/(λ₃ + 2μ)`.)
    pub lambda: f64,
}

impl Membrane3dEnergy {
    /// Builds the energy from reference positions `x_ref` (flat, 3D). Either orientation of a
    /// triangle gives the same energy; degenerate triangles must not be passed.
    pub fn new(triangles: Vec<[usize; 3]>, x_ref: &[f64], mu: f64, lambda: f64) -> Self {
        let mut dm_inv = Vec::with_capacity(triangles.len());
        let mut area = Vec::with_capacity(triangles.len());
        for t in &triangles {
            let ds = ds(x_ref, t);
            let (d1, d2) = (ds.column(0), ds.column(1));
            let e1 = d1.normalize();
            let e2 = d1.cross(&d2).cross(&d1).normalize();
            let dm = Matrix2::new(e1.dot(&d1), e1.dot(&d2), 0.0, e2.dot(&d2));
            area.push(0.5 * dm.determinant());
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

    /// Deformation gradient (3×2) of element `e`.
    pub fn deformation_gradient(&self, x: &[f64], e: usize) -> Matrix3x2<f64> {
        ds(x, &self.triangles[e]) * self.dm_inv[e]
    }

    /// `(E, S)`: Green strain and second Piola–Kirchhoff stress.
    fn strain_stress(&self, f: &Matrix3x2<f64>) -> (Matrix2<f64>, Matrix2<f64>) {
        let e = (f.transpose() * f - Matrix2::identity()) * 0.5;
        let s = e * (2.0 * self.mu) + Matrix2::identity() * (self.lambda * e.trace());
        (e, s)
    }

    fn energy_density(&self, f: &Matrix3x2<f64>) -> f64 {
        let (e, _) = self.strain_stress(f);
        let tr = e.trace();
        self.mu * e.norm_squared() + 0.5 * self.lambda * tr * tr
    }

    /// Exact 9×9 element Hessian.
    fn element_hessian(&self, x: &[f64], e: usize) -> Matrix9 {
        let f = self.deformation_gradient(x, e);
        let (_, s) = self.strain_stress(&f);
        let fft = f * f.transpose();
        let (mu, la) = (self.mu, self.lambda);
        // ∂P_cl/∂F_dn at [2c + l][2d + n]
        let mut dp = [[0.0; 2 * DIM]; 2 * DIM];
        for c in 0..DIM {
            for l in 0..2 {
                for d in 0..DIM {
                    for n in 0..2 {
                        let mut v = mu * f[(c, n)] * f[(d, l)] + la * f[(c, l)] * f[(d, n)];
                        if c == d {
                            v += s[(n, l)];
                        }
                        if l == n {
                            v += mu * fft[(c, d)];
                        }
                        dp[2 * c + l][2 * d + n] = v;
                    }
                }
            }
        }
        let g = self.grad_op(e);
        // t[2c + l][3b + d] = Σ_n ∂P_cl/∂F_dn G_bn
        let mut t = [[0.0; 3 * DIM]; 2 * DIM];
        for (cl, trow) in t.iter_mut().enumerate() {
            for b in 0..3 {
                for d in 0..DIM {
                    trow[DIM * b + d] = dp[cl][2 * d] * g[b][0] + dp[cl][2 * d + 1] * g[b][1];
                }
            }
        }
        let mut h = Matrix9::zeros();
        for a in 0..3 {
            for c in 0..DIM {
                for bd in 0..3 * DIM {
                    let v = g[a][0] * t[2 * c][bd] + g[a][1] * t[2 * c + 1][bd];
                    h[(DIM * a + c, bd)] = self.area[e] * v;
                }
            }
        }
        (h + h.transpose()) * 0.5
    }
}

fn ds(x: &[f64], t: &[usize; 3]) -> Matrix3x2<f64> {
    Matrix3x2::from_fn(|k, m| x[DIM * t[m + 1] + k] - x[DIM * t[0] + k])
}

impl Energy for Membrane3dEnergy {
    fn name(&self) -> &str {
        "membrane3d"
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        chunked_sum(self.triangles.len(), |r| {
            let mut s = 0.0;
            for e in r {
                s += self.area[e] * self.energy_density(&self.deformation_gradient(x, e));
            }
            s
        })
    }

    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        par_scatter(
            self.triangles.len(),
            g,
            |e| {
                let f = self.deformation_gradient(x, e);
                let (_, s) = self.strain_stress(&f);
                let p = f * s;
                let gop = self.grad_op(e);
                let mut ge = [Vector3::zeros(); 3];
                for (a, gea) in ge.iter_mut().enumerate() {
                    *gea = (p.column(0) * gop[a][0] + p.column(1) * gop[a][1]) * self.area[e];
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

    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        chunked_triplets(self.triangles.len(), &mut h.triplets, |e, out| {
            let mut he = self.element_hessian(x, e);
            if projected {
                project_psd(&mut he);
            }
            push_block(out, DIM, &self.triangles[e], |r, c| he[(r, c)]);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use nalgebra::{DMatrix, Matrix3, Rotation3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// An `m×m`-vertex grid on the saddle `z = 0.3 (x² − y²)` (perturbed, mixed triangle
    /// orientations). Returns `(x_ref, triangles)`.
    fn saddle(rng: &mut ChaCha8Rng, m: usize) -> (Vec<f64>, Vec<[usize; 3]>) {
        let h = 1.0 / (m - 1) as f64;
        let mut xr = Vec::with_capacity(3 * m * m);
        for j in 0..m {
            for i in 0..m {
                let px = i as f64 * h + rng.gen_range(-0.1..0.1) * h;
                let py = j as f64 * h + rng.gen_range(-0.1..0.1) * h;
                xr.extend([px, py, 0.3 * (px * px - py * py)]);
            }
        }
        let mut tris = Vec::new();
        for j in 0..m - 1 {
            for i in 0..m - 1 {
                let v = m * j + i;
                tris.push([v, v + 1, v + m + 1]);
                tris.push([v, v + m + 1, v + m]);
                if (i + j) % 2 == 1 {
                    let t = tris.len() - 1;
                    tris[t].swap(1, 2); // clockwise seen from +z
                }
            }
        }
        (xr, tris)
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

    /// A 4×4-vertex saddle patch (18 triangles) under a random map `scale·R(I + A)`
    /// (`|A_ij| < 0.25`, `R` a random rotation) plus vertex noise: stretched for `scale > 1`,
    /// compressed for `scale < 1`.
    fn config(rng: &mut ChaCha8Rng, scale: f64) -> (Membrane3dEnergy, Vec<f64>) {
        let (xr, tris) = saddle(rng, 4);
        let m = Membrane3dEnergy::new(tris, &xr, rng.gen_range(0.5..2.0), rng.gen_range(0.5..5.0));
        let r = Rotation3::from_euler_angles(
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-1.5..1.5),
            rng.gen_range(-3.0..3.0),
        );
        let a =
            Matrix3::from_fn(|i, j| (if i == j { 1.0 } else { 0.0 }) + rng.gen_range(-0.25..0.25));
        let x = deform(rng, &xr, &(r.matrix() * a * scale), 0.03);
        (m, x)
    }

    #[test]
    fn energy_membrane3d_reference_frame_and_known_values() {
        // right triangle with legs 2 and 1, tilted out of the xy plane
        let xr = [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.6, 0.8];
        let m = Membrane3dEnergy::new(vec![[0, 1, 2]], &xr, 1.5, 2.0);
        assert!((m.area[0] - 1.0).abs() < 1e-15);
        let f = m.deformation_gradient(&xr, 0);
        assert!((f.transpose() * f - Matrix2::identity()).norm() < 1e-15);
        assert!(m.value(&xr).abs() < 1e-30);
        // the reversed triangle: same area and energy
        let mr = Membrane3dEnergy::new(vec![[0, 2, 1]], &xr, 1.5, 2.0);
        assert!((mr.area[0] - 1.0).abs() < 1e-15);
        // uniform in-plane stretch by s: E = (s² − 1)/2 I, W = (2μ + 2λ) ((s² − 1)/2)²
        let s = 1.5;
        let x: Vec<f64> = xr.iter().map(|v| s * v).collect();
        let e = 0.5 * (s * s - 1.0);
        let w = (2.0 * 1.5 + 2.0 * 2.0) * e * e;
        assert!((m.value(&x) - w).abs() < 1e-14, "{} vs {w}", m.value(&x));
        assert!((mr.value(&x) - w).abs() < 1e-14);
        // uniaxial stretch along the leg X1 − X0 by s: E = diag((s² − 1)/2, 0)
        let mut x = xr.to_vec();
        x[3] = 2.0 * s;
        let w = (1.5 + 0.5 * 2.0) * e * e;
        assert!((m.value(&x) - w).abs() < 1e-14, "{} vs {w}", m.value(&x));
    }

    #[test]
    fn energy_membrane3d_rest_is_zero_and_rigid_invariant() {
        let mut rng = ChaCha8Rng::seed_from_u64(20);
        let (xr, tris) = saddle(&mut rng, 5);
        let m = Membrane3dEnergy::new(tris, &xr, 1.3, 2.2);
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
        for xm in [xr.clone(), rigid(&xr)] {
            assert!(m.value(&xm).abs() < 1e-28, "{}", m.value(&xm));
            let mut g = vec![0.0; xm.len()];
            m.add_gradient(&xm, &mut g);
            assert!(g.iter().all(|v| v.abs() < 1e-13));
        }
        for scale in [1.3, 0.8] {
            let (m, x) = config(&mut rng, scale);
            let v0 = m.value(&x);
            let v1 = m.value(&rigid(&x));
            assert!(v0 > 0.0 && ((v1 - v0) / v0).abs() < 1e-12, "{v0} {v1}");
        }
    }

    #[test]
    fn energy_membrane3d_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5; stretched and compressed
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for k in 0..12 {
            let (m, x) = config(&mut rng, [1.0, 1.4, 0.7][k % 3]);
            assert!(m.value(&x) > 0.0);
            let mut g = vec![0.0; x.len()];
            m.add_gradient(&x, &mut g);
            let gf = fd_gradient(&m, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-5, "rel {}", rel(&g, &gf));
        }
    }

    #[test]
    fn energy_membrane3d_hessian_fd_and_projection() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(22);
        let (mut saw_indefinite, mut saw_psd) = (false, false);
        for k in 0..12 {
            let (m, x) = config(&mut rng, [1.0, 1.4, 0.7][k % 3]);
            let n = x.len();
            let mut h = Hessian::default();
            m.add_hessian(&x, false, &mut h);
            let hd = h.to_dense(n);
            let hf = fd_hessian(&m, &x, 1e-6);
            let r = rel(hd.as_slice(), hf.as_slice());
            assert!(r <= 1e-5, "rel {r}");
            let mut hp = Hessian::default();
            m.add_hessian(&x, true, &mut hp);
            let hpd = hp.to_dense(n);
            let scale = hpd.norm().max(1.0);
            assert!(hpd.symmetric_eigenvalues().min() >= -1e-10 * scale);
            // element by element: projected is PSD, and equals the exact one when that is PSD
            for e in 0..m.triangles.len() {
                let he = m.element_hessian(&x, e);
                let ev = he.symmetric_eigenvalues();
                let one = Membrane3dEnergy {
                    triangles: vec![[0, 1, 2]],
                    dm_inv: vec![m.dm_inv[e]],
                    area: vec![m.area[e]],
                    mu: m.mu,
                    lambda: m.lambda,
                };
                let mut xe = vec![0.0; 9];
                for (a, &v) in m.triangles[e].iter().enumerate() {
                    xe[3 * a..3 * a + 3].copy_from_slice(&x[3 * v..3 * v + 3]);
                }
                let mut hpe = Hessian::default();
                one.add_hessian(&xe, true, &mut hpe);
                let hpe = hpe.to_dense(9);
                let s = he.norm().max(1.0);
                assert!(hpe.symmetric_eigenvalues().min() >= -1e-10 * s);
                if ev.min() >= 0.0 {
                    saw_psd = true;
                    let hed = DMatrix::from_column_slice(9, 9, he.as_slice());
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
    fn energy_membrane3d_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        // a 70×70-vertex saddle (> 2 chunks of triangles), part stretched and part compressed
        let mut rng = ChaCha8Rng::seed_from_u64(23);
        let (xr, tris) = saddle(&mut rng, 70);
        assert!(tris.len() > 2 * CHUNK);
        let m = Membrane3dEnergy::new(tris, &xr, 1.3, 4.0);
        let a = Matrix3::new(1.4, 0.3, 0.1, -0.2, 0.6, 0.2, 0.1, -0.1, 0.9);
        let x = deform(&mut rng, &xr, &a, 0.005);
        let bits = assert_thread_independent(|| term_bits(&m, &x));
        assert!(f64::from_bits(bits[0]) > 0.0);
        let (mut h, mut hp) = (Hessian::default(), Hessian::default());
        m.add_hessian(&x, false, &mut h);
        m.add_hessian(&x, true, &mut hp);
        assert!(h != hp, "the projection should be exercised");
    }
}
