//! Scenes of the dynamic case (§6): a [`Scene`] plus what a time-stepping run needs besides —
//! a density per body, an initial velocity and a default Δt and number of steps.
//!
//! * `drop` (2D): an elastic ring (an annulus of P1 triangles, neo-Hookean, contact on its
//!   inner and outer boundary edges) released at rest above a fixed floor polyline, under
//!   gravity. Exercises solid–curve contact at impact and at rest: the ring bounces and, with
//!   implicit Euler's numerical dissipation, comes to rest; the contact force at rest is the
//!   "no chatter" measurement.
//! * `collide` (2D): two such rings moving towards each other along the x axis, no gravity,
//!   no fixed vertex; the right ring is `density_ratio` times denser, so the total momentum
//!   is not zero. Exercises solid–solid impact and the conservation of linear momentum
//!   (no external force) and the energy behaviour of the schemes.
//! * `drop3d` (3D): a free square St Venant–Kirchhoff membrane, rotated about z and tilted
//!   about x, falling under gravity onto a fixed flat square obstacle sheet. Exercises 3D
//!   vertex–triangle and edge–edge contact at impact (one edge lands first) and at rest.
//!
//! In every scene the reference configuration is the initial one (bodies start unstressed)
//! and `ε = h/10` by default, `h` the largest reference edge of the moving bodies.

use super::Scene;
use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};
use crate::scene::mesh::{BodyKind, MeshError};
use crate::scene::physics::{
    assemble_energy, BodyPhysics, ElasticTerms, Material, Physics, TermError,
};
use crate::scene::registry::{count, set_fields, BuiltinScene, Params};
use thiserror::Error;

/// A scene for a dynamic run.
pub struct DynamicScene {
    /// Mesh, J, ε, initial positions.
    pub scene: Scene,
    /// Density per body (per area in 2D solids and 3D surfaces, per length for curves, per
    /// volume for tets); fixed bodies' densities do not matter.
    pub density: Vec<f64>,
    /// Initial velocity (flat, like positions).
    pub v0: Vec<f64>,
    /// Default time step.
    pub dt: f64,
    /// Default number of steps.
    pub steps: usize,
}

/// A parameter out of range, or an invalid generated mesh; names the parameter.
#[derive(Debug, Error, PartialEq)]
pub enum DynamicSceneError {
    /// The parameter and why it is rejected.
    #[error("{scene}: invalid {name} = {value}: {reason}")]
    Invalid {
        /// Scene name.
        scene: &'static str,
        /// Parameter name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// Why.
        reason: &'static str,
    },
    /// The generated mesh is invalid.
    #[error("invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    /// An energy term that cannot be built.
    #[error("{0}")]
    Energy(#[from] TermError),
}

fn positive(scene: &'static str, name: &'static str, v: f64) -> Result<(), DynamicSceneError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(DynamicSceneError::Invalid {
            scene,
            name,
            value: v.to_string(),
            reason: "must be finite and > 0",
        })
    }
}

fn non_negative(scene: &'static str, name: &'static str, v: f64) -> Result<(), DynamicSceneError> {
    if v >= 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(DynamicSceneError::Invalid {
            scene,
            name,
            value: v.to_string(),
            reason: "must be finite and >= 0",
        })
    }
}

/// The ring of the 2D scenes: an annulus meshed with P1 triangles.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RingSolid {
    /// Cells around the ring (≥ 8).
    pub n: usize,
    /// Cells across the thickness (≥ 1).
    pub layers: usize,
    /// Outer radius.
    pub radius: f64,
    /// Inner radius (0 < inner < radius).
    pub inner: f64,
    /// Shear modulus μ of the neo-Hookean material.
    pub mu: f64,
    /// Lamé's λ.
    pub lambda: f64,
}

impl Default for RingSolid {
    fn default() -> Self {
        RingSolid {
            n: 24,
            layers: 2,
            radius: 0.5,
            inner: 0.25,
            mu: 1000.0,
            lambda: 1000.0,
        }
    }
}

