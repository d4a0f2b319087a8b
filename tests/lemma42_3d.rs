//! Lemma 4.2 in 3D: every φ in T(ψ) built from the rows of eq. (6) is admissible (exact check
//! over all disjoint point–triangle and edge–edge pairs, and no edge through a triangle); and
//! Remark 4.3: with point–triangle rows alone, two edges pass through each other.

use contactlab::contact::{all_rows_3d, min_distance_brute_force, ClosestPair, Row3};
use contactlab::scene::mesh::Mesh;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Two sheets of two triangles each: vertices 0..4 and 4..8, their triangles and edges.
fn two_sheets() -> (Vec<usize>, Vec<[usize; 2]>, Vec<[usize; 3]>) {
    let mut tris = Vec::new();
    let mut edges = Vec::new();
    for o in [0, 4] {
        tris.push([o, o + 1, o + 2]);
        tris.push([o + 1, o + 3, o + 2]);
        for e in [[0, 1], [1, 2], [2, 0], [1, 3], [3, 2]] {
            edges.push([o + e[0], o + e[1]]);
        }
    }
    ((0..8).collect(), edges, tris)
}

/// A 3D mesh of these contact edges and triangles at `x` (no contact filter).
fn mesh(x: &[f64], edges: &[[usize; 2]], tris: &[[usize; 3]]) -> Mesh {
    Mesh {
        dim: 3,
        x_ref: x.to_vec(),
        fixed: vec![false; x.len() / 3],
        edges: edges.to_vec(),
        edge_body: vec![0; edges.len()],
        triangles: tris.to_vec(),
        faces: tris.to_vec(),
        face_body: vec![0; tris.len()],
        ..Default::default()
    }
}

/// The exact check over all pairs (O(N²), [`min_distance_brute_force`]) of the elements at `x`;
/// `verts` are the vertices of the elements.
fn min_distance_3d(
    x: &[f64],
    verts: &[usize],
    edges: &[[usize; 2]],
    tris: &[[usize; 3]],
) -> (f64, ClosestPair) {
    let m = mesh(x, edges, tris);
    assert_eq!(m.contact_vertices(), verts);
    let md = min_distance_brute_force(&m, x);
    (md.distance, md.pair)
}

/// Largest t in [0, 1] with every row ≥ ε at ψ + t d (rows are affine in t).
fn t_max(rows: &[Row3], psi: &[f64], d: &[f64], eps: f64) -> f64 {
    let mut t: f64 = 1.0;
    for r in rows {
        let v0 = r.value(psi);
        let slope = r.value(d);
        if slope < 0.0 {
            t = t.min((eps - v0) / slope);
        }
    }
    t.max(0.0)
}

#[test]
fn lemma42_3d_every_point_of_t_psi_is_admissible() {
    let (verts, edges, tris) = two_sheets();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let (mut trials, mut clipped, mut vt_only_violations) = (0, 0, 0);
    while trials < 400 {
        let mut psi = vec![0.0; 24];
        for v in 0..8 {
            let off = if v >= 4 { [0.3, 0.2, 0.6] } else { [0.0; 3] };
            for c in 0..3 {
                psi[3 * v + c] = off[c] + rng.gen_range(-0.5..0.5);
            }
        }
        let (d0, _) = min_distance_3d(&psi, &verts, &edges, &tris);
        if d0.is_nan() || d0 <= 1e-3 {
            continue; // not admissible for any reasonable ε
        }
        trials += 1;
        let eps = d0 * rng.gen_range(0.1..0.9);
        let rows = all_rows_3d(&psi, &verts, &edges, &tris, true).unwrap();
        for r in &rows {
            assert!(r.value(&psi) >= eps, "ψ itself must lie in T(ψ)");
        }
        let d: Vec<f64> = (0..24).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let t = t_max(&rows, &psi, &d, eps);
        if t < 1.0 {
            clipped += 1;
        }
        for s in [0.25, 0.5, 1.0] {
            let phi: Vec<f64> = psi.iter().zip(&d).map(|(p, q)| p + s * t * q).collect();
            let (dist, pair) = min_distance_3d(&phi, &verts, &edges, &tris);
            assert!(
                dist >= eps * (1.0 - 1e-9),
                "trial {trials}: φ in T(ψ) at distance {dist:e} < ε = {eps:e} ({pair:?})"
            );
        }
        // the same step with the point–triangle rows only
        let vt = all_rows_3d(&psi, &verts, &edges, &tris, false).unwrap();
        let t_vt = t_max(&vt, &psi, &d, eps);
        let phi: Vec<f64> = psi.iter().zip(&d).map(|(p, q)| p + t_vt * q).collect();
        if min_distance_3d(&phi, &verts, &edges, &tris).0 < eps * (1.0 - 1e-9) {
            vt_only_violations += 1;
        }
    }
    eprintln!(
        "lemma42_3d: {trials} trials, {clipped} steps limited by the rows, \
         {vt_only_violations} inadmissible steps with point–triangle rows only"
    );
    // the test is not vacuous: the rows cut most steps short
    assert!(
        clipped > 300,
        "only {clipped} of 400 steps were limited by the rows"
    );
    // and the edge–edge rows are needed: without them some steps leave A_{h,ε}
    assert!(
        vt_only_violations > 0,
        "point–triangle rows alone never failed in 400 trials"
    );
}

