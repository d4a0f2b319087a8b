//! Energies `J`: value, gradient and a sparse Hessian (optionally projected to be positive
//! semi-definite, element by element).
//!
//! All functions take the flat position vector `x` (`dim` coordinates per vertex) and use the
//! degree-of-freedom numbering `dim*v + k` of [`crate::scene::mesh`].
//!
//! # The terms
//!
//! Each term implements [`Energy`]; its module documents its formulas. Where the formulas
//! allow it a term is one type generic over the dimension `D`, with the per-dimension part
//! kept as small as possible:
//!
//! * [`membrane::TensionString`]`<D>`: tension-only strings and membranes of P1 edges
//!   ([`MembraneEnergy`] in 2D, [`String3dEnergy`] in 3D);
//! * [`P1Solid`]`<D, N, L>`: P1 simplices (triangles, tetrahedra) with a stored energy law
//!   `L` ([`Law`]): the compressible neo-Hookean [`NeoHookean`]`<D, N>` ([`NeoHookean2d`] in
//!   plane strain, [`NeoHookeanPlaneStress2d`], [`NeoHookean3d`]) and the small-strain
//!   [`LinearElastic2d`] (plane strain or stress) and [`LinearElastic3d`]; [`Elasticity`] and
//!   [`Plane`] (in `material`) convert E, ν and give the plane-stress constants;
//! * [`DeadLoad`]: point forces, tractions and pressures on solids' boundaries (dead loads);
//! * [`Gas`]`<R>`: the enclosed gas `−C ln V` over a [`gas::Region`] ([`GasEnergy`] over a
//!   closed polygon's area, [`Gas3dEnergy`] over a closed surface's volume);
//! * [`Gravity`]`<D>`: gravity on lumped vertex masses;
//! * [`Membrane3dEnergy`] (St Venant–Kirchhoff triangles in 3D) and [`PressureEnergy`] (a
//!   pressure load on a closed 2D curve) exist in one dimension only.
//!
//! [`mass::lumped_mass`] gives the lumped P1 vertex masses of a mesh from its bodies'
//! densities: the masses of the inertia term of a time step and of the dynamic scenes'
//! gravity.
//!
//! What a term stands for (elastic, potential, inertia) is its [`TermKind`]
//! ([`Energy::kind`]); [`Energy::name`] is for display only.
//!
//! # Adding an energy
//!
//! At most three files:
//!
//! 1. the new energy's file `src/energy/NAME.rs`: a type implementing [`Energy`] (`kind`,
//!    `value`, `add_gradient`, `add_hessian` with its element-wise projection), generic over
//!    the dimension where the formulas allow it, assembled with the helpers below
//!    (`chunked_sum`, `par_scatter`, `chunked_triplets`, `push_block`,
//!    `project_psd`) so that it is thread-count independent; its module doc gives the
//!    formulas, and its tests the finite-difference gradient and Hessian, the projection
//!    (positive semi-definite), rigid invariance and thread independence (helpers in
//!    `fd_test.rs`);
//! 2. this file: `pub mod NAME;` and the `pub use` of the type;
//! 3. the energy assembler that builds it into a scene's [`TotalEnergy`]
//!    (`src/scene/physics.rs`: a `Material` variant or a `BodyPhysics` field, and the step
//!    that makes the term), shared by the built-in scenes and the scene files; a built-in
//!    scene then uses it from its description, and a scene file once the loader reads its
//!    `[[body]]` key (`src/scene/file/`).
//!
//! Nothing else needs to know the term: the outer loop, the QP assembly and the dynamic runs
//! only see a [`TotalEnergy`] and each term's [`TermKind`].
//!
//! # Parallelism and determinism
//!
//! Assembly is rayon-parallel, and its results are bit-for-bit independent of the number of
//! rayon threads:
//!
//! * sums (energy values, the gas shoelace area) are split into fixed chunks of `CHUNK`
//!   elements, independent of the thread count; one partial sum is computed per chunk and the
//!   partials are added sequentially in chunk order;
//! * gradients: per-element contributions are computed in parallel (independently of each
//!   other) and then scatter-added into `g` sequentially, in element order;
//! * Hessian triplets: each chunk of elements produces its triplets in element order, and the
//!   chunks are concatenated in chunk order.

