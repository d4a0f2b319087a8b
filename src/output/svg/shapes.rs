//! 2D shapes: one panel per configuration (common bounding box, equal aspect), edges as
//! lines and triangles as light-filled polygons, beside the energy history.

use super::energy::{energy_panels, EnergySeries};
use super::*;

/// One 2D shape to draw: positions flat (`x[2*i]`, `x[2*i+1]`), edges drawn
/// as lines and triangles as light-filled polygons.
#[derive(Debug, Clone)]
pub struct Shape<'a> {
    /// Panel label, e.g. `"initial (k=0)"`.
    pub label: String,
    /// Flat 2D positions.
    pub x: &'a [f64],
    /// Edges (pairs of point indices).
    pub edges: &'a [[usize; 2]],
    /// Triangles (triples of point indices).
    pub triangles: &'a [[usize; 3]],
}

fn point(x: &[f64], i: usize) -> Option<(f64, f64)> {
    let (a, b) = (*x.get(2 * i)?, *x.get(2 * i + 1)?);
    (a.is_finite() && b.is_finite()).then_some((a, b))
}

/// Common bounding box of all finite points of all shapes.
fn bbox(shapes: &[Shape]) -> (f64, f64, f64, f64) {
    let (mut x0, mut y0, mut x1, mut y1) =
        (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
    for s in shapes {
        for p in s.x.chunks_exact(2) {
            if p[0].is_finite() && p[1].is_finite() {
                x0 = x0.min(p[0]);
                x1 = x1.max(p[0]);
                y0 = y0.min(p[1]);
                y1 = y1.max(p[1]);
            }
        }
    }
    if x0 > x1 {
        return (0.0, 0.0, 1.0, 1.0);
    }
    (x0, y0, x1, y1)
}

/// Draws one shape panel with its top-left corner at `(ox, oy)`.
fn shape_panel(out: &mut String, s: &Shape, ox: f64, oy: f64, bb: (f64, f64, f64, f64)) {
    let pm = PanelMap::fit(bb, ox, oy);
    let map = |p: (f64, f64)| pm.map(p);

    panel_frame(out, "shape", &s.label, ox, oy);
    let _ = writeln!(
        out,
        "<g class=\"triangles\" fill=\"#cfe0f3\" stroke=\"#9db8d6\" stroke-width=\"0.4\">"
    );
    for t in s.triangles {
        let ps: Option<Vec<(f64, f64)>> = t.iter().map(|&i| point(s.x, i).map(map)).collect();
        if let Some(ps) = ps {
            let _ = writeln!(
                out,
                "<polygon points=\"{:.2},{:.2} {:.2},{:.2} {:.2},{:.2}\"/>",
                ps[0].0, ps[0].1, ps[1].0, ps[1].1, ps[2].0, ps[2].1
            );
        }
    }
    let _ = writeln!(out, "</g>");
    let _ = writeln!(
        out,
        "<g class=\"edges\" stroke=\"#1f3b73\" stroke-width=\"1.2\" stroke-linecap=\"round\">"
    );
    for e in s.edges {
        // Edges with invalid indices or non-finite coordinates are skipped.
        if let (Some(a), Some(b)) = (point(s.x, e[0]), point(s.x, e[1])) {
            let (a, b) = (map(a), map(b));
            let _ = writeln!(
                out,
                "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\"/>",
                a.0, a.1, b.0, b.1
            );
        }
    }
    let _ = writeln!(out, "</g>");
    if s.edges.is_empty() && s.triangles.is_empty() {
        // Bare point cloud: draw the points so the panel is not empty.
        let _ = writeln!(out, "<g class=\"points\" fill=\"#1f3b73\">");
        for p in s.x.chunks_exact(2) {
            if let Some(q) = point(p, 0) {
                let q = map(q);
                let _ = writeln!(out, "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"2\"/>", q.0, q.1);
            }
        }
        let _ = writeln!(out, "</g>");
    }
    let _ = writeln!(out, "</g>");
}

/// Builds one SVG document: one panel per shape (equal aspect, common
/// bounding box over all shapes, edges as lines, triangles as light-filled
/// polygons, labelled with [`Shape::label`]), then a panel plotting `J`
/// against the outer iteration (linear axes, tick labels with at least 6
/// significant digits), then — if at least one `J − J_final` is positive — a
/// panel of `J − J_final` on a log scale.
///
/// `energy` holds `(outer iteration, J)` pairs (sorted by iteration here;
/// non-finite `J` are dropped). Degenerate inputs (no shapes, a single point,
/// constant or empty energy) produce a valid SVG without `NaN`.
///
/// Only mesh edges are drawn with `<line>` elements, so the number of
/// `<line` occurrences equals the number of drawn edges over all panels.
pub fn shapes_and_energy_svg(shapes: &[Shape], energy: &[(usize, f64)], title: &str) -> String {
    let es = EnergySeries::new(energy);
    let panel_h = LABEL_H + PANEL;
    let n = shapes.len() as f64;
    let width = MARGIN + n * (PANEL + MARGIN) + es.n_plots() * (PLOT_W + MARGIN);
    let height = TITLE_H + panel_h + MARGIN;

    let mut out = String::new();
    svg_open(&mut out, width, height, title);

    let bb = bbox(shapes);
    let mut ox = MARGIN;
    for s in shapes {
        shape_panel(&mut out, s, ox, TITLE_H, bb);
        ox += PANEL + MARGIN;
    }

    energy_panels(&mut out, &es, ox, panel_h);

    out.push_str("</svg>\n");
    out
}
