//! A minimal linear-axes line plot in SVG (time series of the dynamic runs: energies, contact
//! force): one polyline per series, "nice" tick grid, axis labels and a legend. Series with a
//! `dashed` style draw reference lines (e.g. a body's weight).

use std::fmt::Write;

/// One series: a label, its `(x, y)` points (non-finite ones skipped) and a line style.
pub struct Line {
    /// Legend label.
    pub label: String,
    /// Points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// Dashed (reference) line.
    pub dashed: bool,
}

const COLORS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];

/// Tick step of about `span/6`, rounded to 1, 2 or 5 times a power of ten.
fn tick_step(span: f64) -> f64 {
    let raw = (span / 6.0).max(f64::MIN_POSITIVE);
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    p * if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    }
}

/// The SVG text of a plot of `lines` with linear axes.
pub fn timeseries_svg(lines: &[Line], title: &str, xlabel: &str, ylabel: &str) -> String {
    let (w, h, l, r, t, b) = (760.0, 440.0, 90.0, 220.0, 40.0, 50.0);
    let pts = || {
        lines
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.0.is_finite() && p.1.is_finite())
    };
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pts() {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        let d = y0.abs().max(1.0) * 0.5;
        (y0, y1) = (y0 - d, y1 + d);
    }
    let (sx, sy) = (tick_step(x1 - x0), tick_step(y1 - y0));
    let (x0, x1) = ((x0 / sx).floor() * sx, (x1 / sx).ceil() * sx);
    let (y0, y1) = ((y0 / sy).floor() * sy, (y1 / sy).ceil() * sy);
    let px = |v: f64| l + (v - x0) / (x1 - x0) * (w - l - r);
    let py = |v: f64| h - b - (v - y0) / (y1 - y0) * (h - t - b);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>"
    );
    let esc = super::vtk::xml_escape;
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
        (w - r + l) / 2.0,
        esc(title)
    );
    let nx = ((x1 - x0) / sx).round() as i64;
    for i in 0..=nx {
        let v = x0 + i as f64 * sx;
        let x = px(v);
        let _ = writeln!(
            s,
            "<line x1=\"{x:.2}\" y1=\"{t}\" x2=\"{x:.2}\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{x:.2}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            h - b,
            h - b + 16.0,
            fmt_tick(v, sx)
        );
    }
    let ny = ((y1 - y0) / sy).round() as i64;
    for i in 0..=ny {
        let v = y0 + i as f64 * sy;
        let y = py(v);
        let _ = writeln!(
            s,
            "<line x1=\"{l}\" y1=\"{y:.2}\" x2=\"{}\" y2=\"{y:.2}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{:.2}\" text-anchor=\"end\">{}</text>",
            w - r,
            l - 6.0,
            y + 4.0,
            fmt_tick(v, sy)
        );
    }
    let _ = writeln!(
        s,
        "<rect x=\"{l}\" y=\"{t}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>",
        w - l - r,
        h - t - b
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
        (w - r + l) / 2.0,
        h - 10.0,
        esc(xlabel)
    );
    let _ = writeln!(
        s,
        "<text x=\"18\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 18 {})\">{}</text>",
        (h - b + t) / 2.0,
        (h - b + t) / 2.0,
        esc(ylabel)
    );
    for (k, line) in lines.iter().enumerate() {
        let c = COLORS[k % COLORS.len()];
        let d: Vec<String> = line
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .map(|p| format!("{:.2},{:.2}", px(p.0), py(p.1)))
            .collect();
        let dash = if line.dashed {
            " stroke-dasharray=\"6,4\""
        } else {
            ""
        };
        if !d.is_empty() {
            let _ = writeln!(
                s,
                "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"1.5\"{dash} points=\"{}\"/>",
                d.join(" ")
            );
        }
        let ly = t + 16.0 + 20.0 * k as f64;
        let lx = w - r + 12.0;
        let _ = writeln!(
            s,
            "<line x1=\"{lx}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"{c}\" stroke-width=\"2\"{dash}/><text x=\"{}\" y=\"{}\">{}</text>",
            lx + 24.0,
            lx + 30.0,
            ly + 4.0,
            esc(&line.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A tick label with as many decimals as the step needs.
fn fmt_tick(v: f64, step: f64) -> String {
    let dec = (-step.log10().floor()).max(0.0) as usize;
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    if v.abs() >= 1e5 || (v != 0.0 && v.abs() < 1e-4) {
        format!("{v:.2e}")
    } else {
        format!("{v:.dec$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timeseries_svg_draws_every_series_and_nice_ticks() {
        assert_eq!(tick_step(6.0), 1.0);
        assert_eq!(tick_step(0.9), 0.2);
        assert_eq!(tick_step(25.0), 5.0);
        let svg = timeseries_svg(
            &[
                Line {
                    label: "F <contact>".into(),
                    points: vec![(0.0, 0.0), (1.0, 2.0), (2.0, f64::NAN), (3.0, 1.5)],
                    dashed: false,
                },
                Line {
                    label: "m g".into(),
                    points: vec![(0.0, 1.5), (3.0, 1.5)],
                    dashed: true,
                },
            ],
            "t & F",
            "time",
            "force",
        );
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert!(svg.contains("F &lt;contact&gt;") && svg.contains("t &amp; F"));
        assert!(svg.contains("stroke-dasharray"));
        assert!(svg.ends_with("</svg>\n"));
    }
}
