//! `paracosm-fuzz`'s arguments (clap): the campaign's options and the subcommands, and the
//! [`Request`] and [`DatasetRequest`](crate::export::dataset::DatasetRequest) they ask for.
//! The binary (`src/bin/paracosm-fuzz.rs`) parses them and runs what they ask.

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use paracosm_generators::Strategy;

use crate::campaign::file::Shard;
use crate::campaign::session::Request;
use crate::cli::SutArgs;
use crate::{Error, ScenarioRef};

/// Run a test campaign on a scenario: sample its open parameters, simulate each test, and
/// write results.jsonl, summary.json and a failure map.
#[derive(Debug, Parser)]
#[command(
    name = "paracosm-fuzz",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
pub struct Cli {
    /// The subcommand, if any; none runs a campaign.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Scenario to test: a path to a `.star` program, or a built-in name (see --list):
    /// pedestrian-crossing, follow-lead-car, fog-light, t-loop, grid-world, cut-in,
    /// roundabout, family-of-worlds, example-3-1, curve-pedestrian, opendrive-junction. Optional with --resume (taken from the folder's campaign.json).
    #[arg(required_unless_present_any = ["list", "resume"])]
    pub scenario: Option<String>,
    /// List the built-in scenarios and exit.
    #[arg(long)]
    pub list: bool,
    /// With an OpenSCENARIO scenario (.xosc): open a declared parameter the file does not
    /// vary, Name=lo..hi (an interval) or Name=a,b,c (levels), checked against its
    /// constraint groups. Repeatable.
    #[arg(long, value_name = "NAME=RANGE")]
    pub open: Vec<String>,
    /// With an OpenSCENARIO variation file: a DistributionRange becomes an interval over its
    /// range instead of its levels.
    #[arg(long)]
    pub continuous: bool,
    /// With an OpenSCENARIO scenario (.xosc): the storyboard moves the ego as it moves every
    /// other entity (its Init, trajectories and actions), and no system under test drives it;
    /// replays a test that `export` wrote. Not with --sut, --sut-cmd or --sut-onnx.
    #[arg(long)]
    pub scripted_ego: bool,
    /// With an OpenSCENARIO scenario (.xosc): the vehicle the system under test drives, for
    /// a file with several vehicles, none named Ego or hero, whose storyboard activates no
    /// controller (such a file is refused without it). The summary names the ego.
    #[arg(long, value_name = "NAME")]
    pub ego: Option<String>,
    /// With an OpenSCENARIO scenario (.xosc): end each test at this simulated time, s, at
    /// the latest (the storyboard's stop trigger may end it sooner). Needed by a storyboard
    /// without a stop trigger, which is refused without it.
    #[arg(long, value_name = "SECONDS")]
    pub horizon: Option<f64>,
    /// With an OpenSCENARIO scenario (.xosc): the set speed of the system under test, m/s,
    /// where the file asks the ego none (CARLA's files leave it to the agent; such a file
    /// is refused without it). A SpeedAction on the ego replaces it.
    #[arg(long, value_name = "M/S")]
    pub ego_speed: Option<f64>,
    /// With an OpenSCENARIO scenario (.xosc): a folder of maps, where a map the file names
    /// but that is not where it says (a CARLA town, `Town01`) is read from (`Town01.xodr`).
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,
    /// With an OpenSCENARIO scenario (.xosc): read it as CARLA's scenario_runner reads its
    /// own (CARLA's left-handed frame, latching conditions, speed actions that last their
    /// distance or time), also when its FileHeader does not say CARLA:.
    #[arg(long)]
    pub carla: bool,
    /// Write each test's trace to OUT/trace/test_N.csv: every entity's pose, speed and
    /// acceleration in the map's frame, laid out as esmini's CSV log (docs/cli.md, "Traces").
    #[arg(long)]
    pub trace: bool,
    /// With --trace: the time between two lines of a trace, s [default: 0.1] (implies
    /// --trace).
    #[arg(long, value_name = "SECONDS")]
    pub trace_every: Option<f64>,
    /// How test points are chosen [default: halton].
    #[arg(long, value_parser = crate::cli::strategy_parser())]
    pub strategy: Option<Strategy>,
    /// With --strategy halton: randomise it by digit permutations (Owen 2017); --seed draws
    /// the permutations.
    #[arg(long)]
    pub scramble: bool,
    /// Strength t of the covering array of --strategy ipog or kwise, and, for any strategy,
    /// the highest t of the k-wise coverage the summary reports [default: 2].
    #[arg(long)]
    pub strength: Option<usize>,
    /// Number of tests of the campaign, at least 1 [default: 100]. With --shard, of the
    /// whole campaign, not of the shard.
    #[arg(long, value_parser = crate::cli::positive)]
    pub budget: Option<u64>,
    /// Campaign seed: seeds the generator and every test [default: 0].
    #[arg(long)]
    pub seed: Option<u64>,
    /// End the campaign at the first failed test (robustness <= 0): no new test starts, and
    /// results.jsonl ends with that test (tests in flight after it are dropped, so the file
    /// does not depend on --jobs). For falsification, e.g. with --strategy falsify-nm.
    #[arg(long)]
    pub stop_at_first_failure: bool,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub jobs: Option<u64>,
    /// Output folder for results.jsonl, summary.json and failure_map.{png,svg}.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Replace what --out holds (otherwise a non-empty folder is refused).
    #[arg(long, conflicts_with = "resume")]
    pub force: bool,
    /// Finish the campaign in --out after a crash, a kill or Ctrl-C: keep its records, cut a
    /// half-written last line, and run the tests that are missing. Refused when the given
    /// arguments differ from the campaign's (campaign.json). Starts the campaign when --out
    /// holds none yet.
    #[arg(long)]
    pub resume: bool,
    /// Run only shard I of N (0 <= I < N): the tests with ids in [I·budget/N,
    /// (I+1)·budget/N). Merge the shard folders with `paracosm-fuzz merge`.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse)]
    pub shard: Option<Shard>,
    /// Also write JUnit XML: one test case per generated test, failures with their monitor
    /// verdicts, parameters and replay command.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Run the tests of FILE instead of generating them (strategy `points`): a CSV with a
    /// header naming the parameters, values in their units (levels as written), one test per
    /// row in order; or another campaign's results.jsonl. The budget is the row count.
    #[arg(long, value_name = "FILE")]
    pub points: Option<PathBuf>,
    /// Refuse to run (exit 2) when the scenario loads with warnings: no monitor, an open
    /// parameter no object reads or that cannot affect the ego (LANGUAGE.md, "Warnings").
    /// For CI.
    #[arg(long)]
    pub deny_warnings: bool,
    /// Print each test's log (what the program's `print` wrote during it) on stderr, as
    /// `test ID: LINE`, as the test finishes. Without it the log is only in results.jsonl.
    #[arg(long)]
    pub verbose: bool,
    /// The system under test (`--sut`, `--sut-cmd`, `--sut-onnx`, ...).
    #[command(flatten)]
    pub sut: SutArgs,
}

