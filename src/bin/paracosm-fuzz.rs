//! `paracosm-fuzz`: run a test campaign on a scenario and report the failures it finds.
//!
//! Exit codes: 0 no failure found, 1 a test failed, 2 bad input or usage, 3 internal error.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use paracosm::cli::{BadInput, StrategyArg, SutArgs};
use tracing::info;

use paracosm::campaign::{Campaign, CampaignError, RESULTS_FILE};
use paracosm::record::Status;
use paracosm::summary::Summary;

/// Run a test campaign on a scenario: sample its open parameters, simulate each test, and
/// write results.jsonl, summary.json and a failure map.
#[derive(Debug, Parser)]
#[command(
    name = "paracosm-fuzz",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Sub>,
    /// Scenario to test: a path to a `.star` program, or a built-in name (see --list):
    /// pedestrian-crossing, follow-lead-car, fog-light, t-loop, grid-world.
    #[arg(required_unless_present = "list")]
    scenario: Option<String>,
    /// List the built-in scenarios and exit.
    #[arg(long)]
    list: bool,
    /// How test points are chosen.
    #[arg(long, value_enum, default_value = "halton")]
    strategy: StrategyArg,
    /// With --strategy halton: randomise it by digit permutations (Owen 2017); --seed draws
    /// the permutations.
    #[arg(long)]
    scramble: bool,
    /// Strength t of the covering array of --strategy ipog or kwise.
    #[arg(long, default_value_t = 2)]
    strength: usize,
    /// Number of tests to run (at least 1).
    #[arg(long, default_value_t = 100, value_parser = paracosm::cli::positive)]
    budget: u64,
    /// Campaign seed: seeds the generator and every test.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    jobs: Option<u64>,
    /// Output folder for results.jsonl, summary.json and failure_map.{png,svg}.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Replace the results of an earlier campaign in --out.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    sut: SutArgs,
}

#[derive(Debug, Subcommand)]
enum Sub {
    /// Re-run one recorded test from its parameters and seed (campaign.json beside the
    /// results), write its camera frames as PNG and a contact sheet, and check that the
    /// verdict equals the recorded one. Exit 0 when it does, 3 when it does not.
    Replay(ReplayArgs),
}

#[derive(Debug, clap::Args)]
struct ReplayArgs {
    /// A campaign's results.jsonl.
    results: PathBuf,
    /// Id of the test to re-run.
    #[arg(long)]
    id: u64,
    /// Folder for frame_NNNNN.png and contact_sheet.png (a 320 x 240 camera at 20 Hz is
    /// mounted when the system under test has none).
    #[arg(long, value_name = "DIR")]
    frames: Option<PathBuf>,
    /// A system under test to replay with instead of the recorded one.
    #[command(flatten)]
    sut: SutArgs,
}

fn main() -> ExitCode {
    let cli = match paracosm::cli::parse_args::<Cli>("paracosm-fuzz") {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let result = match &cli.command {
        Some(Sub::Replay(args)) => replay(args),
        None => run(&cli),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            let code = if e.downcast_ref::<BadInput>().is_some() {
                2
            } else {
                3
            };
            eprintln!("paracosm-fuzz: {e:#}");
            ExitCode::from(code)
        }
    }
}

