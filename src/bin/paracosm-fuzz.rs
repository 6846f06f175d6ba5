//! `paracosm-fuzz`: run a test campaign on a scenario and report the failures it finds.
//!
//! Exit codes: 0 no failure found, 1 a test failed, 2 bad input or usage, 3 a test in error,
//! an output that cannot be written or an internal error, 130 interrupted.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use paracosm::campaign::file::Shard;
use paracosm::campaign::progress::Progress;
use paracosm::campaign::session::{Plan, Request};
use paracosm::cli::SutArgs;
use paracosm::Error;
use paracosm_generators::Strategy;

/// Counts what Starlark evaluation allocates, so one huge allocation of a program or lambda is a
/// clear error with exit code 2 instead of an abort (`paracosm_scenarios::memory`).
#[global_allocator]
static ALLOC: paracosm_scenarios::memory::CountingAlloc = paracosm_scenarios::memory::CountingAlloc;

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
    /// roundabout, family-of-worlds, example-3-1, curve-pedestrian, opendrive-junction. Optional with --resume (taken from the folder's campaign.json).
    #[arg(required_unless_present_any = ["list", "resume"])]
    scenario: Option<String>,
    /// List the built-in scenarios and exit.
    #[arg(long)]
    list: bool,
    /// With an OpenSCENARIO scenario (.xosc): open a declared parameter the file does not
    /// vary, Name=lo..hi (an interval) or Name=a,b,c (levels), checked against its
    /// constraint groups. Repeatable.
    #[arg(long, value_name = "NAME=RANGE")]
    open: Vec<String>,
    /// With an OpenSCENARIO variation file: a DistributionRange becomes an interval over its
    /// range instead of its levels.
    #[arg(long)]
    continuous: bool,
    /// With an OpenSCENARIO scenario (.xosc): the storyboard moves the ego as it moves every
    /// other entity (its Init, trajectories and actions), and no system under test drives it;
    /// replays a test that `export` wrote. Not with --sut, --sut-cmd or --sut-onnx.
    #[arg(long)]
    scripted_ego: bool,
    /// With an OpenSCENARIO scenario (.xosc): the vehicle the system under test drives, for
    /// a file with several vehicles, none named Ego or hero, whose storyboard activates no
    /// controller (such a file is refused without it). The summary names the ego.
    #[arg(long, value_name = "NAME")]
    ego: Option<String>,
    /// With an OpenSCENARIO scenario (.xosc): end each test at this simulated time, s, at
    /// the latest (the storyboard's stop trigger may end it sooner). Needed by a storyboard
    /// without a stop trigger, which is refused without it.
    #[arg(long, value_name = "SECONDS")]
    horizon: Option<f64>,
    /// Write each test's trace to OUT/trace/test_N.csv: every entity's pose, speed and
    /// acceleration in the map's frame, laid out as esmini's CSV log (docs/cli.md, "Traces").
    #[arg(long)]
    trace: bool,
    /// With --trace: the time between two lines of a trace, s [default: 0.1] (implies
    /// --trace).
    #[arg(long, value_name = "SECONDS")]
    trace_every: Option<f64>,
    /// How test points are chosen [default: halton].
    #[arg(long, value_parser = paracosm::cli::strategy_parser())]
    strategy: Option<Strategy>,
    /// With --strategy halton: randomise it by digit permutations (Owen 2017); --seed draws
    /// the permutations.
    #[arg(long)]
    scramble: bool,
    /// Strength t of the covering array of --strategy ipog or kwise, and, for any strategy,
    /// the highest t of the k-wise coverage the summary reports [default: 2].
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
    /// Run the tests of FILE instead of generating them (strategy `points`): a CSV with a
    /// header naming the parameters, values in their units (levels as written), one test per
    /// row in order; or another campaign's results.jsonl. The budget is the row count.
    #[arg(long, value_name = "FILE")]
    points: Option<PathBuf>,
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
    /// coverage, where failures are, and plot paths; redraw plots on other parameters, or the
    /// tests over the road map (--on-map).
    Report(ReportArgs),
    /// Export training data: run a campaign with a teacher (the scenario's system under test
    /// or --sut) and write, per recorded frame, the camera image, depth (.npy), segmentation
    /// mask, COCO boxes, ego state and the teacher's control, indexed by frames.csv.
    Dataset(DatasetArgs),
    /// Write one recorded test as an ASAM OpenSCENARIO 1.2 scenario (DIR/test_ID.xosc) with
    /// its road network as OpenDRIVE (DIR/test_ID.xodr: the program's map, or its pieces
    /// written out), replayed from its parameters and seed: the ego's start, speed and route,
    /// each car's trajectory as driven, each pedestrian's walk starting on the distance to the
    /// ego that triggered it. Exit 0, or 3 when the replayed verdict differs from the recorded
    /// one.
    Export(ExportArgs),
    /// List an OpenDRIVE map's roads (id, length, junction, lane sections with their range of
    /// s and their lanes as id:type), and its junctions with each connection (incoming ->
    /// connecting -> outgoing road, contact point, turn), to pick onLane(road=, lane=, s=);
    /// with --png/--svg, also draw it top-down with road ids, lane directions and junctions.
    /// Exit 0, or 2 for a map that does not load (naming file:line:col).
    Map(MapArgs),
    /// Read an OpenSCENARIO logical scenario (a ParameterValueDistribution file and the
    /// scenario it names, or a scenario alone) and list paracosm's space for it (each varied
    /// parameter, and each --open), the file's own grid, the entities, Init, the storyboard
    /// and everything read but not honoured as written. Exit 0, or 2 for a file that does
    /// not read (naming file:line:col and what is supported).
    Xosc(XoscArgs),
}

