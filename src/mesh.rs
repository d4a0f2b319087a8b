//! Meshes of P1 bodies, with shared vertices and fixed (Dirichlet) vertices. In 2D: curves
//! (edges) and solids (triangles, contact on their boundary edges). In 3D: curves (edges),
//! surfaces (triangles, every triangle a contact face) and solids (tetrahedra, contact on their
//! boundary faces and edges).
//!
//! Positions are stored flat: vertex `v` has coordinates `x[dim*v .. dim*v + dim]`, and the
//! degree of freedom `dim*v + k` is its `k`-th coordinate. Every layer (energies, rows, QP)
//! uses this numbering.

use thiserror::Error;

/// What kind of body a set of elements forms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodyKind {
    /// A curve: P1 edges; every edge and vertex takes part in contact.
    #[default]
    Curve,
    /// A solid: P1 triangles in 2D, P1 tetrahedra in 3D; its boundary edges (and, in 3D,
    /// boundary faces) and their vertices take part in contact.
    Solid,
    /// A surface in 3D: P1 triangles; every triangle, edge and vertex takes part in contact.
    Surface,
}

/// One body of the scene.
#[derive(Clone, Debug, Default)]
pub struct Body {
    /// Name used in outputs (`balloon0`, `box`, …).
    pub name: String,
    /// Curve or solid.
    pub kind: BodyKind,
    /// Reference mesh size (largest reference edge length).
    pub h: f64,
    /// Vertices of the body (a shared vertex is listed by each body that holds it).
    pub vertices: Vec<usize>,
    /// Indices into [`Mesh::edges`] of this body's contact edges.
    pub edges: Vec<usize>,
    /// Indices into [`Mesh::triangles`] of this body's triangles (2D solids, 3D surfaces).
    pub triangles: Vec<usize>,
    /// Indices into [`Mesh::faces`] of this body's contact faces (3D only).
    pub faces: Vec<usize>,
    /// Indices into [`Mesh::tets`] of this body's tetrahedra (3D solids only).
    pub tets: Vec<usize>,
}

/// Invalid mesh input. Every variant names the offending element.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The space dimension is neither 2 nor 3.
    #[error("mesh dimension {0}: only 2 and 3 are supported")]
    Dimension(usize),
    /// The coordinate array is not `dim` per vertex, or `fixed` has the wrong length.
    #[error("{coords} coordinates are not {dim} per vertex, or fixed has {fixed} entries instead of one per vertex")]
    Lengths {
        /// Length of `x_ref`.
        coords: usize,
        /// Dimension.
        dim: usize,
        /// Length of `fixed`.
        fixed: usize,
    },
    /// An element refers to a vertex that does not exist.
    #[error("{element} {index} refers to vertex {vertex}, but the mesh has {nv} vertices")]
    DanglingIndex {
        /// `edge`, `triangle`, `face` or `tet`.
        element: &'static str,
        /// Element index.
        index: usize,
        /// The bad vertex index.
        vertex: usize,
        /// Number of vertices.
        nv: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {value}")]
    NotFinite {
        /// Vertex index.
        vertex: usize,
        /// The value.
        value: f64,
    },
    /// An edge of zero reference length or a triangle of zero reference area.
    #[error("{element} {index} is degenerate ({measure} = {value})")]
    Degenerate {
        /// `edge`, `triangle`, `face` or `tet`.
        element: &'static str,
        /// Element index.
        index: usize,
        /// `length` or `area`.
        measure: &'static str,
        /// The value.
        value: f64,
    },
}

/// The whole discretized scene geometry.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Space dimension, 2 or 3.
    pub dim: usize,
    /// Reference positions, flat (`dim` per vertex). Also the initial state unless a scene
    /// provides another.
    pub x_ref: Vec<f64>,
    /// `fixed[v]`: vertex `v` is a Dirichlet vertex (never moves).
    pub fixed: Vec<bool>,
    /// All contact edges, as vertex pairs.
    pub edges: Vec<[usize; 2]>,
    /// Body owning each contact edge.
    pub edge_body: Vec<usize>,
    /// All triangles: 2D solid elements (counter-clockwise in the reference configuration) or
    /// 3D surface elements.
    pub triangles: Vec<[usize; 3]>,
    /// 3D contact faces (triangles of surfaces, boundary faces of solids); empty in 2D.
    pub faces: Vec<[usize; 3]>,
    /// Body owning each contact face.
    pub face_body: Vec<usize>,
    /// 3D solid elements (positive volume in the reference configuration); empty in 2D.
    pub tets: Vec<[usize; 4]>,
    /// Bodies.
    pub bodies: Vec<Body>,
}