/// `paracosm-fuzz`'s subcommands; none runs a campaign ([`Cli`]).
#[derive(Debug, Subcommand)]
pub enum Command {
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

/// `paracosm-fuzz xosc`: an OpenSCENARIO file listed as paracosm's space.
#[derive(Debug, clap::Args)]
pub struct XoscArgs {
    /// The variation file or scenario (.xosc).
    pub file: PathBuf,
    /// Open a declared parameter the file does not vary: Name=lo..hi (an interval) or
    /// Name=a,b,c (levels), checked against its constraint groups. Repeatable.
    #[arg(long, value_name = "NAME=RANGE")]
    pub open: Vec<String>,
    /// A DistributionRange becomes an interval over its range instead of its levels.
    #[arg(long)]
    pub continuous: bool,
    /// A folder of maps: a map the file names but that is not where it says (a CARLA town,
    /// `Town01`) is read from this folder (`Town01.xodr`).
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,
    /// Read the file as CARLA's scenario_runner reads its own (CARLA's left-handed frame,
    /// latching conditions, speed actions that last their distance or time), also when its
    /// FileHeader's description does not start with CARLA: (docs/openscenario.md).
    #[arg(long)]
    pub carla: bool,
}

/// `paracosm-fuzz map`: an OpenDRIVE map listed and drawn.
#[derive(Debug, clap::Args)]
pub struct MapArgs {
    /// The OpenDRIVE file (.xodr).
    pub file: PathBuf,
    /// Draw the map into this PNG file.
    #[arg(long, value_name = "PATH")]
    pub png: Option<PathBuf>,
    /// Draw the map into this SVG file.
    #[arg(long, value_name = "PATH")]
    pub svg: Option<PathBuf>,
}

/// `paracosm-fuzz export`: one recorded test written as OpenSCENARIO and OpenDRIVE.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// A campaign's results.jsonl.
    pub results: PathBuf,
    /// Id of the test to export.
    #[arg(long)]
    pub id: u64,
    /// Folder for test_ID.xosc and test_ID.xodr (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Write the ego's route (an AssignRouteAction, for another system under test to drive)
    /// instead of the trajectory it drove (a timed FollowTrajectoryAction, the default).
    #[arg(long)]
    pub ego_route: bool,
}