impl RingSolid {
    fn validate(&self, scene: &'static str) -> Result<(), DynamicSceneError> {
        let bad = |name, value: String, reason| {
            Err(DynamicSceneError::Invalid {
                scene,
                name,
                value,
                reason,
            })
        };
        if self.n < 8 {
            return bad(
                "n",
                self.n.to_string(),
                "need at least 8 cells around the ring",
            );
        }
        if self.layers < 1 {
            return bad("layers", self.layers.to_string(), "need at least 1 layer");
        }
        positive(scene, "radius", self.radius)?;
        positive(scene, "mu", self.mu)?;
        non_negative(scene, "lambda", self.lambda)?;
        if !(self.inner > 0.0 && self.inner < self.radius) {
            return bad("inner", self.inner.to_string(), "must be in (0, radius)");
        }
        Ok(())
    }

    /// Appends the ring centred at `centre` to the vertices (`x_ref`, `fixed`) and returns it
    /// as body `name` for [`assemble_mesh`]: its triangles (global vertex indices,
    /// counter-clockwise) and its contact edges, the inner circle then the outer. Vertex
    /// `k·n + j` of the ring is on layer k (radius `inner + k (radius − inner)/layers`) at
    /// angle `2π(j + offset_cells)/n`.
    /// Its material (neo-Hookean, μ and λ).
    fn material(&self) -> Material {
        Material::NeoHookean {
            mu: self.mu,
            lambda: self.lambda,
        }
    }

    fn append(
        &self,
        x_ref: &mut Vec<f64>,
        fixed: &mut Vec<bool>,
        name: &str,
        centre: [f64; 2],
        offset_cells: f64,
    ) -> BodyPart {
        let (n, l) = (self.n, self.layers);
        let base = x_ref.len() / 2;
        for k in 0..=l {
            let r = self.inner + (self.radius - self.inner) * k as f64 / l as f64;
            for j in 0..n {
                let (s, c) =
                    (2.0 * std::f64::consts::PI * (j as f64 + offset_cells) / n as f64).sin_cos();
                x_ref.extend_from_slice(&[centre[0] + r * c, centre[1] + r * s]);
                fixed.push(false);
            }
        }
        let vid = |k: usize, j: usize| base + k * n + j % n;
        let mut tris = Vec::with_capacity(2 * n * l);
        for k in 0..l {
            for j in 0..n {
                let (a, b, c, d) = (vid(k, j), vid(k, j + 1), vid(k + 1, j + 1), vid(k + 1, j));
                tris.push([a, c, b, 0]);
                tris.push([a, d, c, 0]);
            }
        }
        let mut edges = Vec::with_capacity(2 * n);
        for k in [0, l] {
            for j in 0..n {
                edges.push([vid(k, j), vid(k, j + 1)]);
            }
        }
        BodyPart {
            name: name.into(),
            kind: BodyKind::Solid,
            vertices: (base..base + (l + 1) * n).collect(),
            elements: tris,
            arity: 3,
            h: Some(self.mesh_size()),
            edges: Some(edges),
            faces: None,
        }
    }

    /// The largest reference edge: the outer circumferential edge `2R sin(π/n)` or a cell
    /// diagonal, whichever is longer.
    pub fn mesh_size(&self) -> f64 {
        let t = std::f64::consts::PI / self.n as f64;
        let dr = (self.radius - self.inner) / self.layers as f64;
        let mut h: f64 = 2.0 * self.radius * t.sin();
        for k in 0..self.layers {
            let r0 = self.inner + dr * k as f64;
            let r1 = r0 + dr;
            // diagonal from (r0, θ) to (r1, θ + 2π/n)
            let d2 = r0 * r0 + r1 * r1 - 2.0 * r0 * r1 * (2.0 * t).cos();
            h = h.max(d2.sqrt());
        }
        h
    }
}

