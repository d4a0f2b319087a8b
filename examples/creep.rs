//! The 3D creep (docs/measurements.md, 3D runs), two measurements:
//! 1. against the QP margin: rod n = 8 and solids n = 2, 300 outer steps, J and ΔJ at the end;
//! 2. the stationarity of a "converged" state (rod, solids and sheets at their defaults) with
//!    the diagnostics' activity tolerance ×1 … ×10⁴: does a looser set of active pairs
//!    balance J'?
//!
//! Both with Pantz's map (the creep is its own).
//!
//! `cargo run --release --example creep`
use contactlab::harness::diagnostics::{converged_diagnostics, DiagnosticSettings};
use contactlab::scene::rod::{self, RodParams};
use contactlab::scene::sheets::{self, SheetsParams};
use contactlab::scene::solids::{self, SolidsParams};
use contactlab::solve::outer::{run, OuterSettings};
use contactlab::solve::sqp::OuterMethod;
use contactlab_solvers::QpSettings;
use contactlab_solvers::{backend_from_name, default_settings};

fn main() {
    let scenes = [
        (
            "rod n=8",
            rod::build(&RodParams {
                n: 8,
                ..Default::default()
            })
            .unwrap(),
        ),
        (
            "solids n=2",
            solids::build(&SolidsParams {
                n: 2,
                ..Default::default()
            })
            .unwrap(),
        ),
    ];
    for (name, scene) in &scenes {
        for margin_rel in [1e-6, 1e-5, 1e-4, 1e-3] {
            let mut b = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
            let mut s = OuterSettings {
                max_outer: 300,
                method: OuterMethod::Pantz,
                ..Default::default()
            };
            s.inner.margin_rel = margin_rel;
            let mut j = Vec::new();
            let res = run(
                &scene.mesh,
                &scene.energy,
                scene.eps,
                &scene.x0,
                b.as_mut(),
                &s,
                &mut |r, _| j.push(r.energy),
            )
            .unwrap();
            let k = j.len() - 1;
            println!(
                "{name} margin_rel={margin_rel:e}: {} after {} steps, J = {:.12e}, last dJ = {:.3e}, dJ at 100 = {:.3e}",
                res.status.as_str(),
                res.outer_iterations,
                res.energy,
                j[k - 1] - j[k],
                if k > 100 { j[99] - j[100] } else { f64::NAN }
            );
        }
    }

    let defaults = [
        rod::build(&RodParams::default()).unwrap(),
        solids::build(&SolidsParams::default()).unwrap(),
        sheets::build(&SheetsParams::default()).unwrap(),
    ];
    for scene in &defaults {
        let mut b = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
        let res = run(
            &scene.mesh,
            &scene.energy,
            scene.eps,
            &scene.x0,
            b.as_mut(),
            &OuterSettings {
                method: OuterMethod::Pantz,
                ..Default::default()
            },
            &mut |_, _| {},
        )
        .unwrap();
        for factor in [1.0, 10.0, 100.0, 1e3, 1e4] {
            let st = QpSettings {
                eps_abs: 1e-10,
                eps_rel: 1e-10,
                ..Default::default()
            };
            let mut qb = backend_from_name("clarabel", &st).unwrap();
            let mut ds = DiagnosticSettings::for_eps(scene.eps);
            ds.active_tol *= factor;
            let d = converged_diagnostics(
                &scene.mesh,
                &scene.energy,
                &res.x,
                &res.psi,
                scene.eps,
                scene.h,
                &res.last_rows,
                &res.multipliers,
                qb.as_mut(),
                &ds,
            )
            .unwrap();
            println!(
                "{} ({} after {} steps) active_tol x{factor:e}: active pairs {}, stationarity_rel {:.3e}, ratio {:.3e}, dual QP {}",
                scene.name,
                res.status.as_str(),
                res.outer_iterations,
                d.active_pairs,
                d.stationarity_canonical / d.gradient_norm,
                d.ratio,
                d.dual_qp_status
            );
        }
    }
}
