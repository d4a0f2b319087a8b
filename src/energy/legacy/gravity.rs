//! TEMPORARY: the code before the energy/ restructuring, kept (test builds only) for the
//! bit-identity checks of [`super`]; removed when the restructuring is done.
//!
//! Gravity (external potential energy of the lumped masses):
//!
//! ```text
//! J(x) = −Σ_v m_v g · x_v,
//! ```
//!
//! so with `g = (0, −9.81)` it is `Σ_v m_v · 9.81 · y_v`. Linear in `x`: gradient
//! `−m_v g`, zero Hessian.

use crate::energy::{chunked_sum, Energy, Hessian, TermKind};
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
