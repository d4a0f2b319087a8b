//! The vacuum-packed ring: one closed membrane under uniform external pressure, collapsing
//! until its two halves are pressed against each other at distance ε (SELF-contact).
//!
//! One closed P1 curve (body `ring`, [`BodyKind::Curve`]) of `n` edges. Reference
//! configuration: the regular `n`-gon inscribed in the circle of radius `R = 1`, so every
//! reference edge has length `h = 2 sin(π/n)` (≈ 2π/n). Energy
//!
//! ```text
//! J(φ) = Σ_edges ∫ W(φ̇) + p · A(φ),    W(F) = μ (|F|² − 1)² for |F| ≥ 1, 0 otherwise,
//! ```
//!
//! the membrane energy of the balloons ([`crate::energy::MembraneEnergy`]) and the pressure term
//! ([`crate::energy::PressureEnergy`], `A` the shoelace area enclosed by the ring): with `p > 0` it pulls the
//! ring inward. `ε = h/10` by default.
//!
//! Vertex `k` sits at the angle `θ_k = π + 2πk/n`: vertex 0 is the leftmost, `n/2` (n even)
//! the rightmost, `1 … n/2−1` the lower half, `n/2+1 … n−1` the upper half. The initial
//! configuration is the ellipse `(a cos θ_k, b sin θ_k)` with `a = half_span` and
//! `b = aspect · a`.
//!
//! **Why two pinned vertices, and why the span.** The membrane is tension-only and the
//! pressure pulls inward, so a ring held by one vertex has no equilibrium in tension: both the
//! pressure and any tension shorten it, compression costs nothing, and the ring shrinks and
//! crumples until the ε-rows of neighbouring elements stop it (measured: see the tests
//! `tests/ring.rs`). Tension needs the two ends held apart by more than the half rest perimeter `n sin(π/n)` (< π). So the
//! leftmost and rightmost vertices (0 and n/2) are fixed at `(∓a, 0)` with
//! `2a > n sin(π/n)`; the default `a = 2` stretches each flattened half by `F ≈ 4/π ≈ 1.27`.
//! Both halves are then taut strings between the pins; the pressure presses them together
//! over a flat contact zone where the contact force per length equals `p`, and near each pin
//! a free length `≈ √(ε T / p)` (`T = 4μF(F²−1)` the tension) over which the halves open from
//! the shared pin to the gap ε. With the pins fixed no rigid motion is left, and the
//! stretched membrane makes the Hessian positive definite.

use super::Scene;
use crate::contact::broad_phase::{min_distance_2d, point_edge_near, NearPair};
use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};
use crate::scene::mesh::{BodyKind, Mesh};
use crate::scene::physics::{assemble_energy, BodyPhysics, Material, Physics, TermError};
use crate::scene::registry::{BuiltinScene, Params};
use thiserror::Error;

/// Which vertices of the ring are fixed (Dirichlet).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RingPins {
    /// Leftmost and rightmost vertices (0 and n/2): the scene's default, in tension.
    LeftRight,
    /// The leftmost vertex only. The tension-only ring has no tensioned equilibrium then: it
    /// shrinks and crumples (kept to reproduce that measurement, not as an experiment scene).
    Left,
}

/// Parameters of the ring scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RingParams {
    /// Number of edges (even, ≥ 6).
    pub n: usize,
    /// Elasticity coefficient μ of the membrane.
    pub mu: f64,
    /// External pressure p (> 0 pulls the ring inward).
    pub p: f64,
    /// ε; `None` means h/10 with `h = 2 sin(π/n)`.
    pub eps: Option<f64>,
    /// Initial ellipse ratio `b/a` (vertical over horizontal semi-axis), in (0, 1].
    pub aspect: f64,
    /// Horizontal semi-axis `a` of the initial ellipse = half the distance between the pins.
    /// With [`RingPins::LeftRight`] it must exceed `n sin(π/n)/2` (the half rest length of a
    /// half ring) so that the flattened ring is in tension.
    pub half_span: f64,
    /// Fixed vertices.
    pub pins: RingPins,
}

impl Default for RingParams {
    fn default() -> Self {
        RingParams {
            n: 20,
            mu: 1.0,
            p: 1.0,
            eps: None,
            aspect: 0.25,
            half_span: 2.0,
            pins: RingPins::LeftRight,
        }
    }
}

