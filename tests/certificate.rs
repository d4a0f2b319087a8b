//! The minimality certificate κ (docs/method.md, "The minimality certificate") and the
//! unit-free stopping rule (docs/method.md, "The outer loop"): κ is round-off at a known
//! minimum, large at a Pantz fixed point above the minimum, 1 where nothing holds the load,
//! small at a minimum without contact, and the same in any units of length and energy; a run
//! in other units takes the same outer steps to the same relative accuracy.

use contactlab::contact::ContactPair;
use contactlab::energy::{Gravity, Hessian, HessianModel, MembraneEnergy, Objective, TotalEnergy};
use contactlab::scene::balloons::{build, BalloonsParams};
use contactlab::scene::mesh::{Body, BodyKind, Mesh};
use contactlab::scene::rod::{self, RodParams};
use contactlab::scene::Scene;
use contactlab::solve::certificate::{certificate, certificate_with, Certificate, CertificatePath};
use contactlab::solve::h1::H1Norms;
use contactlab::solve::outer::{certificate_active_tol, run, OuterSettings, RunResult, RunStatus};
use contactlab::solve::sqp::OuterMethod;
use contactlab_solvers::{
    backend_from_name, default_settings, CERTIFICATE_BACKEND, CERTIFICATE_TOL,
};
use std::collections::HashMap;
/// The default settings with Pantz's map (these tests are about its fixed points; `auto`, the
/// default, leaves them for the SQP method).
fn pantz() -> OuterSettings {
    OuterSettings {
        method: OuterMethod::Pantz,
        ..Default::default()
    }
}

fn solve(
    mesh: &Mesh,
    energy: &dyn Objective,
    eps: f64,
    x0: &[f64],
    s: &OuterSettings,
) -> (RunResult, Vec<f64>) {
    let mut b = backend_from_name("clarabel", &default_settings("clarabel")).unwrap();
    let mut energies = Vec::new();
    let res = run(mesh, energy, eps, x0, b.as_mut(), s, &mut |r, _| {
        energies.push(r.energy)
    })
    .unwrap();
    (res, energies)
}

/// The balloons at level `n` from the initial `heights`, run with the default settings.
fn balloons(n: usize, heights: [f64; 4]) -> (Scene, RunResult) {
    let scene = build(&BalloonsParams {
        n,
        heights,
        ..Default::default()
    })
    .unwrap();
    let (res, _) = solve(&scene.mesh, &scene.energy, scene.eps, &scene.x0, &pantz());
    (scene, res)
}

fn curve(name: &str, vertices: Vec<usize>, edges: Vec<usize>) -> Body {
    Body {
        name: name.into(),
        kind: BodyKind::Curve,
        h: 1.0,
        vertices,
        edges,
        ..Default::default()
    }
}

/// A free bar (vertices 2, 3, unit masses, no stiffness) under gravity above a fixed floor
/// (vertices 0, 1), bar at height `y2`, `y3`.
fn bar_on_floor(y2: f64, y3: f64) -> (Mesh, TotalEnergy, Vec<f64>) {
    let x = vec![-2.0, 0.0, 2.0, 0.0, -0.5, y2, 0.5, y3];
    let mesh = Mesh {
        dim: 2,
        x_ref: x.clone(),
        fixed: vec![true, true, false, false],
        edges: vec![[0, 1], [2, 3]],
        edge_body: vec![0, 1],
        bodies: vec![
            curve("floor", vec![0, 1], vec![0]),
            curve("bar", vec![2, 3], vec![1]),
        ],
        ..Default::default()
    };
    let energy = TotalEnergy {
        terms: vec![Box::new(Gravity::<2>::new(
            vec![0.0, 0.0, 1.0, 1.0],
            [0.0, -1.0],
        ))],
    };
    (mesh, energy, x)
}

fn cert_at(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    eps: f64,
    active_tol: f64,
) -> Certificate {
    let norms = H1Norms::scaled(mesh).unwrap();
    certificate(mesh, energy, x, eps, active_tol, &norms, &HashMap::new()).unwrap()
}

