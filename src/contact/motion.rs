//! Which rows of T(ψ) a motion can violate: the lazy rows' oracle, by relative displacement.
//!
//! Every row of a pair has the form `n·(φ(p) − φ(q)) ≥ ε` with `n` frozen at ψ, and at ψ each
//! row's value is at least the pair's distance: `n·(ψ(p) − ψ(q)) ≥ d_ψ`, because `n` joins the
//! closest points of two convex elements (eq. 4 and 6). With `u = φ − ψ`,
//!
//! ```text
//!     n·(φ(p) − φ(q)) ≥ d_ψ − |u(p) − u(q)|,
//! ```
//!
//! so a pair's rows can fall below `ε_QP` only when `d_ψ < ε_QP + max |u(p) − u(q)|` over its
//! row vertices: what counts is the *relative* displacement of the two elements, not how far
//! each one moved. Elements that move together (neighbours on an inflating membrane, a body
//! in rigid motion) are never candidates, however far they travel.
//!
//! [`MotionSearch`] holds bounding volume hierarchies ([`Bvh`]) of the contact elements at ψ:
//! vertices × edges in 2D (`point_edge`), vertices × faces (`point_triangle`) and edges ×
//! edges (`edge_edge`) in 3D. They depend on ψ only and are built once per outer step. A query
//! ([`MotionSearch::violated`]) refits, for every node, the box of its elements' displacements
//! (O(N)), and a dual traversal prunes the node pairs whose boxes at ψ are farther apart than
//! `ε_QP` plus the largest relative displacement their displacement boxes allow. The pairs that
//! survive go through the exact row test one by one, as they are found: nothing but the
//! violated rows is stored. The lazy oracle wants only the most violated pair per point
//! ([`MotionSearch::most_violated_per_point`]), and the violated pairs grow like the points
//! times the pairs each point crosses (a membrane moving thousands of h in the balloons' first
//! step): that choice is made inside the traversal, part by part, so its memory is bounded by
//! the points.

use crate::contact::broad_phase::Aabb;
use crate::contact::bvh::Bvh;
use crate::contact::{all_fixed, pair_rows, ContactPair, PairRows};
use crate::scene::mesh::Mesh;

/// Relative slack of the pruning test, far above the round-off of the box arithmetic (the
/// test must never drop a pair that the exact row test would report).
const SLACK: f64 = 1e-9;

/// The contact elements of a mesh at ψ in trees, for [`MotionSearch::violated`].
pub struct MotionSearch<const D: usize> {
    /// Contact vertices (item `k` of `vertex_tree` is `vertices[k]`).
    vertices: Vec<usize>,
    vertex_tree: Bvh<D>,
    /// 2D: the contact edges (item = edge index); 3D: the contact edges, for `edge_edge`.
    edge_tree: Bvh<D>,
    /// 3D: the contact faces (item = face index).
    face_tree: Option<Bvh<D>>,
}

/// The box of the points `vs` of `x` (no inflation).
fn points_box<const D: usize>(x: &[f64], vs: &[usize]) -> Aabb<D> {
    let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
    for &v in vs {
        for c in 0..D {
            lo[c] = lo[c].min(x[D * v + c]);
            hi[c] = hi[c].max(x[D * v + c]);
        }
    }
    (lo, hi)
}

/// Euclidean distance between two boxes (0 when they overlap).
#[inline]
fn box_gap<const D: usize>(a: &Aabb<D>, b: &Aabb<D>) -> f64 {
    let mut s = 0.0;
    for c in 0..D {
        let g = (b.0[c] - a.1[c]).max(a.0[c] - b.1[c]).max(0.0);
        s += g * g;
    }
    s.sqrt()
}

/// The largest `|u − w|` over `u` in box `a` and `w` in box `b`.
#[inline]
fn box_reach<const D: usize>(a: &Aabb<D>, b: &Aabb<D>) -> f64 {
    let mut s = 0.0;
    for c in 0..D {
        let g = (a.1[c] - b.0[c]).abs().max((b.1[c] - a.0[c]).abs());
        s += g * g;
    }
    s.sqrt()
}

/// Per node of a tree: the box of its elements' displacements and their largest norm.
struct Moved<const D: usize> {
    boxes: Vec<Aabb<D>>,
    norms: Vec<f64>,
}

