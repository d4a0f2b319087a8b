//! Balloons in a box, in 3D (the 3D counterpart of the §7 balloons): two closed membranes
//! inflated by an enclosed gas against the walls of a fixed box and against each other.
//!
//! **Geometry.** The box `[−2, 2] × [−1, 1] × [−1, 1]` (body `box`, [`BodyKind::Surface`],
//! every vertex fixed): its six walls gridded in squares of side `2/n` (`2n × n × n` cells),
//! each square cut into two triangles, normals pointing into the box. Two balloons
//! (`balloon0`, `balloon1`, Surface bodies): icospheres (the icosahedron subdivided `n` times,
//! `10·4ⁿ + 2` vertices, projected on the sphere) of radius `r = radius`, rotated so that one
//! triangle (the *pad*) is horizontal at the bottom, centred at `x = −1` and `x = +1`,
//! `y = 0`, the pad at height `pad_gap` above the floor `z = −1`; `balloon1`'s mesh is turned
//! by `twist_deg` about its vertical axis so the two meshes do not mirror each other where
//! they meet. Triangles oriented outward. In `x0` the balloons are their reference spheres
//! (`x0 = x_ref`, unstressed).
//!
//! **Rigid motions.** The three vertices of each balloon's pad are fixed: the balloon is glued
//! to the floor by one small triangle (one pinned vertex would leave the rotations about it
//! free of energy until contact). The glued triangle keeps its reference shape; the rest of
//! the balloon grows around it. That triangle's size is h, so the balloon's twist about its
//! vertical axis, which the flat frictionless walls do not resist, gets softer at every level
//! (docs/method.md, "balloons3d n = 3's tail"); `pad_radius > 0` glues every vertex within that
//! distance of the pad's centre as well (on the reference sphere, fixed where it is), a glued
//! region whose size does not depend on h.
//!
//! **Energy.** Per balloon, the St Venant–Kirchhoff membrane ([`crate::energy::Membrane3dEnergy`],
//! `W = μ|E|² + λ/2 (tr E)²` per unit reference area) and the gas ([`crate::energy::Gas3dEnergy`],
//! `−C ln V`, `V` the volume enclosed by the balloon's closed outward surface).
//!
//! **Defaults.** `n = 1` (42 vertices, 120 edges, 80 triangles per balloon; 12, 30, 20 for the
//! box: 96 vertices; `n = 2`: 162 per balloon, 366 in all), `μ = 1`, `λ = 1`, `C = 30`,
//! `radius = 0.8`, `pad_gap = 0.05`, `twist_deg = 17`; `h` = the largest reference
//! edge of the balloons, `ε = min(h/10, pad_gap/2)`.
//!
//! **At the minimum.** A free spherical StVK balloon of reference radius `r` inflates to the
//! stretch `Λ` where `8π r² (μ + λ) Λ² (Λ² − 1) = 3C`: `Λ ≈ 1.5`, radius ≈ 1.2 with the
//! defaults (the unconstrained equilibrium of the meshed balloons, computed by Newton's method
//! without contact: mean radius 1.20, centre 0.13 above the box's mid-plane; with `C = 100`,
//! 1.52), while each balloon has only the half box `2 × 2 × 2` (inscribed radius 1). So
//! each balloon is pressed against the floor, the ceiling, the three walls around it and the
//! other balloon along the plane `x = 0`, flattened on each at distance ε: vertex–triangle and
//! edge–edge rows between each balloon and the box and between the two balloons are active.

use super::sheets::unique_edges;
use super::Scene;
use crate::contact::broad_phase::min_distance_3d;
use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};
use crate::scene::mesh::{BodyKind, MeshError};
use crate::scene::physics::{assemble_energy, BodyPhysics, Material, Physics, TermError};
use crate::scene::registry::{set_fields, LevelScene, Params};
use nalgebra::{Rotation3, Vector3};
use std::collections::HashMap;
use thiserror::Error;

/// Half extents of the box.
const BOX: [f64; 3] = [2.0, 1.0, 1.0];

