//! The small-strain linear-elastic solid (P1 triangles in 2D, plane strain or plane stress;
//! tetrahedra in 3D), for comparisons with linear theory (Hertz contact, the patch test). The
//! element engine is [`P1Solid`](super::solid::P1Solid); docs/materials.md has the formulas.
//!
//! With the displacement gradient `∇u = F − I` and the small strain `ε = sym(∇u)`:
//!
//! ```text
//! W(F) = μ ε:ε + λ/2 (tr ε)²,   P = σ = 2μ ε + λ (tr ε) I,
//! ∂P_cl/∂F_dn = μ (δ_cd δ_ln + δ_cn δ_ld) + λ δ_cl δ_dn   (constant),
//! ```
//!
//! `tr` and `I` in `D` dimensions. **Plane strain** (2D): `ε_zz = 0`, the in-plane law is the
//! one above with the 3D `λ`, and `σ_zz = λ (ε_xx + ε_yy)`. **Plane stress** (2D): `σ_zz = 0`;
//! eliminating `ε_zz = −λ/(λ + 2μ) (ε_xx + ε_yy)` leaves the same in-plane form with
//! `λ* = 2μλ/(λ + 2μ)` ([`super::material::Elasticity::plane_stress_lambda`]).
//!
//! `J` is a quadratic form of the displacement: its Hessian is constant and positive
//! semi-definite (never projected, [`Law::convex`]), so one QP is a whole sub-problem.
//! **Not rotation invariant**: `ε` is the linearized strain, so a finite rigid rotation by θ
//! stores energy — in 2D `ε = (cos θ − 1) I` and `W = 2(μ + λ)(1 − cos θ)² ≈ (μ + λ)θ⁴/2`
//! per unit area — while the linearized rotation (`∇u` skew) and translations cost nothing. The
//! model is meant for small displacements and rotations. An inverted element has a finite
//! energy: linear theory does not see inversion.

use super::material::Plane;
pub use super::solid::DegenerateTet;
use super::solid::{embed3, Law, P1Solid, PiolaDerivative};
use nalgebra::{Matrix3, SMatrix};

/// The linear-elastic law in `D` dimensions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearLaw {
    /// Shear modulus `μ`.
    pub mu: f64,
    /// The in-plane (2D) or 3D Lamé constant: `λ` (plane strain, 3D) or `λ*` (plane stress).
    pub lambda: f64,
    /// `σ_zz = lambda_zz · tr ε` in 2D: `λ` in plane strain, 0 in plane stress.
    pub lambda_zz: f64,
}

impl LinearLaw {
    /// The law of a material of Lamé constants `mu`, `lambda`: in 2D in `plane` strain or
    /// stress (ignored in 3D).
    pub fn new(mu: f64, lambda: f64, plane: Plane) -> Self {
        match plane {
            Plane::Strain => LinearLaw {
                mu,
                lambda,
                lambda_zz: lambda,
            },
            Plane::Stress => LinearLaw {
                mu,
                lambda: super::material::Elasticity { mu, lambda }.plane_stress_lambda(),
                lambda_zz: 0.0,
            },
        }
    }

    /// `ε = sym(F) − I` and its trace.
    fn strain<const D: usize>(f: &SMatrix<f64, D, D>) -> (SMatrix<f64, D, D>, f64) {
        let e = (f + f.transpose()) * 0.5 - SMatrix::<f64, D, D>::identity();
        let tr = e.trace();
        (e, tr)
    }
}

/// Linear-elastic triangles (2D; plane strain or stress as the law says).
pub type LinearElastic2d = P1Solid<2, 3, LinearLaw>;

/// Linear-elastic tetrahedra (3D).
pub type LinearElastic3d = P1Solid<3, 4, LinearLaw>;

impl LinearElastic2d {
    /// Builds the energy from reference positions `x_ref` (flat, 2D).
    pub fn new(
        triangles: Vec<[usize; 3]>,
        x_ref: &[f64],
        mu: f64,
        lambda: f64,
        plane: Plane,
    ) -> Self {
        Self::triangles(triangles, x_ref, LinearLaw::new(mu, lambda, plane))
    }
}

impl LinearElastic3d {
    /// Builds the energy from reference positions `x_ref` (flat, 3D).
    pub fn new(
        tets: Vec<[usize; 4]>,
        x_ref: &[f64],
        mu: f64,
        lambda: f64,
    ) -> Result<Self, DegenerateTet> {
        Self::tets(tets, x_ref, LinearLaw::new(mu, lambda, Plane::Strain))
    }
}

