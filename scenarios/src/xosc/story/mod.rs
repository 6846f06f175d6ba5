//! The storyboard runtime: an OpenSCENARIO storyboard (OpenSCENARIO 1.3 User Guide,
//! "Storyboard and entities", "Conditions and triggers") run step by step over the test's
//! world. Stories, acts, maneuver groups, maneuvers, events and actions move through the
//! standard's states (standby, running, complete) on their triggers: condition groups (an OR
//! of ANDs), each condition with its edge and delay; event priorities (override, skip,
//! parallel) and execution counts. Scripted entities (every entity but the ego, which the
//! system under test drives) move as their actions say, on the map's lanes.

mod conditions;
mod drive;
mod elements;
mod positions;
mod tasks;

use conditions::Cond;
pub use drive::STRAIGHT_CONTROLLERS;
use drive::{Drive, ToLane, Track};
use elements::{Elem, Kind, Owner, Phase};
pub use tasks::DEFAULT_LATERAL_ACC_MPS2;
pub use tasks::{
    precipitation_extinction_per_m, Stored, WorldEnv, MAP_FRICTION, NOMINAL_ILLUMINANCE_LX,
    VISIBLE_WAVELENGTH_NM,
};
use tasks::{Keep, LatKeep, LatStep, Lateral, Path, Profile, SpeedTask, Synchronizing};

use std::collections::VecDeque;

use paracosm_openscenario::model::{
    self as m, Action, ConditionKind, Edge, EntityTest, Gap, LaneTarget, Position, Priority, Rule,
    SpeedTarget, TrajectoryShape,
};

use super::motion::{
    clothoid_poses, duration_s, nurbs_poses, offset_duration_s, shape_of, Legs, Timed, Transition,
    Untimed,
};
use paracosm_engine::network::roads::{wrap, LanePos, Pose, RoadError, Roads};
use paracosm_engine::transition;

/// Orientation `o` against `base` (rad): a relative one added to it, an absolute one as
/// written, `base` without one.
fn orient(o: &Option<m::Orientation>, base: f64) -> f64 {
    match o {
        Some(o) if o.relative => wrap(base + o.h),
        Some(o) => wrap(o.h),
        None => base,
    }
}

/// One entity as the storyboard sees it.
#[derive(Debug, Clone)]
pub struct Actor {
    /// Its name in the file.
    pub name: String,
    /// Length, width, height of its bounding box, m.
    pub size_m: [f64; 3],
    /// The bounding box's centre relative to the entity's reference point, m (x forward, y
    /// left, z up).
    pub centre_m: [f64; 3],
    /// Its `ObjectType`: `vehicle`, `pedestrian` or `miscellaneous`.
    pub object_type: &'static str,
    /// The limits on the speed changes the storyboard makes it perform (its `Performance`).
    pub performance: m::Performance,
    /// Whether the storyboard moves it now: every entity but the ego the system under test
    /// drives, and that ego too until its controller is activated
    /// ([`Storyboard::hand_over_on_activation`]).
    pub scripted: bool,
    /// Whether it is in the scenario now: placed by `Init` (a `Private` block of its own,
    /// as esmini activates an entity) or added by an `AddEntityAction`, and not deleted
    /// since (`DeleteEntityAction`). An entity out of it is out of the test's world, and
    /// conditions leave it out (esmini's `IsActive`).
    pub present: bool,
    /// Its state now.
    pub state: State,
    /// Where a trailer is hitched to it, m ahead of its reference point (its
    /// `TrailerHitch`), if it has a hitch.
    pub hitch_dx_m: Option<f64>,
    /// Where it is coupled to a tow, m ahead of its reference point (its `TrailerCoupler`),
    /// if it is a trailer.
    pub coupler_dx_m: Option<f64>,
    /// The entity it tows now (its `Trailer`, or the one a `ConnectTrailerAction` hitched):
    /// that trailer is pulled by its hitch, not moved by its own actions.
    pub trailer: Option<usize>,
    /// A reference point ahead of its rear axle (esmini's `refpoint_x_offset`,
    /// [`m::Entity::refpoint_dx_m`]): how far ahead, m, and where its rear axle is now
    /// (`[x, y]`, m). Its body trails the reference point.
    pub front_ref: Option<(f64, [f64; 2])>,
}

