//! Accuracy presets `low`, `default`, `high`: the outer stopping tolerance `tol_J` and, per
//! backend, the QP tolerance (`eps_abs = eps_rel`). The sub-problem accuracy must match the
//! outer stopping rule (docs/method.md): a QP tolerance near 1e-8 leaves constraint violations
//! as large as a 1e-10 energy change, so `high` goes to 1e-11 with Clarabel.
//!
//! | preset  | tol_J  | tol_κ = √tol_J |
//! |---------|--------|----------------|
//! | low     | 1e-6   | 1e-3           |
//! | default | 1e-10  | 1e-5           |
//! | high    | 1e-12  | 1e-6           |
//!
//! `tol_κ` is the minimality certificate's tolerance ([`tol_kappa`]): a run that meets the
//! stopping rule is `converged` when `κ ≤ tol_κ` (docs/method.md).
//!
//! [`RunSettings`] holds everything a run is configured by; the command line (`contactlab
//! run`), a scene file's `[solver]` and a sweep file's blocks all fill it, and its one
//! [`RunSettings::validate`] checks it (docs/cli.md, docs/scene-files.md, docs/sweeps.md).
//!
//! The QP tolerance of a preset is the backend's own (the table in
//! [`contactlab_solvers::registry`]); `default` is each backend's measured default
//! ([`contactlab_solvers::default_settings`]).

use crate::energy::HessianModel;
use crate::solve::outer::{OuterSettings, Pruning, TrustSettings};
use crate::solve::sqp::{Curvature, OuterMethod};
use contactlab_solvers::{default_settings, preset_tolerances, QpSettings, BACKEND_NAMES};
use thiserror::Error;

/// An accuracy preset.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Accuracy {
    /// Fast, loose.
    Low,
    /// The backends' measured defaults.
    Default,
    /// Reference runs.
    High,
}

impl Accuracy {
    /// All presets.
    pub const ALL: [Accuracy; 3] = [Accuracy::Low, Accuracy::Default, Accuracy::High];

    /// Name used in CLI, sweep files and CSV.
    pub fn as_str(&self) -> &'static str {
        match self {
            Accuracy::Low => "low",
            Accuracy::Default => "default",
            Accuracy::High => "high",
        }
    }

    /// Parses a name.
    pub fn from_name(s: &str) -> Option<Accuracy> {
        Accuracy::ALL.into_iter().find(|a| a.as_str() == s)
    }

    /// The outer tolerance `tol_J`.
    pub fn tol_j(&self) -> f64 {
        match self {
            Accuracy::Low => 1e-6,
            Accuracy::Default => 1e-10,
            Accuracy::High => 1e-12,
        }
    }

    /// The QP tolerance of `backend` in this preset (from the backend registry,
    /// [`contactlab_solvers::registry`]).
    pub fn qp_tol(&self, backend: &str) -> f64 {
        let tol = preset_tolerances(backend);
        match self {
            Accuracy::Low => tol.low,
            Accuracy::Default => tol.default,
            Accuracy::High => tol.high,
        }
    }

    /// The backend settings: [`default_settings`] with the preset's tolerance.
    pub fn qp_settings(&self, backend: &str) -> QpSettings {
        let tol = self.qp_tol(backend);
        QpSettings {
            eps_abs: tol,
            eps_rel: tol,
            ..default_settings(backend)
        }
    }
}

/// The certificate's tolerance for a stopping tolerance `tol_j`: `√tol_J`. Near a minimum the
/// energy is quadratic in the position error e and the unbalanced force linear in it, so
/// stopping when the energy changes by `tol_J` of its scale leaves a force of order
/// `√tol_J` of the forces' scale (docs/method.md, "The minimality certificate").
pub fn tol_kappa(tol_j: f64) -> f64 {
    tol_j.sqrt()
}

