//! Lumped P1 masses: the vertex masses of the inertia term of a time step (docs/method.md,
//! §6) and of gravity loads on scenes built from densities. Each body's elements of highest
//! dimension carry its density and give an equal share of their reference mass to each of
//! their vertices.

use crate::scene::mesh::{BodyKind, Mesh};
use thiserror::Error;

/// Input that [`lumped_mass`] refuses.
#[derive(Debug, Error)]
pub enum MassError {
    /// A vector of the wrong length.
    #[error("{what} has {got} entries, expected {expected}")]
    Length {
        /// Which vector.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The expected length.
        expected: usize,
    },
    /// A density that is negative or not finite.
    #[error("{what} {index} is {value}: must be finite and >= 0")]
    BadMass {
        /// `density of body`.
        what: &'static str,
        /// Body index.
        index: usize,
        /// The value.
        value: f64,
    },
}

/// Lumped P1 masses per vertex: each body's elements of highest dimension carry its density
/// — tetrahedra per volume (3D solids), else triangles per area (2D solids, 3D surfaces),
/// else edges per length (curves) — and each element gives an equal share of its reference
/// mass to each of its vertices (a quarter, a third, a half). A vertex shared by two bodies
/// gets mass from both. `density[b]` is body `b`'s density.
pub fn lumped_mass(mesh: &Mesh, x_ref: &[f64], density: &[f64]) -> Result<Vec<f64>, MassError> {
    if density.len() != mesh.bodies.len() {
        return Err(MassError::Length {
            what: "density (one per body)",
            got: density.len(),
            expected: mesh.bodies.len(),
        });
    }
    if x_ref.len() != mesh.x_ref.len() {
        return Err(MassError::Length {
            what: "x_ref",
            got: x_ref.len(),
            expected: mesh.x_ref.len(),
        });
    }
    for (index, &value) in density.iter().enumerate() {
        if !(value >= 0.0 && value.is_finite()) {
            return Err(MassError::BadMass {
                what: "density of body",
                index,
                value,
            });
        }
    }
    let mut mass = vec![0.0; mesh.nv()];
    for (b, &rho) in density.iter().enumerate() {
        add_body_mass(&mut mass, mesh, x_ref, b, rho);
    }
    Ok(mass)
}

/// Adds body `b`'s lumped P1 masses of density `rho` to `mass` (one entry per vertex), as
/// [`lumped_mass`] does for each body (which checks its input; this does not): the elements of
/// highest dimension, each giving an equal share of its reference mass to each of its
/// vertices, in the body's element order. The gravity load of a scene is made of these
/// (`scene::physics`).
pub fn add_body_mass(mass: &mut [f64], mesh: &Mesh, x_ref: &[f64], b: usize, rho: f64) {
    let p = |v: usize| mesh.point(x_ref, v);
    let body = &mesh.bodies[b];
    if !body.tets.is_empty() {
        for &t in &body.tets {
            let t = mesh.tets[t];
            let a = p(t[0]);
            let vol = (p(t[1]) - a)
                .cross(&(p(t[2]) - a))
                .dot(&(p(t[3]) - a))
                .abs()
                / 6.0;
            for v in t {
                mass[v] += rho * vol / 4.0;
            }
        }
    } else if !body.triangles.is_empty() {
        for &t in &body.triangles {
            let t = mesh.triangles[t];
            let area = 0.5 * (p(t[1]) - p(t[0])).cross(&(p(t[2]) - p(t[0]))).norm();
            for v in t {
                mass[v] += rho * area / 3.0;
            }
        }
    } else {
        debug_assert!(body.kind == BodyKind::Curve || body.edges.is_empty());
        for &e in &body.edges {
            let [a, b] = mesh.edges[e];
            let l = (p(b) - p(a)).norm();
            mass[a] += 0.5 * rho * l;
            mass[b] += 0.5 * rho * l;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::Body;

    #[test]
    fn lumped_mass_totals_are_density_times_measure() {
        // 2D: a solid (two triangles of the unit square) and a curve (two edges, lengths 1, 2)
        let mesh = Mesh {
            dim: 2,
            x_ref: vec![
                0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 3.0, 0.0, 3.0, 1.0, 3.0, 3.0,
            ],
            fixed: vec![false; 7],
            edges: vec![[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6]],
            edge_body: vec![0, 0, 0, 0, 1, 1],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            bodies: vec![
                Body {
                    name: "square".into(),
                    kind: BodyKind::Solid,
                    vertices: vec![0, 1, 2, 3],
                    edges: vec![0, 1, 2, 3],
                    triangles: vec![0, 1],
                    ..Default::default()
                },
                Body {
                    name: "curve".into(),
                    kind: BodyKind::Curve,
                    vertices: vec![4, 5, 6],
                    edges: vec![4, 5],
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        let m = lumped_mass(&mesh, &mesh.x_ref, &[2.0, 0.5]).unwrap();
        let square: f64 = m[..4].iter().sum();
        let curve: f64 = m[4..].iter().sum();
        assert!((square - 2.0 * 1.0).abs() < 1e-15, "{square}");
        assert!((curve - 0.5 * 3.0).abs() < 1e-15, "{curve}");
        assert_eq!(m[4], 0.25);
        assert_eq!(m[6], 0.5);
        // bad input named
        let e = lumped_mass(&mesh, &mesh.x_ref, &[1.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("density") && e.contains("1 entries"), "{e}");
        let e = lumped_mass(&mesh, &mesh.x_ref, &[1.0, -1.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("body 1 is -1"), "{e}");
        // 3D: a tet of volume 1/6 (density 6), a surface triangle of area 1/2 (density 4) and
        // a curve of one edge of length 1 along z (density 3)
        let x = vec![
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 5.0, 0.0, 0.0, 6.0, 0.0,
            0.0, 5.0, 1.0, 0.0,
        ];
        let mesh3 = Mesh {
            dim: 3,
            x_ref: x.clone(),
            fixed: vec![false; 7],
            tets: vec![[0, 1, 2, 3]],
            triangles: vec![[4, 5, 6]],
            edges: vec![[0, 3]],
            bodies: vec![
                Body {
                    kind: BodyKind::Solid,
                    tets: vec![0],
                    ..Default::default()
                },
                Body {
                    kind: BodyKind::Surface,
                    triangles: vec![0],
                    ..Default::default()
                },
                Body {
                    kind: BodyKind::Curve,
                    edges: vec![0],
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        let m = lumped_mass(&mesh3, &x, &[6.0, 4.0, 3.0]).unwrap();
        assert!((m[..4].iter().sum::<f64>() - 4.0).abs() < 1e-15);
        assert!((m[4..].iter().sum::<f64>() - 2.0).abs() < 1e-15);
        assert!(
            (m[0] - 1.75).abs() < 1e-15 && (m[3] - 1.75).abs() < 1e-15,
            "{m:?}"
        );
    }
}