fn run(cli: &Cli) -> Result<ExitCode> {
    if cli.list {
        for name in paracosm_scenarios::builtin_names() {
            let s =
                paracosm_scenarios::builtin(&name).context("a built-in scenario fails to load")?;
            let params: Vec<String> = s.space.params().iter().map(|p| p.label()).collect();
            println!(
                "{name}\n    {}\n    parameters: {}",
                s.description,
                params.join(", ")
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    let name = cli.scenario.as_deref().unwrap_or_default();
    let mut scenario = paracosm_scenarios::load(name).map_err(|e| BadInput(e.to_string()))?;
    if let Some(sut) = cli.sut.config().map_err(BadInput)? {
        scenario.sut = sut;
    }
    let strategy = paracosm::cli::strategy(cli.strategy, cli.scramble).map_err(BadInput)?;
    if let Some(cap) = strategy.capacity().filter(|&cap| cli.budget > cap) {
        return Err(BadInput(format!(
            "--budget {} is more than the {} points {strategy} can produce",
            cli.budget, cap
        ))
        .into());
    }
    let jobs = cli.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        |j| j as usize,
    );
    prepare_out_dir(cli)?;
    let campaign_file = paracosm::replay::CampaignFile {
        tool: format!("paracosm {}", env!("CARGO_PKG_VERSION")),
        scenario: match std::fs::canonicalize(name) {
            Ok(path) if std::path::Path::new(name).is_file() => path.display().to_string(),
            _ => name.to_owned(),
        },
        sut: match (&cli.sut.sut, &cli.sut.sut_cmd) {
            (Some(n), _) => paracosm::replay::SutChoice::Builtin { name: n.clone() },
            (None, Some(_)) => match &scenario.sut {
                paracosm_engine::sut::SutConfig::External(e) => {
                    paracosm::replay::SutChoice::Command {
                        command: e.command.clone(),
                        timeout_s: e.timeout_s,
                        reuse: e.reuse,
                    }
                }
                _ => paracosm::replay::SutChoice::Scenario,
            },
            (None, None) => paracosm::replay::SutChoice::Scenario,
        },
        strategy: strategy.name().to_owned(),
        seed: cli.seed,
        budget: cli.budget,
        strength: cli.strength,
    };
    let campaign_path = cli.out.join(paracosm::replay::CAMPAIGN_FILE);
    std::fs::write(
        &campaign_path,
        serde_json::to_string_pretty(&campaign_file)? + "\n",
    )
    .map_err(|e| BadInput(format!("cannot write `{}`: {e}", campaign_path.display())))?;

    let campaign = Campaign {
        scenario: &scenario,
        strategy,
        seed: cli.seed,
        budget: cli.budget,
        strength: cli.strength,
        jobs,
    };
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(cli.budget), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} tests, {msg} ({per_sec}, eta {eta})",
        )
        .context("progress bar template")?,
    );
    let mut failures = 0u64;
    let report = campaign
        .run(&cli.out, |r| {
            failures += u64::from(r.status == Status::Fail);
            bar.set_message(format!("{failures} failed"));
            bar.inc(1);
        })
        .map_err(|e| match e {
            CampaignError::Io { .. } | CampaignError::Generator(_) => {
                anyhow::Error::new(BadInput(e.to_string()))
            }
            CampaignError::Pool { .. } => anyhow::Error::new(e),
        })?;
    bar.finish_and_clear();

    let stem = cli.out.join("failure_map");
    let title = format!(
        "{}: {}, {} tests, {} failed",
        scenario.name, strategy, cli.budget, report.counts.fail
    );
    let plots = paracosm::plot::failure_map(
        &stem,
        &scenario.space,
        &scenario.map_axes,
        &[(&title, &report.records)],
    )
    .map_err(|e| BadInput(e.to_string()))?;

    let rates = paracosm::plot::failure_rate_map(
        &cli.out.join("failure_rate"),
        &scenario.space,
        &scenario.map_axes,
        &format!("{}: failure rate ({} tests)", scenario.name, cli.budget),
        &report.records,
        8,
    )
    .map_err(|e| BadInput(e.to_string()))?;
    let plots: Vec<std::path::PathBuf> = plots.into_iter().chain(rates).collect();
    let mut outputs = vec![RESULTS_FILE.to_owned(), "summary.json".to_owned()];
    outputs.extend(
        plots
            .iter()
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned())),
    );
    let coverage = {
        let set = paracosm::cover::TestSet {
            space: scenario.space.clone(),
            points: report.records.iter().map(|r| r.point.clone()).collect(),
        };
        let metrics: Vec<paracosm::cover::Metric> =
            ["dispersion", "cd", "wd", "md", "l2star", "star"]
                .iter()
                .filter_map(|m| m.parse().ok())
                .collect();
        paracosm::cover::estimate(&set, &metrics, None, None, 10).ok()
    };
    let summary = Summary {
        tool: format!("paracosm {}", env!("CARGO_PKG_VERSION")),
        scenario: scenario.name.clone(),
        strategy: strategy.name().to_owned(),
        seed: cli.seed,
        budget: cli.budget,
        jobs,
        space: scenario.space.params().to_vec(),
        counts: report.counts,
        first_failure: report.first_failure.clone(),
        coverage,
        wall_s: report.wall_s,
        outputs,
    };
    let summary_path = cli.out.join("summary.json");
    std::fs::write(
        &summary_path,
        serde_json::to_string_pretty(&summary)? + "\n",
    )
    .map_err(|e| BadInput(format!("cannot write `{}`: {e}", summary_path.display())))?;
    info!(path = %summary_path.display(), "wrote summary");

    let c = report.counts;
    println!(
        "{} tests of {} ({}, seed {}): {} passed, {} failed, {} errors in {:.1} s ({:.0} tests/s)",
        cli.budget,
        scenario.name,
        strategy,
        cli.seed,
        c.pass,
        c.fail,
        c.error,
        report.wall_s,
        cli.budget as f64 / report.wall_s.max(1e-9)
    );
    if let Some(f) = &report.first_failure {
        let values: Vec<String> = f
            .params
            .iter()
            .map(|(n, v)| {
                let unit = scenario
                    .space
                    .param(n)
                    .and_then(|p| p.unit.clone())
                    .unwrap_or_default();
                match v.as_f64() {
                    Some(x) => format!("{n} = {x:.3} {unit}"),
                    None => format!("{n} = {v}"),
                }
            })
            .collect();
        println!(
            "first failure: test {} ({}), monitors failed: {}",
            f.id,
            values.join(", "),
            f.failed_monitors.join(", ")
        );
    }
    println!(
        "wrote {}, {}, {}",
        cli.out.join(RESULTS_FILE).display(),
        summary_path.display(),
        plots
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(if c.fail > 0 {
        ExitCode::from(1)
    } else if c.error > 0 {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    })
}

