//! Lemma 5.4 / 5.6 diagnostics on converged balloons runs (docs/method.md): the duals satisfy
//! stationarity (the sign convention of docs/method.md, not the paper's printed one), are
//! non-negative and complementary, and the Lemma 5.6 bound holds at the fixed point.

use contactlab::harness::diagnostics::{
    converged_diagnostics, stationarity_residual, DiagnosticSettings,
};
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::solve::h1::h1_gram;
use contactlab::solve::outer::{run, OuterSettings, RunStatus};
use contactlab_solvers::{backend_from_name, default_settings, QpSettings};

fn diagnose(n: usize, backend: &str) -> contactlab::harness::diagnostics::ConvergedDiagnostics {
    let scene = build(&BalloonsParams {
        n,
        ..Default::default()
    })
    .unwrap();
    let mut b = backend_from_name(backend, &default_settings(backend)).unwrap();
    let res = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        b.as_mut(),
        &OuterSettings::default(),
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(res.status, RunStatus::Converged, "{backend} n={n}");
    let st = QpSettings {
        eps_abs: 1e-10,
        eps_rel: 1e-10,
        ..Default::default()
    };
    let mut dual = backend_from_name("clarabel", &st).unwrap();
    converged_diagnostics(
        &scene.mesh,
        &scene.energy,
        &res.x,
        &res.psi,
        scene.eps,
        scene.h,
        &res.last_rows,
        &res.multipliers,
        dual.as_mut(),
        &DiagnosticSettings::for_eps(scene.eps),
    )
    .unwrap()
}

#[test]
fn lemma54_stationarity_sign_and_lemma56_bound() {
    for n in [20, 40] {
        let d = diagnose(n, "clarabel");
        assert_eq!(d.dual_qp_status, "solved", "n={n}");
        assert!(d.active_pairs > 0, "n={n}: no contact at the fixed point");
        // Stationarity J'(φ) = Σ μ ∇row with μ ≥ 0 (docs/method.md sign): relative to |J'|, at the
        // level of the QP tolerance (1e-9) and of the outer stopping rule.
        let rel_raw = d.stationarity_raw / d.gradient_norm;
        let rel_can = d.stationarity_canonical / d.gradient_norm;
        assert!(rel_raw < 1e-6, "n={n}: raw stationarity {rel_raw:.3e}");
        assert!(
            rel_can < 1e-6,
            "n={n}: canonical stationarity {rel_can:.3e}"
        );
        assert!(
            d.min_raw_dual >= 0.0,
            "n={n}: negative dual {}",
            d.min_raw_dual
        );
        assert!(d.pairs.iter().all(|p| p.mu[0] >= 0.0 && p.mu[1] >= 0.0));
        // Complementarity: a dual times its row's slack, at the scale of ε·|μ|.
        let mu_max = d
            .pairs
            .iter()
            .fold(0.0f64, |m, p| m.max(p.mu[0]).max(p.mu[1]));
        assert!(
            d.complementarity_raw <= 1e-4 * d.h * mu_max,
            "n={n}: complementarity {:.3e}",
            d.complementarity_raw
        );
        assert!(d.c_phi >= 1 && d.max_edges_per_vertex <= 6, "n={n}");
        // Lemma 5.6 at a fixed point.
        assert!(d.ratio <= 1.0 + 1e-6, "n={n}: ‖R‖/B = {}", d.ratio);
    }
}

/// With the sign printed in the paper's (9) and (15) (μ ↦ −μ), the same duals are far from
/// stationary: the sign convention is tested, not assumed.
#[test]
fn the_papers_printed_sign_is_not_stationary() {
    let scene = build(&BalloonsParams {
        n: 20,
        ..Default::default()
    })
    .unwrap();
    let mut b = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
    let res = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        b.as_mut(),
        &OuterSettings::default(),
        &mut |_, _| {},
    )
    .unwrap();
    let (m, e, x) = (&scene.mesh, &scene.energy, &res.x);
    let plus = stationarity_residual(m, e, x, &res.last_rows, &res.multipliers);
    let minus_mu: Vec<[f64; 4]> = res.multipliers.iter().map(|u| u.map(|v| -v)).collect();
    let minus = stationarity_residual(m, e, x, &res.last_rows, &minus_mu);
    let zero = stationarity_residual(m, e, x, &res.last_rows, &vec![[0.0; 4]; minus_mu.len()]);
    assert!(
        plus < 1e-6 * zero,
        "sign of docs/method.md: {plus:.3e} vs |J'| = {zero:.3e}"
    );
    assert!(
        minus > 1.5 * zero,
        "printed sign: {minus:.3e} vs |J'| = {zero:.3e}"
    );
}

#[test]
fn gram_matrix_integrates_constants_and_gradients() {
    let scene = build(&BalloonsParams {
        n: 16,
        ..Default::default()
    })
    .unwrap();
    let g = h1_gram(&scene.mesh);
    let dense = g.to_dense();
    let nf = dense.len();
    // Constant 1 in the first coordinate on the free dofs. An edge with both ends free adds its
    // length L (its stiffness annihilates constants); an edge with one end free (a membrane
    // glued to the fixed box) adds that end's diagonal L/3 + 1/L.
    let ones: Vec<f64> = (0..nf)
        .map(|k| if k % 2 == 0 { 1.0 } else { 0.0 })
        .collect();
    let mut quad = 0.0;
    for i in 0..nf {
        for j in 0..nf {
            let gij = if i <= j { dense[i][j] } else { dense[j][i] };
            quad += ones[i] * gij * ones[j];
        }
    }
    let mesh = &scene.mesh;
    let mut expected = 0.0;
    let mut both_free = 0;
    for body in &mesh.bodies {
        for &e in &body.edges {
            let [a, b] = mesh.edges[e];
            let l = (contactlab::scene::mesh::Mesh::p2(&mesh.x_ref, a)
                - contactlab::scene::mesh::Mesh::p2(&mesh.x_ref, b))
            .norm();
            match (mesh.fixed[a], mesh.fixed[b]) {
                (false, false) => {
                    expected += l;
                    both_free += 1;
                }
                (true, true) => {}
                _ => expected += l / 3.0 + 1.0 / l,
            }
        }
    }
    assert!(both_free > 0);
    assert!(
        (quad - expected).abs() <= 1e-12 * expected,
        "1ᵀG1 = {quad}, expected {expected}"
    );
}
