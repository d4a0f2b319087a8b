//! The contact filter: excluded pairs are never produced (2D and 3D pair producers against a
//! brute-force enumeration that applies the declared body mask itself), and a filter that
//! allows everything gives exactly the results of no filter.

use contactlab::contact::{all_movable_pairs, min_distance, near_pairs, ContactPair};
use contactlab::scene::mesh::{Body, BodyKind, ContactFilter, Mesh};
use contactlab::scene::{balloons, sheets, solids};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The mask rule written out independently of `ContactFilter`: a vertex–element pair is
/// allowed when some body holding the vertex may touch the element's body.
fn allowed(mesh: &Mesh, mask: &dyn Fn(usize, usize) -> bool, p: ContactPair) -> bool {
    let holds = |v: usize| -> Vec<usize> {
        (0..mesh.bodies.len())
            .filter(|&b| mesh.bodies[b].vertices.contains(&v))
            .collect()
    };
    let m = |a: usize, b: usize| mask(a.min(b), a.max(b));
    match p {
        ContactPair::PointEdge { x, a } => holds(x).iter().any(|&b| m(b, mesh.edge_body[a])),
        ContactPair::PointTriangle { x, t } => holds(x).iter().any(|&b| m(b, mesh.face_body[t])),
        ContactPair::EdgeEdge { a, b } => m(mesh.edge_body[a], mesh.edge_body[b]),
    }
}

/// Random closed polygons (one body each) in the unit square.
fn random_curves(rng: &mut ChaCha8Rng, bodies: usize, per: usize) -> Mesh {
    let mut mesh = Mesh {
        dim: 2,
        ..Default::default()
    };
    for b in 0..bodies {
        let (cx, cy, r) = (rng.gen::<f64>(), rng.gen::<f64>(), rng.gen_range(0.05..0.3));
        let off = mesh.nv();
        for k in 0..per {
            let t = std::f64::consts::TAU * k as f64 / per as f64;
            let rr = r * rng.gen_range(0.7..1.0);
            mesh.x_ref
                .extend_from_slice(&[cx + rr * t.cos(), cy + rr * t.sin()]);
            mesh.fixed.push(rng.gen_bool(0.1));
        }
        let e0 = mesh.edges.len();
        for k in 0..per {
            mesh.edges.push([off + k, off + (k + 1) % per]);
            mesh.edge_body.push(b);
        }
        mesh.bodies.push(Body {
            name: format!("c{b}"),
            kind: BodyKind::Curve,
            vertices: (off..off + per).collect(),
            edges: (e0..e0 + per).collect(),
            ..Default::default()
        });
    }
    mesh
}

#[test]
fn contact_filter_2d_pairs_match_the_declared_mask() {
    let mut rng = ChaCha8Rng::seed_from_u64(71);
    for trial in 0..20 {
        let mut mesh = random_curves(&mut rng, 5, 12);
        let x = mesh.x_ref.clone();
        let unfiltered_near = near_pairs(&mesh, &x, 0.2, trial % 2 == 0);
        let unfiltered_all = all_movable_pairs(&mesh);
        let bits: Vec<bool> = (0..25).map(|_| rng.gen_bool(0.5)).collect();
        let mask = |a: usize, b: usize| bits[a * 5 + b];
        mesh.contact_filter = Some(ContactFilter::new(&mesh, mask));
        assert_eq!(mesh.validate(), Ok(()));
        let keep = |v: &[ContactPair]| -> Vec<ContactPair> {
            v.iter()
                .copied()
                .filter(|&p| allowed(&mesh, &mask, p))
                .collect()
        };
        assert_eq!(
            near_pairs(&mesh, &x, 0.2, trial % 2 == 0),
            keep(&unfiltered_near)
        );
        assert_eq!(all_movable_pairs(&mesh), keep(&unfiltered_all));
        // the exact check over the allowed pairs: brute force over all allowed point–edge
        // pairs (the fixed ones included) and crossings
        let md = min_distance(&mesh, &x, 1e-3, false);
        let mut best = f64::INFINITY;
        for v in 0..mesh.nv() {
            for (a, e) in mesh.edges.iter().enumerate() {
                let p = ContactPair::PointEdge { x: v, a };
                if e.contains(&v) || !allowed(&mesh, &mask, p) {
                    continue;
                }
                let q = contactlab::contact::distance::point_edge_distance(
                    &Mesh::p2(&x, v),
                    &Mesh::p2(&x, e[0]),
                    &Mesh::p2(&x, e[1]),
                );
                best = best.min(q.distance);
            }
        }
        for (a, ea) in mesh.edges.iter().enumerate() {
            for (b, eb) in mesh.edges.iter().enumerate().skip(a + 1) {
                let p = ContactPair::EdgeEdge { a, b };
                if ea.iter().any(|v| eb.contains(v)) || !allowed(&mesh, &mask, p) {
                    continue;
                }
                let d = contactlab::contact::distance::edge_edge_distance_2d(
                    &Mesh::p2(&x, ea[0]),
                    &Mesh::p2(&x, ea[1]),
                    &Mesh::p2(&x, eb[0]),
                    &Mesh::p2(&x, eb[1]),
                );
                if d == 0.0 {
                    best = 0.0;
                }
            }
        }
        assert_eq!(md.distance, best, "trial {trial}");
    }
}

#[test]
fn contact_filter_3d_pairs_match_the_declared_mask() {
    for (mut mesh, x) in [
        {
            let s = sheets::build(&Default::default()).unwrap();
            (s.mesh, s.x0)
        },
        {
            let s = solids::build(&Default::default()).unwrap();
            (s.mesh, s.x0)
        },
    ] {
        let r = 0.3;
        let unfiltered = near_pairs(&mesh, &x, r, false);
        let unfiltered_all = all_movable_pairs(&mesh);
        // no self-contact: only lower–upper pairs
        let mask = |a: usize, b: usize| a != b;
        mesh.contact_filter = Some(ContactFilter::new(&mesh, mask));
        let keep = |v: &[ContactPair]| -> Vec<ContactPair> {
            v.iter()
                .copied()
                .filter(|&p| allowed(&mesh, &mask, p))
                .collect()
        };
        let got = near_pairs(&mesh, &x, r, false);
        assert_eq!(got, keep(&unfiltered));
        assert!(got.len() < unfiltered.len() && !got.is_empty());
        assert_eq!(all_movable_pairs(&mesh), keep(&unfiltered_all));
        // the exact check: the brute-force form over the same filter
        let md = min_distance(&mesh, &x, 1e-3, false);
        let brute = contactlab::contact::min_distance_brute_force(&mesh, &x);
        assert_eq!(md.distance, brute.distance);
    }
}

#[test]
fn contact_filter_allowing_everything_changes_nothing() {
    let scenes = [
        balloons::build(&Default::default()).unwrap(),
        sheets::build(&Default::default()).unwrap(),
        solids::build(&Default::default()).unwrap(),
    ];
    for s in scenes {
        let mut m = s.mesh.clone();
        m.contact_filter = Some(ContactFilter::new(&m, |_, _| true));
        assert!(m.contact_filter.as_ref().unwrap().is_everything());
        for r in [s.eps * 1.5, 5.0 * s.h] {
            assert_eq!(
                near_pairs(&m, &s.x0, r, true),
                near_pairs(&s.mesh, &s.x0, r, true)
            );
        }
        let (a, b) = (
            min_distance(&m, &s.x0, s.eps, false),
            min_distance(&s.mesh, &s.x0, s.eps, false),
        );
        assert_eq!(a.distance.to_bits(), b.distance.to_bits());
        assert_eq!(a.pair, b.pair);
    }
}
