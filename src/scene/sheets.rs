//! Two sheets: an upper membrane pressed by its weight onto a lower one (3D contact between
//! two surfaces: vertex–triangle AND edge–edge pairs together).
//!
//! **Geometry.** Two square St Venant–Kirchhoff membranes ([`crate::energy::Membrane3dEnergy`]), each an
//! `m × m` grid of squares (`m = 4n`), every square cut by the diagonal from its low-x low-y
//! corner into two triangles; every triangle is a contact face, every grid edge and diagonal a
//! contact edge (`BodyKind::Surface`).
//!
//! * `lower` (body 0): in `x0` the square `[-1, 1]² × {0}`, its boundary vertices fixed; its
//!   reference is the same square shrunk by `1/stretch_lower`, so the pinned sheet is
//!   pre-tensioned (uniform in-plane stretch `stretch_lower`). With `lower_fixed = true` all of
//!   its vertices are fixed (an obstacle) and it carries no energy.
//! * `upper` (body 1): in `x0` the square `[-a, a]²` (`a = half_size`) rotated by `angle_deg`
//!   (default 30°) about the z axis, at height `z = gap`, its boundary vertices fixed; its
//!   reference is the same square shrunk by `1/stretch_upper`. The rotation makes its edges
//!   cross the lower sheet's edges (no parallel pairs: the lower edges run at 0°, 90°, 45°,
//!   the upper ones at 30°, 120°, 75°). The rotated square must project inside the lower one
//!   (`a (|cos θ| + |sin θ|) < 1`), so the upper sheet's pinned boundary lies above the lower
//!   sheet's interior.
//!
//! **Energy.** `J = Σ_sheets Σ_T |T_ref| W(F_T) + weight · Σ_{v ∈ upper} m_v z_v`, the StVK
//! membrane `W = μ|E|² + λ/2 (tr E)²` on both sheets and gravity ([`crate::energy::Gravity`], lumped
//! masses, `weight` = ρg per unit REFERENCE area, pointing to −z) on the upper sheet only.
//! The pre-tension gives both sheets an out-of-plane stiffness at `x0` (a flat unstretched
//! membrane has none: its Hessian would be singular in z and the linearized problem unbounded
//! under gravity).
//!
//! **Defaults.** `n = 2` (`m = 8`: 162 vertices, 416 edges, 256 faces), `μ = 1`, `λ = 1`,
//! `weight = 0.1`, `gap = 0.05`, `half_size = 0.7`, `angle_deg = 30`, `stretch_lower = 1.1`,
//! `stretch_upper = 1.05`, `lower_fixed = false`; `h` = the largest reference edge (the lower
//! sheet's diagonal `2√2 / (m · stretch_lower)` ≈ 0.32), `ε = min(h/10, gap/2)` = 0.025.
//!
//! **At the minimum.** Without contact the lower sheet would stay flat at `z = 0` (it carries
//! no load) and the upper one would sag under its weight (linear estimate
//! `0.074 · weight · (2a)² / T ≈ 0.07` at its centre, `T ≈ (μ + λ)(s² − 1) ≈ 0.2` the
//! pre-tension; the stretching stiffens it): the unconstrained equilibrium of the defaults,
//! computed by Newton's method without contact, has the upper sheet's centre at `z ≈ −0.008`,
//! through the lower sheet (with `weight = 0.3`: `z ≈ −0.083`, 45 of its 49 free vertices
//! below the lower sheet). So at the constrained minimum the upper sheet rests on the lower
//! one over a central region at distance `ε`, the lower sheet carrying part of the weight (it
//! deflects downward too): vertex–triangle rows (vertices of either sheet against triangles of
//! the other) and edge–edge rows (crossing edges) are active together. Every free vertex has a fixed boundary and the sheets are in tension, so there is
//! no zero-energy motion.
//!
//! Why `weight = 0.1`: heavier loads press a larger region but bend the deformable lower sheet
//! more, and the outer loop then creeps (measured with Clarabel at its default settings,
//! `weight = 0.3`: `J` still falling by `ΔJ/J ≈ 6·10⁻⁹` per step after 3000 steps; the
//! defaults converge in 60 steps). With `lower_fixed = true` (a flat obstacle) it converges in
//! 2 steps even at `weight = 0.3`.

