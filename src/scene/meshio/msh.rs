//! Gmsh `.msh` reader, ASCII formats 2.2 and 4.1 (see [`super`] for what is read).
//!
//! Format 2.2: `$Nodes` = count, then `tag x y z` lines; `$Elements` = count, then
//! `tag type ntags tag… node…` lines. Format 4.1: `$Nodes` = `numBlocks numNodes min max`,
//! then per block `entityDim entityTag parametric n`, `n` tag lines and `n` coordinate lines;
//! `$Elements` = `numBlocks numElements min max`, then per block
//! `entityDim entityTag type n` and `n` lines `tag node…`. Other sections (`$Entities`,
//! `$PhysicalNames`, …) are skipped.

use super::{Element, MeshData, MeshReadError};
use std::collections::HashMap;

/// Lines of the text with their 1-based numbers, blank lines skipped.
struct Lines<'a> {
    it: std::iter::Enumerate<std::str::Lines<'a>>,
    path: &'a str,
    last: usize,
}

impl<'a> Lines<'a> {
    fn next(&mut self) -> Option<(usize, &'a str)> {
        for (i, l) in self.it.by_ref() {
            self.last = i + 1;
            let t = l.trim();
            if !t.is_empty() {
                return Some((i + 1, t));
            }
        }
        None
    }

    fn err(&self, line: usize, message: String) -> MeshReadError {
        MeshReadError::Parse {
            path: self.path.to_string(),
            line,
            message,
        }
    }

    /// The next non-blank line, or an error saying what was expected.
    fn expect(&mut self, what: &str) -> Result<(usize, &'a str), MeshReadError> {
        let last = self.last;
        self.next()
            .ok_or_else(|| self.err(last, format!("unexpected end of file: expected {what}")))
    }
}

fn num<T: std::str::FromStr>(
    lines: &Lines,
    line: usize,
    tok: Option<&str>,
    what: &str,
) -> Result<T, MeshReadError> {
    let tok = tok.ok_or_else(|| lines.err(line, format!("missing {what}")))?;
    tok.parse()
        .map_err(|_| lines.err(line, format!("{what} {tok:?} is not a valid number")))
}

/// Number of nodes of a Gmsh element type, for the types this reader knows.
fn nodes_of(t: u32) -> Option<(usize, &'static str)> {
    Some(match t {
        1 => (2, "2-node line"),
        2 => (3, "3-node triangle"),
        3 => (4, "4-node quadrangle"),
        4 => (4, "4-node tetrahedron"),
        5 => (8, "8-node hexahedron"),
        6 => (6, "6-node prism"),
        7 => (5, "5-node pyramid"),
        8 => (3, "3-node second-order line"),
        9 => (6, "6-node second-order triangle"),
        11 => (10, "10-node second-order tetrahedron"),
        15 => (1, "1-node point"),
        _ => return None,
    })
}

/// Collects the elements while reading.
struct Builder {
    tags: HashMap<u64, usize>,
    data: MeshData,
}

impl Builder {
    fn node(
        &mut self,
        lines: &Lines,
        line: usize,
        tag: u64,
        p: [f64; 3],
    ) -> Result<(), MeshReadError> {
        if self.tags.insert(tag, self.data.points.len()).is_some() {
            return Err(lines.err(line, format!("node tag {tag} is defined twice")));
        }
        self.data.points.push(p);
        self.data.point_lines.push(line);
        Ok(())
    }

    fn element(
        &mut self,
        lines: &Lines,
        line: usize,
        etype: u32,
        nodes: &[u64],
    ) -> Result<(), MeshReadError> {
        let mut v = [0usize; 4];
        for (k, tag) in nodes.iter().enumerate() {
            v[k] = *self.tags.get(tag).ok_or_else(|| {
                lines.err(
                    line,
                    format!("element refers to node tag {tag}, which is not in $Nodes"),
                )
            })?;
        }
        match etype {
            1 => self.data.lines.push(Element {
                v: [v[0], v[1]],
                line,
            }),
            2 => self.data.triangles.push(Element {
                v: [v[0], v[1], v[2]],
                line,
            }),
            4 => self.data.tets.push(Element { v, line }),
            _ => {}
        }
        Ok(())
    }
}