/// Parameters of the `drop` scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DropParams {
    /// The ring.
    pub ring: RingSolid,
    /// Density of the ring per unit area.
    pub density: f64,
    /// Gravitational acceleration (along −y).
    pub g: f64,
    /// Initial gap between the ring's lowest point and the floor.
    pub height: f64,
    /// Half width of the floor (centred under the ring).
    pub floor_half_width: f64,
    /// Edges of the floor polyline (default 11: odd, so that the ring's lowest vertex lands
    /// on the middle of an edge, not on a floor vertex).
    pub floor_edges: usize,
    /// ε; `None` means h/10.
    pub eps: Option<f64>,
}

impl Default for DropParams {
    fn default() -> Self {
        DropParams {
            ring: RingSolid::default(),
            density: 1.0,
            g: 9.81,
            height: 0.2,
            floor_half_width: 1.5,
            floor_edges: 11,
            eps: None,
        }
    }
}

/// Builds `drop`: body 0 the ring (centre `(0, radius + height)`), body 1 the floor (the
/// fixed polyline `y = 0`, `|x| ≤ floor_half_width`). Default Δt = 0.02, 300 steps (6 s: with
/// the default ring the kinetic energy has decayed to ~1e-8 of the initial potential energy;
/// docs/measurements.md).
pub fn drop(p: &DropParams) -> Result<DynamicScene, DynamicSceneError> {
    const S: &str = "drop";
    p.ring.validate(S)?;
    positive(S, "density", p.density)?;
    non_negative(S, "g", p.g)?;
    positive(S, "height", p.height)?;
    positive(S, "floor_half_width", p.floor_half_width)?;
    if p.floor_edges < 1 {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "floor_edges",
            value: p.floor_edges.to_string(),
            reason: "need at least 1 edge",
        });
    }
    let h = p.ring.mesh_size();
    let eps = p.eps.unwrap_or(h / 10.0);
    positive(S, "eps", eps)?;
    if eps >= p.height {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "height",
            value: p.height.to_string(),
            reason: "must exceed eps so that the start is admissible",
        });
    }
    let (mut x_ref, mut fixed) = (Vec::new(), Vec::new());
    let ring = p.ring.append(
        &mut x_ref,
        &mut fixed,
        "ring",
        [0.0, p.ring.radius + p.height],
        0.0,
    );
    let base = fixed.len();
    let nf = p.floor_edges;
    for i in 0..=nf {
        let x = -p.floor_half_width + 2.0 * p.floor_half_width * i as f64 / nf as f64;
        x_ref.extend_from_slice(&[x, 0.0]);
        fixed.push(true);
    }
    let floor = BodyPart {
        name: "floor".into(),
        kind: BodyKind::Curve,
        vertices: (base..=base + nf).collect(),
        elements: (0..nf).map(|i| [base + i, base + i + 1, 0, 0]).collect(),
        arity: 2,
        h: Some(2.0 * p.floor_half_width / nf as f64),
        edges: None,
        faces: None,
    };
    let mesh = assemble_mesh(2, x_ref, fixed, &[ring, floor], &file_order(2));
    mesh.validate()?;
    let density = vec![p.density, 0.0];
    // the ring's material, then gravity on the lumped masses of both densities (the floor's
    // is 0)
    let physics = Physics {
        bodies: vec![
            BodyPhysics {
                material: Some(p.ring.material()),
                density: Some(density[0]),
                ..Default::default()
            },
            BodyPhysics {
                density: Some(density[1]),
                ..Default::default()
            },
        ],
        gravity: Some(vec![0.0, -p.g]),
        ..Default::default()
    };
    let x0 = mesh.x_ref.clone();
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    let v0 = vec![0.0; x0.len()];
    Ok(DynamicScene {
        scene: Scene {
            name: S.into(),
            mesh,
            energy,
            eps,
            h,
            x0,
        },
        density,
        v0,
        dt: 0.02,
        steps: 300,
    })
}

