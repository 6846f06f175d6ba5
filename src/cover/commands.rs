//! The commands of `paracosm-cover`, as the binary parses them (clap [`Args`](clap::Args))
//! and runs them: each writes to the sink it is given and fails with a typed [`Error`], whose
//! [`Error::exit_code`] is the tool's (2 for the user's input, 3 otherwise).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use paracosm_generators::coverage::{discrepancy, Discrepancy};
use paracosm_generators::{Halton, ParamSpace, Strategy};

use crate::Error;

use super::{estimate, load_space, plan, read_tests, Metric};

/// Most points `generate` writes: a billion rows of CSV, about 40 GB.
pub const MAX_GENERATE: u64 = 1_000_000_000;

/// The user's input cannot be honoured: [`Error::BadInput`], exit code 2.
fn bad(e: impl ToString) -> Error {
    Error::BadInput(e.to_string())
}

/// What the command prints cannot be written: [`Error::Output`] (a closed pipe included,
/// which the binary takes as the reader's choice).
fn output(e: std::io::Error) -> Error {
    Error::Output(e)
}

/// [`output`] for the CSV writer, keeping the operating system's error (and so its kind)
/// when there is one.
fn csv_output(e: csv::Error) -> Error {
    if !e.is_io_error() {
        return Error::Output(std::io::Error::other(e.to_string()));
    }
    match e.into_kind() {
        csv::ErrorKind::Io(io) => Error::Output(io),
        other => Error::Output(std::io::Error::other(format!("{other:?}"))),
    }
}

/// `paracosm-cover estimate`.
#[derive(Debug, clap::Args)]
pub struct EstimateArgs {
    /// A CSV file with a header, or the results.jsonl of paracosm-fuzz.
    pub file: PathBuf,
    /// The parameters' domains: a built-in scenario name, a scenario program (`.star`) or a
    /// TOML file. Without it every column must lie in [0, 1] and is continuous (a first
    /// column `id` is skipped).
    #[arg(long)]
    pub space: Option<String>,
    /// Largest k-wise strength to report (default: 2, or the number of discrete
    /// parameters if smaller).
    #[arg(long)]
    pub strength: Option<usize>,
    /// Metrics of the continuous part, comma-separated: dispersion, cd, wd, md, l2star, star.
    #[arg(
        long,
        default_value = "dispersion,cd,wd,md,l2star,star",
        value_delimiter = ','
    )]
    pub metrics: Vec<String>,
    /// Uncovered tuples to list per strength.
    #[arg(long, default_value_t = 10)]
    pub missing: usize,
    /// Also decide (k, ε)-covering with k = --strength and this dispersion bound.
    #[arg(long)]
    pub epsilon: Option<f64>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Compute the dispersion (any dimension) and the star discrepancy (d <= 4) exactly,
    /// past the default limits, whatever the time and memory (d = 3: about 45 s and 2 GB for
    /// the star discrepancy of 10,000 points), with progress on stderr.
    #[arg(long)]
    pub exact: bool,
}

/// `paracosm-cover generate`.
#[derive(Debug, clap::Args)]
pub struct GenerateArgs {
    /// The parameters' domains: a built-in scenario name, a scenario program (`.star`) or a
    /// TOML file.
    #[arg(long, required_unless_present = "model", conflicts_with = "model")]
    pub space: Option<String>,
    /// A PICT model: `Name: v1, v2` lines and `IF [A] = "x" THEN [B] <> "y";` constraints.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// The strength t of the covering array (--model, or --strategy ipog / kwise).
    #[arg(long, default_value_t = 2)]
    pub strength: usize,
    /// With --model: rows that must appear first in the array (PICT's /e), as a CSV with a
    /// header of parameter names and values as written in the model; blank cells are free.
    #[arg(long, requires = "model")]
    pub seeds: Option<PathBuf>,
    /// With --model: ipog (IPOG-F), kwise (random, sized by Proposition 3.2 / union bound
    /// for δ = 0.01), or random (random rows until every tuple is covered).
    #[arg(long, value_enum, default_value = "ipog")]
    pub algorithm: Algorithm,
    /// Post-optimise the covering array (--model) by simulated annealing for about this many
    /// seconds of the reference machine (a budget of moves, so the array is the same on any
    /// machine); 0 turns it off. Default: 2 s for a model of at most 100,000 t-tuples, else
    /// off.
    #[arg(long, value_name = "SECONDS")]
    pub optimise: Option<f64>,
    /// How points are chosen.
    #[arg(long, value_parser = crate::cli::strategy_parser(), default_value = "halton")]
    pub strategy: Strategy,
    /// With --strategy halton: randomise it by digit permutations (Owen 2017).
    #[arg(long)]
    pub scramble: bool,
    /// Number of points (at least 1).
    #[arg(
        long,
        value_parser = crate::cli::positive,
        required_unless_present_any = ["model", "epsilon"]
    )]
    pub budget: Option<u64>,
    /// With --strategy ipog or kwise instead of --budget: size each array row's Halton block
    /// so that its measured dispersion is at most this ε (the points per row that `plan`
    /// prints, raised until every row's own block meets ε).
    #[arg(long, conflicts_with = "budget")]
    pub epsilon: Option<f64>,
    /// Seed of the random, scrambled Halton and Sobol strategies.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write to this file instead of standard output (a new or a regular file; a symbolic
    /// link, a directory or a device is refused).
    #[arg(long)]
    pub output: Option<PathBuf>,
}