#[cfg(test)]
pub(crate) mod fd_test;
pub mod gas;
pub mod gravity;
pub mod linear_elastic;
pub mod load;
pub mod mass;
pub mod material;
pub mod membrane;
pub mod membrane3d;
pub mod neo_hookean;
pub mod pressure;
pub mod solid;
pub mod string3d;

pub use gas::{Gas, Gas3dEnergy, GasEnergy, OpenSurface};
pub use gravity::Gravity;
pub use linear_elastic::{LinearElastic2d, LinearElastic3d, LinearLaw};
pub use load::DeadLoad;
pub use material::{Elasticity, MaterialError, Plane};
pub use membrane::MembraneEnergy;
pub use membrane3d::Membrane3dEnergy;
pub use neo_hookean::{
    NeoHookean, NeoHookean2d, NeoHookean3d, NeoHookeanLaw, NeoHookeanPlaneStress,
    NeoHookeanPlaneStress2d,
};
pub use pressure::PressureEnergy;
pub use solid::{DegenerateTet, Law, P1Solid};
pub use string3d::String3dEnergy;

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimSub, SMatrix, U1};
use rayon::prelude::*;
use std::ops::Range;

/// Number of elements per chunk of the parallel assembly. Fixed (never derived from the
/// number of threads) so that every floating-point sum is performed in the same order
/// whatever the thread count.
pub(crate) const CHUNK: usize = 4096;

/// Elements per batch of [`par_scatter`]: bounds the memory held by per-element gradient
/// contributions.
const SCATTER_BATCH: usize = 4 * CHUNK;

/// A sparse Hessian entry `(row dof, col dof, value)`.
pub(crate) type Triplet = (usize, usize, f64);

/// The element ranges `[c·CHUNK, min((c+1)·CHUNK, n))`.
fn chunk_range(c: usize, n: usize) -> Range<usize> {
    c * CHUNK..((c + 1) * CHUNK).min(n)
}

/// `Σ_c f(chunk c)` over the fixed chunks of `0..n`: the partial sums `f(range)` are computed
/// in parallel, collected in chunk order and added sequentially, so the result does not depend
/// on the number of threads. `f` should sum its range sequentially in increasing order.
pub(crate) fn chunked_sum(n: usize, f: impl Fn(Range<usize>) -> f64 + Sync) -> f64 {
    let partials: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| f(chunk_range(c, n)))
        .collect();
    partials.iter().fold(0.0, |s, p| s + p)
}

/// Scatter-adds per-element gradient contributions: `contrib(e)` (computed in parallel, each
/// independently) is passed to `scatter(e, value, g)` sequentially in element order `0..n`
/// (elements with `None` are skipped). Works in batches of [`SCATTER_BATCH`] elements to bound
/// the memory used.
pub(crate) fn par_scatter<T: Send>(
    n: usize,
    g: &mut [f64],
    contrib: impl Fn(usize) -> Option<T> + Sync,
    mut scatter: impl FnMut(usize, T, &mut [f64]),
) {
    let mut buf: Vec<Option<T>> = Vec::with_capacity(n.min(SCATTER_BATCH));
    let mut lo = 0;
    while lo < n {
        let hi = (lo + SCATTER_BATCH).min(n);
        buf.clear();
        buf.par_extend((lo..hi).into_par_iter().with_min_len(256).map(&contrib));
        for (e, c) in (lo..hi).zip(buf.drain(..)) {
            if let Some(c) = c {
                scatter(e, c, g);
            }
        }
        lo = hi;
    }
}

