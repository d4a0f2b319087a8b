//! The balloons scene of §7 (Figure 2); docs/scenes.md.
//!
//! Box `[-1,1]²`, its boundary a fixed closed polyline. On each wall, centred, a support
//! segment of length 1.6; a membrane (reference length 1.6, `n` uniform P1 edges,
//! `h = 1.6/n`) is glued to the box at the support's ends (shared vertices). Energy
//! `I = Σ_i ∫ W(ψ̇_i) − C_i ln V_i`, `W(F) = μ(|F|²−1)²` for `|F| ≥ 1`, 0 otherwise; `V_i` the
//! area between membrane i and its support (shoelace). Defaults `μ = 1`, `C = 50`, `ε = h/10`,
//! initial shape a parabola of height 0.2 above the support.
//!
//! Balloon 0 sits on the bottom wall, 1 on the right, 2 on the top, 3 on the left; the
//! opposite pairs are (0, 2) and (1, 3).

use super::Scene;
use crate::scene::assemble::{assemble_mesh, BodyPart};
use crate::scene::mesh::{BodyKind, Mesh};
use crate::scene::physics::{assemble_energy, BodyPhysics, Material, Physics, TermError};
use crate::scene::registry::{BuiltinScene, Params};
use thiserror::Error;

/// Parameters of the balloons scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BalloonsParams {
    /// Elements per membrane.
    pub n: usize,
    /// Gas constant C (before perturbation).
    pub c: f64,
    /// Elasticity coefficient μ.
    pub mu: f64,
    /// ε; `None` means h/10.
    pub eps: Option<f64>,
    /// Relative perturbation of each `C_i`: `C_i = C (1 + perturb[i])`.
    pub perturb: [f64; 4],
    /// Initial parabola height of each balloon.
    pub heights: [f64; 4],
    /// Balloons 1 and 3 (right and left) have `round(n_ratio · n)` elements where balloons 0
    /// and 2 have `n` (≥ 1; 1: the same mesh everywhere). Bodies of different mesh sizes, whose
    /// contacting vertices do not face each other.
    pub n_ratio: f64,
}

impl Default for BalloonsParams {
    fn default() -> Self {
        BalloonsParams {
            n: 40,
            c: 50.0,
            mu: 1.0,
            eps: None,
            perturb: [0.0; 4],
            heights: [0.2; 4],
            n_ratio: 1.0,
        }
    }
}

/// A parameter out of range; names it.
#[derive(Debug, Error, PartialEq)]
pub enum BalloonsError {
    /// The parameter and why it is rejected.
    #[error("balloons: invalid {name} = {value}: {reason}")]
    Invalid {
        /// Parameter name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// Why.
        reason: &'static str,
    },
    /// An energy term that cannot be built.
    #[error("balloons: {0}")]
    Energy(#[from] TermError),
}

impl BalloonsParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), BalloonsError> {
        let bad = |name, value: String, reason| {
            Err(BalloonsError::Invalid {
                name,
                value,
                reason,
            })
        };
        if self.n < 2 {
            return bad(
                "n",
                self.n.to_string(),
                "need at least 2 elements per membrane",
            );
        }
        if !(self.c > 0.0 && self.c.is_finite()) {
            return bad("c", self.c.to_string(), "must be finite and > 0");
        }
        if !(self.mu > 0.0 && self.mu.is_finite()) {
            return bad("mu", self.mu.to_string(), "must be finite and > 0");
        }
        if let Some(e) = self.eps {
            if !(e > 0.0 && e.is_finite()) {
                return bad("eps", e.to_string(), "must be finite and > 0");
            }
        }
        for (i, p) in self.perturb.iter().enumerate() {
            if !(p.is_finite() && *p > -1.0) {
                return bad(
                    "perturb",
                    format!("{p} (balloon {i})"),
                    "must be finite and > -1",
                );
            }
        }
        if !(self.n_ratio.is_finite() && self.n_ratio >= 1.0 && self.n_ratio <= 100.0) {
            return bad("n_ratio", self.n_ratio.to_string(), "must be in [1, 100]");
        }
        for (i, hgt) in self.heights.iter().enumerate() {
            if !(hgt.is_finite() && *hgt > 0.0 && *hgt < 2.0) {
                return bad(
                    "heights",
                    format!("{hgt} (balloon {i})"),
                    "must be in (0, 2)",
                );
            }
        }
        Ok(())
    }
}

/// Rotation of balloon `k` (by k·90° counter-clockwise): bottom, right, top, left.
fn rot(k: usize, p: [f64; 2]) -> [f64; 2] {
    match k % 4 {
        0 => p,
        1 => [-p[1], p[0]],
        2 => [-p[0], -p[1]],
        _ => [p[1], -p[0]],
    }
}

