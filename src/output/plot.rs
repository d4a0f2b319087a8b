//! `contactlab plot CSV --x X --y Y[,Y2…] [--group COL[,COL…]] [--where COL=VALUE]… [--pareto]
//! --out FILE.svg`: a log–log SVG of sweep columns, one series per group value and y column, with
//! the fitted log–log slope of each series in its legend and on stdout (docs/sweeps.md, "Plots").
//! With `--linear`, linear axes and no fit (profiles: a contact pressure against position),
//! `--dashed Y` drawing reference curves dashed.
//!
//! `X` (and each `Y`) is a column name, `1/COL`, `max(COL,COL)` or `1/max(COL,COL)`. Only
//! rows of runs that stopped on the outer stopping rule (`status` `converged` or
//! `fixed_point`) are plotted unless `--all-statuses` is given; rows whose x or y is empty or
//! not positive are skipped (log axes) and counted on stderr.

use crate::output::loglog::{loglog_slope, loglog_svg, Series};
use crate::output::timeseries::{timeseries_svg, Line};
use crate::output::write_atomic;
use anyhow::{bail, Context, Result};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Arguments of `contactlab plot`.
#[derive(clap::Args, Clone, Debug)]
pub struct PlotArgs {
    /// A sweep CSV.
    pub csv: PathBuf,
    /// The x quantity: COL, 1/COL, max(COL,COL) or 1/max(COL,COL).
    #[arg(long)]
    pub x: String,
    /// The y quantities, comma-separated (same forms as --x).
    #[arg(long, value_delimiter = ',')]
    pub y: Vec<String>,
    /// Columns whose values split the rows into series, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub group: Vec<String>,
    /// Keep only rows with COL=VALUE (repeatable; all must hold).
    #[arg(long = "where")]
    pub filters: Vec<String>,
    /// Keep, per series, only the Pareto-optimal points (no other point has both a smaller x
    /// and a smaller y): the speed/accuracy front.
    #[arg(long)]
    pub pareto: bool,
    /// No fitted slope in the legend (for fronts and scatter, where a power law means nothing).
    #[arg(long)]
    pub no_fit: bool,
    /// Plot every row, not only those of runs stopped by the stopping rule (converged, fixed_point).
    #[arg(long)]
    pub all_statuses: bool,
    /// Linear axes instead of log–log (values of any sign, no fitted slope): profiles such as
    /// a contact pressure against position.
    #[arg(long)]
    pub linear: bool,
    /// Y quantities drawn as dashed lines (reference curves), comma-separated; with --linear.
    #[arg(long, value_delimiter = ',')]
    pub dashed: Vec<String>,
    /// Title.
    #[arg(long, default_value = "")]
    pub title: String,
    /// Output SVG.
    #[arg(long)]
    pub out: PathBuf,
}

/// A quantity read from a row: a column, its inverse, or the max of two columns.
#[derive(Debug, Clone, PartialEq)]
struct Quantity {
    inverse: bool,
    cols: Vec<String>,
}

impl Quantity {
    fn parse(s: &str) -> Result<Quantity> {
        let t = s.trim();
        let (inverse, rest) = match t.strip_prefix("1/") {
            Some(r) => (true, r.trim()),
            None => (false, t),
        };
        let cols: Vec<String> = match rest.strip_prefix("max(").and_then(|r| r.strip_suffix(')')) {
            Some(inner) => inner.split(',').map(|c| c.trim().to_string()).collect(),
            None => vec![rest.to_string()],
        };
        if cols.is_empty()
            || cols
                .iter()
                .any(|c| c.is_empty() || c.contains(['(', ')', '/']))
        {
            bail!("quantity {s:?}: expected COL, 1/COL, max(COL,COL) or 1/max(COL,COL)");
        }
        Ok(Quantity { inverse, cols })
    }

    /// The value on a row; `None` if a column is empty or not a number, or (log axes, with
    /// `positive`) the value is not positive.
    fn eval_any(&self, idx: &BTreeMap<&str, usize>, row: &[String], positive: bool) -> Option<f64> {
        let mut v = f64::NEG_INFINITY;
        for c in &self.cols {
            let x: f64 = row[idx[c.as_str()]].parse().ok()?;
            v = v.max(x);
        }
        let v = if self.inverse { 1.0 / v } else { v };
        (v.is_finite() && (v > 0.0 || !positive)).then_some(v)
    }

    #[cfg(test)]
    fn eval(&self, idx: &BTreeMap<&str, usize>, row: &[String]) -> Option<f64> {
        self.eval_any(idx, row, true)
    }
}

/// Points of `pts` not dominated by another (smaller or equal x and y, one strictly).
fn pareto(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for p in pts {
        if out.last().is_none_or(|q| p.1 < q.1) {
            out.push(p);
        }
    }
    out
}

