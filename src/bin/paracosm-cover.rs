//! `paracosm-cover`: coverage of test sets (estimate), test designs (generate), and test
//! budgets (plan) over a scenario's parameter space.
//!
//! Exit codes: 0 success, 2 bad input or usage, 3 internal error.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use paracosm::cover::{estimate, load_space, plan, read_tests, Metric};
use paracosm::Error;
use paracosm_generators::coverage::{discrepancy, Discrepancy};
use paracosm_generators::{Halton, ParamSpace, Strategy};

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
    Estimate {
        /// A CSV file with a header, or the results.jsonl of paracosm-fuzz.
        file: PathBuf,
        /// The parameters' domains: a built-in scenario name, a scenario program (`.star`) or a
        /// TOML file. Without it every column must lie in [0, 1] and is continuous (a first
        /// column `id` is skipped).
        #[arg(long)]
        space: Option<String>,
        /// Largest k-wise strength to report (default: 2, or the number of discrete
        /// parameters if smaller).
        #[arg(long)]
        strength: Option<usize>,
        /// Metrics of the continuous part, comma-separated: dispersion, cd, wd, md, l2star, star.
        #[arg(
            long,
            default_value = "dispersion,cd,wd,md,l2star,star",
            value_delimiter = ','
        )]
        metrics: Vec<String>,
        /// Uncovered tuples to list per strength.
        #[arg(long, default_value_t = 10)]
        missing: usize,
        /// Also decide (k, ε)-covering with k = --strength and this dispersion bound.
        #[arg(long)]
        epsilon: Option<f64>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Write the first N points of a design as CSV in the parameters' units (header: id and
    /// the parameter names), or, with --model, a covering array for a PICT model (header: the
    /// parameter names, then rows of values as written in the model).
    Generate {
        /// The parameters' domains: a built-in scenario name, a scenario program (`.star`) or a
        /// TOML file.
        #[arg(long, required_unless_present = "model", conflicts_with = "model")]
        space: Option<String>,
        /// A PICT model: `Name: v1, v2` lines and `IF [A] = "x" THEN [B] <> "y";` constraints.
        #[arg(long)]
        model: Option<PathBuf>,
        /// The strength t of the covering array (--model, or --strategy ipog / kwise).
        #[arg(long, default_value_t = 2)]
        strength: usize,
        /// With --model: rows that must appear first in the array (PICT's /e), as a CSV with a
        /// header of parameter names and values as written in the model; blank cells are free.
        #[arg(long, requires = "model")]
        seeds: Option<PathBuf>,
        /// With --model: ipog (IPOG-F), kwise (random, sized by Proposition 3.2 / union bound
        /// for δ = 0.01), or random (random rows until every tuple is covered).
        #[arg(long, value_enum, default_value = "ipog")]
        algorithm: Algorithm,
        /// How points are chosen.
        #[arg(long, value_parser = paracosm::cli::strategy_parser(), default_value = "halton")]
        strategy: Strategy,
        /// With --strategy halton: randomise it by digit permutations (Owen 2017).
        #[arg(long)]
        scramble: bool,
        /// Number of points (at least 1).
        #[arg(
            long,
            value_parser = paracosm::cli::positive,
            required_unless_present_any = ["model", "epsilon"]
        )]
        budget: Option<u64>,
        /// With --strategy ipog or kwise instead of --budget: size each array row's Halton block
        /// for this target dispersion, ceil(C / ε) points with C the measured n·dispersion
        /// constant of `plan`.
        #[arg(long, conflicts_with = "budget")]
        epsilon: Option<f64>,
        /// Seed of the random, scrambled Halton and Sobol strategies.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Write to this file instead of standard output (a new or a regular file; a symbolic
        /// link, a directory or a device is refused).
        #[arg(long)]
        output: Option<PathBuf>,
    },
    /// Print how many tests a (k, ε)-covering set needs: random k-wise rows by Proposition 3.2
    /// and its union bound, Halton points per row from the measured n·dispersion constant.
    Plan {
        /// The parameters' domains: a built-in scenario name, a scenario program (`.star`) or a
        /// TOML file.
        #[arg(long)]
        space: String,
        /// Strength k of the discrete part.
        #[arg(long, default_value_t = 2)]
        strength: usize,
        /// Target dispersion of each row's continuous part, in (0, 1].
        #[arg(long)]
        epsilon: f64,
        /// Allowed failure probability of the random k-wise family, in (0, 1).
        #[arg(long, default_value_t = 0.01)]
        delta: f64,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Evaluate the robustness of a signal temporal logic formula on a trace (a CSV with a
    /// header, one column per signal, one row per sample), as the `Stl` monitor does.
    Stl {
        /// The formula, e.g. "G[0,10](a > 0 -> F[0,2](b < 1))"; bounds in seconds.
        formula: String,
        /// The trace.
        trace: PathBuf,
        /// Sampling period in seconds.
        #[arg(long, default_value_t = 1.0)]
        dt: f64,
        /// Print JSON: robustness at time 0, the samples, the evaluation time in seconds.
        #[arg(long)]
        json: bool,
    },
    /// Time the estimators and generators on fixed inputs (the paracosm side of
    /// experiments/bench/compare_scipy.py).
    Bench {
        /// Print JSON (the format compare_scipy.py reads).
        #[arg(long)]
        json: bool,
    },
}

/// Covering-array constructions for `generate --model`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Algorithm {
    /// IPOG with IPOG-F's horizontal growth.
    Ipog,
    /// Random rows, as many as Proposition 3.2 (or its union bound) asks for δ = 0.01.
    Kwise,
    /// Random rows until every coverable tuple is covered.
    Random,
}

