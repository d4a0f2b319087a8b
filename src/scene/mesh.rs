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
    /// `fixed_dof` has the wrong length, or a vertex has every component prescribed in
    /// `fixed_dof` without being `fixed`.
    #[error("fixed_dof has {len} entries for {ndof} degrees of freedom, or vertex {vertex} has every component prescribed but is not fixed")]
    Fixity {
        /// Length of `fixed_dof`.
        len: usize,
        /// `dim·nv`.
        ndof: usize,
        /// The first inconsistent vertex (`usize::MAX` for a length mismatch).
        vertex: usize,
    },
    /// The contact filter was built for another mesh (vertex, element or body counts differ).
    #[error("the contact filter was built for another mesh (rebuild it after the last change)")]
    StaleFilter,
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
    /// `fixed[v]`: vertex `v` is a Dirichlet vertex (never moves): every one of its degrees of
    /// freedom is prescribed. The pair search leaves out the pairs whose vertices are all
    /// fixed.
    pub fixed: Vec<bool>,
    /// Per degree of freedom (`dim·v + k`): component `k` of vertex `v` is prescribed (a
    /// roller, a symmetry plane, a prescribed displacement of chosen components). Empty when
    /// no vertex is supported in only some components; otherwise `dim·nv` entries, and a
    /// vertex with every component prescribed is also `fixed` ([`Mesh::fix_component`] keeps
    /// that so, [`Mesh::validate`] checks it). Read it through [`Mesh::dof_fixed`].
    pub fixed_dof: Vec<bool>,
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
    /// Which bodies may touch which (docs/scene-files.md, `[contact]`). `None`: every
    /// body may touch every body and itself (the paper's setting, and the default). Pairs the
    /// filter excludes are never searched, never given rows and never checked.
    pub contact_filter: Option<ContactFilter>,
}

/// The declared set of body pairs that may touch: a symmetric `nb × nb` mask (the diagonal:
/// self-contact), plus the body of every contact element, so that a pair of elements can be
/// tested without the mesh.
///
/// A vertex may belong to several bodies (a membrane glued to its support); a pair of a vertex
/// `x` and an element of body `B` is kept when SOME body holding `x` may touch `B`
/// (conservative: a glued vertex keeps the pairs of each of its bodies).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactFilter {
    nb: usize,
    allowed: Vec<bool>,
    /// CSR: bodies of vertex `v` are `vb_list[vb_start[v]..vb_start[v + 1]]`.
    vb_start: Vec<u32>,
    vb_list: Vec<u32>,
    edge_body: Vec<u32>,
    face_body: Vec<u32>,
}

impl ContactFilter {
    /// The filter of `mesh` (its bodies, `edge_body`, `face_body` must be final) from
    /// `allowed(b1, b2)`, asked for `b1 ≤ b2` only (the mask is symmetric).
    pub fn new(mesh: &Mesh, allowed: impl Fn(usize, usize) -> bool) -> ContactFilter {
        let nb = mesh.bodies.len();
        let mut mask = vec![false; nb * nb];
        for i in 0..nb {
            for j in i..nb {
                let a = allowed(i, j);
                mask[i * nb + j] = a;
                mask[j * nb + i] = a;
            }
        }
        let nv = mesh.nv();
        let mut count = vec![0u32; nv + 1];
        for b in &mesh.bodies {
            for &v in &b.vertices {
                if v < nv {
                    count[v + 1] += 1;
                }
            }
        }
        for v in 0..nv {
            count[v + 1] += count[v];
        }
        let mut fill = count.clone();
        let mut list = vec![0u32; count[nv] as usize];
        for (bi, b) in mesh.bodies.iter().enumerate() {
            for &v in &b.vertices {
                if v < nv {
                    list[fill[v] as usize] = bi as u32;
                    fill[v] += 1;
                }
            }
        }
        ContactFilter {
            nb,
            allowed: mask,
            vb_start: count,
            vb_list: list,
            edge_body: mesh.edge_body.iter().map(|&b| b as u32).collect(),
            face_body: mesh.face_body.iter().map(|&b| b as u32).collect(),
        }
    }

