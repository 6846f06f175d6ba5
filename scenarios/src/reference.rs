//! The Rust reference of `pedestrian_crossing.star`: the same study written against the
//! engine directly. The shipped scenario is the Starlark program; this module exists so tests
//! can check that the program gives byte-identical results and benchmarks can measure what the
//! language costs.
//!
//! `pedestrian-crossing`: the paper's "Dynamic Pedestrian Behavior" study (§4.2.2, Figure 9).
//!
//! The ego vehicle drives down a straight two-lane road at 12 m/s under the `aeb` system. A
//! pedestrian waits on the right sidewalk 90 m ahead; when the car comes within the trigger
//! distance it walks across to the far sidewalk at the walking speed. Open parameters: the
//! walking speed `VarInterval(0.5, 10)` m/s and the trigger distance `VarInterval(5, 60)` m.
//! Monitors: no collision, and at least 60 m travelled in the 15 s horizon.

use paracosm_engine::sut::{AebConfig, SutConfig};
use std::sync::Arc;

use paracosm_engine::{Lane, TriggeredPedestrian, WorldSpec};
use paracosm_generators::{Assignment, Param, ParamSpace};

use crate::{real, MonitorSpec, Scenario, ScenarioError};

/// The scenario's name on the command line.
pub const NAME: &str = "pedestrian-crossing";
/// Walking speed of the pedestrian, m/s.
pub const WALKING_SPEED: &str = "walking_speed";
/// Distance between the ego vehicle and the pedestrian's start that starts the crossing, m.
pub const TRIGGER_DISTANCE: &str = "trigger_distance";
/// Walking speed range `[lo, hi)`, m/s (paper Figure 9's x axis).
pub const WALKING_SPEED_RANGE_MPS: (f64, f64) = (0.5, 10.0);
/// Trigger distance range `[lo, hi)`, m (paper Figure 9's y axis).
pub const TRIGGER_DISTANCE_RANGE_M: (f64, f64) = (5.0, 60.0);
/// Test length, s.
pub const HORIZON_S: f64 = 15.0;
/// Where the ego vehicle starts along the road, m.
pub const EGO_START_M: f64 = 10.0;
/// Where the pedestrian crosses along the road, m.
pub const CROSSING_AT_M: f64 = 100.0;
/// `minD` of the distance monitor, m.
pub const MIN_DISTANCE_M: f64 = 60.0;

/// The scenario, ready to run.
pub fn scenario() -> Scenario {
    let space = ParamSpace::new(vec![
        Param::interval(
            WALKING_SPEED,
            WALKING_SPEED_RANGE_MPS.0,
            WALKING_SPEED_RANGE_MPS.1,
            "m/s",
        ),
        Param::interval(
            TRIGGER_DISTANCE,
            TRIGGER_DISTANCE_RANGE_M.0,
            TRIGGER_DISTANCE_RANGE_M.1,
            "m",
        ),
    ])
    .expect("the built-in space is valid");
    Scenario {
        name: NAME.to_owned(),
        description: "a pedestrian crosses in front of the ego vehicle once it comes within a \
                      trigger distance (PARACOSM §4.2.2, Figure 9)"
            .to_owned(),
        space,
        horizon_s: HORIZON_S,
        sut: SutConfig::Aeb(AebConfig::default()),
        monitors: vec![
            MonitorSpec::collision(),
            MonitorSpec::distance(MIN_DISTANCE_M),
            MonitorSpec::implicit_off_road(),
        ],
        map_axes: vec![WALKING_SPEED.to_owned(), TRIGGER_DISTANCE.to_owned()],
        warnings: vec![],
        unused_params: vec![],
        camera_only: vec![],
        worlds: Arc::new(crate::scenario::RustWorlds(world)),
        source: Arc::from(""),
        input_files: Vec::new(),
    }
}

/// The study's world for one assignment (walking speed, m/s; trigger distance, m).
///
/// # Errors
/// [`ScenarioError::MissingParam`] when the assignment lacks either parameter.
pub fn world(a: &Assignment) -> Result<WorldSpec, ScenarioError> {
    Ok(WorldSpec::straight_road(
        200.0,
        EGO_START_M,
        AebConfig::default().cruise.target_speed_mps,
        &[TriggeredPedestrian {
            start: (Lane::SideWalk, CROSSING_AT_M),
            target: (Lane::OppositeSideWalk, CROSSING_AT_M),
            trigger_distance_m: real(a, TRIGGER_DISTANCE)?,
            speed_mps: real(a, WALKING_SPEED)?,
        }],
    )?)
}
