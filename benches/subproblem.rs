//! The sub-problem solver at two sizes (balloons n = 160 and 640, lazy rows, the default Newton
//! model), with Clarabel and with `ip`, each at its default tolerance, against the sparse
//! LDLᵀ an inner step is measured in:
//!
//! - `one_inner_step/{backend}`: the first outer step with `max_inner = 1` (the pair search, the
//!   QP build, the model shift, the backend and the lazy re-solves, the admissibility check),
//!   from the start, where the balloons are apart;
//! - `one_subproblem/{backend}`: the first outer step, inner steps uncapped;
//! - `one_inner_step_in_contact/{backend}`: one outer step with `max_inner = 1` from the state
//!   the first outer step ends at (the balloons in contact, most rows binding): an inner step of
//!   the later outer steps;
//! - `ldlt_of_p`: one LDLᵀ of the first QP's `P` (the Hessian with the proximal term, the
//!   shift and the gas' auxiliary variables; QDLDL, natural ordering). At the start no pair is
//!   within the rows' radius, so `P` is also the Hessian with the start's contact rows;
//! - `ldlt_in_contact`: the numeric phase of `faer`'s LDLᵀ (AMD ordering, the factorization the
//!   `ip` backend uses) of `P + AᵀA` over the contact rows of the QP at the in-contact state:
//!   the Hessian with the contact rows' pattern, what an interior point on the condensed
//!   system factorizes at each iteration. Its symbolic phase (once per pattern) is not in it.
//!
//! The steps are timed by the run's own records: from its record of the start to its record
//! of the step, so the certificate and the polish a run computes after its last step (which
//! the outer loop pays once per run, not per step) are not counted.
//!
//! Run: `cargo bench --bench subproblem` (criterion; results in `target/criterion/`). Other
//! sizes: `SUBPROBLEM_SIZES="1600" cargo bench --bench subproblem` (n = 1600 takes about twelve
//! minutes, most of it ten samples of each whole first step). The sizes of the in-contact QP (rows,
//! entries of `K` and of its factor) are printed to standard error.

use std::time::{Duration, Instant};

use contactlab::contact::{near_pairs, rows_for};
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::Scene;
use contactlab::solve::outer::{median_edge_length, run, OuterSettings};
use contactlab::solve::subproblem::{build_qp, DofMap, InnerSettings, ModelShift};
use contactlab_solvers::linalg::SparseLdl;
use contactlab_solvers::{backend_from_name, default_settings, CscMatrix};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Par, Side, Spec};

fn scene(n: usize) -> Scene {
    build(&BalloonsParams {
        n,
        ..Default::default()
    })
    .expect("balloons scene")
}

/// One outer step from `x` with at most `max_inner` inner steps: the state after it, and the
/// time from the run's record of the start to its record of the step (the step itself; the
/// certificate and the polish the run computes after its last step are not in it).
fn one_step(s: &Scene, x: &[f64], backend: &str, max_inner: usize) -> (Vec<f64>, Duration) {
    let mut settings = OuterSettings {
        max_outer: 1,
        ..Default::default()
    };
    settings.inner.max_inner = max_inner;
    let mut b = backend_from_name(backend, &default_settings(backend)).unwrap();
    let mut start: Option<Instant> = None;
    let mut took: Option<Duration> = None;
    let r = run(
        &s.mesh,
        &s.energy,
        s.eps,
        x,
        b.as_mut(),
        &settings,
        &mut |rec, _| match rec.iteration {
            0 => start = Some(Instant::now()),
            1 => took = start.map(|t| t.elapsed()),
            _ => {}
        },
    )
    .expect("one outer step");
    (r.x, took.expect("the run recorded its start and its step"))
}

/// Criterion's timing of `iters` outer steps: the sum of [`one_step`]'s step times.
fn steps(s: &Scene, x: &[f64], backend: &str, max_inner: usize, iters: u64) -> Duration {
    (0..iters)
        .map(|_| black_box(one_step(s, x, backend, max_inner)).1)
        .sum()
}

