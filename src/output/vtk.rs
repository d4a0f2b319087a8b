//! VTK XML writers: `.vtu` unstructured grids (ASCII) and `.pvd` time series
//! collections, readable by ParaView and by Python `meshio`.

use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::write_atomic;

/// VTK cell type id of a two-node line.
pub const VTK_LINE: u8 = 3;
/// VTK cell type id of a three-node triangle.
pub const VTK_TRIANGLE: u8 = 5;
/// VTK cell type id of a four-node (linear) tetrahedron.
pub const VTK_TETRA: u8 = 10;
/// Value of the `kind` cell array for edges.
pub const KIND_EDGE: i32 = 1;
/// Value of the `kind` cell array for triangles.
pub const KIND_TRIANGLE: i32 = 2;
/// Value of the `kind` cell array for tetrahedra.
pub const KIND_TET: i32 = 3;

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Escapes a string for use inside a double-quoted XML attribute.
pub(crate) fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// Formats a float so that VTK, ParaView and numpy all parse it back exactly
/// (shortest round-trip representation in scientific notation).
fn fmt_f64(v: f64) -> String {
    if v.is_nan() {
        "nan".to_string()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        format!("{v:e}")
    }
}

/// Renders the `.vtu` document (see [`write_vtu`]) as a string.
///
/// Errors (`InvalidInput`) if `dim` is not 2 or 3, if `x.len()` is not a
/// multiple of `dim`, if a cell (edge, triangle or tet; the message names its
/// index) references a non-existent point, or if a point data array does not
/// have one value per point.
pub fn vtu_string(
    dim: usize,
    x: &[f64],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    tets: &[[usize; 4]],
    point_data: &[(&str, &[f64])],
) -> io::Result<String> {
    let fields = VtuFields {
        point_scalars: point_data.to_vec(),
        ..Default::default()
    };
    vtu_string_with(dim, x, edges, triangles, tets, &fields)
}

/// The data arrays of a `.vtu` besides the cell array `kind`: scalar point arrays (one value
/// per point), vector point arrays (three values per point, `x y z`, flat) and scalar cell
/// arrays (one value per cell, in the cells' order: edges, then triangles, then tets). All
/// `Float64`.
#[derive(Clone, Debug, Default)]
pub struct VtuFields<'a> {
    /// `(name, values)`, one value per point.
    pub point_scalars: Vec<(&'a str, &'a [f64])>,
    /// `(name, values)`, three values per point.
    pub point_vectors: Vec<(&'a str, &'a [f64])>,
    /// `(name, values)`, one value per cell.
    pub cell_scalars: Vec<(&'a str, &'a [f64])>,
}

/// [`VtuFields`] that own their arrays (what an observer computes per frame).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OwnedVtuFields {
    /// `(name, values)`, one value per point.
    pub point_scalars: Vec<(String, Vec<f64>)>,
    /// `(name, values)`, three values per point.
    pub point_vectors: Vec<(String, Vec<f64>)>,
    /// `(name, values)`, one value per cell.
    pub cell_scalars: Vec<(String, Vec<f64>)>,
}

impl OwnedVtuFields {
    /// The borrowed view.
    pub fn fields(&self) -> VtuFields<'_> {
        fn view(v: &[(String, Vec<f64>)]) -> Vec<(&str, &[f64])> {
            v.iter().map(|(n, a)| (n.as_str(), a.as_slice())).collect()
        }
        VtuFields {
            point_scalars: view(&self.point_scalars),
            point_vectors: view(&self.point_vectors),
            cell_scalars: view(&self.cell_scalars),
        }
    }
}

