//! The campaign runner: points from a generator, tests in parallel, results in order.
//!
//! Its parts: the campaign file ([`file`]), the folder's lock ([`lock`]), merging shards
//! ([`merge`]), progress ([`progress`]), reading results back ([`results`]), per-test seeds
//! ([`seed`]) and a whole session from the command line ([`session`]).
pub mod file;
pub mod lock;
pub mod merge;
pub mod progress;
pub mod results;
pub mod seed;
pub mod session;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::ops::Range;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use paracosm_generators::{Point, Strategy};
use paracosm_scenarios::{RunOptions, Scenario};

use crate::campaign::seed::test_seed;
use crate::record::{MonitorResult, RunRecord, Status};
use crate::report::summary::{Counts, FirstFailure};
use crate::Error;

/// File name of the per-test results in the output folder.
pub const RESULTS_FILE: &str = "results.jsonl";

/// A campaign's settings.
#[derive(Debug, Clone)]
pub struct Campaign<'a> {
    /// The scenario under test.
    pub scenario: &'a Scenario,
    /// The test-generation strategy.
    pub strategy: Strategy,
    /// Campaign seed: seeds the generator and, with the test index, every test.
    pub seed: u64,
    /// Number of tests, `>= 1`.
    pub budget: u64,
    /// Strength of the covering-suite strategies (`ipog`, `kwise`); ignored by the others.
    pub strength: usize,
    /// Worker threads, `>= 1`. Results do not depend on it.
    pub jobs: usize,
    /// End the campaign at the first failed test (robustness `<= 0`): no new test starts, the
    /// tests in flight finish and are written.
    pub stop_at_first_failure: bool,
    /// The points of [`Strategy::Points`], in test order (`budget` of them at least); `None`
    /// for every other strategy, which makes its own.
    pub points: Option<&'a [Point]>,
    /// Write each test's trace (`--trace`): every entity's pose, speed and acceleration, to
    /// `path/test_N.csv` ([`crate::export::trace`]); `None`: no trace.
    pub trace: Option<crate::export::trace::TraceSpec>,
}

/// What a finished campaign reports.
#[derive(Debug, Clone)]
pub struct CampaignReport {
    /// Every record this run wrote, by id.
    pub records: Vec<RunRecord>,
    /// Whether the stop flag ended the run before every asked id ran.
    pub interrupted: bool,
    /// Whether [`Campaign::stop_at_first_failure`] ended the run before every asked id ran.
    pub stopped_at_failure: bool,
    /// Outcome counts.
    pub counts: Counts,
    /// The failing test with the smallest id.
    pub first_failure: Option<FirstFailure>,
    /// Wall-clock time in seconds.
    pub wall_s: f64,
}