/// A parameter out of range, or a start that is not admissible; names the parameter.
#[derive(Debug, Error, PartialEq)]
pub enum RingError {
    /// The parameter and why it is rejected.
    #[error("ring: invalid {name} = {value}: {reason}")]
    Invalid {
        /// Parameter name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// Why.
        reason: String,
    },
    /// The initial ellipse has two disjoint elements closer than ε.
    #[error(
        "ring: the initial ellipse (half_span = {half_span}, aspect = {aspect}) is not \
         admissible: {pair} at distance {distance:.6e} < eps = {eps:.6e}; increase aspect or \
         lower eps"
    )]
    InadmissibleStart {
        /// `a`.
        half_span: f64,
        /// `b/a`.
        aspect: f64,
        /// The closest pair, printed.
        pair: String,
        /// Its distance.
        distance: f64,
        /// ε.
        eps: f64,
    },
    /// An energy term that cannot be built.
    #[error("ring: {0}")]
    Energy(#[from] TermError),
}

/// Reference edge length `h = 2 sin(π/n)` of the ring with `n` edges (R = 1).
pub fn mesh_size(n: usize) -> f64 {
    2.0 * (std::f64::consts::PI / n as f64).sin()
}

impl RingParams {
    /// Checks every parameter (not the admissibility of the start: [`build`] does that).
    pub fn validate(&self) -> Result<(), RingError> {
        let bad = |name, value: String, reason: String| {
            Err(RingError::Invalid {
                name,
                value,
                reason,
            })
        };
        if self.n < 6 || !self.n.is_multiple_of(2) {
            return bad(
                "n",
                self.n.to_string(),
                "need an even number of edges ≥ 6 (the rightmost vertex must be a vertex)".into(),
            );
        }
        if !(self.mu > 0.0 && self.mu.is_finite()) {
            return bad("mu", self.mu.to_string(), "must be finite and > 0".into());
        }
        if !(self.p > 0.0 && self.p.is_finite()) {
            return bad(
                "p",
                self.p.to_string(),
                "must be finite and > 0 (an external pressure)".into(),
            );
        }
        if let Some(e) = self.eps {
            if !(e > 0.0 && e.is_finite()) {
                return bad("eps", e.to_string(), "must be finite and > 0".into());
            }
        }
        if !(self.aspect > 0.0 && self.aspect <= 1.0) {
            return bad(
                "aspect",
                self.aspect.to_string(),
                "must be in (0, 1]".into(),
            );
        }
        if !(self.half_span > 0.0 && self.half_span.is_finite()) {
            return bad(
                "half_span",
                self.half_span.to_string(),
                "must be finite and > 0".into(),
            );
        }
        let half_rest = 0.5 * self.n as f64 * mesh_size(self.n);
        if self.pins == RingPins::LeftRight && self.half_span <= 0.5 * half_rest {
            return bad(
                "half_span",
                self.half_span.to_string(),
                format!(
                    "must exceed n·sin(π/n)/2 = {:.6} with both ends pinned, otherwise the \
                     flattened ring is slack (tension-only membrane) and its minimizers are \
                     not isolated",
                    0.5 * half_rest
                ),
            );
        }
        Ok(())
    }
}

