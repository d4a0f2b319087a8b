//! `edge_edge` distance: two segments `[a0, a1]` and `[b0, b1]`, in space (eq. 6's edge–edge
//! pairs) and in the plane (the edge crossings of the 2D exact check).
//!
//! # In space
//!
//! Segment–segment distance in space (Ericson, *Real-Time Collision Detection*, §5.1.9), with
//! a deterministic choice of the closest pair when the segments are parallel.
//!
//! With `d1 = a1 − a0`, `d2 = b1 − b0`, the squared distance
//! `F(s, t) = |(b0 + t d2) − (a0 + s d1)|²` is a convex quadratic on `[0, 1]²`. Its minimum is
//! either the critical point of the two lines, when it lies in the square, or on one of the
//! four sides of the square, where it is a clamped point–segment projection. The kernel takes
//! the smallest of these five candidates (in the order: interior, `a0`, `a1`, `b0`, `b1`; the
//! first wins on ties):
//!
//! ```text
//! interior:  n = d1 × d2,   s* = ((b0 − a0) × d2)·n / |n|²,   t* = (pa(s*) − b0)·d2 / |d2|²
//! a0, a1:    (0, clamp((a0 − b0)·d2 / |d2|²)),   (1, clamp((a1 − b0)·d2 / |d2|²))
//! b0, b1:    (clamp((b0 − a0)·d1 / |d1|²), 0),   (clamp((b1 − a0)·d1 / |d1|²), 1)
//! ```
//!
//! `s*` is Ericson's `(b f − c e)/(a e − b²)` rewritten by the Lagrange identity
//! (`a e − b² = |d1 × d2|²`), which avoids its cancellation for nearly parallel segments; `t*`
//! is the exact minimizer for that `s*`, so an error of `s*` only slides the pair along the
//! segments and costs at most `|δs*|·|d1|·sin θ` in distance. Every candidate is a genuine pair
//! of points of the two segments, so the result never falls below the true distance by more
//! than rounding. Points are `pa = (1 − s) a0 + s a1`, `pb = (1 − t) b0 + t b1`, and
//! `distance = |pb − pa|` (so `(pb − pa)/distance` is a unit vector to rounding).
//!
//! **Parallel segments** (eq. 12's `P_{a,b}` is not a singleton). When
//! `|d1 × d2|² ≤ τ² |d1|² |d2|²`, `τ = 1e-12` (the sine of the angle is at most `τ`), and the
//! projections of the segments on the line of `a` overlap, the chosen pair is the **midpoint of
//! the overlap**: with `σ_j = (b_j − a0)·d1 / |d1|²`,
//!
//! ```text
//! s = (max(0, min σ_j) + min(1, max σ_j)) / 2,   t = clamp((pa(s) − b0)·d2 / |d2|²).
//! ```
//!
//! For exactly parallel segments every pair of the overlap is a minimizer and this is the middle
//! one; for segments parallel only up to `τ` the distance of this pair exceeds the minimum by at
//! most `τ ×` the overlap length. Without overlap (parallel segments side by side along their
//! line) the minimizer is unique (a pair of endpoints) and comes from the candidates above.
//! The rule is a function of the input only; it is symmetric under swapping the segments
//! (and, in exact arithmetic, under reversing either segment).
//!
//! **Symmetry.** The two segments are put in a canonical order first (lexicographic order of
//! the coordinates `(a0, a1)` vs `(b0, b1)` under `f64::total_cmp`) and the result is swapped
//! back, so `edge_edge_distance(b0, b1, a0, a1)` is bit-for-bit the swap of
//! `edge_edge_distance(a0, a1, b0, b1)`: same `distance`, `s ↔ t`, `pa ↔ pb`.
//!
//! **Zero-length segments** (`|d|² = 0`): a point. Point–segment: the clamped projection of the
//! point (its parameter is `0`); point–point: `s = t = 0`, `pa = a0`, `pb = b0`.
//!
//! **Non-finite input.** `s` and `t` are always in `[0, 1]` (a NaN parameter is clamped to
//! `0`), but `distance`, `pa` and `pb` are NaN or infinite when a coordinate is (or when the
//! squared lengths overflow, `|x| ≳ 1e150`). Finite input never gives NaN.
//!
//! # In the plane
//!
//! Edge–edge (segment–segment) distance in the plane.
//!
//! Two segments `[a0, a1]` and `[b0, b1]` in ℝ² either intersect (distance `0`: proper
//! crossing, touching at an endpoint, or collinear overlap) or not; in the latter case the
//! minimum of `|p − q|` over the two segments is attained at an endpoint of one of them, so
//!
//! ```text
//! d = min( d(a0, [b0,b1]), d(a1, [b0,b1]), d(b0, [a0,a1]), d(b1, [a0,a1]) ).
//! ```
//!
//! A proper crossing is detected with the orientation signs
//! `o(p, q, r) = (q − p) × (r − p)`: the segments cross when `o(a0,a1,b0)·o(a0,a1,b1) < 0`
//! and `o(b0,b1,a0)·o(b0,b1,a1) < 0`. Touching and collinear overlaps give a zero
//! point–edge distance through [`point_edge_distance`].

