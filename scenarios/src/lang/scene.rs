//! What one evaluation of a scenario program builds: plain Rust data (no Starlark values),
//! turned into the test's [`WorldSpec`] once the program has finished. A program is evaluated
//! once per test, with that test's values of its open parameters (LANGUAGE.md, "A family of
//! worlds"), and a few times when it loads, to learn its parameters and check its worlds.

use super::load_error::{LoadError, LoadErrorKind};
use paracosm_engine::behaviour::{ActorRef, Output};
use paracosm_engine::network::{Location, Network, PieceId, PieceKind, Turn};
use paracosm_engine::rx::{Node, StreamId};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{CarSpec, EgoSpec, ObstacleSpec, PedestrianSpec, Size, VehicleParams};
use paracosm_generators::Value as Level;

use crate::scenario::Warning;

pub use crate::scene::{
    coordinate_names, level_value, representative, ParamDecl, ParamValue, TICK,
};
use crate::scene::{Scene, Site};

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

/// Everything one evaluation of a program declares: the typed [`Scene`] it builds, and what
/// only the language needs on the way (actors not yet placed, `onLane` locations that move
/// with `connect`, the lambdas stored, what the program printed).
#[derive(Debug)]
pub struct SceneBuilder {
    /// The scene this evaluation builds.
    pub scene: Scene,
    /// How far routes are planned, m ([`route_length_m`] of the horizon).
    pub route_m: f64,
    /// Whether `place` ran.
    pub placed: bool,
    /// Where `place(...)` was called, `file:line:col`.
    pub placed_at: Option<String>,
    /// Warnings so far.
    pub warnings: Vec<Warning>,
    /// Number of lambdas stored so far.
    pub lambdas: u32,
    /// What the program printed while this evaluation ran (the start of a test's log).
    pub log: Vec<String>,
    /// `onLane` results, by index.
    pub locs: Vec<LaneRef>,
    /// Where each of `locs` stands on the network as it is now, shared with the `Location`
    /// values of the program.
    pub loc_table: super::position::LocTable,
    /// Declared objects, in declaration order, until `place` places them.
    pub objects: Vec<ObjectDecl>,
    /// The storyboard of the scenario `Import(...)` built into this world, which a test
    /// runs beside the program's lambdas (its host functions from
    /// [`crate::xosc::IMPORT_HOST_BASE`]).
    pub(crate) story: Option<ImportedStory>,
    /// The `Require`s evaluated so far: name and where each stands.
    pub requires: Vec<(String, Site)>,
    /// The `Require` these values break (its message), which stopped the evaluation.
    pub broken: Option<String>,
}

/// The host that runs an imported OpenSCENARIO storyboard ([`SceneBuilder::story`]).
pub(crate) struct ImportedStory(pub(crate) crate::xosc::StoryHost);

impl std::fmt::Debug for ImportedStory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ImportedStory")
    }
}

impl SceneBuilder {
    /// A builder of a scene for an evaluation that gives the parameters `values` (by name;
    /// `None`: representative values).
    pub fn new(values: Option<crate::scene::GivenValues>) -> Self {
        SceneBuilder {
            scene: Scene::new(values),
            route_m: MAX_ROUTE_M,
            placed: false,
            placed_at: None,
            warnings: Vec::new(),
            lambdas: 0,
            log: Vec::new(),
            locs: Vec::new(),
            loc_table: Default::default(),
            objects: Vec::new(),
            story: None,
            requires: Vec::new(),
            broken: None,
        }
    }

    /// Declares an open parameter; returns what the program sees: its value, or for one
    /// that varies over time, its stream. A parameter only these values declare (the program
    /// declared more parameters than with other values) gets its representative value, so that
    /// the run goes on and the load reports it, naming it.
    pub fn param(&mut self, decl: ParamDecl) -> Seen {
        match self.scene.declare_param(decl) {
            (ParamValue::Level(l), _) => Seen::Level(l),
            (ParamValue::Over(_), k) => Seen::Stream(self.scene.push(Node::Param(k))),
        }
    }

    /// A probe stream.
    pub fn probe(&mut self, actor: ActorRef, output: Output) -> StreamId {
        self.scene.probe(actor, output)
    }
}