/// Builds the scene.
#[allow(clippy::needless_range_loop)] // k is the balloon index, used beyond indexing
pub fn build(p: &BalloonsParams) -> Result<Scene, BalloonsError> {
    p.validate()?;
    let n = p.n;
    let h = 1.6 / n as f64;
    let eps = p.eps.unwrap_or(h / 10.0);
    let mut x_ref: Vec<f64> = Vec::new();
    let mut x0: Vec<f64> = Vec::new();
    let mut fixed: Vec<bool> = Vec::new();
    let push = |x_ref: &mut Vec<f64>,
                x0: &mut Vec<f64>,
                fixed: &mut Vec<bool>,
                r: [f64; 2],
                i: [f64; 2],
                f: bool| {
        x_ref.extend_from_slice(&r);
        x0.extend_from_slice(&i);
        fixed.push(f);
        fixed.len() - 1
    };
    // Box polyline, counter-clockwise from the bottom-left corner: per wall k, the corner
    // then the two support ends.
    let mut box_vertices = Vec::new();
    let mut support_ends = [[0usize; 2]; 4];
    for k in 0..4 {
        for (j, q) in [[-1.0, -1.0], [-0.8, -1.0], [0.8, -1.0]].iter().enumerate() {
            let r = rot(k, *q);
            let v = push(&mut x_ref, &mut x0, &mut fixed, r, r, true);
            box_vertices.push(v);
            if j > 0 {
                support_ends[k][j - 1] = v;
            }
        }
    }
    let nb = box_vertices.len();
    let box_part = BodyPart {
        name: "box".into(),
        kind: BodyKind::Curve,
        vertices: box_vertices.clone(),
        elements: (0..nb)
            .map(|i| [box_vertices[i], box_vertices[(i + 1) % nb], 0, 0])
            .collect(),
        arity: 2,
        h: Some(0.2),
        edges: None,
        faces: None,
    };
    let mut parts = Vec::new();
    for k in 0..4 {
        // Elements of this membrane: n, or round(n_ratio·n) on balloons 1 and 3.
        let nk = if k % 2 == 1 {
            (p.n_ratio * n as f64).round() as usize
        } else {
            n
        };
        // Membrane vertices from the support's left end to its right end (in wall frame).
        let mut verts = vec![support_ends[k][0]];
        for i in 1..nk {
            let s = -0.8 + 1.6 * i as f64 / nk as f64;
            let y = -1.0 + p.heights[k] * (1.0 - (s / 0.8).powi(2));
            let v = push(
                &mut x_ref,
                &mut x0,
                &mut fixed,
                rot(k, [s, -1.0]),
                rot(k, [s, y]),
                false,
            );
            verts.push(v);
        }
        verts.push(support_ends[k][1]);
        parts.push(BodyPart {
            name: format!("balloon{k}"),
            kind: BodyKind::Curve,
            elements: verts.windows(2).map(|w| [w[0], w[1], 0, 0]).collect(),
            vertices: verts,
            arity: 2,
            h: Some(1.6 / nk as f64),
            edges: None,
            faces: None,
        });
    }
    parts.push(box_part);
    // The box (body 4) was numbered first: its edges come first too.
    let mesh = assemble_mesh(2, x_ref, fixed, &parts, &[4, 0, 1, 2, 3]);
    // Each balloon: the membrane, then the gas between it and its support; the box: nothing.
    let balloon = |k: usize| BodyPhysics {
        material: Some(Material::String { mu: p.mu }),
        gas: Some(p.c * (1.0 + p.perturb[k])),
        ..Default::default()
    };
    let physics = Physics {
        bodies: (0..4)
            .map(balloon)
            .chain([BodyPhysics::default()])
            .collect(),
        ..Default::default()
    };
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    Ok(Scene {
        name: "balloons".into(),
        mesh,
        energy,
        eps,
        h,
        x0,
    })
}

/// The equilibrium reached, read from the contact pattern (docs/scenes.md).
pub fn classify_state(touching: &[(usize, usize)]) -> String {
    let has = |a: usize, b: usize| {
        touching
            .iter()
            .any(|&(i, j)| (i == a && j == b) || (i == b && j == a))
    };
    let opposite: Vec<String> = [(0, 2), (1, 3)]
        .iter()
        .filter(|&&(a, b)| has(a, b))
        .map(|(a, b)| format!("{a}-{b}"))
        .collect();
    let adjacent = [(0, 1), (1, 2), (2, 3), (0, 3)]
        .iter()
        .filter(|&&(a, b)| has(a, b))
        .count();
    if !opposite.is_empty() {
        format!("broken({})", opposite.join(","))
    } else if adjacent == 4 {
        "symmetric".into()
    } else {
        format!("other({adjacent}_adjacent_pairs)")
    }
}

