//! Scene files as runs load them: [`load_scene_file`] is the scene stage's loader
//! ([`crate::scene::file::load_with`]) with the solver's rules for the file's `[solver]` and
//! `[dynamics]` tables ([`SolveRules`]). The scene stage holds those tables as plain data and
//! does not import the solver; the checks that need the solver's vocabulary (backend names,
//! accuracy presets, outer methods, the SQP model's curvature modes, [`RunSettings::validate`],
//! time-stepping schemes) are here, and run while
//! the file loads, at the place the scene file's other checks give them (after `dim`, `eps`
//! and `gravity`, before the bodies). [`pruning`] and [`pruning_name`] map the file's pruning
//! names to the solver's modes and back.

use crate::energy::HessianModel;
use crate::scene::file::{
    load_with, DynamicsSpec, PruningName, Refusal, RunRules, SceneFile, SceneFileError, SolverSpec,
};
use crate::solve::dynamics::Scheme;
use crate::solve::outer::Pruning;
use crate::solve::settings::{Accuracy, RunSettings};
use crate::solve::sqp::{Curvature, OuterMethod};
use std::path::Path;

/// Reads, checks and builds a scene file for a run: [`crate::scene::file::load_with`] with
/// [`SolveRules`]. Every command that runs a scene file loads it with this.
pub fn load_scene_file(path: &Path) -> Result<SceneFile, SceneFileError> {
    load_with(path, &SolveRules)
}

/// The solver's rules for a scene file's `[solver]` and `[dynamics]`: `[solver]` written over
/// the default [`RunSettings`] must pass [`RunSettings::validate`] and name a known accuracy
/// preset; `[dynamics].scheme` must name a [`Scheme`].
pub struct SolveRules;

impl RunRules for SolveRules {
    fn check_solver(&self, s: &SolverSpec) -> Result<(), Refusal> {
        let mut rs = RunSettings::default();
        fill(s, &mut rs);
        if let Err(e) = rs.validate() {
            return Err(Refusal {
                key: e.key.to_string(),
                value: e.value,
                reason: e.rule.to_string(),
            });
        }
        if let Some(m) = &s.newton_model {
            if HessianModel::from_user_name(m).is_none() {
                return Err(Refusal {
                    key: "newton_model".into(),
                    value: format!("{m:?}"),
                    reason: format!("expected one of {}", HessianModel::USER_NAMES),
                });
            }
        }
        if let Some(m) = &s.outer_method {
            if OuterMethod::from_name(m).is_none() {
                return Err(Refusal {
                    key: "outer_method".into(),
                    value: format!("{m:?}"),
                    reason: format!("expected one of {}", OuterMethod::names()),
                });
            }
        }
        if let Some(c) = &s.sqp_curvature {
            if Curvature::from_name(c).is_none() {
                return Err(Refusal {
                    key: "sqp_curvature".into(),
                    value: format!("{c:?}"),
                    reason: format!("expected one of {}", Curvature::names()),
                });
            }
        }
        if let Some(a) = &s.accuracy {
            if Accuracy::from_name(a).is_none() {
                return Err(Refusal {
                    key: "accuracy".into(),
                    value: format!("{a:?}"),
                    reason: "expected one of low, default, high".into(),
                });
            }
        }
        Ok(())
    }

    fn check_dynamics(&self, d: &DynamicsSpec) -> Result<(), Refusal> {
        if let Some(sc) = &d.scheme {
            if Scheme::from_name(sc).is_none() {
                return Err(Refusal {
                    key: "scheme".into(),
                    value: format!("{sc:?}"),
                    reason: "expected one of euler, newmark".into(),
                });
            }
        }
        Ok(())
    }
}

/// The pruning mode a `[solver].pruning` name stands for.
pub fn pruning(name: PruningName) -> Pruning {
    match name {
        PruningName::AllPairs => Pruning::AllPairs,
        PruningName::Lazy => Pruning::Lazy,
        PruningName::TrustRegion => Pruning::TrustRegion,
    }
}

/// The `[solver].pruning` name of a pruning mode, the inverse of [`pruning`]. Both matches are
/// exhaustive, so a mode added on either side does not build until the other has it.
pub fn pruning_name(mode: Pruning) -> PruningName {
    match mode {
        Pruning::AllPairs => PruningName::AllPairs,
        Pruning::Lazy => PruningName::Lazy,
        Pruning::TrustRegion => PruningName::TrustRegion,
    }
}