fn main() -> ExitCode {
    paracosm_scenarios::memory::set_tool_name("paracosm-cover");
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
            let code = e.downcast_ref::<Error>().map_or(3, Error::exit_code);
            paracosm::cli::to_stderr(&paracosm::cli::error_text(
                "paracosm-cover",
                &format!("{e:#}"),
            ));
            ExitCode::from(code)
        }
    }
}

/// A CSV trace: a header of signal names, one row of numbers per sample.
fn read_trace(path: &std::path::Path, dt_s: f64) -> Result<paracosm_oracles::stl::Trace> {
    let file = path.display().to_string();
    let mut reader = csv::Reader::from_path(path).map_err(|e| bad(format!("{file}: {e}")))?;
    let names: Vec<String> = reader
        .headers()
        .map_err(|e| bad(format!("{file}: {e}")))?
        .iter()
        .map(|n| n.trim().to_owned())
        .collect();
    if names.iter().all(String::is_empty) {
        return Err(bad(format!(
            "{file}:1: the trace is empty: it needs a header of signal names and a row per sample"
        )));
    }
    for (j, n) in names.iter().enumerate() {
        if n.is_empty() {
            return Err(bad(format!("{file}:1: column {}: no signal name", j + 1)));
        }
        if let Some(k) = names[..j].iter().position(|m| m == n) {
            return Err(bad(format!(
                "{file}:1: column {} (`{n}`): the signal is named twice (column {} too)",
                j + 1,
                k + 1
            )));
        }
    }
    let mut columns = vec![Vec::new(); names.len()];
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(format!("{file}:{}: {e}", row + 2)))?;
        for (j, cell) in record.iter().enumerate() {
            // A sample is a finite number: NaN compares false with everything and would be
            // skipped by min and max, infinity is no measurement.
            let v: f64 = cell
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| {
                    bad(format!(
                        "{file}:{}: column {} (`{}`): `{cell}` is not a finite number",
                        row + 2,
                        j + 1,
                        names[j]
                    ))
                })?;
            columns[j].push(v);
        }
    }
    if columns.first().is_none_or(Vec::is_empty) {
        return Err(bad(format!(
            "{file}: the trace has no samples (a header and no rows)"
        )));
    }
    Ok(paracosm_oracles::stl::Trace {
        dt_s,
        signals: names.into_iter().zip(columns).collect(),
    })
}

