//! Reuse across solves of what depends on the sparsity pattern only: the Uzawa backend keeps
//! the symbolic phase of its `LDLᵀ` of `P`, the OSQP backend keeps its set-up problem, the
//! Clarabel backend its solver (same structure of the conic form: patterns and the kinds of
//! bounds of the rows). A sequence of QPs sharing one structure, solved by one backend
//! instance, must give the results of a fresh instance per QP (bit for bit for Uzawa, to the
//! tolerance for OSQP and Clarabel), the reuse must actually happen (counters), and a QP with
//! another structure must invalidate the cache.
//!
//! The `#[ignore]` tests `timing_reuse_vs_fresh` (Uzawa, OSQP) and
//! `timing_clarabel_reuse_vs_fresh` measure the gain on a QP of realistic size:
//! `cargo test --release -p contactlab-solvers --test reuse -- --ignored --nocapture`.

use contactlab_solvers::clarabel_backend::ClarabelBackend;
use contactlab_solvers::linalg::{LdlSymbolic, SparseLdl};
use contactlab_solvers::osqp_backend::{OsqpBackend, OSQP_INFTY};
use contactlab_solvers::uzawa::UzawaBackend;
use contactlab_solvers::{CscMatrix, Qp, QpBackend, QpSettings, QpSolution, QpStatus, WarmStart};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// A sparsity pattern: off-diagonal entries `(i, j)`, `i < j`, of the upper triangle of `P`
/// (the diagonal is always present) and the entries of `A`. Rows 0 and 1 of `A` share their
/// columns, so that some values make the QP infeasible.
struct Pattern {
    n: usize,
    m: usize,
    p_off: Vec<(usize, usize)>,
    a: Vec<(usize, usize)>,
}

fn pattern(seed: u64, n: usize, m: usize) -> Pattern {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut p_off = Vec::new();
    for j in 0..n {
        // A band of width 2 plus a few long-range couplings.
        for i in j.saturating_sub(2)..j {
            p_off.push((i, j));
        }
        if j > 4 && rng.gen_bool(0.2) {
            p_off.push((rng.gen_range(0..j - 3), j));
        }
    }
    let mut a = Vec::new();
    let mut cols0 = Vec::new();
    for i in 0..m {
        let cols: Vec<usize> = if i == 1 {
            cols0.clone()
        } else {
            let k = rng.gen_range(2..6);
            let mut c: Vec<usize> = (0..k).map(|_| rng.gen_range(0..n)).collect();
            c.sort_unstable();
            c.dedup();
            c
        };
        if i == 0 {
            cols0 = cols.clone();
        }
        a.extend(cols.iter().map(|&j| (i, j)));
    }
    Pattern { n, m, p_off, a }
}

/// A QP with pattern `pat` and values drawn from `seed`: `P` strictly diagonally dominant
/// (positive definite) scaled by a random factor, bounds of random kinds (equality, two-sided,
/// one-sided, free) around a feasible point; infeasible (rows 0 and 1 equal, with equality
/// bounds 1 apart) when `infeasible`.
fn qp_with_values(pat: &Pattern, seed: u64, infeasible: bool) -> Qp {
    qp_with_kinds(pat, seed, infeasible, None)
}

