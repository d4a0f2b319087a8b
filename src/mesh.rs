//! Meshes of P1 bodies: curves (edges) and 2D solids (triangles), with shared vertices and
//! fixed (Dirichlet) vertices.
//!
//! Positions are stored flat: vertex `v` has coordinates `x[dim*v .. dim*v + dim]`, and the
//! degree of freedom `dim*v + k` is its `k`-th coordinate. Every layer (energies, rows, QP)
//! uses this numbering.

use thiserror::Error;

/// What kind of body a set of elements forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodyKind {
    /// A curve: P1 edges; every edge and vertex takes part in contact.
    Curve,
    /// A 2D solid: P1 triangles; its boundary edges and their vertices take part in contact.
    Solid,
}

/// One body of the scene.
#[derive(Clone, Debug)]
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
    /// Indices into [`Mesh::triangles`] of this body's triangles (solids only).
    pub triangles: Vec<usize>,
}

/// Invalid mesh input. Every variant names the offending element.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// An element refers to a vertex that does not exist.
    #[error("{element} {index} refers to vertex {vertex}, but the mesh has {nv} vertices")]
    DanglingIndex {
        /// `edge` or `triangle`.
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
        /// `edge` or `triangle`.
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
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Space dimension (2 here).
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
    /// All triangles (solid elements), counter-clockwise in the reference configuration.
    pub triangles: Vec<[usize; 3]>,
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

    /// Contact vertices: every endpoint of a contact edge, sorted, without repetition.
    pub fn contact_vertices(&self) -> Vec<usize> {
        let mut seen = vec![false; self.nv()];
        for e in &self.edges {
            seen[e[0]] = true;
            seen[e[1]] = true;
        }
        (0..self.nv()).filter(|&v| seen[v]).collect()
    }

    /// Checks indices, finiteness and non-degenerate reference elements.
    pub fn validate(&self) -> Result<(), MeshError> {
        let nv = self.nv();
        for (v, c) in self.x_ref.chunks(self.dim).enumerate() {
            for &value in c {
                if !value.is_finite() {
                    return Err(MeshError::NotFinite { vertex: v, value });
                }
            }
        }
        for (i, e) in self.edges.iter().enumerate() {
            for &vertex in e {
                if vertex >= nv {
                    return Err(MeshError::DanglingIndex {
                        element: "edge",
                        index: i,
                        vertex,
                        nv,
                    });
                }
            }
            let len = (Self::p2(&self.x_ref, e[0]) - Self::p2(&self.x_ref, e[1])).norm();
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
            for &vertex in t {
                if vertex >= nv {
                    return Err(MeshError::DanglingIndex {
                        element: "triangle",
                        index: i,
                        vertex,
                        nv,
                    });
                }
            }
            let (a, b, c) = (
                Self::p2(&self.x_ref, t[0]),
                Self::p2(&self.x_ref, t[1]),
                Self::p2(&self.x_ref, t[2]),
            );
            let area = 0.5 * (b - a).perp(&(c - a));
            if area <= 0.0 {
                return Err(MeshError::Degenerate {
                    element: "triangle",
                    index: i,
                    measure: "signed area",
                    value: area,
                });
            }
        }
        Ok(())
    }
}
