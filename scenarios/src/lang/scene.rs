//! What one evaluation of a scenario program builds: plain Rust data (no Starlark values),
//! turned into the test's [`WorldSpec`] once the program has finished. A program is evaluated
//! once per test, with that test's values of its open parameters (LANGUAGE.md, "A family of
//! worlds"), and a few times when it loads, to learn its parameters and check its worlds.

use super::load_error::{LoadError, LoadErrorKind};
use paracosm_engine::actor::Roster;
use paracosm_engine::behaviour::{ActorRef, GraphBuilder, Output, Probe};
use paracosm_engine::network::{Location, Network, PieceId, PieceKind, Turn};
use paracosm_engine::rx::{Node, OpenStream, StreamId, Value};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{
    CarSpec, EgoSpec, EnvironmentSpec, ObstacleSpec, PedestrianSpec, Size, VehicleParams,
    WorldSpec, DEFAULT_DT_S,
};
use paracosm_generators::{Domain, Value as Level};

use super::values::OverTime;
use crate::scenario::Warning;
use crate::MonitorSpec;

/// A level as the stream carries it: numbers as numbers, bools as bools, texts as strings.
pub fn level_value(l: &Level) -> Value {
    match l {
        Level::Int(i) => Value::Num(*i as f64),
        Level::Real(x) => Value::Num(*x),
        Level::Bool(b) => Value::Bool(*b),
        Level::Text(t) => Value::Text(t.clone()),
    }
}

/// The `tick` stream: the first node of every program's graph.
pub const TICK: StreamId = StreamId(0);

/// A `VarInterval` or `VarEnum` as declared.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamDecl {
    /// `name=`, if given.
    pub name: Option<String>,
    /// Range or levels.
    pub domain: Domain,
    /// `unit=`.
    pub unit: Option<String>,
    /// `over_time=`.
    pub over_time: OverTime,
    /// Where it was declared, `file:line:col`.
    pub at: String,
}

/// What an open parameter is in one evaluation of the program.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// A parameter constant over the test: its value, which the program sees as a plain
    /// number, string or bool.
    Level(Level),
    /// A parameter that varies over the test: the stream of its values.
    Over(OpenStream),
}

/// What a program sees of an open parameter it declares ([`SceneBuilder::param`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Seen {
    /// A parameter constant over the test: its value.
    Level(Level),
    /// A parameter that varies over the test: the stream of its values.
    Stream(StreamId),
}

/// What starts a pedestrian walking.
#[derive(Debug, Clone, Copy)]
pub enum PedTrigger {
    /// The paper's trigger: the `car` position stream comes within `dist` metres of the start.
    Near {
        /// Position stream.
        car: StreamId,
        /// Distance stream, m.
        dist: StreamId,
    },
    /// Any stream: its first event starts the walk.
    Stream(StreamId),
    /// None: it walks only when an action moves it (`stream.foreach(p.walk)`).
    Never,
}

/// An `onLane(...)` not yet resolved (pieces may still move).
#[derive(Debug, Clone, Copy)]
pub enum LaneRef {
    /// `r.onLane(lane, at)` on a segment.
    Segment {
        /// The segment.
        piece: PieceId,
        /// The lane.
        lane: paracosm_engine::Lane,
        /// Distance from the segment's port ONE, m.
        at_m: f64,
    },
    /// `j.onLane(port, turn, at, lane=)` in a junction or roundabout.
    Junction {
        /// The junction.
        piece: PieceId,
        /// The port it enters through.
        entry: usize,
        /// The turn its path makes.
        turn: Turn,
        /// Its lane, from the centre line.
        lane: u32,
        /// Distance along the path, m.
        at_m: f64,
    },
    /// `m.onLane(road=, lane=, s=)` on an OpenDRIVE map.
    Map {
        /// The map.
        piece: PieceId,
        /// The road, an index into the map's [`paracosm_engine::network::RoadMap::roads`].
        road: usize,
        /// The lane's OpenDRIVE id.
        lane: i32,
        /// Distance along the road's reference line, m.
        s_m: f64,
    },
}

impl LaneRef {
    /// The location on `roads` as they stand.
    ///
    /// # Errors
    /// The network's message when the location does not exist.
    pub fn resolve(&self, roads: &Network) -> Result<Location, LoadError> {
        match *self {
            LaneRef::Segment { piece, lane, at_m } => roads.on_lane(piece, lane, at_m),
            LaneRef::Junction {
                piece,
                entry,
                turn,
                lane,
                at_m,
            } => roads.on_junction_lane(piece, entry, turn, lane, at_m),
            LaneRef::Map {
                piece,
                road,
                lane,
                s_m,
            } => {
                let PieceKind::Map { map, .. } = &roads.piece(piece).kind else {
                    return Err(LoadError::new(
                        LoadErrorKind::Declarations,
                        "onLane(road=, lane=, s=) on a piece that is no map",
                    ));
                };
                let od_id = map.0.roads[road].od_id.clone();
                roads.on_map_lane(piece, &od_id, lane, s_m)
            }
        }
        .map_err(|e| LoadError::new(LoadErrorKind::Declarations, strip(e)))
    }
}

