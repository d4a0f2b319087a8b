//! Segment–segment distance in space (Ericson, *Real-Time Collision Detection*, §5.1.9).
//!
//! With `d1 = a1 − a0`, `d2 = b1 − b0`, `r = a0 − b0`, `a = d1·d1`, `e = d2·d2`, `f = d2·r`,
//! `b = d1·d2`, `c = d1·r`, the closest points `a0 + s d1`, `b0 + t d2` of the two lines solve
//! a 2×2 system with determinant `a e − b²`; `s` is clamped to `[0, 1]`, `t = (b s + f)/e`, and
//! when `t` leaves `[0, 1]` it is clamped and `s` recomputed.
//!
//! **Parallel segments** (`a e − b² ≤ 1e-14·a e`): the minimizing set is not a singleton
//! (eq. 12's `P_{a,b}`). The rule, a function of the input only: `s = 0`, `t` its projection
//! clamped, then `s` recomputed from `t` and clamped. **Zero-length segments** degrade to
//! point–segment and point–point. The result is then compared with the four
//! endpoint–segment candidates (in the order a0, a1, b0, b1) and the first strictly smaller
//! one replaces it, so round-off in the 2×2 solve can never give more than the endpoint
//! distances.

use nalgebra::Vector3;

/// Result of a segment–segment query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentSegment {
    /// Euclidean distance (not squared).
    pub distance: f64,
    /// Parameter of the closest point on `[a0, a1]`.
    pub s: f64,
    /// Parameter of the closest point on `[b0, b1]`.
    pub t: f64,
    /// `(1 − s) a0 + s a1`.
    pub pa: Vector3<f64>,
    /// `(1 − t) b0 + t b1`.
    pub pb: Vector3<f64>,
}

fn project(p: &Vector3<f64>, a: &Vector3<f64>, d: &Vector3<f64>, l2: f64) -> f64 {
    if l2 > 0.0 {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Distance between the segments `[a0, a1]` and `[b0, b1]`, with closest points.
pub fn segment_segment_distance(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> SegmentSegment {
    let d1 = a1 - a0;
    let d2 = b1 - b0;
    let r = a0 - b0;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let mk = |s: f64, t: f64| {
        let pa = a0 + d1 * s;
        let pb = b0 + d2 * t;
        SegmentSegment {
            distance: (pb - pa).norm(),
            s,
            t,
            pa,
            pb,
        }
    };
    let (a_ok, e_ok) = (a > 0.0, e > 0.0); // false for zero length (or NaN)
    let (s, t) = if !a_ok && !e_ok {
        (0.0, 0.0)
    } else if !a_ok {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if !e_ok {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let mut best = mk(s, t);
    let cands = [
        (0.0, project(a0, b0, &d2, e)),
        (1.0, project(a1, b0, &d2, e)),
        (project(b0, a0, &d1, a), 0.0),
        (project(b1, a0, &d1, a), 1.0),
    ];
    for (s, t) in cands {
        let c = mk(s, t);
        if c.distance < best.distance {
            best = c;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

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

    /// Brute force: sample one segment, exact point–segment distance to the other, both ways.
    fn brute(a0: &Vector3<f64>, a1: &Vector3<f64>, b0: &Vector3<f64>, b1: &Vector3<f64>) -> f64 {
        let n = 20_000;
        let mut m = f64::INFINITY;
        for k in 0..=n {
            let s = k as f64 / n as f64;
            m = m.min(point_seg(&(a0 + (a1 - a0) * s), b0, b1));
            m = m.min(point_seg(&(b0 + (b1 - b0) * s), a0, a1));
        }
        m
    }

    fn check(
        a0: Vector3<f64>,
        a1: Vector3<f64>,
        b0: Vector3<f64>,
        b1: Vector3<f64>,
    ) -> SegmentSegment {
        let r = segment_segment_distance(&a0, &a1, &b0, &b1);
        assert!(r.distance.is_finite() && r.s.is_finite() && r.t.is_finite());
        assert!((0.0..=1.0).contains(&r.s) && (0.0..=1.0).contains(&r.t));
        assert!((r.pa - (a0 + (a1 - a0) * r.s)).norm() < 1e-12);
        assert!((r.pb - (b0 + (b1 - b0) * r.t)).norm() < 1e-12);
        let b = brute(&a0, &a1, &b0, &b1);
        let len = (a1 - a0).norm().max((b1 - b0).norm());
        assert!(r.distance <= b + 1e-12, "kernel {} > brute {b}", r.distance);
        assert!(
            r.distance >= b - len / 20_000.0 - 1e-12,
            "kernel {} << brute {b}",
            r.distance
        );
        let sym = segment_segment_distance(&b0, &b1, &a0, &a1);
        assert!((sym.distance - r.distance).abs() <= 1e-14 * (1.0 + r.distance));
        r
    }

    #[test]
    fn segment_segment_special_cases() {
        // skew, perpendicular, distance 2
        let r = check(
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, -1.0, 2.0),
            v(0.0, 1.0, 2.0),
        );
        assert!((r.distance - 2.0).abs() < 1e-15 && (r.s - 0.5).abs() < 1e-15);
        // crossing in their interiors
        let r = check(
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, -1.0, 0.0),
            v(0.0, 1.0, 0.0),
        );
        assert!(r.distance < 1e-15);
        // parallel, overlapping: distance 1, the rule s = 0 then t from it
        let r = check(
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(3.0, 1.0, 0.0),
        );
        assert!((r.distance - 1.0).abs() < 1e-15);
        let again = segment_segment_distance(
            &v(0.0, 0.0, 0.0),
            &v(2.0, 0.0, 0.0),
            &v(1.0, 1.0, 0.0),
            &v(3.0, 1.0, 0.0),
        );
        assert_eq!(r, again, "parallel choice is deterministic");
        // parallel, disjoint along the line
        let r = check(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 1.0, 0.0),
            v(4.0, 1.0, 0.0),
        );
        assert!((r.distance - 5f64.sqrt()).abs() < 1e-15);
        // collinear overlapping
        let r = check(
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 0.0, 0.0),
        );
        assert_eq!(r.distance, 0.0);
        // nearly parallel
        for ang in [1e-9, 1e-12] {
            check(
                v(0.0, 0.0, 0.0),
                v(1.0, 0.0, 0.0),
                v(0.2, 0.5, 0.0),
                v(1.2, 0.5 + ang, ang),
            );
        }
        // zero-length segments
        let r = check(
            v(0.5, 1.0, 0.0),
            v(0.5, 1.0, 0.0),
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        );
        assert!((r.distance - 1.0).abs() < 1e-15);
        let r = check(
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 3.0, 4.0),
            v(0.0, 3.0, 4.0),
        );
        assert!((r.distance - 5.0).abs() < 1e-15);
    }

    #[test]
    fn segment_segment_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut r = || {
            v(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            )
        };
        for k in 0..200 {
            let (a0, a1, b0, mut b1) = (r(), r(), r(), r());
            if k % 4 == 0 {
                b1 = b0 + (a1 - a0) * 0.7; // parallel
            }
            check(a0, a1, b0, b1);
        }
    }
}
