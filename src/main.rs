//! The `contactlab` command line.
//!
//! `contactlab run [balloons|ring|sheets|rod|solids|balloons3d] [--backend NAME] [--n 40] [--out DIR] …` runs the
//! outer loop on a scene (backend names: `contactlab_solvers::registry`) and writes a run directory (docs/run-directory.md); `contactlab run path/to/scene.toml`
//! runs a scene file (docs/scene-files.md). Exit codes: 0 a run
//! converged (or a command succeeded), 1 a run finished with a failure status (its directory
//! written), 2 an error (bad input, inadmissible start, a violated guarantee), 101 a panic.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use contactlab::harness::run::{run_cmd, RunArgs, RunFinished};
use contactlab::harness::{export, scaling, sweep};
use contactlab::output::plot;

#[derive(Parser)]
#[command(
    name = "contactlab",
    version,
    about = "Pantz (2008) frictionless contact: runs and measurements"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}
#[derive(Subcommand)]
enum Command {
    /// Run the outer loop on a scene and write a run directory.
    Run(Box<RunArgs>),
    /// The scaling experiment: time per outer iteration, pairs, rows and peak memory against
    /// the number of vertices, per pruning mode (CSV + log-log SVG).
    Scaling(scaling::ScalingArgs),
    /// Run a sweep file: one CSV row per run, flushed as each ends (docs/sweeps.md).
    Sweep(sweep::SweepArgs),
    /// Run a scene and write every sub-problem QP as a QPS file (docs/sweeps.md, "QP export").
    ExportQp(export::ExportArgs),
    /// Log-log SVG of sweep CSV columns with fitted slopes (docs/sweeps.md, "Plots").
    Plot(plot::PlotArgs),
    /// One case of the scaling experiment (run by `scaling` in a child process).
    #[command(hide = true)]
    ScalingCase(scaling::CaseArgs),
}

fn main() {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let run_matches = matches.subcommand_matches("run");
    let explicit = |id: &str| {
        run_matches
            .is_some_and(|m| m.value_source(id) == Some(clap::parser::ValueSource::CommandLine))
    };
    let result = match cli.command {
        Some(Command::Run(a)) => run_cmd(*a, &explicit),
        Some(Command::Sweep(a)) => sweep::cmd_sweep(&a),
        Some(Command::Plot(a)) => plot::cmd_plot(&a),
        Some(Command::ExportQp(a)) => export::cmd_export(&a),
        Some(Command::Scaling(a)) => scaling::scaling_cmd(a),
        Some(Command::ScalingCase(a)) => scaling::case_cmd(a),
        None => match Cli::parse_from(["contactlab", "run"]).command {
            Some(Command::Run(a)) => run_cmd(*a, &explicit),
            _ => unreachable!("`run` parses to Command::Run"),
        },
    };
    // Exit codes: 0 a run converged (a dynamic run completed) or a command succeeded; 1 a run
    // finished with a failure status, its outputs written; 2 an error (bad input, a failed
    // write, a violated guarantee); 101 a panic.
    if let Err(e) = result {
        if let Some(f) = e.downcast_ref::<RunFinished>() {
            eprintln!("contactlab: {f}");
            std::process::exit(1);
        }
        eprintln!("error: {e:#}");
        std::process::exit(2);
    }
}
