use rapier3d::prelude::*;
use serde::Serialize;

use crate::actor::{half_open, ActorKind, Contact, Motion, Size, StepWorld, VisibleBox};
use crate::behaviour::{bad_input, placed_pose, Action, ActorRef, POSE_EXPECTED};
use crate::contact::Solids;
use crate::rx::{constant, number, Graph, Input, StreamId, Value};
use crate::{CarSpec, EngineError};

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Height of an NPC car's body above the road, in metres.
pub(crate) const CLEARANCE_M: f64 = 0.2;

/// An NPC car's observable state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CarState {
    /// Ground point under the centre `[x, y, z]`, metres.
    pub pos_m: [f64; 3],
    /// Heading in rad.
    pub heading_rad: f64,
    /// Speed along the path in m/s.
    pub speed_mps: f64,
    /// Whether it is in this test now: a car the world spec disables never is, and one an
    /// OpenSCENARIO storyboard took out (`DeleteEntityAction`, [`crate::Action::SetPresent`])
    /// is not until it is put back.
    pub enabled: bool,
}

/// Where a script puts a car for a step: its ground point `[x, z]` (m) and heading (rad),
/// and the speed the script gives it (m/s), if it gives one ([`Car::place`]).
pub(crate) type ScriptedPose = (([f64; 2], f64), Option<f64>);

/// When a lane change starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum LaneChangeStart {
    /// At this time since the start of the test, s.
    At(f64),
    /// At the first event of this stream.
    When(StreamId),
}

/// A lane change (`Car(lane_change = ChangeLane(...))`): the car moves sideways by
/// `offset_m` (to its right; negative: to its left) over `duration_s`, along the
/// minimum-jerk profile `10τ³ − 15τ⁴ + 6τ⁵` of `τ = (t − t₀) / duration_s` (Flash & Hogan
/// 1985), turning with its sideways speed; then it keeps the offset for the rest of its route.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LaneChangeSpec {
    /// Sideways distance, m, positive to the right of the direction of travel.
    pub offset_m: f64,
    /// When it starts.
    pub start: LaneChangeStart,
    /// How long it takes, s, `> 0`.
    pub duration_s: f64,
}

impl LaneChangeSpec {
    /// The share of the offset done at `tau` in `[0, 1]`, and its rate `d/dτ`: the
    /// minimum-jerk [`crate::transition::Shape`], stepped by the same code as every
    /// OpenSCENARIO transition.
    fn profile(tau: f64) -> (f64, f64) {
        use crate::transition::{progress, progress_slope, Shape};
        (
            progress(Shape::MinimumJerk, tau),
            progress_slope(Shape::MinimumJerk, tau),
        )
    }
}

/// The disc round the ego within which an NPC car stays in the physics step
/// ([`Car::advance`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct AwakeZone {
    /// The ego chassis centre `[x, z]`, m.
    pub(crate) ego_m: [f64; 2],
    /// The radius, m: beyond it no sensor reads the car and the ego cannot touch it.
    pub(crate) radius_m: f64,
}

/// The highest speed (m/s) a car may move at over the next step of `dt_s` s and still stop
/// within `d_m` m braking at no more than `a_mps2`, in the runner's discrete motion (each step
/// moves `v·dt` and changes `v` by at most `a·dt`; it stops after a step slower than `a·dt`).
/// From speed `v` in `(n·u, (n+1)·u]`, `u = a·dt`, the shortest stop is the `n + 1` steps
/// `v, v − u, …, v − n·u`, `dt·(n+1)·(v − n·u/2)` m; this inverts it. `0` for `d_m <= 0`.
fn stopping_speed(d_m: f64, a_mps2: f64, dt_s: f64) -> f64 {
    if d_m <= 0.0 {
        return 0.0;
    }
    if !(a_mps2 > 0.0 && dt_s > 0.0) {
        return f64::INFINITY;
    }
    let u = a_mps2 * dt_s;
    // The distance of the shortest stop from speed (n + 1)·u: dt·u·(n+1)(n+2)/2.
    let full = |n: f64| dt_s * u * (n + 1.0) * (n + 2.0) / 2.0;
    let mut n = ((-3.0 + (1.0 + 8.0 * d_m / (dt_s * u)).sqrt()) / 2.0)
        .ceil()
        .max(0.0);
    while n > 0.0 && full(n - 1.0) >= d_m {
        n -= 1.0;
    }
    while full(n) < d_m {
        n += 1.0;
    }
    d_m / (dt_s * (n + 1.0)) + u * n / 2.0
}

/// Gravitational acceleration in m/s², for the tyres' friction limit `μ·g`.
pub(crate) const GRAVITY_MPS2: f64 = 9.81;

/// Slack added to the distance within which an NPC car stays in the physics step, m: more
/// than the car and the ego can close in one step at any speed the engine models.
const SLEEP_MARGIN_M: f64 = 10.0;

/// Checks car `i` of a graph of `n` streams: its route, size and lane change.
///
/// # Errors
/// [`EngineError::InvalidWorld`] naming the car and the first value out of range.
fn check_spec(i: usize, c: &CarSpec, n: usize) -> Result<(), EngineError> {
    let invalid = |m: String| EngineError::InvalidWorld(m);
    if c.path.len() < 2 || c.path.iter().flatten().any(|v| !v.is_finite()) {
        return Err(invalid(format!(
            "car {i} has no route of two or more points"
        )));
    }
    if !c.size.is_valid() {
        return Err(invalid(format!("car {i} has the size {:?}", c.size)));
    }
    if let Some(change) = c.lane_change {
        let starts_ok = match change.start {
            LaneChangeStart::At(t0) => t0.is_finite() && t0 >= 0.0,
            LaneChangeStart::When(s) => s.0 < n,
        };
        if !(change.offset_m.is_finite()
            && change.duration_s.is_finite()
            && change.duration_s > 0.0
            && starts_ok)
        {
            return Err(invalid(format!("car {i} has the lane change {change:?}")));
        }
    }
    Ok(())
}

