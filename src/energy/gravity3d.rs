//! Gravity in 3D (external potential energy of lumped masses): `J(x) = −Σ_v m_v g · x_v`,
//! gradient `−m_v g`, zero Hessian. The 3D counterpart of [`super::gravity`], with lumped
//! masses for edges (rods, per unit length), surface triangles (sheets, per unit area) and
//! tetrahedra (solids, per unit volume).

use super::{chunked_sum, Energy, Hessian, TermKind};
use rayon::prelude::*;

const DIM: usize = 3;

/// Gravity on lumped vertex masses (3D).
#[derive(Clone, Debug)]
pub struct Gravity3d {
    /// Lumped mass per vertex.
    pub mass: Vec<f64>,
    /// Gravitational acceleration vector.
    pub g: [f64; 3],
}

fn p(x: &[f64], v: usize) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(x[DIM * v], x[DIM * v + 1], x[DIM * v + 2])
}

impl Gravity3d {
    /// Gravity with the given vertex masses.
    pub fn new(mass: Vec<f64>, g: [f64; 3]) -> Self {
        Self { mass, g }
    }

    /// Adds the lumped masses of P1 edges of density `rho` per unit length (half to each end).
    pub fn add_edges(&mut self, edges: &[[usize; 2]], x_ref: &[f64], rho: f64) {
        for &[a, b] in edges {
            let m = rho * (p(x_ref, b) - p(x_ref, a)).norm();
            self.mass[a] += 0.5 * m;
            self.mass[b] += 0.5 * m;
        }
    }

    /// Adds the lumped masses of P1 triangles of density `rho` per unit area (a third each).
    pub fn add_triangles(&mut self, triangles: &[[usize; 3]], x_ref: &[f64], rho: f64) {
        for t in triangles {
            let (a, b, c) = (p(x_ref, t[0]), p(x_ref, t[1]), p(x_ref, t[2]));
            let m = rho * 0.5 * (b - a).cross(&(c - a)).norm();
            for &v in t {
                self.mass[v] += m / 3.0;
            }
        }
    }

    /// Adds the lumped masses of P1 tetrahedra of density `rho` per unit volume (a quarter
    /// each).
    pub fn add_tets(&mut self, tets: &[[usize; 4]], x_ref: &[f64], rho: f64) {
        for t in tets {
            let a = p(x_ref, t[0]);
            let vol = ((p(x_ref, t[1]) - a).cross(&(p(x_ref, t[2]) - a)))
                .dot(&(p(x_ref, t[3]) - a))
                .abs()
                / 6.0;
            for &v in t {
                self.mass[v] += rho * vol / 4.0;
            }
        }
    }
}

impl Energy for Gravity3d {
    fn name(&self) -> &str {
        "gravity3d"
    }

    fn kind(&self) -> TermKind {
        TermKind::Potential
    }

    fn value(&self, x: &[f64]) -> f64 {
        -chunked_sum(self.mass.len(), |r| {
            let mut s = 0.0;
            for v in r {
                s += self.mass[v]
                    * (self.g[0] * x[DIM * v]
                        + self.g[1] * x[DIM * v + 1]
                        + self.g[2] * x[DIM * v + 2]);
            }
            s
        })
    }

    /// Each vertex's dofs get their own contribution: the same whatever the thread count.
    fn add_gradient(&self, _x: &[f64], g: &mut [f64]) {
        g[..DIM * self.mass.len()]
            .par_chunks_mut(DIM)
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

    #[test]
    fn energy_gravity3d_value_gradient_and_lumped_masses() {
        // unit cube corner tet (volume 1/6), a right triangle of area 1/2, an edge of length 1
        let x = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut g = Gravity3d::new(vec![0.0; 4], [0.0, 0.0, -9.81]);
        g.add_tets(&[[0, 1, 2, 3]], &x, 6.0);
        assert!((g.mass.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        g.add_triangles(&[[0, 1, 2]], &x, 2.0);
        assert!((g.mass.iter().sum::<f64>() - 2.0).abs() < 1e-15);
        g.add_edges(&[[0, 3]], &x, 1.0);
        assert!((g.mass.iter().sum::<f64>() - 3.0).abs() < 1e-15);
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
    }
}