/// Appends the triplets of elements `0..n` to `out`: `f(e, v)` pushes element `e`'s triplets
/// to `v`. Each chunk of [`CHUNK`] elements is processed sequentially into its own buffer, the
/// chunks in parallel, and the buffers are appended in chunk order, so `out` is the same as
/// with a sequential loop over `e`, whatever the thread count. Chunks are processed in batches
/// (a few per thread) whose buffers are reused, to keep the extra memory small; the batch size
/// does not affect the result.
pub(crate) fn chunked_triplets(
    n: usize,
    out: &mut Vec<Triplet>,
    f: impl Fn(usize, &mut Vec<Triplet>) + Sync,
) {
    let nchunks = n.div_ceil(CHUNK);
    let batch = (4 * rayon::current_num_threads()).clamp(1, nchunks.max(1));
    let mut bufs: Vec<Vec<Triplet>> = vec![Vec::new(); batch];
    for c0 in (0..nchunks).step_by(batch) {
        let bufs = &mut bufs[..batch.min(nchunks - c0)];
        bufs.par_iter_mut().enumerate().for_each(|(k, buf)| {
            buf.clear();
            for e in chunk_range(c0 + k, n) {
                f(e, buf);
            }
        });
        // (a sequential copy: on the 2-core test machine, copying into the spare capacity in
        // parallel was not measurably faster, the cost being dominated by page faults)
        for buf in bufs.iter() {
            out.extend_from_slice(buf);
        }
    }
}

/// Pushes the triplets of the symmetric block `m(r, c)` (size `vertices.len()·dim`) coupling
/// the listed vertices, skipping zeros: the same entries in the same order as
/// [`Hessian::add_block`].
#[inline]
pub(crate) fn push_block(
    out: &mut Vec<Triplet>,
    dim: usize,
    vertices: &[usize],
    m: impl Fn(usize, usize) -> f64,
) {
    for (a, &va) in vertices.iter().enumerate() {
        for (b, &vb) in vertices.iter().enumerate() {
            for i in 0..dim {
                for j in 0..dim {
                    let v = m(dim * a + i, dim * b + j);
                    if v != 0.0 {
                        out.push((dim * va + i, dim * vb + j, v));
                    }
                }
            }
        }
    }
}

/// Replaces the symmetric matrix `m` by its positive semi-definite part when it has a negative
/// eigenvalue (eigendecomposition `m = Q Λ Qᵀ`, then `Q max(Λ, 0) Qᵀ`, symmetrized); leaves it
/// untouched otherwise. The element-wise projection of the energies whose element Hessians
/// have no closed-form positive part (neo-Hookean, 3D membrane, 3D gas).
pub(crate) fn project_psd<const N: usize>(m: &mut SMatrix<f64, N, N>)
where
    Const<N>: DimSub<U1>,
    DefaultAllocator: Allocator<Const<N>, DimDiff<Const<N>, U1>> + Allocator<DimDiff<Const<N>, U1>>,
{
    let eig = m.symmetric_eigen();
    if eig.eigenvalues.min() < 0.0 {
        let d = eig.eigenvalues.map(|v| v.max(0.0));
        let p = eig.eigenvectors
            * SMatrix::<f64, N, N>::from_diagonal(&d)
            * eig.eigenvectors.transpose();
        *m = (p + p.transpose()) * 0.5;
    }
}

/// A rank-one Hessian term `coef · w wᵀ` (`coef ≥ 0`), kept out of the sparse block so that
/// `P` stays sparse: the QP assembly turns it into one auxiliary variable `s = w·d` and one
/// equality row (SPEC §2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RankOne {
    /// Non-negative coefficient.
    pub coef: f64,
    /// Sparse vector `w` as `(dof, value)` pairs.
    pub w: Vec<(usize, f64)>,
}

/// A Hessian being assembled: sparse triplets (BOTH triangles, duplicates summed by the
/// consumer) plus rank-one terms. The represented matrix is
/// `Σ triplets + Σ_k coef_k w_k w_kᵀ`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hessian {
    /// `(row dof, col dof, value)`, symmetric: `(i, j, v)` and `(j, i, v)` both present for
    /// `i ≠ j`.
    pub triplets: Vec<(usize, usize, f64)>,
    /// Rank-one terms.
    pub rank_one: Vec<RankOne>,
}