/// Everything a run (static, or each step of a dynamic one) is configured by, with the
/// defaults of `contactlab run`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunSettings {
    /// Sub-problem backend, a name of [`contactlab_solvers::registry`].
    pub backend: String,
    /// Accuracy preset (QP tolerance and `tol_J`).
    pub accuracy: Accuracy,
    /// Which pairs of T(ψ) the sub-problems carry.
    pub pruning: Pruning,
    /// Override of the preset's `tol_J` (> 0, finite).
    pub tol_j: Option<f64>,
    /// Override of the preset's QP tolerance, `eps_abs = eps_rel` (> 0, finite).
    pub qp_tol: Option<f64>,
    /// Maximum outer iterations (≥ 1).
    pub max_outer: usize,
    /// Inner (Newton-type) steps per T(ψ) at most (≥ 1); 1 gives inexact sub-problems.
    pub max_inner: usize,
    /// Lazy rows' initial radius cap relative to the median edge (finite, ≥ 0).
    pub lazy_start: f64,
    /// Initial trust-region half-width δ0 relative to the median edge (finite, > 0).
    pub trust_delta0: f64,
    /// Warm-start the QP duals.
    pub warm_start: bool,
    /// Wall-time limit of a static run in seconds (> 0; `None`: none).
    pub time_limit_s: Option<f64>,
    /// The Hessian of the inner steps' quadratic model.
    pub hessian_model: HessianModel,
    /// The outer method: `pantz` (the paper's T(ψ) steps) or `sqp`.
    pub outer_method: OuterMethod,
    /// The SQP model's constraint curvature (`--sqp-curvature`; sqp only).
    pub sqp_curvature: Curvature,
    /// SQP: `γ` of the active pairs' normal stiffness (`--sqp-normal-stiffness`; finite,
    /// ≥ 0).
    pub sqp_normal_stiffness: f64,
    /// SQP: leave out the rows implied by another row of the same vertex or edge
    /// (`--sqp-drop-endpoint-rows`).
    pub sqp_drop_endpoint_rows: bool,
    /// SQP: rows against the extended element (`--sqp-extend-rows`).
    pub sqp_extend_rows: bool,
    /// SQP, 2D: leave out the rows whose closest point is a vertex of the other body
    /// (`--sqp-drop-vertex-rows`).
    pub sqp_drop_vertex_rows: bool,
    /// SQP, 2D: leave out a vertex's row against the side of a corner that the corner's row
    /// implies (`--sqp-drop-side-rows`).
    pub sqp_drop_side_rows: bool,
    /// SQP: no chain limit for the extended rows against a fixed element
    /// (`--sqp-extend-fixed`).
    pub sqp_extend_fixed: bool,
    /// SQP: add a violated row only where the pair comes within `ε + δ` on the step's straight
    /// path (`--sqp-path-rows`).
    pub sqp_path_rows: bool,
    /// SQP: with the endpoint or vertex rows left out, add the rows that would imply a violated
    /// one (`--sqp-implying-rows`).
    pub sqp_implying_rows: bool,
    /// SQP: after a full step, try 2, 4, …, 2^k times it while J falls and every check
    /// passes (`--sqp-extrapolate k`; 0: off).
    pub sqp_extrapolate: usize,
    /// SQP: the normal stiffness only on the pairs whose last multiplier is at least this
    /// fraction of the largest (`--sqp-normal-active-rel`; 0: every positive one; in [0, 1]).
    pub sqp_normal_active_rel: f64,
    /// SQP: `interior` keeps surfaces' edge–edge pairs, with this factor on their normal
    /// stiffness (`--sqp-edge-edge-stiffness`; 0: left out; finite, ≥ 0).
    pub sqp_edge_edge_stiffness: f64,
}

impl Default for RunSettings {
    fn default() -> Self {
        let outer = OuterSettings::default();
        RunSettings {
            backend: contactlab_solvers::DEFAULT_BACKEND.into(),
            accuracy: Accuracy::Default,
            pruning: outer.pruning,
            tol_j: None,
            qp_tol: None,
            max_outer: outer.max_outer,
            max_inner: outer.inner.max_inner,
            lazy_start: outer.lazy_start,
            trust_delta0: outer.trust.delta0,
            warm_start: outer.inner.warm_start,
            time_limit_s: outer.time_limit_s,
            hessian_model: outer.inner.hessian_model,
            outer_method: outer.method,
            sqp_curvature: outer.sqp.curvature,
            sqp_normal_stiffness: outer.sqp.normal_stiffness,
            sqp_drop_endpoint_rows: outer.sqp.drop_endpoint_rows,
            sqp_extend_rows: outer.sqp.extend_rows,
            sqp_drop_vertex_rows: outer.sqp.drop_vertex_rows,
            sqp_drop_side_rows: outer.sqp.drop_side_rows,
            sqp_extend_fixed: outer.sqp.extend_fixed,
            sqp_path_rows: outer.sqp.path_rows,
            sqp_implying_rows: outer.sqp.implying_rows,
            sqp_extrapolate: outer.sqp.extrapolate,
            sqp_normal_active_rel: outer.sqp.normal_active_rel,
            sqp_edge_edge_stiffness: outer.sqp.edge_edge_stiffness,
        }
    }
}

/// Why a [`RunSettings`] value is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// Not a name of the backend registry.
    KnownBackend,
    /// Must be ≥ 1.
    AtLeastOne,
    /// Must be finite and > 0.
    FinitePositive,
    /// Must be finite and ≥ 0.
    FiniteNonNegative,
    /// Must be > 0 (not NaN).
    Positive,
    /// Must be in [0, 1].
    UnitInterval,
}