/// [`vtu_string`] with vector point data and scalar cell data ([`VtuFields`]). Errors also
/// when an array has the wrong length.
pub fn vtu_string_with(
    dim: usize,
    x: &[f64],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    tets: &[[usize; 4]],
    fields: &VtuFields,
) -> io::Result<String> {
    let point_data = &fields.point_scalars;
    if dim != 2 && dim != 3 {
        return Err(invalid(format!("write_vtu: dim must be 2 or 3, got {dim}")));
    }
    if !x.len().is_multiple_of(dim) {
        return Err(invalid(format!(
            "write_vtu: x.len() = {} is not a multiple of dim = {dim}",
            x.len()
        )));
    }
    let n_points = x.len() / dim;
    let n_cells = edges.len() + triangles.len() + tets.len();
    for (k, e) in edges.iter().enumerate() {
        if e.iter().any(|&i| i >= n_points) {
            return Err(invalid(format!(
                "write_vtu: edge {k} = {e:?} references a point >= {n_points}"
            )));
        }
    }
    for (k, t) in triangles.iter().enumerate() {
        if t.iter().any(|&i| i >= n_points) {
            return Err(invalid(format!(
                "write_vtu: triangle {k} = {t:?} references a point >= {n_points}"
            )));
        }
    }
    for (k, t) in tets.iter().enumerate() {
        if t.iter().any(|&i| i >= n_points) {
            return Err(invalid(format!(
                "write_vtu: tet {k} = {t:?} references a point >= {n_points}"
            )));
        }
    }
    for (name, vals) in point_data {
        if vals.len() != n_points {
            return Err(invalid(format!(
                "write_vtu: point data '{name}' has {} values, expected {n_points}",
                vals.len()
            )));
        }
    }
    for (name, vals) in &fields.point_vectors {
        if vals.len() != 3 * n_points {
            return Err(invalid(format!(
                "write_vtu: point vector '{name}' has {} values, expected {}",
                vals.len(),
                3 * n_points
            )));
        }
    }
    for (name, vals) in &fields.cell_scalars {
        if vals.len() != n_cells {
            return Err(invalid(format!(
                "write_vtu: cell data '{name}' has {} values, expected {n_cells}",
                vals.len()
            )));
        }
    }

    let mut s = String::new();
    // `write!` into a String cannot fail; the results are ignored below.
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    s.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );

    // Point data.
    if point_data.is_empty() && fields.point_vectors.is_empty() {
        s.push_str("      <PointData>\n      </PointData>\n");
    } else {
        s.push_str("      <PointData");
        if let Some((name, _)) = point_data.first() {
            let _ = write!(s, " Scalars=\"{}\"", xml_escape(name));
        }
        if let Some((name, _)) = fields.point_vectors.first() {
            let _ = write!(s, " Vectors=\"{}\"", xml_escape(name));
        }
        s.push_str(">\n");
        for (name, vals) in point_data {
            push_f64_array(&mut s, name, 1, vals);
        }
        for (name, vals) in &fields.point_vectors {
            push_f64_array(&mut s, name, 3, vals);
        }
        s.push_str("      </PointData>\n");
    }

    // Cell data: kind.
    s.push_str("      <CellData Scalars=\"kind\">\n");
    s.push_str(
        "        <DataArray type=\"Int32\" Name=\"kind\" NumberOfComponents=\"1\" format=\"ascii\">\n",
    );
    push_values(
        &mut s,
        std::iter::repeat_n(KIND_EDGE, edges.len())
            .chain(std::iter::repeat_n(KIND_TRIANGLE, triangles.len()))
            .chain(std::iter::repeat_n(KIND_TET, tets.len()))
            .map(|k| k.to_string()),
        20,
    );
    s.push_str("        </DataArray>\n");
    for (name, vals) in &fields.cell_scalars {
        push_f64_array(&mut s, name, 1, vals);
    }
    s.push_str("      </CellData>\n");

    // Points (always 3 components).
    s.push_str("      <Points>\n");
    s.push_str(
        "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for p in x.chunks_exact(dim) {
        let z = if dim == 3 { p[2] } else { 0.0 };
        let _ = writeln!(
            s,
            "          {} {} {}",
            fmt_f64(p[0]),
            fmt_f64(p[1]),
            fmt_f64(z)
        );
    }
    s.push_str("        </DataArray>\n");
    s.push_str("      </Points>\n");

    // Cells.
    s.push_str("      <Cells>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for e in edges {
        let _ = writeln!(s, "          {} {}", e[0], e[1]);
    }
    for t in triangles {
        let _ = writeln!(s, "          {} {} {}", t[0], t[1], t[2]);
    }
    for t in tets {
        let _ = writeln!(s, "          {} {} {} {}", t[0], t[1], t[2], t[3]);
    }
    s.push_str("        </DataArray>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    let offsets = (1..=edges.len())
        .map(|k| 2 * k)
        .chain((1..=triangles.len()).map(|k| 2 * edges.len() + 3 * k))
        .chain((1..=tets.len()).map(|k| 2 * edges.len() + 3 * triangles.len() + 4 * k));
    push_values(&mut s, offsets.map(|o| o.to_string()), 20);
    s.push_str("        </DataArray>\n");
    s.push_str("        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    push_values(
        &mut s,
        std::iter::repeat_n(VTK_LINE, edges.len())
            .chain(std::iter::repeat_n(VTK_TRIANGLE, triangles.len()))
            .chain(std::iter::repeat_n(VTK_TETRA, tets.len()))
            .map(|t| t.to_string()),
        20,
    );
    s.push_str("        </DataArray>\n");
    s.push_str("      </Cells>\n");

    s.push_str("    </Piece>\n");
    s.push_str("  </UnstructuredGrid>\n");
    s.push_str("</VTKFile>\n");
    Ok(s)
}

