//! Membrane (string) energy of a P1 curve, tension only (Pantz 2008, §7).
//!
//! The stored energy density is
//!
//! ```text
//! W(F) = μ (|F|² − 1)²   if |F| ≥ 1,      W(F) = 0   otherwise,
//! ```
//!
//! so the membrane resists stretching but not compression (it may wrinkle freely). On an edge
//! `(x0, x1)` with reference length `L`, `F = e / L` with `e = x1 − x0`, and the edge contributes
//! `L · W(F)`. With `s = |e|²/L² − 1`:
//!
//! ```text
//! J_e = μ L s²            (s ≥ 0),
//! ∂J_e/∂x1 = −∂J_e/∂x0 = 4μ s e / L,
//! H = 4μ/L (s I + 2 e eᵀ / L²),   Hessian block [[H, −H], [−H, H]].
//! ```
//!
//! `W` is C¹ at `|F| = 1` (and C² from the left only as far as the value `0` goes); for
//! `|F| > 1`, `s > 0` and `H` is positive definite, and it is `0` for `|F| < 1`, so the exact
//! Hessian is already positive semi-definite: `projected` changes nothing.

use super::{chunked_sum, chunked_triplets, par_scatter, push_block, Energy, Hessian, TermKind};

/// Tension-only energy of a set of P1 edges in `D` dimensions: [`MembraneEnergy`] (2D, the
/// balloons' membranes) and [`super::String3dEnergy`] (3D strings and rods) are this type.
#[derive(Clone, Debug)]
pub struct TensionString<const D: usize> {
    /// Edges `[v0, v1]`.
    pub edges: Vec<[usize; 2]>,
    /// Reference length of each edge.
    pub rest_length: Vec<f64>,
    /// Stiffness `μ`.
    pub mu: f64,
}

/// Tension-only membrane energy of a set of edges (2D).
pub type MembraneEnergy = TensionString<2>;