#[derive(Debug, clap::Args)]
struct XoscArgs {
    /// The variation file or scenario (.xosc).
    file: PathBuf,
    /// Open a declared parameter the file does not vary: Name=lo..hi (an interval) or
    /// Name=a,b,c (levels), checked against its constraint groups. Repeatable.
    #[arg(long, value_name = "NAME=RANGE")]
    open: Vec<String>,
    /// A DistributionRange becomes an interval over its range instead of its levels.
    #[arg(long)]
    continuous: bool,
}

#[derive(Debug, clap::Args)]
struct MapArgs {
    /// The OpenDRIVE file (.xodr).
    file: PathBuf,
    /// Draw the map into this PNG file.
    #[arg(long, value_name = "PATH")]
    png: Option<PathBuf>,
    /// Draw the map into this SVG file.
    #[arg(long, value_name = "PATH")]
    svg: Option<PathBuf>,
}

#[derive(Debug, clap::Args)]
struct ExportArgs {
    /// A campaign's results.jsonl.
    results: PathBuf,
    /// Id of the test to export.
    #[arg(long)]
    id: u64,
    /// Folder for test_ID.xosc and test_ID.xodr (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Write the ego's route (an AssignRouteAction, for another system under test to drive)
    /// instead of the trajectory it drove (a timed FollowTrajectoryAction, the default).
    #[arg(long)]
    ego_route: bool,
}