/// Where an entity is and how it moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Its reference point's pose (the rear axle's centre for a vehicle).
    pub pose: Pose,
    /// Speed along its heading, m/s.
    pub speed: f64,
    /// Acceleration over the last step, m/s².
    pub accel: f64,
    /// Where it is on the map's lanes, when it follows them.
    pub lane: Option<LanePos>,
    /// Distance travelled since the start, m.
    pub travelled_m: f64,
    /// Its velocity in the world, `[x, y]` m/s: its displacement over the last step divided
    /// by the step, or, where it was placed (`Init`, a teleport), its speed along its heading
    /// (esmini's `ScenarioEngine` derives velocities so).
    pub vel: [f64; 2],
    /// How long it has stood still, s.
    pub still_s: f64,
    /// How long since it was found at the end of its lanes, s (0 in the step it got
    /// there, as esmini times an `EndOfRoadCondition` from then); `None` when it is not
    /// there.
    pub at_end_s: Option<f64>,
    /// How long since it was found off the road, s (0 in the step it left it, as esmini
    /// times an `OffroadCondition` from then); `None` on the road. Kept only while an
    /// `OffroadCondition` reads it.
    pub offroad_s: Option<f64>,
    /// Whether it has touched anything solid.
    pub collided: bool,
    /// Its pitch and roll, rad, from the orientation it was last placed with (0 on the
    /// flat roads otherwise); they turn the offsets of a `RelativeObjectPosition` taken
    /// from it.
    pub tilt: [f64; 2],
}

impl State {
    fn at(pose: Pose, lane: Option<LanePos>) -> Self {
        State {
            pose,
            speed: 0.0,
            accel: 0.0,
            lane,
            travelled_m: 0.0,
            vel: [0.0; 2],
            still_s: 0.0,
            at_end_s: None,
            offroad_s: None,
            collided: false,
            tilt: [0.0; 2],
        }
    }
}

/// Why the storyboard cannot go on (an action that cannot be performed where it stands).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{at}: {message}")]
pub struct StoryError {
    /// Where the action or condition is written, `file:line:col`.
    pub at: String,
    /// What went wrong.
    pub message: String,
}

/// The storyboard of one test and the entities it moves.
#[derive(Debug, Clone)]
pub struct Storyboard {
    roads: Roads,
    /// The entities, in the file's order.
    pub actors: Vec<Actor>,
    drives: Vec<Drive>,
    elems: Vec<Elem>,
    roots: Vec<usize>,
    triggers: Vec<Vec<Vec<Cond>>>,
    owners: Vec<Owner>,
    stop: Option<usize>,
    /// The scenario's own parameters, their values changed by `ParameterAction`s.
    params: Vec<tasks::Stored>,
    /// The scenario's variables (`VariableDeclarations`), changed by `VariableAction`s.
    variables: Vec<tasks::Stored>,
    /// The world's environment as `EnvironmentAction`s set it.
    env: tasks::WorldEnv,
    /// How many transitions the storyboard's elements have made ([`elements::Change`]).
    seq: u64,
    /// Whether the storyboard is read as CARLA's scenario_runner reads its files
    /// ([`m::Scenario::carla`]): a condition once true stays true while its element waits,
    /// and its edge is not read (scenario_runner wraps each condition in a one-shot
    /// behaviour and has no edges); the storyboard ends when its stories have; a
    /// `SpeedAction` sets its target at once and lasts its dynamics' value, a distance
    /// travelled (m) or a time (s), as its `ChangeActorTargetSpeed` does ([`speed::Hold`]).
    carla: bool,
    /// Whether an `OffroadCondition` reads how long each entity has been off the road
    /// ([`State::offroad_s`]).
    watch_offroad: bool,
    /// Each traffic signal's state as the storyboard's `TrafficSignalStateAction`s last set
    /// it: (the signal's id or name as the file names it, its state).
    signals: Vec<(String, String)>,
    /// Whether the storyboard's stop trigger has fired.
    pub ended: bool,
    started: bool,
    /// Actions that end in the next step's tasks: a `LightStateAction`, an
    /// `AnimationAction` or a `VisibilityAction` (esmini ends them in their first `Step`,
    /// the frame after they start).
    ending_next: Vec<usize>,
    /// Actions done when they started in this step (a teleport, a global action): they
    /// complete after the step's triggers have been read.
    ending_now: Vec<usize>,
    /// What the storyboard performs otherwise than written, found when it is built: `(where,
    /// what)`, warnings at load ([`Storyboard::notes`]).
    notes: Vec<(String, String)>,
    /// What the storyboard found while it ran, for the test's record
    /// ([`Storyboard::take_said`]).
    said: Vec<String>,
    /// The speed the storyboard asks of the ego the system under test drives now, m/s: its
    /// `SpeedAction`s' transitions, which the host hands the system as its set speed
    /// ([`Storyboard::set_speed`]); `None` until one starts.
    set_speed: Option<f64>,
    /// The ego that the storyboard moves until an `ActivateControllerAction` on it hands it
    /// to the system under test ([`Storyboard::hand_over_on_activation`]).
    hand_over: Option<usize>,
    /// A new route asked of the driven ego since the host last took one
    /// ([`Storyboard::take_route`]).
    route: Option<RouteAsk>,
    /// The extents on a road of the boxes the conditions measured lately
    /// ([`conditions::BoxOnRoad`]): an entity's box is taken to the road once per pose, not
    /// once per condition that reads it.
    boxes: std::cell::RefCell<Vec<conditions::BoxOnRoad>>,
}