/// The first QP of an outer step from `x`: the rows of the pairs within `ε_QP + h̄/4` (the
/// radius a lazy step starts with).
fn first_qp(s: &Scene, x: &[f64]) -> contactlab_solvers::Qp {
    let settings = InnerSettings::default();
    let eps_qp = s.eps * (1.0 + settings.margin_rel) + settings.margin_abs;
    let r = eps_qp + 0.25 * median_edge_length(&s.mesh, x);
    let pairs = near_pairs(&s.mesh, x, r, true);
    let rows = rows_for(&s.mesh, x, &pairs).expect("admissible state");
    let dofs = DofMap::new(&s.mesh);
    build_qp(
        &s.mesh,
        &s.energy,
        &dofs,
        &rows,
        x,
        eps_qp,
        None,
        &settings,
        &mut ModelShift::default(),
    )
    .expect("QP assembly")
    .0
}

/// The number of contact (inequality) rows of `qp`.
fn contact_rows(qp: &contactlab_solvers::Qp) -> usize {
    qp.u.iter().filter(|u| u.is_infinite()).count()
}

/// `faer`'s LDLᵀ of the upper triangle `k`, as the `ip` backend runs it: the symbolic phase
/// (AMD ordering) once, the numeric phase on each call of [`FaerLdl::numeric`].
struct FaerLdl {
    k: CscMatrix,
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    lvals: Vec<f64>,
    buf: MemBuffer,
}

impl FaerLdl {
    fn new(k: CscMatrix) -> FaerLdl {
        let n = k.ncols;
        let pattern =
            SymbolicSparseColMat::new_checked(n, n, k.colptr.clone(), None, k.rowval.clone());
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .expect("symbolic LDLᵀ");
        let req = symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Spec::default());
        let lvals = vec![0.0; symbolic.len_val()];
        FaerLdl {
            k,
            pattern,
            symbolic,
            lvals,
            buf: MemBuffer::try_new(req).expect("LDLᵀ workspace"),
        }
    }

    fn numeric(&mut self) {
        let mat = SparseColMatRef::new(self.pattern.as_ref(), &self.k.nzval);
        self.symbolic
            .factorize_numeric_ldlt(
                &mut self.lvals,
                mat,
                Side::Upper,
                LdltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.buf),
                Spec::default(),
            )
            .expect("P + AᵀA is definite");
    }
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
        // the in-contact state: where the first outer step ends (the default backend's run)
        let x1 = one_step(&s, &s.x0, "ip", 50).0;
        for backend in ["clarabel", "ip"] {
            g.bench_with_input(
                BenchmarkId::new(format!("one_inner_step/{backend}"), n),
                &s,
                |b, s| b.iter_custom(|iters| steps(s, &s.x0, backend, 1, iters)),
            );
            g.bench_with_input(
                BenchmarkId::new(format!("one_subproblem/{backend}"), n),
                &s,
                |b, s| b.iter_custom(|iters| steps(s, &s.x0, backend, 50, iters)),
            );
            g.bench_with_input(
                BenchmarkId::new(format!("one_inner_step_in_contact/{backend}"), n),
                &s,
                |b, s| b.iter_custom(|iters| steps(s, &x1, backend, 1, iters)),
            );
        }
        let qp0 = first_qp(&s, &s.x0);
        assert_eq!(
            contact_rows(&qp0),
            0,
            "the start has contact rows: ldlt_of_p would no longer be the Hessian with them"
        );
        g.bench_with_input(BenchmarkId::new("ldlt_of_p", n), &qp0, |b, qp| {
            b.iter(|| black_box(SparseLdl::factor(&qp.p).expect("P is definite")))
        });
        let qp1 = first_qp(&s, &x1);
        let mut ldl = FaerLdl::new(p_plus_ata(&qp1.p, &qp1.a, &qp1.u));
        eprintln!(
            "subproblem n = {n}: in contact, {} contact rows, K = P + AᵀA of order {} with {} \
             entries (upper), its factor {} (P's: {})",
            contact_rows(&qp1),
            ldl.k.ncols,
            ldl.k.nnz(),
            ldl.symbolic.len_val(),
            FaerLdl::new(qp1.p.clone()).symbolic.len_val()
        );
        g.bench_function(BenchmarkId::new("ldlt_in_contact", n), |b| {
            b.iter(|| ldl.numeric())
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