/// An actor declared but not yet placed.
#[derive(Debug, Clone)]
pub enum Pending {
    /// `AutonomousVehicle`.
    Ego {
        /// Start.
        loc: usize,
        /// Route turns, `None` to keep the lane.
        route: Option<Vec<Turn>>,
        /// Initial speed, m/s.
        initial_speed_mps: f64,
        /// System under test.
        sut: SutConfig,
    },
    /// `Pedestrian`.
    Pedestrian {
        /// Start location.
        start: usize,
        /// Target location.
        target: usize,
        /// Speed stream.
        speed: StreamId,
        /// Trigger.
        trigger: PedTrigger,
    },
    /// `Car`.
    Car(PendingCar),
    /// `Obstacle`.
    Obstacle {
        /// Where its base's centre stands.
        loc: usize,
        /// Its size.
        size: Size,
        /// Colour name.
        color: String,
    },
}

/// A `Car` as declared, before `place` resolves its location and route.
#[derive(Debug, Clone)]
pub struct PendingCar {
    /// Start location.
    pub loc: usize,
    /// Turns.
    pub route: Vec<Turn>,
    /// Speed stream.
    pub speed: StreamId,
    /// Colour name.
    pub color: String,
    /// Presence.
    pub enabled: bool,
    /// Its lane change, if any.
    pub lane_change: Option<super::values::LaneChangeVal>,
    /// The gap it keeps to what is ahead, m (`Car(keep_distance=)`).
    pub keep_distance_m: Option<f64>,
}

/// A declared actor: what it is, where it was declared, and whether `place` saw it.
#[derive(Debug, Clone)]
pub struct ObjectDecl {
    /// How messages name it: its variable (`lead`), else `Car at follow.star:12:7`.
    pub name: String,
    /// Where it was declared, `file:line:col`.
    pub at: String,
    /// The variable it is assigned to, when its declaration runs once (`lead = Car(...)` at
    /// the top level): its outputs are `Stl` signals `lead.speed`, `lead.pos.x`, ...
    pub variable: Option<String>,
    /// The actor it is (`None` for an obstacle).
    pub actor: Option<ActorRef>,
    /// The declaration.
    pub pending: Pending,
    /// Whether `place` included it.
    pub placed: bool,
}

impl ObjectDecl {
    /// How run-time messages name it: `Car lead (f.star:4:5)` for an object assigned to a
    /// variable, else `Car at f.star:4:5`; `kind` is its builtin's name.
    pub fn runtime_name(&self, kind: &str) -> String {
        match &self.variable {
            Some(v) => format!("{kind} {v} ({})", self.at),
            None => format!("{kind} at {}", self.at),
        }
    }
}

/// Everything one evaluation of a program declares.
#[derive(Debug)]
pub struct SceneBuilder {
    /// The stream graph.
    pub graph: GraphBuilder,
    /// Open parameters, in declaration order.
    pub params: Vec<ParamDecl>,
    /// The values this evaluation gives the parameters, by declaration index; `None`: each
    /// parameter's representative value (an interval's lower bound, the first level).
    pub values: Option<Vec<ParamValue>>,
    /// The road pieces.
    pub roads: Network,
    /// Each piece's friction stream.
    pub frictions: Vec<(PieceId, StreamId)>,
    /// Where each road piece was declared (`file:line:col`), by piece.
    pub pieces_at: Vec<String>,
    /// How far routes are planned, m ([`route_length_m`] of the horizon).
    pub route_m: f64,
    /// The ego vehicle, once placed: the engine's spec (an actor goes from its declaration,
    /// [`Pending`], straight to the engine's spec when `place` resolves its locations).
    pub ego: Option<EgoSpec>,
    /// The ego vehicle's system under test (`AutonomousVehicle(sut=)`), once placed.
    pub sut: Option<SutConfig>,
    /// Pedestrians.
    pub pedestrians: Vec<PedestrianSpec>,
    /// Cars.
    pub cars: Vec<CarSpec>,
    /// Static obstacles.
    pub obstacles: Vec<ObstacleSpec>,
    /// `World(light=, fog=)`.
    pub world: Option<(StreamId, StreamId)>,
    /// Whether `place` ran.
    pub placed: bool,
    /// Monitors.
    pub monitors: Vec<MonitorSpec>,
    /// Where each monitor was declared (or last wrapped), `file:line:col`, in the order of
    /// [`SceneBuilder::monitors`].
    pub monitors_at: Vec<String>,
    /// Where `test(...)` was called, `file:line:col`.
    pub test_at: Option<String>,
    /// `test(horizon=)`, seconds.
    pub horizon_s: Option<f64>,
    /// `test(map=)`: one or two parameter names.
    pub map_axes: Option<Vec<String>>,
    /// `test(offroad=)`: whether the default `OffRoadMonitor` is added (default true).
    pub offroad: Option<bool>,
    /// Where `place(...)` was called, `file:line:col`.
    pub placed_at: Option<String>,
    /// Warnings so far.
    pub warnings: Vec<Warning>,
    /// The cars' names for messages, in the order of [`SceneBuilder::cars`].
    pub car_names: Vec<String>,
    /// The obstacles' names for messages, in the order of [`SceneBuilder::obstacles`].
    pub obstacle_names: Vec<String>,
    /// Number of lambdas stored so far.
    pub lambdas: u32,
    /// Streams published by name to monitors (`Monitor`, `Assert`, `Signal`).
    pub published: Vec<(String, StreamId)>,
    /// Each `Signal(name, ...)`'s name and where it was called, `file:line:col`.
    pub signals_at: Vec<(String, String)>,
    /// What the program printed while this evaluation ran (the start of a test's log).
    pub log: Vec<String>,
    /// `onLane` results, by index.
    pub locs: Vec<LaneRef>,
    /// Where each of `locs` stands on the network as it is now, shared with the `Location`
    /// values of the program.
    pub loc_table: super::position::LocTable,
    /// Declared actors, in declaration order.
    pub objects: Vec<ObjectDecl>,
    /// The handles of the pedestrians declared so far, in declaration order (the order of
    /// the world's [`WorldSpec::pedestrians`]).
    pub pedestrian_handles: Roster<PedestrianSpec>,
    /// The handles of the cars declared so far, in declaration order.
    pub car_handles: Roster<CarSpec>,
}