/// A route the storyboard asks of the ego the system under test drives (a `LaneChangeAction`
/// or an `AssignRouteAction` on it): from where the ego is, join `join` (a place on the lane
/// to drive in, abeam the ego, at the offset asked) `ahead_m` metres further along, then
/// follow the lanes from there, through junctions as the ego's route prefers.
#[derive(Debug, Clone, PartialEq)]
pub struct RouteAsk {
    /// The lane position abeam the ego (its station) on the lane to drive in.
    pub join: LanePos,
    /// How far ahead the route joins that lane, m: the lane change's length (its distance, or
    /// its duration at the ego's speed); 0 for a route on the lane the ego is in.
    pub ahead_m: f64,
    /// A path to drive first (a `FollowTrajectoryAction`'s trajectory, its points in the
    /// OpenDRIVE frame): the route follows it, then the lanes on from its end (`join` is
    /// there); empty for a route along the lanes.
    pub path: Vec<Pose>,
}

/// How close the driven ego must come to the end of the trajectory its
/// `FollowTrajectoryAction` hands the system under test as its route for the action to end,
/// m.
pub const PATH_END_REACHED_M: f64 = 1.0;

/// How close to the target lane's centre (plus the offset asked) a driven ego must come for
/// its `LaneChangeAction` to end, m.
pub const LANE_REACHED_M: f64 = 0.3;

/// How close the driven ego's speed must come to a `SpeedAction`'s target, once the action's
/// transition is over, for the action to end: this many m/s plus [`SET_SPEED_REACHED_SHARE`]
/// of the target (a cruise controller settles under its set speed: `aeb`'s proportional
/// gain keeps 11.84 m/s of 12 and 19.14 of 20, `tests/xosc_ego.rs`).
pub const SET_SPEED_REACHED_MPS: f64 = 0.5;
/// See [`SET_SPEED_REACHED_MPS`].
pub const SET_SPEED_REACHED_SHARE: f64 = 0.05;

fn site(pos: &paracosm_openscenario::Pos) -> String {
    pos.to_string()
}