#[derive(Debug, clap::Args)]
struct DatasetArgs {
    /// Scenario: a `.star` path or a built-in name.
    scenario: String,
    /// How test points are chosen (not an adaptive strategy).
    #[arg(long, value_parser = paracosm::cli::dataset_strategy_parser(), default_value = "halton")]
    strategy: Strategy,
    /// Strength t of --strategy ipog or kwise.
    #[arg(long, default_value_t = 2)]
    strength: usize,
    /// Number of tests.
    #[arg(long, value_parser = paracosm::cli::positive, default_value = "10")]
    budget: u64,
    /// Campaign seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Frames recorded per second of simulated time: 60 divided by a whole number of physics
    /// steps (60, 30, 20, 15, 12, 10, ...); another rate is refused.
    #[arg(long, value_name = "HZ", default_value_t = 10.0)]
    rate: f64,
    /// Camera image width in pixels (when the teacher has no camera of its own).
    #[arg(long, default_value_t = 320)]
    width: u32,
    /// Camera image height in pixels.
    #[arg(long, default_value_t = 240)]
    height: u32,
    /// Camera focal length in mm (36 mm sensor width).
    #[arg(long, default_value_t = 24.0)]
    focal_mm: f64,
    /// Worker threads (default: all cores). The data set does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    jobs: Option<u64>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Replace what --out holds.
    #[arg(long)]
    force: bool,
    /// Steering noise added to what the vehicle applies, in steering units (1 = full lock),
    /// so that the teacher's recorded answers show how to recover (DART; docs/experiments.md).
    #[arg(long, value_name = "AMPLITUDE", default_value_t = 0.0)]
    steer_noise: f64,
    /// Seconds each noise value is held.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    noise_hold: f64,
    /// An ONNX network that drives while the teacher labels (DAgger: Ross, Gordon and Bagnell
    /// 2011): the frames show the network's own states, the labels are the teacher's answers
    /// for them (docs/experiments.md)
    #[arg(long, value_name = "MODEL.onnx")]
    learner_onnx: Option<PathBuf>,
    /// With --learner-onnx: the probability in [0, 1] that a decision applies the teacher's
    /// answer instead of the network's (DAgger's beta)
    #[arg(
        long,
        value_name = "P",
        default_value_t = 0.0,
        requires = "learner_onnx"
    )]
    teacher_share: f64,
    /// The teacher, instead of the scenario's system under test.
    #[command(flatten)]
    sut: SutArgs,
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
    /// Plots to redraw from the records.
    #[command(flatten)]
    redraw: paracosm::cli::Redraw,
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
    /// Folder for the test's trace, DIR/test_ID.csv: every entity's pose, speed and
    /// acceleration, laid out as esmini's CSV log (as a campaign's --trace writes).
    #[arg(long, value_name = "DIR")]
    trace: Option<PathBuf>,
    /// With --trace: the time between two lines, s [default: 0.1].
    #[arg(long, value_name = "SECONDS", requires = "trace")]
    trace_every: Option<f64>,
    /// A system under test to replay with instead of the recorded one.
    #[command(flatten)]
    sut: SutArgs,
}

impl DatasetArgs {
    fn request(&self) -> Result<paracosm::export::dataset::DatasetRequest, Error> {
        Ok(paracosm::export::dataset::DatasetRequest {
            scenario: self.scenario.clone(),
            strategy: self.strategy,
            seed: self.seed,
            budget: self.budget,
            strength: self.strength,
            rate_hz: self.rate,
            camera: paracosm_engine::CameraSpec {
                width: self.width,
                height: self.height,
                focal_mm: self.focal_mm,
                ..Default::default()
            },
            sut: self.sut.config()?,
            out: self.out.clone(),
            replace: self.force,
            jobs: self.jobs.map_or_else(num_cpus, |j| j as usize),
            steer_noise: self.steer_noise,
            noise_hold_s: self.noise_hold,
            learner: self
                .learner_onnx
                .as_deref()
                .map(|m| {
                    paracosm_engine::sut::SutConfig::onnx(m)
                        .map_err(|e| Error::BadInput(format!("--learner-onnx: {e}")))
                })
                .transpose()?,
            teacher_share: self.teacher_share,
        })
    }
}

fn num_cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Set by SIGTERM (what Slurm and Kubernetes send to stop a job), besides [`STOP`]: the exit
/// code of an interrupted run is then 143 instead of 130.
static TERMINATED: AtomicBool = AtomicBool::new(false);

