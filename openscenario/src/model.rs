//! The typed model of an OpenSCENARIO scenario as paracosm reads it (OpenSCENARIO 1.3 User
//! Guide: "Entities", "Storyboard", "Positions", "Actions", "Conditions"). Every value is
//! resolved (parameters and expressions evaluated); every entity reference is an index into
//! [`Scenario::entities`]; every item keeps where it was written.
//!
//! Units as the standard's: metres, seconds, m/s, m/s², radians; positions in the map's
//! inertial frame (x east, y north, heading counter-clockwise from x).

use crate::error::Pos;
use crate::params::{ParamDecl, Scope};
use crate::Value;

/// An item with where it was written.
#[derive(Debug, Clone, PartialEq)]
pub struct Located<T> {
    /// The element.
    pub pos: Pos,
    /// What it holds.
    pub item: T,
}

/// Something read but not honoured as written, said once at load (a warning).
#[derive(Debug, Clone, PartialEq)]
pub struct Note {
    /// The element.
    pub pos: Pos,
    /// What is not honoured, and what paracosm does instead.
    pub text: String,
}

/// A scenario file, resolved for one assignment of its parameters.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The file.
    pub file: String,
    /// `FileHeader`'s `revMajor.revMinor` (1.0 to 1.3).
    pub version: (u32, u32),
    /// Whether it is written for CARLA's scenario_runner: its `FileHeader` description
    /// starts with `CARLA:`, as every scenario and catalog of scenario_runner's does, or the
    /// reader is told so (`--carla`, [`crate::FileSet::as_carla`]). CARLA
    /// reads some elements its own way (an `ActivateControllerAction` on a vehicle with no
    /// controller starts CARLA's autopilot).
    pub carla: bool,
    /// The declared parameters (in order) and the value each had.
    pub params: Vec<(ParamDecl, Value)>,
    /// The scope they were evaluated in (for checking other values against their
    /// constraint groups, [`Scope::check_constraints`]).
    pub scope: Scope,
    /// `RoadNetwork/LogicFile`'s path, resolved against the scenario's folder.
    pub road_network: Option<Located<String>>,
    /// The scenario objects.
    pub entities: Vec<Entity>,
    /// `Init`'s private actions: (entity, action).
    pub init: Vec<(usize, NamedAction)>,
    /// `Init`'s global actions (environment, parameter and variable actions), in order.
    pub init_global: Vec<NamedAction>,
    /// `VariableDeclarations` (OpenSCENARIO 1.2): each variable's name, type and initial
    /// value, in order. Unlike a parameter, a variable's value changes while a test runs
    /// (`VariableSetAction`, `VariableModifyAction`) and `VariableCondition` reads it.
    pub variables: Vec<(String, crate::params::ParamType, Value)>,
    /// The stories.
    pub stories: Vec<Story>,
    /// The storyboard's stop trigger.
    pub stop: Option<Trigger>,
    /// What was read but is not honoured as written.
    pub notes: Vec<Note>,
    /// Each orientation with a pitch or roll other than 0 (a bicycle that falls over, a
    /// pedestrian lying down): the storyboard moves its entity's position and heading as
    /// written, and a campaign refuses it, since paracosm's bodies stand upright on flat
    /// roads (their footprint would change).
    pub tilts: Vec<Note>,
}

/// What kind of object an entity is.
#[derive(Debug, Clone, PartialEq)]
pub enum EntityKind {
    /// A `Vehicle` with its `vehicleCategory` (`car`, `truck`, `bus`, `bicycle`, ...).
    Vehicle(String),
    /// A `Pedestrian` with its `pedestrianCategory` (`pedestrian`, `wheelchair`, `animal`).
    Pedestrian(String),
    /// A `MiscObject` with its `miscObjectCategory`.
    MiscObject(String),
}

/// The standard's `ObjectType`s of the scenario's own entities, as
/// [`EntityKind::object_type`] names them (`external`, an object outside the scenario, is not
/// one).
pub const OBJECT_TYPES: [&str; 3] = ["vehicle", "pedestrian", "miscellaneous"];

impl EntityKind {
    /// The standard's `ObjectType` of an entity of this kind: `vehicle`, `pedestrian` or
    /// `miscellaneous` (what a `CollisionCondition`'s `ByType` names).
    pub fn object_type(&self) -> &'static str {
        match self {
            EntityKind::Vehicle(_) => "vehicle",
            EntityKind::Pedestrian(_) => "pedestrian",
            EntityKind::MiscObject(_) => "miscellaneous",
        }
    }
}