/// The value a parameter takes when an evaluation gives it none: an interval's lower bound,
/// the first level (constant over time, or the same as coefficients over time).
pub fn representative(decl: &ParamDecl, horizon_s: f64) -> ParamValue {
    let lowest = match &decl.domain {
        Domain::Interval { lo, .. } => Level::Real(*lo),
        Domain::Levels(levels) => levels[0].clone(),
    };
    match decl.over_time {
        OverTime::Constant => ParamValue::Level(lowest),
        over => {
            let lo = lowest.as_f64().unwrap_or(0.0);
            let n = coordinate_names("p", over).len();
            ParamValue::Over(match over {
                OverTime::Piecewise(_) => OpenStream::Piecewise {
                    values: vec![lo; n],
                    horizon_s,
                },
                _ => OpenStream::Polynomial {
                    coefficients: vec![lo; n],
                    horizon_s,
                },
            })
        }
    }
}

impl SceneBuilder {
    /// A builder with the `tick` stream as stream [`TICK`], for an evaluation that gives the
    /// parameters `values` (by declaration index; `None`: representative values).
    pub fn new(values: Option<Vec<ParamValue>>) -> Self {
        let mut graph = GraphBuilder::new();
        let tick = graph.push(Node::Tick);
        debug_assert_eq!(tick, TICK);
        SceneBuilder {
            graph,
            params: Vec::new(),
            values,
            roads: Network::new(),
            frictions: Vec::new(),
            pieces_at: Vec::new(),
            route_m: MAX_ROUTE_M,
            ego: None,
            sut: None,
            pedestrians: Vec::new(),
            cars: Vec::new(),
            obstacles: Vec::new(),
            world: None,
            placed: false,
            monitors: Vec::new(),
            horizon_s: None,
            map_axes: None,
            offroad: None,
            placed_at: None,
            monitors_at: Vec::new(),
            test_at: None,
            warnings: Vec::new(),
            car_names: Vec::new(),
            obstacle_names: Vec::new(),
            lambdas: 0,
            published: Vec::new(),
            signals_at: Vec::new(),
            log: Vec::new(),
            locs: Vec::new(),
            loc_table: Default::default(),
            objects: Vec::new(),
            pedestrian_handles: Roster::default(),
            car_handles: Roster::default(),
        }
    }

    /// Declares an open parameter; returns what the program sees: its value, or for one
    /// that varies over time, its stream. A parameter only these values declare (the program
    /// declared more parameters than with other values) gets its representative value, so that
    /// the run goes on and the load reports it, naming it.
    pub fn param(&mut self, decl: ParamDecl) -> Seen {
        let k = self.params.len();
        let value = match &self.values {
            None => representative(&decl, self.horizon_s.unwrap_or(super::DEFAULT_HORIZON_S)),
            // A parameter only these values declare: its representative value, so that the
            // run goes on and the program reports it, naming it.
            Some(values) => values.get(k).cloned().unwrap_or_else(|| {
                representative(&decl, self.horizon_s.unwrap_or(super::DEFAULT_HORIZON_S))
            }),
        };
        self.params.push(decl);
        match value {
            ParamValue::Level(l) => Seen::Level(l),
            ParamValue::Over(_) => Seen::Stream(self.graph.push(Node::Param(k))),
        }
    }

    /// A probe stream.
    pub fn probe(&mut self, actor: ActorRef, output: Output) -> StreamId {
        self.graph.push(Node::Probe(Probe::new(actor, output)))
    }
}

/// The names of the coordinates a parameter adds to the space.
pub fn coordinate_names(name: &str, over_time: OverTime) -> Vec<String> {
    match over_time {
        OverTime::Constant => vec![name.to_owned()],
        OverTime::Piecewise(k) => (0..k).map(|i| format!("{name}[{i}]")).collect(),
        OverTime::Polynomial(d) => (0..=d).map(|i| format!("{name}.c{i}")).collect(),
    }
}

/// The streams of the parameters that vary over time, by declaration index, for
/// [`paracosm_engine::rx::Graph::bind`]; constant ones get an unused placeholder.
fn over_time_streams(b: &SceneBuilder, horizon_s: f64) -> Vec<OpenStream> {
    b.params
        .iter()
        .enumerate()
        .map(|(k, decl)| {
            let v = match &b.values {
                Some(values) => values[k].clone(),
                None => representative(decl, horizon_s),
            };
            match v {
                ParamValue::Over(s) => s,
                ParamValue::Level(l) => OpenStream::Constant(level_value(&l)),
            }
        })
        .collect()
}