/// Appends whitespace-separated values, `per_line` per line, indented.
/// One ASCII `Float64` `DataArray` named `name` with `ncomp` components per tuple.
fn push_f64_array(s: &mut String, name: &str, ncomp: usize, vals: &[f64]) {
    let _ = writeln!(
        s,
        "        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{ncomp}\" format=\"ascii\">",
        xml_escape(name)
    );
    push_values(s, vals.iter().map(|&v| fmt_f64(v)), 6);
    s.push_str("        </DataArray>\n");
}

fn push_values(s: &mut String, vals: impl Iterator<Item = String>, per_line: usize) {
    let mut count = 0usize;
    for v in vals {
        if count.is_multiple_of(per_line) {
            if count > 0 {
                s.push('\n');
            }
            s.push_str("          ");
        } else {
            s.push(' ');
        }
        s.push_str(&v);
        count += 1;
    }
    if count > 0 {
        s.push('\n');
    }
}

/// Writes a VTK XML UnstructuredGrid file (`.vtu`, ASCII, version 0.1,
/// LittleEndian) atomically.
///
/// * `dim` — 2 or 3; `x` holds the point coordinates flat
///   (`x[dim*i + c]`). Points are always written with 3 coordinates
///   (`z = 0` in 2D).
/// * `edges` become [`VTK_LINE`] (3) cells, then `triangles` become
///   [`VTK_TRIANGLE`] (5) cells, then `tets` become [`VTK_TETRA`] (10) cells,
///   in that order. Tet vertices are written in the given order (VTK expects
///   a positively oriented tet, i.e. vertex 3 on the side of the face
///   `0, 1, 2` its counter-clockwise normal points to; the writer does not
///   reorder). Pass `&[]` for `tets` in 2D or for surface-only meshes.
/// * A cell data `Int32` array `kind` holds [`KIND_EDGE`] (1) for edges,
///   [`KIND_TRIANGLE`] (2) for triangles and [`KIND_TET`] (3) for tets.
/// * `point_data` holds optional scalar `Float64` point arrays `(name, values)`
///   with one value per point.
///
/// Errors as [`vtu_string`] for inconsistent input, or with the I/O error.
pub fn write_vtu(
    path: &Path,
    dim: usize,
    x: &[f64],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    tets: &[[usize; 4]],
    point_data: &[(&str, &[f64])],
) -> io::Result<()> {
    let s = vtu_string(dim, x, edges, triangles, tets, point_data)?;
    write_atomic(path, s.as_bytes())
}

