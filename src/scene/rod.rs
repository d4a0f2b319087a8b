//! A string in self-contact: one P1 curve in space whose path crosses over itself, the upper
//! strand pulled by gravity onto the lower one. A 3D curve has no faces, so only edge–edge
//! rows carry the contact.
//!
//! **Geometry.** One body `rod` ([`BodyKind::Curve`]), its vertices numbered along the
//! string, through four pinned points
//!
//! ```text
//! P0 = (−1, 0, 0),  P1 = (1, 0, 0),  P2 = (0, −1, H),  P3 = (0, 1, H)      (H = height):
//! ```
//!
//! * the **lower strand** `P0 → P1` (`8n + 1` edges), straight along the x axis in `x0`; its
//!   reference length is `2 / stretch` (`stretch > 1`), so the pins hold it taut;
//! * the **arch** `P1 → P2` (`6n` edges): in `x0` the quarter circle `(cos φ, sin φ)`,
//!   `φ: 0 → −π/2`, rising as `z = H t + 0.3 sin(π t)` (`t = −2φ/π`); its reference length is
//!   the chord `|P2 − P1|` divided by `stretch`, so it is taut too (it straightens towards the
//!   chord, away from both strands);
//! * the **upper strand** `P2 → P3` (`8n + 1` edges) of reference length `2 · slack`
//!   (`slack > 1`: longer than the distance between its pins, it hangs). In `x0` it is the
//!   parabola `depth · (1 − y²)` below the pin axis (the line `x = 0, z = H`), swung by
//!   `swing_deg` (default 75°) about that axis towards −x, its vertices cutting it into equal
//!   chords, each 1.02 times the reference edge (`depth` found by bisection): every edge of
//!   the string is in tension in `x0` (no zero-stiffness direction). It crosses above the
//!   lower strand, at `y = 0`, `x = −depth sin(swing)`, height `H − depth cos(swing)`; a swing
//!   that puts this crossing below the lower strand (at the defaults, below about 62°) is
//!   refused (the strand would hang under it, with no contact), one that puts it within ε is
//!   refused as not admissible.
//!
//! The edge counts are odd on both strands, so each crossing point is the midpoint of an
//! edge (the middle edges of both strands cross at right angles at the minimum).
//!
//! **Energy.** `J = Σ_edges L_e W(F_e) + weight · Σ_v m_v z_v`: the tension-only string
//! energy ([`crate::energy::String3dEnergy`], `W(F) = μ(|F|² − 1)²` for `|F| ≥ 1`) and gravity
//! ([`crate::energy::Gravity`], `weight` = ρg per unit reference length, along −z) on the whole string.
//!
//! **Defaults.** `n = 2` (17 + 12 + 17 edges, 47 vertices), `μ = 1`, `weight = 0.1`,
//! `H = 0.3`, `stretch = 1.1`, `slack = 1.2`, `swing_deg = 75`; `h` = the largest reference
//! edge (the upper strand's `2·slack/(8n+1)`), `ε = h/10`.
//!
//! **At the minimum.** Swinging down about its pin axis keeps the upper strand's length, so
//! gravity brings it to the vertical plane `x = 0`, where a free string of length
//! `2·slack = 2.4` between pins 2 apart would hang about `√(3·0.4/4) ≈ 0.55` below them, to
//! `z ≈ −0.25`, while the lower strand sags under its own weight by only
//! `weight·2²/(8T) ≈ 0.05` (`T = 4μF(F²−1) ≈ 0.92`). (The unconstrained equilibrium of the
//! defaults, computed by Newton's method without contact: the upper strand crosses `y = 0` at
//! `z ≈ −0.31`, the lower strand's middle is at `z ≈ −0.048`.) So the upper strand lies on the
//! lower one: at the constrained minimum its middle edge rests across the lower strand's
//! middle edge at distance ε (an edge–edge row active), both strands bent into a V at the
//! crossing. With the four pins and every strand in tension there is no zero-energy motion.

use super::Scene;
use crate::contact::broad_phase::min_distance_3d;
use crate::scene::assemble::{assemble_mesh, file_order, BodyPart};
use crate::scene::mesh::{BodyKind, MeshError};
use crate::scene::physics::{assemble_energy, BodyPhysics, Material, Physics, TermError};
use crate::scene::registry::{set_fields, LevelScene, Params};
use thiserror::Error;

/// Stretch of every upper-strand edge in `x0` (in tension, so the Hessian has no zero
/// direction there).
const UPPER_X0_STRETCH: f64 = 1.02;