/// Balloon centres' x.
const CENTRES_X: [f64; 2] = [-1.0, 1.0];

/// Parameters of the 3D balloons scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Balloons3dParams {
    /// Mesh level: icosphere subdivisions of each balloon, box cells of side `2/n` (1..=7).
    pub n: usize,
    /// ε; `None` means `min(h/10, pad_gap/2)`.
    pub eps: Option<f64>,
    /// Shear modulus μ of the membranes (per unit reference area).
    pub mu: f64,
    /// 2D Lamé coefficient λ of the membranes (≥ 0).
    pub lambda: f64,
    /// Gas constant C of each balloon.
    pub c: f64,
    /// Reference (= initial) radius of the balloons, in (0, 1).
    pub radius: f64,
    /// Height of each balloon's glued bottom triangle above the floor.
    pub pad_gap: f64,
    /// Turn of `balloon1`'s mesh about its vertical axis, in degrees.
    pub twist_deg: f64,
    /// Radius of the glued region: every balloon vertex whose reference position is within
    /// this distance of the pad's centre (the point of the reference sphere in the direction
    /// of the pad's centroid) is fixed as well. 0: the pad triangle alone, whose size is h.
    pub pad_radius: f64,
}

impl Default for Balloons3dParams {
    fn default() -> Self {
        Balloons3dParams {
            n: 1,
            eps: None,
            mu: 1.0,
            lambda: 1.0,
            c: 30.0,
            radius: 0.8,
            pad_gap: 0.05,
            twist_deg: 17.0,
            pad_radius: 0.0,
        }
    }
}

/// A parameter out of range, or a start that is not admissible; names the parameter.
#[derive(Debug, Error, PartialEq)]
pub enum Balloons3dError {
    /// The parameter and why it is rejected.
    #[error("balloons3d: invalid {name} = {value}: {reason}")]
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
        "balloons3d: the initial configuration is not admissible: {pair} at distance \
         {distance:.6e} < eps = {eps:.6e}; lower radius or eps, or raise pad_gap"
    )]
    InadmissibleStart {
        /// The closest pair, printed.
        pair: String,
        /// Its distance.
        distance: f64,
        /// ε.
        eps: f64,
    },
    /// The generated mesh is invalid.
    #[error("balloons3d: invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    /// An energy term that cannot be built (a balloon surface that is not closed: a bug).
    #[error("balloons3d: {0}")]
    Energy(#[from] TermError),
}

/// The unit icosphere: the icosahedron subdivided `level` times (each triangle into four,
/// midpoints projected on the sphere); triangles oriented outward.
pub fn icosphere(level: usize) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
    let phi = 0.5 * (1.0 + 5f64.sqrt());
    let mut pts: Vec<Vector3<f64>> = [
        [-1.0, phi, 0.0],
        [1.0, phi, 0.0],
        [-1.0, -phi, 0.0],
        [1.0, -phi, 0.0],
        [0.0, -1.0, phi],
        [0.0, 1.0, phi],
        [0.0, -1.0, -phi],
        [0.0, 1.0, -phi],
        [phi, 0.0, -1.0],
        [phi, 0.0, 1.0],
        [-phi, 0.0, -1.0],
        [-phi, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vector3::from(*p).normalize())
    .collect();
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
        let mut next = Vec::with_capacity(4 * tris.len());
        for t in &tris {
            let mut m = [0; 3];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                m[k] = *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    pts.push((pts[a] + pts[b]).normalize());
                    pts.len() - 1
                });
            }
            next.push([t[0], m[0], m[2]]);
            next.push([t[1], m[1], m[0]]);
            next.push([t[2], m[2], m[1]]);
            next.push([m[0], m[1], m[2]]);
        }
        tris = next;
    }
    for t in tris.iter_mut() {
        let (a, b, c) = (pts[t[0]], pts[t[1]], pts[t[2]]);
        if (b - a).cross(&(c - a)).dot(&(a + b + c)) < 0.0 {
            t.swap(1, 2);
        }
    }
    (pts, tris)
}