use super::stacked::{self, Block, StackError};
use super::Scene;
use crate::scene::mesh::{BodyKind, MeshError};
use crate::scene::physics::{assemble_energy, BodyPhysics, Material, Physics, TermError};
use crate::scene::registry::{set_fields, LevelScene, Params};
use thiserror::Error;

/// Parameters of the sheets scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SheetsParams {
    /// Mesh level: each sheet is a `4n × 4n` grid of squares (n ≥ 1).
    pub n: usize,
    /// ε; `None` means `min(h/10, gap/2)`.
    pub eps: Option<f64>,
    /// Shear modulus μ of both membranes (per unit reference area).
    pub mu: f64,
    /// 2D Lamé coefficient λ of both membranes (≥ 0).
    pub lambda: f64,
    /// Weight ρg of the upper sheet per unit reference area (gravity along −z).
    pub weight: f64,
    /// Height of the upper sheet above the lower one in `x0`.
    pub gap: f64,
    /// Half side `a` of the upper sheet in `x0` (the lower one has half side 1).
    pub half_size: f64,
    /// Rotation of the upper sheet about z, in degrees.
    pub angle_deg: f64,
    /// Pre-stretch of the lower sheet (`x0` side / reference side), > 1.
    pub stretch_lower: f64,
    /// Pre-stretch of the upper sheet (`x0` side / reference side), > 1.
    pub stretch_upper: f64,
    /// Fix every vertex of the lower sheet (a rigid obstacle) instead of its boundary only.
    pub lower_fixed: bool,
}

impl Default for SheetsParams {
    fn default() -> Self {
        SheetsParams {
            n: 2,
            eps: None,
            mu: 1.0,
            lambda: 1.0,
            weight: 0.1,
            gap: 0.05,
            half_size: 0.7,
            angle_deg: 30.0,
            stretch_lower: 1.1,
            stretch_upper: 1.05,
            lower_fixed: false,
        }
    }
}

/// A parameter out of range, or a start that is not admissible; names the parameter.
#[derive(Debug, Error, PartialEq)]
pub enum SheetsError {
    /// The parameter and why it is rejected.
    #[error("sheets: invalid {name} = {value}: {reason}")]
    Invalid {
        /// Parameter name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// Why.
        reason: String,
    },
    /// Two disjoint contact elements of `x0` are closer than ε.
    #[error(
        "sheets: the initial configuration is not admissible: {pair} at distance \
         {distance:.6e} < eps = {eps:.6e}; increase gap or lower eps"
    )]
    InadmissibleStart {
        /// The closest pair, printed.
        pair: String,
        /// Its distance.
        distance: f64,
        /// ε.
        eps: f64,
    },
    /// The generated mesh is invalid (a bug, or parameters that degenerate it).
    #[error("sheets: invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    /// An energy term that cannot be built.
    #[error("sheets: {0}")]
    Energy(#[from] TermError),
}

impl From<StackError> for SheetsError {
    fn from(e: StackError) -> Self {
        match e {
            StackError::Mesh(e) => SheetsError::Mesh(e),
            StackError::InadmissibleStart {
                pair,
                distance,
                eps,
            } => SheetsError::InadmissibleStart {
                pair,
                distance,
                eps,
            },
        }
    }
}

/// Grid squares per side of each sheet at level `n`.
pub fn cells(n: usize) -> usize {
    4 * n
}

/// `h`: the largest reference edge, the lower sheet's diagonal `2√2 / (4n · stretch_lower)`.
pub fn mesh_size(p: &SheetsParams) -> f64 {
    let lower = 2.0 * std::f64::consts::SQRT_2 / (cells(p.n) as f64 * p.stretch_lower);
    let upper =
        2.0 * p.half_size * std::f64::consts::SQRT_2 / (cells(p.n) as f64 * p.stretch_upper);
    lower.max(upper)
}

fn finite_positive(name: &'static str, v: f64) -> Result<(), SheetsError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(SheetsError::Invalid {
            name,
            value: v.to_string(),
            reason: "must be finite and > 0".into(),
        })
    }
}