use super::point_edge::point_edge_distance;
use nalgebra::{Vector2, Vector3};
use std::cmp::Ordering;

/// Result of a segment–segment query. `distance` is NOT squared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeEdge {
    /// Euclidean distance between the two closed segments, not squared; equal to `|pb − pa|`.
    pub distance: f64,
    /// Parameter of the closest point on `[a0, a1]`, in `[0, 1]`.
    pub s: f64,
    /// Parameter of the closest point on `[b0, b1]`, in `[0, 1]`.
    pub t: f64,
    /// Closest point on the first segment, `(1 − s) a0 + s a1`.
    pub pa: Vector3<f64>,
    /// Closest point on the second segment, `(1 − t) b0 + t b1`.
    pub pb: Vector3<f64>,
}

/// Sine threshold below which two segments are treated as parallel (see the module docs).
const PARALLEL_SIN: f64 = 1e-12;

/// `x` clamped to `[0, 1]`; NaN gives `0`.
#[inline]
fn clamp01(x: f64) -> f64 {
    if x > 0.0 {
        if x < 1.0 {
            x
        } else {
            1.0
        }
    } else {
        0.0
    }
}

#[inline]
fn lerp(p0: &Vector3<f64>, p1: &Vector3<f64>, u: f64) -> Vector3<f64> {
    p0 * (1.0 - u) + p1 * u
}