/// The unit icosphere of [`icosphere`] rotated so that its lowest triangle is horizontal,
/// at the bottom; returns the points, the triangles and that triangle's index.
fn padded_icosphere(level: usize) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>, usize) {
    let (pts, tris) = icosphere(level);
    let centroid = |t: &[usize; 3]| (pts[t[0]] + pts[t[1]] + pts[t[2]]) / 3.0;
    let pad = (0..tris.len())
        .min_by(|&a, &b| centroid(&tris[a]).z.total_cmp(&centroid(&tris[b]).z))
        .unwrap();
    let t = tris[pad];
    let normal = (pts[t[1]] - pts[t[0]])
        .cross(&(pts[t[2]] - pts[t[0]]))
        .normalize();
    let rot = Rotation3::rotation_between(&normal, &-Vector3::z())
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    let mut pts: Vec<Vector3<f64>> = pts.iter().map(|p| rot * p).collect();
    // the pad's three vertices exactly at one height
    let z = t.iter().map(|&v| pts[v].z).sum::<f64>() / 3.0;
    for &v in &t {
        pts[v].z = z;
    }
    (pts, tris, pad)
}

/// `h`: the largest reference edge of the balloons (radius × the longest unit-icosphere
/// edge).
pub fn mesh_size(p: &Balloons3dParams) -> f64 {
    let (pts, tris) = icosphere(p.n);
    unique_edges(&tris)
        .iter()
        .map(|e| (pts[e[1]] - pts[e[0]]).norm())
        .fold(0.0, f64::max)
        * p.radius
}

impl Balloons3dParams {
    /// Checks every parameter (not the admissibility of the start: [`build`] does that).
    pub fn validate(&self) -> Result<(), Balloons3dError> {
        let bad = |name, value: String, reason: &str| {
            Err(Balloons3dError::Invalid {
                name,
                value,
                reason: reason.into(),
            })
        };
        if self.n == 0 || self.n > 7 {
            return bad("n", self.n.to_string(), "must be in 1..=7");
        }
        if let Some(e) = self.eps {
            if !(e > 0.0 && e.is_finite()) {
                return bad("eps", e.to_string(), "must be finite and > 0");
            }
        }
        for (name, v) in [
            ("mu", self.mu),
            ("c", self.c),
            ("radius", self.radius),
            ("pad_gap", self.pad_gap),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(name, v.to_string(), "must be finite and > 0");
            }
        }
        if !(self.lambda >= 0.0 && self.lambda.is_finite()) {
            return bad("lambda", self.lambda.to_string(), "must be finite and ≥ 0");
        }
        if self.radius >= 1.0 {
            return bad(
                "radius",
                self.radius.to_string(),
                "must be < 1 (the balloons' centres are 1 from the walls and from each other's)",
            );
        }
        if self.pad_gap + 2.0 * self.radius >= 2.0 {
            return bad(
                "pad_gap",
                self.pad_gap.to_string(),
                "pad_gap + 2·radius must be < 2 (the balloon must fit under the ceiling)",
            );
        }
        if !self.twist_deg.is_finite() {
            return bad("twist_deg", self.twist_deg.to_string(), "must be finite");
        }
        if !(self.pad_radius >= 0.0 && self.pad_radius < self.radius) {
            return bad(
                "pad_radius",
                self.pad_radius.to_string(),
                "must be ≥ 0 and < radius (the glued region is a cap of the balloon)",
            );
        }
        Ok(())
    }
}

