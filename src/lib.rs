//! contactlab: Pantz's (2008) frictionless contact algorithm for deformable bodies, and a
//! harness that measures it.
//!
//! Data flows one way, and the modules follow it:
//!
//! ```text
//! scene (mesh + energy + ε) → contact: pairs, rows of T(ψ), exact check → solve: QP, backend
//!   (Uzawa | Clarabel | OSQP), line search, outer loop, time stepping → harness: cases,
//!   sweeps, diagnostics → output: CSV / VTK / SVG
//! ```
//!
//! - [`scene`]: meshes, mesh files, scene files and the built-in scenes;
//! - [`contact`]: the pairs (`point_edge`, `point_triangle`, `edge_edge`), their distance
//!   kernels, the rows of T(ψ) (eq. 4 in 2D, eq. 6 in 3D), the broad phase and the exact
//!   admissibility check;
//! - [`energy`]: the energies J with gradients and sparse Hessians;
//! - [`solve`]: the sub-problem min J over T(ψ), the outer loop of §3, time stepping (§6),
//!   settings and presets;
//! - [`harness`]: runs, cases, sweeps, the diagnostics of §5, QP export;
//! - [`output`]: VTK, SVG and plots.
//!
//! The outer loop of §3 minimizes the energy `J` over the convex polyhedron `T(ψ)` built from
//! linearized non-intersection rows; by Lemma 4.2 every iterate stays in `A_{h,ε}`. The library
//! never imports a QP backend: it receives a `&mut dyn contactlab_solvers::QpBackend`.
#![warn(missing_docs)]

pub mod contact;
pub mod energy;
pub mod harness;
pub mod output;
pub mod scene;
pub mod solve;

pub use contactlab_solvers as solvers;
