use paracosm_engine::sut::SutConfig;
use std::sync::Arc;

use crate::front_end::{FrontEnd, RustScenes, SceneFn};
use crate::scene::{LoadError, LoadErrorKind, MonitorSpec, Scene};
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
/// world template, a system under test, monitors, and a horizon. Built by one constructor,
/// [`Scenario::new`], from a [`FrontEnd`]; read through its accessors.
#[derive(Clone)]
pub struct Scenario {
    name: String,
    description: String,
    space: ParamSpace,
    horizon_s: f64,
    sut: SutConfig,
    monitors: Vec<MonitorSpec>,
    map_axes: Vec<String>,
    map_axes_by_relevance: bool,
    warnings: Vec<Warning>,
    unused_params: Vec<String>,
    camera_only: Vec<CameraOnly>,
    ego: Option<String>,
    source: Arc<str>,
    input_files: Vec<InputFile>,
    front_end: Arc<dyn FrontEnd>,
}

impl Scenario {
    /// The scenario of `front_end`: its space, source and findings as the front end gives
    /// them, and its monitors, system under test, horizon and failure-map axes read from the
    /// scene of the declared values ([`FrontEnd::with_scene`] with `None`) by
    /// [`scene_contract`], as every test's are ([`Scenario::run`] judges a test with its own
    /// scene's monitors).
    ///
    /// # Errors
    /// What the front end's scene returns; [`ScenarioError::Load`] (kind
    /// [`LoadErrorKind::Settings`]) for failure-map axes that are not parameters, or a monitor
    /// named as the default `OffRoadMonitor`; [`ScenarioError::Language`] for a scene without
    /// an ego vehicle.
    pub fn new(front_end: Arc<dyn FrontEnd>) -> Result<Self, ScenarioError> {
        let source = front_end.source();
        let space = front_end.space().clone();
        let mut contract = None;
        front_end.with_scene(None, &mut |scene, _| {
            contract = Some(scene_contract(scene, &space, &source.name));
        })?;
        let contract = contract
            .ok_or_else(|| ScenarioError::Language("the front end built no scene".into()))??;
        let findings = front_end.findings();
        Ok(Scenario {
            name: source.name,
            description: source.description,
            space,
            horizon_s: contract.horizon_s,
            sut: contract.sut,
            monitors: contract.monitors,
            map_axes: contract.map_axes,
            map_axes_by_relevance: source.map_axes_by_relevance,
            warnings: findings.warnings,
            unused_params: findings.unused_params,
            camera_only: findings.camera_only,
            ego: source.ego,
            source: source.text,
            input_files: source.files,
            front_end,
        })
    }

    /// The scenario whose tests `build` declares, in plain Rust ([`RustScenes`]): its space,
    /// monitors, horizon, system under test and failure map are read from the scene `build`
    /// declares with representative values, as for any front end ([`Scenario::new`]).
    ///
    /// # Errors
    /// As [`RustScenes::new`] and [`Scenario::new`].
    pub fn from_scenes(
        name: &str,
        description: &str,
        build: SceneFn,
    ) -> Result<Self, ScenarioError> {
        Scenario::new(Arc::new(RustScenes::new(name, description, build)?))
    }

    /// Name, e.g. `pedestrian-crossing`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// One-line description.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// The open parameters.
    pub fn space(&self) -> &ParamSpace {
        &self.space
    }

    /// Length of one test, in seconds of simulated time, in `(0, ∞)`.
    pub fn horizon_s(&self) -> f64 {
        self.horizon_s
    }

    /// The system under test the scenario runs: the one its scenes place, unless
    /// [`Scenario::set_sut`] chose another.
    pub fn sut(&self) -> &SutConfig {
        &self.sut
    }

    /// Runs the scenario's tests with `sut` instead of the system its scenes place (the
    /// command line's `--sut`, a learned model).
    pub fn set_sut(&mut self, sut: SutConfig) {
        self.sut = sut;
    }

    /// The monitors of the declared values' scene ([`scene_contract`]), the default
    /// `OffRoadMonitor` included; each test is judged by its own scene's.
    pub fn monitors(&self) -> &[MonitorSpec] {
        &self.monitors
    }