/// [`qp_with_values`], with the kind of bounds of each row (`0 | 1` equality, `2..=4` two-sided,
/// `5 | 6` lower, `7 | 8` upper, `9` free) taken from `kinds` when given instead of drawn (the
/// values drawn are the same).
fn qp_with_kinds(pat: &Pattern, seed: u64, infeasible: bool, kinds: Option<&[u32]>) -> Qp {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = pat.n;
    let scale = rng.gen_range(0.5..2.0);
    let mut diag = vec![0.0; n];
    let mut pt = Vec::new();
    for &(i, j) in &pat.p_off {
        let v: f64 = rng.gen_range(-1.0..1.0);
        diag[i] += v.abs();
        diag[j] += v.abs();
        pt.push((i, j, scale * v));
    }
    for (j, d) in diag.iter().enumerate() {
        pt.push((j, j, scale * (d + rng.gen_range(0.1..2.0))));
    }
    let p = CscMatrix::from_triplets(n, n, &pt).unwrap();
    let q: Vec<f64> = (0..n).map(|_| rng.gen_range(-3.0..3.0)).collect();
    let mut at: Vec<(usize, usize, f64)> = pat
        .a
        .iter()
        .map(|&(i, j)| (i, j, rng.gen_range(-2.0..2.0)))
        .collect();
    if infeasible {
        let row0: Vec<f64> = at.iter().filter(|t| t.0 == 0).map(|t| t.2).collect();
        for (t, v) in at.iter_mut().filter(|t| t.0 == 1).zip(row0) {
            t.2 = v;
        }
    }
    let a = CscMatrix::from_triplets(pat.m, n, &at).unwrap();
    let x0: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
    let mut ax = vec![0.0; pat.m];
    a.mul_add(1.0, &x0, &mut ax);
    let (mut l, mut u) = (vec![0.0; pat.m], vec![0.0; pat.m]);
    for i in 0..pat.m {
        let (lo, hi) = (rng.gen_range(0.0..0.5), rng.gen_range(0.0..0.5));
        let drawn = rng.gen_range(0..10);
        (l[i], u[i]) = match kinds.map_or(drawn, |k| k[i]) {
            0 | 1 => (ax[i], ax[i]),
            2..=4 => (ax[i] - lo, ax[i] + hi),
            5 | 6 => (ax[i] - lo, f64::INFINITY),
            7 | 8 => (f64::NEG_INFINITY, ax[i] + hi),
            _ => (f64::NEG_INFINITY, f64::INFINITY),
        };
    }
    if infeasible {
        (l[0], u[0]) = (ax[0], ax[0]);
        (l[1], u[1]) = (ax[0] + 1.0, ax[0] + 1.0);
    }
    Qp { p, q, a, l, u }
}

/// The sequence of QPs with one pattern, and the warm start each is solved from: cold, then
/// from the previous solution, from its `y` only, cold again after a warm one, an infeasible QP
/// in the middle.
fn sequence(pat: &Pattern, seed: u64) -> Vec<(Qp, bool)> {
    (0..8u64)
        .map(|k| (qp_with_values(pat, seed + k, k == 4), k % 3 != 0))
        .collect()
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

fn uzawa_settings() -> QpSettings {
    QpSettings {
        eps_abs: 1e-8,
        eps_rel: 1e-8,
        max_iter: 20_000,
        time_limit_s: f64::INFINITY,
        presolve: true,
    }
}

fn osqp_settings() -> QpSettings {
    QpSettings {
        eps_abs: 1e-7,
        eps_rel: 1e-7,
        max_iter: 100_000,
        time_limit_s: f64::INFINITY,
        presolve: true,
    }
}

/// The warm start for the next QP: the previous solution (or only its `y`, every other time).
fn next_warm(prev: &QpSolution, k: usize) -> WarmStart {
    WarmStart {
        x: if k.is_multiple_of(2) {
            prev.x.clone()
        } else {
            Vec::new()
        },
        y: prev.y.clone(),
    }
}

#[test]
fn ldl_numeric_phase_is_bit_identical_and_checks_the_pattern() {
    let pat = pattern(7, 40, 10);
    let a = qp_with_values(&pat, 100, false).p;
    let b = qp_with_values(&pat, 101, false).p;
    let sym = LdlSymbolic::new(&a).unwrap();
    assert!(sym.matches(&b));
    for m in [&a, &b] {
        let fresh = SparseLdl::factor(m).unwrap();
        let reused = SparseLdl::numeric(m, &sym).unwrap();
        let rhs: Vec<f64> = (0..40).map(|i| (i as f64).sin()).collect();
        let (mut x1, mut x2) = (rhs.clone(), rhs.clone());
        fresh.solve_in_place(&mut x1);
        reused.solve_in_place(&mut x2);
        assert!(same_bits(&x1, &x2));
        assert_eq!(format!("{fresh:?}"), format!("{reused:?}"));
    }
    // Another pattern is refused, not factorized with the wrong symbolic phase.
    let other = qp_with_values(&pattern(8, 40, 10), 100, false).p;
    assert!(!sym.matches(&other));
    assert!(SparseLdl::numeric(&other, &sym).is_none());
    let smaller = qp_with_values(&pattern(7, 39, 10), 100, false).p;
    assert!(!sym.matches(&smaller));
}

#[test]
fn uzawa_reuse_is_bit_identical_to_fresh_instances() {
    let pat = pattern(1, 30, 18);
    let mut reused = UzawaBackend::new(uzawa_settings());
    let mut prev: Option<QpSolution> = None;
    let mut statuses = Vec::new();
    for (k, (qp, warm)) in sequence(&pat, 10).into_iter().enumerate() {
        let w = prev.as_ref().filter(|_| warm).map(|p| next_warm(p, k));
        let r = reused.solve(&qp, w.as_ref()).unwrap();
        let mut fresh_backend = UzawaBackend::new(uzawa_settings());
        let f = fresh_backend.solve(&qp, w.as_ref()).unwrap();
        assert_eq!(fresh_backend.symbolic_phases(), 1);
        assert_eq!(r.status, f.status, "QP {k}");
        assert_eq!(r.iterations, f.iterations, "QP {k}");
        assert!(same_bits(&r.x, &f.x), "QP {k}: x differs");
        assert!(same_bits(&r.y, &f.y), "QP {k}: y differs");
        statuses.push(r.status);
        prev = Some(r);
    }
    // The sequence exercises solved and non-solved QPs; one symbolic phase for all of them.
    assert!(statuses.iter().filter(|&&s| s == QpStatus::Solved).count() >= 5);
    assert_ne!(statuses[4], QpStatus::Solved);
    assert_eq!(reused.symbolic_phases(), 1);

    // Another pattern (a different P, or only a different n) invalidates the cache.
    for (i, other) in [pattern(2, 30, 18), pattern(1, 31, 18)].iter().enumerate() {
        let qp = qp_with_values(other, 50, false);
        let r = reused.solve(&qp, None).unwrap();
        let f = UzawaBackend::new(uzawa_settings())
            .solve(&qp, None)
            .unwrap();
        assert_eq!(reused.symbolic_phases(), 2 + i);
        assert_eq!(r.status, QpStatus::Solved);
        assert!(qp.primal_residual(&r.x) < 1e-6 && qp.dual_residual(&r.x, &r.y) < 1e-6);
        assert!(same_bits(&r.x, &f.x) && same_bits(&r.y, &f.y));
    }
    // A new A alone keeps the symbolic phase of P.
    let mut qp = qp_with_values(&pattern(1, 31, 18), 51, false);
    qp.a = qp_with_values(&pattern(3, 31, 25), 51, false).a;
    qp.l = vec![-1.0; 25];
    qp.u = vec![1.0; 25];
    let r = reused.solve(&qp, None).unwrap();
    assert_eq!(reused.symbolic_phases(), 3);
    assert_eq!(r.status, QpStatus::Solved);
    let f = UzawaBackend::new(uzawa_settings())
        .solve(&qp, None)
        .unwrap();
    assert!(same_bits(&r.x, &f.x) && same_bits(&r.y, &f.y));
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    let scale = a.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * scale)
}

