//! Accuracy presets `low`, `default`, `high`: per backend, the QP tolerance (`eps_abs =
//! eps_rel`), and the outer stopping tolerance `tol_J` (SPEC §3: the sub-problem accuracy must
//! match the outer stopping rule — a QP tolerance near 1e-8 leaves constraint violations as
//! large as a 1e-10 energy change, so `high` goes to 1e-11).
//!
//! | preset  | tol_J  | clarabel | osqp | uzawa |
//! |---------|--------|----------|------|-------|
//! | low     | 1e-6   | 1e-6     | 1e-4 | 1e-6  |
//! | default | 1e-10  | 1e-9     | 1e-6 | 1e-8  |
//! | high    | 1e-12  | 1e-11    | 1e-8 | 1e-10 |
//!
//! `default` is the measured default of each backend (`contactlab_solvers::default_settings`,
//! README "Choosing a backend"). OSQP's ADMM stays three orders looser than Clarabel in each
//! preset: at 1e-9 it hit its iteration limit near the fixed point (README); its solution
//! polishing recovers the active-set solution.

use contactlab_solvers::{default_settings, QpSettings};

/// An accuracy preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
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

    /// The QP tolerance of `backend` (a backend name; `clarabel-reuse` as `clarabel`).
    pub fn qp_tol(&self, backend: &str) -> f64 {
        let osqp = backend == "osqp";
        let uzawa = backend == "uzawa";
        match self {
            Accuracy::Low if osqp => 1e-4,
            Accuracy::Low => 1e-6,
            Accuracy::Default => default_settings(backend).eps_abs,
            Accuracy::High if osqp => 1e-8,
            Accuracy::High if uzawa => 1e-10,
            Accuracy::High => 1e-11,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_ordered_and_default_matches_the_backends() {
        for b in ["clarabel", "clarabel-reuse", "osqp", "uzawa"] {
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
}
