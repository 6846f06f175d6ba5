//! What a scenario program builds while it runs: plain Rust data (no Starlark values), turned
//! into a [`Scenario`] once the program has finished.

use std::sync::Arc;

use paracosm_engine::behaviour::{probe, Actor, GraphBuilder, Output};
use paracosm_engine::network::{Location, Network, PieceId, Turn};
use paracosm_engine::rx::{Graph, Node, OpenStream, StreamId, Value};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{
    CarSpec, EgoSpec, EnvironmentSpec, LidarSpec, PedestrianSpec, VehicleParams, WorldSpec,
    DEFAULT_DT_S,
};
use paracosm_generators::{Assignment, Domain, Param, ParamSpace};

use crate::{Lambdas, MonitorSpec, Scenario, ScenarioError};

/// How an open stream varies over a test (paper §3.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OverTime {
    /// One value for the whole test.
    Constant,
    /// `Piecewise(k)`: `k` values, each held for `T / k`.
    Piecewise(usize),
    /// `Polynomial(deg)`: a Bernstein polynomial with `deg + 1` coefficients.
    Polynomial(usize),
}

/// The `tick` stream: the first node of every program's graph.
pub const TICK: StreamId = StreamId(0);

/// A `VarInterval` or `VarEnum` as declared.
#[derive(Debug, Clone)]
pub struct ParamDecl {
    /// `name=`, or the global variable it was assigned to; `None` gives `param<i>`.
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

/// A scalar input of an object that is fixed for a test: a constant, or an open parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Fixed {
    /// A value known when the program loads.
    Const(Value),
    /// Open parameter number `n` (constant over time).
    Param(usize),
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
}

/// An `onLane(lane, at)` not yet resolved (pieces may still move).
#[derive(Debug, Clone, Copy)]
pub struct LaneRef {
    /// The segment.
    pub piece: PieceId,
    /// The lane.
    pub lane: paracosm_engine::Lane,
    /// Distance from the segment's port ONE, m.
    pub at_m: f64,
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
    Car {
        /// Start location.
        loc: usize,
        /// Turns.
        route: Vec<Turn>,
        /// Speed stream.
        speed: StreamId,
        /// Colour.
        color: Fixed,
        /// Presence.
        enabled: Fixed,
    },
}

/// A declared actor: what it is, where it was declared, and whether `place` saw it.
#[derive(Debug, Clone)]
pub struct ObjectDecl {
    /// E.g. `Car declared at follow.star:12:7`.
    pub name: String,
    /// The declaration.
    pub pending: Pending,
    /// Whether `place` included it.
    pub placed: bool,
}

/// A pedestrian as resolved.
#[derive(Debug, Clone)]
pub struct PedestrianDecl {
    /// Feet start and target, metres.
    pub start: [f64; 3],
    /// Target, metres.
    pub target: [f64; 3],
    /// Speed stream.
    pub speed: StreamId,
}

/// A car as declared.
#[derive(Debug, Clone)]
pub struct CarDecl {
    /// Its route, world `[x, z]` metres.
    pub path: Vec<[f64; 2]>,
    /// Speed stream, m/s.
    pub speed: StreamId,
    /// Colour.
    pub color: Fixed,
    /// Presence.
    pub enabled: Fixed,
}

/// The ego vehicle as declared.
#[derive(Debug, Clone)]
pub struct EgoDecl {
    /// Start.
    pub start: Location,
    /// Route, empty to keep its lane.
    pub route: Vec<[f64; 2]>,
    /// Initial speed, m/s.
    pub initial_speed_mps: f64,
    /// System under test.
    pub sut: SutConfig,
}