/// Builds the scene (name `ring`): one body, vertices `0..n`, edges `[k, k+1 mod n]`.
pub fn build(p: &RingParams) -> Result<Scene, RingError> {
    p.validate()?;
    let n = p.n;
    let h = mesh_size(n);
    let eps = p.eps.unwrap_or(h / 10.0);
    let (a, b) = (p.half_span, p.aspect * p.half_span);
    let mut x_ref = Vec::with_capacity(2 * n);
    let mut x0 = Vec::with_capacity(2 * n);
    for k in 0..n {
        let th = std::f64::consts::PI * (1.0 + 2.0 * k as f64 / n as f64);
        let (s, c) = th.sin_cos();
        x_ref.extend_from_slice(&[c, s]);
        x0.extend_from_slice(&[a * c, b * s]);
    }
    // exact positions of the axis vertices (no cos(π) round-off)
    x_ref[..2].copy_from_slice(&[-1.0, 0.0]);
    x0[..2].copy_from_slice(&[-a, 0.0]);
    x_ref[n..n + 2].copy_from_slice(&[1.0, 0.0]);
    x0[n..n + 2].copy_from_slice(&[a, 0.0]);
    let mut fixed = vec![false; n];
    fixed[0] = true;
    if p.pins == RingPins::LeftRight {
        fixed[n / 2] = true;
    }
    let edges: Vec<[usize; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
    let ring = BodyPart {
        name: "ring".into(),
        kind: BodyKind::Curve,
        vertices: (0..n).collect(),
        elements: edges.iter().map(|e| [e[0], e[1], 0, 0]).collect(),
        arity: 2,
        h: Some(h),
        edges: None,
        faces: None,
    };
    let mesh = assemble_mesh(2, x_ref, fixed, &[ring], &file_order(1));
    let md = min_distance_2d(&mesh, &x0, 2.0 * eps, false);
    if md.distance < eps {
        return Err(RingError::InadmissibleStart {
            half_span: p.half_span,
            aspect: p.aspect,
            pair: md.pair.to_string(),
            distance: md.distance,
            eps,
        });
    }
    // the membrane, then the pressure on the area it encloses (polygon 0, 1, …, n−1)
    let physics = Physics {
        bodies: vec![BodyPhysics {
            material: Some(Material::String { mu: p.mu }),
            pressure: Some(p.p),
            ..Default::default()
        }],
        ..Default::default()
    };
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    Ok(Scene {
        name: "ring".into(),
        mesh,
        energy,
        eps,
        h,
        x0,
    })
}

/// Whether vertex `x` and edge `[a0, a1]` of a ring of `n` vertices numbered along it are
/// separated by at least one vertex on each side (`x` is neither an end of the edge nor a
/// neighbour of one). Pairs that are not are the along-curve neighbours, whose distance is set
/// by the fold angle, not by contact between the halves.
fn separated(n: usize, x: usize, a0: usize, a1: usize) -> bool {
    let gap = |u: usize, v: usize| {
        let d = u.abs_diff(v);
        d.min(n - d)
    };
    gap(x, a0) >= 2 && gap(x, a1) >= 2
}

/// The self-contact pairs of a ring scene at `x`: vertex–edge pairs at distance `< 1.01 ε`
/// whose vertex is neither on the edge nor a neighbour of its ends (along-curve neighbours
/// excluded), sorted by vertex then edge. Assumes the ring's numbering of [`build`] (vertex
/// `k` is the `k`-th along the ring).
pub fn self_contact_pairs(mesh: &Mesh, x: &[f64], eps: f64) -> Vec<NearPair> {
    let nv = mesh.nv();
    point_edge_near(mesh, x, &[], &vec![1.01 * eps; mesh.edges.len()], false)
        .into_iter()
        .filter(|p| {
            let e = mesh.edges[p.pair.a];
            p.distance < 1.01 * eps && separated(nv, p.pair.x, e[0], e[1])
        })
        .collect()
}

/// The state reached, from the contact pattern: `self_contact` when some
/// [`self_contact_pairs`] pair exists, else `no_contact`. (The body-level contact pattern of
/// the harness's diagnostics (`contact_pattern`) would also count along-curve neighbours at a
/// sharp fold as self-contact; this does not.)
pub fn classify_state(mesh: &Mesh, x: &[f64], eps: f64) -> String {
    if self_contact_pairs(mesh, x, eps).is_empty() {
        "no_contact".into()
    } else {
        "self_contact".into()
    }
}

/// The ring in the scene registry: parameters `mu`, `p`, `aspect`, `half_span`; level `n`
/// vertices, `h = 2 sin(π/n)`; end states classified by [`classify_state`].
pub struct Ring;

impl BuiltinScene for Ring {
    fn name(&self) -> &'static str {
        "ring"
    }

    fn build(&self, n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<Scene> {
        let mut p = RingParams {
            n,
            eps,
            ..Default::default()
        };
        for (k, &v) in params {
            match k.as_str() {
                "mu" => p.mu = v,
                "p" => p.p = v,
                "aspect" => p.aspect = v,
                "half_span" => p.half_span = v,
                other => anyhow::bail!(
                    "scene ring: unknown parameter {other:?} (known: mu, p, aspect, half_span)"
                ),
            }
        }
        Ok(build(&p)?)
    }

    /// `h = 2 sin(π/n)` with n even: the smallest even `n ≥ π / asin(h/2)` (at least 6).
    fn n_for_h(&self, h: f64, _params: &Params) -> anyhow::Result<usize> {
        Ok(if h >= 2.0 {
            6
        } else {
            let mut n = ((std::f64::consts::PI / (h / 2.0).asin()).ceil() as usize).max(6);
            n += n % 2;
            while n > 6 && mesh_size(n - 2) <= h {
                n -= 2;
            }
            while mesh_size(n) > h {
                n += 2;
            }
            n
        })
    }

    fn classify_state(
        &self,
        mesh: &Mesh,
        x: &[f64],
        eps: f64,
        _pattern: &[(usize, usize)],
    ) -> Option<String> {
        Some(classify_state(mesh, x, eps))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::PressureEnergy;

    #[test]
    fn ring_geometry_and_energy() {
        let s = build(&RingParams::default()).unwrap();
        let n = 20;
        assert_eq!(s.name, "ring");
        assert_eq!(s.mesh.nv(), n);
        assert!((s.h - mesh_size(n)).abs() < 1e-15);
        assert!((s.eps - s.h / 10.0).abs() < 1e-15);
        assert_eq!(s.mesh.validate(), Ok(()));
        // reference: regular polygon of circumradius 1, all edges h
        for &[a, b] in &s.mesh.edges {
            let l = (Mesh::p2(&s.mesh.x_ref, a) - Mesh::p2(&s.mesh.x_ref, b)).norm();
            assert!((l - s.h).abs() < 1e-14);
        }
        // pins at (∓2, 0), fixed
        assert_eq!(&s.x0[..2], &[-2.0, 0.0]);
        assert_eq!(&s.x0[n..n + 2], &[2.0, 0.0]);
        let fixed: Vec<usize> = (0..n).filter(|&v| s.mesh.fixed[v]).collect();
        assert_eq!(fixed, vec![0, n / 2]);
        // lower half below the axis, counter-clockwise, J = membrane + p·A with A > 0
        assert!(s.x0[3] < 0.0 && s.x0[2 * (n - 1) + 1] > 0.0);
        let pres = PressureEnergy::new((0..n).collect(), 1.0, &s.x0);
        assert_eq!(pres.polygon, (0..n).collect::<Vec<_>>());
        let a = pres.area(&s.x0);
        // inscribed polygon of the ellipse 2 × 0.5: area n/2 sin(2π/n)·a·b
        let exact = 0.5 * n as f64 * (2.0 * std::f64::consts::PI / n as f64).sin();
        assert!((a - exact).abs() < 1e-12, "{a} vs {exact}");
        assert!(s.energy.value(&s.x0) > a);
        // no self-contact at the start
        assert_eq!(classify_state(&s.mesh, &s.x0, s.eps), "no_contact");
    }

    #[test]
    fn ring_bad_params_are_named() {
        let msg = |p: RingParams| build(&p).err().unwrap().to_string();
        let e = msg(RingParams {
            n: 21,
            ..Default::default()
        });
        assert!(e.contains("invalid n = 21"), "{e}");
        let e = msg(RingParams {
            p: -1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid p = -1"), "{e}");
        let e = msg(RingParams {
            mu: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid mu = NaN"), "{e}");
        let e = msg(RingParams {
            aspect: 0.0,
            ..Default::default()
        });
        assert!(e.contains("invalid aspect = 0"), "{e}");
        let e = msg(RingParams {
            eps: Some(0.0),
            ..Default::default()
        });
        assert!(e.contains("invalid eps = 0"), "{e}");
        let e = msg(RingParams {
            half_span: 1.0,
            ..Default::default()
        });
        assert!(
            e.contains("invalid half_span = 1") && e.contains("slack"),
            "{e}"
        );
        // one pin: any span is accepted
        assert!(build(&RingParams {
            half_span: 1.0,
            pins: RingPins::Left,
            ..Default::default()
        })
        .is_ok());
        // too thin for ε: refused, the parameters named
        let e = msg(RingParams {
            aspect: 0.004,
            ..Default::default()
        });
        assert!(
            e.contains("not admissible") && e.contains("aspect = 0.004"),
            "{e}"
        );
    }

    #[test]
    fn ring_separated_pairs() {
        assert!(!separated(20, 1, 19, 0)); // neighbour of the edge's end 0
        assert!(!separated(20, 2, 0, 1));
        assert!(separated(20, 3, 0, 1));
        assert!(separated(20, 18, 0, 1) && !separated(20, 19, 0, 1));
        assert!(separated(20, 10, 19, 0));
    }
}
