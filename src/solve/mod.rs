//! Solving: the sub-problem `min J over T(ψ)` by Newton-type steps and a QP backend
//! ([`subproblem`]), the outer loop of §3 ([`outer`]), time stepping of §6 ([`dynamics`]) and
//! the accuracy presets ([`settings`]); both loops report to [`observer`]s. [`h1`] is the H¹
//! Gram matrix of the reference mesh and its dual norm H⁻¹.

pub mod dynamics;
pub mod h1;
pub mod observer;
pub mod outer;
pub mod settings;
pub mod subproblem;
