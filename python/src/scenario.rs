//! Scenarios as a benchmark: `paracosm.Scenario`'s native half. Tests run exactly as
//! `paracosm-fuzz --points` runs them: strategy `points`, test `i` seeded by
//! `test_seed(seed, i)`, records serialised as the lines of `results.jsonl`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use numpy::prelude::*;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use paracosm::campaign::{Campaign, OnRecord};
use paracosm::RunRecord;
use paracosm_engine::sut::{ExternalConfig, SutConfig};
use paracosm_generators::{Domain, Point, Strategy};
use paracosm_scenarios::Scenario;

use crate::{runtime_error, value_error};

/// Registers the class in `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ScenarioHandle>()?;
    m.add("BUILTIN_SCENARIOS", paracosm_scenarios::builtin_names())?;
    Ok(())
}

/// A loaded scenario program: its space, monitors and warnings, and a way to run tests.
#[pyclass(frozen, module = "paracosm._native")]
pub struct ScenarioHandle {
    scenario: Scenario,
    warnings: Vec<String>,
}

/// A system under test chosen from Python: a built-in name, or a command speaking
/// SUT_PROTOCOL.md.
fn sut_config(
    builtin: Option<&str>,
    command: Option<Vec<String>>,
    timeout_s: f64,
    fresh: bool,
) -> PyResult<Option<SutConfig>> {
    match (builtin, command) {
        // A built-in name, or `onnx:PATH` relative to the working directory.
        (Some(name), _) => SutConfig::named(name, std::path::Path::new(""))
            .map(Some)
            .map_err(value_error),
        (None, Some(words)) => {
            if words.is_empty() {
                return Err(value_error("sut: the command is empty"));
            }
            // As the CLI's --sut-cmd: a program that cannot start is refused before any test
            // (it gave every test an error record).
            paracosm_engine::sut::check_command(&words)
                .map_err(|e| value_error(format!("sut: {e}")))?;
            if !(timeout_s.is_finite() && timeout_s > 0.0) {
                return Err(value_error(format!(
                    "sut_timeout {timeout_s} must be a positive number of seconds"
                )));
            }
            Ok(Some(SutConfig::External(ExternalConfig::new(
                words, timeout_s, !fresh,
            ))))
        }
        (None, None) => Ok(None),
    }
}

