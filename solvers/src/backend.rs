//! The backend trait, settings, solution and status types shared by all backends.

use crate::qp::Qp;
use thiserror::Error;

/// Invalid input to a backend. Non-convergence is NOT an error: it is a [`QpStatus`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum QpError {
    /// A matrix or vector has the wrong shape.
    #[error("{what} has shape {found:?}, expected {expected:?}")]
    DimensionMismatch {
        /// Which matrix or vector.
        what: &'static str,
        /// Expected (rows, cols).
        expected: (usize, usize),
        /// Found (rows, cols).
        found: (usize, usize),
    },
    /// A triplet lies outside the matrix.
    #[error("{what} {index} at ({row}, {col}) is outside a {nrows}×{ncols} matrix")]
    IndexOutOfRange {
        /// What was indexed.
        what: &'static str,
        /// Position of the triplet in the input.
        index: usize,
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
        /// Matrix rows.
        nrows: usize,
        /// Matrix columns.
        ncols: usize,
    },
    /// A NaN or infinite value where a finite one is required.
    #[error("{what} {index} is not finite ({value})")]
    NotFinite {
        /// What holds the value.
        what: &'static str,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// `l_i > u_i`, a NaN bound, `l_i = +∞` or `u_i = −∞`.
    #[error("row {row} has invalid bounds l = {l}, u = {u}")]
    InvalidBounds {
        /// The row.
        row: usize,
        /// Its lower bound.
        l: f64,
        /// Its upper bound.
        u: f64,
    },
    /// `P` has an entry below the diagonal.
    #[error("P must be stored as its upper triangle; found an entry at ({row}, {col})")]
    NotUpperTriangular {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// A setting is out of its range.
    #[error("invalid setting {name} = {value}: {reason}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// The backend name is not one of [`crate::BACKEND_NAMES`] (which the message lists).
    #[error(
        "unknown backend {0:?} (expected one of {names})",
        names = crate::BACKEND_NAMES.join(", ")
    )]
    UnknownBackend(String),
    /// Warm start vectors of the wrong length.
    #[error("warm start {what} has length {found}, expected {expected}")]
    WarmStartLength {
        /// `x` or `y`.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Found length.
        found: usize,
    },
}

/// Outcome of a solve. Only `Solved` carries a solution meeting the tolerances.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QpStatus {
    /// Converged to the requested tolerances.
    Solved,
    /// Stopped at the iteration limit.
    MaxIterations,
    /// Stopped at the time limit.
    TimeLimit,
    /// Certificate (or strong evidence) of primal infeasibility.
    PrimalInfeasible,
    /// Certificate (or strong evidence) of dual infeasibility (unbounded objective).
    DualInfeasible,
    /// Factorization failure or other numerical breakdown.
    NumericalError,
}

impl QpStatus {
    /// Stable lower-case name used in CSV and JSON outputs.
    pub fn as_str(&self) -> &'static str {
        match self {
            QpStatus::Solved => "solved",
            QpStatus::MaxIterations => "max_iterations",
            QpStatus::TimeLimit => "time_limit",
            QpStatus::PrimalInfeasible => "primal_infeasible",
            QpStatus::DualInfeasible => "dual_infeasible",
            QpStatus::NumericalError => "numerical_error",
        }
    }
}

/// Settings common to every backend; each maps them onto its own parameters (documented in its
/// module).
#[derive(Clone, Debug, PartialEq)]
pub struct QpSettings {
    /// Absolute tolerance on primal and dual residuals.
    pub eps_abs: f64,
    /// Relative tolerance on primal and dual residuals.
    pub eps_rel: f64,
    /// Iteration limit.
    pub max_iter: usize,
    /// Wall-clock limit in seconds (`f64::INFINITY` for none).
    pub time_limit_s: f64,
    /// Remove zero rows and positive multiples of other rows before the solve and map the
    /// duals back ([`crate::presolve`]); applied by [`crate::backend_from_name`].
    pub presolve: bool,
}

impl Default for QpSettings {
    fn default() -> Self {
        QpSettings {
            eps_abs: 1e-9,
            eps_rel: 1e-9,
            max_iter: 100_000,
            time_limit_s: f64::INFINITY,
            presolve: true,
        }
    }
}

impl QpSettings {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), QpError> {
        if !(self.eps_abs > 0.0 && self.eps_abs.is_finite()) {
            return Err(QpError::InvalidSetting {
                name: "eps_abs",
                value: self.eps_abs.to_string(),
                reason: "must be finite and > 0",
            });
        }
        if !(self.eps_rel >= 0.0 && self.eps_rel.is_finite()) {
            return Err(QpError::InvalidSetting {
                name: "eps_rel",
                value: self.eps_rel.to_string(),
                reason: "must be finite and >= 0",
            });
        }
        if self.max_iter == 0 {
            return Err(QpError::InvalidSetting {
                name: "max_iter",
                value: "0".into(),
                reason: "must be >= 1",
            });
        }
        if self.time_limit_s.is_nan() || self.time_limit_s <= 0.0 {
            return Err(QpError::InvalidSetting {
                name: "time_limit_s",
                value: self.time_limit_s.to_string(),
                reason: "must be > 0",
            });
        }
        Ok(())
    }
}

/// Optional starting point; backends that cannot use part of it ignore that part.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WarmStart {
    /// Primal guess, length `n`.
    pub x: Vec<f64>,
    /// Dual guess (same sign convention as [`QpSolution::y`]), length `m`.
    pub y: Vec<f64>,
}

/// What a backend returns.
#[derive(Clone, Debug, PartialEq)]
pub struct QpSolution {
    /// Primal solution (the last iterate when not `Solved`), length `n`.
    pub x: Vec<f64>,
    /// Duals, length `m`: `P x + q + Aᵀ y = 0`, `y_i ≤ 0` at an active lower bound.
    pub y: Vec<f64>,
    /// Outcome.
    pub status: QpStatus,
    /// The backend's own iteration count.
    pub iterations: usize,
    /// Wall time inside the backend (setup + solve), seconds.
    pub solve_time_s: f64,
}

/// A sub-problem solver over the QP standard form. Implementations never panic on bad input or
/// non-convergence: bad input is `Err`, non-convergence a status.
pub trait QpBackend: Send {
    /// Short name (`clarabel`, `osqp`, `uzawa`).
    fn name(&self) -> &'static str;
    /// Solves `qp`, optionally from a warm start.
    fn solve(&mut self, qp: &Qp, warm: Option<&WarmStart>) -> Result<QpSolution, QpError>;
    /// The tolerance it solves to (`eps_abs`), or `None` when it has none that
    /// [`QpBackend::set_tolerance`] changes.
    fn tolerance(&self) -> Option<f64> {
        None
    }
    /// Solves the next QPs to `eps_abs = eps_rel = tol` (ignored where
    /// [`QpBackend::tolerance`] is `None`).
    fn set_tolerance(&mut self, _tol: f64) {}
    /// The QPs it did not solve and handed to another backend ([`crate::fallback`]); 0 for a
    /// backend that has none behind it.
    fn fallback_solves(&self) -> usize {
        0
    }
}