    /// Whether bodies `b1` and `b2` may touch (`b1 == b2`: self-contact).
    #[inline]
    pub fn bodies(&self, b1: usize, b2: usize) -> bool {
        self.allowed[b1 * self.nb + b2]
    }

    /// Whether every body may touch every body and itself (the filter excludes nothing).
    pub fn is_everything(&self) -> bool {
        self.allowed.iter().all(|&a| a)
    }

    #[inline]
    fn vertex_body(&self, x: usize, b: u32) -> bool {
        let (s, e) = (self.vb_start[x] as usize, self.vb_start[x + 1] as usize);
        self.vb_list[s..e]
            .iter()
            .any(|&bx| self.allowed[bx as usize * self.nb + b as usize])
    }

    /// Vertex `x` with contact edge `a`.
    #[inline]
    pub fn point_edge(&self, x: usize, a: usize) -> bool {
        self.vertex_body(x, self.edge_body[a])
    }

    /// Vertex `x` with contact face `t` (3D).
    #[inline]
    pub fn point_triangle(&self, x: usize, t: usize) -> bool {
        self.vertex_body(x, self.face_body[t])
    }

    /// Contact edges `a` and `b`.
    #[inline]
    pub fn edge_edge(&self, a: usize, b: usize) -> bool {
        self.bodies(self.edge_body[a] as usize, self.edge_body[b] as usize)
    }

    /// Contact edge `a` with contact face `t` (an edge through a face, 3D).
    #[inline]
    pub fn edge_face(&self, a: usize, t: usize) -> bool {
        self.bodies(self.edge_body[a] as usize, self.face_body[t] as usize)
    }
}

impl Mesh {
    /// Number of vertices.
    pub fn nv(&self) -> usize {
        self.x_ref.len() / self.dim
    }

    /// Whether degree of freedom `dof` (`dim·v + k`) is prescribed: its vertex is fixed, or
    /// that component is supported.
    #[inline]
    pub fn dof_fixed(&self, dof: usize) -> bool {
        self.fixed[dof / self.dim] || self.fixed_dof.get(dof).copied().unwrap_or(false)
    }