/// The test's world from a finished, placed evaluation.
///
/// # Errors
/// An object's name with where it was declared, `Car c (f.star:4:5)`, unless the name already
/// says it (`Car at f.star:2:12 (called from ...)`).
fn declared(name: &str, at: &str) -> String {
    if at.is_empty() || name.contains(at) {
        name.to_owned()
    } else {
        format!("{name} ({at})")
    }
}

/// A message when the program placed nothing or no ego vehicle, or its graph is invalid.
pub fn world(b: &SceneBuilder, horizon_s: f64) -> Result<WorldSpec, LoadError> {
    let worlds = |message: &str| LoadError::new(LoadErrorKind::Worlds, message);
    let ego = b
        .ego
        .as_ref()
        .ok_or_else(|| worlds("the program places no AutonomousVehicle: nothing to test"))?;
    let (light, fog) = b
        .world
        .ok_or_else(|| worlds("the program has no World(...)"))?;
    let mut nodes = b.graph.clone();
    let published = published(b, &mut nodes)?;
    refuse_monitors_of_absent_cars(b, nodes.nodes(), &published)?;
    let graph = nodes.finish().map_err(|e| worlds(&e.to_string()))?;
    let streams = graph
        .bind(&over_time_streams(b, horizon_s))
        .map_err(|e| worlds(&e.to_string()))?;
    // Pieces whose friction is constant carry it; the others get it from their stream each
    // step.
    let mut network = b.roads.clone();
    let mut friction_streams = Vec::new();
    for &(piece, stream) in &b.frictions {
        match streams.nodes().get(stream.0) {
            Some(Node::Const(Value::Num(mu))) => network
                .set_friction(piece, *mu)
                .map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?,
            _ => friction_streams.push((piece, stream)),
        }
    }
    Ok(WorldSpec {
        dt_s: DEFAULT_DT_S,
        network,
        frictions: friction_streams,
        ego: ego.clone(),
        pedestrians: b.pedestrians.clone(),
        cars: b.cars.clone(),
        obstacles: b.obstacles.clone(),
        environment: EnvironmentSpec { light, fog },
        streams,
        published,
        sensors: paracosm_engine::SensorSpec::defaults(),
    })
}

/// Refuses a world in which a monitor reads the outputs of a car this world leaves out
/// (`Car(enabled = False)`): such a car is not in the test, its outputs carry no events, and
/// the monitor would have nothing to judge. A stream depends on a car when the car's probe
/// feeds it through any input but a `takeUntil`'s stop (a stop that never fires cuts
/// nothing).
///
/// # Errors
/// A message naming the monitor, the car, how to read an optional car, and the monitor's
/// `file:line:col`.
fn refuse_monitors_of_absent_cars(
    b: &SceneBuilder,
    nodes: &[Node],
    published: &[(String, StreamId)],
) -> Result<(), LoadError> {
    let absent: Vec<usize> = (0..b.cars.len()).filter(|&i| !b.cars[i].enabled).collect();
    if absent.is_empty() {
        return Ok(());
    }
    // The absent car each stream depends on, in topological order (a node's inputs come
    // before it).
    let mut reads: Vec<Option<usize>> = vec![None; nodes.len()];
    for (i, node) in nodes.iter().enumerate() {
        reads[i] = match node {
            Node::Probe(p) => match p.actor {
                ActorRef::Car(c) if absent.contains(&c.index()) => Some(c.index()),
                _ => None,
            },
            Node::TakeUntil { src, .. } => reads.get(src.0).copied().flatten(),
            other => other
                .inputs()
                .iter()
                .find_map(|s| reads.get(s.0).copied().flatten()),
        };
    }
    for (name, id) in published {
        let Some(car) = reads.get(id.0).copied().flatten() else {
            continue;
        };
        let reader = b.monitors.iter().enumerate().find(|(_, m)| {
            m.signals().iter().any(|s| {
                s == name
                    || s.strip_prefix(name.as_str())
                        .is_some_and(|c| [".x", ".y", ".z"].contains(&c))
            })
        });
        if let Some((k, m)) = reader {
            let at = b.monitors_at.get(k).map(String::as_str).unwrap_or("");
            let car_name = b.car_names.get(car).map(String::as_str).unwrap_or("a Car");
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                "monitor `{}` reads {car_name}, which this world leaves out (enabled = False): \
                 the car is not in the test, its outputs have no events, and the monitor \
                 would have nothing to judge. For a car that is in some tests only, read it \
                 in a lambda through a top-level variable (`lead_speed = lead.speed`), which \
                 is None while the car is absent, and judge a stream that always fires \
                 (`tick.map(...)`)\n --> {at}",
                m.name()
            ),
            ));
        }
    }
    Ok(())
}

/// Checks that every signal a monitor reads is published by the runner, the program or an
/// actor (see [`world`]).
///
/// # Errors
/// A message naming the signal, what is published, and the monitor's `file:line:col`.
pub fn check_signals(b: &SceneBuilder) -> Result<(), LoadError> {
    published(b, &mut b.graph.clone()).map(|_| ())
}

/// The outputs of an actor that `Stl` formulas may read as `<variable>.<output>`.
const ACTOR_SIGNALS: [(&str, Output); 7] = [
    ("pos", Output::Pos),
    ("vel", Output::Vel),
    ("speed", Output::Speed),
    ("heading", Output::Heading),
    ("collision", Output::Collision),
    ("collided", Output::Collided),
    ("separation", Output::Separation),
];

