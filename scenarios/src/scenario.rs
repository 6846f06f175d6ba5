use paracosm_engine::sut::SutConfig;
use std::sync::Arc;

use paracosm_engine::rx::Host;
use paracosm_engine::WorldSpec;
use paracosm_generators::{Assignment, ParamSpace};
use paracosm_oracles::{CollisionMonitor, DistanceMonitor, Monitor, TimeToFailureMonitor};

use crate::runner::signal;
use crate::ScenarioError;

/// A monitor a scenario asks for, built fresh for each test.
#[derive(Debug, Clone, PartialEq)]
pub enum MonitorSpec {
    /// `CollisionMonitor(v)`: no contact between the ego vehicle and a pedestrian or a car.
    /// Robustness: minimum separation in metres.
    Collision {
        /// Key in results files, default `collision`.
        name: String,
    },
    /// `DistanceMonitor(v, minD)`: the ego vehicle travels at least `min_distance_m` metres.
    /// Robustness: `D - minD` in metres.
    Distance {
        /// Key in results files, default `distance`.
        name: String,
        /// `minD`, in metres.
        min_distance_m: f64,
    },
    /// `Stl(formula)`: a signal temporal logic property of the runner's signals
    /// ([`paracosm_oracles::stl`]), judged at time 0 and settled online.
    Stl {
        /// Key in results files, default `stl`.
        name: String,
        /// The formula's text (parsed when the program loads).
        formula: String,
    },
    /// `TimeToFailure(m, minT)`: `m` first fails no earlier than `min_s` seconds.
    /// Robustness in seconds (see [`TimeToFailureMonitor`]).
    TimeToFailure {
        /// Key in results files, default `time_to_failure`.
        name: String,
        /// The wrapped monitor.
        inner: Box<MonitorSpec>,
        /// `minT`, seconds.
        min_s: f64,
    },
}

impl MonitorSpec {
    /// `CollisionMonitor` named `collision`.
    pub fn collision() -> Self {
        MonitorSpec::Collision {
            name: "collision".into(),
        }
    }

    /// `DistanceMonitor` named `distance`.
    pub fn distance(min_distance_m: f64) -> Self {
        MonitorSpec::Distance {
            name: "distance".into(),
            min_distance_m,
        }
    }

    /// A fresh monitor reading the runner's signals (see [`signal`]).
    pub fn build(&self) -> Box<dyn Monitor> {
        match self {
            MonitorSpec::Collision { name } => Box::new(CollisionMonitor::new(
                name,
                signal::EGO_CONTACT,
                signal::EGO_SEPARATION_M,
            )),
            MonitorSpec::Distance {
                name,
                min_distance_m,
            } => Box::new(DistanceMonitor::new(
                name,
                signal::EGO_X_M,
                signal::EGO_Z_M,
                *min_distance_m,
            )),
            MonitorSpec::Stl { name, formula } => Box::new(paracosm_oracles::stl::StlMonitor::new(
                name,
                paracosm_oracles::stl::parse(formula).expect("checked when the program loaded"),
            )),
            MonitorSpec::TimeToFailure { name, inner, min_s } => {
                Box::new(TimeToFailureMonitor::new(name, inner.build(), *min_s))
            }
        }
    }
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
    /// The two parameters of the failure map, `[x axis, y axis]`.
    pub map_axes: [String; 2],
    /// The program text it was loaded from (empty for scenarios written in Rust): part of a
    /// campaign's fingerprint, so a resumed campaign runs the same program.
    pub source: Arc<str>,
    /// Builds the world for an assignment of the open parameters.
    pub(crate) template: Template,
    /// Runs the lambdas of the world's stream graph (Starlark scenarios); `None`: native only.
    pub(crate) lambdas: Option<Arc<dyn Lambdas>>,
}

/// A world template: assignment in, world out.
pub type Template = Arc<dyn Fn(&Assignment) -> Result<WorldSpec, ScenarioError> + Send + Sync>;

/// A source of [`Host`]s for a world's lambdas: each test gets a fresh one (its own heap and
/// evaluator), handed to `f` for the duration of the test.
pub trait Lambdas: Send + Sync {
    /// Calls `f` with a host for one test.
    fn with_host(&self, f: &mut dyn FnMut(&mut dyn Host));
}

impl Scenario {
    /// The concrete world for `assignment` (paper §3.1: a test case closes every open stream).
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for an assignment that lacks a parameter, and
    /// [`ScenarioError::Engine`] when the values give an impossible world.
    pub fn instantiate(&self, assignment: &Assignment) -> Result<WorldSpec, ScenarioError> {
        (self.template)(assignment)
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
