//! `fig9`: the paper's Figure 9, random vs. Halton sampling of the pedestrian-crossing study.
//!
//! `cargo run --release -p paracosm-experiments --bin fig9 -- --budget 500`

use std::path::PathBuf;

use anyhow::Result;
use clap::Parser;

/// Reproduce PARACOSM Figure 9: failure maps of random and Halton sampling side by side.
#[derive(Debug, Parser)]
#[command(name = "fig9")]
struct Cli {
    /// Tests per strategy.
    #[arg(long, default_value_t = 500, value_parser = paracosm::cli::positive)]
    budget: u64,
    /// Seed of the random strategy.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output folder.
    #[arg(long, default_value = "experiments/out")]
    out: PathBuf,
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let jobs = paracosm_experiments::jobs_or_all_cores(cli.jobs);
    let f = paracosm_experiments::figure9(cli.budget, cli.seed, jobs, &cli.out)?;
    println!(
        "random: {} collisions, halton: {} collisions in {} tests each; wrote {} and {}",
        f.random_failures,
        f.halton_failures,
        cli.budget,
        f.plots[0].display(),
        f.plots[1].display()
    );
    Ok(())
}
