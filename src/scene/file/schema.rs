//! The TOML schema of a scene file (serde structs; docs/scene-files.md). Spans
//! ([`toml::Spanned`]) keep the lines errors name.
//!
//! `[solver]` and `[dynamics]` are plain data here: names and numbers as the file gives them.
//! What they mean for a run (the run settings and their rules, the accuracy presets, the
//! time-stepping schemes) belongs to the solver; the harness checks them through
//! [`RunRules`](super::RunRules) and applies them to the run.

use crate::scene::mesh::BodyKind;
use toml::Spanned;

/// `[solver]`: the settings of `contactlab run` (each optional; a flag given on the command
/// line overrides the file). Checked by a [`RunRules`](super::RunRules) while the file loads.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// A backend name of [`contactlab_solvers::registry`].
    pub backend: Option<String>,
    /// `low`, `default` or `high`.
    pub accuracy: Option<String>,
    /// `lazy`, `trust-region` or `all-pairs`.
    pub pruning: Option<PruningName>,
    /// Maximum outer iterations (≥ 1).
    pub max_outer: Option<usize>,
    /// Relative energy tolerance of the outer stopping rule (> 0).
    pub tol_j: Option<f64>,
    /// Backend tolerance (> 0).
    pub qp_tol: Option<f64>,
    /// Inner steps per T(ψ) (≥ 1).
    pub max_inner: Option<usize>,
    /// Lazy rows' initial radius cap relative to the median edge (≥ 0).
    pub lazy_start: Option<f64>,
    /// Initial trust-region half-width relative to the median edge (> 0).
    pub trust_delta0: Option<f64>,
    /// Warm-start the QP duals.
    pub warm_start: Option<bool>,
    /// The inner steps' Newton model: `shifted` or `projected`.
    pub newton_model: Option<String>,
    /// The outer method: `pantz` or `sqp`.
    pub outer_method: Option<String>,
    /// The SQP model's constraint curvature: `off`, `psd`, `full`, `tangent` or `interior`
    /// (used with `outer_method = "sqp"`).
    pub sqp_curvature: Option<String>,
    /// SQP: `γ` of the active pairs' normal stiffness (finite, ≥ 0; used with
    /// `outer_method = "sqp"`).
    pub sqp_normal_stiffness: Option<f64>,
    /// SQP: leave out the rows implied by another row of the same vertex or edge (used with
    /// `outer_method = "sqp"`).
    pub sqp_drop_endpoint_rows: Option<bool>,
    /// SQP: rows against the extended element where the body turns towards the other side
    /// (used with `outer_method = "sqp"`).
    pub sqp_extend_rows: Option<bool>,
    /// SQP, 2D: leave out the rows whose closest point is a vertex of the other body, implied
    /// by that vertex's row (used with `outer_method = "sqp"`).
    pub sqp_drop_vertex_rows: Option<bool>,
    /// SQP, 2D: leave out a vertex's row against the side of a corner that the corner's row
    /// implies (used with `outer_method = "sqp"`).
    pub sqp_drop_side_rows: Option<bool>,
    /// SQP: the extended rows against a fixed element without the chain limit (used with
    /// `sqp_extend_rows = true`).
    pub sqp_extend_fixed: Option<bool>,
    /// SQP: add a violated row only where the pair comes within ε + δ on the step's straight
    /// path (used with `outer_method = "sqp"`).
    pub sqp_path_rows: Option<bool>,
    /// SQP, 2D: with the endpoint or vertex rows left out, add the rows that would imply a
    /// violated one (used with `outer_method = "sqp"`).
    pub sqp_implying_rows: Option<bool>,
    /// SQP: after a full step, try 2, 4, …, 2^k times it while J falls and every check passes
    /// (used with `outer_method = "sqp"`; 0: off).
    pub sqp_extrapolate: Option<usize>,
    /// SQP: the normal stiffness only on the pairs whose last multiplier is at least this
    /// fraction of the largest (in [0, 1]; used with `outer_method = "sqp"`; 0: every
    /// positive one).
    pub sqp_normal_active_rel: Option<f64>,
    /// SQP: `interior` keeps surfaces' edge–edge pairs, with this factor on their normal
    /// stiffness (finite, ≥ 0; used with `outer_method = "sqp"`; 0: left out).
    pub sqp_edge_edge_stiffness: Option<f64>,
}

/// The names `[solver].pruning` takes (the TOML and JSON spelling of the solver's pruning modes,
/// in the same order, so that serde's messages list them the same way). The harness maps each
/// to its pruning mode with an exhaustive match.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PruningName {
    /// `all-pairs`.
    AllPairs,
    /// `lazy`.
    Lazy,
    /// `trust-region`.
    TrustRegion,
}

