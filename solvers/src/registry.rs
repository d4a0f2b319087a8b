//! The backend registry: the one list of backends, by name, with their constructors, their
//! default settings and the QP tolerance of each accuracy preset.
//!
//! Everything that names a backend — the command line (`--backend`), a scene file's
//! `[solver] backend`, a sweep file's `backends`, the accuracy presets of the core — asks this
//! list; nothing else holds backend names.
//!
//! # Defaults and presets
//!
//! Each backend's default tolerance (`eps_abs = eps_rel`, the `default` preset) was measured on
//! the balloons scene (docs/measurements.md, "Choosing a backend"): Clarabel at `1e-9`; Uzawa at
//! `1e-8` (at `1e-9` its accelerated dual ascent hit 10⁵ steps near the fixed point at n = 8,
//! with violation 6e-9); OSQP (ADMM, with solution polishing) at `1e-6` (at `1e-9` it needed
//! 10⁴–10⁵ iterations per QP and hit its iteration limit near the fixed point, while at `1e-6`
//! polishing recovers the active-set solution); `ip` (interior point on the condensed system,
//! [`crate::ipm`], with Clarabel behind it for the QPs it does not solve, [`crate::fallback`]) at 1e-10 (at 1e-9 `ring` ended at a fixed point with κ 1.06e-5, above
//! `tol_κ = 1e-5`; at 1e-10 it is certified, κ 2.7e-6). The `low` and `high` presets keep OSQP three
//! orders looser than Clarabel.
//!
//! | backend          | low  | default | high  |
//! |------------------|------|---------|-------|
//! | `clarabel`       | 1e-6 | 1e-9    | 1e-11 |
//! | `clarabel-reuse` | 1e-6 | 1e-9    | 1e-11 |
//! | `ip`             | 1e-6 | 1e-10   | 1e-11 |
//! | `active-set`     | 1e-6 | 1e-10   | 1e-11 |
//! | `osqp`           | 1e-4 | 1e-6    | 1e-8  |
//! | `uzawa`          | 1e-6 | 1e-8    | 1e-10 |
//!
//! # Adding a backend
//!
//! Three files: the backend's own module (a type implementing [`QpBackend`]), one `mod` line in
//! `lib.rs`, and one entry of [`BACKENDS`] here:
//!
//! ```ignore
//! // solvers/src/lib.rs
//! pub mod my_backend;
//! // solvers/src/registry.rs, in BACKENDS
//! Backend {
//!     name: "mine",
//!     about: "",
//!     tol: PresetTolerances { low: 1e-6, default: 1e-8, high: 1e-10 },
//!     build: |s| Box::new(crate::my_backend::MyBackend::new(s)),
//! },
//! ```
//!
//! It is then accepted by `contactlab run --backend mine`, by scene and sweep files, and
//! compared with the others by `solvers/tests/agreement.rs` (which loops over
//! [`BACKEND_NAMES`]).

use crate::backend::{QpBackend, QpError, QpSettings};

/// The QP tolerance (`eps_abs = eps_rel`) of a backend in each accuracy preset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresetTolerances {
    /// Preset `low`: fast, loose.
    pub low: f64,
    /// Preset `default`: the backend's measured default ([`default_settings`]).
    pub default: f64,
    /// Preset `high`: reference runs.
    pub high: f64,
}

/// One registered backend.
pub struct Backend {
    /// Name on the command line, in scene and sweep files and in outputs.
    pub name: &'static str,
    /// A short description for help texts (empty when the name says it all).
    pub about: &'static str,
    /// Preset tolerances.
    pub tol: PresetTolerances,
    /// Builds the backend from validated settings.
    pub build: fn(QpSettings) -> Box<dyn QpBackend>,
}

/// The presets of `ip` and of `active-set`, which hands the QPs it does not solve to `ip`.
const IP_TOLERANCES: PresetTolerances = PresetTolerances {
    low: 1e-6,
    default: 1e-10,
    high: 1e-11,
};

/// Every backend, in the order of help texts and sweeps.
pub const BACKENDS: [Backend; 6] = [
    Backend {
        name: "clarabel",
        about: "",
        tol: PresetTolerances {
            low: 1e-6,
            default: 1e-9,
            high: 1e-11,
        },
        build: |s| Box::new(crate::clarabel_backend::ClarabelBackend::new(s)),
    },
    Backend {
        name: "clarabel-reuse",
        about: "Clarabel keeping its solver between QPs of one structure",
        tol: PresetTolerances {
            low: 1e-6,
            default: 1e-9,
            high: 1e-11,
        },
        build: |s| Box::new(crate::clarabel_backend::ClarabelBackend::with_reuse(s)),
    },
    Backend {
        name: "ip",
        about: "interior point on the condensed system, faer sparse LDLT; a QP it does not solve \
                goes to Clarabel",
        tol: IP_TOLERANCES,
        build: |s| {
            Box::new(crate::fallback::Fallback::new(
                Box::new(crate::ipm::IpBackend::new(s.clone())),
                Box::new(crate::clarabel_backend::ClarabelBackend::new(s)),
            ))
        },
    },
    Backend {
        name: "active-set",
        about: "primal-dual active set from the warm start's duals; a QP it does not solve goes \
                to ip, then Clarabel",
        tol: IP_TOLERANCES,
        build: |s| {
            Box::new(crate::fallback::Fallback::new(
                Box::new(crate::active_set::ActiveSetBackend::new(s.clone())),
                Box::new(crate::clarabel_backend::ClarabelBackend::new(s)),
            ))
        },
    },
    Backend {
        name: "osqp",
        about: "",
        tol: PresetTolerances {
            low: 1e-4,
            default: 1e-6,
            high: 1e-8,
        },
        build: |s| Box::new(crate::osqp_backend::OsqpBackend::new(s)),
    },
    Backend {
        name: "uzawa",
        about: "",
        tol: PresetTolerances {
            low: 1e-6,
            default: 1e-8,
            high: 1e-10,
        },
        build: |s| Box::new(crate::uzawa::UzawaBackend::new(s)),
    },
];

