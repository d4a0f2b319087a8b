//! 3D configurations in a fixed isometric projection: faces filled and shaded in painter's
//! order, edges that belong to no face drawn as lines, beside the energy history.

use super::energy::{energy_panels, EnergySeries};
use super::*;
use std::collections::BTreeSet;

/// One 3D configuration to draw with [`projection_svg`]: positions flat
/// (`x[3*i]`, `x[3*i+1]`, `x[3*i+2]`), triangular faces filled and shaded,
/// edges that belong to no face drawn as lines.
#[derive(Debug, Clone)]
pub struct Shape3<'a> {
    /// Panel label, e.g. `"initial (k=0)"`.
    pub label: String,
    /// Flat 3D positions (xyz per point).
    pub x: &'a [f64],
    /// Edges (pairs of point indices). Edges that are also a side of one of
    /// the `faces` (in either orientation) are not drawn separately.
    pub edges: &'a [[usize; 2]],
    /// Triangular faces (triples of point indices).
    pub faces: &'a [[usize; 3]],
}

/// Isometric projection of a 3D point: `(page x, page y with y up, depth)`.
///
/// The viewer looks from the direction `v = (1, −1, 1)/√3` (so `depth = p·v`
/// grows towards the viewer); the page axes are `right = (1, 1, 0)/√2` and
/// `up = (−1, 1, 2)/√6`, so `z` points up on the page and `(right, up, v)` is
/// right-handed.
pub(super) fn project(p: [f64; 3]) -> (f64, f64, f64) {
    let (s2, s3, s6) = (2f64.sqrt(), 3f64.sqrt(), 6f64.sqrt());
    let right = (p[0] + p[1]) / s2;
    let up = (-p[0] + p[1] + 2.0 * p[2]) / s6;
    let depth = (p[0] - p[1] + p[2]) / s3;
    (right, up, depth)
}

/// Point `i` of the flat xyz array `x`, if it exists and all its coordinates
/// (and their projection) are finite.
fn point3(x: &[f64], i: usize) -> Option<[f64; 3]> {
    let p = [*x.get(3 * i)?, *x.get(3 * i + 1)?, *x.get(3 * i + 2)?];
    let (a, b, d) = project(p);
    (p.iter().all(|c| c.is_finite()) && a.is_finite() && b.is_finite() && d.is_finite())
        .then_some(p)
}

/// Common bounding box, in projected page coordinates (y up), of all finite
/// points of all panels.
fn bbox3(panels: &[Shape3]) -> (f64, f64, f64, f64) {
    let (mut x0, mut y0, mut x1, mut y1) =
        (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
    for s in panels {
        for i in 0..s.x.len() / 3 {
            if let Some(p) = point3(s.x, i) {
                let (a, b, _) = project(p);
                x0 = x0.min(a);
                x1 = x1.max(a);
                y0 = y0.min(b);
                y1 = y1.max(b);
            }
        }
    }
    if x0 > x1 {
        return (0.0, 0.0, 1.0, 1.0);
    }
    (x0, y0, x1, y1)
}

/// A face ready to draw: its index, the depth of its centroid and its three
/// 3D vertices (all finite).
type DrawFace = (usize, f64, [[f64; 3]; 3]);

/// The faces of `s` whose vertices all exist and are finite, in painter's
/// order: by depth of the centroid along the view direction, far first,
/// ties broken by face index.
pub(super) fn painter_faces(s: &Shape3) -> Vec<DrawFace> {
    let mut faces: Vec<DrawFace> = s
        .faces
        .iter()
        .enumerate()
        .filter_map(|(k, f)| {
            let v = [point3(s.x, f[0])?, point3(s.x, f[1])?, point3(s.x, f[2])?];
            // Divide first so that the sum cannot overflow.
            let depth = v.iter().map(|&p| project(p).2 / 3.0).sum::<f64>();
            Some((k, depth, v))
        })
        .collect();
    faces.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    faces
}

/// Grey level (0–255) of a face: `|n·v|` (unit normal `n`, view direction
/// `v`) mapped to 150 (edge-on) … 245 (facing the viewer). Degenerate faces
/// get the darkest level.
pub(super) fn face_grey(v: &[[f64; 3]; 3]) -> u8 {
    let a = [v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]];
    let b = [v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]];
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let c = project(n).2.abs() / norm;
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    (150.0 + 95.0 * c).round() as u8
}

