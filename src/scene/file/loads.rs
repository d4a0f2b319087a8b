//! Supports and loads of a scene file's bodies (docs/scene-files.md, docs/materials.md):
//! `[[body.support]]` (prescribed displacements of chosen components of a vertex set: rollers,
//! symmetry planes, clamps, imposed motions), `[[body.traction]]` (a dead traction or pressure
//! on a solid's boundary edges or faces) and `[[body.force]]` (point forces).
//!
//! A vertex set is the union of `vertices` (the body's numbering), `all = true` and `box`
//! (a closed box of the **reference** configuration, after `scale` and `translate`); it must
//! select something.
//!
//! **Supports** fix the chosen components of the selected vertices at `reference +
//! displacement` (default displacement 0): the start φ_0 puts them there, and the dofs are left
//! out of the sub-problems ([`Mesh::fix_component`]). A vertex with every component prescribed
//! is a fixed vertex. Two supports that prescribe different values for one dof, or a support
//! that moves a vertex that `fixed` holds at its initial position, are errors. The displaced
//! start must stay admissible (every allowed pair at least ε apart, checked exactly) and must
//! invert no element of a solid: otherwise the file is refused, naming the pair or the
//! element, since Pantz's iteration starts from an admissible φ_0 (§3).
//!
//! **Loads** are dead ([`DeadLoad`]): computed on the reference configuration, they derive
//! from a linear potential and enter `J`.

use super::assemble::supported_closure;
use super::contact::describe;
use super::schema::{BodySpec, BoxSpec};
use super::{fmt_list, Ctx, Loaded, SceneFileError};
use crate::contact::min_distance;
use crate::energy::DeadLoad;
use crate::scene::mesh::{BodyKind, Mesh};
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// The selectors of a vertex set.
struct Selection<'a> {
    vertices: &'a Option<Vec<i64>>,
    all: bool,
    bbox: &'a Option<BoxSpec>,
}

/// A boundary element of a solid (an edge of one triangle in 2D, a face of one tetrahedron in
/// 3D, in mesh numbering) and the opposite vertex of its element.
struct BoundaryElement {
    vertices: Vec<usize>,
    inside: usize,
}