/// Ctrl-C (SIGINT) and SIGTERM: no new test starts; the tests in flight finish and are
/// written, and the tool says how to resume and exits 130 (SIGINT) or 143 (SIGTERM). A second
/// signal exits at once with that code.
fn stop_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        for signal in signals.forever() {
            if signal == SIGTERM {
                TERMINATED.store(true, Ordering::SeqCst);
            }
            if STOP.swap(true, Ordering::SeqCst) {
                std::process::exit(if signal == SIGTERM { 143 } else { 130 });
            }
        }
    });
}

/// The exit code of a run that ended with `code`: an interruption (130) by SIGTERM is 143.
fn interrupted_code(code: u8) -> u8 {
    if code == 130 && TERMINATED.load(Ordering::SeqCst) {
        143
    } else {
        code
    }
}

/// Gives Mesa's Vulkan loader the runtime folder it wants when the environment has none (a
/// sandbox, a batch job): without one it prints "error: XDG_RUNTIME_DIR is invalid or not
/// set" on every render, though rendering works. Set before any thread starts.
fn runtime_dir() {
    let valid =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if !valid {
        // One folder per user, kept between runs (as the loader's own would be).
        let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
        let dir = std::env::temp_dir().join(format!("paracosm-xdg-{user}"));
        if std::fs::create_dir_all(&dir).is_ok() {
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
            }
            std::env::set_var("XDG_RUNTIME_DIR", &dir);
        }
    }
}

/// Mesa's CPU rasterisers (lavapipe, llvmpipe) render on the thread that submits unless
/// `LP_NUM_THREADS` asks for helper threads. Each camera frame is small and every worker
/// submits its own: helper threads only add hand-offs (about a tenth of a camera test's CPU
/// time, docs/performance.md, "The camera loop"). A value the user set is kept; a GPU ignores
/// it. Called first, before any thread starts.
fn render_on_the_calling_thread() {
    if std::env::var_os("LP_NUM_THREADS").is_none() {
        std::env::set_var("LP_NUM_THREADS", "0");
    }
}

