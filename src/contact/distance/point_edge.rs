//! Point–edge distance in the plane.
//!
//! For a point `p` and a segment `[a0, a1]` with direction `e = a1 − a0`, the closest point is
//!
//! ```text
//! t* = clamp( (p − a0)·e / |e|², 0, 1 ),   q = (1 − t*) a0 + t* a1,   d = |p − q|.
//! ```
//!
//! When `0 < t* < 1` the distance is computed as `|(p − a0) × e| / |e|` (the 2D cross
//! product), which is exactly `0` whenever the cross product vanishes exactly, e.g. for a
//! point on the segment with representable coordinates. A zero-length edge (`e = 0`) is
//! treated as the point `a0`: `q = a0`, `alpha = [1, 0]`.

use nalgebra::Vector2;

/// Result of a point–edge query. `distance` is NOT squared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEdge {
    /// Euclidean distance from the point to the segment (not squared).
    pub distance: f64,
    /// Barycentric coordinates of the closest point: `q = alpha[0]*a0 + alpha[1]*a1`,
    /// `alpha ≥ 0`, `alpha[0] + alpha[1] = 1`.
    pub alpha: [f64; 2],
    /// The closest point `q` on the segment.
    pub closest: Vector2<f64>,
}

/// Distance from `p` to the segment `[a0, a1]`, with the closest point and its barycentric
/// coordinates. See the module documentation for the formula.
pub fn point_edge_distance(p: &Vector2<f64>, a0: &Vector2<f64>, a1: &Vector2<f64>) -> PointEdge {
    let e = a1 - a0;
    let l2 = e.norm_squared();
    let d0 = p - a0;
    let at_a0 = || PointEdge {
        distance: d0.norm(),
        alpha: [1.0, 0.0],
        closest: *a0,
    };
    if l2 == 0.0 || !l2.is_finite() {
        return at_a0();
    }
    let s = d0.dot(&e);
    if s <= 0.0 {
        return at_a0();
    }
    if s >= l2 {
        return PointEdge {
            distance: (p - a1).norm(),
            alpha: [0.0, 1.0],
            closest: *a1,
        };
    }
    let t = s / l2;
    let cross = d0.x * e.y - d0.y * e.x;
    let distance = cross.abs() / l2.sqrt();
    let closest = if cross == 0.0 { *p } else { a0 + e * t };
    PointEdge {
        distance,
        alpha: [1.0 - t, t],
        closest,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const N: usize = 10_000;

    fn sampled_min(p: &Vector2<f64>, a0: &Vector2<f64>, a1: &Vector2<f64>) -> f64 {
        (0..=N)
            .map(|k| {
                let t = k as f64 / N as f64;
                (p - (a0 * (1.0 - t) + a1 * t)).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn check(p: &Vector2<f64>, a0: &Vector2<f64>, a1: &Vector2<f64>) {
        let r = point_edge_distance(p, a0, a1);
        let len = (a1 - a0).norm();
        let m = sampled_min(p, a0, a1);
        let tol = 1e-12 * (1.0 + p.norm() + a0.norm() + a1.norm());
        assert!(r.distance <= m + tol, "{} > sampled {}", r.distance, m);
        assert!(
            r.distance >= m - len / N as f64 - tol,
            "{} < sampled {} - h",
            r.distance,
            m
        );
        assert!(r.alpha[0] >= 0.0 && r.alpha[1] >= 0.0);
        assert!((r.alpha[0] + r.alpha[1] - 1.0).abs() <= 1e-15);
        let q = a0 * r.alpha[0] + a1 * r.alpha[1];
        assert!((q - r.closest).norm() <= tol * 10.0 + 1e-12 * len);
        assert!(((p - r.closest).norm() - r.distance).abs() <= tol * 10.0 + 1e-12 * len);
        // symmetric under swapping the endpoints
        let s = point_edge_distance(p, a1, a0);
        assert!((s.distance - r.distance).abs() <= tol * 10.0);
        assert!((s.closest - r.closest).norm() <= tol * 10.0 + 1e-12 * len);
    }

    #[test]
    fn geometry_point_edge_random_vs_sampling() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..300 {
            let mut v = || Vector2::new(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0));
            let (p, a0, a1) = (v(), v(), v());
            check(&p, &a0, &a1);
        }
    }

    #[test]
    fn geometry_point_edge_degenerate_edge() {
        let a = Vector2::new(0.3, -0.7);
        let p = Vector2::new(1.3, 0.3);
        let r = point_edge_distance(&p, &a, &a);
        assert_eq!(r.alpha, [1.0, 0.0]);
        assert_eq!(r.closest, a);
        assert!((r.distance - 2f64.sqrt()).abs() < 1e-15);
        check(&p, &a, &a);
        let r = point_edge_distance(&a, &a, &a);
        assert_eq!(r.distance, 0.0);
    }

    #[test]
    fn geometry_point_edge_collinear_and_on_segment() {
        let a0 = Vector2::new(0.0, 0.0);
        let a1 = Vector2::new(2.0, 0.0);
        // on the segment: exactly zero
        for x in [0.0, 0.5, 1.0, 1.75, 2.0] {
            let p = Vector2::new(x, 0.0);
            let r = point_edge_distance(&p, &a0, &a1);
            assert_eq!(r.distance, 0.0);
            assert!((r.alpha[1] - x / 2.0).abs() < 1e-15);
            check(&p, &a0, &a1);
        }
        // collinear beyond the ends
        let p = Vector2::new(3.0, 0.0);
        let r = point_edge_distance(&p, &a0, &a1);
        assert_eq!(r.distance, 1.0);
        assert_eq!(r.alpha, [0.0, 1.0]);
        let p = Vector2::new(-0.5, 0.0);
        let r = point_edge_distance(&p, &a0, &a1);
        assert_eq!(r.distance, 0.5);
        assert_eq!(r.alpha, [1.0, 0.0]);
        // slanted segment, point on it (exact in binary)
        let b0 = Vector2::new(1.0, 1.0);
        let b1 = Vector2::new(3.0, 2.0);
        let p = Vector2::new(2.0, 1.5);
        let r = point_edge_distance(&p, &b0, &b1);
        assert_eq!(r.distance, 0.0);
        assert_eq!(r.closest, p);
        check(&p, &b0, &b1);
        // perpendicular foot in the interior
        let p = Vector2::new(1.0, 0.25);
        let r = point_edge_distance(&p, &a0, &a1);
        assert_eq!(r.distance, 0.25);
        assert_eq!(r.alpha, [0.5, 0.5]);
    }
}
