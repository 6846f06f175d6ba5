use paracosm_engine::sut::SutConfig;
use paracosm_engine::WorldSpec;
use paracosm_generators::{Assignment, ParamSpace};
use paracosm_oracles::{CollisionMonitor, DistanceMonitor, Monitor};

use crate::runner::signal;
use crate::ScenarioError;

/// A monitor a scenario asks for, built fresh for each test.
#[derive(Debug, Clone, PartialEq)]
pub enum MonitorSpec {
    /// `CollisionMonitor(v)`: no contact between the ego vehicle and a pedestrian. Robustness:
    /// minimum separation in metres.
    Collision,
    /// `DistanceMonitor(v, minD)`: the ego vehicle travels at least `min_distance_m` metres.
    /// Robustness: `D - minD` in metres.
    Distance {
        /// `minD`, in metres.
        min_distance_m: f64,
    },
}

impl MonitorSpec {
    /// A fresh monitor reading the runner's signals (see [`signal`]).
    pub fn build(&self) -> Box<dyn Monitor> {
        match self {
            MonitorSpec::Collision => Box::new(CollisionMonitor::new(
                "collision",
                signal::EGO_PED_CONTACT,
                signal::EGO_PED_SEPARATION_M,
            )),
            MonitorSpec::Distance { min_distance_m } => Box::new(DistanceMonitor::new(
                "distance",
                signal::EGO_X_M,
                signal::EGO_Z_M,
                *min_distance_m,
            )),
        }
    }
}

/// A parameterised family of tests (paper §3.1, "test configuration"): open parameters, a
/// world template, a system under test, monitors, and a horizon.
#[derive(Debug, Clone)]
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
    /// Builds the world for an assignment of the open parameters.
    pub(crate) template: fn(&Assignment) -> Result<WorldSpec, ScenarioError>,
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