fn main() -> ExitCode {
    render_on_the_calling_thread();
    runtime_dir();
    paracosm_scenarios::memory::set_tool_name("paracosm-fuzz");
    stop_on_signals();
    // What an external system under test leaves outside its process group (a `setsid`
    // helper, a double fork) is adopted by this process and killed with the program. Without
    // it (an old kernel) such helpers are only killed with the group, as documented.
    if let Err(e) = paracosm_engine::sut::track_orphans() {
        tracing::debug!("PR_SET_CHILD_SUBREAPER: {e}");
    }
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
        Some(Sub::Replay(a)) => {
            let sut = a.sut.config();
            let trace = a.trace.clone().map(|path| paracosm::export::trace::TraceSpec {
                path,
                every_s: a
                    .trace_every
                    .unwrap_or(paracosm::export::trace::DEFAULT_EVERY_S),
            });
            sut.and_then(|s| {
                paracosm::export::replay::replay_traced(
                    &a.results,
                    a.id,
                    a.frames.as_deref(),
                    s,
                    trace,
                )
            })
                .map_err(anyhow::Error::new)
                .and_then(|r| say(&r.text(a.id, a.frames.as_deref())).map(|()| r))
                .map(|r| if r.matches { 0 } else { 3 })
        }
        Some(Sub::Merge(a)) => {
            paracosm::campaign::merge::merge_folders(&a.dirs, &a.out, a.force, a.junit.as_deref())
                .map_err(anyhow::Error::new)
                .and_then(|(text, counts, warnings)| {
                    warnings
                        .iter()
                        .for_each(|w| paracosm::cli::to_stderr(&format!("paracosm-fuzz: warning: {w}")));
                    say(&text).map(|()| counts.exit_code())
                })
        }
        Some(Sub::Report(a)) => paracosm::report::reread(&a.dir, &a.redraw)
            .map_err(anyhow::Error::new)
            .and_then(|(text, counts)| say(&text).map(|()| counts.exit_code())),
        Some(Sub::Dataset(a)) => a
            .request()
            .and_then(|r| paracosm::export::dataset::export(&r, Some(&STOP)))
            .map_err(anyhow::Error::new)
            .and_then(|s| say(&s.text()).map(|()| s.exit_code())),
        Some(Sub::Export(a)) => paracosm::export::export(
            &a.results,
            a.id,
            &a.out,
            if a.ego_route {
                paracosm::export::xosc::EgoMotion::Route
            } else {
                paracosm::export::xosc::EgoMotion::Trajectory
            },
        )
            .map_err(anyhow::Error::new)
            .and_then(|e| {
                let mut text = format!(
                    "wrote {} (OpenSCENARIO 1.2) and {} (OpenDRIVE){}",
                    e.xosc.display(),
                    e.xodr.display(),
                    if e.matches {
                        ""
                    } else {
                        "\nwarning: the replayed verdict differs from the recorded one; the files describe the replay"
                    }
                );
                if !e.not_in_file.is_empty() {
                    text.push_str(&format!(
                        "\nnote: OpenSCENARIO has no monitors: read back (paracosm-fuzz {} \
                         --scripted-ego), the test is judged by collision and leaving the road; \
                         its monitors {} are not in the file",
                        e.xosc.display(),
                        e.not_in_file.join(", ")
                    ));
                }
                say(&text).map(|()| if e.matches { 0 } else { 3 })
            }),
        Some(Sub::Map(a)) => map(a),
        Some(Sub::Xosc(a)) => paracosm::xosc::inspect_with_map(&a.file, &a.open, a.continuous)
            .map_err(anyhow::Error::from)
            .and_then(|i| say(&i.text()).map(|()| 0)),
        None => run(&cli),
    };
    let code = match result {
        Ok(code) => interrupted_code(code),
        Err(e) => {
            paracosm::cli::to_stderr(&paracosm::cli::error_text(
                "paracosm-fuzz",
                &format!("{e:#}"),
            ));
            e.downcast_ref::<Error>().map_or(3, Error::exit_code)
        }
    };
    drop(cli);
    exit_without_teardown(code)
}

/// Ends the process with `code`, stdout and stderr flushed, without the C library's exit
/// handlers. The camera's GPU device lives in a static that is never dropped, and Mesa's
/// lavapipe tears its driver down in those handlers while its worker threads may still run:
/// once, in CI, a campaign that had written every file aborted there ("corrupted size vs.
/// prev_size in fastbins", exit by signal 6 instead of 0). Every file is written, flushed and
/// closed before this (the campaign's writers are dropped when `run` returns).
fn exit_without_teardown(code: u8) -> ExitCode {
    use std::io::Write;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    #[cfg(unix)]
    // SAFETY: `_exit` ends the process at once; nothing runs after it.
    unsafe {
        libc::_exit(i32::from(code))
    }
    #[cfg(not(unix))]
    ExitCode::from(code)
}

/// Writes `text` and a newline to stdout. A reader that has gone (`| head`) is not an
/// error: the rest of stdout is dropped and the process exits with the campaign's code, as
/// ripgrep does.
fn say(text: &str) -> Result<()> {
    static GONE: AtomicBool = AtomicBool::new(false);
    if GONE.load(Ordering::Relaxed) {
        return Ok(());
    }
    match writeln!(std::io::stdout().lock(), "{text}") {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            GONE.store(true, Ordering::Relaxed);
            Ok(())
        }
        other => other.context("cannot write to stdout"),
    }
}

