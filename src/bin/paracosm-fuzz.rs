//! `paracosm-fuzz`: run a test campaign on a scenario and report the failures it finds.
//!
//! Exit codes: 0 no failure found, 1 a test failed, 2 bad input or usage, 3 internal error.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use paracosm::cli::{BadInput, StrategyArg, SutArgs};
use tracing::info;

use paracosm::campaign::{Campaign, CampaignError};
use paracosm::campaign_file::{CampaignFile, Shard, SutChoice, CAMPAIGN_FILE};
use paracosm::record::Status;
use paracosm::report::Finished;

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
    /// pedestrian-crossing, follow-lead-car, fog-light, t-loop, grid-world, cut-in,
    /// roundabout, family-of-worlds, example-3-1. Optional with --resume (taken from the folder's campaign.json).
    #[arg(required_unless_present_any = ["list", "resume"])]
    scenario: Option<String>,
    /// List the built-in scenarios and exit.
    #[arg(long)]
    list: bool,
    /// How test points are chosen [default: halton].
    #[arg(long, value_enum)]
    strategy: Option<StrategyArg>,
    /// With --strategy halton: randomise it by digit permutations (Owen 2017); --seed draws
    /// the permutations.
    #[arg(long)]
    scramble: bool,
    /// Strength t of the covering array of --strategy ipog or kwise [default: 2].
    #[arg(long)]
    strength: Option<usize>,
    /// Number of tests of the campaign, at least 1 [default: 100]. With --shard, of the
    /// whole campaign, not of the shard.
    #[arg(long, value_parser = paracosm::cli::positive)]
    budget: Option<u64>,
    /// Campaign seed: seeds the generator and every test [default: 0].
    #[arg(long)]
    seed: Option<u64>,
    /// End the campaign at the first failed test (robustness <= 0): no new test starts, and
    /// results.jsonl ends with that test (tests in flight after it are dropped, so the file
    /// does not depend on --jobs). For falsification, e.g. with --strategy falsify-nm.
    #[arg(long)]
    stop_at_first_failure: bool,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    jobs: Option<u64>,
    /// Output folder for results.jsonl, summary.json and failure_map.{png,svg}.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Replace what --out holds (otherwise a non-empty folder is refused).
    #[arg(long, conflicts_with = "resume")]
    force: bool,
    /// Finish the campaign in --out after a crash, a kill or Ctrl-C: keep its records, cut a
    /// half-written last line, and run the tests that are missing. Refused when the given
    /// arguments differ from the campaign's (campaign.json). Starts the campaign when --out
    /// holds none yet.
    #[arg(long)]
    resume: bool,
    /// Run only shard I of N (0 <= I < N): the tests with ids in [I·budget/N,
    /// (I+1)·budget/N). Merge the shard folders with `paracosm-fuzz merge`.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse)]
    shard: Option<Shard>,
    /// Also write JUnit XML: one test case per generated test, failures with their monitor
    /// verdicts, parameters and replay command.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Refuse to run (exit 2) when the scenario loads with warnings: no monitor, an open
    /// parameter no object reads or that cannot affect the ego (LANGUAGE.md, "Warnings").
    /// For CI.
    #[arg(long)]
    deny_warnings: bool,
    /// Print each test's log (what the program's `print` wrote during it) on stderr, as
    /// `test ID: LINE`, as the test finishes. Without it the log is only in results.jsonl.
    #[arg(long)]
    verbose: bool,
    #[command(flatten)]
    sut: SutArgs,
}

#[derive(Debug, Subcommand)]
enum Sub {
    /// Re-run one recorded test from its parameters and seed (campaign.json beside the
    /// results), write its camera frames as PNG and a contact sheet, and check that the
    /// verdict equals the recorded one. Exit 0 when it does, 3 when it does not.
    Replay(ReplayArgs),
    /// Combine the shard folders of one campaign (--shard I/N) into one campaign folder:
    /// results, summary, coverage and plots. Checks that the shards share the campaign's
    /// fingerprint and that none is missing, given twice or incomplete.
    Merge(MergeArgs),
    /// Reprint the summary of a finished or partial campaign folder: counts, first failure,
    /// coverage and plot paths.
    Report(ReportArgs),
}

#[derive(Debug, clap::Args)]
struct MergeArgs {
    /// The shard folders.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Folder for the merged campaign.
    #[arg(long)]
    out: PathBuf,
    /// Replace what --out holds.
    #[arg(long)]
    force: bool,
    /// Also write JUnit XML.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
}