/// Everything a program declares.
#[derive(Debug, Default)]
pub struct SceneBuilder {
    /// The stream graph.
    pub graph: GraphBuilder,
    /// Open parameters, in declaration order.
    pub params: Vec<ParamDecl>,
    /// The road pieces.
    pub roads: Network,
    /// Frictions of pieces, per piece.
    pub frictions: Vec<(PieceId, Fixed)>,
    /// The ego vehicle, once declared.
    pub ego: Option<EgoDecl>,
    /// Pedestrians.
    pub pedestrians: Vec<PedestrianDecl>,
    /// Cars.
    pub cars: Vec<CarDecl>,
    /// `World(light=, fog=)`.
    pub world: Option<(StreamId, StreamId)>,
    /// Whether `place` ran.
    pub placed: bool,
    /// Monitors.
    pub monitors: Vec<MonitorSpec>,
    /// `test(horizon=)`, seconds.
    pub horizon_s: Option<f64>,
    /// `test(map=)`: one or two parameter names.
    pub map_axes: Option<Vec<String>>,
    /// `test(offroad=)`: whether the default `OffRoadMonitor` is added (default true).
    pub offroad: Option<bool>,
    /// Where `place(...)` was called, `file:line:col`.
    pub placed_at: Option<String>,
    /// Warnings so far.
    pub warnings: Vec<crate::scenario::Warning>,
    /// The cars' names for messages, in the order of [`SceneBuilder::cars`].
    pub car_names: Vec<String>,
    /// Number of lambdas stored so far.
    pub lambdas: u32,
    /// `onLane` results, by index.
    pub locs: Vec<LaneRef>,
    /// Declared actors, in declaration order.
    pub objects: Vec<ObjectDecl>,
    /// Pedestrians declared so far (their index in the world).
    pub n_pedestrians: u32,
    /// Cars declared so far.
    pub n_cars: u32,
}

impl SceneBuilder {
    /// A builder with the `tick` stream as stream [`TICK`].
    pub fn new() -> Self {
        let mut b = SceneBuilder::default();
        let tick = b.graph.push(Node::Tick);
        debug_assert_eq!(tick, TICK);
        b
    }

    /// A new open parameter and its stream.
    pub fn param(&mut self, decl: ParamDecl) -> StreamId {
        self.params.push(decl);
        self.graph.push(Node::Param(self.params.len() - 1))
    }

    /// A probe stream.
    pub fn probe(&mut self, actor: Actor, output: Output) -> StreamId {
        self.graph.push(Node::Probe(probe(actor, output)))
    }

    /// Records a warning about what the program declared at `at` (`file:line:col`).
    pub fn warn(&mut self, at: &str, message: String) {
        self.warnings.push(crate::scenario::Warning {
            at: at.to_owned(),
            message,
        });
    }

    /// The stream's node, if it is an open parameter's, its parameter number.
    pub fn param_of(&self, s: StreamId) -> Option<usize> {
        match self.graph.nodes().get(s.0) {
            Some(Node::Param(p)) => Some(*p),
            _ => None,
        }
    }
}

/// The names of the coordinates a parameter adds to the space.
fn coordinate_names(name: &str, over_time: OverTime) -> Vec<String> {
    match over_time {
        OverTime::Constant => vec![name.to_owned()],
        OverTime::Piecewise(k) => (0..k).map(|i| format!("{name}[{i}]")).collect(),
        OverTime::Polynomial(d) => (0..=d).map(|i| format!("{name}.c{i}")).collect(),
    }
}

/// A loaded program, frozen: everything needed to instantiate worlds, shared by workers.
pub struct Frozen {
    params: Vec<(String, ParamDecl)>,
    graph: Graph,
    roads: Network,
    frictions: Vec<(PieceId, Fixed)>,
    ego: EgoDecl,
    pedestrians: Vec<PedestrianDecl>,
    cars: Vec<CarDecl>,
    world: (StreamId, StreamId),
    horizon_s: f64,
}

/// Settings of [`finish`] that come from outside the program.
pub struct Meta {
    /// Scenario name.
    pub name: String,
    /// Description.
    pub description: String,
}

