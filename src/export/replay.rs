//! The replay of one recorded test, from `campaign.json` and its line of `results.jsonl`.

use std::path::{Path, PathBuf};

use paracosm_engine::sut::SutConfig;
use paracosm_engine::{CameraFrame, CameraSpec};
use paracosm_generators::{Point, Strategy};
use paracosm_scenarios::RunOptions;

use crate::campaign::file::CampaignFile;
use crate::campaign::{Campaign, RESULTS_FILE};
use crate::record::{RunRecord, Status};
use crate::Error;

/// The outcome of a replay.
#[derive(Debug)]
pub struct Replay {
    /// The record as written by the campaign (a JSON object).
    pub recorded: serde_json::Value,
    /// The record of the replayed run.
    pub replayed: RunRecord,
    /// Whether status and every monitor's verdict and robustness equal the recorded ones.
    pub matches: bool,
    /// Frames written, in time order.
    pub frames: Vec<PathBuf>,
    /// The contact sheet, when frames were written.
    pub contact_sheet: Option<PathBuf>,
    /// What changed since the campaign ran, when something it recorded the hash of did: the
    /// scenario program, or a file it reads (an OpenDRIVE map). A replay then runs the new
    /// program, so a verdict that differs says nothing about reproducibility.
    pub changed: Option<String>,
}

fn input(e: impl std::fmt::Display) -> Error {
    Error::BadInput(e.to_string())
}

/// The command that replays test `id` of the campaign in `out`.
pub fn replay_command(out: &Path, id: u64) -> String {
    replay_command_for(out, &id.to_string())
}

/// [`replay_command`] with `id` as given: `{id}` gives the command's template (the web
/// report fills it in).
pub fn replay_command_for(out: &Path, id: &str) -> String {
    format!(
        "paracosm-fuzz replay {} --id {id} --frames {}",
        out.join(RESULTS_FILE).display(),
        out.join(format!("frames-{id}")).display()
    )
}

/// The line of `results` whose `id` is `id`.
fn find_record(results: &Path, id: u64) -> Result<(usize, String), Error> {
    paracosm_engine::files::regular_file(results)
        .map_err(|e| input(format!("cannot read `{}`: {e}", results.display())))?;
    let text = std::fs::read_to_string(results)
        .map_err(|e| input(format!("cannot read `{}`: {e}", results.display())))?;
    let mut ids = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let v: serde_json::Value = match serde_json::from_str(line) {
            Ok(v) => v,
            // A half-written last line (the campaign was killed) is not a record.
            Err(_) if n + 1 == text.lines().count() => continue,
            Err(e) => {
                return Err(input(format!(
                    "{}: not a results line: {e}",
                    crate::error::located(results, n + 1, e.column())
                )))
            }
        };
        match v.get("id").and_then(serde_json::Value::as_u64) {
            Some(i) if i == id => return Ok((n + 1, line.to_owned())),
            Some(i) => ids.push(i),
            None => {
                return Err(input(format!(
                    "{}:{}: a results line without an `id`",
                    results.display(),
                    n + 1
                )))
            }
        }
    }
    let range = match (ids.iter().min(), ids.iter().max()) {
        (Some(lo), Some(hi)) => format!("ids {lo}..={hi}"),
        _ => "no records".into(),
    };
    Err(input(format!(
        "no test with id {id} in `{}` ({range})",
        results.display()
    )))
}

/// Re-runs test `id` of the campaign whose results are `results` (with `campaign.json` beside
/// it), from its recorded point and seed. With `frames`, writes every camera frame as
/// `frame_NNNNN.png` there (the system's own camera, or a default 320 × 240 camera at 20 Hz
/// for systems without one), and `contact_sheet.png`. `sut` replaces the recorded system.
///
/// # Errors
/// [`Error::BadInput`] when a file is missing or malformed, the id is not in the results,
/// the scenario does not load, or a frame cannot be written.
pub fn replay(
    results: &Path,
    id: u64,
    frames: Option<&Path>,
    sut: Option<SutConfig>,
) -> Result<Replay, Error> {
    replay_with(results, id, (frames, None), sut, None, None)
}

/// [`replay`], writing the test's trace (`replay --trace DIR`: `DIR/test_ID.csv`,
/// [`crate::export::trace`]) as a campaign's `--trace` does.
///
/// # Errors
/// As [`replay`]; [`Error::BadInput`] or [`Error::Write`] when the folder cannot be made.
pub fn replay_traced(
    results: &Path,
    id: u64,
    frames: Option<&Path>,
    sut: Option<SutConfig>,
    trace: Option<crate::export::trace::TraceSpec>,
) -> Result<Replay, Error> {
    if let Some(t) = &trace {
        if !(t.every_s.is_finite() && t.every_s > 0.0) {
            return Err(Error::BadInput(format!(
                "--trace-every {} s must be a finite number of seconds > 0",
                t.every_s
            )));
        }
        crate::atomic::make_output_folder(&t.path)?;
    }
    replay_with(results, id, (frames, trace), sut, None, None)
}

