//! The one energy assembler of the built-in scenes and the scene files (docs/method.md,
//! docs/scene-files.md): what each body of an assembled [`Mesh`] carries — a material, an
//! enclosed gas, a pressure load, a density — and the scene's gravity become one
//! [`TotalEnergy`]
//!
//! ```text
//! J = Σ_bodies (material + gas + pressure) + gravity,
//! ```
//!
//! its terms in that order: body by body in mesh order (each body's material, then its gas,
//! then its pressure), gravity last. The order is part of the result: [`TotalEnergy`] adds its
//! terms' values in their order, so the same description always gives the same sums, bit for
//! bit.
//!
//! A body's elements are read from the mesh, in the order the mesh assembler
//! ([`super::assemble`]) listed them: a curve's edges, a 2D solid's or a surface's triangles,
//! a 3D solid's tetrahedra. The terms, by body kind:
//!
//! | body | [`Material`] | gas `−C ln V` | pressure `p·A` |
//! |---|---|---|---|
//! | 2D curve | `String`: [`MembraneEnergy`] | [`GasEnergy`], V the area closed by the curve (or its chord) | [`PressureEnergy`] |
//! | 3D curve | `String`: [`String3dEnergy`] | — | — |
//! | surface | `StvkMembrane`: [`Membrane3dEnergy`] | [`Gas3dEnergy`], V the volume of the closed surface | — |
//! | 2D solid | `NeoHookean`: [`NeoHookean2d`] (plane strain); `NeoHookeanPlaneStress`: [`NeoHookeanPlaneStress2d`]; `LinearElastic`: [`LinearElastic2d`] (plane strain or stress) | — | — |
//! | 3D solid | `NeoHookean`: [`NeoHookean3d`]; `LinearElastic`: [`LinearElastic3d`] | — | — |
//!
//! Gravity is `−Σ_v m_v g·x_v` ([`Gravity`]) on the lumped masses of the bodies that have a
//! density ([`crate::energy::mass`], the masses of time stepping too); it is a term whenever
//! the scene has a gravity vector, even if no body has a density. Dead loads (a scene file's
//! tractions and point forces, one [`DeadLoad`]) come after gravity (docs/materials.md).
//!
//! Built-in scenes describe their bodies as a [`Physics`] and call [`assemble_energy`]. A scene
//! file checks each key where it reads it, and reports a fault with the line of that key, so
//! it drives the steps of an [`EnergyAssembler`] itself, between its checks, in the order
//! [`assemble_energy`] takes them; the construction is this module's either way.

use crate::energy::mass::add_body_mass;
use crate::energy::{
    DeadLoad, DegenerateTet, Energy, Gas3dEnergy, GasEnergy, Gravity, LinearElastic2d,
    LinearElastic3d, Membrane3dEnergy, MembraneEnergy, NeoHookean2d, NeoHookean3d,
    NeoHookeanPlaneStress2d, OpenSurface, Plane, PressureEnergy, String3dEnergy, TotalEnergy,
};
use crate::scene::file::topology::chain;
use crate::scene::mesh::{BodyKind, Mesh};
use thiserror::Error;

/// A body's elastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Tension-only string or membrane of P1 edges (curves): `W(F) = μ(|F|² − 1)²` for
    /// `|F| ≥ 1`, 0 otherwise.
    String {
        /// μ.
        mu: f64,
    },
    /// St Venant–Kirchhoff membrane of P1 triangles (3D surfaces):
    /// `W = μ|E|² + λ/2 (tr E)²`.
    StvkMembrane {
        /// μ.
        mu: f64,
        /// λ.
        lambda: f64,
    },
    /// Compressible neo-Hookean P1 simplices (2D solids in plane strain, 3D solids).
    NeoHookean {
        /// μ.
        mu: f64,
        /// λ.
        lambda: f64,
    },
    /// Compressible neo-Hookean P1 triangles in plane stress (2D solids).
    NeoHookeanPlaneStress {
        /// μ.
        mu: f64,
        /// λ (of the 3D material).
        lambda: f64,
    },
    /// Small-strain linear elasticity (2D solids in plane strain or stress, 3D solids).
    LinearElastic {
        /// μ.
        mu: f64,
        /// λ (of the 3D material).
        lambda: f64,
        /// Plane strain or stress (ignored in 3D).
        plane: Plane,
    },
}

