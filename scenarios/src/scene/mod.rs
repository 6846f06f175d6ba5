//! The typed scene model: what one test of a scenario is made of, independent of the front end
//! that declares it (the Starlark language, [`crate::lang`]; a scenario file; a Rust caller).
//!
//! A [`Scene`] holds the open parameters, the road network, the actors, the monitors, the
//! signals published to them, the sensors, the test's settings and the stream graph (paper
//! §2: reactive objects whose inputs are constants, open parameters or computed streams).
//! Every entry carries the [`Site`] where it was declared, so that a refusal points at it.
//! Fields are private: a front end declares through the methods, and [`Scene::world`] turns
//! a finished scene into the engine's [`WorldSpec`] for one test. The engine runs only worlds
//! made this way; the runner builds each test's world from its scene.
//!
//! A scene is per test: the values of its open parameters are bound when it is made
//! ([`Scene::new`]), since an open parameter may shape the world itself (a road's length,
//! how many lanes, whether a car is present).

pub mod builtin_signals;
mod error;
mod monitor;
mod params;
mod signals;
mod stream_types;
mod world;

pub use error::{refused, LoadError, LoadErrorKind, Site};
pub use monitor::MonitorSpec;
pub use params::{
    coordinate_names, level_value, representative, GivenValues, OverTime, ParamDecl, ParamValue,
};
pub use stream_types::{stream_types, SType};

use paracosm_engine::actor::{Roster, Set};
use paracosm_engine::behaviour::{ActorRef, GraphBuilder, Output, Probe};
use paracosm_engine::network::{Network, PieceId};
use paracosm_engine::rx::{Node, StreamId};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{CarSpec, EgoSpec, ObstacleSpec, PedestrianSpec, SensorSpec};

use paracosm_generators::Assignment;

/// The `tick` stream: the first node of every scene's graph.
pub const TICK: StreamId = StreamId(0);

/// A test's length when the scene does not set one, s.
pub const DEFAULT_HORIZON_S: f64 = 15.0;

/// An actor as declared: which one it is, how messages name it (`Car lead`, or `Car at
/// f.star:12:7`), and where it was declared (with the variable it was assigned to, whose
/// outputs monitors read as `<variable>.speed`, `<variable>.pos.x`, ...).
#[derive(Debug, Clone, PartialEq)]
pub struct DeclaredActor {
    /// The actor.
    pub actor: ActorRef,
    /// How messages name it.
    pub name: String,
    /// Where it was declared.
    pub site: Site,
}

/// A stream published to the monitors under a name.
#[derive(Debug, Clone, PartialEq)]
pub struct Signal {
    /// The name monitors read it by (`gap`; `monitor:<name>` for the stream a `Monitor` or
    /// an `Assert` judges).
    pub name: String,
    /// The stream.
    pub stream: StreamId,
    /// Where a user's `Signal(...)` declared it; `None` for the streams monitors publish.
    pub site: Option<Site>,
}

/// The test's settings (`test(horizon=, map=, offroad=)` in the language).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TestSettings {
    /// Where they were set; `None` when they are the defaults.
    pub site: Option<Site>,
    /// The test's length, s, in `(0, ∞)`; `None`: [`DEFAULT_HORIZON_S`].
    pub horizon_s: Option<f64>,
    /// The failure map's axes: one or two parameter names.
    pub map_axes: Option<Vec<String>>,
    /// Whether the default `OffRoadMonitor` is added (`None`: yes).
    pub offroad: Option<bool>,
}

/// What a scene refuses while it is declared.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// A second `World(...)`: light and fog are set once.
    #[error("World(...) is declared twice: first at {first}")]
    SecondEnvironment {
        /// Where the first was declared.
        first: Site,
    },
    /// A second ego vehicle.
    #[error("a second AutonomousVehicle: the first was declared at {first}")]
    SecondEgo {
        /// Where the first was declared.
        first: Site,
    },
    /// An actor's spec placed under a handle that is not the next one of its set: actors are
    /// placed in the order they were declared.
    #[error("{what} placed out of its declaration order")]
    OutOfOrder {
        /// The actor.
        what: String,
    },
    /// Settings given a second time.
    #[error("test(...) is called twice: first at {first}")]
    SecondSettings {
        /// Where the first call stands.
        first: Site,
    },
}

