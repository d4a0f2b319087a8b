//! Criterion benches of the backends on QPs captured from the balloons scene, and of the
//! point–edge distance kernel.
//!
//! - `backends/captured/{backend}/{n}`: the balloons at `n ∈ {20, 40, 80}` elements per
//!   membrane are solved once with Clarabel (default preset, lazy rows) while
//!   [`contactlab::harness::capture::Capture`] records every sub-problem QP; four of them, evenly spaced
//!   over the run (first to last), form the fixture. One iteration solves those four QPs in
//!   order with a fresh backend (its default settings, no warm start), so no reuse state
//!   carries over between iterations. A QP a backend does not solve still counts its time;
//!   the statuses are printed once before the group runs.
//! - `kernel/point_edge_distance`: 4096 random point–segment distances.
//!
//! ```text
//! source scripts/ensure-cmake.sh && cargo bench --bench backends
//! cargo bench --bench backends -- 'captured/(clarabel|ip)/'   # two of them
//! ```

use std::time::Duration;

use contactlab::contact::distance::point_edge_distance;
use contactlab::harness::capture::Capture;
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::solve::outer::{run, OuterSettings};
use contactlab_solvers::{backend_from_name, default_settings, Qp, QpError, QpSolution};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::Vector2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SIZES: [usize; 3] = [20, 40, 80];
const BACKENDS: [&str; 4] = ["clarabel", "ip", "osqp", "uzawa"];

/// Four QPs evenly spaced over a Clarabel run of the balloons at `n`.
fn captured(n: usize) -> Vec<Qp> {
    let scene = build(&BalloonsParams {
        n,
        ..Default::default()
    })
    .expect("balloons scene");
    let mut all: Vec<Qp> = Vec::new();
    let mut sink = |_: usize, qp: &Qp, _: &Result<QpSolution, QpError>| all.push(qp.clone());
    let mut inner = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
    {
        let mut cap = Capture::new(inner.as_mut(), &mut sink);
        run(
            &scene.mesh,
            &scene.energy,
            scene.eps,
            &scene.x0,
            &mut cap,
            &OuterSettings::default(),
            &mut |_, _| {},
        )
        .expect("balloons run");
    }
    let k = all.len();
    let picks = [0, k / 3, (2 * k) / 3, k - 1];
    picks.iter().map(|&i| all[i].clone()).collect()
}

fn benches(c: &mut Criterion) {
    let fixtures: Vec<(usize, Vec<Qp>)> = SIZES.iter().map(|&n| (n, captured(n))).collect();
    let mut group = c.benchmark_group("backends/captured");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for (n, qps) in &fixtures {
        for name in BACKENDS {
            let st = default_settings(name);
            let statuses: Vec<String> = qps
                .iter()
                .map(|qp| {
                    let mut b = backend_from_name(name, &st).unwrap();
                    match b.solve(qp, None) {
                        Ok(s) => format!("{}({} it)", s.status.as_str(), s.iterations),
                        Err(e) => format!("error: {e}"),
                    }
                })
                .collect();
            let sizes: Vec<String> = qps.iter().map(|q| format!("{}x{}", q.n(), q.m())).collect();
            eprintln!("n={n} {name}: QPs {sizes:?} -> {statuses:?}");
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| {
                    let mut be = backend_from_name(name, &st).unwrap();
                    for qp in qps {
                        black_box(be.solve(qp, None).ok());
                    }
                })
            });
        }
    }
    group.finish();

    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pts: Vec<[Vector2<f64>; 3]> = (0..4096)
        .map(|_| {
            let mut v = || Vector2::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
            [v(), v(), v()]
        })
        .collect();
    let mut group = c.benchmark_group("kernel");
    group.bench_function("point_edge_distance/4096", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for p in &pts {
                s += point_edge_distance(&p[0], &p[1], &p[2]).distance;
            }
            black_box(s)
        })
    });
    group.finish();
}

criterion_group!(backend_benches, benches);
criterion_main!(backend_benches);
