//! What a run writes about contact and supports (docs/run-directory.md): per contact vertex
//! the contact force, normal force, pressure and gap (`contacts.csv`, the frames' point data),
//! the reactions at supports (`reactions.csv`, `summary.json`, the frames), and the fields of
//! the frames (displacement; per element Cauchy stress and von Mises).
//!
//! **The contact force on a vertex** `v` of a body is fixed by the equilibrium of that body:
//! stationarity of a sub-problem (Lemma 5.4, with the sign of docs/method.md) reads
//! `J'(φ) = Σ μ ∇row` on the free dofs, and `Σ μ ∇row` restricted to `v` is the force the
//! contact rows exert on `v`. So on a free dof the contact force is `∂J/∂φ(v)` — `J` holds the
//! elastic energy and every external load (dead loads, gravity), so loads acting at `v` are
//! accounted for — and it is unique even where the multipliers are not (nearly parallel rows,
//! rows from both sides of an interface). On a prescribed dof the support and the contact
//! share the dof, and the contact part is taken from the multipliers, `(Σ μ ∇row)(v)`. This
//! **equilibrium-based** force is the default; its cost is one gradient of `J` per written
//! step. At a step that has not converged it is the force that would balance the current
//! iterate (its difference from the multipliers' force is the stationarity residual).
//!
//! **Normal force and pressure.** A frictionless contact force is normal to the contact: the
//! normal force is `|f|`, with a minus sign on a solid's vertex when `f` points outward (a
//! pull, `f·n` positive; `n` the outward unit normal of its boundary at `v`, the normalized sum of its
//! contact edges' outward normals weighted by length in 2D, of its contact faces' by area in
//! 3D). The pressure is the normal force over the vertex's tributary measure **projected
//! normal to `f`**: `Σ_e |e|/k · |n̂_e·f̂|` over its contact edges (2D, `k = 2`) or faces (3D,
//! `k = 3`), at the current positions (Cauchy). On a smooth or flat interface this is half its
//! edges' length / a third of its faces' area ([`Mesh::tributary`]) up to second order in the
//! angle between neighbouring elements; at a corner of a solid (the end of a patch-test
//! interface, where a side edge meets the contact face at 90°) it leaves out the side that does
//! not face the force. `pressure_nominal` uses the reference lengths and normals (the nominal
//! pressure, what a small-strain theory such as Hertz's compares with).
//!
//! **Two-sided pressure** (`pressure_two_sided`, `pressure_nominal_two_sided`): between two
//! deformable bodies the rows of both sides keep the two boundaries ε apart at every vertex of
//! either (the over-constraint of two-pass node-to-segment contact), and with non-matching
//! vertices each side's nodal forces oscillate, in opposite phase. The two-sided pressure of
//! `v` is the mean of its own pressure and the other side's pressure interpolated at the
//! closest point of its nearest element (barycentric weights of that pair); against a fixed
//! obstacle (every vertex of the element fixed) it is `v`'s own. It smooths, it does not
//! conserve each body's total force exactly; measured in results/README.md (Hertz, elastic
//! flat). Cost: a lookup per vertex in the pairs the gap search finds anyway.
//!
//! **The multipliers' pressure** (`pressure_pairs`): the pairs in which `v` is the point
//! (2D vertex–edge, 3D vertex–triangle) carry the force `Σ_i μ_i` along their normal; their sum
//! over the tributary measure is the nodal pressure of a two-pass node-to-segment reading. With
//! rows from both sides of an interface it is not unique and it oscillates (docs/known-gaps.md,
//! results/README.md): it is written for comparison.
//!
//! **Gap**: the distance from `v` (as the point of a pair) to the nearest element it may
//! touch, minus ε; searched within `ε + h̄/4` (h̄ the median contact edge length at the step),
//! NaN beyond.
//!
//! **Reactions**: on a prescribed dof the support exerts `R = ∂J/∂φ − (Σ μ ∇row)`, the
//! balance of the body's forces there (at equilibrium `Σ R = −(the applied loads)`, since the
//! elastic terms are translation invariant and every row exerts opposite forces on its two
//! sides).

