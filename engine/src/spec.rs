use serde::Serialize;

use crate::actor::Roster;
use crate::behaviour::{ActorRef, GraphBuilder, Output, Probe};
use crate::network::{Lane, Location, Network, PieceId};
use crate::rx::{Graph, Node, StreamId, Value};
use crate::{EngineError, SensorSpec, VehicleParams};

/// The default physics step: 1/60 s (rapier's own default).
pub const DEFAULT_DT_S: f64 = 1.0 / 60.0;

/// The ego vehicle (paper §2, `AutonomousVehicle`): where it starts and how it is built.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EgoSpec {
    /// Start: a driving lane of a segment (`onLane`).
    pub start: Location,
    /// Initial forward speed in m/s, `>= 0`.
    pub initial_speed_mps: f64,
    /// Mass, dimensions and actuator limits.
    pub vehicle: VehicleParams,
    /// The route the system under test is asked to follow, world `[x, z]` in metres (a
    /// navigation plan from the lane graph); empty: keep the start lane.
    pub route: Vec<[f64; 2]>,
    /// The speed the scenario asks the system under test to keep, m/s (an OpenSCENARIO
    /// ego's initial speed: ALKS's set speed); `None`: the system's own cruise speed.
    pub set_speed_mps: Option<f64>,
    /// Whether a script places the ego at every step ([`crate::behaviour::Action::PlaceEgo`],
    /// an OpenSCENARIO storyboard's trajectory) instead of the system under test driving it:
    /// its chassis is then a kinematic body, its velocity the move it makes over each step,
    /// and every contact with another actor is recorded as when it drives.
    pub scripted: bool,
}

/// A pedestrian (paper §2, `Pedestrian`): a kinematic capsule that walks in a straight line
/// from `start` to `target` on each event of its `walk` sink (see [`crate::behaviour`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PedestrianSpec {
    /// Start, feet position `[x, y, z]` in metres.
    pub start: [f64; 3],
    /// Target, feet position `[x, y, z]` in metres.
    pub target: [f64; 3],
    /// Walking speed stream, m/s; read at each walking step, values `<= 0` stand still.
    pub speed: StreamId,
    /// Its speed at t = 0, m/s (`>= 0`), the way it faces (from `start` toward `target`):
    /// what it reports before its first step. 0 for a pedestrian that waits to walk (the
    /// language's); a scripted pedestrian (an OpenSCENARIO storyboard's) enters the test at
    /// its `Init` speed.
    pub initial_speed_mps: f64,
    /// How run-time messages name it, e.g. `Pedestrian p (f.star:9:5)`; empty: `pedestrian
    /// N`, by its index.
    pub name: String,
}

/// An NPC car (paper §2, `Car`): a kinematic box that drives along `path` at the speed its
/// stream gives, and stops at the path's end.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CarSpec {
    /// The route, world `[x, z]` in metres, at least two points: from the lane graph.
    pub path: Vec<[f64; 2]>,
    /// Speed stream, m/s; negative values count as 0.
    pub speed: StreamId,
    /// Colour name (for the camera renderer), e.g. `red` ([`crate::colour::COLOURS`]).
    pub color: String,
    /// Its body.
    pub size: crate::Size,
    /// Whether the car is in this test (a scenario may make its presence a parameter).
    pub enabled: bool,
    /// A lane change it makes, if any (a cut-in).
    pub lane_change: Option<crate::LaneChangeSpec>,
    /// The lanes a `changeLane` action may take it to: each driving lane of the segment it
    /// starts on and that lane's sideways offset from its start lane, m, positive to the
    /// right of its direction. Empty when it starts inside a junction.
    pub lane_offsets_m: Vec<(i32, f64)>,
    /// How run-time messages name it, e.g. `Car lead (f.star:4:5)`; empty: `car N`, by its
    /// index.
    pub name: String,
    /// The gap it keeps to whatever is ahead on its path (an obstacle, a car, a pedestrian,
    /// the ego), m, finite and `>= 0`: it brakes, at most `μ·g`, to stop that far short of
    /// it. `None`: it brakes for nothing, and stops only against what it meets.
    pub keep_distance_m: Option<f64>,
    /// Its tow, when it is a trailer: the car (an index into [`WorldSpec::cars`], not its
    /// own) whose hitch it is coupled to. The two touch at the hitch, so their contact is no
    /// collision: neither records it, neither stops for the other, and neither's separation
    /// counts the other. `None` for a car that no car tows.
    pub tow: Option<usize>,
}

/// A static obstacle (`Obstacle(loc=, size=, color=)`): a box that never moves.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObstacleSpec {
    /// Centre of its base `[x, y, z]`, metres.
    pub base_m: [f64; 3],
    /// Heading in rad.
    pub heading_rad: f64,
    /// Its size.
    pub size: crate::Size,
    /// Colour name ([`crate::colour::COLOURS`]).
    pub color: String,
}

/// Global conditions (paper §2, `World(light, fog)`), as streams.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EnvironmentSpec {
    /// Light intensity, `[0, 1]`, nominal 1: the camera's exposure (the lidar ignores it).
    pub light: StreamId,
    /// Fog density in `[0, 1]`: see [`crate::visibility_m`].
    pub fog: StreamId,
}