impl std::fmt::Display for Rule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rule::KnownBackend => write!(f, "expected one of {}", BACKEND_NAMES.join(", ")),
            Rule::AtLeastOne => write!(f, "must be ≥ 1"),
            Rule::FinitePositive => write!(f, "must be finite and > 0"),
            Rule::FiniteNonNegative => write!(f, "must be finite and ≥ 0"),
            Rule::Positive => write!(f, "must be > 0"),
            Rule::UnitInterval => write!(f, "must be in [0, 1]"),
        }
    }
}

/// An invalid [`RunSettings`] value: the key (as in a scene file's `[solver]`), its value and
/// the rule it breaks. Each front end words it in its own terms (a flag, `solver.KEY`, a sweep
/// block).
#[derive(Clone, Debug, Error, PartialEq)]
#[error("{key} = {value}: {rule}")]
pub struct SettingsError {
    /// The key: `backend`, `qp_tol`, `max_outer`, `max_inner`, `lazy_start`, `trust_delta0`,
    /// `time_limit_s`, `tol_j`, `sqp_normal_stiffness`, `sqp_normal_active_rel` or
    /// `sqp_edge_edge_stiffness`.
    pub key: &'static str,
    /// The value, printed (a backend name quoted).
    pub value: String,
    /// The rule it breaks.
    pub rule: Rule,
}

impl RunSettings {
    /// Checks every key, naming the first bad one (in the order of the fields' checks:
    /// backend, qp_tol, max_outer, max_inner, lazy_start, trust_delta0, time_limit_s, tol_j,
    /// sqp_normal_stiffness, sqp_normal_active_rel, sqp_edge_edge_stiffness).
    pub fn validate(&self) -> Result<(), SettingsError> {
        let err = |key, value: String, rule| Err(SettingsError { key, value, rule });
        let finite_pos = |v: f64| v > 0.0 && v.is_finite();
        if !BACKEND_NAMES.contains(&self.backend.as_str()) {
            return err("backend", format!("{:?}", self.backend), Rule::KnownBackend);
        }
        if let Some(t) = self.qp_tol.filter(|&t| !finite_pos(t)) {
            return err("qp_tol", t.to_string(), Rule::FinitePositive);
        }
        if self.max_outer == 0 {
            return err("max_outer", "0".into(), Rule::AtLeastOne);
        }
        if self.max_inner == 0 {
            return err("max_inner", "0".into(), Rule::AtLeastOne);
        }
        if !(self.lazy_start >= 0.0 && self.lazy_start.is_finite()) {
            return err(
                "lazy_start",
                self.lazy_start.to_string(),
                Rule::FiniteNonNegative,
            );
        }
        if !finite_pos(self.trust_delta0) {
            return err(
                "trust_delta0",
                self.trust_delta0.to_string(),
                Rule::FinitePositive,
            );
        }
        if let Some(t) = self.time_limit_s.filter(|t| t.is_nan() || *t <= 0.0) {
            return err("time_limit_s", t.to_string(), Rule::Positive);
        }
        if let Some(t) = self.tol_j.filter(|&t| !finite_pos(t)) {
            return err("tol_j", t.to_string(), Rule::FinitePositive);
        }
        let g = self.sqp_normal_stiffness;
        if !(g >= 0.0 && g.is_finite()) {
            return err(
                "sqp_normal_stiffness",
                g.to_string(),
                Rule::FiniteNonNegative,
            );
        }
        let r = self.sqp_normal_active_rel;
        if !(0.0..=1.0).contains(&r) {
            return err("sqp_normal_active_rel", r.to_string(), Rule::UnitInterval);
        }
        let f = self.sqp_edge_edge_stiffness;
        if !(f >= 0.0 && f.is_finite()) {
            return err(
                "sqp_edge_edge_stiffness",
                f.to_string(),
                Rule::FiniteNonNegative,
            );
        }
        Ok(())
    }

    /// `tol_J`: the override, or the preset's.
    pub fn tol_j(&self) -> f64 {
        self.tol_j.unwrap_or(self.accuracy.tol_j())
    }

    /// The backend settings: the preset's, with `qp_tol` overriding `eps_abs = eps_rel`.
    pub fn qp_settings(&self) -> QpSettings {
        let mut qps = self.accuracy.qp_settings(&self.backend);
        if let Some(t) = self.qp_tol {
            qps.eps_abs = t;
            qps.eps_rel = t;
        }
        qps
    }

