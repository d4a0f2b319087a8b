//! `contactlab scaling`: the scaling experiment (docs/measurements.md).
//!
//! For each size `n` (elements per membrane of the balloons scene) and pruning mode, one child
//! process (`contactlab scaling-case`, so that each case's peak memory is its own) runs either
//! one outer step (`kind = one_step`: time per outer iteration split into pair search, assembly
//! and solve) or the whole solve (`kind = full`, for the sizes that finish in minutes). Each
//! finished case is a row of the CSV, written atomically after every case; rows already in the
//! CSV are skipped, so an interrupted experiment resumes where it stopped. A failed or timed-out
//! case is a row with its status. At the end: a log–log SVG of the time per outer iteration
//! against the number of vertices, with fitted growth exponents.

use crate::harness::rows::{header, ScalingRow};
use crate::output::loglog::{loglog_slope, loglog_svg, Series};
use crate::output::write_atomic;
use crate::scene::balloons::{self, BalloonsParams};
use crate::solve::outer::{run, OuterSettings, Pruning, RunStatus};
use anyhow::{bail, Context, Result};
use contactlab_solvers::{backend_from_name, default_settings};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Arguments of `contactlab scaling`.
#[derive(clap::Args, Clone)]
pub struct ScalingArgs {
    /// Output CSV (the SVG goes beside it, same name with .svg).
    #[arg(long, default_value = "results/scaling.csv")]
    out: PathBuf,
    /// Elements per membrane, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "25,100,400,1600,6400,25600,100000,250000"
    )]
    sizes: Vec<usize>,
    /// Pruning modes, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "lazy,trust-region,all-pairs"
    )]
    modes: Vec<String>,
    /// Largest n run in the all-pairs mode (its rows grow as n²).
    #[arg(long, default_value_t = 80)]
    all_pairs_max_n: usize,
    /// Largest n whose full solve is run (kind = full).
    #[arg(long, default_value_t = 400)]
    full_max_n: usize,
    /// Backend.
    #[arg(long, default_value = contactlab_solvers::DEFAULT_BACKEND)]
    backend: String,
    /// Wall-clock limit per case, seconds (the case is killed and recorded as `timeout`).
    #[arg(long, default_value_t = 1800.0)]
    case_timeout_s: f64,
    /// Initial trust-region half-width relative to the median edge length (trust-region rows).
    #[arg(long, default_value_t = 1.0)]
    trust_delta0: f64,
    /// Inner steps per T(ψ) at most.
    #[arg(long, default_value_t = 50)]
    max_inner: usize,
}

/// Arguments of the hidden `contactlab scaling-case`.
#[derive(clap::Args, Clone)]
pub struct CaseArgs {
    #[arg(long)]
    n: usize,
    #[arg(long)]
    pruning: String,
    #[arg(long)]
    backend: String,
    #[arg(long)]
    max_outer: usize,
    #[arg(long)]
    trust_delta0: f64,
    #[arg(long)]
    max_inner: usize,
}

/// Peak resident set size of this process in MiB (`VmHWM`), 0 where unavailable.
fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

/// The child: one case, one JSON object on stdout.
pub fn case_cmd(a: CaseArgs) -> Result<()> {
    let pruning = Pruning::from_name(&a.pruning)
        .with_context(|| format!("unknown pruning {:?}", a.pruning))?;
    let scene = balloons::build(&BalloonsParams {
        n: a.n,
        ..Default::default()
    })?;
    let qps = default_settings(&a.backend);
    let mut backend = backend_from_name(&a.backend, &qps)?;
    let mut settings = OuterSettings {
        qp_tol: qps.eps_abs,
        max_outer: a.max_outer,
        pruning,
        ..Default::default()
    };
    settings.trust.delta0 = a.trust_delta0;
    settings.inner.max_inner = a.max_inner;
    let mut first = None;
    // Per-run totals over the outer steps: (pairs, assembly, solve) seconds and QP solves.
    let mut total = (0.0, 0.0, 0.0, 0usize);
    let res = run(
        &scene.mesh,
        &scene.energy,
        scene.eps,
        &scene.x0,
        backend.as_mut(),
        &settings,
        &mut |r, _| {
            if r.iteration == 1 {
                first = Some(r.clone());
            }
            total.0 += r.t_pairs_s;
            total.1 += r.t_assembly_s;
            total.2 += r.t_solve_s;
            total.3 += r.inner_iterations + r.lazy_rounds;
        },
    )?;
    let f = first.context("no outer step was taken")?;
    let status = if a.max_outer == 1 && res.status == RunStatus::MaxOuterIterations {
        "one_step_done"
    } else {
        res.status.as_str()
    };
    let row = serde_json::json!({
        "n": a.n,
        "vertices": scene.mesh.nv(),
        "pruning": pruning.as_str(),
        "kind": if a.max_outer == 1 { "one_step" } else { "full" },
        "trust_delta0": delta0_cell(a.trust_delta0),
        "max_inner": a.max_inner,
        "status": status,
        "outer_iterations": res.outer_iterations,
        "inner_iterations": if a.max_outer == 1 { f.inner_iterations } else { res.inner_iterations },
        "pairs": f.pairs,
        "rows": f.rows,
        "step1_t_pairs_s": f.t_pairs_s,
        "step1_t_assembly_s": f.t_assembly_s,
        "step1_t_solve_s": f.t_solve_s,
        "step1_t_step_s": f.t_pairs_s + f.t_assembly_s + f.t_solve_s,
        "total_t_pairs_s": total.0,
        "total_t_assembly_s": total.1,
        "total_t_solve_s": total.2,
        "qp_solves": total.3,
        "wall_time_s": res.wall_time_s,
        "peak_rss_mb": peak_rss_mb(),
        "final_energy": res.energy,
        "backend": a.backend,
    });
    println!("{row}");
    Ok(())
}