/// Draws one 3D panel with its top-left corner at `(ox, oy)`.
fn shape3_panel(out: &mut String, s: &Shape3, ox: f64, oy: f64, bb: (f64, f64, f64, f64)) {
    let pm = PanelMap::fit(bb, ox, oy);
    // Page position of a finite 3D point, if it is finite too.
    let map = |p: [f64; 3]| {
        let (a, b, _) = project(p);
        let q = pm.map((a, b));
        (q.0.is_finite() && q.1.is_finite()).then_some(q)
    };

    panel_frame(out, "shape3", &s.label, ox, oy);

    // Faces, far first.
    let _ = writeln!(
        out,
        "<g class=\"faces\" stroke=\"#555555\" stroke-width=\"0.5\" stroke-linejoin=\"round\">"
    );
    for (_, _, v) in painter_faces(s) {
        let ps: Option<Vec<(f64, f64)>> = v.iter().map(|&p| map(p)).collect();
        if let Some(ps) = ps {
            let g = face_grey(&v);
            let _ = writeln!(
                out,
                "<polygon points=\"{:.2},{:.2} {:.2},{:.2} {:.2},{:.2}\" fill=\"#{g:02x}{g:02x}{g:02x}\"/>",
                ps[0].0, ps[0].1, ps[1].0, ps[1].1, ps[2].0, ps[2].1
            );
        }
    }
    let _ = writeln!(out, "</g>");

    // Edges that are no side of any face (e.g. curves), on top of the faces.
    let face_edges: BTreeSet<(usize, usize)> = s
        .faces
        .iter()
        .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    let _ = writeln!(
        out,
        "<g class=\"edges\" stroke=\"#1f3b73\" stroke-width=\"1.2\" stroke-linecap=\"round\">"
    );
    for e in s.edges {
        if face_edges.contains(&(e[0].min(e[1]), e[0].max(e[1]))) {
            continue;
        }
        let a = point3(s.x, e[0]).and_then(map);
        let b = point3(s.x, e[1]).and_then(map);
        if let (Some(a), Some(b)) = (a, b) {
            let _ = writeln!(
                out,
                "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\"/>",
                a.0, a.1, b.0, b.1
            );
        }
    }
    let _ = writeln!(out, "</g>");
    if s.edges.is_empty() && s.faces.is_empty() {
        // Bare point cloud: draw the points so the panel is not empty.
        let _ = writeln!(out, "<g class=\"points\" fill=\"#1f3b73\">");
        for i in 0..s.x.len() / 3 {
            if let Some(q) = point3(s.x, i).and_then(map) {
                let _ = writeln!(out, "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"2\"/>", q.0, q.1);
            }
        }
        let _ = writeln!(out, "</g>");
    }

    // Axis triad in the bottom-left corner (a path, so `<line` counts edges).
    let (tx, ty) = (
        ox + INNER_PAD + 16.0,
        oy + LABEL_H + PANEL - INNER_PAD - 16.0,
    );
    let mut d = String::new();
    let mut labels = String::new();
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let mut unit = [0.0; 3];
        unit[k] = 1.0;
        let (a, b, _) = project(unit);
        let (ex, ey) = (tx + 14.0 * a, ty - 14.0 * b);
        let _ = write!(d, "M{tx:.1},{ty:.1} L{ex:.1},{ey:.1} ");
        let _ = writeln!(
            labels,
            "<text x=\"{:.1}\" y=\"{:.1}\">{name}</text>",
            tx + 20.0 * a,
            ty - 20.0 * b + 3.5
        );
    }
    let _ = writeln!(
        out,
        "<g class=\"axes\" font-size=\"9\" text-anchor=\"middle\" fill=\"#888888\">"
    );
    let _ = writeln!(
        out,
        "<path d=\"{}\" stroke=\"#888888\" stroke-width=\"0.8\" fill=\"none\"/>",
        d.trim_end()
    );
    out.push_str(&labels);
    let _ = writeln!(out, "</g>");
    let _ = writeln!(out, "</g>");
}

/// Builds one SVG document for a 3D run: one panel per configuration, then
/// the same energy panel(s) as [`shapes_and_energy_svg`] (`J` against the
/// outer iteration, plus a log-scale `J − J_final` panel when some value is
/// positive).
///
/// Every panel uses the same fixed isometric projection (viewer in the
/// direction `(1, −1, 1)/√3`, `z` up on the page, a small `x y z` axis triad
/// in the bottom-left corner) and the same bounding box (of the projections
/// of all finite points of all panels, equal aspect), so panels can be
/// compared directly. Faces are drawn as `<polygon>` elements with a darker
/// outline, filled light grey shaded by `|n·v|` (unit normal `n`, view
/// direction `v`), in painter's order (centroid depth, far first, ties by
/// face index). Then the [`Shape3::edges`] that are no side of any face are
/// drawn on top as `<line>` elements (not hidden by faces). A panel with
/// neither edges nor faces shows its points.
///
/// Faces and edges with a missing point or a non-finite coordinate are
/// skipped, so the output never contains `NaN`. The `<polygon` count is the
/// number of drawn faces and the `<line` count the number of drawn free edges
/// over all panels. The output is deterministic.
pub fn projection_svg(panels: &[Shape3<'_>], energy: &[(usize, f64)], title: &str) -> String {
    let es = EnergySeries::new(energy);
    let panel_h = LABEL_H + PANEL;
    let n = panels.len() as f64;
    let width = MARGIN + n * (PANEL + MARGIN) + es.n_plots() * (PLOT_W + MARGIN);
    let height = TITLE_H + panel_h + MARGIN;

    let mut out = String::new();
    svg_open(&mut out, width, height, title);

    let bb = bbox3(panels);
    let mut ox = MARGIN;
    for s in panels {
        shape3_panel(&mut out, s, ox, TITLE_H, bb);
        ox += PANEL + MARGIN;
    }

    energy_panels(&mut out, &es, ox, panel_h);

    out.push_str("</svg>\n");
    out
}
