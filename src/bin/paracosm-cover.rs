//! `paracosm-cover`: coverage of test sets (estimate), test designs (generate), and test
//! budgets (plan) over a scenario's parameter space.
//!
//! Exit codes: 0 success, 2 bad input or usage, 3 internal error.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use paracosm::cover::commands::{
    run_bench, run_estimate, run_generate, run_plan, run_stl, BenchArgs, EstimateArgs,
    GenerateArgs, PlanArgs, StlArgs,
};
use paracosm::Error;

/// Counts what Starlark evaluation allocates, so one huge allocation of a program or lambda is a
/// clear error with exit code 2 instead of an abort (`paracosm_scenarios::memory`).
#[global_allocator]
static ALLOC: paracosm_scenarios::memory::CountingAlloc = paracosm_scenarios::memory::CountingAlloc;

/// Coverage of test sets, test designs and test budgets over a parameter space.
#[derive(Debug, Parser)]
#[command(name = "paracosm-cover", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Estimate the coverage of a test set: k-wise coverage of the discrete parameters,
    /// dispersion and discrepancies of the continuous ones, and optionally the (k, ε)-covering
    /// verdict.
    Estimate(EstimateArgs),
    /// Write the first N points of a design as CSV in the parameters' units (header: id and
    /// the parameter names), or, with --model, a covering array for a PICT model (header: the
    /// parameter names, then rows of values as written in the model).
    Generate(GenerateArgs),
    /// Print how many tests a (k, ε)-covering set needs: random k-wise rows by Proposition 3.2
    /// and its union bound, Halton points per row measured to have dispersion at most ε.
    Plan(PlanArgs),
    /// Evaluate the robustness of a signal temporal logic formula on a trace (a CSV with a
    /// header, one column per signal, one row per sample), as the `Stl` monitor does.
    Stl(StlArgs),
    /// Time the estimators and generators on fixed inputs (the paracosm side of
    /// experiments/bench/compare_scipy.py).
    Bench(BenchArgs),
}

fn main() -> ExitCode {
    paracosm_scenarios::memory::set_tool_name("paracosm-cover");
    let cli = match paracosm::cli::parse_args::<Cli>("paracosm-cover") {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    let out = &mut std::io::stdout().lock();
    let done = match &cli.command {
        Command::Estimate(a) => run_estimate(a, out),
        Command::Generate(a) => run_generate(a, out),
        Command::Plan(a) => run_plan(a, out),
        Command::Stl(a) => run_stl(a, out),
        Command::Bench(a) => run_bench(a, out),
    };
    match done {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (`| head`) is the reader's choice, not an error.
        Err(Error::Output(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            paracosm::cli::to_stderr(&paracosm::cli::error_text("paracosm-cover", &e.to_string()));
            ExitCode::from(e.exit_code())
        }
    }
}
