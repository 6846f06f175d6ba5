//! The Starlark values of the scenario language. Each holds indices into the program's
//! scene builder (`SceneBuilder`), never other Starlark values, so all are simple values.

use paracosm_engine::behaviour::ActorRef;
use std::fmt;

use allocative::Allocative;
use starlark::starlark_simple_value;
use starlark::values::{
    starlark_value, Heap, NoSerialize, ProvidesStaticType, StarlarkValue, Value, ValueLike,
};
use starlark::StarlarkPagablePanic;

pub use crate::scene::OverTime;

/// A stream (paper §2): `tick`, `Const(...)`, an open parameter, an output of an object, or a
/// combinator over streams.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct Stream {
    /// Node index in the graph.
    pub id: usize,
    /// The number of a `Const(number)`, which inputs fixed for a test read as that number.
    pub number: Option<f64>,
}

impl Stream {
    /// The stream of graph node `id`, not known to be a constant number.
    pub fn of(id: usize) -> Self {
        Self { id, number: None }
    }
}

impl fmt::Display for Stream {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Stream({})", self.id)
    }
}

starlark_simple_value!(Stream);

/// A road piece, or a network of connected pieces represented by its first piece.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct Road {
    /// Piece index in the network.
    pub piece: usize,
    /// Number of ports of the piece.
    pub ports: usize,
    /// Whether it is a segment (has `onLane` and sidewalks).
    pub segment: bool,
    /// Whether this value stands for a whole network (the result of `connect`).
    pub network: bool,
    /// Whether it is an OpenDRIVE map (`OpenDrive(...)`: `onLane(road=, lane=, s=)`).
    pub map: bool,
}

impl fmt::Display for Road {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.network {
            write!(f, "RoadNetwork(piece {})", self.piece)
        } else {
            write!(f, "Road(piece {})", self.piece)
        }
    }
}

/// The names of a piece's ports, in order.
pub(crate) const PORTS: [&str; 4] = ["ONE", "TWO", "THREE", "FOUR"];

starlark_simple_value!(Road);

/// A connection point of a road piece (`t.ONE`).
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct Port {
    /// Piece index.
    pub piece: usize,
    /// Port index.
    pub index: usize,
}

impl fmt::Display for Port {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Port({}.{})", self.piece, PORTS[self.index])
    }
}

starlark_simple_value!(Port);

#[starlark_value(type = "Port")]
impl<'v> StarlarkValue<'v> for Port {}

/// `r.SideWalk` (`opposite: false`) or `-r.SideWalk`.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct LaneSide {
    /// The left (`-z`) sidewalk.
    pub opposite: bool,
}

impl fmt::Display for LaneSide {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.opposite {
            "-SideWalk"
        } else {
            "SideWalk"
        })
    }
}

starlark_simple_value!(LaneSide);

#[starlark_value(type = "SideWalk")]
impl<'v> StarlarkValue<'v> for LaneSide {
    fn minus(&self, heap: Heap<'v>) -> starlark::Result<Value<'v>> {
        Ok(heap.alloc(LaneSide {
            opposite: !self.opposite,
        }))
    }
}

/// An actor with its output streams (`pos`, `vel`, `heading`, `speed`, `collision`) and, for
/// a pedestrian, its `walk` action.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct ActorVal {
    /// Which actor: the ego, or a pedestrian's or a car's handle.
    #[allocative(skip)]
    pub kind: ActorRef,
    /// Output streams: pos, vel, heading, speed, collision, collided, separation.
    pub outputs: [usize; 7],
    /// Index in the placement list.
    pub object: usize,
}

const OUTPUT_NAMES: [&str; 7] = [
    "pos",
    "vel",
    "heading",
    "speed",
    "collision",
    "collided",
    "separation",
];

impl fmt::Display for ActorVal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            ActorRef::Ego => f.write_str("AutonomousVehicle"),
            ActorRef::Pedestrian(h) => write!(f, "Pedestrian({})", h.index()),
            ActorRef::Car(h) => write!(f, "Car({})", h.index()),
            ActorRef::Obstacle(h) => write!(f, "Obstacle({})", h.index()),
        }
    }
}