impl Storyboard {
    /// The storyboard of `scenario` on `roads`, its `Init` performed: every entity placed and
    /// given its initial speed. `ego` is the entity the system under test drives (not
    /// scripted); with `None`, the storyboard moves every entity (the ego too, at the speed
    /// its `Init` gives it).
    ///
    /// # Errors
    /// [`StoryError`] for an `Init` action that cannot be performed (a position off the map,
    /// a relative position to an entity not yet placed).
    pub fn new(
        scenario: &m::Scenario,
        roads: Roads,
        ego: Option<usize>,
    ) -> Result<Self, StoryError> {
        let mut sb = Storyboard::unbuilt(scenario, roads, ego);
        sb.stop = scenario
            .stop
            .as_ref()
            .filter(|t| !t.0.is_empty())
            .map(|t| sb.add_trigger(t, Owner::Storyboard));
        for story in &scenario.stories {
            let s = sb.push(Kind::Story, &story.name, 1);
            sb.roots.push(s);
            for act in &story.acts {
                sb.add_act(s, act)?;
            }
        }
        sb.watch_offroad = sb.triggers.iter().flatten().flatten().any(|c| {
            matches!(
                c.cond.kind,
                ConditionKind::Entity {
                    test: m::EntityTest::Offroad(_),
                    ..
                }
            )
        });
        sb.resolve_references();
        sb.check_signals()?;
        sb.perform_init(scenario)?;
        // Trailers Init did not line up (their tow placed by a trajectory) are pulled to
        // their tows, as in esmini's initial frame.
        sb.pull_trailers(0.0);
        sb.trail_rear_axles();
        for a in &mut sb.actors {
            let st = &mut a.state;
            st.vel = [st.speed * st.pose.h.cos(), st.speed * st.pose.h.sin()];
        }
        // Init's transitions run from the start.
        Ok(sb)
    }

    /// The storyboard of `scenario` on `roads` before its stories are read and its `Init`
    /// performed: every entity at the origin (0 m, 0 m, heading 0 rad), standing, on no
    /// lane; every entity scripted but `ego`.
    fn unbuilt(scenario: &m::Scenario, roads: Roads, ego: Option<usize>) -> Self {
        let actors = scenario
            .entities
            .iter()
            .enumerate()
            .map(|(i, e)| Actor {
                name: e.name.clone(),
                object_type: e.kind.object_type(),
                performance: e.performance,
                size_m: e.dimensions_m,
                centre_m: e.centre_m,
                scripted: Some(i) != ego,
                present: false,
                hitch_dx_m: e.hitch_dx_m,
                coupler_dx_m: e.coupler_dx_m,
                trailer: e.trailer,
                // Its rear axle behind the origin, where it stands before `Init`.
                front_ref: e.refpoint_dx_m.map(|dx| (dx, [-dx, 0.0])),
                state: State::at(
                    Pose {
                        x: 0.0,
                        y: 0.0,
                        h: 0.0,
                    },
                    None,
                ),
            })
            .collect();
        Storyboard {
            roads,
            drives: vec![Drive::default(); scenario.entities.len()],
            actors,
            elems: Vec::new(),
            roots: Vec::new(),
            triggers: Vec::new(),
            owners: Vec::new(),
            stop: None,
            params: scenario
                .params
                .iter()
                .map(|(d, v)| tasks::Stored {
                    name: d.name.clone(),
                    ty: d.ty,
                    text: v.to_text(),
                })
                .collect(),
            variables: scenario
                .variables
                .iter()
                .map(|(name, ty, v)| tasks::Stored {
                    name: name.clone(),
                    ty: *ty,
                    text: v.to_text(),
                })
                .collect(),
            env: tasks::WorldEnv::default(),
            boxes: std::cell::RefCell::default(),
            seq: 0,
            carla: scenario.carla,
            watch_offroad: false,
            signals: Vec::new(),
            ended: false,
            started: false,
            ending_next: Vec::new(),
            ending_now: Vec::new(),
            notes: Vec::new(),
            said: Vec::new(),
            set_speed: None,
            hand_over: None,
            route: None,
        }
    }

    /// The map the storyboard moves its entities on.
    pub fn roads(&self) -> &Roads {
        &self.roads
    }