impl ScenarioHandle {
    /// The scenario with `sut` in place of its own.
    fn with_sut(&self, sut: Option<SutConfig>) -> std::borrow::Cow<'_, Scenario> {
        match sut {
            Some(s) => {
                let mut scenario = self.scenario.clone();
                scenario.set_sut(s);
                std::borrow::Cow::Owned(scenario)
            }
            None => std::borrow::Cow::Borrowed(&self.scenario),
        }
    }

    /// Unit-cube rows (`n × d`, every parameter in declaration order) as points: a continuous
    /// coordinate `u` in `[0, 1]` (1 is taken as the largest value below it, the interval's
    /// upper end), a discrete one as level `min(floor(u · L), L − 1)`.
    fn unit_points(&self, values: &[f64], rows: usize, d: usize) -> PyResult<Vec<Point>> {
        let params = self.scenario.space().params();
        if d != params.len() {
            return Err(value_error(format!(
                "points has {d} columns, the scenario has {} parameters ({})",
                params.len(),
                params
                    .iter()
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        if d == 0 {
            // A scenario without open parameters: `n` rows of nothing, `n` tests.
            return Ok(vec![Point::default(); rows]);
        }
        let mut points = Vec::with_capacity(rows);
        for (r, row) in values.chunks_exact(d).enumerate() {
            let mut p = Point::default();
            for ((c, &u), param) in row.iter().enumerate().zip(params) {
                if !(0.0..=1.0).contains(&u) {
                    return Err(value_error(format!(
                        "points[{r}, {c}] = {u} (`{}`) is outside the unit interval [0, 1]",
                        param.name
                    )));
                }
                match &param.domain {
                    Domain::Interval { .. } => {
                        p.continuous.push(u.min(1.0 - f64::EPSILON / 2.0));
                    }
                    Domain::Levels(levels) => {
                        let l = levels.len() as u32;
                        p.discrete.push(((u * f64::from(l)) as u32).min(l - 1));
                    }
                }
            }
            points.push(p);
        }
        Ok(points)
    }

    /// Runs `points` as a campaign: the records as `results.jsonl` lines, in id order.
    fn run_points(
        &self,
        py: Python<'_>,
        points: Vec<Point>,
        sut: Option<SutConfig>,
        jobs: Option<usize>,
        seed: u64,
    ) -> PyResult<Vec<String>> {
        if points.is_empty() {
            return Err(value_error("points is empty: give at least one test"));
        }
        let scenario = self.with_sut(sut);
        let jobs = jobs.unwrap_or_else(|| {
            std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
        });
        if jobs == 0 {
            return Err(value_error("jobs must be at least 1"));
        }
        // No more workers than tests: `jobs=2000` for 3 tests started 2,000 threads (9 s).
        // The records do not depend on the number of workers.
        let jobs = jobs.min(points.len());
        // The campaign runs on a thread of its own while this one, the GIL released, waits
        // for it and checks for Ctrl-C between waits: a KeyboardInterrupt stops the campaign
        // (no new test starts; the tests in flight finish) and is raised here.
        let stop = AtomicBool::new(false);
        let (result, interrupt) = py.detach(|| {
            std::thread::scope(|s| {
                let (done_tx, done_rx) = mpsc::channel::<()>();
                let worker = s.spawn(|| {
                    let campaign = Campaign {
                        scenario: &scenario,
                        strategy: Strategy::Points,
                        seed,
                        budget: points.len() as u64,
                        strength: 2,
                        jobs,
                        stop_at_first_failure: false,
                        points: Some(&points),
                        trace: None,
                    };
                    let mut lines = Vec::with_capacity(points.len());
                    let mut collect = OnRecord(|r: &RunRecord| {
                        lines.push(serde_json::to_string(r).expect("a record serialises"));
                    });
                    let run = campaign
                        .run_ids(
                            0..points.len() as u64,
                            None,
                            Some(&stop),
                            &mut [&mut collect],
                        )
                        .map(|_| ())
                        .map_err(|e| (e.exit_code(), e.to_string()));
                    drop(done_tx);
                    run.map(|()| lines)
                });
                let mut interrupt = None;
                while let Err(RecvTimeoutError::Timeout) =
                    done_rx.recv_timeout(Duration::from_millis(50))
                {
                    if interrupt.is_none() {
                        if let Err(e) = Python::attach(|py| py.check_signals()) {
                            stop.store(true, Ordering::Relaxed);
                            interrupt = Some(e);
                        }
                    }
                }
                let result = worker.join().unwrap_or_else(|_| {
                    Err((
                        3,
                        "internal error: the campaign's thread panicked".to_owned(),
                    ))
                });
                (result, interrupt)
            })
        });
        if let Some(e) = interrupt {
            return Err(e);
        }
        result.map_err(|(code, message): (u8, String)| {
            if code == 2 {
                value_error(message)
            } else {
                runtime_error(message)
            }
        })
    }
}

#[pymethods]
impl ScenarioHandle {
    /// Loads a built-in scenario by name, a `.star` program or an OpenSCENARIO `.xosc` file by
    /// path, the file read with `paracosm-fuzz`'s options (`open`: `Name=lo..hi` or
    /// `Name=a,b,c` each; `continuous`, `scripted_ego`, `ego`, `horizon` in s, `ego_speed` in
    /// m/s, `maps` a folder, `carla`), which only an
    /// OpenSCENARIO file takes ([`paracosm::ScenarioRef`]).
    #[new]
    #[pyo3(signature = (name_or_path, *, open = Vec::new(), continuous = false, scripted_ego = false, ego = None, horizon = None, ego_speed = None, maps = None, carla = false))]
    // One parameter per keyword argument of Python's `Scenario`, as pyo3 maps them.
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        name_or_path: &str,
        open: Vec<String>,
        continuous: bool,
        scripted_ego: bool,
        ego: Option<String>,
        horizon: Option<f64>,
        ego_speed: Option<f64>,
        maps: Option<String>,
        carla: bool,
    ) -> PyResult<Self> {
        let reference = match paracosm::ScenarioRef::named(name_or_path) {
            paracosm::ScenarioRef::OpenScenario(x) => {
                paracosm::ScenarioRef::OpenScenario(paracosm::scenario_ref::XoscRef {
                    open,
                    continuous,
                    scripted_ego,
                    ego,
                    horizon_s: horizon,
                    ego_speed_mps: ego_speed,
                    maps,
                    carla,
                    ..x
                })
            }
            program
                if open.is_empty()
                    && !continuous
                    && !scripted_ego
                    && ego.is_none()
                    && horizon.is_none()
                    && ego_speed.is_none()
                    && maps.is_none()
                    && !carla =>
            {
                program
            }
            _ => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "{name_or_path}: open, continuous, scripted_ego, ego, horizon, ego_speed, maps and carla are for an \
                     OpenSCENARIO scenario (.xosc)"
                )))
            }
        };
        let scenario = py.detach(|| reference.load()).map_err(value_error)?;
        let warnings = paracosm::report::warnings_of(&scenario);
        Ok(ScenarioHandle { scenario, warnings })
    }

    /// The scenario's name.
    #[getter]
    fn name(&self) -> String {
        self.scenario.name().to_owned()
    }

    /// Its one-line description.
    #[getter]
    fn description(&self) -> String {
        self.scenario.description().to_owned()
    }

    /// Length of one test, s.
    #[getter]
    fn horizon_s(&self) -> f64 {
        self.scenario.horizon_s()
    }

    /// The monitors' names, in order.
    #[getter]
    fn monitors(&self) -> Vec<String> {
        self.scenario
            .monitors()
            .iter()
            .map(|m| m.name().to_owned())
            .collect()
    }

    /// The monitors that steer no falsifier until they fail (the implicit `offroad`).
    #[getter]
    fn passive_monitors(&self) -> Vec<String> {
        self.scenario.passive_monitors()
    }

    /// The system under test it runs by default.
    #[getter]
    fn sut(&self) -> String {
        self.scenario.sut().name()
    }

    /// The name of the system under test that these arguments choose (the scenario's own
    /// when both are None); ValueError for an unknown built-in, a missing ONNX model, an
    /// empty command or a bad timeout, as a run would raise it.
    #[pyo3(signature = (sut=None, sut_cmd=None, sut_timeout=10.0, sut_fresh=false))]
    fn sut_name(
        &self,
        sut: Option<&str>,
        sut_cmd: Option<Vec<String>>,
        sut_timeout: f64,
        sut_fresh: bool,
    ) -> PyResult<String> {
        Ok(sut_config(sut, sut_cmd, sut_timeout, sut_fresh)?
            .map_or_else(|| self.scenario.sut().name(), |s| s.name()))
    }

    /// What the program loads with but checks or varies less than it seems to.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The parameters as JSON (`[{"name", "domain", "unit"}]`, as in `campaign.json`).
    fn space_json(&self) -> String {
        serde_json::to_string(self.scenario.space().params()).expect("a space serialises")
    }

    /// Runs unit-cube rows (`(n, d)` float64, every parameter in declaration order).
    #[pyo3(signature = (points, seed, jobs=None, sut=None, sut_cmd=None, sut_timeout=10.0, sut_fresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn run_unit(
        &self,
        py: Python<'_>,
        points: PyReadonlyArray2<'_, f64>,
        seed: u64,
        jobs: Option<usize>,
        sut: Option<&str>,
        sut_cmd: Option<Vec<String>>,
        sut_timeout: f64,
        sut_fresh: bool,
    ) -> PyResult<Vec<String>> {
        let (n, d) = (points.shape()[0], points.shape()[1]);
        let values = points
            .as_slice()
            .map_err(|_| value_error("points must be a C-contiguous (n, d) array"))?;
        let points = self.unit_points(values, n, d)?;
        let sut = sut_config(sut, sut_cmd, sut_timeout, sut_fresh)?;
        self.run_points(py, points, sut, jobs, seed)
    }

    /// Runs the tests of CSV text in the parameters' units, read as `paracosm-fuzz --points`
    /// reads a file (`file` names it in messages).
    #[pyo3(signature = (text, file, seed, jobs=None, sut=None, sut_cmd=None, sut_timeout=10.0, sut_fresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn run_csv(
        &self,
        py: Python<'_>,
        text: &str,
        file: &str,
        seed: u64,
        jobs: Option<usize>,
        sut: Option<&str>,
        sut_cmd: Option<Vec<String>>,
        sut_timeout: f64,
        sut_fresh: bool,
    ) -> PyResult<Vec<String>> {
        let set = paracosm::cover::parse_tests(file, text, false, Some(self.scenario.space()))
            .map_err(value_error)?;
        let sut = sut_config(sut, sut_cmd, sut_timeout, sut_fresh)?;
        self.run_points(py, set.points, sut, jobs, seed)
    }
}
