//! Gravity (external potential energy of the lumped masses):
//!
//! ```text
//! J(x) = −Σ_v m_v g · x_v,
//! ```
//!
//! so with `g = (0, −9.81)` it is `Σ_v m_v · 9.81 · y_v`. Linear in `x`: gradient
//! `−m_v g`, zero Hessian.

use super::{chunked_sum, Energy, Hessian, TermKind};
use rayon::prelude::*;

const DIM: usize = 2;

/// Gravity on lumped vertex masses (2D).
#[derive(Clone, Debug)]
pub struct Gravity {
    /// Lumped mass per vertex.
    pub mass: Vec<f64>,
    /// Gravitational acceleration vector.
    pub g: [f64; 2],
}

impl Gravity {
    /// Gravity with the given vertex masses.
    pub fn new(mass: Vec<f64>, g: [f64; 2]) -> Self {
        Self { mass, g }
    }

    /// Lumped masses of P1 triangles of density `rho` (per unit area): each triangle gives a
    /// third of its reference mass to each vertex. `nv` is the number of vertices.
    pub fn lumped_triangles(
        nv: usize,
        triangles: &[[usize; 3]],
        x_ref: &[f64],
        rho: f64,
        g: [f64; 2],
    ) -> Self {
        let mut mass = vec![0.0; nv];
        for t in triangles {
            let p = |v: usize, k: usize| x_ref[DIM * v + k];
            let area = 0.5
                * ((p(t[1], 0) - p(t[0], 0)) * (p(t[2], 1) - p(t[0], 1))
                    - (p(t[2], 0) - p(t[0], 0)) * (p(t[1], 1) - p(t[0], 1)))
                .abs();
            for &v in t {
                mass[v] += rho * area / 3.0;
            }
        }
        Self { mass, g }
    }

    /// Lumped masses of P1 edges of density `rho` (per unit length): half to each end.
    pub fn lumped_edges(
        nv: usize,
        edges: &[[usize; 2]],
        x_ref: &[f64],
        rho: f64,
        g: [f64; 2],
    ) -> Self {
        let mut mass = vec![0.0; nv];
        for &[a, b] in edges {
            let l =
                (x_ref[DIM * b] - x_ref[DIM * a]).hypot(x_ref[DIM * b + 1] - x_ref[DIM * a + 1]);
            mass[a] += 0.5 * rho * l;
            mass[b] += 0.5 * rho * l;
        }
        Self { mass, g }
    }
}

impl Energy for Gravity {
    fn name(&self) -> &str {
        "gravity"
    }

    fn kind(&self) -> TermKind {
        TermKind::Potential
    }

    fn value(&self, x: &[f64]) -> f64 {
        -chunked_sum(self.mass.len(), |r| {
            let mut s = 0.0;
            for v in r {
                s += self.mass[v] * (self.g[0] * x[DIM * v] + self.g[1] * x[DIM * v + 1]);
            }
            s
        })
    }

    /// Each vertex's dofs get their own contribution: parallel, and the same whatever the
    /// thread count.
    fn add_gradient(&self, _x: &[f64], g: &mut [f64]) {
        g[..DIM * self.mass.len()]
            .par_chunks_mut(DIM)
            .with_min_len(1024)
            .zip(self.mass.par_iter())
            .for_each(|(gv, m)| {
                gv[0] -= m * self.g[0];
                gv[1] -= m * self.g[1];
            });
    }

    /// Zero Hessian: adds nothing.
    fn add_hessian(&self, _x: &[f64], _projected: bool, _h: &mut Hessian) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn energy_gravity_value_gradient_hessian() {
        let grav = Gravity::new(vec![1.0, 2.0], [0.0, -9.81]);
        let x = [3.0, 1.0, -2.0, 0.5];
        assert!((grav.value(&x) - 9.81 * (1.0 + 2.0 * 0.5)).abs() < 1e-12);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let x: Vec<f64> = (0..4).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let mut g = vec![0.0; 4];
        grav.add_gradient(&x, &mut g);
        // central differences, step 1e-6 (exact for a linear function up to rounding)
        let mut xp = x.clone();
        for i in 0..4 {
            xp[i] = x[i] + 1e-6;
            let fp = grav.value(&xp);
            xp[i] = x[i] - 1e-6;
            let fm = grav.value(&xp);
            xp[i] = x[i];
            assert!(((fp - fm) / 2e-6 - g[i]).abs() <= 1e-5 * (1.0 + g[i].abs()));
        }
        let mut h = Hessian::default();
        grav.add_hessian(&x, true, &mut h);
        assert!(h.triplets.is_empty() && h.rank_one.is_empty());
    }

    #[test]
    fn energy_gravity_lumped_masses() {
        let xr = [0.0, 0.0, 2.0, 0.0, 0.0, 3.0];
        let gt = Gravity::lumped_triangles(3, &[[0, 1, 2]], &xr, 2.0, [0.0, -1.0]);
        let total: f64 = gt.mass.iter().sum();
        assert!((total - 6.0).abs() < 1e-14);
        let ge = Gravity::lumped_edges(3, &[[0, 1], [1, 2]], &xr, 1.0, [0.0, -1.0]);
        let total: f64 = ge.mass.iter().sum();
        assert!((total - (2.0 + 13f64.sqrt())).abs() < 1e-14);
        assert!((ge.mass[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn energy_gravity_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let nv = 5 * CHUNK + 3;
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let mass: Vec<f64> = (0..nv).map(|_| rng.gen_range(0.1..2.0)).collect();
        let grav = Gravity::new(mass, [0.3, -9.81]);
        // one extra unused vertex: its gradient entries stay untouched
        let x: Vec<f64> = (0..2 * nv + 2).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let bits = assert_thread_independent(|| term_bits(&grav, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
        let mut g = vec![0.0; x.len()];
        grav.add_gradient(&x, &mut g);
        assert_eq!(g[2 * nv..], [0.0, 0.0]);
        assert_eq!(g[2 * (nv - 1) + 1], grav.mass[nv - 1] * 9.81);
    }
}