/// A scenario object.
#[derive(Debug, Clone, PartialEq)]
pub struct Entity {
    /// Its name, unique in the file.
    pub name: String,
    /// What it is.
    pub kind: EntityKind,
    /// Bounding box `[length, width, height]`, m.
    pub dimensions_m: [f64; 3],
    /// Bounding box centre in the entity's frame `[x, y, z]`, m (x forward from the rear
    /// axle, the standard's reference point for vehicles).
    pub centre_m: [f64; 3],
    /// Where its bounding box's `Dimensions` are written (in a catalog file for a catalog
    /// entry).
    pub box_pos: Pos,
    /// Its `ObjectController`s' names (their own `name`, else their controller's), in the
    /// file's order
    /// (OpenSCENARIO 1.2 allows several; an `ActivateControllerAction` names one by
    /// `objectControllerRef`, else the first is meant). Empty: none.
    pub controllers: Vec<String>,
    /// Its `Performance`: the limits on the speed changes the storyboard makes it perform.
    pub performance: Performance,
    /// Where it is declared.
    pub pos: Pos,
    /// Its `TrailerHitch`'s `dx`: where a trailer is hitched to it, m ahead of its reference
    /// point (negative behind it); `None` when it has no hitch and tows nothing.
    pub hitch_dx_m: Option<f64>,
    /// Its `TrailerCoupler`'s `dx`: where it is coupled to a vehicle that tows it, m ahead
    /// of its reference point; `None` when it is no trailer.
    pub coupler_dx_m: Option<f64>,
    /// esmini's `refpoint_x_offset` property of a vehicle: its reference point is this far
    /// ahead of its rear axle, m (a car driven by its front axle). Its body trails the
    /// reference point as a rear axle trails its front one: each step it faces from where
    /// its rear axle was to where its reference point is (esmini's `ScenarioEngine::step`).
    /// [`Entity::centre_m`] is already taken from the reference point, as esmini moves the
    /// box. `None`: the reference point is the rear axle, as the standard has it.
    pub refpoint_dx_m: Option<f64>,
    /// The entity it tows from the start (an index into [`Scenario::entities`]): its
    /// `Trailer`, written in it (read as an entity of its own, named as esmini names it, the
    /// tow's name and `+`) or a `TrailerRef` to another entity. The trailer is pulled by its
    /// hitch as esmini pulls it ([`Entity::hitch_dx_m`], [`Entity::coupler_dx_m`]): its
    /// coupler stays at the tow's hitch and it turns towards it.
    pub trailer: Option<usize>,
}

/// A vehicle's `Performance` (OpenSCENARIO 1.3, `Performance`), as esmini applies it to the
/// `SpeedAction`s of the entities its storyboard moves: the target speed at most
/// `max_speed_mps` in magnitude, and a transition's change of speed per step within
/// `[−max_deceleration_mps2, max_acceleration_mps2]` (`LongSpeedAction::Step`). Pedestrians
/// and miscellaneous objects have none (unbounded; esmini gives a miscellaneous object a
/// `maxSpeed` of 0, so that its speed actions do not move it: paracosm moves it as they say).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Performance {
    /// `maxSpeed`, m/s (`> 0`).
    pub max_speed_mps: f64,
    /// `maxAcceleration`, m/s² (`> 0`).
    pub max_acceleration_mps2: f64,
    /// `maxDeceleration`, m/s² (`> 0`, a magnitude).
    pub max_deceleration_mps2: f64,
}

impl Performance {
    /// No limits: every value infinite.
    pub const UNBOUNDED: Performance = Performance {
        max_speed_mps: f64::INFINITY,
        max_acceleration_mps2: f64::INFINITY,
        max_deceleration_mps2: f64::INFINITY,
    };
    /// esmini's defaults for a vehicle whose `Performance` does not give a value: 100 m/s,
    /// 10 m/s², 10 m/s² (`Vehicle::Vehicle` in esmini's `Entities.cpp`).
    pub const VEHICLE_DEFAULT: Performance = Performance {
        max_speed_mps: 100.0,
        max_acceleration_mps2: 10.0,
        max_deceleration_mps2: 10.0,
    };
}

/// A distance action's `DynamicConstraints` as written: each limit is `> 0`. For a
/// `LongitudinalDistanceAction`, one left out is the entity's [`Performance`] value (a rate:
/// unbounded), and one above it is cut to it, as esmini's `parseDynamicConstraints` reads
/// them; for a `LateralDistanceAction`, one left out is unbounded and one above the
/// entity's `Performance` is taken as written (esmini warns and accepts it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DistanceConstraints {
    /// `maxAcceleration`, m/s².
    pub max_acceleration_mps2: Option<f64>,
    /// `maxDeceleration`, m/s² (a magnitude).
    pub max_deceleration_mps2: Option<f64>,
    /// `maxAccelerationRate`, m/s³.
    pub max_acceleration_rate_mps3: Option<f64>,
    /// `maxDecelerationRate`, m/s³ (a magnitude).
    pub max_deceleration_rate_mps3: Option<f64>,
    /// `maxSpeed`, m/s.
    pub max_speed_mps: Option<f64>,
}

/// A story.
#[derive(Debug, Clone, PartialEq)]
pub struct Story {
    /// Its name.
    pub name: String,
    /// Its acts.
    pub acts: Vec<Act>,
}

/// An act: maneuver groups that start together.
#[derive(Debug, Clone, PartialEq)]
pub struct Act {
    /// Its name.
    pub name: String,
    /// When it starts; none: at once.
    pub start: Option<Trigger>,
    /// When it stops, if ever.
    pub stop: Option<Trigger>,
    /// Its maneuver groups.
    pub groups: Vec<ManeuverGroup>,
}

/// A maneuver group: maneuvers for a set of actors.
#[derive(Debug, Clone, PartialEq)]
pub struct ManeuverGroup {
    /// Its name.
    pub name: String,
    /// `maximumExecutionCount`, at least 1.
    pub max_count: u32,
    /// The actors (entity indices).
    pub actors: Vec<usize>,
    /// `selectTriggeringEntities`.
    pub select_triggering: bool,
    /// Its maneuvers.
    pub maneuvers: Vec<Maneuver>,
}

/// A maneuver: events.
#[derive(Debug, Clone, PartialEq)]
pub struct Maneuver {
    /// Its name.
    pub name: String,
    /// Its events.
    pub events: Vec<Event>,
}

/// An event's `priority`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Priority {
    /// `override` (1.0–1.1: `overwrite`): stops the maneuver's running events.
    Override,
    /// `skip`: does not start while another event of the maneuver runs.
    Skip,
    /// `parallel`: runs beside the others.
    Parallel,
}

/// An event: actions started together by a trigger.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Its name.
    pub name: String,
    /// Its priority.
    pub priority: Priority,
    /// `maximumExecutionCount`, at least 1.
    pub max_count: u32,
    /// Its actions.
    pub actions: Vec<NamedAction>,
    /// When it starts; none: as soon as its act has started.
    pub start: Option<Trigger>,
}