impl Material {
    /// The material a body of `kind` takes, by its scene-file name: `string` (curves),
    /// `stvk-membrane` (surfaces), `neo-hookean` (solids).
    pub fn model_for(kind: BodyKind) -> &'static str {
        match kind {
            BodyKind::Curve => "string",
            BodyKind::Surface => "stvk-membrane",
            BodyKind::Solid => "neo-hookean",
        }
    }

    /// The material of a body of `kind` with the coefficients `mu` and `lambda` (`lambda` is
    /// not used by the string).
    pub fn of_kind(kind: BodyKind, mu: f64, lambda: f64) -> Self {
        match kind {
            BodyKind::Curve => Material::String { mu },
            BodyKind::Surface => Material::StvkMembrane { mu, lambda },
            BodyKind::Solid => Material::NeoHookean { mu, lambda },
        }
    }

    /// Its scene-file name ([`Material::model_for`]).
    pub fn model(&self) -> &'static str {
        match self {
            Material::String { .. } => "string",
            Material::StvkMembrane { .. } => "stvk-membrane",
            Material::NeoHookean { .. } | Material::NeoHookeanPlaneStress { .. } => "neo-hookean",
            Material::LinearElastic { .. } => "linear-elastic",
        }
    }

    /// Whether a body of `kind` takes it: a solid takes `neo-hookean` or `linear-elastic`,
    /// the other kinds their [`Material::model_for`].
    pub fn fits(&self, kind: BodyKind) -> bool {
        match kind {
            BodyKind::Solid => matches!(self.model(), "neo-hookean" | "linear-elastic"),
            _ => self.model() == Material::model_for(kind),
        }
    }
}

/// What one body carries; every field optional (an obstacle carries nothing).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodyPhysics {
    /// Its elastic material.
    pub material: Option<Material>,
    /// The constant C of an enclosed gas `−C ln V`.
    pub gas: Option<f64>,
    /// The pressure p of a load `p·A` (A the area the curve encloses).
    pub pressure: Option<f64>,
    /// Its density (per unit reference length, area or volume): its share of the gravity
    /// load.
    pub density: Option<f64>,
}

/// How the bodies' materials become terms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ElasticTerms {
    /// One term per body with a material (scene files, and most built-in scenes).
    #[default]
    PerBody,
    /// One term over the elements of every body with a material, in mesh order, placed where
    /// the first such body's term would be; they must share one material. The sum of one term
    /// is not bit for bit the sum of two: `solids` (with `contrast = 1`) and `collide` were
    /// measured in this form.
    Joined,
}

/// A scene's physics: one [`BodyPhysics`] per body of the mesh (same order), the gravity
/// vector (`dim` components) if any, and how materials become terms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Physics {
    /// Per body, in mesh order.
    pub bodies: Vec<BodyPhysics>,
    /// The gravitational acceleration; `None`: no gravity term.
    pub gravity: Option<Vec<f64>>,
    /// One elastic term per body, or one for all.
    pub elastic: ElasticTerms,
}

/// Why a term cannot be built from a body. The texts are the scene files' (docs/scene-files.md,
/// "Validation"), which report them with the line of the offending key.
#[derive(Debug, Error, PartialEq)]
pub enum TermError {
    /// A material that does not fit the body's kind.
    #[error(
        "a {kind} body takes model = {expected:?}, not {model:?} (models: string for curves, \
         stvk-membrane for 3D surfaces, neo-hookean or linear-elastic for solids)"
    )]
    MaterialKind {
        /// The body's kind, in lower case.
        kind: String,
        /// The model given.
        model: &'static str,
        /// The model its kind takes.
        expected: &'static str,
    },
    /// The bodies of a joined elastic term do not share one material.
    #[error("one elastic term over several bodies needs one material, got {0:?} and {1:?}")]
    JoinedMaterials(Material, Material),
    /// Plane stress asked of a 3D solid.
    #[error("plane stress is a choice of 2D solids")]
    PlaneStress3d,
    /// A reference tetrahedron of zero volume.
    #[error(transparent)]
    DegenerateTet(#[from] DegenerateTet),
    /// A gas in a body that encloses nothing.
    #[error("a gas fills a 2D curve (closed, or closed by its chord) or a closed 3D surface")]
    GasKind,
    /// A gas surface that is not closed.
    #[error(transparent)]
    OpenSurface(#[from] OpenSurface),
    /// A pressure on a body that is not a 2D curve.
    #[error("a pressure acts on a 2D curve")]
    PressureKind,
    /// A curve that is not one simple path or cycle (gas and pressure need its vertex order).
    #[error("{0}")]
    Chain(String),
}

/// The steps of the energy assembly, one term at a time, on one mesh: [`assemble_energy`]
/// takes them for a [`Physics`]; a scene file takes them between its checks.
pub struct EnergyAssembler<'a> {
    mesh: &'a Mesh,
    x0: &'a [f64],
    energy: TotalEnergy,
    /// The lumped masses of the bodies with a density, so far.
    mass: Vec<f64>,
    /// The dead loads, a term after gravity.
    dead: Option<DeadLoad>,
}

