//! Scene files: a scene described in TOML (bodies with their meshes, materials, loads, fixed
//! vertices and gas; ε; which bodies may touch; solver settings), run by
//! `contactlab run path/to/scene.toml` without recompiling. The full schema, with an example,
//! is in docs/scene-files.md; in short:
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
//!
//! [[body]]                    # a solid (docs/materials.md)
//! kind = "solid"
//! material = { model = "linear-elastic", E = 1.0, nu = 0.3, plane = "strain" }  # or neo-hookean
//! [[body.support]]            # prescribed components of a vertex set (vertices, all, box)
//! box = { min = [-0.01, -9.0], max = [0.01, 9.0] }
//! components = [0]            # default: all; displacement = [..] (default 0)
//! [[body.traction]]           # dead traction = [..] or pressure = p on the boundary edges/faces
//! box = { min = [-9.0, 0.99], max = [9.0, 9.0] }
//! pressure = 0.01
//! [[body.force]]              # a point force on each selected vertex
//! vertices = [3]
//! value = [0.0, -1e-3]
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
//! not checked). **Welds** (`weld`): see [`SceneFile`] and docs/scene-files.md ("Welded vertices"):
//! unknown bodies, indices out of range, a body welded to itself, vertices apart by more than
//! [`WELD_TOL`] × the longer longest edge, and chains merging two vertices of one body are
//! errors.
//!
//! **What the solver checks.** `[solver]` and `[dynamics]` name the solver's settings
//! (backends, accuracy presets, the run settings' ranges, time-stepping schemes). The scene
//! stage does not import the solver: [`load_with`] takes those rules as a [`RunRules`],
//! implemented by the harness (`harness::scene_file::load_scene_file`, what every run of a
//! scene file loads it with), and applies them where the file's other checks run, so their
//! errors keep their place among the others. [`load`] and [`parse`] check everything else.
//!
//! The module is split by concern: `schema` holds the TOML structs (serde), `validate` the
//! scene-level keys, `body` the loading and checking of each body's mesh, `welds` the shared
//! vertices, `contact` the `[contact]` filter, `assemble` the mesh, energy terms and the
//! checks of the assembled scene, `solid` the solids' materials, `loads` the supports and dead
//! loads (and the checks of a displaced start), `topology` boundaries and chains of element
//! lists.

mod assemble;
mod body;
mod contact;
mod loads;
mod schema;
mod solid;
pub(crate) mod topology;
mod validate;
mod welds;

use crate::scene::mesh::BodyKind;
use crate::scene::meshio::MeshReadError;
use crate::scene::Scene;
use schema::FileSpec;
pub use schema::{DynamicsSpec, PruningName, SolverSpec};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Largest accepted absolute coordinate: squared distances stay finite.
pub const MAX_COORDINATE: f64 = 1e100;

/// Relative threshold under which an element counts as degenerate (area ≤ tol·ℓ²,
/// 6·volume ≤ tol·ℓ³, ℓ its longest edge).
pub const DEGENERATE_TOL: f64 = 1e-12;

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
    /// The prescribed displacements of `[[body.support]]` bring two allowed disjoint elements
    /// of the start closer than ε.
    #[error(
        "{path}: the prescribed displacements ([[body.support]]) make the initial configuration \
         inadmissible: {pair} are at distance {distance:.6e} < eps = {eps:.6e} (the start puts \
         every supported component at its prescribed value: prescribe a smaller displacement, \
         or move the bodies apart)"
    )]
    DisplacedStart {
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
    /// The dead loads of `[[body.traction]]` and `[[body.force]]` (also a term of the
    /// scene's energy), if any.
    pub dead_load: Option<crate::energy::DeadLoad>,
    /// Line of each `[[body]]` table.
    body_lines: Vec<usize>,
}

impl SceneFile {
    /// The scene for `contactlab run FILE --dynamic`: lumped masses from each body's
    /// `density`, the initial velocity of the bodies' `velocity` keys, Δt and steps from
    /// `[dynamics]` (0 when absent: a dynamic run refuses them unless the command line gives
    /// them). A body with a free vertex needs a
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

/// A value of `[solver]` or `[dynamics]` that a [`RunRules`] refuses; the loader reports it
/// as [`SceneFileError::Invalid`] at the table's line, with the key `solver.KEY` or
/// `dynamics.KEY`.
#[derive(Clone, Debug, PartialEq)]
pub struct Refusal {
    /// The key inside its table (`backend`, `accuracy`, `scheme`, …).
    pub key: String,
    /// Its value, printed (names quoted).
    pub value: String,
    /// Why it is refused.
    pub reason: String,
}

/// The checks of `[solver]` and `[dynamics]` that need the solver's vocabulary, run while a
/// scene file loads ([`load_with`]). The harness implements it with the run settings' rules;
/// [`NoRunRules`] accepts every value.
pub trait RunRules {
    /// Checks `[solver]`: the first refused key, if any.
    fn check_solver(&self, solver: &SolverSpec) -> Result<(), Refusal>;
    /// Checks `[dynamics]` after its `dt` and `steps`, which the loader checks itself (> 0,
    /// ≥ 1): the first refused key, if any.
    fn check_dynamics(&self, dynamics: &DynamicsSpec) -> Result<(), Refusal>;
}

/// Rules that accept every `[solver]` and `[dynamics]` value (what [`load`] and [`parse`]
/// use).
pub struct NoRunRules;

impl RunRules for NoRunRules {
    fn check_solver(&self, _: &SolverSpec) -> Result<(), Refusal> {
        Ok(())
    }
    fn check_dynamics(&self, _: &DynamicsSpec) -> Result<(), Refusal> {
        Ok(())
    }
}

/// Reads and builds a scene file, without the solver's checks of `[solver]` and `[dynamics]`
/// ([`NoRunRules`]; a run loads with [`load_with`] and the solver's rules).
pub fn load(path: &Path) -> Result<SceneFile, SceneFileError> {
    load_with(path, &NoRunRules)
}

/// Reads and builds a scene file, checking `[solver]` and `[dynamics]` with `rules`.
pub fn load_with(path: &Path, rules: &dyn RunRules) -> Result<SceneFile, SceneFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneFileError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse_with(&text, path, rules)
}

/// Builds a scene from the text of a scene file; `path` names it in errors and its directory
/// resolves the mesh paths. Without the solver's checks, like [`load`].
pub fn parse(text: &str, path: &Path) -> Result<SceneFile, SceneFileError> {
    parse_with(text, path, &NoRunRules)
}

/// [`parse`], checking `[solver]` and `[dynamics]` with `rules`.
pub fn parse_with(
    text: &str,
    path: &Path,
    rules: &dyn RunRules,
) -> Result<SceneFile, SceneFileError> {
    let ctx = Ctx {
        path: path.display().to_string(),
        text,
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        rules,
    };
    let spec: FileSpec = toml::from_str(text).map_err(|e| SceneFileError::Toml {
        path: ctx.path.clone(),
        line: e.span().map_or(0, |s| ctx.line(s.start)),
        message: e.message().trim().to_string(),
    })?;
    ctx.build(spec, path)
}

/// The scene file being read: its name for errors, its text for line numbers, its
/// directory for mesh paths, the rules of `[solver]` and `[dynamics]`.
struct Ctx<'a> {
    path: String,
    text: &'a str,
    dir: PathBuf,
    rules: &'a dyn RunRules,
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
    pub(super) fn line(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        1 + self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    pub(super) fn invalid(
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
}
