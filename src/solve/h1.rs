//! The H¹ Gram matrix of the reference mesh and the dual norm H⁻¹ it defines, the norm in
//! which Lemma 5.6 measures the residual of problem (3) and in which the minimality
//! certificate ([`super::certificate`]) measures the KKT residual (docs/method.md).
//!
//! `G = M + K`: P1 mass and stiffness on the reference mesh (curves: their edges; 2D solids
//! and 3D surfaces: their triangles, with tangential gradients on surfaces; 3D solids: their
//! tetrahedra), one copy per coordinate. A force `r` (the nodal vector of a linear form on the
//! P1 space) has `‖r‖_{H⁻¹} = (rᵀ G⁻¹ r)^{1/2}`.
//!
//! `M` scales like `length^m` and `K` like `length^{m−2}` (m the body's dimension), so on the
//! scene's own reference positions the norm depends on the length unit. [`H1Norm::scaled`]
//! builds `G` on the reference positions divided by their diameter `ℓ`: the norm is then the
//! same in any length unit (a force scaled by `E/L` has its norm scaled by `E/L`).

use crate::scene::mesh::{BodyKind, Mesh};
use contactlab_solvers::linalg::SparseLdl;
use contactlab_solvers::CscMatrix;
use thiserror::Error;

/// Why the H¹ norm of a mesh cannot be built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum H1Error {
    /// A free vertex belongs to no element, so `G` is singular on its dofs.
    #[error("free vertex {0} belongs to no edge, triangle or tetrahedron of its bodies: the H1 Gram matrix is singular there")]
    IsolatedVertex(usize),
    /// The reference positions have no extent (all vertices at one point) or are not finite.
    #[error("the reference positions have diameter {0}: no length scale for the H1 norm")]
    NoExtent(f64),
    /// The factorization failed (a degenerate reference element).
    #[error("the H1 Gram matrix of the reference mesh is not positive definite (a degenerate reference element?)")]
    NotDefinite,
}

/// `col[dof]`: the column of each dof of `mesh` (free dofs only when `free_only` —
/// [`Mesh::dof_fixed`]: fixed vertices and supported components are not free —, in dof order;
/// `usize::MAX` for a dof left out), and the number of columns.
pub fn dof_columns(mesh: &Mesh, free_only: bool) -> (Vec<usize>, usize) {
    let mut col = vec![usize::MAX; mesh.x_ref.len()];
    let mut k = 0;
    for (dof, c) in col.iter_mut().enumerate() {
        if !(free_only && mesh.dof_fixed(dof)) {
            *c = k;
            k += 1;
        }
    }
    (col, k)
}

/// The H¹ Gram matrix `G = M + K` of P1 functions on the reference mesh, one copy per
/// coordinate, restricted to the free dofs (upper triangle, CSC).
pub fn h1_gram(mesh: &Mesh) -> CscMatrix {
    let (col, n) = dof_columns(mesh, true);
    h1_gram_on(mesh, &mesh.x_ref, &col, n)
}

/// The H¹ Gram matrix on the positions `xr` (as the reference positions) over the dofs
/// `col` (see [`dof_columns`]; `n` columns), upper triangle, CSC.
pub fn h1_gram_on(mesh: &Mesh, xr: &[f64], col: &[usize], n: usize) -> CscMatrix {
    let d = mesh.dim;
    let mut trip: Vec<(usize, usize, f64)> = Vec::new();
    let mut add = |vs: &[usize], m: &dyn Fn(usize, usize) -> f64| {
        for (i, &vi) in vs.iter().enumerate() {
            for (j, &vj) in vs.iter().enumerate() {
                for c in 0..d {
                    let (ri, rj) = (col[d * vi + c], col[d * vj + c]);
                    if ri != usize::MAX && rj != usize::MAX && ri <= rj {
                        trip.push((ri, rj, m(i, j)));
                    }
                }
            }
        }
    };
    let pt = |v: usize| mesh.point(xr, v);
    for body in &mesh.bodies {
        match (body.kind, mesh.dim) {
            (BodyKind::Curve, _) => {
                for &e in &body.edges {
                    let [a, b] = mesh.edges[e];
                    let l = (pt(a) - pt(b)).norm();
                    add(&[a, b], &|i, j| {
                        let mass = if i == j { l / 3.0 } else { l / 6.0 };
                        let stiff = if i == j { 1.0 / l } else { -1.0 / l };
                        mass + stiff
                    });
                }
            }
            // triangles: 2D solids, 3D surfaces (tangential gradients)
            (BodyKind::Solid, 2) | (BodyKind::Surface, _) => {
                for &t in &body.triangles {
                    let vs = mesh.triangles[t];
                    let p: Vec<_> = vs.iter().map(|&v| pt(v)).collect();
                    let nrm = (p[1] - p[0]).cross(&(p[2] - p[0]));
                    let area = 0.5 * nrm.norm();
                    // ∇φ_i = n̂ × e_i / (2·area), e_i the edge opposite vertex i (cyclic):
                    // ∇φ_i·∇φ_j = e_i·e_j / (4·area²).
                    let e: Vec<_> = (0..3).map(|i| p[(i + 2) % 3] - p[(i + 1) % 3]).collect();
                    add(&vs, &|i, j| {
                        let mass = if i == j { area / 6.0 } else { area / 12.0 };
                        mass + e[i].dot(&e[j]) / (4.0 * area)
                    });
                }
            }
            (BodyKind::Solid, _) => {
                for &t in &body.tets {
                    let vs = mesh.tets[t];
                    let p: Vec<_> = vs.iter().map(|&v| pt(v)).collect();
                    let m =
                        nalgebra::Matrix3::from_columns(&[p[1] - p[0], p[2] - p[0], p[3] - p[0]]);
                    let vol = m.determinant() / 6.0;
                    let Some(minv) = m.try_inverse() else {
                        continue;
                    };
                    // ∇φ_1..3 are the rows of M⁻¹, ∇φ_0 = −Σ.
                    let mut grads = [nalgebra::Vector3::zeros(); 4];
                    for k in 0..3 {
                        grads[k + 1] = minv.row(k).transpose();
                    }
                    grads[0] = -(grads[1] + grads[2] + grads[3]);
                    add(&vs, &|i, j| {
                        let mass = if i == j { vol / 10.0 } else { vol / 20.0 };
                        mass + vol * grads[i].dot(&grads[j])
                    });
                }
            }
        }
    }
    CscMatrix::from_triplets(n, n, &trip).expect("indices in range, values finite")
}

