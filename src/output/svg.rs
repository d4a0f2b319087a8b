//! Hand-written SVG figures: one panel per shape (common bounding box, equal
//! aspect) and a panel plotting the energy `J` against the outer iteration,
//! plus (when meaningful) a log-scale panel of `J − J_final`.
//!
//! 2D runs use [`shapes_and_energy_svg`]; 3D runs use [`projection_svg`],
//! which draws each configuration in a fixed isometric projection.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::write_atomic;

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

// Layout constants (pixels).
const MARGIN: f64 = 16.0;
const TITLE_H: f64 = 34.0;
const LABEL_H: f64 = 22.0;
const PANEL: f64 = 300.0; // side of a shape drawing area
const INNER_PAD: f64 = 10.0;
const PLOT_W: f64 = 380.0;
const PLOT_LEFT: f64 = 92.0; // room for tick labels
const PLOT_RIGHT: f64 = 14.0;
const PLOT_BOTTOM: f64 = 40.0;
const PLOT_TOP: f64 = 8.0;

fn esc(s: &str) -> String {
    super::vtk::xml_escape(s)
}

/// Formats `v` with `sig` significant digits (fixed notation for moderate
/// magnitudes, scientific otherwise), trimming trailing zeros.
fn fmt_sig(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return "?".to_string();
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let sig = sig.max(1);
    let e = v.abs().log10().floor() as i32;
    if (-4..6).contains(&e) {
        let decimals = (sig as i32 - 1 - e).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" {
            "0".to_string()
        } else {
            s
        }
    } else {
        let p = sig - 1;
        let s = format!("{v:.p$e}");
        // Trim zeros in the mantissa: 1.50000e-7 -> 1.5e-7.
        match s.split_once('e') {
            Some((m, ex)) if m.contains('.') => {
                format!("{}e{ex}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}

/// Tick labels with at least 6 significant digits, more if needed to make
/// neighbouring labels distinct (up to 15).
fn tick_labels(vals: &[f64]) -> Vec<String> {
    let mut labels = Vec::new();
    for sig in 6..=15 {
        labels = vals.iter().map(|&v| fmt_sig(v, sig)).collect::<Vec<_>>();
        if labels.windows(2).all(|w| w[0] != w[1]) {
            break;
        }
    }
    labels
}

/// A "nice" step (1, 2 or 5 times a power of ten) of about `raw`.
fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(raw.log10().floor());
    let f = raw / p;
    let m = if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    m * p
}

/// Linear map from `[a0, a1]` to `[b0, b1]` (`a0 != a1` guaranteed by callers).
fn lin(v: f64, a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    b0 + (v - a0) / (a1 - a0) * (b1 - b0)
}

/// Pads a range so it is non-degenerate and finite.
fn padded_range(lo: f64, hi: f64, frac: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span > 0.0 && span > 1e-14 * lo.abs().max(hi.abs()) {
        (lo - frac * span, hi + frac * span)
    } else {
        let mid = 0.5 * (lo + hi);
        let d = if mid == 0.0 { 1.0 } else { 1e-3 * mid.abs() };
        (mid - d, mid + d)
    }
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

/// Maps drawing coordinates (y up) of a common bounding box into the square
/// drawing area of one panel (page coordinates, y down), equal aspect.
#[derive(Debug, Clone, Copy)]
struct PanelMap {
    /// Page coordinates of the panel centre.
    pcx: f64,
    pcy: f64,
    /// Centre of the bounding box.
    cx: f64,
    cy: f64,
    /// Pixels per drawing unit.
    scale: f64,
}

impl PanelMap {
    /// Fits the bounding box `bb = (x0, y0, x1, y1)` into the panel whose
    /// top-left corner (above its label) is `(ox, oy)`.
    fn fit(bb: (f64, f64, f64, f64), ox: f64, oy: f64) -> Self {
        let (x0, y0, x1, y1) = bb;
        let (mut w, mut h) = (x1 - x0, y1 - y0);
        if w <= 0.0 && h <= 0.0 {
            w = 1.0;
            h = 1.0;
        }
        let avail = PANEL - 2.0 * INNER_PAD;
        let scale = match (w > 0.0, h > 0.0) {
            (true, true) => (avail / w).min(avail / h),
            (true, false) => avail / w,
            _ => avail / h,
        };
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let top = oy + LABEL_H;
        let (pcx, pcy) = (ox + 0.5 * PANEL, top + 0.5 * PANEL);
        Self {
            pcx,
            pcy,
            cx,
            cy,
            scale,
        }
    }

    fn map(&self, p: (f64, f64)) -> (f64, f64) {
        (
            self.pcx + (p.0 - self.cx) * self.scale,
            self.pcy - (p.1 - self.cy) * self.scale,
        )
    }
}

/// Opens a shape panel group: `<g class="{class}">`, the centred label and the
/// grey frame of the drawing area.
fn panel_frame(out: &mut String, class: &str, label: &str, ox: f64, oy: f64) {
    let top = oy + LABEL_H;
    let _ = writeln!(out, "<g class=\"{class}\">");
    let _ = writeln!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
        ox + 0.5 * PANEL,
        oy + LABEL_H - 7.0,
        esc(label)
    );
    let _ = writeln!(
        out,
        "<rect x=\"{ox:.1}\" y=\"{top:.1}\" width=\"{PANEL}\" height=\"{PANEL}\" fill=\"none\" stroke=\"#bbbbbb\"/>"
    );
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

/// Y-axis ticks of a plot: `(value, label)`.
type Ticks = Vec<(f64, String)>;

/// Draws a generic x–y plot (axes, ticks, polyline and markers) inside the
/// box whose top-left corner is `(ox, oy)` and size `PLOT_W × height`.
#[allow(clippy::too_many_arguments)]
fn plot_panel(
    out: &mut String,
    ox: f64,
    oy: f64,
    height: f64,
    heading: &str,
    ylabel: &str,
    pts: &[(f64, f64)],
    xr: (f64, f64),
    yr: (f64, f64),
    yticks: Ticks,
    color: &str,
) {
    let top = oy + LABEL_H;
    let (l, r) = (ox + PLOT_LEFT, ox + PLOT_W - PLOT_RIGHT);
    let (t, b) = (top + PLOT_TOP, top + height - PLOT_BOTTOM);
    let sx = |v: f64| lin(v, xr.0, xr.1, l, r);
    let sy = |v: f64| lin(v, yr.0, yr.1, b, t);

    let _ = writeln!(out, "<g class=\"plot\">");
    let _ = writeln!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
        0.5 * (l + r),
        oy + LABEL_H - 7.0,
        esc(heading)
    );
    // Frame.
    let _ = writeln!(
        out,
        "<path d=\"M{l:.1},{t:.1} L{l:.1},{b:.1} L{r:.1},{b:.1}\" fill=\"none\" stroke=\"black\"/>"
    );
    // X ticks: integer-friendly nice steps.
    let step = nice_step((xr.1 - xr.0) / 5.0).max(1.0);
    let mut xt = (xr.0 / step).ceil() * step;
    let mut guard = 0;
    let mut grid = String::new();
    let _ = writeln!(out, "<g font-size=\"11\" text-anchor=\"middle\">");
    while xt <= xr.1 + 1e-9 * step && guard < 50 {
        let px = sx(xt);
        let _ = write!(grid, "M{px:.1},{b:.1} L{px:.1},{:.1} ", b + 4.0);
        let _ = writeln!(
            out,
            "<text x=\"{px:.1}\" y=\"{:.1}\">{}</text>",
            b + 16.0,
            fmt_sig(xt, 6)
        );
        xt += step;
        guard += 1;
    }
    let _ = writeln!(out, "</g>");
    let _ = writeln!(out, "<g font-size=\"11\" text-anchor=\"end\">");
    let mut hgrid = String::new();
    for (v, label) in &yticks {
        let py = sy(*v);
        let _ = write!(grid, "M{:.1},{py:.1} L{l:.1},{py:.1} ", l - 4.0);
        let _ = write!(hgrid, "M{l:.1},{py:.1} L{r:.1},{py:.1} ");
        let _ = writeln!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            l - 6.0,
            py + 4.0,
            esc(label)
        );
    }
    let _ = writeln!(out, "</g>");
    if !hgrid.is_empty() {
        let _ = writeln!(
            out,
            "<path d=\"{}\" stroke=\"#e4e4e4\" stroke-width=\"0.8\" fill=\"none\"/>",
            hgrid.trim_end()
        );
    }
    if !grid.is_empty() {
        let _ = writeln!(
            out,
            "<path d=\"{}\" stroke=\"black\" fill=\"none\"/>",
            grid.trim_end()
        );
    }
    // Axis labels.
    let _ = writeln!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"12\">outer iteration</text>",
        0.5 * (l + r),
        b + 32.0
    );
    let (lx, ly) = (ox + 12.0, 0.5 * (t + b));
    let _ = writeln!(
        out,
        "<text x=\"{lx:.1}\" y=\"{ly:.1}\" text-anchor=\"middle\" font-size=\"12\" transform=\"rotate(-90 {lx:.1} {ly:.1})\">{}</text>",
        esc(ylabel)
    );
    // Data.
    if pts.is_empty() {
        let _ = writeln!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" fill=\"#888888\">no data</text>",
            0.5 * (l + r),
            0.5 * (t + b)
        );
    } else {
        if pts.len() > 1 {
            let mut d = String::new();
            for (k, p) in pts.iter().enumerate() {
                let _ = write!(
                    d,
                    "{}{:.2},{:.2} ",
                    if k == 0 { "M" } else { "L" },
                    sx(p.0),
                    sy(p.1)
                );
            }
            let _ = writeln!(
                out,
                "<path d=\"{}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"/>",
                d.trim_end()
            );
        }
        let _ = writeln!(out, "<g fill=\"{color}\">");
        for p in pts {
            let _ = writeln!(
                out,
                "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"3\"/>",
                sx(p.0),
                sy(p.1)
            );
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

/// Opens the SVG document of size `width × height`: root element, white
/// background and the bold centred `title`.
fn svg_open(out: &mut String, width: f64, height: f64, title: &str) {
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{height:.0}\" viewBox=\"0 0 {width:.0} {height:.0}\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(
        out,
        "<rect x=\"0\" y=\"0\" width=\"{width:.0}\" height=\"{height:.0}\" fill=\"white\"/>"
    );
    let _ = writeln!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"16\" font-weight=\"bold\">{}</text>",
        0.5 * width,
        TITLE_H - 10.0,
        esc(title)
    );
}

/// Energy history prepared for plotting.
struct EnergySeries {
    /// `(outer iteration, J)`, finite `J` only, sorted by iteration.
    e: Vec<(f64, f64)>,
    /// `(outer iteration, log10(J − J_final))` where `J − J_final > 0`.
    log_pts: Vec<(f64, f64)>,
}

impl EnergySeries {
    fn new(energy: &[(usize, f64)]) -> Self {
        let mut e: Vec<(f64, f64)> = energy
            .iter()
            .filter(|(_, j)| j.is_finite())
            .map(|&(k, j)| (k as f64, j))
            .collect();
        e.sort_by(|a, b| a.0.total_cmp(&b.0));

        // Log panel data: J - J_final for earlier iterations, positive only.
        let log_pts: Vec<(f64, f64)> = match e.last() {
            Some(&(_, jf)) => e
                .iter()
                .filter(|p| p.1 - jf > 0.0)
                .map(|p| (p.0, (p.1 - jf).log10()))
                .filter(|p| p.1.is_finite())
                .collect(),
            None => Vec::new(),
        };
        Self { e, log_pts }
    }

    /// Number of plot panels [`energy_panels`] draws (1 or 2).
    fn n_plots(&self) -> f64 {
        if self.log_pts.is_empty() {
            1.0
        } else {
            2.0
        }
    }
}

/// Draws the linear `J` panel and, when there is data for it, the log-scale
/// `J − J_final` panel, left to right starting at `x = ox`, below the title.
fn energy_panels(out: &mut String, es: &EnergySeries, mut ox: f64, panel_h: f64) {
    let (e, log_pts) = (&es.e, &es.log_pts);
    // Linear J panel.
    let (xr, yr, yticks) = if e.is_empty() {
        ((0.0, 1.0), (0.0, 1.0), Vec::new())
    } else {
        let (kmin, kmax) = (e[0].0, e[e.len() - 1].0);
        let xr = if kmax > kmin {
            (kmin, kmax)
        } else {
            (kmin - 1.0, kmax + 1.0)
        };
        let jmin = e.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let jmax = e.iter().map(|p| p.1).fold(-f64::INFINITY, f64::max);
        let yr = padded_range(jmin, jmax, 0.06);
        let vals: Vec<f64> = (0..5)
            .map(|i| lin(i as f64, 0.0, 4.0, yr.0, yr.1))
            .collect();
        let labels = tick_labels(&vals);
        (xr, yr, vals.into_iter().zip(labels).collect())
    };
    let mut heading = "energy J".to_string();
    if let Some(&(k, j)) = e.last() {
        heading = format!("energy J (final k={}: {})", k as usize, fmt_sig(j, 10));
    }
    plot_panel(
        out,
        ox,
        TITLE_H,
        panel_h - LABEL_H,
        &heading,
        "J",
        e,
        xr,
        yr,
        yticks,
        "#c0392b",
    );
    ox += PLOT_W + MARGIN;

    // Log panel of J - J_final.
    if !log_pts.is_empty() {
        let lmin = log_pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let lmax = log_pts.iter().map(|p| p.1).fold(-f64::INFINITY, f64::max);
        let (mut y0, mut y1) = (lmin.floor(), lmax.ceil());
        if y1 <= y0 {
            y0 -= 1.0;
            y1 += 1.0;
        }
        let dstep = ((y1 - y0) / 6.0).ceil().max(1.0);
        let mut ticks = Vec::new();
        let mut d = y0;
        while d <= y1 + 1e-9 {
            ticks.push((d, format!("1e{}", d as i64)));
            d += dstep;
        }
        plot_panel(
            out,
            ox,
            TITLE_H,
            panel_h - LABEL_H,
            "J − J_final (log scale)",
            "J − J_final",
            log_pts,
            xr,
            (y0, y1),
            ticks,
            "#2471a3",
        );
    }
}

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
fn project(p: [f64; 3]) -> (f64, f64, f64) {
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
fn painter_faces(s: &Shape3) -> Vec<DrawFace> {
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
fn face_grey(v: &[[f64; 3]; 3]) -> u8 {
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

/// Writes an SVG document to `path` atomically (see [`super::write_atomic`]).
pub fn write_svg(path: &Path, svg: &str) -> io::Result<()> {
    write_atomic(path, svg.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_wellformed(svg: &str) {
        assert!(svg.starts_with("<svg"), "does not start with <svg");
        assert!(
            svg.trim_end().ends_with("</svg>"),
            "does not end with </svg>"
        );
        assert_eq!(svg.matches("<svg").count(), 1);
        let opens = svg.matches("<g>").count() + svg.matches("<g ").count();
        assert_eq!(opens, svg.matches("</g>").count(), "unbalanced <g>");
        assert_eq!(
            svg.matches("<text").count(),
            svg.matches("</text>").count(),
            "unbalanced <text>"
        );
        assert_eq!(svg.matches('<').count(), svg.matches('>').count());
        assert!(!svg.contains("NaN"), "NaN in svg");
        assert!(
            !svg.contains("=\"inf") && !svg.contains("-inf"),
            "inf in svg"
        );
    }

    fn square(offset: f64) -> Vec<f64> {
        vec![
            offset,
            0.0,
            offset + 1.0,
            0.0,
            offset + 1.0,
            1.0,
            offset,
            1.0,
        ]
    }

    const EDGES: [[usize; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];
    const TRIS: [[usize; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    #[test]
    fn svg_has_one_line_per_edge_per_panel() {
        let a = square(0.0);
        let b = square(0.5);
        let shapes = [
            Shape {
                label: "initial (k=0)".into(),
                x: &a,
                edges: &EDGES,
                triangles: &TRIS,
            },
            Shape {
                label: "final (k=7)".into(),
                x: &b,
                edges: &EDGES[..3],
                triangles: &TRIS,
            },
        ];
        let energy: Vec<(usize, f64)> = (0..8).map(|k| (k, 1.0 + 0.5f64.powi(k as i32))).collect();
        let svg = shapes_and_energy_svg(&shapes, &energy, "two squares <&>");
        check_wellformed(&svg);
        assert_eq!(svg.matches("<line").count(), 4 + 3);
        assert_eq!(svg.matches("<polygon").count(), 4);
        assert!(svg.contains("initial (k=0)"));
        assert!(svg.contains("two squares &lt;&amp;&gt;"));
        // Log panel present since J - J_final > 0 for k < 7.
        assert!(svg.contains("log scale"));
    }

    #[test]
    fn svg_degenerate_inputs_have_no_nan() {
        let p = [0.3, -0.2];
        let single = [Shape {
            label: "point".into(),
            x: &p,
            edges: &[],
            triangles: &[],
        }];
        for energy in [
            vec![],
            vec![(0usize, 2.5)],
            vec![(0, 1.0), (1, 1.0), (2, 1.0)],
            vec![(0, 0.0)],
        ] {
            let svg = shapes_and_energy_svg(&single, &energy, "degenerate");
            check_wellformed(&svg);
            assert_eq!(svg.matches("<line").count(), 0);
            assert!(
                !svg.contains("log scale"),
                "constant J must not get a log panel"
            );
        }
        // No shapes at all, NaN energies dropped.
        let svg = shapes_and_energy_svg(&[], &[(0, f64::NAN), (1, 3.0)], "");
        check_wellformed(&svg);
        // A shape whose points are all identical (zero-size bounding box).
        let q = [1.0, 1.0, 1.0, 1.0];
        let s = [Shape {
            label: "collapsed".into(),
            x: &q,
            edges: &[[0, 1]],
            triangles: &[],
        }];
        let svg = shapes_and_energy_svg(&s, &[(3, 1.0)], "collapsed");
        check_wellformed(&svg);
        assert_eq!(svg.matches("<line").count(), 1);
    }

    #[test]
    fn tick_labels_distinguish_small_differences() {
        let e = [(0usize, 1.000_000_03), (1, 1.000_000_02), (2, 1.000_000_01)];
        let p = [0.0, 0.0, 1.0, 0.0];
        let s = [Shape {
            label: "s".into(),
            x: &p,
            edges: &[[0, 1]],
            triangles: &[],
        }];
        let svg = shapes_and_energy_svg(&s, &e, "tiny");
        check_wellformed(&svg);
        let labels = tick_labels(&[1.0, 1.0 + 1e-8, 1.0 + 2e-8]);
        assert!(labels.windows(2).all(|w| w[0] != w[1]), "{labels:?}");
        assert_eq!(fmt_sig(1.234_567_89, 6), "1.23457");
        assert_eq!(fmt_sig(-0.000_012_345_678, 6), "-1.23457e-5");
        assert_eq!(fmt_sig(1234567.0, 6), "1.23457e6");
        assert_eq!(fmt_sig(2.0, 6), "2");
    }

    #[test]
    fn write_svg_writes_file() {
        let dir = std::env::temp_dir().join(format!("contactlab_svg_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = square(0.0);
        let shapes = [Shape {
            label: "initial (k=0)".into(),
            x: &a,
            edges: &EDGES,
            triangles: &TRIS,
        }];
        let svg = shapes_and_energy_svg(&shapes, &[(0, 2.0), (1, 1.5)], "t");
        let path = dir.join("fig.svg");
        write_svg(&path, &svg).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), svg);
        assert!(!dir.join("fig.svg.tmp").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
    /// Surface of the unit tet (4 outward faces) with its 6 sides listed as
    /// edges too, plus a free 2-edge curve above it (points 4, 5, 6).
    fn tet_and_curve(shift: [f64; 3]) -> Vec<f64> {
        let pts = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.5],
            [0.5, 0.5, 1.5],
            [1.0, 1.0, 1.5],
        ];
        pts.iter()
            .flat_map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]])
            .collect()
    }
    const FACES3: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    // Six tet sides (some reversed) + two free curve edges.
    const EDGES3: [[usize; 2]; 8] = [
        [0, 1],
        [2, 1],
        [0, 2],
        [3, 0],
        [1, 3],
        [2, 3],
        [4, 5],
        [5, 6],
    ];

    fn geometric_energy() -> Vec<(usize, f64)> {
        (0..6).map(|k| (k, 2.0 + 0.5f64.powi(k as i32))).collect()
    }

    #[test]
    fn projection_svg_counts_faces_and_free_edges() {
        let a = tet_and_curve([0.0; 3]);
        let b = tet_and_curve([0.2, -0.1, 0.3]);
        let panels = [
            Shape3 {
                label: "initial (k=0)".into(),
                x: &a,
                edges: &EDGES3,
                faces: &FACES3,
            },
            Shape3 {
                label: "final (k=5)".into(),
                x: &b,
                edges: &EDGES3[..7],
                faces: &FACES3[..2],
            },
        ];
        let svg = projection_svg(&panels, &geometric_energy(), "tet <&> curve");
        check_wellformed(&svg);
        assert_eq!(svg.matches("<polygon").count(), 4 + 2);
        // Face sides are not drawn as lines, only free edges are. Panel 1:
        // the two curve edges. Panel 2 has faces [0, 2, 1] and [0, 1, 3]
        // only, so the side [2, 3] is free, plus the curve edge [4, 5].
        assert_eq!(svg.matches("<line").count(), 2 + 2);
        assert_eq!(svg.matches("class=\"shape3\"").count(), 2);
        assert!(svg.contains("initial (k=0)"));
        assert!(svg.contains("tet &lt;&amp;&gt; curve"));
        // Same energy panels as the 2D figure.
        assert!(svg.contains("energy J (final k=5"));
        assert!(svg.contains("log scale"));
        // Deterministic.
        assert_eq!(
            svg,
            projection_svg(&panels, &geometric_energy(), "tet <&> curve")
        );
    }

    #[test]
    fn projection_svg_skips_non_finite_elements() {
        let mut a = tet_and_curve([0.0; 3]);
        a[3 * 3 + 2] = f64::NAN; // point 3: faces 1, 2, 3 and edges to it go
        a[3 * 6] = f64::INFINITY; // point 6: curve edge [5, 6] goes
        let big = [1e308, -1e308, 1e308, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
        let panels = [
            Shape3 {
                label: "nan".into(),
                x: &a,
                edges: &EDGES3,
                // Out-of-range indices are skipped too.
                faces: &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2], [0, 1, 99]],
            },
            Shape3 {
                label: "huge".into(),
                x: &big,
                edges: &[[0, 1], [1, 2]],
                faces: &[[0, 1, 2]],
            },
        ];
        let svg = projection_svg(&panels, &[(0, f64::NAN), (1, 1.0)], "bad");
        check_wellformed(&svg);
        assert!(!svg.contains("inf"), "inf in svg");
        // Panel 1: only face [0, 2, 1]. Panel 2: its one face is dropped since
        // the projection of point 0 overflows.
        assert_eq!(svg.matches("<polygon").count(), 1);
        // Panel 1: the tet sides are sides of (possibly skipped) faces, so
        // not free; [4, 5] is drawn, [5, 6] has a non-finite end. Panel 2:
        // [0, 1] and [1, 2] are face sides.
        assert_eq!(svg.matches("<line").count(), 1);
    }

    #[test]
    fn projection_svg_degenerate_inputs() {
        for energy in [vec![], vec![(0usize, 2.5)], vec![(0, 1.0), (1, 1.0)]] {
            let svg = projection_svg(&[], &energy, "");
            check_wellformed(&svg);
            assert!(!svg.contains("log scale"));
        }
        // A point cloud and a collapsed configuration.
        let cloud = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0];
        let same = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let panels = [
            Shape3 {
                label: "cloud".into(),
                x: &cloud,
                edges: &[],
                faces: &[],
            },
            Shape3 {
                label: "collapsed".into(),
                x: &same,
                edges: &[[0, 1]],
                faces: &[[0, 1, 2]],
            },
        ];
        let svg = projection_svg(&panels, &[(3, 1.0)], "degenerate");
        check_wellformed(&svg);
        assert_eq!(svg.matches("<circle cx").count(), 2 + 1); // 2 points + 1 J marker
        assert_eq!(svg.matches("<polygon").count(), 1);
        assert_eq!(svg.matches("<line").count(), 0);
    }

    /// The projection is isometric with z up, and all panels share it and
    /// the bounding box: identical configurations give identical drawings,
    /// shifted by one panel width.
    #[test]
    fn projection_is_common_and_z_up() {
        let (r, u, d) = project([0.0, 0.0, 1.0]);
        assert!(r.abs() < 1e-15 && u > 0.0 && d > 0.0);
        for k in 0..3 {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            let (r, u, _) = project(e);
            // Isometric: the three unit axes project to the same length.
            assert!((r.hypot(u) - (2.0f64 / 3.0).sqrt()).abs() < 1e-15);
        }
        let a = tet_and_curve([0.0; 3]);
        let panel = |label: &str| Shape3 {
            label: label.into(),
            x: &a,
            edges: &EDGES3,
            faces: &FACES3,
        };
        let svg = projection_svg(&[panel("one"), panel("two")], &[], "same");
        let polys: Vec<Vec<f64>> = svg
            .lines()
            .filter(|l| l.starts_with("<polygon"))
            .map(|l| {
                let pts = l.split('"').nth(1).unwrap();
                pts.split([' ', ','])
                    .map(|t| t.parse::<f64>().unwrap())
                    .collect()
            })
            .collect();
        assert_eq!(polys.len(), 8);
        for (p, q) in polys[..4].iter().zip(&polys[4..]) {
            for (c, (a, b)) in p.iter().zip(q).enumerate() {
                let shift = if c % 2 == 0 { PANEL + MARGIN } else { 0.0 };
                assert!((b - a - shift).abs() < 0.011, "{p:?} vs {q:?}");
            }
        }
    }

    #[test]
    fn painter_order_is_far_first_with_index_tie_break() {
        // Three horizontal triangles: face 0 nearest (highest z, since
        // depth = p·v grows with z), faces 1 and 2 at the same depth, far.
        let x = [
            0.0, 0.0, 2.0, 1.0, 0.0, 2.0, 0.0, 1.0, 2.0, // 0..3 at z = 2
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, // 3..6 at z = 0
        ];
        let s = Shape3 {
            label: String::new(),
            x: &x,
            edges: &[],
            faces: &[[0, 1, 2], [3, 4, 5], [5, 4, 3]],
        };
        let order: Vec<usize> = painter_faces(&s).iter().map(|f| f.0).collect();
        assert_eq!(order, vec![1, 2, 0]);
        // Shading: a face seen head-on is lighter than one seen edge-on.
        let head_on = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 2.0]];
        let edge_on = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, -1.0, 1.0]];
        assert_eq!(face_grey(&head_on), 245);
        assert_eq!(face_grey(&edge_on), 150);
        assert_eq!(face_grey(&[[0.0; 3]; 3]), 150);
    }
}
