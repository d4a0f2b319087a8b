//! `[contact]`: which bodies may touch which, and the closest pair named in the bodies' own
//! numbering.

use super::schema::ContactSpec;
use super::{Ctx, SceneFileError};
use crate::contact::ClosestPair;
use crate::scene::mesh::{Body, Mesh};
use toml::Spanned;

impl Ctx<'_> {
    /// The symmetric body mask of `[contact]` (row-major `nb × nb`).
    pub(super) fn contact_mask(
        &self,
        contact: Option<Spanned<ContactSpec>>,
        names: &[String],
    ) -> Result<Vec<bool>, SceneFileError> {
        let nb = names.len();
        let mut allowed = vec![true; nb * nb];
        let Some(c) = contact else {
            return Ok(allowed);
        };
        let line = self.line(c.span().start);
        let c = c.into_inner();
        let idx = |key: &str, n: &str| -> Result<usize, SceneFileError> {
            names.iter().position(|m| m == n).ok_or_else(|| {
                self.invalid(
                    line,
                    key,
                    format!("{n:?}"),
                    format!("no body has this name (bodies: {})", names.join(", ")),
                )
            })
        };
        if let Some(pairs) = &c.pairs {
            for i in 0..nb {
                for j in 0..nb {
                    if i != j {
                        allowed[i * nb + j] = false;
                    }
                }
            }
            for [a, b] in pairs {
                let (i, j) = (idx("contact.pairs", a)?, idx("contact.pairs", b)?);
                if i == j {
                    return Err(self.invalid(
                        line,
                        "contact.pairs",
                        format!("[{a:?}, {b:?}]"),
                        "a body with itself: list it in contact.self",
                    ));
                }
                allowed[i * nb + j] = true;
                allowed[j * nb + i] = true;
            }
        }
        if let Some(s) = &c.self_ {
            for i in 0..nb {
                allowed[i * nb + i] = false;
            }
            for a in s {
                let i = idx("contact.self", a)?;
                allowed[i * nb + i] = true;
            }
        }
        for [a, b] in c.exclude.iter().flatten() {
            let (i, j) = (idx("contact.exclude", a)?, idx("contact.exclude", b)?);
            allowed[i * nb + j] = false;
            allowed[j * nb + i] = false;
        }
        Ok(allowed)
    }
}

/// The closest pair in the bodies' own numbering (a welded vertex: in the first body that
/// holds it).
pub(super) fn describe(mesh: &Mesh, names: &[String], pair: &ClosestPair) -> String {
    let loc = |b: usize, v: usize| {
        mesh.bodies[b]
            .vertices
            .iter()
            .position(|&w| w == v)
            .unwrap_or(v)
    };
    let vb = |v: usize| {
        let b = (0..mesh.bodies.len())
            .find(|&b| mesh.bodies[b].vertices.contains(&v))
            .unwrap_or(0);
        format!("vertex {} of body {:?}", loc(b, v), names[b])
    };
    let local = |list: &dyn Fn(&Body) -> &Vec<usize>, owner: usize, k: usize| {
        list(&mesh.bodies[owner])
            .iter()
            .position(|&e| e == k)
            .unwrap_or(k)
    };
    let eb = |a: usize| {
        let b = mesh.edge_body[a];
        let e = mesh.edges[a];
        format!(
            "edge {} [{}, {}] of body {:?}",
            local(&|b: &Body| &b.edges, b, a),
            loc(b, e[0]),
            loc(b, e[1]),
            names[b]
        )
    };
    let fb = |t: usize| {
        let b = mesh.face_body[t];
        let f = mesh.faces[t];
        format!(
            "face {} [{}, {}, {}] of body {:?}",
            local(&|b: &Body| &b.faces, b, t),
            loc(b, f[0]),
            loc(b, f[1]),
            loc(b, f[2]),
            names[b]
        )
    };
    match *pair {
        ClosestPair::PointEdge { x, a, .. } => format!("{} and {}", vb(x), eb(a)),
        ClosestPair::EdgeEdge { a, b } => format!("{} and {} (crossing)", eb(a), eb(b)),
        ClosestPair::PointTriangle { x, t, .. } => format!("{} and {}", vb(x), fb(t)),
        ClosestPair::Segments { a, b, .. } => format!("{} and {}", eb(a), eb(b)),
        ClosestPair::EdgeThroughFace { a, t } => {
            format!("{} and {} (the edge passes through the face)", eb(a), fb(t))
        }
        ClosestPair::None => "no pair".into(),
    }
}