use crate::contact::{near_pairs, pair_rows, ContactPair, PairRows};
use crate::energy::{Objective, TermKind, TotalEnergy};
use crate::output::run_dir::Writer;
use crate::output::vtk::OwnedVtuFields;
use crate::scene::mesh::{BodyKind, Mesh};
use crate::solve::outer::{median_edge_length, OuterEvent, OuterLoop, RunResult};
use anyhow::Result;
use std::collections::HashMap;
use std::fs::File;
use std::path::Path;

/// The contact quantities of one contact vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexContact {
    /// The vertex.
    pub vertex: usize,
    /// The first body holding it.
    pub body: usize,
    /// Its position (`z = 0` in 2D).
    pub position: [f64; 3],
    /// The contact force on it (equilibrium-based; `z = 0` in 2D).
    pub force: [f64; 3],
    /// The outward unit normal of its body (solids), or the curve's / surface's normal.
    pub normal: [f64; 3],
    /// `|f|`, negative on a solid's vertex pulled outward.
    pub normal_force: f64,
    /// Tributary length (2D) or area (3D) projected normal to `f`, at the current positions.
    pub tributary: f64,
    /// The same in the reference configuration.
    pub tributary_ref: f64,
    /// `normal_force / tributary`.
    pub pressure: f64,
    /// `normal_force / tributary_ref`.
    pub pressure_nominal: f64,
    /// The mean of `pressure` and the other side's, interpolated at the closest point of the
    /// nearest element `v` may touch (`pressure` when that element's vertices are all fixed).
    pub pressure_two_sided: f64,
    /// The same with the nominal pressures.
    pub pressure_nominal_two_sided: f64,
    /// The multipliers' nodal pressure: `Σ_{pairs with point v} Σ_i μ_i / tributary`.
    pub pressure_pairs: f64,
    /// Distance to the nearest element it may touch (NaN beyond the search radius).
    pub distance: f64,
}

/// The contact state of a configuration: per-vertex arrays (for the frames) and the contact
/// vertices near contact (for `contacts.csv`).
#[derive(Clone, Debug)]
pub struct ContactState {
    /// Space dimension.
    pub dim: usize,
    /// Contact force per dof (equilibrium-based; 0 off the contact vertices).
    pub force: Vec<f64>,
    /// `Σ μ ∇row` per dof.
    pub force_mult: Vec<f64>,
    /// The support's force per prescribed dof (0 on free dofs).
    pub reaction: Vec<f64>,
    /// Pressure per vertex (0 off the contact vertices).
    pub pressure: Vec<f64>,
    /// The two-sided pressure per vertex.
    pub pressure_two_sided: Vec<f64>,
    /// The multipliers' nodal pressure per vertex.
    pub pressure_pairs: Vec<f64>,
    /// Distance − ε per vertex (NaN beyond the search radius or off the contact vertices).
    pub gap: Vec<f64>,
    /// The contact vertices with an element within the search radius or a multiplier force
    /// (above `1e-6` of the largest).
    pub near: Vec<VertexContact>,
}

