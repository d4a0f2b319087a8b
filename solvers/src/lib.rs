//! QP standard form, the backend trait and the sub-problem backends of contactlab.
//!
//! Every backend solves the same problem
//!
//! ```text
//!     min ½ xᵀ P x + qᵀ x    s.t.  l ≤ A x ≤ u
//! ```
//!
//! with `P` symmetric positive semi-definite (stored as its upper triangle, CSC), `A` in CSC,
//! `l_i ∈ [-∞, ∞)`, `u_i ∈ (-∞, ∞]`, `l_i ≤ u_i` (`l_i = u_i` is an equality row).
//!
//! **Dual sign convention** (the OSQP one, shared by every backend): the returned `y` satisfies
//! stationarity `P x + q + Aᵀ y = 0`, with `y_i ≤ 0` when the lower bound of row `i` is active,
//! `y_i ≥ 0` when the upper bound is active and `y_i = 0` on inactive rows. A contact row
//! `n·(φ(a_i) − φ(x)) ≥ ε` is a lower bound, so its multiplier is `−y_i ≥ 0`.
//!
//! The core library never imports a backend: it talks to [`QpBackend`] only, and picks one by
//! name with [`backend_from_name`] from the one list of backends, [`registry`] (names,
//! constructors, default settings, preset tolerances). Sparse linear algebra that is not a
//! backend (the `LDLᵀ` factorization) lives in [`linalg`], which the core may use.
//!
//! **Adding a backend** touches three files: its module, its `mod` line below, and its entry
//! in [`registry::BACKENDS`] (example in [`registry`]).
#![warn(missing_docs)]
// Index loops over several parallel arrays are the clearest form for the sparse kernels here.
#![allow(clippy::needless_range_loop)]

pub mod active_set;
pub mod backend;
pub mod clarabel_backend;
pub mod fallback;
pub mod hash;
pub mod ipm;
pub mod linalg;
pub mod osqp_backend;
pub mod presolve;
pub mod qp;
pub mod qps;
pub mod registry;
pub mod uzawa;

pub use backend::{QpBackend, QpError, QpSettings, QpSolution, QpStatus, WarmStart};
pub use qp::{CscMatrix, Qp};
pub use qps::{read_qps, read_qps_file, write_qps, write_qps_file, QpsError};
pub use registry::{
    backend_from_name, default_settings, preset_tolerances, PresetTolerances, BACKEND_NAMES,
    CERTIFICATE_BACKEND, CERTIFICATE_TOL, DEFAULT_BACKEND, REFERENCE_BACKEND,
};