/// Writes the keys `[solver]` gives into `settings` (all but `accuracy`, a name checked
/// separately).
fn fill(spec: &SolverSpec, settings: &mut RunSettings) {
    let s = settings;
    if let Some(v) = &spec.backend {
        s.backend = v.clone();
    }
    if let Some(v) = spec.pruning {
        s.pruning = pruning(v);
    }
    if let Some(v) = spec.max_outer {
        s.max_outer = v;
    }
    if let Some(v) = spec.max_inner {
        s.max_inner = v;
    }
    if let Some(v) = spec.lazy_start {
        s.lazy_start = v;
    }
    if let Some(v) = spec.trust_delta0 {
        s.trust_delta0 = v;
    }
    if let Some(v) = spec.warm_start {
        s.warm_start = v;
    }
    if let Some(m) = spec
        .newton_model
        .as_deref()
        .and_then(HessianModel::from_name)
    {
        s.hessian_model = m;
    }
    if let Some(m) = spec
        .outer_method
        .as_deref()
        .and_then(OuterMethod::from_name)
    {
        s.outer_method = m;
    }
    if let Some(c) = spec.sqp_curvature.as_deref().and_then(Curvature::from_name) {
        s.sqp_curvature = c;
    }
    if let Some(v) = spec.sqp_normal_stiffness {
        s.sqp_normal_stiffness = v;
    }
    if let Some(v) = spec.sqp_drop_endpoint_rows {
        s.sqp_drop_endpoint_rows = v;
    }
    if let Some(v) = spec.sqp_extend_rows {
        s.sqp_extend_rows = v;
    }
    if let Some(v) = spec.sqp_drop_vertex_rows {
        s.sqp_drop_vertex_rows = v;
    }
    if let Some(v) = spec.sqp_drop_side_rows {
        s.sqp_drop_side_rows = v;
    }
    if let Some(v) = spec.sqp_extend_fixed {
        s.sqp_extend_fixed = v;
    }
    if let Some(v) = spec.sqp_path_rows {
        s.sqp_path_rows = v;
    }
    if let Some(v) = spec.sqp_implying_rows {
        s.sqp_implying_rows = v;
    }
    if let Some(v) = spec.sqp_extrapolate {
        s.sqp_extrapolate = v;
    }
    if let Some(v) = spec.sqp_normal_active_rel {
        s.sqp_normal_active_rel = v;
    }
    if let Some(v) = spec.sqp_edge_edge_stiffness {
        s.sqp_edge_edge_stiffness = v;
    }
    s.tol_j = spec.tol_j.or(s.tol_j);
    s.qp_tol = spec.qp_tol.or(s.qp_tol);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pruning_names_are_the_pruning_modes_spelled_alike() {
        for mode in [Pruning::AllPairs, Pruning::Lazy, Pruning::TrustRegion] {
            let name = pruning_name(mode);
            assert_eq!(pruning(name), mode);
            assert_eq!(
                serde_json::to_value(name).unwrap(),
                serde_json::to_value(mode).unwrap()
            );
            assert_eq!(serde_json::to_value(name).unwrap(), mode.as_str());
        }
    }

    #[test]
    fn solve_rules_refuse_with_the_key_inside_the_table() {
        let solver = |f: &dyn Fn(&mut SolverSpec)| {
            let mut s = SolverSpec::default();
            f(&mut s);
            SolveRules.check_solver(&s)
        };
        assert_eq!(solver(&|_| ()), Ok(()));
        let e = solver(&|s| s.backend = Some("gurobi".into())).unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.value.as_str()),
            ("backend", "\"gurobi\"")
        );
        let e = solver(&|s| s.max_outer = Some(0)).unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.value.as_str(), e.reason.as_str()),
            ("max_outer", "0", "must be ≥ 1")
        );
        // the run settings' rules come before the accuracy name
        let e = solver(&|s| {
            s.accuracy = Some("bogus".into());
            s.tol_j = Some(0.0);
        })
        .unwrap_err();
        assert_eq!(e.key, "tol_j");
        let e = solver(&|s| s.sqp_curvature = Some("hessian".into())).unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.value.as_str(), e.reason.as_str()),
            (
                "sqp_curvature",
                "\"hessian\"",
                "expected one of off, psd, full, tangent, interior, auto"
            )
        );
        let e = solver(&|s| s.sqp_normal_stiffness = Some(-1.0)).unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.value.as_str(), e.reason.as_str()),
            ("sqp_normal_stiffness", "-1", "must be finite and ≥ 0")
        );
        let ok = solver(&|s| {
            s.sqp_curvature = Some("psd".into());
            s.sqp_normal_stiffness = Some(0.01);
        });
        assert_eq!(ok, Ok(()));
        let e = solver(&|s| s.accuracy = Some("bogus".into())).unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.value.as_str(), e.reason.as_str()),
            (
                "accuracy",
                "\"bogus\"",
                "expected one of low, default, high"
            )
        );
        let dynamics = |scheme: &str| {
            SolveRules.check_dynamics(&DynamicsSpec {
                scheme: Some(scheme.into()),
                ..Default::default()
            })
        };
        assert_eq!(dynamics("newmark"), Ok(()));
        assert_eq!(
            dynamics("rk4"),
            Err(Refusal {
                key: "scheme".into(),
                value: "\"rk4\"".into(),
                reason: "expected one of euler, newmark".into(),
            })
        );
    }
}