/// An action with its name.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedAction {
    /// Its name (`""` for an `Init` action).
    pub name: String,
    /// Where it is written.
    pub pos: Pos,
    /// What it does.
    pub action: Action,
}

/// A transition's shape (`DynamicsShape`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// Jumps at once.
    Step,
    /// Changes at a constant rate.
    Linear,
    /// A cubic with zero slope at both ends.
    Cubic,
    /// Half a cosine period.
    Sinusoidal,
}

/// What a transition's value measures (`DynamicsDimension`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Its duration, s.
    Time,
    /// The distance it takes, m.
    Distance,
    /// Its rate (m/s² for speed, m/s for a lane change's lateral speed).
    Rate,
}

/// How an action's value changes over time (`TransitionDynamics`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dynamics {
    /// The shape.
    pub shape: Shape,
    /// What `value` measures.
    pub dimension: Dimension,
    /// The duration (s), distance (m) or rate, `>= 0`.
    pub value: f64,
}

/// A speed target.
#[derive(Debug, Clone, PartialEq)]
pub enum SpeedTarget {
    /// m/s.
    Absolute(f64),
    /// Relative to another entity's speed: `delta` adds `value` m/s, `factor` multiplies.
    Relative {
        /// The entity.
        entity: usize,
        /// The delta (m/s) or factor.
        value: f64,
        /// `true`: factor; `false`: delta.
        factor: bool,
        /// Whether the target follows the entity's speed after it is reached.
        continuous: bool,
    },
}

/// A lane change's target lane.
#[derive(Debug, Clone, PartialEq)]
pub enum LaneTarget {
    /// A lane id of the road the entity is on.
    Absolute(i32),
    /// Lanes counted from another entity's lane, positive to the left (the standard's
    /// `RelativeTargetLane`, which counts in the entity's driving direction).
    Relative {
        /// The entity.
        entity: usize,
        /// Lanes to the left (negative: right).
        lanes: i32,
    },
}

/// A lane offset's target.
#[derive(Debug, Clone, PartialEq)]
pub enum OffsetTarget {
    /// m from the lane centre, positive to the left.
    Absolute(f64),
    /// m from another entity's lane offset.
    Relative {
        /// The entity.
        entity: usize,
        /// m.
        value: f64,
    },
}

