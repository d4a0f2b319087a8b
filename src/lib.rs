//! contactlab: Pantz's (2008) frictionless contact algorithm for deformable bodies, and a
//! harness that measures it.
//!
//! Data flows one way:
//!
//! ```text
//! scene (mesh + energy + ε) → pair search → rows of T(ψ) → QP (standard form)
//!   → backend (Uzawa | Clarabel | OSQP) → line search / outer loop → diagnostics → CSV / VTK / SVG
//! ```
//!
//! The outer loop of §3 minimizes the energy `J` over the convex polyhedron `T(ψ)` built from
//! linearized non-intersection rows (eq. 4 in 2D); by Lemma 4.2 every iterate stays in
//! `A_{h,ε}`. The library never imports a QP backend: it receives a
//! `&mut dyn contactlab_solvers::QpBackend`.
#![warn(missing_docs)]

pub mod broad_phase;
pub mod bvh;
pub mod capture;
pub mod contact;
pub mod diagnostics;
pub mod dynamics;
pub mod energy;
pub mod geometry;
pub mod mesh;
pub mod meshio;
pub mod outer;
pub mod output;
pub mod pairs;
pub mod presets;
pub mod rows;
pub mod rows3d;
pub mod scene;
pub mod scenefile;
pub mod subproblem;

pub use contactlab_solvers as solvers;