impl Hessian {
    /// Adds the symmetric block `m` (size `k·dim`) coupling the listed vertices.
    pub fn add_block(&mut self, dim: usize, vertices: &[usize], m: &nalgebra::DMatrix<f64>) {
        push_block(&mut self.triplets, dim, vertices, |r, c| m[(r, c)]);
    }

    /// Dense `n × n` matrix (tests and small problems).
    pub fn to_dense(&self, n: usize) -> nalgebra::DMatrix<f64> {
        let mut h = nalgebra::DMatrix::zeros(n, n);
        for &(i, j, v) in &self.triplets {
            h[(i, j)] += v;
        }
        for r in &self.rank_one {
            for &(i, a) in &r.w {
                for &(j, b) in &r.w {
                    h[(i, j)] += r.coef * a * b;
                }
            }
        }
        h
    }
}

/// What a term of the energy stands for: how a dynamic run books its value (the `elastic` and
/// `potential` columns of its per-step record).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TermKind {
    /// Stored energy of the bodies: membranes, strings, neo-Hookean solids, the gas, and the
    /// pressure load.
    Elastic,
    /// Potential energy of an external field: gravity.
    Potential,
    /// The inertia term of a time step (added by time stepping), not part of a scene's J.
    Inertia,
}

/// One term of the total energy.
pub trait Energy: Send + Sync {
    /// Short name, for display only (tables, messages); what the term is is [`Energy::kind`].
    fn name(&self) -> &str;
    /// The kind of the term.
    fn kind(&self) -> TermKind;
    /// `J(x)`; `f64::INFINITY` where undefined (inverted triangle, non-positive gas area).
    fn value(&self, x: &[f64]) -> f64;
    /// `g += ∇J(x)`.
    fn add_gradient(&self, x: &[f64], g: &mut [f64]);
    /// Adds the Hessian at `x`. With `projected = false` the exact Hessian (for tests); with
    /// `projected = true` every element's contribution is replaced by its positive
    /// semi-definite part (what the QP uses).
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian);
    /// Whether the Newton model ([`HessianModel::Shifted`]) takes this term's exact Hessian.
    /// True for the terms of a global measure (the gas term, the pressure load), whose split
    /// into shoelace or triangle blocks is not a split into elements: projecting each block
    /// adds a stiffness `~ C/V` per vertex that does not scale with the mesh, while the force
    /// per vertex does (docs/method.md, the Newton model). False (the default) for the terms
    /// of elements (strings, membranes, solids), whose element-wise projection is kept.
    fn exact_in_model(&self) -> bool {
        false
    }
    /// The Cauchy stress of each element at `x`, for the terms of solids (the cell data of the
    /// VTK frames); `None` (the default) for the other terms.
    fn element_stress(&self, _x: &[f64]) -> Option<ElementStress> {
        None
    }
}

/// Per-element Cauchy stress of a solid term ([`Energy::element_stress`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ElementStress {
    /// Each element's vertices (a triangle's fourth entry is `usize::MAX`).
    pub elements: Vec<[usize; 4]>,
    /// Its Cauchy stress, a 3×3 tensor (2D: with the out-of-plane `σ_zz` of plane strain or
    /// stress); NaN where the element is inverted.
    pub sigma: Vec<nalgebra::Matrix3<f64>>,
}

/// Which Hessian the inner steps' quadratic model uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HessianModel {
    /// The exact Hessian of every term (tests, finite differences); may be indefinite.
    Exact,
    /// Every element block replaced by its positive semi-definite part, including the gas and
    /// pressure terms' blocks: always PSD, but over-stiff in the gas' global modes.
    Projected,
    /// Element terms projected, global-measure terms ([`Energy::exact_in_model`]) exact; the
    /// sub-problem makes the model positive definite with an adaptive shift `σI` checked by
    /// an inertia test (docs/method.md, "The Newton model"). The default.
    #[default]
    Shifted,
    /// [`HessianModel::Shifted`] with the shift bisected: the grid's factor 4 between the
    /// last shift that failed and the first that passed is narrowed to `4^(1/64)` by six more
    /// factorizations, so that `σ` is within about 2% of the smallest that makes the model
    /// definite (docs/method.md, "The Newton model").
    ShiftedTight,
}