/// An action paracosm reads.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// `SpeedAction`.
    Speed {
        /// Target.
        target: SpeedTarget,
        /// Transition.
        dynamics: Dynamics,
    },
    /// `LaneChangeAction`.
    LaneChange {
        /// Target lane.
        target: LaneTarget,
        /// Transition (lateral).
        dynamics: Dynamics,
        /// `targetLaneOffset`, m.
        offset_m: f64,
    },
    /// `LaneOffsetAction`.
    LaneOffset {
        /// Target offset.
        target: OffsetTarget,
        /// Shape of the transition.
        shape: Shape,
        /// `maxLateralAcc`, m/s², if given.
        max_lateral_acc: Option<f64>,
        /// Whether the offset is held after it is reached.
        continuous: bool,
    },
    /// `LongitudinalDistanceAction`: keep a distance or time gap to an entity.
    LongitudinalDistance {
        /// The entity kept at a distance.
        entity: usize,
        /// Distance, m, or
        distance_m: Option<f64>,
        /// time gap, s (one of the two).
        time_gap_s: Option<f64>,
        /// Whether the distance is between bounding boxes.
        freespace: bool,
        /// Whether it is kept after it is reached.
        continuous: bool,
        /// `displacement`: `trailingReferencedEntity` (default), `leadingReferencedEntity`
        /// or `any`.
        displacement: String,
        /// `coordinateSystem`: `entity` (default), `lane`, `road` or `trajectory`.
        frame: String,
        /// `DynamicConstraints`: the gap is approached within them (esmini's damped spring);
        /// none, it is taken at once and held kinematically.
        constraints: Option<DistanceConstraints>,
    },
    /// `LateralDistanceAction`: keep a lateral distance to an entity.
    LateralDistance {
        /// The entity kept at a distance.
        entity: usize,
        /// `distance`, m: from OpenSCENARIO 1.1 a magnitude (a negative one is read as its
        /// magnitude, noted), its side given by `displacement`; in 1.0 signed, to the left of
        /// the entity when positive. `None`: the distance at the action's start is kept.
        distance_m: Option<f64>,
        /// Whether the distance is between bounding boxes (the half widths added).
        freespace: bool,
        /// Whether it is kept after it is reached.
        continuous: bool,
        /// `displacement`: `leftToReferencedEntity`, `rightToReferencedEntity` or `any` (left,
        /// as esmini resolves it; 1.0 has none: `any`).
        displacement: String,
        /// `coordinateSystem`: `entity` (default) or `road`.
        frame: String,
        /// `DynamicConstraints`: `maxAcceleration` (and `maxAccelerationRate`) and `maxSpeed`
        /// of the lateral motion; none, the distance is taken at once.
        constraints: Option<DistanceConstraints>,
    },
    /// `TeleportAction`.
    Teleport(Position),
    /// `FollowTrajectoryAction`.
    FollowTrajectory {
        /// The trajectory's shape.
        shape: TrajectoryShape,
        /// `Timing`: `(absolute, scale, offset_s)`; none: follow at the entity's speed.
        timing: Option<(bool, f64, f64)>,
        /// `TrajectoryFollowingMode` is `position` (esmini turns a polyline's heading at its
        /// corners only); else `follow`, also when the element is missing, as esmini reads
        /// it (the heading turns along each whole leg).
        position_mode: bool,
        /// `initialDistanceOffset`, m (`>= 0`; 0 when absent): where along the trajectory the
        /// entity starts, as esmini places it when the action starts (untimed only).
        initial_offset_m: f64,
    },
    /// `AcquirePositionAction`: a route from where the entity is to this position.
    AcquirePosition(Position),
    /// `InfrastructureAction`'s `TrafficSignalStateAction` (a global action): the traffic
    /// signal `signal` (an OpenDRIVE `<signal>`'s id, or its name) shows `state` (as written,
    /// for example `off;off;on`), which `TrafficSignalCondition`s read; nothing paracosm
    /// simulates draws or obeys a signal.
    TrafficSignalState {
        /// The signal's id or name.
        signal: String,
        /// Its state, as written.
        state: String,
    },
    /// An empty `<Action/>` in a file read as CARLA's ([`Scenario::carla`]): scenario_runner
    /// builds no behaviour for it, so it does nothing and completes at once (read as a global
    /// action: on the world, once).
    Nothing,
    /// `TrailerAction`: `ConnectTrailerAction` hitches entity `Some(trailer)` (an index into
    /// [`Scenario::entities`]) to the entity, unhitching the one it tows;
    /// `DisconnectTrailerAction` (`None`) unhitches it, the trailer then standing where it
    /// is, at the speed it had.
    Trailer(Option<usize>),
    /// `SynchronizeAction`: the entity's speed is set each step so that it reaches its
    /// target position when the master entity reaches the master's.
    Synchronize(Box<Synchronize>),
    /// `SpeedProfileAction` (OpenSCENARIO 1.2): the entity's speed through a sequence of
    /// speeds, each reached a time after the one before.
    SpeedProfile(Box<SpeedProfile>),
    /// `AssignRouteAction`: a route through waypoints (the first is where the entity is
    /// routed from), each with its `routeStrategy`.
    AssignRoute {
        /// The waypoints, at least two.
        waypoints: Vec<(Position, String)>,
    },
    /// `ActivateControllerAction`: the system under test takes the entity over.
    ActivateController {
        /// Lateral control, when said.
        lateral: Option<bool>,
        /// Longitudinal control, when said.
        longitudinal: Option<bool>,
    },
    /// `AssignControllerAction`: the entity is given controller `controller`, of kind
    /// `kind` (its CARLA `module` or esmini `esminiController` property), which it obeys in
    /// the domains activated here (`Some(true)`; in a file written for CARLA, whose
    /// scenario_runner hands the entity over at once, both). On the ego a system under test
    /// drives, the controller is that system.
    AssignController {
        /// The controller's name.
        controller: String,
        /// What kind of controller it is, when a property says.
        kind: Option<String>,
        /// `activateLateral`.
        lateral: Option<bool>,
        /// `activateLongitudinal`.
        longitudinal: Option<bool>,
    },
    /// An `OverrideControllerValueAction` whose values are all inactive: it does nothing
    /// (an active one is refused at load).
    OverrideController,
    /// `AppearanceAction`: a vehicle's lights (`LightStateAction`) or an animation
    /// (`AnimationAction`), named here; paracosm draws neither, and nothing it models reads
    /// them.
    Appearance(String),
    /// `VisibilityAction`: whether the entity is drawn (`graphics`), seen by the other
    /// traffic (`traffic`) and by sensors (`sensors`).
    Visibility {
        /// Drawn by the image generator (the camera).
        graphics: bool,
        /// Seen by other traffic participants.
        traffic: bool,
        /// Seen by sensors (the system under test's).
        sensors: bool,
    },
    /// `EnvironmentAction` (a global action): the parts of the world's environment it
    /// gives, the others kept.
    Environment(Environment),
    /// `AddEntityAction` (a global `EntityAction`): entity `entity` (an index into
    /// [`Scenario::entities`]) enters the scenario at `position`. An entity is in the
    /// scenario from the start when `Init` places it (a `Private` block of its own, as
    /// esmini activates it) or adds it; an `AddEntityAction` on an entity in the scenario
    /// does nothing (esmini: "already active").
    AddEntity {
        /// The entity.
        entity: usize,
        /// Where it enters.
        position: Position,
    },
    /// `DeleteEntityAction` (a global `EntityAction`): entity `entity` leaves the scenario:
    /// nothing senses or touches it, and conditions leave it out, until an
    /// `AddEntityAction` adds it again.
    DeleteEntity {
        /// The entity.
        entity: usize,
    },
    /// `ParameterSetAction` or `VariableSetAction` (global): the parameter or variable
    /// `name` takes `value` (of its declared type).
    SetValue {
        /// The parameter's or variable's name.
        name: String,
        /// A variable (`VariableAction`), else a parameter (`ParameterAction`).
        variable: bool,
        /// The new value, of the declared type.
        value: Value,
    },
    /// `ParameterModifyAction` or `VariableModifyAction` (global): the numeric parameter or
    /// variable `name` becomes `value + by` (`AddValue`) or `value · by` (`MultiplyByValue`).
    ModifyValue {
        /// The parameter's or variable's name.
        name: String,
        /// A variable, else a parameter.
        variable: bool,
        /// `MultiplyByValue`, else `AddValue`.
        multiply: bool,
        /// The operand.
        by: f64,
    },
}

/// A `SynchronizeAction` (OpenSCENARIO 1.3 User Guide, "SynchronizeAction"): its entity
/// arrives at `target` when `master` arrives at `master_target`, at the final speed if one
/// is given.
#[derive(Debug, Clone, PartialEq)]
pub struct Synchronize {
    /// The master entity (`masterEntityRef`).
    pub master: usize,
    /// Where the master is headed (`TargetPositionMaster`).
    pub master_target: Position,
    /// Where the entity is headed (`TargetPosition`).
    pub target: Position,
    /// `targetToleranceMaster`, m (`>= 0`; 0 when absent, as esmini reads it).
    pub master_tolerance_m: f64,
    /// `targetTolerance`, m (`>= 0`; 0 when absent).
    pub tolerance_m: f64,
    /// `FinalSpeed`, if given.
    pub final_speed: Option<FinalSpeed>,
}