/// Covering-array constructions for `generate --model`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Algorithm {
    /// IPOG with IPOG-F's horizontal growth.
    Ipog,
    /// Random rows, as many as Proposition 3.2 (or its union bound) asks for δ = 0.01.
    Kwise,
    /// Random rows until every coverable tuple is covered.
    Random,
}

/// `paracosm-cover plan`.
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// The parameters' domains: a built-in scenario name, a scenario program (`.star`) or a
    /// TOML file.
    #[arg(long)]
    pub space: String,
    /// Strength k of the discrete part.
    #[arg(long, default_value_t = 2)]
    pub strength: usize,
    /// Target dispersion of each row's continuous part, in (0, 1].
    #[arg(long)]
    pub epsilon: f64,
    /// Allowed failure probability of the random k-wise family, in (0, 1).
    #[arg(long, default_value_t = 0.01)]
    pub delta: f64,
    /// Seed of the random k-wise array that `generate --strategy kwise --seed` would draw
    /// (the plan prints what `generate --epsilon` writes with it).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `paracosm-cover stl`.
#[derive(Debug, clap::Args)]
pub struct StlArgs {
    /// The formula, e.g. "G[0,10](a > 0 -> F[0,2](b < 1))"; bounds in seconds.
    pub formula: String,
    /// The trace.
    pub trace: PathBuf,
    /// Sampling period in seconds.
    #[arg(long, default_value_t = 1.0)]
    pub dt: f64,
    /// Print JSON: robustness at time 0, the samples, the evaluation time in seconds.
    #[arg(long)]
    pub json: bool,
}

/// `paracosm-cover bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Print JSON (the format compare_scipy.py reads).
    #[arg(long)]
    pub json: bool,
}

