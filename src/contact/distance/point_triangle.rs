//! Point–triangle distance in space (Ericson, *Real-Time Collision Detection*, §5.1.5).
//!
//! The closest point `q` of the triangle `T = (t0, t1, t2)` to `p` lies in one of seven Voronoi
//! regions: three vertices, three edges, the face. With `ab = t1 − t0`, `ac = t2 − t0`,
//! `bc = t2 − t1`, `ap = p − t0`, `bp = p − t1`, `cp = p − t2` and a normal `n` of the plane,
//! the regions are tested in Ericson's order:
//!
//! ```text
//! vertex t0:  ab·ap ≤ 0,  ac·ap ≤ 0
//! vertex t1:  ab·bp ≥ 0,  bc·bp ≤ 0
//! edge t0t1:  vc ≤ 0,  ab·ap ≥ 0,  ab·bp ≤ 0          vc = n·(ab × ap)
//! vertex t2:  ac·cp ≥ 0,  bc·cp ≥ 0
//! edge t0t2:  vb ≤ 0,  ac·ap ≥ 0,  ac·cp ≤ 0          vb = n·(cp × ac)
//! edge t1t2:  va ≤ 0,  bc·bp ≥ 0,  bc·cp ≤ 0          va = n·(bc × bp)
//! face:       otherwise; beta ∝ (va, vb, vc) (computed as below)
//! ```
//!
//! `va, vb, vc` are Ericson's `d3 d6 − d5 d4`, `d5 d2 − d1 d6`, `d1 d4 − d3 d2` rewritten by the
//! Lagrange identity `(u × v)·(w × z) = (u·w)(v·z) − (u·z)(v·w)` and `bp × cp = bc × bp` etc.:
//! the triple-product form avoids the cancellation of the products of dot products on thin
//! triangles. `n` is the cross product of the two edges at the vertex opposite the longest edge
//! (the three choices are equal in exact arithmetic; this one is the best conditioned). In an
//! edge region the closest point is the clamped projection on that edge, in a vertex region the
//! vertex itself.
//!
//! **Face weights.** Normalizing `(va, vb, vc)` loses accuracy on thin triangles (a relative error
//! of order `ε_mach · longest / width` in every weight, which moves the point *along* the
//! triangle). Instead, with `t_i → t_j` the longest edge, `e = t_j − t_i`, and `t_o` the opposite
//! vertex,
//!
//! ```text
//! beta_o = v_o / (n·n),   beta_j = x − beta_o x_o,   beta_i = 1 − beta_j − beta_o,
//! x = (p − t_i)·e / |e|²,   x_o = (t_o − t_i)·e / |e|²,
//! ```
//!
//! (`va + vb + vc = n·n` exactly), clamped to `≥ 0` and renormalized: the coordinate along the
//! longest edge is then that of the projection of `p`, and an error in `beta_o` only moves the
//! point across the triangle, by at most its width. Slivers and needles down to a width of
//! `1e-14 ×` their length are tested to `2e-15` against an exact 2D reference.
//!
//! **Exact zeros.** A point exactly at a vertex gives distance `0`; in an edge region the
//! closest point is `p` itself when `(p − t_i) × (t_j − t_i)` vanishes exactly, and in the face
//! region when `n·ap` vanishes exactly (triangles that are not thin only:
//! `(2 area)² > 1e-6 · longest⁴`), so a point on the triangle with exactly representable cross
//! products (e.g. on a triangle in a coordinate plane) gets distance exactly `0`. Elsewhere
//! `distance = |p − closest|` (so `(closest − p)/distance` is a unit vector to rounding), and
//! `closest = Σ beta_i t_i` up to rounding; the closest point is always a convex combination
//! of the vertices, so the distance never falls below the true one by more than rounding.
//!
//! **Degenerate triangles.** When the triangle has no usable normal (`n·n = 0`: collinear or
//! coincident vertices up to rounding to exactly zero), the answer is the best of the three
//! clamped edge projections in the order `t0t1`, `t1t2`, `t2t0` (first wins on ties; a
//! zero-length edge is its first vertex): two coincident vertices give the distance to the
//! remaining segment, three coincident vertices the distance to the point with
//! `beta = [1, 0, 0]`. Collinear vertices whose `n` is rounding noise go through the region
//! walk, whose vertex and edge tests use only dot products along the line, and whose face
//! formula keeps the coordinate along the line: the result is the closest point of the hull
//! segment to rounding.
//! `beta` is always finite, `≥ 0` and sums to `1` (to rounding); no NaN arises from finite
//! input.
//!
//! **Non-finite input.** Comparisons with NaN are false, so the region tests fall through to
//! the edge fallback, whose clamping maps NaN parameters to `0`: `beta` stays a valid triple,
//! but `distance` and `closest` are NaN or infinite. Callers treat a NaN distance as "no
//! answer" (as `rows3d` does). Finite coordinates large enough to overflow the squared lengths
//! (`|x| ≳ 1e150`) behave the same way.

