//! Scenes: a mesh, an energy, ε and an initial admissible configuration.

pub mod balloons;
pub mod balloons3d;
pub mod dynamic;
pub mod file;
pub mod mesh;
pub mod meshio;
pub mod registry;
pub mod ring;
pub mod rod;
pub mod sheets;
pub mod solids;

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
