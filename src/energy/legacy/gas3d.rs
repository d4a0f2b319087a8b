//! TEMPORARY: the code before the energy/ restructuring, kept (test builds only) for the
//! bit-identity checks of [`super`]; removed when the restructuring is done.
//!
//! Enclosed-gas energy of an inflated closed surface in 3D (the 3D counterpart of
//! [`super::gas`]; Pantz 2008, §7: isothermal perfect gas).
//!
//! The gas fills the volume enclosed by a closed, consistently oriented surface of P1
//! triangles `T = (x_a, x_b, x_c)`. By the divergence theorem its signed volume is
//!
//! ```text
//! V(x) = Σ_T det(x_a − o, x_b − o, x_c − o) / 6 = Σ_T (x_a − o) · ((x_b − o) × (x_c − o)) / 6,
//! ```
//!
//! for any point `o`: on a closed surface (every directed edge `a → b` is matched by an edge
//! `b → a`) the terms in `o` cancel, and with `o = 0` this is `Σ_T x_a · (x_b × x_c) / 6`. The
//! triangles are oriented at construction so that `V(x0) > 0` (all reversed if needed: outward
//! normals). The terms are evaluated relative to the centroid `o` of the surface vertices at
//! `x`: the sums are then translation invariant and well conditioned (with `o = 0`, a body far
//! from the origin would make `Σ_T x_a · (x_b × x_c)` cancel large terms), and so is the
//! projected Hessian below (its triangle blocks depend on `y = x − o`). Since `V` does not
//! depend on `o`, the derivatives are taken with `o` fixed. The gas energy is
//!
//! ```text
//! J(x) = −C ln V(x)     (J = +∞ when V ≤ 0),
//! ∇J = −C/V ∇V,          ∂V/∂x_a = (y_b × y_c)/6 (and cyclically), y = x − o,
//! ∇²J = C/V² ∇V ∇Vᵀ − C/V ∇²V.
//! ```
//!
//! The first Hessian part is pushed as a [`RankOne`] term (`coef = C/V²`, `w = ∇V`) in both
//! modes. The second is a sum over the triangles: triangle `T` couples its 9 dofs through the
//! block `M_T = −C/V ∇²V_T`, whose 3×3 sub-blocks are
//!
//! ```text
//! (∇²V_T)_{pq} = ε(p, q, r) [y_r]ₓᵀ / 6   (p ≠ q, r the third corner),   (∇²V_T)_{pp} = 0,
//! ```
//!
//! with `ε(p, q, r) = ±1` the sign of the permutation of the corners and `[y]ₓ` the cross
//! product matrix (`[y]ₓ z = y × z`). `M_T` has a zero diagonal, so (unless it vanishes) it is
//! indefinite; with `projected = true` each `M_T` is replaced by its positive semi-definite
//! part (symmetric eigendecomposition, negative eigenvalues clamped to zero,
//! [`super::project_psd`]), as [`super::gas`] does with its shoelace blocks.
//!
//! Assembly follows the conventions of [`super`]: the centroid and the volume are chunked
//! sums, `∇V` is scatter-added per triangle in triangle order, the Hessian triplets are
//! produced in chunks in triangle order; all bit-identical for any thread count.

use super::neo_hookean3d::project_psd;
use crate::energy::membrane3d::Matrix9;
use crate::energy::{
    chunked_sum, chunked_triplets, par_scatter, push_block, Energy, Hessian, RankOne, TermKind,
};
use std::collections::HashMap;

const DIM: usize = 3;

/// `−C ln V` for the volume `V` enclosed by a closed triangulated surface (3D).
#[derive(Clone, Debug)]
pub struct Gas3dEnergy {
    /// Triangles, oriented so that the volume at the construction configuration is positive.
    triangles: Vec<[usize; 3]>,
    /// Gas constant `C` (amount × temperature), `C > 0`.
    pub c: f64,
    /// The surface's vertices, increasing.
    vertices: Vec<usize>,
    /// The triangles' corners as indices into `vertices`.
    local: Vec<[usize; 3]>,
}

/// An edge of `triangles` that is not matched by an opposite one (`[a, b]` with more
/// occurrences of `a → b` than of `b → a`), the smallest such `(min, max)` pair; `None` if
/// the surface is closed and consistently oriented. Edges `a → a` (of degenerate triangles)
/// are ignored: they contribute nothing to the volume.
pub fn open_edge(triangles: &[[usize; 3]]) -> Option<[usize; 2]> {
    let mut count: HashMap<(usize, usize), i64> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                *count.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
            }
        }
    }
    count
        .into_iter()
        .filter(|&(_, n)| n != 0)
        .min_by_key(|&(e, _)| e)
        .map(|((a, b), n)| if n > 0 { [a, b] } else { [b, a] })
}

/// The gas surface is not closed and consistently oriented: edge `a → b` has no opposite edge.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("gas surface is not closed and consistently oriented: edge {a} -> {b} has no opposite edge {b} -> {a}")]
pub struct OpenSurface {
    /// First vertex of the unmatched edge.
    pub a: usize,
    /// Second vertex.
    pub b: usize,
}