/// Lexicographic order of `(a0, a1)` against `(b0, b1)` under `total_cmp`.
fn canonical_order(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> Ordering {
    a0.iter()
        .chain(a1.iter())
        .zip(b0.iter().chain(b1.iter()))
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or(Ordering::Equal)
}

/// Distance between the closed segments `[a0, a1]` and `[b0, b1]`, with the parameters and
/// the closest points. See the module documentation for the formulas, the deterministic
/// midpoint rule for parallel segments, and what degenerate and non-finite inputs return.
/// Never NaN for finite input (short of overflow, `|x| ≳ 1e150`); symmetric bit for bit under
/// swapping the two segments.
pub fn edge_edge_distance(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> EdgeEdge {
    if canonical_order(a0, a1, b0, b1) == Ordering::Greater {
        let r = solve(b0, b1, a0, a1);
        EdgeEdge {
            distance: r.distance,
            s: r.t,
            t: r.s,
            pa: r.pb,
            pb: r.pa,
        }
    } else {
        solve(a0, a1, b0, b1)
    }
}

/// The kernel proper, for segments already in canonical order.
fn solve(a0: &Vector3<f64>, a1: &Vector3<f64>, b0: &Vector3<f64>, b1: &Vector3<f64>) -> EdgeEdge {
    let d1 = a1 - a0;
    let d2 = b1 - b0;
    let la = d1.norm_squared();
    let lb = d2.norm_squared();
    let pair = |s: f64, t: f64| {
        let pa = lerp(a0, a1, s);
        let pb = lerp(b0, b1, t);
        EdgeEdge {
            distance: (pb - pa).norm(),
            s,
            t,
            pa,
            pb,
        }
    };
    // parameter of the clamped projection of x on segment a (resp. b)
    let on_a = |x: &Vector3<f64>| clamp01((x - a0).dot(&d1) / la);
    let on_b = |x: &Vector3<f64>| clamp01((x - b0).dot(&d2) / lb);
    let zero = |l: f64| l.is_nan() || l <= 0.0; // zero length (or NaN)
    let (a_point, b_point) = (zero(la), zero(lb));
    if a_point && b_point {
        return pair(0.0, 0.0);
    }
    if a_point {
        return pair(0.0, on_b(a0));
    }
    if b_point {
        return pair(on_a(b0), 0.0);
    }
    let n = d1.cross(&d2);
    let n2 = n.norm_squared();
    let mut best: Option<EdgeEdge> = None;
    if n2 <= PARALLEL_SIN * PARALLEL_SIN * la * lb {
        let sig0 = (b0 - a0).dot(&d1) / la;
        let sig1 = (b1 - a0).dot(&d1) / la;
        let lo = sig0.min(sig1).max(0.0);
        let hi = sig0.max(sig1).min(1.0);
        if lo <= hi {
            let s = clamp01(0.5 * (lo + hi));
            return pair(s, on_b(&lerp(a0, a1, s)));
        }
    } else {
        let s = (b0 - a0).cross(&d2).dot(&n) / n2;
        if (0.0..=1.0).contains(&s) {
            let t = (lerp(a0, a1, s) - b0).dot(&d2) / lb;
            if (0.0..=1.0).contains(&t) {
                best = Some(pair(s, t));
            }
        }
    }
    for (s, t) in [
        (0.0, on_b(a0)),
        (1.0, on_b(a1)),
        (on_a(b0), 0.0),
        (on_a(b1), 1.0),
    ] {
        let c = pair(s, t);
        if best.is_none_or(|b| c.distance < b.distance) {
            best = Some(c);
        }
    }
    best.expect("at least the four side candidates")
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const SAMPLES: usize = 20_000;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Exact point–segment distance (clamped projection).
    fn point_seg(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        let d = b - a;
        let l2 = d.norm_squared();
        let t = if l2 > 0.0 {
            ((p - a).dot(&d) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (a + d * t)).norm()
    }

    /// Brute force: sample one segment at `SAMPLES + 1` points and take the exact point–segment
    /// distance to the other, both ways. Over-estimates by at most `max length / (2 SAMPLES)`.
    fn brute(a0: &Vector3<f64>, a1: &Vector3<f64>, b0: &Vector3<f64>, b1: &Vector3<f64>) -> f64 {
        let mut m = f64::INFINITY;
        for k in 0..=SAMPLES {
            let u = k as f64 / SAMPLES as f64;
            m = m.min(point_seg(&lerp(a0, a1, u), b0, b1));
            m = m.min(point_seg(&lerp(b0, b1, u), a0, a1));
        }
        m
    }

    /// Invariants and symmetry (no brute force).
    fn check_invariants(
        a0: &Vector3<f64>,
        a1: &Vector3<f64>,
        b0: &Vector3<f64>,
        b1: &Vector3<f64>,
    ) -> EdgeEdge {
        let r = edge_edge_distance(a0, a1, b0, b1);
        assert!(
            r.distance.is_finite() && r.s.is_finite() && r.t.is_finite(),
            "{r:?}"
        );
        assert!(r.pa.iter().chain(r.pb.iter()).all(|x| x.is_finite()));
        assert!(
            (0.0..=1.0).contains(&r.s) && (0.0..=1.0).contains(&r.t),
            "{r:?}"
        );
        assert_eq!(r.pa, lerp(a0, a1, r.s));
        assert_eq!(r.pb, lerp(b0, b1, r.t));
        assert_eq!(r.distance, (r.pb - r.pa).norm());
        // symmetry: bit for bit, closest points swapped
        let w = edge_edge_distance(b0, b1, a0, a1);
        assert_eq!(w.distance, r.distance);
        assert_eq!((w.s, w.t, w.pa, w.pb), (r.t, r.s, r.pb, r.pa));
        // determinism
        assert_eq!(r, edge_edge_distance(a0, a1, b0, b1));
        // reversing a segment: same distance (to rounding)
        let tol = 1e-14
            * (1.0
                + [a0, a1, b0, b1]
                    .iter()
                    .map(|x| x.norm())
                    .fold(0.0, f64::max));
        let x = edge_edge_distance(a1, a0, b0, b1);
        assert!((x.distance - r.distance).abs() <= tol, "{x:?} vs {r:?}");
        let x = edge_edge_distance(a0, a1, b1, b0);
        assert!((x.distance - r.distance).abs() <= tol, "{x:?} vs {r:?}");
        r
    }

    fn check(a0: Vector3<f64>, a1: Vector3<f64>, b0: Vector3<f64>, b1: Vector3<f64>) -> EdgeEdge {
        let r = check_invariants(&a0, &a1, &b0, &b1);
        let m = brute(&a0, &a1, &b0, &b1);
        let len = (a1 - a0).norm().max((b1 - b0).norm());
        let tol = 1e-12 * (1.0 + len + a0.norm() + b0.norm());
        assert!(
            r.distance <= m + tol,
            "kernel {} > brute {m}: {r:?}",
            r.distance
        );
        assert!(
            r.distance >= m - len / SAMPLES as f64 - tol,
            "kernel {} < brute {m} − h",
            r.distance
        );
        r
    }

    #[test]
    fn geometry_segment_segment_skew_and_crossing() {
        // skew, perpendicular, distance 2, closest points at the middles
        let r = check(
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, -1.0, 2.0),
            v(0.0, 1.0, 2.0),
        );
        assert_eq!((r.distance, r.s, r.t), (2.0, 0.5, 0.5));
        assert_eq!((r.pa, r.pb), (v(0.0, 0.0, 0.0), v(0.0, 0.0, 2.0)));
        // skew, perpendicular, foot outside one segment: endpoint–segment
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, -1.0, 2.0),
            v(3.0, 1.0, 2.0),
        );
        assert_eq!((r.s, r.t), (1.0, 0.5));
        assert!((r.distance - 8f64.sqrt()).abs() <= 1e-15);
        // skew, generic: distance = |w·n|/|n| for interior closest points
        let (a0, a1, b0, b1) = (
            v(0.0, 0.0, 0.0),
            v(2.0, 1.0, 0.5),
            v(0.0, 2.0, 1.0),
            v(2.0, -1.0, 0.0),
        );
        let n = (a1 - a0).cross(&(b1 - b0));
        let r = check(a0, a1, b0, b1);
        assert!(r.s > 0.0 && r.s < 1.0 && r.t > 0.0 && r.t < 1.0);
        assert!((r.distance - ((b0 - a0).dot(&n) / n.norm()).abs()).abs() <= 1e-15);
        // crossing in their interiors: exactly 0 with representable data
        let r = check(
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, -1.0, 0.0),
            v(0.0, 1.0, 0.0),
        );
        assert_eq!((r.distance, r.s, r.t), (0.0, 0.5, 0.5));
        // random crossings: 0 to rounding, pa ≈ pb
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..200 {
            let mut r3 = || {
                v(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            };
            let (x, u, w) = (r3(), r3(), r3());
            let (s, t): (f64, f64) = (rng.gen_range(0.05..0.95), rng.gen_range(0.05..0.95));
            let (a0, a1) = (x - u * s, x + u * (1.0 - s));
            let (b0, b1) = (x - w * t, x + w * (1.0 - t));
            let r = check_invariants(&a0, &a1, &b0, &b1);
            assert!(r.distance <= 1e-14, "{r:?}");
            assert!(
                (r.pa - x).norm() <= 1e-13 && (r.pb - x).norm() <= 1e-13,
                "{r:?}"
            );
        }
        // T-junction and shared endpoint
        let r = check(
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 3.0, 1.0),
        );
        assert_eq!((r.distance, r.s, r.t), (0.0, 0.5, 0.0));
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 1.0, 1.0),
            v(1.0, 1.0, 1.0),
            v(2.0, 0.0, 5.0),
        );
        assert_eq!((r.distance, r.s, r.t), (0.0, 1.0, 0.0));
    }

    #[test]
    fn geometry_segment_segment_parallel_rule() {
        // overlapping, same direction: overlap s ∈ [0.5, 1] → s = 0.75, t = 0.25
        let (a0, a1, b0, b1) = (
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(3.0, 1.0, 0.0),
        );
        let r = check(a0, a1, b0, b1);
        assert_eq!((r.distance, r.s, r.t), (1.0, 0.75, 0.25));
        // the same, b reversed (anti-parallel): still the middle of the overlap
        let r = check(a0, a1, b1, b0);
        assert_eq!((r.distance, r.s, r.t), (1.0, 0.75, 0.75));
        // a reversed
        let r = check(a1, a0, b0, b1);
        assert_eq!((r.distance, r.s, r.t), (1.0, 0.25, 0.25));
        // one inside the other: the middle of the shorter one
        let r = check(
            v(0.0, 0.0, 0.0),
            v(4.0, 0.0, 0.0),
            v(1.0, 0.0, 2.0),
            v(2.0, 0.0, 2.0),
        );
        assert_eq!((r.distance, r.s, r.t), (2.0, 0.375, 0.5));
        // collinear overlapping: 0, the middle of the overlap
        let r = check(
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 0.0, 0.0),
        );
        assert_eq!((r.distance, r.s, r.t), (0.0, 0.75, 0.25));
        assert_eq!(r.pa, v(1.5, 0.0, 0.0));
        // identical segments: the middle
        let r = check(a0, a1, a0, a1);
        assert_eq!((r.distance, r.s, r.t), (0.0, 0.5, 0.5));
        // touching projections (overlap is one point)
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 0.0, 1.0),
            v(2.0, 0.0, 1.0),
        );
        assert_eq!((r.distance, r.s, r.t), (1.0, 1.0, 0.0));
        // parallel, disjoint along the line: the unique pair of nearest endpoints
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 1.0, 0.0),
            v(4.0, 1.0, 0.0),
        );
        assert_eq!((r.s, r.t), (1.0, 0.0));
        assert!((r.distance - 5f64.sqrt()).abs() <= 1e-15);
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(4.0, 1.0, 0.0),
            v(3.0, 1.0, 0.0),
        );
        assert_eq!((r.s, r.t), (1.0, 1.0));
        // collinear, disjoint
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(2.5, 0.0, 0.0),
            v(3.0, 0.0, 0.0),
        );
        assert_eq!((r.distance, r.s, r.t), (1.5, 1.0, 0.0));
        // determinism: repeated calls give identical results
        for _ in 0..3 {
            assert_eq!(
                edge_edge_distance(&a0, &a1, &b0, &b1),
                check_invariants(&a0, &a1, &b0, &b1)
            );
        }
    }

    /// The documented rule on random parallel and anti-parallel segments (parallel up to the
    /// rounding of their construction): `s` is the middle of the overlap of the projections.
    #[test]
    fn geometry_segment_segment_parallel_rule_random() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let mut overlapping = 0;
        for k in 0..300 {
            let mut r3 = || {
                v(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            };
            let (a0, d, off) = (r3(), r3(), r3());
            // offset normal to d, so that the projections on a's line are u0 and u1
            let off = if k % 5 == 0 {
                Vector3::zeros() // collinear
            } else {
                off - d * (off.dot(&d) / d.norm_squared())
            };
            let a1 = a0 + d;
            let u0: f64 = rng.gen_range(-1.5..2.5);
            let u1: f64 = u0 + rng.gen_range(0.1..2.0) * if k % 2 == 0 { 1.0 } else { -1.0 };
            let b0 = a0 + d * u0 + off;
            let b1 = a0 + d * u1 + off;
            let r = check(a0, a1, b0, b1);
            // parallel up to the rounding of the construction: the rule applies
            let (d1, d2) = (a1 - a0, b1 - b0);
            let sin2 = d1.cross(&d2).norm_squared() / (d1.norm_squared() * d2.norm_squared());
            assert!(sin2 <= PARALLEL_SIN * PARALLEL_SIN, "{sin2}");
            let (lo, hi) = (u0.min(u1).max(0.0), u0.max(u1).min(1.0));
            if lo < hi - 1e-9 {
                overlapping += 1;
                let s = 0.5 * (lo + hi);
                assert!((r.s - s).abs() <= 1e-12, "s {} vs the rule {s}", r.s);
                let t = (s - u0) / (u1 - u0);
                assert!((r.t - t).abs() <= 1e-11, "t {} vs {t}", r.t);
                // every pair of the overlap is at the distance |off|
                let perp = off.norm();
                assert!(
                    (r.distance - perp).abs() <= 1e-14,
                    "{} vs {perp}",
                    r.distance
                );
            }
        }
        assert!(overlapping > 100, "{overlapping}");
    }

    #[test]
    fn geometry_segment_segment_nearly_parallel() {
        for ang in [1e-6, 1e-9, 1e-11, 1e-12, 1e-13, 1e-15] {
            // offset 0.5, b tilts away from a: the minimum is at b0, 0.5 exactly
            let (a0, a1) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
            let r = check(a0, a1, v(0.2, 0.5, 0.0), v(1.2, 0.5 + ang, ang));
            assert!((r.distance - 0.5).abs() <= 1e-15 + ang, "{ang}: {r:?}");
            // crossing at a tiny angle in the middle of both: distance 0 to rounding
            let (b0, b1) = (v(0.0, -0.5 * ang, 0.0), v(1.0, 0.5 * ang, 0.0));
            let r = check(a0, a1, b0, b1);
            assert!(r.distance <= 1e-16 + ang * 1e-3, "{ang}: {r:?}");
            // skew at a tiny angle, height 1e-3: the distance is 1e-3 (to second order in ang)
            let (b0, b1) = (v(0.0, -0.5 * ang, 1e-3), v(1.0, 0.5 * ang, 1e-3));
            let r = check(a0, a1, b0, b1);
            assert!((r.distance - 1e-3).abs() <= 1e-15, "{ang}: {r:?}");
            // rotated copies in a generic direction, both crossing and skew
            let (e, f, g) = (v(0.6, -0.48, 0.64), v(0.8, 0.36, -0.48), v(0.0, 0.8, 0.6));
            let a0 = v(0.3, -0.2, 0.1);
            let a1 = a0 + e * 2.0;
            let b0 = a0 - f * ang + g * 0.25;
            let b1 = a0 + e * 2.0 + f * ang + g * 0.25;
            let r = check(a0, a1, b0, b1);
            assert!((r.distance - 0.25).abs() <= 1e-14, "{ang}: {r:?}");
            let b0 = a0 - f * ang;
            let b1 = a0 + e * 2.0 + f * ang;
            let r = check(a0, a1, b0, b1);
            assert!(r.distance <= 1e-14, "{ang}: {r:?}");
        }
    }

    #[test]
    fn geometry_segment_segment_zero_length() {
        let (a0, a1) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        // point – segment, both argument orders
        let p = v(0.5, 1.0, 0.0);
        let r = check(p, p, a0, a1);
        assert_eq!((r.distance, r.s, r.t), (1.0, 0.0, 0.5));
        let r = check(a0, a1, p, p);
        assert_eq!((r.distance, r.s, r.t), (1.0, 0.5, 0.0));
        // beyond the end
        let q = v(3.0, 4.0, 0.0);
        let r = check(q, q, a0, a1);
        assert_eq!((r.s, r.t), (0.0, 1.0));
        assert!((r.distance - 20f64.sqrt()).abs() <= 1e-15);
        // on the segment
        let r = check(v(0.25, 0.0, 0.0), v(0.25, 0.0, 0.0), a0, a1);
        assert_eq!(r.distance, 0.0);
        // point – point
        let r = check(a0, a0, v(0.0, 3.0, 4.0), v(0.0, 3.0, 4.0));
        assert_eq!((r.distance, r.s, r.t), (5.0, 0.0, 0.0));
        let r = check(a0, a0, a0, a0);
        assert_eq!(r.distance, 0.0);
    }

    #[test]
    fn geometry_segment_segment_random_vs_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut kinds = [0usize; 8];
        for k in 0..320 {
            let mut r3 = |s: f64| {
                v(
                    rng.gen_range(-s..s),
                    rng.gen_range(-s..s),
                    rng.gen_range(-s..s),
                )
            };
            let (a0, a1, mut b0, mut b1) = (r3(1.0), r3(1.0), r3(1.0), r3(1.0));
            let kind = k % 8;
            match kind {
                0 => b1 = b0 + (a1 - a0) * 0.7, // parallel
                1 => b1 = b0 - (a1 - a0) * 1.3, // anti-parallel
                2 => {
                    // collinear
                    b0 = a0 + (a1 - a0) * -0.4;
                    b1 = a0 + (a1 - a0) * 0.6;
                }
                3 => b1 = b0,                              // zero-length b
                4 => b1 = b0 + (a1 - a0) * 0.9 + r3(1e-8), // nearly parallel
                5 => {
                    // crossing (or touching) lines
                    let x = a0 + (a1 - a0) * 0.3;
                    b1 = x + (x - b0) * 0.8;
                }
                6 => {
                    // both zero length
                    let c = r3(1.0);
                    check(c, c, b0, b0);
                    kinds[kind] += 1;
                    continue;
                }
                _ => {}
            }
            check(a0, a1, b0, b1);
            kinds[kind] += 1;
        }
        assert!(kinds.iter().all(|&n| n >= 40), "{kinds:?}");
    }

    #[test]
    fn geometry_segment_segment_symmetry_random() {
        let mut rng = ChaCha8Rng::seed_from_u64(23);
        for k in 0..2000 {
            let mut r3 = || {
                v(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            };
            let (a0, a1, b0, mut b1) = (r3(), r3(), r3(), r3());
            if k % 3 == 0 {
                b1 = b0 + (a1 - a0) * -0.6;
            }
            check_invariants(&a0, &a1, &b0, &b1);
        }
    }

    /// Tight cross-check against an independent formulation: `g(s) = dist(pa(s), [b0, b1])` is
    /// convex, minimized by golden-section search to the resolution of f64.
    #[test]
    fn geometry_segment_segment_vs_golden_section() {
        fn reference(
            a0: &Vector3<f64>,
            a1: &Vector3<f64>,
            b0: &Vector3<f64>,
            b1: &Vector3<f64>,
        ) -> f64 {
            let g = |s: f64| point_seg(&lerp(a0, a1, s), b0, b1);
            let phi = 0.5 * (5f64.sqrt() - 1.0);
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for _ in 0..120 {
                let m1 = hi - phi * (hi - lo);
                let m2 = lo + phi * (hi - lo);
                if g(m1) <= g(m2) {
                    hi = m2;
                } else {
                    lo = m1;
                }
            }
            g(0.5 * (lo + hi)).min(g(0.0)).min(g(1.0))
        }
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        for k in 0..5_000 {
            let mut r3 = || {
                v(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            };
            let (a0, a1, b0, mut b1) = (r3(), r3(), r3(), r3());
            match k % 4 {
                0 => b1 = b0 + (a1 - a0) * 0.8 + r3() * 1e-7, // nearly parallel
                1 => {
                    let x = a0 + (a1 - a0) * 0.6; // crossing
                    b1 = x + (x - b0) * 0.5;
                }
                _ => {}
            }
            let r = check_invariants(&a0, &a1, &b0, &b1);
            let m = reference(&a0, &a1, &b0, &b1);
            assert!(
                (r.distance - m).abs() <= 1e-14 * (1.0 + m),
                "{k}: {} vs {m}",
                r.distance
            );
        }
    }

    #[test]
    fn geometry_segment_segment_non_finite_input() {
        let (a0, a1) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        let nan = v(f64::NAN, 0.0, 0.0);
        let inf = v(f64::INFINITY, 1.0, 0.0);
        for (p0, p1, q0, q1) in [
            (nan, a1, a0, a1),
            (a0, a1, nan, nan),
            (a0, inf, a0, a1),
            (a0, a1, inf, a0),
        ] {
            let r = edge_edge_distance(&p0, &p1, &q0, &q1);
            assert!(
                (0.0..=1.0).contains(&r.s) && (0.0..=1.0).contains(&r.t),
                "{r:?}"
            );
        }
    }
}

fn orient(p: &Vector2<f64>, q: &Vector2<f64>, r: &Vector2<f64>) -> f64 {
    let u = q - p;
    let v = r - p;
    u.x * v.y - u.y * v.x
}

/// Exact (up to rounding) distance between the segments `[a0, a1]` and `[b0, b1]`; `0` when
/// they intersect (crossing, touching or collinear overlap).
pub fn edge_edge_distance_2d(
    a0: &Vector2<f64>,
    a1: &Vector2<f64>,
    b0: &Vector2<f64>,
    b1: &Vector2<f64>,
) -> f64 {
    let o1 = orient(a0, a1, b0);
    let o2 = orient(a0, a1, b1);
    let o3 = orient(b0, b1, a0);
    let o4 = orient(b0, b1, a1);
    let opposite = |u: f64, v: f64| (u < 0.0 && v > 0.0) || (u > 0.0 && v < 0.0);
    if opposite(o1, o2) && opposite(o3, o4) {
        return 0.0;
    }
    point_edge_distance(a0, b0, b1)
        .distance
        .min(point_edge_distance(a1, b0, b1).distance)
        .min(point_edge_distance(b0, a0, a1).distance)
        .min(point_edge_distance(b1, a0, a1).distance)
}

#[cfg(test)]
mod tests_2d {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Brute force: for each sample of one segment, the exact point–segment distance to the
    /// other (the inner minimum is convex, so sampling only one segment suffices); both ways.
    fn brute(a0: &Vector2<f64>, a1: &Vector2<f64>, b0: &Vector2<f64>, b1: &Vector2<f64>) -> f64 {
        let n = 10_000;
        let mut m = f64::INFINITY;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let p = a0 * (1.0 - t) + a1 * t;
            m = m.min(point_edge_distance(&p, b0, b1).distance);
            let q = b0 * (1.0 - t) + b1 * t;
            m = m.min(point_edge_distance(&q, a0, a1).distance);
        }
        m
    }

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    #[test]
    fn geometry_edge_edge_random_vs_sampling() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut crossings = 0;
        for _ in 0..200 {
            let mut r = || v(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0));
            let (a0, a1, b0, b1) = (r(), r(), r(), r());
            let d = edge_edge_distance_2d(&a0, &a1, &b0, &b1);
            let m = brute(&a0, &a1, &b0, &b1);
            let h = ((a1 - a0).norm() + (b1 - b0).norm()) / 1e4;
            assert!(d <= m + 1e-12, "{d} > {m}");
            assert!(d >= m - h - 1e-12, "{d} < {m} - {h}");
            if d == 0.0 {
                crossings += 1;
            }
            // symmetric in the order of segments and endpoints
            let d2 = edge_edge_distance_2d(&b1, &b0, &a1, &a0);
            assert!((d - d2).abs() <= 1e-13);
        }
        assert!(crossings > 10, "random set should contain crossings");
    }

    #[test]
    fn geometry_edge_edge_special_cases() {
        // crossing
        assert_eq!(
            edge_edge_distance_2d(&v(-1.0, 0.0), &v(1.0, 0.0), &v(0.0, -1.0), &v(0.0, 1.0)),
            0.0
        );
        // parallel, offset
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(2.0, 0.0), &v(0.5, 0.5), &v(3.0, 0.5));
        assert_eq!(d, 0.5);
        // parallel, no overlap in projection
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(1.0, 0.0), &v(4.0, 4.0), &v(5.0, 4.0));
        assert!((d - 5.0).abs() < 1e-15);
        // collinear overlapping
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(2.0, 0.0), &v(1.0, 0.0), &v(3.0, 0.0));
        assert_eq!(d, 0.0);
        // collinear, one inside the other
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(4.0, 0.0), &v(1.0, 0.0), &v(3.0, 0.0));
        assert_eq!(d, 0.0);
        // collinear, disjoint
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(1.0, 0.0), &v(2.5, 0.0), &v(3.0, 0.0));
        assert_eq!(d, 1.5);
        // touching at a shared endpoint
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(1.0, 1.0), &v(1.0, 1.0), &v(2.0, 0.0));
        assert_eq!(d, 0.0);
        // T-junction: endpoint of b on the interior of a
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(2.0, 0.0), &v(1.0, 0.0), &v(1.0, 3.0));
        assert_eq!(d, 0.0);
        // near-miss T
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(2.0, 0.0), &v(1.0, 0.25), &v(1.0, 3.0));
        assert_eq!(d, 0.25);
        // degenerate segments (points)
        let d = edge_edge_distance_2d(&v(0.0, 0.0), &v(0.0, 0.0), &v(3.0, 4.0), &v(3.0, 4.0));
        assert_eq!(d, 5.0);
        for (a0, a1, b0, b1) in [
            (v(0.0, 0.0), v(2.0, 0.0), v(0.5, 0.5), v(3.0, 0.5)),
            (v(0.0, 0.0), v(1.0, 1.0), v(1.0, 1.0), v(2.0, 0.0)),
            (v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.25), v(1.0, 3.0)),
        ] {
            let m = brute(&a0, &a1, &b0, &b1);
            let d = edge_edge_distance_2d(&a0, &a1, &b0, &b1);
            assert!(d <= m + 1e-12 && d >= m - 1e-3);
        }
    }
}
