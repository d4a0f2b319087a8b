//! TEMPORARY: the code before the energy/ restructuring, kept (test builds only) for the
//! bit-identity checks of [`super`]; removed when the restructuring is done.
//!
//! Gravity in 3D (external potential energy of lumped masses): `J(x) = −Σ_v m_v g · x_v`,
//! gradient `−m_v g`, zero Hessian. The 3D counterpart of [`super::gravity`], with lumped
//! masses for edges (rods, per unit length), surface triangles (sheets, per unit area) and
//! tetrahedra (solids, per unit volume).

use crate::energy::{chunked_sum, Energy, Hessian, TermKind};
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
