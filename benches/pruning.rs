//! Criterion benches of the broad phase and of the pruned QP assembly on the balloons scene.
//!
//! Three sizes, `n ∈ {1 000, 10 000, 100 000}` elements per membrane (about `4n` vertices, so
//! ~4·10³, 4·10⁴ and 4·10⁵ vertices), all at the scene's initial configuration `x0`:
//!
//! - `broad_phase/point_edge_near`: the pair search of a lazy outer step, radius
//!   `ε_qp + h̄` on every edge (`ε_qp = ε(1 + 10⁻⁶) + 10⁻¹¹`, `h̄` the median contact edge length),
//!   pairs with both ends fixed skipped;
//! - `broad_phase/min_distance`: the exact admissibility check of every iterate,
//!   `contact::min_distance(mesh, x0, 2ε, true)`;
//! - `broad_phase/structure`: the uniform grid (`grid`, [`AabbGrid`]) against the bounding volume
//!   hierarchy (`bvh`, [`Bvh`]) on the query pattern of the first bench: the contact edge boxes
//!   inflated by the same radius, the structure built over them, then one query per contact
//!   vertex with its point box (in parallel, as `point_edge_near`); the candidates are only
//!   counted (no narrow phase), so the grid's superset and the BVH's exact answer cost their
//!   own query time only. The contact vertex list is computed once, outside the timed loop;
//! - `assembly/pruned_qp`: the rows of the pairs found by the first bench
//!   (`contact::rows_for`) then `build_qp` (gradient, projected Hessian, QP matrices); the pairs
//!   are found once, outside the timed loop.
//!
//! Throughput is reported in vertices. Run with
//!
//! ```text
//! source scripts/ensure-cmake.sh && cargo bench --bench pruning
//! ```
//!
//! (append `-- <filter>` to run a subset, e.g. `-- broad_phase`). Criterion's output stays in
//! `target/criterion/`; no HTML report is produced.

use std::time::Duration;

use contactlab::contact::broad_phase::{point_edge_near, Aabb, AabbGrid};
use contactlab::contact::bvh::Bvh;
use contactlab::contact::PointEdgePair;
use contactlab::contact::{min_distance, rows_for, ContactPair};
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::mesh::Mesh;
use contactlab::scene::Scene;
use contactlab::solve::outer::median_edge_length;
use contactlab::solve::subproblem::{build_qp, DofMap, InnerSettings, ModelShift};
use criterion::{
    black_box, criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, Throughput,
};
use rayon::prelude::*;

/// Elements per membrane.
const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

/// One size: the scene, the QP level and the broad-phase radius per edge.
struct Fixture {
    n: usize,
    scene: Scene,
    eps_qp: f64,
    r_edge: Vec<f64>,
}

impl Fixture {
    fn new(n: usize) -> Fixture {
        let scene = build(&BalloonsParams {
            n,
            ..Default::default()
        })
        .expect("balloons scene");
        let settings = InnerSettings::default();
        let eps_qp = scene.eps * (1.0 + settings.margin_rel) + settings.margin_abs;
        let r = eps_qp + median_edge_length(&scene.mesh, &scene.x0);
        let r_edge = vec![r; scene.mesh.edges.len()];
        Fixture {
            n,
            scene,
            eps_qp,
            r_edge,
        }
    }

    /// The pairs of a lazy outer step at `x0`.
    fn pairs(&self) -> Vec<PointEdgePair> {
        point_edge_near(&self.scene.mesh, &self.scene.x0, &[], &self.r_edge, true)
            .into_iter()
            .map(|p| p.pair)
            .collect()
    }
}

/// The box of each contact edge inflated by `r_edge` (as `broad_phase::edge_index` builds them).
fn edge_boxes(mesh: &Mesh, x: &[f64], r_edge: &[f64]) -> Vec<Aabb<2>> {
    mesh.edges
        .par_iter()
        .zip(r_edge)
        .map(|(&[i, j], &r)| {
            let (a, b) = (Mesh::p2(x, i), Mesh::p2(x, j));
            (
                [a.x.min(b.x) - r, a.y.min(b.y) - r],
                [a.x.max(b.x) + r, a.y.max(b.y) + r],
            )
        })
        .collect()
}