impl<const D: usize> Moved<D> {
    fn new<'a>(tree: &Bvh<D>, u: &[f64], norm: &[f64], verts: impl Fn(u32) -> &'a [usize]) -> Self {
        Moved {
            boxes: tree.refit(|k| points_box::<D>(u, verts(k))),
            norms: tree
                .refit::<1>(|k| {
                    let m = verts(k).iter().fold(0.0f64, |m, &v| m.max(norm[v]));
                    ([m], [m])
                })
                .into_iter()
                .map(|b| b.1[0])
                .collect(),
        }
    }
}

impl<const D: usize> MotionSearch<D> {
    /// The trees of `mesh`'s contact elements at `psi` (`D` must be the mesh's dimension).
    pub fn new(mesh: &Mesh, psi: &[f64]) -> Self {
        assert_eq!(mesh.dim, D, "MotionSearch<{D}> on a {}D mesh", mesh.dim);
        let vertices = mesh.contact_vertices();
        let vboxes: Vec<Aabb<D>> = vertices.iter().map(|&v| points_box(psi, &[v])).collect();
        let eboxes: Vec<Aabb<D>> = mesh.edges.iter().map(|e| points_box(psi, e)).collect();
        let face_tree = (D == 3).then(|| {
            let fboxes: Vec<Aabb<D>> = mesh.faces.iter().map(|f| points_box(psi, f)).collect();
            Bvh::build(&fboxes)
        });
        MotionSearch {
            vertex_tree: Bvh::build(&vboxes),
            vertices,
            edge_tree: Bvh::build(&eboxes),
            face_tree,
        }
    }

    /// Every pair of disjoint contact elements with a free vertex, allowed by the mesh's
    /// contact filter, one of whose rows of T(ψ) is below `eps_qp` at `phi`, sorted by pair
    /// (the order of [`ContactPair`]). Exactly the pairs of the all-pairs mode that `phi`
    /// violates (module documentation).
    pub fn violated(&self, mesh: &Mesh, psi: &[f64], phi: &[f64], eps_qp: f64) -> Vec<PairRows> {
        self.violated_where(mesh, psi, phi, eps_qp, &|_| false, &|_| {})
    }

    /// Of [`MotionSearch::violated`]'s pairs that `skip` does not reject, per point (the
    /// vertex of a point pair, the first edge of an edge–edge pair: [`point_key`]) the one with
    /// the smallest row value at `phi` (on ties the first in pair order), sorted by pair: the
    /// lazy oracle's choice. The choice is made during the traversal, so memory is bounded by
    /// the points, not by every violated pair (which grows like the points times the pairs a
    /// point crosses).
    pub fn most_violated_per_point(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        eps_qp: f64,
        skip: &(dyn Fn(ContactPair) -> bool + Sync),
    ) -> Vec<PairRows> {
        let reduce = |out: &mut Vec<PairRows>| keep_most_violated(out, phi);
        self.violated_where(mesh, psi, phi, eps_qp, skip, &reduce)
    }

    /// The violated pairs (as [`MotionSearch::violated`]) that `skip` does not reject, with
    /// `reduce` applied as the traversal goes ([`Bvh::dual_reduced`]).
    fn violated_where(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        eps_qp: f64,
        skip: &(dyn Fn(ContactPair) -> bool + Sync),
        reduce: &(dyn Fn(&mut Vec<PairRows>) + Sync),
    ) -> Vec<PairRows> {
        self.traverse_reduced(
            mesh,
            psi,
            phi,
            eps_qp,
            &|pair, out: &mut Vec<PairRows>| {
                if skip(pair) {
                    return;
                }
                if let Some(r) = pair_rows(mesh, psi, pair) {
                    if r.min_value(phi) < eps_qp {
                        out.push(r);
                    }
                }
            },
            reduce,
        )
    }

    /// Every pair of disjoint contact elements with a free vertex, allowed by the mesh's
    /// contact filter, whose distance can fall below `thickness` somewhere on the straight
    /// motion from `psi` to `phi`, sorted by pair: the pairs with
    /// `d_ψ < thickness + max |u(p) − u(q)|` up to the boxes' looseness (a superset: the
    /// distance of two elements is 1-Lipschitz in the relative displacement of their vertices,
    /// so the others stay at least `thickness` apart along the whole motion). The broad phase
    /// of the continuous check ([`crate::contact::continuous`]) and of the linearized rows of
    /// the SQP outer method.
    pub fn candidates(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        thickness: f64,
    ) -> Vec<ContactPair> {
        self.traverse(
            mesh,
            psi,
            phi,
            thickness,
            &|pair, out: &mut Vec<ContactPair>| out.push(pair),
        )
    }

