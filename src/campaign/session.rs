//! A campaign from its settings to its files, as `paracosm-fuzz` runs it: the settings checked
//! against the output folder, a resume, the loop with its observers, and `summary.json`, the
//! plots and JUnit at the end. The binary parses arguments into a [`Request`] and maps the
//! [`Error`] to an exit code; other front ends (the Python package) do the same.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use paracosm_engine::sut::SutConfig;
use paracosm_generators::{GeneratorError, Point, Strategy};
use paracosm_scenarios::Scenario;

use crate::campaign::file::{CampaignFile, PointsFile, Settings, Shard, SutChoice, CAMPAIGN_FILE};
use crate::campaign::{Campaign, CampaignReport, Observer, ResultsFile, RESULTS_FILE};
use crate::record::RunRecord;
use crate::report::summary::Summary;
use crate::report::{warnings_of, write_outputs, Finished};
use crate::{Error, ScenarioRef};

/// The folder of a campaign's traces (`--trace`), inside its output folder.
pub const TRACE_FOLDER: &str = "trace";

/// What to run: `paracosm-fuzz`'s arguments as data. `None` fields take the defaults (or,
/// with `resume`, the stored campaign's values).
#[derive(Debug, Clone)]
pub struct Request {
    /// A built-in scenario's name, a `.star` path or an OpenSCENARIO file with its options;
    /// `None` only with `resume` (taken from the folder's `campaign.json`).
    pub scenario: Option<ScenarioRef>,
    /// The strategy [default: halton].
    pub strategy: Option<Strategy>,
    /// Campaign seed [default: 0].
    pub seed: Option<u64>,
    /// Tests of the whole campaign, `>= 1` [default: 100].
    pub budget: Option<u64>,
    /// Strength of the covering suites [default: 2].
    pub strength: Option<usize>,
    /// Only this shard of the campaign.
    pub shard: Option<Shard>,
    /// A system under test instead of the scenario's.
    pub sut: Option<SutConfig>,
    /// The campaign folder.
    pub out: PathBuf,
    /// Replace what `out` holds (`--force`).
    pub replace: bool,
    /// Finish the campaign in `out` (`--resume`).
    pub resume: bool,
    /// Worker threads [default: all cores]; results do not depend on it.
    pub jobs: Option<usize>,
    /// End at the first failed test.
    pub stop_at_first_failure: bool,
    /// Refuse a scenario that loads with warnings.
    pub deny_warnings: bool,
    /// Also write JUnit XML here.
    pub junit: Option<PathBuf>,
    /// Run the tests of this file (`--points`): a CSV with a header naming the parameters,
    /// values in their units (levels as written), one test per row in file order, or the
    /// `results.jsonl` of another campaign. Strategy `points`; the budget is the row count.
    pub points: Option<PathBuf>,
    /// Write each test's trace into `out/trace/test_N.csv`, a line every this many seconds
    /// (`--trace`, `--trace-every`; [`crate::export::trace`]).
    pub trace_every_s: Option<f64>,
}

impl Request {
    /// A request for `scenario` into `out`, everything else by default.
    pub fn new(scenario: &str, out: &Path) -> Self {
        Request {
            scenario: Some(ScenarioRef::named(scenario)),
            strategy: None,
            seed: None,
            budget: None,
            strength: None,
            shard: None,
            sut: None,
            out: out.to_path_buf(),
            replace: false,
            resume: false,
            jobs: None,
            stop_at_first_failure: false,
            deny_warnings: false,
            junit: None,
            points: None,
            trace_every_s: None,
        }
    }
}

/// What a session tells its observers before the first test: enough for a progress bar and
/// the messages of a resume.
#[derive(Debug)]
pub struct Plan<'a> {
    /// The scenario under test.
    pub scenario: &'a Scenario,
    /// The campaign's settings, as stored in `campaign.json`.
    pub file: &'a CampaignFile,
    /// The scenario's warnings for this system under test.
    pub warnings: &'a [String],
    /// Records already in the folder (a resume).
    pub done: u64,
    /// Tests this run will do at most.
    pub to_run: u64,
    /// Bytes of a half-written last line cut off `results.jsonl` (a resume after a kill).
    pub repaired_bytes: u64,
    /// Whether this run finishes an earlier one.
    pub resumed: bool,
}