impl<'a> EnergyAssembler<'a> {
    /// An empty energy on `mesh` (reference `mesh.x_ref`); `x0` is the start, which orients
    /// gas and pressure polygons and surfaces.
    pub fn new(mesh: &'a Mesh, x0: &'a [f64]) -> Self {
        Self {
            mesh,
            x0,
            energy: TotalEnergy::default(),
            mass: vec![0.0; mesh.nv()],
            dead: None,
        }
    }

    /// The edges of body `b` (its elements if it is a curve), in mesh order.
    fn edges(&self, b: usize) -> Vec<[usize; 2]> {
        let m = self.mesh;
        m.bodies[b].edges.iter().map(|&e| m.edges[e]).collect()
    }

    /// The triangles of body `b` (its elements if it is a 2D solid or a surface).
    fn triangles(&self, b: usize) -> Vec<[usize; 3]> {
        let m = self.mesh;
        m.bodies[b]
            .triangles
            .iter()
            .map(|&t| m.triangles[t])
            .collect()
    }

    /// The elastic term of `material` over the elements of `bodies` (one body, or the bodies
    /// of a joined term: all of one kind), in that order.
    pub fn material(&mut self, bodies: &[usize], material: Material) -> Result<(), TermError> {
        let m = self.mesh;
        let kind = m.bodies[bodies[0]].kind;
        let expected = Material::model_for(kind);
        if !material.fits(kind) || bodies.iter().any(|&b| m.bodies[b].kind != kind) {
            return Err(TermError::MaterialKind {
                kind: format!("{kind:?}").to_lowercase(),
                model: material.model(),
                expected,
            });
        }
        let x_ref = &m.x_ref;
        let term: Box<dyn Energy> = match (material, kind, m.dim) {
            (Material::String { mu }, _, dim) => {
                let edges: Vec<[usize; 2]> = bodies.iter().flat_map(|&b| self.edges(b)).collect();
                if dim == 2 {
                    Box::new(MembraneEnergy::new(edges, x_ref, mu))
                } else {
                    Box::new(String3dEnergy::new(edges, x_ref, mu))
                }
            }
            (Material::StvkMembrane { mu, lambda }, _, _) => {
                let tris = bodies.iter().flat_map(|&b| self.triangles(b)).collect();
                Box::new(Membrane3dEnergy::new(tris, x_ref, mu, lambda))
            }
            (Material::NeoHookean { mu, lambda }, _, 2) => {
                let tris = bodies.iter().flat_map(|&b| self.triangles(b)).collect();
                Box::new(NeoHookean2d::new(tris, x_ref, mu, lambda))
            }
            (Material::NeoHookean { mu, lambda }, _, _) => {
                let tets = bodies
                    .iter()
                    .flat_map(|&b| m.bodies[b].tets.iter().map(|&t| m.tets[t]))
                    .collect();
                Box::new(NeoHookean3d::new(tets, x_ref, mu, lambda)?)
            }
            (Material::NeoHookeanPlaneStress { mu, lambda }, _, 2) => {
                let tris = bodies.iter().flat_map(|&b| self.triangles(b)).collect();
                Box::new(NeoHookeanPlaneStress2d::new(tris, x_ref, mu, lambda))
            }
            (Material::NeoHookeanPlaneStress { .. }, _, _) => return Err(TermError::PlaneStress3d),
            (Material::LinearElastic { mu, lambda, plane }, _, 2) => {
                let tris = bodies.iter().flat_map(|&b| self.triangles(b)).collect();
                Box::new(LinearElastic2d::new(tris, x_ref, mu, lambda, plane))
            }
            (Material::LinearElastic { mu, lambda, .. }, _, _) => {
                let tets = bodies
                    .iter()
                    .flat_map(|&b| m.bodies[b].tets.iter().map(|&t| m.tets[t]))
                    .collect();
                Box::new(LinearElastic3d::new(tets, x_ref, mu, lambda)?)
            }
        };
        self.energy.terms.push(term);
        Ok(())
    }

