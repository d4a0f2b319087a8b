//! Enclosed-gas energy of an inflated membrane (Pantz 2008, §7: isothermal perfect gas), in 2D
//! and 3D.
//!
//! The gas fills a region of signed measure `V(x)`: the area of a closed polygon in 2D
//! ([`area::ClosedPolygon`]), the volume enclosed by a closed oriented triangle surface in 3D
//! ([`volume::ClosedSurface`]); the sign is fixed at construction so that `V(x0) > 0`. The gas
//! energy is
//!
//! ```text
//! J(x) = −C ln V(x)     (J = +∞ when V ≤ 0),
//! ∇J = −C/V ∇V,
//! ∇²J = C/V² ∇V ∇Vᵀ − C/V ∇²V.
//! ```
//!
//! This composition is one code, [`Gas`], for both dimensions; what depends on the dimension
//! is the region ([`Region`]: `V`, `∇V` and the per-element blocks of `−C/V ∇²V`), in
//! [`area`] and [`volume`]. The first Hessian part is pushed as a [`RankOne`] term
//! (`coef = C/V²`, `w = ∇V`) in both modes. The second is a sum of element blocks (a shoelace
//! term in 2D, a triangle in 3D), each indefinite; with `projected = true` each is replaced by
//! its positive semi-definite part (in closed form in 2D, by eigendecomposition in 3D: see
//! the region modules).

pub mod area;
pub mod volume;

pub(crate) use area::shoelace_hessian;
pub use area::ClosedPolygon;
pub use volume::{open_edge, ClosedSurface, OpenSurface};

use super::{Energy, Hessian, RankOne, TermKind};

/// The region a gas fills, in one dimension: its signed measure `V` and what [`Gas`] needs of
/// its derivatives.
pub trait Region: Send + Sync {
    /// Name of the gas term over such a region (for display).
    const NAME: &'static str;
    /// The signed measure `V(x)` (area in 2D, volume in 3D), positive in the reference
    /// orientation.
    fn measure(&self, x: &[f64]) -> f64;
    /// `∇V(x)` as sparse `(dof, value)` pairs.
    fn measure_gradient(&self, x: &[f64]) -> Vec<(usize, f64)>;
    /// Adds `−C/V ∇²V` (`c = C`, `v = V(x) > 0`), element block by element block; with
    /// `projected`, each block is replaced by its positive semi-definite part.
    fn add_measure_hessian(&self, x: &[f64], c: f64, v: f64, projected: bool, h: &mut Hessian);
}

/// `−C ln V` for the measure `V` of a region `R`: [`GasEnergy`] (2D, a polygon's area) and
/// [`Gas3dEnergy`] (3D, a closed surface's volume) are this type.
#[derive(Clone, Debug)]
pub struct Gas<R> {
    /// The region the gas fills.
    pub region: R,
    /// Gas constant `C` (amount × temperature), `C > 0`.
    pub c: f64,
}

/// `−C ln V` for the area `V` enclosed by a membrane polygon closed by its support chord (2D).
pub type GasEnergy = Gas<ClosedPolygon>;

/// `−C ln V` for the volume `V` enclosed by a closed triangulated surface (3D).
pub type Gas3dEnergy = Gas<ClosedSurface>;

impl<R: Region> Gas<R> {
    /// `V(x)`.
    pub fn measure(&self, x: &[f64]) -> f64 {
        self.region.measure(x)
    }
}

impl GasEnergy {
    /// Builds the energy on `polygon` (see [`ClosedPolygon::new`]: oriented so that the area
    /// at `x0` is positive).
    pub fn new(polygon: Vec<usize>, c: f64, x0: &[f64]) -> Self {
        Self {
            region: ClosedPolygon::new(polygon, x0),
            c,
        }
    }
}

impl Gas3dEnergy {
    /// Builds the energy on the surface `triangles` (see [`ClosedSurface::new`]: oriented so
    /// that the volume at `x0` is positive; a surface that is not closed and consistently
    /// oriented is an error naming an unmatched edge).
    pub fn new(triangles: Vec<[usize; 3]>, c: f64, x0: &[f64]) -> Result<Self, OpenSurface> {
        Ok(Self {
            region: ClosedSurface::new(triangles, x0)?,
            c,
        })
    }
}

impl<R: Region> Energy for Gas<R> {
    fn name(&self) -> &str {
        R::NAME
    }

    fn kind(&self) -> TermKind {
        TermKind::Elastic
    }

    fn exact_in_model(&self) -> bool {
        true
    }

    fn value(&self, x: &[f64]) -> f64 {
        let v = self.region.measure(x);
        if v > 0.0 {
            -self.c * v.ln()
        } else {
            f64::INFINITY
        }
    }

    /// Adds `−C/V ∇V`; adds nothing when `V ≤ 0` (the energy is `+∞` there).
    fn add_gradient(&self, x: &[f64], g: &mut [f64]) {
        let v = self.region.measure(x);
        if v <= 0.0 {
            return;
        }
        for (dof, w) in self.region.measure_gradient(x) {
            g[dof] -= self.c / v * w;
        }
    }

    /// Adds nothing when `V ≤ 0`.
    fn add_hessian(&self, x: &[f64], projected: bool, h: &mut Hessian) {
        let v = self.region.measure(x);
        if v <= 0.0 {
            return;
        }
        h.rank_one.push(RankOne {
            coef: self.c / (v * v),
            w: self.region.measure_gradient(x),
        });
        self.region.add_measure_hessian(x, self.c, v, projected, h);
    }
}
