//! The sub-problem solver at two sizes (balloons n = 160 and 640, lazy rows, the default Newton
//! model), with Clarabel and with `ip`, each at its default tolerance: one inner step (the
//! first outer step with `max_inner = 1`: the QP build, the model shift, the backend and the
//! lazy re-solves) and one full sub-problem (the first outer step, inner steps uncapped),
//! beside one sparse LDLᵀ of the first QP's `P` (the Hessian with the proximal term, the shift
//! and the gas' auxiliary variables) and one of `P + AᵀA` (the same with the contact rows'
//! pattern: what an interior point on the condensed system factorizes at each iteration), the
//! units an inner step is measured against.
//!
//! Run: `cargo bench --bench subproblem` (criterion; results in `target/criterion/`). Other
//! sizes: `SUBPROBLEM_SIZES="1600" cargo bench --bench subproblem` (n = 1600 takes about ten
//! minutes: ten samples of each whole first step).

use std::time::Duration;

use contactlab::contact::{near_pairs, rows_for};
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::Scene;
use contactlab::solve::outer::{median_edge_length, run, OuterSettings};
use contactlab::solve::subproblem::{build_qp, DofMap, InnerSettings, ModelShift};
use contactlab_solvers::linalg::SparseLdl;
use contactlab_solvers::{backend_from_name, default_settings, CscMatrix};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};

fn scene(n: usize) -> Scene {
    build(&BalloonsParams {
        n,
        ..Default::default()
    })
    .expect("balloons scene")
}

/// The first outer step with at most `max_inner` inner steps; returns J after it.
fn first_step(s: &Scene, backend: &str, max_inner: usize) -> f64 {
    let mut settings = OuterSettings {
        max_outer: 1,
        ..Default::default()
    };
    settings.inner.max_inner = max_inner;
    let mut b = backend_from_name(backend, &default_settings(backend)).unwrap();
    run(
        &s.mesh,
        &s.energy,
        s.eps,
        &s.x0,
        b.as_mut(),
        &settings,
        &mut |_, _| {},
    )
    .expect("first outer step")
    .energy
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("subproblem");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    let sizes: Vec<usize> = match std::env::var("SUBPROBLEM_SIZES") {
        Ok(v) => v
            .split_whitespace()
            .map(|t| {
                t.parse().unwrap_or_else(|_| {
                    eprintln!("SUBPROBLEM_SIZES: {t:?} is not a balloons size (e.g. \"160 640\")");
                    std::process::exit(2)
                })
            })
            .collect(),
        Err(_) => vec![160, 640],
    };
    for n in sizes {
        let s = scene(n);
        for backend in ["clarabel", "ip"] {
            g.bench_with_input(
                BenchmarkId::new(format!("one_inner_step/{backend}"), n),
                &s,
                |b, s| b.iter(|| black_box(first_step(s, backend, 1))),
            );
            g.bench_with_input(
                BenchmarkId::new(format!("one_subproblem/{backend}"), n),
                &s,
                |b, s| b.iter(|| black_box(first_step(s, backend, 50))),
            );
        }
        // The first QP of the step: the rows of the pairs a lazy step starts with.
        let settings = InnerSettings::default();
        let eps_qp = s.eps * (1.0 + settings.margin_rel) + settings.margin_abs;
        let r = eps_qp + 0.25 * median_edge_length(&s.mesh, &s.x0);
        let pairs = near_pairs(&s.mesh, &s.x0, r, true);
        let rows = rows_for(&s.mesh, &s.x0, &pairs).expect("admissible start");
        let dofs = DofMap::new(&s.mesh);
        let (qp, _) = build_qp(
            &s.mesh,
            &s.energy,
            &dofs,
            &rows,
            &s.x0,
            eps_qp,
            None,
            &settings,
            &mut ModelShift::default(),
        )
        .expect("QP assembly");
        g.bench_with_input(BenchmarkId::new("ldlt_of_p", n), &qp, |b, qp| {
            b.iter(|| black_box(SparseLdl::factor(&qp.p).expect("P is definite")))
        });
        let k = p_plus_ata(&qp.p, &qp.a, &qp.u);
        g.bench_with_input(BenchmarkId::new("ldlt_of_p_plus_rows", n), &k, |b, k| {
            b.iter(|| black_box(SparseLdl::factor(k).expect("P + AᵀA is definite")))
        });
    }
    g.finish();
}

/// The upper triangle of `P + AᵀA` over the contact rows of `A` (its inequality rows, `u =
/// +∞`; the gas' auxiliary equality rows, which couple a whole membrane, left out): the
/// pattern of the Hessian with the contact rows'.
fn p_plus_ata(p: &CscMatrix, a: &CscMatrix, u: &[f64]) -> CscMatrix {
    let mut t: Vec<(usize, usize, f64)> = Vec::new();
    for j in 0..p.ncols {
        for k in p.colptr[j]..p.colptr[j + 1] {
            t.push((p.rowval[k], j, p.nzval[k]));
        }
    }
    // rows of A: (column, value) lists
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); a.nrows];
    for j in 0..a.ncols {
        for k in a.colptr[j]..a.colptr[j + 1] {
            rows[a.rowval[k]].push((j, a.nzval[k]));
        }
    }
    for (r, _) in rows.iter().zip(u).filter(|(_, ub)| ub.is_infinite()) {
        for &(i, x) in r {
            for &(j, y) in r {
                if i <= j {
                    t.push((i, j, x * y));
                }
            }
        }
    }
    CscMatrix::from_triplets(p.nrows, p.ncols, &t).expect("P + AᵀA")
}

criterion_group!(benches, bench);
criterion_main!(benches);