/// The contact state at `x` of a scene with minimal distance `eps`, with the rows of the last
/// sub-problem and their multipliers (module doc).
pub fn contact_state(
    mesh: &Mesh,
    energy: &dyn Objective,
    x: &[f64],
    eps: f64,
    rows: &[PairRows],
    mult: &[[f64; 4]],
) -> ContactState {
    let dim = mesh.dim;
    let nv = mesh.nv();
    let g = energy.gradient(x);
    let mut force_mult = vec![0.0; dim * nv];
    let mut pair_force = vec![0.0; nv];
    for (r, m) in rows.iter().zip(mult) {
        let mut total = 0.0;
        for (i, &mu) in m.iter().enumerate().take(r.len) {
            total += mu;
            for c in 0..dim {
                force_mult[dim * r.plus[i] + c] += mu * r.n[c];
                force_mult[dim * r.minus[i] + c] -= mu * r.n[c];
            }
        }
        match r.pair {
            ContactPair::PointEdge { x, .. } | ContactPair::PointTriangle { x, .. } => {
                pair_force[x] += total
            }
            ContactPair::EdgeEdge { .. } => {}
        }
    }
    let contact = mesh.contact_vertices();
    let mut force = vec![0.0; dim * nv];
    for &v in &contact {
        for c in 0..dim {
            let dof = dim * v + c;
            force[dof] = if mesh.dof_fixed(dof) {
                force_mult[dof]
            } else {
                g[dof]
            };
        }
    }
    let reaction: Vec<f64> = (0..dim * nv)
        .map(|dof| {
            if mesh.dof_fixed(dof) {
                g[dof] - force_mult[dof]
            } else {
                0.0
            }
        })
        .collect();
    let (normal, solid) = vertex_normals(mesh, x);
    let dir: Vec<[f64; 3]> = (0..nv)
        .map(|v| {
            let f: [f64; 3] =
                std::array::from_fn(|c| if c < dim { force[dim * v + c] } else { 0.0 });
            let l = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            if l > 0.0 {
                [f[0] / l, f[1] / l, f[2] / l]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let trib = projected_tributary(mesh, x, &dir);
    let trib_ref = projected_tributary(mesh, &mesh.x_ref, &dir);
    // distances of the points of the pairs within ε + h̄/4
    let mut dist = vec![f64::NAN; nv];
    // the nearest element of each point: its vertices and the closest point's weights
    let mut nearest: Vec<Option<([usize; 3], [f64; 3])>> = vec![None; nv];
    let hbar = median_edge_length(mesh, x);
    for p in near_pairs(mesh, x, eps + 0.25 * hbar, false) {
        let (v, verts) = match p {
            ContactPair::PointEdge { x, a } => {
                let e = mesh.edges[a];
                (x, [e[0], e[1], usize::MAX])
            }
            ContactPair::PointTriangle { x, t } => (x, mesh.faces[t]),
            ContactPair::EdgeEdge { .. } => continue,
        };
        let r = pair_rows(mesh, x, p);
        let d = r.map_or(0.0, |r| r.distance);
        if dist[v].is_nan() || d < dist[v] {
            dist[v] = d;
            nearest[v] = r.map(|r| (verts, [r.weight[0], r.weight[1], r.weight[2]]));
        }
    }
    let body_of = first_body(mesh);
    // a multiplier force counts above round-off of the largest (an interior-point backend
    // leaves duals of order its tolerance on inactive rows)
    let fm_max = force_mult.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let mut pressure = vec![0.0; nv];
    let mut pressure_nominal = vec![0.0; nv];
    let mut pressure_pairs = vec![0.0; nv];
    let mut normal_force = vec![0.0; nv];
    let mut gap = vec![f64::NAN; nv];
    for &v in &contact {
        let f: [f64; 3] = std::array::from_fn(|c| if c < dim { force[dim * v + c] } else { 0.0 });
        let n = normal[v];
        let fabs = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
        let fnorm = if solid[v] && f[0] * n[0] + f[1] * n[1] + f[2] * n[2] > 0.0 {
            -fabs
        } else {
            fabs
        };
        let per = |m: f64| if m > 0.0 { fnorm / m } else { 0.0 };
        normal_force[v] = fnorm;
        pressure[v] = per(trib[v]);
        pressure_nominal[v] = per(trib_ref[v]);
        pressure_pairs[v] = if trib[v] > 0.0 {
            pair_force[v] / trib[v]
        } else {
            0.0
        };
        gap[v] = dist[v] - eps;
    }
    // two-sided: the mean of v's pressure and the other side's, interpolated at the closest
    // point of v's nearest element (its own pressure when that element is an obstacle's, every
    // vertex fixed)
    let two_sided = |p: &[f64], v: usize| match nearest[v] {
        Some((verts, w)) if !verts.iter().all(|&u| u == usize::MAX || mesh.fixed[u]) => {
            let other: f64 = verts
                .iter()
                .zip(w)
                .filter(|(&u, _)| u != usize::MAX)
                .map(|(&u, w)| w * p[u])
                .sum();
            0.5 * (p[v] + other)
        }
        _ => p[v],
    };
    let pressure_two_sided: Vec<f64> = (0..nv).map(|v| two_sided(&pressure, v)).collect();
    let mut near = Vec::new();
    for &v in &contact {
        let f: [f64; 3] = std::array::from_fn(|c| if c < dim { force[dim * v + c] } else { 0.0 });
        let has_mult = (0..dim).any(|c| force_mult[dim * v + c].abs() > 1e-6 * fm_max);
        if dist[v].is_finite() || has_mult {
            near.push(VertexContact {
                vertex: v,
                body: body_of[v],
                position: std::array::from_fn(|c| if c < dim { x[dim * v + c] } else { 0.0 }),
                force: f,
                normal: normal[v],
                normal_force: normal_force[v],
                tributary: trib[v],
                tributary_ref: trib_ref[v],
                pressure: pressure[v],
                pressure_nominal: pressure_nominal[v],
                pressure_two_sided: pressure_two_sided[v],
                pressure_nominal_two_sided: two_sided(&pressure_nominal, v),
                pressure_pairs: pressure_pairs[v],
                distance: dist[v],
            });
        }
    }
    ContactState {
        dim,
        force,
        force_mult,
        reaction,
        pressure,
        pressure_two_sided,
        pressure_pairs,
        gap,
        near,
    }
}

/// The contact elements around each vertex: contact faces (3D), else contact edges, for the
/// tributary measures of [`ContactAdjacency::projected`].
pub struct ContactAdjacency {
    /// CSR: the elements of vertex `v` are `list[start[v]..start[v + 1]]`, each `(is_face,
    /// index into Mesh::faces or Mesh::edges)`.
    start: Vec<usize>,
    list: Vec<(bool, usize)>,
}

impl ContactAdjacency {
    /// The adjacency of `mesh`: a vertex on a contact face takes its faces, any other its
    /// contact edges.
    pub fn new(mesh: &Mesh) -> Self {
        let nv = mesh.nv();
        let mut per: Vec<Vec<(bool, usize)>> = vec![Vec::new(); nv];
        for (i, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                per[v].push((true, i));
            }
        }
        for (i, e) in mesh.edges.iter().enumerate() {
            for &v in e {
                if !per[v].first().is_some_and(|t| t.0) {
                    per[v].push((false, i));
                }
            }
        }
        let mut start = vec![0];
        let mut list = Vec::new();
        for p in per {
            list.extend(p);
            start.push(list.len());
        }
        ContactAdjacency { start, list }
    }

    /// The measure of `v`'s contact elements at `x` projected normal to the unit vector `dir`
    /// (or 0): `Σ_e |e|/k · |n̂_e·dir|` over its contact edges (2D, `k = 2`) or faces (3D,
    /// `k = 3`), `n̂_e` their unit normals; with `dir = 0`, and for the edges of 3D curves (no
    /// normal), the plain `|e|/k` ([`Mesh::tributary`]). On a flat or smooth interface this is
    /// the tributary measure to second order in the angle between neighbouring elements; at a
    /// corner of a solid (the end of a patch-test interface) it leaves out the side that does
    /// not face `dir`.
    pub fn projected(&self, mesh: &Mesh, x: &[f64], v: usize, dir: [f64; 3]) -> f64 {
        let d = nalgebra::Vector3::from(dir);
        let has_dir = d.norm_squared() > 0.0;
        let mut out = 0.0;
        for &(is_face, i) in &self.list[self.start[v]..self.start[v + 1]] {
            let (share, n) = if is_face {
                let f = mesh.faces[i];
                let (a, b, c) = (
                    mesh.point(x, f[0]),
                    mesh.point(x, f[1]),
                    mesh.point(x, f[2]),
                );
                let cr = (b - a).cross(&(c - a));
                let area = 0.5 * cr.norm();
                (area / 3.0, (area > 0.0).then(|| cr / (2.0 * area)))
            } else {
                let e = mesh.edges[i];
                let t = mesh.point(x, e[1]) - mesh.point(x, e[0]);
                let l = t.norm();
                let n =
                    (mesh.dim == 2 && l > 0.0).then(|| nalgebra::Vector3::new(t.y, -t.x, 0.0) / l);
                (0.5 * l, n)
            };
            out += share
                * match n {
                    Some(n) if has_dir => n.dot(&d).abs(),
                    _ => 1.0,
                };
        }
        out
    }
}

/// Per vertex [`ContactAdjacency::projected`] along `dir[v]`.
fn projected_tributary(mesh: &Mesh, x: &[f64], dir: &[[f64; 3]]) -> Vec<f64> {
    let adj = ContactAdjacency::new(mesh);
    (0..mesh.nv())
        .map(|v| adj.projected(mesh, x, v, dir[v]))
        .collect()
}

/// The first body holding each vertex (`usize::MAX` for none).
fn first_body(mesh: &Mesh) -> Vec<usize> {
    let mut b = vec![usize::MAX; mesh.nv()];
    for (bi, body) in mesh.bodies.iter().enumerate() {
        for &v in &body.vertices {
            if b[v] == usize::MAX {
                b[v] = bi;
            }
        }
    }
    b
}

/// Per vertex the unit normal of its contact elements at `x` (2D: the edges' `(dy, −dx)`,
/// outward for a solid's boundary edges, weighted by length; 3D: the faces' normals, outward
/// for a solid, weighted by area), and whether a solid holds it.
fn vertex_normals(mesh: &Mesh, x: &[f64]) -> (Vec<[f64; 3]>, Vec<bool>) {
    let nv = mesh.nv();
    let mut acc = vec![nalgebra::Vector3::<f64>::zeros(); nv];
    let mut solid = vec![false; nv];
    for body in &mesh.bodies {
        let is_solid = body.kind == BodyKind::Solid;
        if mesh.dim == 2 {
            for &e in &body.edges {
                let [a, b] = mesh.edges[e];
                let d = mesh.point(x, b) - mesh.point(x, a);
                let n = nalgebra::Vector3::new(d.y, -d.x, 0.0);
                for v in [a, b] {
                    acc[v] += n;
                    solid[v] |= is_solid;
                }
            }
        } else {
            for &f in &body.faces {
                let t = mesh.faces[f];
                let (a, b, c) = (
                    mesh.point(x, t[0]),
                    mesh.point(x, t[1]),
                    mesh.point(x, t[2]),
                );
                let n = (b - a).cross(&(c - a));
                for v in t {
                    acc[v] += n;
                    solid[v] |= is_solid;
                }
            }
        }
    }
    let normal = acc
        .iter()
        .map(|n| {
            let l = n.norm();
            if l > 0.0 {
                [n.x / l, n.y / l, n.z / l]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    (normal, solid)
}

/// The total external load: `−Σ ∇` of the potential terms (dead loads, gravity), per
/// component.
pub fn applied_load(energy: &TotalEnergy, dim: usize, x: &[f64]) -> Vec<f64> {
    let mut g = vec![0.0; x.len()];
    for t in energy
        .terms
        .iter()
        .filter(|t| t.kind() == TermKind::Potential)
    {
        t.add_gradient(x, &mut g);
    }
    let mut total = vec![0.0; dim];
    for c in g.chunks(dim) {
        for (k, v) in c.iter().enumerate() {
            total[k] -= v;
        }
    }
    total
}

/// Per component, the sum of a flat per-dof vector.
pub fn component_sums(v: &[f64], dim: usize) -> Vec<f64> {
    let mut total = vec![0.0; dim];
    for c in v.chunks(dim) {
        for (k, a) in c.iter().enumerate() {
            total[k] += a;
        }
    }
    total
}

/// The Cauchy stress of the solid elements at `x`, per cell of a frame (edges, then triangles —
/// the 2D solid triangles or the 3D contact faces —, then tetrahedra): `sigma_xx, sigma_yy,
/// sigma_zz, sigma_xy, sigma_yz, sigma_xz, von_mises`, NaN on cells that are not solid elements.
pub fn cell_stress(mesh: &Mesh, energy: &TotalEnergy, x: &[f64]) -> Option<[Vec<f64>; 7]> {
    let tris = if mesh.dim == 3 {
        &mesh.faces
    } else {
        &mesh.triangles
    };
    let ncell = mesh.edges.len() + tris.len() + mesh.tets.len();
    let mut index: HashMap<[usize; 4], usize> = HashMap::new();
    let key = |vs: &[usize]| {
        let mut k = [usize::MAX; 4];
        k[..vs.len()].copy_from_slice(vs);
        k.sort_unstable();
        k
    };
    if mesh.dim == 2 {
        for (i, t) in mesh.triangles.iter().enumerate() {
            index.insert(key(t), mesh.edges.len() + i);
        }
    }
    for (i, t) in mesh.tets.iter().enumerate() {
        index.insert(key(t), mesh.edges.len() + tris.len() + i);
    }
    let mut out: [Vec<f64>; 7] = std::array::from_fn(|_| vec![f64::NAN; ncell]);
    let mut any = false;
    for term in &energy.terms {
        let Some(st) = term.element_stress(x) else {
            continue;
        };
        for (e, s) in st.elements.iter().zip(&st.sigma) {
            let n = e.iter().take_while(|&&v| v != usize::MAX).count();
            let Some(&cell) = index.get(&key(&e[..n])) else {
                continue;
            };
            any = true;
            let vals = [
                s[(0, 0)],
                s[(1, 1)],
                s[(2, 2)],
                s[(0, 1)],
                s[(1, 2)],
                s[(0, 2)],
                von_mises(s),
            ];
            for (o, v) in out.iter_mut().zip(vals) {
                o[cell] = v;
            }
        }
    }
    any.then_some(out)
}

/// The von Mises stress of a Cauchy stress tensor.
pub fn von_mises(s: &nalgebra::Matrix3<f64>) -> f64 {
    let d = (s[(0, 0)] - s[(1, 1)]).powi(2)
        + (s[(1, 1)] - s[(2, 2)]).powi(2)
        + (s[(2, 2)] - s[(0, 0)]).powi(2);
    let sh = s[(0, 1)].powi(2) + s[(1, 2)].powi(2) + s[(0, 2)].powi(2);
    (0.5 * d + 3.0 * sh).sqrt()
}

/// The names of the stress cell arrays, in the order of [`cell_stress`].
pub const STRESS_NAMES: [&str; 7] = [
    "sigma_xx",
    "sigma_yy",
    "sigma_zz",
    "sigma_xy",
    "sigma_yz",
    "sigma_xz",
    "von_mises",
];

/// The data arrays of a static frame at `x`: point data `displacement`, `contact_force`,
/// `reaction` (vectors), `contact_pressure`, `contact_pressure_two_sided`,
/// `contact_pressure_pairs`, `gap` (scalars); cell
/// data the Cauchy stress components and von Mises of the solid elements.
pub fn frame_fields(
    mesh: &Mesh,
    energy: &TotalEnergy,
    x: &[f64],
    eps: f64,
    rows: &[PairRows],
    mult: &[[f64; 4]],
) -> OwnedVtuFields {
    let dim = mesh.dim;
    let st = contact_state(mesh, energy, x, eps, rows, mult);
    let to3 = |v: &[f64]| -> Vec<f64> {
        v.chunks(dim)
            .flat_map(|c| [c[0], c[1], if dim == 3 { c[2] } else { 0.0 }])
            .collect()
    };
    let disp: Vec<f64> = x.iter().zip(&mesh.x_ref).map(|(a, b)| a - b).collect();
    let mut f = OwnedVtuFields {
        point_scalars: vec![
            ("contact_pressure".into(), st.pressure),
            ("contact_pressure_two_sided".into(), st.pressure_two_sided),
            ("contact_pressure_pairs".into(), st.pressure_pairs),
            ("gap".into(), st.gap),
        ],
        point_vectors: vec![
            ("displacement".into(), to3(&disp)),
            ("contact_force".into(), to3(&st.force)),
            ("reaction".into(), to3(&st.reaction)),
        ],
        cell_scalars: Vec::new(),
    };
    if let Some(cells) = cell_stress(mesh, energy, x) {
        for (name, v) in STRESS_NAMES.iter().zip(cells) {
            f.cell_scalars.push((name.to_string(), v));
        }
    }
    f
}

/// One row of a static run's `contacts.csv`.
#[derive(serde::Serialize, serde::Deserialize, Clone, Debug, PartialEq)]
pub struct ContactRow {
    /// Outer iteration.
    pub step: usize,
    /// Vertex (mesh numbering).
    pub vertex: usize,
    /// Its (first) body's name.
    pub body: String,
    /// Position.
    pub x: f64,
    /// Position.
    pub y: f64,
    /// Position (0 in 2D).
    pub z: f64,
    /// Reference position (what small-strain theory, Hertz's, compares with).
    pub x_ref: f64,
    /// Reference position.
    pub y_ref: f64,
    /// Reference position (0 in 2D).
    pub z_ref: f64,
    /// Contact force (equilibrium-based).
    pub fx: f64,
    /// Contact force.
    pub fy: f64,
    /// Contact force (0 in 2D).
    pub fz: f64,
    /// Normal force (compression > 0).
    pub normal_force: f64,
    /// Tributary length / area (current).
    pub tributary: f64,
    /// Pressure (per current tributary).
    pub pressure: f64,
    /// Pressure per reference tributary.
    pub pressure_nominal: f64,
    /// Two-sided pressure.
    pub pressure_two_sided: f64,
    /// Two-sided nominal pressure.
    pub pressure_nominal_two_sided: f64,
    /// The multipliers' nodal pressure.
    pub pressure_pairs: f64,
    /// Distance to the nearest element (empty beyond the search radius).
    pub distance: Option<f64>,
    /// Distance − ε.
    pub gap: Option<f64>,
}

/// The rows of `contacts.csv` of a contact state at `step`.
pub fn contact_rows(mesh: &Mesh, st: &ContactState, eps: f64, step: usize) -> Vec<ContactRow> {
    st.near
        .iter()
        .map(|c| ContactRow {
            step,
            vertex: c.vertex,
            body: mesh
                .bodies
                .get(c.body)
                .map_or(String::new(), |b| b.name.clone()),
            x: c.position[0],
            y: c.position[1],
            z: c.position[2],
            x_ref: mesh.x_ref[mesh.dim * c.vertex],
            y_ref: mesh.x_ref[mesh.dim * c.vertex + 1],
            z_ref: if mesh.dim == 3 {
                mesh.x_ref[3 * c.vertex + 2]
            } else {
                0.0
            },
            fx: c.force[0],
            fy: c.force[1],
            fz: c.force[2],
            normal_force: c.normal_force,
            tributary: c.tributary,
            pressure: c.pressure,
            pressure_nominal: c.pressure_nominal,
            pressure_two_sided: c.pressure_two_sided,
            pressure_nominal_two_sided: c.pressure_nominal_two_sided,
            pressure_pairs: c.pressure_pairs,
            distance: c.distance.is_finite().then_some(c.distance),
            gap: c.distance.is_finite().then_some(c.distance - eps),
        })
        .collect()
}

/// `contacts.csv` of a static run: per outer iteration (0 = the start) the contact vertices
/// near contact ([`ContactRow`]); flushed after every step.
pub struct StaticContacts<'a> {
    out: csv::Writer<File>,
    mesh: &'a Mesh,
    energy: &'a TotalEnergy,
    eps: f64,
}

impl<'a> StaticContacts<'a> {
    /// Creates `path` and writes its header (so that a run without contact has one too).
    pub fn create(path: &Path, mesh: &'a Mesh, energy: &'a TotalEnergy, eps: f64) -> Result<Self> {
        let mut out = csv::WriterBuilder::new()
            .has_headers(false)
            .from_path(path)?;
        out.write_record(CONTACT_HEADER)?;
        out.flush()?;
        Ok(Self {
            out,
            mesh,
            energy,
            eps,
        })
    }
}

impl Writer<OuterLoop> for StaticContacts<'_> {
    fn write(&mut self, event: &OuterEvent<'_>) -> Result<()> {
        let st = contact_state(
            self.mesh,
            self.energy,
            event.x,
            self.eps,
            event.rows,
            event.multipliers,
        );
        for r in contact_rows(self.mesh, &st, self.eps, event.record.iteration) {
            self.out.serialize(r)?;
        }
        self.out.flush()?;
        Ok(())
    }
    /// After an accepted polish at ε (not an outer step) the returned state differs from the
    /// last step's: its rows are written once more, as step `outer_iterations + 1`, so the
    /// last step of the file is the returned state (the one of `final.vtu` and `summary.json`).
    fn finish(&mut self, outcome: &RunResult) -> Result<()> {
        if outcome.polish.as_ref().is_some_and(|p| p.accepted) {
            let st = contact_state(
                self.mesh,
                self.energy,
                &outcome.x,
                self.eps,
                &outcome.last_rows,
                &outcome.multipliers,
            );
            for r in contact_rows(self.mesh, &st, self.eps, outcome.outer_iterations + 1) {
                self.out.serialize(r)?;
            }
        }
        Ok(self.out.flush()?)
    }
}

/// The header of `contacts.csv` (the fields of [`ContactRow`]).
pub const CONTACT_HEADER: [&str; 21] = [
    "step",
    "vertex",
    "body",
    "x",
    "y",
    "z",
    "x_ref",
    "y_ref",
    "z_ref",
    "fx",
    "fy",
    "fz",
    "normal_force",
    "tributary",
    "pressure",
    "pressure_nominal",
    "pressure_two_sided",
    "pressure_nominal_two_sided",
    "pressure_pairs",
    "distance",
    "gap",
];

/// Loads, reactions and contact forces of a run's returned state (`summary.json`'s
/// `contact`).
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
pub struct ContactSummary {
    /// `Σ` of the dead loads and gravity, per component.
    pub applied_load: Vec<f64>,
    /// `Σ` of the reactions at the supports, per component (`≈ −applied_load` at equilibrium).
    pub reaction_total: Vec<f64>,
    /// Per body (by name), `Σ` of the contact forces on its contact vertices.
    pub contact_force: std::collections::BTreeMap<String, Vec<f64>>,
    /// The largest pressure over the contact vertices.
    pub max_pressure: f64,
    /// Contact vertices near contact (the rows `contacts.csv` has for the returned state).
    pub vertices_near_contact: usize,
}

/// One row of `reactions.csv`: a vertex with a prescribed component.
#[derive(serde::Serialize, serde::Deserialize, Clone, Debug, PartialEq)]
pub struct ReactionRow {
    /// Vertex (mesh numbering).
    pub vertex: usize,
    /// Its (first) body's name.
    pub body: String,
    /// The prescribed components (`x`, `y`, `z` letters).
    pub fixed: String,
    /// Reaction (the support's force on the vertex; 0 on a free component).
    pub rx: f64,
    /// Reaction.
    pub ry: f64,
    /// Reaction (0 in 2D).
    pub rz: f64,
}

/// Writes `reactions.csv` of the run's returned state and returns its [`ContactSummary`].
pub fn write_reactions(
    path: &Path,
    scene: &crate::scene::Scene,
    res: &RunResult,
) -> Result<ContactSummary> {
    let mesh = &scene.mesh;
    let dim = mesh.dim;
    let st = contact_state(
        mesh,
        &scene.energy,
        &res.x,
        scene.eps,
        &res.last_rows,
        &res.multipliers,
    );
    let body_of = first_body(mesh);
    let name = |v: usize| {
        mesh.bodies
            .get(body_of[v])
            .map_or(String::new(), |b| b.name.clone())
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut any = false;
    for v in 0..mesh.nv() {
        let fixed: String = (0..dim)
            .filter(|&c| mesh.dof_fixed(dim * v + c))
            .map(|c| ['x', 'y', 'z'][c])
            .collect();
        if fixed.is_empty() {
            continue;
        }
        any = true;
        let r = |c: usize| {
            if c < dim {
                st.reaction[dim * v + c]
            } else {
                0.0
            }
        };
        w.serialize(ReactionRow {
            vertex: v,
            body: name(v),
            fixed,
            rx: r(0),
            ry: r(1),
            rz: r(2),
        })?;
    }
    if !any {
        w.write_record(["vertex", "body", "fixed", "rx", "ry", "rz"])?;
    }
    crate::output::write_atomic(path, &w.into_inner()?)?;
    let mut contact_force = std::collections::BTreeMap::new();
    for c in &st.near {
        let e = contact_force
            .entry(name(c.vertex))
            .or_insert_with(|| vec![0.0; dim]);
        for (k, f) in e.iter_mut().enumerate() {
            *f += c.force[k];
        }
    }
    Ok(ContactSummary {
        applied_load: applied_load(&scene.energy, dim, &res.x),
        reaction_total: component_sums(&st.reaction, dim),
        contact_force,
        max_pressure: st.near.iter().map(|c| c.pressure).fold(0.0, f64::max),
        vertices_near_contact: st.near.len(),
    })
}