/// Rise of the arch's midpoint above the straight ramp from `P1` to `P2`.
const ARCH_RISE: f64 = 0.3;

/// Parameters of the rod scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RodParams {
    /// Mesh level: `8n + 1` edges per strand, `6n` on the arch (n ≥ 1).
    pub n: usize,
    /// ε; `None` means h/10.
    pub eps: Option<f64>,
    /// Elasticity coefficient μ of the string.
    pub mu: f64,
    /// Weight ρg per unit reference length (gravity along −z).
    pub weight: f64,
    /// Height `H` of the upper strand's pins above the lower strand.
    pub height: f64,
    /// Pre-stretch of the lower strand and of the arch (pinned span / reference length), > 1.
    pub stretch: f64,
    /// Reference length of the upper strand over the distance of its pins (2), > 1.
    pub slack: f64,
    /// Angle (degrees, in [0, 90)) of the upper strand's plane from the vertical in `x0`; large
    /// enough that the strand starts above the lower one (at the defaults, more than about 60°).
    pub swing_deg: f64,
}

impl Default for RodParams {
    fn default() -> Self {
        RodParams {
            n: 2,
            eps: None,
            mu: 1.0,
            weight: 0.1,
            height: 0.3,
            stretch: 1.1,
            slack: 1.2,
            swing_deg: 75.0,
        }
    }
}

/// A parameter out of range, or a start that is not admissible; names the parameter.
#[derive(Debug, Error, PartialEq)]
pub enum RodError {
    /// The parameter and why it is rejected.
    #[error("rod: invalid {name} = {value}: {reason}")]
    Invalid {
        /// Parameter name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// Why.
        reason: String,
    },
    /// Two disjoint edges of `x0` are closer than ε.
    #[error(
        "rod: the initial configuration (height = {height}, swing_deg = {swing_deg}) is not \
         admissible: {pair} at distance {distance:.6e} < eps = {eps:.6e}; increase height, \
         lower swing_deg or lower eps"
    )]
    InadmissibleStart {
        /// `H`.
        height: f64,
        /// The swing angle.
        swing_deg: f64,
        /// The closest pair, printed.
        pair: String,
        /// Its distance.
        distance: f64,
        /// ε.
        eps: f64,
    },
    /// The generated mesh is invalid.
    #[error("rod: invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    /// An energy term that cannot be built.
    #[error("rod: {0}")]
    Energy(#[from] TermError),
}

/// Edges of each strand at level `n` (odd).
pub fn strand_edges(n: usize) -> usize {
    8 * n + 1
}

/// Edges of the arch at level `n`.
pub fn arch_edges(n: usize) -> usize {
    6 * n
}

/// `h`: the largest reference edge.
pub fn mesh_size(p: &RodParams) -> f64 {
    let ms = strand_edges(p.n) as f64;
    let upper = 2.0 * p.slack / ms;
    let lower = 2.0 / p.stretch / ms;
    let arch = chord(p.height) / p.stretch / arch_edges(p.n) as f64;
    upper.max(lower).max(arch)
}

fn chord(height: f64) -> f64 {
    (2.0 + height * height).sqrt()
}

impl RodParams {
    /// Checks every parameter (not the admissibility of the start: [`build`] does that).
    pub fn validate(&self) -> Result<(), RodError> {
        let bad = |name, value: String, reason: &str| {
            Err(RodError::Invalid {
                name,
                value,
                reason: reason.into(),
            })
        };
        if self.n == 0 || self.n > 100_000 {
            return bad("n", self.n.to_string(), "must be in 1..=100000");
        }
        if let Some(e) = self.eps {
            if !(e > 0.0 && e.is_finite()) {
                return bad("eps", e.to_string(), "must be finite and > 0");
            }
        }
        for (name, v) in [
            ("mu", self.mu),
            ("weight", self.weight),
            ("height", self.height),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(name, v.to_string(), "must be finite and > 0");
            }
        }
        if !(self.stretch > 1.0 && self.stretch < 2.0) {
            return bad(
                "stretch",
                self.stretch.to_string(),
                "must be in (1, 2): the lower strand and the arch must be taut",
            );
        }
        if !(self.slack > 1.0 && self.slack < 3.0) {
            return bad(
                "slack",
                self.slack.to_string(),
                "must be in (1, 3): the upper strand must be longer than its span",
            );
        }
        if !(self.swing_deg >= 0.0 && self.swing_deg < 90.0) {
            return bad(
                "swing_deg",
                self.swing_deg.to_string(),
                "must be in [0, 90)",
            );
        }
        Ok(())
    }
}