/// Refuses a `Signal` named as an actor's output (`Signal("lead.speed", ...)`: a formula
/// reading `lead.speed` would read the Signal in the car's place) or as a component another
/// `Signal` gives itself (`Signal("lp", lead.pos)` publishes `lp.x`, `lp.y` and `lp.z`).
fn check_signal_names(b: &SceneBuilder) -> Result<(), LoadError> {
    // A Signal may not take an actor output's name (`Signal("lead.speed", ...)`): a formula
    // reading `lead.speed` would read the Signal in the car's place.
    for (name, at) in &b.signals_at {
        let mut parts = name.split('.');
        let (Some(var), Some(field)) = (parts.next(), parts.next()) else {
            continue;
        };
        let actor = b
            .objects
            .iter()
            .find(|o| o.actor.is_some() && o.variable.as_deref() == Some(var));
        if let (Some(o), true) = (actor, ACTOR_SIGNALS.iter().any(|(n, _)| *n == field)) {
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                    "Signal `{name}` takes the name of an output of {} (`{var}.{field}`), which \
                 monitors read as that actor's; give the Signal another name\n --> {at}",
                    o.name
                ),
            ));
        }
    }
    // Nor the name of a component another Signal gives itself (`Signal("lp", lead.pos)`
    // publishes `lp.x`, `lp.y` and `lp.z`): one would hide the other.
    for (k, (name, at)) in b.signals_at.iter().enumerate() {
        let whole = b.signals_at[..k].iter().find(|(other, _)| {
            [".x", ".y", ".z"]
                .iter()
                .any(|c| *name == format!("{other}{c}") || *other == format!("{name}{c}"))
        });
        if let Some((other, first)) = whole {
            let (vector, component) = if name.len() > other.len() {
                (other, name)
            } else {
                (name, other)
            };
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                    "Signal `{name}` and Signal `{other}` (declared at {first}) clash: a vector \
                 Signal `{vector}` is published as `{vector}.x`, `{vector}.y` and `{vector}.z`, \
                 so `{component}` would read one of them; give one another name\n --> {at}"
                ),
            ));
        }
    }
    Ok(())
}

/// Whether `s` names a published signal of `out` (whose streams carry vectors as `vector`
/// says): a stream of numbers or bools by its name, a vector's component by `name.x`, `.y`,
/// `.z`.
///
/// # Errors
/// A vector named whole, or a component of a number.
fn known_signal(
    out: &[(String, StreamId)],
    vector: &[Option<bool>],
    s: &str,
) -> Result<bool, LoadError> {
    if crate::runner::signal::ALL.contains(&s) {
        return Ok(true);
    }
    for ((n, _), v) in out.iter().zip(vector) {
        let component = s
            .strip_prefix(n.as_str())
            .is_some_and(|c| [".x", ".y", ".z"].contains(&c));
        match (n == s, component, v) {
            (true, _, Some(true)) => {
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "`{s}` is a vector: a formula compares numbers, so write `{s}.x`, \
                     `{s}.y` or `{s}.z`"
                    ),
                ))
            }
            (false, true, Some(false)) => {
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "`{n}` is a number, with no component `{}`: write `{n}`",
                        &s[n.len() + 1..]
                    ),
                ))
            }
            (true, _, _) | (_, true, _) => return Ok(true),
            _ => {}
        }
    }
    Ok(false)
}