starlark_simple_value!(ActorVal);

#[starlark_value(type = "Actor")]
impl<'v> StarlarkValue<'v> for ActorVal {
    fn get_attr(&self, attribute: &str, heap: Heap<'v>) -> Option<Value<'v>> {
        use paracosm_engine::behaviour::Action as Act;
        let action = match (self.kind, attribute) {
            (ActorRef::Pedestrian(h), "walk") => Some((Act::Walk(h), "walk")),
            (ActorRef::Car(h), "setSpeed") => Some((Act::SetSpeed(h), "setSpeed")),
            (ActorRef::Car(h), "brake") => Some((Act::Brake(h), "brake")),
            (ActorRef::Car(h), "changeLane") => Some((Act::ChangeLane(h), "changeLane")),
            _ => None,
        };
        if let Some((a, method)) = action {
            return Some(heap.alloc(Action {
                sink: a,
                method,
                bound: None,
            }));
        }
        let i = OUTPUT_NAMES.iter().position(|n| *n == attribute)?;
        Some(heap.alloc(Stream::of(self.outputs[i])))
    }

    fn dir_attr(&self) -> Vec<String> {
        let mut v: Vec<String> = OUTPUT_NAMES.iter().map(|s| s.to_string()).collect();
        match self.kind {
            ActorRef::Pedestrian(_) => v.push("walk".into()),
            ActorRef::Car(_) => v.extend(["setSpeed", "brake", "changeLane"].map(String::from)),
            ActorRef::Ego | ActorRef::Obstacle(_) => {}
        }
        v
    }
}

/// An action (paper §2, `foreach(walk)`): `p.walk`, `car.setSpeed`, `car.brake`,
/// `car.changeLane`, with its argument when a call bound one (`car.brake(6)`).
///
/// Given to `foreach`, it is performed at each event: a bound action with its argument, an
/// unbound one with the event's value as its argument. Called during a test (inside a `def`
/// given to `foreach`), it is performed at once.
#[derive(Debug, Clone, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct Action {
    /// What it does to which actor.
    #[allocative(skip)]
    pub sink: paracosm_engine::behaviour::Action,
    /// The method's name, for messages.
    pub method: &'static str,
    /// The arguments a call bound: a number (m/s, m/s², a lane), and for `changeLane` a
    /// duration (s); `None` before a call.
    #[allocative(skip)]
    pub bound: Option<(f64, Option<f64>)>,
}

impl Action {
    /// The event value the engine's sink reads for the bound arguments.
    pub fn bound_value(&self) -> Option<paracosm_engine::rx::Value> {
        use paracosm_engine::rx::Value as Rx;
        self.bound.map(|(a, b)| match b {
            Some(d) => Rx::Tuple(vec![Rx::Num(a), Rx::Num(d)]),
            None => Rx::Num(a),
        })
    }

    /// Whether the action needs an argument (all but `walk`).
    pub fn takes_argument(&self) -> bool {
        self.method != "walk"
    }
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.bound {
            None => write!(f, "{}", self.method),
            Some((a, None)) => write!(f, "{}({a})", self.method),
            Some((a, Some(d))) => write!(f, "{}({a}, duration = {d})", self.method),
        }
    }
}

starlark_simple_value!(Action);

/// What a test's evaluator carries: the actions performed by host functions, and the lines
/// the program printed (the test's log).
#[derive(Debug, Default, ProvidesStaticType)]
pub struct TestState {
    /// Actions performed since the host last drained them, `(sink, value)`.
    pub performed: std::cell::RefCell<
        Vec<(
            paracosm_engine::behaviour::Action,
            paracosm_engine::rx::Value,
        )>,
    >,
    /// Lines printed, in order.
    pub log: std::cell::RefCell<Vec<String>>,
}

impl starlark::PrintHandler for TestState {
    fn println(&self, text: &str) -> starlark::Result<()> {
        self.log.borrow_mut().push(text.to_owned());
        Ok(())
    }
}