/// Parameters of the `collide` scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CollideParams {
    /// Both rings.
    pub ring: RingSolid,
    /// Density of the left ring per unit area.
    pub density: f64,
    /// Density of the right ring / density of the left one.
    pub density_ratio: f64,
    /// Initial gap between the rings.
    pub gap: f64,
    /// Speed of each ring towards the other.
    pub speed: f64,
    /// Rotation of the right ring, in cells (`2π/n` each). The default 0.5 puts the left
    /// ring's rightmost vertex in front of the middle of an edge of the right ring; with 0
    /// two vertices face each other, and the outer loop creeps at impact (measured: the
    /// contact point slides towards the vertex with `ΔJ` shrinking by a factor ≈ 0.98 per
    /// outer iteration, hundreds of iterations per step).
    pub offset_cells: f64,
    /// ε; `None` means h/10.
    pub eps: Option<f64>,
}

impl Default for CollideParams {
    fn default() -> Self {
        CollideParams {
            ring: RingSolid::default(),
            density: 1.0,
            density_ratio: 2.0,
            gap: 0.1,
            speed: 1.0,
            offset_cells: 0.5,
            eps: None,
        }
    }
}

/// Builds `collide`: body 0 the left ring (centre `(−radius − gap/2, 0)`, velocity
/// `(+speed, 0)`), body 1 the right ring (centre `(radius + gap/2, 0)`, velocity
/// `(−speed, 0)`). No gravity, no fixed vertex. Default Δt = 0.005, 60 steps (impact at
/// t = gap / (2 speed) = 0.05).
pub fn collide(p: &CollideParams) -> Result<DynamicScene, DynamicSceneError> {
    const S: &str = "collide";
    p.ring.validate(S)?;
    positive(S, "density", p.density)?;
    positive(S, "density_ratio", p.density_ratio)?;
    positive(S, "gap", p.gap)?;
    non_negative(S, "speed", p.speed)?;
    if !p.offset_cells.is_finite() {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "offset_cells",
            value: p.offset_cells.to_string(),
            reason: "must be finite",
        });
    }
    let h = p.ring.mesh_size();
    let eps = p.eps.unwrap_or(h / 10.0);
    positive(S, "eps", eps)?;
    if eps >= p.gap {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "gap",
            value: p.gap.to_string(),
            reason: "must exceed eps so that the start is admissible",
        });
    }
    let (mut x_ref, mut fixed) = (Vec::new(), Vec::new());
    let c = p.ring.radius + 0.5 * p.gap;
    let left = p
        .ring
        .append(&mut x_ref, &mut fixed, "left", [-c, 0.0], 0.0);
    let nv_ring = fixed.len();
    let right = p
        .ring
        .append(&mut x_ref, &mut fixed, "right", [c, 0.0], p.offset_cells);
    let mesh = assemble_mesh(2, x_ref, fixed, &[left, right], &file_order(2));
    mesh.validate()?;
    let x0 = mesh.x_ref.clone();
    let mut v0 = vec![0.0; x0.len()];
    for v in 0..mesh.nv() {
        v0[2 * v] = if v < nv_ring { p.speed } else { -p.speed };
    }
    // one neo-Hookean term over both rings (the form the committed runs were made in)
    let ring = BodyPhysics {
        material: Some(p.ring.material()),
        ..Default::default()
    };
    let physics = Physics {
        bodies: vec![ring.clone(), ring],
        gravity: None,
        elastic: ElasticTerms::Joined,
    };
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    Ok(DynamicScene {
        scene: Scene {
            name: S.into(),
            mesh,
            energy,
            eps,
            h,
            x0,
        },
        density: vec![p.density, p.density * p.density_ratio],
        v0,
        dt: 0.005,
        steps: 60,
    })
}