/// The user's input cannot be honoured: exit code 2.
fn bad(e: impl ToString) -> anyhow::Error {
    Error::BadInput(e.to_string()).into()
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Estimate {
            file,
            space,
            strength,
            metrics,
            missing,
            epsilon,
            json,
        } => {
            let metrics = metrics
                .iter()
                .map(|m| m.parse::<Metric>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(bad)?;
            let space = space.map(|s| load_space(&s)).transpose().map_err(bad)?;
            let set = read_tests(&file, space.as_ref()).map_err(bad)?;
            let report = estimate(&set, &metrics, strength, epsilon, missing).map_err(bad)?;
            let mut out = std::io::stdout().lock();
            if json {
                serde_json::to_writer_pretty(&mut out, &report)?;
                writeln!(out)?;
            } else {
                write!(out, "{report}")?;
            }
            Ok(())
        }
        Command::Generate {
            space,
            model,
            seeds,
            strength,
            algorithm,
            epsilon,
            strategy,
            scramble,
            budget,
            seed,
            output,
        } => {
            if let Some(path) = &output {
                paracosm::atomic::check_target(path)?;
            }
            if let Some(model) = model {
                return generate_array(
                    &model,
                    seeds.as_deref(),
                    strength,
                    algorithm,
                    seed,
                    output.as_deref(),
                );
            }
            let space = load_space(space.as_deref().unwrap_or_default()).map_err(bad)?;
            let strategy = paracosm::cli::strategy(strategy, scramble).map_err(bad)?;
            if strategy.method().is_some() {
                return Err(bad(format!(
                    "{strategy} chooses each test from the robustness of earlier ones, so it \
                     needs a simulator: run it with paracosm-fuzz --strategy {strategy}"
                )));
            }
            if strategy == Strategy::Points {
                return Err(bad(
                    "points replays the rows of a CSV file: it is a paracosm-fuzz strategy \
                     (--strategy points --points FILE); generate writes new designs",
                ));
            }
            let budget = match (budget, epsilon) {
                (Some(b), _) => b,
                (None, Some(eps)) => suite_budget(&space, strategy, strength, eps, seed)?,
                (None, None) => return Err(bad("give --budget or --epsilon")),
            };
            if let Some(cap) = strategy.capacity().filter(|&c| budget > c) {
                return Err(bad(format!(
                    "--budget {budget} is more than the {cap} points {strategy} can produce"
                )));
            }
            if budget > MAX_GENERATE {
                return Err(bad(format!(
                    "the design would have {budget} points, more than the {MAX_GENERATE} this \
                     command writes (about 40 GB of CSV); give a smaller --budget or a larger \
                     --epsilon"
                )));
            }
            let mut generator = strategy
                .build_sized(&space, seed, budget, strength)
                .map_err(bad)?;
            // Points are asked for and written in chunks, so memory does not grow with the
            // budget; into a temporary file renamed at the end with --output.
            let mut write_design = |sink: &mut dyn Write| -> Result<()> {
                let mut w = csv::Writer::from_writer(sink);
                let mut header = vec!["id".to_owned()];
                header.extend(space.params().iter().map(|p| p.name.clone()));
                w.write_record(&header)?;
                let mut next = 0u64;
                while next < budget {
                    let n = (budget - next).min(1 << 16) as usize;
                    for p in generator.ask(n).map_err(bad)? {
                        let a = space.decode(&p)?;
                        let mut row = vec![next.to_string()];
                        row.extend(a.iter().map(|(_, v)| v.to_string()));
                        w.write_record(&row)?;
                        next += 1;
                    }
                }
                w.flush().context("writing the design")?;
                Ok(())
            };
            match &output {
                Some(path) => paracosm::atomic::with_temp(path, |tmp| -> Result<()> {
                    let mut f = std::io::BufWriter::new(std::fs::File::create(tmp)?);
                    write_design(&mut f)?;
                    f.flush()?;
                    Ok(())
                })?,
                None => write_design(&mut std::io::stdout().lock())?,
            }
            Ok(())
        }
        Command::Plan {
            space,
            strength,
            epsilon,
            delta,
            json,
        } => {
            if !(epsilon > 0.0 && epsilon <= 1.0) {
                return Err(bad(format!("--epsilon {epsilon} is not in (0, 1]")));
            }
            if !(delta > 0.0 && delta < 1.0) {
                return Err(bad(format!("--delta {delta} is not in (0, 1)")));
            }
            let space = load_space(&space).map_err(bad)?;
            let nd = space.level_counts().len();
            if nd > 0 && (strength == 0 || strength > nd.min(6)) {
                return Err(bad(format!(
                    "--strength {strength} is not in 1..={} (the space has {nd} discrete parameters)",
                    nd.min(6)
                )));
            }
            let p = plan(&space, strength, epsilon, delta).map_err(bad)?;
            if json {
                writeln!(std::io::stdout(), "{}", serde_json::to_string_pretty(&p)?)?;
            } else {
                write!(std::io::stdout(), "{p}")?;
            }
            Ok(())
        }
        Command::Stl {
            formula,
            trace,
            dt,
            json,
        } => {
            let f = paracosm_oracles::stl::parse(&formula).map_err(bad)?;
            let t = read_trace(&trace, dt)?;
            let started = std::time::Instant::now();
            let r = paracosm_oracles::stl::robustness(&f, &t).map_err(bad)?;
            let eval_s = started.elapsed().as_secs_f64();
            let r0 = r.first().copied().unwrap_or(f64::INFINITY);
            if json {
                writeln!(
                    std::io::stdout(),
                    "{}",
                    serde_json::json!({"robustness": r0, "samples": r.len(), "eval_s": eval_s})
                )?;
            } else {
                writeln!(
                    std::io::stdout(),
                    "robustness {r0} ({}) over {} samples, evaluated in {:.3} ms",
                    if r0 > 0.0 { "satisfied" } else { "violated" },
                    r.len(),
                    eval_s * 1e3
                )?;
            }
            Ok(())
        }
        Command::Bench { json } => {
            let r = bench();
            if json {
                writeln!(std::io::stdout(), "{}", serde_json::to_string(&r)?)?;
            } else {
                for (k, v) in r.as_object().into_iter().flatten() {
                    writeln!(std::io::stdout(), "{k:<30} {v}")?;
                }
            }
            Ok(())
        }
    }
}

