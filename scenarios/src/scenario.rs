use paracosm_engine::sut::SutConfig;
use std::sync::Arc;

use crate::scene::{LoadError, MonitorSpec, Scene};
use crate::ScenarioError;
use paracosm_engine::rx::Host;
use paracosm_engine::WorldSpec;
use paracosm_generators::{Assignment, ParamSpace};

/// Something in a program that runs but checks or varies less than it seems to (a program
/// with no monitor, an open parameter no object reads...): printed once per campaign, and an
/// error with `paracosm-fuzz --deny-warnings`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// Where, `file:line:col`.
    pub at: String,
    /// What, in one sentence.
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "warning: {}\n --> {}", self.message, self.at)
    }
}

/// A file a scenario read, as it names it, and the SHA-256 of its bytes (64 hex digits; an
/// OpenSCENARIO file's as read: UTF-8 text without a byte-order mark).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InputFile {
    /// The path as the program writes it (relative to the program's folder); for an
    /// OpenSCENARIO campaign relative to the folder of the file it names.
    pub path: String,
    /// SHA-256 of the file's bytes (or text, above), lowercase hex.
    pub sha256: String,
}

/// An open parameter that only a camera can see (the light, a colour): it affects the ego
/// only when the system under test has a camera.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CameraOnly {
    /// The parameter's name.
    pub param: String,
    /// Where it was declared, `file:line:col`.
    pub at: String,
    /// What it sets, e.g. `the light` or `the colour of Car declared at f.star:9:8`.
    pub sets: String,
}

/// A parameterised family of tests (paper §3.1, "test configuration"): open parameters, a
/// world template, a system under test, monitors, and a horizon.
#[derive(Clone)]
pub struct Scenario {
    /// Name, e.g. `pedestrian-crossing`.
    pub name: String,
    /// One-line description.
    pub description: String,
    /// The open parameters.
    pub space: ParamSpace,
    /// Length of one test, in seconds of simulated time.
    pub horizon_s: f64,
    /// The system under test the scenario runs by default.
    pub sut: SutConfig,
    /// The monitors, evaluated on every test.
    pub monitors: Vec<MonitorSpec>,
    /// The parameters of the failure map: none (a scenario without open parameters gets no
    /// map), one (a strip plot), or two (`[x axis, y axis]`). Continuous or discrete.
    pub map_axes: Vec<String>,
    /// Whether a campaign's failure map is drawn over the two parameters its triage ranks
    /// most relevant (when it ranks two) rather than [`Scenario::map_axes`], which are then
    /// the fallback: an OpenSCENARIO campaign, whose file names no axes.
    pub map_axes_by_relevance: bool,
    /// What the program loads with but checks or varies less than it seems to, whatever the
    /// system under test (see [`Scenario::warnings_for`] for the rest).
    pub warnings: Vec<Warning>,
    /// The coordinates of the space that no object reads (by name, as in
    /// [`ParamSpace::params`]): sampled and recorded, but left out of coverage.
    pub unused_params: Vec<String>,
    /// The open parameters that only a camera sees.
    pub camera_only: Vec<CameraOnly>,
    /// The vehicle the system under test drives, as the summary names it, when the
    /// scenario's file chose it among its entities (OpenSCENARIO: `Ego, 5 × 2 × 1.8 m`);
    /// `None` for a program's `AutonomousVehicle`.
    pub ego: Option<String>,
    /// The program text it was loaded from (empty for scenarios written in Rust): part of a
    /// campaign's fingerprint, so a resumed campaign runs the same program.
    pub source: Arc<str>,
    /// The files the scenario read (its OpenDRIVE maps; an OpenSCENARIO scenario's variation
    /// file, scenario and catalogs), with their SHA-256: part of a campaign's fingerprint, so
    /// `--resume` refuses a campaign whose map or catalog has changed.
    pub input_files: Vec<InputFile>,
    /// Builds each test's world.
    pub(crate) worlds: Arc<dyn Worlds>,
}

