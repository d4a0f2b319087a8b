//! The 3D gas region: a closed, consistently oriented surface of P1 triangles
//! `T = (x_a, x_b, x_c)`, and the volume it encloses.
//!
//! By the divergence theorem the signed volume is
//!
//! ```text
//! V(x) = Σ_T det(x_a − o, x_b − o, x_c − o) / 6 = Σ_T (x_a − o) · ((x_b − o) × (x_c − o)) / 6,
//! ```
//!
//! for any point `o`: on a closed surface (every directed edge `a → b` is matched by an edge
//! `b → a`) the terms in `o` cancel, and with `o = 0` this is `Σ_T x_a · (x_b × x_c) / 6`. The
//! triangles are oriented at construction so that `V(x0) > 0` (all reversed if needed: outward
//! normals). The terms are evaluated relative to the centroid `o` of the surface vertices at
//! `x`: the sums are then translation invariant and well conditioned (with `o = 0`, a body far
//! from the origin would make `Σ_T x_a · (x_b × x_c)` cancel large terms), and so is the
//! projected Hessian below (its triangle blocks depend on `y = x − o`). Since `V` does not
//! depend on `o`, the derivatives are taken with `o` fixed:
//!
//! ```text
//! ∂V/∂x_a = (y_b × y_c)/6 (and cyclically),   y = x − o.
//! ```
//!
//! The second-derivative part `−C/V ∇²V` of the gas Hessian ([`super`]) is a sum over the
//! triangles: triangle `T` couples its 9 dofs through the block `M_T = −C/V ∇²V_T`, whose 3×3
//! sub-blocks are
//!
//! ```text
//! (∇²V_T)_{pq} = ε(p, q, r) [y_r]ₓᵀ / 6   (p ≠ q, r the third corner),   (∇²V_T)_{pp} = 0,
//! ```
//!
//! with `ε(p, q, r) = ±1` the sign of the permutation of the corners and `[y]ₓ` the cross
//! product matrix (`[y]ₓ z = y × z`). `M_T` has a zero diagonal, so (unless it vanishes) it is
//! indefinite; with `projected = true` each `M_T` is replaced by its positive semi-definite
//! part (symmetric eigendecomposition, negative eigenvalues clamped to zero,
//! `energy::project_psd`), as [`super::area`] does with its shoelace blocks.
//!
//! Assembly follows the conventions of [`crate::energy`]: the centroid and the volume are
//! chunked sums, `∇V` is scatter-added per triangle in triangle order, the Hessian triplets
//! are produced in chunks in triangle order; all bit-identical for any thread count.

use super::Region;
use crate::energy::membrane3d::Matrix9;
use crate::energy::{chunked_sum, chunked_triplets, par_scatter, project_psd, push_block, Hessian};
use std::collections::HashMap;

const DIM: usize = 3;

/// A closed triangulated surface, oriented so that its volume at construction is positive.
#[derive(Clone, Debug)]
pub struct ClosedSurface {
    /// Triangles, oriented so that the volume at the construction configuration is positive.
    triangles: Vec<[usize; 3]>,
    /// The surface's vertices, increasing.
    vertices: Vec<usize>,
    /// The triangles' corners as indices into `vertices`.
    local: Vec<[usize; 3]>,
}

/// An edge of `triangles` that is not matched by an opposite one (`[a, b]` with more
/// occurrences of `a → b` than of `b → a`), the smallest such `(min, max)` pair; `None` if
/// the surface is closed and consistently oriented. Edges `a → a` (of degenerate triangles)
/// are ignored: they contribute nothing to the volume.
pub fn open_edge(triangles: &[[usize; 3]]) -> Option<[usize; 2]> {
    let mut count: HashMap<(usize, usize), i64> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                *count.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
            }
        }
    }
    count
        .into_iter()
        .filter(|&(_, n)| n != 0)
        .min_by_key(|&(e, _)| e)
        .map(|((a, b), n)| if n > 0 { [a, b] } else { [b, a] })
}

/// The gas surface is not closed and consistently oriented: edge `a → b` has no opposite edge.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("gas surface is not closed and consistently oriented: edge {a} -> {b} has no opposite edge {b} -> {a}")]
pub struct OpenSurface {
    /// First vertex of the unmatched edge.
    pub a: usize,
    /// Second vertex.
    pub b: usize,
}

