//! Lemma 4.2 as a property test: for random admissible ψ and random φ ∈ T(ψ) (eq. 4),
//! φ is admissible. The φ are taken ON the boundary of T(ψ) (the largest step along a random
//! direction that stays in T(ψ)), where the lemma is tightest.

use contactlab::contact::point_edge_rows;
use contactlab::contact::{min_distance_brute_force, point_edge_pairs};
use contactlab::scene::mesh::{Body, BodyKind, Mesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Three random polylines (one closed) in the unit square, all vertices free.
fn random_mesh(rng: &mut ChaCha8Rng) -> Mesh {
    let mut x = Vec::new();
    let mut edges = Vec::new();
    let mut edge_body = Vec::new();
    let mut bodies = Vec::new();
    for b in 0..3 {
        let nv = rng.gen_range(3..7);
        let first = x.len() / 2;
        let (cx, cy) = (rng.gen_range(0.0..1.0), rng.gen_range(0.0..1.0));
        for _ in 0..nv {
            x.push(cx + rng.gen_range(-0.3..0.3));
            x.push(cy + rng.gen_range(-0.3..0.3));
        }
        let mut be = Vec::new();
        let closed = b == 0;
        let ne = if closed { nv } else { nv - 1 };
        for i in 0..ne {
            edges.push([first + i, first + (i + 1) % nv]);
            edge_body.push(b);
            be.push(edges.len() - 1);
        }
        bodies.push(Body {
            name: format!("c{b}"),
            kind: BodyKind::Curve,
            h: 0.1,
            vertices: (first..first + nv).collect(),
            edges: be,
            triangles: vec![],
            ..Default::default()
        });
    }
    let nv = x.len() / 2;
    Mesh {
        dim: 2,
        x_ref: x,
        fixed: vec![false; nv],
        edges,
        edge_body,
        triangles: vec![],
        bodies,
        ..Default::default()
    }
}

#[test]
fn lemma_4_2_boundary_points_of_t_psi_are_admissible() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let eps = 0.01;
    let (mut meshes, mut samples, mut outside_inadmissible) = (0, 0, 0);
    while meshes < 200 {
        let mesh = random_mesh(&mut rng);
        let psi = mesh.x_ref.clone();
        let (pairs, _) = point_edge_pairs(&mesh);
        if min_distance_brute_force(&mesh, &psi).distance < eps {
            continue; // ψ must be admissible: draw again
        }
        meshes += 1;
        let rows = point_edge_rows(&mesh, &psi, &pairs).unwrap();
        for _ in 0..20 {
            let scale = rng.gen_range(0.01..1.0);
            let d: Vec<f64> = (0..psi.len())
                .map(|_| rng.gen_range(-scale..scale))
                .collect();
            // Largest t with ψ + t d ∈ T(ψ): every row is affine in t.
            let mut tmax = f64::INFINITY;
            for r in &rows {
                let v0 = r.values(&psi);
                let v1 = r.values(&d); // linear part
                for i in 0..2 {
                    // values(&d) = n·(d(a_i) − d(x)): the rate of row i along d.
                    let rate = v1[i];
                    if rate < 0.0 {
                        tmax = tmax.min((v0[i] - eps) / -rate);
                    }
                }
            }
            if !tmax.is_finite() {
                continue;
            }
            let phi: Vec<f64> = psi.iter().zip(&d).map(|(p, q)| p + tmax * q).collect();
            let md = min_distance_brute_force(&mesh, &phi);
            assert!(
                md.distance >= eps * (1.0 - 1e-9),
                "Lemma 4.2 violated: {} at {:.3e} < eps",
                md.pair,
                md.distance
            );
            samples += 1;
            // Power of the test: a point past the boundary of T(ψ) is often inadmissible.
            let beyond: Vec<f64> = psi
                .iter()
                .zip(&d)
                .map(|(p, q)| p + 3.0 * tmax * q)
                .collect();
            if min_distance_brute_force(&mesh, &beyond).distance < eps {
                outside_inadmissible += 1;
            }
        }
    }
    assert!(samples > 1000, "too few samples: {samples}");
    assert!(
        outside_inadmissible > samples / 20,
        "the check never fails outside T(ψ): {outside_inadmissible}/{samples}"
    );
}