fn replay(args: &ReplayArgs) -> Result<ExitCode> {
    let sut = args.sut.config().map_err(BadInput)?;
    let r = paracosm::replay::replay(&args.results, args.id, args.frames.as_deref(), sut)
        .map_err(|e| BadInput(e.to_string()))?;
    let recorded = r.recorded["status"].as_str().unwrap_or("?");
    let replayed = paracosm::replay::status_name(r.replayed.status);
    let verdicts: Vec<String> = r
        .replayed
        .monitors
        .iter()
        .map(|(n, m)| {
            format!(
                "{n} {} (robustness {:.3})",
                if m.passed { "passed" } else { "failed" },
                m.robustness
            )
        })
        .collect();
    println!(
        "test {}: recorded {recorded}, replayed {replayed}: {}{}",
        args.id,
        verdicts.join(", "),
        r.replayed
            .error
            .as_deref()
            .map(|e| format!(" ({e})"))
            .unwrap_or_default()
    );
    if let Some(sheet) = &r.contact_sheet {
        println!(
            "wrote {} frames to {} and {}",
            r.frames.len(),
            args.frames
                .as_deref()
                .unwrap_or(std::path::Path::new("."))
                .display(),
            sheet.display()
        );
    }
    if r.matches {
        println!("the replayed verdict equals the recorded one");
        Ok(ExitCode::SUCCESS)
    } else {
        println!(
            "the replayed verdict DIFFERS from the recorded one: recorded monitors {}",
            r.recorded["monitors"]
        );
        Ok(ExitCode::from(3))
    }
}

/// Creates `--out` and refuses to overwrite an earlier campaign's results without `--force`.
fn prepare_out_dir(cli: &Cli) -> Result<()> {
    let results = cli.out.join(RESULTS_FILE);
    if results.exists() && !cli.force {
        return Err(BadInput(format!(
            "`{}` already holds a campaign's results; pass --force to replace them, or choose \
             another --out",
            cli.out.display()
        ))
        .into());
    }
    std::fs::create_dir_all(&cli.out).map_err(|e| {
        BadInput(format!(
            "cannot create output folder `{}`: {e}",
            cli.out.display()
        ))
    })?;
    // Probe writability now, before any test runs.
    let probe = cli.out.join(".paracosm-write-probe");
    std::fs::write(&probe, b"").map_err(|e| {
        BadInput(format!(
            "cannot write to output folder `{}`: {e}",
            cli.out.display()
        ))
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}