/// A kinematic NPC car following a polyline at a commanded speed. Solid: the ego vehicle
/// collides with it physically, and the lidar sees it.
///
/// It enters the test at its commanded speed; from then on its speed follows the command no
/// faster than its tyres allow: by at most `μ·g` m/s² (the friction circle's longitudinal
/// limit), where `μ` is the friction of the road piece under the car that step (or the
/// ground's off the network). Where its path ends (a dead end) it brakes at most as hard, to
/// stop with its front at the end: its speed is held to the fastest from which it can still
/// stop there ([`stopping_speed`], about `√(2·μ·g·d)`, `d` the distance left). A car that
/// enters the test too fast to stop before the end brakes at `μ·g` from its first step and
/// stops at the end with what speed is left.
pub(crate) struct Car {
    pub(crate) body: Option<(RigidBodyHandle, ColliderHandle)>,
    path: Vec<[f64; 2]>,
    cumulative: Vec<f64>,
    /// Arc length where it stops, m: its front at the path's end (half its length before
    /// it), or where it starts when that is beyond.
    stop_s: f64,
    /// The leg the car was on at its last lookup: arc lengths only grow, so the next lookup
    /// walks on from there instead of searching the whole path.
    leg: std::cell::Cell<usize>,
    /// The leg whose ends' tangent headings (rad, [`crate::network::tangent_at`]) were worked
    /// out last, and those tangents: the car's heading is interpolated between them, so it
    /// turns smoothly along a sampled curve instead of jumping at each vertex.
    tangents: std::cell::Cell<(usize, f64, f64)>,
    /// Per path vertex, the sideways shift of one metre of offset to the right (m per m):
    /// the mitre of the two legs' right normals, so a car offset from its path (a lane
    /// change) moves on a parallel polyline whose legs meet at each vertex; worked out on
    /// the first lane change.
    mitres: std::cell::OnceCell<Vec<[f64; 2]>>,
    s: f64,
    /// Its speed over the ground in the last step (the distance its ground point moved over
    /// the step's length), m/s; before the first step, the speed it enters the test at.
    speed: f64,
    /// Its velocity over the ground in the last step, `[x, z]` m/s: the ground point's move
    /// over the step's length; before the first step, its entry speed along its heading.
    velocity: [f64; 2],
    /// Speed the tyres hold (the command, limited to `μ·g` of change per second), m/s;
    /// `None` before the first step.
    rolling: Option<f64>,
    /// Ground point `[x, z]` (m) and heading (rad) at `s`, kept from the last move.
    here: ([f64; 2], f64),
    /// Ground point and heading of its collider: `here` once the physics step has taken the
    /// last move ([`Car::settle`]), the one before until then. Asleep, the collider is left
    /// behind, and a lidar sees the car here instead ([`Car::collider_pose`]).
    placed: ([f64; 2], f64),
    /// Its body; the collider spans `[CLEARANCE_M, CLEARANCE_M + height]` above the road.
    pub(crate) size: Size,
    /// Its collider's shape, a box of its size ([`Car::shape`]).
    collider_shape: SharedShape,
    /// How the camera draws it.
    pub(crate) albedo: [f32; 3],
    /// Its speed stream, m/s.
    pub(crate) speed_stream: crate::rx::Input,
    /// Whether it touches the ego vehicle now, and whether it has touched anything since the
    /// test began (the ego, a car, a pedestrian, an obstacle).
    contact: Contact,
    /// How messages name it ([`CarSpec::name`], else `car i`).
    name: String,
    /// The lanes of the segment it starts on, for `changeLane`: each lane's number and its
    /// offset from the start lane, m ([`CarSpec::lane_offsets_m`]).
    lanes: Vec<(i32, f64)>,
    /// Whether it has crashed: run into a car or an obstacle, or been run into by a car. A
    /// crashed car stops for the rest of the test ([`Car::advance`]); a pedestrian it meets
    /// only stops it until the pedestrian has walked out of its path.
    pub(crate) wrecked: bool,
    /// Whether it is out of the test ([`crate::Action::SetPresent`]): its body and collider
    /// stay disabled, and what it would touch is not recorded.
    pub(crate) absent: bool,
    /// The gap it keeps to whatever is ahead on its path, m (`Car(keep_distance=)`): it
    /// brakes, no harder than its tyres allow, to stop that far from it. `None`: it does not
    /// brake for anything (it still stops against what it meets).
    pub(crate) keep_distance_m: Option<f64>,
    /// Its lane change, if it has one.
    pub(crate) lane_change: Option<LaneChangeSpec>,
    /// When its lane change started, s.
    pub(crate) change_started_s: Option<f64>,
    /// The sideways offset its current lane change starts from, m (0 for the first).
    change_from_m: f64,
    /// The speed an action set (`setSpeed`, `brake`), m/s: it then drives at this instead of
    /// its speed stream's value.
    pub(crate) speed_override: Option<f64>,
    /// The pose a place action gave it for this step (`[x, z]` m, heading rad): it goes
    /// there instead of along its path ([`Car::place`]).
    pub(crate) script: Option<ScriptedPose>,
}

impl Car {
    /// Car `i` of a world whose stream graph is `graph`, built into `physics` from its spec.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] naming the car and the first value out of range: a route
    /// of fewer than two finite points, a size, a lane change or a kept distance.
    pub(crate) fn from_spec(
        i: usize,
        c: &CarSpec,
        graph: &Graph,
        physics: &mut PhysicsWorld,
    ) -> Result<Self, EngineError> {
        check_spec(i, c, graph.nodes().len())?;
        let mut car = Car::build(
            physics,
            c.path.clone(),
            c.size,
            c.enabled,
            crate::colour::albedo(&c.color).unwrap_or([0.45, 0.45, 0.45]),
            Input::of(graph, c.speed),
        );
        car.lane_change = c.lane_change;
        if let Some(keep) = c.keep_distance_m {
            if !(keep.is_finite() && keep >= 0.0) {
                return Err(EngineError::InvalidWorld(format!(
                    "car {i} keeps the distance {keep} m (finite and >= 0)"
                )));
            }
        }
        car.keep_distance_m = c.keep_distance_m;
        // A car enters the test at its speed stream's first value, so at t = 0 (before a
        // step has measured it) its speed is that value where it is known without running
        // the program's code: a constant or an open parameter, also one varying over time.
        if let Some(v) = constant(graph, c.speed).filter(|v| v.is_finite()) {
            car.enter_at(v);
        }
        car.name = if c.name.is_empty() {
            format!("car {i}")
        } else {
            c.name.clone()
        };
        car.lanes = c.lane_offsets_m.clone();
        Ok(car)
    }

