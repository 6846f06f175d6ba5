//! The storyboard runtime: an OpenSCENARIO storyboard (OpenSCENARIO 1.3 User Guide,
//! "Storyboard and entities", "Conditions and triggers") run step by step over the test's
//! world. Stories, acts, maneuver groups, maneuvers, events and actions move through the
//! standard's states (standby, running, complete) on their triggers: condition groups (an OR
//! of ANDs), each condition with its edge and delay; event priorities (override, skip,
//! parallel) and execution counts. Scripted entities (every entity but the ego, which the
//! system under test drives) move as their actions say, on the map's lanes.

use std::collections::VecDeque;

use paracosm_openscenario::model::{
    self as m, Action, ConditionKind, Edge, EntityTest, Gap, LaneTarget, OffsetTarget, Position,
    Priority, Rule, SpeedTarget, TrajectoryShape,
};

use super::motion::{
    clothoid_poses, duration_s, nurbs_poses, offset_duration_s, Timed, Transition, Untimed,
};
use super::road::{wrap, LanePos, Pose, RoadError, Roads};

/// The largest lateral acceleration of a `LaneOffsetAction` without `maxLateralAcc`, m/s².
pub const DEFAULT_LATERAL_ACC_MPS2: f64 = 0.5;

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
    /// Whether the storyboard moves it now: every entity but the ego the system under test
    /// drives, and that ego too until its controller is activated
    /// ([`Storyboard::hand_over_on_activation`]).
    pub scripted: bool,
    /// Its state now.
    pub state: State,
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
    /// How long it has stood still, s.
    pub still_s: f64,
    /// How long it has stood at the end of its lanes, s.
    pub at_end_s: f64,
    /// Whether it has touched anything solid.
    pub collided: bool,
}

impl State {
    fn at(pose: Pose, lane: Option<LanePos>) -> Self {
        State {
            pose,
            speed: 0.0,
            accel: 0.0,
            lane,
            travelled_m: 0.0,
            still_s: 0.0,
            at_end_s: 0.0,
            collided: false,
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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Story,
    Act,
    Group,
    Maneuver,
    Event,
    Action,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Story => "story",
            Kind::Act => "act",
            Kind::Group => "maneuverGroup",
            Kind::Maneuver => "maneuver",
            Kind::Event => "event",
            Kind::Action => "action",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Standby,
    Running,
    Complete,
}

/// The transitions an element made in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Moves {
    start: bool,
    end: bool,
    stop: bool,
    skip: bool,
}

#[derive(Debug, Clone)]
struct Elem {
    kind: Kind,
    name: String,
    children: Vec<usize>,
    phase: Phase,
    runs: u32,
    max_runs: u32,
    /// Entity tasks of an action still in flight.
    pending: usize,
    start: Option<usize>,
    stop: Option<usize>,
    priority: Priority,
    /// An action's action and the entities it acts on.
    action: Option<(m::NamedAction, Vec<usize>)>,
    moves: Moves,
    last: Moves,
}

/// Whose trigger a trigger is, which says when it is evaluated: a start trigger while its
/// element waits in standby under a running parent, a stop trigger while its element runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    Storyboard,
    ActStart(usize),
    ActStop(usize),
    EventStart { event: usize, maneuver: usize },
}

#[derive(Debug, Clone)]
struct Cond {
    cond: m::Condition,
    /// Its value at its last evaluation; `None` before its first (its first evaluation, at
    /// the start of the simulation or when its element first waits, is no edge: a rising
    /// edge needs the condition seen false before it is seen true, as in esmini's
    /// `OSCCondition::CheckEdge`).
    prev: Option<bool>,
    history: VecDeque<(f64, bool)>,
}

/// A speed target that follows another entity: its index, the value, whether a factor.
type Track = Option<(usize, f64, bool)>;

/// A lane change's target: the lane and the offset from its centre there, m.
type ToLane = Option<(usize, f64)>;

/// A scripted entity's motion in progress, each with the action it belongs to.
#[derive(Debug, Clone, Default)]
struct Drive {
    /// The speed transition, a target that follows another entity, the action.
    speed: Option<(Transition, Track, usize)>,
    /// The lateral move in progress.
    lateral: Option<Lateral>,
    path: Option<(Path, usize)>,
    /// A driven ego's lane change in progress: the lane it changes to, the offset from its
    /// centre there (m), the action; it ends once the ego is there ([`LANE_REACHED_M`]).
    lane_goal: Option<(usize, f64, usize)>,
    prefer_roads: Vec<usize>,
    /// Its heading relative to its lane's travel, rad, kept as it moves along the lane
    /// (esmini's relative heading): set where it is placed or where its trajectory ends,
    /// 0 after a lateral move.
    rel_h: f64,
}

/// A lateral move (`LaneChangeAction`, `LaneOffsetAction`) as esmini performs it: the offset
/// `d` (m, left of increasing `s`) over a parameter that counts time (s) or, for a lane change
/// by distance, the path along the lane (m), from 0; stepped only while the entity moves.
#[derive(Debug, Clone, Copy)]
struct Lateral {
    /// The offset over the parameter (`start_s` 0).
    tr: Transition,
    /// The parameter so far.
    param: f64,
    /// Whether the parameter is the path along the lane (a lane change by distance).
    by_distance: bool,
    /// A `LaneOffsetAction`: the offset lags one step and the lane motion is not slowed.
    offset: bool,
    /// The lane it changes to.
    to_lane: ToLane,
    /// Its action.
    action: usize,
    /// Whether it goes on after its transition (`continuous`).
    continuous: bool,
}

#[derive(Debug, Clone)]
enum Path {
    Timed(Timed),
    Untimed(Untimed),
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
    trigger_now: Vec<bool>,
    stop: Option<usize>,
    params: Vec<(String, String)>,
    /// Whether the storyboard's stop trigger has fired.
    pub ended: bool,
    started: bool,
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
}