/// Turns a finished program's declarations into a [`Scenario`].
///
/// # Errors
/// A message (the caller makes it a [`ScenarioError::Language`]) when something required is
/// missing (no `place`, no ego vehicle, an actor never placed) or the parameters clash.
pub fn finish(
    b: SceneBuilder,
    meta: Meta,
    lambdas: Option<Arc<dyn Lambdas>>,
) -> Result<Scenario, String> {
    if !b.placed {
        return Err("the program never calls place(...): nothing to test".into());
    }
    if let Some(o) = b.objects.iter().find(|o| !o.placed) {
        return Err(format!("{} is never placed: pass it to place(...)", o.name));
    }
    let ego = b
        .ego
        .clone()
        .ok_or("the program places no AutonomousVehicle: nothing to test")?;
    let horizon_s = b.horizon_s.unwrap_or(super::DEFAULT_HORIZON_S);
    let world = match b.world {
        Some(w) => w,
        None => return Err("the program has no World(...)".into()),
    };
    let mut params: Vec<(String, ParamDecl)> = Vec::new();
    let mut space = Vec::new();
    for (i, p) in b.params.iter().enumerate() {
        let name = p.name.clone().unwrap_or_else(|| format!("param{i}"));
        if let Some((_, first)) = params.iter().find(|(n, _)| *n == name) {
            return Err(format!(
                "two open parameters are named `{name}` (declared at {} and {}); give one another name=",
                first.at, p.at
            ));
        }
        for coordinate in coordinate_names(&name, p.over_time) {
            space.push(Param {
                name: coordinate,
                domain: p.domain.clone(),
                unit: p.unit.clone(),
            });
        }
        params.push((name, p.clone()));
    }
    let space = ParamSpace::new(space).map_err(|e| e.to_string())?;
    let map_axes =
        match &b.map_axes {
            Some(axes) => {
                for a in axes {
                    if space.param(a).is_none() {
                        let known: Vec<&str> =
                            space.params().iter().map(|p| p.name.as_str()).collect();
                        return Err(format!(
                        "test(map=...) names `{a}`, which is not a parameter (the parameters: {})",
                        if known.is_empty() { "none".to_owned() } else { known.join(", ") }
                    ));
                    }
                }
                axes.clone()
            }
            None => space
                .params()
                .iter()
                .take(2)
                .map(|p| p.name.clone())
                .collect(),
        };

    // Monitors: the default OffRoadMonitor unless the program has one or opts out.
    let mut monitors = b.monitors.clone();
    let declared = monitors.len();
    let has_off_road = monitors.iter().any(MonitorSpec::judges_off_road);
    if b.offroad.unwrap_or(true) && !has_off_road {
        let implicit = MonitorSpec::implicit_off_road();
        if monitors.iter().any(|m| m.name() == implicit.name()) {
            return Err(format!(
                "a monitor is named `{}`, the name of the default OffRoadMonitor: rename it, \
                 declare OffRoadMonitor(v) yourself, or opt out with test(offroad = False)",
                implicit.name()
            ));
        }
        monitors.push(implicit);
    }
    let mut warnings = b.warnings.clone();
    let place_at = b.placed_at.clone().unwrap_or_default();
    if declared == 0 {
        warnings.push(crate::scenario::Warning {
            at: place_at.clone(),
            message: if monitors.is_empty() {
                "the program declares no monitor and opts out of the default OffRoadMonitor: \
                 every test passes whatever happens"
                    .to_owned()
            } else {
                "the program declares no monitor: only the default OffRoadMonitor judges its \
                 tests, so a test passes whatever else happens (add CollisionMonitor(v), \
                 DistanceMonitor(v, minD = ...) or Stl(...))"
                    .to_owned()
            },
        });
    }
    let stl_reads_light = monitors
        .iter()
        .any(|m| m.reads_signal(crate::signal::LIGHT));
    let names: Vec<String> = params.iter().map(|(n, _)| n.clone()).collect();
    let usage = super::usage::analyse(&b, &names, stl_reads_light);
    warnings.extend(usage.warnings);
    let unused_params: Vec<String> = usage
        .unused
        .iter()
        .flat_map(|&p| coordinate_names(&names[p], params[p].1.over_time))
        .collect();
    let graph = b.graph.finish().map_err(|e| e.to_string())?;
    let sut = ego.sut.clone();
    let frozen = Arc::new(Frozen {
        params,
        graph,
        roads: b.roads,
        frictions: b.frictions,
        ego,
        pedestrians: b.pedestrians,
        cars: b.cars,
        world,
        horizon_s,
    });
    Ok(Scenario {
        name: meta.name,
        description: meta.description,
        space,
        horizon_s,
        sut,
        monitors,
        map_axes,
        warnings,
        unused_params,
        camera_only: usage.camera_only,
        template: Arc::new(move |a: &Assignment| frozen.instantiate(a)),
        lambdas,
        source: Arc::from(""),
    })
}