/// The streams published to the monitors: those the program published (`Monitor`, `Assert`,
/// `Signal`), then each actor output a monitor reads by name (`lead.speed`, `p.pos.x`), as a
/// probe added to `graph`.
///
/// # Errors
/// A message naming a signal a monitor reads that is neither the runner's, the program's nor
/// an actor's.
fn published(
    b: &SceneBuilder,
    graph: &mut GraphBuilder,
) -> Result<Vec<(String, StreamId)>, LoadError> {
    check_signal_names(b)?;
    let mut out = b.published.clone();
    // Whether each published stream carries vectors: `Some(true)` it does, `Some(false)` it
    // carries numbers or bools, `None` unknown until the test runs (a lambda's values; the
    // check at load looks at its sample, `program::judged_kinds`).
    let types = super::types::stream_types(b);
    let mut vector: Vec<Option<bool>> = out
        .iter()
        .map(|(_, id)| match types.get(id.0) {
            Some(super::types::SType::Vec3) => Some(true),
            Some(super::types::SType::Any) | None => None,
            Some(_) => Some(false),
        })
        .collect();
    // Whether `s` names a published signal: a stream of numbers or bools by its name, a
    // vector's component by `name.x`, `.y`, `.z`; a vector named whole, or a component of a
    // number, is an error.
    let known = known_signal;
    for (k, m) in b.monitors.iter().enumerate() {
        let at = b.monitors_at.get(k).map(String::as_str).unwrap_or("");
        let located = |e: String| {
            LoadError::new(
                LoadErrorKind::Declarations,
                format!("{} reads the signal: {e}\n --> {at}", m.name()),
            )
        };
        for s in m.signals() {
            if known(&out, &vector, &s).map_err(|e| located(e.message))? {
                continue;
            }
            let found = s.split_once('.').and_then(|(var, rest)| {
                let object = b
                    .objects
                    .iter()
                    .find(|o| o.variable.as_deref() == Some(var))?;
                let actor = object.actor?;
                let field = rest.split('.').next()?;
                let (_, output) = ACTOR_SIGNALS.iter().find(|(n, _)| *n == field)?;
                Some((format!("{var}.{field}"), actor, *output))
            });
            match found {
                Some((name, actor, output)) => {
                    let id = graph.push(Node::Probe(Probe::new(actor, output)));
                    out.push((name.clone(), id));
                    vector.push(Some(matches!(output, Output::Pos | Output::Vel)));
                    if !known(&out, &vector, &s).map_err(|e| located(e.message))? {
                        return Err(located(format!(
                            "`{s}` is no output of `{name}`; an actor's outputs are .pos.x, \
                             .pos.y, .pos.z, .vel.x, .vel.y, .vel.z, .speed, .heading, \
                             .collision, .collided and .separation"
                        )));
                    }
                }
                None => {
                    let actors: Vec<&str> = b
                        .objects
                        .iter()
                        .filter(|o| o.actor.is_some())
                        .filter_map(|o| o.variable.as_deref())
                        .collect();
                    let mine: Vec<&str> = b
                        .published
                        .iter()
                        .map(|(n, _)| n.as_str())
                        .filter(|n| !n.starts_with("monitor:"))
                        .collect();
                    return Err(LoadError::new(
                        LoadErrorKind::Declarations,
                        format!(
                        "monitor `{}` reads the signal `{s}`, which nothing publishes. The runner \
                         publishes {}; the program's Signal(...)s: {}; each actor assigned to a \
                         variable at the top level publishes <variable>.pos.x/.y/.z, .vel.x/.y/.z, \
                         .speed, .heading and .collision (actors: {})\n --> {at}",
                        m.name(),
                        crate::runner::signal::ALL.join(", "),
                        if mine.is_empty() {
                            "none".to_owned()
                        } else {
                            mine.join(", ")
                        },
                        if actors.is_empty() {
                            "none".to_owned()
                        } else {
                            actors.join(", ")
                        },
                    ),
                    ));
                }
            }
        }
    }
    Ok(out)
}

/// Parses a route list of turns.
pub fn turns(names: &[String]) -> Result<Vec<Turn>, LoadError> {
    names
        .iter()
        .map(|n| {
            Turn::parse(n).ok_or_else(|| {
                LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "route entry `{n}` is not a turn; use \"straight\", \"left\" or \"right\""
                    ),
                )
            })
        })
        .collect()
}

/// Longest route computed for an actor, in metres.
const MAX_ROUTE_M: f64 = 5000.0;

/// Fastest an NPC car or the ego is taken to drive when its route is planned, m/s (216 km/h):
/// a route is planned as far as that speed goes in the test's horizon (at least
/// [`MAX_ROUTE_M`]), so that on a loop a car does not run out of route and stop.
pub const ROUTE_SPEED_MPS: f64 = 60.0;

/// How far routes are planned for a test of `horizon_s` seconds, m.
pub fn route_length_m(horizon_s: f64) -> f64 {
    MAX_ROUTE_M.max(ROUTE_SPEED_MPS * horizon_s)
}

impl SceneBuilder {
    /// Resolves every location again on the network as it stands (after `connect` moved
    /// pieces); a location that no longer resolves is `None` until it does.
    pub fn resolve_locations(&mut self) {
        let now: Vec<_> = self
            .locs
            .iter()
            .map(|l| l.resolve(&self.roads).ok())
            .collect();
        if let Ok(mut t) = self.loc_table.write() {
            *t = now;
        }
    }