fn check_type(lines: &Lines, line: usize, etype: u32) -> Result<usize, MeshReadError> {
    match nodes_of(etype) {
        Some((n, _)) if matches!(etype, 1 | 2 | 4 | 15) => Ok(n),
        Some((_, name)) => Err(lines.err(
            line,
            format!(
                "element type {etype} ({name}) is not supported: only P1 lines (1), triangles \
                 (2), tetrahedra (4) and points (15)"
            ),
        )),
        None => Err(lines.err(line, format!("unknown element type {etype}"))),
    }
}

/// Parses the text of a `.msh` file; `path` names it in errors.
pub fn parse_msh(text: &str, path: &str) -> Result<MeshData, MeshReadError> {
    let mut lines = Lines {
        it: text.lines().enumerate(),
        path,
        last: 0,
    };
    let mut version: Option<u32> = None; // 2 or 4
    let mut b = Builder {
        tags: HashMap::new(),
        data: MeshData::default(),
    };
    let (mut seen_nodes, mut seen_elements) = (false, false);
    while let Some((line, l)) = lines.next() {
        if !l.starts_with('$') {
            return Err(lines.err(
                line,
                format!("expected a section header like $Nodes, found {l:?}"),
            ));
        }
        let section = &l[1..];
        match section {
            "MeshFormat" => {
                let (fl, f) = lines.expect("the format line `version file-type data-size`")?;
                let mut t = f.split_whitespace();
                let v: &str = t.next().unwrap_or("");
                version = match v {
                    "2.2" | "2.1" | "2" | "2.0" => Some(2),
                    "4.1" => Some(4),
                    _ => {
                        return Err(lines.err(
                            fl,
                            format!("mesh format version {v:?} is not supported (2.2 or 4.1)"),
                        ))
                    }
                };
                let ft: u32 = num(&lines, fl, t.next(), "file-type")?;
                if ft != 0 {
                    return Err(lines.err(
                        fl,
                        format!(
                            "file-type {ft}: binary .msh files are not supported, save as ASCII"
                        ),
                    ));
                }
            }
            "Nodes" => {
                let v =
                    version.ok_or_else(|| lines.err(line, "$Nodes before $MeshFormat".into()))?;
                if seen_nodes {
                    return Err(lines.err(line, "a second $Nodes section".into()));
                }
                seen_nodes = true;
                if v == 2 {
                    read_nodes_2(&mut lines, &mut b)?;
                } else {
                    read_nodes_4(&mut lines, &mut b)?;
                }
            }
            "Elements" => {
                let v = version
                    .ok_or_else(|| lines.err(line, "$Elements before $MeshFormat".into()))?;
                if !seen_nodes {
                    return Err(lines.err(line, "$Elements before $Nodes".into()));
                }
                if seen_elements {
                    return Err(lines.err(line, "a second $Elements section".into()));
                }
                seen_elements = true;
                if v == 2 {
                    read_elements_2(&mut lines, &mut b)?;
                } else {
                    read_elements_4(&mut lines, &mut b)?;
                }
            }
            s if s.starts_with("End") => {
                return Err(lines.err(line, format!("{l} without its opening section")));
            }
            _ => {
                // skip an unknown section up to its end marker
                let end = format!("$End{section}");
                loop {
                    let (_, l2) = lines.expect(&end)?;
                    if l2 == end {
                        break;
                    }
                }
                continue;
            }
        }
        let end = format!("$End{section}");
        let (el, l2) = lines.expect(&end)?;
        if l2 != end {
            return Err(lines.err(el, format!("expected {end}, found {l2:?}")));
        }
    }
    if version.is_none() {
        return Err(lines.err(0, "no $MeshFormat section: not a Gmsh .msh file".into()));
    }
    if !seen_nodes || !seen_elements {
        return Err(lines.err(0, "the file needs a $Nodes and an $Elements section".into()));
    }
    Ok(b.data)
}