    /// The parameters of the failure map: none (a scenario without open parameters gets no
    /// map), one (a strip plot), or two (`[x axis, y axis]`). Continuous or discrete.
    pub fn map_axes(&self) -> &[String] {
        &self.map_axes
    }

    /// Whether a campaign's failure map is drawn over the two parameters its triage ranks
    /// most relevant (when it ranks two) rather than [`Scenario::map_axes`], which are then
    /// the fallback: an OpenSCENARIO campaign, whose file names no axes.
    pub fn map_axes_by_relevance(&self) -> bool {
        self.map_axes_by_relevance
    }

    /// What the scenario loads with but checks or varies less than it seems to, whatever
    /// the system under test (see [`Scenario::warnings_for`] for the rest).
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The coordinates of the space that no object reads (by name, as in
    /// [`ParamSpace::params`]): sampled and recorded, but left out of coverage.
    pub fn unused_params(&self) -> &[String] {
        &self.unused_params
    }

    /// The open parameters that only a camera sees.
    pub fn camera_only(&self) -> &[CameraOnly] {
        &self.camera_only
    }

    /// The vehicle the system under test drives, as the summary names it, when the
    /// scenario's file chose it among its entities (OpenSCENARIO: `Ego, 5 × 2 × 1.8 m`);
    /// `None` for a program's `AutonomousVehicle`.
    pub fn ego(&self) -> Option<&str> {
        self.ego.as_deref()
    }

    /// The program text it was loaded from (empty for scenarios written in Rust): part of a
    /// campaign's fingerprint, so a resumed campaign runs the same program.
    pub fn source(&self) -> &Arc<str> {
        &self.source
    }

    /// The files the scenario read (its OpenDRIVE maps; an OpenSCENARIO scenario's variation
    /// file, scenario and catalogs), with their SHA-256: part of a campaign's fingerprint, so
    /// `--resume` refuses a campaign whose map or catalog has changed.
    pub fn input_files(&self) -> &[InputFile] {
        &self.input_files
    }

    /// The front end that builds each test's scene.
    pub fn front_end(&self) -> &Arc<dyn FrontEnd> {
        &self.front_end
    }

    /// Builds the scene of the test `assignment` and calls `run` with it and the host that
    /// runs its lambdas ([`FrontEnd::with_scene`]).
    ///
    /// # Errors
    /// As [`FrontEnd::with_scene`].
    pub fn with_scene(
        &self,
        assignment: &Assignment,
        run: &mut dyn FnMut(&Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        self.front_end.with_scene(Some(assignment), run)
    }

    /// Builds the world of the test `assignment` and calls `run` with it and the host that
    /// runs its lambdas, for a caller that steps the test's [`paracosm_engine::Simulation`]
    /// itself (to read every actor's outputs each step, as `tests/motion.rs` does).
    ///
    /// # Errors
    /// As [`FrontEnd::with_scene`], and [`ScenarioError::Load`] when the test's scene builds
    /// no world ([`Scene::world`]).
    pub fn with_world(
        &self,
        assignment: &Assignment,
        run: &mut dyn FnMut(&WorldSpec, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        let mut built = Ok(());
        self.with_scene(assignment, &mut |scene, host| {
            built = world_of(scene).map(|spec| run(&spec, host));
        })?;
        built
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

/// What a scene says of how its test is judged: read by [`Scenario::new`] from the declared
/// values' scene and by the runner from each test's.
#[derive(Debug, Clone)]
pub struct SceneContract {
    /// The scene's monitors, then the default `OffRoadMonitor` unless the scene judges
    /// leaving the road or opts out (`test(offroad = False)`).
    pub monitors: Vec<MonitorSpec>,
    /// The failure map's axes: the scene's settings', else the space's first two
    /// parameters.
    pub map_axes: Vec<String>,
    /// The test's length, s.
    pub horizon_s: f64,
    /// The system under test the scene places.
    pub sut: SutConfig,
}

/// The monitors that judge a test of `scene`: its own, then the default `OffRoadMonitor`
/// ([`MonitorSpec::implicit_off_road`]) unless one judges leaving the road or the settings
/// opt out.
///
/// # Errors
/// [`LoadError`] of kind [`LoadErrorKind::Settings`] naming the monitor's place: a monitor
/// named as the default one, which would then be added beside it. `file` names the place
/// when the scene has no site for it.
pub fn monitors_of(scene: &Scene, file: &str) -> Result<Vec<MonitorSpec>, LoadError> {
    let mut monitors = scene.monitor_specs();
    let has_off_road = monitors.iter().any(MonitorSpec::judges_off_road);
    if scene.settings().offroad.unwrap_or(true) && !has_off_road {
        let implicit = MonitorSpec::implicit_off_road();
        if let Some(k) = monitors.iter().position(|m| m.name() == implicit.name()) {
            let at = scene
                .monitors()
                .nth(k)
                .map_or(file.to_owned(), |(_, s)| s.to_string());
            return Err(LoadError::new(
                LoadErrorKind::Settings,
                format!(
                    "error: a monitor is named `{}`, the name of the default OffRoadMonitor: \
                     rename it, declare OffRoadMonitor(v) yourself, or opt out with \
                     test(offroad = False)\n --> {at}",
                    implicit.name()
                ),
            ));
        }
        monitors.push(implicit);
    }
    Ok(monitors)
}

/// How `scene` is judged ([`SceneContract`]), its failure-map axes checked against `space`.
///
/// # Errors
/// As [`monitors_of`]; [`LoadErrorKind::Settings`] for axes that name one parameter twice
/// or a name that is not a parameter of `space`; [`ScenarioError::Language`] for a scene
/// without an ego vehicle.
pub fn scene_contract(
    scene: &Scene,
    space: &ParamSpace,
    file: &str,
) -> Result<SceneContract, ScenarioError> {
    let monitors = monitors_of(scene, file)?;
    let map_axes = map_axes_of(scene, space, file)?;
    let sut = scene
        .ego()
        .map(|(_, sut)| sut.clone())
        .ok_or_else(|| ScenarioError::Language("the scene places no ego vehicle".into()))?;
    Ok(SceneContract {
        monitors,
        map_axes,
        horizon_s: scene.horizon_s(),
        sut,
    })
}

/// The failure map's axes of `scene`: its settings' (`test(map = ...)`), checked against
/// `space`, else the space's first two parameters.
///
/// # Errors
/// [`LoadErrorKind::Settings`] for axes that name one parameter twice or a name that is not
/// a parameter of `space`, at the settings' site (else `file`).
pub fn map_axes_of(
    scene: &Scene,
    space: &ParamSpace,
    file: &str,
) -> Result<Vec<String>, LoadError> {
    let settings = |message: String| LoadError::new(LoadErrorKind::Settings, message);
    // Where `test(map=)` was given, else the scenario's file.
    let test_at = || {
        let site = scene.settings().site.as_ref();
        site.map_or(file.to_owned(), ToString::to_string)
    };
    let Some(axes) = &scene.settings().map_axes else {
        return Ok(space
            .params()
            .iter()
            .take(2)
            .map(|p| p.name.clone())
            .collect());
    };
    if let [a, b] = &axes[..] {
        if a == b {
            return Err(settings(format!(
                "error: test(map=...) names `{a}` twice: a failure map needs two different \
                 parameters\n --> {}",
                test_at(),
            )));
        }
    }
    for a in axes {
        if space.param(a).is_none() {
            let known: Vec<&str> = space.params().iter().map(|p| p.name.as_str()).collect();
            return Err(settings(format!(
                "error: test(map=...) names `{a}`, which is not a parameter (the parameters: \
                 {})\n --> {}",
                if known.is_empty() {
                    "none".to_owned()
                } else {
                    known.join(", ")
                },
                test_at(),
            )));
        }
    }
    Ok(axes.clone())
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
        self.with_scene(assignment, &mut |scene, _| out = Some(world_of(scene)))?;
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
