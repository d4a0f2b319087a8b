//! TEMPORARY (energy/ restructuring): the energies as they were before it, compiled in test
//! builds only, and tests that the new generic types compute bit for bit the same values,
//! gradients and Hessian triplets (in the same order) on seeded random inputs. Removed, with
//! the old code, when the restructuring is done.

#![allow(missing_docs, dead_code)]

pub mod gravity;
pub mod gravity3d;

use super::fd_test::term_bits;
use super::Energy;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Asserts `term_bits` equal, and the names and kinds.
fn assert_same(old: &dyn Energy, new: &dyn Energy, x: &[f64]) {
    assert_eq!(old.name(), new.name());
    assert_eq!(old.kind(), new.kind());
    let (a, b) = (term_bits(old, x), term_bits(new, x));
    assert_eq!(a.len(), b.len());
    assert!(
        a == b,
        "bits differ ({} of {} words)",
        a.iter().zip(&b).filter(|(p, q)| p != q).count(),
        a.len()
    );
}

/// `n` random points in `[lo, hi)^dim`, flat.
fn random_x(rng: &mut ChaCha8Rng, n: usize, dim: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n * dim).map(|_| rng.gen_range(lo..hi)).collect()
}

#[test]
fn legacy_gravity_bit_identical() {
    let mut rng = ChaCha8Rng::seed_from_u64(1001);
    for round in 0..40 {
        let nv = [7, 50, 3 * super::CHUNK + 11][round % 3];
        // 2D: lumped edges and triangles, and given masses
        let xr = random_x(&mut rng, nv, 2, -1.0, 1.0);
        let x = random_x(&mut rng, nv + 1, 2, -3.0, 3.0);
        let tris: Vec<[usize; 3]> = (0..nv)
            .map(|_| {
                [
                    rng.gen_range(0..nv),
                    rng.gen_range(0..nv),
                    rng.gen_range(0..nv),
                ]
            })
            .collect();
        let edges: Vec<[usize; 2]> = tris.iter().map(|t| [t[0], t[1]]).collect();
        let g2 = [rng.gen_range(-2.0..2.0), rng.gen_range(-10.0..10.0)];
        let rho = rng.gen_range(0.1..3.0);
        let old = gravity::Gravity::lumped_triangles(nv, &tris, &xr, rho, g2);
        let new = super::Gravity::lumped_triangles(nv, &tris, &xr, rho, g2);
        assert_eq!(old.mass, new.mass);
        assert_same(&old, &new, &x);
        let old = gravity::Gravity::lumped_edges(nv, &edges, &xr, rho, g2);
        let new = super::Gravity::lumped_edges(nv, &edges, &xr, rho, g2);
        assert_eq!(old.mass, new.mass);
        assert_same(&old, &new, &x);
        let mass: Vec<f64> = (0..nv).map(|_| rng.gen_range(0.0..2.0)).collect();
        assert_same(
            &gravity::Gravity::new(mass.clone(), g2),
            &super::Gravity::new(mass, g2),
            &x,
        );
        // 3D: masses added from edges, triangles and tets
        let xr = random_x(&mut rng, nv, 3, -1.0, 1.0);
        let x = random_x(&mut rng, nv + 1, 3, -3.0, 3.0);
        let tets: Vec<[usize; 4]> = (0..nv)
            .map(|_| std::array::from_fn(|_| rng.gen_range(0..nv)))
            .collect();
        let tris: Vec<[usize; 3]> = tets.iter().map(|t| [t[0], t[1], t[2]]).collect();
        let edges: Vec<[usize; 2]> = tets.iter().map(|t| [t[0], t[3]]).collect();
        let g3 = [
            rng.gen_range(-2.0..2.0),
            rng.gen_range(-2.0..2.0),
            rng.gen_range(-10.0..10.0),
        ];
        let mut old = gravity3d::Gravity3d::new(vec![0.0; nv], g3);
        let mut new = super::Gravity::new(vec![0.0; nv], g3);
        for (k, r) in [0.5, 1.5, 2.5].into_iter().enumerate() {
            match (round + k) % 3 {
                0 => {
                    old.add_edges(&edges, &xr, r);
                    new.add_edges(&edges, &xr, r);
                }
                1 => {
                    old.add_triangles(&tris, &xr, r);
                    new.add_triangles(&tris, &xr, r);
                }
                _ => {
                    old.add_tets(&tets, &xr, r);
                    new.add_tets(&tets, &xr, r);
                }
            }
        }
        assert_eq!(old.mass, new.mass);
        assert_same(&old, &new, &x);
    }
}