/// Parameters of the `drop3d` scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Drop3dParams {
    /// Mesh level: the sheet is a `4n × 4n` grid of squares (the obstacle `4 × 4`).
    pub n: usize,
    /// Half side of the sheet.
    pub half_size: f64,
    /// Rotation of the sheet about z, degrees (its edges cross the obstacle's).
    pub angle_deg: f64,
    /// Tilt of the sheet about the x axis, degrees (one side lands first).
    pub tilt_deg: f64,
    /// Height of the sheet's lowest point above the obstacle.
    pub height: f64,
    /// Half side of the obstacle (fixed square at z = 0).
    pub obstacle_half_size: f64,
    /// Shear modulus μ of the membrane.
    pub mu: f64,
    /// 2D Lamé λ of the membrane.
    pub lambda: f64,
    /// Density per unit area.
    pub density: f64,
    /// Gravitational acceleration (along −z).
    pub g: f64,
    /// ε; `None` means h/10.
    pub eps: Option<f64>,
}

impl Default for Drop3dParams {
    fn default() -> Self {
        Drop3dParams {
            n: 1,
            half_size: 0.5,
            angle_deg: 30.0,
            tilt_deg: 10.0,
            height: 0.1,
            obstacle_half_size: 1.0,
            mu: 50.0,
            lambda: 50.0,
            density: 1.0,
            g: 9.81,
            eps: None,
        }
    }
}

/// The largest reference edge of the sheet of `drop3d`: its cell diagonal `2√2 a / (4n)`.
pub fn drop3d_mesh_size(p: &Drop3dParams) -> f64 {
    2.0 * std::f64::consts::SQRT_2 * p.half_size / (4 * p.n) as f64
}

/// A `m × m` grid of `[-1, 1]²` (row-major points) and its triangles (counter-clockwise from
/// +z).
fn grid(m: usize) -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let mut pts = Vec::new();
    for j in 0..=m {
        for i in 0..=m {
            pts.push([
                -1.0 + 2.0 * i as f64 / m as f64,
                -1.0 + 2.0 * j as f64 / m as f64,
            ]);
        }
    }
    let mut tris = Vec::new();
    for j in 0..m {
        for i in 0..m {
            let v = j * (m + 1) + i;
            tris.push([v, v + 1, v + m + 2]);
            tris.push([v, v + m + 2, v + m + 1]);
        }
    }
    (pts, tris)
}