#[test]
fn certificate_is_round_off_at_a_known_minimum_and_one_where_nothing_holds_the_load() {
    let eps = 0.1;
    // The minimum: the bar lying on the floor at distance ε (J' = the weights, held by the
    // two point–edge contacts with multipliers 1).
    let (mesh, energy, x) = bar_on_floor(eps, eps);
    let c = cert_at(&mesh, &energy, &x, eps, 1e-12);
    assert_eq!((c.pairs, c.positive), (2, 2));
    assert!(c.kappa <= 1e-15, "κ = {:e} at the minimum", c.kappa);
    // Lifted by 1e-3: no pair at distance ε, nothing holds the weight, κ = 1.
    let (mesh, energy, x) = bar_on_floor(eps + 1e-3, eps + 1e-3);
    let c = cert_at(&mesh, &energy, &x, eps, 1e-12);
    assert_eq!(c.pairs, 0);
    assert!((c.kappa - 1.0).abs() <= 1e-14, "κ = {}", c.kappa);
    // One end on the floor: one generator e (the vertex's distance gradient, +y at vertex
    // 2), so the minimum over μ ≥ 0 is the projection of J' = e + e' (the two weights) off
    // e in the G⁻¹ inner product: κ² = 1 − ⟨e, J'⟩² / (‖e‖² ‖J'‖²). The H⁻¹ norm weighs the
    // unbalanced moment (e − e') less than the unbalanced weight (e + e'), so κ < 1/√2.
    let (mesh, energy, x) = bar_on_floor(eps, eps + 0.2);
    let c = cert_at(&mesh, &energy, &x, eps, 1e-12);
    assert_eq!(c.pairs, 1);
    let norms = H1Norms::scaled(&mesh).unwrap();
    let unit = |dof: usize| {
        let mut v = vec![0.0; norms.free.n];
        v[dof] = 1.0;
        v
    };
    let (ey, ey3) = (unit(1), unit(3));
    let add = |a: &[f64], b: &[f64], s: f64| -> Vec<f64> {
        a.iter().zip(b).map(|(x, y)| x + s * y).collect()
    };
    let g = add(&ey, &ey3, 1.0);
    let nrm = |v: &[f64]| norms.free.norm(v);
    let inner = (nrm(&add(&ey, &g, 1.0)).powi(2) - nrm(&add(&ey, &g, -1.0)).powi(2)) / 4.0;
    assert!(inner > 0.0);
    let expected = (1.0 - inner * inner / (nrm(&ey).powi(2) * nrm(&g).powi(2))).sqrt();
    assert!(
        (c.kappa - expected).abs() <= 1e-12,
        "κ = {} vs {expected}",
        c.kappa
    );
    assert!(c.kappa > 0.01 && c.kappa < 0.5f64.sqrt(), "κ = {}", c.kappa);
    // The outer loop from a height of 0.5 ends on the floor, certified.
    let (mesh, energy, _) = bar_on_floor(0.5, 0.5);
    let (res, _) = solve(&mesh, &energy, eps, &mesh.x_ref.clone(), &pantz());
    assert_eq!(res.status, RunStatus::Converged);
    assert!(
        res.certificate.kappa <= 1e-15,
        "κ = {:e}",
        res.certificate.kappa
    );
}

/// A string of `k` edges, ends fixed, sagging under gravity: a minimum without contact.
fn hanging_string(k: usize) -> (Mesh, TotalEnergy, Vec<f64>) {
    let nv = k + 1;
    let x_ref: Vec<f64> = (0..nv).flat_map(|i| [i as f64 / k as f64, 0.0]).collect();
    let edges: Vec<[usize; 2]> = (0..k).map(|i| [i, i + 1]).collect();
    let mut fixed = vec![false; nv];
    fixed[0] = true;
    fixed[k] = true;
    let mesh = Mesh {
        dim: 2,
        x_ref: x_ref.clone(),
        fixed,
        edges: edges.clone(),
        edge_body: vec![0; k],
        bodies: vec![curve("string", (0..nv).collect(), (0..k).collect())],
        ..Default::default()
    };
    let mass = vec![1.0 / k as f64; nv];
    let energy = TotalEnergy {
        terms: vec![
            Box::new(MembraneEnergy::new(edges, &x_ref, 1.0)),
            Box::new(Gravity::<2>::new(mass, [0.0, -1.0])),
        ],
    };
    let x0: Vec<f64> = (0..nv)
        .flat_map(|i| {
            let s = i as f64 / k as f64;
            [s, -0.1 * (std::f64::consts::PI * s).sin()]
        })
        .collect();
    (mesh, energy, x0)
}