    /// The outer loop's settings.
    pub fn outer_settings(&self) -> OuterSettings {
        let mut settings = OuterSettings {
            tol_j: self.tol_j(),
            tol_kappa: tol_kappa(self.tol_j()),
            qp_tol: self.qp_settings().eps_abs,
            max_outer: self.max_outer,
            pruning: self.pruning,
            lazy_start: self.lazy_start,
            trust: TrustSettings {
                delta0: self.trust_delta0,
                ..Default::default()
            },
            ..Default::default()
        };
        settings.inner.max_inner = self.max_inner;
        settings.inner.warm_start = self.warm_start;
        settings.inner.hessian_model = self.hessian_model;
        settings.method = self.outer_method;
        settings.sqp.curvature = self.sqp_curvature;
        settings.sqp.normal_stiffness = self.sqp_normal_stiffness;
        settings.sqp.drop_endpoint_rows = self.sqp_drop_endpoint_rows;
        settings.sqp.extend_rows = self.sqp_extend_rows;
        settings.sqp.drop_vertex_rows = self.sqp_drop_vertex_rows;
        settings.sqp.drop_side_rows = self.sqp_drop_side_rows;
        settings.sqp.extend_fixed = self.sqp_extend_fixed;
        settings.sqp.path_rows = self.sqp_path_rows;
        settings.sqp.implying_rows = self.sqp_implying_rows;
        settings.sqp.extrapolate = self.sqp_extrapolate;
        settings.sqp.normal_active_rel = self.sqp_normal_active_rel;
        settings.sqp.edge_edge_stiffness = self.sqp_edge_edge_stiffness;
        settings.time_limit_s = self.time_limit_s;
        settings
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_ordered_and_default_matches_the_backends() {
        for b in BACKEND_NAMES {
            assert_eq!(Accuracy::Default.qp_settings(b), default_settings(b), "{b}");
            assert!(Accuracy::Low.qp_tol(b) > Accuracy::Default.qp_tol(b), "{b}");
            assert!(
                Accuracy::Default.qp_tol(b) > Accuracy::High.qp_tol(b),
                "{b}"
            );
        }
        assert!(Accuracy::Low.tol_j() > Accuracy::Default.tol_j());
        assert!(Accuracy::Default.tol_j() > Accuracy::High.tol_j());
        for a in Accuracy::ALL {
            assert_eq!(Accuracy::from_name(a.as_str()), Some(a));
        }
        assert_eq!(Accuracy::from_name("medium"), None);
    }

    #[test]
    fn run_settings_defaults_are_valid_and_errors_name_the_key() {
        let d = RunSettings::default();
        assert_eq!(d.validate(), Ok(()));
        assert_eq!(d.outer_settings(), OuterSettings::default());
        let bad = |f: &dyn Fn(&mut RunSettings)| {
            let mut s = RunSettings::default();
            f(&mut s);
            s.validate().unwrap_err().to_string()
        };
        assert_eq!(
            bad(&|s| s.backend = "gurobi".into()),
            format!(
                "backend = \"gurobi\": expected one of {}",
                BACKEND_NAMES.join(", ")
            )
        );
        assert_eq!(bad(&|s| s.max_inner = 0), "max_inner = 0: must be ≥ 1");
        assert_eq!(bad(&|s| s.max_outer = 0), "max_outer = 0: must be ≥ 1");
        assert_eq!(
            bad(&|s| s.tol_j = Some(0.0)),
            "tol_j = 0: must be finite and > 0"
        );
        assert_eq!(
            bad(&|s| s.qp_tol = Some(f64::INFINITY)),
            "qp_tol = inf: must be finite and > 0"
        );
        assert_eq!(
            bad(&|s| s.lazy_start = -1.0),
            "lazy_start = -1: must be finite and ≥ 0"
        );
        assert_eq!(
            bad(&|s| s.trust_delta0 = 0.0),
            "trust_delta0 = 0: must be finite and > 0"
        );
        assert_eq!(
            bad(&|s| s.time_limit_s = Some(0.0)),
            "time_limit_s = 0: must be > 0"
        );
        assert_eq!(
            bad(&|s| s.sqp_normal_stiffness = -0.5),
            "sqp_normal_stiffness = -0.5: must be finite and ≥ 0"
        );
        assert_eq!(
            bad(&|s| s.sqp_normal_active_rel = 1.5),
            "sqp_normal_active_rel = 1.5: must be in [0, 1]"
        );
        assert_eq!(
            bad(&|s| s.sqp_normal_active_rel = f64::NAN),
            "sqp_normal_active_rel = NaN: must be in [0, 1]"
        );
        assert_eq!(
            bad(&|s| s.sqp_edge_edge_stiffness = f64::INFINITY),
            "sqp_edge_edge_stiffness = inf: must be finite and ≥ 0"
        );
        assert_eq!(
            bad(&|s| s.sqp_normal_stiffness = f64::NAN),
            "sqp_normal_stiffness = NaN: must be finite and ≥ 0"
        );
        let s: RunSettings = toml::from_str("backend = \"uzawa\"\naccuracy = \"high\"").unwrap();
        assert_eq!((s.backend.as_str(), s.accuracy), ("uzawa", Accuracy::High));
    }
}