/// A `SpeedProfileAction` (OpenSCENARIO 1.2 User Guide, "SpeedProfileAction"): the entity's
/// speed through `entries`, each speed reached `time` s after the entry before it (the first
/// after the action's start).
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedProfile {
    /// `entityRef`: each entry's speed is relative to this entity's speed when the action
    /// starts (an index into [`Scenario::entities`]); `None`: absolute.
    pub entity: Option<usize>,
    /// `followingMode` is `follow`: the speed changes within the constraints' acceleration
    /// and its rate (jerk), rounding each corner of the profile; `position`: the speed is
    /// linear between entries.
    pub follow: bool,
    /// `DynamicConstraints`, if given (none: unbounded, as esmini leaves them).
    pub constraints: Option<DistanceConstraints>,
    /// The `SpeedProfileEntry`s: `time` (s, `>= 0`; `None` when left out: reached at the
    /// constraints' acceleration) and `speed` (m/s), at least one.
    pub entries: Vec<(Option<f64>, f64)>,
}

/// A `SynchronizeAction`'s `FinalSpeed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinalSpeed {
    /// `AbsoluteSpeed` (`None`: the value, m/s) or `RelativeSpeedToMaster` (`Some(factor)`:
    /// the master's speed times (`factor`) or plus the value, as the master moves).
    pub relative: Option<bool>,
    /// The speed, m/s, or the factor, or the difference to the master's speed, m/s.
    pub value: f64,
    /// The steady state held before the target (`TargetDistanceSteadyState`: a distance,
    /// m; `TargetTimeSteadyState`: a time, s), if given.
    pub steady: Option<SteadyState>,
}

/// How long a `SynchronizeAction`'s entity holds its final speed before its target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SteadyState {
    /// `TargetDistanceSteadyState`: the last metres, m.
    Distance(f64),
    /// `TargetTimeSteadyState`: the last seconds, s (the final speed times this, m).
    Time(f64),
}

/// An `Environment` (inline or from an environment catalog): what an `EnvironmentAction`
/// sets. Each part is `None` where the element does not give it (the world keeps it).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Environment {
    /// `TimeOfDay`: the time of day its `dateTime` gives, s after midnight (`[0, 86400)`),
    /// and whether it runs on with the simulated time (`animation`).
    pub time_of_day: Option<(f64, bool)>,
    /// `Weather/Sun`: illuminance, lux (1.2's `illuminance`, 1.0's `intensity`), and
    /// elevation above the horizon, rad.
    pub sun: Option<(f64, f64)>,
    /// `Weather/Fog`'s `visualRange`, m (> 0).
    pub fog_visual_range_m: Option<f64>,
    /// `Weather/Precipitation`: its type (`dry`, `rain`, `snow`) and intensity, mm/h.
    pub precipitation: Option<(String, f64)>,
    /// `RoadCondition`'s `frictionScaleFactor` (>= 0): the factor on the road's friction.
    pub friction_scale: Option<f64>,
}

impl Action {
    /// The element's name in the standard: `SpeedAction`, `LaneChangeAction`, ...
    pub fn kind_name(&self) -> &'static str {
        match self {
            Action::Speed { .. } => "SpeedAction",
            Action::LaneChange { .. } => "LaneChangeAction",
            Action::LaneOffset { .. } => "LaneOffsetAction",
            Action::LongitudinalDistance { .. } => "LongitudinalDistanceAction",
            Action::LateralDistance { .. } => "LateralDistanceAction",
            Action::Teleport(_) => "TeleportAction",
            Action::FollowTrajectory { .. } => "FollowTrajectoryAction",
            Action::AssignRoute { .. } => "AssignRouteAction",
            Action::AcquirePosition(_) => "AcquirePositionAction",
            Action::Trailer(Some(_)) => "ConnectTrailerAction",
            Action::Trailer(None) => "DisconnectTrailerAction",
            Action::Nothing => "Action",
            Action::TrafficSignalState { .. } => "TrafficSignalStateAction",
            Action::Synchronize(_) => "SynchronizeAction",
            Action::SpeedProfile(_) => "SpeedProfileAction",
            Action::ActivateController { .. } => "ActivateControllerAction",
            Action::AssignController { .. } => "AssignControllerAction",
            Action::OverrideController => "OverrideControllerValueAction",
            Action::Appearance(_) => "AppearanceAction",
            Action::Visibility { .. } => "VisibilityAction",
            Action::Environment(_) => "EnvironmentAction",
            Action::AddEntity { .. } => "AddEntityAction",
            Action::DeleteEntity { .. } => "DeleteEntityAction",
            Action::SetValue {
                variable: false, ..
            } => "ParameterSetAction",
            Action::SetValue { variable: true, .. } => "VariableSetAction",
            Action::ModifyValue {
                variable: false, ..
            } => "ParameterModifyAction",
            Action::ModifyValue { variable: true, .. } => "VariableModifyAction",
        }
    }

    /// Whether it activates a controller of its entity: an `ActivateControllerAction` that
    /// activates a domain (one it leaves unsaid is activated), or an
    /// `AssignControllerAction` that activates one.
    pub fn hands_over(&self) -> bool {
        match self {
            Action::ActivateController {
                lateral,
                longitudinal,
            } => *lateral != Some(false) || *longitudinal != Some(false),
            Action::AssignController {
                lateral,
                longitudinal,
                ..
            } => *lateral == Some(true) || *longitudinal == Some(true),
            _ => false,
        }
    }

    /// Whether it is a global action (it acts on the world, not on the maneuver group's
    /// actors).
    pub fn is_global(&self) -> bool {
        matches!(
            self,
            Action::Environment(_)
                | Action::SetValue { .. }
                | Action::ModifyValue { .. }
                | Action::AddEntity { .. }
                | Action::DeleteEntity { .. }
                | Action::Nothing
                | Action::TrafficSignalState { .. }
        )
    }
}

