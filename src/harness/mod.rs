//! The harness: one run of a scene and its run directory ([`run`], [`dynamic_run`]), scene
//! files loaded with the solver's rules for their `[solver]` and `[dynamics]`
//! ([`scene_file`]), a case
//! (scene × backend × preset × pruning, diagnosed: [`case`]), sweeps of cases ([`sweep`]),
//! the rows they write, one struct per kind of row ([`rows`]: where a column is added),
//! starting from a saved state ([`restart`]), the scaling experiment ([`scaling`]), the diagnostics of §5 ([`diagnostics`]), contact
//! forces, pressures, gaps, reactions and stresses of a run ([`contact_output`]) and QP
//! export ([`export`], [`capture`]).
//!
//! Errors here are reports to the user of the command line (`anyhow`), not values a caller
//! matches on; the numerical library below keeps `thiserror` enums.

pub mod capture;
pub mod case;
pub mod contact_output;
pub mod diagnostics;
pub mod dynamic_run;
pub mod export;
pub mod restart;
pub mod rows;
pub mod run;
pub mod scaling;
pub mod scene_file;
pub mod sweep;