impl Plan<'_> {
    /// What a front end tells the user before the first test: the warnings, a half-written
    /// line cut off, how far a resumed campaign had got.
    pub fn notes(&self) -> Vec<String> {
        let mut notes = self.warnings.to_vec();
        if self.repaired_bytes > 0 {
            notes.push(format!(
                "cut a half-written last line ({} bytes) off results.jsonl; that test runs again",
                self.repaired_bytes
            ));
        }
        if self.resumed {
            notes.push(format!(
                "resuming: {} of {} tests already done",
                self.done,
                self.done + self.to_run
            ));
        }
        notes
    }
}

/// A finished (or interrupted) session.
#[derive(Debug)]
pub struct Outcome {
    /// The campaign's settings.
    pub file: CampaignFile,
    /// The scenario.
    pub scenario: Scenario,
    /// The folder.
    pub out: PathBuf,
    /// What the loop reported (this run's records only).
    pub report: CampaignReport,
    /// Records in the folder now (earlier and this run's).
    pub done: u64,
    /// Tests the folder should hold (the shard's or the campaign's).
    pub expected: u64,
    /// `summary.json` as written; `None` when interrupted (the folder is to be resumed).
    pub summary: Option<Summary>,
    /// Plots that could not be drawn (also in the summary's warnings).
    pub plot_warnings: Vec<String>,
}

impl Outcome {
    /// The outcome of the campaign of `file` and `scenario` in `out`: `done` records of the
    /// `expected` in the folder, what the loop reported, and the outputs `written` at the end
    /// (`None` when interrupted).
    fn new(
        file: CampaignFile,
        scenario: Scenario,
        out: &Path,
        report: CampaignReport,
        done: u64,
        expected: u64,
        written: Option<crate::report::Written>,
    ) -> Outcome {
        Outcome {
            done,
            expected,
            plot_warnings: written
                .as_ref()
                .map(|w: &crate::report::Written| w.plot_warnings.clone())
                .unwrap_or_default(),
            summary: written.map(|w| w.summary),
            report,
            file,
            scenario,
            out: out.to_path_buf(),
        }
    }

    /// What a front end tells the user besides the summary: an interruption and how to
    /// resume, a stop at the first failure, plots that could not be drawn.
    pub fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.summary.is_none() {
            notes.push(format!(
                "interrupted: {} of {} tests are in {}; finish the campaign with:\n    \
                 paracosm-fuzz --resume --out {}",
                self.done,
                self.expected,
                results_path(&self.out).display(),
                self.out.display()
            ));
        }
        if self.report.stopped_at_failure {
            notes.push(format!(
                "--stop-at-first-failure: stopped after {} of {} tests",
                self.done, self.expected
            ));
        }
        notes.extend(self.plot_warnings.iter().map(|w| format!("warning: {w}")));
        notes
    }

    /// The human summary ([`crate::report::human`]), `None` when interrupted.
    pub fn human(&self) -> Option<String> {
        let summary = self.summary.as_ref()?;
        Some(crate::report::human(
            summary,
            &self.scenario,
            &self.out,
            self.expected,
            Some(self.report.records.len() as u64),
        ))
    }

    /// The tools' exit code: 130 interrupted, 1 a test failed, 3 a test ended in an error, 0
    /// otherwise.
    pub fn exit_code(&self) -> u8 {
        match &self.summary {
            None => 130,
            Some(s) if s.counts.fail > 0 => 1,
            Some(s) if s.counts.error > 0 => 3,
            Some(_) => 0,
        }
    }
}