impl ClosedSurface {
    /// The surface, reversing every triangle if the volume at `x0` is negative, so that
    /// `V(x0) ≥ 0` (outward normals).
    ///
    /// A surface that is not closed and consistently oriented (see [`open_edge`]) is an
    /// error naming the unmatched edge: `V` would not be a volume.
    pub fn new(triangles: Vec<[usize; 3]>, x0: &[f64]) -> Result<Self, OpenSurface> {
        if let Some([a, b]) = open_edge(&triangles) {
            return Err(OpenSurface { a, b });
        }
        let mut vertices: Vec<usize> = triangles.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let pos: HashMap<usize, usize> =
            vertices.iter().enumerate().map(|(l, &v)| (v, l)).collect();
        let local = triangles.iter().map(|t| t.map(|v| pos[&v])).collect();
        let mut s = Self {
            triangles,
            vertices,
            local,
        };
        if s.volume(x0) < 0.0 {
            for (t, l) in s.triangles.iter_mut().zip(s.local.iter_mut()) {
                t.swap(1, 2);
                l.swap(1, 2);
            }
        }
        Ok(s)
    }

    /// The triangles, in their stored (outward) orientation.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// The surface's vertices, increasing.
    pub fn vertices(&self) -> &[usize] {
        &self.vertices
    }

    /// The centroid `o` of the surface vertices at `x` (chunked sums).
    fn origin(&self, x: &[f64]) -> [f64; DIM] {
        let n = self.vertices.len();
        std::array::from_fn(|k| {
            let s = chunked_sum(n, |r| {
                let mut s = 0.0;
                for l in r {
                    s += x[DIM * self.vertices[l] + k];
                }
                s
            });
            s / n.max(1) as f64
        })
    }

    /// `y_p = x_p − o` for the corners of triangle `t`.
    #[inline]
    fn corners(&self, x: &[f64], o: &[f64; DIM], t: usize) -> [[f64; DIM]; 3] {
        self.triangles[t].map(|v| std::array::from_fn(|k| x[DIM * v + k] - o[k]))
    }

    /// Signed volume `V(x)` (positive in the reference orientation).
    pub fn volume(&self, x: &[f64]) -> f64 {
        let o = self.origin(x);
        let s = chunked_sum(self.triangles.len(), |r| {
            let mut s = 0.0;
            for t in r {
                let [a, b, c] = self.corners(x, &o, t);
                s += dot(&a, &cross(&b, &c));
            }
            s
        });
        s / 6.0
    }

    /// `∇V(x)` as sparse `(dof, value)` pairs, by increasing vertex (the three dofs of each
    /// vertex of [`ClosedSurface::vertices`] in turn).
    pub fn volume_gradient(&self, x: &[f64]) -> Vec<(usize, f64)> {
        let o = self.origin(x);
        let mut buf = vec![0.0; DIM * self.vertices.len()];
        par_scatter(
            self.triangles.len(),
            &mut buf,
            |t| {
                let [a, b, c] = self.corners(x, &o, t);
                Some([cross(&b, &c), cross(&c, &a), cross(&a, &b)])
            },
            |t, w, buf| {
                for (p, &l) in self.local[t].iter().enumerate() {
                    for k in 0..DIM {
                        buf[DIM * l + k] += w[p][k] / 6.0;
                    }
                }
            },
        );
        self.vertices
            .iter()
            .flat_map(|&v| (0..DIM).map(move |k| DIM * v + k))
            .zip(buf)
            .collect()
    }

    /// The 9×9 block `k ∇²V_T` of triangle `t` (`y` relative to `o`).
    fn triangle_block(&self, x: &[f64], o: &[f64; DIM], t: usize, k: f64) -> Matrix9 {
        let y = self.corners(x, o, t);
        let mut m = Matrix9::zeros();
        for p in 0..3 {
            for q in 0..3 {
                if p == q {
                    continue;
                }
                let r = 3 - p - q;
                // ε(p, q, r) = +1 for the cyclic orders (0,1,2), (1,2,0), (2,0,1)
                let sign = if q == (p + 1) % 3 { k } else { -k };
                // (ε_ijl y_r,l) = [y_r]ₓᵀ
                let yr = &y[r];
                let c = [
                    [0.0, yr[2], -yr[1]],
                    [-yr[2], 0.0, yr[0]],
                    [yr[1], -yr[0], 0.0],
                ];
                for i in 0..DIM {
                    for j in 0..DIM {
                        m[(DIM * p + i, DIM * q + j)] = sign * c[i][j] / 6.0;
                    }
                }
            }
        }
        m
    }
}