/// The box surface: vertices of the `nx × ny × nz` lattice on its boundary, scaled to
/// `[−BOX, BOX]`, and its triangles (normals into the box).
fn box_surface(nx: usize, ny: usize, nz: usize) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let dims = [nx, ny, nz];
    let mut index: HashMap<[usize; 3], usize> = HashMap::new();
    let mut pts = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                if i == 0 || j == 0 || k == 0 || i == nx || j == ny || k == nz {
                    index.insert([i, j, k], pts.len());
                    pts.push(
                        [i, j, k]
                            .iter()
                            .enumerate()
                            .map(|(c, &l)| BOX[c] * (2.0 * l as f64 / dims[c] as f64 - 1.0))
                            .collect::<Vec<f64>>()
                            .try_into()
                            .unwrap(),
                    );
                }
            }
        }
    }
    let mut tris = Vec::new();
    // each wall: axis `a` fixed at 0 or dims[a]; (b, c) the other two axes
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for side in [0, dims[a]] {
            for u in 0..dims[b] {
                for v in 0..dims[c] {
                    let q = |du: usize, dv: usize| {
                        let mut l = [0; 3];
                        l[a] = side;
                        l[b] = u + du;
                        l[c] = v + dv;
                        index[&l]
                    };
                    tris.push([q(0, 0), q(1, 0), q(1, 1)]);
                    tris.push([q(0, 0), q(1, 1), q(0, 1)]);
                }
            }
        }
    }
    let p = |v: usize| Vector3::from(pts[v]);
    for t in tris.iter_mut() {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        // into the box: the normal points towards the centre (the origin)
        if (b - a).cross(&(c - a)).dot(&(a + b + c)) > 0.0 {
            t.swap(1, 2);
        }
    }
    (pts, tris)
}