#[test]
fn osqp_reuse_matches_fresh_instances() {
    let pat = pattern(1, 30, 18);
    let mut reused = OsqpBackend::new(osqp_settings());
    let mut prev: Option<QpSolution> = None;
    let mut statuses = Vec::new();
    for (k, (qp, warm)) in sequence(&pat, 10).into_iter().enumerate() {
        let w = prev.as_ref().filter(|_| warm).map(|p| next_warm(p, k));
        let r = reused.solve(&qp, w.as_ref()).unwrap();
        let mut fresh_backend = OsqpBackend::new(osqp_settings());
        let f = fresh_backend.solve(&qp, w.as_ref()).unwrap();
        assert_eq!(fresh_backend.setups(), 1);
        assert_eq!(r.status, f.status, "QP {k}");
        assert!(close(&r.x, &f.x, 1e-5), "QP {k}: x {:?} vs {:?}", r.x, f.x);
        assert!(close(&r.y, &f.y, 1e-5), "QP {k}: y {:?} vs {:?}", r.y, f.y);
        if r.status == QpStatus::Solved {
            assert!(qp.primal_residual(&r.x) < 1e-5, "QP {k}");
            assert!(qp.dual_residual(&r.x, &r.y) < 1e-5, "QP {k}");
        }
        statuses.push(r.status);
        prev = Some(r);
    }
    assert!(statuses.iter().filter(|&&s| s == QpStatus::Solved).count() >= 7);
    assert_eq!(statuses[4], QpStatus::PrimalInfeasible);
    assert_eq!(reused.setups(), 1);

    // Same QP twice, the second time cold: the reused problem restarts from zero (not from the
    // previous solution), so it behaves as a fresh one.
    let qp = qp_with_values(&pat, 30, false);
    let f = OsqpBackend::new(osqp_settings()).solve(&qp, None).unwrap();
    let r1 = reused.solve(&qp, None).unwrap();
    let r2 = reused.solve(&qp, None).unwrap();
    assert_eq!(reused.setups(), 1);
    let hot = WarmStart {
        x: r2.x.clone(),
        y: r2.y.clone(),
    };
    let r3 = reused.solve(&qp, Some(&hot)).unwrap();
    assert!(
        r3.iterations < r2.iterations,
        "the cold solve started from the previous solution"
    );
    for r in [&r1, &r2, &r3] {
        assert_eq!(r.status, f.status);
        assert!(close(&r.x, &f.x, 1e-5) && close(&r.y, &f.y, 1e-5));
    }

    // Another pattern of P, of A, or another m: new set-ups, correct solutions.
    let others = [pattern(2, 30, 18), pattern(1, 30, 19), pattern(1, 31, 18)];
    for (i, other) in others.iter().enumerate() {
        let qp = qp_with_values(other, 60, false);
        let r = reused.solve(&qp, None).unwrap();
        let f = OsqpBackend::new(osqp_settings()).solve(&qp, None).unwrap();
        assert_eq!(reused.setups(), 2 + i);
        assert_eq!(r.status, QpStatus::Solved);
        assert_eq!(f.status, QpStatus::Solved);
        assert!(close(&r.x, &f.x, 1e-5) && close(&r.y, &f.y, 1e-5));
        assert!(qp.primal_residual(&r.x) < 1e-5 && qp.dual_residual(&r.x, &r.y) < 1e-5);
    }
    // A clone sets up its own problem.
    let mut c = reused.clone();
    let qp = qp_with_values(&others[2], 61, false);
    c.solve(&qp, None).unwrap();
    assert_eq!(c.setups(), reused.setups() + 1);
    reused.solve(&qp, None).unwrap();
    assert_eq!(c.setups(), reused.setups() + 1);
}