/// Runs `request`: checks it (against the folder's campaign when resuming), prepares the
/// folder, runs the tests it lacks with a [`ResultsFile`] and `observers`, and writes
/// `summary.json`, the plots and JUnit. `started` is called with the [`Plan`] before any test
/// runs; `stop` is the Ctrl-C flag.
///
/// # Errors
/// [`Error::BadInput`] for settings that cannot be honoured (a non-empty folder without
/// `replace` or `resume`, other settings than the stored campaign's, a budget past the
/// strategy's capacity, a shard of an adaptive campaign, warnings with `deny_warnings`);
/// [`Error::Scenario`] when it does not load; [`Error::Input`] for an unreadable campaign
/// folder; [`Error::Write`] when a file cannot be written. Records already written stay.
pub fn run(
    request: &Request,
    stop: Option<&AtomicBool>,
    started: &mut dyn FnMut(&Plan<'_>),
    observers: &mut [&mut dyn Observer],
) -> Result<Outcome, Error> {
    let out = &request.out;
    let Checked {
        stored,
        file,
        scenario,
        points,
        warnings,
        strategy,
        jobs,
    } = check_request(request)?;
    // One writer per folder, from here to the end of the run (crate::campaign::lock).
    let _lock = claim_folder(request, &file, stored.is_some())?;
    let ids = file.ids();
    let existing = existing_records(out, &scenario, ids.clone(), stored.is_some())?;
    let start = ids.start + existing.records.len() as u64;
    let campaign = new_campaign(request, &scenario, &file, strategy, jobs, points.as_deref())?;
    campaign.check_origin(
        &existing.records,
        ids.start,
        &out.join(RESULTS_FILE),
        Some(&file.tag()),
    )?;
    started(&Plan {
        scenario: &scenario,
        file: &file,
        warnings: &warnings,
        done: existing.records.len() as u64,
        to_run: ids.end - start,
        repaired_bytes: existing.repaired_bytes as u64,
        resumed: stored.is_some(),
    });
    let mut written = None;
    let junit_path = request.junit.as_deref();
    let mut chain = Chain {
        results: ResultsFile::new(out, stored.is_some()).tagged(file.tag()),
        others: observers,
        // summary.json (counts, first failure, coverage of the points run) and the plots.
        outputs: AtEnd::new(Box::new(
            |records: &[RunRecord], report: &CampaignReport| {
                written = Some(write_outputs(&Finished {
                    out,
                    scenario: &scenario,
                    file: &file,
                    records,
                    jobs,
                    wall_s: report.wall_s,
                    junit: junit_path,
                    warnings: warnings.clone(),
                })?);
                Ok(())
            },
        )),
        junit: junit_path.map(|path| junit_at_end(path, scenario.name().to_owned(), out)),
    };
    let prior = stored.is_some().then_some(existing.records.as_slice());
    let report = campaign.run_ids(start..ids.end, prior, stop, &mut [&mut chain])?;
    let done = chain.outputs.records.len() as u64;
    drop(chain);
    Ok(Outcome::new(
        file,
        scenario,
        out,
        report,
        done,
        ids.end - ids.start,
        written,
    ))
}

/// A request's settings, checked before anything is written ([`check_request`]).
struct Checked {
    /// The campaign in the folder that the request resumes, if any.
    stored: Option<CampaignFile>,
    /// The campaign's settings, as stored in `campaign.json`.
    file: CampaignFile,
    /// The scenario under test.
    scenario: Scenario,
    /// The points of a `--points` campaign, in test order.
    points: Option<Vec<Point>>,
    /// The scenario's warnings for this system under test.
    warnings: Vec<String>,
    /// The campaign's strategy.
    strategy: Strategy,
    /// Worker threads.
    jobs: usize,
}

/// The settings of `request` (with the campaign it resumes, if any), checked and refused
/// before anything is written ([`run`]'s errors but [`Error::Write`]).
fn check_request(request: &Request) -> Result<Checked, Error> {
    let stored = stored_campaign(request)?;
    let (mut file, scenario, points) = settings(request, stored.as_ref())?;
    // A campaign that stops at its first failure does so when resumed too.
    let stop_at_first_failure = match &stored {
        Some(s) => s.stop_at_first_failure || request.stop_at_first_failure,
        None => request.stop_at_first_failure,
    };
    file.stop_at_first_failure = stop_at_first_failure;
    let warnings = warnings_of(&scenario);
    let strategy = refusals(request, &file, &warnings)?;
    check_strength(request, &scenario, strategy)?;
    let jobs = request.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    Ok(Checked {
        stored,
        file,
        scenario,
        points,
        warnings,
        strategy,
        jobs,
    })
}

/// The records already in `out` for the campaign of `scenario` over `ids` when `resumed`
/// (a half-written last line cut off), none otherwise.
fn existing_records(
    out: &Path,
    scenario: &Scenario,
    ids: std::ops::Range<u64>,
    resumed: bool,
) -> Result<crate::campaign::results::Existing, Error> {
    Ok(if resumed {
        crate::campaign::results::load(out, scenario, ids, true)?
    } else {
        crate::campaign::results::Existing {
            records: Vec::new(),
            repaired_bytes: 0,
        }
    })
}

/// The campaign of `file` over `scenario` with `strategy` on `jobs` threads (with its
/// `points`), writing traces when `request` asks for them ([`trace_spec`]).
fn new_campaign<'a>(
    request: &Request,
    scenario: &'a Scenario,
    file: &CampaignFile,
    strategy: Strategy,
    jobs: usize,
    points: Option<&'a [Point]>,
) -> Result<Campaign<'a>, Error> {
    Ok(Campaign {
        scenario,
        strategy,
        seed: file.seed,
        budget: file.budget,
        strength: file.strength,
        jobs,
        stop_at_first_failure: file.stop_at_first_failure,
        points,
        trace: trace_spec(request)?,
    })
}