/// `paracosm-fuzz map`: the listing on stdout, the importer's warnings on stderr, then the
/// drawings.
fn map(a: &MapArgs) -> Result<u8> {
    let listing = paracosm::map::read(&a.file)?;
    for w in &listing.warnings {
        paracosm::cli::to_stderr(&format!("paracosm-fuzz: warning: {w}"));
    }
    let mut wrote = Vec::new();
    if let Some(p) = &a.png {
        wrote.push(listing.draw_png(p)?.display().to_string());
    }
    if let Some(p) = &a.svg {
        wrote.push(listing.draw_svg(p)?.display().to_string());
    }
    say(&listing.text())?;
    if !wrote.is_empty() {
        say(&format!("wrote: {}", wrote.join(", ")))?;
    }
    Ok(0)
}

/// Set by Ctrl-C or SIGTERM ([`stop_on_signals`]): no new test starts.
static STOP: AtomicBool = AtomicBool::new(false);

fn run(cli: &Cli) -> Result<u8> {
    if cli.list {
        for name in paracosm_scenarios::builtin_names() {
            let s =
                paracosm_scenarios::builtin(&name).context("a built-in scenario fails to load")?;
            let params: Vec<String> = s.space.params().iter().map(|p| p.label()).collect();
            say(&format!(
                "{name}\n    {}\n    parameters: {}",
                s.description,
                params.join(", ")
            ))?;
        }
        return Ok(0);
    }
    let mut progress = Progress::new(cli.verbose);
    let bar = progress.clone();
    let mut plan = |p: &Plan<'_>| {
        p.notes()
            .iter()
            .for_each(|n| paracosm::cli::to_stderr(&format!("paracosm-fuzz: {n}")));
        bar.start(p.to_run);
    };
    let outcome = paracosm::campaign::session::run(
        &cli.request()?,
        Some(&STOP),
        &mut plan,
        &mut [&mut progress],
    )?;
    progress.finish();
    outcome
        .notes()
        .iter()
        .for_each(|n| paracosm::cli::to_stderr(&format!("paracosm-fuzz: {n}")));
    if let Some(r) = paracosm_engine::render::Renderer::in_use() {
        // Which adapter drew the camera frames: a GPU, or lavapipe on the CPU.
        paracosm::cli::to_stderr(&format!("paracosm-fuzz: camera renderer: {}", r.adapter()));
    }
    if let Some(text) = outcome.human() {
        say(&text)?;
    }
    Ok(outcome.exit_code())
}

impl Cli {
    /// The campaign the arguments ask for.
    fn request(&self) -> Result<Request, Error> {
        let strategy = self
            .strategy
            .map(|s| paracosm::cli::strategy(s, self.scramble));
        let scenario = match &self.scenario {
            Some(s) if paracosm::xosc::is_xosc(s) => Some(paracosm::xosc::campaign_name(
                s,
                &paracosm::xosc::XoscOptions {
                    open: self.open.clone(),
                    continuous: self.continuous,
                    scripted_ego: self.scripted_ego,
                    ego: self.ego.clone(),
                    horizon_s: self.horizon,
                },
            )),
            Some(_)
                if !self.open.is_empty()
                    || self.continuous
                    || self.scripted_ego
                    || self.ego.is_some()
                    || self.horizon.is_some() =>
            {
                return Err(Error::BadInput(
                    "--open, --continuous, --scripted-ego, --ego and --horizon are for an \
                     OpenSCENARIO scenario (.xosc)"
                        .into(),
                ))
            }
            other => other.clone(),
        };
        Ok(Request {
            scenario,
            strategy: strategy.transpose()?,
            seed: self.seed,
            budget: self.budget,
            strength: self.strength,
            shard: self.shard,
            sut: self.sut.config()?,
            out: self.out.clone(),
            replace: self.force,
            resume: self.resume,
            jobs: self.jobs.map(|j| j as usize),
            stop_at_first_failure: self.stop_at_first_failure,
            deny_warnings: self.deny_warnings,
            junit: self.junit.clone(),
            points: self.points.clone(),
            trace_every_s: (self.trace || self.trace_every.is_some()).then_some(
                self.trace_every
                    .unwrap_or(paracosm::export::trace::DEFAULT_EVERY_S),
            ),
        })
    }
}