#[inline]
fn cross(a: &[f64; DIM], b: &[f64; DIM]) -> [f64; DIM] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn dot(a: &[f64; DIM], b: &[f64; DIM]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Region for ClosedSurface {
    const NAME: &'static str = "gas3d";

    fn measure(&self, x: &[f64]) -> f64 {
        self.volume(x)
    }

    fn measure_gradient(&self, x: &[f64]) -> Vec<(usize, f64)> {
        self.volume_gradient(x)
    }

    /// The triangle blocks `−C/V ∇²V_T` (module docs), each projected by eigendecomposition
    /// if asked.
    fn add_measure_hessian(&self, x: &[f64], c: f64, v: f64, projected: bool, h: &mut Hessian) {
        let o = self.origin(x);
        let k = -c / v;
        chunked_triplets(self.triangles.len(), &mut h.triplets, |t, out| {
            let mut m = self.triangle_block(x, &o, t, k);
            if projected {
                project_psd(&mut m);
            }
            push_block(out, DIM, &self.triangles[t], |r, c| m[(r, c)]);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::fd_test::{fd_gradient, fd_hessian, rel};
    use crate::energy::gas::Gas3dEnergy;
    use crate::energy::{Energy, TermKind};
    use nalgebra::{Rotation3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A UV sphere of radius `r` centred at `center`: poles and `nlat − 1` rings of `nlon`
    /// vertices, `2 (nlat − 1) nlon` triangles with outward normals, each vertex moved by a
    /// random amount `< noise` per coordinate. Returns `(x, triangles)`.
    fn sphere(
        rng: &mut ChaCha8Rng,
        nlat: usize,
        nlon: usize,
        r: f64,
        center: [f64; 3],
        noise: f64,
    ) -> (Vec<f64>, Vec<[usize; 3]>) {
        use std::f64::consts::PI;
        let mut x = vec![0.0, 0.0, r];
        for j in 1..nlat {
            let th = PI * j as f64 / nlat as f64;
            for i in 0..nlon {
                let ph = 2.0 * PI * i as f64 / nlon as f64;
                x.extend([
                    r * th.sin() * ph.cos(),
                    r * th.sin() * ph.sin(),
                    r * th.cos(),
                ]);
            }
        }
        x.extend([0.0, 0.0, -r]);
        for p in x.chunks_mut(3) {
            for k in 0..3 {
                p[k] += center[k] + rng.gen_range(-noise..noise);
            }
        }
        let ring = |j: usize, i: usize| 1 + (j - 1) * nlon + i % nlon;
        let south = 1 + (nlat - 1) * nlon;
        let mut tris = Vec::with_capacity(2 * (nlat - 1) * nlon);
        for i in 0..nlon {
            tris.push([0, ring(1, i), ring(1, i + 1)]);
        }
        for j in 1..nlat - 1 {
            for i in 0..nlon {
                let (a, b, c, d) = (
                    ring(j, i),
                    ring(j + 1, i),
                    ring(j + 1, i + 1),
                    ring(j, i + 1),
                );
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        for i in 0..nlon {
            tris.push([south, ring(nlat - 1, i + 1), ring(nlat - 1, i)]);
        }
        (x, tris)
    }

    /// A perturbed 4×5 UV sphere off the origin (radius in `[0.5, 1.5]`), listed outward or
    /// inward, plus an unused extra vertex to check sparsity.
    fn config(rng: &mut ChaCha8Rng, reverse: bool) -> (Gas3dEnergy, Vec<f64>) {
        let r = rng.gen_range(0.5..1.5);
        let (mut x, mut tris) = sphere(rng, 4, 5, r, [0.3, -0.2, 0.5], 0.05 * r);
        x.extend([5.0, -3.0, 2.0]);
        if reverse {
            for t in tris.iter_mut() {
                t.swap(0, 1);
            }
        }
        let gas = Gas3dEnergy::new(tris, rng.gen_range(0.5..3.0), &x).unwrap();
        (gas, x)
    }

    /// The surface of the unit cube `[0, 1]³`, 12 triangles with outward normals.
    fn cube_surface() -> (Vec<f64>, Vec<[usize; 3]>) {
        let mut x = Vec::new();
        for v in 0..8 {
            x.extend([(v & 1) as f64, ((v >> 1) & 1) as f64, ((v >> 2) & 1) as f64]);
        }
        let quads = [
            [0, 2, 3, 1], // z = 0
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let mut tris = Vec::new();
        for [a, b, c, d] in quads {
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
        (x, tris)
    }

    #[test]
    fn energy_gas3d_orientation_and_known_volumes() {
        let (x, tris) = cube_surface();
        let gas = Gas3dEnergy::new(tris.clone(), 2.0, &x).unwrap();
        assert_eq!((gas.name(), gas.kind()), ("gas3d", TermKind::Elastic));
        assert_eq!(gas.region.triangles(), &tris[..]);
        assert_eq!(gas.region.vertices(), &(0..8).collect::<Vec<_>>()[..]);
        assert!((gas.region.volume(&x) - 1.0).abs() < 1e-15);
        assert!(gas.value(&x).abs() < 1e-15);
        // inward-listed: reversed at construction
        let inward: Vec<[usize; 3]> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let gas = Gas3dEnergy::new(inward.clone(), 2.0, &x).unwrap();
        assert_eq!(gas.region.triangles(), &tris[..]);
        assert!((gas.region.volume(&x) - 1.0).abs() < 1e-15);
        // scaled by 2 and translated far away: V = 8, J = −C ln 8
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| 2.0 * v + 1e3 * (i % 3) as f64)
            .collect();
        assert!((gas.region.volume(&y) - 8.0).abs() < 1e-12);
        assert!((gas.value(&y) + 2.0 * 8f64.ln()).abs() < 1e-12);
        // the regular tetrahedron inscribed in [−1, 1]³: V = 8/3
        let xt = [
            1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0, -1.0, -1.0, -1.0, 1.0,
        ];
        let tets = vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]];
        for rev in [false, true] {
            let t = if rev {
                tets.iter().map(|t| [t[1], t[0], t[2]]).collect()
            } else {
                tets.clone()
            };
            let gas = Gas3dEnergy::new(t, 1.5, &xt).unwrap();
            assert!((gas.region.volume(&xt) - 8.0 / 3.0).abs() < 1e-15);
            assert!((gas.value(&xt) + 1.5 * (8.0f64 / 3.0).ln()).abs() < 1e-15);
        }
    }

    #[test]
    fn energy_gas3d_open_surface() {
        let (_, mut tris) = cube_surface();
        assert_eq!(open_edge(&tris), None);
        let t = tris.pop().unwrap();
        let e = open_edge(&tris).unwrap();
        assert!(
            [[t[1], t[0]], [t[2], t[1]], [t[0], t[2]]].contains(&e),
            "{e:?} {t:?}"
        );
        // an inconsistently oriented triangle
        tris.push([t[0], t[2], t[1]]);
        assert!(open_edge(&tris).is_some());
        // without the face x = 1 (quad 1 → 3 → 7 → 5): its edges are unmatched
        assert_eq!(open_edge(&tris[..10]), Some([3, 1]));
    }

    #[test]
    fn energy_gas3d_open_surface_is_an_error() {
        let (x, tris) = cube_surface();
        let e = Gas3dEnergy::new(tris[1..].to_vec(), 1.0, &x).unwrap_err();
        assert!(e.to_string().contains("not closed"), "{e}");
    }

    #[test]
    fn energy_gas3d_gradient_fd() {
        // central differences, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(50);
        for k in 0..16 {
            let (gas, x) = config(&mut rng, k % 2 == 1);
            let mut g = vec![0.0; x.len()];
            gas.add_gradient(&x, &mut g);
            let gf = fd_gradient(&gas, &x, 1e-6);
            assert!(rel(&g, &gf) <= 1e-5, "rel {}", rel(&g, &gf));
            // volume gradient on its own
            let mut xp = x.clone();
            for (dof, w) in gas.region.volume_gradient(&x) {
                xp[dof] += 1e-6;
                let vp = gas.region.volume(&xp);
                xp[dof] = x[dof] - 1e-6;
                let vm = gas.region.volume(&xp);
                xp[dof] = x[dof];
                assert!(((vp - vm) / 2e-6 - w).abs() <= 1e-8);
            }
        }
    }

    #[test]
    fn energy_gas3d_hessian_fd_and_projection_psd() {
        // central differences of the gradient, step 1e-6; relative error ≤ 1e-5
        let mut rng = ChaCha8Rng::seed_from_u64(51);
        for k in 0..16 {
            let (gas, x) = config(&mut rng, k % 2 == 1);
            let n = x.len();
            let mut h = Hessian::default();
            gas.add_hessian(&x, false, &mut h);
            assert_eq!(h.rank_one.len(), 1);
            assert!(h.rank_one[0].coef >= 0.0);
            let hd = h.to_dense(n);
            let hf = fd_hessian(&gas, &x, 1e-6);
            let r = rel(hd.as_slice(), hf.as_slice());
            assert!(r <= 1e-5, "rel {r}");
            let mut hp = Hessian::default();
            gas.add_hessian(&x, true, &mut hp);
            assert_eq!(hp.rank_one, h.rank_one);
            let hpd = hp.to_dense(n);
            assert!((&hpd - hpd.transpose()).norm() <= 1e-14 * hpd.norm());
            let scale = hpd.norm().max(1.0);
            let ev = hpd.symmetric_eigenvalues();
            assert!(ev.min() >= -1e-10 * scale, "min eig {}", ev.min());
            // the sparse part alone is PSD too (the exact one is not)
            let sp = Hessian {
                triplets: hp.triplets.clone(),
                rank_one: vec![],
            };
            let ev = sp.to_dense(n).symmetric_eigenvalues();
            assert!(ev.min() >= -1e-10 * scale);
            let se = Hessian {
                triplets: h.triplets.clone(),
                rank_one: vec![],
            };
            assert!(se.to_dense(n).symmetric_eigenvalues().min() < -1e-3 * scale);
            // the unused vertex has no entries
            assert!(hp.triplets.iter().all(|t| t.0 < n - 3 && t.1 < n - 3));
            assert!(h.rank_one[0].w.iter().all(|w| w.0 < n - 3));
        }
    }

    #[test]
    fn energy_gas3d_rigid_invariant() {
        let mut rng = ChaCha8Rng::seed_from_u64(52);
        let (gas, x) = config(&mut rng, false);
        let rot = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let t = Vector3::new(1.0, -2.0, 0.5);
        let mut y = x.clone();
        for (p, q) in y.chunks_mut(3).zip(x.chunks(3)) {
            let z = rot * Vector3::new(q[0], q[1], q[2]) + t;
            p.copy_from_slice(z.as_slice());
        }
        let (v0, v1) = (gas.region.volume(&x), gas.region.volume(&y));
        assert!(((v1 - v0) / v0).abs() < 1e-12, "{v0} {v1}");
        let (j0, j1) = (gas.value(&x), gas.value(&y));
        assert!((j1 - j0).abs() < 1e-12 * gas.c.max(j0.abs()), "{j0} {j1}");
    }

    #[test]
    fn energy_gas3d_nonpositive_volume_is_infinite() {
        let x0 = [
            1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0, -1.0, -1.0, -1.0, 1.0,
        ];
        let g =
            Gas3dEnergy::new(vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]], 1.0, &x0).unwrap();
        // reflected through z = 0: negative volume
        let mut x = x0;
        for k in 0..4 {
            x[3 * k + 2] = -x[3 * k + 2];
        }
        assert!(g.region.volume(&x) < 0.0);
        assert_eq!(g.value(&x), f64::INFINITY);
        let mut gr = vec![0.0; 12];
        g.add_gradient(&x, &mut gr);
        assert_eq!(gr, vec![0.0; 12]);
        let mut h = Hessian::default();
        g.add_hessian(&x, true, &mut h);
        assert!(h.triplets.is_empty() && h.rank_one.is_empty());
        // flattened into z = 0: zero volume
        for k in 0..4 {
            x[3 * k + 2] = 0.0;
        }
        assert_eq!(g.value(&x), f64::INFINITY);
        assert!(g.value(&x0).is_finite());
    }

    #[test]
    fn energy_gas3d_thread_independent() {
        use crate::energy::fd_test::{assert_thread_independent, term_bits};
        use crate::energy::CHUNK;
        let mut rng = ChaCha8Rng::seed_from_u64(53);
        for reverse in [false, true] {
            let (x, mut tris) = sphere(&mut rng, 40, 64, 1.0, [0.3, -0.2, 0.5], 0.01);
            assert!(tris.len() > CHUNK);
            if reverse {
                tris.reverse();
                for t in tris.iter_mut() {
                    t.swap(1, 2);
                }
            }
            let gas = Gas3dEnergy::new(tris, 1.7, &x).unwrap();
            let bits = assert_thread_independent(|| term_bits(&gas, &x));
            assert!(f64::from_bits(bits[0]).is_finite());
            let v = 4.0 / 3.0 * std::f64::consts::PI;
            assert!(((gas.region.volume(&x) - v) / v).abs() < 0.01);
        }
    }
}