/// Most points `generate` writes: a billion rows of CSV, about 40 GB.
const MAX_GENERATE: u64 = 1_000_000_000;

/// The budget of a covering suite whose rows each get `ceil(C / ε)` Halton points.
fn suite_budget(
    space: &ParamSpace,
    strategy: Strategy,
    strength: usize,
    epsilon: f64,
    seed: u64,
) -> Result<u64> {
    use paracosm_generators::covering::{ArrayKind, CoveringSuite};
    if !(epsilon > 0.0 && epsilon <= 1.0) {
        return Err(bad(format!("--epsilon {epsilon} is not in (0, 1]")));
    }
    let kind = match strategy {
        Strategy::Ipog => ArrayKind::Ipog,
        Strategy::KWise => ArrayKind::RandomKWise,
        other => {
            return Err(bad(format!(
                "--epsilon sizes the covering suites (ipog, kwise), not {other}; give --budget"
            )))
        }
    };
    let rows = CoveringSuite::new(space, strength, kind, 1, seed)
        .map_err(bad)?
        .rows() as u64;
    let (per_row, _) =
        paracosm::cover::suite_per_row(space, strength, kind, epsilon, seed, MAX_GENERATE)
            .map_err(bad)?;
    Ok(rows.saturating_mul(per_row))
}