/// Everything one test of a scenario is made of (see the module's documentation).
#[derive(Debug, Clone)]
pub struct Scene {
    graph: GraphBuilder,
    params: Vec<ParamDecl>,
    given: Option<GivenValues>,
    /// The value each declared parameter took, by declaration index (with `given`).
    bound: Vec<ParamValue>,
    roads: Network,
    road_sites: Vec<Site>,
    frictions: Vec<(PieceId, StreamId)>,
    actors: Vec<DeclaredActor>,
    pedestrian_handles: Roster<PedestrianSpec>,
    car_handles: Roster<CarSpec>,
    ego: Option<(EgoSpec, SutConfig)>,
    pedestrians: Set<PedestrianSpec>,
    cars: Set<CarSpec>,
    obstacles: Set<ObstacleSpec>,
    obstacle_names: Vec<(String, Site)>,
    environment: Option<(StreamId, StreamId, Site)>,
    monitors: Vec<(MonitorSpec, Site)>,
    signals: Vec<Signal>,
    sensors: Vec<SensorSpec>,
    settings: TestSettings,
    /// Top-level variables that hold an actor declared under another name (`lead = s.Lead`
    /// of an imported scenario): each publishes the actor's outputs as its own
    /// (`lead.speed`), as a variable a declaration is assigned to does.
    aliases: Vec<(String, ActorRef)>,
    /// What the front end's host reads in this test ([`HostInputs`]).
    host_inputs: Option<std::sync::Arc<dyn HostInputs>>,
}

/// What a front end's host (an OpenSCENARIO storyboard, which moves its entities outside the
/// scene's stream graph) reads in one test, kept with the test's scene so that the load's
/// analyses can tell two tests apart by it as by their worlds ([`crate::analysis`]).
pub trait HostInputs: std::fmt::Debug + Send + Sync {
    /// Whether `other` is the same front end's and reads the same (its values compared, not
    /// where they were written).
    fn same_as(&self, other: &dyn HostInputs) -> bool;

    /// The inputs as [`std::any::Any`], for [`HostInputs::same_as`] to downcast `other`.
    fn as_any(&self) -> &dyn std::any::Any;
}

impl Scene {
    /// An empty scene whose graph holds the `tick` stream as [`TICK`], for a test that gives
    /// the open parameters `values` (bound by name as each is declared, [`GivenValues`];
    /// `None`: each parameter's [`representative`] value, as a front end uses to learn a
    /// scenario's parameters). The sensors are [`SensorSpec::defaults`].
    pub fn new(values: Option<GivenValues>) -> Self {
        let mut graph = GraphBuilder::new();
        let tick = graph.push(Node::Tick);
        debug_assert_eq!(tick, TICK);
        Scene {
            graph,
            params: Vec::new(),
            given: values,
            bound: Vec::new(),
            roads: Network::new(),
            road_sites: Vec::new(),
            frictions: Vec::new(),
            actors: Vec::new(),
            pedestrian_handles: Roster::default(),
            car_handles: Roster::default(),
            ego: None,
            pedestrians: Set::default(),
            cars: Set::default(),
            obstacles: Set::default(),
            obstacle_names: Vec::new(),
            environment: None,
            monitors: Vec::new(),
            signals: Vec::new(),
            sensors: SensorSpec::defaults(),
            settings: TestSettings::default(),
            aliases: Vec::new(),
            host_inputs: None,
        }
    }

    /// An empty scene (as [`Scene::new`]) whose open parameters take their values from
    /// `assignment` by name as they are declared ([`GivenValues::of_assignment`]).
    pub fn for_assignment(assignment: &Assignment) -> Self {
        Scene::new(Some(GivenValues::of_assignment(assignment)))
    }

    /// Keeps what the front end's host reads in this test ([`HostInputs`]), replacing any
    /// kept before.
    pub fn set_host_inputs(&mut self, inputs: std::sync::Arc<dyn HostInputs>) {
        self.host_inputs = Some(inputs);
    }

    /// What the front end's host reads in this test; `None` for a scene with no host or one
    /// whose front end keeps nothing (a program's lambdas are analysed from its code).
    pub fn host_inputs(&self) -> Option<&dyn HostInputs> {
        self.host_inputs.as_deref()
    }

    /// [`Scene::host_inputs`], shared, to keep beside the scene's world after the scene is
    /// dropped.
    pub fn shared_host_inputs(&self) -> Option<std::sync::Arc<dyn HostInputs>> {
        self.host_inputs.clone()
    }

    // ---- the stream graph ----