/// Estimates the coverage of a test set and prints it to `out` (a table, or JSON).
///
/// # Errors
/// [`Error::BadInput`] for an unknown metric, a space or test file that cannot be read or
/// does not fit, an impossible strength or ε; [`Error::Output`] when `out` cannot be written.
pub fn run_estimate(a: &EstimateArgs, out: &mut dyn Write) -> Result<(), Error> {
    let metrics = a
        .metrics
        .iter()
        .map(|m| m.parse::<Metric>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(bad)?;
    let space = a
        .space
        .as_deref()
        .map(load_space)
        .transpose()
        .map_err(bad)?;
    let set = read_tests(&a.file, space.as_ref()).map_err(bad)?;
    let tell = ExactTeller::new();
    let report = estimate(
        &set,
        &metrics,
        a.strength,
        a.epsilon,
        a.missing,
        a.exact
            .then_some(&|name: &str, done: u64, total: u64| tell.tell(name, done, total)),
    )
    .map_err(bad)?;
    if a.json {
        serde_json::to_writer_pretty(&mut *out, &report).map_err(|e| output(e.into()))?;
        writeln!(out).map_err(output)
    } else {
        write!(out, "{report}").map_err(output)
    }
}

/// Tells an exact computation's progress on stderr, a line at each tenth of its work and at
/// most every 5 s between (`exact star discrepancy: 40 % (12.3 s)`), so that a log shows it as
/// a terminal does.
struct ExactTeller {
    /// When it started, and the last line's (tenths done, when).
    state: std::sync::Mutex<(Instant, Option<(u64, Instant)>)>,
}

impl ExactTeller {
    fn new() -> Self {
        ExactTeller {
            state: std::sync::Mutex::new((Instant::now(), None)),
        }
    }

    /// `done` of `total` units of the exact `name` are done.
    fn tell(&self, name: &str, done: u64, total: u64) {
        let mut s = self
            .state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let now = Instant::now();
        if done == 0 {
            // A computation starts.
            *s = (now, None);
        }
        let tenths = (done * 10).checked_div(total).unwrap_or(10);
        let due = match s.1 {
            None => true,
            Some((t, at)) => tenths > t || now.duration_since(at).as_secs_f64() >= 5.0,
        };
        if due {
            s.1 = Some((tenths, now));
            let pct = (done * 100).checked_div(total).unwrap_or(100);
            crate::cli::to_stderr(&format!(
                "exact {name}: {pct} % ({:.1} s)",
                now.duration_since(s.0).as_secs_f64()
            ));
        }
    }
}

/// Writes a design (CSV of `id` and the parameters in their units) or, with `--model`, a
/// covering array, to `a.output` (through a temporary file) or else to `out`.
///
/// # Errors
/// [`Error::BadInput`] for an adaptive or `points` strategy, a budget the strategy cannot
/// serve or above [`MAX_GENERATE`], an unreadable space or model, a bad ε; [`Error::Write`]
/// naming `a.output`; [`Error::Output`] for `out`.
pub fn run_generate(a: &GenerateArgs, out: &mut dyn Write) -> Result<(), Error> {
    if let Some(path) = &a.output {
        crate::atomic::check_target(path)?;
    }
    if let Some(model) = &a.model {
        return generate_array(a, model, out);
    }
    let space = load_space(a.space.as_deref().unwrap_or_default()).map_err(bad)?;
    let strategy = crate::cli::strategy(a.strategy, a.scramble)?;
    if strategy.is_adaptive() {
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
    let budget = match (a.budget, a.epsilon) {
        (Some(b), _) => b,
        (None, Some(eps)) => suite_budget(&space, strategy, a.strength, eps, a.seed)?,
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
        .build_sized(&space, a.seed, budget, a.strength)
        .map_err(bad)?;
    // Points are asked for and written in chunks, so memory does not grow with the budget;
    // into a temporary file renamed at the end with --output.
    let mut write_design = |sink: &mut dyn Write| -> Result<(), Error> {
        let mut w = csv::Writer::from_writer(sink);
        let mut header = vec!["id".to_owned()];
        header.extend(space.params().iter().map(|p| p.name.clone()));
        w.write_record(&header).map_err(csv_output)?;
        let mut next = 0u64;
        while next < budget {
            let n = (budget - next).min(1 << 16) as usize;
            for p in generator.ask(n).map_err(bad)? {
                let assignment = space.decode(&p)?;
                let mut row = vec![next.to_string()];
                row.extend(assignment.iter().map(|(_, v)| v.to_string()));
                w.write_record(&row).map_err(csv_output)?;
                next += 1;
            }
        }
        w.flush().map_err(output)
    };
    match &a.output {
        Some(path) => crate::atomic::with_temp(path, |tmp| -> Result<(), Error> {
            let file = std::fs::File::create(tmp).map_err(|e| Error::write(path, e))?;
            let mut f = std::io::BufWriter::new(file);
            write_design(&mut f)?;
            f.flush().map_err(|e| Error::write(path, e))
        }),
        None => write_design(out),
    }
}

/// Prints how many tests a (k, ε)-covering set needs (text or JSON) to `out`.
///
/// # Errors
/// [`Error::BadInput`] for ε outside (0, 1], δ outside (0, 1), a strength outside
/// `1..=min(6, discrete parameters)` or an unreadable space; [`Error::Output`] for `out`.
pub fn run_plan(a: &PlanArgs, out: &mut dyn Write) -> Result<(), Error> {
    let (epsilon, delta, strength) = (a.epsilon, a.delta, a.strength);
    if !(epsilon > 0.0 && epsilon <= 1.0) {
        return Err(bad(format!("--epsilon {epsilon} is not in (0, 1]")));
    }
    if !(delta > 0.0 && delta < 1.0) {
        return Err(bad(format!("--delta {delta} is not in (0, 1)")));
    }
    let space = load_space(&a.space).map_err(bad)?;
    let nd = space.level_counts().len();
    if nd > 0 && (strength == 0 || strength > nd.min(6)) {
        return Err(bad(format!(
            "--strength {strength} is not in 1..={} (the space has {nd} discrete parameters)",
            nd.min(6)
        )));
    }
    let mut p = plan(&space, strength, epsilon, delta).map_err(bad)?;
    super::plan_suites(&mut p, &space, a.seed, MAX_GENERATE).map_err(bad)?;
    if a.json {
        let text = serde_json::to_string_pretty(&p).map_err(|e| Error::Internal(e.to_string()))?;
        writeln!(out, "{text}").map_err(output)
    } else {
        write!(out, "{p}").map_err(output)
    }
}

/// Evaluates an STL formula's robustness at time 0 on a CSV trace and prints it to `out`.
///
/// # Errors
/// [`Error::BadInput`] for a formula that does not parse, a trace that is not a header of
/// distinct signal names over rows of finite numbers ([`read_trace`]), or a formula naming a
/// signal the trace lacks; [`Error::Output`] for `out`.
pub fn run_stl(a: &StlArgs, out: &mut dyn Write) -> Result<(), Error> {
    let f = paracosm_oracles::stl::parse(&a.formula).map_err(bad)?;
    let t = read_trace(&a.trace, a.dt)?;
    let started = Instant::now();
    let r = paracosm_oracles::stl::robustness(&f, &t).map_err(bad)?;
    let eval_s = started.elapsed().as_secs_f64();
    let r0 = r.first().copied().unwrap_or(f64::INFINITY);
    if a.json {
        let v = serde_json::json!({"robustness": r0, "samples": r.len(), "eval_s": eval_s});
        writeln!(out, "{v}").map_err(output)
    } else {
        writeln!(
            out,
            "robustness {r0} ({}) over {} samples, evaluated in {:.3} ms",
            if r0 > 0.0 { "satisfied" } else { "violated" },
            r.len(),
            eval_s * 1e3
        )
        .map_err(output)
    }
}

/// Times the estimators and generators on fixed inputs and prints the times (ms) to `out`.
///
/// # Errors
/// [`Error::Output`] for `out`; [`Error::Internal`] if the fixed inputs are refused.
pub fn run_bench(a: &BenchArgs, out: &mut dyn Write) -> Result<(), Error> {
    let r = bench()?;
    if a.json {
        writeln!(out, "{r}").map_err(output)
    } else {
        for (k, v) in r.as_object().into_iter().flatten() {
            writeln!(out, "{k:<30} {v}").map_err(output)?;
        }
        Ok(())
    }
}

/// A CSV trace: a header of signal names, one row of finite numbers per sample, sampled
/// every `dt_s` seconds.
///
/// # Errors
/// [`Error::BadInput`] naming `path` and the line (and column) of an unreadable file, an
/// empty or repeated signal name, a cell that is not a finite number, or no rows.
pub fn read_trace(path: &Path, dt_s: f64) -> Result<paracosm_oracles::stl::Trace, Error> {
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

/// The budget of a covering suite whose rows each get `ceil(C / ε)` Halton points.
fn suite_budget(
    space: &ParamSpace,
    strategy: Strategy,
    strength: usize,
    epsilon: f64,
    seed: u64,
) -> Result<u64, Error> {
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
        super::suite_per_row(space, strength, kind, epsilon, seed, MAX_GENERATE).map_err(bad)?;
    Ok(rows.saturating_mul(per_row))
}

/// Reads a file the user named, refusing what is not a regular file.
fn read_user_file(path: &Path) -> Result<String, Error> {
    paracosm_engine::files::regular_file(path)
        .map_err(|e| bad(format!("cannot read `{}`: {e}", path.display())))?;
    std::fs::read_to_string(path).map_err(|e| bad(format!("cannot read `{}`: {e}", path.display())))
}

/// The t-tuples a model of `levels` has at strength `t` under which `generate --model`
/// post-optimises its array by default.
pub const DEFAULT_OPTIMISE_MAX_TUPLES: f64 = 100_000.0;

/// Seconds of post-optimisation a small model gets by default.
pub const DEFAULT_OPTIMISE_S: f64 = 2.0;

/// `array` post-optimised as `--optimise` asks (by default for a small model).
///
/// # Errors
/// [`Error::BadInput`] for a negative or non-finite number of seconds.
fn optimised(
    array: &paracosm_generators::covering::CoveringArray,
    a: &GenerateArgs,
    constraints: &paracosm_generators::covering::Constraints,
    frozen: usize,
) -> Result<paracosm_generators::covering::CoveringArray, Error> {
    use paracosm_generators::covering::{optimise, Optimise};
    let t = array.strength;
    // Σ over t-subsets of the level products: the elementary symmetric polynomial e_t.
    let mut e = vec![0.0f64; t + 1];
    e[0] = 1.0;
    for &v in &array.levels {
        for j in (1..=t).rev() {
            e[j] += e[j - 1] * f64::from(v);
        }
    }
    let tuples = e[t];
    let seconds = match a.optimise {
        Some(s) if s.is_finite() && s >= 0.0 => s,
        Some(s) => {
            return Err(bad(format!(
                "--optimise {s}: give a number of seconds >= 0"
            )))
        }
        None if tuples <= DEFAULT_OPTIMISE_MAX_TUPLES => DEFAULT_OPTIMISE_S,
        None => 0.0,
    };
    let how = Optimise::seconds(seconds, a.seed);
    Ok(optimise(array, constraints, frozen, how))
}

/// `generate --model`: a covering array for a PICT model, written as CSV of value names.
fn generate_array(a: &GenerateArgs, model: &Path, out: &mut dyn Write) -> Result<(), Error> {
    use paracosm_generators::covering::{ipog_with, random_kwise_with, random_until_covered_with};
    let text = read_user_file(model)?;
    let m = super::parse_pict(&model.display().to_string(), &text).map_err(bad)?;
    let levels = m.levels();
    let seed_rows = match &a.seeds {
        Some(path) => {
            let text = read_user_file(path)?;
            super::read_seeds(&m, &path.display().to_string(), &text).map_err(bad)?
        }
        None => Vec::new(),
    };
    let (t, seed, constraints) = (a.strength, a.seed, &m.constraints);
    let array = match a.algorithm {
        Algorithm::Ipog => ipog_with(&levels, t, constraints, &seed_rows),
        Algorithm::Kwise => random_kwise_with(&levels, t, 0.01, seed, constraints, &seed_rows),
        Algorithm::Random => {
            random_until_covered_with(&levels, t, seed, 10_000_000, constraints, &seed_rows)
        }
    }
    .map_err(bad)?;
    let array = optimised(&array, a, constraints, seed_rows.len())?;
    let mut buffer = Vec::new();
    {
        let sink: &mut dyn Write = match a.output {
            Some(_) => &mut buffer,
            None => out,
        };
        let mut w = csv::Writer::from_writer(sink);
        w.write_record(m.params.iter().map(|(n, _)| n.as_str()))
            .map_err(csv_output)?;
        for r in 0..array.len() {
            let row = array.row(r);
            let names = row
                .iter()
                .zip(&m.params)
                .map(|(&v, (_, values))| values[v as usize].as_str());
            w.write_record(names).map_err(csv_output)?;
        }
        w.flush().map_err(output)?;
    }
    match &a.output {
        Some(path) => crate::atomic::write(path, &buffer),
        None => Ok(()),
    }
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

/// The timings of `bench`: scrambled Halton 65,536 × 8 and four L2 discrepancies of
/// 4,000 × 8 random points, ms.
fn bench() -> Result<serde_json::Value, Error> {
    let s8 = ParamSpace::unit_cube(8);
    let halton = best_ms(|| {
        let h = Halton::scrambled(&s8, 0);
        std::hint::black_box(h.unit_points(0, 65_536));
    });
    let x: Vec<f64> = Strategy::Random
        .build(&s8, 0)
        .and_then(|mut g| g.ask(4000))
        .map_err(|e| Error::Internal(e.to_string()))?
        .into_iter()
        .flat_map(|p| p.continuous)
        .collect();
    let mut failed = None;
    let mut disc = |k: Discrepancy| {
        best_ms(|| match discrepancy(&x, 8, k) {
            Ok(v) => {
                std::hint::black_box(v);
            }
            Err(e) => failed = Some(e.to_string()),
        })
    };
    let v = serde_json::json!({
        "halton_scrambled_65536x8_ms": halton,
        "cd_4000x8_ms": disc(Discrepancy::Centered),
        "wd_4000x8_ms": disc(Discrepancy::WrapAround),
        "md_4000x8_ms": disc(Discrepancy::Mixture),
        "l2star_4000x8_ms": disc(Discrepancy::L2Star),
        "threads": rayon::current_num_threads(),
    });
    match failed {
        Some(e) => Err(Error::Internal(e)),
        None => Ok(v),
    }
}
