//! The minimality certificate's two solvers on the balloons' final states (docs/method.md,
//! "The minimality certificate"): the exact active set (Lawson–Hanson on the dense normal
//! equations) against the sparse dual QP with each backend and tolerance given, time and
//! residual, to choose the sparse path's backend and the threshold between the paths.
//!
//! `cargo run --release --example cert_paths -- CASE [CASE …] [--skip-exact-above K]
//!  [--qp backend:tol,…]`, a CASE `N` (balloons at level N), `asym:N` (the balloons from
//! heights 0.9, 0.2, 0.9, 0.2) or `SCENE:N` (a built-in static scene); each run with `ip` at
//! its default tolerance and Pantz's map, the settings of `contactlab run balloons --n N
//! --backend ip --outer-method pantz`.
use contactlab::contact::ContactPair;
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::registry::build_scene;
use contactlab::solve::certificate::{certificate_with, CertificatePath};
use contactlab::solve::h1::H1Norms;
use contactlab::solve::outer::{certificate_active_tol, run, OuterSettings};
use contactlab::solve::sqp::OuterMethod;
use contactlab_solvers::{backend_from_name, default_settings};
use std::collections::HashMap;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut ns = Vec::new();
    let mut skip_exact_above = usize::MAX;
    let mut qps: Vec<(String, f64)> = vec![
        ("ip".into(), 1e-9),
        ("ip".into(), 1e-10),
        ("ip".into(), 1e-11),
        ("clarabel".into(), 1e-9),
        ("clarabel".into(), 1e-10),
    ];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--skip-exact-above" => skip_exact_above = it.next().unwrap().parse().unwrap(),
            "--qp" => {
                qps = it
                    .next()
                    .unwrap()
                    .split(',')
                    .map(|s| {
                        let (b, t) = s.split_once(':').unwrap();
                        (b.to_string(), t.parse().unwrap())
                    })
                    .collect()
            }
            spec => ns.push(spec.to_string()),
        }
    }
    for spec in ns {
        // `N` (balloons), `asym:N` (balloons from heights 0.9, 0.2, 0.9, 0.2) or `SCENE:N`.
        let (name, n) = spec.split_once(':').unwrap_or(("balloons", &spec));
        let n: usize = match n {
            "default" => contactlab::scene::registry::default_n(name),
            n => n.parse().unwrap(),
        };
        let scene = match name {
            "balloons" | "asym" => build(&BalloonsParams {
                n,
                heights: if name == "asym" {
                    [0.9, 0.2, 0.9, 0.2]
                } else {
                    BalloonsParams::default().heights
                },
                ..Default::default()
            })
            .unwrap(),
            _ => build_scene(name, n, None, &Default::default()).unwrap(),
        };
        let mut b = backend_from_name("ip", &default_settings("ip")).unwrap();
        let s = OuterSettings {
            qp_tol: default_settings("ip").eps_abs,
            method: OuterMethod::Pantz,
            ..Default::default()
        };
        let t = Instant::now();
        let res = run(
            &scene.mesh,
            &scene.energy,
            scene.eps,
            &scene.x0,
            b.as_mut(),
            &s,
            &mut |_, _| {},
        )
        .unwrap();
        let run_s = t.elapsed().as_secs_f64();
        let norms = H1Norms::scaled(&scene.mesh).unwrap();
        let tol = certificate_active_tol(&s, scene.eps, norms.free.ell);
        let warm: HashMap<ContactPair, f64> = res
            .last_rows
            .iter()
            .zip(&res.multipliers)
            .map(|(r, m)| (r.pair, m.iter().take(r.len).sum()))
            .collect();
        println!(
            "{name} n={n} run {run_s:.1}s status {} outer {} free dofs {}; in-run certificate: {} kappa {:.6e} {:.3}s",
            res.status.as_str(),
            res.outer_iterations,
            norms.free.n,
            res.certificate.method,
            res.certificate.kappa,
            res.certificate.seconds
        );
        let cert = |path| {
            certificate_with(
                &scene.mesh,
                &scene.energy,
                &res.x,
                scene.eps,
                tol,
                &norms,
                &warm,
                path,
            )
            .unwrap()
        };
        let exact = (res.certificate.generators <= skip_exact_above)
            .then(|| cert(CertificatePath::ActiveSet));
        if let Some(e) = &exact {
            println!(
                "  active_set: generators {} positive {} kappa {:.6e} residual {:.6e} dual_gap {:.3e} iterations {} unresolved {} seconds {:.3}",
                e.generators, e.positive, e.kappa, e.residual, e.dual_gap, e.iterations, e.unresolved, e.seconds
            );
        }
        for (backend, qtol) in &qps {
            let c = cert(CertificatePath::Qp {
                backend,
                tol: *qtol,
            });
            let diff = exact
                .as_ref()
                .map_or(f64::NAN, |e| (c.residual - e.residual) / c.scale);
            println!(
                "  qp {backend}@{qtol:e}: generators {} positive {} kappa {:.6e} residual {:.6e} (residual - exact)/S {:.3e} dual_gap {:.3e} iterations {} unresolved {} seconds {:.3}",
                c.generators, c.positive, c.kappa, c.residual, diff, c.dual_gap, c.iterations, c.unresolved, c.seconds
            );
        }
    }
}