fn clarabel_settings() -> QpSettings {
    QpSettings {
        eps_abs: 1e-9,
        eps_rel: 1e-9,
        max_iter: 200,
        time_limit_s: f64::INFINITY,
        presolve: true,
    }
}

/// Bound kinds for `m` rows (see [`qp_with_kinds`]), rows 0 and 1 equalities so that the
/// infeasible QP of a sequence has the structure of the others.
fn fixed_kinds(m: usize, seed: u64) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..m)
        .map(|i| if i < 2 { 0 } else { rng.gen_range(0..10) })
        .collect()
}

/// Solves `qp` with `reused` and with a fresh backend; checks that the statuses agree, that
/// `x` and `y` agree to `1e-6` and that a solved point meets the tolerance. Returns the reused
/// solution.
fn clarabel_vs_fresh(reused: &mut ClarabelBackend, qp: &Qp, what: &str) -> QpSolution {
    let r = reused.solve(qp, None).unwrap();
    let mut fresh_backend = ClarabelBackend::new(clarabel_settings());
    let f = fresh_backend.solve(qp, None).unwrap();
    assert_eq!(fresh_backend.setups(), 1);
    assert_eq!(r.status, f.status, "{what}");
    if r.status == QpStatus::Solved {
        assert!(close(&r.x, &f.x, 1e-6), "{what}: x {:?} vs {:?}", r.x, f.x);
        assert!(close(&r.y, &f.y, 1e-6), "{what}: y {:?} vs {:?}", r.y, f.y);
        assert!(qp.primal_residual(&r.x) < 1e-7, "{what}");
        assert!(qp.dual_residual(&r.x, &r.y) < 1e-7, "{what}");
    }
    r
}

/// The default Clarabel backend (`clarabel`) sets up a new solver for every QP, even when the
/// structure repeats, and gives what a fresh instance gives, bit for bit.
#[test]
fn clarabel_default_never_reuses() {
    let pat = pattern(1, 30, 18);
    let kinds = fixed_kinds(18, 5);
    let mut b = ClarabelBackend::new(clarabel_settings());
    assert_eq!(b.name(), "clarabel");
    for k in 0..4u64 {
        let qp = qp_with_kinds(&pat, 10 + k, false, Some(&kinds));
        let r = b.solve(&qp, None).unwrap();
        let f = ClarabelBackend::new(clarabel_settings())
            .solve(&qp, None)
            .unwrap();
        assert_eq!(b.setups(), k as usize + 1);
        assert_eq!((r.x, r.y, r.status), (f.x, f.y, f.status), "QP {k}");
    }
    assert_eq!(
        ClarabelBackend::with_reuse(clarabel_settings()).name(),
        "clarabel-reuse"
    );
}