    /// The gas `−C ln V` of body `b` (`c` = C): V the area closed by a 2D curve (by its chord
    /// if it is open) or the volume of a closed surface, oriented so that `V(x0) ≥ 0`.
    /// Returns `V(x0)` (a scene file refuses `V(x0) ≤ 0`).
    pub fn gas(&mut self, b: usize, c: f64) -> Result<f64, TermError> {
        let (kind, dim) = (self.mesh.bodies[b].kind, self.mesh.dim);
        let (term, v0): (Box<dyn Energy>, f64) = match (kind, dim) {
            (BodyKind::Curve, 2) => {
                let polygon = chain(&self.edges(b)).map_err(TermError::Chain)?;
                let gas = GasEnergy::new(polygon, c, self.x0);
                let v0 = gas.measure(self.x0);
                (Box::new(gas), v0)
            }
            (BodyKind::Surface, 3) => {
                let gas = Gas3dEnergy::new(self.triangles(b), c, self.x0)?;
                let v0 = gas.measure(self.x0);
                (Box::new(gas), v0)
            }
            _ => return Err(TermError::GasKind),
        };
        self.energy.terms.push(term);
        Ok(v0)
    }

    /// The pressure load `p·A` of body `b`, a 2D curve, A the area it encloses (closed by its
    /// chord if it is open), counter-clockwise at `x0`.
    pub fn pressure(&mut self, b: usize, p: f64) -> Result<(), TermError> {
        if !(self.mesh.bodies[b].kind == BodyKind::Curve && self.mesh.dim == 2) {
            return Err(TermError::PressureKind);
        }
        let polygon = chain(&self.edges(b)).map_err(TermError::Chain)?;
        self.energy
            .terms
            .push(Box::new(PressureEnergy::new(polygon, p, self.x0)));
        Ok(())
    }

    /// Body `b`'s lumped masses of density `rho`, added to the gravity load.
    pub fn load(&mut self, b: usize, rho: f64) {
        add_body_mass(&mut self.mass, self.mesh, &self.mesh.x_ref, b, rho);
    }

    /// The dead loads (tractions, pressures, point forces), a term after gravity.
    pub fn dead_load(&mut self, load: DeadLoad) {
        self.dead = Some(load);
    }

    /// The energy: the terms so far, then gravity `g` (`dim` components) on the masses
    /// loaded, if given, then the dead loads, if any.
    pub fn finish(mut self, gravity: Option<&[f64]>) -> TotalEnergy {
        if let Some(g) = gravity {
            let term: Box<dyn Energy> = if self.mesh.dim == 3 {
                Box::new(Gravity::new(self.mass, [g[0], g[1], g[2]]))
            } else {
                Box::new(Gravity::new(self.mass, [g[0], g[1]]))
            };
            self.energy.terms.push(term);
        }
        if let Some(load) = self.dead {
            self.energy.terms.push(Box::new(load));
        }
        self.energy
    }
}