use nalgebra::Vector3;

/// Result of a point–triangle query. `distance` is NOT squared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTriangle {
    /// Euclidean distance from the point to the (closed) triangle, not squared.
    pub distance: f64,
    /// Barycentric coordinates of the closest point: `closest = Σ beta_i t_i` (to rounding),
    /// `beta_i ≥ 0`, `Σ beta_i = 1` (to rounding).
    pub beta: [f64; 3],
    /// The closest point of the triangle.
    pub closest: Vector3<f64>,
}

/// A triangle is *thin* when `(2 area)² ≤ NEAR_DEGENERATE · (longest edge)⁴`; its plane is then
/// not trusted for the exact-zero shortcut of the face region.
const NEAR_DEGENERATE: f64 = 1e-6;

/// Clamped projection of `p` on the segment `[a, b]`: the parameter `u ∈ [0, 1]` and the point.
/// A zero-length (or non-finite) segment gives `u = 0`, the point `a`; a point exactly on the
/// segment's line (exactly vanishing cross product) inside the segment is returned as itself.
fn closest_on_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> (f64, Vector3<f64>) {
    let e = b - a;
    let l2 = e.norm_squared();
    if l2.is_nan() || l2 <= 0.0 {
        return (0.0, *a);
    }
    let ap = p - a;
    let s = ap.dot(&e);
    if s.is_nan() || s <= 0.0 {
        return (0.0, *a);
    }
    if s >= l2 {
        return (1.0, *b);
    }
    let u = s / l2;
    let q = if ap.cross(&e) == Vector3::zeros() {
        *p
    } else {
        a + e * u
    };
    (u, q)
}

fn result(p: &Vector3<f64>, beta: [f64; 3], closest: Vector3<f64>) -> PointTriangle {
    PointTriangle {
        distance: (p - closest).norm(),
        beta,
        closest,
    }
}