/// The balloons in the scene registry: parameters `c`, `mu`, `perturb0..perturb3`, `height0..height3` (the `--heights` of `contactlab run`), `n_ratio`; level
/// `n` elements per membrane, `h = 1.6/n`; end states classified by [`classify_state`].
pub struct Balloons;

impl BuiltinScene for Balloons {
    fn name(&self) -> &'static str {
        "balloons"
    }

    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Scene> {
        let mut p = BalloonsParams {
            n,
            eps,
            ..Default::default()
        };
        for (k, &v) in params {
            match k.as_str() {
                "c" => p.c = v,
                "mu" => p.mu = v,
                "perturb0" => p.perturb[0] = v,
                "perturb1" => p.perturb[1] = v,
                "perturb2" => p.perturb[2] = v,
                "perturb3" => p.perturb[3] = v,
                "height0" => p.heights[0] = v,
                "height1" => p.heights[1] = v,
                "height2" => p.heights[2] = v,
                "height3" => p.heights[3] = v,
                "n_ratio" => p.n_ratio = v,
                other => anyhow::bail!(
                    "scene balloons: unknown parameter {other:?} (known: c, mu, perturb0..perturb3, height0..height3, n_ratio)"
                ),
            }
        }
        Ok(build(&p)?)
    }

    /// `h = 1.6/n`, so `n = ⌈1.6/h⌉`.
    fn n_for_h(&self, h: f64, _params: &Params) -> anyhow::Result<usize> {
        let mut n = (1.6 / h).ceil().max(1.0) as usize;
        // guard the rounding of 1.6/h
        while n > 1 && 1.6 / ((n - 1) as f64) <= h {
            n -= 1;
        }
        Ok(n)
    }

    fn classify_state(
        &self,
        mesh: &Mesh,
        _x: &[f64],
        _eps: f64,
        pattern: &[(usize, usize)],
    ) -> Option<String> {
        // by name: a scene file lists the box first (experiments/scenes/balloons.toml)
        let balloon = |b: usize| {
            mesh.bodies[b]
                .name
                .strip_prefix("balloon")
                .and_then(|k| k.parse::<usize>().ok())
                .filter(|&k| k < 4)
        };
        let balloon_pairs: Vec<(usize, usize)> = pattern
            .iter()
            .filter_map(|&(i, j)| Some((balloon(i)?, balloon(j)?)))
            .collect();
        Some(classify_state(&balloon_pairs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classify() {
        assert_eq!(
            classify_state(&[(0, 1), (1, 2), (2, 3), (0, 3)]),
            "symmetric"
        );
        assert_eq!(classify_state(&[(0, 1), (0, 2), (2, 3)]), "broken(0-2)");
        assert_eq!(classify_state(&[]), "other(0_adjacent_pairs)");
    }

    #[test]
    fn bad_params_are_named() {
        let e = build(&BalloonsParams {
            n: 1,
            ..Default::default()
        })
        .err()
        .unwrap();
        assert!(e.to_string().contains("invalid n = 1"), "{e}");
        let e = build(&BalloonsParams {
            heights: [0.2, f64::NAN, 0.2, 0.2],
            ..Default::default()
        })
        .err()
        .unwrap();
        assert!(e.to_string().contains("balloon 1"), "{e}");
        for bad in [0.5, f64::INFINITY, 101.0] {
            let e = build(&BalloonsParams {
                n_ratio: bad,
                ..Default::default()
            })
            .err()
            .unwrap();
            assert!(e.to_string().contains("invalid n_ratio"), "{e}");
        }
    }

    #[test]
    fn n_ratio_refines_balloons_1_and_3_only() {
        let s = build(&BalloonsParams {
            n: 8,
            n_ratio: 1.5,
            ..Default::default()
        })
        .unwrap();
        let body = |name: &str| s.mesh.bodies.iter().find(|b| b.name == name).unwrap();
        for (name, elements) in [
            ("balloon0", 8),
            ("balloon1", 12),
            ("balloon2", 8),
            ("balloon3", 12),
        ] {
            let b = body(name);
            assert_eq!(b.edges.len(), elements, "{name}");
            assert!(
                (b.h - 1.6 / elements as f64).abs() < 1e-15,
                "{name}: h {}",
                b.h
            );
        }
        // the scene's h (and ε = h/10) stay those of the coarser membranes
        assert!((s.h - 0.2).abs() < 1e-15 && (s.eps - 0.02).abs() < 1e-15);
        // the same ratio 1 is the scene as before
        let plain = build(&BalloonsParams {
            n: 8,
            ..Default::default()
        })
        .unwrap();
        let one = build(&BalloonsParams {
            n: 8,
            n_ratio: 1.0,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(plain.x0, one.x0);
    }
}