#[test]
fn clarabel_reuse_matches_fresh_instances() {
    let pat = pattern(1, 30, 18);
    let kinds = fixed_kinds(18, 5);
    let mut reused = ClarabelBackend::with_reuse(clarabel_settings());
    let mut prev: Option<QpSolution> = None;
    let mut statuses = Vec::new();
    for k in 0..8u64 {
        let qp = qp_with_kinds(&pat, 10 + k, k == 4, Some(&kinds));
        // The warm start is ignored: the reused solver starts from Clarabel's default point.
        let w = prev.as_ref().map(|p| next_warm(p, k as usize));
        let r = reused.solve(&qp, w.as_ref()).unwrap();
        let f = ClarabelBackend::new(clarabel_settings())
            .solve(&qp, w.as_ref())
            .unwrap();
        assert_eq!(r.status, f.status, "QP {k}");
        if r.status == QpStatus::Solved {
            assert!(close(&r.x, &f.x, 1e-6), "QP {k}: x {:?} vs {:?}", r.x, f.x);
            assert!(close(&r.y, &f.y, 1e-6), "QP {k}: y {:?} vs {:?}", r.y, f.y);
            assert!(qp.primal_residual(&r.x) < 1e-7, "QP {k}");
            assert!(qp.dual_residual(&r.x, &r.y) < 1e-7, "QP {k}");
        }
        statuses.push(r.status);
        prev = Some(r);
    }
    assert_eq!(
        statuses.iter().filter(|&&s| s == QpStatus::Solved).count(),
        7
    );
    assert_eq!(statuses[4], QpStatus::PrimalInfeasible);
    assert_eq!(reused.setups(), 1);
    // Solved again after the infeasible QP, same as QP 5 above.
    clarabel_vs_fresh(
        &mut reused,
        &qp_with_kinds(&pat, 15, false, Some(&kinds)),
        "again",
    );
    assert_eq!(reused.setups(), 1);

    // Same conic structure from another QP structure: a row switching from an upper to a lower
    // bound keeps its conic row (with negated values), a free row added has no conic row.
    let upper = (2..18).find(|&i| (7..=8).contains(&kinds[i])).unwrap();
    let mut switched = kinds.clone();
    switched[upper] = 5;
    let qp = qp_with_kinds(&pat, 20, false, Some(&switched));
    clarabel_vs_fresh(&mut reused, &qp, "upper → lower");
    assert_eq!(reused.setups(), 1);
    let mut wider = pattern(1, 30, 18);
    wider.m = 19;
    wider.a.extend([(18, 3), (18, 17)]);
    let mut kinds19 = kinds.clone();
    kinds19.push(9);
    let qp = qp_with_kinds(&wider, 21, false, Some(&kinds19));
    let r = clarabel_vs_fresh(&mut reused, &qp, "free row");
    assert_eq!(r.status, QpStatus::Solved);
    assert_eq!(r.y[18], 0.0);
    assert_eq!(reused.setups(), 1);

    // Another structure: an inequality row becoming an equality, another pattern of P, of A,
    // another n: new set-ups, correct solutions.
    let ineq = (2..18).find(|&i| (2..=8).contains(&kinds[i])).unwrap();
    let mut eq = kinds.clone();
    eq[ineq] = 0;
    let qp = qp_with_kinds(&pat, 22, false, Some(&eq));
    let r = clarabel_vs_fresh(&mut reused, &qp, "inequality → equality");
    assert_eq!(r.status, QpStatus::Solved);
    assert_eq!(reused.setups(), 2);
    let others = [pattern(2, 30, 18), pattern(1, 30, 19), pattern(1, 31, 18)];
    for (i, other) in others.iter().enumerate() {
        let qp = qp_with_kinds(other, 60, false, Some(&fixed_kinds(other.m, 5)));
        let r = clarabel_vs_fresh(&mut reused, &qp, &format!("pattern {i}"));
        assert_eq!(r.status, QpStatus::Solved);
        assert_eq!(reused.setups(), 3 + i);
    }

    // An upper bound above Clarabel's infinity: a fresh solver presolves the row away, so the
    // kept solver (same conic structure) is not updated with it; the presolved solver is not
    // kept either.
    let other = &others[2];
    let kinds = fixed_kinds(other.m, 5);
    let qp = qp_with_kinds(other, 61, false, Some(&kinds));
    let upper = (2..other.m).find(|&i| (7..=8).contains(&kinds[i])).unwrap();
    let mut huge = qp.clone();
    huge.u[upper] = 1e25;
    let setups = reused.setups();
    for (k, q) in [&huge, &huge, &qp, &qp].into_iter().enumerate() {
        let r = clarabel_vs_fresh(&mut reused, q, &format!("huge bound {k}"));
        assert_eq!(r.status, QpStatus::Solved);
    }
    assert_eq!(reused.setups(), setups + 3);

    // A clone sets up its own solver.
    let mut c = reused.clone();
    c.solve(&qp, None).unwrap();
    assert_eq!(c.setups(), reused.setups() + 1);
    reused.solve(&qp, None).unwrap();
    assert_eq!(c.setups(), reused.setups() + 1);
}