/// The diameter of the reference positions (the diagonal of their bounding box).
pub fn reference_diameter(mesh: &Mesh) -> f64 {
    let d = mesh.dim;
    let mut lo = vec![f64::INFINITY; d];
    let mut hi = vec![f64::NEG_INFINITY; d];
    for p in mesh.x_ref.chunks(d) {
        for c in 0..d {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (0..d).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt()
}

/// The factorized Gram matrix of [`h1_gram_on`] over a set of dofs: `‖r‖_{H⁻¹}`.
pub struct H1Norm {
    /// `col[dof]`: the column of each dof, `usize::MAX` for a dof left out.
    pub col: Vec<usize>,
    /// Number of columns.
    pub n: usize,
    /// The length `ℓ` the reference positions were divided by (their diameter).
    pub ell: f64,
    /// `G` itself (upper triangle, CSC; the sparse path of the certificate's least-squares
    /// problem takes it as the Hessian of its dual QP).
    pub gram: CscMatrix,
    ldl: Option<SparseLdl>,
}

impl H1Norm {
    /// The unit-free norm: `G` on the reference positions divided by their diameter `ℓ`
    /// ([`reference_diameter`]), over the free dofs (`free_only`) or over all dofs. A free
    /// vertex in no element is an error naming it.
    pub fn scaled(mesh: &Mesh, free_only: bool) -> Result<H1Norm, H1Error> {
        let ell = reference_diameter(mesh);
        if !(ell > 0.0 && ell.is_finite()) {
            return Err(H1Error::NoExtent(ell));
        }
        let (col, n) = dof_columns(mesh, free_only);
        let mut in_element = vec![false; mesh.nv()];
        for body in &mesh.bodies {
            let mut mark = |vs: &[usize]| vs.iter().for_each(|&v| in_element[v] = true);
            match (body.kind, mesh.dim) {
                (BodyKind::Curve, _) => body.edges.iter().for_each(|&e| mark(&mesh.edges[e])),
                (BodyKind::Solid, 2) | (BodyKind::Surface, _) => body
                    .triangles
                    .iter()
                    .for_each(|&t| mark(&mesh.triangles[t])),
                (BodyKind::Solid, _) => body.tets.iter().for_each(|&t| mark(&mesh.tets[t])),
            }
        }
        if let Some(v) = (0..mesh.nv()).find(|&v| col[mesh.dim * v] != usize::MAX && !in_element[v])
        {
            return Err(H1Error::IsolatedVertex(v));
        }
        let xr: Vec<f64> = mesh.x_ref.iter().map(|v| v / ell).collect();
        let gram = h1_gram_on(mesh, &xr, &col, n);
        let ldl = if n == 0 {
            None
        } else {
            Some(SparseLdl::factor(&gram).ok_or(H1Error::NotDefinite)?)
        };
        Ok(H1Norm {
            col,
            n,
            ell,
            gram,
            ldl,
        })
    }

    /// The restriction of a full-length vector (one entry per dof) to the columns.
    pub fn restrict(&self, full: &[f64]) -> Vec<f64> {
        let mut r = vec![0.0; self.n];
        for (dof, &c) in self.col.iter().enumerate() {
            if c != usize::MAX {
                r[c] = full[dof];
            }
        }
        r
    }

    /// `G⁻¹ r` in place (`r` of length [`H1Norm::n`]).
    pub fn solve_in_place(&self, r: &mut [f64]) {
        if let Some(ldl) = &self.ldl {
            ldl.solve_in_place(r);
        }
    }

    /// `‖r‖_{H⁻¹} = (rᵀ G⁻¹ r)^{1/2}` of a vector over the columns.
    pub fn norm(&self, r: &[f64]) -> f64 {
        let mut z = r.to_vec();
        self.solve_in_place(&mut z);
        dot(r, &z).max(0.0).sqrt()
    }
}

/// The two scaled norms the outer loop and the certificate use: over the free dofs (a
/// residual of the KKT conditions, the net force) and over all dofs (a term's force with its
/// reactions at the fixed vertices).
pub struct H1Norms {
    /// Over the free dofs.
    pub free: H1Norm,
    /// Over all dofs.
    pub all: H1Norm,
}

impl H1Norms {
    /// Both norms of [`H1Norm::scaled`].
    pub fn scaled(mesh: &Mesh) -> Result<H1Norms, H1Error> {
        Ok(H1Norms {
            free: H1Norm::scaled(mesh, true)?,
            all: H1Norm::scaled(mesh, false)?,
        })
    }
}

/// `aᵀb`.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