impl<const D: usize> TensionString<D> {
    /// Builds the energy, taking rest lengths from the reference positions `x_ref` (flat, `D`
    /// per vertex).
    pub fn new(edges: Vec<[usize; 2]>, x_ref: &[f64], mu: f64) -> Self {
        let rest_length = edges
            .iter()
            .map(|&[a, b]| {
                if D == 2 {
                    let dx = x_ref[D * b] - x_ref[D * a];
                    let dy = x_ref[D * b + 1] - x_ref[D * a + 1];
                    dx.hypot(dy)
                } else {
                    (0..D)
                        .map(|c| (x_ref[D * b + c] - x_ref[D * a + c]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                }
            })
            .collect();
        Self {
            edges,
            rest_length,
            mu,
        }
    }

    /// `(e, s)` for edge `k`: `e = x1 − x0`, `s = |e|²/L² − 1`.
    fn edge_state(&self, x: &[f64], k: usize) -> ([f64; D], f64) {
        let [a, b] = self.edges[k];
        let l = self.rest_length[k];
        let mut e = [0.0; D];
        for (c, ec) in e.iter_mut().enumerate() {
            *ec = x[D * b + c] - x[D * a + c];
        }
        let s = e.iter().map(|v| v * v).sum::<f64>() / (l * l) - 1.0;
        (e, s)
    }
}

impl<const D: usize> Energy for TensionString<D> {
    fn name(&self) -> &str {
        if D == 2 {
            "membrane"
        } else {
            "string3d"
        }
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        chunked_sum(self.edges.len(), |r| {
            let mut sum = 0.0;
            for k in r {
                let (_, s) = self.edge_state(x, k);
                if s > 0.0 {
                    sum += self.mu * self.rest_length[k] * s * s;
                }
            }
            sum
        })
    }

    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        par_scatter(
            self.edges.len(),
            g,
            |k| {
                let (e, s) = self.edge_state(x, k);
                if s <= 0.0 {
                    return None;
                }
                let c = 4.0 * self.mu * s / self.rest_length[k];
                Some(e.map(|v| c * v))
            },
            |k, ce, g| {
                let [a, b] = self.edges[k];
                for i in 0..D {
                    g[D * b + i] += ce[i];
                    g[D * a + i] -= ce[i];
                }
            },
        );
    }

    /// Exact Hessian; it is already positive semi-definite, so `projected` is ignored.
    fn add_hessian(&self, x: &[f64], _projected: bool, h: &mut Hessian) {
        chunked_triplets(self.edges.len(), &mut h.triplets, |k, out| {
            let (e, s) = self.edge_state(x, k);
            if s <= 0.0 {
                return;
            }
            let l = self.rest_length[k];
            let c = 4.0 * self.mu / l;
            let mut hb = [[0.0; D]; D];
            for (i, row) in hb.iter_mut().enumerate() {
                for (j, hij) in row.iter_mut().enumerate() {
                    *hij = c * (if i == j { s } else { 0.0 } + 2.0 * e[i] * e[j] / (l * l));
                }
            }
            // block [[H, −H], [−H, H]]
            push_block(out, D, &self.edges[k], |r, q| {
                let v = hb[r % D][q % D];
                if (r < D) == (q < D) {
                    v
                } else {
                    -v
                }
            });
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A polyline of `n` vertices on the x axis (reference), then stretched/compressed edge by
    /// edge with factors away from 1 (alternating > 1.15 and < 0.85), plus random rotation.
    fn config(rng: &mut ChaCha8Rng, n: usize) -> (MembraneEnergy, Vec<f64>) {
        let mut xr = vec![0.0; 2 * n];
        for v in 0..n {
            xr[2 * v] = v as f64 * 0.3 + rng.gen_range(0.0..0.1);
            xr[2 * v + 1] = rng.gen_range(-0.05..0.05);
        }
        let edges: Vec<[usize; 2]> = (0..n - 1).map(|v| [v, v + 1]).collect();
        let m = MembraneEnergy::new(edges, &xr, 2.5);
        let mut x = vec![0.0; 2 * n];
        x[0] = rng.gen_range(-1.0..1.0);
        x[1] = rng.gen_range(-1.0..1.0);
        for k in 0..n - 1 {
            let f = if k % 2 == 0 {
                rng.gen_range(1.15..1.6)
            } else {
                rng.gen_range(0.3..0.85)
            };
            let th: f64 = rng.gen_range(-3.0..3.0);
            let l = m.rest_length[k] * f;
            x[2 * (k + 1)] = x[2 * k] + l * th.cos();
            x[2 * (k + 1) + 1] = x[2 * k + 1] + l * th.sin();
        }
        (m, x)
    }

    #[test]
    fn energy_membrane_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(1);
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
    fn energy_membrane_hessian_fd_and_psd() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(2);
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
    fn energy_membrane_compressed_is_zero() {
        let xr = [0.0, 0.0, 1.0, 0.0];
        let m = MembraneEnergy::new(vec![[0, 1]], &xr, 1.0);
        assert!((m.rest_length[0] - 1.0).abs() < 1e-15);
        let x = [0.0, 0.0, 0.5, 0.2];
        assert_eq!(m.value(&x), 0.0);
        let mut g = vec![0.0; 4];
        m.add_gradient(&x, &mut g);
        assert_eq!(g, vec![0.0; 4]);
        let mut h = Hessian::default();
        m.add_hessian(&x, true, &mut h);
        assert!(h.triplets.is_empty());
        // stretched by 2: s = 3, J = μ L s² = 9
        let x = [0.0, 0.0, 2.0, 0.0];
        assert!((m.value(&x) - 9.0).abs() < 1e-14);
    }

    #[test]
    fn energy_membrane_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let (m, x) = config(&mut rng, 5 * CHUNK + 123);
        let bits = assert_thread_independent(|| term_bits(&m, &x));
        assert!(f64::from_bits(bits[0]) > 0.0);
        // the Hessian is the same sequence of triplets as the element-by-element loop
        let mut hs = Hessian::default();
        for k in 0..m.edges.len() {
            let one = MembraneEnergy {
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