    /// The dual traversal: `emit(pair, out)` for every pair of disjoint contact elements with a
    /// free vertex, allowed by the contact filter, whose gap at ψ is at most `reach0` plus the
    /// largest relative displacement of its vertices (the test of the module documentation);
    /// the output sorted by pair.
    fn traverse<R: Send + HasPair>(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        reach0: f64,
        emit: &(dyn Fn(ContactPair, &mut Vec<R>) + Sync),
    ) -> Vec<R> {
        self.traverse_reduced(mesh, psi, phi, reach0, emit, &|_| {})
    }

    /// [`MotionSearch::traverse`] with `reduce` applied to the output of each part of the
    /// traversal ([`Bvh::dual_reduced`]) and to the whole before it is sorted.
    fn traverse_reduced<R: Send + HasPair>(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        reach0: f64,
        emit: &(dyn Fn(ContactPair, &mut Vec<R>) + Sync),
        reduce: &(dyn Fn(&mut Vec<R>) + Sync),
    ) -> Vec<R> {
        let u: Vec<f64> = phi.iter().zip(psi).map(|(a, b)| a - b).collect();
        let filter = mesh.filter();
        // One pair: first the same bound on the two elements alone (cheap), then `emit`.
        let test = |pair: ContactPair, minus: &[usize], plus: &[usize], out: &mut Vec<R>| {
            if all_fixed(mesh, pair) {
                return;
            }
            let mut reach = 0.0f64;
            for &p in plus {
                for &q in minus {
                    let mut s = 0.0;
                    for c in 0..D {
                        let d = u[D * p + c] - u[D * q + c];
                        s += d * d;
                    }
                    reach = reach.max(s);
                }
            }
            let gap = box_gap(&points_box::<D>(psi, minus), &points_box::<D>(psi, plus));
            if gap > (reach0 + reach.sqrt()) * (1.0 + SLACK) {
                return;
            }
            emit(pair, out);
        };
        let norm: Vec<f64> = u
            .chunks(D)
            .map(|w| w.iter().map(|c| c * c).sum::<f64>().sqrt())
            .collect();
        let vert_u = Moved::new(&self.vertex_tree, &u, &norm, |k| {
            std::slice::from_ref(&self.vertices[k as usize])
        });
        let edge_u = Moved::new(&self.edge_tree, &u, &norm, |k| &mesh.edges[k as usize][..]);
        // Two bounds of |u(p) − u(q)| below a node pair: the displacement boxes' reach, and
        // the sum of the largest displacements (tighter where the boxes are loose).
        let keep = |ta: &Bvh<D>, ua: &Moved<D>, tb: &Bvh<D>, ub: &Moved<D>, i: usize, j: usize| {
            let reach = box_reach(&ua.boxes[i], &ub.boxes[j]).min(ua.norms[i] + ub.norms[j]);
            box_gap(&ta.node_box(i), &tb.node_box(j)) <= (reach0 + reach) * (1.0 + SLACK)
        };
        let mut out: Vec<R> = if D == 2 {
            let (tv, te) = (&self.vertex_tree, &self.edge_tree);
            tv.dual_reduced(
                Some(te),
                &|i, j| keep(tv, &vert_u, te, &edge_u, i, j),
                &|k, a, out| {
                    let (x, a) = (self.vertices[k as usize], a as usize);
                    let e = mesh.edges[a];
                    if x == e[0] || x == e[1] || filter.is_some_and(|f| !f.point_edge(x, a)) {
                        return;
                    }
                    test(ContactPair::PointEdge { x, a }, &[x], &e, out);
                },
                reduce,
            )
        } else {
            let (tv, tf) = (&self.vertex_tree, self.face_tree.as_ref().expect("3D"));
            let face_u = Moved::new(tf, &u, &norm, |k| &mesh.faces[k as usize][..]);
            let mut out = tv.dual_reduced(
                Some(tf),
                &|i, j| keep(tv, &vert_u, tf, &face_u, i, j),
                &|k, t, out| {
                    let (x, t) = (self.vertices[k as usize], t as usize);
                    if mesh.faces[t].contains(&x) || filter.is_some_and(|f| !f.point_triangle(x, t))
                    {
                        return;
                    }
                    test(
                        ContactPair::PointTriangle { x, t },
                        &[x],
                        &mesh.faces[t],
                        out,
                    );
                },
                reduce,
            );
            let te = &self.edge_tree;
            out.extend(te.dual_reduced(
                None,
                &|i, j| keep(te, &edge_u, te, &edge_u, i, j),
                &|a, b, out| {
                    let (a, b) = ((a.min(b)) as usize, (a.max(b)) as usize);
                    let (ea, eb) = (mesh.edges[a], mesh.edges[b]);
                    if ea.iter().any(|v| eb.contains(v))
                        || filter.is_some_and(|f| !f.edge_edge(a, b))
                    {
                        return;
                    }
                    test(ContactPair::EdgeEdge { a, b }, &ea, &eb, out);
                },
                reduce,
            ));
            out
        };
        reduce(&mut out);
        out.sort_unstable_by_key(|r| r.pair());
        out
    }
}