    /// Entity `e`'s reference point and the centre of its bounding box, engine world
    /// coordinates: `([x, y, z] m of the box's base centre, heading rad)`.
    pub fn engine_pose(&self, e: usize) -> ([f64; 3], f64) {
        let a = &self.actors[e];
        let p = a.state.pose;
        let (c, s) = (p.h.cos(), p.h.sin());
        let centre = Pose {
            x: p.x + c * a.centre_m[0] - s * a.centre_m[1],
            y: p.y + s * a.centre_m[0] + c * a.centre_m[1],
            h: p.h,
        };
        self.roads.to_engine(centre)
    }

    /// Sets the state of an entity the storyboard does not move (the ego) from what the
    /// simulation shows: its box centre `[x, y, z]` (engine world, m), heading (rad), speed
    /// along its heading (m/s); `dt` is the step (s).
    pub fn observe(&mut self, e: usize, centre: [f64; 3], heading: f64, speed: f64, dt: f64) {
        let a = &mut self.actors[e];
        let o = self.roads.map().origin_m;
        let (x, y) = (centre[0] + o[0], -centre[2] + o[1]);
        let (c, s) = (heading.cos(), heading.sin());
        let pose = Pose {
            x: x - c * a.centre_m[0] + s * a.centre_m[1],
            y: y - s * a.centre_m[0] - c * a.centre_m[1],
            h: heading,
        };
        let st = &mut a.state;
        let moved = (pose.x - st.pose.x).hypot(pose.y - st.pose.y);
        if self.started {
            st.accel = (speed - st.speed) / dt;
            st.travelled_m += moved;
            st.vel = [(pose.x - st.pose.x) / dt, (pose.y - st.pose.y) / dt];
        } else {
            st.vel = [speed * heading.cos(), speed * heading.sin()];
        }
        st.speed = speed;
        st.pose = pose;
        st.lane = self
            .roads
            .anchor(pose.x, pose.y)
            .map(|lp| self.roads.facing(lp, heading));
        st.still_s = if speed.abs() < 1e-3 {
            st.still_s + dt
        } else {
            0.0
        };
    }

    /// Whether the lanes entity `e` follows end within `margin_m` (m) of its bounding box's
    /// front: there is no lane for it to drive on beyond. `false` off every lane.
    pub fn road_ends_ahead(&self, e: usize, margin_m: f64) -> bool {
        let a = &self.actors[e];
        let Some(mut lp) = a.state.lane else {
            return false;
        };
        let reach = (a.centre_m[0] + a.size_m[0] / 2.0).max(0.0) + margin_m;
        !self.roads.advance(&mut lp, reach, &|_| false)
    }

    /// Whether any event of the storyboard has started (run at least once, or runs now).
    pub fn any_event_started(&self) -> bool {
        self.elems
            .iter()
            .any(|e| e.kind == Kind::Event && (e.runs > 0 || e.phase != Phase::Standby))
    }

    /// The acts and events that have never started and wait on their start triggers now,
    /// each as `act "NAME" (file:line:col)` with where its trigger's first condition is
    /// written: what the file describes and a test cut short by its horizon never played.
    /// An element that waits on a reaction a good run never sees (a collision, leaving the
    /// road, the end of the road, standing still) is not counted, nor one that waits for a
    /// simulation time past [`crate::xosc::HORIZON_CAP_S`] (a file's "never").
    pub fn never_started(&self) -> Vec<String> {
        let reaction = |c: &Cond| {
            matches!(
                c.cond.kind,
                m::ConditionKind::Entity {
                    test: m::EntityTest::Collision(_)
                        | m::EntityTest::CollisionByType(_)
                        | m::EntityTest::Offroad(_)
                        | m::EntityTest::EndOfRoad(_)
                        | m::EntityTest::Standstill(_),
                    ..
                }
            )
        };
        // A group that needs a simulation time past the longest test without `--horizon`
        // (files write 10^7 s for "never": CARLA's `ChangingWeather`) cannot fire in a test.
        let never = |c: &Cond| {
            matches!(
                c.cond.kind,
                m::ConditionKind::SimulationTime {
                    rule: Rule::Gt | Rule::Ge | Rule::Eq,
                    value,
                } if value > crate::xosc::HORIZON_CAP_S
            )
        };
        let mut waiting = Vec::new();
        for k in (0..self.triggers.len()).filter(|&k| self.waits(k)) {
            if self.triggers[k].iter().flatten().any(reaction) {
                continue;
            }
            if self.triggers[k].iter().all(|g| g.iter().any(never)) {
                continue;
            }
            let elem = match self.owners[k] {
                elements::Owner::ActStart(a) => a,
                elements::Owner::EventStart { event, .. } => event,
                elements::Owner::Storyboard | elements::Owner::ActStop(_) => continue,
            };
            let e = &self.elems[elem];
            if e.runs > 0 {
                continue;
            }
            let at = self.triggers[k]
                .iter()
                .flatten()
                .next()
                .map(|c| format!(" ({})", c.cond.pos))
                .unwrap_or_default();
            waiting.push(format!("{} {:?}{at}", e.kind.name(), e.name));
        }
        waiting
    }