/// Everything needed to build a [`crate::Simulation`]: the road network, the actors, the
/// stream graph (with every open parameter bound) that drives their behaviour, and sensors.
#[derive(Debug, Clone)]
pub struct WorldSpec {
    /// Physics step in seconds, `> 0`. Default [`DEFAULT_DT_S`].
    pub dt_s: f64,
    /// The roads, with the friction each piece has at the start.
    pub network: Network,
    /// Pieces whose friction varies over the test: each piece and its friction stream (in
    /// `(0, 2]`), read every step; the other pieces keep their friction.
    pub frictions: Vec<(PieceId, StreamId)>,
    /// The ego vehicle.
    pub ego: EgoSpec,
    /// Pedestrians, in the order of their handles ([`crate::actor::Roster`]): the `i`-th is
    /// the one the `i`-th handle names in probes and actions ([`crate::behaviour::ActorRef`]).
    pub pedestrians: Vec<PedestrianSpec>,
    /// NPC cars, in order.
    pub cars: Vec<CarSpec>,
    /// Static obstacles, in order.
    pub obstacles: Vec<ObstacleSpec>,
    /// Light and fog.
    pub environment: EnvironmentSpec,
    /// The reactive graph, bound (no open parameter slot left).
    pub streams: Graph,
    /// Streams published by name for monitors and `Stl` formulas (`Monitor`, `Signal`, an
    /// actor's `lead.speed`): [`crate::Simulation::current`] reads each one's latest value.
    pub published: Vec<(String, StreamId)>,
    /// The sensors on the ego vehicle, with their settings, in the order they are mounted
    /// (and their readings listed in [`crate::Observation::readings`]); usually
    /// [`SensorSpec::defaults`], the lidar.
    pub sensors: Vec<SensorSpec>,
}

/// A pedestrian of [`WorldSpec::straight_road`]: the paper's crossing pedestrian with constant
/// trigger distance and speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriggeredPedestrian {
    /// Start lane (usually [`Lane::SideWalk`]) and position along the road in metres.
    pub start: (Lane, f64),
    /// Target lane (usually [`Lane::OppositeSideWalk`]) and position along the road in metres.
    pub target: (Lane, f64),
    /// Trigger distance in metres, `> 0`: the pedestrian starts when the planar distance between
    /// the ego vehicle's centre and `start` drops below it.
    pub trigger_distance_m: f64,
    /// Walking speed in m/s, `> 0`.
    pub speed_mps: f64,
}

impl WorldSpec {
    /// The paper's first example (§2, "A Simple World") built in Rust: one straight road of
    /// `length_m` metres with 2 lanes and friction 0.8, the ego vehicle on lane 1 at `ego_at_m`
    /// metres moving at `initial_speed_mps`, and pedestrians with the paper's behaviour, under
    /// clear daylight (light 1, fog 0) and the default lidar.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a position off the road or a non-positive speed or
    /// trigger distance.
    pub fn straight_road(
        length_m: f64,
        ego_at_m: f64,
        initial_speed_mps: f64,
        pedestrians: &[TriggeredPedestrian],
    ) -> Result<WorldSpec, EngineError> {
        let network = Network::single_segment(length_m, 2, 0.8)?;
        let road = PieceId(0);
        let start = network.on_lane(road, Lane::Driving(1), ego_at_m)?;
        let mut g = GraphBuilder::new();
        let ego_pos = g.push(Node::Probe(Probe::new(ActorRef::Ego, Output::Pos)));
        let light = g.push(Node::Const(Value::Num(1.0)));
        let fog = g.push(Node::Const(Value::Num(0.0)));
        let mut peds = Vec::with_capacity(pedestrians.len());
        let mut roster = Roster::default();
        for (i, p) in pedestrians.iter().enumerate() {
            let ok = |v: f64| v.is_finite() && v > 0.0;
            if !ok(p.speed_mps) || !ok(p.trigger_distance_m) {
                return Err(EngineError::InvalidWorld(format!(
                    "pedestrian {i}: speed {} m/s and trigger distance {} m must be positive",
                    p.speed_mps, p.trigger_distance_m
                )));
            }
            let s = network.on_lane(road, p.start.0, p.start.1)?.pos_m;
            let t = network.on_lane(road, p.target.0, p.target.1)?.pos_m;
            let dist = g.push(Node::Const(Value::Num(p.trigger_distance_m)));
            let speed = g.push(Node::Const(Value::Num(p.speed_mps)));
            g.pedestrian(roster.add(), s, t, ego_pos, dist);
            peds.push(PedestrianSpec {
                start: s,
                target: t,
                speed,
                initial_speed_mps: 0.0,
                name: String::new(),
            });
        }
        Ok(WorldSpec {
            dt_s: DEFAULT_DT_S,
            network,
            frictions: vec![],
            ego: EgoSpec {
                start,
                initial_speed_mps,
                vehicle: VehicleParams::default(),
                route: vec![],
                set_speed_mps: None,
                scripted: false,
            },
            pedestrians: peds,
            cars: vec![],
            obstacles: vec![],
            environment: EnvironmentSpec { light, fog },
            streams: g.finish()?,
            published: vec![],
            sensors: SensorSpec::defaults(),
        })
    }
}