/// [`replay`], also calling `on_world` with the test's world as built and `on_step` with its
/// state at the start and after every step (what `paracosm-fuzz export` records).
///
/// # Errors
/// As [`replay`].
pub fn replay_with(
    results: &Path,
    id: u64,
    (frames, trace): (Option<&Path>, Option<crate::export::trace::TraceSpec>),
    sut: Option<SutConfig>,
    on_world: Option<&mut dyn FnMut(&paracosm_engine::WorldSpec)>,
    on_step: Option<&mut dyn FnMut(&paracosm_engine::Snapshot)>,
) -> Result<Replay, Error> {
    let dir = results.parent().unwrap_or(Path::new("."));
    let (line_no, line) = find_record(results, id)?;
    let campaign_file = CampaignFile::read(dir).map_err(input)?;
    let mut scenario = campaign_file.scenario.load()?;
    let changed = changed_since(&campaign_file, &scenario);
    let record = RunRecord::from_line(&line, scenario.space()).map_err(|e| {
        input(format!(
            "{}: not a results record of this campaign: {e}",
            crate::error::located(results, line_no, e.column())
        ))
    })?;
    let recorded: serde_json::Value =
        serde_json::from_str(&line).expect("from_line parsed it as JSON");
    let point: Point = record.point;
    if let Some(s) = sut.or(campaign_file.sut.config().map_err(input)?) {
        crate::refuse_sut_for_scripted_ego(&scenario)?;
        scenario.set_sut(s);
    }
    let strategy: Strategy = campaign_file.strategy.parse().map_err(input)?;
    let campaign = Campaign {
        scenario: &scenario,
        strategy,
        seed: campaign_file.seed,
        budget: campaign_file.budget,
        strength: campaign_file.strength,
        jobs: 1,
        stop_at_first_failure: false,
        points: None,
        trace,
    };
    let (replayed, written, thumbnails) =
        run_writing_frames(&campaign, id, &point, frames, on_world, on_step)?;
    if record.seed != replayed.seed {
        return Err(input(format!(
            "{}:{line_no}: test {id} was recorded with seed {} but campaign.json gives {}: the \
             results and campaign.json are from different campaigns",
            results.display(),
            record.seed,
            replayed.seed
        )));
    }
    let contact_sheet = write_contact_sheet(frames, &thumbnails, id)?;
    let matches = verdicts_match(&recorded, &replayed);
    Ok(Replay {
        recorded,
        replayed,
        matches,
        frames: written,
        contact_sheet,
        changed,
    })
}

/// Thumbnails of the frames written, with their times (s), in time order.
type Thumbnails = Vec<(f64, image::RgbImage)>;

/// Runs test `id` at `point` with `campaign`, calling `on_world` and `on_step`. With
/// `frames`, makes that folder and writes every camera frame (a default camera) as
/// `frame_NNNNN.png` there. Returns the run's record, the frames written in time order, and
/// their thumbnails with their times (s).
///
/// # Errors
/// [`Error::BadInput`] when the folder cannot be made or a frame cannot be written.
fn run_writing_frames(
    campaign: &Campaign<'_>,
    id: u64,
    point: &Point,
    frames: Option<&Path>,
    on_world: Option<&mut dyn FnMut(&paracosm_engine::WorldSpec)>,
    on_step: Option<&mut dyn FnMut(&paracosm_engine::Snapshot)>,
) -> Result<(RunRecord, Vec<PathBuf>, Thumbnails), Error> {
    if let Some(dir) = frames {
        std::fs::create_dir_all(dir)
            .map_err(|e| input(format!("cannot create `{}`: {e}", dir.display())))?;
    }
    let mut written = Vec::new();
    let mut thumbnails = Vec::new();
    let mut write_error = None;
    let mut on_frame = |f: &CameraFrame| {
        let Some(dir) = frames else { return };
        let path = dir.join(format!("frame_{:05}.png", written.len()));
        match crate::atomic::with_temp(&path, |tmp| f.save_png(tmp)).map_err(|e| e.to_string()) {
            Ok(()) => {
                written.push(path);
                thumbnails.push((f.t_s, f.to_image()));
            }
            Err(e) => {
                write_error.get_or_insert(e);
            }
        }
    };
    let replayed = campaign.run_one_with(
        id,
        point,
        &mut RunOptions {
            camera: frames.map(|_| CameraSpec::default()),
            on_frame: Some(&mut on_frame),
            on_sample: None,
            perturb: None,
            on_world: on_world.map(|f| f as &mut dyn FnMut(&paracosm_engine::WorldSpec)),
            on_step: on_step.map(|f| f as &mut dyn FnMut(&paracosm_engine::Snapshot)),
        },
    );
    if let Some(e) = write_error {
        return Err(input(e));
    }
    Ok((replayed, written, thumbnails))
}

