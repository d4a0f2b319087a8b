//! The 2D gas region: the polygon closed by a membrane and its support chord, and its area.
//!
//! The membrane vertices `x_0, …, x_{n−1}` (in order from one glued end to the other) and the
//! support chord `x_{n−1} → x_0` close a polygon of signed area (shoelace formula)
//!
//! ```text
//! V(x) = sign · ½ Σ_{i=0}^{n−1} (x_i y_{i+1} − x_{i+1} y_i),   indices mod n,
//! ```
//!
//! with `sign = ±1` fixed at construction so that `V(x0) > 0`. `∂V/∂x_i = sign/2 (y_{i+1} −
//! y_{i−1})`, `∂V/∂y_i = sign/2 (x_{i−1} − x_{i+1})`. The second-derivative part `−C/V ∇²V`
//! of the gas Hessian ([`super`]) is a sum over the shoelace terms: term `i` couples
//! `(x_i, y_i, x_{i+1}, y_{i+1})` through the 4×4 block `M_i = k S` with `k = −C·sign/(2V)` and
//! `S = [[0,0,0,1],[0,0,−1,0],[0,−1,0,0],[1,0,0,0]]`. Since `S² = I` its eigenvalues are
//! `±1`, so `M_i` has eigenvalues `±C/(2V)` and its PSD part is
//! `(M_i + |M_i|)/2 = (k S + |k| I)/2`, used when `projected = true`.

use super::Region;
use crate::energy::{chunked_sum, chunked_triplets, push_block, Hessian};
use rayon::prelude::*;
use std::collections::hash_map::{Entry, HashMap};

const DIM: usize = 2;

/// A polygon closed by its last → first side (a membrane and its support chord), with the
/// orientation that makes its area positive at construction.
#[derive(Clone, Debug)]
pub struct ClosedPolygon {
    /// Polygon vertices in order (the closing side last → first is the support chord).
    pub polygon: Vec<usize>,
    /// Orientation `±1` making the reference area positive.
    pub sign: f64,
}

impl ClosedPolygon {
    /// The polygon, choosing `sign` so that the signed area at `x0` is positive (`sign = 1`
    /// if the raw area is exactly zero).
    pub fn new(polygon: Vec<usize>, x0: &[f64]) -> Self {
        let mut p = Self { polygon, sign: 1.0 };
        if p.area(x0) < 0.0 {
            p.sign = -1.0;
        }
        p
    }

    fn xy(&self, x: &[f64], i: usize) -> (f64, f64) {
        polygon_xy(&self.polygon, x, i)
    }