/// Builds `drop3d`: body 0 the obstacle (a fixed `4 × 4` grid on `[-b, b]² × {0}`, no energy),
/// body 1 the sheet (free, StVK membrane + gravity). Default Δt = 0.005, 80 steps.
pub fn drop3d(p: &Drop3dParams) -> Result<DynamicScene, DynamicSceneError> {
    const S: &str = "drop3d";
    if p.n < 1 {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "n",
            value: p.n.to_string(),
            reason: "need n >= 1",
        });
    }
    positive(S, "half_size", p.half_size)?;
    positive(S, "height", p.height)?;
    positive(S, "obstacle_half_size", p.obstacle_half_size)?;
    positive(S, "mu", p.mu)?;
    non_negative(S, "lambda", p.lambda)?;
    positive(S, "density", p.density)?;
    non_negative(S, "g", p.g)?;
    if !p.tilt_deg.is_finite() || p.tilt_deg.abs() >= 80.0 || !p.angle_deg.is_finite() {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "tilt_deg",
            value: p.tilt_deg.to_string(),
            reason: "must be in (-80, 80) (and angle_deg finite)",
        });
    }
    let h = drop3d_mesh_size(p);
    let eps = p.eps.unwrap_or(h / 10.0);
    positive(S, "eps", eps)?;
    if eps >= p.height {
        return Err(DynamicSceneError::Invalid {
            scene: S,
            name: "height",
            value: p.height.to_string(),
            reason: "must exceed eps so that the start is admissible",
        });
    }
    let (opts, otris) = grid(4);
    let (spts, stris) = grid(4 * p.n);
    let (no, ns) = (opts.len(), spts.len());
    let mut x = Vec::with_capacity(3 * (no + ns));
    let mut fixed = Vec::with_capacity(no + ns);
    for q in &opts {
        x.extend_from_slice(&[
            p.obstacle_half_size * q[0],
            p.obstacle_half_size * q[1],
            0.0,
        ]);
        fixed.push(true);
    }
    let (sa, ca) = p.angle_deg.to_radians().sin_cos();
    let (st, ct) = p.tilt_deg.to_radians().sin_cos();
    // lowest point of the tilted sheet: y' = ±a → z = ±a sin(tilt) (before rotation about z)
    let z0 = p.height + p.half_size * st.abs();
    for q in &spts {
        let (u, v) = (p.half_size * q[0], p.half_size * q[1]);
        // tilt about x, then rotate about z
        let (y1, z1) = (ct * v, st * v);
        let (rx, ry) = (ca * u - sa * y1, sa * u + ca * y1);
        x.extend_from_slice(&[rx, ry, z0 + z1]);
        fixed.push(false);
    }
    let stris: Vec<[usize; 3]> = stris.iter().map(|t| t.map(|v| v + no)).collect();
    let surface = |name: &str, vertices: std::ops::Range<usize>, tris: &[[usize; 3]], h| BodyPart {
        name: name.into(),
        kind: BodyKind::Surface,
        vertices: vertices.collect(),
        elements: tris.iter().map(|t| [t[0], t[1], t[2], 0]).collect(),
        arity: 3,
        h: Some(h),
        edges: None,
        faces: None,
    };
    let parts = [
        surface(
            "obstacle",
            0..no,
            &otris,
            2.0 * std::f64::consts::SQRT_2 * p.obstacle_half_size / 4.0,
        ),
        surface("sheet", no..no + ns, &stris, h),
    ];
    let mesh = assemble_mesh(3, x.clone(), fixed, &parts, &file_order(2));
    mesh.validate()?;
    let density = vec![0.0, p.density];
    // the sheet's membrane, then gravity on its weight (the obstacle carries nothing)
    let physics = Physics {
        bodies: vec![
            BodyPhysics::default(),
            BodyPhysics {
                material: Some(Material::StvkMembrane {
                    mu: p.mu,
                    lambda: p.lambda,
                }),
                density: Some(p.density),
                ..Default::default()
            },
        ],
        gravity: Some(vec![0.0, 0.0, -p.g]),
        ..Default::default()
    };
    let energy = assemble_energy(&mesh, &x, &physics)?;
    let v0 = vec![0.0; x.len()];
    Ok(DynamicScene {
        scene: Scene {
            name: S.into(),
            mesh,
            energy,
            eps,
            h,
            x0: x,
        },
        density,
        v0,
        dt: 0.005,
        steps: 80,
    })
}

/// The smallest level in `start..=400` whose dynamic scene has a mesh size at most `h`.
fn dynamic_level(
    s: &dyn BuiltinScene,
    start: usize,
    h: f64,
    params: &Params,
) -> anyhow::Result<usize> {
    for n in start..=400 {
        if s.dynamic(Some(n), None, params)?.0.scene.h <= h {
            return Ok(n);
        }
    }
    anyhow::bail!("h = {h} needs a level above the scene's n ≤ 400")
}

/// `drop` in the scene registry (dynamic only): parameters the fields of [`DropParams`] and
/// its ring's (`layers`, `floor_edges` non-negative integers); level `n` the ring's cells
/// around.
pub struct Drop;

