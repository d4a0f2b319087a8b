//! Two solids: a compressed tetrahedral block relaxing onto another one (3D contact between
//! the boundaries of two non-thin bodies).
//!
//! **Geometry.** Two cubes of P1 tetrahedra ([`BodyKind::Solid`]), each an `n × n × n` grid
//! of cells, every cell cut into the 6 tetrahedra of its Kuhn subdivision (around the cell
//! diagonal from its low corner to its high corner: conforming between cells), all stored with
//! positive reference volume. The contact elements of each block are its boundary faces
//! (`12 n²` triangles, oriented outward) and their edges; its `(n − 1)³` interior vertices are
//! not contact vertices.
//!
//! * `lower` (body 0): the cube `[−½, ½]² × [−1, 0]`, `x0 = x_ref` (unstressed), its bottom
//!   face `z = −1` fixed.
//! * `upper` (body 1): in the reference, the cube of side `s = upper_size` rotated by
//!   `angle_deg` (default 20°) about the z axis (so its edges do not align with the lower
//!   block's), spanning `z ∈ [z_top − s, z_top]` with `z_top = s − overlap`: relaxed, it would
//!   reach `overlap` below the lower block's top face `z = 0`. Its top face is fixed. In `x0`
//!   it is compressed along z towards its top, `z ↦ z_top − c (z_top − z)` with
//!   `c = (s − overlap − gap) / s`, so that its bottom face lies at `z = gap` above the lower
//!   block. The rotated footprint must lie inside the lower block's top face
//!   (`s (|cos θ| + |sin θ|) < 1`).
//!
//! **Energy.** The compressible neo-Hookean energy ([`crate::energy::NeoHookean3d`],
//! `W = μ/2 (|F|² − 3) − μ ln J + λ/2 (ln J)²`) on both blocks, no gravity.
//!
//! **Defaults.** `n = 3` (per block 64 vertices, 8 of them interior, 162 tets, 108 faces,
//! 162 edges), `μ = 1`, `λ = 1`, `angle_deg = 20`, `upper_size = 0.7`, `overlap = 0.1`,
//! `gap = 0.1` (so `c = 5/7`); `h` = the largest reference edge (the lower
//! cells' diagonal `√3/n`), `ε = min(h/10, gap/2)` = 0.05.
//!
//! **At the minimum.** Without contact the upper block would relax to its reference,
//! `overlap` deep inside the lower one. So at the constrained minimum its bottom face is
//! pressed onto the lower block's top face at distance ε over the whole (rotated) footprint,
//! both blocks compressed: vertex–triangle rows (bottom vertices of the upper block over top
//! faces of the lower one and conversely) and edge–edge rows (the 20° rotation makes the
//! edges cross) are active. The fixed bottom and top faces leave no rigid motion.

#[cfg(test)]
use super::sheets::unique_edges;
use super::stacked::{self, Block, StackError};
use super::Scene;
use crate::scene::mesh::{BodyKind, MeshError};
use crate::scene::physics::{
    assemble_energy, BodyPhysics, ElasticTerms, Material, Physics, TermError,
};
use crate::scene::registry::{set_fields, LevelScene, Params};
use nalgebra::Vector3;
use std::collections::HashMap;
use thiserror::Error;

/// Parameters of the solids scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolidsParams {
    /// Mesh level: each block is an `n × n × n` grid of cells (n ≥ 1).
    pub n: usize,
    /// ε; `None` means `min(h/10, gap/2)`.
    pub eps: Option<f64>,
    /// Shear modulus μ.
    pub mu: f64,
    /// Lamé's first parameter λ (≥ 0).
    pub lambda: f64,
    /// Rotation of the upper block about z, in degrees.
    pub angle_deg: f64,
    /// Side of the upper block (the lower one has side 1).
    pub upper_size: f64,
    /// Depth the relaxed upper block would reach inside the lower one (> 0).
    pub overlap: f64,
    /// Distance between the blocks in `x0` (> 0).
    pub gap: f64,
    /// Stiffness contrast: the upper block's μ and λ are `contrast` times the lower block's
    /// (> 0; the extremes experiment sweeps it from 1 to 1e8).
    pub contrast: f64,
}

impl Default for SolidsParams {
    fn default() -> Self {
        SolidsParams {
            n: 3,
            eps: None,
            mu: 1.0,
            lambda: 1.0,
            angle_deg: 20.0,
            upper_size: 0.7,
            overlap: 0.1,
            gap: 0.1,
            contrast: 1.0,
        }
    }
}