    /// Adds `node` to the stream graph; returns its stream.
    pub fn push(&mut self, node: Node) -> StreamId {
        self.graph.push(node)
    }

    /// The stream graph so far.
    pub fn graph(&self) -> &GraphBuilder {
        &self.graph
    }

    /// The stream graph, for a front end that wires behaviours into it (a pedestrian's walk,
    /// a stream's source position).
    pub fn graph_mut(&mut self) -> &mut GraphBuilder {
        &mut self.graph
    }

    /// The nodes of the stream graph so far, by [`StreamId`].
    pub fn nodes(&self) -> &[Node] {
        self.graph.nodes()
    }

    /// A probe stream: `output` of `actor` each step.
    pub fn probe(&mut self, actor: ActorRef, output: Output) -> StreamId {
        self.graph.push(Node::Probe(Probe::new(actor, output)))
    }

    /// The static kind of every stream so far, by [`StreamId`].
    pub fn stream_types(&self) -> Vec<SType> {
        stream_types(self.graph.nodes(), &self.params)
    }

    // ---- open parameters ----

    /// Declares an open parameter; returns its value in this test, bound by name
    /// ([`GivenValues::value_of`]; a parameter the values do not name gets its
    /// [`representative`] value, so that a front end goes on and reports the mismatch, naming
    /// it) and its index in declaration order.
    pub fn declare_param(&mut self, decl: ParamDecl) -> (ParamValue, usize) {
        let k = self.params.len();
        let value = (self.given.as_ref())
            .and_then(|g| g.value_of(&decl, k).cloned())
            .unwrap_or_else(|| representative(&decl, self.horizon_s()));
        if self.given.is_some() {
            self.bound.push(value.clone());
        }
        self.params.push(decl);
        (value, k)
    }

    /// The open parameters, in declaration order.
    pub fn params(&self) -> &[ParamDecl] {
        &self.params
    }

    /// Whether this scene was made with values for its parameters (`false`: representative
    /// values, as when a front end learns a scenario's parameters).
    pub fn has_values(&self) -> bool {
        self.given.is_some()
    }

    /// The name of the parameter declared `k`-th: the one its values are given under, else
    /// its declaration's own (`name=`), else the variable it is assigned to.
    pub fn param_name(&self, k: usize) -> Option<String> {
        let decl = self.params.get(k)?;
        match &self.given {
            Some(g) => g.name_of(decl, k).map(str::to_owned),
            None => decl.name.clone().or_else(|| decl.site.variable.clone()),
        }
    }

    /// The value of the parameter declared `k`-th in this test.
    pub fn param_value(&self, k: usize) -> Option<ParamValue> {
        let decl = self.params.get(k)?;
        Some(match &self.given {
            Some(_) => self.bound.get(k)?.clone(),
            None => representative(decl, self.horizon_s()),
        })
    }

    // ---- roads ----

    /// Adds a road piece with `add` (one of [`Network`]'s constructors), its friction stream
    /// (dimensionless, `[0, ∞)`) and where it was declared.
    ///
    /// # Errors
    /// What `add` returns.
    pub fn add_road<E>(
        &mut self,
        add: impl FnOnce(&mut Network) -> Result<PieceId, E>,
        friction: StreamId,
        site: Site,
    ) -> Result<PieceId, E> {
        let id = add(&mut self.roads)?;
        self.frictions.push((id, friction));
        self.road_sites.push(site);
        Ok(id)
    }

    /// The road network as declared so far.
    pub fn roads(&self) -> &Network {
        &self.roads
    }

    /// The road network, for a front end that connects or moves its pieces (`connect`).
    pub fn roads_mut(&mut self) -> &mut Network {
        &mut self.roads
    }

    /// Where road piece `piece` was declared.
    pub fn road_site(&self, piece: PieceId) -> Option<&Site> {
        self.road_sites.get(piece.0)
    }

    /// Each road piece's friction stream.
    pub fn frictions(&self) -> &[(PieceId, StreamId)] {
        &self.frictions
    }

    // ---- actors ----

    /// Declares the ego vehicle (its spec comes with [`Scene::place_ego`]).
    pub fn declare_ego(&mut self, name: String, site: Site) -> ActorRef {
        self.actors.push(DeclaredActor {
            actor: ActorRef::Ego,
            name,
            site,
        });
        ActorRef::Ego
    }