/// A route the storyboard asks of the ego the system under test drives (a `LaneChangeAction`
/// or an `AssignRouteAction` on it): from where the ego is, join `join` (a place on the lane
/// to drive in, abeam the ego, at the offset asked) `ahead_m` metres further along, then
/// follow the lanes from there, through junctions as the ego's route prefers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RouteAsk {
    /// The lane position abeam the ego (its station) on the lane to drive in.
    pub join: LanePos,
    /// How far ahead the route joins that lane, m: the lane change's length (its distance, or
    /// its duration at the ego's speed); 0 for a route on the lane the ego is in.
    pub ahead_m: f64,
}

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
        sb.trigger_now = vec![false; sb.triggers.len()];
        sb.perform_init(scenario)?;
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
                size_m: e.dimensions_m,
                centre_m: e.centre_m,
                scripted: Some(i) != ego,
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
            trigger_now: Vec::new(),
            stop: None,
            params: scenario
                .params
                .iter()
                .map(|(d, v)| (d.name.clone(), v.to_text()))
                .collect(),
            ended: false,
            started: false,
            set_speed: None,
            hand_over: None,
            route: None,
        }
    }

    /// Adds `act` under story element `s`: the act, its triggers, and its maneuver groups
    /// with their maneuvers, events and actions.
    ///
    /// # Errors
    /// [`StoryError`] for an action naming a road or lane the map lacks
    /// ([`Storyboard::check_references`]).
    fn add_act(&mut self, s: usize, act: &m::Act) -> Result<(), StoryError> {
        let a = self.push(Kind::Act, &act.name, 1);
        self.elems[s].children.push(a);
        // An empty trigger (`<StartTrigger/>`) is no trigger: the act starts with
        // its story (esmini's reading); an empty stop trigger never fires.
        self.elems[a].start = act
            .start
            .as_ref()
            .filter(|t| !t.0.is_empty())
            .map(|t| self.add_trigger(t, Owner::ActStart(a)));
        self.elems[a].stop = act
            .stop
            .as_ref()
            .filter(|t| !t.0.is_empty())
            .map(|t| self.add_trigger(t, Owner::ActStop(a)));
        for g in &act.groups {
            let gi = self.push(Kind::Group, &g.name, g.max_count);
            self.elems[a].children.push(gi);
            for man in &g.maneuvers {
                let mi = self.push(Kind::Maneuver, &man.name, 1);
                self.elems[gi].children.push(mi);
                for ev in &man.events {
                    self.add_event(mi, ev, &g.actors)?;
                }
            }
        }
        Ok(())
    }

    /// Adds event `ev` under maneuver element `mi`: the event, its start trigger, and its
    /// actions, each acting on `actors` (its maneuver group's).
    ///
    /// # Errors
    /// [`StoryError`] for an action naming a road or lane the map lacks
    /// ([`Storyboard::check_references`]).
    fn add_event(&mut self, mi: usize, ev: &m::Event, actors: &[usize]) -> Result<(), StoryError> {
        let ei = self.push(Kind::Event, &ev.name, ev.max_count);
        self.elems[mi].children.push(ei);
        self.elems[ei].priority = ev.priority;
        self.elems[ei].start = ev.start.as_ref().filter(|t| !t.0.is_empty()).map(|t| {
            self.add_trigger(
                t,
                Owner::EventStart {
                    event: ei,
                    maneuver: mi,
                },
            )
        });
        for na in &ev.actions {
            self.check_references(na)?;
            let ai = self.push(Kind::Action, &na.name, 1);
            self.elems[ei].children.push(ai);
            self.elems[ai].action = Some((na.clone(), actors.to_vec()));
        }
        Ok(())
    }

    /// Performs `scenario`'s `Init`: positions first, in the file's order, then the rest (a
    /// relative position may name an entity placed later in the file).
    ///
    /// # Errors
    /// [`StoryError`] for an `Init` action that cannot be performed.
    fn perform_init(&mut self, scenario: &m::Scenario) -> Result<(), StoryError> {
        let (places, rest): (Vec<_>, Vec<_>) = scenario
            .init
            .iter()
            .partition(|(_, a)| matches!(a.action, Action::Teleport(_)));
        for (e, a) in places.into_iter().chain(rest) {
            self.start_task(*e, a, None, 0.0)?;
        }
        Ok(())
    }

    /// Checks the roads and lanes that `na` names where they do not depend on where an
    /// entity is when it starts: a teleport or a route's waypoint to a lane or road position
    /// (the road, the lane at that station), and a lane change to an absolute lane id (some
    /// road of the map has it). So a reference that cannot be met is refused when the file
    /// loads, at the action's line and column, rather than failing every test.
    ///
    /// # Errors
    /// [`StoryError`] at the action, naming the action and the map's refusal.
    fn check_references(&self, na: &m::NamedAction) -> Result<(), StoryError> {
        let refused = |message: String| StoryError {
            at: site(&na.pos),
            message: format!("{} {:?}: {message}", na.action.kind_name(), na.name),
        };
        let position = |p: &Position| -> Result<(), StoryError> {
            match p {
                Position::Lane { road, lane, s, .. } => self
                    .roads
                    .lane_pos(road, *lane, *s, 0.0)
                    .map(drop)
                    .map_err(|e| refused(e.to_string())),
                Position::Road { road, s, t, .. } => self
                    .roads
                    .road_pos(road, *s, *t)
                    .map(drop)
                    .map_err(|e| refused(e.to_string())),
                _ => Ok(()),
            }
        };
        match &na.action {
            Action::Teleport(p) => position(p),
            Action::AssignRoute { waypoints } => {
                waypoints.iter().try_for_each(|(p, _)| position(p))
            }
            Action::LaneChange {
                target: LaneTarget::Absolute(id),
                ..
            } => {
                if self.roads.map().lanes.iter().any(|l| l.od_id == *id) {
                    Ok(())
                } else {
                    Err(refused(format!(
                        "no road of the map has a lane {id}, so no entity can change to it"
                    )))
                }
            }
            _ => Ok(()),
        }
    }

    fn push(&mut self, kind: Kind, name: &str, max_runs: u32) -> usize {
        self.elems.push(Elem {
            kind,
            name: name.to_owned(),
            children: Vec::new(),
            phase: Phase::Standby,
            runs: 0,
            max_runs: max_runs.max(1),
            pending: 0,
            start: None,
            stop: None,
            priority: Priority::Override,
            action: None,
            moves: Moves::default(),
            last: Moves::default(),
        });
        self.elems.len() - 1
    }

    fn add_trigger(&mut self, t: &m::Trigger, owner: Owner) -> usize {
        self.owners.push(owner);
        self.triggers.push(
            t.0.iter()
                .map(|g| {
                    g.iter()
                        .map(|c| Cond {
                            cond: c.clone(),
                            prev: None,
                            history: VecDeque::new(),
                        })
                        .collect()
                })
                .collect(),
        );
        self.triggers.len() - 1
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
                || (a.scripted && (d.speed.is_some() || d.lateral.is_some() || d.path.is_some()))
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
                                test: m::EntityTest::Standstill(_) | m::EntityTest::EndOfRoad(_),
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
            e.last = std::mem::take(&mut e.moves);
        }
        if !self.started {
            self.started = true;
            for r in self.roots.clone() {
                self.start_elem(r, t)?;
            }
        }
        for k in 0..self.triggers.len() {
            if self.waits(k) {
                self.trigger_now[k] = self.evaluate(k, t);
            } else {
                // Not waiting: its delays start afresh when it waits again; an edge is taken
                // against the last value seen (esmini's `OSCCondition::Reset` clears only the
                // delay history).
                self.trigger_now[k] = false;
                for c in self.triggers[k].iter_mut().flatten() {
                    c.history.clear();
                }
            }
        }
        if let Some(k) = self.stop {
            if self.trigger_now[k] {
                self.ended = true;
            }
        }
        for r in self.roots.clone() {
            self.run_story(r, t)?;
        }
        for e in 0..self.actors.len() {
            if self.actors[e].scripted {
                self.drive(e, t, dt)?;
            } else {
                self.ask_speed(e, t + dt);
                self.ask_lane(e);
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
                    self.elems[ev].phase = Phase::Standby;
                }
            }
        }
        Ok(())
    }

    /// Whether trigger `k` is evaluated now: the storyboard's stop trigger always, a start
    /// trigger while its element waits in standby under a running parent, an act's stop
    /// trigger while the act runs.
    fn waits(&self, k: usize) -> bool {
        match self.owners[k] {
            Owner::Storyboard => true,
            Owner::ActStart(a) => self.elems[a].phase == Phase::Standby,
            Owner::ActStop(a) => self.elems[a].phase == Phase::Running,
            Owner::EventStart { event, maneuver } => {
                self.elems[event].phase == Phase::Standby
                    && self.elems[maneuver].phase == Phase::Running
            }
        }
    }

    fn run_story(&mut self, s: usize, t: f64) -> Result<(), StoryError> {
        for a in self.elems[s].children.clone() {
            match self.elems[a].phase {
                Phase::Standby => {
                    let go = self.elems[a].start.is_none_or(|k| self.trigger_now[k]);
                    if go {
                        self.start_elem(a, t)?;
                        for g in self.elems[a].children.clone() {
                            self.start_group(g, t)?;
                        }
                    }
                }
                Phase::Running => {
                    if self.elems[a].stop.is_some_and(|k| self.trigger_now[k]) {
                        self.stop_elem(a);
                        continue;
                    }
                    let mut all = true;
                    for g in self.elems[a].children.clone() {
                        self.run_group(g, t)?;
                        all &= self.elems[g].phase == Phase::Complete;
                    }
                    if all {
                        self.end_elem(a);
                    }
                }
                Phase::Complete => {}
            }
        }
        if self.elems[s]
            .children
            .iter()
            .all(|&a| self.elems[a].phase == Phase::Complete)
            && self.elems[s].phase == Phase::Running
        {
            self.end_elem(s);
        }
        Ok(())
    }

    fn start_group(&mut self, g: usize, t: f64) -> Result<(), StoryError> {
        self.start_elem(g, t)?;
        for man in self.elems[g].children.clone() {
            self.start_elem(man, t)?;
            for ev in self.elems[man].children.clone() {
                let e = &mut self.elems[ev];
                e.phase = Phase::Standby;
                e.runs = 0;
            }
        }
        Ok(())
    }

    fn run_group(&mut self, g: usize, t: f64) -> Result<(), StoryError> {
        if self.elems[g].phase != Phase::Running {
            return Ok(());
        }
        let mut all = true;
        for man in self.elems[g].children.clone() {
            self.run_maneuver(man, t)?;
            all &= self.elems[man].phase == Phase::Complete;
        }
        if all {
            self.elems[g].runs += 1;
            if self.elems[g].runs < self.elems[g].max_runs {
                let runs = self.elems[g].runs;
                self.start_group(g, t)?;
                self.elems[g].runs = runs;
            } else {
                self.end_elem(g);
            }
        }
        Ok(())
    }

    fn run_maneuver(&mut self, man: usize, t: f64) -> Result<(), StoryError> {
        if self.elems[man].phase != Phase::Running {
            return Ok(());
        }
        let events = self.elems[man].children.clone();
        for &ev in &events {
            if self.elems[ev].phase != Phase::Standby {
                continue;
            }
            if !self.elems[ev].start.is_none_or(|k| self.trigger_now[k]) {
                continue;
            }
            let others: Vec<usize> = events
                .iter()
                .copied()
                .filter(|&o| o != ev && self.elems[o].phase == Phase::Running)
                .collect();
            match self.elems[ev].priority {
                Priority::Skip if !others.is_empty() => {
                    self.elems[ev].moves.skip = true;
                    continue;
                }
                Priority::Override => {
                    for o in others {
                        self.stop_elem(o);
                    }
                }
                _ => {}
            }
            self.start_elem(ev, t)?;
            self.elems[ev].runs += 1;
            for a in self.elems[ev].children.clone() {
                self.start_action(a, t)?;
            }
        }
        for &ev in &events {
            if self.elems[ev].phase == Phase::Running
                && self.elems[ev]
                    .children
                    .iter()
                    .all(|&a| self.elems[a].phase == Phase::Complete)
            {
                self.end_elem(ev);
                if self.elems[ev].runs < self.elems[ev].max_runs {
                    self.elems[ev].phase = Phase::Standby;
                }
            }
        }
        if events
            .iter()
            .all(|&ev| self.elems[ev].phase == Phase::Complete)
        {
            self.end_elem(man);
        }
        Ok(())
    }

    fn start_elem(&mut self, i: usize, _t: f64) -> Result<(), StoryError> {
        let e = &mut self.elems[i];
        e.phase = Phase::Running;
        e.moves.start = true;
        Ok(())
    }

    fn end_elem(&mut self, i: usize) {
        let e = &mut self.elems[i];
        if e.phase != Phase::Complete {
            e.phase = Phase::Complete;
            e.moves.end = true;
        }
    }

    /// Stops element `i` and everything running below it (their entity tasks end).
    fn stop_elem(&mut self, i: usize) {
        for c in self.elems[i].children.clone() {
            if self.elems[c].phase != Phase::Complete {
                self.stop_elem(c);
            }
        }
        if self.elems[i].kind == Kind::Action {
            for d in &mut self.drives {
                if d.speed.as_ref().is_some_and(|s| s.2 == i) {
                    d.speed = None;
                }
                if d.lateral.as_ref().is_some_and(|l| l.action == i) {
                    d.lateral = None;
                }
                if d.path.as_ref().is_some_and(|s| s.1 == i) {
                    d.path = None;
                }
            }
            self.elems[i].pending = 0;
        }
        let e = &mut self.elems[i];
        e.phase = Phase::Complete;
        e.moves.stop = true;
    }

    fn start_action(&mut self, a: usize, t: f64) -> Result<(), StoryError> {
        self.start_elem(a, t)?;
        let Some((action, actors)) = self.elems[a].action.clone() else {
            return Ok(());
        };
        for e in actors {
            // An action that cannot be performed names itself and its entity.
            self.start_task(e, &action, Some(a), t)
                .map_err(|err| StoryError {
                    at: err.at,
                    message: format!(
                        "{} {:?} of {}: {}",
                        action.action.kind_name(),
                        action.name,
                        self.actors[e].name,
                        err.message
                    ),
                })?;
        }
        if self.elems[a].pending == 0 {
            self.end_elem(a);
        }
        Ok(())
    }

    /// A task of action `a` (an element, `None` in `Init`) ended.
    fn task_done(&mut self, a: Option<usize>) {
        if let Some(a) = a {
            let e = &mut self.elems[a];
            e.pending = e.pending.saturating_sub(1);
            if e.pending == 0 && e.phase == Phase::Running {
                self.end_elem(a);
            }
        }
    }

    /// Lane position `lp` facing `h` (rad): its pose, and its place on the lanes the way it
    /// faces.
    fn placed(&self, lp: LanePos, h: f64) -> (Pose, Option<LanePos>) {
        let lp = self.roads.facing(lp, h);
        let pose = Pose {
            h,
            ..self.roads.pose_of(&lp)
        };
        (pose, Some(lp))
    }

    /// Where entity `e` is on the lanes, for a position of kind `what` relative to it.
    ///
    /// # Errors
    /// [`StoryError`] at `at` when `e` is on no lane.
    fn lane_of(
        &self,
        e: usize,
        what: &str,
        at: &paracosm_openscenario::Pos,
    ) -> Result<LanePos, StoryError> {
        let r = &self.actors[e];
        r.state.lane.ok_or_else(|| StoryError {
            at: site(at),
            message: format!("a {what} to {}, which is not on a lane", r.name),
        })
    }

    /// Where `p` is now: its pose and its place on the lanes.
    ///
    /// # Errors
    /// [`StoryError`] for a position off the map.
    pub fn resolve(
        &self,
        p: &Position,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let bad = |message: String| StoryError {
            at: site(at),
            message,
        };
        Ok(match p {
            Position::World { x, y, h } => {
                let pose = Pose {
                    x: *x,
                    y: *y,
                    h: h.unwrap_or(0.0),
                };
                (pose, self.facing(self.roads.anchor(*x, *y), pose.h))
            }
            Position::RelativeWorld {
                entity,
                dx,
                dy,
                orientation,
            } => self.world_offset(*entity, *dx, *dy, orientation),
            Position::RelativeObject {
                entity,
                dx,
                dy,
                orientation,
            } => self.object_offset(*entity, *dx, *dy, orientation),
            Position::Road {
                road,
                s,
                t,
                orientation,
            } => {
                let lp = self
                    .roads
                    .road_pos(road, *s, *t)
                    .map_err(|e| bad(e.to_string()))?;
                let h = orient(orientation, self.roads.along_heading(&lp));
                self.placed(lp, h)
            }
            Position::Lane {
                road,
                lane,
                s,
                offset,
                orientation,
            } => self.lane_position(road, (*lane, *s, *offset), orientation, at)?,
            Position::RelativeRoad {
                entity,
                ds,
                dt,
                orientation,
            } => self.road_offset(*entity, (*ds, *dt), orientation, at)?,
            Position::RelativeLane {
                entity,
                d_lane,
                ds,
                offset,
            } => {
                let lp = self.lane_of(*entity, "RelativeLanePosition", at)?;
                let lp = self
                    .roads
                    .relative_lane(&lp, *d_lane, *ds, *offset)
                    .map_err(|e| bad(e.to_string()))?;
                (self.roads.pose_of(&lp), Some(lp))
            }
        })
    }

    /// A `RelativeWorldPosition`: `dx`, `dy` (m, along the world's axes) from entity
    /// `entity`, heading `orientation` against the entity's (rad); its pose and its place on
    /// the lanes.
    fn world_offset(
        &self,
        entity: usize,
        dx: f64,
        dy: f64,
        orientation: &Option<m::Orientation>,
    ) -> (Pose, Option<LanePos>) {
        let r = self.actors[entity].state.pose;
        let (x, y) = (r.x + dx, r.y + dy);
        let pose = Pose {
            x,
            y,
            h: orient(orientation, r.h),
        };
        (pose, self.facing(self.roads.anchor(x, y), pose.h))
    }

    /// A `RelativeObjectPosition`: `dx` forward and `dy` left (m, in entity `entity`'s
    /// frame) of the entity, heading `orientation` against the entity's (rad); its pose and
    /// its place on the lanes.
    fn object_offset(
        &self,
        entity: usize,
        dx: f64,
        dy: f64,
        orientation: &Option<m::Orientation>,
    ) -> (Pose, Option<LanePos>) {
        let r = self.actors[entity].state.pose;
        let (c, s) = (r.h.cos(), r.h.sin());
        let (x, y) = (r.x + c * dx - s * dy, r.y + s * dx + c * dy);
        let pose = Pose {
            x,
            y,
            h: orient(orientation, r.h),
        };
        (pose, self.facing(self.roads.anchor(x, y), pose.h))
    }

    /// A `LanePosition`: lane id `lane` of road `road`, `s` along the road (m), `offset` from
    /// the lane's centre (m), heading `orientation` against the lane's driving direction
    /// (rad); its pose and its place on the lanes.
    ///
    /// # Errors
    /// [`StoryError`] at `at` for a road or lane the map lacks.
    fn lane_position(
        &self,
        road: &str,
        (lane, s, offset): (i32, f64, f64),
        orientation: &Option<m::Orientation>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let lp = self
            .roads
            .lane_pos(road, lane, s, offset)
            .map_err(|e| StoryError {
                at: site(at),
                message: e.to_string(),
            })?;
        // Without an orientation, or relative to it, the lane's driving direction
        // (esmini's reading: a left lane of right-hand traffic faces against `s`).
        let travel = self.roads.travel_heading(&LanePos { rev: false, ..lp });
        let h = orient(orientation, travel);
        Ok(self.placed(lp, h))
    }

    /// A `RelativeRoadPosition`: `ds` along and `dt` across (m) entity `entity`'s road from
    /// its road coordinates, heading `orientation` against the road's reference line (rad);
    /// its pose and its place on the lanes.
    ///
    /// # Errors
    /// [`StoryError`] at `at` when the entity is on no lane or the place is off its road.
    fn road_offset(
        &self,
        entity: usize,
        (ds, dt): (f64, f64),
        orientation: &Option<m::Orientation>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let bad = |message: String| StoryError {
            at: site(at),
            message,
        };
        let lp = self.lane_of(entity, "RelativeRoadPosition", at)?;
        let (road, t) = self.roads.road_t(&lp).map_err(|e| bad(e.to_string()))?;
        let lp = self
            .roads
            .road_pos(&road, lp.s + ds, t + dt)
            .map_err(|e| bad(e.to_string()))?;
        let h = orient(orientation, self.roads.along_heading(&lp));
        Ok(self.placed(lp, h))
    }

    /// Starts action `action` on entity `e` at `t` (s), for action element `a` (`None` in
    /// `Init`).
    fn start_task(
        &mut self,
        e: usize,
        action: &m::NamedAction,
        a: Option<usize>,
        t: f64,
    ) -> Result<(), StoryError> {
        let bad = |message: String| StoryError {
            at: site(&action.pos),
            message,
        };
        let scripted = self.actors[e].scripted;
        match &action.action {
            Action::Teleport(p) => {
                if scripted || a.is_none() {
                    self.teleport(e, p, &action.pos)?;
                }
            }
            Action::Speed { target, dynamics } => {
                return self.start_speed(e, (target, dynamics), a, t);
            }
            Action::LaneChange {
                target,
                dynamics,
                offset_m,
            } => {
                return self.start_lane_change(e, (target, dynamics, offset_m), (a, &action.pos));
            }
            Action::LaneOffset {
                target,
                shape,
                max_lateral_acc,
                continuous,
            } => {
                return self.start_lane_offset(
                    e,
                    (target, shape, max_lateral_acc, continuous),
                    (a, &action.pos),
                );
            }
            Action::LongitudinalDistance {
                entity,
                distance_m,
                time_gap_s,
                freespace,
                displacement,
                ..
            } => {
                if !scripted {
                    return Ok(());
                }
                self.place_at_distance(
                    e,
                    *entity,
                    (*distance_m, *time_gap_s, *freespace),
                    displacement,
                )
                .map_err(|e| bad(e.to_string()))?;
            }
            Action::FollowTrajectory { shape, timing } => {
                return self.start_trajectory(e, (shape, timing), (a, &action.pos), t);
            }
            Action::AssignRoute { waypoints } => {
                self.assign_route(e, waypoints, &action.pos, scripted)?;
            }
            Action::ActivateController {
                lateral,
                longitudinal,
            } => self.activate_controller(e, *lateral, *longitudinal),
        }
        Ok(())
    }

    /// Performs a `TeleportAction` of entity `e` to `p` (written at `at`): places it there,
    /// notes its heading relative to its lane's travel (rad), and ends the path or lateral
    /// move it was making (and their actions).
    ///
    /// # Errors
    /// [`StoryError`] for a position off the map.
    fn teleport(
        &mut self,
        e: usize,
        p: &Position,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(), StoryError> {
        let (pose, lane) = self.resolve(p, at)?;
        let st = &mut self.actors[e].state;
        st.pose = pose;
        st.lane = lane;
        self.drives[e].rel_h = self.relative_heading(pose.h, lane);
        let d = &mut self.drives[e];
        // The motion it was making ends (and its action with it).
        let old = [
            d.path.take().map(|p| p.1),
            d.lateral.take().map(|l| l.action),
        ];
        for o in old {
            self.override_task(o);
        }
        Ok(())
    }

    /// Performs an `AssignRouteAction` (written at `at`) on entity `e`: the roads of its
    /// `waypoints` become the roads it prefers at junctions; for the driven ego (not
    /// `scripted`), a route planned again from where it is.
    ///
    /// # Errors
    /// [`StoryError`] for a waypoint off the map.
    fn assign_route(
        &mut self,
        e: usize,
        waypoints: &[(Position, String)],
        at: &paracosm_openscenario::Pos,
        scripted: bool,
    ) -> Result<(), StoryError> {
        let mut roads = Vec::new();
        for (p, _) in waypoints {
            if let (_, Some(lp)) = self.resolve(p, at)? {
                roads.push(self.roads.ids(lp.lane).1);
            }
        }
        self.drives[e].prefer_roads = roads;
        if !scripted {
            // The driven ego's route, planned again from where it is.
            if let Some(lp) = self.actors[e].state.lane {
                self.route = Some(RouteAsk {
                    join: lp,
                    ahead_m: 0.0,
                });
            }
        }
        Ok(())
    }

    /// Performs an `ActivateControllerAction` on entity `e` with its `lateral` and
    /// `longitudinal` domains: the ego handed over on activation is then driven by the
    /// system under test, its lateral move and path ended.
    fn activate_controller(&mut self, e: usize, lateral: Option<bool>, longitudinal: Option<bool>) {
        // Any domain activated hands the whole ego over (the load says so); a
        // deactivation is refused at load (`check`).
        let on = lateral.unwrap_or(true) || longitudinal.unwrap_or(true);
        if on && Some(e) == self.hand_over && self.actors[e].scripted {
            self.actors[e].scripted = false;
            // Its lateral move and path end with the script (and their actions); a
            // running SpeedAction goes on as the system's set speed.
            let old = [
                self.drives[e].lateral.take().map(|l| l.action),
                self.drives[e].path.take().map(|p| p.1),
            ];
            for o in old {
                self.override_task(o);
            }
        }
    }

    /// Starts a `SpeedAction` on `e` (see [`Storyboard::start_task`]).
    fn start_speed(
        &mut self,
        e: usize,
        (target, dynamics): (&SpeedTarget, &m::Dynamics),
        a: Option<usize>,
        t: f64,
    ) -> Result<(), StoryError> {
        let scripted = self.actors[e].scripted;
        let begin = |sb: &mut Storyboard| {
            if let Some(a) = a {
                sb.elems[a].pending += 1;
            }
        };

        let v0 = self.actors[e].state.speed;
        let (to, track) = match target {
            SpeedTarget::Absolute(v) => (*v, None),
            SpeedTarget::Relative {
                entity,
                value,
                factor,
                continuous,
            } => {
                let r = self.actors[*entity].state.speed;
                let v = if *factor { r * value } else { r + value };
                (v, continuous.then_some((*entity, *value, *factor)))
            }
        };
        if !scripted && a.is_none() {
            // The ego's initial speed; later, the system under test drives it.
            self.actors[e].state.speed = to.max(0.0);
            return Ok(());
        }
        let tr = Transition {
            from: v0,
            to: to.max(0.0),
            start_s: t,
            duration_s: duration_s(dynamics, to - v0, 0.5 * (v0 + to).abs()),
            shape: dynamics.shape,
        };
        if a.is_none() && tr.duration_s == 0.0 {
            self.actors[e].state.speed = tr.to;
            return Ok(());
        }
        let old = self.drives[e].speed.take().map(|s| s.2);
        self.override_task(old);
        begin(self);
        self.drives[e].speed = Some((tr, track, a.unwrap_or(usize::MAX)));

        Ok(())
    }

    /// Starts a `LaneChangeAction` on `e`.
    fn start_lane_change(
        &mut self,
        e: usize,
        (target, dynamics, offset_m): (&LaneTarget, &m::Dynamics, &f64),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
    ) -> Result<(), StoryError> {
        let bad = |message: String| StoryError {
            at: site(pos),
            message,
        };
        let scripted = self.actors[e].scripted;
        let st = self.actors[e].state;
        let Some(lp) = st.lane else {
            return Err(bad(format!(
                "a LaneChangeAction for {}, which is not on a lane",
                self.actors[e].name
            )));
        };
        let id = self.lane_change_target_id(target, pos)?;
        let to_lane = self.roads.lane_with_id(lp.lane, id, lp.s).ok_or_else(|| {
            bad(format!(
                "{}'s road has no lane {id} at s = {:.1} m",
                self.actors[e].name, lp.s
            ))
        })?;
        let target_d = self.roads.lateral_between(lp.lane, to_lane, lp.s) + offset_m;
        // By distance, the parameter is the path along the lane; by time or rate, time.
        let by_distance = dynamics.dimension == m::Dimension::Distance;
        let duration = if by_distance {
            dynamics.value.abs()
        } else {
            duration_s(dynamics, target_d - lp.d, st.speed.abs())
        };
        if !scripted {
            self.ask_lane_change_route(e, (lp, to_lane, *offset_m), (by_distance, duration), a);
            return Ok(());
        }
        let tr = Transition {
            from: lp.d,
            to: target_d,
            start_s: 0.0,
            duration_s: if dynamics.shape == m::Shape::Step {
                0.0
            } else {
                duration
            },
            shape: dynamics.shape,
        };
        self.begin_lateral(
            e,
            Lateral {
                tr,
                param: 0.0,
                by_distance,
                offset: false,
                to_lane: Some((to_lane, *offset_m)),
                action: a.unwrap_or(usize::MAX),
                continuous: false,
            },
            a,
        );
        Ok(())
    }

    /// The lane id a `LaneChangeAction` (written at `pos`) changes to: an absolute one as
    /// written; a relative one counted from the reference entity's lane, to its left as it
    /// drives, skipping id 0.
    ///
    /// # Errors
    /// [`StoryError`] at `pos` when the reference entity is on no lane.
    fn lane_change_target_id(
        &self,
        target: &LaneTarget,
        pos: &paracosm_openscenario::Pos,
    ) -> Result<i32, StoryError> {
        Ok(match target {
            LaneTarget::Absolute(id) => *id,
            LaneTarget::Relative { entity, lanes } => {
                let Some(rl) = self.actors[*entity].state.lane else {
                    return Err(StoryError {
                        at: site(pos),
                        message: format!(
                            "a lane change relative to {}, which is not on a lane",
                            self.actors[*entity].name
                        ),
                    });
                };
                // Counted to the reference's left as it drives: +t along s.
                let step = if rl.along_s(&self.roads) {
                    lanes.signum()
                } else {
                    -lanes.signum()
                };
                let mut id = self.roads.ids(rl.lane).0;
                for _ in 0..lanes.unsigned_abs() {
                    id += step;
                    if id == 0 {
                        id += step;
                    }
                }
                id
            }
        })
    }

    /// A lane change of the driven ego `e` (which the system under test drives), from `lp`
    /// into lane `to_lane` at `offset_m` (m) from its centre, for action `a`: asks for a
    /// route into the lane over the change's length (`duration` is m when `by_distance`,
    /// else s at the ego's speed; at least one second of driving and 1 m), which it follows,
    /// and notes the lane goal that ends the action, ending the one it replaces.
    fn ask_lane_change_route(
        &mut self,
        e: usize,
        (lp, to_lane, offset_m): (LanePos, usize, f64),
        (by_distance, duration): (bool, f64),
        a: Option<usize>,
    ) {
        let st = self.actors[e].state;
        // The system under test drives it: a route into the lane, over the change's
        // length (at least one second of driving), which it follows.
        let ahead_m = if by_distance {
            duration
        } else {
            duration * st.speed.abs()
        }
        .max(st.speed.abs())
        .max(1.0);
        let join = LanePos {
            lane: to_lane,
            s: lp.s,
            d: offset_m,
            rev: lp.rev,
        };
        self.route = Some(RouteAsk { join, ahead_m });
        let old = self.drives[e].lane_goal.take().map(|g| g.2);
        self.override_task(old);
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        self.drives[e].lane_goal = Some((to_lane, offset_m, a.unwrap_or(usize::MAX)));
    }

    /// Starts lateral move `l` of `e` for action `a`, ending the one it replaces.
    fn begin_lateral(&mut self, e: usize, l: Lateral, a: Option<usize>) {
        let old = self.drives[e].lateral.take().map(|s| s.action);
        self.override_task(old);
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        // It aligns with the road as it starts (esmini's reading).
        self.drives[e].rel_h = 0.0;
        self.drives[e].lateral = Some(l);
    }

    /// Starts a `LaneOffsetAction` on `e`.
    fn start_lane_offset(
        &mut self,
        e: usize,
        (target, shape, max_lateral_acc, continuous): (
            &OffsetTarget,
            &m::Shape,
            &Option<f64>,
            &bool,
        ),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
    ) -> Result<(), StoryError> {
        let bad = |message: String| StoryError {
            at: site(pos),
            message,
        };
        let scripted = self.actors[e].scripted;
        if !scripted {
            return Ok(());
        }
        let Some(lp) = self.actors[e].state.lane else {
            return Err(bad(format!(
                "a LaneOffsetAction for {}, which is not on a lane",
                self.actors[e].name
            )));
        };
        let to = match target {
            OffsetTarget::Absolute(v) => *v,
            OffsetTarget::Relative { entity, value } => {
                self.actors[*entity].state.lane.map_or(0.0, |l| l.d) + value
            }
        };
        let acc = max_lateral_acc.unwrap_or(DEFAULT_LATERAL_ACC_MPS2);
        let tr = Transition {
            from: lp.d,
            to,
            start_s: 0.0,
            duration_s: offset_duration_s(*shape, to - lp.d, acc),
            shape: *shape,
        };
        self.begin_lateral(
            e,
            Lateral {
                tr,
                param: 0.0,
                by_distance: false,
                offset: true,
                to_lane: None,
                action: a.unwrap_or(usize::MAX),
                continuous: *continuous,
            },
            a,
        );
        Ok(())
    }

    /// Starts a `FollowTrajectoryAction` on `e`.
    #[allow(clippy::type_complexity)]
    fn start_trajectory(
        &mut self,
        e: usize,
        (shape, timing): (&TrajectoryShape, &Option<(bool, f64, f64)>),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
        t: f64,
    ) -> Result<(), StoryError> {
        let scripted = self.actors[e].scripted;
        let begin = |sb: &mut Storyboard| {
            if let Some(a) = a {
                sb.elems[a].pending += 1;
            }
        };

        if !scripted {
            return Ok(());
        }
        let points = self.trajectory_points(e, shape, pos)?;
        let timed = points.iter().all(|(time, _)| time.is_some());
        let path = match timing {
            Some((absolute, scale, offset)) if timed => {
                let base = if *absolute { 0.0 } else { t };
                Path::Timed(Timed {
                    vertices: points
                        .iter()
                        .map(|(time, p)| (base + time.unwrap_or(0.0) * scale + offset, *p))
                        .collect(),
                })
            }
            _ => Path::Untimed(Untimed {
                vertices: points.into_iter().map(|(_, p)| p).collect(),
                gone_m: 0.0,
            }),
        };
        // On the trajectory from the start (esmini's reading): a timed one where it is at `t`,
        // one started in `Init` at its first vertex.
        let here = match &path {
            Path::Timed(p) => Some(p.at(t).0),
            Path::Untimed(u) if a.is_none() => u.vertices.first().copied(),
            Path::Untimed(_) => None,
        };
        if let Some(p) = here {
            let lane = self.facing(self.roads.anchor(p.x, p.y), p.h);
            let st = &mut self.actors[e].state;
            st.pose = p;
            st.lane = lane;
        }
        let d = &mut self.drives[e];
        let old = [
            d.path.take().map(|p| p.1),
            d.lateral.take().map(|l| l.action),
        ];
        for o in old {
            self.override_task(o);
        }
        begin(self);
        self.drives[e].path = Some((path, a.unwrap_or(usize::MAX)));

        Ok(())
    }

    /// The points of trajectory `shape` for entity `e`, with their times in the file (none
    /// untimed): a polyline's vertices (a world vertex without a heading facing along its leg,
    /// the next vertex, or for the last the one before, as esmini aligns what a file omits); a
    /// clothoid sampled from its start (`e`'s pose without a `Position`), its times linear in
    /// the distance along it; a NURBS sampled along its parameter.
    ///
    /// # Errors
    /// [`StoryError`] for a position that cannot be resolved (`pos`: the action's).
    fn trajectory_points(
        &self,
        e: usize,
        shape: &TrajectoryShape,
        pos: &paracosm_openscenario::Pos,
    ) -> Result<Vec<(Option<f64>, Pose)>, StoryError> {
        Ok(match shape {
            TrajectoryShape::Polyline(vertices) => {
                let mut poses = Vec::new();
                for (_, p) in vertices {
                    poses.push(self.resolve(p, pos)?.0);
                }
                for k in 0..poses.len() {
                    if matches!(vertices[k].1, Position::World { h: None, .. }) {
                        let (a, b) = match (poses.get(k), poses.get(k + 1)) {
                            (Some(a), Some(b)) => (*a, *b),
                            _ if k > 0 => (poses[k - 1], poses[k]),
                            _ => continue,
                        };
                        if (b.x - a.x).hypot(b.y - a.y) > 1e-9 {
                            poses[k].h = (b.y - a.y).atan2(b.x - a.x);
                        }
                    }
                }
                vertices.iter().map(|(t, _)| *t).zip(poses).collect()
            }
            TrajectoryShape::Clothoid {
                start,
                curvature,
                curvature_prime,
                length,
                times,
            } => {
                let from = match start {
                    Some(p) => self.resolve(p, pos)?.0,
                    None => self.actors[e].state.pose,
                };
                clothoid_poses(from, *curvature, *curvature_prime, *length)
                    .into_iter()
                    .map(|(d, p)| (times.map(|(a, b)| a + (b - a) * d / length), p))
                    .collect()
            }
            TrajectoryShape::Nurbs {
                order,
                points,
                knots,
            } => {
                let mut at = Vec::new();
                for (time, weight, p) in points {
                    let q = self.resolve(p, pos)?.0;
                    let given = !matches!(p, Position::World { h: None, .. });
                    at.push((*time, *weight, [q.x, q.y], given.then_some(q.h)));
                }
                nurbs_poses(*order, &at, knots)
            }
        })
    }

    /// `lp` (if any) facing `h`.
    fn facing(&self, lp: Option<LanePos>, h: f64) -> Option<LanePos> {
        lp.map(|lp| self.roads.facing(lp, h))
    }

    /// Heading `h` relative to the travel of lane position `lp`, rad (0 off the lanes).
    fn relative_heading(&self, h: f64, lp: Option<LanePos>) -> f64 {
        lp.map_or(0.0, |lp| wrap(h - self.roads.travel_heading(&lp)))
    }

    /// A task replaced by a new one of the same kind on the same entity ends (its action
    /// completes once all its tasks have).
    fn override_task(&mut self, a: Option<usize>) {
        if let Some(a) = a.filter(|&a| a != usize::MAX) {
            self.task_done(Some(a));
        }
    }

    /// Puts entity `e` on `reference`'s lane at a distance `(distance, time gap, freespace)`
    /// ahead of it (`leadingReferencedEntity`, or `any` when ahead now) or behind it.
    fn place_at_distance(
        &mut self,
        e: usize,
        reference: usize,
        (distance, gap_s, freespace): (Option<f64>, Option<f64>, bool),
        displacement: &str,
    ) -> Result<(), RoadError> {
        let r = self.actors[reference].clone();
        let me = self.actors[e].clone();
        let Some(rl) = r.state.lane else {
            return Err(RoadError(format!(
                "a LongitudinalDistanceAction to {}, which is not on a lane",
                r.name
            )));
        };
        let gap = match (distance, gap_s) {
            (Some(d), _) => d,
            (None, Some(g)) => g * r.state.speed.abs(),
            (None, None) => 0.0,
        };
        let ahead = match displacement {
            "trailingReferencedEntity" => false,
            "leadingReferencedEntity" => true,
            _ => {
                let p = me.state.pose;
                let (dx, dy) = (p.x - r.state.pose.x, p.y - r.state.pose.y);
                dx * r.state.pose.h.cos() + dy * r.state.pose.h.sin() >= 0.0
            }
        };
        let ds = match (freespace, ahead) {
            (false, true) => gap,
            (false, false) => -gap,
            (true, true) => {
                gap + (r.centre_m[0] + r.size_m[0] / 2.0) - (me.centre_m[0] - me.size_m[0] / 2.0)
            }
            (true, false) => {
                -(gap + (me.centre_m[0] + me.size_m[0] / 2.0) - (r.centre_m[0] - r.size_m[0] / 2.0))
            }
        };
        let mut lp = rl;
        if ds >= 0.0 {
            let prefer = |_: usize| false;
            self.roads.advance(&mut lp, ds, &prefer);
        } else {
            let up = lp.along_s(&self.roads);
            let s = lp.s + if up { ds } else { -ds };
            let (id, road) = self.roads.ids(lp.lane);
            let road = self.roads.map().roads[road].od_id.clone();
            let rev = lp.rev;
            lp = self.roads.lane_pos(&road, id, s, lp.d)?;
            lp.rev = rev;
        }
        // On a lane of the same road, it keeps its own lane and offset there (esmini moves
        // it along `s`); elsewhere it takes the reference's.
        if let Some(own) = me.state.lane {
            let (id, road) = self.roads.ids(own.lane);
            if road == self.roads.ids(lp.lane).1 {
                let name = self.roads.map().roads[road].od_id.clone();
                if let Ok(mut mine) = self.roads.lane_pos(&name, id, lp.s, own.d) {
                    mine.rev = own.rev;
                    lp = mine;
                }
            }
        }
        let st = &mut self.actors[e].state;
        st.pose = self.roads.pose_of(&lp);
        st.lane = Some(lp);
        // And it takes the reference's speed.
        st.speed = r.state.speed;
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

    /// The speed the storyboard asks of the ego the system under test drives, m/s, at the
    /// end of the last step: the value its `SpeedAction`s' transitions have then (a target
    /// that follows another entity, that entity's speed then); `None` before the first
    /// `SpeedAction` of the storyboard on it (its set speed is its `Init` speed).
    pub fn set_speed(&self) -> Option<f64> {
        self.set_speed
    }

    /// Whether entity `e`'s route (its `AssignRouteAction`) takes lane `lane`: a lane of a
    /// road it names, or a junction's connecting lane that leads to one (false without a
    /// route).
    pub fn route_takes(&self, e: usize, lane: usize) -> bool {
        let roads = &self.drives[e].prefer_roads;
        roads.contains(&self.roads.ids(lane).1) || roads.contains(&self.roads.exit_road(lane))
    }

    /// Has the storyboard move `ego` (scripted, as in [`Storyboard::new`] with `None`) until
    /// an `ActivateControllerAction` on it activates a domain: from then on the system
    /// under test drives it (its [`Actor::scripted`] turns false, the host hands it over and
    /// feeds its motion back through [`Storyboard::observe`]), as esmini's default
    /// controller hands the ego to the controller the file activates.
    pub fn hand_over_on_activation(&mut self, ego: usize) {
        self.hand_over = Some(ego);
        self.actors[ego].scripted = true;
    }

    /// The route asked of the driven ego since the last call, if any (a `LaneChangeAction`
    /// or an `AssignRouteAction` on it): the host hands it to the system under test.
    pub fn take_route(&mut self) -> Option<RouteAsk> {
        self.route.take()
    }

    /// Ends the driven ego `e`'s `LaneChangeAction` once it is in the lane it changes to,
    /// within [`LANE_REACHED_M`] of the offset asked.
    fn ask_lane(&mut self, e: usize) {
        let Some((lane, offset, a)) = self.drives[e].lane_goal else {
            return;
        };
        let there = self.actors[e]
            .state
            .lane
            .is_some_and(|lp| lp.lane == lane && (lp.d - offset).abs() <= LANE_REACHED_M);
        if there {
            self.drives[e].lane_goal = None;
            self.task_done(Some(a));
        }
    }

    /// The speed asked at `t1` of entity `e`, which the system under test drives
    /// ([`Storyboard::set_speed`]); its `SpeedAction` ends once the transition is over and
    /// its speed has come within [`SET_SPEED_REACHED_MPS`] and [`SET_SPEED_REACHED_SHARE`]
    /// of the target.
    fn ask_speed(&mut self, e: usize, t1: f64) {
        let Some((tr, track, a)) = self.drives[e].speed else {
            return;
        };
        let (mut v, over) = tr.at(t1);
        if over {
            if let Some((r, value, factor)) = track {
                let rv = self.actors[r].state.speed;
                v = if factor { rv * value } else { rv + value };
            } else {
                let reached = SET_SPEED_REACHED_MPS + SET_SPEED_REACHED_SHARE * tr.to.abs();
                if (self.actors[e].state.speed - tr.to).abs() <= reached {
                    self.drives[e].speed = None;
                    self.task_done(Some(a));
                }
            }
        }
        self.set_speed = Some(v.max(0.0));
    }

    /// Moves scripted entity `e` from `t` to `t + dt`.
    fn drive(&mut self, e: usize, t: f64, dt: f64) -> Result<(), StoryError> {
        let t1 = t + dt;
        let st = self.actors[e].state;
        // Speed.
        let mut v1 = st.speed;
        let mut done = Vec::new();
        if let Some((tr, track, a)) = self.drives[e].speed {
            let (v, over) = tr.at(t1);
            v1 = v;
            if over {
                match track {
                    Some((r, value, factor)) => {
                        let rv = self.actors[r].state.speed;
                        v1 = if factor { rv * value } else { rv + value };
                    }
                    None => {
                        self.drives[e].speed = None;
                        done.push(a);
                    }
                }
            }
        }
        v1 = v1.max(0.0);
        // At the new speed over the step (esmini's integration: the speed first, then the
        // move).
        let dist = v1 * dt;
        let mut pose = st.pose;
        let mut lane = st.lane;
        let mut at_end = false;
        let mut speed_now = v1;
        if let Some((path, a)) = &mut self.drives[e].path {
            let (p, over) = match path {
                Path::Timed(p) => p.at(t1),
                Path::Untimed(u) => u.advance(dist),
            };
            let timed = matches!(path, Path::Timed(_));
            let a = *a;
            if timed {
                let moved = (p.x - pose.x).hypot(p.y - pose.y);
                if moved > 1e-9 || !over {
                    speed_now = moved / dt;
                }
            }
            pose = p;
            lane = self.facing(self.roads.anchor(p.x, p.y), p.h);
            if over {
                // It goes on at the speed it had, along its lane facing the way the last leg
                // went (esmini's reading).
                self.drives[e].rel_h = self.relative_heading(p.h, lane);
                self.drives[e].path = None;
                done.push(a);
            }
        } else if let Some(lp) = lane {
            let (p, l, end, ended) = self.drive_on_lane(e, lp, (dist, dt, pose.h));
            pose = p;
            lane = Some(l);
            at_end = end;
            done.extend(ended);
        } else {
            pose.x += dist * pose.h.cos();
            pose.y += dist * pose.h.sin();
        }
        let moved = (pose.x - st.pose.x).hypot(pose.y - st.pose.y);
        let s = &mut self.actors[e].state;
        s.accel = (speed_now - s.speed) / dt;
        s.speed = speed_now;
        s.pose = pose;
        s.lane = lane;
        s.travelled_m += moved;
        s.still_s = if speed_now.abs() < 1e-3 {
            s.still_s + dt
        } else {
            0.0
        };
        s.at_end_s = if at_end { s.at_end_s + dt } else { 0.0 };
        for a in done {
            self.override_task(Some(a));
        }
        Ok(())
    }

    /// Moves scripted entity `e`, on lane position `lp` facing `h0`, a step of `dt` s in which
    /// it travels `dist` m, along its lanes with its lateral move: its pose, lane position,
    /// whether its lanes ended, and the action whose lateral move ended (if any).
    ///
    /// A lateral move is esmini's (`LatLaneChangeAction`, `LatLaneOffsetAction`): a lane
    /// change takes its lateral step out of the step's travel (by time, `√(dist² − lat²)` along
    /// the lane; by distance, `dist / √(1 + r²)` with `r` the offset's slope per metre) and
    /// faces the way it moves; a lane offset lags one step and faces `atan(rate / speed)`.
    fn drive_on_lane(
        &mut self,
        e: usize,
        mut lp: LanePos,
        (dist, dt, h0): (f64, f64, f64),
    ) -> (Pose, LanePos, bool, Option<usize>) {
        let mut ended = None;
        let mut along = dist;
        // The heading relative to the lane's travel, as a slope against the travel.
        let mut slip = 0.0;
        if let Some(mut l) = self.drives[e].lateral {
            let moving = dist > 1e-12;
            let (d, over) = if l.offset {
                let (d, over) = l.tr.at(l.param);
                slip = (l.tr.slope(l.param) * dt).atan2(dist);
                l.param += dt;
                (d, over)
            } else if !moving {
                // Standing, a lane change waits (esmini steps it only while moving).
                (lp.d, false)
            } else if l.tr.duration_s <= 0.0 {
                (l.tr.to, true)
            } else if l.by_distance {
                let r = l.tr.slope(l.param);
                along = dist / (1.0 + r * r).sqrt();
                l.param += along;
                slip = r.atan();
                l.tr.at(l.param)
            } else {
                let lat = (l.tr.slope(l.param) * dt).abs().min(dist);
                along = (dist * dist - lat * lat).sqrt();
                slip = (l.tr.slope(l.param) * dt).signum() * lat.atan2(along);
                l.param += dt;
                l.tr.at(l.param)
            };
            lp.d = d;
            self.drives[e].lateral = Some(l);
            if over {
                slip = 0.0;
                if let Some((k, offset)) = l.to_lane {
                    let up = lp.along_s(&self.roads);
                    let beside = (self.roads.ids(k).1 == self.roads.ids(lp.lane).1)
                        .then(|| self.roads.lane_with_id(lp.lane, self.roads.ids(k).0, lp.s))
                        .flatten();
                    if let Some(k2) = beside {
                        // Re-anchored on the target lane beside it here.
                        lp.lane = k2;
                        lp.rev = self.roads.forward(k2) != up;
                        lp.d = offset;
                    }
                }
                if !l.continuous {
                    self.drives[e].lateral = None;
                    ended = Some(l.action);
                }
            }
        }
        let prefer_roads = self.drives[e].prefer_roads.clone();
        // A route names the roads it takes; a junction's connecting road is preferred by
        // the road it leads to.
        let prefer = |n: usize| {
            prefer_roads.contains(&self.roads.ids(n).1)
                || prefer_roads.contains(&self.roads.exit_road(n))
        };
        let up_before = lp.along_s(&self.roads);
        let at_end = !self.roads.advance(&mut lp, along, &prefer);
        if lp.along_s(&self.roads) != up_before {
            // Its lane runs on in a road of the other direction: a lateral move in
            // progress keeps its side of the motion.
            if let Some(l) = &mut self.drives[e].lateral {
                l.tr.from = -l.tr.from;
                l.tr.to = -l.tr.to;
                if let Some((_, offset)) = &mut l.to_lane {
                    *offset = -*offset;
                }
            }
        }
        let travel = self.roads.travel_heading(&lp);
        // `d` is left of increasing `s`: against `s`, the same move turns the other way.
        let side = if lp.along_s(&self.roads) { 1.0 } else { -1.0 };
        let h = if dist > 1e-12 {
            wrap(travel + side * slip + self.drives[e].rel_h)
        } else {
            h0
        };
        let mut pose = self.roads.pose_of(&lp);
        // Standing still, it keeps the way it faces.
        pose.h = h;
        (pose, lp, at_end, ended)
    }

    fn evaluate(&mut self, k: usize, t: f64) -> bool {
        let mut any = false;
        for g in 0..self.triggers[k].len() {
            let mut all = true;
            for c in 0..self.triggers[k][g].len() {
                let raw = self.condition(&self.triggers[k][g][c].cond.kind, t);
                let cond = &mut self.triggers[k][g][c];
                let edged = match cond.cond.edge {
                    Edge::None => raw,
                    Edge::Rising => raw && cond.prev == Some(false),
                    Edge::Falling => !raw && cond.prev == Some(true),
                    Edge::RisingOrFalling => cond.prev.is_some_and(|p| p != raw),
                };
                cond.prev = Some(raw);
                // With a delay, the condition's value `delay` seconds ago.
                let value = if cond.cond.delay_s > 0.0 {
                    cond.history.push_back((t, edged));
                    let cut = t - cond.cond.delay_s + 1e-9;
                    let mut v = false;
                    while let Some(&(ts, e)) = cond.history.front() {
                        if ts <= cut {
                            v |= e;
                            cond.history.pop_front();
                        } else {
                            break;
                        }
                    }
                    v
                } else {
                    edged
                };
                all &= value;
            }
            any |= all;
        }
        any
    }

    fn condition(&self, kind: &ConditionKind, t: f64) -> bool {
        match kind {
            ConditionKind::SimulationTime { rule, value } => rule.holds(t, *value),
            ConditionKind::ElementState {
                element_type,
                element,
                state,
            } => self.elems.iter().any(|e| {
                e.kind.name().eq_ignore_ascii_case(element_type)
                    && e.name == *element
                    && match state.as_str() {
                        "startTransition" => e.last.start,
                        "endTransition" => e.last.end,
                        "stopTransition" => e.last.stop,
                        "skipTransition" => e.last.skip,
                        "completeState" => e.phase == Phase::Complete,
                        "runningState" => e.phase == Phase::Running,
                        "standbyState" => e.phase == Phase::Standby,
                        _ => false,
                    }
            }),
            ConditionKind::Parameter { name, rule, value } => {
                let Some((_, v)) = self.params.iter().find(|(n, _)| n == name) else {
                    return false;
                };
                match (v.trim().parse::<f64>(), value.trim().parse::<f64>()) {
                    (Ok(a), Ok(b)) => rule.holds(a, b),
                    _ => match rule {
                        Rule::Eq => v == value,
                        Rule::Ne => v != value,
                        _ => false,
                    },
                }
            }
            ConditionKind::Entity {
                entities,
                all,
                test,
            } => {
                let mut hits = entities.iter().map(|&e| self.entity_test(e, test));
                if *all {
                    hits.all(|h| h)
                } else {
                    hits.any(|h| h)
                }
            }
        }
    }

    fn entity_test(&self, e: usize, test: &EntityTest) -> bool {
        let st = &self.actors[e].state;
        match test {
            // Undefined (the reference behind, or the entity standing; not closing in) is
            // false whatever the rule, as esmini has it: an "infinite" headway must not
            // satisfy `greaterThan`.
            EntityTest::TimeHeadway(g) => {
                let (long, _, _) = self.gap(e, g);
                long >= 0.0 && st.speed > 1e-9 && g.rule.holds(long / st.speed, g.value)
            }
            EntityTest::TimeToCollision(g) => {
                let (long, _, closing) = self.gap(e, g);
                long >= 0.0 && closing > 1e-9 && g.rule.holds(long / closing, g.value)
            }
            EntityTest::RelativeDistance(g) => {
                let (long, lat, _) = self.gap(e, g);
                let d = match g.kind.as_str() {
                    "longitudinal" => long.abs(),
                    "lateral" => lat.abs(),
                    _ => long.hypot(lat),
                };
                g.rule.holds(d, g.value)
            }
            EntityTest::Distance {
                position,
                rule,
                value,
                freespace,
                kind,
            } => {
                let at = paracosm_openscenario::Pos {
                    file: String::new(),
                    line: 0,
                    col: 0,
                };
                self.resolve(position, &at).is_ok_and(|(p, _)| {
                    let d = self.distance_to_point(e, [p.x, p.y], *freespace, kind);
                    rule.holds(d, *value)
                })
            }
            EntityTest::ReachPosition {
                position,
                tolerance,
            } => {
                let at = paracosm_openscenario::Pos {
                    file: String::new(),
                    line: 0,
                    col: 0,
                };
                self.resolve(position, &at)
                    .is_ok_and(|(p, _)| (p.x - st.pose.x).hypot(p.y - st.pose.y) <= *tolerance)
            }
            EntityTest::Speed { rule, value } => rule.holds(st.speed, *value),
            EntityTest::RelativeSpeed {
                entity,
                rule,
                value,
            } => rule.holds(st.speed - self.actors[*entity].state.speed, *value),
            EntityTest::Acceleration { rule, value } => rule.holds(st.accel, *value),
            EntityTest::Standstill(d) => st.still_s >= *d - 1e-9,
            EntityTest::TraveledDistance(d) => st.travelled_m >= *d,
            EntityTest::EndOfRoad(d) => st.at_end_s > 0.0 && st.at_end_s >= *d - 1e-9,
            EntityTest::Collision(other) => match other {
                Some(o) => st.collided && self.touching(e, *o),
                None => st.collided,
            },
        }
    }

    /// The longitudinal and lateral distances from entity `e` to `g`'s entity in `e`'s frame
    /// (m; between bounding boxes with `freespace`, between reference points otherwise) and
    /// the speed at which `e` closes in on it along its heading (m/s).
    fn gap(&self, e: usize, g: &Gap) -> (f64, f64, f64) {
        let (a, b) = (&self.actors[e], &self.actors[g.entity]);
        let h = a.state.pose.h;
        let (c, s) = (h.cos(), h.sin());
        let centre = |x: &Actor| {
            let p = x.state.pose;
            let (cc, ss) = (p.h.cos(), p.h.sin());
            (
                p.x + cc * x.centre_m[0] - ss * x.centre_m[1],
                p.y + ss * x.centre_m[0] + cc * x.centre_m[1],
            )
        };
        let (pa, pb) = if g.freespace {
            (centre(a), centre(b))
        } else {
            (
                (a.state.pose.x, a.state.pose.y),
                (b.state.pose.x, b.state.pose.y),
            )
        };
        let (dx, dy) = (pb.0 - pa.0, pb.1 - pa.1);
        let mut long = dx * c + dy * s;
        let mut lat = -dx * s + dy * c;
        if g.freespace {
            // Half the extent of each box along and across `e`'s heading.
            let rel = b.state.pose.h - h;
            let half_long_b = 0.5 * (b.size_m[0] * rel.cos().abs() + b.size_m[1] * rel.sin().abs());
            let half_lat_b = 0.5 * (b.size_m[0] * rel.sin().abs() + b.size_m[1] * rel.cos().abs());
            let shrink = |d: f64, half: f64| d.signum() * (d.abs() - half).max(0.0);
            long = shrink(long, a.size_m[0] / 2.0 + half_long_b);
            lat = shrink(lat, a.size_m[1] / 2.0 + half_lat_b);
        }
        let vb = b.state.speed * (b.state.pose.h - h).cos();
        let closing = if long >= 0.0 {
            a.state.speed - vb
        } else {
            vb - a.state.speed
        };
        (long, lat, closing)
    }

    /// The distance from entity `e` to the point `p` (`[x, y]` m), as `kind` measures it in
    /// `e`'s frame (`longitudinal`, `lateral`, else euclidean): from its reference point, or
    /// with `freespace` from its bounding box (0 inside it). OpenSCENARIO `DistanceCondition`.
    fn distance_to_point(&self, e: usize, p: [f64; 2], freespace: bool, kind: &str) -> f64 {
        let a = &self.actors[e];
        let pose = a.state.pose;
        let (c, s) = (pose.h.cos(), pose.h.sin());
        let (dx, dy) = (p[0] - pose.x, p[1] - pose.y);
        let (mut long, mut lat) = (dx * c + dy * s, -dx * s + dy * c);
        if freespace {
            long = ((long - a.centre_m[0]).abs() - a.size_m[0] / 2.0).max(0.0);
            lat = ((lat - a.centre_m[1]).abs() - a.size_m[1] / 2.0).max(0.0);
        }
        match kind {
            "longitudinal" => long.abs(),
            "lateral" => lat.abs(),
            _ => long.hypot(lat),
        }
    }

    /// Whether the bounding boxes of `a` and `b` touch (within 5 cm).
    fn touching(&self, a: usize, b: usize) -> bool {
        let g = Gap {
            entity: b,
            rule: Rule::Lt,
            value: 0.0,
            freespace: true,
            frame: "entity".into(),
            kind: "euclidianDistance".into(),
        };
        let (long, lat, _) = self.gap(a, &g);
        long.abs() <= 0.05 && lat.abs() <= 0.05
    }

    /// The R157-style measures of entity `e`: its time headway (s) and following distance (m,
    /// between bounding boxes) to the nearest entity ahead of it in its lane (within the two
    /// half-widths sideways), `inf` with none; and the distance from its box's side to its
    /// lane's nearer edge (m, negative once over it; `nan` off every lane).
    pub fn measures(&self, e: usize) -> (f64, f64, f64) {
        let a = &self.actors[e];
        let mut gap_m = f64::INFINITY;
        for (j, b) in self.actors.iter().enumerate() {
            if j == e {
                continue;
            }
            let g = Gap {
                entity: j,
                rule: Rule::Lt,
                value: 0.0,
                freespace: true,
                frame: "entity".into(),
                kind: "longitudinal".into(),
            };
            let (long, lat, _) = self.gap(e, &g);
            let _ = b;
            if long >= 0.0 && lat == 0.0 {
                gap_m = gap_m.min(long);
            }
        }
        let headway_s = if a.state.speed > 1e-9 {
            gap_m / a.state.speed
        } else {
            f64::INFINITY
        };
        let edge_m = match a.state.lane {
            Some(lp) => {
                let w = self.roads.lane_width(lp.lane, lp.s);
                w / 2.0 - lp.d.abs() - a.size_m[1] / 2.0
            }
            None => f64::NAN,
        };
        (headway_s, gap_m, edge_m)
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