impl Action {
    /// A number argument of the action (an int or a float; a bool is no number).
    fn number_arg<'v>(&self, v: Value<'v>, what: &str) -> starlark::Result<f64> {
        v.unpack_i32()
            .map(f64::from)
            .or_else(|| {
                starlark::values::ValueLike::downcast_ref::<starlark::values::float::StarlarkFloat>(
                    v,
                )
                .map(|f| f.0)
            })
            .ok_or_else(|| {
                starlark::Error::new_other(anyhow::anyhow!(
                    "{}: {what} is a number, got {}",
                    self.method,
                    crate::lang::a_type(v.get_type())
                ))
            })
    }

    /// The arguments a call binds, checked: `given` by position in the action's signature,
    /// `required(i)` argument `i` or the error that it is missing.
    fn bind<'v>(
        &self,
        given: &[Option<Value<'v>>],
        required: &dyn Fn(usize) -> starlark::Result<Value<'v>>,
    ) -> starlark::Result<Option<(f64, Option<f64>)>> {
        let fail = |m: String| starlark::Error::new_other(anyhow::anyhow!(m));
        Ok(match self.method {
            "walk" => None,
            "changeLane" => {
                let lane = self.number_arg(required(0)?, "the lane")?;
                let duration = match given[1] {
                    Some(v) => Some(self.number_arg(v, "duration (s)")?),
                    None => None,
                };
                if lane.fract() != 0.0 || lane == 0.0 {
                    return Err(fail(format!(
                        "changeLane: a lane is a whole number other than 0, got {lane}"
                    )));
                }
                if duration.is_some_and(|d| !(d.is_finite() && d > 0.0)) {
                    return Err(fail("changeLane(duration=) is a time > 0 in s".into()));
                }
                Some((lane, duration))
            }
            method => {
                let v = self.number_arg(
                    required(0)?,
                    if method == "brake" {
                        "the deceleration (m/s²)"
                    } else {
                        "the speed (m/s)"
                    },
                )?;
                let ok = if method == "brake" {
                    v.is_finite() && v > 0.0
                } else {
                    v.is_finite() && v >= 0.0
                };
                if !ok {
                    return Err(fail(format!(
                        "{method} needs {}, got {v}",
                        if method == "brake" {
                            "a deceleration > 0 m/s²"
                        } else {
                            "a speed >= 0 m/s"
                        }
                    )));
                }
                Some((v, None))
            }
        })
    }
}

#[starlark_value(type = "Action")]
impl<'v> StarlarkValue<'v> for Action {
    fn invoke(
        &self,
        _me: Value<'v>,
        args: &starlark::eval::Arguments<'v, '_>,
        eval: &mut starlark::eval::Evaluator<'v, '_, '_>,
    ) -> starlark::Result<Value<'v>> {
        let fail = |m: String| starlark::Error::new_other(anyhow::anyhow!(m));
        if self.bound.is_some() {
            return Err(fail(format!(
                "{self} is already an action with its argument; pass it to foreach"
            )));
        }
        let heap = eval.heap();
        // Each argument by position or by keyword (the names LANGUAGE.md's table gives), once.
        let signature: Vec<&str> = crate::lang::builtins::find(self.method)
            .map(|b| b.inputs.iter().map(|a| a.keyword).collect())
            .unwrap_or_default();
        let usage = format!("{}({})", self.method, signature.join(", "));
        let mut given: Vec<Option<Value<'v>>> = vec![None; signature.len()];
        for (i, v) in args.positions(heap)?.enumerate() {
            let slot = given.get_mut(i).ok_or_else(|| {
                fail(format!(
                    "{self} takes {} argument{} ({usage}), got more",
                    signature.len(),
                    if signature.len() == 1 { "" } else { "s" }
                ))
            })?;
            *slot = Some(v);
        }
        for (k, v) in args.names_map()?.iter() {
            let Some(i) = signature.iter().position(|n| *n == k.as_str()) else {
                return Err(fail(format!(
                    "{self} has no argument `{}`: it is {usage}",
                    k.as_str()
                )));
            };
            if given[i].replace(*v).is_some() {
                return Err(fail(format!(
                    "{self}: `{}` is given twice, by position and by name ({usage})",
                    k.as_str()
                )));
            }
        }
        let required = |i: usize| {
            given[i].ok_or_else(|| fail(format!("{self} needs `{}`: it is {usage}", signature[i])))
        };
        let bound = self.bind(&given, &required)?;
        let action = Action {
            bound,
            ..self.clone()
        };
        // During a test, calling an action performs it.
        if let Some(test) = eval.extra.and_then(|e| e.downcast_ref::<TestState>()) {
            let value = action
                .bound_value()
                .unwrap_or(paracosm_engine::rx::Value::Unit);
            test.performed.borrow_mut().push((action.sink, value));
            return Ok(Value::new_none());
        }
        Ok(heap.alloc(action))
    }
}