impl SheetsParams {
    /// Checks every parameter (not the admissibility of the start: [`build`] does that).
    pub fn validate(&self) -> Result<(), SheetsError> {
        let bad = |name, value: String, reason: &str| {
            Err(SheetsError::Invalid {
                name,
                value,
                reason: reason.into(),
            })
        };
        if self.n == 0 || self.n > 1000 {
            return bad("n", self.n.to_string(), "must be in 1..=1000");
        }
        if let Some(e) = self.eps {
            finite_positive("eps", e)?;
        }
        finite_positive("mu", self.mu)?;
        if !(self.lambda >= 0.0 && self.lambda.is_finite()) {
            return bad("lambda", self.lambda.to_string(), "must be finite and ≥ 0");
        }
        finite_positive("weight", self.weight)?;
        finite_positive("gap", self.gap)?;
        finite_positive("half_size", self.half_size)?;
        if !self.angle_deg.is_finite() {
            return bad("angle_deg", self.angle_deg.to_string(), "must be finite");
        }
        if stacked::rotated_extent(self.half_size, self.angle_deg) >= 1.0 {
            return bad(
                "half_size",
                self.half_size.to_string(),
                "the rotated upper square must project inside the lower one \
                 (half_size · (|cos θ| + |sin θ|) < 1)",
            );
        }
        for (name, v) in [
            ("stretch_lower", self.stretch_lower),
            ("stretch_upper", self.stretch_upper),
        ] {
            if !(v > 1.0 && v < 2.0) {
                return bad(
                    name,
                    v.to_string(),
                    "must be in (1, 2): the pinned sheet must be in tension",
                );
            }
        }
        Ok(())
    }
}

