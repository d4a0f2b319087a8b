//! Scenes: a mesh, an energy, ε and an initial admissible configuration.
//!
//! A scene comes from a scene file ([`mod@file`], docs/scene-files.md) or is built in: one module
//! per built-in scene (docs/scenes.md), each listed once in [`registry::SCENES`]. Both go
//! through the same two assemblers: [`assemble`] makes the mesh of their bodies, [`physics`]
//! the energy of what the bodies carry (materials, gas, pressure, densities under gravity).
//!
//! # Where to add a scene
//!
//! 1. Its module here (`src/scene/NAME.rs`, declared below): a parameter struct, a `build`
//!    returning a [`Scene`], and a unit type implementing [`registry::BuiltinScene`] (name,
//!    parameters from `NAME=VALUE`, build, default level, level for a mesh size h; optionally
//!    an end-state classification and, for a dynamic-only scene, its dynamics).
//! 2. One line in [`registry::SCENES`].
//! 3. Its documentation (docs/scenes.md).
//!
//! ```ignore
//! pub struct Wedge;
//! impl BuiltinScene for Wedge {
//!     fn name(&self) -> &'static str { "wedge" }
//!     fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Scene> {
//!         let mut p = WedgeParams { n, eps, ..Default::default() };
//!         set_fields("wedge", &mut p, params, &[("mu", |p| &mut p.mu)], &[])?;
//!         Ok(build(&p)?)
//!     }
//!     fn n_for_h(&self, h: f64, _params: &Params) -> anyhow::Result<usize> {
//!         first_level(h, 1000, |n| 1.0 / n as f64)
//!     }
//! }
//! // registry.rs: pub static SCENES: &[&dyn BuiltinScene] = &[ …, &crate::scene::wedge::Wedge ];
//! ```
//!
//! `contactlab run wedge`, `--dynamic` (density 1, zero velocity) and sweeps then know it.

pub mod assemble;
pub mod balloons;
pub mod balloons3d;
pub mod dynamic;
pub mod file;
pub mod mesh;
pub mod meshio;
pub mod physics;
pub mod registry;
pub mod ring;
pub mod rod;
pub mod sheets;
pub mod solids;
mod stacked;

use crate::energy::TotalEnergy;
use crate::scene::mesh::Mesh;

/// Everything the outer loop needs.
pub struct Scene {
    /// Scene name (`balloons`).
    pub name: String,
    /// The mesh.
    pub mesh: Mesh,
    /// The energy J.
    pub energy: TotalEnergy,
    /// Minimal distance ε between disjoint elements.
    pub eps: f64,
    /// Mesh size h.
    pub h: f64,
    /// Initial configuration φ_0 (flat).
    pub x0: Vec<f64>,
}