/// The shape of a `FollowTrajectoryAction`'s trajectory.
#[derive(Debug, Clone, PartialEq)]
pub enum TrajectoryShape {
    /// `Polyline`: vertices with their times, s (none without timing), at least two.
    Polyline(Vec<(Option<f64>, Position)>),
    /// `Clothoid`: from `start` (the entity's pose when none), facing as it does, with
    /// curvature `curvature` (1/m, positive to the left) changing by `curvature_prime`
    /// (1/m², 1.0's `curvatureDot`) over `length` (m, > 0); `times`: at its start and its
    /// end, s (`startTime`, `stopTime`), linear in the distance along it.
    Clothoid {
        /// Where it starts, and the heading it starts with.
        start: Option<Position>,
        /// 1/m.
        curvature: f64,
        /// 1/m².
        curvature_prime: f64,
        /// m.
        length: f64,
        /// `(startTime, stopTime)`, s.
        times: Option<(f64, f64)>,
    },
    /// `ClothoidSpline` (1.3): clothoid segments laid end to end from `start` (the entity's
    /// pose when none), each `(curvature at its start, at its end, 1/m; length, m, > 0;
    /// heading offset at its start, rad)`.
    ClothoidSpline {
        /// Where the first segment starts (its `PositionStart`), and the heading it starts
        /// with.
        start: Option<Position>,
        /// `(curvatureStart, curvatureEnd, length, hOffset)` of each segment, in order.
        segments: Vec<[f64; 4]>,
        /// The segments after the first that give their own `PositionStart` (by index):
        /// each starts there, not where the one before ends (as esmini lays them).
        restarts: Vec<(usize, Position)>,
        /// Its times (OpenSCENARIO 1.3): each segment's `timeStart` (s, increasing) and the
        /// spline's `timeEnd`; along each segment the distance is linear in time, as esmini
        /// reads them. `None`: followed at the entity's speed.
        times: Option<(Vec<f64>, f64)>,
    },
    /// `Nurbs`: a rational B-spline of `order` (degree + 1, at least 2) over its control
    /// points `(time s, weight > 0, position)` and `knots` (control points + order of them,
    /// non-decreasing). Piegl and Tiller, *The NURBS Book* (1997), §4.2.
    Nurbs {
        /// Degree + 1.
        order: usize,
        /// `(time, weight, position)`.
        points: Vec<(Option<f64>, f64, Position)>,
        /// The knot vector.
        knots: Vec<f64>,
    },
}

/// An orientation given with a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orientation {
    /// Heading, rad.
    pub h: f64,
    /// Pitch, rad (`p`): the storyboard carries it to rotate the offsets of a
    /// [`Position::RelativeObject`] taken from the entity; a campaign refuses a tilt
    /// ([`Scenario::tilts`]).
    pub p: f64,
    /// Roll, rad (`r`), carried as the pitch is.
    pub r: f64,
    /// `type="relative"` (to the road's or lane's direction, or the entity's heading);
    /// a missing `type` is absolute.
    pub relative: bool,
}

/// A position.
#[derive(Debug, Clone, PartialEq)]
pub enum Position {
    /// `WorldPosition`: `x`, `y` (m), heading `h` (rad).
    World {
        /// m.
        x: f64,
        /// m.
        y: f64,
        /// rad, if given.
        h: Option<f64>,
    },
    /// `RelativeWorldPosition`.
    RelativeWorld {
        /// The entity.
        entity: usize,
        /// m.
        dx: f64,
        /// m.
        dy: f64,
        /// Orientation (relative: to the entity's heading).
        orientation: Option<Orientation>,
    },
    /// `RelativeObjectPosition` (in the entity's frame).
    RelativeObject {
        /// The entity.
        entity: usize,
        /// m, forward.
        dx: f64,
        /// m, left.
        dy: f64,
        /// m, up: the offsets are turned by the entity's heading, pitch and roll (esmini's
        /// `RotateVec3d`), and the part along the ground is taken.
        dz: f64,
        /// Orientation (relative: to the entity's heading).
        orientation: Option<Orientation>,
    },
    /// `RoadPosition`.
    Road {
        /// Road id.
        road: String,
        /// m along the road.
        s: f64,
        /// m left of the reference line.
        t: f64,
        /// Orientation.
        orientation: Option<Orientation>,
    },
    /// `LanePosition`.
    Lane {
        /// Road id.
        road: String,
        /// Lane id.
        lane: i32,
        /// m along the road.
        s: f64,
        /// m from the lane centre along +t (left of the road's reference line direction,
        /// which is the driver's right on a lane driven against `s`).
        offset: f64,
        /// Orientation.
        orientation: Option<Orientation>,
    },
    /// `RelativeRoadPosition`: `ds` along the entity's road and `dt` across it from the
    /// entity's own road coordinates.
    RelativeRoad {
        /// The entity.
        entity: usize,
        /// m along the road's reference line (increasing `s`).
        ds: f64,
        /// m along +t (left of the reference line).
        dt: f64,
        /// Orientation (relative: to the road's reference line there).
        orientation: Option<Orientation>,
    },
    /// `RelativeLanePosition`.
    RelativeLane {
        /// The entity.
        entity: usize,
        /// Lanes counted along +t (toward positive lane ids' side).
        d_lane: i32,
        /// m along the road (`ds`) from the entity.
        ds: f64,
        /// m from the target lane's centre along +t.
        offset: f64,
        /// Orientation: relative to the lane's heading there (as the position faces without
        /// one), or absolute.
        orientation: Option<Orientation>,
    },
    /// `TrajectoryPosition` (1.2+): `s` m along a trajectory's shape from its start, `t` m to
    /// the left of it there, facing along it (turned by `orientation`, relative to that
    /// direction, or absolute).
    Trajectory {
        /// The trajectory's shape (written in place or from a trajectory catalog).
        shape: Box<TrajectoryShape>,
        /// m along the shape (`>= 0`).
        s: f64,
        /// m to the left of the shape (`t`, 0 when absent).
        t: f64,
        /// Orientation, if given.
        orientation: Option<Orientation>,
    },
    /// `RoutePosition`: a place on a route (written in place or from a route catalog).
    Route {
        /// The route's waypoints (each a position and its `routeStrategy`), at least two.
        waypoints: Vec<(Position, String)>,
        /// Where on it (`InRoutePosition`).
        at: InRoute,
        /// Orientation: relative to the route's direction there, or absolute.
        orientation: Option<Orientation>,
    },
}