/// The edges of a triangle list, each once, as sorted vertex pairs in increasing order.
pub fn unique_edges(triangles: &[[usize; 3]]) -> Vec<[usize; 2]> {
    let mut edges: Vec<[usize; 2]> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// A `m × m` grid on `[-1, 1]²`: the points (row-major, `j·(m+1) + i` at
/// `(-1 + 2i/m, -1 + 2j/m)`), the triangles (counter-clockwise seen from +z, local indices)
/// and whether each point is on the boundary.
fn unit_grid(m: usize) -> (Vec<[f64; 2]>, Vec<[usize; 3]>, Vec<bool>) {
    let mut pts = Vec::with_capacity((m + 1) * (m + 1));
    let mut boundary = Vec::with_capacity((m + 1) * (m + 1));
    for j in 0..=m {
        for i in 0..=m {
            pts.push([
                -1.0 + 2.0 * i as f64 / m as f64,
                -1.0 + 2.0 * j as f64 / m as f64,
            ]);
            boundary.push(i == 0 || j == 0 || i == m || j == m);
        }
    }
    let mut tris = Vec::with_capacity(2 * m * m);
    for j in 0..m {
        for i in 0..m {
            let v = j * (m + 1) + i;
            tris.push([v, v + 1, v + m + 2]);
            tris.push([v, v + m + 2, v + m + 1]);
        }
    }
    (pts, tris, boundary)
}

/// Builds the scene (name `sheets`). Vertices: the lower sheet's `(m+1)²` then the upper
/// sheet's, each row-major; triangles, faces and edges: the lower sheet's then the upper's.
pub fn build(p: &SheetsParams) -> Result<Scene, SheetsError> {
    p.validate()?;
    let m = cells(p.n);
    let h = mesh_size(p);
    let eps = p.eps.unwrap_or((h / 10.0).min(0.5 * p.gap));
    let (pts, grid_tris, boundary) = unit_grid(m);
    let np = pts.len();
    let sc = stacked::sin_cos(p.angle_deg);
    let mut x_ref = Vec::with_capacity(6 * np);
    let mut x0 = Vec::with_capacity(6 * np);
    let mut fixed = Vec::with_capacity(2 * np);
    for (k, q) in pts.iter().enumerate() {
        x_ref.extend_from_slice(&[q[0] / p.stretch_lower, q[1] / p.stretch_lower, 0.0]);
        x0.extend_from_slice(&[q[0], q[1], 0.0]);
        fixed.push(p.lower_fixed || boundary[k]);
    }
    for (k, q) in pts.iter().enumerate() {
        let (u, v) = (p.half_size * q[0], p.half_size * q[1]);
        let (rx, ry) = stacked::rotate_z(sc, u, v);
        x_ref.extend_from_slice(&[rx / p.stretch_upper, ry / p.stretch_upper, p.gap]);
        x0.extend_from_slice(&[rx, ry, p.gap]);
        fixed.push(boundary[k]);
    }
    let lower_tris = grid_tris.clone();
    let upper_tris: Vec<[usize; 3]> = grid_tris.iter().map(|t| t.map(|v| v + np)).collect();
    let sq2 = std::f64::consts::SQRT_2;
    let block = |tris: &[[usize; 3]], h: f64| Block {
        elements: tris.iter().map(|t| [t[0], t[1], t[2], 0]).collect(),
        h,
        faces: None,
    };
    let blocks = [
        block(&lower_tris, 2.0 * sq2 / (m as f64 * p.stretch_lower)),
        block(
            &upper_tris,
            2.0 * p.half_size * sq2 / (m as f64 * p.stretch_upper),
        ),
    ];
    let mesh = stacked::assemble(BodyKind::Surface, 3, np, blocks, x_ref, fixed, &x0, eps)?;
    // both membranes (the lower one only when it deforms), then gravity on the upper one's
    // weight per unit area along −z
    let membrane = Material::StvkMembrane {
        mu: p.mu,
        lambda: p.lambda,
    };
    let physics = Physics {
        bodies: vec![
            BodyPhysics {
                material: (!p.lower_fixed).then_some(membrane),
                ..Default::default()
            },
            BodyPhysics {
                material: Some(membrane),
                density: Some(p.weight),
                ..Default::default()
            },
        ],
        gravity: Some(vec![0.0, 0.0, -1.0]),
        ..Default::default()
    };
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    Ok(Scene {
        name: "sheets".into(),
        mesh,
        energy,
        eps,
        h,
        x0,
    })
}

/// The `sheets` scene in the scene registry: its parameters are the numeric fields of
/// [`SheetsParams`]; the level for a mesh size h is the smallest whose [`mesh_size`] is at most h.
pub struct Sheets;

impl LevelScene for Sheets {
    type P = SheetsParams;
    const NAME: &'static str = "sheets";
    const MAX_LEVEL: usize = 1000;

    fn params(n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<SheetsParams> {
        let mut p = SheetsParams {
            n,
            eps,
            ..Default::default()
        };
        set_fields(
            "sheets",
            &mut p,
            params,
            &[
                ("mu", |p| &mut p.mu),
                ("lambda", |p| &mut p.lambda),
                ("weight", |p| &mut p.weight),
                ("gap", |p| &mut p.gap),
                ("half_size", |p| &mut p.half_size),
                ("angle_deg", |p| &mut p.angle_deg),
                ("stretch_lower", |p| &mut p.stretch_lower),
                ("stretch_upper", |p| &mut p.stretch_upper),
            ],
            &[("lower_fixed", |p| &mut p.lower_fixed)],
        )?;
        Ok(p)
    }

    fn level(p: &SheetsParams) -> usize {
        p.n
    }

    fn at_level(p: &SheetsParams, n: usize) -> SheetsParams {
        SheetsParams { n, ..p.clone() }
    }

    fn build_scene(p: &SheetsParams) -> anyhow::Result<Scene> {
        Ok(build(p)?)
    }

    fn mesh_size(p: &SheetsParams) -> f64 {
        mesh_size(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::broad_phase::min_distance_3d;

    #[test]
    fn sheets_default_mesh_counts_and_admissibility() {
        let s = build(&SheetsParams::default()).unwrap();
        let m = &s.mesh;
        assert_eq!(s.name, "sheets");
        assert_eq!(m.validate(), Ok(()));
        // two 8×8 grids: 81 vertices, 8·9·2 + 64 = 208 edges, 128 triangles each
        assert_eq!(m.nv(), 162);
        assert_eq!(m.edges.len(), 416);
        assert_eq!(m.faces.len(), 256);
        assert_eq!(m.triangles, m.faces);
        assert_eq!(m.contact_vertices().len(), 162);
        // fixed: the two boundaries (32 vertices each)
        assert_eq!(m.fixed.iter().filter(|&&f| f).count(), 64);
        // h, ε
        let h = 2.0 * std::f64::consts::SQRT_2 / (8.0 * 1.1);
        assert!((s.h - h).abs() < 1e-15);
        assert!(h / 10.0 > 0.025);
        assert_eq!(s.eps, 0.025); // gap/2 < h/10
                                  // admissible: the closest pair is between the sheets, at the gap
        let (d, _) = min_distance_3d(m, &s.x0, s.eps);
        assert!(d >= s.eps, "{d}");
        assert!((d - 0.05).abs() < 1e-12, "{d}");
        // J(x0) finite; the membranes are stretched: positive elastic energy, below weight·z
        let j = s.energy.value(&s.x0);
        assert!(j.is_finite() && j > 0.0, "{j}");
        // bodies
        assert_eq!(m.bodies.len(), 2);
        for (b, body) in m.bodies.iter().enumerate() {
            assert_eq!(body.kind, BodyKind::Surface);
            assert_eq!(body.faces.len(), 128);
            assert_eq!(body.edges.len(), 208);
            assert!(body.faces.iter().all(|&f| m.face_body[f] == b));
            assert!(body.edges.iter().all(|&e| m.edge_body[e] == b));
        }
    }

    #[test]
    fn sheets_contact_edges_listed_once_and_complete() {
        let s = build(&SheetsParams {
            n: 1,
            ..Default::default()
        })
        .unwrap();
        let m = &s.mesh;
        let mut sorted: Vec<[usize; 2]> = m
            .edges
            .iter()
            .map(|e| [e[0].min(e[1]), e[0].max(e[1])])
            .collect();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), m.edges.len());
        assert_eq!(sorted, unique_edges(&m.faces));
    }

    #[test]
    fn sheets_gradient_pulls_the_upper_sheet_down() {
        // at x0 the lower sheet is in equilibrium (uniform stretch) and gravity pulls the
        // free vertices of the upper sheet down
        let s = build(&SheetsParams::default()).unwrap();
        let g = s.energy.gradient(&s.x0);
        let np = 81;
        for v in 0..2 * np {
            if s.mesh.fixed[v] {
                continue;
            }
            if v < np {
                assert!(g[3 * v..3 * v + 3].iter().all(|x| x.abs() < 1e-12));
            } else {
                assert!(g[3 * v + 2] > 0.0);
            }
        }
    }

    #[test]
    fn sheets_obstacle_variant() {
        let s = build(&SheetsParams {
            lower_fixed: true,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(s.mesh.fixed.iter().filter(|&&f| f).count(), 81 + 32);
        assert!(s.energy.value(&s.x0).is_finite());
    }

    #[test]
    fn sheets_bad_params_are_named() {
        let msg = |p: SheetsParams| build(&p).err().unwrap().to_string();
        let e = msg(SheetsParams {
            n: 0,
            ..Default::default()
        });
        assert!(e.contains("invalid n = 0"), "{e}");
        let e = msg(SheetsParams {
            eps: Some(0.0),
            ..Default::default()
        });
        assert!(e.contains("invalid eps = 0"), "{e}");
        let e = msg(SheetsParams {
            eps: Some(-1.0),
            ..Default::default()
        });
        assert!(e.contains("invalid eps = -1"), "{e}");
        let e = msg(SheetsParams {
            eps: Some(f64::NAN),
            ..Default::default()
        });
        assert!(e.contains("invalid eps = NaN"), "{e}");
        let e = msg(SheetsParams {
            mu: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid mu = NaN"), "{e}");
        let e = msg(SheetsParams {
            lambda: -1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid lambda = -1"), "{e}");
        let e = msg(SheetsParams {
            weight: f64::INFINITY,
            ..Default::default()
        });
        assert!(e.contains("invalid weight = inf"), "{e}");
        let e = msg(SheetsParams {
            gap: 0.0,
            ..Default::default()
        });
        assert!(e.contains("invalid gap = 0"), "{e}");
        let e = msg(SheetsParams {
            half_size: 0.8,
            ..Default::default()
        });
        assert!(e.contains("invalid half_size = 0.8"), "{e}");
        let e = msg(SheetsParams {
            angle_deg: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid angle_deg = NaN"), "{e}");
        let e = msg(SheetsParams {
            stretch_upper: 1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid stretch_upper = 1"), "{e}");
        let e = msg(SheetsParams {
            stretch_lower: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid stretch_lower = NaN"), "{e}");
        // ε larger than the gap: refused as not admissible
        let e = msg(SheetsParams {
            eps: Some(0.06),
            ..Default::default()
        });
        assert!(e.contains("not admissible"), "{e}");
    }

    #[test]
    fn sheets_params_from_toml_reject_unknown_keys() {
        let p: SheetsParams = toml::from_str("n = 3\nweight = 0.5").unwrap();
        assert_eq!(p.n, 3);
        assert_eq!(p.weight, 0.5);
        assert_eq!(p.gap, SheetsParams::default().gap);
        assert!(toml::from_str::<SheetsParams>("wieght = 0.5").is_err());
    }
}
