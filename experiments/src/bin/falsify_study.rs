//! `falsify_study`: simulations until the first failure for random, Halton, Sobol and the
//! falsifiers (Bayesian optimisation included), on `pedestrian-crossing` and `follow-lead-car`, over 20 seeds.
//!
//! `cargo run --release -p paracosm-experiments --bin falsify_study`

use std::path::PathBuf;

use anyhow::Result;
use clap::Parser;
use paracosm_experiments::falsification::{falsification_study, StudySettings};
use paracosm_generators::Strategy;

/// Measure how many simulations each strategy needs to find a first failure.
#[derive(Debug, Parser)]
#[command(name = "falsify_study")]
struct Cli {
    /// Seeds per strategy (plain Halton has none and runs once).
    #[arg(long, default_value_t = 20, value_parser = paracosm::cli::positive)]
    seeds: u64,
    /// Most simulations per campaign; one without a failure by then counts as censored.
    #[arg(long, default_value_t = 1000, value_parser = paracosm::cli::positive)]
    cap: u64,
    /// Worker threads per campaign (default: all cores). Results do not depend on it.
    #[arg(long)]
    jobs: Option<usize>,
    /// Output folder.
    #[arg(long, default_value = "experiments/out")]
    out: PathBuf,
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let jobs = paracosm_experiments::jobs_or_all_cores(cli.jobs);
    let strategies = [
        Strategy::Random,
        Strategy::Halton,
        Strategy::ScrambledHalton,
        Strategy::Sobol,
        Strategy::FalsifyNm,
        Strategy::FalsifyPso,
        Strategy::FalsifySa,
        Strategy::FalsifyCe,
        Strategy::FalsifyBo,
        Strategy::FalsifyBoLcb,
    ];
    let study = falsification_study(
        &StudySettings {
            scenarios: &["pedestrian-crossing", "follow-lead-car"],
            strategies: &strategies,
            seeds: cli.seeds,
            cap: cli.cap,
            jobs,
        },
        &cli.out,
    )?;
    println!("{}", study.table);
    for f in &study.files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
