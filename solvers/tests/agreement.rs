//! Every registered backend agrees on seeded random feasible QPs, report infeasibility as a status,
//! reject bad input with a named error, and solve a degenerate contact-like QP.

use contactlab_solvers::{
    backend_from_name, CscMatrix, Qp, QpError, QpSettings, QpStatus, WarmStart, BACKEND_NAMES,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Tight tolerances: the objective error of a point with violation `v` is about `‖y‖∞·v`, and a
/// few seeds have `‖y‖∞ ≈ 2e3`, so 1e-10 keeps the 1e-6 relative objective agreement safe.
fn settings() -> QpSettings {
    QpSettings {
        eps_abs: 1e-10,
        eps_rel: 1e-10,
        max_iter: 200_000,
        time_limit_s: 10.0,
        presolve: true,
    }
}

/// A random feasible QP: P = MᵀM + 0.1 I, sparse-ish A, bounds around a known feasible point,
/// with equality, two-sided, one-sided (both kinds) and free rows.
fn random_qp(seed: u64) -> Qp {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = rng.gen_range(3..15);
    let m = rng.gen_range(1..20);
    let k = n + 2;
    let mm: Vec<Vec<f64>> = (0..k)
        .map(|_| (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect())
        .collect();
    let mut pt = Vec::new();
    for j in 0..n {
        for i in 0..=j {
            let mut v: f64 = (0..k).map(|r| mm[r][i] * mm[r][j]).sum();
            if i == j {
                v += 0.1;
            }
            pt.push((i, j, v));
        }
    }
    let p = CscMatrix::from_triplets(n, n, &pt).unwrap();
    let q: Vec<f64> = (0..n).map(|_| rng.gen_range(-3.0..3.0)).collect();
    let mut at = Vec::new();
    for i in 0..m {
        let mut any = false;
        for j in 0..n {
            if rng.gen_bool(0.4) {
                at.push((i, j, rng.gen_range(-2.0..2.0)));
                any = true;
            }
        }
        if !any {
            at.push((i, rng.gen_range(0..n), 1.0));
        }
    }
    let a = CscMatrix::from_triplets(m, n, &at).unwrap();
    let x0: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
    let mut ax = vec![0.0; m];
    a.mul_add(1.0, &x0, &mut ax);
    let (mut l, mut u) = (vec![0.0; m], vec![0.0; m]);
    for i in 0..m {
        let kind = rng.gen_range(0..10);
        let (lo, hi) = (rng.gen_range(0.0..0.5), rng.gen_range(0.0..0.5));
        match kind {
            0 | 1 => {
                l[i] = ax[i];
                u[i] = ax[i];
            }
            2..=4 => {
                l[i] = ax[i] - lo;
                u[i] = ax[i] + hi;
            }
            5..=6 => {
                l[i] = ax[i] - lo;
                u[i] = f64::INFINITY;
            }
            7..=8 => {
                l[i] = f64::NEG_INFINITY;
                u[i] = ax[i] + hi;
            }
            _ => {
                l[i] = f64::NEG_INFINITY;
                u[i] = f64::INFINITY;
            }
        }
    }
    Qp { p, q, a, l, u }
}

fn solve_all_and_compare(qp: &Qp, label: &str) {
    let mut sols = Vec::new();
    for name in BACKEND_NAMES {
        let mut b = backend_from_name(name, &settings()).unwrap();
        let s = b.solve(qp, None).unwrap();
        assert_eq!(s.status, QpStatus::Solved, "{label}: {name} status");
        let pr = qp.primal_residual(&s.x);
        let dr = qp.dual_residual(&s.x, &s.y);
        assert!(pr <= 1e-6, "{label}: {name} primal residual {pr}");
        assert!(dr <= 1e-5, "{label}: {name} dual residual {dr}");
        sols.push((name, qp.objective(&s.x), s.x));
    }
    let (_, f0, x0) = &sols[0];
    for (name, f, x) in &sols[1..] {
        assert!(
            (f - f0).abs() <= 1e-6 * f0.abs().max(1.0),
            "{label}: {name} objective {f} vs {f0}"
        );
        let dx = x
            .iter()
            .zip(x0)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(dx <= 1e-5, "{label}: {name} x differs by {dx}");
    }
}

#[test]
fn random_feasible_qps_agree() {
    for seed in 0..200 {
        let qp = random_qp(seed);
        solve_all_and_compare(&qp, &format!("seed {seed}"));
    }
}

#[test]
fn degenerate_redundant_contact_rows() {
    // min ½‖x‖² + 0.1 I proximal-like term − x1, with x0 ≥ 1 repeated 5 times, x0 + x1 ≥ 1.5
    // twice, and a duplicate upper row.
    let n = 3;
    let p = CscMatrix::from_triplets(n, n, &[(0, 0, 1.1), (0, 1, 0.2), (1, 1, 1.1), (2, 2, 1.1)])
        .unwrap();
    let mut t = Vec::new();
    for i in 0..5 {
        t.push((i, 0, 1.0));
    }
    for i in 5..7 {
        t.push((i, 0, 1.0));
        t.push((i, 1, 1.0));
    }
    t.push((7, 2, 1.0));
    t.push((8, 2, 1.0));
    let a = CscMatrix::from_triplets(9, n, &t).unwrap();
    let mut l = vec![1.0; 9];
    l[5] = 1.5;
    l[6] = 1.5;
    l[7] = f64::NEG_INFINITY;
    l[8] = f64::NEG_INFINITY;
    let mut u = vec![f64::INFINITY; 9];
    u[7] = -0.5;
    u[8] = -0.5;
    let qp = Qp {
        p,
        q: vec![0.0, -0.1, 0.0],
        a,
        l,
        u,
    };
    solve_all_and_compare(&qp, "degenerate");
}

#[test]
fn infeasible_qps_are_a_status() {
    for seed in 0..5 {
        let mut qp = random_qp(100 + seed);
        // Append x0 ≥ 1 and x0 ≤ −1 as two rows (each with valid bounds).
        let (n, m) = (qp.n(), qp.m());
        let mut t = Vec::new();
        for j in 0..n {
            for p in qp.a.colptr[j]..qp.a.colptr[j + 1] {
                t.push((qp.a.rowval[p], j, qp.a.nzval[p]));
            }
        }
        t.push((m, 0, 1.0));
        t.push((m + 1, 0, 1.0));
        qp.a = CscMatrix::from_triplets(m + 2, n, &t).unwrap();
        qp.l.extend([1.0, f64::NEG_INFINITY]);
        qp.u.extend([f64::INFINITY, -1.0]);
        for name in BACKEND_NAMES {
            let s = backend_from_name(name, &settings())
                .unwrap()
                .solve(&qp, None)
                .unwrap();
            assert_ne!(s.status, QpStatus::Solved, "seed {seed}: {name}");
            assert_eq!((s.x.len(), s.y.len()), (n, m + 2));
        }
    }
}

#[test]
fn bad_input_is_a_named_error() {
    let base = random_qp(7);
    for name in BACKEND_NAMES {
        let mut b = backend_from_name(name, &settings()).unwrap();

        let mut qp = base.clone();
        qp.l[0] = 2.0;
        qp.u[0] = 1.0;
        assert_eq!(
            b.solve(&qp, None).unwrap_err(),
            QpError::InvalidBounds {
                row: 0,
                l: 2.0,
                u: 1.0
            },
            "{name}"
        );

        let mut qp = base.clone();
        qp.q[1] = f64::NAN;
        let e = b.solve(&qp, None).unwrap_err();
        assert!(
            matches!(
                e,
                QpError::NotFinite {
                    what: "q",
                    index: 1,
                    ..
                }
            ),
            "{name}: {e}"
        );

        let mut qp = base.clone();
        let mut t = vec![(1, 0, 0.5)];
        for j in 0..qp.n() {
            for p in qp.p.colptr[j]..qp.p.colptr[j + 1] {
                t.push((qp.p.rowval[p], j, qp.p.nzval[p]));
            }
        }
        qp.p = CscMatrix::from_triplets(qp.n(), qp.n(), &t).unwrap();
        assert_eq!(
            b.solve(&qp, None).unwrap_err(),
            QpError::NotUpperTriangular { row: 1, col: 0 },
            "{name}"
        );

        let w = WarmStart {
            x: vec![0.0; base.n()],
            y: vec![0.0; base.m() + 1],
        };
        let e = b.solve(&base, Some(&w)).unwrap_err();
        assert_eq!(
            e,
            QpError::WarmStartLength {
                what: "y",
                expected: base.m(),
                found: base.m() + 1
            },
            "{name}"
        );
    }
}

#[test]
fn unconstrained_and_free_rows_only() {
    let p = CscMatrix::from_triplets(2, 2, &[(0, 0, 2.0), (0, 1, 0.5), (1, 1, 1.0)]).unwrap();
    let q = vec![1.0, -1.0];
    let none = Qp {
        p: p.clone(),
        q: q.clone(),
        a: CscMatrix::zeros(0, 2),
        l: vec![],
        u: vec![],
    };
    solve_all_and_compare(&none, "no rows");
    let a = CscMatrix::from_triplets(1, 2, &[(0, 0, 1.0), (0, 1, 1.0)]).unwrap();
    let free = Qp {
        p,
        q,
        a,
        l: vec![f64::NEG_INFINITY],
        u: vec![f64::INFINITY],
    };
    solve_all_and_compare(&free, "free row");
}