/// Where and how often to write each test's trace (`--trace-every`, s), creating the folder
/// `out/trace`; `None` without `--trace`.
///
/// # Errors
/// [`Error::BadInput`] for a time that is not finite and `> 0`; the folder's error when it
/// cannot be made.
fn trace_spec(request: &Request) -> Result<Option<crate::export::trace::TraceSpec>, Error> {
    match request.trace_every_s {
        Some(every_s) => {
            if !(every_s.is_finite() && every_s > 0.0) {
                return Err(Error::BadInput(format!(
                    "--trace-every {every_s} s must be a finite number of seconds > 0"
                )));
            }
            let path = request.out.join(TRACE_FOLDER);
            crate::atomic::make_output_folder(&path)?;
            Ok(Some(crate::export::trace::TraceSpec { path, every_s }))
        }
        None => Ok(None),
    }
}

/// Prepares the campaign folder (`replace`, `resume`), takes its lock, and writes `file` into
/// it unless the campaign is `resumed`. Returns the lock: the caller holds it to the end of the
/// run.
fn claim_folder(
    request: &Request,
    file: &CampaignFile,
    resumed: bool,
) -> Result<crate::campaign::lock::CampaignLock, Error> {
    let out = &request.out;
    prepare_out_dir(out, request.replace, request.resume)?;
    let lock = crate::campaign::lock::CampaignLock::acquire(out)?;
    if request.resume {
        // Ours alone now: what an earlier writer killed mid-write left is stale.
        crate::atomic::remove_stale_temps(out);
    }
    if !resumed {
        file.write(out)?;
    }
    Ok(lock)
}

/// The observer that writes JUnit XML for scenario `name` to `path` when the campaign in `out`
/// finishes.
fn junit_at_end<'c>(path: &'c Path, name: String, out: &'c Path) -> AtEnd<AtEndFn<'c>> {
    AtEnd::new(Box::new(
        move |records: &[RunRecord], _: &CampaignReport| {
            crate::report::junit::write(path, &name, records, out)
        },
    ))
}