/// Total number of candidates over one point-box query per vertex of `verts` (in parallel,
/// one buffer per rayon task, as `point_edge_near_in`).
fn count_candidates(
    verts: &[usize],
    x: &[f64],
    query: impl Fn(&[f64; 2], &[f64; 2], &mut Vec<u32>) + Sync,
) -> usize {
    verts
        .par_iter()
        .map_init(Vec::new, |buf: &mut Vec<u32>, &v| {
            let p = [x[2 * v], x[2 * v + 1]];
            buf.clear();
            query(&p, &p, buf);
            buf.len()
        })
        .sum()
}

fn configure(group: &mut BenchmarkGroup<'_, criterion::measurement::WallTime>) {
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
}

fn benches(c: &mut Criterion) {
    let fixtures: Vec<Fixture> = SIZES.iter().map(|&n| Fixture::new(n)).collect();

    let mut group = c.benchmark_group("broad_phase/point_edge_near");
    configure(&mut group);
    for f in &fixtures {
        let (mesh, x) = (&f.scene.mesh, &f.scene.x0);
        group.throughput(Throughput::Elements(mesh.nv() as u64));
        group.bench_function(BenchmarkId::from_parameter(f.n), |b| {
            b.iter(|| point_edge_near(mesh, black_box(x), &[], &f.r_edge, true))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("broad_phase/min_distance");
    configure(&mut group);
    for f in &fixtures {
        let (mesh, x) = (&f.scene.mesh, &f.scene.x0);
        group.throughput(Throughput::Elements(mesh.nv() as u64));
        group.bench_function(BenchmarkId::from_parameter(f.n), |b| {
            b.iter(|| min_distance(mesh, black_box(x), 2.0 * f.scene.eps, true))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("broad_phase/structure");
    configure(&mut group);
    for f in &fixtures {
        let (mesh, x) = (&f.scene.mesh, &f.scene.x0);
        let verts = mesh.contact_vertices();
        group.throughput(Throughput::Elements(mesh.nv() as u64));
        group.bench_function(BenchmarkId::new("grid", f.n), |b| {
            b.iter(|| {
                let x = black_box(x);
                let grid = AabbGrid::build(&edge_boxes(mesh, x, &f.r_edge), None);
                black_box(count_candidates(&verts, x, |lo, hi, out| {
                    grid.query(lo, hi, out)
                }))
            })
        });
        group.bench_function(BenchmarkId::new("bvh", f.n), |b| {
            b.iter(|| {
                let x = black_box(x);
                let bvh = Bvh::build(&edge_boxes(mesh, x, &f.r_edge));
                black_box(count_candidates(&verts, x, |lo, hi, out| {
                    bvh.query(lo, hi, out)
                }))
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("assembly/pruned_qp");
    configure(&mut group);
    let settings = InnerSettings::default();
    for f in &fixtures {
        let (mesh, x) = (&f.scene.mesh, &f.scene.x0);
        let dofs = DofMap::new(mesh);
        let pairs: Vec<ContactPair> = f.pairs().into_iter().map(Into::into).collect();
        group.throughput(Throughput::Elements(mesh.nv() as u64));
        group.bench_function(BenchmarkId::from_parameter(f.n), |b| {
            b.iter(|| {
                let rows = rows_for(mesh, black_box(x), &pairs).expect("x0 admissible");
                build_qp(
                    mesh,
                    &f.scene.energy,
                    &dofs,
                    &rows,
                    x,
                    f.eps_qp,
                    None,
                    &settings,
                    &mut ModelShift::default(),
                )
                .expect("QP assembly")
            })
        });
    }
    group.finish();
}

criterion_group!(pruning, benches);
criterion_main!(pruning);