/// Where on a route a `RoutePosition` is (`InRoutePosition`).
#[derive(Debug, Clone, PartialEq)]
pub enum InRoute {
    /// `FromCurrentEntity`: where the entity is.
    Entity(usize),
    /// `FromLaneCoordinates`: `path_s` m along the route from its first waypoint (in the
    /// roads' stations), on the lane of `<lane id>` `lane` of the road there, `offset` m
    /// from its centre along +t.
    Lane {
        /// m along the route.
        path_s: f64,
        /// `<lane id>`.
        lane: i32,
        /// m from the lane's centre.
        offset: f64,
    },
    /// `FromRoadCoordinates`: `path_s` m along the route, `t` m across the road there.
    Road {
        /// m along the route.
        path_s: f64,
        /// m left of the reference line.
        t: f64,
    },
}

/// A comparison (`Rule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// `greaterThan`.
    Gt,
    /// `lessThan`.
    Lt,
    /// `equalTo`.
    Eq,
    /// `greaterOrEqual`.
    Ge,
    /// `lessOrEqual`.
    Le,
    /// `notEqualTo`.
    Ne,
}

impl Rule {
    /// Whether `a rule b` holds (`equalTo` within 1e-9 relative).
    pub fn holds(self, a: f64, b: f64) -> bool {
        let eq = (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0);
        match self {
            Rule::Gt => a > b,
            Rule::Lt => a < b,
            Rule::Eq => eq,
            Rule::Ge => a >= b || eq,
            Rule::Le => a <= b || eq,
            Rule::Ne => !eq,
        }
    }
}

/// When a condition's value counts (`conditionEdge`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    /// Whenever it holds.
    None,
    /// When it turns true.
    Rising,
    /// When it turns false.
    Falling,
    /// When it changes.
    RisingOrFalling,
}

/// A trigger: condition groups, of which any one whose conditions all hold fires it.
#[derive(Debug, Clone, PartialEq)]
pub struct Trigger(pub Vec<Vec<Condition>>);

/// A condition.
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    /// Its name.
    pub name: String,
    /// `delay`, s: the condition reports what held this long ago.
    pub delay_s: f64,
    /// `conditionEdge`.
    pub edge: Edge,
    /// What it tests.
    pub kind: ConditionKind,
    /// Where it is written.
    pub pos: Pos,
}

/// What a condition tests.
#[derive(Debug, Clone, PartialEq)]
pub enum ConditionKind {
    /// `SimulationTimeCondition`: time (s) `rule` value.
    SimulationTime {
        /// Comparison.
        rule: Rule,
        /// s.
        value: f64,
    },
    /// `StoryboardElementStateCondition`.
    ElementState {
        /// `storyboardElementType` (`story`, `act`, `maneuverGroup`, `maneuver`, `event`,
        /// `action`).
        element_type: String,
        /// The element's name.
        element: String,
        /// `state` (`startTransition`, `endTransition`, `completeState`, `runningState`, ...).
        state: String,
    },
    /// `ParameterCondition`.
    Parameter {
        /// The parameter.
        name: String,
        /// Comparison.
        rule: Rule,
        /// The value as written.
        value: String,
    },
    /// `TrafficSignalCondition`: traffic signal `signal` (an OpenDRIVE `<signal>`'s id or
    /// name) shows `state`, as the storyboard's `TrafficSignalStateAction`s last set it (no
    /// state before one does).
    TrafficSignal {
        /// The signal's id or name.
        signal: String,
        /// The state, as written.
        state: String,
    },
    /// `VariableCondition` (OpenSCENARIO 1.2): as [`ConditionKind::Parameter`], on a
    /// declared variable's current value.
    Variable {
        /// The variable.
        name: String,
        /// Comparison.
        rule: Rule,
        /// The value as written.
        value: String,
    },
    /// A `ByEntityCondition`: the triggering entities and what each is tested for.
    Entity {
        /// The triggering entities.
        entities: Vec<usize>,
        /// `triggeringEntitiesRule="all"` (else `any`).
        all: bool,
        /// The test.
        test: EntityTest,
    },
}