impl<const D: usize> Law<D> for LinearLaw {
    fn name(&self) -> &'static str {
        if D == 2 {
            "linear_elastic"
        } else {
            "linear_elastic3d"
        }
    }

    fn density(&self, f: &SMatrix<f64, D, D>) -> f64 {
        let (e, tr) = Self::strain(f);
        self.mu * e.norm_squared() + 0.5 * self.lambda * tr * tr
    }

    fn piola(&self, f: &SMatrix<f64, D, D>) -> Option<SMatrix<f64, D, D>> {
        let (e, tr) = Self::strain(f);
        Some(e * (2.0 * self.mu) + SMatrix::<f64, D, D>::identity() * (self.lambda * tr))
    }

    fn tangent(&self, _f: &SMatrix<f64, D, D>) -> Option<PiolaDerivative<D>> {
        let mut dp = [[[[0.0; D]; D]; D]; D];
        let delta = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
        for (c, dpc) in dp.iter_mut().enumerate() {
            for (l, dpcl) in dpc.iter_mut().enumerate() {
                for (d, dpcld) in dpcl.iter_mut().enumerate() {
                    for (n, v) in dpcld.iter_mut().enumerate() {
                        *v = self.mu * (delta(c, d) * delta(l, n) + delta(c, n) * delta(l, d))
                            + self.lambda * delta(c, l) * delta(d, n);
                    }
                }
            }
        }
        Some(dp)
    }

    fn cauchy(&self, f: &SMatrix<f64, D, D>) -> Option<Matrix3<f64>> {
        let p = self.piola(f)?;
        let mut s = embed3(&p);
        if D == 2 {
            s[(2, 2)] = self.lambda_zz * Self::strain(f).1;
        }
        Some(s)
    }

    fn convex(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use crate::energy::material::Elasticity;
    use crate::energy::{Energy, Hessian};
    use nalgebra::{Matrix2, Rotation3, Vector2, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// An `m×m`-vertex jittered grid of the square `[0, 1]²` (2(m−1)² triangles, the
    /// diagonals alternating), and which vertices are interior.
    pub(crate) fn grid2(rng: &mut ChaCha8Rng, m: usize) -> (Vec<f64>, Vec<[usize; 3]>, Vec<bool>) {
        let h = 1.0 / (m - 1) as f64;
        let mut x = Vec::new();
        let mut interior = Vec::new();
        for j in 0..m {
            for i in 0..m {
                let inner = i > 0 && j > 0 && i + 1 < m && j + 1 < m;
                let jit = if inner { 0.25 * h } else { 0.0 };
                x.push(i as f64 * h + rng.gen_range(-jit..=jit));
                x.push(j as f64 * h + rng.gen_range(-jit..=jit));
                interior.push(inner);
            }
        }
        let mut t = Vec::new();
        for j in 0..m - 1 {
            for i in 0..m - 1 {
                let v = m * j + i;
                if (i + j) % 2 == 0 {
                    t.push([v, v + 1, v + m + 1]);
                    t.push([v, v + m + 1, v + m]);
                } else {
                    t.push([v, v + 1, v + m]);
                    t.push([v + 1, v + m + 1, v + m]);
                }
            }
        }
        (x, t, interior)
    }

    /// The 2×2×2 cube grid of side 0.5 split into 48 tets (the neo-Hookean tests' grid),
    /// jittered.
    fn grid3(rng: &mut ChaCha8Rng) -> (Vec<f64>, Vec<[usize; 4]>) {
        let (x, tets) = crate::energy::neo_hookean::tests_3d::cube_grid(2, 0.5);
        (perturb(rng, &x, 0.04), tets)
    }

    fn perturb(rng: &mut ChaCha8Rng, x: &[f64], a: f64) -> Vec<f64> {
        x.iter().map(|v| v + rng.gen_range(-a..a)).collect()
    }

    /// Value, gradient and Hessian against central differences; the Hessian is constant and
    /// positive semi-definite, and the projected one equals the exact one.
    fn check_fd(e: &dyn Energy, x: &[f64], y: &[f64]) {
        let mut g = vec![0.0; x.len()];
        e.add_gradient(x, &mut g);
        assert!(rel(&g, &fd_gradient(e, x, 1e-6)) <= 1e-7, "gradient");
        let (mut h, mut hy, mut hp) = (Hessian::default(), Hessian::default(), Hessian::default());
        e.add_hessian(x, false, &mut h);
        e.add_hessian(y, false, &mut hy);
        e.add_hessian(x, true, &mut hp);
        let hd = h.to_dense(x.len());
        assert!(
            rel(hd.as_slice(), fd_hessian(e, x, 1e-5).as_slice()) <= 1e-7,
            "hessian"
        );
        assert_eq!(h, hy, "the Hessian is constant");
        assert_eq!(h, hp, "a convex law is not projected");
        let s = hd.norm();
        assert!(hd.symmetric_eigenvalues().min() >= -1e-12 * s);
        // a quadratic: J(y) = J(x) + g·(y − x) + ½ (y − x)ᵀ H (y − x)
        let d: Vec<f64> = y.iter().zip(x).map(|(a, b)| a - b).collect();
        let dv = nalgebra::DVector::from_column_slice(&d);
        let taylor = e.value(x)
            + g.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>()
            + 0.5 * (dv.transpose() * &hd * &dv)[0];
        assert!((e.value(y) - taylor).abs() <= 1e-12 * e.value(y).abs().max(1.0));
    }

    #[test]
    fn energy_linear_elastic_fd_constant_hessian_and_quadratic() {
        let mut rng = ChaCha8Rng::seed_from_u64(51);
        let (xr, tris, _) = grid2(&mut rng, 4);
        for plane in [Plane::Strain, Plane::Stress] {
            let le = LinearElastic2d::new(tris.clone(), &xr, 1.3, 2.2, plane);
            let x = perturb(&mut rng, &xr, 0.05);
            let y = perturb(&mut rng, &xr, 0.08);
            check_fd(&le, &x, &y);
        }
        let (xr, tets) = grid3(&mut rng);
        let le = LinearElastic3d::new(tets, &xr, 0.7, 3.1).unwrap();
        let x = perturb(&mut rng, &xr, 0.05);
        let y = perturb(&mut rng, &xr, 0.08);
        check_fd(&le, &x, &y);
    }

    #[test]
    fn energy_linear_elastic_translations_are_free_finite_rotations_are_not() {
        let mut rng = ChaCha8Rng::seed_from_u64(52);
        let (xr, tris, _) = grid2(&mut rng, 4);
        let (mu, la) = (1.3, 2.2);
        let le = LinearElastic2d::new(tris, &xr, mu, la, Plane::Strain);
        let area: f64 = le.measure.iter().sum();
        assert!((area - 1.0).abs() < 1e-12);
        let x = perturb(&mut rng, &xr, 0.05);
        let moved: Vec<f64> = x.chunks(2).flat_map(|p| [p[0] + 3.0, p[1] - 1.5]).collect();
        assert!((le.value(&moved) - le.value(&x)).abs() <= 1e-12 * le.value(&x));
        // the reference rotated by θ: W = 2(μ + λ)(1 − cos θ)² per unit area, not 0
        for theta in [1e-3f64, 0.1, 0.7] {
            let r = Matrix2::new(theta.cos(), -theta.sin(), theta.sin(), theta.cos());
            let xrot: Vec<f64> = xr
                .chunks(2)
                .flat_map(|p| {
                    let q = r * Vector2::new(p[0], p[1]);
                    [q.x, q.y]
                })
                .collect();
            let w = 2.0 * (mu + la) * (1.0 - theta.cos()).powi(2) * area;
            let v = le.value(&xrot);
            assert!(
                (v - w).abs() <= 1e-9 * w.max(1e-300),
                "θ = {theta}: {v} vs {w}"
            );
        }
        // 3D: the same (ε = (cos θ − 1)(I − e eᵀ) about the axis e): W = (2μ + 2λ)(1 − cos θ)²
        let (xr3, tets) = grid3(&mut rng);
        let le3 = LinearElastic3d::new(tets, &xr3, mu, la).unwrap();
        let vol: f64 = le3.measure.iter().sum();
        let theta = 0.4f64;
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), theta);
        let x3: Vec<f64> = xr3
            .chunks(3)
            .flat_map(|p| {
                let q = rot * Vector3::new(p[0], p[1], p[2]);
                [q.x + 1.0, q.y, q.z - 2.0]
            })
            .collect();
        let w = 2.0 * (mu + la) * (1.0 - theta.cos()).powi(2) * vol;
        assert!((le3.value(&x3) - w).abs() <= 1e-9 * w);
    }

    #[test]
    fn energy_linear_elastic_patch_affine_fields_are_exact() {
        // an affine displacement u = A X on an irregular patch: every element has the strain
        // sym(A), the energy is |Ω| W(A), the stress is 2μ ε + λ tr ε I (λ* in plane stress),
        // and the nodal forces vanish at the interior vertices (the P1 patch test)
        let mut rng = ChaCha8Rng::seed_from_u64(53);
        let (xr, tris, interior) = grid2(&mut rng, 6);
        let a = Matrix2::new(0.011, -0.004, 0.007, -0.006);
        let x: Vec<f64> = xr
            .chunks(2)
            .flat_map(|p| {
                let u = a * Vector2::new(p[0], p[1]);
                [p[0] + u.x, p[1] + u.y]
            })
            .collect();
        let m = Elasticity::from_young_poisson(2.0, 0.3).unwrap();
        let eps = (a + a.transpose()) * 0.5;
        let tr = eps.trace();
        for plane in [Plane::Strain, Plane::Stress] {
            let le = LinearElastic2d::new(tris.clone(), &xr, m.mu, m.lambda, plane);
            let lam = match plane {
                Plane::Strain => m.lambda,
                Plane::Stress => m.plane_stress_lambda(),
            };
            let sigma = eps * (2.0 * m.mu) + Matrix2::identity() * (lam * tr);
            let w = m.mu * eps.norm_squared() + 0.5 * lam * tr * tr;
            assert!((le.value(&x) - w).abs() <= 1e-12 * w);
            let st = le.element_stress(&x).unwrap();
            let szz = match plane {
                Plane::Strain => m.lambda * tr,
                Plane::Stress => 0.0,
            };
            for s in &st.sigma {
                for i in 0..2 {
                    for j in 0..2 {
                        assert!((s[(i, j)] - sigma[(i, j)]).abs() <= 1e-14);
                    }
                }
                assert!((s[(2, 2)] - szz).abs() <= 1e-14);
            }
            let mut g = vec![0.0; x.len()];
            le.add_gradient(&x, &mut g);
            let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (v, &inner) in interior.iter().enumerate() {
                if inner {
                    assert!(
                        g[2 * v].abs() <= 1e-12 * gmax && g[2 * v + 1].abs() <= 1e-12 * gmax,
                        "vertex {v}: {} {} (max {gmax})",
                        g[2 * v],
                        g[2 * v + 1]
                    );
                }
            }
            // the boundary forces are the tractions σ n: on the right side x = 1 (length 1),
            // Σ f = σ e_x
            let right: Vec<usize> = (0..xr.len() / 2).filter(|&v| xr[2 * v] == 1.0).collect();
            let fx: f64 = right.iter().map(|&v| g[2 * v]).sum();
            let fy: f64 = right.iter().map(|&v| g[2 * v + 1]).sum();
            // (the corners also get half of the top and bottom edges' σ(±e_y)h, which
            // cancel)
            assert!(
                (fx - sigma[(0, 0)]).abs() <= 1e-13,
                "{fx} vs {}",
                sigma[(0, 0)]
            );
            assert!(
                (fy - sigma[(1, 0)]).abs() <= 1e-13,
                "{fy} vs {}",
                sigma[(1, 0)]
            );
        }
    }

    #[test]
    fn energy_linear_and_neo_hookean_agree_at_small_strain() {
        // at strain 1e-5 the neo-Hookean forces equal the linear ones to O(strain²): plane
        // strain against NeoHookean2d, plane stress against NeoHookeanPlaneStress2d, 3D
        // against NeoHookean3d
        use crate::energy::{NeoHookean2d, NeoHookean3d, NeoHookeanPlaneStress2d};
        let mut rng = ChaCha8Rng::seed_from_u64(54);
        let (xr, tris, _) = grid2(&mut rng, 4);
        let (mu, la) = (1.1, 2.7);
        let x = perturb(&mut rng, &xr, 1e-5);
        let grad = |e: &dyn Energy, x: &[f64]| {
            let mut g = vec![0.0; x.len()];
            e.add_gradient(x, &mut g);
            g
        };
        let pairs: Vec<(Box<dyn Energy>, Box<dyn Energy>)> = vec![
            (
                Box::new(LinearElastic2d::new(
                    tris.clone(),
                    &xr,
                    mu,
                    la,
                    Plane::Strain,
                )),
                Box::new(NeoHookean2d::new(tris.clone(), &xr, mu, la)),
            ),
            (
                Box::new(LinearElastic2d::new(
                    tris.clone(),
                    &xr,
                    mu,
                    la,
                    Plane::Stress,
                )),
                Box::new(NeoHookeanPlaneStress2d::new(tris.clone(), &xr, mu, la)),
            ),
        ];
        for (lin, nh) in &pairs {
            let r = rel(&grad(nh.as_ref(), &x), &grad(lin.as_ref(), &x));
            assert!(r < 1e-3, "{} vs {}: {r}", nh.name(), lin.name());
        }
        let (xr3, tets) = grid3(&mut rng);
        let x3 = perturb(&mut rng, &xr3, 1e-5);
        let lin = LinearElastic3d::new(tets.clone(), &xr3, mu, la).unwrap();
        let nh = NeoHookean3d::new(tets, &xr3, mu, la).unwrap();
        let r = rel(&grad(&nh, &x3), &grad(&lin, &x3));
        assert!(r < 1e-3, "3D: {r}");
    }
}