/// Builds the scene (name `balloons3d`). Vertices: `balloon0`'s, `balloon1`'s, then the
/// box's; triangles (= faces) and edges in the same body order.
pub fn build(p: &Balloons3dParams) -> Result<Scene, Balloons3dError> {
    p.validate()?;
    let h = mesh_size(p);
    let eps = p.eps.unwrap_or((h / 10.0).min(0.5 * p.pad_gap));
    let (unit, sphere_tris, pad) = padded_icosphere(p.n);
    let nb = unit.len();
    let pad_depth = -unit[sphere_tris[pad][0]].z; // centre to pad plane, unit sphere
    let zc = -BOX[2] + p.pad_gap + p.radius * pad_depth;
    let mut x = Vec::new();
    let mut fixed = Vec::new();
    let mut bodies_tris: Vec<Vec<[usize; 3]>> = Vec::new();
    for (k, &xc) in CENTRES_X.iter().enumerate() {
        let turn = Rotation3::from_axis_angle(
            &Vector3::z_axis(),
            if k == 1 {
                p.twist_deg.to_radians()
            } else {
                0.0
            },
        );
        let off = k * nb;
        let [a, b, c] = sphere_tris[pad];
        let pad_centre = (unit[a] + unit[b] + unit[c]).normalize();
        for (v, q) in unit.iter().enumerate() {
            let r = turn * q * p.radius;
            let z = if sphere_tris[pad].contains(&v) {
                -BOX[2] + p.pad_gap // exactly
            } else {
                zc + r.z
            };
            x.extend_from_slice(&[xc + r.x, r.y, z]);
            let glued = p.pad_radius > 0.0 && p.radius * (q - pad_centre).norm() < p.pad_radius;
            fixed.push(sphere_tris[pad].contains(&v) || glued);
        }
        let tris: Vec<[usize; 3]> = sphere_tris.iter().map(|t| t.map(|v| v + off)).collect();
        bodies_tris.push(tris);
    }
    let (box_pts, box_local) = box_surface(2 * p.n, p.n, p.n);
    let box_off = 2 * nb;
    for q in &box_pts {
        x.extend_from_slice(q);
        fixed.push(true);
    }
    let box_tris: Vec<[usize; 3]> = box_local.iter().map(|t| t.map(|v| v + box_off)).collect();
    bodies_tris.push(box_tris);
    let nv = box_off + box_pts.len();
    let names = ["balloon0", "balloon1", "box"];
    let parts: Vec<BodyPart> = bodies_tris
        .iter()
        .enumerate()
        .map(|(b, tris)| {
            // h: the longest edge of the body's triangles
            let bh = unique_edges(tris)
                .iter()
                .map(|e| {
                    (0..3)
                        .map(|c| (x[3 * e[1] + c] - x[3 * e[0] + c]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max);
            BodyPart {
                name: names[b].into(),
                kind: BodyKind::Surface,
                vertices: if b < 2 {
                    (b * nb..(b + 1) * nb).collect()
                } else {
                    (box_off..nv).collect()
                },
                elements: tris.iter().map(|t| [t[0], t[1], t[2], 0]).collect(),
                arity: 3,
                h: Some(bh),
                edges: None,
                faces: None,
            }
        })
        .collect();
    let mesh = assemble_mesh(3, x.clone(), fixed, &parts, &file_order(3));
    mesh.validate()?;
    let (distance, pair) = min_distance_3d(&mesh, &x, eps);
    if distance < eps {
        return Err(Balloons3dError::InadmissibleStart {
            pair: format!("{pair:?}"),
            distance,
            eps,
        });
    }
    // each balloon: its membrane, then its gas; the box: nothing
    let balloon = BodyPhysics {
        material: Some(Material::StvkMembrane {
            mu: p.mu,
            lambda: p.lambda,
        }),
        gas: Some(p.c),
        ..Default::default()
    };
    let physics = Physics {
        bodies: vec![balloon.clone(), balloon, BodyPhysics::default()],
        ..Default::default()
    };
    let energy = assemble_energy(&mesh, &x, &physics)?;
    Ok(Scene {
        name: "balloons3d".into(),
        mesh,
        energy,
        eps,
        h,
        x0: x,
    })
}

/// The `balloons3d` scene in the scene registry: its parameters are the numeric fields of
/// [`Balloons3dParams`]; the level for a mesh size h is the smallest whose [`mesh_size`] is at most h.
pub struct Balloons3d;

impl LevelScene for Balloons3d {
    type P = Balloons3dParams;
    const NAME: &'static str = "balloons3d";
    const MAX_LEVEL: usize = 7;

    fn params(n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Balloons3dParams> {
        let mut p = Balloons3dParams {
            n,
            eps,
            ..Default::default()
        };
        set_fields(
            "balloons3d",
            &mut p,
            params,
            &[
                ("mu", |p| &mut p.mu),
                ("lambda", |p| &mut p.lambda),
                ("c", |p| &mut p.c),
                ("radius", |p| &mut p.radius),
                ("pad_gap", |p| &mut p.pad_gap),
                ("twist_deg", |p| &mut p.twist_deg),
                ("pad_radius", |p| &mut p.pad_radius),
            ],
            &[],
        )?;
        Ok(p)
    }

    fn level(p: &Balloons3dParams) -> usize {
        p.n
    }

    fn at_level(p: &Balloons3dParams, n: usize) -> Balloons3dParams {
        Balloons3dParams { n, ..p.clone() }
    }

    fn build_scene(p: &Balloons3dParams) -> anyhow::Result<Scene> {
        Ok(build(p)?)
    }

    fn mesh_size(p: &Balloons3dParams) -> f64 {
        mesh_size(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::p3;
    use crate::energy::Gas3dEnergy;

    #[test]
    fn balloons3d_icosphere_counts() {
        for level in 0..4 {
            let (pts, tris) = icosphere(level);
            let f = 20 * 4usize.pow(level as u32);
            assert_eq!(tris.len(), f);
            assert_eq!(pts.len(), f / 2 + 2);
            assert_eq!(unique_edges(&tris).len(), 3 * f / 2);
            assert!(pts.iter().all(|p| (p.norm() - 1.0).abs() < 1e-14));
            assert_eq!(crate::energy::gas::open_edge(&tris), None);
        }
    }

    #[test]
    fn balloons3d_default_mesh_counts_and_admissibility() {
        let s = build(&Balloons3dParams::default()).unwrap();
        let m = &s.mesh;
        assert_eq!(s.name, "balloons3d");
        assert_eq!(m.validate(), Ok(()));
        // balloons: 42 vertices, 120 edges, 80 faces each; box 2 × 1 × 1 cells: 12 vertices,
        // 30 edges, 20 faces
        assert_eq!(m.nv(), 96);
        assert_eq!(m.edges.len(), 270);
        assert_eq!(m.faces.len(), 180);
        assert_eq!(m.triangles, m.faces);
        assert_eq!(m.contact_vertices().len(), m.nv());
        let counts: Vec<(usize, usize, usize)> = m
            .bodies
            .iter()
            .map(|b| (b.vertices.len(), b.edges.len(), b.faces.len()))
            .collect();
        assert_eq!(counts, vec![(42, 120, 80), (42, 120, 80), (12, 30, 20)]);
        // fixed: the box and three pad vertices per balloon, at pad_gap above the floor
        assert_eq!(m.fixed.iter().filter(|&&f| f).count(), 12 + 6);
        for v in 0..2 * 42 {
            if m.fixed[v] {
                assert_eq!(s.x0[3 * v + 2], -1.0 + 0.05);
            } else {
                assert!(s.x0[3 * v + 2] > -1.0 + 0.05);
            }
        }
        assert!((s.h - mesh_size(&Balloons3dParams::default())).abs() < 1e-15);
        assert!((s.eps - (s.h / 10.0).min(0.025)).abs() < 1e-15);
        let (d, _) = min_distance_3d(m, &s.x0, s.eps);
        assert!(d >= s.eps, "{d}");
        assert!((d - 0.05).abs() < 1e-12, "{d}"); // the pads
        assert!(s.energy.value(&s.x0).is_finite());
        let mut e = m.edges.clone();
        e.sort_unstable();
        e.dedup();
        assert_eq!(e.len(), m.edges.len());
    }

    #[test]
    fn balloons3d_gas_on_closed_outward_surfaces() {
        let p = Balloons3dParams::default();
        let s = build(&p).unwrap();
        let m = &s.mesh;
        let sphere = 4.0 / 3.0 * std::f64::consts::PI * p.radius.powi(3);
        for b in 0..2 {
            let tris: Vec<[usize; 3]> = m.bodies[b].faces.iter().map(|&f| m.faces[f]).collect();
            // outward as stored: Σ centroid·normal·area > 0, i.e. the enclosed volume
            let vol: f64 = tris
                .iter()
                .map(|t| {
                    let (a, bb, c) = (p3(&s.x0, t[0]), p3(&s.x0, t[1]), p3(&s.x0, t[2]));
                    a.dot(&bb.cross(&c)) / 6.0
                })
                .sum();
            assert!(vol > 0.75 * sphere && vol < sphere, "{vol} vs {sphere}");
            let gas = Gas3dEnergy::new(tris.clone(), p.c, &s.x0).unwrap();
            assert_eq!(gas.region.triangles(), &tris[..]); // not reversed: already outward
            assert!((gas.region.volume(&s.x0) - vol).abs() < 1e-12);
            // the pad is one of the balloon's triangles
            let pad: Vec<usize> = m.bodies[b]
                .vertices
                .iter()
                .copied()
                .filter(|&v| m.fixed[v])
                .collect();
            assert!(tris.iter().any(|t| pad.iter().all(|v| t.contains(v))));
        }
        // the gas pushes outward: −∇J points away from each balloon's centre on average
        let g = s.energy.gradient(&s.x0);
        for (b, xc) in CENTRES_X.iter().enumerate() {
            let c = Vector3::new(*xc, 0.0, 0.0);
            let out: f64 = m.bodies[b]
                .vertices
                .iter()
                .filter(|&&v| !m.fixed[v])
                .map(|&v| -Vector3::new(g[3 * v], g[3 * v + 1], 0.0).dot(&(p3(&s.x0, v) - c)))
                .sum();
            assert!(out > 0.0);
        }
    }

    #[test]
    fn balloons3d_other_levels() {
        let s = build(&Balloons3dParams {
            n: 2,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(s.mesh.nv(), 2 * 162 + 42);
        assert_eq!(s.mesh.edges.len(), 2 * 480 + 120);
        assert_eq!(s.mesh.faces.len(), 2 * 320 + 80);
        assert_eq!(s.eps, 0.025);
        assert!(s.energy.value(&s.x0).is_finite());
    }

    #[test]
    fn balloons3d_pad_radius_glues_a_cap_of_that_size_at_every_level() {
        // 0 (the default): the pad triangle's three vertices per balloon, at every level
        for n in [1, 3] {
            let s = build(&Balloons3dParams {
                n,
                ..Default::default()
            })
            .unwrap();
            let nb = s.mesh.bodies[0].vertices.len();
            assert_eq!(s.mesh.fixed[..2 * nb].iter().filter(|&&f| f).count(), 6);
        }
        let r = 0.25;
        let mut glued = Vec::new();
        for n in [1, 3, 4] {
            let p = Balloons3dParams {
                n,
                pad_radius: r,
                ..Default::default()
            };
            let s = build(&p).unwrap();
            let m = &s.mesh;
            for b in 0..2 {
                let verts = &m.bodies[b].vertices;
                let fixed: Vec<usize> = verts.iter().copied().filter(|&v| m.fixed[v]).collect();
                // the glued vertices lie in one cap around the pad: each within 2r of the
                // balloon's lowest vertex
                let lowest = *verts
                    .iter()
                    .min_by(|&&a, &&c| s.x0[3 * a + 2].total_cmp(&s.x0[3 * c + 2]))
                    .unwrap();
                for &v in &fixed {
                    assert!((p3(&s.x0, v) - p3(&s.x0, lowest)).norm() < 2.0 * r + 1e-12);
                }
                if b == 0 {
                    glued.push(fixed.len());
                }
            }
            let (d, _) = min_distance_3d(m, &s.x0, s.eps);
            assert!(d >= s.eps, "n = {n}: {d}");
        }
        // the region keeps its size, so it holds more vertices at finer levels (the pad's 3
        // at n = 1)
        assert_eq!(glued, vec![3, 14, 61]);
    }

    #[test]
    fn balloons3d_bad_params_are_named() {
        let msg = |p: Balloons3dParams| build(&p).err().unwrap().to_string();
        for (v, shown) in [(-0.1, "-0.1"), (0.8, "0.8"), (f64::NAN, "NaN")] {
            let e = msg(Balloons3dParams {
                pad_radius: v,
                ..Default::default()
            });
            assert!(e.contains(&format!("invalid pad_radius = {shown}")), "{e}");
        }
        let e = msg(Balloons3dParams {
            n: 0,
            ..Default::default()
        });
        assert!(e.contains("invalid n = 0"), "{e}");
        let e = msg(Balloons3dParams {
            n: 8,
            ..Default::default()
        });
        assert!(e.contains("invalid n = 8"), "{e}");
        for (eps, shown) in [(0.0, "0"), (-0.1, "-0.1"), (f64::NAN, "NaN")] {
            let e = msg(Balloons3dParams {
                eps: Some(eps),
                ..Default::default()
            });
            assert!(e.contains(&format!("invalid eps = {shown}")), "{e}");
        }
        let e = msg(Balloons3dParams {
            c: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid c = NaN"), "{e}");
        let e = msg(Balloons3dParams {
            mu: -1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid mu = -1"), "{e}");
        let e = msg(Balloons3dParams {
            lambda: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid lambda = NaN"), "{e}");
        let e = msg(Balloons3dParams {
            radius: 1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid radius = 1"), "{e}");
        let e = msg(Balloons3dParams {
            pad_gap: 0.5,
            ..Default::default()
        });
        assert!(e.contains("invalid pad_gap = 0.5"), "{e}");
        let e = msg(Balloons3dParams {
            twist_deg: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid twist_deg = NaN"), "{e}");
        // the pads closer to the floor than ε: refused
        let e = msg(Balloons3dParams {
            eps: Some(0.06),
            ..Default::default()
        });
        assert!(e.contains("not admissible"), "{e}");
    }
}
