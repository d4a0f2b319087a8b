//! Finite-difference helpers shared by the energies' tests.

use super::Energy;
use nalgebra::DMatrix;

/// Central-difference gradient (step `h`).
pub fn fd_gradient(e: &dyn Energy, x: &[f64], h: f64) -> Vec<f64> {
    let mut xp = x.to_vec();
    (0..x.len())
        .map(|i| {
            xp[i] = x[i] + h;
            let fp = e.value(&xp);
            xp[i] = x[i] - h;
            let fm = e.value(&xp);
            xp[i] = x[i];
            (fp - fm) / (2.0 * h)
        })
        .collect()
}

/// Central differences of the gradient (step `h`), symmetrized.
pub fn fd_hessian(e: &dyn Energy, x: &[f64], h: f64) -> DMatrix<f64> {
    let n = x.len();
    let mut m = DMatrix::zeros(n, n);
    let mut xp = x.to_vec();
    for j in 0..n {
        let mut gp = vec![0.0; n];
        let mut gm = vec![0.0; n];
        xp[j] = x[j] + h;
        e.add_gradient(&xp, &mut gp);
        xp[j] = x[j] - h;
        e.add_gradient(&xp, &mut gm);
        xp[j] = x[j];
        for i in 0..n {
            m[(i, j)] = (gp[i] - gm[i]) / (2.0 * h);
        }
    }
    (&m + m.transpose()) * 0.5
}

pub fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a
        .iter()
        .zip(b)
        .map(|(u, v)| (u - v).powi(2))
        .sum::<f64>()
        .sqrt();
    let s: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    d / s.max(1e-12)
}