/// What a headway, time to collision or relative distance condition compares: to which
/// entity, how, and measured where.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// The other entity.
    pub entity: usize,
    /// Comparison.
    pub rule: Rule,
    /// s (headway, time to collision) or m (distance).
    pub value: f64,
    /// Between bounding boxes.
    pub freespace: bool,
    /// `coordinateSystem`: `entity` (default), `lane`, `road` or `trajectory` (1.0's
    /// `alongRoute="true"` is `road`).
    pub frame: String,
    /// `relativeDistanceType`: `longitudinal`, `lateral` or `euclidianDistance` (the default;
    /// 1.0's `cartesianDistance`).
    pub kind: String,
}

/// A condition's gap from an entity to a position: a `DistanceCondition` (m) or a
/// `TimeToCollisionCondition` with a position target (s).
#[derive(Debug, Clone, PartialEq)]
pub struct PositionGap {
    /// The position.
    pub position: Position,
    /// Comparison.
    pub rule: Rule,
    /// m (distance) or s (time to collision).
    pub value: f64,
    /// From the entity's bounding box (its reference point otherwise).
    pub freespace: bool,
    /// `relativeDistanceType`: `longitudinal`, `lateral` or `euclidianDistance`.
    pub kind: String,
    /// `coordinateSystem`: `entity` or `road` (`lane` longitudinally).
    pub frame: String,
}

/// An entity condition's test (the standard's `EntityCondition` choices paracosm reads).
#[derive(Debug, Clone, PartialEq)]
pub enum EntityTest {
    /// `TimeHeadwayCondition`: time (s) to reach the entity at the current speed.
    TimeHeadway(Gap),
    /// `TimeToCollisionCondition` to an entity, s.
    TimeToCollision(Gap),
    /// `RelativeDistanceCondition`, m.
    RelativeDistance(Gap),
    /// `DistanceCondition`: the distance from the entity to a position, m (in the entity's
    /// frame: `coordinateSystem` `entity`; from its bounding box with `freespace`).
    Distance(PositionGap),
    /// `TimeToCollisionCondition` to a position: the distance to it (as a
    /// `DistanceCondition` measures it) over the entity's speed, s; undefined (every rule
    /// false) at no distance, standing, or moving away (esmini's `TrigByTimeToCollision`).
    TimeToPosition(PositionGap),
    /// `ReachPositionCondition`.
    ReachPosition {
        /// The position.
        position: Position,
        /// m.
        tolerance: f64,
    },
    /// `SpeedCondition`, m/s.
    Speed {
        /// Comparison.
        rule: Rule,
        /// m/s.
        value: f64,
    },
    /// `RelativeSpeedCondition`: own speed minus `entity`'s, m/s.
    RelativeSpeed {
        /// The other entity.
        entity: usize,
        /// Comparison.
        rule: Rule,
        /// m/s.
        value: f64,
    },
    /// `AccelerationCondition`, m/s².
    Acceleration {
        /// Comparison.
        rule: Rule,
        /// m/s².
        value: f64,
    },
    /// `StandStillCondition`: still for this long, s.
    Standstill(f64),
    /// `TraveledDistanceCondition`, m.
    TraveledDistance(f64),
    /// `EndOfRoadCondition`: off the road's end for this long, s.
    EndOfRoad(f64),
    /// `OffroadCondition`: off every lane of the map (its reference point outside the
    /// road's width, as esmini's `Position::IsOffRoad`) for longer than this, s.
    Offroad(f64),
    /// `CollisionCondition` with this entity (`None` is kept for a collision with
    /// anything).
    Collision(Option<usize>),
    /// `CollisionCondition` `ByType`: with any other entity of this type (`vehicle`,
    /// `pedestrian` or `miscellaneous`, [`EntityKind::object_type`]).
    CollisionByType(String),
    /// `AngleCondition` (1.3): the entity's heading, in `frame`, within `tolerance` of
    /// `angle` (the absolute difference of the two, taken into `[0, π]`, below
    /// `tolerance` + 1e-6 rad, as esmini has it).
    Angle(AngleTest),
    /// `RelativeClearanceCondition` (1.2): the lanes beside and around the entity are free
    /// (esmini's `TrigByRelativeClearance`).
    RelativeClearance(Clearance),
    /// `RelativeAngleCondition` (1.3): the entity's heading less `entity`'s, each in
    /// `test.frame`, within `test.tolerance` of `test.angle`.
    RelativeAngle {
        /// The other entity.
        entity: usize,
        /// The angle, its tolerance and the frame.
        test: AngleTest,
    },
}

/// What a `RelativeClearanceCondition` (1.2) asks: that no other entity (of `entities`,
/// or any) stands in the lanes `ranges` counts from the entity's, from `backward_m` behind
/// it to `forward_m` ahead along the road, and that such a lane exists where it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Clearance {
    /// `distanceForward`, m, `>= 0`.
    pub forward_m: f64,
    /// `distanceBackward`, m, `>= 0`.
    pub backward_m: f64,
    /// `freeSpace`: between the boxes (else between reference points).
    pub freespace: bool,
    /// `oppositeLanes`: lanes of the other direction count too.
    pub opposite_lanes: bool,
    /// Each `RelativeLaneRange`'s `from` and `to` (lanes counted as `<lane id>`s differ,
    /// the centre lane skipped; an absent bound is unbounded); none: every lane.
    pub ranges: Vec<(i64, i64)>,
    /// The entities that may stand there (`EntityRef`s); none: every other entity.
    pub entities: Vec<usize>,
}

/// What an angle condition compares: a heading (rad) within a tolerance, in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct AngleTest {
    /// rad.
    pub angle: f64,
    /// rad, `>= 0`.
    pub tolerance: f64,
    /// `coordinateSystem`: `world` (the default of `AngleCondition`), `entity` (the default
    /// of `RelativeAngleCondition`; an entity's own heading in its own frame is 0), `road`
    /// (less the direction of increasing `s` where the entity is) or `lane` (less the
    /// direction of travel of the entity's lane).
    pub frame: String,
}
