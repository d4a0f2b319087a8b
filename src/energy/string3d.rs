//! String energy of a P1 curve in 3D (a cable or rod in space), tension only (Pantz 2008, §7;
//! the 3D counterpart of [`super::membrane`]).
//!
//! The stored energy density is
//!
//! ```text
//! W(F) = μ (|F|² − 1)²   if |F| ≥ 1,      W(F) = 0   otherwise,
//! ```
//!
//! so the string resists stretching but not compression (it may buckle freely). On an edge
//! `(x0, x1)` with reference length `L`, `F = e / L` with `e = x1 − x0 ∈ ℝ³`, and the edge
//! contributes `L · W(F)`. With `s = |e|²/L² − 1`:
//!
//! ```text
//! J_e = μ L s²            (s ≥ 0),
//! ∂J_e/∂x1 = −∂J_e/∂x0 = 4μ s e / L,
//! H = 4μ/L (s I + 2 e eᵀ / L²)   (3×3),   Hessian block [[H, −H], [−H, H]].
//! ```
//!
//! `W` is C¹ at `|F| = 1`; for `|F| > 1`, `s > 0` and `H` is positive definite, and it is `0`
//! for `|F| < 1`, so the exact Hessian is already positive semi-definite: `projected` changes
//! nothing.

/// Tension-only string energy of a set of edges (3D): the generic
/// [`super::membrane::TensionString`] in three dimensions.
pub type String3dEnergy = super::membrane::TensionString<3>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use crate::energy::{Energy, Hessian};
    use nalgebra::{Rotation3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random unit vector.
    fn direction(rng: &mut ChaCha8Rng) -> Vector3<f64> {
        loop {
            let v = Vector3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let n = v.norm();
            if n > 0.1 && n < 1.0 {
                return v / n;
            }
        }
    }

    /// A polyline of `n` vertices along the x axis (reference, perturbed in y and z), then
    /// stretched/compressed edge by edge with factors away from 1 (alternating > 1.15 and
    /// < 0.85), each edge in a random direction of space.
    fn config(rng: &mut ChaCha8Rng, n: usize) -> (String3dEnergy, Vec<f64>) {
        let mut xr = vec![0.0; 3 * n];
        for v in 0..n {
            xr[3 * v] = v as f64 * 0.3 + rng.gen_range(0.0..0.1);
            xr[3 * v + 1] = rng.gen_range(-0.05..0.05);
            xr[3 * v + 2] = rng.gen_range(-0.05..0.05);
        }
        let edges: Vec<[usize; 2]> = (0..n - 1).map(|v| [v, v + 1]).collect();
        let m = String3dEnergy::new(edges, &xr, 2.5);
        let mut x = vec![0.0; 3 * n];
        for xi in x.iter_mut().take(3) {
            *xi = rng.gen_range(-1.0..1.0);
        }
        for k in 0..n - 1 {
            let f = if k % 2 == 0 {
                rng.gen_range(1.15..1.6)
            } else {
                rng.gen_range(0.3..0.85)
            };
            let d = direction(rng) * (m.rest_length[k] * f);
            for i in 0..3 {
                x[3 * (k + 1) + i] = x[3 * k + i] + d[i];
            }
        }
        (m, x)
    }

    #[test]
    fn energy_string3d_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(40);
        for _ in 0..20 {
            let (m, x) = config(&mut rng, 7);
            assert!(m.value(&x) > 0.0);
            let mut g = vec![0.0; x.len()];
            m.add_gradient(&x, &mut g);
            let gf = fd_gradient(&m, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-5, "rel {}", rel(&g, &gf));
        }
    }

    #[test]
    fn energy_string3d_hessian_fd_and_psd() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(41);
        for _ in 0..20 {
            let (m, x) = config(&mut rng, 7);
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
            assert_eq!(hpd, hd, "projected must equal exact (already PSD)");
            let ev = hd.symmetric_eigenvalues();
            let scale = hd.norm().max(1.0);
            assert!(ev.min() >= -1e-10 * scale, "min eig {}", ev.min());
        }
    }

    #[test]
    fn energy_string3d_compressed_is_zero_and_known_values() {
        let xr = [0.0, 0.0, 0.0, 0.0, 0.6, 0.8];
        let m = String3dEnergy::new(vec![[0, 1]], &xr, 1.0);
        assert!((m.rest_length[0] - 1.0).abs() < 1e-15);
        let x = [0.0, 0.0, 0.0, 0.5, 0.2, -0.3];
        assert_eq!(m.value(&x), 0.0);
        let mut g = vec![0.0; 6];
        m.add_gradient(&x, &mut g);
        assert_eq!(g, vec![0.0; 6]);
        let mut h = Hessian::default();
        m.add_hessian(&x, true, &mut h);
        assert!(h.triplets.is_empty());
        // stretched by 2 along z: s = 3, J = μ L s² = 9
        let x = [1.0, 1.0, 1.0, 1.0, 1.0, 3.0];
        assert!((m.value(&x) - 9.0).abs() < 1e-14);
        // at rest: zero energy
        assert_eq!(m.value(&xr), 0.0);
    }

    #[test]
    fn energy_string3d_rigid_invariant() {
        let mut rng = ChaCha8Rng::seed_from_u64(42);
        let (m, x) = config(&mut rng, 9);
        let rot = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let t = Vector3::new(1.0, -2.0, 0.5);
        let mut y = x.clone();
        for (p, q) in y.chunks_mut(3).zip(x.chunks(3)) {
            let z = rot * Vector3::new(q[0], q[1], q[2]) + t;
            p.copy_from_slice(z.as_slice());
        }
        let (v0, v1) = (m.value(&x), m.value(&y));
        assert!(v0 > 0.0 && ((v1 - v0) / v0).abs() < 1e-12, "{v0} {v1}");
    }

    #[test]
    fn energy_string3d_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let mut rng = ChaCha8Rng::seed_from_u64(43);
        let (m, x) = config(&mut rng, 5 * CHUNK + 123);
        let bits = assert_thread_independent(|| term_bits(&m, &x));
        assert!(f64::from_bits(bits[0]) > 0.0);
        // the Hessian is the same sequence of triplets as the element-by-element loop
        let mut hs = Hessian::default();
        for k in 0..m.edges.len() {
            let one = String3dEnergy {
                edges: vec![m.edges[k]],
                rest_length: vec![m.rest_length[k]],
                mu: m.mu,
            };
            one.add_hessian(&x, false, &mut hs);
        }
        let mut h = Hessian::default();
        m.add_hessian(&x, false, &mut h);
        assert_eq!(h, hs);
    }
}