impl Gas3dEnergy {
    /// Builds the energy, reversing every triangle if the volume at `x0` is negative, so that
    /// `V(x0) ≥ 0` (outward normals).
    ///
    /// A surface that is not closed and consistently oriented (see [`open_edge`]) is an
    /// error naming the unmatched edge: `V` would not be a volume.
    pub fn new(triangles: Vec<[usize; 3]>, c: f64, x0: &[f64]) -> Result<Self, OpenSurface> {
        if let Some([a, b]) = open_edge(&triangles) {
            return Err(OpenSurface { a, b });
        }
        let mut vertices: Vec<usize> = triangles.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let pos: HashMap<usize, usize> =
            vertices.iter().enumerate().map(|(l, &v)| (v, l)).collect();
        let local = triangles.iter().map(|t| t.map(|v| pos[&v])).collect();
        let mut gas = Self {
            triangles,
            c,
            vertices,
            local,
        };
        if gas.volume(x0) < 0.0 {
            for (t, l) in gas.triangles.iter_mut().zip(gas.local.iter_mut()) {
                t.swap(1, 2);
                l.swap(1, 2);
            }
        }
        Ok(gas)
    }

    /// The triangles, in their stored (outward) orientation.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// The surface's vertices, increasing.
    pub fn vertices(&self) -> &[usize] {
        &self.vertices
    }

    /// The centroid `o` of the surface vertices at `x` (chunked sums).
    fn origin(&self, x: &[f64]) -> [f64; DIM] {
        let n = self.vertices.len();
        std::array::from_fn(|k| {
            let s = chunked_sum(n, |r| {
                let mut s = 0.0;
                for l in r {
                    s += x[DIM * self.vertices[l] + k];
                }
                s
            });
            s / n.max(1) as f64
        })
    }

    /// `y_p = x_p − o` for the corners of triangle `t`.
    #[inline]
    fn corners(&self, x: &[f64], o: &[f64; DIM], t: usize) -> [[f64; DIM]; 3] {
        self.triangles[t].map(|v| std::array::from_fn(|k| x[DIM * v + k] - o[k]))
    }

    /// Signed volume `V(x)` (positive in the reference orientation).
    pub fn volume(&self, x: &[f64]) -> f64 {
        let o = self.origin(x);
        let s = chunked_sum(self.triangles.len(), |r| {
            let mut s = 0.0;
            for t in r {
                let [a, b, c] = self.corners(x, &o, t);
                s += dot(&a, &cross(&b, &c));
            }
            s
        });
        s / 6.0
    }

    /// `∇V(x)` as sparse `(dof, value)` pairs, by increasing vertex (the three dofs of each
    /// vertex of [`Gas3dEnergy::vertices`] in turn).
    pub fn volume_gradient(&self, x: &[f64]) -> Vec<(usize, f64)> {
        let o = self.origin(x);
        let mut buf = vec![0.0; DIM * self.vertices.len()];
        par_scatter(
            self.triangles.len(),
            &mut buf,
            |t| {
                let [a, b, c] = self.corners(x, &o, t);
                Some([cross(&b, &c), cross(&c, &a), cross(&a, &b)])
            },
            |t, w, buf| {
                for (p, &l) in self.local[t].iter().enumerate() {
                    for k in 0..DIM {
                        buf[DIM * l + k] += w[p][k] / 6.0;
                    }
                }
            },
        );
        self.vertices
            .iter()
            .flat_map(|&v| (0..DIM).map(move |k| DIM * v + k))
            .zip(buf)
            .collect()
    }

    /// The 9×9 block `k ∇²V_T` of triangle `t` (`y` relative to `o`).
    fn triangle_block(&self, x: &[f64], o: &[f64; DIM], t: usize, k: f64) -> Matrix9 {
        let y = self.corners(x, o, t);
        let mut m = Matrix9::zeros();
        for p in 0..3 {
            for q in 0..3 {
                if p == q {
                    continue;
                }
                let r = 3 - p - q;
                // ε(p, q, r) = +1 for the cyclic orders (0,1,2), (1,2,0), (2,0,1)
                let sign = if q == (p + 1) % 3 { k } else { -k };
                // (ε_ijl y_r,l) = [y_r]ₓᵀ
                let yr = &y[r];
                let c = [
                    [0.0, yr[2], -yr[1]],
                    [-yr[2], 0.0, yr[0]],
                    [yr[1], -yr[0], 0.0],
                ];
                for i in 0..DIM {
                    for j in 0..DIM {
                        m[(DIM * p + i, DIM * q + j)] = sign * c[i][j] / 6.0;
                    }
                }
            }
        }
        m
    }
}

#[inline]
fn cross(a: &[f64; DIM], b: &[f64; DIM]) -> [f64; DIM] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn dot(a: &[f64; DIM], b: &[f64; DIM]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Energy for Gas3dEnergy {
    fn name(&self) -> &str {
        "gas3d"
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        let v = self.volume(x);
        if v > 0.0 {
            -self.c * v.ln()
        } else {
            f64::INFINITY
        }
    }

    /// Adds `−C/V ∇V`; adds nothing when `V ≤ 0` (the energy is `+∞` there).
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        let v = self.volume(x);
        if v <= 0.0 {
            return;
        }
        for (dof, w) in self.volume_gradient(x) {
            g[dof] -= self.c / v * w;
        }
    }

    /// Adds nothing when `V ≤ 0`.
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        let v = self.volume(x);
        if v <= 0.0 {
            return;
        }
        h.rank_one.push(RankOne {
            coef: self.c / (v * v),
            w: self.volume_gradient(x),
        });
        let o = self.origin(x);
        let k = -self.c / v;
        chunked_triplets(self.triangles.len(), &mut h.triplets, |t, out| {
            let mut m = self.triangle_block(x, &o, t, k);
            if projected {
                project_psd(&mut m);
            }
            push_block(out, DIM, &self.triangles[t], |r, c| m[(r, c)]);
        });
    }
}
