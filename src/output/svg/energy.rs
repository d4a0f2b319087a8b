//! The energy history: `J` against the outer iteration and, when meaningful, a log-scale
//! panel of `J − J_final`.

use super::*;

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

/// Energy history prepared for plotting.
pub(super) struct EnergySeries {
    /// `(outer iteration, J)`, finite `J` only, sorted by iteration.
    e: Vec<(f64, f64)>,
    /// `(outer iteration, log10(J − J_final))` where `J − J_final > 0`.
    log_pts: Vec<(f64, f64)>,
}

impl EnergySeries {
    pub(super) fn new(energy: &[(usize, f64)]) -> Self {
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
    pub(super) fn n_plots(&self) -> f64 {
        if self.log_pts.is_empty() {
            1.0
        } else {
            2.0
        }
    }
}

/// Draws the linear `J` panel and, when there is data for it, the log-scale
/// `J − J_final` panel, left to right starting at `x = ox`, below the title.
pub(super) fn energy_panels(out: &mut String, es: &EnergySeries, mut ox: f64, panel_h: f64) {
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
