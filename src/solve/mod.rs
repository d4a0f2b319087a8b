//! Solving: the sub-problem `min J over T(ψ)` by Newton-type steps and a QP backend
//! ([`subproblem`]), the outer loop of §3 ([`outer`]) with its stopping rule and the
//! minimality certificate that classifies where it stops ([`certificate`], measured in the
//! H⁻¹ norm of [`h1`]), time stepping of §6 ([`dynamics`]) and the accuracy presets
//! ([`settings`]); both loops report to [`observer`]s. The sub-problem hands its QPs to the
//! backend in the run's own units ([`qp_units`]).

pub mod certificate;
pub mod dynamics;
pub mod h1;
pub mod observer;
pub mod outer;
pub mod qp_units;
pub mod second_order;
pub mod settings;
pub mod sqp;
pub mod subproblem;