fn read_rows(path: &Path) -> Result<Vec<ScalingRow>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut rd =
        csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut rows = Vec::new();
    // Rows written before the columns trust_delta0 and max_inner existed ran with the defaults
    // (ScalingRow's defaults).
    for (i, rec) in rd.deserialize().enumerate() {
        rows.push(rec.with_context(|| format!("{}: bad row {}", path.display(), i + 2))?);
    }
    Ok(rows)
}

fn write_rows(path: &Path, rows: &[ScalingRow]) -> Result<()> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.write_record(header::<ScalingRow>())?;
    for r in rows {
        w.serialize(r)?;
    }
    write_atomic(path, &w.into_inner()?)?;
    Ok(())
}

/// The `trust_delta0` cell of δ0: Rust's shortest form of the number (`1`, `0.25`), the form
/// of the committed CSV and of the resume key.
fn delta0_cell(delta0: f64) -> String {
    delta0.to_string()
}

/// A row's key: `(n, pruning, kind, trust_delta0, max_inner)`; `trust_delta0` as a number
/// (rows written as `1.0` by earlier binaries match δ0 = 1), `max_inner` as written.
type Key = (usize, String, String, String, String);

fn key(r: &ScalingRow) -> Key {
    let delta0 = r
        .trust_delta0
        .parse()
        .map_or_else(|_| r.trust_delta0.clone(), delta0_cell);
    (
        r.n.parse().unwrap_or(0),
        r.pruning.clone(),
        r.kind.clone(),
        delta0,
        r.max_inner.clone(),
    )
}