#[derive(Debug, clap::Args)]
struct ReportArgs {
    /// A campaign (or shard) folder.
    dir: PathBuf,
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
        Some(Sub::Merge(args)) => merge(args),
        Some(Sub::Report(args)) => report(args),
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

/// Set by Ctrl-C: no new test starts.
static STOP: AtomicBool = AtomicBool::new(false);

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
    let stored = if cli.resume && cli.out.join(CAMPAIGN_FILE).exists() {
        Some(CampaignFile::read(&cli.out).map_err(BadInput)?)
    } else {
        None
    };
    let (file, scenario) = settings(cli, stored.as_ref())?;
    // Warnings once per campaign, before anything runs; with --deny-warnings they refuse it.
    let warnings = warnings_of(&scenario);
    for w in &warnings {
        eprintln!("paracosm-fuzz: {w}");
    }
    if cli.deny_warnings && !warnings.is_empty() {
        return Err(BadInput(format!(
            "--deny-warnings: the scenario loads with {} warning{} (above)",
            warnings.len(),
            if warnings.len() == 1 { "" } else { "s" }
        ))
        .into());
    }
    let strategy: paracosm_generators::Strategy = file
        .strategy
        .parse()
        .map_err(|e: paracosm_generators::GeneratorError| BadInput(e.to_string()))?;
    if let Some(cap) = strategy.capacity().filter(|&cap| file.budget > cap) {
        return Err(BadInput(format!(
            "--budget {} is more than the {} points {strategy} can produce",
            file.budget, cap
        ))
        .into());
    }
    if file.shard.is_some() && strategy.method().is_some() {
        return Err(BadInput(format!(
            "--shard cannot split a {strategy} campaign: each of its tests depends on all \
             earlier ones. Run it whole (it is parallel inside: --jobs)"
        ))
        .into());
    }
    let jobs = cli.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        |j| j as usize,
    );
    prepare_out_dir(&cli.out, cli.force, cli.resume)?;
    if stored.is_none() {
        file.write(&cli.out).map_err(BadInput)?;
    }
    let ids = file.ids();
    let existing = if stored.is_some() {
        paracosm::results::load(&cli.out, &scenario.space, ids.clone(), true).map_err(BadInput)?
    } else {
        paracosm::results::Existing {
            records: Vec::new(),
            repaired_bytes: 0,
        }
    };
    if existing.repaired_bytes > 0 {
        eprintln!(
            "paracosm-fuzz: cut a half-written last line ({} bytes) off {}; that test runs again",
            existing.repaired_bytes,
            cli.out.join(paracosm::campaign::RESULTS_FILE).display()
        );
    }
    let start = ids.start + existing.records.len() as u64;
    if stored.is_some() {
        eprintln!(
            "paracosm-fuzz: resuming: {} of {} tests already done",
            existing.records.len(),
            ids.end - ids.start
        );
    }
    // Ctrl-C: finish the tests in flight, write them, and say how to resume. A second
    // Ctrl-C exits at once.
    let _ = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });

    let campaign = Campaign {
        scenario: &scenario,
        strategy,
        seed: file.seed,
        budget: file.budget,
        strength: file.strength,
        jobs,
        stop_at_first_failure: cli.stop_at_first_failure,
    };
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(ids.end - start), ProgressDrawTarget::stderr())
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
        .run_ids(
            &cli.out,
            start..ids.end,
            stored.is_some().then_some(existing.records.as_slice()),
            Some(&STOP),
            |r| {
                failures += u64::from(r.status == Status::Fail);
                if cli.verbose {
                    bar.suspend(|| {
                        for line in &r.log {
                            eprintln!("test {}: {line}", r.id);
                        }
                    });
                }
                bar.set_message(format!("{failures} failed"));
                bar.inc(1);
            },
        )
        .map_err(|e| match e {
            CampaignError::Io { .. } | CampaignError::Generator(_) | CampaignError::Adaptive(_) => {
                anyhow::Error::new(BadInput(e.to_string()))
            }
            CampaignError::Pool { .. } => anyhow::Error::new(e),
        })?;
    bar.finish_and_clear();
    let done = existing.records.len() + report.records.len();
    if report.interrupted {
        eprintln!(
            "paracosm-fuzz: interrupted: {done} of {} tests are in {}; finish the campaign \
             with:\n    paracosm-fuzz --resume --out {}",
            ids.end - ids.start,
            cli.out.join(paracosm::campaign::RESULTS_FILE).display(),
            cli.out.display()
        );
        return Ok(ExitCode::from(130));
    }
    if report.stopped_at_failure {
        eprintln!(
            "paracosm-fuzz: --stop-at-first-failure: stopped after {done} of {} tests",
            ids.end - ids.start
        );
    }
    let mut records = existing.records;
    records.extend(report.records);
    let written = paracosm::report::write_outputs(&Finished {
        out: &cli.out,
        scenario: &scenario,
        file: &file,
        records: &records,
        jobs,
        wall_s: report.wall_s,
        junit: cli.junit.as_deref(),
        warnings,
    })
    .map_err(BadInput)?;
    for w in &written.plot_warnings {
        eprintln!("paracosm-fuzz: warning: {w}");
    }
    let summary = written.summary;
    info!(path = %cli.out.display(), "wrote summary");
    println!(
        "{}",
        paracosm::report::human(&summary, &scenario, &cli.out, ids.end - ids.start)
    );
    Ok(exit_code(&summary.counts))
}