impl BuiltinScene for Drop {
    fn name(&self) -> &'static str {
        "drop"
    }

    fn dynamic_only(&self) -> bool {
        true
    }

    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Scene> {
        Ok(self.dynamic(Some(n), eps, params)?.0.scene)
    }

    fn n_for_h(&self, h: f64, params: &Params) -> anyhow::Result<usize> {
        dynamic_level(self, 8, h, params)
    }

    fn dynamic(
        &self,
        n: Option<usize>,
        eps: Option<f64>,
        params: &Params,
    ) -> anyhow::Result<(DynamicScene, serde_json::Value)> {
        let mut p = DropParams {
            eps,
            ..Default::default()
        };
        if let Some(n) = n {
            p.ring.n = n;
        }
        let mut layers = p.ring.layers as f64;
        let mut floor_edges = p.floor_edges as f64;
        set_fields(
            "drop",
            &mut (&mut p, &mut layers, &mut floor_edges),
            params,
            &[
                ("mu", |p| &mut p.0.ring.mu),
                ("lambda", |p| &mut p.0.ring.lambda),
                ("radius", |p| &mut p.0.ring.radius),
                ("inner", |p| &mut p.0.ring.inner),
                ("layers", |p| &mut *p.1),
                ("density", |p| &mut p.0.density),
                ("g", |p| &mut p.0.g),
                ("height", |p| &mut p.0.height),
                ("floor_half_width", |p| &mut p.0.floor_half_width),
                ("floor_edges", |p| &mut *p.2),
            ],
            &[],
        )?;
        p.ring.layers = count("drop", "layers", layers)?;
        p.floor_edges = count("drop", "floor_edges", floor_edges)?;
        Ok((drop(&p)?, serde_json::to_value(&p)?))
    }
}

/// `collide` in the scene registry (dynamic only): parameters the fields of
/// [`CollideParams`] and its rings' (`layers` a non-negative integer); level `n` the rings'
/// cells around.
pub struct Collide;

impl BuiltinScene for Collide {
    fn name(&self) -> &'static str {
        "collide"
    }

    fn dynamic_only(&self) -> bool {
        true
    }

    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Scene> {
        Ok(self.dynamic(Some(n), eps, params)?.0.scene)
    }

    fn n_for_h(&self, h: f64, params: &Params) -> anyhow::Result<usize> {
        dynamic_level(self, 8, h, params)
    }

    fn dynamic(
        &self,
        n: Option<usize>,
        eps: Option<f64>,
        params: &Params,
    ) -> anyhow::Result<(DynamicScene, serde_json::Value)> {
        let mut p = CollideParams {
            eps,
            ..Default::default()
        };
        if let Some(n) = n {
            p.ring.n = n;
        }
        let mut layers = p.ring.layers as f64;
        set_fields(
            "collide",
            &mut (&mut p, &mut layers),
            params,
            &[
                ("mu", |p| &mut p.0.ring.mu),
                ("lambda", |p| &mut p.0.ring.lambda),
                ("radius", |p| &mut p.0.ring.radius),
                ("inner", |p| &mut p.0.ring.inner),
                ("layers", |p| &mut *p.1),
                ("density", |p| &mut p.0.density),
                ("density_ratio", |p| &mut p.0.density_ratio),
                ("gap", |p| &mut p.0.gap),
                ("speed", |p| &mut p.0.speed),
                ("offset_cells", |p| &mut p.0.offset_cells),
            ],
            &[],
        )?;
        p.ring.layers = count("collide", "layers", layers)?;
        Ok((collide(&p)?, serde_json::to_value(&p)?))
    }
}

/// `drop3d` in the scene registry (dynamic only): parameters the fields of [`Drop3dParams`];
/// level `n` its own.
pub struct Drop3d;