#[test]
fn certificate_of_a_minimum_without_contact_is_measured_against_the_terms_forces() {
    // At a minimum without contact J'(φ_h) vanishes: the ratio to it alone would be noise
    // over noise (≈ 1). The scale is the terms' forces (the weight, the tension), which do
    // not vanish.
    let (mesh, energy, x0) = hanging_string(16);
    let (res, _) = solve(&mesh, &energy, 0.01, &x0, &pantz());
    let c = &res.certificate;
    assert_eq!(res.status, RunStatus::Converged, "{c:?}");
    assert_eq!(c.pairs, 0);
    assert!(c.gradient <= 1e-6 * c.term_force, "{c:?}");
    // no contact: the residual is the net force itself
    assert_eq!(c.residual, c.gradient);
    assert!(c.kappa <= 1e-6, "κ = {:e}", c.kappa);
}

#[test]
fn certificate_separates_the_symmetric_minimum_from_the_asymmetric_fixed_point() {
    // docs/method.md: from the symmetric start Pantz's iteration ends at a KKT point of (3);
    // from the heights 0.9, 0.2, 0.9, 0.2 it ends at a fixed point above the minimum of the
    // broken state it reaches (Lemma 5.6's ‖R‖ ≈ 0.3–0.5 there).
    let (_, res) = balloons(40, [0.2; 4]);
    assert_eq!(res.status, RunStatus::Converged);
    assert!(
        res.certificate.kappa <= 1e-7,
        "κ = {:e}",
        res.certificate.kappa
    );
    let (_, res) = balloons(40, [0.9, 0.2, 0.9, 0.2]);
    assert_eq!(res.status, RunStatus::FixedPoint);
    // measured 5.5e-3: the unbalanced force is 0.55 % of the net force, 500 times the
    // default tolerance 1e-5
    assert!(
        res.certificate.kappa >= 1e-3,
        "κ = {:e}",
        res.certificate.kappa
    );
    assert_eq!(res.certificate.unresolved, 0);
}

/// `J_s(y) = E·J(y/L)`: the same problem in units where energies are `E` and lengths `L`
/// times the original ones.
struct Scaled<'a> {
    inner: &'a TotalEnergy,
    e: f64,
    l: f64,
}

impl Scaled<'_> {
    fn down(&self, y: &[f64]) -> Vec<f64> {
        y.iter().map(|v| v / self.l).collect()
    }
}

impl Objective for Scaled<'_> {
    fn value(&self, y: &[f64]) -> f64 {
        self.e * self.inner.value(&self.down(y))
    }
    fn gradient(&self, y: &[f64]) -> Vec<f64> {
        let f = self.e / self.l;
        self.inner
            .gradient(&self.down(y))
            .into_iter()
            .map(|g| f * g)
            .collect()
    }
    fn hessian(&self, y: &[f64], model: HessianModel) -> Hessian {
        let f = self.e / (self.l * self.l);
        let mut h = self.inner.model_hessian(&self.down(y), model);
        h.triplets.iter_mut().for_each(|t| t.2 *= f);
        h.rank_one.iter_mut().for_each(|r| r.coef *= f);
        h
    }
    fn model_is_psd(&self, model: HessianModel) -> bool {
        Objective::model_is_psd(self.inner, model)
    }
    fn term_gradients(&self, y: &[f64]) -> Vec<Vec<f64>> {
        let f = self.e / self.l;
        Objective::term_gradients(self.inner, &self.down(y))
            .into_iter()
            .map(|g| g.into_iter().map(|v| f * v).collect())
            .collect()
    }
}

fn scaled_mesh(mesh: &Mesh, l: f64) -> Mesh {
    let mut m = mesh.clone();
    m.x_ref.iter_mut().for_each(|v| *v *= l);
    m.bodies.iter_mut().for_each(|b| b.h *= l);
    m
}

#[test]
fn certificate_does_not_depend_on_the_units() {
    // The asymmetric fixed point at n = 20 (κ well above round-off), in the original units
    // and with energies × 1e-6 and lengths × 1e-3 (and × 1e3).
    let (scene, res) = balloons(20, [0.9, 0.2, 0.9, 0.2]);
    let tol = certificate_active_tol(&OuterSettings::default(), scene.eps, 1.0);
    let base = cert_at(&scene.mesh, &scene.energy, &res.x, scene.eps, tol);
    assert!(base.kappa > 1e-3, "{base:?}");
    for (e, l) in [(1e-6, 1e-3), (1e-6, 1e3), (1e3, 1.0)] {
        let mesh = scaled_mesh(&scene.mesh, l);
        let energy = Scaled {
            inner: &scene.energy,
            e,
            l,
        };
        let x: Vec<f64> = res.x.iter().map(|v| v * l).collect();
        let c = cert_at(&mesh, &energy, &x, scene.eps * l, tol * l);
        assert_eq!(
            (c.pairs, c.positive),
            (base.pairs, base.positive),
            "E = {e}, L = {l}"
        );
        assert!(
            (c.kappa - base.kappa).abs() <= 1e-9 * base.kappa,
            "E = {e}, L = {l}: κ = {} vs {}",
            c.kappa,
            base.kappa
        );
        // the forces scale as E/L
        let f = e / l;
        assert!((c.residual - f * base.residual).abs() <= 1e-9 * f * base.residual);
        assert!((c.gradient - f * base.gradient).abs() <= 1e-9 * f * base.gradient);
    }
}

