//! One `[[body]]`: its mesh (a mesh file or inline vertices and elements), its initial
//! positions, transform and fixed vertices, in the body's own numbering, and the checks of
//! its elements (dangling, unused, degenerate, inverted).

use super::schema::{BodySpec, BoxSpec};
use super::{fmt_list, Ctx, Loaded, SceneFileError, DEGENERATE_TOL, MAX_COORDINATE};
use crate::scene::mesh::BodyKind;
use crate::scene::meshio::{read_mesh_file, MeshData};

impl Ctx<'_> {
    /// Reads a mesh file relative to the scene file.
    pub(super) fn read(
        &self,
        rel: &str,
        key: &str,
        line: usize,
    ) -> Result<(MeshData, String), SceneFileError> {
        let p = self.dir.join(rel);
        if !p.is_file() {
            return Err(self.invalid(
                line,
                key,
                format!("{rel:?}"),
                format!("no such file {}", p.display()),
            ));
        }
        Ok((read_mesh_file(&p)?, p.display().to_string()))
    }

    /// Points of a mesh file as `dim`-vectors (z = 0 required in 2D), finite and bounded.
    pub(super) fn points_from_file(
        &self,
        m: &MeshData,
        file: &str,
        body: &str,
        dim: usize,
    ) -> Result<Vec<[f64; 3]>, SceneFileError> {
        for (k, p) in m.points.iter().enumerate() {
            let bad = |reason: String| SceneFileError::Element {
                file: file.to_string(),
                line: m.point_lines[k],
                body: body.to_string(),
                what: format!("vertex {k}"),
                reason,
            };
            if let Some(c) = p
                .iter()
                .find(|c| !c.is_finite() || c.abs() > MAX_COORDINATE)
            {
                return Err(bad(format!(
                    "coordinate {c:?} is not finite or exceeds {MAX_COORDINATE:e} in absolute value"
                )));
            }
            if dim == 2 && p[2] != 0.0 {
                return Err(bad(format!("z = {} in a 2D scene (must be 0)", p[2])));
            }
        }
        Ok(m.points.clone())
    }

    /// Inline vertices (`vertices`, `initial_vertices`) as `dim`-vectors, finite and bounded.
    pub(super) fn inline_points(
        &self,
        v: &[Vec<f64>],
        key: &str,
        line: usize,
        dim: usize,
    ) -> Result<Vec<[f64; 3]>, SceneFileError> {
        let mut out = Vec::with_capacity(v.len());
        for (k, p) in v.iter().enumerate() {
            if p.len() != dim {
                return Err(self.invalid(
                    line,
                    format!("{key}[{k}]"),
                    fmt_list(p),
                    format!("a vertex has {dim} coordinates in a {dim}D scene"),
                ));
            }
            if let Some(c) = p
                .iter()
                .find(|c| !c.is_finite() || c.abs() > MAX_COORDINATE)
            {
                return Err(self.invalid(
                    line,
                    format!("{key}[{k}]"),
                    fmt_list(p),
                    format!("coordinate {c:?} is not finite or exceeds {MAX_COORDINATE:e} in absolute value"),
                ));
            }
            let mut q = [0.0; 3];
            q[..dim].copy_from_slice(p);
            out.push(q);
        }
        Ok(out)
    }

    /// Body `i` (its table at `line`) in its own numbering: mesh, initial positions,
    /// transform, fixed vertices, checked elements.
    pub(super) fn load_body(
        &self,
        b: &BodySpec,
        i: usize,
        line: usize,
        dim: usize,
    ) -> Result<Loaded, SceneFileError> {
        let key = format!("body[{i}]");
        let arity = match (b.kind, dim) {
            (BodyKind::Curve, _) => 2,
            (BodyKind::Surface, 3) => 3,
            (BodyKind::Surface, _) => {
                return Err(self.invalid(
                    line,
                    format!("{key}.kind"),
                    "\"surface\"",
                    "surfaces need dim = 3 (a 2D body is a curve or a solid)",
                ))
            }
            (BodyKind::Solid, 2) => 3,
            (BodyKind::Solid, _) => 4,
        };
        // reference vertices and elements
        #[allow(clippy::type_complexity)]
        let (x_ref, point_lines, elems, elem_lines, file): (
            Vec<[f64; 3]>,
            Vec<usize>,
            Vec<[usize; 4]>,
            Vec<usize>,
            String,
        ) = match (&b.mesh, &b.vertices, &b.elements) {
            (Some(m), None, None) => {
                let (data, file) = self.read(m, &format!("{key}.mesh"), line)?;
                let pts = self.points_from_file(&data, &file, &b.name, dim)?;
                let (els, lines): (Vec<[usize; 4]>, Vec<usize>) = match arity {
                    2 => data
                        .lines
                        .iter()
                        .map(|e| ([e.v[0], e.v[1], 0, 0], e.line))
                        .unzip(),
                    3 => data
                        .triangles
                        .iter()
                        .map(|e| ([e.v[0], e.v[1], e.v[2], 0], e.line))
                        .unzip(),
                    _ => data.tets.iter().map(|e| (e.v, e.line)).unzip(),
                };
                if els.is_empty() {
                    let what = [
                        "",
                        "",
                        "lines (msh type 1, obj `l`)",
                        "triangles (msh type 2, obj `f`)",
                        "tetrahedra (msh type 4)",
                    ][arity];
                    return Err(self.invalid(
                        line,
                        format!("{key}.mesh"),
                        format!("{m:?}"),
                        format!(
                            "a {:?} body in {dim}D needs {what}, and the file has none",
                            b.kind
                        )
                        .to_lowercase(),
                    ));
                }
                (pts, data.point_lines, els, lines, file)
            }
            (None, Some(v), Some(e)) => {
                let pts = self.inline_points(v, &format!("{key}.vertices"), line, dim)?;
                let mut els = Vec::with_capacity(e.len());
                for (k, el) in e.iter().enumerate() {
                    let ek = format!("{key}.elements[{k}]");
                    if el.len() != arity {
                        return Err(self.invalid(
                            line,
                            ek,
                            fmt_list(el),
                            format!("a {:?} element in {dim}D has {arity} vertices", b.kind)
                                .to_lowercase(),
                        ));
                    }
                    let mut q = [0usize; 4];
                    for (j, &v) in el.iter().enumerate() {
                        if v < 0 || v as u64 >= pts.len() as u64 {
                            return Err(self.invalid(line, ek, fmt_list(el), format!("vertex {v} does not exist (the body has {} vertices, numbered from 0)", pts.len())));
                        }
                        q[j] = v as usize;
                    }
                    els.push(q);
                }
                if els.is_empty() {
                    return Err(self.invalid(
                        line,
                        format!("{key}.elements"),
                        "[]",
                        "a body needs at least one element",
                    ));
                }
                let (n, np) = (els.len(), pts.len());
                (pts, vec![line; np], els, vec![line; n], self.path.clone())
            }
            _ => {
                return Err(self.invalid(
                    line,
                    key,
                    format!("{:?}", b.name),
                    "give either `mesh` (a file) or both `vertices` and `elements`",
                ))
            }
        };
        let nv = x_ref.len();
        // initial positions
        let x0 = match (&b.initial, &b.initial_vertices) {
            (None, None) => x_ref.clone(),
            (Some(f), None) => {
                let (data, file) = self.read(f, &format!("{key}.initial"), line)?;
                let pts = self.points_from_file(&data, &file, &b.name, dim)?;
                if pts.len() != nv {
                    return Err(self.invalid(
                        line,
                        format!("{key}.initial"),
                        format!("{f:?}"),
                        format!("has {} vertices, the mesh {nv}", pts.len()),
                    ));
                }
                pts
            }
            (None, Some(v)) => {
                let pts = self.inline_points(v, &format!("{key}.initial_vertices"), line, dim)?;
                if pts.len() != nv {
                    return Err(self.invalid(
                        line,
                        format!("{key}.initial_vertices"),
                        format!("{} vertices", pts.len()),
                        format!("the mesh has {nv}"),
                    ));
                }
                pts
            }
            _ => {
                return Err(self.invalid(
                    line,
                    format!("{key}.initial"),
                    format!("{:?}", b.name),
                    "give `initial` or `initial_vertices`, not both",
                ))
            }
        };
        // transform
        let scale = b.scale.unwrap_or(1.0);
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(self.invalid(
                line,
                format!("{key}.scale"),
                scale,
                "must be finite and > 0",
            ));
        }
        let mut shift = [0.0; 3];
        if let Some(t) = &b.translate {
            if t.len() != dim || t.iter().any(|c| !c.is_finite()) {
                return Err(self.invalid(
                    line,
                    format!("{key}.translate"),
                    fmt_list(t),
                    format!("must be {dim} finite numbers"),
                ));
            }
            shift[..dim].copy_from_slice(t);
        }
        let tr = |p: &[f64; 3]| -> [f64; 3] { std::array::from_fn(|c| scale * p[c] + shift[c]) };
        let x_ref: Vec<[f64; 3]> = x_ref.iter().map(tr).collect();
        let x0: Vec<[f64; 3]> = x0.iter().map(tr).collect();
        if let Some(p) = x_ref
            .iter()
            .chain(&x0)
            .find(|p| p.iter().any(|c| !c.is_finite() || c.abs() > MAX_COORDINATE))
        {
            return Err(self.invalid(
                line,
                format!("{key}.scale"),
                scale,
                format!("moves a vertex to {p:?}, beyond {MAX_COORDINATE:e}"),
            ));
        }
        let mut l = Loaded {
            name: b.name.clone(),
            kind: b.kind,
            line,
            key: key.clone(),
            file,
            x_ref,
            point_lines,
            x0,
            elems,
            elem_lines,
            arity,
            fixed: vec![false; nv],
        };
        self.check_elements(&l, dim)?;
        // fixed vertices
        if let Some(f) = &b.fixed {
            if f.all {
                l.fixed.iter_mut().for_each(|v| *v = true);
            }
            for &v in f.vertices.iter().flatten() {
                if v < 0 || v as u64 >= nv as u64 {
                    return Err(self.invalid(
                        line,
                        format!("{key}.fixed.vertices"),
                        v,
                        format!("no such vertex (the body has {nv}, numbered from 0)"),
                    ));
                }
                l.fixed[v as usize] = true;
            }
            if let Some(bx) = &f.bbox {
                let hits =
                    self.box_select(line, &format!("{key}.fixed.box"), bx, &l.x0, dim, "initial")?;
                for v in hits {
                    l.fixed[v] = true;
                }
            }
        }
        Ok(l)
    }

    /// The vertices of `points` (a body's positions in its `config` configuration) in the
    /// closed box `bx`; an error naming `key` when the box is malformed or holds none.
    pub(super) fn box_select(
        &self,
        line: usize,
        key: &str,
        bx: &BoxSpec,
        points: &[[f64; 3]],
        dim: usize,
        config: &str,
    ) -> Result<Vec<usize>, SceneFileError> {
        let shown = || format!("min = {:?}, max = {:?}", bx.min, bx.max);
        if bx.min.len() != dim
            || bx.max.len() != dim
            || bx.min.iter().chain(&bx.max).any(|c| c.is_nan())
        {
            return Err(self.invalid(
                line,
                key,
                shown(),
                format!("min and max must be {dim} numbers each"),
            ));
        }
        let hits: Vec<usize> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| (0..dim).all(|c| bx.min[c] <= p[c] && p[c] <= bx.max[c]))
            .map(|(v, _)| v)
            .collect();
        if hits.is_empty() {
            return Err(self.invalid(
                line,
                key,
                shown(),
                format!("holds no vertex of the body's {config} configuration"),
            ));
        }
        Ok(hits)
    }

    /// Unused vertices, degenerate and inverted elements, in the body's own numbering.
    pub(super) fn check_elements(&self, l: &Loaded, dim: usize) -> Result<(), SceneFileError> {
        let nv = l.x_ref.len();
        let mut used = vec![false; nv];
        for e in &l.elems {
            for &v in &e[..l.arity] {
                used[v] = true;
            }
        }
        if let Some(v) = used.iter().position(|&u| !u) {
            return Err(SceneFileError::Element {
                file: l.file.clone(),
                line: l.point_lines[v],
                body: l.name.clone(),
                what: format!("vertex {v}"),
                reason: format!(
                    "belongs to no {} (a vertex without element has no energy)",
                    ["", "", "edge", "triangle", "tetrahedron"][l.arity]
                ),
            });
        }
        let elem_name = ["", "", "edge", "triangle", "tetrahedron"][l.arity];
        for (k, e) in l.elems.iter().enumerate() {
            let e = &e[..l.arity];
            for (conf, x, solid_only) in [("reference", &l.x_ref, false), ("initial", &l.x0, true)]
            {
                if solid_only && l.kind != BodyKind::Solid {
                    continue;
                }
                let bad = |reason: String| SceneFileError::Element {
                    file: l.file.clone(),
                    line: l.elem_lines[k],
                    body: l.name.clone(),
                    what: format!("{elem_name} {k} {e:?}"),
                    reason: format!("{reason} in the {conf} configuration"),
                };
                let p = |v: usize| nalgebra::Vector3::from(x[v]);
                let mut lmax: f64 = 0.0;
                for a in 0..e.len() {
                    for b in a + 1..e.len() {
                        lmax = lmax.max((p(e[a]) - p(e[b])).norm());
                    }
                }
                match e.len() {
                    2 => {
                        if lmax == 0.0 {
                            return Err(bad("zero length".into()));
                        }
                    }
                    3 => {
                        let cr = (p(e[1]) - p(e[0])).cross(&(p(e[2]) - p(e[0])));
                        let area = if dim == 2 {
                            0.5 * cr.z
                        } else {
                            0.5 * cr.norm()
                        };
                        if area.abs() <= DEGENERATE_TOL * lmax * lmax || lmax == 0.0 {
                            return Err(bad(format!("zero area ({area:e})")));
                        }
                        if area < 0.0 {
                            return Err(bad(format!(
                                "inverted: signed area {area:e} < 0 (2D triangles must be counter-clockwise)"
                            )));
                        }
                    }
                    _ => {
                        let a = p(e[0]);
                        let v6 = (p(e[1]) - a).cross(&(p(e[2]) - a)).dot(&(p(e[3]) - a));
                        if v6.abs() <= DEGENERATE_TOL * lmax * lmax * lmax || lmax == 0.0 {
                            return Err(bad(format!("zero volume ({:e})", v6 / 6.0)));
                        }
                        if v6 < 0.0 {
                            return Err(bad(format!("inverted: signed volume {:e} < 0", v6 / 6.0)));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