fn to_rx(v: &paracosm_generators::Value) -> Value {
    super::types::level_value(v)
}

impl Frozen {
    fn open(&self, a: &Assignment) -> Result<Vec<OpenStream>, ScenarioError> {
        self.params
            .iter()
            .map(|(name, p)| {
                let get = |n: &str| {
                    a.get(n)
                        .ok_or_else(|| ScenarioError::MissingParam(n.to_owned()))
                };
                let reals = |names: Vec<String>| -> Result<Vec<f64>, ScenarioError> {
                    names
                        .iter()
                        .map(|n| {
                            get(n)?
                                .as_f64()
                                .ok_or(ScenarioError::MissingParam(n.clone()))
                        })
                        .collect()
                };
                Ok(match p.over_time {
                    OverTime::Constant => OpenStream::Constant(to_rx(get(name)?)),
                    OverTime::Piecewise(_) => OpenStream::Piecewise {
                        values: reals(coordinate_names(name, p.over_time))?,
                        horizon_s: self.horizon_s,
                    },
                    OverTime::Polynomial(_) => OpenStream::Polynomial {
                        coefficients: reals(coordinate_names(name, p.over_time))?,
                        horizon_s: self.horizon_s,
                    },
                })
            })
            .collect()
    }

    fn fixed(&self, f: &Fixed, open: &[OpenStream]) -> Value {
        match f {
            Fixed::Const(v) => v.clone(),
            Fixed::Param(p) => open[*p].at(0.0),
        }
    }

    fn instantiate(&self, a: &Assignment) -> Result<WorldSpec, ScenarioError> {
        let open = self.open(a)?;
        let streams = self
            .graph
            .bind(&open)
            .map_err(paracosm_engine::EngineError::from)?;
        let mut network = self.roads.clone();
        for (piece, f) in &self.frictions {
            let mu = self.fixed(f, &open).as_num().unwrap_or(f64::NAN);
            network.set_friction(*piece, mu)?;
        }
        let cars = self
            .cars
            .iter()
            .map(|c| CarSpec {
                path: c.path.clone(),
                speed: c.speed,
                color: match self.fixed(&c.color, &open) {
                    Value::Text(t) => t,
                    v => format!("{v:?}"),
                },
                size_m: CAR_SIZE_M,
                enabled: self.fixed(&c.enabled, &open).as_bool().unwrap_or(true),
            })
            .collect();
        Ok(WorldSpec {
            dt_s: DEFAULT_DT_S,
            network,
            ego: EgoSpec {
                start: self.ego.start,
                initial_speed_mps: self.ego.initial_speed_mps,
                vehicle: VehicleParams::default(),
                route: self.ego.route.clone(),
            },
            pedestrians: self
                .pedestrians
                .iter()
                .map(|p| PedestrianSpec {
                    start: p.start,
                    target: p.target,
                    speed: p.speed,
                })
                .collect(),
            cars,
            environment: EnvironmentSpec {
                light: self.world.0,
                fog: self.world.1,
            },
            streams,
            lidar: LidarSpec::default(),
        })
    }
}

/// Parses a route list of turns.
pub fn turns(names: &[String]) -> Result<Vec<Turn>, String> {
    names
        .iter()
        .map(|n| {
            Turn::parse(n).ok_or_else(|| {
                format!("route entry `{n}` is not a turn; use \"straight\", \"left\" or \"right\"")
            })
        })
        .collect()
}

/// Longest route computed for an actor, in metres.
const MAX_ROUTE_M: f64 = 5000.0;
/// Body size of the ego vehicle and NPC cars for the placement check, metres.
const EGO_SIZE_M: [f64; 3] = [4.5, 1.8, 1.0];
const CAR_SIZE_M: [f64; 3] = [4.5, 1.8, 1.5];