    /// What the storyboard performs otherwise than written, found when it was built:
    /// `(file:line:col, what)` (a synchronization's target beyond its road's end, taken at
    /// the end as esmini takes it).
    pub fn notes(&self) -> &[(String, String)] {
        &self.notes
    }

    /// What the storyboard found in the last steps that the test's record should say (a
    /// speed profile whose plan leaves its entries' speeds), each once.
    pub fn take_said(&mut self) -> Vec<String> {
        std::mem::take(&mut self.said)
    }

    /// The events that have never started, each as `event "NAME"`, in the storyboard's order:
    /// what a test that ended (by its stop trigger, or its stories in CARLA's reading) did not
    /// play, for its record.
    pub fn never_ran(&self) -> Vec<String> {
        (self.elems.iter())
            .filter(|e| e.kind == Kind::Event && e.runs == 0 && e.phase != Phase::Running)
            .map(|e| format!("{} {:?}", e.kind.name(), e.name))
            .collect()
    }

    /// What the storyboard waits on when it can wait no more: `None` while anything can still
    /// change a condition it waits on; else the conditions of the triggers it waits on
    /// (their names and kinds). Nothing can change when every entity stands still (at most
    /// `still_mps`, m/s), no scripted entity has a motion in progress, and no trigger it waits
    /// on reads time: a `SimulationTimeCondition`, a `StandStillCondition` or
    /// `EndOfRoadCondition` (they hold after a duration), or a `delay`. A still world keeps
    /// every other condition's value, and so every edge away.
    pub fn stuck(&self, still_mps: f64) -> Option<Vec<String>> {
        if self.ended || !self.started {
            return None;
        }
        let moving = self.actors.iter().zip(&self.drives).any(|(a, d)| {
            a.state.speed.abs() > still_mps
                || (a.scripted
                    && (d.speed.is_some()
                        || d.lateral.is_some()
                        || d.lat_keep.is_some()
                        || d.path.is_some()
                        || d.sync.is_some()))
        });
        if moving {
            return None;
        }
        let mut waited = Vec::new();
        for k in (0..self.triggers.len()).filter(|&k| self.waits(k)) {
            for c in self.triggers[k].iter().flatten() {
                let timed = c.cond.delay_s > 0.0
                    || matches!(
                        c.cond.kind,
                        m::ConditionKind::SimulationTime { .. }
                            | m::ConditionKind::Entity {
                                test: m::EntityTest::Standstill(_)
                                    | m::EntityTest::EndOfRoad(_)
                                    | m::EntityTest::Offroad(_),
                                ..
                            }
                    );
                if timed {
                    return None;
                }
                waited.push(format!("{:?} ({})", c.cond.name, c.cond.pos));
            }
        }
        (!waited.is_empty()).then_some(waited)
    }

    /// Records whether entity `e` has touched anything solid.
    pub fn set_collided(&mut self, e: usize, collided: bool) {
        self.actors[e].state.collided = collided;
    }