    /// Prescribes component `k` of vertex `v` (a support); the vertex becomes fixed when every
    /// one of its components is.
    pub fn fix_component(&mut self, v: usize, k: usize) {
        if self.fixed_dof.is_empty() {
            self.fixed_dof = vec![false; self.x_ref.len()];
        }
        let d = self.dim;
        self.fixed_dof[d * v + k] = true;
        if (0..d).all(|c| self.fixed_dof[d * v + c]) {
            self.fixed[v] = true;
        }
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

    /// The contact filter, or `None` when every pair may touch. Pair producers call this once
    /// and skip the per-pair test when it is `None`, so the default leaves results unchanged.
    #[inline]
    pub fn filter(&self) -> Option<&ContactFilter> {
        self.contact_filter.as_ref()
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

    /// The tributary measure of each vertex on the contact elements at `x`: in 2D half the
    /// length of its contact edges; in 3D a third of the area of its contact faces, or, for a
    /// vertex on no contact face (a curve's), half the length of its contact edges. 0 for a
    /// vertex on no contact element. The local size by which a contact force becomes a
    /// pressure (a force per length in 2D, per area in 3D).
    pub fn tributary(&self, x: &[f64]) -> Vec<f64> {
        let nv = self.nv();
        let mut area = vec![0.0; nv];
        for f in &self.faces {
            let (a, b, c) = (
                self.point(x, f[0]),
                self.point(x, f[1]),
                self.point(x, f[2]),
            );
            let third = (b - a).cross(&(c - a)).norm() / 6.0;
            for &v in f {
                area[v] += third;
            }
        }
        let mut length = vec![0.0; nv];
        for e in &self.edges {
            let half = 0.5 * (self.point(x, e[0]) - self.point(x, e[1])).norm();
            length[e[0]] += half;
            length[e[1]] += half;
        }
        area.iter()
            .zip(&length)
            .map(|(&a, &l)| if a > 0.0 { a } else { l })
            .collect()
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
        if !self.fixed_dof.is_empty() {
            let d = self.dim;
            let bad = |vertex| MeshError::Fixity {
                len: self.fixed_dof.len(),
                ndof: d * nv,
                vertex,
            };
            if self.fixed_dof.len() != d * nv {
                return Err(bad(usize::MAX));
            }
            if let Some(v) =
                (0..nv).find(|&v| !self.fixed[v] && (0..d).all(|k| self.fixed_dof[d * v + k]))
            {
                return Err(bad(v));
            }
        }
        if let Some(f) = self.filter() {
            if f.vb_start.len() != nv + 1
                || f.edge_body.len() != self.edges.len()
                || f.face_body.len() != self.faces.len()
                || f.nb != self.bodies.len()
            {
                return Err(MeshError::StaleFilter);
            }
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of the unit square, one solid body.
    fn square() -> Mesh {
        Mesh {
            dim: 2,
            x_ref: vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0],
            fixed: vec![false; 4],
            edges: vec![[0, 1], [1, 2], [2, 3], [3, 0]],
            edge_body: vec![0; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            bodies: vec![Body {
                name: "square".into(),
                kind: BodyKind::Solid,
                vertices: vec![0, 1, 2, 3],
                edges: vec![0, 1, 2, 3],
                triangles: vec![0, 1],
                ..Default::default()
            }],
            ..Default::default()
        }
    }

    #[test]
    fn mesh_fixity_per_dof_and_fixed_vertices() {
        let mut m = square();
        assert!(m.fixed_dof.is_empty() && (0..8).all(|d| !m.dof_fixed(d)));
        // a roller: vertex 1 held in y only
        m.fix_component(1, 1);
        assert_eq!(m.fixed_dof.len(), 8);
        assert!(m.dof_fixed(3) && !m.dof_fixed(2) && !m.fixed[1]);
        // both components: the vertex is fixed (the pair search's all-fixed pairs)
        m.fix_component(1, 0);
        assert!(m.fixed[1] && m.dof_fixed(2));
        m.validate().unwrap();
        // a fixed vertex has every dof fixed without fixed_dof
        m.fixed[3] = true;
        assert!(m.dof_fixed(6) && m.dof_fixed(7));
        // inconsistent: every component prescribed but the vertex not fixed
        let mut bad = square();
        bad.fixed_dof = vec![false, false, true, true, false, false, false, false];
        assert_eq!(
            bad.validate(),
            Err(MeshError::Fixity {
                len: 8,
                ndof: 8,
                vertex: 1
            })
        );
        bad.fixed_dof.pop();
        assert!(matches!(
            bad.validate(),
            Err(MeshError::Fixity { len: 7, .. })
        ));
    }

    #[test]
    fn mesh_tributary_lengths_and_areas() {
        let m = square();
        // every vertex of the unit square: half of two unit edges
        assert_eq!(m.tributary(&m.x_ref), vec![1.0; 4]);
        let x: Vec<f64> = m.x_ref.iter().map(|v| 2.0 * v).collect();
        assert_eq!(m.tributary(&x), vec![2.0; 4]);
        // 3D: a unit right triangle face (area 1/2): a third to each vertex
        let m3 = Mesh {
            dim: 3,
            x_ref: vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            fixed: vec![false; 3],
            faces: vec![[0, 1, 2]],
            edges: vec![[0, 1], [1, 2], [2, 0]],
            ..Default::default()
        };
        let t = m3.tributary(&m3.x_ref);
        assert!(t.iter().all(|a| (a - 1.0 / 6.0).abs() < 1e-15), "{t:?}");
    }
}