    /// `w.place(...)`: marks `objects` placed, resolves every actor's location and route on
    /// the final road network, builds the pedestrians' behaviour, and runs the checks: no
    /// overlapping road pieces, no objects starting in collision, vehicles on the road.
    ///
    /// # Errors
    /// A message naming the offending pieces or objects.
    pub fn place(&mut self, objects: &[usize]) -> Result<(), LoadError> {
        use paracosm_engine::placement::{check, Footprint, Placed};
        if self.placed {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                "place(...) may be called only once",
            ));
        }
        if let Some((a, b)) = self.roads.first_overlap() {
            let named = |p: PieceId| {
                let name = &self.roads.piece(p).name;
                declared(name, self.pieces_at.get(p.0).map_or("", String::as_str))
            };
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!("road pieces overlap: {} and {}", named(a), named(b)),
            ));
        }
        for &o in objects {
            self.objects[o].placed = true;
        }
        if let Some(o) = self.objects.iter().find(|o| !o.placed) {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!(
                    "{} is not in this place(...): place(...) is called once, and lists every \
                 actor and obstacle",
                    o.name
                ),
            ));
        }
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(&b.roads);
        // Check the starting positions before anything depends on them (routes, behaviours).
        let mut placed = Vec::new();
        for o in &self.objects {
            // A disabled car is not in the test: nothing can start in collision with it, and
            // where it would stand does not matter.
            if matches!(o.pending, Pending::Car(PendingCar { enabled: false, .. })) {
                continue;
            }
            let (loc, footprint, on_road) = match &o.pending {
                Pending::Ego { loc, .. } => (*loc, Some(VehicleParams::default().size), true),
                Pending::Car(PendingCar { loc, .. }) => (*loc, Some(Size::CAR), true),
                Pending::Obstacle { loc, size, .. } => (*loc, Some(*size), false),
                Pending::Pedestrian { start, .. } => (*start, None, false),
            };
            let at = resolve(self, loc)?;
            placed.push(Placed {
                name: declared(&o.name, &o.at),
                footprint: match footprint {
                    Some(size) => Footprint::Vehicle {
                        pos_m: at.pos_m,
                        heading_rad: at.heading_rad,
                        size,
                    },
                    None => Footprint::Pedestrian { pos_m: at.pos_m },
                },
                on_road,
            });
        }
        check(&placed, &self.roads).map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?;
        for o in self.objects.clone() {
            match o.pending.clone() {
                Pending::Ego {
                    loc,
                    route,
                    initial_speed_mps,
                    sut,
                } => self.place_ego(&o, loc, route, initial_speed_mps, sut)?,
                Pending::Pedestrian {
                    start,
                    target,
                    speed,
                    trigger,
                } => self.place_pedestrian(&o, start, target, speed, trigger)?,
                Pending::Car(car) => self.place_car(&o, car)?,
                Pending::Obstacle { loc, size, color } => {
                    let at = resolve(self, loc)?;
                    self.obstacles.push(ObstacleSpec {
                        base_m: at.pos_m,
                        heading_rad: at.heading_rad,
                        size,
                        color,
                    });
                    self.obstacle_names.push(o.name.clone());
                }
            }
        }
        self.placed = true;
        Ok(())
    }

    /// Places the ego vehicle declared by `o`: its start, route, speed and system under test.
    fn place_ego(
        &mut self,
        o: &ObjectDecl,
        loc: usize,
        route: Option<Vec<Turn>>,
        initial_speed_mps: f64,
        sut: SutConfig,
    ) -> Result<(), LoadError> {
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(&b.roads);
        let start = resolve(self, loc)?;
        let route = match route {
            Some(turns) => self
                .roads
                .route(&start, &turns, self.route_m)
                .map_err(|e| {
                    LoadError::new(LoadErrorKind::Worlds, format!("{}: {}", o.name, strip(e)))
                })?,
            // Without a route the ego keeps its lane: the lane's path (straight on
            // through junctions where it can, round a roundabout's ring, into a
            // T's turn from its stem), or, where that path is the start line
            // itself (straight roads), the start line.
            None if self.roads.group_of(start.piece).iter().any(|&id| {
                let kind = &self.roads.piece(id).kind;
                kind.ref_line().is_some() || matches!(kind, PieceKind::Map { .. })
            }) =>
            {
                self.roads
                    .route(&start, &[], self.route_m)
                    .map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?
            }
            None => {
                let lane = self
                    .roads
                    .route(&start, &[], self.route_m)
                    .map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?;
                if on_start_line(&start, &lane) {
                    vec![]
                } else {
                    lane
                }
            }
        };
        if self.ego.is_some() {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!("{}: a scenario has one AutonomousVehicle", o.name),
            ));
        }
        self.ego = Some(EgoSpec {
            start,
            initial_speed_mps,
            vehicle: VehicleParams::default(),
            route,
        });
        self.sut = Some(sut);
        Ok(())
    }

    /// Places the pedestrian declared by `o` and its walking behaviour.
    fn place_pedestrian(
        &mut self,
        o: &ObjectDecl,
        start: usize,
        target: usize,
        speed: StreamId,
        trigger: PedTrigger,
    ) -> Result<(), LoadError> {
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(&b.roads);
        let pedestrian_name = o.runtime_name("Pedestrian");
        let s = resolve(self, start)?.pos_m;
        let t = resolve(self, target)?.pos_m;
        let Some(ActorRef::Pedestrian(handle)) = o.actor else {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!("{}: a Pedestrian without its handle", o.name),
            ));
        };
        match trigger {
            PedTrigger::Near { car, dist } => {
                self.graph.pedestrian(handle, s, t, car, dist);
            }
            PedTrigger::Stream(trigger) => {
                self.graph.pedestrian_with_trigger(handle, t, trigger);
            }
            PedTrigger::Never => {}
        }
        if !matches!(trigger, PedTrigger::Never) {
            // The behaviour's `foreach(walk)` is named by the Pedestrian's
            // declaration, for the check of two behaviours walking it.
            let walk = paracosm_engine::rx::StreamId(self.graph.nodes().len() - 1);
            self.graph.set_site(walk, o.at.clone());
        }
        self.pedestrians.push(PedestrianSpec {
            start: s,
            target: t,
            speed,
            name: pedestrian_name,
        });
        Ok(())
    }

    /// Places the NPC car declared by `o`: its path along its route and its lane change.
    fn place_car(&mut self, o: &ObjectDecl, car: PendingCar) -> Result<(), LoadError> {
        let PendingCar {
            loc,
            route,
            speed,
            color,
            enabled,
            lane_change,
            keep_distance_m,
        } = car;
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(&b.roads);
        let car_name = o.runtime_name("Car");
        let start = resolve(self, loc)?;
        let path = match self.roads.route(&start, &route, self.route_m) {
            Ok(path) => path,
            // A disabled car is not in the test: where it would drive does not
            // matter (it may stand on a sidewalk); one metre ahead stands in.
            Err(_) if !enabled => {
                let (p, h) = (start.pos_m, start.heading_rad);
                vec![[p[0], p[2]], [p[0] + h.cos(), p[2] - h.sin()]]
            }
            Err(e) => {
                return Err(LoadError::new(
                    LoadErrorKind::Worlds,
                    format!("{}: {}", o.name, strip(e)),
                ))
            }
        };
        let lane_change = match lane_change {
            Some(c) => {
                // Into a lane of the other direction: allowed (an overtaking
                // manoeuvre), but the car keeps its own direction there.
                if let paracosm_engine::Lane::Driving(k) = start.lane {
                    if k.signum() != c.to.signum() {
                        self.warnings.push(Warning {
                            at: o.at.clone(),
                            message: format!(
                                "{}: ChangeLane(to = {}) moves it from lane {k} into \
                                     a lane of the other direction, where it goes on \
                                     driving its own way (against the traffic there)",
                                o.name, c.to
                            ),
                        });
                    }
                }
                match self.lane_change(&o.name, &start, c) {
                    Ok(change) => Some(change),
                    Err(_) if !enabled => None,
                    Err(e) => return Err(e),
                }
            }
            None => None,
        };
        let lane_offsets_m = self.lane_offsets(&start);
        self.cars.push(CarSpec {
            path,
            speed,
            color,
            size: Size::CAR,
            enabled,
            lane_change,
            lane_offsets_m,
            name: car_name,
            keep_distance_m,
        });
        self.car_names.push(o.name.clone());
        Ok(())
    }
}