/// Writes `contact_sheet.png` of test `id` into `frames` from the `thumbnails` (time s,
/// image); `None` without a folder or frames.
fn write_contact_sheet(
    frames: Option<&Path>,
    thumbnails: &[(f64, image::RgbImage)],
    id: u64,
) -> Result<Option<PathBuf>, Error> {
    Ok(match frames {
        Some(dir) if !thumbnails.is_empty() => {
            let path = dir.join("contact_sheet.png");
            crate::atomic::with_temp(&path, |tmp| {
                crate::report::plot::contact_sheet(tmp, thumbnails, &format!("test {id}"))
            })?;
            Some(path)
        }
        _ => None,
    })
}

/// What of the campaign's inputs changed since `file` was written: the program (its SHA-256)
/// or a file it reads; `None` when nothing did, or the file predates the hashes.
pub fn changed_since(
    file: &CampaignFile,
    scenario: &paracosm_scenarios::Scenario,
) -> Option<String> {
    let now = crate::campaign::file::sha256_hex(scenario.source().as_bytes());
    if file
        .scenario_sha256
        .as_ref()
        .is_some_and(|then| *then != now)
    {
        return Some(format!(
            "the scenario program `{}` changed since the campaign ran (its SHA-256 differs \
             from campaign.json's)",
            file.scenario
        ));
    }
    file.input_files
        .iter()
        .find(|f| !scenario.input_files().contains(f))
        .map(|f| {
            format!(
                "the file `{}` the program reads changed since the campaign ran",
                f.path
            )
        })
}

/// Status, and each monitor's `passed`, `robustness` and `first_violation_s`, equal between a
/// recorded line and a replayed record (compared through their JSON form, as written).
fn verdicts_match(recorded: &serde_json::Value, replayed: &RunRecord) -> bool {
    let Ok(replayed) = serde_json::to_value(replayed) else {
        return false;
    };
    recorded["status"] == replayed["status"] && recorded["monitors"] == replayed["monitors"]
}

impl Replay {
    /// What `paracosm-fuzz replay` prints for test `id`: both verdicts, what the program
    /// printed, the frames written (into `frames`), and whether the verdicts agree.
    pub fn text(&self, id: u64, frames: Option<&Path>) -> String {
        let recorded = self.recorded["status"].as_str().unwrap_or("?");
        let verdicts: Vec<String> = self
            .replayed
            .monitors
            .iter()
            .map(|(n, m)| {
                // A monitor cut short by another's failure did not fail the test.
                let word = match (m.passed, m.cut_short) {
                    (true, _) => "passed",
                    (false, true) => "cut short",
                    (false, false) => "failed",
                };
                format!("{n} {word} (robustness {:.3})", m.robustness)
            })
            .collect();
        let error = self.replayed.error.as_deref();
        let mut lines = vec![format!(
            "test {id}: recorded {recorded}, replayed {}: {}{}",
            status_name(self.replayed.status),
            verdicts.join(", "),
            error.map(|e| format!(" ({e})")).unwrap_or_default()
        )];
        lines.extend(self.replayed.log.iter().map(|l| format!("print: {l}")));
        if let Some(sheet) = &self.contact_sheet {
            lines.push(format!(
                "wrote {} frames to {} and {}",
                self.frames.len(),
                frames.unwrap_or(Path::new(".")).display(),
                sheet.display()
            ));
        }
        lines.push(if self.matches {
            "the replayed verdict equals the recorded one".to_owned()
        } else {
            format!(
                "the replayed verdict DIFFERS from the recorded one: recorded monitors {}",
                self.recorded["monitors"]
            )
        });
        if let Some(c) = &self.changed {
            lines.push(format!(
                "note: {c}: this replay ran the program as it is now, not the one that made \
                 the record"
            ));
        }
        lines.join("\n")
    }
}

/// `pass`, `fail` or `error`.
pub fn status_name(s: Status) -> &'static str {
    match s {
        Status::Pass => "pass",
        Status::Fail => "fail",
        Status::Error => "error",
    }
}