    /// Declares a pedestrian; its handle is the one its spec gets at
    /// [`Scene::place_pedestrian`].
    pub fn declare_pedestrian(&mut self, name: String, site: Site) -> ActorRef {
        let actor = ActorRef::Pedestrian(self.pedestrian_handles.add());
        self.actors.push(DeclaredActor { actor, name, site });
        actor
    }

    /// Declares an NPC car; its handle is the one its spec gets at [`Scene::place_car`].
    pub fn declare_car(&mut self, name: String, site: Site) -> ActorRef {
        let actor = ActorRef::Car(self.car_handles.add());
        self.actors.push(DeclaredActor { actor, name, site });
        actor
    }

    /// Names `actor` by the top-level `variable` that holds it (`lead = s.Lead`), so that
    /// its outputs are published as `variable.speed`, ... as a declaration's own variable's
    /// are.
    pub fn alias_actor(&mut self, variable: String, actor: ActorRef) {
        if !self.aliases.iter().any(|(v, _)| *v == variable) {
            self.aliases.push((variable, actor));
        }
    }

    /// The actor a top-level variable names: the declaration assigned to it, else an alias
    /// ([`Scene::alias_actor`]).
    pub fn actor_of_variable(&self, variable: &str) -> Option<ActorRef> {
        self.actors
            .iter()
            .find(|o| o.site.variable.as_deref() == Some(variable))
            .map(|o| o.actor)
            .or_else(|| {
                self.aliases
                    .iter()
                    .find(|(v, _)| v == variable)
                    .map(|(_, a)| *a)
            })
    }

    /// The actors declared so far, in declaration order.
    pub fn actors(&self) -> &[DeclaredActor] {
        &self.actors
    }

    /// Places the ego vehicle: its spec and its system under test.
    ///
    /// # Errors
    /// [`SceneError::SecondEgo`] when one is placed already.
    pub fn place_ego(&mut self, spec: EgoSpec, sut: SutConfig) -> Result<(), SceneError> {
        if self.ego.is_some() {
            let first = self
                .actors
                .iter()
                .find(|a| a.actor == ActorRef::Ego)
                .map_or_else(|| Site::of("?"), |a| a.site.clone());
            return Err(SceneError::SecondEgo { first });
        }
        self.ego = Some((spec, sut));
        Ok(())
    }

    /// Places the pedestrian declared as `actor` with its spec.
    ///
    /// # Errors
    /// [`SceneError::OutOfOrder`] unless it is the next pedestrian declared.
    pub fn place_pedestrian(
        &mut self,
        actor: ActorRef,
        spec: PedestrianSpec,
    ) -> Result<(), SceneError> {
        let next = match actor {
            ActorRef::Pedestrian(h) => Some(h.index()),
            _ => None,
        };
        place_next(&mut self.pedestrians, actor, next, spec)
    }

    /// Places the NPC car declared as `actor` with its spec.
    ///
    /// # Errors
    /// [`SceneError::OutOfOrder`] unless it is the next car declared.
    pub fn place_car(&mut self, actor: ActorRef, spec: CarSpec) -> Result<(), SceneError> {
        let next = match actor {
            ActorRef::Car(h) => Some(h.index()),
            _ => None,
        };
        place_next(&mut self.cars, actor, next, spec)
    }

    /// Places a static obstacle, named `name` in messages, declared at `site`.
    pub fn place_obstacle(&mut self, spec: ObstacleSpec, name: String, site: Site) -> ActorRef {
        self.obstacle_names.push((name, site));
        ActorRef::Obstacle(self.obstacles.insert(spec))
    }

    /// The ego vehicle's spec and system under test, once placed.
    pub fn ego(&self) -> Option<(&EgoSpec, &SutConfig)> {
        self.ego.as_ref().map(|(e, s)| (e, s))
    }

    /// The pedestrians placed, in declaration order.
    pub fn pedestrians(&self) -> &Set<PedestrianSpec> {
        &self.pedestrians
    }

    /// The NPC cars placed, in declaration order.
    pub fn cars(&self) -> &Set<CarSpec> {
        &self.cars
    }

    /// The obstacles placed, in declaration order.
    pub fn obstacles(&self) -> &Set<ObstacleSpec> {
        &self.obstacles
    }

    /// How messages name the NPC car with index `i` in [`Scene::cars`].
    pub fn car_name(&self, i: usize) -> Option<&str> {
        self.actors
            .iter()
            .find(|a| matches!(a.actor, ActorRef::Car(h) if h.index() == i))
            .map(|a| a.name.as_str())
    }

