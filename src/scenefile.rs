//! Scene files: a scene described in TOML (bodies with their meshes, materials, loads, fixed
//! vertices and gas; ε; which bodies may touch; solver settings), run by
//! `contactlab run path/to/scene.toml` without recompiling. The full schema, with an example,
//! is in the README ("Scene files"); in short:
//!
//! ```toml
//! name = "two-strings"        # optional, default: the file's stem
//! dim = 2                     # 2 or 3
//! eps = 0.01                  # ε > 0
//! gravity = [0.0, -1.0]       # optional acceleration; loads every body with a density
//! weld = [["lower", 0, "upper", 0]]  # optional: vertex 0 of lower and vertex 0 of upper are one
//!
//! [dynamics]                  # optional defaults of `--dynamic` (--dt/--steps/--scheme override)
//! dt = 0.01
//! steps = 100
//! scheme = "euler"            # euler | newmark
//!
//! [contact]                   # optional; default: every body may touch every body and itself
//! pairs = [["upper", "lower"]]   # if present: the only pairs of distinct bodies that may touch
//! self = []                      # if present: the only bodies that may touch themselves
//! exclude = [["a", "b"]]         # removes pairs ([a, a] removes a's self-contact)
//!
//! [solver]                    # optional; the keys of `contactlab run` (flags given override)
//! backend = "clarabel"
//! pruning = "lazy"
//!
//! [[body]]
//! name = "lower"
//! kind = "curve"              # curve | surface (3D) | solid
//! mesh = "lower.obj"          # path relative to this file (.msh or .obj) …
//! # vertices = [[0, 0], [1, 0]]  # … or inline vertices and elements (0-based)
//! # elements = [[0, 1]]
//! initial = "lower_start.obj" # optional initial positions (same vertices), else the mesh
//! translate = [0.0, 0.0]      # optional, applied to mesh and initial: x ↦ scale·x + translate
//! scale = 1.0
//! material = { model = "string", mu = 1.0 }   # string | stvk-membrane | neo-hookean
//! density = 1.0               # per unit length / area / volume of the reference: gravity,
//!                             # and the masses of --dynamic (required there if a vertex is free)
//! velocity = [0.0, -1.0]      # optional initial velocity for --dynamic (uniform on the body)
//! fixed = { vertices = [0, 10], all = false, box = { min = [-1, -1], max = [1, -0.9] } }
//! gas = { c = 50.0 }          # optional: −C ln V (closed or chord-closed curve, closed surface)
//! pressure = { p = 1.0 }      # optional (2D curves): p·A
//! ```
//!
//! **Validation.** Every rule returns a [`SceneFileError`] naming the file and the line, key and
//! value at fault; nothing panics (fuzzed in `tests/fuzz.rs`): unknown keys; missing files;
//! NaN, infinite or huge (|x| > 1e100) coordinates; dangling indices; zero-length edges,
//! zero-area triangles, zero-volume tetrahedra (relative to their longest edge: area ≤ 1e-12 ℓ²,
//! 6·volume ≤ 1e-12 ℓ³); inverted elements (2D triangles clockwise, tetrahedra of negative
//! volume) in the reference or the initial configuration; vertices used by no element;
//! ε ≤ 0; **ε larger than the scene can hold**: the reference (rest) configuration of every
//! body that may touch itself must be admissible on its own, i.e. every pair of its disjoint
//! contact elements at least ε apart (otherwise its rest shape violates the constraint and the
//! rows fight the elasticity at mesh scale); **an inadmissible start**: the initial
//! configuration must have every allowed pair of disjoint elements at least ε apart (the
//! closest pair is named with its bodies, its distance against ε); **an unbounded problem**: a
//! body with no fixed vertex carrying a non-zero gravity load (every elastic, gas and pressure
//! term is invariant under translation, so J decreases without bound along g) must be able to
//! touch, under the contact filter, a body that holds a fixed vertex, directly or through
//! other such bodies (a necessary condition only: whether that body is actually below it is
//! not checked). **Welds** (`weld`): see [`SceneFile`] and the README ("Welded vertices"):
//! unknown bodies, indices out of range, a body welded to itself, vertices apart by more than
//! [`WELD_TOL`] × the longer longest edge, and chains merging two vertices of one body are
//! errors.

use crate::contact::min_distance;
use crate::energy::{
    Gas3dEnergy, GasEnergy, Gravity, Membrane3dEnergy, MembraneEnergy, NeoHookean2d, NeoHookean3d,
    PressureEnergy, String3dEnergy, TotalEnergy,
};
use crate::mesh::{Body, BodyKind, ContactFilter, Mesh};
use crate::meshio::{read_mesh_file, MeshData, MeshReadError};
use crate::outer::Pruning;
use crate::pairs::ClosestPair;
use crate::scene::Scene;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use thiserror::Error;
use toml::Spanned;

/// Largest accepted absolute coordinate: squared distances stay finite.
pub const MAX_COORDINATE: f64 = 1e100;

/// Relative threshold under which an element counts as degenerate (area ≤ tol·ℓ²,
/// 6·volume ≤ tol·ℓ³, ℓ its longest edge).
pub const DEGENERATE_TOL: f64 = 1e-12;

/// Backends `[solver] backend` accepts.
pub const BACKENDS: [&str; 4] = ["clarabel", "clarabel-reuse", "osqp", "uzawa"];

/// An invalid scene file. Every variant names the file and what is at fault.
#[derive(Debug, Error)]
pub enum SceneFileError {
    /// The scene file cannot be read.
    #[error("{path}: cannot read the scene file: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// TOML syntax, an unknown key, a missing key or a value of the wrong type.
    #[error("{path}:{line}: {message}")]
    Toml {
        /// The file.
        path: String,
        /// 1-based line (0 when the parser gives no position).
        line: usize,
        /// The parser's message (names the key).
        message: String,
    },
    /// A key whose value is out of range or inconsistent.
    #[error("{path}:{line}: {key} = {value}: {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// 1-based line of the key (or of its table).
        line: usize,
        /// The key, as a TOML path (`body[1].material.mu`).
        key: String,
        /// Its value, printed.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// A mesh file that cannot be read.
    #[error(transparent)]
    MeshFile(#[from] MeshReadError),
    /// A bad element or vertex of a body's mesh (in a mesh file, or inline in the scene file).
    #[error("{file}:{line}: body {body:?}: {what}: {reason}")]
    Element {
        /// The mesh file (or the scene file for inline meshes).
        file: String,
        /// The line defining the element or vertex.
        line: usize,
        /// The body.
        body: String,
        /// `triangle 3 [4, 7, 5]`, `vertex 12`, …
        what: String,
        /// Why it is rejected, with the value.
        reason: String,
    },
    /// Two allowed disjoint elements of the initial configuration are closer than ε.
    #[error(
        "{path}: the initial configuration is not admissible: {pair} are at distance \
         {distance:.6e} < eps = {eps:.6e} (move the bodies apart or lower eps)"
    )]
    InadmissibleStart {
        /// The scene file.
        path: String,
        /// The closest pair, with its bodies and local indices.
        pair: String,
        /// Its distance.
        distance: f64,
        /// ε.
        eps: f64,
    },
}