/// The key of a pair in the lazy oracle's choice of one pair per point: the vertex of a
/// point pair, or (offset past every vertex index) the first edge of an edge–edge pair.
pub fn point_key(pair: ContactPair) -> usize {
    match pair {
        ContactPair::PointEdge { x, .. } | ContactPair::PointTriangle { x, .. } => x,
        ContactPair::EdgeEdge { a, .. } => usize::MAX / 2 + a,
    }
}

/// Keeps, of `rows`, per [`point_key`] the pair of smallest row value at `phi` (on ties the
/// smaller pair), in their order in `rows`. Applied to any prefix and then to the rest, it
/// keeps what it keeps applied once to the whole.
fn keep_most_violated(rows: &mut Vec<PairRows>, phi: &[f64]) {
    use std::collections::hash_map::Entry;
    let mut best: std::collections::HashMap<usize, (f64, usize), _> =
        std::collections::HashMap::with_capacity_and_hasher(
            rows.len(),
            std::hash::BuildHasherDefault::<super::PairHasher>::default(),
        );
    for (i, r) in rows.iter().enumerate() {
        let v = r.min_value(phi);
        match best.entry(point_key(r.pair)) {
            Entry::Vacant(e) => {
                e.insert((v, i));
            }
            Entry::Occupied(mut e) => {
                let (bv, bi) = *e.get();
                if v < bv || (v == bv && r.pair < rows[bi].pair) {
                    e.insert((v, i));
                }
            }
        }
    }
    if best.len() == rows.len() {
        return;
    }
    let mut keep: Vec<usize> = best.into_values().map(|(_, i)| i).collect();
    keep.sort_unstable();
    *rows = keep.into_iter().map(|i| rows[i]).collect();
}

/// What the traversal's outputs are sorted by.
trait HasPair {
    fn pair(&self) -> ContactPair;
}

impl HasPair for PairRows {
    fn pair(&self) -> ContactPair {
        self.pair
    }
}

impl HasPair for ContactPair {
    fn pair(&self) -> ContactPair {
        *self
    }
}

/// A [`MotionSearch`] in the mesh's dimension (2 or 3), chosen at run time.
pub enum AnyMotionSearch {
    /// A 2D mesh.
    Two(MotionSearch<2>),
    /// A 3D mesh.
    Three(MotionSearch<3>),
}

impl AnyMotionSearch {
    /// [`MotionSearch::new`] in `mesh.dim`.
    pub fn new(mesh: &Mesh, psi: &[f64]) -> AnyMotionSearch {
        if mesh.dim == 2 {
            AnyMotionSearch::Two(MotionSearch::new(mesh, psi))
        } else {
            AnyMotionSearch::Three(MotionSearch::new(mesh, psi))
        }
    }

    /// [`MotionSearch::violated`].
    pub fn violated(&self, mesh: &Mesh, psi: &[f64], phi: &[f64], eps_qp: f64) -> Vec<PairRows> {
        match self {
            AnyMotionSearch::Two(s) => s.violated(mesh, psi, phi, eps_qp),
            AnyMotionSearch::Three(s) => s.violated(mesh, psi, phi, eps_qp),
        }
    }

    /// [`MotionSearch::most_violated_per_point`].
    pub fn most_violated_per_point(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        eps_qp: f64,
        skip: &(dyn Fn(ContactPair) -> bool + Sync),
    ) -> Vec<PairRows> {
        match self {
            AnyMotionSearch::Two(s) => s.most_violated_per_point(mesh, psi, phi, eps_qp, skip),
            AnyMotionSearch::Three(s) => s.most_violated_per_point(mesh, psi, phi, eps_qp, skip),
        }
    }