/// An object's name with where it was declared, `Car c (f.star:4:5)`, unless the name already
/// says it (`Car at f.star:2:12 (called from ...)`).
fn declared(name: &str, at: &str) -> String {
    if at.is_empty() || name.contains(at) {
        name.to_owned()
    } else {
        format!("{name} ({at})")
    }
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
                        "route entry `{n}` is not a turn; use \"straight\", \"left\", \"right\", \"uturn\" \
                         or, on a map, \"road:ID\" (a connecting road's <road id>)"
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
            .map(|l| l.resolve(self.scene.roads()).ok())
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
        if let Some((a, b)) = self.scene.roads().first_overlap() {
            let named = |p: PieceId| {
                let name = &self.scene.roads().piece(p).name;
                let site = self.scene.road_site(p).map(Site::to_string);
                declared(name, site.as_deref().unwrap_or(""))
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
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(b.scene.roads());
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
        check(&placed, self.scene.roads())
            .map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?;
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
                    self.scene.place_obstacle(
                        ObstacleSpec {
                            base_m: at.pos_m,
                            heading_rad: at.heading_rad,
                            size,
                            color,
                        },
                        o.name.clone(),
                        Site::of(&o.at).with_variable(o.variable.clone()),
                    );
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
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(b.scene.roads());
        let start = resolve(self, loc)?;
        let route = match route {
            Some(turns) => self
                .scene
                .roads()
                .route(&start, &turns, self.route_m)
                .map_err(|e| {
                    LoadError::new(LoadErrorKind::Worlds, format!("{}: {}", o.name, strip(e)))
                })?,
            // Without a route the ego keeps its lane: the lane's path (straight on
            // through junctions where it can, round a roundabout's ring, into a
            // T's turn from its stem), or, where that path is the start line
            // itself (straight roads), the start line.
            None if self.scene.roads().group_of(start.piece).iter().any(|&id| {
                let kind = &self.scene.roads().piece(id).kind;
                kind.ref_line().is_some() || matches!(kind, PieceKind::Map { .. })
            }) =>
            {
                self.scene
                    .roads()
                    .route(&start, &[], self.route_m)
                    .map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?
            }
            None => {
                let lane = self
                    .scene
                    .roads()
                    .route(&start, &[], self.route_m)
                    .map_err(|e| LoadError::new(LoadErrorKind::Worlds, strip(e)))?;
                if on_start_line(&start, &lane) {
                    vec![]
                } else {
                    lane
                }
            }
        };
        self.scene
            .place_ego(
                EgoSpec {
                    start,
                    initial_speed_mps,
                    vehicle: VehicleParams::default(),
                    route,
                    set_speed_mps: None,
                    scripted: false,
                },
                sut,
            )
            .map_err(|_| {
                LoadError::new(
                    LoadErrorKind::Worlds,
                    format!("{}: a scenario has one AutonomousVehicle", o.name),
                )
            })
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
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(b.scene.roads());
        let pedestrian_name = o.runtime_name("Pedestrian");
        let s = resolve(self, start)?.pos_m;
        let t = resolve(self, target)?.pos_m;
        let Some(actor @ ActorRef::Pedestrian(handle)) = o.actor else {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!("{}: a Pedestrian without its handle", o.name),
            ));
        };
        match trigger {
            PedTrigger::Near { car, dist } => {
                self.scene.graph_mut().pedestrian(handle, s, t, car, dist);
            }
            PedTrigger::Stream(trigger) => {
                self.scene
                    .graph_mut()
                    .pedestrian_with_trigger(handle, t, trigger);
            }
            PedTrigger::Never => {}
        }
        if !matches!(trigger, PedTrigger::Never) {
            // The behaviour's `foreach(walk)` is named by the Pedestrian's
            // declaration, for the check of two behaviours walking it.
            let walk = paracosm_engine::rx::StreamId(self.scene.nodes().len() - 1);
            self.scene.graph_mut().set_site(walk, o.at.clone());
        }
        self.scene
            .place_pedestrian(
                actor,
                PedestrianSpec {
                    start: s,
                    target: t,
                    speed,
                    initial_speed_mps: 0.0,
                    name: pedestrian_name,
                },
            )
            .map_err(|e| LoadError::new(LoadErrorKind::Worlds, format!("{}: {e}", o.name)))
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
        let resolve = |b: &SceneBuilder, i: usize| b.locs[i].resolve(b.scene.roads());
        let car_name = o.runtime_name("Car");
        let start = resolve(self, loc)?;
        let path = match self.scene.roads().route(&start, &route, self.route_m) {
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
        let Some(actor) = o.actor else {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!("{}: a Car without its handle", o.name),
            ));
        };
        self.scene
            .place_car(
                actor,
                CarSpec {
                    path,
                    speed,
                    color,
                    size: Size::CAR,
                    enabled,
                    lane_change,
                    lane_offsets_m,
                    name: car_name,
                    keep_distance_m,
                    tow: None,
                },
            )
            .map_err(|e| LoadError::new(LoadErrorKind::Worlds, format!("{}: {e}", o.name)))
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
        let half = (self.scene.roads().piece(start.piece).kind.lanes() / 2) as i32;
        (-half..=half)
            .filter(|&l| l != 0)
            .filter_map(|l| {
                let at = self
                    .scene
                    .roads()
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
            .scene
            .roads()
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
