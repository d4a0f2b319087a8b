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
use nalgebra::Vector2;

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
mod tests {
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
