//! Wavefront `.obj` reader (see [`super`] for what is read): `v` points, `l` polylines (each
//! consecutive pair of a polyline is one line element), `f` polygons (triangulated as a fan
//! from their first vertex). Indices are 1-based; a negative index `-k` is the `k`-th last
//! vertex read so far. A reference to a vertex that the file never defines is an error naming
//! its line.

use super::{Element, MeshData, MeshReadError};

/// Parses the text of a `.obj` file; `path` names it in errors.
pub fn parse_obj(text: &str, path: &str) -> Result<MeshData, MeshReadError> {
    let err = |line: usize, message: String| MeshReadError::Parse {
        path: path.to_string(),
        line,
        message,
    };
    let mut data = MeshData::default();
    // polylines and polygons as raw 0-based indices, checked at the end (forward references)
    let mut polylines: Vec<(usize, Vec<usize>)> = Vec::new();
    let mut polygons: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.split('#').next().unwrap_or("").trim();
        if l.is_empty() {
            continue;
        }
        let mut t = l.split_whitespace();
        let key = t.next().unwrap_or("");
        match key {
            "v" => {
                let vals: Vec<&str> = t.collect();
                if vals.len() < 2 || vals.len() > 4 {
                    return Err(err(
                        line,
                        format!("`v` takes 2 to 4 coordinates, found {} in {l:?}", vals.len()),
                    ));
                }
                let mut p = [0.0; 3];
                for (k, s) in vals.iter().take(3).enumerate() {
                    p[k] = s.parse().map_err(|_| {
                        err(line, format!("coordinate {s:?} is not a valid number"))
                    })?;
                }
                data.points.push(p);
                data.point_lines.push(line);
            }
            "l" | "f" => {
                let mut idx = Vec::new();
                for tok in t {
                    let first = tok.split('/').next().unwrap_or("");
                    let k: i64 = first.parse().map_err(|_| {
                        err(line, format!("vertex reference {tok:?} is not an integer"))
                    })?;
                    let n = data.points.len() as i64;
                    let v = if k > 0 {
                        k - 1
                    } else if k < 0 {
                        if -k > n {
                            return Err(err(
                                line,
                                format!(
                                    "relative vertex reference {k} goes before the first vertex \
                                     ({n} read so far)"
                                ),
                            ));
                        }
                        n + k
                    } else {
                        return Err(err(line, "vertex reference 0 (indices are 1-based)".into()));
                    };
                    idx.push(v as usize);
                }
                let need = if key == "l" { 2 } else { 3 };
                if idx.len() < need {
                    return Err(err(
                        line,
                        format!("`{key}` needs at least {need} vertices, found {} in {l:?}", idx.len()),
                    ));
                }
                if key == "l" {
                    polylines.push((line, idx));
                } else {
                    polygons.push((line, idx));
                }
            }
            "vt" | "vn" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" => {}
            other => {
                return Err(err(
                    line,
                    format!("unsupported statement {other:?} (supported: v, l, f; ignored: vt, vn, vp, o, g, s, usemtl, mtllib)"),
                ))
            }
        }
    }
    let nv = data.points.len();
    let check = |line: usize, idx: &[usize]| {
        for &v in idx {
            if v >= nv {
                return Err(err(
                    line,
                    format!(
                        "vertex reference {} but the file defines {nv} vertices",
                        v + 1
                    ),
                ));
            }
        }
        Ok(())
    };
    for (line, idx) in polylines {
        check(line, &idx)?;
        for w in idx.windows(2) {
            data.lines.push(Element {
                v: [w[0], w[1]],
                line,
            });
        }
    }
    for (line, idx) in polygons {
        check(line, &idx)?;
        for k in 1..idx.len() - 1 {
            data.triangles.push(Element {
                v: [idx[0], idx[k], idx[k + 1]],
                line,
            });
        }
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_reads_polylines_faces_and_relative_indices() {
        let text = "# a square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvt 0 0\nvn 0 0 1\no sq\nl 1 2 3\nf 1/1/1 2/1/1 3/1/1 -1/1/1\n";
        let m = parse_obj(text, "a.obj").unwrap();
        assert_eq!(m.points.len(), 4);
        assert_eq!(
            m.lines.iter().map(|e| e.v).collect::<Vec<_>>(),
            vec![[0, 1], [1, 2]]
        );
        assert_eq!(
            m.triangles.iter().map(|e| e.v).collect::<Vec<_>>(),
            vec![[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(m.triangles[1].line, 10);
    }

    #[test]
    fn obj_errors_name_line_and_token() {
        let e = parse_obj("v 0 0 0\nv 1 x 0\n", "a.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.obj:2") && e.contains("\"x\""), "{e}");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nl 1 3\n", "a.obj")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("a.obj:3") && e.contains("vertex reference 3"),
            "{e}"
        );
        let e = parse_obj("v 0 0 0\nl 1 -2\n", "a.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.obj:2") && e.contains("-2"), "{e}");
        let e = parse_obj("v 0 0 0\ncurv 0 1 1 2\n", "a.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.obj:2") && e.contains("\"curv\""), "{e}");
        let e = parse_obj("v 0 0 0\nl 0 1\n", "a.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.obj:2") && e.contains("reference 0"), "{e}");
    }
}