/// `[solver]`: the settings of `contactlab run` (each optional; a flag given on the command
/// line overrides the file).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// `clarabel`, `clarabel-reuse`, `osqp` or `uzawa`.
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

/// A loaded scene file: the scene and the file's solver settings.
pub struct SceneFile {
    /// The scene (mesh, energy, ε, h, φ_0).
    pub scene: Scene,
    /// `[solver]`.
    pub solver: SolverSpec,
    /// `[dynamics]`.
    pub dynamics: DynamicsSpec,
    /// The scene file.
    pub path: PathBuf,
    /// Body names, in mesh order.
    pub body_names: Vec<String>,
    /// Each body's `density`, if given.
    pub densities: Vec<Option<f64>>,
    /// Initial velocity (flat, like positions) from the bodies' `velocity` keys; 0 elsewhere
    /// and at fixed vertices.
    pub v0: Vec<f64>,
    /// `gravity`, if non-zero.
    pub gravity: Option<Vec<f64>>,
    /// Line of each `[[body]]` table.
    body_lines: Vec<usize>,
}

impl SceneFile {
    /// The scene for `contactlab run FILE --dynamic`: lumped masses from each body's
    /// `density`, the initial velocity of the bodies' `velocity` keys, Δt and steps from
    /// `[dynamics]` (0 when absent: [`crate::dynamics::DynamicSettings::validate`] refuses
    /// them unless the command line gives them). A body with a free vertex needs a
    /// `density > 0` (a massless free vertex has no dynamics); a body whose vertices are all
    /// fixed may omit it (taken as 0).
    pub fn into_dynamic(self) -> Result<crate::scene::dynamic::DynamicScene, SceneFileError> {
        let mesh = &self.scene.mesh;
        let mut density = Vec::with_capacity(mesh.bodies.len());
        for (bi, (b, rho)) in mesh.bodies.iter().zip(&self.densities).enumerate() {
            let free = b.vertices.iter().any(|&v| !mesh.fixed[v]);
            match rho {
                Some(r) if *r > 0.0 || !free => density.push(*r),
                None if !free => density.push(0.0),
                _ => {
                    return Err(SceneFileError::Invalid {
                        path: self.path.display().to_string(),
                        line: self.body_lines[bi],
                        key: format!("body[{bi}].density"),
                        value: rho.map_or("(missing)".into(), |r| r.to_string()),
                        reason: format!(
                            "body {:?} has free vertices: a dynamic run (--dynamic) needs its \
                             density > 0 (lumped masses); only a body whose vertices are all \
                             fixed may have none",
                            b.name
                        ),
                    })
                }
            }
        }
        Ok(crate::scene::dynamic::DynamicScene {
            density,
            v0: self.v0,
            dt: self.dynamics.dt.unwrap_or(0.0),
            steps: self.dynamics.steps.unwrap_or(0),
            scene: self.scene,
        })
    }
}

/// Largest distance, relative to the longer of the two bodies' longest reference edges, at
/// which two welded vertices still count as the same point (in the reference and in the
/// initial configuration).
pub const WELD_TOL: f64 = 1e-9;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    name: Option<Spanned<String>>,
    dim: Spanned<i64>,
    eps: Spanned<f64>,
    gravity: Option<Spanned<Vec<f64>>>,
    contact: Option<Spanned<ContactSpec>>,
    solver: Option<Spanned<SolverSpec>>,
    weld: Option<Vec<Spanned<WeldSpec>>>,
    dynamics: Option<Spanned<DynamicsSpec>>,
    #[serde(default)]
    body: Vec<Spanned<BodySpec>>,
}

/// `weld = [["a", i, "b", j], …]`: vertex `i` of body `a` and vertex `j` of body `b` are one
/// vertex.
type WeldSpec = (String, i64, String, i64);