/// A parameter out of range, or a start that is not admissible; names the parameter.
#[derive(Debug, Error, PartialEq)]
pub enum SolidsError {
    /// The parameter and why it is rejected.
    #[error("solids: invalid {name} = {value}: {reason}")]
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
        "solids: the initial configuration is not admissible: {pair} at distance \
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
    /// The generated mesh is invalid.
    #[error("solids: invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    /// An energy term that cannot be built (a generated tetrahedron is degenerate).
    #[error("solids: {0}")]
    Energy(#[from] TermError),
}

impl From<StackError> for SolidsError {
    fn from(e: StackError) -> Self {
        match e {
            StackError::Mesh(e) => SolidsError::Mesh(e),
            StackError::InadmissibleStart {
                pair,
                distance,
                eps,
            } => SolidsError::InadmissibleStart {
                pair,
                distance,
                eps,
            },
        }
    }
}

/// `h`: the largest reference edge, the lower block's cell diagonal `√3/n`.
pub fn mesh_size(p: &SolidsParams) -> f64 {
    // (the upper block is smaller: validate requires upper_size < 1)
    3f64.sqrt() / p.n as f64
}

impl SolidsParams {
    /// Checks every parameter (not the admissibility of the start: [`build`] does that).
    pub fn validate(&self) -> Result<(), SolidsError> {
        let bad = |name, value: String, reason: &str| {
            Err(SolidsError::Invalid {
                name,
                value,
                reason: reason.into(),
            })
        };
        if self.n == 0 || self.n > 200 {
            return bad("n", self.n.to_string(), "must be in 1..=200");
        }
        if let Some(e) = self.eps {
            if !(e > 0.0 && e.is_finite()) {
                return bad("eps", e.to_string(), "must be finite and > 0");
            }
        }
        for (name, v) in [
            ("mu", self.mu),
            ("upper_size", self.upper_size),
            ("overlap", self.overlap),
            ("gap", self.gap),
            ("contrast", self.contrast),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(name, v.to_string(), "must be finite and > 0");
            }
        }
        if !(self.lambda >= 0.0 && self.lambda.is_finite()) {
            return bad("lambda", self.lambda.to_string(), "must be finite and ≥ 0");
        }
        if !self.angle_deg.is_finite() {
            return bad("angle_deg", self.angle_deg.to_string(), "must be finite");
        }
        if stacked::rotated_extent(self.upper_size, self.angle_deg) >= 1.0 {
            return bad(
                "upper_size",
                self.upper_size.to_string(),
                "the rotated upper block must stand inside the lower block's top face \
                 (upper_size · (|cos θ| + |sin θ|) < 1)",
            );
        }
        if self.overlap + self.gap >= 0.9 * self.upper_size {
            return bad(
                "overlap",
                self.overlap.to_string(),
                "overlap + gap must be < 0.9 · upper_size (the compressed upper block keeps \
                 at least a tenth of its height)",
            );
        }
        Ok(())
    }
}