/// `World(light=, fog=)`.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct WorldVal {
    /// Light stream.
    pub light: usize,
    /// Fog stream.
    pub fog: usize,
}

impl fmt::Display for WorldVal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("World")
    }
}

starlark_simple_value!(WorldVal);

/// A monitor, registered when created.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct MonitorVal {
    /// Index in the program's monitor list.
    pub index: usize,
    /// How many `TimeToFailure`s wrap the monitor it stands for (0 for a monitor as
    /// declared): the slot at `index` holds it only while it has not been wrapped again.
    pub wraps: usize,
}

impl fmt::Display for MonitorVal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Monitor({})", self.index)
    }
}

starlark_simple_value!(MonitorVal);

#[starlark_value(type = "Monitor")]
impl<'v> StarlarkValue<'v> for MonitorVal {}

/// `Piecewise(k)` or `Polynomial(deg)`.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct OverTimeVal {
    /// The profile.
    #[allocative(skip)]
    pub over_time: OverTime,
}

impl fmt::Display for OverTimeVal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.over_time {
            OverTime::Constant => f.write_str("Constant"),
            OverTime::Piecewise(k) => write!(f, "Piecewise({k})"),
            OverTime::Polynomial(d) => write!(f, "Polynomial({d})"),
        }
    }
}

starlark_simple_value!(OverTimeVal);

#[starlark_value(type = "OverTime")]
impl<'v> StarlarkValue<'v> for OverTimeVal {}

/// When a `ChangeLane` starts.
#[derive(Debug, Clone, Copy, PartialEq, Allocative)]
pub enum ChangeStart {
    /// At this time, s.
    At(f64),
    /// At the first event of this stream.
    When(usize),
}

/// `ChangeLane(to=, at=, when=, duration=)`: a lane change for `Car(lane_change=)`.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct LaneChangeVal {
    /// The lane it moves to, on the car's segment.
    pub to: i32,
    /// When it starts.
    pub start: ChangeStart,
    /// How long it takes, s.
    pub duration_s: f64,
}

impl fmt::Display for LaneChangeVal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "ChangeLane(to = {}, duration = {})",
            self.to, self.duration_s
        )
    }
}

starlark_simple_value!(LaneChangeVal);

#[starlark_value(type = "ChangeLane")]
impl<'v> StarlarkValue<'v> for LaneChangeVal {}

/// `Obstacle(...)`: a static box, for `place`.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct ObstacleVal {
    /// Index in the program's declared objects.
    pub object: usize,
}

impl fmt::Display for ObstacleVal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Obstacle({})", self.object)
    }
}

starlark_simple_value!(ObstacleVal);

#[starlark_value(type = "Obstacle")]
impl<'v> StarlarkValue<'v> for ObstacleVal {}

/// A hint for a stream passed where a value is needed, empty for anything else.
pub(crate) fn stream_hint(v: Value) -> &'static str {
    if v.downcast_ref::<Stream>().is_some() {
        " (a stream has a value only while a test runs: apply the function inside a lambda, \
         e.g. s.map(lambda x: sqrt(x)))"
    } else {
        ""
    }
}