/// `generate --model`: a covering array for a PICT model, written as CSV of value names.
fn generate_array(
    model: &std::path::Path,
    seeds: Option<&std::path::Path>,
    t: usize,
    algorithm: Algorithm,
    seed: u64,
    output: Option<&std::path::Path>,
) -> Result<()> {
    use paracosm_generators::covering::{ipog_with, random_kwise_with, random_until_covered_with};
    paracosm_engine::files::regular_file(model)
        .map_err(|e| bad(format!("cannot read `{}`: {e}", model.display())))?;
    let text = std::fs::read_to_string(model)
        .map_err(|e| bad(format!("cannot read `{}`: {e}", model.display())))?;
    let m = paracosm::cover::parse_pict(&model.display().to_string(), &text).map_err(bad)?;
    let levels = m.levels();
    let seed_rows = match seeds {
        Some(path) => {
            paracosm_engine::files::regular_file(path)
                .map_err(|e| bad(format!("cannot read `{}`: {e}", path.display())))?;
            let text = std::fs::read_to_string(path)
                .map_err(|e| bad(format!("cannot read `{}`: {e}", path.display())))?;
            paracosm::cover::read_seeds(&m, &path.display().to_string(), &text).map_err(bad)?
        }
        None => Vec::new(),
    };
    let array = match algorithm {
        Algorithm::Ipog => ipog_with(&levels, t, &m.constraints, &seed_rows),
        Algorithm::Kwise => random_kwise_with(&levels, t, 0.01, seed, &m.constraints, &seed_rows),
        Algorithm::Random => {
            random_until_covered_with(&levels, t, seed, 10_000_000, &m.constraints, &seed_rows)
        }
    }
    .map_err(bad)?;
    let mut buffer = Vec::new();
    {
        let sink: Box<dyn Write + '_> = match output {
            Some(_) => Box::new(&mut buffer),
            None => Box::new(std::io::stdout().lock()),
        };
        let mut w = csv::Writer::from_writer(sink);
        w.write_record(m.params.iter().map(|(n, _)| n.as_str()))?;
        for r in 0..array.len() {
            w.write_record(
                array
                    .row(r)
                    .iter()
                    .zip(&m.params)
                    .map(|(&v, (_, values))| values[v as usize].as_str()),
            )?;
        }
        w.flush().context("writing the array")?;
    }
    if let Some(path) = output {
        paracosm::atomic::write(path, &buffer)?;
    }
    Ok(())
}

/// Best of 7 runs after a warm-up, in milliseconds.
fn best_ms(mut f: impl FnMut()) -> f64 {
    f();
    (0..7)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

fn bench() -> serde_json::Value {
    let s8 = ParamSpace::unit_cube(8);
    let halton = best_ms(|| {
        let h = Halton::scrambled(&s8, 0);
        std::hint::black_box(h.unit_points(0, 65_536));
    });
    let x: Vec<f64> = Strategy::Random
        .build(&s8, 0)
        .and_then(|mut g| g.ask(4000))
        .expect("random points")
        .into_iter()
        .flat_map(|p| p.continuous)
        .collect();
    let disc = |k: Discrepancy| {
        best_ms(|| {
            std::hint::black_box(discrepancy(&x, 8, k).expect("valid points"));
        })
    };
    serde_json::json!({
        "halton_scrambled_65536x8_ms": halton,
        "cd_4000x8_ms": disc(Discrepancy::Centered),
        "wd_4000x8_ms": disc(Discrepancy::WrapAround),
        "md_4000x8_ms": disc(Discrepancy::Mixture),
        "l2star_4000x8_ms": disc(Discrepancy::L2Star),
        "threads": rayon::current_num_threads(),
    })
}