    /// One step at time `t` (s) of length `dt` (s): the triggers read the world as it is at
    /// `t`, the elements move through their states, and every scripted entity moves to where
    /// it is at `t + dt`.
    ///
    /// # Errors
    /// [`StoryError`] for an action that cannot be performed where its entity stands.
    pub fn step(&mut self, t: f64, dt: f64) -> Result<(), StoryError> {
        // The transitions of the last step, for this step's conditions.
        for e in &mut self.elems {
            e.moves = elements::Moves::default();
        }
        let first = !self.started;
        if !self.started {
            self.started = true;
            for r in self.roots.clone() {
                self.start_elem(r, t)?;
            }
        }
        // A waiting trigger is evaluated when its element is visited (`run_story`).
        for k in 0..self.triggers.len() {
            if !self.waits(k) {
                // Not waiting: its delays start afresh when it waits again (and a latched
                // condition is unlatched); an edge is taken against the last value seen
                // (esmini's `OSCCondition::Reset` clears only the delay history).
                for c in self.triggers[k].iter_mut().flatten() {
                    c.forget_delay();
                }
            }
        }
        // The storyboard's stop trigger first, as esmini's traversal evaluates it.
        if let Some(k) = self.stop {
            if self.evaluate(k, t) {
                self.ended = true;
            }
        }
        for a in std::mem::take(&mut self.ending_next) {
            self.task_done(Some(a));
        }
        for r in self.roots.clone() {
            self.run_story(r, t)?;
        }
        self.end_instant_actions();
        self.keep_distances(t + dt, dt)?;
        self.synchronize(dt, first);
        for e in 0..self.actors.len() {
            if self.tow_of(e).is_some() {
                // A trailer goes where its tow pulls it (below).
                continue;
            }
            if self.actors[e].scripted {
                self.drive(e, t, dt)?;
            } else {
                self.ask_speed(e, t + dt);
                self.ask_lane(e);
                self.ask_path(e);
            }
        }
        self.pull_trailers(dt);
        self.trail_rear_axles();
        if self.watch_offroad {
            for a in &mut self.actors {
                // Off its own road's lanes where it moves along one (esmini's
                // `Position::IsOffRoad` reads `t` against its road's width), else off every
                // lane of the map.
                let p = a.state.pose;
                let off = match a.state.lane {
                    Some(lp) => !self.roads.on_its_road(&lp),
                    None => self.roads.anchor(p.x, p.y).is_none(),
                };
                a.state.offroad_s = off.then(|| a.state.offroad_s.map_or(0.0, |s| s + dt));
            }
        }
        // An event whose actions ended in this step's motion ends in this step.
        for ev in 0..self.elems.len() {
            let e = &self.elems[ev];
            if e.kind == Kind::Event
                && e.phase == Phase::Running
                && e.children
                    .iter()
                    .all(|&a| self.elems[a].phase == Phase::Complete)
            {
                self.end_elem(ev);
                if self.elems[ev].runs < self.elems[ev].max_runs {
                    self.rearm(ev);
                }
            }
        }
        self.settle_all(t)?;
        // CARLA's scenario ends with its stories (scenario_runner's behaviour tree succeeds
        // when every story has).
        let roots = &self.roots;
        if self.carla
            && !roots.is_empty()
            && roots
                .iter()
                .all(|&r| self.elems[r].phase == Phase::Complete)
        {
            self.ended = true;
        }
        Ok(())
    }

    /// The transitions the acts, events and actions made in the last [`Storyboard::step`]:
    /// `(kind, name, transition)`, kind `act`, `event` or `action`, transition `start`,
    /// `end`, `stop` or `skip` (the standard's names: startTransition, endTransition,
    /// stopTransition, skipTransition), in the storyboard's order.
    pub fn transitions(&self) -> Vec<(&'static str, &str, &'static str)> {
        let mut out = Vec::new();
        for e in &self.elems {
            if !matches!(e.kind, Kind::Act | Kind::Event | Kind::Action) {
                continue;
            }
            for (made, what) in [
                (e.moves.start, "start"),
                (e.moves.end, "end"),
                (e.moves.stop, "stop"),
                (e.moves.skip, "skip"),
            ] {
                if made {
                    out.push((e.kind.name(), e.name.as_str(), what));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_named_as_the_standard_names_them() {
        assert_eq!(Kind::Group.name(), "maneuverGroup");
        assert!(Kind::Action.name().eq_ignore_ascii_case("ACTION"));
    }
}
