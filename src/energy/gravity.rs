//! Gravity (external potential energy of lumped vertex masses) in `D = 2` or `3` dimensions:
//!
//! ```text
//! J(x) = −Σ_v m_v g · x_v,
//! ```
//!
//! so with `g = (0, −9.81)` it is `Σ_v m_v · 9.81 · y_v`. Linear in `x`: gradient `−m_v g`,
//! zero Hessian.
//!
//! The masses are the lumped P1 masses of the bodies' densities ([`super::mass`]), the same
//! as those of time stepping's inertia.

use super::{chunked_sum, Energy, Hessian, TermKind};
use rayon::prelude::*;

/// Gravity on lumped vertex masses, in `D` dimensions (`D = 2` or `3`).
#[derive(Clone, Debug)]
pub struct Gravity<const D: usize> {
    /// Lumped mass per vertex.
    pub mass: Vec<f64>,
    /// Gravitational acceleration vector.
    pub g: [f64; D],
}

impl<const D: usize> Gravity<D> {
    /// Gravity with the given vertex masses.
    pub fn new(mass: Vec<f64>, g: [f64; D]) -> Self {
        Self { mass, g }
    }
}

impl<const D: usize> Energy for Gravity<D> {
    fn name(&self) -> &str {
        if D == 2 {
            "gravity"
        } else {
            "gravity3d"
        }
    }

    fn kind(&self) -> TermKind {
        TermKind::Potential
    }

    fn value(&self, x: &[f64]) -> f64 {
        -chunked_sum(self.mass.len(), |r| {
            let mut s = 0.0;
            for v in r {
                // g · x_v, summed in coordinate order
                let mut gx = self.g[0] * x[D * v];
                for k in 1..D {
                    gx += self.g[k] * x[D * v + k];
                }
                s += self.mass[v] * gx;
            }
            s
        })
    }

    /// Each vertex's dofs get their own contribution: parallel, and the same whatever the
    /// thread count.
    fn add_gradient(&self, _x: &[f64], g: &mut [f64]) {
        g[..D * self.mass.len()]
            .par_chunks_mut(D)
            .with_min_len(1024)
            .zip(self.mass.par_iter())
            .for_each(|(gv, m)| {
                for (gc, ac) in gv.iter_mut().zip(self.g) {
                    *gc -= m * ac;
                }
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
        assert_eq!((grav.name(), grav.kind()), ("gravity", TermKind::Potential));
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

    #[test]
    fn energy_gravity3d_value_gradient_hessian() {
        // the lumped masses of a unit cube corner tet (density 6), its right triangle in z = 0
        // (density 2) and its edge along z (density 1)
        let x = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let (t, e) = (0.25 + 1.0 / 3.0, 0.5);
        let g = Gravity::new(vec![t + e, t, t, 0.25 + e], [0.0, 0.0, -9.81]);
        // J = Σ m_v 9.81 z_v: only vertex 3 is above z = 0
        assert!((g.value(&x) - 9.81 * g.mass[3]).abs() < 1e-14);
        let mut grad = vec![0.0; 12];
        g.add_gradient(&x, &mut grad);
        for v in 0..4 {
            assert_eq!(&grad[3 * v..3 * v + 2], &[0.0, 0.0]);
            assert_eq!(grad[3 * v + 2], g.mass[v] * 9.81);
        }
        // linear: the gradient is the finite difference
        let mut xp = x;
        xp[11] += 1e-3;
        assert!(((g.value(&xp) - g.value(&x)) / 1e-3 - grad[11]).abs() < 1e-9);
        let mut h = Hessian::default();
        g.add_hessian(&x, true, &mut h);
        assert!(h.triplets.is_empty() && h.rank_one.is_empty());
        assert_eq!((g.name(), g.kind()), ("gravity3d", TermKind::Potential));
    }

    #[test]
    fn energy_gravity3d_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let nv = 3 * CHUNK + 5;
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let mass: Vec<f64> = (0..nv).map(|_| rng.gen_range(0.1..2.0)).collect();
        let grav = Gravity::new(mass, [0.3, -0.2, -9.81]);
        let x: Vec<f64> = (0..3 * nv + 3).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let bits = assert_thread_independent(|| term_bits(&grav, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
        let mut g = vec![0.0; x.len()];
        grav.add_gradient(&x, &mut g);
        assert_eq!(g[3 * nv..], [0.0, 0.0, 0.0]);
    }
}
