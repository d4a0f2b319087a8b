//! Uniform external pressure on a closed curve: `J(x) = p · A(x)`.
//!
//! `A` is the signed (shoelace) area of the polygon `x_0, …, x_{n−1}` (closed: `x_n = x_0`),
//!
//! ```text
//! A(x) = ½ Σ_{i=0}^{n−1} (x_i y_{i+1} − x_{i+1} y_i),   indices mod n,
//! ```
//!
//! positive when the polygon is listed counter-clockwise ([`PressureEnergy::new`] orders it so
//! at the configuration it is given). With `p > 0` the term pulls the curve inward (a vacuum
//! outside-in load); `p < 0` would inflate it. The energy is linear in `p` and quadratic in `x`:
//!
//! ```text
//! ∂J/∂x_i = p/2 (y_{i+1} − y_{i−1}),   ∂J/∂y_i = p/2 (x_{i−1} − x_{i+1}),
//! ∇²J = Σ_i M_i,   M_i = (p/2) S on (x_i, y_i, x_{i+1}, y_{i+1}),
//! S = [[0,0,0,1],[0,0,−1,0],[0,−1,0,0],[1,0,0,0]].
//! ```
//!
//! The Hessian is constant and indefinite (the area is a saddle-shaped quadratic form: a
//! uniform dilation grows it, a shear does not). **Projection:** as for the gas term
//! ([`super::gas`]), per shoelace element: `S² = I`, so `M_i` has eigenvalues `±p/2` and its
//! positive semi-definite part is `(M_i + |M_i|)/2 = ((p/2) S + |p/2| I)/2`, used when
//! `projected = true`. Each vertex belongs to two shoelace terms, so the projected Hessian
//! adds `|p|/2` to each of its diagonal entries plus the couplings `p/4·S` between
//! neighbours. This is the element-wise convention of the other energies; it over-estimates the
//! curvature of `J` (the exact term is indefinite), which only makes the inner Newton-type
//! steps more conservative: the line search is on the exact `J`.
//!
//! Assembly follows the conventions of [`super`]: the area is a chunked sum, the gradient a
//! per-vertex contribution scatter-added in polygon order, the Hessian triplets are produced in
//! chunks in shoelace-term order; all bit-identical for any thread count.

use super::gas::area::{polygon_xy as xy, shoelace_sum};
use super::{par_scatter, Energy, Hessian, TermKind};

const DIM: usize = 2;

/// `p · A` for the signed area `A` enclosed by a closed polygon (2D).
#[derive(Clone, Debug)]
pub struct PressureEnergy {
    /// Polygon vertices in order; the closing side is last → first. Counter-clockwise for a
    /// positive area.
    pub polygon: Vec<usize>,
    /// Pressure `p` (energy per unit area); `p > 0` pulls the curve inward.
    pub p: f64,
}

impl PressureEnergy {
    /// Builds the energy, reversing `polygon` if its signed area at `x0` is negative, so that
    /// `A(x0) ≥ 0` (counter-clockwise order).
    pub fn new(mut polygon: Vec<usize>, p: f64, x0: &[f64]) -> Self {
        if signed_area(&polygon, x0) < 0.0 {
            polygon.reverse();
        }
        Self { polygon, p }
    }

    /// Signed area `A(x)` of the polygon, in its stored order.
    pub fn area(&self, x: &[f64]) -> f64 {
        signed_area(&self.polygon, x)
    }
}

/// Shoelace area of `polygon` at `x` (the gas's sum, [`super::gas::area`]).
fn signed_area(polygon: &[usize], x: &[f64]) -> f64 {
    0.5 * shoelace_sum(polygon, x)
}

impl Energy for PressureEnergy {
    fn name(&self) -> &str {
        "pressure"
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn exact_in_model(&self) -> bool {
        true
    }

    fn value(&self, x: &[f64]) -> f64 {
        self.p * self.area(x)
    }

    /// Adds `p ∇A`, vertex by vertex in polygon order (a repeated vertex gets both terms).
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        let n = self.polygon.len();
        let half_p = 0.5 * self.p;
        par_scatter(
            n,
            g,
            |i| {
                let (xp, yp) = xy(&self.polygon, x, i + n - 1);
                let (xn, yn) = xy(&self.polygon, x, i + 1);
                Some([half_p * (yn - yp), half_p * (xp - xn)])
            },
            |i, c, g| {
                let v = self.polygon[i];
                g[DIM * v] += c[0];
                g[DIM * v + 1] += c[1];
            },
        );
    }