/// A QP of contactlab's size: `P` a banded stiffness-like matrix (bandwidth 4) plus a proximal
/// diagonal, `A` contact rows on 6 variables each (lower bounds) coupling the two halves of the
/// variables at matching places, plus a two-sided box on a tenth of the variables. (Contact rows
/// between random far-apart variables would make OSQP's KKT factor nearly dense.)
fn big_qp(n: usize, contacts: usize, k: u64) -> Qp {
    let mut rng = ChaCha8Rng::seed_from_u64(1000 + k);
    let s = 1.0 + 0.05 * k as f64;
    let mut pt = Vec::new();
    for j in 0..n {
        for i in j.saturating_sub(4)..j {
            pt.push((i, j, -s * rng.gen_range(0.1..0.25)));
        }
        pt.push((j, j, s * 2.5 + 1e-2));
    }
    let p = CscMatrix::from_triplets(n, n, &pt).unwrap();
    let q: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
    let mut prng = ChaCha8Rng::seed_from_u64(1);
    let mut at = Vec::new();
    for r in 0..contacts {
        // Two bodies numbered one after the other, in contact along an interface: a point
        // of the first faces an edge of the second at the matching place.
        let c0 = prng.gen_range(0..n / 2 - 2);
        let c1 = (n / 2 + c0 + prng.gen_range(0..8)).min(n - 4);
        for c in [c0, c0 + 1, c1, c1 + 1, c1 + 2, c1 + 3] {
            at.push((r, c, rng.gen_range(-1.0..1.0)));
        }
    }
    let nbox = n / 10;
    for b in 0..nbox {
        at.push((contacts + b, 10 * b, 1.0));
    }
    let m = contacts + nbox;
    let a = CscMatrix::from_triplets(m, n, &at).unwrap();
    let mut l = vec![0.0; m];
    let mut u = vec![f64::INFINITY; m];
    for lr in &mut l[..contacts] {
        *lr = rng.gen_range(-0.2..0.3);
    }
    for b in 0..nbox {
        l[contacts + b] = -0.5;
        u[contacts + b] = 0.5;
    }
    Qp { p, q, a, l, u }
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

#[test]
#[ignore = "timing; run with --ignored --nocapture"]
fn timing_reuse_vs_fresh() {
    let (n, contacts, count) = (20_000, 3_000, 20u64);
    let qps: Vec<Qp> = (0..count).map(|k| big_qp(n, contacts, k)).collect();
    println!(
        "QP: n = {n}, m = {}, nnz(P) = {}, nnz(A) = {}, {count} solves",
        qps[0].m(),
        qps[0].p.nnz(),
        qps[0].a.nnz()
    );

    // Uzawa: the two phases of the factorization, then the whole solves.
    let reps = 20;
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(LdlSymbolic::new(&qps[0].p).unwrap());
    }
    let t_sym = secs(t) / reps as f64;
    let sym = LdlSymbolic::new(&qps[0].p).unwrap();
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(SparseLdl::numeric(&qps[0].p, &sym).unwrap());
    }
    let t_num = secs(t) / reps as f64;
    println!(
        "uzawa LDL: nnz(L) = {}, symbolic {:.3} ms, numeric {:.3} ms",
        sym.nnz_l(),
        1e3 * t_sym,
        1e3 * t_num
    );
    // Dual steps capped: the symbolic phase costs the same per solve whatever the step count.
    let st = QpSettings {
        eps_abs: 1e-8,
        eps_rel: 1e-8,
        max_iter: 200,
        time_limit_s: f64::INFINITY,
        presolve: true,
    };
    let mut reused = UzawaBackend::new(st.clone());
    let (mut t_reuse, mut t_fresh, mut iters) = (0.0, 0.0, 0);
    for qp in &qps {
        let t = Instant::now();
        let r = reused.solve(qp, None).unwrap();
        t_reuse += secs(t);
        let t = Instant::now();
        let f = UzawaBackend::new(st.clone()).solve(qp, None).unwrap();
        t_fresh += secs(t);
        assert!(same_bits(&r.x, &f.x) && r.status == f.status);
        iters += r.iterations;
    }
    assert_eq!(reused.symbolic_phases(), 1);
    println!(
        "uzawa {count} solves ({} dual steps): reuse {:.1} ms, fresh {:.1} ms (saved {:.2} ms)",
        iters,
        1e3 * t_reuse,
        1e3 * t_fresh,
        1e3 * (t_fresh - t_reuse)
    );

    // OSQP: set-up alone, data update alone, then the whole solves.
    let os = osqp_settings();
    let settings = osqp::Settings::default()
        .eps_abs(os.eps_abs)
        .eps_rel(os.eps_rel)
        .polish(true)
        .verbose(false);
    let csc = |m: &CscMatrix| osqp::CscMatrix {
        nrows: m.nrows,
        ncols: m.ncols,
        indptr: m.colptr.clone().into(),
        indices: m.rowval.clone().into(),
        data: m.nzval.clone().into(),
    };
    let bounds = |qp: &Qp| -> (Vec<f64>, Vec<f64>) {
        (
            qp.l.iter().map(|v| v.max(-OSQP_INFTY)).collect(),
            qp.u.iter().map(|v| v.min(OSQP_INFTY)).collect(),
        )
    };
    // Best of 3 for each part.
    let (mut t_setup, mut t_vec, mut t_rho, mut t_pa) = (f64::MAX, f64::MAX, f64::MAX, f64::MAX);
    for _ in 0..3 {
        let (l0, u0) = bounds(&qps[0]);
        let t = Instant::now();
        let mut prob = osqp::Problem::new(
            csc(&qps[0].p),
            &qps[0].q,
            csc(&qps[0].a),
            &l0,
            &u0,
            &settings,
        )
        .unwrap();
        t_setup = t_setup.min(secs(t));
        let (l1, u1) = bounds(&qps[1]);
        let t = Instant::now();
        prob.update_bounds(&l1, &u1);
        prob.update_lin_cost(&qps[1].q);
        t_vec = t_vec.min(secs(t));
        let t = Instant::now();
        prob.update_rho(0.1);
        t_rho = t_rho.min(secs(t));
        let t = Instant::now();
        prob.update_P_A(csc(&qps[1].p), csc(&qps[1].a));
        t_pa = t_pa.min(secs(t));
    }
    println!(
        "osqp: set-up {:.2} ms; update of l, u and q {:.2} ms, of rho {:.2} ms, of P and A {:.2} ms",
        1e3 * t_setup,
        1e3 * t_vec,
        1e3 * t_rho,
        1e3 * t_pa
    );
    let mut reused = OsqpBackend::new(os.clone());
    let (mut t_reuse, mut t_fresh, mut it_r, mut it_f) = (0.0, 0.0, 0, 0);
    for qp in &qps {
        let t = Instant::now();
        let r = reused.solve(qp, None).unwrap();
        t_reuse += secs(t);
        let t = Instant::now();
        let f = OsqpBackend::new(os.clone()).solve(qp, None).unwrap();
        t_fresh += secs(t);
        assert_eq!(r.status, f.status);
        assert!(close(&r.x, &f.x, 1e-5));
        it_r += r.iterations;
        it_f += f.iterations;
    }
    assert_eq!(reused.setups(), 1);
    println!(
        "osqp {count} solves: reuse {:.1} ms ({it_r} ADMM iterations), fresh {:.1} ms ({it_f}), \
         saved {:.1} ms",
        1e3 * t_reuse,
        1e3 * t_fresh,
        1e3 * (t_fresh - t_reuse)
    );
}