/// The best of the three edges, in the order `t0t1`, `t1t2`, `t2t0` (first wins on ties).
fn best_edge(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> PointTriangle {
    let (u, q) = closest_on_segment(p, t0, t1);
    let mut best = result(p, [1.0 - u, u, 0.0], q);
    let (u, q) = closest_on_segment(p, t1, t2);
    let c = result(p, [0.0, 1.0 - u, u], q);
    if c.distance < best.distance {
        best = c;
    }
    let (u, q) = closest_on_segment(p, t2, t0);
    let c = result(p, [u, 0.0, 1.0 - u], q);
    if c.distance < best.distance {
        best = c;
    }
    best
}

/// Ericson's region walk with the normal `n` (`n ≠ 0`, `s2 = n·n`); `(i, j)` is the longest edge
/// (in cyclic order, `o` the opposite vertex), `thin` whether the triangle is nearly
/// degenerate. `None` when the face weights are unusable (only for a numerically degenerate or
/// non-finite configuration).
fn by_regions(
    p: &Vector3<f64>,
    t: [&Vector3<f64>; 3],
    n: &Vector3<f64>,
    s2: f64,
    base: (usize, usize, usize),
    thin: bool,
) -> Option<PointTriangle> {
    let [t0, t1, t2] = t;
    let ab = t1 - t0;
    let ac = t2 - t0;
    let bc = t2 - t1;
    let ap = p - t0;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return Some(result(p, [1.0, 0.0, 0.0], *t0));
    }
    let bp = p - t1;
    let d3 = ab.dot(&bp);
    let e1 = bc.dot(&bp);
    if d3 >= 0.0 && e1 <= 0.0 {
        return Some(result(p, [0.0, 1.0, 0.0], *t1));
    }
    let vc = n.dot(&ab.cross(&ap));
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let (u, q) = closest_on_segment(p, t0, t1);
        return Some(result(p, [1.0 - u, u, 0.0], q));
    }
    let cp = p - t2;
    let d6 = ac.dot(&cp);
    let e2 = bc.dot(&cp);
    if d6 >= 0.0 && e2 >= 0.0 {
        return Some(result(p, [0.0, 0.0, 1.0], *t2));
    }
    let vb = n.dot(&cp.cross(&ac));
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let (u, q) = closest_on_segment(p, t0, t2);
        return Some(result(p, [1.0 - u, 0.0, u], q));
    }
    let va = n.dot(&bc.cross(&bp));
    if va <= 0.0 && e1 >= 0.0 && e2 <= 0.0 {
        let (u, q) = closest_on_segment(p, t1, t2);
        return Some(result(p, [0.0, 1.0 - u, u], q));
    }
    // Face region (va, vb, vc > 0 and va + vb + vc = n·n in exact arithmetic). On the longest
    // edge t_i → t_j with opposite vertex t_o: beta_o = v_o / n·n, and beta_j is chosen so that
    // the coordinate along the edge is exactly the projection of p, x = (p − t_i)·e / |e|²:
    // an error in beta_o (large on thin triangles) then moves the point across the triangle
    // only, by at most its width.
    let (i, j, o) = base;
    let e = t[j] - t[i];
    let le = e.norm_squared();
    let x = (p - t[i]).dot(&e) / le;
    let xo = (t[o] - t[i]).dot(&e) / le;
    let bo = ([va, vb, vc][o] / s2).clamp(0.0, 1.0);
    let bj = (x - bo * xo).max(0.0);
    let bi = (1.0 - bj - bo).max(0.0);
    let sum = bi + bj + bo;
    if !(sum > 0.0 && sum.is_finite()) {
        return None;
    }
    let mut beta = [0.0; 3];
    beta[i] = bi / sum;
    beta[j] = bj / sum;
    beta[o] = bo / sum;
    let closest = if !thin && n.dot(&ap) == 0.0 {
        *p
    } else {
        t0 * beta[0] + t1 * beta[1] + t2 * beta[2]
    };
    Some(result(p, beta, closest))
}