fn coords(
    lines: &Lines,
    line: usize,
    t: &mut std::str::SplitWhitespace,
) -> Result<[f64; 3], MeshReadError> {
    let mut p = [0.0; 3];
    for (k, c) in p.iter_mut().enumerate() {
        *c = num(lines, line, t.next(), ["x", "y", "z"][k])?;
    }
    Ok(p)
}

fn read_nodes_2(lines: &mut Lines, b: &mut Builder) -> Result<(), MeshReadError> {
    let (cl, c) = lines.expect("the number of nodes")?;
    let n: u64 = num(lines, cl, Some(c), "number of nodes")?;
    for _ in 0..n {
        let (line, l) = lines.expect("a node line `tag x y z`")?;
        let mut t = l.split_whitespace();
        let tag: u64 = num(lines, line, t.next(), "node tag")?;
        let p = coords(lines, line, &mut t)?;
        b.node(lines, line, tag, p)?;
    }
    Ok(())
}

fn read_elements_2(lines: &mut Lines, b: &mut Builder) -> Result<(), MeshReadError> {
    let (cl, c) = lines.expect("the number of elements")?;
    let n: u64 = num(lines, cl, Some(c), "number of elements")?;
    for _ in 0..n {
        let (line, l) = lines.expect("an element line `tag type ntags tags… nodes…`")?;
        let mut t = l.split_whitespace();
        let _tag: u64 = num(lines, line, t.next(), "element tag")?;
        let etype: u32 = num(lines, line, t.next(), "element type")?;
        let nn = check_type(lines, line, etype)?;
        let ntags: u32 = num(lines, line, t.next(), "number of tags")?;
        for _ in 0..ntags {
            let _: i64 = num(lines, line, t.next(), "tag")?;
        }
        let mut nodes = [0u64; 4];
        for node in nodes.iter_mut().take(nn) {
            *node = num(lines, line, t.next(), "node tag")?;
        }
        if let Some(extra) = t.next() {
            return Err(lines.err(
                line,
                format!("unexpected token {extra:?} after the element's nodes"),
            ));
        }
        b.element(lines, line, etype, &nodes[..nn])?;
    }
    Ok(())
}

fn read_nodes_4(lines: &mut Lines, b: &mut Builder) -> Result<(), MeshReadError> {
    let (hl, h) = lines.expect("`numEntityBlocks numNodes minNodeTag maxNodeTag`")?;
    let mut t = h.split_whitespace();
    let blocks: u64 = num(lines, hl, t.next(), "numEntityBlocks")?;
    let total: u64 = num(lines, hl, t.next(), "numNodes")?;
    let mut count = 0u64;
    for _ in 0..blocks {
        let (bl, bh) = lines.expect("a node block header `entityDim entityTag parametric n`")?;
        let mut t = bh.split_whitespace();
        let _dim: u32 = num(lines, bl, t.next(), "entityDim")?;
        let _tag: i64 = num(lines, bl, t.next(), "entityTag")?;
        let parametric: u32 = num(lines, bl, t.next(), "parametric")?;
        if parametric != 0 {
            return Err(lines.err(bl, "parametric nodes are not supported".into()));
        }
        let n: u64 = num(lines, bl, t.next(), "numNodesInBlock")?;
        let mut tags = Vec::new();
        for _ in 0..n {
            let (line, l) = lines.expect("a node tag")?;
            tags.push(num::<u64>(lines, line, Some(l), "node tag")?);
        }
        for tag in tags {
            let (line, l) = lines.expect("a coordinate line `x y z`")?;
            let mut t = l.split_whitespace();
            let p = coords(lines, line, &mut t)?;
            b.node(lines, line, tag, p)?;
        }
        count += n;
    }
    if count != total {
        return Err(lines.err(
            hl,
            format!("numNodes = {total} but the blocks hold {count} nodes"),
        ));
    }
    Ok(())
}