#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ContactSpec {
    pairs: Option<Vec<[String; 2]>>,
    #[serde(rename = "self")]
    self_: Option<Vec<String>>,
    exclude: Option<Vec<[String; 2]>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct BodySpec {
    name: String,
    kind: BodyKind,
    mesh: Option<String>,
    vertices: Option<Vec<Vec<f64>>>,
    elements: Option<Vec<Vec<i64>>>,
    initial: Option<String>,
    initial_vertices: Option<Vec<Vec<f64>>>,
    translate: Option<Vec<f64>>,
    scale: Option<f64>,
    material: Option<MaterialSpec>,
    density: Option<f64>,
    velocity: Option<Vec<f64>>,
    fixed: Option<FixedSpec>,
    gas: Option<GasSpec>,
    pressure: Option<PressureSpec>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    model: String,
    mu: Option<f64>,
    lambda: Option<f64>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FixedSpec {
    vertices: Option<Vec<i64>>,
    #[serde(default)]
    all: bool,
    #[serde(rename = "box")]
    bbox: Option<BoxSpec>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxSpec {
    min: Vec<f64>,
    max: Vec<f64>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct GasSpec {
    c: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PressureSpec {
    p: f64,
}

/// Reads and builds a scene file.
pub fn load(path: &Path) -> Result<SceneFile, SceneFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneFileError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse(&text, path)
}

/// Builds a scene from the text of a scene file; `path` names it in errors and its directory
/// resolves the mesh paths.
pub fn parse(text: &str, path: &Path) -> Result<SceneFile, SceneFileError> {
    let ctx = Ctx {
        path: path.display().to_string(),
        text,
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
    };
    let spec: FileSpec = toml::from_str(text).map_err(|e| SceneFileError::Toml {
        path: ctx.path.clone(),
        line: e.span().map_or(0, |s| ctx.line(s.start)),
        message: e.message().trim().to_string(),
    })?;
    ctx.build(spec, path)
}

struct Ctx<'a> {
    path: String,
    text: &'a str,
    dir: PathBuf,
}

/// A body after loading, in its own numbering.
struct Loaded {
    name: String,
    kind: BodyKind,
    line: usize,
    key: String,
    /// Where the elements come from (mesh file or scene file), and each element's line.
    file: String,
    x_ref: Vec<[f64; 3]>,
    /// Line defining each vertex.
    point_lines: Vec<usize>,
    x0: Vec<[f64; 3]>,
    /// Elements (`arity` entries used).
    elems: Vec<[usize; 4]>,
    elem_lines: Vec<usize>,
    arity: usize,
    fixed: Vec<bool>,
}

fn fmt_list<T: std::fmt::Debug>(v: &[T]) -> String {
    format!("{v:?}")
}

impl Ctx<'_> {
    fn line(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        1 + self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    fn invalid(
        &self,
        line: usize,
        key: impl Into<String>,
        value: impl ToString,
        reason: impl Into<String>,
    ) -> SceneFileError {
        SceneFileError::Invalid {
            path: self.path.clone(),
            line,
            key: key.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    fn build(&self, spec: FileSpec, path: &Path) -> Result<SceneFile, SceneFileError> {
        let dim_line = self.line(spec.dim.span().start);
        let dim = *spec.dim.get_ref();
        if dim != 2 && dim != 3 {
            return Err(self.invalid(dim_line, "dim", dim, "must be 2 or 3"));
        }
        let dim = dim as usize;
        let eps_line = self.line(spec.eps.span().start);
        let eps = *spec.eps.get_ref();
        if !(eps > 0.0 && eps.is_finite()) {
            return Err(self.invalid(eps_line, "eps", eps, "must be finite and > 0"));
        }
        let gravity = match &spec.gravity {
            None => None,
            Some(g) => {
                let line = self.line(g.span().start);
                let v = g.get_ref();
                if v.len() != dim || v.iter().any(|c| !c.is_finite()) {
                    return Err(self.invalid(
                        line,
                        "gravity",
                        fmt_list(v),
                        format!("must be {dim} finite numbers"),
                    ));
                }
                v.iter().any(|&c| c != 0.0).then(|| (v.clone(), line))
            }
        };
        let solver = match spec.solver {
            None => SolverSpec::default(),
            Some(s) => {
                let line = self.line(s.span().start);
                let s = s.into_inner();
                self.check_solver(&s, line)?;
                s
            }
        };
        let dynamics = match spec.dynamics {
            None => DynamicsSpec::default(),
            Some(d) => {
                let line = self.line(d.span().start);
                let d = d.into_inner();
                if let Some(dt) = d.dt {
                    if !(dt > 0.0 && dt.is_finite()) {
                        return Err(self.invalid(
                            line,
                            "dynamics.dt",
                            dt,
                            "must be finite and > 0",
                        ));
                    }
                }
                if d.steps == Some(0) {
                    return Err(self.invalid(line, "dynamics.steps", 0, "must be ≥ 1"));
                }
                if let Some(sc) = &d.scheme {
                    if crate::dynamics::Scheme::from_name(sc).is_none() {
                        return Err(self.invalid(
                            line,
                            "dynamics.scheme",
                            format!("{sc:?}"),
                            "expected one of euler, newmark",
                        ));
                    }
                }
                d
            }
        };
        if spec.body.is_empty() {
            return Err(self.invalid(1, "body", "[]", "the scene needs at least one [[body]]"));
        }
        let name = match &spec.name {
            Some(n) => {
                let v = n.get_ref();
                if v.is_empty() || v.contains(['/', '\\']) {
                    return Err(self.invalid(
                        self.line(n.span().start),
                        "name",
                        format!("{v:?}"),
                        "must be non-empty and contain no path separator",
                    ));
                }
                v.clone()
            }
            None => path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scene")
                .to_string(),
        };
        // bodies
        let mut loaded = Vec::with_capacity(spec.body.len());
        let mut specs = Vec::with_capacity(spec.body.len());
        let mut names: HashMap<String, usize> = HashMap::new();
        for (i, b) in spec.body.into_iter().enumerate() {
            let line = self.line(b.span().start);
            let b = b.into_inner();
            let key = format!("body[{i}]");
            if b.name.is_empty() {
                return Err(self.invalid(line, format!("{key}.name"), "\"\"", "must be non-empty"));
            }
            if let Some(j) = names.insert(b.name.clone(), i) {
                return Err(self.invalid(
                    line,
                    format!("{key}.name"),
                    format!("{:?}", b.name),
                    format!("body[{j}] has the same name"),
                ));
            }
            loaded.push(self.load_body(&b, i, line, dim)?);
            specs.push(b);
        }
        self.assemble(
            name,
            dim,
            eps,
            eps_line,
            gravity,
            spec.contact,
            spec.weld.unwrap_or_default(),
            (solver, dynamics),
            loaded,
            specs,
            path,
        )
    }

    fn check_solver(&self, s: &SolverSpec, line: usize) -> Result<(), SceneFileError> {
        if let Some(b) = &s.backend {
            if !BACKENDS.contains(&b.as_str()) {
                return Err(self.invalid(
                    line,
                    "solver.backend",
                    format!("{b:?}"),
                    format!("expected one of {}", BACKENDS.join(", ")),
                ));
            }
        }
        if let Some(a) = &s.accuracy {
            if crate::presets::Accuracy::from_name(a).is_none() {
                return Err(self.invalid(
                    line,
                    "solver.accuracy",
                    format!("{a:?}"),
                    "expected one of low, default, high",
                ));
            }
        }
        for (k, v) in [("max_outer", s.max_outer), ("max_inner", s.max_inner)] {
            if v == Some(0) {
                return Err(self.invalid(line, format!("solver.{k}"), 0, "must be ≥ 1"));
            }
        }
        for (k, v) in [
            ("tol_j", s.tol_j),
            ("qp_tol", s.qp_tol),
            ("trust_delta0", s.trust_delta0),
        ] {
            if let Some(v) = v {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(self.invalid(
                        line,
                        format!("solver.{k}"),
                        v,
                        "must be finite and > 0",
                    ));
                }
            }
        }
        if let Some(v) = s.lazy_start {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(self.invalid(line, "solver.lazy_start", v, "must be finite and ≥ 0"));
            }
        }
        Ok(())
    }

    /// Reads a mesh file relative to the scene file.
    fn read(
        &self,
        rel: &str,
        key: &str,
        line: usize,
    ) -> Result<(MeshData, String), SceneFileError> {
        let p = self.dir.join(rel);
        if !p.is_file() {
            return Err(self.invalid(
                line,
                key,
                format!("{rel:?}"),
                format!("no such file {}", p.display()),
            ));
        }
        Ok((read_mesh_file(&p)?, p.display().to_string()))
    }

    /// Points of a mesh file as `dim`-vectors (z = 0 required in 2D), finite and bounded.
    fn points_from_file(
        &self,
        m: &MeshData,
        file: &str,
        body: &str,
        dim: usize,
    ) -> Result<Vec<[f64; 3]>, SceneFileError> {
        for (k, p) in m.points.iter().enumerate() {
            let bad = |reason: String| SceneFileError::Element {
                file: file.to_string(),
                line: m.point_lines[k],
                body: body.to_string(),
                what: format!("vertex {k}"),
                reason,
            };
            if let Some(c) = p
                .iter()
                .find(|c| !c.is_finite() || c.abs() > MAX_COORDINATE)
            {
                return Err(bad(format!(
                    "coordinate {c:?} is not finite or exceeds {MAX_COORDINATE:e} in absolute value"
                )));
            }
            if dim == 2 && p[2] != 0.0 {
                return Err(bad(format!("z = {} in a 2D scene (must be 0)", p[2])));
            }
        }
        Ok(m.points.clone())
    }

    fn inline_points(
        &self,
        v: &[Vec<f64>],
        key: &str,
        line: usize,
        dim: usize,
    ) -> Result<Vec<[f64; 3]>, SceneFileError> {
        let mut out = Vec::with_capacity(v.len());
        for (k, p) in v.iter().enumerate() {
            if p.len() != dim {
                return Err(self.invalid(
                    line,
                    format!("{key}[{k}]"),
                    fmt_list(p),
                    format!("a vertex has {dim} coordinates in a {dim}D scene"),
                ));
            }
            if let Some(c) = p
                .iter()
                .find(|c| !c.is_finite() || c.abs() > MAX_COORDINATE)
            {
                return Err(self.invalid(
                    line,
                    format!("{key}[{k}]"),
                    fmt_list(p),
                    format!("coordinate {c:?} is not finite or exceeds {MAX_COORDINATE:e} in absolute value"),
                ));
            }
            let mut q = [0.0; 3];
            q[..dim].copy_from_slice(p);
            out.push(q);
        }
        Ok(out)
    }

    fn load_body(
        &self,
        b: &BodySpec,
        i: usize,
        line: usize,
        dim: usize,
    ) -> Result<Loaded, SceneFileError> {
        let key = format!("body[{i}]");
        let arity = match (b.kind, dim) {
            (BodyKind::Curve, _) => 2,
            (BodyKind::Surface, 3) => 3,
            (BodyKind::Surface, _) => {
                return Err(self.invalid(
                    line,
                    format!("{key}.kind"),
                    "\"surface\"",
                    "surfaces need dim = 3 (a 2D body is a curve or a solid)",
                ))
            }
            (BodyKind::Solid, 2) => 3,
            (BodyKind::Solid, _) => 4,
        };
        // reference vertices and elements
        #[allow(clippy::type_complexity)]
        let (x_ref, point_lines, elems, elem_lines, file): (
            Vec<[f64; 3]>,
            Vec<usize>,
            Vec<[usize; 4]>,
            Vec<usize>,
            String,
        ) = match (&b.mesh, &b.vertices, &b.elements) {
            (Some(m), None, None) => {
                let (data, file) = self.read(m, &format!("{key}.mesh"), line)?;
                let pts = self.points_from_file(&data, &file, &b.name, dim)?;
                let (els, lines): (Vec<[usize; 4]>, Vec<usize>) = match arity {
                    2 => data
                        .lines
                        .iter()
                        .map(|e| ([e.v[0], e.v[1], 0, 0], e.line))
                        .unzip(),
                    3 => data
                        .triangles
                        .iter()
                        .map(|e| ([e.v[0], e.v[1], e.v[2], 0], e.line))
                        .unzip(),
                    _ => data.tets.iter().map(|e| (e.v, e.line)).unzip(),
                };
                if els.is_empty() {
                    let what = [
                        "",
                        "",
                        "lines (msh type 1, obj `l`)",
                        "triangles (msh type 2, obj `f`)",
                        "tetrahedra (msh type 4)",
                    ][arity];
                    return Err(self.invalid(
                        line,
                        format!("{key}.mesh"),
                        format!("{m:?}"),
                        format!(
                            "a {:?} body in {dim}D needs {what}, and the file has none",
                            b.kind
                        )
                        .to_lowercase(),
                    ));
                }
                (pts, data.point_lines, els, lines, file)
            }
            (None, Some(v), Some(e)) => {
                let pts = self.inline_points(v, &format!("{key}.vertices"), line, dim)?;
                let mut els = Vec::with_capacity(e.len());
                for (k, el) in e.iter().enumerate() {
                    let ek = format!("{key}.elements[{k}]");
                    if el.len() != arity {
                        return Err(self.invalid(
                            line,
                            ek,
                            fmt_list(el),
                            format!("a {:?} element in {dim}D has {arity} vertices", b.kind)
                                .to_lowercase(),
                        ));
                    }
                    let mut q = [0usize; 4];
                    for (j, &v) in el.iter().enumerate() {
                        if v < 0 || v as u64 >= pts.len() as u64 {
                            return Err(self.invalid(line, ek, fmt_list(el), format!("vertex {v} does not exist (the body has {} vertices, numbered from 0)", pts.len())));
                        }
                        q[j] = v as usize;
                    }
                    els.push(q);
                }
                if els.is_empty() {
                    return Err(self.invalid(
                        line,
                        format!("{key}.elements"),
                        "[]",
                        "a body needs at least one element",
                    ));
                }
                let (n, np) = (els.len(), pts.len());
                (pts, vec![line; np], els, vec![line; n], self.path.clone())
            }
            _ => {
                return Err(self.invalid(
                    line,
                    key,
                    format!("{:?}", b.name),
                    "give either `mesh` (a file) or both `vertices` and `elements`",
                ))
            }
        };
        let nv = x_ref.len();
        // initial positions
        let x0 = match (&b.initial, &b.initial_vertices) {
            (None, None) => x_ref.clone(),
            (Some(f), None) => {
                let (data, file) = self.read(f, &format!("{key}.initial"), line)?;
                let pts = self.points_from_file(&data, &file, &b.name, dim)?;
                if pts.len() != nv {
                    return Err(self.invalid(
                        line,
                        format!("{key}.initial"),
                        format!("{f:?}"),
                        format!("has {} vertices, the mesh {nv}", pts.len()),
                    ));
                }
                pts
            }
            (None, Some(v)) => {
                let pts = self.inline_points(v, &format!("{key}.initial_vertices"), line, dim)?;
                if pts.len() != nv {
                    return Err(self.invalid(
                        line,
                        format!("{key}.initial_vertices"),
                        format!("{} vertices", pts.len()),
                        format!("the mesh has {nv}"),
                    ));
                }
                pts
            }
            _ => {
                return Err(self.invalid(
                    line,
                    format!("{key}.initial"),
                    format!("{:?}", b.name),
                    "give `initial` or `initial_vertices`, not both",
                ))
            }
        };
        // transform
        let scale = b.scale.unwrap_or(1.0);
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(self.invalid(
                line,
                format!("{key}.scale"),
                scale,
                "must be finite and > 0",
            ));
        }
        let mut shift = [0.0; 3];
        if let Some(t) = &b.translate {
            if t.len() != dim || t.iter().any(|c| !c.is_finite()) {
                return Err(self.invalid(
                    line,
                    format!("{key}.translate"),
                    fmt_list(t),
                    format!("must be {dim} finite numbers"),
                ));
            }
            shift[..dim].copy_from_slice(t);
        }
        let tr = |p: &[f64; 3]| -> [f64; 3] { std::array::from_fn(|c| scale * p[c] + shift[c]) };
        let x_ref: Vec<[f64; 3]> = x_ref.iter().map(tr).collect();
        let x0: Vec<[f64; 3]> = x0.iter().map(tr).collect();
        if let Some(p) = x_ref
            .iter()
            .chain(&x0)
            .find(|p| p.iter().any(|c| !c.is_finite() || c.abs() > MAX_COORDINATE))
        {
            return Err(self.invalid(
                line,
                format!("{key}.scale"),
                scale,
                format!("moves a vertex to {p:?}, beyond {MAX_COORDINATE:e}"),
            ));
        }
        let mut l = Loaded {
            name: b.name.clone(),
            kind: b.kind,
            line,
            key: key.clone(),
            file,
            x_ref,
            point_lines,
            x0,
            elems,
            elem_lines,
            arity,
            fixed: vec![false; nv],
        };
        self.check_elements(&l, dim)?;
        // fixed vertices
        if let Some(f) = &b.fixed {
            if f.all {
                l.fixed.iter_mut().for_each(|v| *v = true);
            }
            for &v in f.vertices.iter().flatten() {
                if v < 0 || v as u64 >= nv as u64 {
                    return Err(self.invalid(
                        line,
                        format!("{key}.fixed.vertices"),
                        v,
                        format!("no such vertex (the body has {nv}, numbered from 0)"),
                    ));
                }
                l.fixed[v as usize] = true;
            }
            if let Some(bx) = &f.bbox {
                if bx.min.len() != dim
                    || bx.max.len() != dim
                    || bx.min.iter().chain(&bx.max).any(|c| c.is_nan())
                {
                    return Err(self.invalid(
                        line,
                        format!("{key}.fixed.box"),
                        format!("min = {:?}, max = {:?}", bx.min, bx.max),
                        format!("min and max must be {dim} numbers each"),
                    ));
                }
                let mut hit = 0;
                for (v, p) in l.x0.iter().enumerate() {
                    if (0..dim).all(|c| bx.min[c] <= p[c] && p[c] <= bx.max[c]) {
                        l.fixed[v] = true;
                        hit += 1;
                    }
                }
                if hit == 0 {
                    return Err(self.invalid(
                        line,
                        format!("{key}.fixed.box"),
                        format!("min = {:?}, max = {:?}", bx.min, bx.max),
                        "holds no vertex of the body's initial configuration",
                    ));
                }
            }
        }
        Ok(l)
    }

    /// Unused vertices, degenerate and inverted elements, in the body's own numbering.
    fn check_elements(&self, l: &Loaded, dim: usize) -> Result<(), SceneFileError> {
        let nv = l.x_ref.len();
        let mut used = vec![false; nv];
        for e in &l.elems {
            for &v in &e[..l.arity] {
                used[v] = true;
            }
        }
        if let Some(v) = used.iter().position(|&u| !u) {
            return Err(SceneFileError::Element {
                file: l.file.clone(),
                line: l.point_lines[v],
                body: l.name.clone(),
                what: format!("vertex {v}"),
                reason: format!(
                    "belongs to no {} (a vertex without element has no energy)",
                    ["", "", "edge", "triangle", "tetrahedron"][l.arity]
                ),
            });
        }
        let elem_name = ["", "", "edge", "triangle", "tetrahedron"][l.arity];
        for (k, e) in l.elems.iter().enumerate() {
            let e = &e[..l.arity];
            for (conf, x, solid_only) in [("reference", &l.x_ref, false), ("initial", &l.x0, true)]
            {
                if solid_only && l.kind != BodyKind::Solid {
                    continue;
                }
                let bad = |reason: String| SceneFileError::Element {
                    file: l.file.clone(),
                    line: l.elem_lines[k],
                    body: l.name.clone(),
                    what: format!("{elem_name} {k} {e:?}"),
                    reason: format!("{reason} in the {conf} configuration"),
                };
                let p = |v: usize| nalgebra::Vector3::from(x[v]);
                let mut lmax: f64 = 0.0;
                for a in 0..e.len() {
                    for b in a + 1..e.len() {
                        lmax = lmax.max((p(e[a]) - p(e[b])).norm());
                    }
                }
                match e.len() {
                    2 => {
                        if lmax == 0.0 {
                            return Err(bad("zero length".into()));
                        }
                    }
                    3 => {
                        let cr = (p(e[1]) - p(e[0])).cross(&(p(e[2]) - p(e[0])));
                        let area = if dim == 2 {
                            0.5 * cr.z
                        } else {
                            0.5 * cr.norm()
                        };
                        if area.abs() <= DEGENERATE_TOL * lmax * lmax || lmax == 0.0 {
                            return Err(bad(format!("zero area ({area:e})")));
                        }
                        if area < 0.0 {
                            return Err(bad(format!(
                                "inverted: signed area {area:e} < 0 (2D triangles must be counter-clockwise)"
                            )));
                        }
                    }
                    _ => {
                        let a = p(e[0]);
                        let v6 = (p(e[1]) - a).cross(&(p(e[2]) - a)).dot(&(p(e[3]) - a));
                        if v6.abs() <= DEGENERATE_TOL * lmax * lmax * lmax || lmax == 0.0 {
                            return Err(bad(format!("zero volume ({:e})", v6 / 6.0)));
                        }
                        if v6 < 0.0 {
                            return Err(bad(format!("inverted: signed volume {:e} < 0", v6 / 6.0)));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        &self,
        name: String,
        dim: usize,
        eps: f64,
        eps_line: usize,
        gravity: Option<(Vec<f64>, usize)>,
        contact: Option<Spanned<ContactSpec>>,
        welds: Vec<Spanned<WeldSpec>>,
        (solver, dynamics): (SolverSpec, DynamicsSpec),
        loaded: Vec<Loaded>,
        specs: Vec<BodySpec>,
        path: &Path,
    ) -> Result<SceneFile, SceneFileError> {
        let nb = loaded.len();
        let mut mesh = Mesh {
            dim,
            ..Default::default()
        };
        let (global, welded) = self.resolve_welds(&welds, &loaded)?;
        let nv = global.iter().flatten().copied().max().map_or(0, |m| m + 1);
        // positions of a welded vertex: those of its first occurrence (body order); fixed if
        // any of its occurrences is
        let mut x0 = vec![0.0; dim * nv];
        mesh.x_ref = vec![0.0; dim * nv];
        mesh.fixed = vec![false; nv];
        let mut seen = vec![false; nv];
        for (l, map) in loaded.iter().zip(&global) {
            for (k, &v) in map.iter().enumerate() {
                if !seen[v] {
                    seen[v] = true;
                    mesh.x_ref[dim * v..dim * v + dim].copy_from_slice(&l.x_ref[k][..dim]);
                    x0[dim * v..dim * v + dim].copy_from_slice(&l.x0[k][..dim]);
                }
                mesh.fixed[v] |= l.fixed[k];
            }
        }
        // contact edges / faces of each body, as global indices
        let mut body_elements: Vec<Vec<[usize; 4]>> = Vec::with_capacity(nb);
        for (bi, l) in loaded.iter().enumerate() {
            let map = &global[bi];
            let els: Vec<[usize; 4]> = l
                .elems
                .iter()
                .map(|e| std::array::from_fn(|k| if k < l.arity { map[e[k]] } else { 0 }))
                .collect();
            let mut body = Body {
                name: l.name.clone(),
                kind: l.kind,
                vertices: map.clone(),
                ..Default::default()
            };
            let push_edges = |mesh: &mut Mesh, body: &mut Body, edges: Vec<[usize; 2]>| {
                for e in edges {
                    body.edges.push(mesh.edges.len());
                    mesh.edges.push(e);
                    mesh.edge_body.push(bi);
                }
            };
            let tri = |e: &[usize; 4]| [e[0], e[1], e[2]];
            match (l.kind, dim) {
                (BodyKind::Curve, _) => {
                    push_edges(
                        &mut mesh,
                        &mut body,
                        els.iter().map(|e| [e[0], e[1]]).collect(),
                    );
                }
                (BodyKind::Solid, 2) => {
                    for e in &els {
                        body.triangles.push(mesh.triangles.len());
                        mesh.triangles.push(tri(e));
                    }
                    let tris: Vec<[usize; 3]> = els.iter().map(tri).collect();
                    push_edges(&mut mesh, &mut body, boundary_edges(&tris));
                }
                (BodyKind::Surface, _) => {
                    let tris: Vec<[usize; 3]> = els.iter().map(tri).collect();
                    for t in &tris {
                        body.triangles.push(mesh.triangles.len());
                        mesh.triangles.push(*t);
                        body.faces.push(mesh.faces.len());
                        mesh.faces.push(*t);
                        mesh.face_body.push(bi);
                    }
                    push_edges(
                        &mut mesh,
                        &mut body,
                        crate::scene::sheets::unique_edges(&tris),
                    );
                }
                (BodyKind::Solid, _) => {
                    for e in &els {
                        body.tets.push(mesh.tets.len());
                        mesh.tets.push(*e);
                    }
                    let faces = boundary_faces(&els);
                    for f in &faces {
                        body.faces.push(mesh.faces.len());
                        mesh.faces.push(*f);
                        mesh.face_body.push(bi);
                    }
                    push_edges(
                        &mut mesh,
                        &mut body,
                        crate::scene::sheets::unique_edges(&faces),
                    );
                }
            }
            // h: the longest reference edge of the body's elements
            let mut h: f64 = 0.0;
            for e in &els {
                for a in 0..l.arity {
                    for b in a + 1..l.arity {
                        h = h.max(
                            (mesh.point(&mesh.x_ref, e[a]) - mesh.point(&mesh.x_ref, e[b])).norm(),
                        );
                    }
                }
            }
            body.h = h;
            mesh.bodies.push(body);
            body_elements.push(els);
        }
        // h: the mesh size of the bodies that deform (a body whose vertices are all fixed is
        // an obstacle, its edges may be long); of all bodies if every vertex is fixed
        let deforms = |b: &Body| b.vertices.iter().any(|&v| !mesh.fixed[v]);
        let h = if mesh.bodies.iter().any(deforms) {
            mesh.bodies
                .iter()
                .filter(|b| deforms(b))
                .map(|b| b.h)
                .fold(0.0, f64::max)
        } else {
            mesh.bodies.iter().map(|b| b.h).fold(0.0, f64::max)
        };
        let body_all_fixed: Vec<bool> = mesh.bodies.iter().map(|b| !deforms(b)).collect();

        // energy terms, body by body: material, then gas, then pressure; gravity last
        let mut energy = TotalEnergy::default();
        let mut mass = vec![0.0; mesh.nv()];
        let mut gravity3 = Gravity::<3>::new(vec![0.0; mesh.nv()], [0.0; 3]);
        for (bi, (l, s)) in loaded.iter().zip(&specs).enumerate() {
            let key = &l.key;
            let line = l.line;
            let els = &body_elements[bi];
            let all_fixed = body_all_fixed[bi];
            match &s.material {
                None if all_fixed => {}
                None => {
                    return Err(self.invalid(line, format!("{key}.material"), "(missing)", "a body with a free vertex needs a material (only a body with `fixed.all = true` may have none)"));
                }
                Some(m) => {
                    let mk = format!("{key}.material");
                    let expect = match (l.kind, dim) {
                        (BodyKind::Curve, _) => "string",
                        (BodyKind::Surface, _) => "stvk-membrane",
                        (BodyKind::Solid, _) => "neo-hookean",
                    };
                    if m.model != expect {
                        return Err(self.invalid(line, format!("{mk}.model"), format!("{:?}", m.model), format!("a {:?} body takes model = {expect:?} (models: string for curves, stvk-membrane for 3D surfaces, neo-hookean for solids)", l.kind).to_lowercase()));
                    }
                    let mu = m.mu.ok_or_else(|| {
                        self.invalid(line, format!("{mk}.mu"), "(missing)", "required")
                    })?;
                    if !(mu > 0.0 && mu.is_finite()) {
                        return Err(self.invalid(
                            line,
                            format!("{mk}.mu"),
                            mu,
                            "must be finite and > 0",
                        ));
                    }
                    let lambda = match (expect, m.lambda) {
                        ("string", Some(v)) => {
                            return Err(self.invalid(
                                line,
                                format!("{mk}.lambda"),
                                v,
                                "the string model has no lambda",
                            ));
                        }
                        ("string", None) => 0.0,
                        (_, None) => {
                            return Err(self.invalid(
                                line,
                                format!("{mk}.lambda"),
                                "(missing)",
                                "required",
                            ));
                        }
                        (_, Some(v)) => v,
                    };
                    if !(lambda >= 0.0 && lambda.is_finite()) {
                        return Err(self.invalid(
                            line,
                            format!("{mk}.lambda"),
                            lambda,
                            "must be finite and ≥ 0",
                        ));
                    }
                    let edges: Vec<[usize; 2]> = els.iter().map(|e| [e[0], e[1]]).collect();
                    let tris: Vec<[usize; 3]> = els.iter().map(|e| [e[0], e[1], e[2]]).collect();
                    match (l.kind, dim) {
                        (BodyKind::Curve, 2) => {
                            energy
                                .terms
                                .push(Box::new(MembraneEnergy::new(edges, &mesh.x_ref, mu)))
                        }
                        (BodyKind::Curve, _) => {
                            energy
                                .terms
                                .push(Box::new(String3dEnergy::new(edges, &mesh.x_ref, mu)))
                        }
                        (BodyKind::Surface, _) => energy.terms.push(Box::new(
                            Membrane3dEnergy::new(tris, &mesh.x_ref, mu, lambda),
                        )),
                        (BodyKind::Solid, 2) => energy.terms.push(Box::new(NeoHookean2d::new(
                            tris,
                            &mesh.x_ref,
                            mu,
                            lambda,
                        ))),
                        (BodyKind::Solid, _) => {
                            let e = NeoHookean3d::new(els.clone(), &mesh.x_ref, mu, lambda)
                                .map_err(|e| {
                                    self.invalid(
                                        line,
                                        key.clone(),
                                        format!("{:?}", l.name),
                                        e.to_string(),
                                    )
                                })?;
                            energy.terms.push(Box::new(e));
                        }
                    }
                }
            }
            if let Some(g) = &s.gas {
                let gk = format!("{key}.gas.c");
                if !(g.c > 0.0 && g.c.is_finite()) {
                    return Err(self.invalid(line, gk, g.c, "must be finite and > 0"));
                }
                match (l.kind, dim) {
                    (BodyKind::Curve, 2) => {
                        let poly = chain(els).map_err(|r| self.invalid(line, &gk, g.c, r))?;
                        let gas = GasEnergy::new(poly, g.c, &x0);
                        if gas.measure(&x0).is_nan() || gas.measure(&x0) <= 0.0 {
                            return Err(self.invalid(line, gk, g.c, "the curve encloses zero area in the initial configuration"));
                        }
                        energy.terms.push(Box::new(gas));
                    }
                    (BodyKind::Surface, 3) => {
                        let tris: Vec<[usize; 3]> = els.iter().map(|e| [e[0], e[1], e[2]]).collect();
                        let gas = Gas3dEnergy::new(tris, g.c, &x0).map_err(|e| self.invalid(line, &gk, g.c, e.to_string()))?;
                        if gas.measure(&x0).is_nan() || gas.measure(&x0) <= 0.0 {
                            return Err(self.invalid(line, gk, g.c, "the surface encloses zero volume in the initial configuration"));
                        }
                        energy.terms.push(Box::new(gas));
                    }
                    _ => return Err(self.invalid(line, gk, g.c, "a gas fills a 2D curve (closed, or closed by its chord) or a closed 3D surface")),
                }
            }
            if let Some(p) = &s.pressure {
                let pk = format!("{key}.pressure.p");
                if !p.p.is_finite() {
                    return Err(self.invalid(line, pk, p.p, "must be finite"));
                }
                if !(l.kind == BodyKind::Curve && dim == 2) {
                    return Err(self.invalid(line, pk, p.p, "a pressure acts on a 2D curve"));
                }
                let poly = chain(els).map_err(|r| self.invalid(line, &pk, p.p, r))?;
                energy
                    .terms
                    .push(Box::new(PressureEnergy::new(poly, p.p, &x0)));
            }
            if let Some(rho) = s.density {
                if !(rho >= 0.0 && rho.is_finite()) {
                    return Err(self.invalid(
                        line,
                        format!("{key}.density"),
                        rho,
                        "must be finite and ≥ 0",
                    ));
                }
                if dim == 3 {
                    match l.kind {
                        BodyKind::Curve => gravity3.add_edges(
                            &els.iter().map(|e| [e[0], e[1]]).collect::<Vec<_>>(),
                            &mesh.x_ref,
                            rho,
                        ),
                        BodyKind::Surface => gravity3.add_triangles(
                            &els.iter().map(|e| [e[0], e[1], e[2]]).collect::<Vec<_>>(),
                            &mesh.x_ref,
                            rho,
                        ),
                        BodyKind::Solid => gravity3.add_tets(els, &mesh.x_ref, rho),
                    }
                } else {
                    let g = match l.kind {
                        BodyKind::Curve => Gravity::lumped_edges(
                            mesh.nv(),
                            &els.iter().map(|e| [e[0], e[1]]).collect::<Vec<_>>(),
                            &mesh.x_ref,
                            rho,
                            [0.0; 2],
                        ),
                        _ => Gravity::lumped_triangles(
                            mesh.nv(),
                            &els.iter().map(|e| [e[0], e[1], e[2]]).collect::<Vec<_>>(),
                            &mesh.x_ref,
                            rho,
                            [0.0; 2],
                        ),
                    };
                    for (m, gm) in mass.iter_mut().zip(&g.mass) {
                        *m += gm;
                    }
                }
            } else if let Some((g, gl)) = gravity.as_ref().filter(|_| !all_fixed) {
                return Err(self.invalid(*gl, "gravity", fmt_list(g), format!("body {:?} ({key}) has a free vertex but no density: give {key}.density (0 for no load)", l.name)));
            }
        }
        if let Some((g, _)) = &gravity {
            if dim == 3 {
                gravity3.g = [g[0], g[1], g[2]];
                energy.terms.push(Box::new(gravity3));
            } else {
                energy
                    .terms
                    .push(Box::new(Gravity::new(mass, [g[0], g[1]])));
            }
        }

        // contact filter
        let names: Vec<String> = loaded.iter().map(|l| l.name.clone()).collect();
        let allowed = self.contact_mask(contact, &names)?;
        if allowed.iter().any(|&a| !a) {
            mesh.contact_filter = Some(ContactFilter::new(&mesh, |i, j| allowed[i * nb + j]));
        }
        if let Err(e) = mesh.validate() {
            // the per-body checks above catch every case first; kept as a safety net
            return Err(self.invalid(1, "body", "(assembled mesh)", e.to_string()));
        }

        // unbounded: a free body with a gravity load must be able to touch an anchored body
        if let Some((g, gl)) = &gravity {
            let has_load: Vec<bool> = specs
                .iter()
                .map(|s| s.density.unwrap_or(0.0) > 0.0)
                .collect();
            let mut supported: Vec<bool> = mesh
                .bodies
                .iter()
                .map(|b| b.vertices.iter().any(|&v| mesh.fixed[v]))
                .collect();
            loop {
                let mut changed = false;
                for i in 0..nb {
                    if !supported[i]
                        && (0..nb).any(|j| {
                            j != i && supported[j] && (allowed[i * nb + j] || welded[i * nb + j])
                        })
                    {
                        supported[i] = true;
                        changed = true;
                    }
                }
                if !changed {
                    break;
                }
            }
            for i in 0..nb {
                if !supported[i] && has_load[i] {
                    return Err(self.invalid(
                        *gl,
                        "gravity",
                        fmt_list(g),
                        format!(
                            "the problem is unbounded: body {:?} has no fixed vertex, carries a \
                             gravity load, and may touch no body that holds a fixed vertex \
                             (directly or through other bodies; see [contact] and weld), so translating \
                             it along gravity lowers J without bound",
                            names[i]
                        ),
                    ));
                }
            }
        }

        // ε against the rest shapes: each self-touching body's reference must be admissible
        let self_mask: Vec<bool> = (0..nb).map(|i| allowed[i * nb + i]).collect();
        if self_mask.iter().any(|&a| a) {
            let mut rest = mesh.clone();
            rest.contact_filter = Some(ContactFilter::new(&rest, |i, j| i == j && self_mask[i]));
            let md = min_distance(&rest, &rest.x_ref, eps, false);
            if md.distance < eps {
                return Err(self.invalid(
                    eps_line,
                    "eps",
                    eps,
                    format!(
                        "larger than the scene can hold: in the reference (rest) configuration \
                         {} are at distance {:.6e} < eps, so that body's rest shape is not \
                         admissible (refine nothing: lower eps below {:.6e}, or exclude the \
                         body's self-contact in [contact])",
                        describe(&mesh, &names, &md.pair),
                        md.distance,
                        md.distance
                    ),
                ));
            }
        }
        // the start
        let md0 = min_distance(&mesh, &x0, 2.0 * eps, false);
        if md0.distance < eps {
            return Err(SceneFileError::InadmissibleStart {
                path: self.path.clone(),
                pair: describe(&mesh, &names, &md0.pair),
                distance: md0.distance,
                eps,
            });
        }
        if !energy.value(&x0).is_finite() {
            return Err(self.invalid(
                1,
                "body",
                "(initial configuration)",
                "the initial energy is not finite",
            ));
        }
        // initial velocities: uniform per body; a free vertex shared by bodies must get the
        // same velocity from each (no `velocity`: zero)
        let mut v0 = vec![0.0; dim * mesh.nv()];
        let mut v_from: Vec<Option<usize>> = vec![None; mesh.nv()];
        for (bi, (l, s)) in loaded.iter().zip(&specs).enumerate() {
            let vel = match &s.velocity {
                None => vec![0.0; dim],
                Some(v) => {
                    if v.len() != dim || v.iter().any(|c| !c.is_finite()) {
                        return Err(self.invalid(
                            l.line,
                            format!("{}.velocity", l.key),
                            fmt_list(v),
                            format!("must be {dim} finite numbers"),
                        ));
                    }
                    v.clone()
                }
            };
            for (k, &v) in mesh.bodies[bi].vertices.iter().enumerate() {
                if mesh.fixed[v] {
                    continue;
                }
                let cur = &mut v0[dim * v..dim * v + dim];
                if let Some(first) = v_from[v] {
                    if cur != vel.as_slice() {
                        return Err(self.invalid(
                            l.line,
                            format!("{}.velocity", l.key),
                            fmt_list(&vel),
                            format!(
                                "vertex {k} of body {:?} is welded to body {:?}, whose velocity is \
                                 {:?}: a free welded vertex needs the same velocity in every body \
                                 holding it",
                                l.name, names[first], cur
                            ),
                        ));
                    }
                } else {
                    cur.copy_from_slice(&vel);
                    v_from[v] = Some(bi);
                }
            }
        }
        Ok(SceneFile {
            scene: Scene {
                name,
                mesh,
                energy,
                eps,
                h,
                x0,
            },
            solver,
            dynamics,
            path: path.to_path_buf(),
            body_names: names,
            densities: specs.iter().map(|s| s.density).collect(),
            v0,
            gravity: gravity.map(|(g, _)| g),
            body_lines: loaded.iter().map(|l| l.line).collect(),
        })
    }

    /// The global vertex of each body's local vertex, and which bodies share a vertex
    /// (row-major `nb × nb`). Vertices are numbered body by body in file order; the welds
    /// merge vertices into classes (chains `a~b, b~c` into one, a cycle's closing weld is
    /// redundant), and a class takes the number of its first occurrence. Each weld must name
    /// existing bodies and vertices, two vertices at the same position (to
    /// [`WELD_TOL`] × the longer longest edge of the two bodies, in the reference and the
    /// initial configuration), and may not merge two vertices of one body, directly or
    /// through a chain.
    #[allow(clippy::type_complexity)]
    fn resolve_welds(
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

    /// The symmetric body mask of `[contact]` (row-major `nb × nb`).
    fn contact_mask(
        &self,
        contact: Option<Spanned<ContactSpec>>,
        names: &[String],
    ) -> Result<Vec<bool>, SceneFileError> {
        let nb = names.len();
        let mut allowed = vec![true; nb * nb];
        let Some(c) = contact else {
            return Ok(allowed);
        };
        let line = self.line(c.span().start);
        let c = c.into_inner();
        let idx = |key: &str, n: &str| -> Result<usize, SceneFileError> {
            names.iter().position(|m| m == n).ok_or_else(|| {
                self.invalid(
                    line,
                    key,
                    format!("{n:?}"),
                    format!("no body has this name (bodies: {})", names.join(", ")),
                )
            })
        };
        if let Some(pairs) = &c.pairs {
            for i in 0..nb {
                for j in 0..nb {
                    if i != j {
                        allowed[i * nb + j] = false;
                    }
                }
            }
            for [a, b] in pairs {
                let (i, j) = (idx("contact.pairs", a)?, idx("contact.pairs", b)?);
                if i == j {
                    return Err(self.invalid(
                        line,
                        "contact.pairs",
                        format!("[{a:?}, {b:?}]"),
                        "a body with itself: list it in contact.self",
                    ));
                }
                allowed[i * nb + j] = true;
                allowed[j * nb + i] = true;
            }
        }
        if let Some(s) = &c.self_ {
            for i in 0..nb {
                allowed[i * nb + i] = false;
            }
            for a in s {
                let i = idx("contact.self", a)?;
                allowed[i * nb + i] = true;
            }
        }
        for [a, b] in c.exclude.iter().flatten() {
            let (i, j) = (idx("contact.exclude", a)?, idx("contact.exclude", b)?);
            allowed[i * nb + j] = false;
            allowed[j * nb + i] = false;
        }
        Ok(allowed)
    }
}

/// The closest pair in the bodies' own numbering (a welded vertex: in the first body that
/// holds it).
fn describe(mesh: &Mesh, names: &[String], pair: &ClosestPair) -> String {
    let loc = |b: usize, v: usize| {
        mesh.bodies[b]
            .vertices
            .iter()
            .position(|&w| w == v)
            .unwrap_or(v)
    };
    let vb = |v: usize| {
        let b = (0..mesh.bodies.len())
            .find(|&b| mesh.bodies[b].vertices.contains(&v))
            .unwrap_or(0);
        format!("vertex {} of body {:?}", loc(b, v), names[b])
    };
    let local = |list: &dyn Fn(&Body) -> &Vec<usize>, owner: usize, k: usize| {
        list(&mesh.bodies[owner])
            .iter()
            .position(|&e| e == k)
            .unwrap_or(k)
    };
    let eb = |a: usize| {
        let b = mesh.edge_body[a];
        let e = mesh.edges[a];
        format!(
            "edge {} [{}, {}] of body {:?}",
            local(&|b: &Body| &b.edges, b, a),
            loc(b, e[0]),
            loc(b, e[1]),
            names[b]
        )
    };
    let fb = |t: usize| {
        let b = mesh.face_body[t];
        let f = mesh.faces[t];
        format!(
            "face {} [{}, {}, {}] of body {:?}",
            local(&|b: &Body| &b.faces, b, t),
            loc(b, f[0]),
            loc(b, f[1]),
            loc(b, f[2]),
            names[b]
        )
    };
    match *pair {
        ClosestPair::PointEdge { x, a, .. } => format!("{} and {}", vb(x), eb(a)),
        ClosestPair::EdgeEdge { a, b } => format!("{} and {} (crossing)", eb(a), eb(b)),
        ClosestPair::VertexTriangle { x, t, .. } => format!("{} and {}", vb(x), fb(t)),
        ClosestPair::Segments { a, b, .. } => format!("{} and {}", eb(a), eb(b)),
        ClosestPair::EdgeThroughFace { a, t } => {
            format!("{} and {} (the edge passes through the face)", eb(a), fb(t))
        }
        ClosestPair::None => "no pair".into(),
    }
}

/// Edges of exactly one triangle (the boundary of a 2D triangle mesh), as stored in their
/// triangle, sorted.
fn boundary_edges(tris: &[[usize; 3]]) -> Vec<[usize; 2]> {
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
fn boundary_faces(tets: &[[usize; 4]]) -> Vec<[usize; 3]> {
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

/// The vertices of a curve in order along it: a simple path (closed by its chord) or a simple
/// cycle.
fn chain(els: &[[usize; 4]]) -> Result<Vec<usize>, String> {
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
        let c = |v: &[[usize; 2]]| chain(&v.iter().map(|e| [e[0], e[1], 0, 0]).collect::<Vec<_>>());
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
