//! TEMPORARY: the code before the energy/ restructuring, kept (test builds only) for the
//! bit-identity checks of [`super`]; removed when the restructuring is done.
//!
//! Enclosed-gas energy of an inflated membrane (Pantz 2008, §7: isothermal perfect gas).
//!
//! The membrane vertices `x_0, …, x_{n−1}` (in order from one glued end to the other) and the
//! support chord `x_{n−1} → x_0` close a polygon of signed area (shoelace formula)
//!
//! ```text
//! V(x) = sign · ½ Σ_{i=0}^{n−1} (x_i y_{i+1} − x_{i+1} y_i),   indices mod n,
//! ```
//!
//! with `sign = ±1` fixed at construction so that `V(x0) > 0`. The gas energy is
//!
//! ```text
//! J(x) = −C ln V(x)     (J = +∞ when V ≤ 0),
//! ∇J = −C/V ∇V,
//! ∇²J = C/V² ∇V ∇Vᵀ − C/V ∇²V.
//! ```
//!
//! The first Hessian part is pushed as a [`RankOne`] term (`coef = C/V²`, `w = ∇V`) in both
//! modes. The second is a sum over the shoelace terms: term `i` couples `(x_i, y_i, x_{i+1},
//! y_{i+1})` through the 4×4 block `M_i = k S` with `k = −C·sign/(2V)` and
//! `S = [[0,0,0,1],[0,0,−1,0],[0,−1,0,0],[1,0,0,0]]`. Since `S² = I` its eigenvalues are
//! `±1`, so `M_i` has eigenvalues `±C/(2V)` and its PSD part is
//! `(M_i + |M_i|)/2 = (k S + |k| I)/2`, used when `projected = true`.

use crate::energy::{
    chunked_sum, chunked_triplets, push_block, Energy, Hessian, RankOne, TermKind,
};
use rayon::prelude::*;
use std::collections::hash_map::{Entry, HashMap};

const DIM: usize = 2;

/// `−C ln V` for the area `V` enclosed by a membrane polygon closed by its support chord.
#[derive(Clone, Debug)]
pub struct GasEnergy {
    /// Polygon vertices in order (the closing side last → first is the support chord).
    pub polygon: Vec<usize>,
    /// Gas constant `C` (amount × temperature), `C > 0`.
    pub c: f64,
    /// Orientation `±1` making the reference area positive.
    pub sign: f64,
}

impl GasEnergy {
    /// Builds the energy, choosing `sign` so that the signed area at `x0` is positive
    /// (`sign = 1` if the raw area is exactly zero).
    pub fn new(polygon: Vec<usize>, c: f64, x0: &[f64]) -> Self {
        let mut gas = Self {
            polygon,
            c,
            sign: 1.0,
        };
        if gas.area(x0) < 0.0 {
            gas.sign = -1.0;
        }
        gas
    }

    fn xy(&self, x: &[f64], i: usize) -> (f64, f64) {
        let v = self.polygon[i % self.polygon.len()];
        (x[DIM * v], x[DIM * v + 1])
    }

    /// Signed area `V(x)` (positive in the reference orientation).
    pub fn area(&self, x: &[f64]) -> f64 {
        let n = self.polygon.len();
        let s = chunked_sum(n, |r| {
            let mut s = 0.0;
            for i in r {
                let (xi, yi) = self.xy(x, i);
                let (xj, yj) = self.xy(x, i + 1);
                s += xi * yj - xj * yi;
            }
            s
        });
        self.sign * 0.5 * s
    }

    /// `∇V(x)` as sparse `(dof, value)` pairs, in polygon order (duplicates summed into the
    /// first occurrence if a vertex repeats).
    pub fn area_gradient(&self, x: &[f64]) -> Vec<(usize, f64)> {
        let n = self.polygon.len();
        // per-vertex terms, in parallel (each independent of the others)
        let terms: Vec<[(usize, f64); 2]> = (0..n)
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| {
                let v = self.polygon[i];
                let (xp, yp) = self.xy(x, i + n - 1);
                let (xn, yn) = self.xy(x, i + 1);
                let gx = self.sign * 0.5 * (yn - yp);
                let gy = self.sign * 0.5 * (xp - xn);
                [(DIM * v, gx), (DIM * v + 1, gy)]
            })
            .collect();
        if !has_repeats(&self.polygon) {
            return terms.into_iter().flatten().collect();
        }
        // a vertex repeats: merge sequentially, in polygon order
        let mut w: Vec<(usize, f64)> = Vec::with_capacity(DIM * n);
        let mut pos: HashMap<usize, usize> = HashMap::with_capacity(n);
        for (i, t) in terms.into_iter().enumerate() {
            match pos.entry(self.polygon[i]) {
                Entry::Occupied(p) => {
                    let p = *p.get();
                    w[p].1 += t[0].1;
                    w[p + 1].1 += t[1].1;
                }
                Entry::Vacant(p) => {
                    p.insert(w.len());
                    w.extend(t);
                }
            }
        }
        w
    }
}

/// Whether some vertex occurs more than once in `polygon`.
fn has_repeats(polygon: &[usize]) -> bool {
    let mut sorted = polygon.to_vec();
    sorted.par_sort_unstable();
    sorted.windows(2).any(|p| p[0] == p[1])
}

impl Energy for GasEnergy {
    fn name(&self) -> &str {
        "gas"
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn value(&self, x: &[f64]) -> f64 {
        let v = self.area(x);
        if v > 0.0 {
            -self.c * v.ln()
        } else {
            f64::INFINITY
        }
    }

    /// Adds `−C/V ∇V`; adds nothing when `V ≤ 0` (the energy is `+∞` there).
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        let v = self.area(x);
        if v <= 0.0 {
            return;
        }
        for (dof, w) in self.area_gradient(x) {
            g[dof] -= self.c / v * w;
        }
    }

    /// Adds nothing when `V ≤ 0`.
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        let v = self.area(x);
        if v <= 0.0 {
            return;
        }
        h.rank_one.push(RankOne {
            coef: self.c / (v * v),
            w: self.area_gradient(x),
        });
        let k = -self.c * self.sign / (2.0 * v);
        shoelace_hessian(&self.polygon, k, projected, h);
    }
}

/// Adds `Σ_i k·S` on the consecutive vertex pairs `(x_i, x_{i+1})` of a closed `polygon`, `S`
/// the 4×4 shoelace block with `S² = I` (so `k·S` has eigenvalues `±k`); with `projected`, each
/// block is replaced by its PSD part `(k S + |k| I)/2`. Shared by the gas and pressure terms.
pub(crate) fn shoelace_hessian(polygon: &[usize], k: f64, projected: bool, h: &mut Hessian) {
    let mut m = [[0.0; 2 * DIM]; 2 * DIM];
    m[0][3] = k;
    m[3][0] = k;
    m[1][2] = -k;
    m[2][1] = -k;
    if projected {
        for (d, row) in m.iter_mut().enumerate() {
            for v in row.iter_mut() {
                *v *= 0.5;
            }
            row[d] = 0.5 * k.abs();
        }
    }
    let n = polygon.len();
    chunked_triplets(n, &mut h.triplets, |i, out| {
        let a = polygon[i];
        let b = polygon[(i + 1) % n];
        push_block(out, DIM, &[a, b], |r, c| m[r][c]);
    });
}