    /// The constant Hessian `Σ_i (p/2) S` on consecutive vertex pairs; with `projected` each
    /// block is replaced by its PSD part `((p/2) S + |p/2| I)/2` (module docs).
    fn add_hessian(&self, _x: &[f64], projected: bool, h: &mut Hessian) {
        let k = 0.5 * self.p;
        super::gas::shoelace_hessian(&self.polygon, k, projected, h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A perturbed ellipse of `n` vertices (listed counter-clockwise or clockwise), plus an
    /// unused extra vertex to check sparsity; random pressure of either sign.
    fn config(rng: &mut ChaCha8Rng, n: usize, reverse: bool) -> (PressureEnergy, Vec<f64>) {
        let mut x = vec![0.0; 2 * (n + 1)];
        for v in 0..n {
            let t = 2.0 * std::f64::consts::PI * v as f64 / n as f64;
            x[2 * v] = 1.5 * t.cos() + rng.gen_range(-0.05..0.05);
            x[2 * v + 1] = 0.7 * t.sin() + rng.gen_range(-0.05..0.05);
        }
        x[2 * n] = 5.0;
        x[2 * n + 1] = -3.0;
        let mut poly: Vec<usize> = (0..n).collect();
        if reverse {
            poly.reverse();
        }
        let p = rng.gen_range(0.5..3.0) * if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
        (PressureEnergy::new(poly, p, &x), x)
    }

    #[test]
    fn energy_pressure_orientation_and_area() {
        let x = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0];
        let e = PressureEnergy::new(vec![0, 1, 2], 2.0, &x);
        assert_eq!(e.polygon, vec![0, 1, 2]);
        assert!((e.area(&x) - 0.5).abs() < 1e-15);
        assert!((e.value(&x) - 1.0).abs() < 1e-15);
        let e = PressureEnergy::new(vec![2, 1, 0], 2.0, &x);
        assert_eq!(e.polygon, vec![0, 1, 2], "reordered counter-clockwise");
        assert!((e.area(&x) - 0.5).abs() < 1e-15);
        // flipped configuration: the signed area (and J) go negative, no infinity
        let xf = [0.0, 0.0, 1.0, 0.0, 1.0, -1.0];
        assert!((e.value(&xf) + 1.0).abs() < 1e-15);
        // a polygon inscribed in an ellipse of semi-axes 1.5, 0.7 approaches π·1.05
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for rev in [false, true] {
            let (e, x) = config(&mut rng, 400, rev);
            assert!((e.area(&x) - std::f64::consts::PI * 1.05).abs() < 0.05);
        }
    }

    #[test]
    fn energy_pressure_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-7 (J is quadratic: exact up to
        // round-off)
        let mut rng = ChaCha8Rng::seed_from_u64(22);
        for k in 0..20 {
            let (e, x) = config(&mut rng, 7 + k % 3, k % 2 == 1);
            let mut g = vec![0.0; x.len()];
            e.add_gradient(&x, &mut g);
            let gf = fd_gradient(&e, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-7, "rel {}", rel(&g, &gf));
            // the unused vertex gets nothing
            assert_eq!(&g[g.len() - 2..], &[0.0, 0.0]);
        }
    }

    #[test]
    fn energy_pressure_hessian_fd_and_projection_psd() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-7
        let mut rng = ChaCha8Rng::seed_from_u64(23);
        for k in 0..20 {
            let (e, x) = config(&mut rng, 6 + k % 4, k % 2 == 1);
            let n = x.len();
            let mut h = Hessian::default();
            e.add_hessian(&x, false, &mut h);
            assert!(h.rank_one.is_empty());
            let hd = h.to_dense(n);
            let hf = fd_hessian(&e, &x, 1e-6);
            let r = rel(hd.as_slice(), hf.as_slice());
            assert!(r <= 1e-7, "rel {r}");
            // the exact Hessian is indefinite
            let ev = hd.symmetric_eigenvalues();
            assert!(ev.min() < -1e-3 && ev.max() > 1e-3, "{ev}");
            let mut hp = Hessian::default();
            e.add_hessian(&x, true, &mut hp);
            assert!(hp.rank_one.is_empty());
            let hpd = hp.to_dense(n);
            assert!((&hpd - hpd.transpose()).norm() <= 1e-14 * hpd.norm());
            let ev = hpd.symmetric_eigenvalues();
            assert!(ev.min() >= -1e-12 * hpd.norm(), "min eig {}", ev.min());
            // diagonal |p|/2 per coordinate of each polygon vertex
            for d in 0..n - 2 {
                assert!((hpd[(d, d)] - 0.5 * e.p.abs()).abs() < 1e-15);
            }
            // the unused vertex has no entries
            assert!(hp.triplets.iter().all(|t| t.0 < n - 2 && t.1 < n - 2));
        }
    }

    #[test]
    fn energy_pressure_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let mut rng = ChaCha8Rng::seed_from_u64(24);
        for reverse in [false, true] {
            let (e, x) = config(&mut rng, 5 * CHUNK + 77, reverse);
            let bits = assert_thread_independent(|| term_bits(&e, &x));
            assert!(f64::from_bits(bits[0]).is_finite());
        }
        // a repeated vertex (the first one closes the polygon again): both of its gradient
        // terms are added
        let (mut e, x) = config(&mut rng, 3 * CHUNK + 5, false);
        e.polygon.push(e.polygon[0]);
        let bits = assert_thread_independent(|| term_bits(&e, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
        let (mut e, x) = config(&mut rng, 9, false);
        e.polygon.insert(4, e.polygon[0]);
        let mut g = vec![0.0; x.len()];
        e.add_gradient(&x, &mut g);
        let gf = fd_gradient(&e, &x, 1e-6);
        assert!(rel(&g, &gf) <= 1e-7, "rel {}", rel(&g, &gf));
    }
}