/// The campaign in the folder that `request` resumes, if any (a `--junit` path inside the
/// folder is refused first).
///
/// # Errors
/// [`Error::BadInput`] for a `--junit` path that is no side output, or for a resume of a folder
/// that holds records without their `campaign.json`; [`Error::Input`] for an unreadable one.
fn stored_campaign(request: &Request) -> Result<Option<CampaignFile>, Error> {
    let out = &request.out;
    if let Some(junit) = &request.junit {
        crate::atomic::check_side_output(junit, "--junit", out)?;
    }
    let stored = if request.resume && out.join(CAMPAIGN_FILE).exists() {
        Some(CampaignFile::read(out)?)
    } else {
        None
    };
    // Records without their campaign: nothing tells which campaign they belong to, and
    // starting one here would replace them.
    if request.resume && stored.is_none() && out.join(RESULTS_FILE).exists() {
        return Err(Error::BadInput(format!(
            "`{}` holds {RESULTS_FILE} but no {CAMPAIGN_FILE}: its records belong to no campaign \
             that can be resumed, and a new one would replace them; move them away, or pass \
             --force to replace them",
            out.display()
        )));
    }
    Ok(stored)
}

/// Refuses a strength asked for that the space cannot have: with fewer discrete parameters
/// there are no t-tuples (and a space with none has no covering array at all).
fn check_strength(request: &Request, scenario: &Scenario, strategy: Strategy) -> Result<(), Error> {
    if let (Some(t), true) = (request.strength, Strategy::SUITES.contains(&strategy)) {
        let nd = scenario.space().level_counts().len();
        if t > nd {
            return Err(Error::BadInput(format!(
                "--strength {t}: a covering array of strength {t} needs {t} discrete parameters, \
                 and {} has {nd}{}",
                scenario.name(),
                if nd == 0 {
                    " (its suite is Halton points alone: leave --strength out)"
                } else {
                    ""
                }
            )));
        }
    }
    Ok(())
}

/// The campaign's strategy, unless the campaign must be refused before anything is written:
/// warnings under `deny_warnings`, a budget past the strategy's capacity, a shard of an
/// adaptive strategy.
fn refusals(
    request: &Request,
    file: &CampaignFile,
    warnings: &[String],
) -> Result<Strategy, Error> {
    if request.deny_warnings && !warnings.is_empty() {
        return Err(Error::BadInput(format!(
            "--deny-warnings: the scenario loads with {} warning{}: {}",
            warnings.len(),
            if warnings.len() == 1 { "" } else { "s" },
            warnings.join("; ")
        )));
    }
    let strategy: Strategy = file.strategy.parse()?;
    if let Some(cap) = strategy.capacity().filter(|&cap| file.budget > cap) {
        return Err(Error::BadInput(format!(
            "--budget {} is more than the {cap} points {strategy} can produce",
            file.budget
        )));
    }
    if file.shard.is_some() && strategy.is_adaptive() {
        return Err(Error::BadInput(format!(
            "--shard cannot split a {strategy} campaign: each of its tests depends on all \
             earlier ones. Run it whole (it is parallel inside: --jobs)"
        )));
    }
    Ok(strategy)
}

/// The session's observers in their order: the results file first (a record reaches the
/// others once it is on disk), the caller's, the summary with its coverage and plots, then
/// JUnit.
struct Chain<'a, 'b, 'c> {
    results: ResultsFile,
    others: &'a mut [&'b mut dyn Observer],
    outputs: AtEnd<AtEndFn<'c>>,
    junit: Option<AtEnd<AtEndFn<'c>>>,
}

impl Chain<'_, '_, '_> {
    fn each(
        &mut self,
        mut f: impl FnMut(&mut dyn Observer) -> Result<(), Error>,
    ) -> Result<(), Error> {
        f(&mut self.results)?;
        for o in self.others.iter_mut() {
            f(&mut **o)?;
        }
        f(&mut self.outputs)?;
        match self.junit.as_mut() {
            Some(j) => f(j),
            None => Ok(()),
        }
    }
}

impl Observer for Chain<'_, '_, '_> {
    fn started(&mut self, prior: &[RunRecord]) -> Result<(), Error> {
        self.each(|o| o.started(prior))
    }

    fn record(&mut self, record: &RunRecord) -> Result<(), Error> {
        self.each(|o| o.record(record))
    }

    fn finished(&mut self, report: &CampaignReport) -> Result<(), Error> {
        self.each(|o| o.finished(report))
    }
}

/// What an [`AtEnd`] does with the records when the campaign finishes.
type AtEndFn<'a> = Box<dyn FnMut(&[RunRecord], &CampaignReport) -> Result<(), Error> + 'a>;

