//! Dead loads: point forces, tractions and pressures on the boundary of solids, summed into one
//! nodal force vector `f` (docs/materials.md, "Loads"):
//!
//! ```text
//! J(x) = −Σ_dof f_dof x_dof,      ∇J = −f,      ∇²J = 0.
//! ```
//!
//! **Dead**: the loads are computed once on the reference configuration and do not follow the
//! deformation, so they derive from this linear potential (conservative) and enter Pantz's
//! energy minimization (problem (3)) as one more term of `J`. A follower pressure (normal to
//! the current boundary, per current length or area) has a potential only in special cases
//! (a pressure on a closed boundary, `p·V`, as the 2D curves' `pressure` term does), so it is
//! not offered on solids' boundaries.
//!
//! The nodal forces of P1 elements are exact for a uniform traction `t` (force per reference
//! length in 2D, per reference area in 3D): an edge of reference length `ℓ` gives `ℓ t / 2` to
//! each end, a face of reference area `A` gives `A t / 3` to each vertex. A pressure `p` is the
//! traction `t = −p n`, `n` the outward unit normal of the edge or face in the reference (a
//! positive `p` pushes on the body).

use super::{Energy, Hessian, TermKind};
use nalgebra::Vector3;

/// A dead load: a fixed nodal force vector (flat, `dim` per vertex).
#[derive(Clone, Debug, PartialEq)]
pub struct DeadLoad {
    /// Space dimension.
    pub dim: usize,
    /// Nodal forces, flat like positions.
    pub force: Vec<f64>,
}

/// The reference position of vertex `v` as a 3-vector (`z = 0` in 2D).
fn p(dim: usize, x: &[f64], v: usize) -> Vector3<f64> {
    let mut q = Vector3::zeros();
    for k in 0..dim {
        q[k] = x[dim * v + k];
    }
    q
}

impl DeadLoad {
    /// No load on `nv` vertices in `dim` dimensions.
    pub fn new(dim: usize, nv: usize) -> Self {
        DeadLoad {
            dim,
            force: vec![0.0; dim * nv],
        }
    }

    /// Adds the force `f` (`dim` components) on vertex `v`.
    pub fn add_point(&mut self, v: usize, f: &[f64]) {
        for (k, fk) in f.iter().enumerate().take(self.dim) {
            self.force[self.dim * v + k] += fk;
        }
    }

    /// Adds the uniform traction `t` (force per reference length or area) on a boundary edge
    /// (2D, 2 vertices) or face (3D, 3 vertices) of the reference positions `x_ref`.
    pub fn add_traction(&mut self, x_ref: &[f64], element: &[usize], t: &[f64]) {
        let (share, _) = self.measure_share(x_ref, element, None);
        for &v in element {
            self.add_point(v, &t.iter().map(|tk| share * tk).collect::<Vec<_>>());
        }
    }

    /// Adds the uniform pressure `p` on a boundary edge (2D) or face (3D): the traction
    /// `−p n`, `n` its reference unit normal pointing away from `inside`, a vertex of its
    /// element off the boundary.
    pub fn add_pressure(&mut self, x_ref: &[f64], element: &[usize], inside: usize, p: f64) {
        let (share, n) = self.measure_share(x_ref, element, Some(inside));
        let t: Vec<f64> = (0..self.dim).map(|k| -p * n[k]).collect();
        for &v in element {
            self.add_point(v, &t.iter().map(|tk| share * tk).collect::<Vec<_>>());
        }
    }

    /// The share of each vertex in the element's reference measure (`ℓ/2` or `A/3`) and, with
    /// `inside`, the unit normal pointing away from it.
    fn measure_share(
        &self,
        x_ref: &[f64],
        element: &[usize],
        inside: Option<usize>,
    ) -> (f64, Vector3<f64>) {
        let d = self.dim;
        let a = p(d, x_ref, element[0]);
        let b = p(d, x_ref, element[1]);
        let (measure, mut n) = if element.len() == 2 {
            let e = b - a;
            (e.norm(), Vector3::new(e.y, -e.x, 0.0).normalize())
        } else {
            let c = p(d, x_ref, element[2]);
            let cr = (b - a).cross(&(c - a));
            (0.5 * cr.norm(), cr.normalize())
        };
        if let Some(i) = inside {
            if n.dot(&(p(d, x_ref, i) - a)) > 0.0 {
                n = -n;
            }
        }
        (measure / element.len() as f64, n)
    }

    /// The total force `Σ_v f_v` (`dim` components).
    pub fn total(&self) -> Vec<f64> {
        let mut t = vec![0.0; self.dim];
        for c in self.force.chunks(self.dim) {
            for (k, v) in c.iter().enumerate() {
                t[k] += v;
            }
        }
        t
    }
}

impl Energy for DeadLoad {
    fn name(&self) -> &str {
        "dead_load"
    }

    fn kind(&self) -> TermKind {
        TermKind::Potential
    }

    fn value(&self, x: &[f64]) -> f64 {
        -self.force.iter().zip(x).map(|(f, x)| f * x).sum::<f64>()
    }

    fn add_gradient(&self, _x: &[f64], g: &mut [f64]) {
        for (gi, f) in g.iter_mut().zip(&self.force) {
            *gi -= f;
        }
    }

    fn add_hessian(&self, _x: &[f64], _projected: bool, _h: &mut Hessian) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, rel};

    #[test]
    fn energy_dead_load_nodal_forces_gradient_and_totals() {
        // 2D: the unit square's bottom edge [0, 1] (interior vertex 2 above it), pressure 2:
        // force (0, +2) in total (pushing up into the body), 1 per end; traction (3, 0) on the
        // right edge [1, 2] of length 1: 1.5 per end
        let x = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0];
        let mut l = DeadLoad::new(2, 3);
        l.add_pressure(&x, &[0, 1], 2, 2.0);
        assert_eq!(l.force, vec![0.0, 1.0, 0.0, 1.0, 0.0, 0.0]);
        l.add_traction(&x, &[1, 2], &[3.0, 0.0]);
        l.add_point(2, &[0.0, -0.5]);
        assert_eq!(l.total(), vec![3.0, 1.5]);
        let y = [0.1, 0.2, 1.3, -0.4, 0.5, 0.9];
        let mut g = vec![0.0; 6];
        l.add_gradient(&y, &mut g);
        assert!(rel(&g, &fd_gradient(&l, &y, 1e-6)) < 1e-9);
        assert_eq!(l.value(&[0.0; 6]), 0.0);
        // 3D: the face [0, 1, 2] of the unit tet (inside vertex 3 above it, z > 0), area 1/2,
        // pressure 3: total force 1.5 along +z (into the body), 0.5 per vertex
        let x3 = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut l3 = DeadLoad::new(3, 4);
        l3.add_pressure(&x3, &[0, 2, 1], 3, 3.0);
        let t = l3.total();
        assert!(
            (t[2] - 1.5).abs() < 1e-15 && t[0] == 0.0 && t[1] == 0.0,
            "{t:?}"
        );
        assert!((l3.force[2] - 0.5).abs() < 1e-15);
        let mut h = Hessian::default();
        l3.add_hessian(&x3, true, &mut h);
        assert!(h.triplets.is_empty() && h.rank_one.is_empty());
    }
}