/// A cube grid of `m³` cells on `[0, 1]³`: the points (`(k(m+1) + j)(m+1) + i` at
/// `(i, j, l)/m`), the Kuhn tetrahedra (positively oriented) and the outward boundary faces.
#[allow(clippy::type_complexity)]
fn unit_cube(m: usize) -> (Vec<[f64; 3]>, Vec<[usize; 4]>, Vec<[usize; 3]>) {
    let idx = |i: usize, j: usize, k: usize| (k * (m + 1) + j) * (m + 1) + i;
    let mut pts = Vec::with_capacity((m + 1).pow(3));
    for k in 0..=m {
        for j in 0..=m {
            for i in 0..=m {
                pts.push([i as f64, j as f64, k as f64].map(|c| c / m as f64));
            }
        }
    }
    let pv = |v: usize| Vector3::from(pts[v]);
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut tets = Vec::with_capacity(6 * m * m * m);
    for k in 0..m {
        for j in 0..m {
            for i in 0..m {
                let corner = |b: usize| idx(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                for p in perms {
                    let b1 = 1 << p[0];
                    let b2 = b1 | (1 << p[1]);
                    let mut t = [corner(0), corner(b1), corner(b2), corner(7)];
                    let a = pv(t[0]);
                    let vol = (pv(t[1]) - a).cross(&(pv(t[2]) - a)).dot(&(pv(t[3]) - a));
                    if vol < 0.0 {
                        t.swap(1, 2);
                    }
                    tets.push(t);
                }
            }
        }
    }
    // boundary faces: those of exactly one tet, oriented away from the tet's fourth vertex
    let mut count: HashMap<[usize; 3], (usize, [usize; 3], usize)> = HashMap::new();
    for t in &tets {
        for opp in 0..4 {
            let f = [t[(opp + 1) % 4], t[(opp + 2) % 4], t[(opp + 3) % 4]];
            let mut key = f;
            key.sort_unstable();
            count.entry(key).or_insert((0, f, t[opp])).0 += 1;
        }
    }
    let mut faces: Vec<[usize; 3]> = count
        .into_values()
        .filter(|&(c, _, _)| c == 1)
        .map(|(_, mut f, o)| {
            let (a, b, c) = (pv(f[0]), pv(f[1]), pv(f[2]));
            if (b - a).cross(&(c - a)).dot(&(a - pv(o))) < 0.0 {
                f.swap(1, 2);
            }
            f
        })
        .collect();
    faces.sort_unstable();
    (pts, tets, faces)
}

/// Builds the scene (name `solids`). Vertices: the lower block's `(n+1)³` then the upper
/// block's; tets, faces and edges: the lower block's then the upper's.
pub fn build(p: &SolidsParams) -> Result<Scene, SolidsError> {
    p.validate()?;
    let m = p.n;
    let h = mesh_size(p);
    let eps = p.eps.unwrap_or((h / 10.0).min(0.5 * p.gap));
    let (pts, cube_tets, cube_faces) = unit_cube(m);
    let np = pts.len();
    let s = p.upper_size;
    let z_top = s - p.overlap;
    let comp = (s - p.overlap - p.gap) / s;
    let sc = stacked::sin_cos(p.angle_deg);
    let mut x_ref = Vec::with_capacity(6 * np);
    let mut x0 = Vec::with_capacity(6 * np);
    let mut fixed = Vec::with_capacity(2 * np);
    for q in &pts {
        let r = [q[0] - 0.5, q[1] - 0.5, q[2] - 1.0];
        x_ref.extend_from_slice(&r);
        x0.extend_from_slice(&r);
        fixed.push(q[2] == 0.0);
    }
    for q in &pts {
        let (u, v) = (s * (q[0] - 0.5), s * (q[1] - 0.5));
        let (x, y) = stacked::rotate_z(sc, u, v);
        let z = z_top - s * (1.0 - q[2]);
        x_ref.extend_from_slice(&[x, y, z]);
        x0.extend_from_slice(&[x, y, z_top - comp * (z_top - z)]);
        fixed.push(q[2] == 1.0);
    }
    let tets: Vec<[usize; 4]> = cube_tets
        .iter()
        .copied()
        .chain(cube_tets.iter().map(|t| t.map(|v| v + np)))
        .collect();
    let lower_faces = cube_faces.clone();
    let upper_faces: Vec<[usize; 3]> = cube_faces.iter().map(|f| f.map(|v| v + np)).collect();
    let nt = cube_tets.len();
    let block = |b: usize, faces: Vec<[usize; 3]>, h: f64| Block {
        elements: tets[b * nt..(b + 1) * nt].to_vec(),
        h,
        faces: Some(faces),
    };
    let blocks = [
        block(0, lower_faces, 3f64.sqrt() / m as f64),
        block(1, upper_faces, 3f64.sqrt() * s / m as f64),
    ];
    let mesh = stacked::assemble(BodyKind::Solid, 4, np, blocks, x_ref, fixed, &x0, eps)?;
    // One term over both blocks when they are alike (the sums of the committed results), one
    // per block otherwise.
    let solid = |c: f64| BodyPhysics {
        material: Some(Material::NeoHookean {
            mu: c * p.mu,
            lambda: c * p.lambda,
        }),
        ..Default::default()
    };
    let physics = Physics {
        bodies: vec![solid(1.0), solid(p.contrast)],
        gravity: None,
        elastic: if p.contrast == 1.0 {
            ElasticTerms::Joined
        } else {
            ElasticTerms::PerBody
        },
    };
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    Ok(Scene {
        name: "solids".into(),
        mesh,
        energy,
        eps,
        h,
        x0,
    })
}

/// The `solids` scene in the scene registry: its parameters are the numeric fields of
/// [`SolidsParams`]; the level for a mesh size h is the smallest whose [`mesh_size`] is at most h.
pub struct Solids;

impl LevelScene for Solids {
    type P = SolidsParams;
    const NAME: &'static str = "solids";
    const MAX_LEVEL: usize = 200;

    fn params(n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<SolidsParams> {
        let mut p = SolidsParams {
            n,
            eps,
            ..Default::default()
        };
        set_fields(
            "solids",
            &mut p,
            params,
            &[
                ("mu", |p| &mut p.mu),
                ("lambda", |p| &mut p.lambda),
                ("angle_deg", |p| &mut p.angle_deg),
                ("upper_size", |p| &mut p.upper_size),
                ("overlap", |p| &mut p.overlap),
                ("gap", |p| &mut p.gap),
                ("contrast", |p| &mut p.contrast),
            ],
            &[],
        )?;
        Ok(p)
    }

    fn level(p: &SolidsParams) -> usize {
        p.n
    }

    fn at_level(p: &SolidsParams, n: usize) -> SolidsParams {
        SolidsParams { n, ..p.clone() }
    }

    fn build_scene(p: &SolidsParams) -> anyhow::Result<Scene> {
        Ok(build(p)?)
    }

    fn mesh_size(p: &SolidsParams) -> f64 {
        mesh_size(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::broad_phase::min_distance_3d;
    use crate::contact::p3;

    /// `Σ_faces centroid · normal · area / 3`: the volume enclosed by outward faces.
    fn enclosed_volume(x: &[f64], faces: &[[usize; 3]]) -> f64 {
        faces
            .iter()
            .map(|f| {
                let (a, b, c) = (p3(x, f[0]), p3(x, f[1]), p3(x, f[2]));
                let n2a = (b - a).cross(&(c - a)); // normal × 2 area
                ((a + b + c) / 3.0).dot(&n2a) / 6.0
            })
            .sum()
    }

    #[test]
    fn solids_default_mesh_counts_and_admissibility() {
        let s = build(&SolidsParams::default()).unwrap();
        let m = &s.mesh;
        assert_eq!(s.name, "solids");
        assert_eq!(m.validate(), Ok(()));
        // per block: 64 vertices (8 interior), 162 tets, 108 faces, 162 edges
        assert_eq!(m.nv(), 128);
        assert_eq!(m.tets.len(), 324);
        assert_eq!(m.faces.len(), 216);
        assert_eq!(m.edges.len(), 324);
        assert!(m.triangles.is_empty());
        assert_eq!(m.contact_vertices().len(), 112);
        // fixed: the lower block's bottom and the upper block's top, 16 each
        assert_eq!(m.fixed.iter().filter(|&&f| f).count(), 32);
        assert!((s.h - 3f64.sqrt() / 3.0).abs() < 1e-15);
        assert!((s.eps - 0.05).abs() < 1e-15); // gap/2 < h/10
        let (d, _) = min_distance_3d(m, &s.x0, s.eps);
        assert!(d >= s.eps, "{d}");
        assert!((d - 0.1).abs() < 1e-12, "{d}"); // the gap
        let j = s.energy.value(&s.x0);
        assert!(j.is_finite() && j > 0.0, "{j}"); // the upper block is compressed
        assert!(s.energy.value(&m.x_ref).abs() < 1e-12);
        // the upper block's fixed top is where the reference puts it
        for v in 0..m.nv() {
            if m.fixed[v] {
                assert_eq!(s.x0[3 * v..3 * v + 3], m.x_ref[3 * v..3 * v + 3]);
            }
        }
        // relaxed, the upper block's bottom reaches overlap below the lower one's top
        let zmin = (64..128)
            .map(|v| m.x_ref[3 * v + 2])
            .fold(f64::INFINITY, f64::min);
        assert!((zmin + 0.1).abs() < 1e-12);
    }

    #[test]
    fn solids_faces_outward_edges_once() {
        let s = build(&SolidsParams::default()).unwrap();
        let m = &s.mesh;
        for (b, body) in m.bodies.iter().enumerate() {
            assert_eq!(body.kind, BodyKind::Solid);
            let faces: Vec<[usize; 3]> = body.faces.iter().map(|&f| m.faces[f]).collect();
            let vol = enclosed_volume(&m.x_ref, &faces);
            let (expected, tol) = if b == 0 { (1.0, 1e-12) } else { (0.343, 1e-12) };
            assert!((vol - expected).abs() < tol, "body {b}: {vol}");
            // each face outward on its own: normal away from the block's centre
            let c: Vector3<f64> = body
                .vertices
                .iter()
                .map(|&v| p3(&m.x_ref, v))
                .sum::<Vector3<f64>>()
                / body.vertices.len() as f64;
            for f in &faces {
                let (a, bb, cc) = (p3(&m.x_ref, f[0]), p3(&m.x_ref, f[1]), p3(&m.x_ref, f[2]));
                assert!((bb - a).cross(&(cc - a)).dot(&((a + bb + cc) / 3.0 - c)) > 0.0);
            }
            // tets: volumes sum to the block's
            let tv: f64 = body
                .tets
                .iter()
                .map(|&t| {
                    let t = m.tets[t];
                    let a = p3(&m.x_ref, t[0]);
                    (p3(&m.x_ref, t[1]) - a)
                        .cross(&(p3(&m.x_ref, t[2]) - a))
                        .dot(&(p3(&m.x_ref, t[3]) - a))
                        / 6.0
                })
                .sum();
            assert!((tv - vol).abs() < 1e-12);
        }
        let mut e = m.edges.clone();
        e.sort_unstable();
        e.dedup();
        assert_eq!(e.len(), m.edges.len());
        assert_eq!(e, unique_edges(&m.faces));
        // interior vertices of the lower block are not contact vertices
        let cv = m.contact_vertices();
        let interior = 21; // (i, j, k) = (1, 1, 1): (1·4 + 1)·4 + 1
        assert!(!cv.contains(&interior));
    }

    #[test]
    fn solids_other_levels() {
        for n in [1, 2, 4] {
            let s = build(&SolidsParams {
                n,
                ..Default::default()
            })
            .unwrap();
            let m = &s.mesh;
            assert_eq!(m.nv(), 2 * (n + 1).pow(3));
            assert_eq!(m.tets.len(), 12 * n * n * n);
            assert_eq!(m.faces.len(), 24 * n * n);
            assert!(s.energy.value(&s.x0).is_finite());
        }
    }

    #[test]
    fn solids_bad_params_are_named() {
        let msg = |p: SolidsParams| build(&p).err().unwrap().to_string();
        let e = msg(SolidsParams {
            n: 0,
            ..Default::default()
        });
        assert!(e.contains("invalid n = 0"), "{e}");
        for (eps, shown) in [(0.0, "0"), (-0.1, "-0.1"), (f64::NAN, "NaN")] {
            let e = msg(SolidsParams {
                eps: Some(eps),
                ..Default::default()
            });
            assert!(e.contains(&format!("invalid eps = {shown}")), "{e}");
        }
        let e = msg(SolidsParams {
            mu: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid mu = NaN"), "{e}");
        let e = msg(SolidsParams {
            lambda: -1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid lambda = -1"), "{e}");
        let e = msg(SolidsParams {
            angle_deg: f64::INFINITY,
            ..Default::default()
        });
        assert!(e.contains("invalid angle_deg = inf"), "{e}");
        let e = msg(SolidsParams {
            upper_size: 0.9,
            ..Default::default()
        });
        assert!(e.contains("invalid upper_size = 0.9"), "{e}");
        let e = msg(SolidsParams {
            overlap: 0.0,
            ..Default::default()
        });
        assert!(e.contains("invalid overlap = 0"), "{e}");
        let e = msg(SolidsParams {
            overlap: 0.6,
            ..Default::default()
        });
        assert!(e.contains("invalid overlap = 0.6"), "{e}");
        let e = msg(SolidsParams {
            gap: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid gap = NaN"), "{e}");
        let e = msg(SolidsParams {
            eps: Some(0.2),
            ..Default::default()
        });
        assert!(e.contains("not admissible"), "{e}");
        let e = msg(SolidsParams {
            contrast: 0.0,
            ..Default::default()
        });
        assert!(e.contains("invalid contrast = 0"), "{e}");
    }

    #[test]
    fn solids_contrast_scales_the_upper_block_only() {
        // E_c = E_lower + c · E_upper: affine in c, the same slope from any two contrasts; at
        // c = 1 it is the one-term energy of the committed results.
        let energy = |c: f64| {
            build(&SolidsParams {
                contrast: c,
                ..Default::default()
            })
            .unwrap()
        };
        let one = energy(1.0);
        // a deformed state: the relaxed x0 moved by a smooth field
        let x: Vec<f64> = one
            .x0
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.01 * ((i as f64) * 0.37).sin())
            .collect();
        let e1 = one.energy.value(&x);
        let (e7, e1e8) = (energy(7.0).energy.value(&x), energy(1e8).energy.value(&x));
        let upper = (e7 - e1) / 6.0;
        assert!(upper > 0.0, "{upper}");
        let rel = ((e1e8 - e1) / (1e8 - 1.0) - upper).abs() / upper;
        assert!(
            rel < 1e-9,
            "slopes {upper} and {} (rel {rel:e})",
            (e1e8 - e1) / (1e8 - 1.0)
        );
        assert_eq!(energy(1.0).energy.terms.len(), 1);
        assert_eq!(energy(7.0).energy.terms.len(), 2);
    }
}