/// An [`Observer`] that gathers every record of the folder (earlier ones included) and hands
/// them to `then` when the campaign finishes: the summary and plots, JUnit XML. Nothing is
/// written after an interruption: the folder is to be resumed.
struct AtEnd<F> {
    records: Vec<RunRecord>,
    then: F,
}

impl<F> AtEnd<F> {
    fn new(then: F) -> Self {
        AtEnd {
            records: Vec::new(),
            then,
        }
    }
}

impl<F: FnMut(&[RunRecord], &CampaignReport) -> Result<(), Error>> Observer for AtEnd<F> {
    fn started(&mut self, prior: &[RunRecord]) -> Result<(), Error> {
        self.records = prior.to_vec();
        Ok(())
    }

    fn record(&mut self, record: &RunRecord) -> Result<(), Error> {
        self.records.push(record.clone());
        Ok(())
    }

    fn finished(&mut self, report: &CampaignReport) -> Result<(), Error> {
        if report.interrupted {
            return Ok(());
        }
        (self.then)(&self.records, report)
    }
}

/// The campaign's settings and scenario: from the request (checked against the folder's
/// campaign when resuming), or from the folder's campaign alone (a resume without a scenario).
fn settings(
    request: &Request,
    stored: Option<&CampaignFile>,
) -> Result<(CampaignFile, Scenario, Option<Vec<Point>>), Error> {
    match (&request.scenario, stored) {
        (Some(name), _) => requested_settings(request, stored, name),
        (None, Some(st)) => stored_settings(request, st),
        (None, None) => Err(Error::BadInput(format!(
            "--resume without SCENARIO needs a campaign in `{}`, which has no {CAMPAIGN_FILE}",
            request.out.display()
        ))),
    }
}

/// The refusal to resume the campaign in `out` whose settings differ from the request's.
fn refuse(out: &Path, diffs: Vec<String>) -> Error {
    Error::BadInput(format!(
        "refusing to resume: `{}` holds a campaign with other settings ({}); resume without \
         those arguments, or start a new campaign with --force or another --out",
        out.display(),
        diffs.join("; ")
    ))
}

/// Scenario `name`, under the system under test of `choice` when it names one.
fn load_scenario(name: &ScenarioRef, choice: &SutChoice) -> Result<Scenario, Error> {
    let mut scenario = name.load()?;
    if let Some(s) = choice.config()? {
        crate::refuse_sut_for_scripted_ego(&scenario)?;
        scenario.set_sut(s);
    }
    Ok(scenario)
}

/// The settings of a request that names scenario `name`, which must equal `stored`'s when
/// resuming.
fn requested_settings(
    request: &Request,
    stored: Option<&CampaignFile>,
    name: &ScenarioRef,
) -> Result<(CampaignFile, Scenario, Option<Vec<Point>>), Error> {
    let choice = SutChoice::of(request.sut.as_ref());
    let scenario = load_scenario(name, &choice)?;
    let given = match &request.points {
        Some(path) => Some(read_points(path, request, &scenario)?),
        None if request.strategy == Some(Strategy::Points) => {
            return Err(Error::Generator(GeneratorError::NeedsPoints))
        }
        None => None,
    };
    let file = CampaignFile::new(
        name,
        &scenario,
        Settings {
            sut: choice,
            strategy: match given {
                Some(_) => Strategy::Points,
                None => request.strategy.unwrap_or(Strategy::Halton),
            }
            .name()
            .into(),
            seed: request.seed.unwrap_or(0),
            budget: match &given {
                Some((_, points)) => points.len() as u64,
                None => request.budget.unwrap_or(100),
            },
            // The default strength, 2, is lowered to the number of discrete
            // parameters when there are fewer (a strength asked for is kept, and
            // refused if too high).
            strength: request.strength.unwrap_or_else(|| {
                let suite = request
                    .strategy
                    .is_some_and(|s| Strategy::SUITES.contains(&s));
                match scenario.space().level_counts().len() {
                    1 if suite => 1,
                    _ => 2,
                }
            }),
            shard: request.shard,
            points: given.as_ref().map(|(f, _)| f.clone()),
        },
    );
    match stored.map(|st| st.differences(&file)) {
        Some(diffs) if !diffs.is_empty() => Err(refuse(&request.out, diffs)),
        _ => Ok((file, scenario, given.map(|(_, p)| p))),
    }
}

