//! `paracosm-cover`: test designs over a scenario's parameter space.
//!
//! `paracosm-cover generate SCENARIO --strategy halton -n 50` writes the first 50 points of
//! the design as CSV (one column per parameter, values in the parameters' units), so that a
//! design can be inspected, plotted or run by another tool.
//!
//! Exit codes: 0 success, 2 bad input or usage, 3 internal error.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use paracosm::cli::{BadInput, StrategyArg};

use paracosm_generators::Strategy;

/// Test designs over a scenario's parameter space.
#[derive(Debug, Parser)]
#[command(name = "paracosm-cover", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Write the first N points of a design as CSV: a header of parameter names, then one row
    /// per test with its id and values in the parameters' units.
    Generate {
        /// Built-in scenario whose open parameters span the space (e.g. pedestrian-crossing).
        scenario: String,
        /// How points are chosen.
        #[arg(long, value_enum, default_value = "halton")]
        strategy: StrategyArg,
        /// Number of points (at least 1).
        #[arg(short = 'n', long, value_parser = paracosm::cli::positive)]
        count: u64,
        /// Seed of the random and Sobol strategies.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Write to this file instead of standard output.
        #[arg(long)]
        output: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = match paracosm::cli::parse_args::<Cli>("paracosm-cover") {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A closed pipe (`| head`) is the reader's choice, not an error.
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) {
                return ExitCode::SUCCESS;
            }
            let code = if e.downcast_ref::<BadInput>().is_some() {
                2
            } else {
                3
            };
            eprintln!("paracosm-cover: {e:#}");
            ExitCode::from(code)
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Generate {
            scenario,
            strategy,
            count,
            seed,
            output,
        } => {
            let scenario =
                paracosm_scenarios::builtin(&scenario).map_err(|e| BadInput(e.to_string()))?;
            let strategy = Strategy::from(strategy);
            let points = strategy
                .build(&scenario.space, seed)
                .and_then(|mut g| g.ask(count as usize))
                .map_err(|e| BadInput(e.to_string()))?;
            let sink: Box<dyn Write> = match &output {
                Some(path) => Box::new(
                    std::fs::File::create(path)
                        .map_err(|e| BadInput(format!("cannot write `{}`: {e}", path.display())))?,
                ),
                None => Box::new(std::io::stdout().lock()),
            };
            let mut w = csv::Writer::from_writer(sink);
            let mut header = vec!["id".to_owned()];
            header.extend(scenario.space.params().iter().map(|p| p.name.clone()));
            w.write_record(&header)?;
            for (i, p) in points.iter().enumerate() {
                let a = scenario.space.decode(p)?;
                let mut row = vec![i.to_string()];
                row.extend(a.iter().map(|(_, v)| v.to_string()));
                w.write_record(&row)?;
            }
            w.flush().context("writing the design")?;
            Ok(())
        }
    }
}