    /// Performs one of this step's actions on the car ([`Action::SetSpeed`],
    /// [`Action::Brake`], [`Action::ChangeLane`], [`Action::PlaceCar`]) with its event's
    /// `value`.
    ///
    /// # Errors
    /// [`crate::rx::RxError::Input`] for a value the action cannot take, naming the car.
    pub(crate) fn act(
        &mut self,
        action: Action,
        value: &Value,
        world: &StepWorld,
    ) -> Result<(), EngineError> {
        let (t, dt) = (world.t_s, world.dt_s);
        let bad = |name: String, expected: &str| bad_input(t, name, value, expected);
        match action {
            Action::SetSpeed(_) => match value.as_num() {
                Some(v) if v.is_finite() && v >= 0.0 && !matches!(value, Value::Bool(_)) => {
                    self.speed_override = Some(v)
                }
                _ => {
                    return Err(bad(
                        format!("the speed given to {}'s setSpeed", self.name),
                        "a finite number >= 0 (m/s)",
                    ))
                }
            },
            Action::Brake(_) => match value {
                Value::Num(d) if d.is_finite() && *d > 0.0 => {
                    self.speed_override = Some((self.speed_mps() - d * dt).max(0.0))
                }
                _ => {
                    return Err(bad(
                        format!("the deceleration given to {}'s brake", self.name),
                        "a finite number > 0 (m/s²)",
                    ))
                }
            },
            Action::ChangeLane(_) => self.change_lane(value, t)?,
            Action::PlaceCar(_) => {
                let pose = placed_pose(value).ok_or_else(|| {
                    bad(format!("the pose given to {}", self.name), POSE_EXPECTED)
                })?;
                self.script = Some((([pose.0[0], pose.0[2]], pose.1), pose.2));
            }
            _ => {}
        }
        Ok(())
    }

    /// Performs a `changeLane` event at time `t` (s): `value` is the lane, or `(lane,
    /// duration in s)` (3 s when only the lane is given).
    ///
    /// # Errors
    /// [`crate::rx::RxError::Input`] for a lane the car's segment lacks or a duration that is
    /// not positive, naming the lanes it has.
    fn change_lane(&mut self, value: &Value, t: f64) -> Result<(), EngineError> {
        let (lane, duration) = match value {
            Value::Num(l) => (*l, 3.0),
            Value::Tuple(v) if v.len() == 2 => match (&v[0], &v[1]) {
                (Value::Num(l), Value::Num(d)) => (*l, *d),
                _ => (f64::NAN, f64::NAN),
            },
            _ => (f64::NAN, f64::NAN),
        };
        let offset = self
            .lanes
            .iter()
            .find(|(l, _)| f64::from(*l) == lane)
            .map(|(_, o)| *o);
        let Some(offset) = offset.filter(|_| duration.is_finite() && duration > 0.0) else {
            let known: Vec<String> = self.lanes.iter().map(|(l, _)| l.to_string()).collect();
            return Err(bad_input(
                t,
                format!("the lane given to {}'s changeLane", self.name),
                value,
                &if known.is_empty() {
                    "a lane of the segment the car starts on; it starts inside a junction, where there is none".to_owned()
                } else {
                    format!(
                        "a lane of the segment the car starts on ({}), or (lane, duration > 0 s)",
                        known.join(", ")
                    )
                },
            ));
        };
        self.change_lane_to(offset, duration, t);
        Ok(())
    }

