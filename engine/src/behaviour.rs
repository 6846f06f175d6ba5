//! How the world and the stream graph meet: probes (physics outputs as streams), sinks
//! (actions on actors), a graph builder, and the paper's pedestrian behaviour.

use crate::actor::Handle;
use crate::rx::{Func, Graph, NativeError, Node, RxError, StreamId, Value};
use crate::{CarSpec, ObstacleSpec, PedestrianSpec};

/// An actor of a world, by its typed handle (paper §2: the reactive objects whose streams a
/// program reads and acts on).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ActorRef {
    /// The ego vehicle.
    Ego,
    /// A pedestrian, named by its handle in [`crate::WorldSpec::pedestrians`]' order.
    Pedestrian(Handle<PedestrianSpec>),
    /// An NPC car, named by its handle in [`crate::WorldSpec::cars`]' order.
    Car(Handle<CarSpec>),
    /// A static obstacle, named by its handle in [`crate::WorldSpec::obstacles`]' order.
    Obstacle(Handle<ObstacleSpec>),
}

impl ActorRef {
    /// Whether a car that runs into this actor crashes, and stops for the rest of the test:
    /// every actor but a pedestrian, which only stops it until it has walked out of its path.
    pub(crate) fn wrecks_a_car(self) -> bool {
        !matches!(self, ActorRef::Pedestrian(_))
    }

    /// Its handle's index in its kind's order (0 for the ego).
    pub(crate) fn index(self) -> usize {
        match self {
            ActorRef::Ego => 0,
            ActorRef::Pedestrian(h) => h.index(),
            ActorRef::Car(h) => h.index(),
            ActorRef::Obstacle(h) => h.index(),
        }
    }
}

/// What a probe reads from its actor, each step (paper §2: `rxout pos, vel, ...`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Output {
    /// Position `[x, y, z]` in metres (the ego's chassis centre, a pedestrian's feet, a car's
    /// centre, an obstacle's base).
    Pos,
    /// Velocity `[x, y, z]` in m/s.
    Vel,
    /// Heading in rad.
    Heading,
    /// Speed in m/s (signed along the heading for the ego).
    Speed,
    /// Contact: `true` while the actor touches the ego vehicle (for the ego: touches any
    /// actor).
    Collision,
    /// `true` from the step the actor first touched anything solid (the ego, a car, a
    /// pedestrian, an obstacle) to the end of the test.
    Collided,
    /// The smallest distance from the actor's body to any other solid body (the ego, a car
    /// in the test, a pedestrian, an obstacle), m; `0` while touching, `inf` with nothing
    /// else in the world.
    Separation,
}

impl Output {
    /// Every output, in the order a program's actor lists them (`pos`, `vel`, `heading`,
    /// `speed`, `collision`, `collided`, `separation`).
    pub const ALL: [Output; 7] = [
        Output::Pos,
        Output::Vel,
        Output::Heading,
        Output::Speed,
        Output::Collision,
        Output::Collided,
        Output::Separation,
    ];
}

/// A physics output read each step: one output of one actor ([`Node::Probe`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Probe {
    /// Whose output.
    pub actor: ActorRef,
    /// Which output.
    pub output: Output,
}

impl Probe {
    /// `output` of `actor`.
    pub fn new(actor: ActorRef, output: Output) -> Self {
        Probe { actor, output }
    }
}