/// The backend of runs, sweeps and scene files that name none (the core takes it from here and
/// never names a backend itself).
pub const DEFAULT_BACKEND: &str = BACKENDS[2].name;

/// The backend of the diagnostics' reference solves (the canonical multipliers and the
/// stationarity check of a converged run), whatever backend the run used.
pub const REFERENCE_BACKEND: &str = BACKENDS[0].name;

/// The backend of the minimality certificate's sparse path (the dual QP of its non-negative
/// least-squares problem, `contactlab::solve::certificate`), and its tolerance
/// (`eps_abs = eps_rel`). Chosen by measurement on the balloons' final states (docs/method.md,
/// "The minimality certificate").
pub const CERTIFICATE_BACKEND: &str = BACKENDS[0].name;
/// See [`CERTIFICATE_BACKEND`].
pub const CERTIFICATE_TOL: f64 = 1e-10;

/// The names of [`BACKENDS`], in order.
pub const BACKEND_NAMES: [&str; BACKENDS.len()] = {
    let mut names = [""; BACKENDS.len()];
    let mut i = 0;
    while i < BACKENDS.len() {
        names[i] = BACKENDS[i].name;
        i += 1;
    }
    names
};

/// The registered backend called `name`.
pub fn backend(name: &str) -> Option<&'static Backend> {
    BACKENDS.iter().find(|b| b.name == name)
}

/// Builds a backend from its name and the common settings (validated first), behind the row
/// presolve of [`crate::presolve`] when `settings.presolve`.
pub fn backend_from_name(name: &str, settings: &QpSettings) -> Result<Box<dyn QpBackend>, QpError> {
    settings.validate()?;
    match backend(name) {
        Some(b) if settings.presolve => Ok(Box::new(crate::presolve::Presolved::new((b.build)(
            settings.clone(),
        )))),
        Some(b) => Ok((b.build)(settings.clone())),
        None => Err(QpError::UnknownBackend(name.to_string())),
    }
}

/// The preset tolerances of `name`; an unknown name gets Clarabel's (the first entry), so that
/// a summary can be written before the name is refused by [`backend_from_name`].
pub fn preset_tolerances(name: &str) -> PresetTolerances {
    backend(name).unwrap_or(&BACKENDS[0]).tol
}

/// Default settings of a backend: [`QpSettings::default`] with its `default` preset tolerance.
pub fn default_settings(name: &str) -> QpSettings {
    let tol = preset_tolerances(name).default;
    QpSettings {
        eps_abs: tol,
        eps_rel: tol,
        ..QpSettings::default()
    }
}

/// `a, b (about b), c or d`: the backend names for a help text.
pub fn backend_list_help() -> String {
    let items: Vec<String> = BACKENDS
        .iter()
        .map(|b| match b.about {
            "" => b.name.to_string(),
            about => format!("{} ({about})", b.name),
        })
        .collect();
    match items.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_presets_ordered() {
        for (i, b) in BACKENDS.iter().enumerate() {
            assert_eq!(BACKEND_NAMES[i], b.name);
            assert_eq!(backend(b.name).map(|x| x.name), Some(b.name));
            assert!(
                b.tol.low > b.tol.default && b.tol.default > b.tol.high,
                "{}",
                b.name
            );
        }
        assert!(backend("gurobi").is_none());
        assert_eq!(CERTIFICATE_BACKEND, "clarabel");
        // the refusal lists every registered backend
        let e = backend_from_name("gurobi", &QpSettings::default())
            .err()
            .expect("gurobi is not registered");
        assert_eq!(
            e.to_string(),
            "unknown backend \"gurobi\" (expected one of clarabel, clarabel-reuse, ip, active-set, osqp, \
             uzawa)"
        );
        for name in BACKEND_NAMES {
            assert!(e.to_string().contains(name), "{name}");
        }
        assert_eq!(
            backend_list_help(),
            "clarabel, clarabel-reuse (Clarabel keeping its solver between QPs of one \
             structure), ip (interior point on the condensed system, faer sparse LDLT; a QP it \
             does not solve goes to Clarabel), active-set (primal-dual active set from the warm \
             start's duals; a QP it does not solve goes to ip, then Clarabel), osqp or uzawa"
        );
    }
}