/// Runs one case in a child process with a time limit.
fn run_case(a: &ScalingArgs, n: usize, mode: &str, max_outer: usize) -> Result<ScalingRow> {
    let (backend, timeout) = (a.backend.as_str(), a.case_timeout_s);
    let exe = std::env::current_exe()?;
    let mut child = Command::new(exe)
        .args([
            "scaling-case",
            "--n",
            &n.to_string(),
            "--pruning",
            mode,
            "--backend",
            backend,
            "--max-outer",
            &max_outer.to_string(),
            "--trust-delta0",
            &a.trust_delta0.to_string(),
            "--max-inner",
            &a.max_inner.to_string(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let start = Instant::now();
    let fail = |status: String| ScalingRow {
        n: n.to_string(),
        vertices: String::new(),
        pruning: mode.to_string(),
        kind: if max_outer == 1 { "one_step" } else { "full" }.to_string(),
        trust_delta0: delta0_cell(a.trust_delta0),
        max_inner: a.max_inner.to_string(),
        status,
        wall_time_s: format!("{:.1}", start.elapsed().as_secs_f64()),
        backend: backend.to_string(),
        ..ScalingRow::empty()
    };
    loop {
        if let Some(st) = child.try_wait()? {
            let out = child.wait_with_output()?;
            if !st.success() {
                let err = String::from_utf8_lossy(&out.stderr);
                let last = err.lines().last().unwrap_or("").replace(',', ";");
                return Ok(fail(format!("failed: {last}")));
            }
            let v: serde_json::Value =
                serde_json::from_slice(&out.stdout).context("scaling-case printed no JSON")?;
            let obj = v
                .as_object()
                .context("scaling-case JSON is not an object")?;
            // every cell as the child wrote it (numbers in serde_json's form)
            let cells: serde_json::Map<String, serde_json::Value> = obj
                .iter()
                .map(|(k, v)| {
                    let s = match v {
                        serde_json::Value::String(s) => s.clone(),
                        other => other.to_string(),
                    };
                    (k.clone(), serde_json::Value::String(s))
                })
                .collect();
            return ScalingRow::from_cells(cells);
        }
        if start.elapsed().as_secs_f64() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            return Ok(fail(format!("timeout after {timeout} s")));
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A progress cell: `-` when empty (a failed case has no timings).
fn or_dash(s: &str) -> &str {
    if s.is_empty() {
        "-"
    } else {
        s
    }
}

/// `contactlab scaling`.
pub fn scaling_cmd(a: ScalingArgs) -> Result<()> {
    for m in &a.modes {
        if Pruning::from_name(m).is_none() {
            bail!("--modes: unknown pruning {m:?} (expected lazy, trust-region, all-pairs)");
        }
    }
    if let Some(&bad) = a.sizes.iter().find(|&&n| n < 2) {
        bail!("--sizes: {bad} elements per membrane is too few (at least 2)");
    }
    if a.case_timeout_s.is_nan() || a.case_timeout_s <= 0.0 {
        bail!("--case-timeout-s must be > 0, got {}", a.case_timeout_s);
    }
    if !(a.trust_delta0 > 0.0 && a.trust_delta0.is_finite()) {
        bail!(
            "--trust-delta0 must be finite and > 0, got {}",
            a.trust_delta0
        );
    }
    if a.max_inner == 0 {
        bail!("--max-inner must be >= 1, got 0");
    }
    backend_from_name(&a.backend, &default_settings(&a.backend))?;
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut rows = read_rows(&a.out)?;
    let mut cases = Vec::new();
    for &n in &a.sizes {
        for m in &a.modes {
            if m == "all-pairs" && n > a.all_pairs_max_n {
                continue;
            }
            cases.push((n, m.clone(), 1usize));
            if n <= a.full_max_n {
                cases.push((n, m.clone(), OuterSettings::default().max_outer));
            }
        }
    }
    let total = cases.len();
    for (i, (n, m, max_outer)) in cases.into_iter().enumerate() {
        let kind = if max_outer == 1 { "one_step" } else { "full" };
        let k: Key = (
            n,
            m.clone(),
            kind.to_string(),
            delta0_cell(a.trust_delta0),
            a.max_inner.to_string(),
        );
        if rows.iter().any(|r| key(r) == k) {
            eprintln!("[{}/{total}] n={n} {m} {kind}: in the CSV, skipped", i + 1);
            continue;
        }
        eprint!("[{}/{total}] n={n} {m} {kind} ... ", i + 1);
        let _ = std::io::stderr().flush();
        let row = run_case(&a, n, &m, max_outer)?;
        eprintln!(
            "{} (step {} s, wall {} s, peak {} MiB)",
            row.status,
            or_dash(&row.step1_t_step_s),
            or_dash(&row.wall_time_s),
            or_dash(&row.peak_rss_mb),
        );
        rows.push(row);
        rows.sort_by_key(key);
        write_rows(&a.out, &rows)?;
    }
    // The picture and the fitted exponents, from every finished one-step row in the CSV.
    let mut series = Vec::new();
    // One series per setting: pruning mode, δ0 (trust region only) and max_inner.
    let done: Vec<&ScalingRow> = rows
        .iter()
        .filter(|r| r.kind == "one_step" && r.status == "one_step_done")
        .collect();
    let label_of = |r: &ScalingRow| {
        let mut l = r.pruning.clone();
        if l == "trust-region" {
            l += &format!(" δ0={}h", r.trust_delta0);
        }
        if r.max_inner != "50" {
            l += &format!(" inner≤{}", r.max_inner);
        }
        l
    };
    let mut labels: Vec<String> = done.iter().map(|r| label_of(r)).collect();
    labels.sort();
    labels.dedup();
    for m in labels {
        let pts: Vec<(f64, f64)> = done
            .iter()
            .filter(|r| label_of(r) == m)
            .filter_map(|r| Some((r.vertices.parse().ok()?, r.step1_t_step_s.parse().ok()?)))
            .collect();
        let slope = loglog_slope(&pts);
        let label = match slope {
            Some(s) => format!("{m} (slope {s:.2})"),
            None => m.clone(),
        };
        println!(
            "{m}: time per outer iteration ~ N^{} over {} sizes",
            slope.map_or("?".into(), |s| format!("{s:.3}")),
            pts.len()
        );
        series.push(Series { label, points: pts });
    }
    let svg = loglog_svg(
        &series,
        &format!("balloons, first outer step, {}", a.backend),
        "vertices N",
        "time of one outer iteration (s)",
    );
    let svg_path = a.out.with_extension("svg");
    write_atomic(&svg_path, svg.as_bytes())?;
    println!("wrote {} and {}", a.out.display(), svg_path.display());
    Ok(())
}
