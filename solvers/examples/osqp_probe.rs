//! Probe: solve exported QPS files with OSQP under varied settings, and with Clarabel, to tell
//! a hard QP from a bad setting. `cargo run --release -p contactlab-solvers --example osqp_probe -- FILE.qps...`
use contactlab_solvers::qps::read_qps_file;
use contactlab_solvers::{backend_from_name, QpSettings};
use osqp::{CscMatrix as OsCsc, Problem, Settings, Status};
use std::borrow::Cow;
use std::path::Path;

fn to_osqp(m: &contactlab_solvers::qp::CscMatrix) -> OsCsc<'_> {
    OsCsc {
        nrows: m.nrows,
        ncols: m.ncols,
        indptr: Cow::Borrowed(&m.colptr),
        indices: Cow::Borrowed(&m.rowval),
        data: Cow::Borrowed(&m.nzval),
    }
}

fn main() {
    for file in std::env::args().skip(1) {
        let (_, qp) = read_qps_file(Path::new(&file)).expect("read");
        let l: Vec<f64> = qp.l.iter().map(|&v| v.max(-1e30)).collect();
        let u: Vec<f64> = qp.u.iter().map(|&v| v.min(1e30)).collect();
        let mut clar = backend_from_name(
            "clarabel",
            &QpSettings {
                eps_abs: 1e-10,
                eps_rel: 1e-10,
                ..Default::default()
            },
        )
        .unwrap();
        let cs = clar.solve(&qp, None).unwrap();
        let obj = |x: &[f64]| qp.objective(x);
        println!(
            "{file}: n={} m={} clarabel {:?} obj {:.12e} it {}",
            qp.n(),
            qp.m(),
            cs.status,
            obj(&cs.x),
            cs.iterations
        );
        let variants: Vec<(&str, Settings)> = vec![
            (
                "as-is (rho .1, interval 25, 1e-6)",
                base(1e-6, 0.1, Some(25), 10, 100_000),
            ),
            ("max_iter 1e6", base(1e-6, 0.1, Some(25), 10, 1_000_000)),
            (
                "max_iter 1e6 + interval auto",
                base(1e-6, 0.1, None, 10, 1_000_000),
            ),
            ("interval auto", base(1e-6, 0.1, None, 10, 100_000)),
            ("scaling 50", base(1e-6, 0.1, Some(25), 50, 100_000)),
            ("rho 1e-3", base(1e-6, 1e-3, Some(25), 10, 100_000)),
            ("rho 10", base(1e-6, 10.0, Some(25), 10, 100_000)),
            ("eps 1e-5", base(1e-5, 0.1, Some(25), 10, 100_000)),
            ("eps 1e-4", base(1e-4, 0.1, Some(25), 10, 100_000)),
        ];
        for (name, s) in variants {
            let mut p = Problem::new(to_osqp(&qp.p), &qp.q, to_osqp(&qp.a), &l, &u, &s).unwrap();
            let r = p.solve();
            let it = r.iter();
            let (st, o) = match &r {
                Status::Solved(s) => ("solved", obj(s.x())),
                Status::SolvedInaccurate(s) => ("inaccurate", obj(s.x())),
                Status::MaxIterationsReached(s) => ("max_iter", obj(s.x())),
                _ => ("other", f64::NAN),
            };
            println!("   {name:36} {st:10} it {it:7} obj {o:.12e}");
        }
    }
}

fn base(eps: f64, rho: f64, interval: Option<u32>, scaling: u32, max_iter: u32) -> Settings {
    Settings::default()
        .rho(rho)
        .eps_abs(eps)
        .eps_rel(eps)
        .max_iter(max_iter)
        .polish(true)
        .verbose(false)
        .adaptive_rho(true)
        .adaptive_rho_interval(interval)
        .scaling(Some(scaling))
}