#[test]
fn stopping_rule_does_not_depend_on_the_units() {
    // The rod (3D, 10 outer steps with J ≈ 0.15: the former rule's floor max(1, |J|) = 1
    // was in force) in units where energies are 2⁻²⁰ (≈ 1e-6) and lengths 2⁻³ times the
    // original ones (powers of two: the change of units is exact in floating point). The
    // run's absolute floors (the proximal weight, the row margin) are given in the same
    // units, and the QPs go to the backend in the run's own units (`qp_in_run_units`: the
    // backends' tolerances are partly absolute). The run then takes the same outer steps
    // through the same energies (relative to the energy unit) to the same certificate. The
    // former rule |ΔJ| ≤ tol_J·max(1, |J|) would have stopped the scaled run earlier.
    let scene = rod::build(&RodParams::default()).unwrap();
    let s0 = OuterSettings {
        qp_in_run_units: true,
        ..pantz()
    };
    let (res, j) = solve(&scene.mesh, &scene.energy, scene.eps, &scene.x0, &s0);
    let (e, l) = (2f64.powi(-20), 2f64.powi(-3));
    let mesh = scaled_mesh(&scene.mesh, l);
    let energy = Scaled {
        inner: &scene.energy,
        e,
        l,
    };
    let x0: Vec<f64> = scene.x0.iter().map(|v| v * l).collect();
    let mut s = s0.clone();
    s.inner.rho_abs *= e / (l * l);
    s.inner.margin_abs *= l;
    let (res_s, j_s) = solve(&mesh, &energy, scene.eps * l, &x0, &s);
    assert!(
        res.outer_iterations >= 5,
        "{} outer steps",
        res.outer_iterations
    );
    assert_eq!(res_s.outer_iterations, res.outer_iterations);
    assert_eq!(res_s.status, res.status);
    let dj = j.first().unwrap() - j.last().unwrap();
    for (a, b) in j.iter().zip(&j_s) {
        assert!((a - b / e).abs() <= 1e-12 * dj, "{a} vs {}", b / e);
    }
    let (k, ks) = (res.certificate.kappa, res_s.certificate.kappa);
    assert!((k - ks).abs() <= 1e-9 * k, "κ {k} vs {ks}");
    // the former rule on the scaled run's energies
    let old_stop = j_s
        .windows(2)
        .position(|w| (w[0] - w[1]).abs() <= 1e-10 * w[0].abs().max(1.0))
        .map_or(j_s.len(), |k| k + 1);
    assert!(
        old_stop < res.outer_iterations,
        "the former rule stops at step {old_stop} of {}",
        res.outer_iterations
    );
}

#[test]
fn certificate_warm_start_changes_only_the_work() {
    // The active set starts from the last sub-problem's multipliers; from none it reaches
    // the same residual.
    let (scene, res) = balloons(20, [0.2; 4]);
    let norms = H1Norms::scaled(&scene.mesh).unwrap();
    let tol = certificate_active_tol(&OuterSettings::default(), scene.eps, norms.free.ell);
    let warm: HashMap<ContactPair, f64> = res
        .last_rows
        .iter()
        .zip(&res.multipliers)
        .map(|(r, m)| (r.pair, m.iter().sum()))
        .collect();
    let [cold, hot] = [HashMap::new(), warm].map(|w| {
        certificate(
            &scene.mesh,
            &scene.energy,
            &res.x,
            scene.eps,
            tol,
            &norms,
            &w,
        )
        .unwrap()
    });
    assert_eq!(cold.pairs, hot.pairs);
    assert!(cold.pairs > 0);
    assert!(
        (cold.residual - hot.residual).abs() <= 1e-9 * cold.scale,
        "{cold:?} {hot:?}"
    );
}