/// `contactlab plot`.
pub fn cmd_plot(a: &PlotArgs) -> Result<()> {
    let mut rdr = csv::Reader::from_path(&a.csv).with_context(|| format!("opening {:?}", a.csv))?;
    let header: Vec<String> = rdr.headers()?.iter().map(String::from).collect();
    let idx: BTreeMap<&str, usize> = header
        .iter()
        .enumerate()
        .map(|(i, c)| (c.as_str(), i))
        .collect();
    let col = |c: &str| -> Result<()> {
        if idx.contains_key(c) {
            Ok(())
        } else {
            bail!(
                "{:?} has no column {c:?} (columns: {})",
                a.csv,
                header.join(", ")
            )
        }
    };
    let x = Quantity::parse(&a.x)?;
    if a.y.is_empty() {
        bail!("--y: give at least one column");
    }
    let ys: Vec<Quantity> =
        a.y.iter()
            .map(|s| Quantity::parse(s))
            .collect::<Result<_>>()?;
    for q in std::iter::once(&x).chain(&ys) {
        for c in &q.cols {
            col(c)?;
        }
    }
    for g in &a.group {
        col(g)?;
    }
    let mut filters = Vec::new();
    for f in &a.filters {
        let (c, v) = f
            .split_once('=')
            .with_context(|| format!("--where {f:?}: expected COL=VALUE"))?;
        col(c)?;
        filters.push((idx[c], v.to_string()));
    }
    let status = if a.all_statuses {
        None
    } else {
        col("status")?;
        Some(idx["status"])
    };
    let mut series: BTreeMap<(String, usize), Vec<(f64, f64)>> = BTreeMap::new();
    let (mut used, mut skipped) = (0usize, 0usize);
    for rec in rdr.records() {
        let row: Vec<String> = rec?.iter().map(String::from).collect();
        if filters.iter().any(|(i, v)| &row[*i] != v) {
            continue;
        }
        if status.is_some_and(|i| row[i] != "converged" && row[i] != "fixed_point") {
            continue;
        }
        let g = a
            .group
            .iter()
            .map(|c| format!("{c}={}", row[idx[c.as_str()]]))
            .collect::<Vec<_>>()
            .join(" ");
        for (k, y) in ys.iter().enumerate() {
            let positive = !a.linear;
            match (
                x.eval_any(&idx, &row, positive),
                y.eval_any(&idx, &row, positive),
            ) {
                (Some(px), Some(py)) => {
                    series.entry((g.clone(), k)).or_default().push((px, py));
                    used += 1;
                }
                _ => skipped += 1,
            }
        }
    }
    if used == 0 {
        bail!(
            "{:?}: no plottable point (filters {:?}; only converged and fixed_point rows unless --all-statuses)",
            a.csv,
            a.filters
        );
    }
    if skipped > 0 {
        eprintln!("plot: {skipped} point(s) skipped (empty, non-numeric or not positive)");
    }
    if a.linear {
        let lines: Vec<Line> = series
            .into_iter()
            .map(|((g, k), mut pts)| {
                pts.sort_by(|p, q| p.0.total_cmp(&q.0));
                let name = if ys.len() > 1 || g.is_empty() {
                    format!("{} {}", g, a.y[k]).trim().to_string()
                } else {
                    g
                };
                println!("{name}: {} points", pts.len());
                Line {
                    label: name,
                    points: pts,
                    dashed: a.dashed.contains(&a.y[k]),
                }
            })
            .collect();
        let svg = timeseries_svg(&lines, &a.title, &a.x, &a.y.join(", "));
        write_atomic(&a.out, svg.as_bytes()).with_context(|| format!("writing {:?}", a.out))?;
        eprintln!("plot: wrote {:?}", a.out);
        return Ok(());
    }
    let mut out = Vec::new();
    for ((g, k), mut pts) in series {
        pts.sort_by(|p, q| p.0.total_cmp(&q.0));
        if a.pareto {
            pts = pareto(pts);
        }
        let slope = if a.no_fit { None } else { loglog_slope(&pts) };
        let name = if ys.len() > 1 || g.is_empty() {
            format!("{} {}", g, a.y[k]).trim().to_string()
        } else {
            g
        };
        let label = match slope {
            Some(s) => format!("{name} (slope {s:.2})"),
            None => name,
        };
        println!("{label}: {} points", pts.len());
        out.push(Series { label, points: pts });
    }
    let svg = loglog_svg(&out, &a.title, &a.x, &a.y.join(", "));
    write_atomic(&a.out, svg.as_bytes()).with_context(|| format!("writing {:?}", a.out))?;
    eprintln!("plot: wrote {:?}", a.out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_quantities_parse_and_evaluate() {
        let q = Quantity::parse("1/max(h, eps)").unwrap();
        assert_eq!(q.cols, vec!["h", "eps"]);
        assert!(q.inverse);
        let idx: BTreeMap<&str, usize> = [("h", 0), ("eps", 1)].into_iter().collect();
        let row = vec!["0.5".to_string(), "0.25".to_string()];
        assert_eq!(q.eval(&idx, &row), Some(2.0));
        assert_eq!(Quantity::parse("eps").unwrap().eval(&idx, &row), Some(0.25));
        assert_eq!(
            Quantity::parse("h")
                .unwrap()
                .eval(&idx, &["".into(), "1".into()]),
            None
        );
        // linear axes keep zero and negative values, log axes drop them
        let neg = vec!["-0.5".to_string(), "0".to_string()];
        assert_eq!(Quantity::parse("h").unwrap().eval(&idx, &neg), None);
        assert_eq!(
            Quantity::parse("h").unwrap().eval_any(&idx, &neg, false),
            Some(-0.5)
        );
        assert_eq!(
            Quantity::parse("eps").unwrap().eval_any(&idx, &neg, false),
            Some(0.0)
        );
        assert!(Quantity::parse("max(h").is_err());
        assert!(Quantity::parse("1/").is_err());
    }

    #[test]
    fn plot_pareto_front_keeps_the_non_dominated_points() {
        let f = pareto(vec![
            (1.0, 5.0),
            (2.0, 3.0),
            (3.0, 4.0),
            (4.0, 1.0),
            (0.5, 9.0),
        ]);
        assert_eq!(f, vec![(0.5, 9.0), (1.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
    }
}
