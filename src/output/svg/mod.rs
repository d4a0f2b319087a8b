//! Hand-written SVG figures, one file per thing drawn: 2D shapes (`shapes.rs`), 3D
//! configurations in an isometric projection (`projection.rs`) and the energy history
//! (`energy.rs`: `J` against the outer iteration, plus, when meaningful, a log-scale panel of
//! `J − J_final`). This file holds the page layout and the primitives they share.
//!
//! 2D runs use [`shapes_and_energy_svg`]; 3D runs use [`projection_svg`].

mod energy;
mod projection;
mod shapes;

pub use projection::{projection_svg, Shape3};
pub use shapes::{shapes_and_energy_svg, Shape};

use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::write_atomic;

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

/// Writes an SVG document to `path` atomically (see [`super::write_atomic`]).
pub fn write_svg(path: &Path, svg: &str) -> io::Result<()> {
    write_atomic(path, svg.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::projection::{face_grey, painter_faces, project};
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