#[test]
fn certificate_paths_agree_on_real_states() {
    // The exact active set and the sparse dual QP (docs/method.md, "The minimality
    // certificate") on final states of built-in scenes. At a fixed point above the minimum
    // (κ of 1e-3 and more) both reach the minimum: measured within 5e-12 of S of each other
    // (`examples/cert_paths.rs`), asserted within 1e-9, and the QP's weak-duality gap is
    // small. At a minimum κ is at the noise floor of the least-squares problem (about 1e-8
    // on the balloons): both residuals are upper bounds at that floor, measured within
    // 3e-8 of S of each other up to n = 1600, asserted within 1e-7 (tol_κ is 1e-5).
    let settings = pantz();
    let mut states: Vec<(String, Scene, RunResult)> = Vec::new();
    for (name, heights) in [
        ("symmetric", [0.2; 4]),
        ("asymmetric", [0.9, 0.2, 0.9, 0.2]),
    ] {
        let (scene, res) = balloons(40, heights);
        states.push((format!("balloons {name}"), scene, res));
    }
    for name in ["solids", "ring"] {
        let scene = contactlab::scene::registry::build_scene(
            name,
            contactlab::scene::registry::default_n(name),
            None,
            &Default::default(),
        )
        .unwrap();
        let (res, _) = solve(&scene.mesh, &scene.energy, scene.eps, &scene.x0, &settings);
        states.push((name.to_string(), scene, res));
    }
    for (name, scene, res) in &states {
        let norms = H1Norms::scaled(&scene.mesh).unwrap();
        let tol = certificate_active_tol(&settings, scene.eps, norms.free.ell);
        let cert = |path| {
            certificate_with(
                &scene.mesh,
                &scene.energy,
                &res.x,
                scene.eps,
                tol,
                &norms,
                &HashMap::new(),
                path,
            )
            .unwrap()
        };
        let exact = cert(CertificatePath::ActiveSet);
        assert!(exact.generators > 0, "{name}");
        // the registry's certificate backend, and `ip` (`--certificate-backend ip`)
        for backend in [CERTIFICATE_BACKEND, "ip"] {
            let qp = cert(CertificatePath::Qp {
                backend,
                tol: CERTIFICATE_TOL,
            });
            assert_eq!(
                (exact.unresolved, qp.unresolved),
                (0, 0),
                "{name} {backend}"
            );
            assert_eq!(qp.method, "qp");
            let diff = (qp.kappa - exact.kappa).abs();
            if exact.kappa >= 1e-3 {
                assert!(diff <= 1e-9, "{name} {backend}: {exact:?} {qp:?}");
                assert!(qp.dual_gap <= 1e-8, "{name} {backend}: {qp:?}");
            } else {
                assert!(diff <= 1e-7, "{name} {backend}: {exact:?} {qp:?}");
            }
        }
    }
    // the scenes cover both kinds of state
    assert!(states.iter().any(|s| s.2.certificate.kappa >= 1e-3));
    assert!(states.iter().any(|s| s.2.certificate.kappa <= 1e-6));
}

/// `contactlab run ARGS --quiet --out DIR`: its exit code, stderr and (where written)
/// summary.json.
fn cli(args: &[&str], tag: &str) -> (Option<i32>, String, Option<serde_json::Value>) {
    let dir = std::env::temp_dir().join(format!("contactlab-cert-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .arg("run")
        .args(args)
        .args(["--quiet", "--frame-every", "1000000", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let summary = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .map(|t| serde_json::from_str(&t).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into(),
        summary,
    )
}

#[test]
fn certificate_backend_is_chosen_on_the_command_line() {
    // balloons n = 800: 3 268 generators at its certified state, so the certificate takes
    // the dual QP (from QP_PATH_MIN_GENERATORS on), with the backend given
    let (code, err, s) = cli(
        &["balloons", "--n", "800", "--certificate-backend", "ip"],
        "ip",
    );
    assert_eq!(code, Some(0), "{err}");
    let s = s.unwrap();
    assert_eq!(s["settings"]["certificate_backend"], "ip");
    assert_eq!(s["status"], "converged");
    let c = &s["certificate"];
    assert_eq!(c["method"], "qp", "{c}");
    assert!(c["generators"].as_u64().unwrap() >= 3000, "{c}");
    assert!(c["kappa"].as_f64().unwrap() <= 1e-5, "{c}");
    // bad names and dynamic runs are refused by name, with the usage-error code
    let (code, err, _) = cli(
        &["balloons", "--n", "20", "--certificate-backend", "nope"],
        "bad",
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--certificate-backend \"nope\""), "{err}");
    let (code, err, _) = cli(&["drop", "--dynamic", "--certificate-backend", "ip"], "dyn");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("--certificate-backend is an option of static runs"),
        "{err}"
    );
}