impl Campaign<'_> {
    /// The campaign's points, in test order, in chunks of at most 4,096:
    /// `budget` points from the strategy's generator, each chunk asked for when `each` has
    /// taken the one before, so memory does not grow with the budget. `each` gets the id of
    /// the chunk's first point and the chunk, and returns whether to go on.
    ///
    /// # Errors
    /// [`Error::Generator`] when the strategy cannot produce them; [`Error::BadInput`] for an
    /// adaptive strategy, whose points exist only as the campaign runs; the first error of
    /// `each`.
    pub fn points_in_chunks(
        &self,
        mut each: impl FnMut(u64, Vec<Point>) -> Result<bool, Error>,
    ) -> Result<(), Error> {
        let mut generator = self.generator()?;
        if generator.batch().is_some() {
            return Err(Error::BadInput(format!(
                "{} chooses each batch from the robustness of the last: its points exist only \
                 as a campaign runs",
                self.strategy
            )));
        }
        self.check_capacity(generator.as_ref(), self.budget)?;
        let mut next = 0;
        while next < self.budget {
            let n = POINT_CHUNK.min(self.budget - next);
            let chunk = generator.ask(n as usize)?;
            if !each(next, chunk)? {
                break;
            }
            next += n;
        }
        Ok(())
    }

    /// Checks that `records` (the tests `first_id..` in order, as read from `file`, whose line
    /// `k + 1` holds `records[k]`) were written by this campaign: each record's `campaign` tag
    /// is `tag` (when both are known: files written before tags existed have none), its seed is this
    /// campaign's seed for its id ([`test_seed`]), its strategy is this campaign's, and, for a
    /// non-adaptive strategy, its point is the one the strategy proposes for its id. A line
    /// copied from a campaign with another seed, strategy or space fails here. (An adaptive
    /// strategy's points are checked as its searches are replayed, in [`Campaign::run_ids`].)
    ///
    /// # Errors
    /// [`Error::BadInput`] naming the file, the line and what differs; [`Error::Generator`]
    /// when the strategy cannot produce the points.
    pub fn check_origin(
        &self,
        records: &[RunRecord],
        first_id: u64,
        file: &Path,
        tag: Option<&str>,
    ) -> Result<(), Error> {
        let foreign = |k: usize, what: String| {
            Error::BadInput(format!(
                "{}:{}: {what}; the record was not written by this campaign (copied from \
                 another one?). Remove the line and what follows it, then --resume again",
                file.display(),
                k + 1
            ))
        };
        let strategy = self.strategy.to_string();
        for (k, r) in records.iter().enumerate() {
            if let (Some(ours), Some(theirs)) = (tag, r.campaign.as_deref()) {
                if ours != theirs {
                    return Err(foreign(
                        k,
                        format!(
                            "test {} carries campaign tag `{theirs}`, this campaign's is `{ours}`",
                            r.id
                        ),
                    ));
                }
            }
            if r.strategy != strategy {
                return Err(foreign(
                    k,
                    format!(
                        "test {} has strategy `{}`, this campaign's is `{strategy}`",
                        r.id, r.strategy
                    ),
                ));
            }
            let seed = test_seed(self.seed, r.id);
            if r.seed != seed {
                return Err(foreign(
                    k,
                    format!(
                        "test {} has seed {}, but this campaign (seed {}) gives it seed {seed}",
                        r.id, r.seed, self.seed
                    ),
                ));
            }
        }
        if records.is_empty() || (self.strategy == Strategy::Points && self.points.is_none()) {
            // (`merge` does not read a points campaign's points file: seeds only.)
            return Ok(());
        }
        let mut generator = self.generator()?;
        if generator.batch().is_some() {
            return Ok(());
        }
        generator.skip(first_id)?;
        for (chunk, block) in records.chunks(POINT_CHUNK as usize).enumerate() {
            let points = generator.ask(block.len())?;
            for (j, (r, p)) in block.iter().zip(&points).enumerate() {
                if &r.point != p {
                    return Err(foreign(
                        chunk * POINT_CHUNK as usize + j,
                        format!(
                            "test {}'s point is not the one {strategy} proposes for it",
                            r.id
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The campaign's generator, fresh.
    fn generator(&self) -> Result<Box<dyn paracosm_generators::Generator>, Error> {
        if self.strategy == Strategy::Points {
            let points = self
                .points
                .ok_or(paracosm_generators::GeneratorError::NeedsPoints)?;
            return Ok(Strategy::build_given(
                self.scenario.space(),
                points.to_vec(),
            )?);
        }
        Ok(self.strategy.build_sized(
            self.scenario.space(),
            self.seed,
            self.budget,
            self.strength,
        )?)
    }

    /// Runs test `id` at `point` alone: what a worker does.
    pub fn run_one(&self, id: u64, point: &Point) -> RunRecord {
        self.run_one_with(id, point, &mut RunOptions::default())
    }

    /// As [`Campaign::run_one`], with a viewing camera and a frame callback: what a replay
    /// does.
    pub fn run_one_with(&self, id: u64, point: &Point, options: &mut RunOptions<'_>) -> RunRecord {
        match &self.trace {
            Some(trace) if options.on_world.is_none() && options.on_step.is_none() => {
                let mut world = None;
                let mut states = Vec::new();
                let mut on_world = |w: &paracosm_engine::WorldSpec| world = Some(w.clone());
                let mut on_step = |s: &paracosm_engine::Snapshot| states.push(s.clone());
                let mut traced = RunOptions {
                    camera: options.camera.clone(),
                    on_frame: options
                        .on_frame
                        .as_deref_mut()
                        .map(|f| f as &mut dyn FnMut(&paracosm_engine::CameraFrame)),
                    on_sample: options
                        .on_sample
                        .as_deref_mut()
                        .map(|f| f as &mut dyn FnMut(&paracosm_scenarios::Sample<'_>)),
                    perturb: options.perturb.as_deref_mut().map(|f| {
                        f as &mut dyn FnMut(
                            f64,
                            paracosm_engine::Control,
                        ) -> paracosm_engine::Control
                    }),
                    on_world: Some(&mut on_world),
                    on_step: Some(&mut on_step),
                };
                let mut record = self.run_one_untraced(id, point, &mut traced);
                if let Some(world) = world {
                    let path = trace.path.join(format!("test_{id}.csv"));
                    let written = crate::export::trace::write(
                        &path,
                        &world,
                        &states,
                        (trace.every_s, world.dt_s),
                        (
                            self.scenario.name(),
                            &crate::export::trace::ego_name(self.scenario),
                        ),
                    );
                    if let Err(e) = written {
                        // A test whose trace was asked for and is missing is no result.
                        record.status = Status::Error;
                        record.error = Some(format!("its trace was not written: {e}"));
                    }
                }
                record
            }
            _ => self.run_one_untraced(id, point, options),
        }
    }

    /// [`Campaign::run_one_with`] without writing a trace.
    fn run_one_untraced(&self, id: u64, point: &Point, options: &mut RunOptions<'_>) -> RunRecord {
        let started = Instant::now();
        let seed = test_seed(self.seed, id);
        let scenario = self.scenario;
        let decoded = scenario.space().decode(point);
        let outcome = match &decoded {
            Ok(assignment) => catch_unwind(AssertUnwindSafe(|| {
                scenario.run_with(assignment, seed, options)
            }))
            .map_err(|panic| {
                // A defect of paracosm (or of a library it calls), not of the system under
                // test: recorded as such, and the campaign goes on.
                let msg = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic without a message".into());
                Error::Internal(format!("the simulation panicked: {msg}")).to_string()
            })
            .and_then(|run| run.map_err(|e| e.to_string())),
            Err(e) => Err(e.to_string()),
        };
        let (status, monitors, metrics, error, log) = match outcome {
            Ok(o) => (
                if o.passed() {
                    Status::Pass
                } else {
                    Status::Fail
                },
                o.monitors
                    .iter()
                    .map(|(n, v)| (n.clone(), MonitorResult::new(v, o.cut_short.contains(n))))
                    .collect(),
                o.metrics
                    .into_iter()
                    .map(|(n, v)| (n.to_owned(), v))
                    .collect(),
                None,
                o.log,
            ),
            Err(e) => (Status::Error, Vec::new(), Vec::new(), Some(e), Vec::new()),
        };
        RunRecord {
            passive: self.scenario.passive_monitors(),
            campaign: None,
            id,
            seed,
            strategy: self.strategy.name().to_owned(),
            point: point.clone(),
            params: decoded.ok(),
            status,
            monitors,
            metrics,
            error,
            log,
            wall_ms: started.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// Runs the campaign, writing `results.jsonl` into `out_dir` (created if needed, the file
    /// replaced). `on_done` is called in the calling thread as each record is written (for
    /// progress bars). [`Campaign::run_ids`] with a [`ResultsFile`] and `on_done` as observers.
    ///
    /// Tests are handed to `jobs` rayon workers one index at a time, so tests finish roughly in
    /// index order. Each record is appended and flushed as soon as every record before it is
    /// written: the file is in id order and byte-identical for any `jobs`, and at most the
    /// tests in flight are missing if the process dies.
    ///
    /// An adaptive strategy ([`Strategy::FALSIFIERS`]) runs in batches of its
    /// `Generator::batch` size: ask, simulate the batch in parallel, tell the robustness of
    /// every test in id order, ask again.
    ///
    /// # Errors
    /// [`Error::Generator`] when the points cannot be generated, [`Error::Internal`] when the
    /// pool cannot start, [`Error::Write`] when the results file cannot be written. Records
    /// already written stay on disk.
    pub fn run(
        &self,
        out_dir: &Path,
        on_done: impl FnMut(&RunRecord),
    ) -> Result<CampaignReport, Error> {
        let mut file = ResultsFile::new(out_dir, false);
        let mut each = OnRecord(on_done);
        self.run_ids(0..self.budget, None, None, &mut [&mut file, &mut each])
    }

    /// Runs the tests with ids in `ids` (a sub-range of `0..budget`: a shard, or what a
    /// resumed run has left) and reports to `observers`, in this order: each one's
    /// [`Observer::started`] once the campaign is accepted (nothing is touched before), its
    /// [`Observer::record`] for each record in id order, its [`Observer::finished`] at the
    /// end. A [`ResultsFile`] among them writes `results.jsonl`. `prior = Some(records)` are
    /// the records of an earlier run of this campaign (the ids just before `ids.start`, in
    /// order). When `stop` becomes true no new test starts; the tests in flight finish, the
    /// records that follow without a gap are reported, and the report says `interrupted`. With [`Campaign::stop_at_first_failure`] the first
    /// failed test stops the campaign: no new test starts, and the file ends with the first
    /// failure in id order (records of tests that were in flight after it are dropped, so the
    /// file does not depend on `jobs`); the report is not `interrupted`. When `prior` already
    /// holds a failure, nothing runs.
    ///
    /// An adaptive strategy replays `prior` into its searches (their robustness, without
    /// simulating them again) before it runs the rest, so a resumed campaign equals an
    /// uninterrupted one. It cannot run a shard: its tests depend on all earlier ones.
    ///
    /// # Errors
    /// As [`Campaign::run`]; [`Error::BadInput`] for a shard of an adaptive campaign or prior
    /// records that the strategy would not have proposed; the first error an observer
    /// returns (no new test starts after it).
    pub fn run_ids(
        &self,
        ids: Range<u64>,
        prior: Option<&[RunRecord]>,
        stop: Option<&AtomicBool>,
        observers: &mut [&mut dyn Observer],
    ) -> Result<CampaignReport, Error> {
        let started = Instant::now();
        let mut generator = self.generator()?;
        let ids = ids.start.min(self.budget)..ids.end.min(self.budget);
        let prior_len = prior.map_or(0, <[RunRecord]>::len) as u64;
        let prior_failed = prior.is_some_and(|p| p.iter().any(|r| r.status == Status::Fail));
        if self.stop_at_first_failure && prior_failed {
            // A resumed campaign that had already found its failure is finished.
            let report = CampaignReport {
                records: Vec::new(),
                interrupted: false,
                stopped_at_failure: true,
                counts: Counts::default(),
                first_failure: None,
                wall_s: started.elapsed().as_secs_f64(),
            };
            for o in observers.iter_mut() {
                o.started(prior.unwrap_or(&[]))?;
                o.finished(&report)?;
            }
            return Ok(report);
        }
        // Everything that can be refused is refused before the output folder is touched.
        let upfront = self.first_chunk(&mut *generator, &ids, prior_len)?;
        for o in observers.iter_mut() {
            o.started(prior.unwrap_or(&[]))?;
        }
        let mut run = Run::open(self, stop)?;
        match upfront {
            Some(first) => run.chunks(&mut *generator, &ids, first, observers)?,
            None => run.batches(&mut *generator, &ids, prior.unwrap_or(&[]), observers)?,
        }
        let records = run.records;
        let asked = ids.end - ids.start;
        let counts = Counts::of(&records);
        let first_failure = FirstFailure::of(&records);
        let report = CampaignReport {
            interrupted: (records.len() as u64) < asked && run.stopped_by_user,
            stopped_at_failure: (records.len() as u64) < asked && !run.stopped_by_user,
            records,
            counts,
            first_failure,
            wall_s: started.elapsed().as_secs_f64(),
        };
        for o in observers.iter_mut() {
            o.finished(&report)?;
        }
        Ok(report)
    }
}

impl Campaign<'_> {
    /// The first chunk of a non-adaptive strategy's points for the tests `ids` (its points
    /// are asked for in chunks as the tests run, so memory does not grow with the budget);
    /// `None` for an adaptive strategy, which asks batch by batch.
    ///
    /// # Errors
    /// [`Error::Generator`] for a budget past what the strategy can produce (refused now,
    /// before anything runs) or points it cannot give; [`Error::BadInput`] for a shard of an
    /// adaptive strategy (`ids` other than all tests after the `prior_len` earlier ones).
    fn first_chunk(
        &self,
        generator: &mut dyn paracosm_generators::Generator,
        ids: &Range<u64>,
        prior_len: u64,
    ) -> Result<Option<Vec<Point>>, Error> {
        match generator.batch() {
            None => {
                self.check_capacity(&*generator, ids.end)?;
                generator.skip(ids.start)?;
                let n = POINT_CHUNK.min(ids.end - ids.start) as usize;
                Ok(Some(generator.ask(n)?))
            }
            Some(_) if ids.start != prior_len || ids.end != self.budget => {
                Err(Error::BadInput(format!(
                    "{} adapts each test to all earlier ones, so it runs whole campaigns \
                     only, not a shard",
                    self.strategy
                )))
            }
            Some(_) => Ok(None),
        }
    }
}

impl Campaign<'_> {
    /// Refuses `end` points from `generator` when its strategy has fewer (a covering array's
    /// rows, the points given), before any test runs.
    ///
    /// # Errors
    /// [`Error::Generator`] with the strategy's limit.
    fn check_capacity(
        &self,
        generator: &dyn paracosm_generators::Generator,
        end: u64,
    ) -> Result<(), Error> {
        let capacity = match self.strategy {
            Strategy::Points => self.points.map(|p| p.len() as u64),
            s => s.capacity(),
        };
        match capacity.filter(|&c| end > c) {
            Some(limit) => Err(paracosm_generators::GeneratorError::CapacityExceeded {
                generator: generator.name(),
                what: "points",
                limit,
                requested: end,
            }
            .into()),
            None => Ok(()),
        }
    }
}

/// How many points of a non-adaptive strategy a campaign asks for at a time (each chunk runs
/// in parallel; the next is asked for when it is done).
const POINT_CHUNK: u64 = 4096;

/// The state of a running campaign: the worker pool, the stop flags and the records reported
/// so far.
struct Run<'c, 'a> {
    campaign: &'c Campaign<'a>,
    pool: rayon::ThreadPool,
    stop: Option<&'c AtomicBool>,
    /// Set by the first failed test when the campaign stops at its first failure.
    failed: AtomicBool,
    stopped_by_user: bool,
    records: Vec<RunRecord>,
}

impl<'c, 'a> Run<'c, 'a> {
    fn open(campaign: &'c Campaign<'a>, stop: Option<&'c AtomicBool>) -> Result<Self, Error> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(campaign.jobs)
            .thread_name(|i| format!("paracosm-worker-{i}"))
            .build()
            .map_err(|e| {
                Error::Internal(format!(
                    "cannot start {} worker threads: {e}",
                    campaign.jobs
                ))
            })?;
        Ok(Run {
            campaign,
            pool,
            stop,
            failed: AtomicBool::new(false),
            stopped_by_user: false,
            records: Vec::new(),
        })
    }

    /// Runs the tests `ids` of a non-adaptive strategy, `first` the points of the first chunk,
    /// asking `generator` for the next chunk as each is done, until the end or a halt.
    fn chunks(
        &mut self,
        generator: &mut dyn paracosm_generators::Generator,
        ids: &Range<u64>,
        first: Vec<Point>,
        observers: &mut [&mut dyn Observer],
    ) -> Result<(), Error> {
        let mut next = ids.start;
        let mut points = first;
        loop {
            self.execute(next, &points, observers)?;
            next += points.len() as u64;
            if next >= ids.end || self.halted() {
                return Ok(());
            }
            points = generator.ask(POINT_CHUNK.min(ids.end - next) as usize)?;
        }
    }

    /// Runs the tests up to `ids.end` of an adaptive strategy batch by batch: ask, simulate,
    /// tell. The tests before `ids.start` are not simulated again: `prior` (an earlier run's
    /// records) tells their robustness, after checking that they are the points proposed.
    fn batches(
        &mut self,
        generator: &mut dyn paracosm_generators::Generator,
        ids: &Range<u64>,
        prior: &[RunRecord],
        observers: &mut [&mut dyn Observer],
    ) -> Result<(), Error> {
        let strategy = self.campaign.strategy;
        let passive = self.campaign.scenario.passive_monitors();
        let batch = generator.batch().unwrap_or(1);
        let mut next = 0u64;
        while next < ids.end && !self.halted() {
            let n = (batch as u64).min(ids.end - next) as usize;
            let points = generator.ask(n)?;
            if points.is_empty() {
                return Err(Error::BadInput(format!(
                    "{strategy} proposed no point at test {next}"
                )));
            }
            // The part of the batch that an earlier run already simulated.
            let known = ((ids.start - next.min(ids.start)) as usize).min(points.len());
            let mut told: Vec<(Point, f64)> = Vec::with_capacity(points.len());
            for (j, p) in points[..known].iter().enumerate() {
                let r = &prior[next as usize + j];
                if &r.point != p {
                    return Err(Error::BadInput(format!(
                        "test {} in the results is not the point {strategy} proposes; the \
                         results were not written by this campaign",
                        r.id
                    )));
                }
                told.push((p.clone(), r.cost(&passive)));
            }
            let fresh = self.execute(next + known as u64, &points[known..], observers)?;
            told.extend(
                self.records[fresh]
                    .iter()
                    .map(|r| (r.point.clone(), r.cost(&passive))),
            );
            generator.tell(&told);
            next += points.len() as u64;
        }
        Ok(())
    }

    /// Whether no new test may start: the user's stop, or the first failure.
    fn halted(&self) -> bool {
        // (`execute` repeats this on split borrows of the fields.)
        self.stop.is_some_and(|s| s.load(Ordering::Relaxed)) || self.failed.load(Ordering::Relaxed)
    }

    /// Runs `points` as tests `first..`, in parallel, reporting each record to the observers
    /// once every record before it is reported. Returns where this call's records are in
    /// `self.records` (fewer than `points` when halted).
    fn execute(
        &mut self,
        first: u64,
        points: &[Point],
        observers: &mut [&mut dyn Observer],
    ) -> Result<Range<usize>, Error> {
        let campaign = self.campaign;
        let jobs = campaign.jobs;
        let next = AtomicUsize::new(0);
        let (tx, rx) = mpsc::channel::<RunRecord>();
        let mut done: Vec<RunRecord> = Vec::with_capacity(points.len());
        let mut pending: BTreeMap<u64, RunRecord> = BTreeMap::new();
        let mut observed = Ok(());
        let (pool, stop, failed) = (&self.pool, self.stop, &self.failed);
        let halted =
            || stop.is_some_and(|s| s.load(Ordering::Relaxed)) || failed.load(Ordering::Relaxed);
        std::thread::scope(|scope| {
            let next = &next;
            let halted = &halted;
            scope.spawn(move || {
                pool.scope(|s| {
                    for _ in 0..jobs {
                        let tx = tx.clone();
                        s.spawn(move |_| {
                            // Past a hard heap limit, park: the loop below writes what
                            // finished before, then ends the process.
                            paracosm_scenarios::memory::park_on_hard_limit(true);
                            loop {
                                if halted() {
                                    break;
                                }
                                let i = next.fetch_add(1, Ordering::Relaxed);
                                let Some(p) = points.get(i) else { break };
                                if tx.send(campaign.run_one(first + i as u64, p)).is_err() {
                                    break; // the writer gave up; stop taking work
                                }
                            }
                            paracosm_scenarios::memory::park_on_hard_limit(false);
                        });
                    }
                });
            });
            // With stop_at_first_failure, records after the first failure (in id order) are
            // tests that were in flight: dropped, so the file does not depend on timing.
            let mut closed = false;
            loop {
                let record = match rx.recv_timeout(std::time::Duration::from_millis(50)) {
                    Ok(record) => record,
                    Err(mpsc::RecvTimeoutError::Disconnected) => break,
                    Err(mpsc::RecvTimeoutError::Timeout) => {
                        if !paracosm_scenarios::memory::hard_limit_hit() {
                            continue;
                        }
                        // A worker passed a hard heap limit (its message is printed) and is
                        // parked: write the records that follow on without a gap, then end
                        // the process as the limit promises (exit 2).
                        while let Ok(r) = rx.try_recv() {
                            pending.insert(r.id, r);
                        }
                        while let Some(r) = pending.remove(&(first + done.len() as u64)) {
                            if observed.is_ok() {
                                observed = observers.iter_mut().try_for_each(|o| o.record(&r));
                            }
                            done.push(r);
                        }
                        std::process::exit(2);
                    }
                };
                if campaign.stop_at_first_failure && record.status == Status::Fail {
                    failed.store(true, Ordering::Relaxed);
                }
                pending.insert(record.id, record);
                while let Some(r) = pending.remove(&(first + done.len() as u64)) {
                    if closed {
                        break;
                    }
                    closed = campaign.stop_at_first_failure && r.status == Status::Fail;
                    if observed.is_ok() {
                        observed = observers.iter_mut().try_for_each(|o| o.record(&r));
                        if observed.is_err() {
                            // Stop the workers: nothing more can be saved.
                            next.store(usize::MAX / 2, Ordering::Relaxed);
                        }
                    }
                    done.push(r);
                }
            }
        });
        observed?;
        if done.len() < points.len() && self.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            self.stopped_by_user = true;
        }
        let start = self.records.len();
        self.records.append(&mut done);
        Ok(start..self.records.len())
    }
}

/// What a campaign reports to, as it runs (in the style of argmin's observers): the results
/// file, a progress bar, JUnit, a test's own checks. All calls come from the thread that runs
/// the campaign, in id order. An error stops the campaign: no new test starts, and
/// [`Campaign::run_ids`] returns it.
pub trait Observer {
    /// Once the campaign is accepted, before any test runs; `prior` are the records of an
    /// earlier run of it (a resume), which are not reported again.
    ///
    /// # Errors
    /// Whatever stops the observer (e.g. [`Error::Write`]).
    fn started(&mut self, _prior: &[RunRecord]) -> Result<(), Error> {
        Ok(())
    }

    /// Each new record, in id order.
    ///
    /// # Errors
    /// As [`Observer::started`].
    fn record(&mut self, _record: &RunRecord) -> Result<(), Error> {
        Ok(())
    }

    /// Once, when no more tests will run (also after an interruption: see
    /// [`CampaignReport::interrupted`]).
    ///
    /// # Errors
    /// As [`Observer::started`].
    fn finished(&mut self, _report: &CampaignReport) -> Result<(), Error> {
        Ok(())
    }
}

/// An [`Observer`] that calls a closure with each record.
pub struct OnRecord<F>(pub F);

impl<F: FnMut(&RunRecord)> Observer for OnRecord<F> {
    fn record(&mut self, record: &RunRecord) -> Result<(), Error> {
        (self.0)(record);
        Ok(())
    }
}

/// The [`Observer`] that writes `results.jsonl`: one line per record, flushed at once, so at
/// most the tests in flight are missing if the process dies.
pub struct ResultsFile {
    path: PathBuf,
    append: bool,
    tag: Option<String>,
    out: Option<BufWriter<File>>,
}

impl ResultsFile {
    /// `results.jsonl` in `dir` (created when the campaign starts): replaced, or appended to
    /// when `append` (a resumed campaign; the file must then end with a whole line).
    pub fn new(dir: &Path, append: bool) -> Self {
        ResultsFile {
            path: dir.join(RESULTS_FILE),
            append,
            tag: None,
            out: None,
        }
    }

    /// Writes `tag` (the campaign's, `CampaignFile::tag`) into every record's `campaign`.
    pub fn tagged(mut self, tag: String) -> Self {
        self.tag = Some(tag);
        self
    }
}

impl Observer for ResultsFile {
    fn started(&mut self, _prior: &[RunRecord]) -> Result<(), Error> {
        if let Some(dir) = self.path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
        }
        let file = crate::atomic::open_regular(&self.path, self.append)?;
        self.out = Some(BufWriter::new(file));
        Ok(())
    }

    fn record(&mut self, record: &RunRecord) -> Result<(), Error> {
        let out = self
            .out
            .as_mut()
            .ok_or_else(|| Error::Internal("a record before the campaign started".into()))?;
        let tagged;
        let record = match &self.tag {
            Some(tag) if record.campaign.as_ref() != Some(tag) => {
                tagged = RunRecord {
                    campaign: Some(tag.clone()),
                    ..record.clone()
                };
                &tagged
            }
            _ => record,
        };
        serde_json::to_writer(&mut *out, record)
            .map_err(std::io::Error::from)
            .and_then(|()| out.write_all(b"\n"))
            .and_then(|()| out.flush())
            .map_err(|e| Error::write(&self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn campaign(scenario: &Scenario, jobs: usize) -> Campaign<'_> {
        Campaign {
            scenario,
            strategy: Strategy::Random,
            seed: 5,
            budget: 12,
            strength: 2,
            jobs,
            stop_at_first_failure: false,
            points: None,
            trace: None,
        }
    }

    fn strip_wall(mut r: RunRecord) -> RunRecord {
        r.wall_ms = 0.0;
        r
    }

    #[test]
    fn records_are_in_id_order_and_independent_of_jobs() {
        let s = paracosm_scenarios::reference::scenario();
        let dir = tempfile::tempdir().unwrap();
        let mut seen = Vec::new();
        let one = campaign(&s, 1)
            .run(&dir.path().join("one"), |r| seen.push(r.id))
            .unwrap();
        let three = campaign(&s, 3)
            .run(&dir.path().join("three"), |_| {})
            .unwrap();
        assert_eq!(seen.len(), 12);
        let ids: Vec<u64> = one.records.iter().map(|r| r.id).collect();
        assert_eq!(ids, (0..12).collect::<Vec<_>>());
        let a: Vec<_> = one.records.into_iter().map(strip_wall).collect();
        let b: Vec<_> = three.records.into_iter().map(strip_wall).collect();
        assert_eq!(a, b);
        assert_eq!(one.counts, three.counts);
        assert_eq!(one.counts.pass + one.counts.fail + one.counts.error, 12);
        let written = std::fs::read_to_string(dir.path().join("one").join(RESULTS_FILE)).unwrap();
        assert_eq!(written.lines().count(), 12);
        assert!(written.ends_with('\n'));
    }

    #[test]
    fn any_test_can_be_replayed_alone() {
        let s = paracosm_scenarios::reference::scenario();
        let c = campaign(&s, 2);
        let dir = tempfile::tempdir().unwrap();
        let report = c.run(dir.path(), |_| {}).unwrap();
        let mut points = Vec::new();
        c.points_in_chunks(|first, chunk| {
            assert_eq!(first, points.len() as u64);
            points.extend(chunk);
            Ok(true)
        })
        .unwrap();
        assert_eq!(points.len(), 12);
        for id in [0u64, 7, 11] {
            let replay = c.run_one(id, &points[id as usize]);
            assert_eq!(
                strip_wall(replay),
                strip_wall(report.records[id as usize].clone())
            );
        }
    }

    /// Points asked for in chunks of 4,096 are the points asked for at once, in order, for a
    /// sequence and for seeded random draws; `each` returning false stops the asking.
    #[test]
    fn points_in_chunks_are_the_points_asked_for_at_once() {
        let s = paracosm_scenarios::reference::scenario();
        for strategy in [Strategy::Halton, Strategy::Random] {
            let c = Campaign {
                strategy,
                budget: 5000,
                ..campaign(&s, 1)
            };
            let whole = c.generator().unwrap().ask(5000).unwrap();
            let mut chunks = Vec::new();
            c.points_in_chunks(|first, chunk| {
                chunks.push((first, chunk.len()));
                assert_eq!(
                    chunk[..],
                    whole[first as usize..first as usize + chunk.len()]
                );
                Ok(true)
            })
            .unwrap();
            assert_eq!(chunks, [(0, 4096), (4096, 904)], "{strategy}");
            let mut asked = 0;
            c.points_in_chunks(|_, _| {
                asked += 1;
                Ok(false)
            })
            .unwrap();
            assert_eq!(asked, 1);
        }
    }

    #[test]
    fn a_point_that_does_not_decode_becomes_an_error_record() {
        let s = paracosm_scenarios::reference::scenario();
        let r = campaign(&s, 1).run_one(
            0,
            &Point {
                discrete: vec![],
                continuous: vec![1.5, 0.5],
            },
        );
        assert_eq!(r.status, Status::Error);
        assert_eq!(r.params, None);
        assert!(r.error.unwrap().contains("outside [0, 1)"));
    }

    #[test]
    fn sobol_past_its_capacity_is_refused_before_anything_runs() {
        let s = paracosm_scenarios::reference::scenario();
        let c = Campaign {
            strategy: Strategy::Sobol,
            budget: 70_000,
            ..campaign(&s, 1)
        };
        let dir = tempfile::tempdir().unwrap();
        let err = c.run(&dir.path().join("x"), |_| {}).unwrap_err();
        assert!(matches!(err, Error::Generator(_)));
        assert!(!dir.path().join("x").exists());
    }
}