/// The energy of `physics` on `mesh` (start `x0`): for each body in mesh order its material,
/// gas, pressure and density, then gravity (module docs).
pub fn assemble_energy(
    mesh: &Mesh,
    x0: &[f64],
    physics: &Physics,
) -> Result<TotalEnergy, TermError> {
    debug_assert_eq!(physics.bodies.len(), mesh.bodies.len());
    let mut a = EnergyAssembler::new(mesh, x0);
    let with_material: Vec<usize> = (0..physics.bodies.len())
        .filter(|&b| physics.bodies[b].material.is_some())
        .collect();
    for (b, body) in physics.bodies.iter().enumerate() {
        if let Some(m) = body.material {
            match physics.elastic {
                ElasticTerms::PerBody => a.material(&[b], m)?,
                ElasticTerms::Joined if b == with_material[0] => {
                    let materials = with_material
                        .iter()
                        .filter_map(|&o| physics.bodies[o].material);
                    if let Some(other) = materials.into_iter().find(|&o| o != m) {
                        return Err(TermError::JoinedMaterials(m, other));
                    }
                    a.material(&with_material, m)?;
                }
                ElasticTerms::Joined => {}
            }
        }
        if let Some(c) = body.gas {
            a.gas(b, c)?;
        }
        if let Some(p) = body.pressure {
            a.pressure(b, p)?;
        }
        if let Some(rho) = body.density {
            a.load(b, rho);
        }
    }
    Ok(a.finish(physics.gravity.as_deref()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::mass::lumped_mass;
    use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};

    fn part(kind: BodyKind, vertices: Vec<usize>, elements: &[&[usize]]) -> BodyPart {
        let arity = elements[0].len();
        BodyPart {
            name: format!("{kind:?}"),
            kind,
            vertices,
            elements: elements
                .iter()
                .map(|e| std::array::from_fn(|k| e.get(k).copied().unwrap_or(0)))
                .collect(),
            arity,
            ..Default::default()
        }
    }

    /// 2D: body 0 a tilted closed curve of four edges (vertices 0–3), body 1 a solid of two
    /// triangles (vertices 4–7), body 2 a "Y" of three edges (vertices 8–11).
    fn mesh_2d() -> Mesh {
        let x = vec![
            0.0, 0.0, 1.0, 0.3, 1.2, 1.1, 0.1, 0.9, // curve
            3.0, 0.0, 4.0, 0.1, 4.1, 1.0, 3.1, 0.9, // solid
            6.0, 0.0, 6.0, 1.0, 5.0, 2.0, 7.0, 2.0, // Y
        ];
        let parts = [
            part(
                BodyKind::Curve,
                (0..4).collect(),
                &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
            ),
            part(BodyKind::Solid, (4..8).collect(), &[&[4, 5, 6], &[4, 6, 7]]),
            part(
                BodyKind::Curve,
                (8..12).collect(),
                &[&[8, 9], &[9, 10], &[9, 11]],
            ),
        ];
        assemble_mesh(2, x, vec![false; 12], &parts, &file_order(3))
    }

    fn names(e: &TotalEnergy) -> Vec<&str> {
        e.terms.iter().map(|t| t.name()).collect()
    }

    #[test]
    fn physics_terms_in_order_body_by_body_gravity_last() {
        let mesh = mesh_2d();
        let x0 = mesh.x_ref.clone();
        let physics = Physics {
            bodies: vec![
                BodyPhysics {
                    material: Some(Material::String { mu: 1.0 }),
                    gas: Some(2.0),
                    pressure: Some(0.5),
                    density: Some(1.3),
                },
                BodyPhysics {
                    material: Some(Material::NeoHookean {
                        mu: 1.0,
                        lambda: 2.0,
                    }),
                    density: Some(0.7),
                    ..Default::default()
                },
                BodyPhysics::default(),
            ],
            gravity: Some(vec![0.0, -1.0]),
            elastic: ElasticTerms::PerBody,
        };
        let e = assemble_energy(&mesh, &x0, &physics).unwrap();
        assert_eq!(
            names(&e),
            ["membrane", "gas", "pressure", "neo_hookean", "gravity"]
        );
        assert!(e.value(&x0).is_finite());
        // without gravity, no gravity term; densities alone add nothing
        let none = Physics {
            gravity: None,
            ..physics.clone()
        };
        let e = assemble_energy(&mesh, &x0, &none).unwrap();
        assert_eq!(names(&e), ["membrane", "gas", "pressure", "neo_hookean"]);
    }

    #[test]
    fn physics_gravity_masses_are_the_lumped_masses_of_time_stepping() {
        // gravity (0, −1): the y entries of ∇J are the masses themselves, bit for bit; on a
        // tilted curve and a solid they are lumped_mass's (the masses of a time step)
        let mesh = mesh_2d();
        let x0 = mesh.x_ref.clone();
        let density = [1.3, 0.7, 0.0];
        let physics = Physics {
            bodies: density
                .iter()
                .map(|&rho| BodyPhysics {
                    density: Some(rho),
                    ..Default::default()
                })
                .collect(),
            gravity: Some(vec![0.0, -1.0]),
            ..Default::default()
        };
        let e = assemble_energy(&mesh, &x0, &physics).unwrap();
        assert_eq!(names(&e), ["gravity"]);
        let g = e.gradient(&x0);
        let m = lumped_mass(&mesh, &mesh.x_ref, &density).unwrap();
        for v in 0..mesh.nv() {
            assert_eq!(g[2 * v + 1].to_bits(), m[v].to_bits(), "vertex {v}");
            assert_eq!(g[2 * v], 0.0);
        }
        assert!(m[1] > 0.0 && m[5] > 0.0);
    }

    #[test]
    fn physics_joined_elastic_term_is_one_term() {
        let mesh = mesh_2d();
        let x0 = mesh.x_ref.clone();
        let string = |mu| BodyPhysics {
            material: Some(Material::String { mu }),
            ..Default::default()
        };
        let mut physics = Physics {
            bodies: vec![string(1.0), BodyPhysics::default(), string(1.0)],
            gravity: None,
            elastic: ElasticTerms::Joined,
        };
        let joined = assemble_energy(&mesh, &x0, &physics).unwrap();
        assert_eq!(names(&joined), ["membrane"]);
        physics.elastic = ElasticTerms::PerBody;
        let per_body = assemble_energy(&mesh, &x0, &physics).unwrap();
        assert_eq!(names(&per_body), ["membrane", "membrane"]);
        // the same energy, summed in another order
        let mut x = x0.clone();
        x[2] += 0.4;
        x[18] += 0.3;
        let (j, p) = (joined.value(&x), per_body.value(&x));
        assert!(j > 0.0 && (j - p).abs() <= 1e-14 * j, "{j} {p}");
        physics.elastic = ElasticTerms::Joined;
        physics.bodies[2] = string(2.0);
        let e = assemble_energy(&mesh, &x0, &physics).err();
        assert_eq!(
            e,
            Some(TermError::JoinedMaterials(
                Material::String { mu: 1.0 },
                Material::String { mu: 2.0 }
            ))
        );
    }

    #[test]
    fn physics_refuses_terms_a_body_cannot_carry() {
        let mesh = mesh_2d();
        let x0 = mesh.x_ref.clone();
        let mut a = EnergyAssembler::new(&mesh, &x0);
        assert_eq!(a.gas(1, 1.0), Err(TermError::GasKind));
        assert_eq!(a.pressure(1, 1.0), Err(TermError::PressureKind));
        let e = a.gas(2, 1.0).unwrap_err().to_string();
        assert!(e.contains("vertex 9 has 3 neighbours"), "{e}");
        let e = a.pressure(2, 1.0).unwrap_err().to_string();
        assert!(e.contains("vertex 9 has 3 neighbours"), "{e}");
        let e = a.material(&[1], Material::String { mu: 1.0 }).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a solid body takes model = \"neo-hookean\", not \"string\" (models: string for \
             curves, stvk-membrane for 3D surfaces, neo-hookean or linear-elastic for solids)"
        );
        assert!(a.finish(None).terms.is_empty());
    }

    #[test]
    fn physics_3d_surface_gas_and_solid_tets() {
        // a closed tetrahedral surface (vertices 0–3), a solid of one flat tet (4–7), an open
        // surface (8–11)
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, // surface
            3.0, 0.0, 0.0, 4.0, 0.0, 0.0, 3.0, 1.0, 0.0, 4.0, 1.0, 0.0, // flat tet
            6.0, 0.0, 0.0, 7.0, 0.0, 0.0, 6.0, 1.0, 0.0, 6.0, 0.0, 1.0, // open surface
        ];
        let parts = [
            part(
                BodyKind::Surface,
                (0..4).collect(),
                &[&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]],
            ),
            part(BodyKind::Solid, (4..8).collect(), &[&[4, 5, 6, 7]]),
            part(
                BodyKind::Surface,
                (8..12).collect(),
                &[&[8, 10, 9], &[8, 9, 11], &[8, 11, 10]],
            ),
        ];
        let mesh = assemble_mesh(3, x, vec![false; 12], &parts, &file_order(3));
        let x0 = mesh.x_ref.clone();
        let balloon = BodyPhysics {
            material: Some(Material::StvkMembrane {
                mu: 1.0,
                lambda: 1.0,
            }),
            gas: Some(1.0),
            density: Some(2.0),
            ..Default::default()
        };
        let physics = Physics {
            bodies: vec![balloon, BodyPhysics::default(), BodyPhysics::default()],
            gravity: Some(vec![0.0, 0.0, -1.0]),
            ..Default::default()
        };
        let e = assemble_energy(&mesh, &x0, &physics).unwrap();
        assert_eq!(names(&e), ["membrane3d", "gas3d", "gravity3d"]);
        let mut a = EnergyAssembler::new(&mesh, &x0);
        let v0 = a.gas(0, 1.0).unwrap();
        assert!((v0 - 1.0 / 6.0).abs() < 1e-15, "{v0}");
        let neo = Material::NeoHookean {
            mu: 1.0,
            lambda: 1.0,
        };
        assert!(matches!(
            a.material(&[1], neo),
            Err(TermError::DegenerateTet(DegenerateTet { index: 0, .. }))
        ));
        assert_eq!(a.pressure(0, 1.0), Err(TermError::PressureKind));
        assert!(matches!(a.gas(2, 1.0), Err(TermError::OpenSurface(_))));
    }
}