/// The settings of a bare resume: the stored campaign `st`'s, once the request's settings,
/// the campaign file, the scenario and its points file are found to agree with it.
fn stored_settings(
    request: &Request,
    st: &CampaignFile,
) -> Result<(CampaignFile, Scenario, Option<Vec<Point>>), Error> {
    check_bare_resume(request, st)?;
    let scenario = load_scenario(&st.scenario, &st.sut)?;
    let again = CampaignFile::new(&st.scenario, &scenario, st.settings());
    if again.fingerprint != st.fingerprint {
        return Err(refuse(&request.out, vec![what_changed(st, &again)]));
    }
    let points = match &st.points {
        Some(stored_file) => {
            let path = Path::new(&stored_file.path);
            let (now, points) = read_points(path, request, &scenario)?;
            if now.sha256 != stored_file.sha256 {
                return Err(refuse(
                    &request.out,
                    vec![format!(
                        "the points file `{}` changed since the campaign started",
                        stored_file.path
                    )],
                ));
            }
            Some(points)
        }
        None => None,
    };
    Ok((st.clone(), scenario, points))
}

/// Refuses a bare resume whose settings differ from the stored campaign `st`'s, or whose
/// `campaign.json` was edited by hand.
fn check_bare_resume(request: &Request, st: &CampaignFile) -> Result<(), Error> {
    // Settings given with a bare resume must agree with the stored campaign.
    let mut diffs = Vec::new();
    let mut check = |name: &str, given: Option<String>, stored: String| {
        if let Some(g) = given.filter(|g| *g != stored) {
            diffs.push(format!("{name}: {stored} vs {g}"));
        }
    };
    check(
        "seed",
        request.seed.map(|v| v.to_string()),
        st.seed.to_string(),
    );
    check(
        "budget",
        request.budget.map(|v| v.to_string()),
        st.budget.to_string(),
    );
    check(
        "strength",
        request.strength.map(|v| v.to_string()),
        st.strength.to_string(),
    );
    check(
        "strategy",
        request.strategy.map(|s| s.name().to_owned()),
        st.strategy.clone(),
    );
    let shard = |s: Option<Shard>| s.map_or("none".to_owned(), |s| s.to_string());
    check(
        "shard",
        request.shard.map(|s| shard(Some(s))),
        shard(st.shard),
    );
    let sut = request.sut.as_ref();
    if sut.is_some() && SutChoice::of(sut) != st.sut {
        diffs.push("system under test differs".into());
    }
    if !diffs.is_empty() {
        return Err(refuse(&request.out, diffs));
    }
    let edited = st.edited_fields();
    if !edited.is_empty() {
        return Err(Error::BadInput(format!(
            "refusing to resume: {} was edited by hand: {} no longer match{} what the \
             campaign wrote. Put the value{} back, or start a new campaign with --force \
             or another --out",
            request.out.join(CAMPAIGN_FILE).display(),
            edited
                .iter()
                .map(|f| format!("`{f}`"))
                .collect::<Vec<_>>()
                .join(", "),
            if edited.len() == 1 { "es" } else { "" },
            if edited.len() == 1 { "" } else { "s" },
        )));
    }
    Ok(())
}