impl HessianModel {
    /// Name used in settings, CSV and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            HessianModel::Exact => "exact",
            HessianModel::Projected => "projected",
            HessianModel::Shifted => "shifted",
            HessianModel::ShiftedTight => "shifted-tight",
        }
    }

    /// Parses [`HessianModel::as_str`].
    pub fn from_name(s: &str) -> Option<HessianModel> {
        [
            HessianModel::Exact,
            HessianModel::Projected,
            HessianModel::Shifted,
            HessianModel::ShiftedTight,
        ]
        .into_iter()
        .find(|m| m.as_str() == s)
    }

    /// Parses a model a user may choose (every one but [`HessianModel::Exact`]).
    pub fn from_user_name(s: &str) -> Option<HessianModel> {
        HessianModel::from_name(s).filter(|m| *m != HessianModel::Exact)
    }

    /// The names [`HessianModel::from_user_name`] accepts, for error messages.
    pub const USER_NAMES: &'static str = "shifted, shifted-tight, projected";

    /// Log-space bisections of the model's shift after the grid search (0: the grid's
    /// factor 4).
    pub fn shift_bisections(&self) -> usize {
        match self {
            HessianModel::ShiftedTight => 6,
            _ => 0,
        }
    }

    /// Whether `term`'s blocks are projected under this model.
    pub fn projects(&self, term: &dyn Energy) -> bool {
        match self {
            HessianModel::Exact => false,
            HessianModel::Projected => true,
            HessianModel::Shifted | HessianModel::ShiftedTight => !term.exact_in_model(),
        }
    }
}

/// What the solver minimises (the outer loop of §3): `J`'s value, gradient and (projected)
/// Hessian. [`TotalEnergy`] is one; time stepping wraps it with its inertia term.
pub trait Objective {
    /// `J(x)`.
    fn value(&self, x: &[f64]) -> f64;
    /// `∇J(x)`.
    fn gradient(&self, x: &[f64]) -> Vec<f64>;
    /// The Hessian of the given model.
    fn hessian(&self, x: &[f64], model: HessianModel) -> Hessian;
    /// Whether every term's Hessian under `model` is positive semi-definite by construction
    /// (every term projected), so that no shift is needed.
    fn model_is_psd(&self, model: HessianModel) -> bool;
    /// The gradient of each term of `J` (they sum to [`Objective::gradient`]): the forces
    /// that balance at a stationary point, the scale of the minimality certificate
    /// (docs/method.md, "The minimality certificate"). The default is `J` as one term.
    fn term_gradients(&self, x: &[f64]) -> Vec<Vec<f64>> {
        vec![self.gradient(x)]
    }
}

impl Objective for TotalEnergy {
    fn value(&self, x: &[f64]) -> f64 {
        TotalEnergy::value(self, x)
    }
    fn gradient(&self, x: &[f64]) -> Vec<f64> {
        TotalEnergy::gradient(self, x)
    }
    fn hessian(&self, x: &[f64], model: HessianModel) -> Hessian {
        TotalEnergy::model_hessian(self, x, model)
    }
    fn model_is_psd(&self, model: HessianModel) -> bool {
        self.terms.iter().all(|t| model.projects(t.as_ref()))
    }
    fn term_gradients(&self, x: &[f64]) -> Vec<Vec<f64>> {
        self.terms
            .iter()
            .map(|t| {
                let mut g = vec![0.0; x.len()];
                t.add_gradient(x, &mut g);
                g
            })
            .collect()
    }
}

/// Sum of energy terms.
#[derive(Default)]
pub struct TotalEnergy {
    /// The terms.
    pub terms: Vec<Box<dyn Energy>>,
}