/// What a `foreach` sink does with each event (paper §2: `foreach(walk)`). The event's value
/// is the action's argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    /// The pedestrian takes one walking step toward its target (the value is ignored).
    Walk(Handle<PedestrianSpec>),
    /// The car drives at the value, m/s (a number `>= 0`), from now on.
    SetSpeed(Handle<CarSpec>),
    /// The car slows by the value times the step, m/s² (a number `> 0`), and keeps the
    /// lower speed.
    Brake(Handle<CarSpec>),
    /// The car changes to the lane the value names (a lane number of its start segment, or a
    /// `(lane, duration_s)` tuple; 3 s by default).
    ChangeLane(Handle<CarSpec>),
    /// The car is put at the value, `(Vec3 [x, y, z] m, heading rad)` or `(Vec3, heading,
    /// speed m/s)`, for this step, off its path: a scripted car (an OpenSCENARIO
    /// storyboard's) whose motion its script computes. Its reported velocity is the speed
    /// given, along its heading (backwards for a negative speed: a reversing car), else the
    /// move it makes over the step (so a teleport with a
    /// speed given reports that speed, not the jump over one step). It stops for nothing, but
    /// what it touches at the new pose is recorded as a collision of both.
    PlaceCar(Handle<CarSpec>),
    /// The pedestrian is put at the value, `(Vec3 [x, y, z] m of its feet, heading rad)`, for
    /// this step, as [`Action::PlaceCar`].
    PlacePedestrian(Handle<PedestrianSpec>),
    /// The ego is put at the value, `(Vec3 [x, y, z] m of its footprint's centre on the
    /// ground, heading rad)`, for this step, as [`Action::PlaceCar`]: only for an ego whose
    /// [`crate::EgoSpec::scripted`] is set (a storyboard replays it; no system under test
    /// drives it).
    PlaceEgo,
    /// The system under test is asked to keep the value, m/s (a finite number `>= 0`), from
    /// now on: the set speed its observation carries ([`crate::Observation::set_speed_mps`]),
    /// as an OpenSCENARIO storyboard's `SpeedAction` on the ego it drives asks.
    SetEgoSpeed,
    /// The system under test takes over the ego that a script placed until now (the value is
    /// ignored): its chassis becomes a dynamic body moving at the velocity of its last placed
    /// step, and the system's control drives it from this step on (an OpenSCENARIO
    /// storyboard's `ActivateControllerAction` on the ego, after which esmini hands the ego
    /// to its controller). Only for an ego whose [`crate::EgoSpec::scripted`] is set; a
    /// second release does nothing.
    ReleaseEgo,
    /// The system under test is given a new route to follow from now on: the value is a
    /// tuple of two or more `Vec3 [x, y, z]` points (m, world frame; `y` is not read), the
    /// route its observation carries ([`crate::Observation::route`]), as an OpenSCENARIO
    /// storyboard's `LaneChangeAction` or `AssignRouteAction` on the ego it drives asks.
    SetEgoRoute,
    /// The actor enters the test (the value `true`) or leaves it (`false`), as an
    /// OpenSCENARIO storyboard's `AddEntityAction` and `DeleteEntityAction` ask. An actor out
    /// of the test has its body and collider out of the physics step (nothing touches it,
    /// no ray or sensor meets it, the camera does not draw it), its outputs have no events,
    /// and what it would touch is not recorded; it keeps its pose, which its place actions
    /// still move. An action on the ego does nothing (the ego is always in the test).
    SetPresent(ActorRef),
}

impl Action {
    /// The actor it acts on.
    pub fn actor(self) -> ActorRef {
        match self {
            Action::Walk(p) | Action::PlacePedestrian(p) => ActorRef::Pedestrian(p),
            Action::SetSpeed(c)
            | Action::Brake(c)
            | Action::ChangeLane(c)
            | Action::PlaceCar(c) => ActorRef::Car(c),
            Action::PlaceEgo | Action::SetEgoSpeed | Action::ReleaseEgo | Action::SetEgoRoute => {
                ActorRef::Ego
            }
            Action::SetPresent(r) => r,
        }
    }
}

/// What a place action's value must be ([`Action::PlaceCar`]), as its error says.
pub(crate) const POSE_EXPECTED: &str =
    "a (Vec3 [x, y, z] m, heading rad[, speed m/s]) tuple of finite numbers";

/// A placed actor's pose, `(Vec3 [x, y, z] m, heading rad)`, and the speed its script gives
/// it when the tuple has a third number (m/s, finite; negative backwards along its heading, a
/// storyboard's reversing entity): see [`Action::PlaceCar`].
/// `None` for anything else.
pub(crate) fn placed_pose(value: &Value) -> Option<([f64; 3], f64, Option<f64>)> {
    let pose = |p: &[f64; 3], h: f64| p.iter().all(|x| x.is_finite()) && h.is_finite();
    match value {
        Value::Tuple(t) => match t.as_slice() {
            [Value::Vec3(p), Value::Num(h)] if pose(p, *h) => Some((*p, *h, None)),
            [Value::Vec3(p), Value::Num(h), Value::Num(v)] if pose(p, *h) && v.is_finite() => {
                Some((*p, *h, Some(*v)))
            }
            _ => None,
        },
        _ => None,
    }
}

/// The error for `value`, given at time `t_s` (s) to `name` (an action's argument), which
/// is not `expected`.
pub(crate) fn bad_input(
    t_s: f64,
    name: String,
    value: &Value,
    expected: &str,
) -> crate::EngineError {
    crate::rx::RxError::Input {
        name,
        t_s,
        value: crate::rx::describe(value),
        expected: expected.into(),
    }
    .into()
}