#[test]
fn remark43_edges_pass_through_without_edge_edge_rows() {
    // Sheet A: triangle in the plane y = 0 with its bottom edge along x at z = 1.
    // Sheet B: triangle in the plane x = 0 with its top edge along y at z = 0.
    // (Edges of length 4, so that every vertex stays away from the other triangle.)
    let psi = vec![
        -2.0, 0.0, 1.0, // 0
        2.0, 0.0, 1.0, // 1
        0.0, 0.0, 3.0, // 2
        0.0, -2.0, 0.0, // 3
        0.0, 2.0, 0.0, // 4
        0.0, 0.0, -2.0, // 5
    ];
    let verts: Vec<usize> = (0..6).collect();
    let tris = vec![[0, 1, 2], [3, 4, 5]];
    let edges = vec![[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3]];
    let eps = 0.1;
    let (d0, _) = min_distance_3d(&psi, &verts, &edges, &tris);
    assert!((d0 - 1.0).abs() < 1e-12, "start at distance {d0}");
    // move sheet A down by 2: its bottom edge ends at z = −1, through sheet B
    let mut phi = psi.clone();
    for v in 0..3 {
        phi[3 * v + 2] -= 2.0;
    }
    let (d1, pair) = min_distance_3d(&phi, &verts, &edges, &tris);
    assert_eq!(d1, 0.0);
    assert!(
        matches!(pair, ClosestPair::EdgeThroughFace { .. }),
        "{pair:?}"
    );
    // every point–triangle row still holds at φ: those rows alone allow the step
    let vt = all_rows_3d(&psi, &verts, &edges, &tris, false).unwrap();
    assert!(!vt.is_empty());
    for r in &vt {
        assert!(
            r.value(&phi) >= eps,
            "a point–triangle row is violated: {r:?}"
        );
    }
    // the edge–edge rows forbid it
    let all = all_rows_3d(&psi, &verts, &edges, &tris, true).unwrap();
    let worst = all
        .iter()
        .map(|r| r.value(&phi))
        .fold(f64::INFINITY, f64::min);
    assert!(
        worst < eps,
        "no row forbids the pass-through (min row value {worst})"
    );
}

/// Random soups of small triangles: the BVH pair search finds exactly the pairs of the O(N²)
/// search, and the BVH form of the exact check gives the same minimum.
#[test]
fn broad_phase_3d_matches_all_pairs() {
    use contactlab::contact::distance::{edge_edge_distance, point_triangle_distance};
    use contactlab::contact::p3;
    use contactlab::contact::{min_distance, near_pairs_3d};
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for trial in 0..40 {
        let nt = 30;
        let mut x = Vec::new();
        let mut tris = Vec::new();
        let mut edges = Vec::new();
        for t in 0..nt {
            let c = [
                rng.gen_range(0.0..3.0),
                rng.gen_range(0.0..3.0),
                rng.gen_range(0.0..3.0),
            ];
            for _ in 0..3 {
                for ck in c {
                    x.push(ck + rng.gen_range(-0.3..0.3));
                }
            }
            let o = 3 * t;
            tris.push([o, o + 1, o + 2]);
            edges.extend_from_slice(&[[o, o + 1], [o + 1, o + 2], [o + 2, o]]);
        }
        let verts: Vec<usize> = (0..3 * nt).collect();
        let r = 0.25;
        let near = near_pairs_3d(&x, &verts, &edges, &tris, r, None);
        let mut vt = Vec::new();
        for (ti, t) in tris.iter().enumerate() {
            for &v in &verts {
                if !t.contains(&v) {
                    let d = point_triangle_distance(
                        &p3(&x, v),
                        &p3(&x, t[0]),
                        &p3(&x, t[1]),
                        &p3(&x, t[2]),
                    )
                    .distance;
                    if d < r {
                        vt.push((v, ti, d));
                    }
                }
            }
        }
        vt.sort_by_key(|p| (p.0, p.1));
        let mut ee = Vec::new();
        for (ai, a) in edges.iter().enumerate() {
            for (bi, b) in edges.iter().enumerate().skip(ai + 1) {
                if a.iter().any(|v| b.contains(v)) {
                    continue;
                }
                let d =
                    edge_edge_distance(&p3(&x, a[0]), &p3(&x, a[1]), &p3(&x, b[0]), &p3(&x, b[1]))
                        .distance;
                if d < r {
                    ee.push((ai, bi, d));
                }
            }
        }
        assert_eq!(near.point_triangle, vt, "trial {trial}");
        assert_eq!(near.edge_edge, ee, "trial {trial}");
        assert!(
            !vt.is_empty() && !ee.is_empty(),
            "trial {trial}: nothing near, test vacuous"
        );
        let brute = min_distance_3d(&x, &verts, &edges, &tris);
        let fast = min_distance(&mesh(&x, &edges, &tris), &x, 0.01, false);
        let fast = (fast.distance, fast.pair);
        assert_eq!(brute.0, fast.0, "trial {trial}: {brute:?} vs {fast:?}");
    }
}
