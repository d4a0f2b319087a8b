//! Finite-difference and thread-determinism helpers shared by the energies' tests.

use super::{Energy, Hessian, TotalEnergy};
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

/// Everything an energy term computes at `x`, as raw bits (for exact comparisons): value,
/// gradient (added to a gradient prefilled with a pattern, to exercise `+=`), exact Hessian and
/// projected Hessian.
pub fn term_bits(e: &dyn Energy, x: &[f64]) -> Vec<u64> {
    let mut out = vec![e.value(x).to_bits()];
    let mut g: Vec<f64> = (0..x.len()).map(|i| (i % 7) as f64 * 0.125).collect();
    e.add_gradient(x, &mut g);
    out.extend(g.iter().map(|v| v.to_bits()));
    for projected in [false, true] {
        let mut h = Hessian::default();
        e.add_hessian(x, projected, &mut h);
        hessian_bits(&h, &mut out);
    }
    out
}

/// [`term_bits`] for a [`TotalEnergy`].
pub fn total_bits(t: &TotalEnergy, x: &[f64]) -> Vec<u64> {
    let mut out = vec![t.value(x).to_bits()];
    out.extend(t.gradient(x).iter().map(|v| v.to_bits()));
    for projected in [false, true] {
        hessian_bits(&t.hessian(x, projected), &mut out);
    }
    out
}

fn hessian_bits(h: &Hessian, out: &mut Vec<u64>) {
    out.push(h.triplets.len() as u64);
    for &(i, j, v) in &h.triplets {
        out.extend([i as u64, j as u64, v.to_bits()]);
    }
    out.push(h.rank_one.len() as u64);
    for r in &h.rank_one {
        out.push(r.coef.to_bits());
        out.push(r.w.len() as u64);
        for &(i, v) in &r.w {
            out.extend([i as u64, v.to_bits()]);
        }
    }
}

/// Runs `f` in rayon pools of 1, 2 and 3 threads and asserts that the three results are
/// identical; returns the result.
pub fn assert_thread_independent<R: PartialEq + Send>(f: impl Fn() -> R + Sync) -> R {
    let run = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(&f)
    };
    let r1 = run(1);
    for n in [2, 3] {
        assert!(
            run(n) == r1,
            "result with {n} threads differs from 1 thread"
        );
    }
    r1
}
