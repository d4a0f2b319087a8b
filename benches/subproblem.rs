//! The sub-problem solver at two sizes (balloons n = 160 and 640, Clarabel at its default
//! tolerance, lazy rows, the default Newton model): one inner step (the first outer step with
//! `max_inner = 1`: the QP build, the model shift, the backend and the lazy re-solves) and one
//! full sub-problem (the first outer step, inner steps uncapped), beside one sparse LDLᵀ of the
//! first QP's `P` (the Hessian with the proximal term, the shift and the gas' auxiliary
//! variables), the unit the issue of the sub-problem solver measures an inner step against.
//!
//! Run: `cargo bench --bench subproblem` (criterion; results in `target/criterion/`).

use std::time::Duration;

use contactlab::contact::{near_pairs, rows_for};
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::Scene;
use contactlab::solve::outer::{median_edge_length, run, OuterSettings};
use contactlab::solve::subproblem::{build_qp, DofMap, InnerSettings, ModelShift};
use contactlab_solvers::linalg::SparseLdl;
use contactlab_solvers::{backend_from_name, default_settings};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};

fn scene(n: usize) -> Scene {
    build(&BalloonsParams {
        n,
        ..Default::default()
    })
    .expect("balloons scene")
}

/// The first outer step with at most `max_inner` inner steps; returns J after it.
fn first_step(s: &Scene, max_inner: usize) -> f64 {
    let mut settings = OuterSettings {
        max_outer: 1,
        ..Default::default()
    };
    settings.inner.max_inner = max_inner;
    let mut b = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
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
    for n in [160usize, 640] {
        let s = scene(n);
        g.bench_with_input(BenchmarkId::new("one_inner_step", n), &s, |b, s| {
            b.iter(|| black_box(first_step(s, 1)))
        });
        g.bench_with_input(BenchmarkId::new("one_subproblem", n), &s, |b, s| {
            b.iter(|| black_box(first_step(s, 50)))
        });
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
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