/// Why the stored campaign `st` has another fingerprint than the same settings give now
/// (`again`): the program, a file it reads, its parameters, or `campaign.json` itself.
fn what_changed(st: &CampaignFile, again: &CampaignFile) -> String {
    if st
        .scenario_sha256
        .as_ref()
        .is_some_and(|h| Some(h) != again.scenario_sha256.as_ref())
    {
        format!(
            "the scenario program `{}` changed since the campaign started (its \
             SHA-256 differs)",
            st.scenario
        )
    } else if let Some((was, now)) = st
        .input_files
        .iter()
        .zip(&again.input_files)
        .find(|(a, b)| a != b)
    {
        format!(
            "the file `{}` that the scenario program reads changed since the \
             campaign started (SHA-256 {} then, {} now)",
            now.path,
            &was.sha256[..12],
            &now.sha256[..12]
        )
    } else if st.input_files.len() != again.input_files.len() {
        format!(
            "the scenario program `{}` reads other files than when the campaign \
             started",
            st.scenario
        )
    } else if st.space != again.space {
        format!(
            "the parameters of `{}` differ from the `space` in {CAMPAIGN_FILE}",
            st.scenario
        )
    } else if st.scenario_sha256.is_some() {
        format!(
            "{CAMPAIGN_FILE} was edited: its strategy, seed, budget, strength or \
             system under test no longer give its `fingerprint` (the scenario \
             program is unchanged)"
        )
    } else {
        format!(
            "the scenario `{}` changed since the campaign started, or {CAMPAIGN_FILE} \
             was edited",
            st.scenario
        )
    }
}

/// The tests of a `--points` file, read against the scenario's space, with the file's hash.
/// Refuses `--strategy` other than `points` and a `--budget` other than the row count.
fn read_points(
    path: &Path,
    request: &Request,
    scenario: &Scenario,
) -> Result<(PointsFile, Vec<Point>), Error> {
    if let Some(s) = request.strategy.filter(|&s| s != Strategy::Points) {
        return Err(Error::BadInput(format!(
            "--points chooses the tests, so --strategy {s} cannot be used with it"
        )));
    }
    paracosm_engine::files::regular_file(path).map_err(|e| Error::input(path, e))?;
    let bytes = std::fs::read(path).map_err(|e| Error::input(path, e))?;
    let text = String::from_utf8(bytes.clone())
        .map_err(|e| Error::malformed(path, format!("{}: not UTF-8 text: {e}", path.display())))?;
    let is_jsonl = path.extension().is_some_and(|e| e == "jsonl");
    let set = crate::cover::parse_tests(
        &path.display().to_string(),
        &text,
        is_jsonl,
        Some(scenario.space()),
    )
    .map_err(|e| Error::malformed(path, e.to_string()))?;
    if let Some(b) = request.budget.filter(|&b| b != set.points.len() as u64) {
        return Err(Error::BadInput(format!(
            "--budget {b} differs from the {} tests of --points `{}`; leave --budget out",
            set.points.len(),
            path.display()
        )));
    }
    Ok((PointsFile::of(path, &bytes), set.points))
}

/// Creates `out`; refuses a non-empty folder unless `replace` or `resume`, and a folder that
/// cannot be written.
///
/// # Errors
/// [`Error::BadInput`] naming the folder.
pub fn prepare_out_dir(out: &Path, replace: bool, resume: bool) -> Result<(), Error> {
    // The lock file of this very run ([`crate::campaign::lock`]) does not make a folder non-empty.
    let non_empty = std::fs::read_dir(out)
        .map(|mut d| d.any(|e| e.is_ok_and(|e| e.file_name() != crate::campaign::lock::LOCK_FILE)))
        .unwrap_or(false);
    if out.exists() && !out.is_dir() {
        return Err(Error::BadInput(format!(
            "--out `{}` is not a folder",
            out.display()
        )));
    }
    if non_empty && !replace && !resume {
        return Err(Error::BadInput(format!(
            "`{}` is not empty; pass --resume to finish the campaign in it, --force to replace \
             it, or choose another --out",
            out.display()
        )));
    }
    std::fs::create_dir_all(out).map_err(|e| {
        Error::BadInput(format!(
            "cannot create output folder `{}`: {e}",
            out.display()
        ))
    })?;
    // Probe writability now, before any test runs, and every file the campaign will write.
    crate::atomic::probe_writable(out)?;
    crate::atomic::check_targets(out, crate::atomic::CAMPAIGN_OUTPUTS)
}

/// The path of the results file in `out`, for messages.
pub fn results_path(out: &Path) -> PathBuf {
    out.join(RESULTS_FILE)
}