/// [`write_vtu`] with the arrays of [`VtuFields`] (vector point data, scalar cell data).
#[allow(clippy::too_many_arguments)]
pub fn write_vtu_with(
    path: &Path,
    dim: usize,
    x: &[f64],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    tets: &[[usize; 4]],
    fields: &VtuFields,
) -> io::Result<()> {
    let s = vtu_string_with(dim, x, edges, triangles, tets, fields)?;
    write_atomic(path, s.as_bytes())
}

/// The values of the data array `name` of a `.vtu` written by this module (point or cell
/// data, all components flat), parsed back; `None` if there is no such array or a value does
/// not parse. For reading outputs back in tests and scripts.
pub fn vtu_array(text: &str, name: &str) -> Option<Vec<f64>> {
    let key = format!("Name=\"{}\"", xml_escape(name));
    let start = text.find(&key)?;
    let open_end = start + text[start..].find('>')? + 1;
    let close = open_end + text[open_end..].find("</DataArray>")?;
    text[open_end..close]
        .split_whitespace()
        .map(|v| v.parse::<f64>().ok())
        .collect()
}

/// A ParaView `.pvd` collection: a time series of data files.
///
/// Push one `(time, file)` entry per frame (the file name is relative to the
/// directory of the `.pvd`) and call [`PvdSeries::write`]; rewriting the
/// `.pvd` after every frame is fine (it is written atomically).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PvdSeries {
    /// `(time, file name relative to the .pvd)` entries, in push order.
    pub entries: Vec<(f64, String)>,
}