/// Distance from `p` to the closed triangle `(t0, t1, t2)`, with the closest point and its
/// barycentric coordinates (Ericson's Voronoi regions; see the module documentation for the
/// formulas and for what degenerate and non-finite inputs return). Never NaN for finite input
/// (short of overflow, `|x| ≳ 1e150`); `beta` is always a valid barycentric triple.
pub fn point_triangle_distance(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> PointTriangle {
    let ab = t1 - t0;
    let ac = t2 - t0;
    let bc = t2 - t1;
    let (lab, lac, lbc) = (ab.norm_squared(), ac.norm_squared(), bc.norm_squared());
    // normal from the two edges at the vertex opposite the longest edge: ab × ac = bc × ba
    // = ca × cb in exact arithmetic.
    let n = if lbc >= lab && lbc >= lac {
        ab.cross(&ac)
    } else if lac >= lab {
        bc.cross(&(-ab))
    } else {
        (-ac).cross(&(-bc))
    };
    let longest = lab.max(lac).max(lbc);
    // the longest edge as (i, j) in cyclic order, and the opposite vertex
    let base = if lbc >= lab && lbc >= lac {
        (1, 2, 0)
    } else if lac >= lab {
        (2, 0, 1)
    } else {
        (0, 1, 2)
    };
    let s2 = n.norm_squared();
    if !(s2 > 0.0 && s2.is_finite()) {
        return best_edge(p, t0, t1, t2);
    }
    let thin = s2 <= NEAR_DEGENERATE * longest * longest;
    by_regions(p, [t0, t1, t2], &n, s2, base, thin).unwrap_or_else(|| best_edge(p, t0, t1, t2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const GRID: usize = 300;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Brute force: the minimum over a `GRID × GRID` barycentric grid of the triangle. Any point
    /// of the triangle is within `longest edge / GRID` of a grid point.
    fn brute(p: &Vector3<f64>, t: &[Vector3<f64>; 3]) -> f64 {
        let mut m = f64::INFINITY;
        for i in 0..=GRID {
            for j in 0..=(GRID - i) {
                let (b1, b2) = (i as f64 / GRID as f64, j as f64 / GRID as f64);
                let q = t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
                m = m.min((p - q).norm_squared());
            }
        }
        m.sqrt()
    }

    /// The invariants of a result (no brute force): finite, valid barycentrics, closest point
    /// consistent with them and with the distance.
    fn check_invariants(p: &Vector3<f64>, t: &[Vector3<f64>; 3], r: &PointTriangle) {
        let scale = 1.0 + p.norm() + t.iter().map(|x| x.norm()).fold(0.0, f64::max);
        assert!(r.distance.is_finite(), "NaN/inf distance {r:?}");
        assert!(r.closest.iter().all(|c| c.is_finite()), "{r:?}");
        assert!(r.beta.iter().all(|&b| b.is_finite() && b >= 0.0), "{r:?}");
        assert!((r.beta.iter().sum::<f64>() - 1.0).abs() <= 1e-15, "{r:?}");
        let q = t[0] * r.beta[0] + t[1] * r.beta[1] + t[2] * r.beta[2];
        assert!(
            (q - r.closest).norm() <= 1e-12 * scale,
            "closest off the triangle {r:?}"
        );
        assert!(((p - r.closest).norm() - r.distance).abs() <= 1e-12 * scale);
    }

    fn check(p: &Vector3<f64>, t: &[Vector3<f64>; 3]) -> PointTriangle {
        let r = point_triangle_distance(p, &t[0], &t[1], &t[2]);
        check_invariants(p, t, &r);
        let b = brute(p, t);
        let longest = (t[1] - t[0])
            .norm()
            .max((t[2] - t[0]).norm())
            .max((t[2] - t[1]).norm());
        let tol = 1e-12 * (1.0 + p.norm() + longest);
        assert!(r.distance <= b + tol, "kernel {} > brute {b}", r.distance);
        assert!(
            r.distance >= b - longest / GRID as f64 - tol,
            "kernel {} < brute {b} − h",
            r.distance
        );
        // invariant under a cyclic relabelling and a reflection of the vertices
        for (i, j, k) in [(1, 2, 0), (2, 0, 1), (0, 2, 1)] {
            let s = point_triangle_distance(p, &t[i], &t[j], &t[k]);
            assert!((s.distance - r.distance).abs() <= tol, "{s:?} vs {r:?}");
        }
        r
    }

    #[test]
    fn geometry_point_triangle_voronoi_regions_exact() {
        // a scalene triangle in z = 0
        let t = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        // (point, expected closest point, expected beta)
        let cases = [
            (v(-1.0, -1.0, 1.0), v(0.0, 0.0, 0.0), [1.0, 0.0, 0.0]), // vertex t0
            (v(3.0, -0.5, 1.0), v(2.0, 0.0, 0.0), [0.0, 1.0, 0.0]),  // vertex t1
            (v(-0.5, 2.0, -1.0), v(0.0, 1.0, 0.0), [0.0, 0.0, 1.0]), // vertex t2
            (v(0.5, -1.0, 2.0), v(0.5, 0.0, 0.0), [0.75, 0.25, 0.0]), // edge t0t1
            (v(-1.0, 0.25, 0.0), v(0.0, 0.25, 0.0), [0.75, 0.0, 0.25]), // edge t0t2
            // edge t1t2: outward normal (1, 2, 0); foot (1, 0.5, 0)
            (v(2.0, 2.5, 3.0), v(1.0, 0.5, 0.0), [0.0, 0.5, 0.5]),
            (v(0.5, 0.25, -4.0), v(0.5, 0.25, 0.0), [0.5, 0.25, 0.25]), // face
        ];
        for (p, q, beta) in cases {
            let r = check(&p, &t);
            assert_eq!(r.closest, q, "{p:?}");
            assert_eq!(r.distance, (p - q).norm(), "{p:?}");
            for (got, want) in r.beta.iter().zip(beta) {
                assert!((got - want).abs() <= 1e-15, "{p:?}: {:?}", r.beta);
            }
        }
    }

    #[test]
    fn geometry_point_triangle_voronoi_regions_tilted() {
        // A triangle in a tilted plane with integer data: closest points constructed as
        // q + h·n + k·m with m an outward direction of q's region (normal cone).
        let t = [v(1.0, 0.0, 0.0), v(0.0, 2.0, 0.0), v(0.0, 0.0, 3.0)];
        let n = (t[1] - t[0]).cross(&(t[2] - t[0])); // (6, 3, 2)
        let out = |a: usize, b: usize| (t[b] - t[a]).cross(&n); // outward in-plane edge normal
        let (m01, m12, m20) = (out(0, 1), out(1, 2), out(2, 0));
        let third = (t[0] + t[1] + t[2]) / 3.0;
        let cases = [
            (t[0], m01 + m20, [1.0, 0.0, 0.0]),
            (t[1], m01 + m12, [0.0, 1.0, 0.0]),
            (t[2], m12 + m20, [0.0, 0.0, 1.0]),
            ((t[0] + t[1]) * 0.5, m01, [0.5, 0.5, 0.0]),
            ((t[1] + t[2]) * 0.5, m12, [0.0, 0.5, 0.5]),
            ((t[2] + t[0]) * 0.5, m20, [0.5, 0.0, 0.5]),
            (third, Vector3::zeros(), [1.0 / 3.0; 3]),
        ];
        for (q, m, beta) in cases {
            for (h, k) in [(0.0, 0.5), (0.25, 0.125), (-0.5, 1.0), (1.0, 0.0)] {
                if m == Vector3::zeros() && k != 0.0 {
                    continue;
                }
                let p = q + n * h + m * k;
                let r = check(&p, &t);
                let want = (p - q).norm();
                assert!(
                    (r.closest - q).norm() <= 1e-14,
                    "{p:?}: {:?} vs {q:?}",
                    r.closest
                );
                assert!((r.distance - want).abs() <= 1e-14 * want.max(1.0));
                for (got, want) in r.beta.iter().zip(beta) {
                    assert!((got - want).abs() <= 1e-14, "{:?}", r.beta);
                }
            }
        }
    }

    #[test]
    fn geometry_point_triangle_exact_zero_on_triangle() {
        let t = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let on = [
            t[0],
            t[1],
            t[2],
            v(1.0, 0.0, 0.0),    // edge t0t1
            v(0.0, 0.5, 0.0),    // edge t0t2
            v(1.0, 0.5, 0.0),    // edge t1t2
            v(0.5, 0.25, 0.0),   // face
            v(0.125, 0.75, 0.0), // face, near t2
        ];
        for p in on {
            let r = check(&p, &t);
            assert_eq!(r.distance, 0.0, "{p:?}: {r:?}");
            assert_eq!(r.closest, p);
        }
        // tilted plane z = x + y: exact cross products
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 1.0), v(0.0, 1.0, 1.0)];
        for p in [v(0.25, 0.25, 0.5), v(0.5, 0.0, 0.5), v(0.5, 0.5, 1.0), t[1]] {
            let r = check(&p, &t);
            assert_eq!(r.distance, 0.0, "{p:?}: {r:?}");
        }
        // random points on random triangles: zero to rounding
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for _ in 0..200 {
            let mut r3 = || v(rng.gen(), rng.gen(), rng.gen());
            let t = [r3(), r3(), r3()];
            let (u, w): (f64, f64) = (rng.gen(), rng.gen());
            let (u, w) = if u + w > 1.0 {
                (1.0 - u, 1.0 - w)
            } else {
                (u, w)
            };
            let p = t[0] * (1.0 - u - w) + t[1] * u + t[2] * w;
            let r = point_triangle_distance(&p, &t[0], &t[1], &t[2]);
            check_invariants(&p, &t, &r);
            assert!(r.distance <= 1e-14, "{r:?}");
        }
    }

    #[test]
    fn geometry_point_triangle_coplanar_points() {
        let t = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        // inside: 0 exactly
        for p in [v(0.3, 0.3, 0.0), v(1.5, 0.2, 0.0), v(1e-300, 1e-300, 0.0)] {
            assert_eq!(check(&p, &t).distance, 0.0);
        }
        // outside, in the plane: the in-plane distance to the boundary
        let cases = [
            (v(-0.5, 0.5, 0.0), 0.5),
            (v(1.0, -0.25, 0.0), 0.25),
            (v(3.0, 0.0, 0.0), 1.0),
            (v(-3.0, -4.0, 0.0), 5.0),
            (v(2.0, 1.0, 0.0), 2.0 / 5f64.sqrt()), // beyond edge t1t2, foot (1.2, 0.4)
        ];
        for (p, d) in cases {
            let r = check(&p, &t);
            assert!(
                (r.distance - d).abs() <= 1e-15,
                "{p:?}: {} vs {d}",
                r.distance
            );
            assert_eq!(r.closest.z, 0.0);
        }
    }

    #[test]
    fn geometry_point_triangle_degenerate_triangles() {
        let p = v(0.3, 1.0, -0.5);
        let a = v(0.1, 0.2, 0.3);
        let b = v(1.1, -0.8, 0.7);
        // three coincident vertices: the point
        let r = check(&p, &[a, a, a]);
        assert_eq!(r.beta, [1.0, 0.0, 0.0]);
        assert_eq!(r.closest, a);
        assert_eq!(r.distance, (p - a).norm());
        assert_eq!(point_triangle_distance(&a, &a, &a, &a).distance, 0.0);
        // two coincident vertices: the segment [a, b], any position of the repeated vertex
        let seg = closest_on_segment(&p, &a, &b).1;
        for t in [
            [a, a, b],
            [a, b, a],
            [b, a, a],
            [a, b, b],
            [b, b, a],
            [b, a, b],
        ] {
            let r = check(&p, &t);
            assert!((r.distance - (p - seg).norm()).abs() <= 1e-15, "{t:?}");
        }
        // collinear: the hull is the longest edge, whichever vertex is in the middle
        let c = a + (b - a) * 0.25;
        for t in [[a, b, c], [a, c, b], [c, a, b], [b, c, a]] {
            let r = check(&p, &t);
            assert!((r.distance - (p - seg).norm()).abs() <= 1e-15, "{t:?}");
        }
        // collinear with exactly representable data, point on the line in the middle
        let t = [v(0.0, 0.0, 0.0), v(4.0, 0.0, 0.0), v(1.0, 0.0, 0.0)];
        let r = check(&v(3.0, 0.0, 0.0), &t);
        assert_eq!(r.distance, 0.0);
        assert_eq!(r.closest, v(3.0, 0.0, 0.0));
        let r = check(&v(3.0, 0.0, 2.0), &t);
        assert_eq!(r.distance, 2.0);
        // nearly collinear slivers (thin in one direction) and needles (one tiny edge)
        for eps in [1e-6, 1e-9, 1e-12, 1e-15, 1e-18] {
            let t = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.0, eps, eps)];
            for p in [
                v(1.0, 0.0, 0.5),
                v(1.0, 0.5, 0.0),
                v(2.5, 0.0, 0.0),
                v(0.7, -0.3, 0.2),
            ] {
                check(&p, &t);
            }
            let t = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(2.0, eps, 0.0)];
            for p in [
                v(1.0, 0.0, 0.5),
                v(1.0, 0.5, 0.0),
                v(2.5, 0.0, 0.0),
                v(0.7, -0.3, 0.2),
            ] {
                check(&p, &t);
            }
        }
    }

    #[test]
    fn geometry_point_triangle_random_vs_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut kinds = [0usize; 8];
        for k in 0..320 {
            let mut r3 = |s: f64| {
                v(
                    rng.gen_range(-s..s),
                    rng.gen_range(-s..s),
                    rng.gen_range(-s..s),
                )
            };
            let (mut p, a, b, mut c) = (r3(1.0), r3(1.0), r3(1.0), r3(1.0));
            let kind = k % 8;
            match kind {
                0 => c = a + (b - a) * 0.3,  // collinear, c inside
                1 => c = a + (b - a) * -0.7, // collinear, c outside [a, b]
                2 => c = b,                  // two coincident vertices
                3 => {
                    // point in the plane of the triangle (inside or outside)
                    let n = (b - a).cross(&(c - a));
                    p -= n * ((p - a).dot(&n) / n.norm_squared());
                }
                4 => {
                    // point close to the plane
                    let n = (b - a).cross(&(c - a)).normalize();
                    p -= n * ((p - a).dot(&n) - 1e-3 * (p.x - 0.5));
                }
                5 => c = a + (b - a) * 0.5 + r3(1e-7), // sliver
                6 => {
                    // small triangle far away, and a point near it
                    let off = v(3.0, -2.0, 1.0);
                    let (a, b, c) = (off + a * 1e-3, off + b * 1e-3, off + c * 1e-3);
                    let q = off + r3(2e-3);
                    check(&q, &[a, b, c]);
                    kinds[kind] += 1;
                    continue;
                }
                _ => {}
            }
            check(&p, &[a, b, c]);
            kinds[kind] += 1;
        }
        // three coincident vertices
        for _ in 0..20 {
            let mut r3 = || v(rng.gen(), rng.gen(), rng.gen());
            let (p, a) = (r3(), r3());
            let r = check(&p, &[a, a, a]);
            assert_eq!(r.distance, (p - a).norm());
            kinds[7] += 1;
        }
        assert!(kinds.iter().all(|&n| n >= 20), "{kinds:?}");
    }

    /// Tight cross-check on well-shaped triangles against an independent formulation: the
    /// foot of the perpendicular on the plane (barycentrics from the 2×2 Gram system) when it is
    /// inside, else the best of the three clamped edge projections.
    #[test]
    fn geometry_point_triangle_vs_independent_reference() {
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        let mut inside = 0;
        let mut n_cases = 0;
        while n_cases < 20_000 {
            let mut r3 = || {
                v(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            };
            let (p, a, b, c) = (r3() * 2.0, r3(), r3(), r3());
            let (ab, ac, bc) = (b - a, c - a, c - b);
            let area2 = ab.cross(&ac).norm();
            let longest2 = ab
                .norm_squared()
                .max(ac.norm_squared())
                .max(bc.norm_squared());
            if area2 < 0.1 * longest2 {
                continue; // not well shaped
            }
            n_cases += 1;
            let (g11, g12, g22) = (ab.dot(&ab), ab.dot(&ac), ac.dot(&ac));
            let (r1, r2) = (ab.dot(&(p - a)), ac.dot(&(p - a)));
            let det = g11 * g22 - g12 * g12;
            let (u, w) = ((g22 * r1 - g12 * r2) / det, (g11 * r2 - g12 * r1) / det);
            let reference = if u >= 0.0 && w >= 0.0 && u + w <= 1.0 {
                inside += 1;
                (p - (a + ab * u + ac * w)).norm()
            } else {
                let seg = |x: &Vector3<f64>, y: &Vector3<f64>| {
                    (p - closest_on_segment(&p, x, y).1).norm()
                };
                seg(&a, &b).min(seg(&b, &c)).min(seg(&c, &a))
            };
            let r = point_triangle_distance(&p, &a, &b, &c);
            check_invariants(&p, &[a, b, c], &r);
            assert!(
                (r.distance - reference).abs() <= 1e-14 * (1.0 + reference),
                "{} vs {reference}",
                r.distance
            );
        }
        assert!(inside > 500, "{inside}");
    }

    /// 2D reference: distance from (x, y) to the triangle (exact signs for these small data).
    fn dist_2d(q: [f64; 2], t: &[[f64; 2]; 3]) -> f64 {
        let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        let o = orient(t[0], t[1], t[2]).signum();
        if (0..3).all(|i| orient(t[i], t[(i + 1) % 3], q) * o >= 0.0) {
            return 0.0;
        }
        (0..3)
            .map(|i| {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let e = [b[0] - a[0], b[1] - a[1]];
                let w = [q[0] - a[0], q[1] - a[1]];
                let u = ((w[0] * e[0] + w[1] * e[1]) / (e[0] * e[0] + e[1] * e[1])).clamp(0.0, 1.0);
                (w[0] - u * e[0]).hypot(w[1] - u * e[1])
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Thin triangles (slivers with a vertex near the middle of the long edge, needles with a
    /// tiny edge) in z = 0, moved by a rotation with exactly orthonormal rational entries and a
    /// translation: the distance must match the 2D reference `hypot(h, d_2D)` closely.
    #[test]
    fn geometry_point_triangle_thin_triangles_accuracy() {
        let (e, f, g) = (v(0.6, -0.48, 0.64), v(0.8, 0.36, -0.48), v(0.0, 0.8, 0.6));
        let origin = v(0.3, -0.7, 0.2);
        let place = |x: f64, y: f64, z: f64| origin + e * x + f * y + g * z;
        let mut worst: f64 = 0.0;
        let mut rng = ChaCha8Rng::seed_from_u64(37);
        for delta in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
            let shapes = [
                [[0.0, 0.0], [2.0, 0.0], [1.0, delta]],    // sliver
                [[0.0, 0.0], [2.0, 0.0], [0.3, delta]],    // sliver, off-centre
                [[0.0, 0.0], [2.0, 0.0], [2.0, delta]],    // needle
                [[0.0, 0.0], [2.0, -delta], [2.0, delta]], // needle, symmetric
            ];
            for t2 in shapes {
                let t3 = t2.map(|q| place(q[0], q[1], 0.0));
                for _ in 0..100 {
                    let x = rng.gen_range(-0.5..2.5);
                    let y = match rng.gen_range(0..3) {
                        0 => rng.gen_range(-2.0..2.0) * delta,
                        1 => rng.gen_range(-1e-3..1e-3),
                        _ => rng.gen_range(-1.0..1.0),
                    };
                    let h = [0.0, 1e-3, 0.5][rng.gen_range(0..3)];
                    let p = place(x, y, h);
                    let want = h.hypot(dist_2d([x, y], &t2));
                    let r = point_triangle_distance(&p, &t3[0], &t3[1], &t3[2]);
                    check_invariants(&p, &t3, &r);
                    worst = worst.max((r.distance - want).abs());
                }
            }
        }
        eprintln!("thin triangles: worst error {worst:e}");
        assert!(worst <= 2e-15, "{worst:e}");
    }

    #[test]
    fn geometry_point_triangle_non_finite_input() {
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let nan = f64::NAN;
        let inputs = [
            (v(nan, 0.0, 0.0), t[0], t[1], t[2]),
            (v(0.2, 0.2, 0.0), v(nan, 0.0, 0.0), t[1], t[2]),
            (v(0.2, 0.2, 0.0), t[0], t[1], v(0.0, f64::INFINITY, 0.0)),
            (v(f64::INFINITY, 0.0, 0.0), t[0], t[1], t[2]),
        ];
        for (p, a, b, c) in inputs {
            let r = point_triangle_distance(&p, &a, &b, &c);
            // documented: beta stays a valid triple; distance may be NaN or infinite
            assert!(r.beta.iter().all(|&x| x.is_finite() && x >= 0.0), "{r:?}");
            assert!((r.beta.iter().sum::<f64>() - 1.0).abs() <= 1e-15, "{r:?}");
        }
    }

    #[test]
    fn geometry_point_triangle_deterministic() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for _ in 0..100 {
            let mut r3 = || v(rng.gen(), rng.gen(), rng.gen());
            let (p, a, b, c) = (r3(), r3(), r3(), r3());
            let r = point_triangle_distance(&p, &a, &b, &c);
            assert_eq!(r, point_triangle_distance(&p, &a, &b, &c));
        }
    }
}
