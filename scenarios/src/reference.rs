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

use paracosm_engine::behaviour::{ActorRef, Output};
use paracosm_engine::network::{PieceId, PieceKind};
use paracosm_engine::rx::{Node, Value};
use paracosm_engine::sut::{AebConfig, SutConfig};
use paracosm_engine::{EgoSpec, Lane, PedestrianSpec, VehicleParams};
use paracosm_generators::{Domain, Value as Level};

use crate::scene::{
    LoadError, LoadErrorKind, OverTime, ParamDecl, ParamValue, Scene, Site, TestSettings,
};
use crate::{MonitorSpec, Scenario, ScenarioError};

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
pub const MIN_DISTANCE_M: f64 = 95.0;

/// The scenario, ready to run: [`scene`]'s declarations read as a front end's load reads a
/// program's ([`Scenario::from_scenes`]).
pub fn scenario() -> Scenario {
    Scenario::from_scenes(
        NAME,
        "a pedestrian crosses in front of the ego vehicle once it comes within a trigger \
         distance (PARACOSM §4.2.2, Figure 9)",
        scene,
    )
    .expect("the reference scene declares a valid scenario")
}

/// Where a declaration of this file stands, naming the variable `pedestrian_crossing.star`
/// assigns it to.
fn here(line: u32, variable: &str) -> Site {
    Site {
        file: file!().to_owned(),
        line,
        col: 5,
        variable: Some(variable.to_owned()),
    }
}

/// Declares the study into `scene` (an empty scene whose parameters take the test's values
/// by name), as `pedestrian_crossing.star` does, in plain Rust: the two open parameters, a
/// 200 m two-lane road of friction 0.8, the ego vehicle under `aeb` 10 m along lane 1 at the
/// system's cruise speed, the pedestrian 100 m along from the right sidewalk to the left one,
/// walking once the ego comes within the trigger distance, a collision monitor, a distance
/// monitor (60 m) and a 15 s horizon.
///
/// # Errors
/// [`ScenarioError::Load`] if a location is off the road or a declaration is repeated
/// (neither happens for the study's ranges).
pub fn scene(mut scene: Scene) -> Result<Scene, ScenarioError> {
    let walking_speed = number(
        &mut scene,
        WALKING_SPEED,
        WALKING_SPEED_RANGE_MPS,
        "m/s",
        line!(),
    )?;
    let trigger = number(
        &mut scene,
        TRIGGER_DISTANCE,
        TRIGGER_DISTANCE_RANGE_M,
        "m",
        line!(),
    )?;
    let road = build_road(&mut scene)?;
    place_actors(&mut scene, road, walking_speed, trigger)?;
    scene.add_monitor(MonitorSpec::collision(), here(line!(), "collision"));
    scene.add_monitor(
        MonitorSpec::distance(MIN_DISTANCE_M),
        here(line!(), "distance"),
    );
    scene
        .set_settings(TestSettings {
            site: Some(here(line!(), "test")),
            horizon_s: Some(HORIZON_S),
            map_axes: Some(vec![WALKING_SPEED.to_owned(), TRIGGER_DISTANCE.to_owned()]),
            offroad: None,
        })
        .map_err(|e| worlds(e.to_string()))?;
    Ok(scene)
}

/// A load error of kind [`LoadErrorKind::Worlds`] saying `e`.
fn worlds(e: String) -> ScenarioError {
    ScenarioError::Load(LoadError::new(LoadErrorKind::Worlds, e))
}

/// Declares into `scene` the open parameter `name`, an interval `[lo, hi)` in `unit`,
/// declared at line `line`, and returns its value in this scene.
///
/// # Errors
/// [`ScenarioError::Load`] when the scene gives it a value that is not a number.
fn number(
    scene: &mut Scene,
    name: &str,
    (lo, hi): (f64, f64),
    unit: &str,
    line: u32,
) -> Result<f64, ScenarioError> {
    let decl = ParamDecl {
        name: Some(name.to_owned()),
        domain: Domain::Interval { lo, hi },
        unit: Some(unit.to_owned()),
        over_time: OverTime::Constant,
        site: here(line, name),
    };
    match scene.declare_param(decl).0 {
        ParamValue::Level(Level::Real(x)) => Ok(x),
        other => Err(worlds(format!(
            "{name}: a number was expected, got {other:?}"
        ))),
    }
}

/// Sets `scene`'s environment (light 0.5, no fog) and adds the road: one straight piece
/// `r`, 200 m long with two lanes, of friction 0.8.
///
/// # Errors
/// [`ScenarioError::Load`] if the environment or the road is declared twice.
fn build_road(scene: &mut Scene) -> Result<PieceId, ScenarioError> {
    let light = scene.push(Node::Const(Value::Num(0.5)));
    let fog = scene.push(Node::Const(Value::Num(0.0)));
    scene
        .set_environment(light, fog, here(line!(), "w"))
        .map_err(|e| worlds(e.to_string()))?;
    let friction = scene.push(Node::Const(Value::Num(0.8)));
    scene
        .add_road(
            |n| {
                n.add(
                    "r",
                    PieceKind::Segment {
                        length_m: 200.0,
                        lanes: 2,
                        friction: 0.8,
                    },
                )
            },
            friction,
            here(line!(), "r"),
        )
        .map_err(|e| worlds(e.to_string()))
}

/// Declares and places the actors on `road`: the ego under `aeb` on lane 1,
/// [`EGO_START_M`] along, at the system's cruise speed; the pedestrian at [`CROSSING_AT_M`]
/// from the right sidewalk to the left one, walking at `walking_speed` (m/s) once the ego
/// comes within `trigger` (m).
///
/// # Errors
/// [`ScenarioError::Load`] if a location is off the road or an actor is placed twice.
fn place_actors(
    scene: &mut Scene,
    road: PieceId,
    walking_speed: f64,
    trigger: f64,
) -> Result<(), ScenarioError> {
    let on = |scene: &Scene, lane, at_m| {
        scene
            .roads()
            .on_lane(road, lane, at_m)
            .map_err(|e| worlds(e.to_string()))
    };
    let start = on(scene, Lane::Driving(1), EGO_START_M)?;
    let ego = scene.declare_ego("v".to_owned(), here(line!(), "v"));
    let ego_pos = scene.probe(ego, Output::Pos);
    let pedestrian = scene.declare_pedestrian("p".to_owned(), here(line!(), "p"));
    let from = on(scene, Lane::SideWalk, CROSSING_AT_M)?.pos_m;
    let to = on(scene, Lane::OppositeSideWalk, CROSSING_AT_M)?.pos_m;
    let dist = scene.push(Node::Const(Value::Num(trigger)));
    let speed = scene.push(Node::Const(Value::Num(walking_speed)));
    let ActorRef::Pedestrian(handle) = pedestrian else {
        unreachable!("declare_pedestrian declares a pedestrian")
    };
    scene
        .graph_mut()
        .pedestrian(handle, from, to, ego_pos, dist);
    let aeb = AebConfig::default();
    scene
        .place_ego(
            EgoSpec {
                start,
                initial_speed_mps: aeb.cruise.target_speed_mps,
                vehicle: VehicleParams::default(),
                route: vec![],
                set_speed_mps: None,
                scripted: false,
            },
            SutConfig::Aeb(aeb),
        )
        .map_err(|e| worlds(e.to_string()))?;
    scene
        .place_pedestrian(
            pedestrian,
            PedestrianSpec {
                start: from,
                target: to,
                speed,
                initial_speed_mps: 0.0,
                name: "Pedestrian p".to_owned(),
            },
        )
        .map_err(|e| worlds(e.to_string()))?;
    Ok(())
}