impl PvdSeries {
    /// An empty series.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a frame at `time` stored in `file` (relative to the `.pvd`).
    pub fn push(&mut self, time: f64, file: impl Into<String>) {
        self.entries.push((time, file.into()));
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when no frame was pushed.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Renders the `.pvd` document.
    pub fn to_xml(&self) -> String {
        let mut s = String::new();
        s.push_str("<?xml version=\"1.0\"?>\n");
        s.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
        s.push_str("  <Collection>\n");
        for (t, f) in &self.entries {
            let _ = writeln!(
                s,
                "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
                fmt_f64(*t),
                xml_escape(f)
            );
        }
        s.push_str("  </Collection>\n");
        s.push_str("</VTKFile>\n");
        s
    }

    /// Writes the `.pvd` collection to `path` atomically.
    pub fn write(&self, path: &Path) -> io::Result<()> {
        write_atomic(path, self.to_xml().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;
    use std::process::Command;

    fn tmp_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("contactlab_vtk_{tag}_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Returns the whitespace-separated tokens of the DataArray named `name`.
    fn data_array(text: &str, name: &str) -> Vec<String> {
        let key = format!("Name=\"{name}\"");
        let start = text.find(&key).unwrap_or_else(|| panic!("no array {name}"));
        let open_end = start + text[start..].find('>').unwrap() + 1;
        let close = open_end + text[open_end..].find("</DataArray>").unwrap();
        text[open_end..close]
            .split_whitespace()
            .map(str::to_string)
            .collect()
    }

    /// Unit square split into two triangles, with its 4 boundary edges.
    fn square() -> (Vec<f64>, Vec<[usize; 2]>, Vec<[usize; 3]>) {
        let x = vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
        let edges = vec![[0, 1], [1, 2], [2, 3], [3, 0]];
        let tris = vec![[0, 1, 2], [0, 2, 3]];
        (x, edges, tris)
    }

    #[test]
    fn vtu_is_consistent() {
        let (x, edges, tris) = square();
        let u = [0.0, 0.5, 1.0, 1e-30];
        let dir = tmp_dir("consistent");
        let path = dir.join("mesh.vtu");
        write_vtu(&path, 2, &x, &edges, &tris, &[], &[("u", &u)]).unwrap();
        assert!(!dir.join("mesh.vtu.tmp").exists());
        let text = std::fs::read_to_string(&path).unwrap();

        assert!(text.starts_with("<?xml"));
        assert!(text.contains(
            "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
        ));
        assert!(text.contains("NumberOfPoints=\"4\""));
        assert!(text.contains("NumberOfCells=\"6\""));
        assert!(text.trim_end().ends_with("</VTKFile>"));
        for tag in [
            "VTKFile",
            "UnstructuredGrid",
            "Piece",
            "PointData",
            "CellData",
            "Points",
            "Cells",
        ] {
            assert_eq!(
                text.matches(&format!("<{tag}")).count(),
                text.matches(&format!("</{tag}>")).count(),
                "unbalanced {tag}"
            );
        }
        assert_eq!(
            text.matches("<DataArray").count(),
            text.matches("</DataArray>").count()
        );

        let pts: Vec<f64> = data_array(&text, "Points")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(pts.len(), 12);
        for i in 0..4 {
            assert_eq!(pts[3 * i], x[2 * i]);
            assert_eq!(pts[3 * i + 1], x[2 * i + 1]);
            assert_eq!(pts[3 * i + 2], 0.0);
        }

        let conn: Vec<usize> = data_array(&text, "connectivity")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        let offs: Vec<usize> = data_array(&text, "offsets")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        let types: Vec<u8> = data_array(&text, "types")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        let kind: Vec<i32> = data_array(&text, "kind")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(offs.len(), 6);
        assert_eq!(types, vec![3, 3, 3, 3, 5, 5]);
        assert_eq!(kind, vec![1, 1, 1, 1, 2, 2]);
        assert_eq!(*offs.last().unwrap(), conn.len());
        let mut prev = 0;
        for (c, (&o, &t)) in offs.iter().zip(&types).enumerate() {
            let nverts = match t {
                3 => 2,
                5 => 3,
                _ => unreachable!(),
            };
            assert_eq!(o - prev, nverts, "cell {c}");
            prev = o;
        }
        assert_eq!(conn, vec![0, 1, 1, 2, 2, 3, 3, 0, 0, 1, 2, 0, 2, 3]);
        assert!(conn.iter().all(|&i| i < 4));

        let uu: Vec<f64> = data_array(&text, "u")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(uu, u.to_vec());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn vtu_rejects_bad_input() {
        let (x, edges, tris) = square();
        assert!(vtu_string(4, &x, &edges, &tris, &[], &[]).is_err());
        assert!(vtu_string(3, &x[..7], &edges, &tris, &[], &[]).is_err());
        assert!(vtu_string(2, &x, &[[0, 4]], &[], &[], &[]).is_err());
        assert!(vtu_string(2, &x, &[], &[[0, 1, 9]], &[], &[]).is_err());
        assert!(vtu_string(2, &x, &edges, &tris, &[], &[("u", &[1.0])]).is_err());
        // A tet referencing a missing point: the error names the tet index.
        let err = vtu_string(2, &x, &edges, &tris, &[[0, 1, 2, 3], [0, 1, 2, 4]], &[]).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("tet 1"), "{err}");
        // Empty mesh is fine.
        let s = vtu_string(2, &[], &[], &[], &[], &[]).unwrap();
        assert!(s.contains("NumberOfPoints=\"0\" NumberOfCells=\"0\""));
    }

    /// A test mesh: flat points, edges, triangles, tets.
    type Mesh = (Vec<f64>, Vec<[usize; 2]>, Vec<[usize; 3]>, Vec<[usize; 4]>);

    /// Two tets sharing the face `1, 2, 3` (5 points in 3D), plus one boundary
    /// triangle and one edge, so all three cell kinds appear.
    fn two_tets() -> Mesh {
        let x = vec![
            0.0, 0.0, 0.0, // 0
            1.0, 0.0, 0.0, // 1
            0.0, 1.0, 0.0, // 2
            0.0, 0.0, 1.0, // 3
            1.0, 1.0, 1.0, // 4
        ];
        let edges = vec![[0, 4]];
        let tris = vec![[0, 2, 1]];
        // Both positively oriented: (p1-p0) x (p2-p0) . (p3-p0) > 0.
        let tets = vec![[0, 1, 2, 3], [1, 4, 2, 3]];
        (x, edges, tris, tets)
    }

    #[test]
    fn vtu_two_tets_round_trip() {
        let (x, edges, tris, tets) = two_tets();
        let u = [0.0, 1.0, 2.0, 3.0, 4.5];
        let dir = tmp_dir("tets");
        let path = dir.join("tets.vtu");
        write_vtu(&path, 3, &x, &edges, &tris, &tets, &[("u", &u)]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            vtu_string(3, &x, &edges, &tris, &tets, &[("u", &u)]).unwrap()
        );
        assert!(text.contains("NumberOfPoints=\"5\" NumberOfCells=\"4\""));

        let parse_usize = |name: &str| -> Vec<usize> {
            data_array(&text, name)
                .iter()
                .map(|t| t.parse().unwrap())
                .collect()
        };
        let pts: Vec<f64> = data_array(&text, "Points")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(pts, x, "3D points are written as given");
        let types: Vec<u8> = data_array(&text, "types")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        let kind: Vec<i32> = data_array(&text, "kind")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(types, vec![VTK_LINE, VTK_TRIANGLE, VTK_TETRA, VTK_TETRA]);
        assert_eq!(types, vec![3, 5, 10, 10]);
        assert_eq!(kind, vec![KIND_EDGE, KIND_TRIANGLE, KIND_TET, KIND_TET]);
        assert_eq!(kind, vec![1, 2, 3, 3]);
        assert_eq!(parse_usize("offsets"), vec![2, 5, 9, 13]);
        assert_eq!(
            parse_usize("connectivity"),
            vec![0, 4, 0, 2, 1, 0, 1, 2, 3, 1, 4, 2, 3]
        );

        // Tets only: offsets are multiples of 4.
        let s = vtu_string(3, &x, &[], &[], &tets, &[]).unwrap();
        let offs: Vec<usize> = data_array(&s, "offsets")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(offs, vec![4, 8]);
        assert_eq!(data_array(&s, "types"), vec!["10", "10"]);
        assert_eq!(data_array(&s, "kind"), vec!["3", "3"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Tets in a 2D file are accepted (points get z = 0); validation is by
    /// point count only.
    #[test]
    fn vtu_tets_in_2d_get_zero_z() {
        let x = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let s = vtu_string(2, &x, &[], &[], &[[0, 1, 2, 3]], &[]).unwrap();
        let pts: Vec<f64> = data_array(&s, "Points")
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(pts.len(), 12);
        assert!(pts.iter().skip(2).step_by(3).all(|&z| z == 0.0));
        assert_eq!(data_array(&s, "types"), vec!["10"]);
    }

    #[test]
    fn vtu_vectors_and_cell_data_round_trip() {
        let (x, edges, tris) = square();
        let disp: Vec<f64> = (0..12).map(|k| k as f64 * 0.25 - 1.0).collect();
        let p: Vec<f64> = vec![0.5, f64::NAN, 2.0, 1e-300];
        let cells: Vec<f64> = (0..6).map(|k| -(k as f64) / 3.0).collect();
        let fields = VtuFields {
            point_scalars: vec![("p", &p)],
            point_vectors: vec![("displacement", &disp)],
            cell_scalars: vec![("von_mises", &cells)],
        };
        let text = vtu_string_with(2, &x, &edges, &tris, &[], &fields).unwrap();
        assert!(text.contains("<PointData Scalars=\"p\" Vectors=\"displacement\">"));
        assert!(text.contains("Name=\"displacement\" NumberOfComponents=\"3\""));
        assert_eq!(vtu_array(&text, "displacement").unwrap(), disp);
        assert_eq!(vtu_array(&text, "von_mises").unwrap(), cells);
        let back = vtu_array(&text, "p").unwrap();
        assert!(back[1].is_nan() && back[0] == 0.5 && back[3] == 1e-300);
        assert_eq!(vtu_array(&text, "kind").unwrap().len(), 6);
        assert!(vtu_array(&text, "nothing").is_none());
        // wrong lengths are named errors
        let short_vectors = VtuFields {
            point_vectors: vec![("displacement", &disp[..9])],
            ..Default::default()
        };
        let short_cells = VtuFields {
            cell_scalars: vec![("s", &cells[..5])],
            ..Default::default()
        };
        for (bad, msg) in [
            (short_vectors, "'displacement' has 9 values, expected 12"),
            (short_cells, "cell data 's' has 5 values, expected 6"),
        ] {
            let e = vtu_string_with(2, &x, &edges, &tris, &[], &bad).unwrap_err();
            assert!(e.to_string().contains(msg), "{e}");
        }
        // without the new arrays the document is the one write_vtu always wrote
        assert_eq!(
            vtu_string_with(2, &x, &edges, &tris, &[], &VtuFields::default()).unwrap(),
            vtu_string(2, &x, &edges, &tris, &[], &[]).unwrap()
        );
    }

    #[test]
    fn pvd_lists_frames() {
        let dir = tmp_dir("pvd");
        let mut pvd = PvdSeries::new();
        assert!(pvd.is_empty());
        pvd.push(0.0, "frame_0000.vtu");
        pvd.write(&dir.join("series.pvd")).unwrap();
        pvd.push(1.5, "frame_0001.vtu");
        pvd.write(&dir.join("series.pvd")).unwrap();
        let text = std::fs::read_to_string(dir.join("series.pvd")).unwrap();
        assert!(text.contains("type=\"Collection\""));
        assert_eq!(text.matches("<DataSet").count(), 2);
        assert!(text.contains("file=\"frame_0001.vtu\""));
        assert!(text.contains("timestep=\"1.5e0\""));
        assert!(!dir.join("series.pvd.tmp").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn meshio_available() -> bool {
        Command::new("python3")
            .args(["-c", "import meshio"])
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false)
    }

    /// Reads the file back with Python `meshio` when it is importable;
    /// otherwise prints "meshio not installed, skipped".
    #[test]
    fn vtu_readable_by_meshio() {
        if !meshio_available() {
            println!("meshio not installed, skipped");
            return;
        }
        let (x, edges, tris) = square();
        let u = [1.0, 2.0, 3.0, 4.0];
        let dir = tmp_dir("meshio");
        let path = dir.join("mesh.vtu");
        write_vtu(&path, 2, &x, &edges, &tris, &[], &[("u", &u), ("v", &u)]).unwrap();
        let script = r#"
import sys, meshio
m = meshio.read(sys.argv[1])
counts = {b.type: len(b.data) for b in m.cells}
print(len(m.points), counts.get("line", 0), counts.get("triangle", 0),
      sorted(m.point_data.keys()), int(sum(int(k.sum()) for k in m.cell_data["kind"])),
      float(m.point_data["u"].sum()))
"#;
        let out = Command::new("python3")
            .arg("-c")
            .arg(script)
            .arg(&path)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "meshio failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        // 4 points, 4 lines, 2 triangles, kind sum = 4*1 + 2*2 = 8, u sum = 10.
        assert_eq!(stdout.trim(), "4 4 2 ['u', 'v'] 8 10.0", "got {stdout}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