/// Collects nodes; each push returns the new stream's id.
#[derive(Debug, Clone, Default)]
pub struct GraphBuilder {
    nodes: Vec<Node>,
    sites: Vec<Option<String>>,
}

impl GraphBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        GraphBuilder::default()
    }

    /// Adds `node`.
    pub fn push(&mut self, node: Node) -> StreamId {
        self.nodes.push(node);
        self.sites.push(None);
        StreamId(self.nodes.len() - 1)
    }

    /// Adds `node` made at `site` (a program's `file:line:col`), which errors of the node
    /// name instead of `stream N` (see [`Graph::site`]).
    pub fn push_at(&mut self, node: Node, site: String) -> StreamId {
        let id = self.push(node);
        self.sites[id.0] = Some(site);
        id
    }

    /// Names `site` (a program's `file:line:col`) as where node `id` was made, as
    /// [`GraphBuilder::push_at`] does; an id past the graph is ignored.
    pub fn set_site(&mut self, id: StreamId, site: String) {
        if let Some(s) = self.sites.get_mut(id.0) {
            *s = Some(site);
        }
    }

    /// The nodes so far.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Where node `node` was made (`file:line:col`), when it was pushed with
    /// [`GraphBuilder::push_at`].
    pub fn site(&self, node: usize) -> Option<&str> {
        self.sites.get(node).and_then(Option::as_deref)
    }

    /// The checked graph.
    ///
    /// # Errors
    /// As [`Graph::new`].
    pub fn finish(self) -> Result<Graph, RxError> {
        Ok(Graph::new(self.nodes)?.with_sites(self.sites))
    }

    /// The paper's pedestrian behaviour (§2, "Reactive Behaviors") for `pedestrian`:
    ///
    /// ```text
    /// trigger = car.zip(dist).filter(|car - start| < dist)   // planar distance, m
    /// done    = pos.filter(_ == target)
    /// tick.skipUntil(trigger).takeUntil(done).foreach(walk)
    /// ```
    ///
    /// `car` is a position stream (m), `dist` the trigger distance stream (m). The distance is
    /// measured in the ground plane (`x`, `z`), so the heights of a car's centre and a curb do
    /// not count. Returns the trigger stream.
    pub fn pedestrian(
        &mut self,
        pedestrian: Handle<PedestrianSpec>,
        start: [f64; 3],
        target: [f64; 3],
        car: StreamId,
        dist: StreamId,
    ) -> StreamId {
        let pair = self.push(Node::Zip(car, dist));
        let trigger = self.push(Node::Filter {
            src: pair,
            pred: Func::native("|car - start| < dist", move |a| match &a[0] {
                Value::Tuple(p) => match (p[0].as_vec3(), p[1].as_num()) {
                    (Some(c), Some(d)) => {
                        Ok(Value::Bool((c[0] - start[0]).hypot(c[2] - start[2]) < d))
                    }
                    _ => Err("the car stream must carry positions and dist numbers".into()),
                },
                v => Err(NativeError(format!(
                    "expected a (position, distance) pair, got a {}",
                    v.kind()
                ))),
            }),
        });
        self.pedestrian_with_trigger(pedestrian, target, trigger);
        trigger
    }

    /// `tick.skipUntil(trigger).takeUntil(done).foreach(walk)` for `pedestrian`, with any
    /// trigger stream (e.g. one a scenario computes with lambdas).
    pub fn pedestrian_with_trigger(
        &mut self,
        pedestrian: Handle<PedestrianSpec>,
        target: [f64; 3],
        trigger: StreamId,
    ) {
        let actor = ActorRef::Pedestrian(pedestrian);
        let pos = self.push(Node::Probe(Probe::new(actor, Output::Pos)));
        let done = self.push(Node::Filter {
            src: pos,
            pred: Func::native("_ == target", move |a| {
                Ok(Value::Bool(a[0] == Value::Vec3(target)))
            }),
        });
        let tick = self.push(Node::Tick);
        let skip = self.push(Node::SkipUntil { src: tick, trigger });
        let take = self.push(Node::TakeUntil {
            src: skip,
            stop: done,
        });
        self.push(Node::Foreach {
            src: take,
            sink: Action::Walk(pedestrian),
        });
    }
}