/// Whether every point of `path` (world `[x, z]`, m) lies on the line ahead of `start` along
/// its heading, to 1 cm: the ego following the start line drives that path.
fn on_start_line(start: &Location, path: &[[f64; 2]]) -> bool {
    let d = paracosm_engine::network::direction(start.heading_rad);
    path.iter().all(|q| {
        let r = [q[0] - start.pos_m[0], q[1] - start.pos_m[2]];
        (r[0] * d[1] - r[1] * d[0]).abs() <= 0.01 && r[0] * d[0] + r[1] * d[1] >= -0.01
    })
}

impl SceneBuilder {
    /// Each driving lane of the segment `start` is on, with its sideways offset from
    /// `start`'s lane (m, positive to the right of the direction of travel); empty inside a
    /// junction.
    pub fn lane_offsets(&self, start: &Location) -> Vec<(i32, f64)> {
        if start.through.is_some() || start.map_lane.is_some() {
            return Vec::new();
        }
        let h = start.heading_rad;
        let right = [h.sin(), h.cos()];
        let half = (self.roads.piece(start.piece).kind.lanes() / 2) as i32;
        (-half..=half)
            .filter(|&l| l != 0)
            .filter_map(|l| {
                let at = self
                    .roads
                    .on_lane(start.piece, paracosm_engine::Lane::Driving(l), start.at_m)
                    .ok()?;
                let d = [at.pos_m[0] - start.pos_m[0], at.pos_m[2] - start.pos_m[2]];
                Some((l, d[0] * right[0] + d[1] * right[1]))
            })
            .collect()
    }

    /// The engine's lane change of car `name` starting at `start`: the sideways offset to lane
    /// `c.to` of the same segment, measured to the right of the car's direction.
    ///
    /// # Errors
    /// A message when the car does not start on a segment's driving lane or the target lane
    /// does not exist there.
    fn lane_change(
        &self,
        name: &str,
        start: &Location,
        c: super::values::LaneChangeVal,
    ) -> Result<paracosm_engine::LaneChangeSpec, LoadError> {
        if start.through.is_some() {
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                    "{name}: a lane change starts on a RoadSegment's lane, not inside a junction"
                ),
            ));
        }
        if start.map_lane.is_some() {
            return Err(LoadError::new(LoadErrorKind::Declarations, format!(
                "{name}: ChangeLane is not available on an OpenDRIVE map (start the car in the lane it should drive, or give it a route)"
            )));
        }
        let target = self
            .roads
            .on_lane(
                start.piece,
                paracosm_engine::Lane::Driving(c.to),
                start.at_m,
            )
            .map_err(|e| {
                LoadError::new(
                    LoadErrorKind::Declarations,
                    format!("{name}: ChangeLane(to = {}): {}", c.to, strip(e)),
                )
            })?;
        let h = start.heading_rad;
        let right = [h.sin(), h.cos()];
        let d = [
            target.pos_m[0] - start.pos_m[0],
            target.pos_m[2] - start.pos_m[2],
        ];
        let offset_m = d[0] * right[0] + d[1] * right[1];
        if offset_m.abs() < 1e-6 {
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!("{name}: ChangeLane(to = {}) is the lane it starts on", c.to),
            ));
        }
        Ok(paracosm_engine::LaneChangeSpec {
            offset_m,
            start: match c.start {
                super::values::ChangeStart::At(t) => paracosm_engine::LaneChangeStart::At(t),
                super::values::ChangeStart::When(s) => {
                    paracosm_engine::LaneChangeStart::When(StreamId(s))
                }
            },
            duration_s: c.duration_s,
        })
    }
}

/// An engine error's message, without the `invalid world: ` that an
/// [`paracosm_engine::EngineError::InvalidWorld`] adds (the program's message says where).
pub fn strip(e: paracosm_engine::EngineError) -> String {
    match e {
        paracosm_engine::EngineError::InvalidWorld(reason) => reason,
        other => other.to_string(),
    }
}
