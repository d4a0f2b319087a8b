//! One mesh assembler for the built-in scenes and the scene files (docs/scene-files.md,
//! docs/scenes.md): bodies given in mesh numbering become one [`Mesh`].
//!
//! Each body is a list of elements (`arity` vertices each: 2 for a curve, 3 for a 2D solid or
//! a 3D surface, 4 for a 3D solid). Its contact elements are derived from its kind: a curve's
//! edges are its elements; a 2D solid's are its boundary edges; a surface's contact faces are
//! its triangles and its contact edges their edges; a 3D solid's contact faces are its
//! outward boundary faces (or the faces the scene states) and its contact edges their
//! edges. Its `h` is the longest reference
//! edge of its elements unless the scene states it; a scene may also state a solid's contact
//! edges (2D) or faces (3D) in its own order.
//!
//! The global order is explicit, because it decides the order of every floating-point sum
//! downstream (contact rows, energy terms): the caller numbers the vertices (a scene file:
//! body by body in file order, welded vertices merged; a built-in scene: its own numbering),
//! and [`assemble_mesh`] takes the order in which the bodies' elements enter the global
//! lists (`edges`, `triangles`, `faces`, `tets`). [`file_order`] is the default, body by body
//! in the order given; the bodies themselves are always listed in the order given. The
//! energy of the assembled bodies is made by the one energy assembler, [`super::physics`].

use crate::scene::file::topology::{boundary_edges, boundary_faces};
use crate::scene::mesh::{Body, BodyKind, Mesh};
use crate::scene::sheets::unique_edges;

/// One body to assemble, in mesh numbering.
#[derive(Clone, Debug, Default)]
pub struct BodyPart {
    /// Name used in outputs.
    pub name: String,
    /// Curve, surface or solid.
    pub kind: BodyKind,
    /// Its vertices (a vertex shared with another body is listed by both).
    pub vertices: Vec<usize>,
    /// Its elements; the first `arity` entries are used, the rest are 0.
    pub elements: Vec<[usize; 4]>,
    /// Vertices per element.
    pub arity: usize,
    /// Its mesh size if the scene states it; `None`: the longest reference edge of its
    /// elements.
    pub h: Option<f64>,
    /// A 2D solid's contact edges if the scene states them (in its own order); `None`: its
    /// boundary edges, sorted.
    pub edges: Option<Vec<[usize; 2]>>,
    /// A 3D solid's contact faces if the scene states them (outward, in its own order);
    /// `None`: its outward boundary faces, sorted.
    pub faces: Option<Vec<[usize; 3]>>,
}

/// The default element order: body by body in the order given.
pub fn file_order(bodies: usize) -> Vec<usize> {
    (0..bodies).collect()
}

/// The mesh of `parts` on the vertices `x_ref` / `fixed` (`dim` coordinates per vertex),
/// the bodies' elements entering the global lists in `element_order` (a permutation of the
/// body indices). Body `i` of the mesh is `parts[i]`.
pub fn assemble_mesh(
    dim: usize,
    x_ref: Vec<f64>,
    fixed: Vec<bool>,
    parts: &[BodyPart],
    element_order: &[usize],
) -> Mesh {
    debug_assert_eq!(element_order.len(), parts.len());
    let mut mesh = Mesh {
        dim,
        x_ref,
        fixed,
        ..Default::default()
    };
    let mut bodies: Vec<Option<Body>> = vec![None; parts.len()];
    for &bi in element_order {
        bodies[bi] = Some(body_mesh(&mut mesh, bi, &parts[bi]));
    }
    mesh.bodies = bodies
        .into_iter()
        .map(|b| b.expect("element_order is a permutation of the bodies"))
        .collect();
    mesh
}

/// Body `bi`'s elements and contact elements pushed onto the mesh's lists; its [`Body`].
fn body_mesh(mesh: &mut Mesh, bi: usize, part: &BodyPart) -> Body {
    let dim = mesh.dim;
    let els = &part.elements;
    let mut body = Body {
        name: part.name.clone(),
        kind: part.kind,
        vertices: part.vertices.clone(),
        ..Default::default()
    };
    let push_edges = |mesh: &mut Mesh, body: &mut Body, edges: Vec<[usize; 2]>| {
        for e in edges {
            body.edges.push(mesh.edges.len());
            mesh.edges.push(e);
            mesh.edge_body.push(bi);
        }
    };
    let tri = |e: &[usize; 4]| [e[0], e[1], e[2]];
    match (part.kind, dim) {
        (BodyKind::Curve, _) => {
            push_edges(mesh, &mut body, els.iter().map(|e| [e[0], e[1]]).collect());
        }
        (BodyKind::Solid, 2) => {
            for e in els {
                body.triangles.push(mesh.triangles.len());
                mesh.triangles.push(tri(e));
            }
            let tris: Vec<[usize; 3]> = els.iter().map(tri).collect();
            let edges = part.edges.clone().unwrap_or_else(|| boundary_edges(&tris));
            push_edges(mesh, &mut body, edges);
        }
        (BodyKind::Surface, _) => {
            let tris: Vec<[usize; 3]> = els.iter().map(tri).collect();
            for t in &tris {
                body.triangles.push(mesh.triangles.len());
                mesh.triangles.push(*t);
                body.faces.push(mesh.faces.len());
                mesh.faces.push(*t);
                mesh.face_body.push(bi);
            }
            push_edges(mesh, &mut body, unique_edges(&tris));
        }
        (BodyKind::Solid, _) => {
            for e in els {
                body.tets.push(mesh.tets.len());
                mesh.tets.push(*e);
            }
            let faces = part.faces.clone().unwrap_or_else(|| boundary_faces(els));
            for f in &faces {
                body.faces.push(mesh.faces.len());
                mesh.faces.push(*f);
                mesh.face_body.push(bi);
            }
            push_edges(mesh, &mut body, unique_edges(&faces));
        }
    }
    body.h = match part.h {
        Some(h) => h,
        None => {
            // the longest reference edge of the body's elements
            let mut h: f64 = 0.0;
            for e in els {
                for a in 0..part.arity {
                    for b in a + 1..part.arity {
                        h = h.max(
                            (mesh.point(&mesh.x_ref, e[a]) - mesh.point(&mesh.x_ref, e[b])).norm(),
                        );
                    }
                }
            }
            h
        }
    };
    body
}