fn exit_code(c: &paracosm::summary::Counts) -> ExitCode {
    if c.fail > 0 {
        ExitCode::from(1)
    } else if c.error > 0 {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    }
}

/// The campaign's settings and scenario: from the arguments (checked against the folder's
/// campaign when resuming), or from the folder's campaign alone (`--resume` without SCENARIO).
fn settings(
    cli: &Cli,
    stored: Option<&CampaignFile>,
) -> Result<(CampaignFile, paracosm_scenarios::Scenario)> {
    let refuse = |diffs: Vec<String>| -> anyhow::Error {
        BadInput(format!(
            "refusing to resume: `{}` holds a campaign with other settings ({}); resume without \
             those arguments, or start a new campaign with --force or another --out",
            cli.out.display(),
            diffs.join("; ")
        ))
        .into()
    };
    let sut = cli.sut.config().map_err(BadInput)?;
    match (&cli.scenario, stored) {
        (Some(name), _) => {
            let mut scenario =
                paracosm_scenarios::load(name).map_err(|e| BadInput(e.to_string()))?;
            if let Some(s) = &sut {
                scenario.sut = s.clone();
            }
            let strategy =
                paracosm::cli::strategy(cli.strategy.unwrap_or(StrategyArg::Halton), cli.scramble)
                    .map_err(BadInput)?;
            let file = CampaignFile::new(
                name,
                &scenario,
                SutChoice::of(sut.as_ref()),
                strategy.name(),
                cli.seed.unwrap_or(0),
                cli.budget.unwrap_or(100),
                cli.strength.unwrap_or(2),
                cli.shard,
            );
            if let Some(st) = stored {
                let diffs = st.differences(&file);
                if !diffs.is_empty() {
                    return Err(refuse(diffs));
                }
            }
            Ok((file, scenario))
        }
        (None, Some(st)) => {
            // Arguments given with a bare --resume must agree with the stored campaign.
            let mut diffs = Vec::new();
            let mut check = |name: &str, given: Option<String>, stored: String| {
                if let Some(g) = given.filter(|g| *g != stored) {
                    diffs.push(format!("{name}: {stored} vs {g}"));
                }
            };
            check("seed", cli.seed.map(|v| v.to_string()), st.seed.to_string());
            check(
                "budget",
                cli.budget.map(|v| v.to_string()),
                st.budget.to_string(),
            );
            check(
                "strength",
                cli.strength.map(|v| v.to_string()),
                st.strength.to_string(),
            );
            let strategy = cli
                .strategy
                .map(|s| paracosm::cli::strategy(s, cli.scramble).map(|s| s.name().to_owned()))
                .transpose()
                .map_err(BadInput)?;
            check("strategy", strategy, st.strategy.clone());
            let shard = |s: Option<Shard>| s.map_or("none".to_owned(), |s| s.to_string());
            check("shard", cli.shard.map(|s| shard(Some(s))), shard(st.shard));
            if sut.is_some() && SutChoice::of(sut.as_ref()) != st.sut {
                diffs.push("system under test differs".into());
            }
            if !diffs.is_empty() {
                return Err(refuse(diffs));
            }
            let mut scenario =
                paracosm_scenarios::load(&st.scenario).map_err(|e| BadInput(e.to_string()))?;
            if let Some(s) = st.sut.config().map_err(BadInput)? {
                scenario.sut = s;
            }
            let again = CampaignFile::new(
                &st.scenario,
                &scenario,
                st.sut.clone(),
                &st.strategy,
                st.seed,
                st.budget,
                st.strength,
                st.shard,
            );
            if again.fingerprint != st.fingerprint {
                return Err(refuse(vec![format!(
                    "the scenario `{}` changed since the campaign started",
                    st.scenario
                )]));
            }
            Ok((st.clone(), scenario))
        }
        (None, None) => Err(BadInput(format!(
            "--resume without SCENARIO needs a campaign in `{}`, which has no {CAMPAIGN_FILE}",
            cli.out.display()
        ))
        .into()),
    }
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
    for line in &r.replayed.log {
        println!("print: {line}");
    }
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

fn merge(args: &MergeArgs) -> Result<ExitCode> {
    prepare_out_dir(&args.out, args.force, false)?;
    let m = paracosm::merge::merge(&args.dirs, &args.out).map_err(BadInput)?;
    // The campaign's wall time: the shards' own, added up (they may have run in parallel).
    let wall_s: f64 = args
        .dirs
        .iter()
        .filter_map(|d| std::fs::read_to_string(d.join(paracosm::report::SUMMARY_FILE)).ok())
        .filter_map(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .filter_map(|s| s["wall_s"].as_f64())
        .sum();
    let written = paracosm::report::write_outputs(&Finished {
        out: &args.out,
        scenario: &m.scenario,
        file: &m.file,
        records: &m.records,
        jobs: 1,
        wall_s,
        junit: args.junit.as_deref(),
        warnings: warnings_of(&m.scenario),
    })
    .map_err(BadInput)?;
    for w in &written.plot_warnings {
        eprintln!("paracosm-fuzz: warning: {w}");
    }
    let summary = written.summary;
    println!(
        "merged {} shards into {}",
        args.dirs.len(),
        args.out.display()
    );
    println!(
        "{}",
        paracosm::report::human(&summary, &m.scenario, &args.out, m.file.budget)
    );
    Ok(exit_code(&summary.counts))
}

fn report(args: &ReportArgs) -> Result<ExitCode> {
    let file = CampaignFile::read(&args.dir).map_err(BadInput)?;
    let mut scenario =
        paracosm_scenarios::load(&file.scenario).map_err(|e| BadInput(e.to_string()))?;
    if let Some(s) = file.sut.config().map_err(BadInput)? {
        scenario.sut = s;
    }
    let ids = file.ids();
    let existing = paracosm::results::load(&args.dir, &scenario.space, ids.clone(), false)
        .map_err(BadInput)?;
    let stored: Option<serde_json::Value> =
        std::fs::read_to_string(args.dir.join(paracosm::report::SUMMARY_FILE))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
    let wall_s = stored
        .as_ref()
        .and_then(|s| s["wall_s"].as_f64())
        .unwrap_or_else(|| existing.records.iter().map(|r| r.wall_ms).sum::<f64>() / 1e3);
    let outputs: Vec<String> = [
        paracosm::campaign::RESULTS_FILE,
        paracosm::report::SUMMARY_FILE,
        "failure_map.png",
        "failure_map.svg",
        "failure_rate.png",
        "failure_rate.svg",
    ]
    .iter()
    .filter(|f| args.dir.join(f).exists())
    .map(|f| f.to_string())
    .collect();
    let summary = paracosm::report::summarise(
        &Finished {
            out: &args.dir,
            scenario: &scenario,
            file: &file,
            records: &existing.records,
            jobs: stored
                .as_ref()
                .and_then(|s| s["jobs"].as_u64())
                .unwrap_or(1) as usize,
            wall_s,
            junit: None,
            warnings: warnings_of(&scenario),
        },
        outputs,
    );
    let expected = ids.end - ids.start;
    println!(
        "{}",
        paracosm::report::human(&summary, &scenario, &args.dir, expected)
    );
    if (existing.records.len() as u64) < expected {
        println!(
            "partial: {} of {expected} tests; finish it with `paracosm-fuzz --resume --out {}`",
            existing.records.len(),
            args.dir.display()
        );
    }
    Ok(exit_code(&summary.counts))
}

/// The scenario's warnings for its system under test, as text.
fn warnings_of(scenario: &paracosm_scenarios::Scenario) -> Vec<String> {
    scenario
        .warnings_for(&scenario.sut)
        .iter()
        .map(ToString::to_string)
        .collect()
}

/// Creates `out`; refuses a non-empty folder unless `force` (replace) or `resume`.
fn prepare_out_dir(out: &std::path::Path, force: bool, resume: bool) -> Result<()> {
    let non_empty = std::fs::read_dir(out)
        .map(|mut d| d.next().is_some())
        .unwrap_or(false);
    if out.exists() && !out.is_dir() {
        return Err(BadInput(format!("--out `{}` is not a folder", out.display())).into());
    }
    if non_empty && !force && !resume {
        return Err(BadInput(format!(
            "`{}` is not empty; pass --resume to finish the campaign in it, --force to replace \
             it, or choose another --out",
            out.display()
        ))
        .into());
    }
    std::fs::create_dir_all(out).map_err(|e| {
        BadInput(format!(
            "cannot create output folder `{}`: {e}",
            out.display()
        ))
    })?;
    // Probe writability now, before any test runs.
    let probe = out.join(".paracosm-write-probe");
    std::fs::write(&probe, b"").map_err(|e| {
        BadInput(format!(
            "cannot write to output folder `{}`: {e}",
            out.display()
        ))
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}