/// Walks `m` chords of length `c` along the parabola `w = d(1 − y²)` from `y = −1`: the
/// points `(y_k, w_k)` (each next one the first point of the curve at distance `c`, by
/// bisection).
fn chord_walk(d: f64, c: f64, m: usize) -> Vec<[f64; 2]> {
    let w = |y: f64| d * (1.0 - y * y);
    let mut pts = vec![[-1.0, 0.0]];
    for _ in 0..m {
        let [y0, w0] = *pts.last().unwrap();
        let (mut lo, mut hi) = (y0, y0 + c);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if (mid - y0).hypot(w(mid) - w0) < c {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let y = 0.5 * (lo + hi);
        pts.push([y, w(y)]);
    }
    pts
}

/// The `x0` positions of the upper strand (`m + 1` points from `P2` to `P3`): `m` equal
/// chords of length `c` on the parabola `depth · (1 − y²)` hung below the pin axis, its depth
/// found by bisection so that the last chord ends at `y = 1`; then swung by `swing` about the
/// pin axis towards −x.
fn upper_strand(m: usize, c: f64, height: f64, swing: f64) -> Vec<[f64; 3]> {
    // a longer curve (deeper parabola) ends the walk at a smaller y
    let (mut lo, mut hi) = (0.0, m as f64 * c);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if chord_walk(mid, c, m)[m][0] > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut pts = chord_walk(0.5 * (lo + hi), c, m);
    pts[m] = [1.0, 0.0];
    let (ss, cs) = swing.sin_cos();
    pts.iter()
        .map(|&[y, sag]| [-sag * ss, y, height - sag * cs])
        .collect()
}

/// Builds the scene (name `rod`): vertices `0 … N` along the string from `P0` to `P3`, edge
/// `k = [k, k+1]`; pins at `P0` (vertex 0), `P1` (`8n+1`), `P2` (`14n+1`) and `P3` (last).
pub fn build(p: &RodParams) -> Result<Scene, RodError> {
    p.validate()?;
    let (ms, ma) = (strand_edges(p.n), arch_edges(p.n));
    let h = mesh_size(p);
    let eps = p.eps.unwrap_or(h / 10.0);
    let hh = p.height;
    let mut x0: Vec<[f64; 3]> = Vec::new();
    let mut rest: Vec<f64> = Vec::new(); // reference length of each edge
                                         // lower strand
    for k in 0..=ms {
        x0.push([-1.0 + 2.0 * k as f64 / ms as f64, 0.0, 0.0]);
    }
    rest.extend(std::iter::repeat_n(2.0 / p.stretch / ms as f64, ms));
    // arch (its first point is P1, already pushed)
    for k in 1..=ma {
        let t = k as f64 / ma as f64;
        let phi = -0.5 * std::f64::consts::PI * t;
        let z = hh * t + ARCH_RISE * (std::f64::consts::PI * t).sin();
        x0.push([phi.cos(), phi.sin(), z]);
    }
    // exact pin
    *x0.last_mut().unwrap() = [0.0, -1.0, hh];
    rest.extend(std::iter::repeat_n(chord(hh) / p.stretch / ma as f64, ma));
    // upper strand
    let upper_rest = 2.0 * p.slack / ms as f64;
    let pts = upper_strand(
        ms,
        upper_rest * UPPER_X0_STRETCH,
        hh,
        p.swing_deg.to_radians(),
    );
    // where the upper strand passes y = 0 (the middle of its middle edge): above the lower one
    let cross = 0.5 * (pts[ms / 2][2] + pts[ms / 2 + 1][2]);
    if cross <= 0.0 {
        return Err(RodError::Invalid {
            name: "swing_deg",
            value: p.swing_deg.to_string(),
            reason: format!(
                "the upper strand would start below the lower one (it crosses y = 0 at \
                 height {cross:.4}): it would hang under it, without contact; swing it higher"
            ),
        });
    }
    x0.extend_from_slice(&pts[1..]);
    *x0.last_mut().unwrap() = [0.0, 1.0, hh];
    rest.extend(std::iter::repeat_n(upper_rest, ms));
    let nv = x0.len();
    debug_assert_eq!(rest.len(), nv - 1);
    // reference: the string laid straight along the x axis with the reference lengths
    let mut x_ref = Vec::with_capacity(3 * nv);
    let mut s = 0.0;
    x_ref.extend_from_slice(&[0.0, 0.0, 0.0]);
    for r in &rest {
        s += r;
        x_ref.extend_from_slice(&[s, 0.0, 0.0]);
    }
    let pins = [0, ms, ms + ma, nv - 1];
    let mut fixed = vec![false; nv];
    for &v in &pins {
        fixed[v] = true;
    }
    let edges: Vec<[usize; 2]> = (0..nv - 1).map(|k| [k, k + 1]).collect();
    let x0: Vec<f64> = x0.into_iter().flatten().collect();
    let rod = BodyPart {
        name: "rod".into(),
        kind: BodyKind::Curve,
        vertices: (0..nv).collect(),
        elements: edges.iter().map(|e| [e[0], e[1], 0, 0]).collect(),
        arity: 2,
        h: Some(h),
        edges: None,
        faces: None,
    };
    let mesh = assemble_mesh(3, x_ref, fixed, &[rod], &file_order(1));
    mesh.validate()?;
    let (distance, pair) = min_distance_3d(&mesh, &x0, eps);
    if distance < eps {
        return Err(RodError::InadmissibleStart {
            height: p.height,
            swing_deg: p.swing_deg,
            pair: format!("{pair:?}"),
            distance,
            eps,
        });
    }
    // the string, then gravity on its weight per unit length along −z
    let physics = Physics {
        bodies: vec![BodyPhysics {
            material: Some(Material::String { mu: p.mu }),
            density: Some(p.weight),
            ..Default::default()
        }],
        gravity: Some(vec![0.0, 0.0, -1.0]),
        ..Default::default()
    };
    let energy = assemble_energy(&mesh, &x0, &physics)?;
    Ok(Scene {
        name: "rod".into(),
        mesh,
        energy,
        eps,
        h,
        x0,
    })
}

/// The `rod` scene in the scene registry: its parameters are the numeric fields of
/// [`RodParams`]; the level for a mesh size h is the smallest whose [`mesh_size`] is at most h.
pub struct Rod;

impl LevelScene for Rod {
    type P = RodParams;
    const NAME: &'static str = "rod";
    const MAX_LEVEL: usize = 100000;

    fn params(n: usize, eps: Option<f64>, params: &Params) -> anyhow::Result<RodParams> {
        let mut p = RodParams {
            n,
            eps,
            ..Default::default()
        };
        set_fields(
            "rod",
            &mut p,
            params,
            &[
                ("mu", |p| &mut p.mu),
                ("weight", |p| &mut p.weight),
                ("height", |p| &mut p.height),
                ("stretch", |p| &mut p.stretch),
                ("slack", |p| &mut p.slack),
                ("swing_deg", |p| &mut p.swing_deg),
            ],
            &[],
        )?;
        Ok(p)
    }

    fn level(p: &RodParams) -> usize {
        p.n
    }

    fn at_level(p: &RodParams, n: usize) -> RodParams {
        RodParams { n, ..p.clone() }
    }

    fn build_scene(p: &RodParams) -> anyhow::Result<Scene> {
        Ok(build(p)?)
    }

    fn mesh_size(p: &RodParams) -> f64 {
        mesh_size(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::p3;

    #[test]
    fn rod_default_mesh_counts_and_admissibility() {
        let s = build(&RodParams::default()).unwrap();
        let m = &s.mesh;
        assert_eq!(s.name, "rod");
        assert_eq!(m.validate(), Ok(()));
        assert_eq!(m.nv(), 47);
        assert_eq!(m.edges.len(), 46);
        assert!(m.faces.is_empty() && m.triangles.is_empty() && m.tets.is_empty());
        assert_eq!(m.contact_vertices().len(), 47);
        let fixed: Vec<usize> = (0..m.nv()).filter(|&v| m.fixed[v]).collect();
        assert_eq!(fixed, vec![0, 17, 29, 46]);
        assert_eq!(p3(&s.x0, 0), nalgebra::Vector3::new(-1.0, 0.0, 0.0));
        assert_eq!(p3(&s.x0, 17), nalgebra::Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(p3(&s.x0, 29), nalgebra::Vector3::new(0.0, -1.0, 0.3));
        assert_eq!(p3(&s.x0, 46), nalgebra::Vector3::new(0.0, 1.0, 0.3));
        assert!((s.h - 2.4 / 17.0).abs() < 1e-15);
        assert!((s.eps - s.h / 10.0).abs() < 1e-15);
        let (d, _) = min_distance_3d(m, &s.x0, s.eps);
        assert!(d >= s.eps, "{d}");
        assert!(s.energy.value(&s.x0).is_finite());
        // each contact edge once
        let mut e = m.edges.clone();
        e.sort_unstable();
        e.dedup();
        assert_eq!(e.len(), m.edges.len());
    }

    #[test]
    fn rod_every_edge_in_tension_at_x0_and_upper_crosses_above() {
        let p = RodParams::default();
        let s = build(&p).unwrap();
        let m = &s.mesh;
        for (k, e) in m.edges.iter().enumerate() {
            let l = (p3(&s.x0, e[1]) - p3(&s.x0, e[0])).norm();
            let r = (p3(&m.x_ref, e[1]) - p3(&m.x_ref, e[0])).norm();
            assert!(l / r > 1.0 + 1e-3, "edge {k}: F = {}", l / r);
        }
        // the upper strand's edges are all stretched by 1.02
        for k in 29..46 {
            let l = (p3(&s.x0, k + 1) - p3(&s.x0, k)).norm();
            assert!((l / (2.4 / 17.0) - 1.02).abs() < 1e-9, "edge {k}");
        }
        // its middle edge (37 → 38) crosses y = 0 above the lower strand's middle edge
        let (a, b) = (p3(&s.x0, 37), p3(&s.x0, 38));
        assert!(a.y < 0.0 && b.y > 0.0);
        let mid = 0.5 * (a + b);
        assert!(mid.x < -0.3 && mid.x > -1.0 && mid.z > 0.1, "{mid}");
        // the lower strand's middle edge (8 → 9) straddles x = 0
        assert!(s.x0[3 * 8] < 0.0 && s.x0[3 * 9] > 0.0);
    }

    #[test]
    fn rod_chord_walk() {
        // a flat curve: chords along the y axis
        let pts = chord_walk(0.0, 0.5, 4);
        assert!((pts[4][0] - 1.0).abs() < 1e-12);
        // a hung strand: equal chords, ends at the pins
        let pts = upper_strand(9, 0.3, 0.3, 0.0);
        assert_eq!(pts[0], [0.0, -1.0, 0.3]);
        assert_eq!(pts[9], [0.0, 1.0, 0.3]);
        for w in pts.windows(2) {
            let l = (0..3)
                .map(|c| (w[1][c] - w[0][c]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!((l - 0.3).abs() < 1e-9, "{l}");
        }
        assert!(pts[4][2] < 0.3 - 0.5 && pts[5][2] < 0.3 - 0.5);
    }

    #[test]
    fn rod_bad_params_are_named() {
        let msg = |p: RodParams| build(&p).err().unwrap().to_string();
        let e = msg(RodParams {
            n: 0,
            ..Default::default()
        });
        assert!(e.contains("invalid n = 0"), "{e}");
        for (eps, shown) in [(0.0, "0"), (-0.1, "-0.1"), (f64::NAN, "NaN")] {
            let e = msg(RodParams {
                eps: Some(eps),
                ..Default::default()
            });
            assert!(e.contains(&format!("invalid eps = {shown}")), "{e}");
        }
        let e = msg(RodParams {
            mu: 0.0,
            ..Default::default()
        });
        assert!(e.contains("invalid mu = 0"), "{e}");
        let e = msg(RodParams {
            weight: f64::NAN,
            ..Default::default()
        });
        assert!(e.contains("invalid weight = NaN"), "{e}");
        let e = msg(RodParams {
            height: -0.3,
            ..Default::default()
        });
        assert!(e.contains("invalid height = -0.3"), "{e}");
        let e = msg(RodParams {
            stretch: 0.9,
            ..Default::default()
        });
        assert!(e.contains("invalid stretch = 0.9"), "{e}");
        let e = msg(RodParams {
            slack: 1.0,
            ..Default::default()
        });
        assert!(e.contains("invalid slack = 1"), "{e}");
        let e = msg(RodParams {
            swing_deg: 90.0,
            ..Default::default()
        });
        assert!(e.contains("invalid swing_deg = 90"), "{e}");
        // hanging straight down from the start: under the lower strand, refused
        let e = msg(RodParams {
            swing_deg: 0.0,
            ..Default::default()
        });
        assert!(
            e.contains("invalid swing_deg = 0") && e.contains("below"),
            "{e}"
        );
        // crossing just above the lower strand: closer than ε, refused
        let e = msg(RodParams {
            swing_deg: 62.0,
            ..Default::default()
        });
        assert!(
            e.contains("not admissible") && e.contains("swing_deg = 62"),
            "{e}"
        );
        let e = msg(RodParams {
            eps: Some(0.5),
            ..Default::default()
        });
        assert!(e.contains("not admissible"), "{e}");
    }
}