impl BuiltinScene for Drop3d {
    fn name(&self) -> &'static str {
        "drop3d"
    }

    fn dynamic_only(&self) -> bool {
        true
    }

    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Scene> {
        Ok(self.dynamic(Some(n), eps, params)?.0.scene)
    }

    fn n_for_h(&self, h: f64, params: &Params) -> anyhow::Result<usize> {
        dynamic_level(self, 1, h, params)
    }

    fn dynamic(
        &self,
        n: Option<usize>,
        eps: Option<f64>,
        params: &Params,
    ) -> anyhow::Result<(DynamicScene, serde_json::Value)> {
        let mut p = Drop3dParams {
            eps,
            ..Default::default()
        };
        if let Some(n) = n {
            p.n = n;
        }
        set_fields(
            "drop3d",
            &mut p,
            params,
            &[
                ("half_size", |p| &mut p.half_size),
                ("angle_deg", |p| &mut p.angle_deg),
                ("tilt_deg", |p| &mut p.tilt_deg),
                ("height", |p| &mut p.height),
                ("obstacle_half_size", |p| &mut p.obstacle_half_size),
                ("mu", |p| &mut p.mu),
                ("lambda", |p| &mut p.lambda),
                ("density", |p| &mut p.density),
                ("g", |p| &mut p.g),
            ],
            &[],
        )?;
        Ok((drop3d(&p)?, serde_json::to_value(&p)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::min_distance;
    use crate::energy::mass::lumped_mass;

    #[test]
    fn dynamic_scenes_build_admissible_with_the_expected_masses() {
        let d = drop(&DropParams::default()).unwrap();
        let s = &d.scene;
        assert_eq!(s.mesh.validate(), Ok(()));
        let r = RingSolid::default();
        assert_eq!(s.mesh.nv(), 3 * 24 + 12);
        assert_eq!(s.mesh.triangles.len(), 2 * 2 * 24);
        let m = lumped_mass(&s.mesh, &s.mesh.x_ref, &d.density).unwrap();
        // the inscribed polygons' annulus area: n/2 sin(2π/n) (R² − r²)
        let area =
            12.0 * (std::f64::consts::PI / 12.0).sin() * (r.radius.powi(2) - r.inner.powi(2));
        assert!((m.iter().sum::<f64>() - area).abs() < 1e-12);
        assert!(min_distance(&s.mesh, &s.x0, 2.0 * s.eps, false).distance >= s.eps);
        assert!(s.energy.value(&s.x0).is_finite());
        // the ring's lowest vertex is `height` above the floor (vertex at angle 3π/2)
        let ymin = (0..72)
            .map(|v| s.x0[2 * v + 1])
            .fold(f64::INFINITY, f64::min);
        assert!((ymin - 0.2).abs() < 1e-12, "{ymin}");

        let c = collide(&CollideParams::default()).unwrap();
        assert_eq!(c.scene.mesh.bodies.len(), 2);
        assert!(c.scene.mesh.fixed.iter().all(|f| !f));
        let m = lumped_mass(&c.scene.mesh, &c.scene.mesh.x_ref, &c.density).unwrap();
        assert!((m[72..].iter().sum::<f64>() - 2.0 * m[..72].iter().sum::<f64>()).abs() < 1e-12);
        let d3 = drop3d(&Drop3dParams::default()).unwrap();
        let s = &d3.scene;
        assert_eq!(s.mesh.validate(), Ok(()));
        assert!(min_distance(&s.mesh, &s.x0, 2.0 * s.eps, false).distance >= s.eps);
        let m = lumped_mass(&s.mesh, &s.mesh.x_ref, &d3.density).unwrap();
        assert!((m.iter().sum::<f64>() - 1.0).abs() < 1e-12); // (2·0.5)² × density 1
    }

    #[test]
    fn dynamic_scene_bad_params_are_named() {
        let e = drop(&DropParams {
            height: -1.0,
            ..Default::default()
        })
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("drop: invalid height = -1"), "{e}");
        let e = collide(&CollideParams {
            ring: RingSolid {
                inner: 0.6,
                ..Default::default()
            },
            ..Default::default()
        })
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("collide: invalid inner = 0.6"), "{e}");
        let e = drop3d(&Drop3dParams {
            n: 0,
            ..Default::default()
        })
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("drop3d: invalid n = 0"), "{e}");
    }
}