impl Ctx<'_> {
    /// The body's vertices (its own numbering, sorted) that `sel` selects; `key` names the
    /// table (`body[1].support[0]`).
    fn select(
        &self,
        line: usize,
        key: &str,
        sel: Selection,
        l: &Loaded,
        dim: usize,
    ) -> Result<Vec<usize>, SceneFileError> {
        let nv = l.x_ref.len();
        if sel.vertices.is_none() && !sel.all && sel.bbox.is_none() {
            return Err(self.invalid(
                line,
                key,
                "(no vertex set)",
                "select vertices with `vertices = [..]`, `all = true` or `box = { min, max }`",
            ));
        }
        let mut set = BTreeSet::new();
        if sel.all {
            set.extend(0..nv);
        }
        for &v in sel.vertices.iter().flatten() {
            if v < 0 || v as u64 >= nv as u64 {
                return Err(self.invalid(
                    line,
                    format!("{key}.vertices"),
                    v,
                    format!("no such vertex (the body has {nv}, numbered from 0)"),
                ));
            }
            set.insert(v as usize);
        }
        if let Some(bx) = sel.bbox {
            set.extend(self.box_select(
                line,
                &format!("{key}.box"),
                bx,
                &l.x_ref,
                dim,
                "reference",
            )?);
        }
        if set.is_empty() {
            return Err(self.invalid(
                line,
                key,
                "(empty vertex set)",
                "selects no vertex of the body",
            ));
        }
        Ok(set.into_iter().collect())
    }

    /// `dim` finite numbers, or an error naming `key`.
    fn vector(
        &self,
        line: usize,
        key: String,
        v: &[f64],
        dim: usize,
    ) -> Result<Vec<f64>, SceneFileError> {
        if v.len() != dim || v.iter().any(|c| !c.is_finite()) {
            return Err(self.invalid(
                line,
                key,
                fmt_list(v),
                format!("must be {dim} finite numbers"),
            ));
        }
        Ok(v.to_vec())
    }

    /// Applies `[[body.support]]`: the supported components of `mesh` ([`Mesh::fix_component`])
    /// and their prescribed values in `x0`. Returns whether a support moved a vertex of `x0`.
    pub(super) fn apply_supports(
        &self,
        mesh: &mut Mesh,
        x0: &mut [f64],
        loaded: &[Loaded],
        specs: &[BodySpec],
        global: &[Vec<usize>],
    ) -> Result<bool, SceneFileError> {
        let dim = mesh.dim;
        // dof -> (value, key of the support that set it)
        let mut set: HashMap<usize, (f64, String)> = HashMap::new();
        let mut moved = false;
        let fixed_before = mesh.fixed.clone();
        for (bi, (l, s)) in loaded.iter().zip(specs).enumerate() {
            for (j, sp) in s.support.iter().flatten().enumerate() {
                let line = self.line(sp.span().start);
                let sp = sp.get_ref();
                let key = format!("{}.support[{j}]", l.key);
                let sel = Selection {
                    vertices: &sp.vertices,
                    all: sp.all,
                    bbox: &sp.bbox,
                };
                let verts = self.select(line, &key, sel, l, dim)?;
                let comps: Vec<usize> = match &sp.components {
                    None => (0..dim).collect(),
                    Some(cs) => {
                        let mut out = BTreeSet::new();
                        for &c in cs {
                            if c < 0 || c as u64 >= dim as u64 {
                                return Err(self.invalid(
                                    line,
                                    format!("{key}.components"),
                                    c,
                                    format!(
                                        "component {c} is out of range: 0..{} in {dim}D (0 = x, 1 = y{})",
                                        dim - 1,
                                        if dim == 3 { ", 2 = z" } else { "" }
                                    ),
                                ));
                            }
                            out.insert(c as usize);
                        }
                        if out.is_empty() {
                            return Err(self.invalid(
                                line,
                                format!("{key}.components"),
                                "[]",
                                "names no component (omit the key to prescribe all)",
                            ));
                        }
                        out.into_iter().collect()
                    }
                };
                let disp = match &sp.displacement {
                    None => vec![0.0; dim],
                    Some(d) => self.vector(line, format!("{key}.displacement"), d, dim)?,
                };
                for &k in &verts {
                    let v = global[bi][k];
                    for &c in &comps {
                        let dof = dim * v + c;
                        let value = mesh.x_ref[dof] + disp[c];
                        let tol = 1e-12 * (1.0 + mesh.x_ref[dof].abs());
                        if fixed_before[v] && (value - x0[dof]).abs() > tol {
                            return Err(self.invalid(
                                line,
                                format!("{key}.displacement"),
                                fmt_list(&disp),
                                format!(
                                    "vertex {k} of body {:?} is held by `fixed` at its initial position; a support cannot move it",
                                    l.name
                                ),
                            ));
                        }
                        if let Some((old, by)) = set.get(&dof) {
                            if (old - value).abs() > tol {
                                return Err(self.invalid(
                                    line,
                                    format!("{key}.displacement"),
                                    fmt_list(&disp),
                                    format!(
                                        "vertex {k} of body {:?}, component {c}: {by} prescribes {old:e}, this support {value:e}",
                                        l.name
                                    ),
                                ));
                            }
                        }
                        set.insert(dof, (value, key.clone()));
                        moved |= x0[dof] != value;
                        x0[dof] = value;
                        mesh.fix_component(v, c);
                    }
                }
            }
        }
        Ok(moved)
    }

    /// The dead loads of `[[body.traction]]` and `[[body.force]]`, `None` without any.
    /// `body_elements[b]`: body `b`'s elements in mesh numbering.
    pub(super) fn dead_loads(
        &self,
        mesh: &Mesh,
        loaded: &[Loaded],
        specs: &[BodySpec],
        global: &[Vec<usize>],
        body_elements: &[Vec<[usize; 4]>],
    ) -> Result<Option<DeadLoad>, SceneFileError> {
        let dim = mesh.dim;
        let mut load = DeadLoad::new(dim, mesh.nv());
        let mut any = false;
        for (bi, (l, s)) in loaded.iter().zip(specs).enumerate() {
            for (j, tr) in s.traction.iter().flatten().enumerate() {
                any = true;
                let line = self.line(tr.span().start);
                let tr = tr.get_ref();
                let key = format!("{}.traction[{j}]", l.key);
                if l.kind != BodyKind::Solid {
                    return Err(self.invalid(
                        line,
                        key,
                        format!("{:?}", l.name),
                        format!(
                            "a traction acts on the boundary of a solid, and body {:?} is a {} (no boundary edges or faces: use [[body.force]] for point forces)",
                            l.name,
                            format!("{:?}", l.kind).to_lowercase()
                        ),
                    ));
                }
                let value = match (&tr.traction, tr.pressure) {
                    (Some(t), None) => Ok(self.vector(line, format!("{key}.traction"), t, dim)?),
                    (None, Some(p)) if p.is_finite() => Err(p),
                    (None, Some(p)) => {
                        return Err(self.invalid(line, format!("{key}.pressure"), p, "must be finite"))
                    }
                    _ => {
                        return Err(self.invalid(
                            line,
                            key,
                            "(traction and pressure)",
                            "give exactly one of `traction = [..]` (force per reference length or area) and `pressure = p`",
                        ))
                    }
                };
                let sel = Selection {
                    vertices: &tr.vertices,
                    all: tr.all,
                    bbox: &tr.bbox,
                };
                let chosen: BTreeSet<usize> = self
                    .select(line, &key, sel, l, dim)?
                    .into_iter()
                    .map(|k| global[bi][k])
                    .collect();
                let mut hit = 0;
                for be in boundary(&body_elements[bi], dim) {
                    if be.vertices.iter().all(|v| chosen.contains(v)) {
                        hit += 1;
                        match &value {
                            Ok(t) => load.add_traction(&mesh.x_ref, &be.vertices, t),
                            Err(p) => load.add_pressure(&mesh.x_ref, &be.vertices, be.inside, *p),
                        }
                    }
                }
                if hit == 0 {
                    let what = if dim == 2 {
                        "boundary edge (an edge of one triangle)"
                    } else {
                        "boundary face (a face of one tetrahedron)"
                    };
                    return Err(self.invalid(
                        line,
                        key,
                        format!("{:?}", l.name),
                        format!("selects no {what} with all its vertices selected"),
                    ));
                }
            }
            for (j, f) in s.force.iter().flatten().enumerate() {
                any = true;
                let line = self.line(f.span().start);
                let f = f.get_ref();
                let key = format!("{}.force[{j}]", l.key);
                let value = self.vector(line, format!("{key}.value"), &f.value, dim)?;
                let sel = Selection {
                    vertices: &f.vertices,
                    all: f.all,
                    bbox: &f.bbox,
                };
                for k in self.select(line, &key, sel, l, dim)? {
                    load.add_point(global[bi][k], &value);
                }
            }
        }
        Ok(any.then_some(load))
    }

    /// Unbounded under dead loads: a body whose dead loads have a non-zero net force in a
    /// direction in which it is not supported must be able to touch a supported body (directly,
    /// through other bodies, or through welds). A body is supported when it has a fixed vertex
    /// or, for every component of its net load that is not zero, a vertex supported in that
    /// component. A necessary condition only, like the gravity check.
    #[allow(clippy::too_many_arguments)] // the assembled scene, its bodies and the contact mask
    pub(super) fn check_dead_loads_bounded(
        &self,
        mesh: &Mesh,
        loaded: &[Loaded],
        specs: &[BodySpec],
        global: &[Vec<usize>],
        load: &DeadLoad,
        allowed: &[bool],
        welded: &[bool],
    ) -> Result<(), SceneFileError> {
        let dim = mesh.dim;
        let nb = mesh.bodies.len();
        // each body's net load: the forces of the vertices its own tables selected
        let mut net = vec![vec![0.0; dim]; nb];
        let mut owner: BTreeMap<usize, usize> = BTreeMap::new();
        for (bi, s) in specs.iter().enumerate() {
            if s.traction.is_some() || s.force.is_some() {
                for &v in &global[bi] {
                    owner.entry(v).or_insert(bi);
                }
            }
        }
        for (&v, &bi) in &owner {
            for (c, n) in net[bi].iter_mut().enumerate() {
                *n += load.force[dim * v + c];
            }
        }
        let scale = load.force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        let supported: Vec<bool> = (0..nb)
            .map(|b| {
                let vs = &mesh.bodies[b].vertices;
                vs.iter().any(|&v| mesh.fixed[v])
                    || (0..dim).all(|c| {
                        net[b][c].abs() <= 1e-12 * scale
                            || vs.iter().any(|&v| mesh.dof_fixed(dim * v + c))
                    })
            })
            .collect();
        let has_load: Vec<bool> = net
            .iter()
            .map(|n| n.iter().any(|c| c.abs() > 1e-12 * scale))
            .collect();
        let closure = supported_closure(nb, supported, allowed, welded);
        for b in 0..nb {
            if has_load[b] && !closure[b] {
                let l = &loaded[b];
                return Err(self.invalid(
                    l.line,
                    format!("{}.traction/force", l.key),
                    fmt_list(&net[b]),
                    format!(
                        "the problem is unbounded: the dead loads of body {:?} have this net force, the body has no fixed vertex and no support along the force, and it may touch no supported body (see [contact] and weld), so translating it along the load lowers J without bound: add a [[body.support]]",
                        l.name
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The start with the supports' displacements applied: every allowed pair at least ε apart,
    /// and no solid element inverted.
    pub(super) fn check_displaced_start(
        &self,
        mesh: &Mesh,
        x0: &[f64],
        eps: f64,
        loaded: &[Loaded],
        global: &[Vec<usize>],
        names: &[String],
    ) -> Result<(), SceneFileError> {
        let dim = mesh.dim;
        for (bi, l) in loaded.iter().enumerate() {
            if l.kind != BodyKind::Solid {
                continue;
            }
            for (k, e) in l.elems.iter().enumerate() {
                let g: Vec<usize> = e[..l.arity].iter().map(|&v| global[bi][v]).collect();
                let p = |v: usize| crate::scene::mesh::Mesh::point(mesh, x0, v);
                let a = p(g[0]);
                let measure = if dim == 2 {
                    0.5 * (p(g[1]) - a).cross(&(p(g[2]) - a)).z
                } else {
                    (p(g[1]) - a).cross(&(p(g[2]) - a)).dot(&(p(g[3]) - a)) / 6.0
                };
                if measure <= 0.0 {
                    return Err(SceneFileError::Element {
                        file: l.file.clone(),
                        line: l.elem_lines[k],
                        body: l.name.clone(),
                        what: format!(
                            "{} {k} {:?}",
                            if dim == 2 { "triangle" } else { "tetrahedron" },
                            &e[..l.arity]
                        ),
                        reason: format!(
                            "inverted by the prescribed displacements ([[body.support]]): signed {} {measure:e} ≤ 0 in the initial configuration (prescribe a smaller displacement, or move the body's start with `initial`)",
                            if dim == 2 { "area" } else { "volume" }
                        ),
                    });
                }
            }
        }
        let md = min_distance(mesh, x0, 2.0 * eps, false);
        if md.distance < eps {
            return Err(SceneFileError::DisplacedStart {
                path: self.path.clone(),
                pair: describe(mesh, names, &md.pair),
                distance: md.distance,
                eps,
            });
        }
        Ok(())
    }
}

/// The boundary elements of a solid's elements (mesh numbering): 2D the edges of exactly one
/// triangle (as stored in it), 3D the faces of exactly one tetrahedron, each with the opposite
/// vertex of its element; sorted.
fn boundary(els: &[[usize; 4]], dim: usize) -> Vec<BoundaryElement> {
    let mut count: BTreeMap<Vec<usize>, (Vec<usize>, usize, usize)> = BTreeMap::new();
    for e in els {
        let n = dim + 1;
        for skip in 0..n {
            let f: Vec<usize> = (0..n).filter(|&i| i != skip).map(|i| e[i]).collect();
            let mut key = f.clone();
            key.sort_unstable();
            count.entry(key).or_insert((f, e[skip], 0)).2 += 1;
        }
    }
    count
        .into_values()
        .filter(|&(_, _, c)| c == 1)
        .map(|(vertices, inside, _)| BoundaryElement { vertices, inside })
        .collect()
}