#[test]
#[ignore = "timing; run with --ignored --nocapture"]
fn timing_clarabel_reuse_vs_fresh() {
    use clarabel::algebra::CscMatrix as ClCsc;
    use clarabel::solver::{DefaultSettings, DefaultSolver, NonnegativeConeT};
    let (n, contacts, count) = (20_000, 3_000, 20u64);
    let qps: Vec<Qp> = (0..count).map(|k| big_qp(n, contacts, k)).collect();
    println!(
        "QP: n = {n}, m = {}, nnz(P) = {}, nnz(A) = {}, {count} solves",
        qps[0].m(),
        qps[0].p.nnz(),
        qps[0].a.nnz()
    );

    // Set-up alone and data update alone, on a conic form of the same structure as the
    // backend's (big_qp has lower bounds on the contact rows, two-sided boxes).
    let conic = |qp: &Qp| {
        let (mut ti, mut tj, mut tv, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut push = |i: usize, j: usize, v: f64| {
            ti.push(i);
            tj.push(j);
            tv.push(v);
        };
        for j in 0..n {
            for p in qp.a.colptr[j]..qp.a.colptr[j + 1] {
                let (i, v) = (qp.a.rowval[p], qp.a.nzval[p]);
                if i < contacts {
                    push(i, j, -v);
                } else {
                    let k = contacts + 2 * (i - contacts);
                    push(k, j, v);
                    push(k + 1, j, -v);
                }
            }
        }
        for i in 0..qp.m() {
            if i < contacts {
                b.push(-qp.l[i]);
            } else {
                b.extend([qp.u[i], -qp.l[i]]);
            }
        }
        (ClCsc::new_from_triplets(b.len(), n, ti, tj, tv), b)
    };
    let p = |qp: &Qp| {
        ClCsc::new(
            n,
            n,
            qp.p.colptr.clone(),
            qp.p.rowval.clone(),
            qp.p.nzval.clone(),
        )
    };
    let (a0, b0) = conic(&qps[0]);
    let (a1, b1) = conic(&qps[1]);
    let cones = [NonnegativeConeT(b0.len())];
    let settings = DefaultSettings::<f64> {
        verbose: false,
        ..DefaultSettings::default()
    };
    // Best of 3 for each part.
    let (mut t_setup, mut t_update) = (f64::MAX, f64::MAX);
    for _ in 0..3 {
        let t = Instant::now();
        let mut s =
            DefaultSolver::new(&p(&qps[0]), &qps[0].q, &a0, &b0, &cones, settings.clone()).unwrap();
        t_setup = t_setup.min(secs(t));
        assert!(s.is_data_update_allowed());
        let t = Instant::now();
        s.update_P(&qps[1].p.nzval).unwrap();
        s.update_A(&a1.nzval).unwrap();
        s.update_q(&qps[1].q).unwrap();
        s.update_b(&b1).unwrap();
        t_update = t_update.min(secs(t));
    }
    println!(
        "clarabel: set-up {:.2} ms; update of P, A, q and b {:.2} ms",
        1e3 * t_setup,
        1e3 * t_update
    );

    let st = clarabel_settings();
    let mut reused = ClarabelBackend::with_reuse(st.clone());
    let (mut t_reuse, mut t_fresh, mut it_r, mut it_f) = (0.0, 0.0, 0, 0);
    for qp in &qps {
        let t = Instant::now();
        let r = reused.solve(qp, None).unwrap();
        t_reuse += secs(t);
        let t = Instant::now();
        let f = ClarabelBackend::new(st.clone()).solve(qp, None).unwrap();
        t_fresh += secs(t);
        assert_eq!(r.status, QpStatus::Solved);
        assert_eq!(f.status, QpStatus::Solved);
        // This QP is ill-conditioned (P's smallest eigenvalues are near its 1e-2 diagonal):
        // at the gap tolerance the two points differ by up to ~1e-4 in x, the objectives by
        // ~1e-10 relative, both points feasible.
        let (or, of) = (qp.objective(&r.x), qp.objective(&f.x));
        assert!((or - of).abs() <= 1e-8 * of.abs().max(1.0), "{or} vs {of}");
        assert!(close(&r.x, &f.x, 1e-3));
        assert!(qp.primal_residual(&r.x) < 1e-7 && qp.dual_residual(&r.x, &r.y) < 1e-7);
        it_r += r.iterations;
        it_f += f.iterations;
    }
    assert_eq!(reused.setups(), 1);
    println!(
        "clarabel {count} solves: reuse {:.1} ms ({it_r} IP iterations, {:.2} ms/solve), fresh \
         {:.1} ms ({it_f}, {:.2} ms/solve), saved {:.2} ms/solve",
        1e3 * t_reuse,
        1e3 * t_reuse / count as f64,
        1e3 * t_fresh,
        1e3 * t_fresh / count as f64,
        1e3 * (t_fresh - t_reuse) / count as f64
    );
}
