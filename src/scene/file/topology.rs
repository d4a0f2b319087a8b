//! Boundaries and chains of element lists: the boundary edges of a 2D triangle mesh, the
//! outward boundary faces of a tetrahedral mesh, the vertex order along a curve.

use std::collections::{BTreeMap, HashMap};

/// Edges of exactly one triangle (the boundary of a 2D triangle mesh), as stored in their
/// triangle, sorted.
pub(crate) fn boundary_edges(tris: &[[usize; 3]]) -> Vec<[usize; 2]> {
    let mut count: HashMap<[usize; 2], ([usize; 2], usize)> = HashMap::new();
    for t in tris {
        for k in 0..3 {
            let e = [t[k], t[(k + 1) % 3]];
            let key = [e[0].min(e[1]), e[0].max(e[1])];
            count.entry(key).or_insert((e, 0)).1 += 1;
        }
    }
    let mut out: Vec<[usize; 2]> = count
        .into_values()
        .filter(|&(_, c)| c == 1)
        .map(|(e, _)| e)
        .collect();
    out.sort_unstable();
    out
}

/// Faces of exactly one (positively oriented) tetrahedron, oriented outward, sorted.
pub(crate) fn boundary_faces(tets: &[[usize; 4]]) -> Vec<[usize; 3]> {
    let mut count: HashMap<[usize; 3], ([usize; 3], usize)> = HashMap::new();
    for t in tets {
        // outward faces of a positive tet [0, 1, 2, 3]
        for f in [
            [t[1], t[2], t[3]],
            [t[0], t[3], t[2]],
            [t[0], t[1], t[3]],
            [t[0], t[2], t[1]],
        ] {
            let mut key = f;
            key.sort_unstable();
            count.entry(key).or_insert((f, 0)).1 += 1;
        }
    }
    let mut out: Vec<[usize; 3]> = count
        .into_values()
        .filter(|&(_, c)| c == 1)
        .map(|(f, _)| f)
        .collect();
    out.sort_unstable();
    out
}

/// The vertices of a curve (its edges `els`) in order along it: a simple path (closed by its
/// chord) or a simple cycle.
pub(crate) fn chain(els: &[[usize; 2]]) -> Result<Vec<usize>, String> {
    let mut adj: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for e in els {
        adj.entry(e[0]).or_default().push(e[1]);
        adj.entry(e[1]).or_default().push(e[0]);
    }
    if let Some((v, n)) = adj.iter().find(|(_, n)| n.len() > 2) {
        return Err(format!(
            "the curve must be one simple path or cycle, but vertex {v} has {} neighbours",
            n.len()
        ));
    }
    // a path starts at its smaller end; a cycle at the first element's first vertex, following
    // the elements' direction
    let start = adj
        .iter()
        .find(|(_, n)| n.len() == 1)
        .map_or(els[0][0], |(&v, _)| v);
    let mut order = vec![start];
    let (mut prev, mut cur) = (None, start);
    while order.len() <= adj.len() {
        match adj[&cur].iter().copied().find(|&w| Some(w) != prev) {
            Some(w) if w != start => {
                order.push(w);
                prev = Some(cur);
                cur = w;
            }
            _ => break,
        }
    }
    if order.len() != adj.len() {
        return Err(format!(
            "the curve must be one connected path or cycle, but only {} of its {} vertices \
             are reached from vertex {start}",
            order.len(),
            adj.len()
        ));
    }
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenefile_chain_orders_paths_and_cycles() {
        let c = |v: &[[usize; 2]]| chain(v);
        assert_eq!(
            c(&[[0, 1], [1, 2], [2, 3], [3, 0]]).unwrap(),
            vec![0, 1, 2, 3]
        );
        assert_eq!(c(&[[2, 1], [1, 0], [3, 2]]).unwrap(), vec![0, 1, 2, 3]);
        assert!(c(&[[0, 1], [2, 3]]).unwrap_err().contains("connected"));
        assert!(c(&[[0, 1], [0, 2], [0, 3]])
            .unwrap_err()
            .contains("3 neighbours"));
    }

    #[test]
    fn scenefile_boundary_faces_of_a_cube_corner() {
        // one positive tet: all four faces are boundary, outward
        let x = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let faces = boundary_faces(&[[0, 1, 2, 3]]);
        assert_eq!(faces.len(), 4);
        let p = |v: usize| nalgebra::Vector3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
        let centre = (p(0) + p(1) + p(2) + p(3)) / 4.0;
        for f in faces {
            let n = (p(f[1]) - p(f[0])).cross(&(p(f[2]) - p(f[0])));
            assert!(n.dot(&(p(f[0]) - centre)) > 0.0, "{f:?} points inward");
        }
        // two tets sharing a face: 6 boundary faces
        assert_eq!(boundary_faces(&[[0, 1, 2, 3], [1, 2, 3, 4]]).len(), 6);
        assert_eq!(
            boundary_edges(&[[0, 1, 2], [0, 2, 3]]),
            vec![[0, 1], [1, 2], [2, 3], [3, 0]]
        );
    }
}