impl SceneBuilder {
    /// `w.place(...)`: marks `objects` placed, resolves every actor's location and route on
    /// the final road network, builds the pedestrians' behaviour, and runs the checks: no
    /// overlapping road pieces, no objects starting in collision, vehicles on the road.
    ///
    /// # Errors
    /// A message naming the offending pieces or objects.
    pub fn place(&mut self, objects: &[usize]) -> Result<(), String> {
        use paracosm_engine::placement::{check, Footprint, Placed};
        if self.placed {
            return Err("place(...) may be called only once".into());
        }
        self.roads.check_all_overlaps().map_err(strip)?;
        for &o in objects {
            self.objects[o].placed = true;
        }
        let resolve = |b: &SceneBuilder, i: usize| {
            let l = b.locs[i];
            b.roads.on_lane(l.piece, l.lane, l.at_m).map_err(strip)
        };
        // Check the starting positions before anything depends on them (routes, behaviours).
        let mut placed = Vec::new();
        for o in &self.objects {
            let (loc, footprint) = match &o.pending {
                Pending::Ego { loc, .. } => (*loc, Some(EGO_SIZE_M)),
                Pending::Car { loc, .. } => (*loc, Some(CAR_SIZE_M)),
                Pending::Pedestrian { start, .. } => (*start, None),
            };
            let at = resolve(self, loc)?;
            placed.push(Placed {
                name: o.name.clone(),
                footprint: match footprint {
                    Some(size_m) => Footprint::Vehicle {
                        pos_m: at.pos_m,
                        heading_rad: at.heading_rad,
                        size_m,
                    },
                    None => Footprint::Pedestrian { pos_m: at.pos_m },
                },
                on_road: footprint.is_some(),
            });
        }
        check(&placed, &self.roads).map_err(strip)?;
        let mut pedestrians = Vec::new();
        let mut cars = Vec::new();
        let mut ped_index = 0u32;
        for o in self.objects.clone() {
            match o.pending {
                Pending::Ego {
                    loc,
                    route,
                    initial_speed_mps,
                    sut,
                } => {
                    let start = resolve(self, loc)?;
                    let route = match route {
                        Some(turns) => self
                            .roads
                            .route(&start, &turns, MAX_ROUTE_M)
                            .map_err(strip)?,
                        None => vec![],
                    };
                    if self.ego.is_some() {
                        return Err(format!("{}: a scenario has one AutonomousVehicle", o.name));
                    }
                    self.ego = Some(EgoDecl {
                        start,
                        route,
                        initial_speed_mps,
                        sut,
                    });
                }
                Pending::Pedestrian {
                    start,
                    target,
                    speed,
                    trigger,
                } => {
                    let s = resolve(self, start)?.pos_m;
                    let t = resolve(self, target)?.pos_m;
                    match trigger {
                        PedTrigger::Near { car, dist } => {
                            self.graph.pedestrian(ped_index, s, t, car, dist);
                        }
                        PedTrigger::Stream(trigger) => {
                            self.graph.pedestrian_with_trigger(ped_index, t, trigger);
                        }
                    }
                    ped_index += 1;
                    pedestrians.push(PedestrianDecl {
                        start: s,
                        target: t,
                        speed,
                    });
                }
                Pending::Car {
                    loc,
                    route,
                    speed,
                    color,
                    enabled,
                } => {
                    let start = resolve(self, loc)?;
                    let path = self
                        .roads
                        .route(&start, &route, MAX_ROUTE_M)
                        .map_err(strip)?;
                    cars.push(CarDecl {
                        path,
                        speed,
                        color,
                        enabled,
                    });
                    self.car_names.push(o.name.clone());
                }
            }
        }
        self.pedestrians = pedestrians;
        self.cars = cars;
        self.placed = true;
        Ok(())
    }
}

/// An engine error's message without the `invalid world: ` prefix.
pub fn strip(e: paracosm_engine::EngineError) -> String {
    let s = e.to_string();
    s.strip_prefix("invalid world: ").unwrap_or(&s).to_owned()
}