    /// Moves the car over the step: to the pose its script gave it this step, else along its
    /// path at its commanded speed (an action's, else its speed stream's), starting its lane
    /// change when due; and moves it in `solids`. `me` is its handle; `reach` is the ego's
    /// planar position `[x, z]` (m) and the distance from it within which the car stays in
    /// the physics step before the car's own radius and a margin are added (the farthest
    /// reach of the sensors that read the physics world plus the ego's bounding radius, m).
    /// Returns what it ran into, if anything.
    ///
    /// # Errors
    /// [`EngineError::Stream`] for a speed stream without a number now.
    pub(crate) fn step(
        &mut self,
        me: ActorRef,
        world: &mut StepWorld,
        reach: ([f64; 2], f64),
        solids: &mut Solids,
    ) -> Result<Option<ActorRef>, EngineError> {
        let (t, dt) = (world.t_s, world.dt_s);
        let zone = AwakeZone {
            ego_m: reach.0,
            radius_m: reach.1 + self.radius_m() + SLEEP_MARGIN_M,
        };
        let hit = if let Some((pose, speed)) = self.script.take() {
            self.place(world.physics, (pose, speed), dt, zone, solids, me)
        } else {
            let v = match self.speed_override {
                Some(v) => v,
                None => {
                    let what = || format!("the speed of {}", self.name);
                    number(world.streams, self.speed_stream, t, what)?
                }
            };
            match self.lane_change.map(|c| c.start) {
                Some(LaneChangeStart::At(t0)) if t >= t0 => self.start_lane_change(t0),
                Some(LaneChangeStart::When(s)) if world.streams.fired(s) => {
                    self.start_lane_change(t)
                }
                _ => {}
            }
            let friction = world.surface.friction_at(self.ground_m());
            self.advance(world.physics, v, friction, (t, dt), zone, solids, me)
        };
        if self.body.is_some() {
            solids.move_to(me, self.pose());
        }
        Ok(hit)
    }
    /// A car on `path` (world `[x, z]` metres, two points or more), in the physics world when
    /// `enabled`, driven by `speed_stream`.
    pub(crate) fn build(
        physics: &mut PhysicsWorld,
        path: Vec<[f64; 2]>,
        size: Size,
        enabled: bool,
        albedo: [f32; 3],
        speed_stream: crate::rx::Input,
    ) -> Self {
        let mut cumulative = vec![0.0];
        for w in path.windows(2) {
            let last = *cumulative.last().expect("non-empty");
            cumulative.push(last + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
        }
        let stop_s = (cumulative.last().expect("non-empty") - size.length_m / 2.0).max(0.0);
        let mut car = Car {
            body: None,
            path,
            cumulative,
            stop_s,
            leg: std::cell::Cell::new(1),
            tangents: std::cell::Cell::new((0, 0.0, 0.0)),
            mitres: std::cell::OnceCell::new(),
            s: 0.0,
            speed: 0.0,
            velocity: [0.0; 2],
            rolling: None,
            here: ([0.0; 2], 0.0),
            placed: ([0.0; 2], 0.0),
            size,
            collider_shape: SharedShape::cuboid(
                (size.length_m / 2.0) as f32,
                (size.height_m / 2.0) as f32,
                (size.width_m / 2.0) as f32,
            ),
            albedo,
            speed_stream,
            contact: Contact::default(),
            name: String::new(),
            lanes: Vec::new(),
            wrecked: false,
            absent: false,
            keep_distance_m: None,
            lane_change: None,
            change_started_s: None,
            change_from_m: 0.0,
            speed_override: None,
            script: None,
        };
        car.here = car.at(0.0);
        car.placed = car.here;
        if enabled {
            let pose = car.pose();
            let body = RigidBodyBuilder::kinematic_position_based().pose(pose);
            // Half extents along the body's x (length), y (height) and z (width).
            let collider = ColliderBuilder::cuboid(
                (size.length_m / 2.0) as f32,
                (size.height_m / 2.0) as f32,
                (size.width_m / 2.0) as f32,
            )
            .active_events(ActiveEvents::COLLISION_EVENTS);
            car.body = Some(physics.insert(body, collider));
        }
        car
    }

    /// The leg `i` (`path[i - 1] → path[i]`, `1 <= i < path.len()`) that arc length `s` lies
    /// on: the first whose end is beyond `s`, or the last. Walks on from the last lookup's
    /// leg, which holds for an `s` no smaller than that leg's start; searches otherwise.
    fn leg_at(&self, s: f64) -> usize {
        let last = self.path.len() - 1;
        let mut i = self.leg.get().clamp(1, last);
        if self.cumulative[i - 1] > s {
            i = self.cumulative.partition_point(|&c| c <= s).clamp(1, last);
        }
        while i < last && self.cumulative[i] <= s {
            i += 1;
        }
        self.leg.set(i);
        i
    }

    /// The leg `i` that arc length `s` lies on ([`Car::leg_at`]) and how far along it, `u`
    /// in `[0, 1]` (0 on a leg of no length).
    fn on_leg(&self, s: f64) -> (usize, f64) {
        let i = self.leg_at(s);
        let len = self.cumulative[i] - self.cumulative[i - 1];
        let u = if len > 0.0 {
            ((s - self.cumulative[i - 1]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (i, u)
    }

    /// Position `[x, z]` on the path and the path's heading at arc length `s`: the heading
    /// is interpolated between the tangents at the leg's ends
    /// ([`crate::network::heading_on_leg`]), continuous along the path.
    fn at(&self, s: f64) -> ([f64; 2], f64) {
        let (i, u) = self.on_leg(s);
        let (a, b) = (self.path[i - 1], self.path[i]);
        let (ta, tb) = self.tangents_of(i);
        (
            [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])],
            crate::network::heading_between(ta, tb, u),
        )
    }

    /// The tangent headings at the two ends of leg `i` (`1 <= i`), rad, kept for the leg
    /// looked up last.
    fn tangents_of(&self, i: usize) -> (f64, f64) {
        match self.tangents.get() {
            (leg, a, b) if leg == i => (a, b),
            _ => {
                let a = crate::network::tangent_at(&self.path, i - 1);
                let b = crate::network::tangent_at(&self.path, i);
                self.tangents.set((i, a, b));
                (a, b)
            }
        }
    }

    /// The pose of its collider now: the body's pose when it is in the physics step, and the
    /// pose it would have when it is asleep (out of the step, its collider left behind).
    pub(crate) fn pose(&self) -> Pose {
        self.pose_at(self.here)
    }

    /// Where its collider is, asleep or awake, bit for bit: its pose ([`Car::pose`]) once
    /// the physics step has taken its last move, and the pose before that move until then.
    /// An awake car's collider is there; an asleep car's would be.
    pub(crate) fn collider_pose(&self) -> Pose {
        self.pose_at(self.placed)
    }

    /// Records that the physics step has taken the car's last move: its collider, or the one
    /// it would have asleep, is now at [`Car::pose`].
    pub(crate) fn settle(&mut self) {
        self.placed = self.here;
    }

    /// Whether it is in the test but asleep, out of the physics step ([`Car::advance`]).
    pub(crate) fn is_asleep(&self, physics: &PhysicsWorld) -> bool {
        self.body
            .is_some_and(|(body, _)| !physics.bodies[body].is_enabled())
    }

    /// The collider's pose for the ground point `[x, z]` (m) and heading (rad) `here`.
    fn pose_at(&self, here: ([f64; 2], f64)) -> Pose {
        let ([x, z], h) = here;
        Pose::from_parts(
            Vector::new(
                x as f32,
                (CLEARANCE_M + self.size.height_m / 2.0) as f32,
                z as f32,
            ),
            Rotation::from_rotation_y(h as f32),
        )
    }

    /// The ground point `[x, z]` under the car now, metres.
    pub(crate) fn ground_m(&self) -> [f64; 2] {
        self.here.0
    }

    /// The mitre at each vertex of the path ([`Car::mitres`]): the sum of the right normals
    /// `n` of the legs before and after it (a leg of no length takes its neighbour's),
    /// divided by `1 + n_before · n_after`, so the offset polyline's legs stay parallel to
    /// the path's at the offset's distance; the divisor is held to at least 0.25 at a turn
    /// sharper than about 140°.
    fn mitres(&self) -> &[[f64; 2]] {
        self.mitres.get_or_init(|| {
            let n = self.path.len();
            // The right normal of each leg, `None` for a leg of no length.
            let normals: Vec<Option<[f64; 2]>> = self
                .path
                .windows(2)
                .map(|w| {
                    let (dx, dz) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
                    let len = dx.hypot(dz);
                    (len > 0.0).then(|| [-dz / len, dx / len])
                })
                .collect();
            let first = normals
                .iter()
                .flatten()
                .next()
                .copied()
                .unwrap_or([0.0, 1.0]);
            // Each leg's normal, a leg of no length taking the one before it.
            let mut legs = Vec::with_capacity(normals.len());
            let mut last = first;
            for nrm in &normals {
                last = nrm.unwrap_or(last);
                legs.push(last);
            }
            (0..n)
                .map(|i| {
                    let before = if i == 0 {
                        legs.first()
                    } else {
                        legs.get(i - 1)
                    };
                    let after = legs.get(i).or(legs.last());
                    match (before, after) {
                        (Some(a), Some(b)) => {
                            let k = (1.0 + a[0] * b[0] + a[1] * b[1]).max(0.25);
                            [(a[0] + b[0]) / k, (a[1] + b[1]) / k]
                        }
                        _ => first,
                    }
                })
                .collect()
        })
    }

    /// The ground point and heading at arc length `s` and time `t_s`, with the lane change's
    /// sideways offset and the turn of its sideways speed. The offset is taken along the
    /// path's mitres ([`Car::mitres`]), so the car moves on a polyline parallel to its path,
    /// without a jump where the path turns.
    fn place_at(&self, s: f64, t_s: f64) -> ([f64; 2], f64) {
        let (p, heading) = self.at(s);
        let (Some(change), Some(t0)) = (self.lane_change, self.change_started_s) else {
            return (p, heading);
        };
        let tau = (t_s - t0) / change.duration_s;
        let (share, rate) = LaneChangeSpec::profile(tau);
        let from = self.change_from_m;
        let d = from + (change.offset_m - from) * share;
        let (i, u) = self.on_leg(s);
        let m = self.mitres();
        let (ma, mb) = (m[i - 1], m[i]);
        let shift = [ma[0] + u * (mb[0] - ma[0]), ma[1] + u * (mb[1] - ma[1])];
        let sideways_mps = if (0.0..1.0).contains(&tau) {
            (change.offset_m - from) * rate / change.duration_s
        } else {
            0.0
        };
        // Its speed is over the ground (`Car::advance`), sideways motion included: the rest
        // is along the path.
        let along = (self.speed * self.speed - sideways_mps * sideways_mps)
            .max(0.0)
            .sqrt()
            .max(0.1);
        let turn = sideways_mps.atan2(along);
        ([p[0] + d * shift[0], p[1] + d * shift[1]], heading - turn)
    }

    /// Starts its lane change at `t_s` if it has one that has not started.
    pub(crate) fn start_lane_change(&mut self, t_s: f64) {
        if self.lane_change.is_some() && self.change_started_s.is_none() {
            self.change_started_s = Some(t_s);
        }
    }

    /// The sideways offset from its start lane now, m (positive to the right).
    fn offset_now_m(&self, t_s: f64) -> f64 {
        match (self.lane_change, self.change_started_s) {
            (Some(c), Some(t0)) => {
                let (share, _) = LaneChangeSpec::profile((t_s - t0) / c.duration_s);
                self.change_from_m + (c.offset_m - self.change_from_m) * share
            }
            _ => 0.0,
        }
    }

    /// Starts moving sideways at `t_s` to `offset_m` from its start lane (m, positive to the
    /// right) over `duration_s`, from wherever it is now (a `changeLane` action). Changing
    /// to the offset it is already moving to does nothing, so an action repeated every step
    /// makes one lane change.
    pub(crate) fn change_lane_to(&mut self, offset_m: f64, duration_s: f64, t_s: f64) {
        if self.change_started_s.is_some()
            && self.lane_change.is_some_and(|c| c.offset_m == offset_m)
        {
            return;
        }
        if self.change_started_s.is_none() && offset_m == 0.0 {
            return;
        }
        self.change_from_m = self.offset_now_m(t_s);
        self.lane_change = Some(LaneChangeSpec {
            offset_m,
            start: LaneChangeStart::At(t_s),
            duration_s,
        });
        self.change_started_s = Some(t_s);
    }

    /// Sets the speed it reports before its first step (m/s, negative counts as 0): the speed
    /// it enters the test at. The first step sets its speed from the speed stream anyway.
    pub(crate) fn enter_at(&mut self, speed_mps: f64) {
        self.speed = speed_mps.max(0.0);
        let d = crate::network::direction(self.here.1);
        self.velocity = [d[0] * self.speed, d[1] * self.speed];
    }

    /// Its speed along the path in the last step (before the first step, the speed it enters
    /// the test at, when known), m/s.
    pub(crate) fn speed_mps(&self) -> f64 {
        self.speed
    }

    /// How far from its ground point the car's collider reaches, horizontally or up, m: half
    /// its box's diagonal plus its clearance.
    pub(crate) fn radius_m(&self) -> f64 {
        let s = self.size;
        0.5 * (s.length_m.powi(2) + s.width_m.powi(2) + s.height_m.powi(2)).sqrt() + CLEARANCE_M
    }

    /// Drives one step of `dt_s` at time `t_s` toward the commanded `speed_mps` (negative
    /// counts as 0) on a surface of friction `friction`: the speed changes by at most
    /// `friction · g · dt_s` (except in the first step, which sets it), and the car does not
    /// pass its path's end. The speed is over the ground: a car offset from its path (a lane
    /// change) moves its path's station by as much as makes its ground point move
    /// `speed · dt_s` (to 1e-6 of it), on a bend's outside as on its inside, sideways motion
    /// included.
    ///
    /// `solids` are the other solid objects where they stand now (`me` is this car): the car
    /// does not move into one. A move that would touch one ends where it touches (to 0.1 mm),
    /// the car stops there, and the object is returned; the car records the collision. With
    /// a [`Car::keep_distance_m`], it also brakes (at most `μ·g`) to stop that far short of
    /// whatever is ahead on its path, the ego included.
    ///
    /// A car outside `zone` once it has moved is asleep: its body and collider are disabled,
    /// so rapier's step, contacts and ray casts skip it (its pose is still kept here,
    /// [`Car::pose`]). A car that wakes is put back where it was at the start of the step
    /// before it is moved, so rapier sees the same motion, and the same velocity, as if it
    /// had never slept.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn advance(
        &mut self,
        physics: &mut PhysicsWorld,
        speed_mps: f64,
        friction: f64,
        (t_s, dt_s): (f64, f64),
        zone: AwakeZone,
        solids: &Solids,
        me: ActorRef,
    ) -> Option<ActorRef> {
        let start = self.here;
        let end = self.stop_s.max(self.s);
        let braking = friction * GRAVITY_MPS2;
        let next_t = t_s + dt_s;
        // No faster than it can still stop at the end, braking at `μ·g`.
        let mut room = stopping_speed(end - self.s, braking, dt_s);
        if let Some(keep) = self.keep_distance_m {
            let reach = self.speed * self.speed / (2.0 * braking.max(1e-6))
                + keep
                + 2.0 * speed_mps.max(self.speed) * dt_s
                + 1.0;
            if let Some(gap) = self.free_ahead_m(solids, me, next_t, reach.min(end - self.s)) {
                room = room.min(stopping_speed(gap - keep, braking, dt_s));
            }
        }
        // A crashed car (it ran into a car or an obstacle, or a car ran into it) stops there
        // for the rest of the test: at once against what it ran into, else braking at `μ·g`.
        let wanted = if self.wrecked {
            0.0
        } else {
            speed_mps.max(0.0).min(room)
        };
        let rolling = match self.rolling {
            // It enters the test at its command; one too fast to stop before the end brakes
            // at `μ·g` from the first step and stops at the end.
            None => speed_mps.max(0.0),
            Some(v) => {
                let dv = braking * dt_s;
                wanted.clamp(v - dv, v + dv)
            }
        };
        let step = rolling * dt_s;
        let mut s_new = (self.s + step).min(end);
        if step > 0.0 && self.change_started_s.is_some() {
            // Offset from its path, the ground moves other than the station (faster on a
            // bend's outside, and sideways during a change): scale the station's step until
            // the ground point moves `step`, to 1e-6 of it.
            let mut k = 1.0;
            for _ in 0..8 {
                let ground = dist(self.place_at(self.s + k * step, next_t).0, start.0);
                if ground <= 1e-12 || (ground - step).abs() <= 1e-6 * step {
                    break;
                }
                k *= step / ground;
            }
            s_new = (self.s + k * step).min(end);
        }
        let hit = if self.absent {
            None
        } else {
            self.first_contact(solids, me, (self.s, s_new), next_t)
        };
        if let Some((free_s, o)) = hit {
            s_new = free_s;
            self.contact.collided = true;
            self.wrecked |= o.wrecks_a_car();
        }
        self.s = s_new;
        // At the end of its path, or against what it ran into, the car has stopped.
        self.rolling = Some(if self.s >= end || hit.is_some() {
            0.0
        } else {
            rolling
        });
        self.here = self.place_at(self.s, next_t);
        self.moved_from(physics, start, dt_s, zone);
        hit.map(|(_, o)| o)
    }

    /// Puts the car at `pose` (`[x, z]` m, heading rad) for this step, off its path (a
    /// scripted car): its velocity is the move over the step, or, when its script gives its
    /// speed (m/s), that speed along its heading (a teleport's step then has the car's speed,
    /// not the jump over the step, as esmini reports it). It stops for nothing; returns the
    /// first object of `solids` its box touches there, which it records as collided.
    pub(crate) fn place(
        &mut self,
        physics: &mut PhysicsWorld,
        (pose, speed): (([f64; 2], f64), Option<f64>),
        dt_s: f64,
        zone: AwakeZone,
        solids: &Solids,
        me: ActorRef,
    ) -> Option<ActorRef> {
        let start = self.here;
        self.here = pose;
        self.rolling = Some(0.0);
        self.moved_from(physics, start, dt_s, zone);
        if let Some(v) = speed {
            self.speed = v;
            self.velocity = [v * pose.1.cos(), -v * pose.1.sin()];
        }
        self.body?;
        if self.absent {
            return None;
        }
        let [x, z] = pose.0;
        let centre = [x, CLEARANCE_M + self.size.height_m / 2.0, z];
        if !solids.any_near(me, centre, self.radius_m(), false) {
            return None;
        }
        let hit = solids.first_hit(me, self.shape().as_ref(), &self.pose_at(pose), false);
        self.contact.collided |= hit.is_some();
        hit
    }

    /// Sets the velocity and speed from the move from `start` to where the car is now over
    /// `dt_s`, and moves its body there (or puts it to sleep outside `zone`).
    fn moved_from(
        &mut self,
        physics: &mut PhysicsWorld,
        start: ([f64; 2], f64),
        dt_s: f64,
        zone: AwakeZone,
    ) {
        self.velocity = [
            (self.here.0[0] - start.0[0]) / dt_s,
            (self.here.0[1] - start.0[1]) / dt_s,
        ];
        self.speed = self.velocity[0].hypot(self.velocity[1]);
        if let Some((body, collider)) = self.body {
            let [x, z] = self.here.0;
            let (dx, dz) = (x - zone.ego_m[0], z - zone.ego_m[1]);
            // A distance that is not a number keeps the car awake.
            let asleep = self.absent || dx * dx + dz * dz > zone.radius_m * zone.radius_m;
            let rb = &mut physics.bodies[body];
            if asleep {
                if rb.is_enabled() {
                    rb.set_enabled(false);
                    physics.colliders[collider].set_enabled(false);
                }
                return;
            }
            if !rb.is_enabled() {
                rb.set_enabled(true);
                rb.set_position(self.pose_at(start), false);
                physics.colliders[collider].set_enabled(true);
            }
            physics.bodies[body].set_next_kinematic_position(self.pose());
        }
    }

    /// Its collider's shape: a box of its size.
    pub(crate) fn shape(&self) -> SharedShape {
        self.collider_shape.clone()
    }

    /// The first object of `solids` that the car touches moving from station `from` to `to`
    /// at time `t_s`, and the last station before it touches (within 0.1 mm of the touch):
    /// `from` itself when it touches there already. `None` when the move is free. Only the
    /// end of the move is tested: a step (under 1 m at any speed a car has) is shorter than
    /// a car, so its box at the start and at the end of the step cover the way between.
    fn first_contact(
        &self,
        solids: &Solids,
        me: ActorRef,
        (from, to): (f64, f64),
        t_s: f64,
    ) -> Option<(f64, ActorRef)> {
        self.body?;
        let shape = self.shape();
        let reach = self.radius_m();
        let touches = |s: f64| {
            let here = self.place_at(s, t_s);
            let [x, z] = here.0;
            // Most steps nothing is near: no pose, no shape test.
            if !solids.any_near(
                me,
                [x, CLEARANCE_M + self.size.height_m / 2.0, z],
                reach,
                false,
            ) {
                return None;
            }
            solids.first_hit(me, shape.as_ref(), &self.pose_at(here), false)
        };
        let other = touches(to)?;
        if touches(from).is_some() {
            return Some((from, other));
        }
        let (mut lo, mut hi) = (from, to);
        while hi - lo > 1e-4 {
            let mid = 0.5 * (lo + hi);
            if touches(mid).is_some() {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some((lo, other))
    }

    /// How far (m, along its path) the car can drive from where it is before its box
    /// touches an object of `solids` (the ego included), looking `reach_m` ahead; `None`
    /// when nothing is within reach. Found in steps of 0.5 m, then to 1 cm.
    fn free_ahead_m(&self, solids: &Solids, me: ActorRef, t_s: f64, reach_m: f64) -> Option<f64> {
        self.body?;
        let shape = self.shape();
        let touches = |s: f64| {
            solids
                .first_hit(
                    me,
                    shape.as_ref(),
                    &self.pose_at(self.place_at(s, t_s)),
                    true,
                )
                .is_some()
        };
        if reach_m <= 0.0 {
            return None;
        }
        let n = (reach_m / 0.5).ceil() as usize;
        let mut lo = 0.0;
        for k in 1..=n {
            let d = (k as f64 * 0.5).min(reach_m);
            if touches(self.s + d) {
                let mut hi = d;
                while hi - lo > 0.01 {
                    let mid = 0.5 * (lo + hi);
                    if touches(self.s + mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Some(lo);
            }
            lo = d;
        }
        None
    }

    /// The centre of its body `[x, y, z]`, metres: its `pos` output (an actor's reference
    /// point, as the ego's chassis centre is the ego's).
    pub(crate) fn centre_m(&self) -> [f64; 3] {
        let ([x, z], _) = self.here;
        [x, CLEARANCE_M + self.size.height_m / 2.0, z]
    }

    pub(crate) fn state(&self) -> CarState {
        let ([x, z], heading_rad) = self.here;
        CarState {
            pos_m: [x, 0.0, z],
            heading_rad,
            speed_mps: self.speed,
            enabled: self.body.is_some() && !self.absent,
        }
    }
}

impl ActorKind for Car {
    fn contact(&self) -> Contact {
        self.contact
    }

    fn contact_mut(&mut self) -> &mut Contact {
        &mut self.contact
    }

    fn motion(&self) -> Option<Motion> {
        self.body?;
        let [vx, vz] = self.velocity;
        // The size of its velocity, negative when it moves against its heading (a scripted
        // car a storyboard reverses), as the ego's speed is.
        let (sin, cos) = self.here.1.sin_cos();
        let backwards = vx * cos - vz * sin < 0.0;
        let size = vx.hypot(vz);
        Some(Motion {
            pos_m: self.centre_m(),
            vel_mps: [vx, 0.0, vz],
            heading_rad: half_open(self.here.1),
            speed_mps: if backwards { -size } else { size },
        })
    }

    fn solid(&self, _: &PhysicsWorld) -> Option<(Pose, SharedShape)> {
        self.body?;
        Some((self.pose(), self.shape()))
    }

    fn collider_now<'a>(&self, physics: &'a PhysicsWorld) -> Option<(Pose, &'a dyn Shape)> {
        // A sleeping car's collider stays where it fell asleep: it gives the pose it keeps
        // itself (equal to the collider's when awake).
        let (body, h) = self.body?;
        let co = &physics.colliders[h];
        let awake = physics.bodies[body].is_enabled();
        Some((if awake { *co.position() } else { self.pose() }, co.shape()))
    }

    /// The car as the time-to-collision test sees it, `None` when it is not in this test.
    fn mover(&self) -> Option<crate::ttc::Mover> {
        self.body?;
        let ([x, z], heading_rad) = self.here;
        Some(crate::ttc::Mover {
            pos_m: [x, z],
            velocity_mps: self.velocity,
            heading_rad,
            half_size_m: [self.size.length_m / 2.0, self.size.width_m / 2.0],
        })
    }

    /// The box the camera draws: from the road to its roof, so it covers the wheels under
    /// the collider's clearance.
    fn visible(&self, index: usize) -> Option<VisibleBox> {
        self.body?;
        let ([x, z], heading_rad) = self.here;
        Some(VisibleBox {
            base_m: [x, 0.0, z],
            size: Size {
                height_m: self.size.height_m + CLEARANCE_M,
                ..self.size
            },
            heading_rad,
            albedo: self.albedo,
            class: crate::segmentation::SemanticClass::Car,
            actor: index,
        })
    }

    /// Run into by a car: a crash, which ends its drive too.
    fn run_into_by_car(&mut self) {
        self.contact.collided = true;
        self.wrecked = true;
    }

    fn end_step(&mut self) {
        self.settle();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Braking by [`stopping_speed`] each step, the discrete motion stops exactly at the
    /// end, never braking harder than `a` (to rounding), from any speed and distance.
    #[test]
    fn stopping_speed_stops_at_the_end_within_the_limit() {
        let dt = 1.0 / 60.0;
        for a in [0.49, 0.98, 7.85, 16.7] {
            for v0 in [0.5, 3.0, 15.0, 50.0] {
                for d0 in [0.01, 0.7, 7.5, 92.75] {
                    let (mut s, mut v_prev) = (0.0f64, None::<f64>);
                    let mut worst: f64 = 0.0;
                    // The first step enters at the capped speed (as `advance` does).
                    let mut last = None::<f64>;
                    for _ in 0..100_000 {
                        let want = v0.min(stopping_speed(d0 - s, a, dt));
                        let v = match v_prev {
                            None => want,
                            Some(p) => want.clamp(p - a * dt, p + a * dt),
                        };
                        let before = s;
                        s = (s + v * dt).min(d0);
                        let moved = (s - before) / dt;
                        if let Some(l) = last {
                            worst = worst.max((l - moved) / dt);
                        }
                        last = Some(moved);
                        v_prev = Some(if s >= d0 { 0.0 } else { v });
                        if s >= d0 && moved == 0.0 {
                            break;
                        }
                    }
                    assert_eq!(s, d0, "a {a}, v0 {v0}, d {d0}");
                    assert!(worst <= a * (1.0 + 1e-6), "a {a}, v0 {v0}, d {d0}: {worst}");
                }
            }
        }
    }

    fn car(path: Vec<[f64; 2]>) -> Car {
        let size = Size {
            length_m: 4.5,
            width_m: 1.8,
            height_m: 1.5,
        };
        Car::build(
            &mut PhysicsWorld::new(),
            path,
            size,
            false,
            [0.5; 3],
            crate::rx::Input::Stream(StreamId(0)),
        )
    }

    #[test]
    fn the_leg_walked_on_is_the_leg_a_search_finds() {
        // Legs of unequal length, one of zero length, and arc lengths that go forward, stay,
        // jump, go back and run past the end.
        let c = car(vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 0.0],
            [3.0, 1.0],
            [3.5, 4.0],
            [10.0, 4.0],
        ]);
        let search = |s: f64| c.cumulative.partition_point(|&x| x <= s).clamp(1, 5);
        let end = *c.cumulative.last().unwrap();
        let mut queries: Vec<f64> = (0..400).map(|k| k as f64 * 0.05).collect();
        queries.extend([1.0, 1.0, 0.5, 3.2, 0.0, end, end + 3.0, 2.0, -1.0, 7.0]);
        for s in queries {
            assert_eq!(c.leg_at(s), search(s), "s = {s}");
            let (p, h) = c.at(s);
            let (i, u) = c.on_leg(s);
            assert_eq!(i, search(s));
            // The heading is the leg's ends' tangents interpolated: between the headings of
            // the legs that meet at its ends.
            let tangents = crate::network::vertex_tangents(&c.path);
            assert_eq!(h, crate::network::heading_on_leg(&tangents, i, u));
            assert!(p.iter().all(|v| v.is_finite()) && h.is_finite());
        }
    }

    #[test]
    fn a_car_offset_by_a_lane_change_moves_without_a_jump_where_its_path_turns() {
        // A quarter circle of radius 30 m in 2 m legs, then a straight: the offset was taken
        // along each leg's own normal, so at each vertex the car jumped sideways by
        // 3.5 m × the turn (0.23 m in one step of 0.1 m).
        let mut path: Vec<[f64; 2]> = (0..=24)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::FRAC_PI_2 / 24.0;
                [30.0 * a.sin(), 30.0 - 30.0 * a.cos()]
            })
            .collect();
        path.push([30.0, 80.0]);
        let (dt, v) = (1.0 / 60.0, 6.0);
        for offset in [3.5, -3.5] {
            let mut c = car(path.clone());
            c.lane_change = Some(LaneChangeSpec {
                offset_m: offset,
                start: LaneChangeStart::At(0.5),
                duration_s: 2.0,
            });
            let mut physics = PhysicsWorld::new();
            let zone = AwakeZone {
                ego_m: [0.0, 0.0],
                radius_m: 1e9,
            };
            let mut last = c.ground_m();
            for k in 0..1200 {
                let t = f64::from(k) * dt;
                if t >= 0.5 {
                    c.start_lane_change(0.5);
                }
                c.advance(
                    &mut physics,
                    v,
                    0.8,
                    (t, dt),
                    zone,
                    &Solids::new(),
                    ActorRef::Car(crate::actor::Roster::default().add()),
                );
                let here = c.ground_m();
                let moved = (here[0] - last[0]).hypot(here[1] - last[1]);
                // Along a parallel of radius 30 ± 3.5 m, plus the sideways speed of the change
                // (at most 1.875 × 3.5 / 2 m/s).
                let most = (v * 33.5 / 30.0 + 1.875 * 3.5 / 2.0) * dt;
                assert!(
                    moved <= most * 1.01,
                    "offset {offset}, t = {t}: {moved} m in a step"
                );
                // (Before it brakes for the end of its path.)
                if t < 14.0 {
                    assert!(
                        moved >= v * 26.5 / 30.0 * dt * 0.99,
                        "{offset}, t = {t}: {moved}"
                    );
                }
                last = here;
            }
            // It ends on the straight, 3.5 m to the side of it.
            let [x, _] = c.ground_m();
            assert!((x - (30.0 - offset)).abs() < 1e-6, "{x}");
        }
    }
}