/// `paracosm-fuzz dataset`: training data from a campaign with a teacher.
#[derive(Debug, clap::Args)]
pub struct DatasetArgs {
    /// Scenario: a `.star` path or a built-in name.
    pub scenario: String,
    /// How test points are chosen (not an adaptive strategy).
    #[arg(long, value_parser = crate::cli::dataset_strategy_parser(), default_value = "halton")]
    pub strategy: Strategy,
    /// Strength t of --strategy ipog or kwise.
    #[arg(long, default_value_t = 2)]
    pub strength: usize,
    /// Number of tests.
    #[arg(long, value_parser = crate::cli::positive, default_value = "10")]
    pub budget: u64,
    /// Campaign seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Frames recorded per second of simulated time: 60 divided by a whole number of physics
    /// steps (60, 30, 20, 15, 12, 10, ...); another rate is refused.
    #[arg(long, value_name = "HZ", default_value_t = 10.0)]
    pub rate: f64,
    /// Camera image width in pixels (when the teacher has no camera of its own).
    #[arg(long, default_value_t = 320)]
    pub width: u32,
    /// Camera image height in pixels.
    #[arg(long, default_value_t = 240)]
    pub height: u32,
    /// Camera focal length in mm (36 mm sensor width).
    #[arg(long, default_value_t = 24.0)]
    pub focal_mm: f64,
    /// Worker threads (default: all cores). The data set does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub jobs: Option<u64>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace what --out holds.
    #[arg(long)]
    pub force: bool,
    /// Steering noise added to what the vehicle applies, in steering units (1 = full lock),
    /// so that the teacher's recorded answers show how to recover (DART; docs/experiments.md).
    #[arg(long, value_name = "AMPLITUDE", default_value_t = 0.0)]
    pub steer_noise: f64,
    /// Seconds each noise value is held.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    pub noise_hold: f64,
    /// An ONNX network that drives while the teacher labels (DAgger: Ross, Gordon and Bagnell
    /// 2011): the frames show the network's own states, the labels are the teacher's answers
    /// for them (docs/experiments.md)
    #[arg(long, value_name = "MODEL.onnx")]
    pub learner_onnx: Option<PathBuf>,
    /// With --learner-onnx: the probability in [0, 1] that a decision applies the teacher's
    /// answer instead of the network's (DAgger's beta)
    #[arg(
        long,
        value_name = "P",
        default_value_t = 0.0,
        requires = "learner_onnx"
    )]
    pub teacher_share: f64,
    /// The teacher, instead of the scenario's system under test.
    #[command(flatten)]
    pub sut: SutArgs,
}

