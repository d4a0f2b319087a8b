//! The TOML schema of a scene file (serde structs; docs/scene-files.md). Spans
//! ([`toml::Spanned`]) keep the lines errors name.

use crate::scene::mesh::BodyKind;
use crate::solve::outer::Pruning;
use crate::solve::settings::RunSettings;
use toml::Spanned;

/// `[solver]`: the settings of `contactlab run` (each optional; a flag given on the command
/// line overrides the file).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// A backend name of [`contactlab_solvers::registry`].
    pub backend: Option<String>,
    /// `low`, `default` or `high`.
    pub accuracy: Option<String>,
    /// `lazy`, `trust-region` or `all-pairs`.
    pub pruning: Option<Pruning>,
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
}

impl SolverSpec {
    /// Writes the keys the file gives into `settings` (all but `accuracy`, a name checked and
    /// parsed by the caller).
    pub fn fill(&self, settings: &mut RunSettings) {
        let s = settings;
        if let Some(v) = &self.backend {
            s.backend = v.clone();
        }
        if let Some(v) = self.pruning {
            s.pruning = v;
        }
        if let Some(v) = self.max_outer {
            s.max_outer = v;
        }
        if let Some(v) = self.max_inner {
            s.max_inner = v;
        }
        if let Some(v) = self.lazy_start {
            s.lazy_start = v;
        }
        if let Some(v) = self.trust_delta0 {
            s.trust_delta0 = v;
        }
        if let Some(v) = self.warm_start {
            s.warm_start = v;
        }
        s.tol_j = self.tol_j.or(s.tol_j);
        s.qp_tol = self.qp_tol.or(s.qp_tol);
    }
}

/// `[dynamics]`: defaults of `contactlab run FILE --dynamic` (each optional; `--dt`,
/// `--steps`, `--scheme` override).
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
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialSpec {
    pub(super) model: String,
    pub(super) mu: Option<f64>,
    pub(super) lambda: Option<f64>,
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