    /// How messages name the obstacle with index `i` in [`Scene::obstacles`].
    pub fn obstacle_name(&self, i: usize) -> Option<&str> {
        self.obstacle_names.get(i).map(|(n, _)| n.as_str())
    }

    /// Where the obstacle with index `i` in [`Scene::obstacles`] was declared.
    pub fn obstacle_site(&self, i: usize) -> Option<&Site> {
        self.obstacle_names.get(i).map(|(_, s)| s)
    }

    // ---- environment, monitors, signals, sensors, settings ----

    /// Sets the light (`[0, 1]`) and fog density (`[0, 1]`) streams.
    ///
    /// # Errors
    /// [`SceneError::SecondEnvironment`] when they are set already.
    pub fn set_environment(
        &mut self,
        light: StreamId,
        fog: StreamId,
        site: Site,
    ) -> Result<(), SceneError> {
        if let Some((_, _, first)) = &self.environment {
            return Err(SceneError::SecondEnvironment {
                first: first.clone(),
            });
        }
        self.environment = Some((light, fog, site));
        Ok(())
    }

    /// The light and fog streams, once set.
    pub fn environment(&self) -> Option<(StreamId, StreamId)> {
        self.environment.as_ref().map(|(l, f, _)| (*l, *f))
    }

    /// Adds a monitor; returns its index.
    pub fn add_monitor(&mut self, spec: MonitorSpec, site: Site) -> usize {
        self.monitors.push((spec, site));
        self.monitors.len() - 1
    }

    /// Replaces monitor `k` by `spec` declared at `site` (a monitor wrapped by another, as
    /// `TimeToFailure` wraps one); does nothing for an index out of range.
    pub fn replace_monitor(&mut self, k: usize, spec: MonitorSpec, site: Site) {
        if let Some(m) = self.monitors.get_mut(k) {
            *m = (spec, site);
        }
    }

    /// The monitors with where each was declared, in declaration order.
    pub fn monitors(&self) -> impl ExactSizeIterator<Item = (&MonitorSpec, &Site)> + Clone {
        self.monitors.iter().map(|(m, s)| (m, s))
    }

    /// The monitors' specs, in declaration order.
    pub fn monitor_specs(&self) -> Vec<MonitorSpec> {
        self.monitors.iter().map(|(m, _)| m.clone()).collect()
    }

    /// Publishes `stream` to the monitors as `name`; `site` is where a user's `Signal(...)`
    /// declared it (`None` for a monitor's own stream).
    pub fn publish(&mut self, name: String, stream: StreamId, site: Option<Site>) {
        self.signals.push(Signal { name, stream, site });
    }

    /// The streams published to the monitors so far, in order.
    pub fn signals(&self) -> &[Signal] {
        &self.signals
    }

    /// Adds a sensor to the world's defaults.
    pub fn add_sensor(&mut self, sensor: SensorSpec) {
        self.sensors.push(sensor);
    }

    /// The sensors the world carries.
    pub fn sensors(&self) -> &[SensorSpec] {
        &self.sensors
    }

    /// Sets the test's settings.
    ///
    /// # Errors
    /// [`SceneError::SecondSettings`] when they are set already.
    pub fn set_settings(&mut self, settings: TestSettings) -> Result<(), SceneError> {
        if let Some(first) = &self.settings.site {
            return Err(SceneError::SecondSettings {
                first: first.clone(),
            });
        }
        self.settings = settings;
        Ok(())
    }

    /// The test's settings.
    pub fn settings(&self) -> &TestSettings {
        &self.settings
    }

    /// The test's length, s: the settings' horizon, else [`DEFAULT_HORIZON_S`].
    pub fn horizon_s(&self) -> f64 {
        self.settings.horizon_s.unwrap_or(DEFAULT_HORIZON_S)
    }
}

/// Inserts `spec` into `set` when `index` (the declared actor's handle index, `None` for an
/// actor of another kind) is the set's next one.
///
/// # Errors
/// [`SceneError::OutOfOrder`] naming `actor` otherwise.
fn place_next<T>(
    set: &mut Set<T>,
    actor: ActorRef,
    index: Option<usize>,
    spec: T,
) -> Result<(), SceneError> {
    if index != Some(set.len()) {
        return Err(SceneError::OutOfOrder {
            what: format!("{actor:?}"),
        });
    }
    set.insert(spec);
    Ok(())
}

#[cfg(test)]
mod tests;