    /// [`MotionSearch::candidates`].
    pub fn candidates(
        &self,
        mesh: &Mesh,
        psi: &[f64],
        phi: &[f64],
        thickness: f64,
    ) -> Vec<ContactPair> {
        match self {
            AnyMotionSearch::Two(s) => s.candidates(mesh, psi, phi, thickness),
            AnyMotionSearch::Three(s) => s.candidates(mesh, psi, phi, thickness),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{all_movable_pairs, rows_for};
    use crate::scene::mesh::{Body, BodyKind};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The violated pairs of the all-pairs rows, sorted.
    fn brute(mesh: &Mesh, psi: &[f64], phi: &[f64], eps_qp: f64) -> Vec<ContactPair> {
        let pairs = all_movable_pairs(mesh);
        let rows = rows_for(mesh, psi, &pairs).unwrap();
        let mut v: Vec<ContactPair> = rows
            .iter()
            .filter(|r| r.min_value(phi) < eps_qp)
            .map(|r| r.pair)
            .collect();
        v.sort_unstable();
        v
    }

    /// Closed polylines (2D) of `k` vertices each, on circles, some vertices fixed.
    fn rings_2d(rng: &mut ChaCha8Rng, rings: usize, k: usize) -> (Mesh, Vec<f64>) {
        let mut x = Vec::new();
        let mut edges = Vec::new();
        let mut edge_body = Vec::new();
        let mut bodies = Vec::new();
        for r in 0..rings {
            let (cx, cy) = (2.5 * r as f64, 0.3 * r as f64);
            let base = x.len() / 2;
            let noise = 0.1 * std::f64::consts::TAU / k as f64;
            for i in 0..k {
                let t = std::f64::consts::TAU * i as f64 / k as f64;
                x.push(cx + t.cos() + rng.gen_range(-noise..noise));
                x.push(cy + t.sin() + rng.gen_range(-noise..noise));
                edges.push([base + i, base + (i + 1) % k]);
                edge_body.push(r);
            }
            bodies.push(Body {
                name: format!("r{r}"),
                kind: BodyKind::Curve,
                vertices: (base..base + k).collect(),
                ..Default::default()
            });
        }
        let nv = x.len() / 2;
        let fixed = (0..nv).map(|v| v % 7 == 0).collect();
        let mesh = Mesh {
            dim: 2,
            x_ref: x.clone(),
            fixed,
            edges,
            edge_body,
            bodies,
            ..Default::default()
        };
        (mesh, x)
    }

    /// A motion: a rigid translation per body, a smooth field and a little noise, with the
    /// fixed vertices kept in place.
    fn motion(rng: &mut ChaCha8Rng, mesh: &Mesh, psi: &[f64], scale: f64) -> Vec<f64> {
        let d = mesh.dim;
        let mut phi = psi.to_vec();
        let shifts: Vec<Vec<f64>> = (0..mesh.bodies.len())
            .map(|_| (0..d).map(|_| rng.gen_range(-scale..scale)).collect())
            .collect();
        for (b, body) in mesh.bodies.iter().enumerate() {
            for &v in &body.vertices {
                if mesh.fixed[v] {
                    continue;
                }
                for c in 0..d {
                    let s = (psi[d * v + (c + 1) % d] * 3.0).sin();
                    phi[d * v + c] +=
                        shifts[b][c] + 0.3 * scale * s + rng.gen_range(-0.05..0.05) * scale;
                }
            }
        }
        phi
    }

    /// For random motions of each `scale` from `psi` and each `eps`, asserts that `search`
    /// returns exactly the all-pairs violated rows; returns how many cases had any.
    #[allow(clippy::too_many_arguments)]
    fn compare_with_brute<const D: usize>(
        search: &MotionSearch<D>,
        rng: &mut ChaCha8Rng,
        mesh: &Mesh,
        psi: &[f64],
        scales: [f64; 3],
        epss: [f64; 3],
        trial: usize,
    ) -> usize {
        let mut nonempty = 0;
        for scale in scales {
            let phi = motion(rng, mesh, psi, scale);
            for eps in epss {
                let got: Vec<ContactPair> = search
                    .violated(mesh, psi, &phi, eps)
                    .iter()
                    .map(|r| r.pair)
                    .collect();
                let want = brute(mesh, psi, &phi, eps);
                nonempty += usize::from(!want.is_empty());
                assert_eq!(got, want, "trial {trial}, scale {scale}, eps {eps}");
                // The oracle's choice made in the traversal = the choice made afterwards
                // from every violated pair (some of them skipped as carried).
                let skip = |p: ContactPair| want.binary_search(&p).is_ok_and(|i| i % 3 == 1);
                let got: Vec<ContactPair> = search
                    .most_violated_per_point(mesh, psi, &phi, eps, &skip)
                    .iter()
                    .map(|r| r.pair)
                    .collect();
                let rows: Vec<PairRows> = want
                    .iter()
                    .filter(|&&p| !skip(p))
                    .map(|&p| pair_rows(mesh, psi, p).expect("rows"))
                    .collect();
                let pick = crate::solve::outer::most_violated_per_point(
                    rows.iter().map(|r| (r.pair, r.min_value(&phi))),
                );
                let want: Vec<ContactPair> = pick.into_iter().map(|i| rows[i].pair).collect();
                assert_eq!(
                    got, want,
                    "most violated: trial {trial}, scale {scale}, eps {eps}"
                );
            }
        }
        nonempty
    }

    #[test]
    fn motion_2d_finds_exactly_the_violated_all_pairs_rows() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut nonempty = 0;
        for trial in 0..30 {
            let (mesh, psi) = rings_2d(&mut rng, 3, 12 + trial);
            let search = MotionSearch::<2>::new(&mesh, &psi);
            nonempty += compare_with_brute(
                &search,
                &mut rng,
                &mesh,
                &psi,
                [0.01, 0.3, 1.5],
                [1e-3, 0.05, 0.4],
                trial,
            );
        }
        assert!(nonempty > 100, "too few motions violate a row: {nonempty}");
    }

    #[test]
    fn motion_3d_finds_exactly_the_violated_all_pairs_rows() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let mut nonempty = 0;
        for trial in 0..12 {
            // two triangulated sheets of k×k squares, stacked and shifted
            let k = 3 + trial % 3;
            let mut x = Vec::new();
            let mut faces = Vec::new();
            let mut bodies = Vec::new();
            let mut face_body = Vec::new();
            for s in 0..2 {
                let base = x.len() / 3;
                for i in 0..=k {
                    for j in 0..=k {
                        x.push(i as f64 / k as f64 + 0.13 * s as f64);
                        x.push(j as f64 / k as f64 - 0.07 * s as f64);
                        x.push(0.3 * s as f64 + rng.gen_range(-0.01..0.01));
                    }
                }
                let id = |i: usize, j: usize| base + i * (k + 1) + j;
                for i in 0..k {
                    for j in 0..k {
                        faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                        faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                        face_body.extend([s, s]);
                    }
                }
                bodies.push(Body {
                    name: format!("s{s}"),
                    kind: BodyKind::Surface,
                    vertices: (base..base + (k + 1) * (k + 1)).collect(),
                    ..Default::default()
                });
            }
            let mut edges: Vec<[usize; 2]> = Vec::new();
            let mut edge_body = Vec::new();
            for (f, b) in faces.iter().zip(&face_body) {
                for (p, q) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
                    let e = [p.min(q), p.max(q)];
                    if !edges.contains(&e) {
                        edges.push(e);
                        edge_body.push(*b);
                    }
                }
            }
            let nv = x.len() / 3;
            let mesh = Mesh {
                dim: 3,
                x_ref: x.clone(),
                fixed: (0..nv).map(|v| v % 5 == 0).collect(),
                edges,
                edge_body,
                triangles: faces.clone(),
                faces,
                face_body,
                bodies,
                ..Default::default()
            };
            let search = MotionSearch::<3>::new(&mesh, &x);
            nonempty += compare_with_brute(
                &search,
                &mut rng,
                &mesh,
                &x,
                [0.01, 0.2, 0.8],
                [1e-3, 0.05, 0.2],
                trial,
            );
        }
        assert!(nonempty > 40, "too few motions violate a row: {nonempty}");
    }

    #[test]
    fn motion_ignores_elements_moving_together() {
        // a ring translated far as a whole violates none of its self-contact rows
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let (mut mesh, psi) = rings_2d(&mut rng, 1, 200);
        mesh.fixed = vec![false; mesh.nv()];
        let phi: Vec<f64> = psi
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 2 == 0 { 7.0 } else { -3.0 })
            .collect();
        let search = MotionSearch::<2>::new(&mesh, &psi);
        // admissible at ψ, so that φ (a translate of ψ) violates nothing
        assert!(crate::contact::min_distance(&mesh, &psi, 0.1, false).distance > 1e-3);
        assert!(search.violated(&mesh, &psi, &phi, 1e-3).is_empty());
        assert!(brute(&mesh, &psi, &phi, 1e-3).is_empty());
    }
}
