//! `fig9`: the paper's Figure 9, random vs. Halton sampling of the pedestrian-crossing study.
//!
//! `cargo run --release -p paracosm-experiments --bin fig9 -- --budget 500`
//!
//! With a learned driver (docs/experiments.md, "Learned drivers"):
//! `cargo run --release -p paracosm-experiments --bin fig9 -- --budget 500 --sut pilotnet
//! --docs docs/fig9_pilotnet.png`

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
    /// The system under test, instead of the scenario's `aeb` (e.g. `pilotnet`); the
    /// campaigns and the figure go to `OUT/fig9-NAME/`.
    #[arg(long)]
    sut: Option<String>,
    /// Also copy the figure's PNG here (e.g. `docs/fig9_pilotnet.png`).
    #[arg(long)]
    docs: Option<PathBuf>,
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let jobs = paracosm_experiments::jobs_or_all_cores(cli.jobs);
    let f = match &cli.sut {
        None => paracosm_experiments::figure9(cli.budget, cli.seed, jobs, &cli.out)?,
        Some(name) => {
            let sut = paracosm_engine::sut::SutConfig::builtin(name)?;
            let dir = cli.out.join(format!("fig9-{name}"));
            paracosm_experiments::figure9_with(cli.budget, cli.seed, jobs, &dir, Some(sut))?
        }
    };
    if let Some(docs) = &cli.docs {
        paracosm::atomic::write(docs, &std::fs::read(&f.plots[0])?)?;
    }
    println!(
        "random: {} failed (dispersion {:.4}), halton: {} failed (dispersion {:.4}) in {} tests \
         each; wrote {} and {}",
        f.random_failures,
        f.dispersion[0],
        f.halton_failures,
        f.dispersion[1],
        cli.budget,
        f.plots[0].display(),
        f.plots[1].display()
    );
    println!(
        "collisions by walking speed, both campaigns' {} tests (95 % Wilson intervals):",
        2 * cli.budget
    );
    println!("| walking speed, m/s | tests | collisions | rate | 95 % interval |");
    println!("|---|---:|---:|---:|---|");
    for b in &f.by_speed {
        println!(
            "| {:.1}–{:.1} | {} | {} | {:.3} | [{:.3}, {:.3}] |",
            b.lo,
            b.hi,
            b.tests,
            b.collisions,
            b.collisions as f64 / b.tests.max(1) as f64,
            b.ci95.0,
            b.ci95.1
        );
    }
    Ok(())
}