fn read_elements_4(lines: &mut Lines, b: &mut Builder) -> Result<(), MeshReadError> {
    let (hl, h) = lines.expect("`numEntityBlocks numElements minTag maxTag`")?;
    let mut t = h.split_whitespace();
    let blocks: u64 = num(lines, hl, t.next(), "numEntityBlocks")?;
    let total: u64 = num(lines, hl, t.next(), "numElements")?;
    let mut count = 0u64;
    for _ in 0..blocks {
        let (bl, bh) = lines.expect("an element block header `entityDim entityTag type n`")?;
        let mut t = bh.split_whitespace();
        let _dim: u32 = num(lines, bl, t.next(), "entityDim")?;
        let _tag: i64 = num(lines, bl, t.next(), "entityTag")?;
        let etype: u32 = num(lines, bl, t.next(), "elementType")?;
        let nn = check_type(lines, bl, etype)?;
        let n: u64 = num(lines, bl, t.next(), "numElementsInBlock")?;
        for _ in 0..n {
            let (line, l) = lines.expect("an element line `tag node…`")?;
            let mut t = l.split_whitespace();
            let _tag: u64 = num(lines, line, t.next(), "element tag")?;
            let mut nodes = [0u64; 4];
            for node in nodes.iter_mut().take(nn) {
                *node = num(lines, line, t.next(), "node tag")?;
            }
            if let Some(extra) = t.next() {
                return Err(lines.err(
                    line,
                    format!("unexpected token {extra:?} after the element's nodes"),
                ));
            }
            b.element(lines, line, etype, &nodes[..nn])?;
        }
        count += n;
    }
    if count != total {
        return Err(lines.err(
            hl,
            format!("numElements = {total} but the blocks hold {count} elements"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const V22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"body\"\n$EndPhysicalNames\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n7 1 1 0\n$EndNodes\n$Elements\n4\n1 15 2 0 1 1\n2 1 2 0 1 1 2\n3 2 2 1 1 1 2 3\n4 2 2 1 1 2 7 3\n$EndElements\n";

    const V41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 1 0\n1 0 0 0 1 1 0 0 0\n$EndEntities\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n2 3 1 3\n3 1 4 1\n1 1 2 3 4\n2 1 1 2\n5 1 2\n6 2 3\n$EndElements\n";

    #[test]
    fn msh_reads_format_22() {
        let m = parse_msh(V22, "a.msh").unwrap();
        assert_eq!(m.points.len(), 4);
        assert_eq!(m.points[3], [1.0, 1.0, 0.0]);
        assert_eq!(m.lines.len(), 1);
        assert_eq!(m.lines[0].v, [0, 1]);
        assert_eq!(
            m.triangles.iter().map(|t| t.v).collect::<Vec<_>>(),
            vec![[0, 1, 2], [1, 3, 2]]
        );
        assert_eq!(m.triangles[1].line, 20);
    }

    #[test]
    fn msh_reads_format_41() {
        let m = parse_msh(V41, "a.msh").unwrap();
        assert_eq!(m.points.len(), 4);
        assert_eq!(m.tets.len(), 1);
        assert_eq!(m.tets[0].v, [0, 1, 2, 3]);
        assert_eq!(
            m.lines.iter().map(|t| t.v).collect::<Vec<_>>(),
            vec![[0, 1], [1, 2]]
        );
    }

    #[test]
    fn msh_errors_name_line_and_token() {
        let bad = V22.replace("2 1 0 0\n", "2 1 zz 0\n");
        let e = parse_msh(&bad, "a.msh").unwrap_err().to_string();
        assert!(e.contains("a.msh:11") && e.contains("\"zz\""), "{e}");
        let bad = V22.replace("4 2 2 1 1 2 7 3", "4 2 2 1 1 2 8 3");
        let e = parse_msh(&bad, "a.msh").unwrap_err().to_string();
        assert!(e.contains("a.msh:20") && e.contains("node tag 8"), "{e}");
        let bad = V22.replace("3 2 2 1 1 1 2 3", "3 9 2 1 1 1 2 3 4 5 6");
        let e = parse_msh(&bad, "a.msh").unwrap_err().to_string();
        assert!(e.contains("a.msh:19") && e.contains("type 9"), "{e}");
        let bad = V22.replace("2.2 0 8", "2.2 1 8");
        let e = parse_msh(&bad, "a.msh").unwrap_err().to_string();
        assert!(e.contains("a.msh:2") && e.contains("binary"), "{e}");
        let e = parse_msh(&V22[..V22.len() - 29], "a.msh")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unexpected end of file"), "{e}");
    }
}
