//! Point–triangle distance in space (Ericson, *Real-Time Collision Detection*, §5.1.5).
//!
//! The closest point of the triangle `(t0, t1, t2)` to `p` lies in one of seven Voronoi regions
//! (three vertices, three edges, the face), told apart by the signs of dot products of
//! `p − t_i` with the edge vectors. A degenerate triangle (collinear or coincident vertices,
//! `|(t1 − t0) × (t2 − t0)|² ≤ 1e-30·scale⁴`) is treated as its three edges.

use nalgebra::Vector3;

/// Result of a point–triangle query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTriangle {
    /// Euclidean distance (not squared).
    pub distance: f64,
    /// Barycentric coordinates of the closest point (≥ 0, sum 1).
    pub beta: [f64; 3],
    /// The closest point `Σ beta_i t_i`.
    pub closest: Vector3<f64>,
}

fn on_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> (f64, Vector3<f64>) {
    let e = b - a;
    let l2 = e.norm_squared();
    let usable = l2 > 0.0;
    if !usable {
        return (0.0, *a);
    }
    let t = ((p - a).dot(&e) / l2).clamp(0.0, 1.0);
    (t, a + e * t)
}

/// Distance from `p` to the triangle `(t0, t1, t2)`, with the closest point and its
/// barycentric coordinates.
pub fn point_triangle_distance(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> PointTriangle {
    let ab = t1 - t0;
    let ac = t2 - t0;
    let scale = ab.norm_squared().max(ac.norm_squared());
    let mk = |beta: [f64; 3]| {
        let closest = t0 * beta[0] + t1 * beta[1] + t2 * beta[2];
        PointTriangle {
            distance: (p - closest).norm(),
            beta,
            closest,
        }
    };
    if ab.cross(&ac).norm_squared() <= 1e-30 * scale * scale {
        // degenerate: the best of the three edges
        let (s0, _) = on_segment(p, t0, t1);
        let (s1, _) = on_segment(p, t1, t2);
        let (s2, _) = on_segment(p, t2, t0);
        let cands = [
            mk([1.0 - s0, s0, 0.0]),
            mk([0.0, 1.0 - s1, s1]),
            mk([s2, 0.0, 1.0 - s2]),
        ];
        return cands
            .into_iter()
            .min_by(|a, b| a.distance.total_cmp(&b.distance))
            .expect("three candidates");
    }
    let ap = p - t0;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return mk([1.0, 0.0, 0.0]);
    }
    let bp = p - t1;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return mk([0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return mk([1.0 - v, v, 0.0]);
    }
    let cp = p - t2;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return mk([0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return mk([1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return mk([0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    let mut r = mk([1.0 - v - w, v, w]);
    // inside the face: the distance to the plane, exactly 0 for a point on it
    let n = ab.cross(&ac);
    r.distance = (ap.dot(&n) / n.norm()).abs();
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Brute force over a barycentric grid.
    fn brute(p: &Vector3<f64>, t: &[Vector3<f64>; 3]) -> f64 {
        let n = 300;
        let mut m = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (b1, b2) = (i as f64 / n as f64, j as f64 / n as f64);
                let q = t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
                m = m.min((p - q).norm());
            }
        }
        m
    }

    fn check(p: &Vector3<f64>, t: &[Vector3<f64>; 3]) {
        let r = point_triangle_distance(p, &t[0], &t[1], &t[2]);
        assert!(r.distance.is_finite() && r.beta.iter().all(|b| b.is_finite()));
        assert!(r.beta.iter().all(|&b| b >= -1e-12), "{:?}", r.beta);
        assert!((r.beta.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let q = t[0] * r.beta[0] + t[1] * r.beta[1] + t[2] * r.beta[2];
        assert!((q - r.closest).norm() < 1e-12);
        assert!(((p - r.closest).norm() - r.distance).abs() < 1e-10);
        let b = brute(p, t);
        // the grid's spacing bounds how far above the true minimum the brute force can be
        let spacing = (t[1] - t[0]).norm().max((t[2] - t[0]).norm()) / 300.0;
        assert!(r.distance <= b + 1e-12, "kernel {} > brute {b}", r.distance);
        assert!(
            r.distance >= b - spacing,
            "kernel {} << brute {b}",
            r.distance
        );
    }

    #[test]
    fn point_triangle_voronoi_regions() {
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let cases = [
            (v(-1.0, -1.0, 1.0), v(0.0, 0.0, 0.0)),
            (v(2.0, -0.5, 1.0), v(1.0, 0.0, 0.0)),
            (v(-0.5, 2.0, -1.0), v(0.0, 1.0, 0.0)),
            (v(0.5, -1.0, 2.0), v(0.5, 0.0, 0.0)),
            (v(-1.0, 0.3, 0.0), v(0.0, 0.3, 0.0)),
            (v(1.0, 1.0, 3.0), v(0.5, 0.5, 0.0)),
            (v(0.2, 0.3, -4.0), v(0.2, 0.3, 0.0)),
        ];
        for (p, q) in cases {
            let r = point_triangle_distance(&p, &t[0], &t[1], &t[2]);
            assert!((r.closest - q).norm() < 1e-15, "{p:?}: {:?}", r.closest);
            assert!((r.distance - (p - q).norm()).abs() < 1e-15);
            check(&p, &t);
        }
        // on the face and at a vertex: exactly 0
        assert_eq!(
            point_triangle_distance(&v(0.25, 0.25, 0.0), &t[0], &t[1], &t[2]).distance,
            0.0
        );
        assert_eq!(
            point_triangle_distance(&t[1], &t[0], &t[1], &t[2]).distance,
            0.0
        );
    }

    #[test]
    fn point_triangle_matches_brute_force_including_degenerate() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut r = || {
            v(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            )
        };
        for k in 0..240 {
            let (p, a, b, mut c) = (r(), r(), r(), r());
            match k % 6 {
                0 => c = a + (b - a) * 0.3, // collinear
                1 => c = b,                 // two coincident vertices
                2 => {
                    // point coplanar with the triangle
                    let n = (b - a).cross(&(c - a));
                    let p2 = p - n * ((p - a).dot(&n) / n.norm_squared());
                    check(&p2, &[a, b, c]);
                    continue;
                }
                _ => {}
            }
            check(&p, &[a, b, c]);
        }
        // all three vertices equal
        let a = v(0.1, 0.2, 0.3);
        let q = point_triangle_distance(&v(1.0, 0.2, 0.3), &a, &a, &a);
        assert!((q.distance - 0.9).abs() < 1e-15);
    }
}
