//! Mesh file readers: Gmsh `.msh` (ASCII 2.2 and 4.1) and Wavefront `.obj`.
//!
//! Both produce a [`MeshData`]: points in R³ (a 2D scene requires `z = 0`) and P1 elements —
//! lines (curves), triangles (surfaces, 2D solids) and tetrahedra (3D solids) — as 0-based
//! indices into the points, each with the line of the file that defined it, so that later
//! checks (degenerate or inverted elements) can name the line.
//!
//! | format | points | lines | triangles | tetrahedra |
//! |---|---|---|---|---|
//! | `.msh` 2.2 / 4.1 ASCII | `$Nodes` (tags mapped to 0-based order of appearance) | type 1 | type 2 | type 4 |
//! | `.obj` | `v x y [z [w]]` | `l` polylines (consecutive pairs) | `f` polygons (fan from the first vertex) | — |
//!
//! `.msh`: points (type 15) are ignored; any other element type (quadrangles, second-order
//! elements, …) is an error naming it; physical and elementary tags are read and ignored; binary
//! files are refused. `.obj`: indices are 1-based, negative ones count back from the last `v`
//! read; `vt`, `vn`, `vp`, `o`, `g`, `s`, `usemtl`, `mtllib` and comments are ignored; any other
//! statement is an error naming it. Every error is a [`MeshReadError`] naming the file, the
//! line and the offending token; no input makes a reader panic (fuzzed in `tests/fuzz.rs`).

pub mod msh;
pub mod obj;

use std::path::Path;
use thiserror::Error;

/// One element of a mesh file: its vertices (0-based) and the 1-based line defining it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Element<const N: usize> {
    /// Vertex indices into [`MeshData::points`].
    pub v: [usize; N],
    /// Line of the file (1-based).
    pub line: usize,
}

/// What a mesh file holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Points, always three coordinates (`z = 0` for planar files).
    pub points: Vec<[f64; 3]>,
    /// 1-based line of each point.
    pub point_lines: Vec<usize>,
    /// Two-node elements.
    pub lines: Vec<Element<2>>,
    /// Three-node elements.
    pub triangles: Vec<Element<3>>,
    /// Four-node tetrahedra.
    pub tets: Vec<Element<4>>,
}

/// A mesh file that cannot be read. Names the file, the line and the offending token.
#[derive(Debug, Error)]
pub enum MeshReadError {
    /// The file cannot be read.
    #[error("{path}: cannot read the mesh file: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The extension is neither `.msh` nor `.obj`.
    #[error("{path}: unknown mesh format (expected a .msh or .obj file)")]
    Format {
        /// The file.
        path: String,
    },
    /// A syntax or consistency error at a line.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// 1-based line (0: the whole file).
        line: usize,
        /// What is wrong, with the offending token or value.
        message: String,
    },
}

/// Reads a `.msh` or `.obj` file (chosen by its extension).
pub fn read_mesh_file(path: &Path) -> Result<MeshData, MeshReadError> {
    let name = path.display().to_string();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("msh") | Some("obj")) {
        return Err(MeshReadError::Format { path: name });
    }
    let bytes = std::fs::read(path).map_err(|source| MeshReadError::Io {
        path: name.clone(),
        source,
    })?;
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
            return Err(MeshReadError::Parse {
                path: name,
                line,
                message: "the file is not UTF-8 text (binary mesh files are not supported)".into(),
            });
        }
    };
    if ext.as_deref() == Some("msh") {
        msh::parse_msh(&text, &name)
    } else {
        obj::parse_obj(&text, &name)
    }
}

/// Writes points (`dim` coordinates each, flat) with lines and triangles as a `.obj` text
/// (1-based indices; one `l` statement per line element; `z = 0` added in 2D). Coordinates are
/// printed with Rust's shortest round-trip formatting, so reading the file back gives the same
/// `f64` values.
pub fn write_obj(dim: usize, x: &[f64], lines: &[[usize; 2]], triangles: &[[usize; 3]]) -> String {
    let mut s = String::new();
    for p in x.chunks(dim) {
        let z = if dim == 3 { p[2] } else { 0.0 };
        s.push_str(&format!("v {:?} {:?} {:?}\n", p[0], p[1], z));
    }
    for l in lines {
        s.push_str(&format!("l {} {}\n", l[0] + 1, l[1] + 1));
    }
    for t in triangles {
        s.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    s
}

/// Writes points (`dim` coordinates each, flat) with lines, triangles and tetrahedra as a Gmsh
/// ASCII 2.2 `.msh` text (node tags `1..`, shortest round-trip coordinates).
pub fn write_msh22(
    dim: usize,
    x: &[f64],
    lines: &[[usize; 2]],
    triangles: &[[usize; 3]],
    tets: &[[usize; 4]],
) -> String {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    s.push_str(&format!("{}\n", x.len() / dim));
    for (i, p) in x.chunks(dim).enumerate() {
        let z = if dim == 3 { p[2] } else { 0.0 };
        s.push_str(&format!("{} {:?} {:?} {:?}\n", i + 1, p[0], p[1], z));
    }
    s.push_str(&format!(
        "$EndNodes\n$Elements\n{}\n",
        lines.len() + triangles.len() + tets.len()
    ));
    let mut k = 0;
    let mut el = |s: &mut String, ty: u32, vs: &[usize]| {
        k += 1;
        s.push_str(&format!("{k} {ty} 2 1 1"));
        for v in vs {
            s.push_str(&format!(" {}", v + 1));
        }
        s.push('\n');
    };
    for l in lines {
        el(&mut s, 1, l);
    }
    for t in triangles {
        el(&mut s, 2, t);
    }
    for t in tets {
        el(&mut s, 4, t);
    }
    s.push_str("$EndElements\n");
    s
}