/// `paracosm-fuzz merge`: the shard folders of one campaign combined.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The shard folders.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Folder for the merged campaign.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace what --out holds.
    #[arg(long)]
    pub force: bool,
    /// Also write JUnit XML.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
}

/// `paracosm-fuzz report`: a campaign folder's summary reprinted, its plots redrawn.
#[derive(Debug, clap::Args)]
pub struct ReportArgs {
    /// A campaign (or shard) folder.
    pub dir: PathBuf,
    /// Plots to redraw from the records.
    #[command(flatten)]
    pub redraw: crate::cli::Redraw,
}

/// `paracosm-fuzz replay`: one recorded test run again and compared.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// A campaign's results.jsonl.
    pub results: PathBuf,
    /// Id of the test to re-run.
    #[arg(long)]
    pub id: u64,
    /// Folder for frame_NNNNN.png and contact_sheet.png (a 320 x 240 camera at 20 Hz is
    /// mounted when the system under test has none).
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// Folder for the test's trace, DIR/test_ID.csv: every entity's pose, speed and
    /// acceleration, laid out as esmini's CSV log (as a campaign's --trace writes).
    #[arg(long, value_name = "DIR")]
    pub trace: Option<PathBuf>,
    /// With --trace: the time between two lines, s [default: 0.1].
    #[arg(long, value_name = "SECONDS", requires = "trace")]
    pub trace_every: Option<f64>,
    /// A system under test to replay with instead of the recorded one.
    #[command(flatten)]
    pub sut: SutArgs,
}

impl DatasetArgs {
    /// The dataset export the arguments ask for.
    ///
    /// # Errors
    /// [`Error::BadInput`] for a system under test or a `--learner-onnx` model that cannot
    /// be configured.
    pub fn request(&self) -> Result<crate::export::dataset::DatasetRequest, Error> {
        Ok(crate::export::dataset::DatasetRequest {
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

pub(crate) fn num_cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

impl Cli {
    /// The campaign the arguments ask for.
    ///
    /// # Errors
    /// [`Error::BadInput`] for `--scramble` with a strategy other than `halton`, an
    /// OpenSCENARIO option given with a program, or a system under test that cannot be
    /// configured.
    pub fn request(&self) -> Result<Request, Error> {
        let strategy = self
            .strategy
            .map(|s| crate::cli::strategy(s, self.scramble));
        let scenario = match &self.scenario {
            Some(s) if crate::scenario_ref::is_xosc(s) => {
                Some(ScenarioRef::OpenScenario(crate::scenario_ref::XoscRef {
                    xosc: s.clone(),
                    open: self.open.clone(),
                    continuous: self.continuous,
                    scripted_ego: self.scripted_ego,
                    ego: self.ego.clone(),
                    horizon_s: self.horizon,
                    ego_speed_mps: self.ego_speed,
                    maps: self.maps.as_ref().map(|d| d.display().to_string()),
                    carla: self.carla,
                }))
            }
            Some(_)
                if !self.open.is_empty()
                    || self.continuous
                    || self.scripted_ego
                    || self.ego.is_some()
                    || self.horizon.is_some()
                    || self.ego_speed.is_some()
                    || self.maps.is_some()
                    || self.carla =>
            {
                return Err(Error::BadInput(
                    "--open, --continuous, --scripted-ego, --ego, --horizon, --ego-speed, \
                     --maps and --carla are for an OpenSCENARIO scenario (.xosc)"
                        .into(),
                ))
            }
            other => other.as_deref().map(ScenarioRef::named),
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
                    .unwrap_or(crate::export::trace::DEFAULT_EVERY_S),
            ),
        })
    }
}