/// `[dynamics]`: defaults of `contactlab run FILE --dynamic` (each optional; `--dt`,
/// `--steps`, `--scheme` override). `dt` and `steps` are checked here; `scheme`, a name of
/// the solver's, by a [`RunRules`](super::RunRules).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicsSpec {
    /// Time step Δt (> 0).
    pub dt: Option<f64>,
    /// Number of steps (≥ 1).
    pub steps: Option<usize>,
    /// `euler` or `newmark`.
    pub scheme: Option<String>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FileSpec {
    pub(super) name: Option<Spanned<String>>,
    pub(super) dim: Spanned<i64>,
    pub(super) eps: Spanned<f64>,
    pub(super) gravity: Option<Spanned<Vec<f64>>>,
    pub(super) contact: Option<Spanned<ContactSpec>>,
    pub(super) solver: Option<Spanned<SolverSpec>>,
    pub(super) weld: Option<Vec<Spanned<WeldSpec>>>,
    pub(super) dynamics: Option<Spanned<DynamicsSpec>>,
    #[serde(default)]
    pub(super) body: Vec<Spanned<BodySpec>>,
}

/// `weld = [["a", i, "b", j], …]`: vertex `i` of body `a` and vertex `j` of body `b` are one
/// vertex.
pub(super) type WeldSpec = (String, i64, String, i64);

#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct ContactSpec {
    pub(super) pairs: Option<Vec<[String; 2]>>,
    #[serde(rename = "self")]
    pub(super) self_: Option<Vec<String>>,
    pub(super) exclude: Option<Vec<[String; 2]>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BodySpec {
    pub(super) name: String,
    pub(super) kind: BodyKind,
    pub(super) mesh: Option<String>,
    pub(super) vertices: Option<Vec<Vec<f64>>>,
    pub(super) elements: Option<Vec<Vec<i64>>>,
    pub(super) initial: Option<String>,
    pub(super) initial_vertices: Option<Vec<Vec<f64>>>,
    pub(super) translate: Option<Vec<f64>>,
    pub(super) scale: Option<f64>,
    pub(super) material: Option<MaterialSpec>,
    pub(super) density: Option<f64>,
    pub(super) velocity: Option<Vec<f64>>,
    pub(super) fixed: Option<FixedSpec>,
    pub(super) gas: Option<GasSpec>,
    pub(super) pressure: Option<PressureSpec>,
    pub(super) support: Option<Vec<Spanned<SupportSpec>>>,
    pub(super) traction: Option<Vec<Spanned<TractionSpec>>>,
    pub(super) force: Option<Vec<Spanned<ForceSpec>>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialSpec {
    pub(super) model: String,
    pub(super) mu: Option<f64>,
    pub(super) lambda: Option<f64>,
    /// Young's modulus (solids; instead of `mu`, `lambda`).
    #[serde(rename = "E")]
    pub(super) young: Option<f64>,
    /// Poisson's ratio (solids; with `E`).
    pub(super) nu: Option<f64>,
    /// `strain` or `stress` (2D solids).
    pub(super) plane: Option<String>,
}

/// `[[body.support]]`: prescribed displacements of chosen components of a vertex set (the
/// vertices listed, all of them, or those in a box of the reference configuration).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SupportSpec {
    pub(super) vertices: Option<Vec<i64>>,
    #[serde(default)]
    pub(super) all: bool,
    #[serde(rename = "box")]
    pub(super) bbox: Option<BoxSpec>,
    /// The prescribed components (0 = x, 1 = y, 2 = z); default: all.
    pub(super) components: Option<Vec<i64>>,
    /// The displacement from the reference (`dim` numbers; only the chosen components are
    /// used); default 0.
    pub(super) displacement: Option<Vec<f64>>,
}

/// `[[body.traction]]`: a dead traction or pressure on the boundary edges (2D) or faces (3D) of
/// a solid whose vertices are all selected.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TractionSpec {
    pub(super) vertices: Option<Vec<i64>>,
    #[serde(default)]
    pub(super) all: bool,
    #[serde(rename = "box")]
    pub(super) bbox: Option<BoxSpec>,
    /// Force per reference length (2D) or area (3D), `dim` numbers.
    pub(super) traction: Option<Vec<f64>>,
    /// Pressure on the reference normal (positive pushes on the body).
    pub(super) pressure: Option<f64>,
}

/// `[[body.force]]`: the same point force on every selected vertex.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ForceSpec {
    pub(super) vertices: Option<Vec<i64>>,
    #[serde(default)]
    pub(super) all: bool,
    #[serde(rename = "box")]
    pub(super) bbox: Option<BoxSpec>,
    /// The force on each selected vertex, `dim` numbers.
    pub(super) value: Vec<f64>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FixedSpec {
    pub(super) vertices: Option<Vec<i64>>,
    #[serde(default)]
    pub(super) all: bool,
    #[serde(rename = "box")]
    pub(super) bbox: Option<BoxSpec>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoxSpec {
    pub(super) min: Vec<f64>,
    pub(super) max: Vec<f64>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GasSpec {
    pub(super) c: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PressureSpec {
    pub(super) p: f64,
}