impl Scenario {
    /// Builds the world of the test `assignment` and calls `run` with it and the host that
    /// runs its lambdas, for a caller that steps the test's [`paracosm_engine::Simulation`]
    /// itself (to read every actor's outputs each step, as `tests/motion.rs` does).
    ///
    /// # Errors
    /// As [`Worlds::with_scene`], and [`ScenarioError::Load`] when the test's scene builds
    /// no world ([`Scene::world`]).
    pub fn with_world(
        &self,
        assignment: &Assignment,
        run: &mut dyn FnMut(&WorldSpec, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        let mut built = Ok(());
        self.worlds.with_scene(assignment, &mut |scene, host| {
            built = world_of(scene).map(|spec| run(&spec, host));
        })?;
        built
    }

    /// The scenario with its scenes built by `worlds` instead: for a library user's own
    /// scene builder (or a test's), keeping the space, monitors and system under test.
    pub fn with_worlds(mut self, worlds: Arc<dyn Worlds>) -> Self {
        self.worlds = worlds;
        self
    }
}

/// The engine's world of a test's scene.
///
/// # Errors
/// [`ScenarioError::Load`] naming the test's values as the cause.
pub(crate) fn world_of(scene: &Scene) -> Result<WorldSpec, ScenarioError> {
    scene.world().map_err(|e| {
        ScenarioError::Load(LoadError {
            message: format!("this test's values build no world: {}", e.message),
            ..e
        })
    })
}

/// Builds the scene of each test (paper §3.1: a test case closes every open stream).
pub trait Worlds: Send + Sync {
    /// Builds the scene for `assignment` and calls `run` with it and a host for its lambdas
    /// (a Starlark program's: each test gets its own evaluation of the program, heap and
    /// evaluator), for the duration of the test.
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for an assignment that lacks a parameter;
    /// [`ScenarioError::Load`] or [`ScenarioError::Engine`] when these values give an
    /// impossible scene.
    fn with_scene(
        &self,
        assignment: &Assignment,
        run: &mut dyn FnMut(&Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError>;
}

/// Scenes declared by a Rust function, whose streams call no lambda: it receives an empty
/// scene whose open parameters take the test's values by name ([`Scene::for_assignment`])
/// and declares the test into it.
pub struct RustWorlds(pub SceneFn);

/// A Rust function that declares a scenario's scene into the empty scene it receives.
pub type SceneFn = fn(Scene) -> Result<Scene, ScenarioError>;

impl Worlds for RustWorlds {
    fn with_scene(
        &self,
        assignment: &Assignment,
        run: &mut dyn FnMut(&Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        let scene = (self.0)(Scene::for_assignment(assignment))?;
        run(&scene, &mut paracosm_engine::rx::NoHost);
        Ok(())
    }
}

impl Scenario {
    /// The scenario whose tests `build` declares, in plain Rust: its space, monitors, horizon,
    /// system under test and failure map are read from the scene `build` declares with
    /// representative values, as a front end's load does (the default `OffRoadMonitor` is
    /// added unless the scene judges leaving the road or opts out).
    ///
    /// # Errors
    /// What `build` returns; [`ScenarioError::Language`] for an open parameter without a
    /// name, one that varies over time (a Rust scene declares constant parameters), or a
    /// scene without an ego vehicle; [`ScenarioError::Space`] for an invalid space.
    pub fn from_scenes(
        name: &str,
        description: &str,
        build: SceneFn,
    ) -> Result<Self, ScenarioError> {
        let probe = build(Scene::new(None))?;
        let mut params = Vec::new();
        for d in probe.params() {
            let bad = |why: &str| {
                ScenarioError::Language(format!("the parameter declared at {}: {why}", d.site))
            };
            let name = d.name.as_deref().ok_or_else(|| bad("it has no name"))?;
            if d.over_time != crate::scene::OverTime::Constant {
                return Err(bad(
                    "it varies over time, which a Rust scene does not declare",
                ));
            }
            params.push(match &d.domain {
                paracosm_generators::Domain::Interval { lo, hi } => {
                    paracosm_generators::Param::interval(
                        name,
                        *lo,
                        *hi,
                        d.unit.as_deref().unwrap_or(""),
                    )
                }
                paracosm_generators::Domain::Levels(levels) => {
                    paracosm_generators::Param::levels(name, levels.clone())
                }
            });
        }
        let space = ParamSpace::new(params)?;
        let mut monitors = probe.monitor_specs();
        if probe.settings().offroad.unwrap_or(true)
            && !monitors.iter().any(MonitorSpec::judges_off_road)
        {
            monitors.push(MonitorSpec::implicit_off_road());
        }
        let sut = probe
            .ego()
            .map(|(_, sut)| sut.clone())
            .ok_or_else(|| ScenarioError::Language("the scene places no ego vehicle".into()))?;
        let map_axes = probe.settings().map_axes.clone().unwrap_or_else(|| {
            space
                .params()
                .iter()
                .take(2)
                .map(|p| p.name.clone())
                .collect()
        });
        Ok(Scenario {
            name: name.to_owned(),
            description: description.to_owned(),
            space,
            horizon_s: probe.horizon_s(),
            sut,
            monitors,
            map_axes,
            map_axes_by_relevance: false,
            warnings: vec![],
            unused_params: vec![],
            camera_only: vec![],
            ego: None,
            source: Arc::from(""),
            input_files: Vec::new(),
            worlds: Arc::new(RustWorlds(build)),
        })
    }
}

impl Scenario {
    /// The warnings of this scenario when it tests `sut`: [`Scenario::warnings`], and for a
    /// system without a camera every parameter that only a camera sees.
    pub fn warnings_for(&self, sut: &SutConfig) -> Vec<Warning> {
        let mut out = self.warnings.clone();
        if sut.has_camera() == Some(false) {
            for c in &self.camera_only {
                out.push(Warning {
                    at: c.at.clone(),
                    message: format!(
                        "`{}` sets {}, which only a camera sees, and the system under test `{}` \
                         has none: it is sampled and counted in coverage but cannot affect the \
                         ego",
                        c.param,
                        c.sets,
                        sut.name()
                    ),
                });
            }
        }
        out
    }

    /// The monitors that judge every test but do not steer a falsifier until they fail: the
    /// default `OffRoadMonitor` (its margin to the road's edge, about 1.75 m in the middle of
    /// a lane, would otherwise flatten the cost that falsifiers descend). A record's
    /// falsification cost is the smallest robustness over the other monitors, and over these
    /// only where they are `<= 0`.
    pub fn passive_monitors(&self) -> Vec<String> {
        self.monitors
            .iter()
            .filter(|m| matches!(m, MonitorSpec::OffRoad { implicit: true, .. }))
            .map(|m| m.name().to_owned())
            .collect()
    }

    /// The concrete world for `assignment` (paper §3.1: a test case closes every open stream).
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for an assignment that lacks a parameter, and
    /// [`ScenarioError::Engine`] when the values give an impossible world.
    pub fn instantiate(&self, assignment: &Assignment) -> Result<WorldSpec, ScenarioError> {
        let mut out = None;
        self.worlds
            .with_scene(assignment, &mut |scene, _| out = Some(world_of(scene)))?;
        out.ok_or_else(|| ScenarioError::Language("no world was built".into()))?
    }
}

impl std::fmt::Debug for Scenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scenario")
            .field("name", &self.name)
            .field("space", &self.space)
            .field("horizon_s", &self.horizon_s)
            .field("sut", &self.sut)
            .field("monitors", &self.monitors)
            .finish_non_exhaustive()
    }
}

/// Why a `Monitor` (`bools = false`, it reads numbers) or an `Assert` (`bools = true`) cannot
/// judge `value`; `None` when it can. A bool is not a number, nor a number a bool: nothing is
/// read as 0 or 1 in place of the kind the monitor judges.
pub(crate) fn judged_kind_error(value: &paracosm_engine::rx::Value, bools: bool) -> Option<String> {
    use paracosm_engine::rx::{describe, Value};
    match (value, bools) {
        (Value::Num(_), false) | (Value::Bool(_), true) => None,
        (Value::Bool(_), false) => Some(format!(
            "Monitor reads numbers, and its stream carried {}: a bool is not a number here (for \
             a stream of bools, use Assert)",
            describe(value)
        )),
        (Value::Num(_), true) => Some(format!(
            "Assert reads bools, and its stream carried {}: a number is not a bool here (write \
             the condition meant, e.g. `.map(lambda x: x > 0)`)",
            describe(value)
        )),
        (_, false) => Some(format!(
            "Monitor reads numbers, and its stream carried {}",
            describe(value)
        )),
        (_, true) => Some(format!(
            "Assert reads bools, and its stream carried {}",
            describe(value)
        )),
    }
}