impl Mesh {
    /// Number of vertices.
    pub fn nv(&self) -> usize {
        self.x_ref.len() / self.dim
    }

    /// Position of vertex `v` in the flat array `x`, as a 2-vector.
    #[inline]
    pub fn p2(x: &[f64], v: usize) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::new(x[2 * v], x[2 * v + 1])
    }

    /// Position of vertex `v` of a mesh of dimension `dim` as a 3-vector (`z = 0` in 2D).
    #[inline]
    pub fn point(&self, x: &[f64], v: usize) -> nalgebra::Vector3<f64> {
        if self.dim == 3 {
            nalgebra::Vector3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2])
        } else {
            nalgebra::Vector3::new(x[2 * v], x[2 * v + 1], 0.0)
        }
    }

    /// Contact vertices: every endpoint of a contact edge or vertex of a contact face, sorted,
    /// without repetition.
    pub fn contact_vertices(&self) -> Vec<usize> {
        let mut seen = vec![false; self.nv()];
        for e in &self.edges {
            seen[e[0]] = true;
            seen[e[1]] = true;
        }
        for f in &self.faces {
            for &v in f {
                seen[v] = true;
            }
        }
        (0..self.nv()).filter(|&v| seen[v]).collect()
    }

    /// Checks the dimension, indices, finiteness and non-degenerate reference elements.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.dim != 2 && self.dim != 3 {
            return Err(MeshError::Dimension(self.dim));
        }
        if !self.x_ref.len().is_multiple_of(self.dim) || self.fixed.len() != self.nv() {
            return Err(MeshError::Lengths {
                coords: self.x_ref.len(),
                dim: self.dim,
                fixed: self.fixed.len(),
            });
        }
        let nv = self.nv();
        for (v, c) in self.x_ref.chunks(self.dim).enumerate() {
            for &value in c {
                if !value.is_finite() {
                    return Err(MeshError::NotFinite { vertex: v, value });
                }
            }
        }
        let check = |element: &'static str, index: usize, vs: &[usize]| {
            for &vertex in vs {
                if vertex >= nv {
                    return Err(MeshError::DanglingIndex {
                        element,
                        index,
                        vertex,
                        nv,
                    });
                }
            }
            Ok(())
        };
        let p = |v: usize| self.point(&self.x_ref, v);
        for (i, e) in self.edges.iter().enumerate() {
            check("edge", i, e)?;
            let len = (p(e[0]) - p(e[1])).norm();
            if len == 0.0 {
                return Err(MeshError::Degenerate {
                    element: "edge",
                    index: i,
                    measure: "length",
                    value: len,
                });
            }
        }
        for (i, t) in self.triangles.iter().enumerate() {
            check("triangle", i, t)?;
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            let cross = (b - a).cross(&(c - a));
            // 2D: the signed area (counter-clockwise required); 3D: the area
            let (measure, area) = if self.dim == 2 {
                ("signed area", 0.5 * cross.z)
            } else {
                ("area", 0.5 * cross.norm())
            };
            if area <= 0.0 {
                return Err(MeshError::Degenerate {
                    element: "triangle",
                    index: i,
                    measure,
                    value: area,
                });
            }
        }
        for (i, f) in self.faces.iter().enumerate() {
            check("face", i, f)?;
            let area = 0.5 * (p(f[1]) - p(f[0])).cross(&(p(f[2]) - p(f[0]))).norm();
            if area <= 0.0 {
                return Err(MeshError::Degenerate {
                    element: "face",
                    index: i,
                    measure: "area",
                    value: area,
                });
            }
        }
        for (i, t) in self.tets.iter().enumerate() {
            check("tet", i, t)?;
            let a = p(t[0]);
            let vol = (p(t[1]) - a).cross(&(p(t[2]) - a)).dot(&(p(t[3]) - a)) / 6.0;
            if vol <= 0.0 {
                return Err(MeshError::Degenerate {
                    element: "tet",
                    index: i,
                    measure: "signed volume",
                    value: vol,
                });
            }
        }
        Ok(())
    }
}