impl TotalEnergy {
    /// `J(x) = Σ terms`.
    pub fn value(&self, x: &[f64]) -> f64 {
        self.terms.iter().map(|t| t.value(x)).sum()
    }
    /// `∇J(x)`.
    pub fn gradient(&self, x: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; x.len()];
        for t in &self.terms {
            t.add_gradient(x, &mut g);
        }
        g
    }
    /// The (projected) Hessian.
    pub fn hessian(&self, x: &[f64], projected: bool) -> Hessian {
        let mut h = Hessian::default();
        for t in &self.terms {
            t.add_hessian(x, projected, &mut h);
        }
        h
    }
    /// The Hessian of `model`, term by term ([`HessianModel::projects`]).
    pub fn model_hessian(&self, x: &[f64], model: HessianModel) -> Hessian {
        let mut h = Hessian::default();
        for t in &self.terms {
            t.add_hessian(x, model.projects(t.as_ref()), &mut h);
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::fd_test::{assert_thread_independent, total_bits};
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn energy_chunk_helpers_match_sequential_loops() {
        let n = 3 * CHUNK + 17;
        let vals: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 + 0.1)
            .collect();
        // chunked_sum: partial sums in chunk order
        let mut expected = 0.0;
        for c in 0..n.div_ceil(CHUNK) {
            expected += chunk_range(c, n).map(|i| vals[i]).fold(0.0, |s, v| s + v);
        }
        let s = assert_thread_independent(|| {
            chunked_sum(n, |r| r.map(|i| vals[i]).fold(0.0, |s, v| s + v))
        });
        assert_eq!(s.to_bits(), expected.to_bits());
        // par_scatter over more than one batch: the same as the sequential loop
        let m = SCATTER_BATCH + 3 * CHUNK + 5;
        let nv = 1000;
        let mut expected = vec![0.0; nv];
        for e in 0..m {
            if e % 3 != 0 {
                expected[(e * 31) % nv] += 1.0 / (e + 1) as f64;
            }
        }
        let g = assert_thread_independent(|| {
            let mut g = vec![0.0; nv];
            par_scatter(
                m,
                &mut g,
                |e| (e % 3 != 0).then(|| 1.0 / (e + 1) as f64),
                |e, v, g| g[(e * 31) % nv] += v,
            );
            g
        });
        assert!(g == expected);
        // chunked_triplets: the element-order sequence, appended after existing entries
        let mut expected = vec![(7, 7, 1.0)];
        for (e, &v) in vals.iter().enumerate() {
            for k in 0..e % 4 {
                expected.push((e, k, v));
            }
        }
        let t = assert_thread_independent(|| {
            let mut t = vec![(7, 7, 1.0)];
            chunked_triplets(n, &mut t, |e, out| {
                for k in 0..e % 4 {
                    out.push((e, k, vals[e]));
                }
            });
            t
        });
        assert!(t == expected);
    }

    #[test]
    fn energy_term_kinds_and_names() {
        let x2 = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let x3 = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let tet = vec![[0, 1, 2, 3]];
        let surface = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let terms: Vec<(Box<dyn Energy>, &str, TermKind)> = vec![
            (
                Box::new(MembraneEnergy::new(vec![[0, 1]], &x2, 1.0)),
                "membrane",
                TermKind::Elastic,
            ),
            (
                Box::new(String3dEnergy::new(vec![[0, 1]], &x3, 1.0)),
                "string3d",
                TermKind::Elastic,
            ),
            (
                Box::new(Membrane3dEnergy::new(vec![[0, 1, 2]], &x3, 1.0, 1.0)),
                "membrane3d",
                TermKind::Elastic,
            ),
            (
                Box::new(NeoHookean2d::new(vec![[0, 1, 2]], &x2, 1.0, 1.0)),
                "neo_hookean",
                TermKind::Elastic,
            ),
            (
                Box::new(NeoHookean3d::new(tet, &x3, 1.0, 1.0).unwrap()),
                "neo_hookean3d",
                TermKind::Elastic,
            ),
            (
                Box::new(GasEnergy::new(vec![0, 1, 2], 1.0, &x2)),
                "gas",
                TermKind::Elastic,
            ),
            (
                Box::new(Gas3dEnergy::new(surface, 1.0, &x3).unwrap()),
                "gas3d",
                TermKind::Elastic,
            ),
            (
                Box::new(PressureEnergy::new(vec![0, 1, 2], 1.0, &x2)),
                "pressure",
                TermKind::Elastic,
            ),
            (
                Box::new(Gravity::new(vec![1.0; 3], [0.0, -1.0])),
                "gravity",
                TermKind::Potential,
            ),
            (
                Box::new(Gravity::new(vec![1.0; 4], [0.0, 0.0, -1.0])),
                "gravity3d",
                TermKind::Potential,
            ),
        ];
        for (t, name, kind) in terms {
            assert_eq!((t.name(), t.kind()), (name, kind));
        }
    }

    #[test]
    fn energy_total_thread_independent() {
        // an m×m grid: neo-Hookean triangles, a membrane on the horizontal edges, gravity on
        // lumped masses and a gas in the boundary polygon; stretched by an affine map
        let m = 110;
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let mut xr = Vec::new();
        for j in 0..m {
            for i in 0..m {
                xr.push(i as f64 * 0.1 + rng.gen_range(-0.01..0.01));
                xr.push(j as f64 * 0.1 + rng.gen_range(-0.01..0.01));
            }
        }
        let mut tris = Vec::new();
        let mut edges = Vec::new();
        for j in 0..m {
            for i in 0..m - 1 {
                let v = m * j + i;
                edges.push([v, v + 1]);
                if j + 1 < m {
                    tris.push([v, v + 1, v + m + 1]);
                    tris.push([v, v + m + 1, v + m]);
                }
            }
        }
        assert!(tris.len() > 4 * CHUNK && edges.len() > 2 * CHUNK);
        let mut boundary: Vec<usize> = (0..m).collect();
        boundary.extend((1..m).map(|j| m * j + m - 1));
        boundary.extend((0..m - 1).rev().map(|i| m * (m - 1) + i));
        boundary.extend((1..m - 1).rev().map(|j| m * j));
        let mut x = xr.clone();
        for v in 0..m * m {
            let (px, py) = (xr[2 * v], xr[2 * v + 1]);
            x[2 * v] = 1.2 * px + 0.1 * py + rng.gen_range(-0.01..0.01);
            x[2 * v + 1] = -0.1 * px + 0.9 * py + rng.gen_range(-0.01..0.01);
        }
        // the lumped masses of the triangles, density 1.5 (energy::mass)
        let mut mass = vec![0.0; m * m];
        for t in &tris {
            let p = |v: usize| (xr[2 * v], xr[2 * v + 1]);
            let ((ax, ay), (bx, by), (cx, cy)) = (p(t[0]), p(t[1]), p(t[2]));
            let area = 0.5 * ((bx - ax) * (cy - ay) - (cx - ax) * (by - ay)).abs();
            for &v in t {
                mass[v] += 1.5 * area / 3.0;
            }
        }
        let total = TotalEnergy {
            terms: vec![
                Box::new(NeoHookean2d::new(tris.clone(), &xr, 1.0, 3.0)),
                Box::new(MembraneEnergy::new(edges, &xr, 2.0)),
                Box::new(Gravity::new(mass, [0.0, -9.81])),
                Box::new(GasEnergy::new(boundary, 0.7, &xr)),
            ],
        };
        let bits = assert_thread_independent(|| total_bits(&total, &x));
        assert!(f64::from_bits(bits[0]).is_finite());
        let h = total.hessian(&x, true);
        assert_eq!(h.rank_one.len(), 1);
        assert!(h.triplets.iter().any(|t| t.0 / 2 == t.1 / 2 + 1)); // membrane couplings
    }
}