    /// Signed area `V(x)` (positive in the reference orientation).
    pub fn area(&self, x: &[f64]) -> f64 {
        self.sign * 0.5 * shoelace_sum(&self.polygon, x)
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

/// Position of the `i`-th vertex of a closed `polygon` (index mod its length).
#[inline]
pub(crate) fn polygon_xy(polygon: &[usize], x: &[f64], i: usize) -> (f64, f64) {
    let v = polygon[i % polygon.len()];
    (x[DIM * v], x[DIM * v + 1])
}

/// `Σ_{i=0}^{n−1} (x_i y_{i+1} − x_{i+1} y_i)` (indices mod n) over a closed `polygon`: twice
/// its signed area. A chunked sum (thread-count independent); shared by the gas and pressure
/// terms.
pub(crate) fn shoelace_sum(polygon: &[usize], x: &[f64]) -> f64 {
    chunked_sum(polygon.len(), |r| {
        let mut s = 0.0;
        for i in r {
            let (xi, yi) = polygon_xy(polygon, x, i);
            let (xj, yj) = polygon_xy(polygon, x, i + 1);
            s += xi * yj - xj * yi;
        }
        s
    })
}

/// Whether some vertex occurs more than once in `polygon`.
fn has_repeats(polygon: &[usize]) -> bool {
    let mut sorted = polygon.to_vec();
    sorted.par_sort_unstable();
    sorted.windows(2).any(|p| p[0] == p[1])
}

impl Region for ClosedPolygon {
    const NAME: &'static str = "gas";

    fn measure(&self, x: &[f64]) -> f64 {
        self.area(x)
    }

    fn measure_gradient(&self, x: &[f64]) -> Vec<(usize, f64)> {
        self.area_gradient(x)
    }

    /// The shoelace blocks `k S`, `k = −C·sign/(2V)` (module docs).
    fn add_measure_hessian(&self, _x: &[f64], c: f64, v: f64, projected: bool, h: &mut Hessian) {
        let k = -c * self.sign / (2.0 * v);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use crate::energy::gas::GasEnergy;
    use crate::energy::{Energy, TermKind};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Perturbed parabola `y = 1 − x²` on `[−1, 1]` with `n` vertices, listed left→right or
    /// right→left (both orientations), plus an unused extra vertex to check sparsity.
    fn config(rng: &mut ChaCha8Rng, n: usize, reverse: bool) -> (GasEnergy, Vec<f64>) {
        let mut x = vec![0.0; 2 * (n + 1)];
        for v in 0..n {
            let t = -1.0 + 2.0 * v as f64 / (n - 1) as f64;
            x[2 * v] = t + rng.gen_range(-0.03..0.03);
            x[2 * v + 1] = 1.0 - t * t + rng.gen_range(-0.03..0.03);
        }
        x[2 * n] = 5.0;
        x[2 * n + 1] = -3.0;
        let mut poly: Vec<usize> = (0..n).collect();
        if reverse {
            poly.reverse();
        }
        let gas = GasEnergy::new(poly, rng.gen_range(0.5..3.0), &x);
        (gas, x)
    }

    #[test]
    fn energy_gas_sign_and_area() {
        let x = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0];
        let g = GasEnergy::new(vec![0, 1, 2], 1.0, &x);
        assert_eq!((g.name(), g.kind()), ("gas", TermKind::Elastic));
        assert_eq!(g.region.sign, 1.0);
        assert!((g.region.area(&x) - 0.5).abs() < 1e-15);
        let g = GasEnergy::new(vec![2, 1, 0], 1.0, &x);
        assert_eq!(g.region.sign, -1.0);
        assert!((g.region.area(&x) - 0.5).abs() < 1e-15);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for rev in [false, true] {
            let (gas, x) = config(&mut rng, 9, rev);
            // parabola area 4/3 up to the perturbation and polygon error
            assert!((gas.region.area(&x) - 4.0 / 3.0).abs() < 0.2);
        }
    }

    #[test]
    fn energy_gas_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for k in 0..20 {
            let (gas, x) = config(&mut rng, 8, k % 2 == 1);
            let mut g = vec![0.0; x.len()];
            gas.add_gradient(&x, &mut g);
            let gf = fd_gradient(&gas, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-5, "rel {}", rel(&g, &gf));
            // area gradient on its own
            let v0 = gas.region.area(&x);
            let mut xp = x.clone();
            for (dof, w) in gas.region.area_gradient(&x) {
                xp[dof] += 1e-6;
                let vp = gas.region.area(&xp);
                xp[dof] = x[dof] - 1e-6;
                let vm = gas.region.area(&xp);
                xp[dof] = x[dof];
                assert!(((vp - vm) / 2e-6 - w).abs() <= 1e-8, "{v0}");
            }
        }
    }

    #[test]
    fn energy_gas_hessian_fd_and_projection_psd() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for k in 0..20 {
            let (gas, x) = config(&mut rng, 8, k % 2 == 1);
            let n = x.len();
            let mut h = Hessian::default();
            gas.add_hessian(&x, false, &mut h);
            assert_eq!(h.rank_one.len(), 1);
            assert!(h.rank_one[0].coef >= 0.0);
            let hd = h.to_dense(n);
            let hf = fd_hessian(&gas, &x, 1e-6);
            let r = rel(hd.as_slice(), hf.as_slice());
            assert!(r <= 1e-5, "rel {r}");
            let mut hp = Hessian::default();
            gas.add_hessian(&x, true, &mut hp);
            assert_eq!(hp.rank_one, h.rank_one);
            let hpd = hp.to_dense(n);
            assert!((&hpd - hpd.transpose()).norm() <= 1e-14 * hpd.norm());
            let scale = hpd.norm().max(1.0);
            let ev = hpd.symmetric_eigenvalues();
            assert!(ev.min() >= -1e-10 * scale, "min eig {}", ev.min());
            // the sparse part alone is PSD too
            let sp = Hessian {
                triplets: hp.triplets.clone(),
                rank_one: vec![],
            };
            let ev = sp.to_dense(n).symmetric_eigenvalues();
            assert!(ev.min() >= -1e-10 * scale);
            // the unused vertex has no entries
            assert!(hp.triplets.iter().all(|t| t.0 < 2 * 8 && t.1 < 2 * 8));
        }
    }

    #[test]
    fn energy_gas_nonpositive_area_is_infinite() {
        let x0 = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0];
        let g = GasEnergy::new(vec![0, 1, 2], 1.0, &x0);
        // flip: negative area
        let x = [0.0, 0.0, 1.0, 0.0, 1.0, -1.0];
        assert!(g.region.area(&x) < 0.0);
        assert_eq!(g.value(&x), f64::INFINITY);
        // degenerate: zero area
        let x = [0.0, 0.0, 1.0, 0.0, 2.0, 0.0];
        assert_eq!(g.value(&x), f64::INFINITY);
        assert!(g.value(&x0).is_finite());
        assert!((g.value(&x0) - 2f64.ln()).abs() < 1e-15);
    }

    #[test]
    fn energy_gas_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for reverse in [false, true] {
            let (gas, x) = config(&mut rng, 5 * CHUNK + 77, reverse);
            let bits = assert_thread_independent(|| term_bits(&gas, &x));
            assert!(f64::from_bits(bits[0]).is_finite());
            assert!(((gas.region.area(&x) - 4.0 / 3.0) / (4.0 / 3.0)).abs() < 0.05);
        }
        // a repeated vertex (the first one closes the polygon again): merged gradient entries
        let n = 5 * CHUNK + 5;
        let (mut gas, x) = config(&mut rng, n, false);
        let w0 = gas.region.area_gradient(&x);
        gas.region.polygon.push(gas.region.polygon[0]);
        let w = assert_thread_independent(|| gas.region.area_gradient(&x));
        assert_eq!(w.len(), 2 * n);
        for (k, (a, b)) in w.iter().zip(&w0).enumerate() {
            assert_eq!(a.0, b.0);
            if k >= 2 && k < 2 * n - 2 {
                assert_eq!(a.1, b.1);
            }
        }
        let bits = assert_thread_independent(|| term_bits(&gas, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
    }
}
