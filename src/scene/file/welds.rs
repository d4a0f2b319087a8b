//! Welds (`weld`): vertices of different bodies that are one vertex of the mesh.

use super::schema::WeldSpec;
use super::{Ctx, Loaded, SceneFileError, WELD_TOL};
use toml::Spanned;

impl Ctx<'_> {
    /// The global vertex of each body's local vertex, and which bodies share a vertex
    /// (row-major `nb × nb`). Vertices are numbered body by body in file order; the welds
    /// merge vertices into classes (chains `a~b, b~c` into one, a cycle's closing weld is
    /// redundant), and a class takes the number of its first occurrence. Each weld must name
    /// existing bodies and vertices, two vertices at the same position (to
    /// [`WELD_TOL`] × the longer longest edge of the two bodies, in the reference and the
    /// initial configuration), and may not merge two vertices of one body, directly or
    /// through a chain.
    #[allow(clippy::type_complexity)]
    pub(super) fn resolve_welds(
        &self,
        welds: &[Spanned<WeldSpec>],
        loaded: &[Loaded],
    ) -> Result<(Vec<Vec<usize>>, Vec<bool>), SceneFileError> {
        let nb = loaded.len();
        let mut offsets = Vec::with_capacity(nb + 1);
        offsets.push(0);
        for l in loaded {
            offsets.push(offsets.last().copied().unwrap_or(0) + l.x_ref.len());
        }
        let total = offsets[nb];
        let names: Vec<&str> = loaded.iter().map(|l| l.name.as_str()).collect();
        let h: Vec<f64> = loaded
            .iter()
            .map(|l| {
                let mut h: f64 = 0.0;
                for e in &l.elems {
                    for a in 0..l.arity {
                        for b in a + 1..l.arity {
                            let d = (0..3)
                                .map(|c| (l.x_ref[e[a]][c] - l.x_ref[e[b]][c]).powi(2))
                                .sum::<f64>();
                            h = h.max(d.sqrt());
                        }
                    }
                }
                h
            })
            .collect();
        // union–find over (body, local vertex), the root of a class its smallest member
        let mut parent: Vec<usize> = (0..total).collect();
        let mut members: Vec<Vec<(usize, usize)>> = (0..nb)
            .flat_map(|b| (0..loaded[b].x_ref.len()).map(move |k| vec![(b, k)]))
            .collect();
        fn find(parent: &mut [usize], mut v: usize) -> usize {
            while parent[v] != v {
                parent[v] = parent[parent[v]];
                v = parent[v];
            }
            v
        }
        let mut welded = vec![false; nb * nb];
        for (k, w) in welds.iter().enumerate() {
            let line = self.line(w.span().start);
            let (a, i, b, j) = w.get_ref();
            let key = format!("weld[{k}]");
            let value = format!("[{a:?}, {i}, {b:?}, {j}]");
            let body = |n: &str| {
                names.iter().position(|m| *m == n).ok_or_else(|| {
                    self.invalid(
                        line,
                        &key,
                        &value,
                        format!("no body is named {n:?} (bodies: {})", names.join(", ")),
                    )
                })
            };
            let (ba, bb) = (body(a)?, body(b)?);
            for (bi, v) in [(ba, *i), (bb, *j)] {
                let nv = loaded[bi].x_ref.len();
                if v < 0 || v as u64 >= nv as u64 {
                    return Err(self.invalid(
                        line,
                        &key,
                        &value,
                        format!(
                            "body {:?} has no vertex {v} (it has {nv}, numbered from 0)",
                            names[bi]
                        ),
                    ));
                }
            }
            let (i, j) = (*i as usize, *j as usize);
            if ba == bb {
                return Err(self.invalid(
                    line,
                    &key,
                    &value,
                    format!(
                        "welds body {:?} to itself: a weld joins vertices of two different \
                         bodies (merge the vertices in the body's own mesh instead)",
                        names[ba]
                    ),
                ));
            }
            let tol = WELD_TOL * h[ba].max(h[bb]);
            for (conf, pa, pb) in [
                ("reference", &loaded[ba].x_ref[i], &loaded[bb].x_ref[j]),
                ("initial", &loaded[ba].x0[i], &loaded[bb].x0[j]),
            ] {
                let d = (0..3).map(|c| (pa[c] - pb[c]).powi(2)).sum::<f64>().sqrt();
                if d.is_nan() || d > tol {
                    return Err(self.invalid(
                        line,
                        &key,
                        &value,
                        format!(
                            "the two vertices are at distance {d:e} > {tol:e} in the {conf} \
                             configuration ({pa:?} and {pb:?}); welded vertices must coincide \
                             (tolerance {WELD_TOL:e} × the longer of the two bodies' longest \
                             edges)"
                        ),
                    ));
                }
            }
            welded[ba * nb + bb] = true;
            welded[bb * nb + ba] = true;
            let (ra, rb) = (
                find(&mut parent, offsets[ba] + i),
                find(&mut parent, offsets[bb] + j),
            );
            if ra == rb {
                continue; // already one vertex (a chain closed into a cycle, or a repeat)
            }
            // two vertices of one body in the merged class: the body would fold onto itself
            for &(b1, k1) in &members[ra] {
                if let Some(&(_, k2)) = members[rb].iter().find(|&&(b2, _)| b2 == b1) {
                    return Err(self.invalid(
                        line,
                        &key,
                        &value,
                        format!(
                            "merges vertices {k1} and {k2} of body {:?} (through a chain of \
                             welds): a weld joins vertices of two different bodies, at most \
                             one vertex of each body",
                            names[b1]
                        ),
                    ));
                }
            }
            let (root, other) = (ra.min(rb), ra.max(rb));
            parent[other] = root;
            let moved = std::mem::take(&mut members[other]);
            members[root].extend(moved);
        }
        // numbering: body by body; a class takes the number of its first (smallest) member
        let mut number = vec![usize::MAX; total];
        let mut next = 0;
        for f in 0..total {
            let r = find(&mut parent, f);
            if r == f {
                number[f] = next;
                next += 1;
            } else {
                number[f] = number[r];
            }
        }
        let global = (0..nb)
            .map(|b| number[offsets[b]..offsets[b + 1]].to_vec())
            .collect();
        Ok((global, welded))
    }
}
