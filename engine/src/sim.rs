use std::sync::mpsc::{channel, Receiver};

use rapier3d::prelude::*;
use serde::Serialize;

use crate::actor::{Contact, Handle, Size, StepWorld, VisibleBox};
use crate::actors::Actors;
use crate::behaviour::{Action, ActorRef, Output, Probe};
use crate::car::{CarState, LaneChangeStart};
use crate::contact::Solids;
use crate::ego::{Ego, EgoState};
use crate::network::{Lane, Network, PieceId, Surface};
use crate::obstacle::ObstacleState;
use crate::rx::{constant, number, Host, Input, Inputs, Runtime, StreamId, Value};
use crate::sensor::{Reading, Scene, Sensor, Sensors};
use crate::vehicle::EgoVehicle;
use crate::{
    CameraFrame, CameraSpec, CarSpec, Control, EngineError, ObstacleSpec, PedestrianSpec,
    PedestrianState, WorldSpec, NOMINAL_LIGHT,
};

/// What a system under test sees at one instant.
#[derive(Debug, Clone)]
pub struct Observation<'a> {
    /// Time since the start, in seconds.
    pub t_s: f64,
    /// Physics step in seconds.
    pub dt_s: f64,
    /// The ego vehicle's own state (odometry).
    pub ego: EgoState,
    /// The route to follow, world `[x, z]` in metres (navigation); empty: keep the lane.
    pub route: &'a [[f64; 2]],
    /// The speed the scenario asks the system to keep, m/s ([`EgoSpec::set_speed_mps`]);
    /// `None`: its own.
    pub set_speed_mps: Option<f64>,
    /// Every sensor's latest reading, by the sensor's name, in the order the sensors were
    /// mounted (what an external system receives, SUT_PROTOCOL.md). Read one with
    /// [`Observation::reading`], or typed: [`Observation::lidar`], [`Observation::camera`].
    pub readings: Vec<(&'static str, Reading<'a>)>,
}

impl<'a> Observation<'a> {
    /// The latest reading of the sensor called `name` (`lidar`, `camera`, or a sensor's own
    /// name; the first mounted when several share it), `None` when none is mounted or it has
    /// not captured yet.
    pub fn reading(&self, name: &str) -> Option<Reading<'a>> {
        self.readings
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, reading)| *reading)
    }
}

/// The world's state after a step: what monitors are computed from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Snapshot {
    /// Time since the start, in seconds.
    pub t_s: f64,
    /// The ego vehicle.
    pub ego: EgoState,
    /// Every pedestrian, in the order of [`WorldSpec::pedestrians`].
    pub pedestrians: Vec<PedestrianState>,
    /// Every NPC car, in the order of [`WorldSpec::cars`].
    pub cars: Vec<CarState>,
    /// Every static obstacle, in the order of [`WorldSpec::obstacles`].
    pub obstacles: Vec<ObstacleState>,
    /// Whether the ego vehicle's body touches a pedestrian, a car or an obstacle now
    /// (collision events).
    pub ego_contact: bool,
    /// The smallest distance between the ego vehicle's body and a pedestrian's capsule, a
    /// car's or an obstacle's body, in metres; `0` when touching, `+inf` without actors.
    pub min_separation_m: f64,
    /// Path time to collision of the ego vehicle in seconds ([`crate::ttc::time_to_collision_s`]):
    /// `+inf` when nothing in its path is closing in, `0` when touching; NaN when
    /// [`Simulation::snapshot_of`] left it out.
    pub ttc_s: f64,
    /// Light intensity now, `[0, 1]`.
    pub light: f64,
    /// Fog density now, `[0, 1]`.
    pub fog: f64,
    /// Whether the centre of the ego vehicle's footprint is on no driving surface of the
    /// network (a sidewalk, an island, the ground beside the road or beyond a dead end).
    pub ego_off_road: bool,
    /// Signed distance from the centre of the ego vehicle's footprint to the edge of the
    /// driving surface, in metres: `> 0` on it, `<= 0` off it ([`Surface::edge_distance_m`]).
    pub ego_road_edge_m: f64,
    /// Lateral offset of the ego vehicle's centre from the centre line of the nearest lane
    /// in its direction of travel, in metres, positive to the right
    /// ([`Surface::lane_offset_m`]); NaN when [`Simulation::snapshot_of`] left it out.
    pub ego_lane_offset_m: f64,
}

/// Which of a [`Snapshot`]'s costlier signals [`Simulation::snapshot_of`] computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SnapshotParts {
    /// [`Snapshot::ttc_s`], the path time to collision (one prediction per actor).
    pub ttc: bool,
    /// [`Snapshot::ego_lane_offset_m`] (a search of the lanes near the ego vehicle).
    pub lane_offset: bool,
}

impl SnapshotParts {
    /// Every signal.
    pub const ALL: SnapshotParts = SnapshotParts {
        ttc: true,
        lane_offset: true,
    };
}

/// Checks what [`Simulation::new`] checks before it builds anything: the step, the sensors'
/// settings, and the ego vehicle's start lane and speed.
///
/// # Errors
/// [`EngineError::InvalidWorld`] naming the first value out of range.
fn check_ego_and_step(spec: &WorldSpec) -> Result<(), EngineError> {
    let invalid = |m: String| EngineError::InvalidWorld(m);
    if !(spec.dt_s.is_finite() && spec.dt_s > 0.0) {
        return Err(invalid(format!(
            "time step {} s is not positive",
            spec.dt_s
        )));
    }
    for sensor in &spec.sensors {
        sensor.validate().map_err(|e| invalid(e.to_string()))?;
    }
    if !matches!(spec.ego.start.lane, Lane::Driving(_)) {
        return Err(invalid(
            "the ego vehicle must start on a driving lane".into(),
        ));
    }
    crate::VehicleParams::check_size(&spec.ego.vehicle.size)?;
    if !(spec.ego.initial_speed_mps.is_finite() && spec.ego.initial_speed_mps >= 0.0) {
        return Err(invalid(format!(
            "ego initial speed {} m/s is negative or not finite",
            spec.ego.initial_speed_mps
        )));
    }
    Actors::check(spec)
}

/// The streams the world itself reads every step: the actors' ([`Actors::read_streams`]),
/// the varying frictions, the published streams, light and fog.
fn read_streams(spec: &WorldSpec) -> impl Iterator<Item = StreamId> + Clone + '_ {
    Actors::read_streams(spec)
        .chain(spec.frictions.iter().map(|f| f.1))
        .chain(spec.published.iter().map(|p| p.1))
        .chain([spec.environment.light, spec.environment.fog])
}

/// The runtime of `spec`'s stream graph, evaluating only what the world reads (`reads`, from
/// [`read_streams`]), the streams that start a car's lane change, and what they need.
fn world_runtime(spec: &WorldSpec, reads: impl Iterator<Item = StreamId>) -> Runtime {
    // The streams the world reads; the rest of the graph is evaluated only where these, an
    // action or a function need it (Runtime::evaluate_only).
    let mut rt = Runtime::new(spec.streams.clone());
    // A constant input is read once, when the world is built (`Input::Const`), never from
    // the runtime.
    let reads: Vec<StreamId> = reads
        .filter(|&id| {
            spec.published.iter().any(|p| p.1 == id)
                || Input::of(&spec.streams, id).stream().is_some()
        })
        .collect();
    let when = spec.cars.iter().filter_map(|c| match c.lane_change?.start {
        LaneChangeStart::When(s) => Some(s),
        LaneChangeStart::At(_) => None,
    });
    rt.evaluate_only(reads.into_iter().chain(when));
    rt
}

/// A running world: the physics, the actors in their sets, the stream graph that drives
/// them, and the ego vehicle's sensors, advanced in fixed steps by [`Simulation::step`].
pub struct Simulation {
    physics: PhysicsWorld,
    network: Network,
    surface: Surface,
    ego: Ego,
    /// The NPC cars, pedestrians and obstacles, each kind in its set.
    actors: Actors,
    /// The light and the fog density, each `[0, 1]`.
    light_fog_inputs: (Input, Input),
    light_fog: (f64, f64),
    /// Pieces whose friction varies over the test, and their streams.
    frictions: Vec<(PieceId, StreamId)>,
    streams: Runtime,
    /// The step whose streams [`Simulation::evaluate`] has computed, if it has.
    evaluated: Option<u64>,
    sinks: Vec<(Action, Value)>,
    sensors: Sensors,
    events: Receiver<CollisionEvent>,
    collector: ChannelEventCollector,
    dt_s: f64,
    tick: u64,
}

impl Simulation {
    /// Builds the world described by `spec`, with its sensors ([`WorldSpec::sensors`]) mounted.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when a position, a speed, a size, a sensor's settings,
    /// the step or a car's path is invalid; the message says which. [`EngineError::Sensor`]
    /// when a sensor cannot be set up (a camera without a GPU adapter).
    pub fn new(spec: &WorldSpec) -> Result<Self, EngineError> {
        check_ego_and_step(spec)?;
        let mut physics = PhysicsWorld::new();
        physics.integration_parameters.dt = spec.dt_s as f32;
        // A test's world holds a few dozen colliders, most of them fixed: rapier's incremental
        // tree optimizer rebuilt the broad phase's BVH on most steps for no gain (issue 23).
        physics.broad_phase =
            BroadPhaseBvh::with_optimization_strategy(BvhOptimizationStrategy::None);
        spec.network.build(&mut physics);

        let start = spec.ego.start;
        let surface = Surface::new(&spec.network);
        // Each step sets every wheel's friction from the piece under it (EgoVehicle::grip).
        let friction = surface.friction_at([start.pos_m[0], start.pos_m[2]]);
        let vehicle = EgoVehicle::build(
            &mut physics,
            &spec.ego.vehicle,
            (start.pos_m, start.heading_rad, spec.ego.initial_speed_mps),
            friction,
            spec.ego.scripted,
        );
        let ego = Ego::new(
            vehicle,
            &physics,
            spec.ego.route.clone(),
            spec.ego.set_speed_mps,
        );

        let ids = read_streams(spec);
        let n = spec.streams.nodes().len();
        for id in ids.clone() {
            if id.0 >= n {
                return Err(EngineError::InvalidWorld(format!(
                    "stream {} does not exist",
                    id.0
                )));
            }
        }
        let actors = Actors::build(spec, &mut physics)?;

        let (collision_tx, events) = channel();
        let (force_tx, _) = channel();
        let (tear_tx, _) = channel();
        let sensors = crate::sensor::mounted(spec)?;
        let mut sim = Simulation {
            physics,
            network: spec.network.clone(),
            surface,
            ego,
            actors,
            light_fog_inputs: (
                Input::of(&spec.streams, spec.environment.light),
                Input::of(&spec.streams, spec.environment.fog),
            ),
            frictions: spec.frictions.clone(),
            // Known before the first step when they are constants (a camera frame at t = 0
            // needs them); time-varying ones are set by the first step.
            light_fog: (
                constant(&spec.streams, spec.environment.light).unwrap_or(NOMINAL_LIGHT),
                constant(&spec.streams, spec.environment.fog).unwrap_or(0.0),
            ),
            streams: world_runtime(spec, ids),
            evaluated: None,
            sinks: Vec::new(),
            sensors,
            events,
            collector: ChannelEventCollector::new(collision_tx, force_tx, tear_tx),
            dt_s: spec.dt_s,
            tick: 0,
        };
        // Contacts and ray casts need the broad phase filled before the first step.
        sim.physics.detect_collisions(&(), &());
        sim.capture_all(|_| true)?;
        Ok(sim)
    }

    /// Time since the start, in seconds (`tick · dt`).
    pub fn t_s(&self) -> f64 {
        self.tick as f64 * self.dt_s
    }

    /// The physics step in seconds.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The road network.
    pub fn network(&self) -> &Network {
        &self.network
    }

    /// The ego vehicle's state now.
    pub fn ego_state(&self) -> EgoState {
        self.ego.state(&self.physics)
    }

    /// What the system under test sees now: odometry, its route, and every sensor's latest
    /// reading.
    pub fn observation(&self) -> Observation<'_> {
        let readings: Vec<(&'static str, Reading<'_>)> = self
            .sensors
            .values()
            .filter_map(|s| s.reading().map(|r| (s.name(), r)))
            .collect();
        Observation {
            t_s: self.t_s(),
            dt_s: self.dt_s,
            ego: self.ego_state(),
            route: &self.ego.route,
            set_speed_mps: self.ego.set_speed_mps,
            readings,
        }
    }

    /// Mounts `camera` on the ego vehicle, rendering through the process's shared
    /// [`crate::render::Renderer`] at the camera's rate; `seed` drives the camera's pixel
    /// noise. It takes its first frame now.
    ///
    /// # Errors
    /// [`EngineError::Sensor`] when the camera's values are out of range, no GPU adapter is
    /// found, or this build lacks the `render` feature.
    pub fn attach_camera(&mut self, camera: &CameraSpec, seed: u64) -> Result<(), EngineError> {
        self.attach_camera_for(camera, crate::FrameUse::ALL, seed)
    }

    /// [`Simulation::attach_camera`] for a consumer that reads only what `usage` says (a
    /// region of the image, some planes): the camera renders and reads back only that, and
    /// its frames hold nothing else ([`crate::CameraFrame`]).
    ///
    /// # Errors
    /// As [`Simulation::attach_camera`].
    pub fn attach_camera_for(
        &mut self,
        camera: &CameraSpec,
        usage: crate::FrameUse,
        seed: u64,
    ) -> Result<(), EngineError> {
        let sensor = crate::sensor::camera::sensor(&self.network, camera, usage, seed, self.dt_s)?;
        self.mount(sensor)
    }

    /// Mounts `sensor` on the ego vehicle beside those [`crate::sensor::mounted`] registers;
    /// it takes its first reading now, then one every [`Sensor::period_ticks`] steps, and its
    /// readings appear in [`Simulation::observation`] under its name.
    ///
    /// # Errors
    /// [`EngineError::Sensor`] when its first capture fails.
    pub fn mount(&mut self, sensor: Box<dyn Sensor>) -> Result<(), EngineError> {
        let h = self.sensors.insert(sensor);
        self.capture_all(|handle| handle == h)
    }

    /// The latest frame of the attached camera, if any.
    pub fn camera_frame(&self) -> Option<&CameraFrame> {
        self.sensors.values().find_map(|s| match s.reading() {
            Some(Reading::Camera(f)) => Some(f),
            _ => None,
        })
    }

    /// The boxes the camera draws: every enabled NPC car (its colour, from the ground to its
    /// roof), every pedestrian and every obstacle.
    pub fn visible_boxes(&self) -> Vec<VisibleBox> {
        self.actors.visible_boxes()
    }

    /// Captures every sensor that `due` selects.
    fn capture_all(
        &mut self,
        due: impl Fn(Handle<Box<dyn Sensor>>) -> bool,
    ) -> Result<(), EngineError> {
        let handles: Vec<_> = self.sensors.iter().map(|(h, _)| h).collect();
        let draws = handles
            .iter()
            .any(|&h| due(h) && self.sensors.get(h).is_some_and(|s| s.draws()));
        let boxes = if draws {
            self.visible_boxes()
        } else {
            Vec::new()
        };
        let asleep = self.actors.asleep(&self.physics);
        let scene = Scene {
            asleep: &asleep,
            physics: &self.physics,
            ego_body: self.ego.vehicle.body,
            ego: self.ego.state(&self.physics),
            light: self.light_fog.0,
            fog: self.light_fog.1,
            t_s: self.t_s(),
            boxes: &boxes,
        };
        for h in handles {
            if due(h) {
                if let Some(s) = self.sensors.get_mut(h) {
                    s.capture(&scene)?;
                }
            }
        }
        Ok(())
    }

    /// Advances the world by one step of `dt` under `control`: the stream graph first (actor
    /// behaviours, light, fog, frictions, from the world as it is at the start of the step),
    /// then the vehicle model, pedestrians, NPC cars, the rapier step, contact events, and
    /// every sensor that is due. `host` runs the graph's lambdas.
    ///
    /// # Errors
    /// [`EngineError::Stream`] when the stream graph fails (a lambda raised, a value of the
    /// wrong kind); [`EngineError::Sensor`] when a sensor fails.
    pub fn step(&mut self, control: Control, host: &mut dyn Host) -> Result<(), EngineError> {
        let dt = self.dt_s;
        let t = self.t_s();
        self.evaluate(host)?;
        let before = self.ego.position(&self.physics);
        self.set_frictions(t)?;
        self.ego
            .drive(control, &mut self.physics, &self.surface, dt);
        self.actors.start_step();
        self.act(t)?;
        self.move_kinematic_actors(t)?;
        if self.tick == 0 {
            // The sensors' first readings were taken before light and fog were known.
            self.capture_again_before_first_step()?;
        }
        let moved = crate::physics_step::step(&mut self.physics, &self.collector);
        self.ego.kinematic = moved.of(self.ego.vehicle.body);
        self.actors.end_step();
        self.record_ego_contacts();
        self.ego.collided |= self.ego_contact();
        self.ego.measure(before, &self.physics, dt);
        self.tick += 1;
        self.capture_due()
    }

    /// Sets the friction of each piece whose friction varies ([`WorldSpec::frictions`]) from
    /// its stream at time `t` (s).
    ///
    /// # Errors
    /// [`EngineError::Stream`] for a friction stream without a number now.
    fn set_frictions(&mut self, t: f64) -> Result<(), EngineError> {
        for &(piece, stream) in &self.frictions {
            let network = &self.network;
            let what = || format!("the friction of {}", network.piece(piece).name);
            let mu = number(&self.streams, Input::Stream(stream), t, what)?;
            self.surface.set_friction(piece, mu);
        }
        Ok(())
    }

    /// Moves the kinematic actors for the step at time `t` (s): each NPC car along its path
    /// (stopping short of, or against, what it meets; asleep when out of every sensor's
    /// reach), then records the pedestrians that walked into a car or an obstacle
    /// ([`Actors::move_kinematic`]).
    ///
    /// # Errors
    /// [`EngineError::Stream`] for a car speed stream without a number now.
    fn move_kinematic_actors(&mut self, t: f64) -> Result<(), EngineError> {
        // NPC cars beyond the reach of every sensor that reads the physics world, and of the
        // ego's body, sleep out of rapier's step (Car::step).
        let reach_m = self
            .sensors
            .values()
            .map(|s| s.physics_reach_m())
            .fold(0.0, f64::max);
        let chassis = self.ego.position(&self.physics);
        let ego_m = [chassis[0], chassis[2]];
        let ego_radius_m = {
            let s = self.ego.vehicle.size();
            0.5 * (s.length_m.powi(2) + s.width_m.powi(2) + s.height_m.powi(2)).sqrt()
        };
        // What a car may run into: obstacles, pedestrians (where this step's walk took
        // them), the other cars (each where it is when this one moves), and the ego for a
        // car that keeps its distance.
        let mut solids = if self.actors.kinematic_contacts() {
            self.solids()
        } else {
            Solids::new()
        };
        let mut world = StepWorld {
            physics: &mut self.physics,
            streams: &self.streams,
            surface: &self.surface,
            t_s: t,
            dt_s: self.dt_s,
        };
        self.actors
            .move_kinematic(&mut world, &mut solids, (ego_m, reach_m + ego_radius_m))
    }

    /// Reads this step's collision events between the ego vehicle and the actors: each actor
    /// touching it now, and having collided since the start.
    fn record_ego_contacts(&mut self) {
        while let Ok(event) = self.events.try_recv() {
            let (a, b, started) = match event {
                CollisionEvent::Started(a, b, _) => (a, b, true),
                CollisionEvent::Stopped(a, b, _) => (a, b, false),
            };
            let other = if a == self.ego.vehicle.collider {
                b
            } else if b == self.ego.vehicle.collider {
                a
            } else {
                continue;
            };
            self.actors.record_ego_contact(other, started);
        }
    }

    /// Captures every sensor due at this tick (one whose period divides it).
    ///
    /// # Errors
    /// [`EngineError::Sensor`] when a sensor fails.
    fn capture_due(&mut self) -> Result<(), EngineError> {
        let tick = self.tick;
        if self
            .sensors
            .values()
            .all(|s| !tick.is_multiple_of(s.period_ticks()))
        {
            return Ok(());
        }
        let due: Vec<bool> = self
            .sensors
            .values()
            .map(|s| tick.is_multiple_of(s.period_ticks()))
            .collect();
        self.capture_all(|h| due[h.index()])
    }

    /// Evaluates the stream graph for the current step, once: [`Simulation::step`] calls it,
    /// and a runner calls it before reading [`Simulation::current`] so that published
    /// streams hold this step's values (those of the state a [`Simulation::snapshot`] shows
    /// now). Evaluating again in the same step does nothing.
    ///
    /// # Errors
    /// [`EngineError::Stream`] when the graph fails (a lambda raised, a value of the wrong
    /// kind).
    pub fn evaluate(&mut self, host: &mut dyn Host) -> Result<(), EngineError> {
        if self.evaluated == Some(self.tick) {
            return Ok(());
        }
        let t = self.t_s();
        self.sinks.clear();
        // Field by field, not `self.inputs()`: the graph's step borrows `self.streams`.
        let inputs = WorldInputs {
            physics: &self.physics,
            ego: &self.ego,
            ego_touching: self.ego_contact(),
            actors: &self.actors,
        };
        self.streams.step(t, &inputs, host, &mut self.sinks)?;
        self.evaluated = Some(self.tick);
        // Light and fog now: the step from here uses them, and a snapshot shows them.
        self.light_fog = (
            number(&self.streams, self.light_fog_inputs.0, t, || {
                "the light".into()
            })?,
            number(&self.streams, self.light_fog_inputs.1, t, || {
                "the fog".into()
            })?,
        );
        Ok(())
    }

    /// What a program reads as `output` of `actor` now (the value its probe stream carries
    /// at this step): the one source of every actor's reported motion.
    pub fn read(&self, actor: ActorRef, output: Output) -> Value {
        self.inputs().probe(Probe::new(actor, output))
    }

    /// The handles of the world's NPC cars, in [`WorldSpec::cars`]' order (a disabled car
    /// included).
    pub fn cars(&self) -> impl Iterator<Item = Handle<CarSpec>> + '_ {
        self.actors.cars.iter().map(|(h, _)| h)
    }

    /// The handles of the world's pedestrians, in [`WorldSpec::pedestrians`]' order.
    pub fn pedestrians(&self) -> impl Iterator<Item = Handle<PedestrianSpec>> + '_ {
        self.actors.pedestrians.iter().map(|(h, _)| h)
    }

    /// The handles of the world's obstacles, in [`WorldSpec::obstacles`]' order.
    pub fn obstacles(&self) -> impl Iterator<Item = Handle<ObstacleSpec>> + '_ {
        self.actors.obstacles.iter().map(|(h, _)| h)
    }

    /// The latest value of stream `id` (after [`Simulation::evaluate`] for this step), `None`
    /// before its first event or for an id past the graph.
    pub fn current(&self, id: StreamId) -> Option<&Value> {
        self.streams.current(id)
    }

    /// Calls every function of the stream graph once on sample values of this world at its
    /// current time ([`crate::rx::Runtime::check`]), on a copy: the simulation is unchanged.
    /// Returns the sample value of each stream, indexed by [`StreamId`] (`None` for a stream
    /// that had none: a `take(0)`, or a stream fed by one).
    ///
    /// # Errors
    /// [`EngineError::Stream`] with the first failure.
    pub fn check_streams(&self, host: &mut dyn Host) -> Result<Vec<Option<Value>>, EngineError> {
        let mut copy = Runtime::new(self.streams.graph().clone());
        copy.check(self.t_s(), &self.inputs(), host)?;
        Ok((0..copy.graph().nodes().len())
            .map(|i| copy.current(StreamId(i)).cloned())
            .collect())
    }

    /// Performs this step's `foreach` events, in order: each actor's ([`Actors::act`]:
    /// walking steps, car speeds, brakes, lane changes, placements) and the ego's.
    ///
    /// # Errors
    /// [`crate::rx::RxError::Input`] for an argument the action cannot take (a speed that is
    /// not a number, a lane the car's segment lacks).
    fn act(&mut self, t: f64) -> Result<(), EngineError> {
        let mut world = StepWorld {
            physics: &mut self.physics,
            streams: &self.streams,
            surface: &self.surface,
            t_s: t,
            dt_s: self.dt_s,
        };
        for (sink, value) in &self.sinks {
            if sink.actor() == ActorRef::Ego {
                self.ego.act(*sink, value, world.physics, t)?;
            } else {
                self.actors.act(*sink, value, &mut world)?;
            }
        }
        Ok(())
    }

    /// Every solid object's collider where it is now, for the kinematic actors' contacts
    /// ([`crate::contact`]): the ego, the cars in the test, the pedestrians, the obstacles.
    fn solids(&self) -> Solids {
        self.inputs().solids()
    }

    /// Captures again every sensor that asks to before the first physics step
    /// ([`Sensor::recaptures_before_first_step`]).
    fn capture_again_before_first_step(&mut self) -> Result<(), EngineError> {
        let again: Vec<bool> = self
            .sensors
            .values()
            .map(|s| s.recaptures_before_first_step())
            .collect();
        self.capture_all(|h| again[h.index()])
    }

    /// The physics outputs the stream graph reads now.
    fn inputs(&self) -> WorldInputs<'_> {
        WorldInputs {
            physics: &self.physics,
            ego: &self.ego,
            ego_touching: self.ego_contact(),
            actors: &self.actors,
        }
    }

    /// Whether the ego vehicle touches any actor now.
    fn ego_contact(&self) -> bool {
        self.actors.touching_ego()
    }

    /// The state monitors are computed from, every field of it.
    pub fn snapshot(&self) -> Snapshot {
        self.snapshot_of(SnapshotParts::ALL)
    }

    /// The state monitors are computed from, with only the costlier signals in `parts`
    /// computed: a field left out ([`Snapshot::ttc_s`], [`Snapshot::ego_lane_offset_m`]) is
    /// NaN, for a runner whose monitors do not read it. Every other field is as
    /// [`Simulation::snapshot`] gives it, bit for bit.
    pub fn snapshot_of(&self, parts: SnapshotParts) -> Snapshot {
        let chassis = &self.physics.colliders[self.ego.vehicle.collider];
        // Each actor's shape where it is now ([`ActorKind::collider_now`]).
        let actors = (self.actors.all()).filter_map(|(_, a)| a.collider_now(&self.physics));
        // The exact distance (GJK) to the nearest actor. The distance between bounding boxes
        // is a lower bound, so an actor whose bound is no smaller than the best distance found
        // cannot change the minimum, and is skipped; nearest bounds are tried first.
        let chassis_box = chassis.compute_aabb();
        let mut by_bound: Vec<(f32, Pose, &dyn Shape)> = actors
            .map(|(pose, shape)| {
                let b = shape.compute_aabb(&pose);
                let gap = (b.mins - chassis_box.maxs)
                    .max(chassis_box.mins - b.maxs)
                    .max(Vector::ZERO);
                (gap.length(), pose, shape)
            })
            .collect();
        by_bound.sort_by(|a, b| a.0.total_cmp(&b.0));
        let far = chassis.position().translation.abs().max_element();
        let slack = 1e-3 + 8.0 * f64::from(f32::EPSILON) * f64::from(far.max(1.0));
        let mut min_sep = f64::INFINITY;
        for (bound, pose, shape) in by_bound {
            // 1 mm of slack, plus the f32 rounding of coordinates this far from the origin,
            // covers the rounding of both computations.
            if f64::from(bound) - slack >= min_sep {
                break;
            }
            if let Ok(d) =
                rapier3d::parry::query::distance(chassis.position(), chassis.shape(), &pose, shape)
            {
                min_sep = min_sep.min(f64::from(d.distance));
            }
        }
        let ego = self.ego_state();
        let centre = [ego.pos_m[0], ego.pos_m[2]];
        let edge = self.surface.edge_distance_m(centre);
        let size = self.ego.vehicle.size();
        let ego_mover = crate::ttc::Mover {
            pos_m: [ego.pos_m[0], ego.pos_m[2]],
            velocity_mps: [
                ego.speed_mps * ego.heading_rad.cos(),
                -ego.speed_mps * ego.heading_rad.sin(),
            ],
            heading_rad: ego.heading_rad,
            half_size_m: [size.length_m / 2.0, size.width_m / 2.0],
        };
        let ttc_s = if parts.ttc {
            let movers: Vec<crate::ttc::Mover> =
                self.actors.all().filter_map(|(_, a)| a.mover()).collect();
            crate::ttc::time_to_collision_s(&ego_mover, &movers)
        } else {
            f64::NAN
        };
        Snapshot {
            t_s: self.t_s(),
            ego,
            ttc_s,
            pedestrians: self
                .actors
                .pedestrians
                .values()
                .map(|p| p.state())
                .collect(),
            cars: self.actors.cars.values().map(|c| c.state()).collect(),
            obstacles: self.actors.obstacles.values().map(|o| o.state()).collect(),
            ego_contact: self.ego_contact(),
            min_separation_m: min_sep,
            light: self.light_fog.0,
            fog: self.light_fog.1,
            ego_off_road: edge < 0.0,
            ego_road_edge_m: edge,
            ego_lane_offset_m: if parts.lane_offset {
                self.surface.lane_offset_m(centre, ego.heading_rad)
            } else {
                f64::NAN
            },
        }
    }

    /// The road surface's point queries (friction, edges, lanes) for this world.
    pub fn surface(&self) -> &Surface {
        &self.surface
    }

    /// The tyre friction coefficient each wheel of the ego vehicle gripped with in the last
    /// step (set from the piece under the wheel at the start of the step), in the order front
    /// right, front left, rear right, rear left; before the first step, the start piece's.
    pub fn ego_wheel_frictions(&self) -> Vec<f64> {
        self.ego.vehicle.wheel_frictions()
    }

    /// The size of the ego vehicle's body.
    pub fn ego_size(&self) -> Size {
        self.ego.vehicle.size()
    }

    /// The half extents of a car's collider along its length, height and width, metres, or
    /// `None` for a car not in this test (for checking that the drawing and the collider
    /// agree).
    pub fn car_collider_half_extents_m(&self, car: usize) -> Option<[f64; 3]> {
        let (_, c) = self.actors.cars.iter().nth(car)?;
        let (_, collider) = c.body?;
        let cuboid = self.physics.colliders[collider].shape().as_cuboid()?;
        let h = cuboid.half_extents;
        Some([f64::from(h.x), f64::from(h.y), f64::from(h.z)])
    }
}

/// The physics outputs the stream graph reads.
struct WorldInputs<'a> {
    physics: &'a PhysicsWorld,
    ego: &'a Ego,
    /// Whether the ego vehicle touches any actor.
    ego_touching: bool,
    actors: &'a Actors,
}

impl WorldInputs<'_> {
    /// Every solid object's collider where it is now ([`Simulation::solids`]).
    fn solids(&self) -> Solids {
        let mut solids = Solids::new();
        let ego = &self.physics.colliders[self.ego.vehicle.collider];
        solids.put(ActorRef::Ego, *ego.position(), ego.shared_shape().clone());
        self.actors.put_solids(self.physics, &mut solids);
        solids
    }

    /// The smallest distance from `me`'s `shape` at `pose` to every other solid, m (`0`
    /// while `touching`).
    fn separation(&self, me: ActorRef, shape: &dyn Shape, pose: &Pose, touching: bool) -> Value {
        if touching {
            return Value::Num(0.0);
        }
        Value::Num(self.solids().clearance_m(me, shape, pose))
    }
}

impl Inputs for WorldInputs<'_> {
    fn probe(&self, probe: Probe) -> Value {
        let me = probe.actor;
        // A disabled car is not in the test: its outputs have no events (it still moves
        // along its path unseen, which nothing reads).
        let (motion, contact, solid) = match me {
            ActorRef::Ego => {
                let c = &self.physics.colliders[self.ego.vehicle.collider];
                let contact = Contact {
                    touching: self.ego_touching,
                    collided: self.ego.collided,
                };
                let solid = Some((*c.position(), c.shared_shape().clone()));
                (self.ego.motion(self.physics), contact, solid)
            }
            other => {
                let Some(a) = self.actors.get(other) else {
                    return Value::Unit;
                };
                let Some(m) = a.motion() else {
                    return Value::Unit;
                };
                (m, a.contact(), a.solid(self.physics))
            }
        };
        match probe.output {
            Output::Pos => Value::Vec3(motion.pos_m),
            Output::Vel => Value::Vec3(motion.vel_mps),
            Output::Heading => Value::Num(motion.heading_rad),
            Output::Speed => Value::Num(motion.speed_mps),
            Output::Collision => Value::Bool(contact.touching),
            Output::Collided => Value::Bool(contact.collided),
            Output::Separation => match solid {
                Some((pose, shape)) => self.separation(me, shape.as_ref(), &pose, contact.touching),
                None => Value::Unit,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::network::PieceKind;
    use crate::rx::NoHost;
    use crate::{EgoSpec, Lane, LidarSpec, TriggeredPedestrian};

    fn spec() -> WorldSpec {
        WorldSpec::straight_road(
            200.0,
            10.0,
            5.0,
            &[TriggeredPedestrian {
                start: (Lane::Driving(1), 40.0),
                target: (Lane::Driving(1), 40.0),
                trigger_distance_m: 1e-6,
                speed_mps: 1.0,
            }],
        )
        .unwrap()
    }

    #[test]
    fn invalid_worlds_are_errors_naming_the_problem() {
        let mut sidewalk = spec();
        sidewalk.ego.start.lane = Lane::SideWalk;
        let cases: Vec<(WorldSpec, &str)> = vec![
            (
                WorldSpec {
                    dt_s: 0.0,
                    ..spec()
                },
                "time step",
            ),
            (sidewalk, "driving lane"),
            (
                WorldSpec {
                    ego: EgoSpec {
                        initial_speed_mps: -1.0,
                        ..spec().ego
                    },
                    ..spec()
                },
                "initial speed",
            ),
            (
                WorldSpec {
                    sensors: vec![crate::SensorSpec::Lidar(LidarSpec {
                        beams: 0,
                        ..LidarSpec::default()
                    })],
                    ..spec()
                },
                "lidar",
            ),
        ];
        for (s, needle) in cases {
            let err = Simulation::new(&s)
                .err()
                .expect("invalid world")
                .to_string();
            assert!(err.contains(needle), "{err}");
        }
        let bad_ped = WorldSpec::straight_road(
            200.0,
            10.0,
            5.0,
            &[TriggeredPedestrian {
                start: (Lane::SideWalk, 50.0),
                target: (Lane::OppositeSideWalk, 50.0),
                trigger_distance_m: 10.0,
                speed_mps: 0.0,
            }],
        );
        assert!(bad_ped.unwrap_err().to_string().contains("pedestrian 0"));
    }

    #[test]
    fn starts_at_its_lane_with_its_speed_and_the_lidar_sees_the_pedestrian() {
        let sim = Simulation::new(&spec()).unwrap();
        let ego = sim.ego_state();
        assert_eq!(ego.pos_m[0], 10.0);
        assert_eq!(ego.pos_m[2], 1.75);
        assert!((ego.speed_mps - 5.0).abs() < 1e-5);
        assert_eq!(ego.heading_rad, 0.0);
        let obs = sim.observation();
        assert_eq!(obs.readings.len(), 1, "the lidar alone");
        let ahead = obs
            .lidar()
            .iter()
            .filter(|r| r.point_m[2].abs() < 0.5)
            .map(|r| r.point_m[0])
            .reduce(f64::min)
            .expect("a return straight ahead");
        // Pedestrian centre 30 m ahead of the chassis centre, capsule radius 0.3 m.
        assert!((ahead - 29.7).abs() < 0.05, "nearest return at {ahead} m");
        let snap = sim.snapshot();
        assert!(!snap.ego_contact);
        // 30 m between centres, less half the car (2.25 m) and the capsule radius (0.3 m).
        assert!((snap.min_separation_m - 27.45).abs() < 0.05);
    }

    /// A sensor that reads nothing and gives no reach: with it mounted, no car ever sleeps.
    struct Unbounded;

    impl Sensor for Unbounded {
        fn name(&self) -> &'static str {
            "unbounded"
        }
        fn period_ticks(&self) -> u64 {
            u64::MAX
        }
        fn capture(&mut self, _: &crate::sensor::Scene<'_>) -> Result<(), EngineError> {
            Ok(())
        }
        fn reading(&self) -> Option<Reading<'_>> {
            None
        }
    }

    /// A 1 km road with the ego at 10 m and three NPC cars: one pulling away 355 m ahead in
    /// the ego's lane, one oncoming from 500 m in the other lane, one stopped 350 m ahead.
    fn with_cars() -> WorldSpec {
        let mut s = WorldSpec::straight_road(1000.0, 10.0, 12.0, &[]).unwrap();
        let mut nodes = s.streams.nodes().to_vec();
        let mut car = |from: f64, to: f64, z: f64, speed: f64| {
            nodes.push(crate::rx::Node::Const(Value::Num(speed)));
            crate::CarSpec {
                path: vec![[from, z], [to, z]],
                speed: StreamId(nodes.len() - 1),
                color: "red".into(),
                size: crate::Size::CAR,
                enabled: true,
                lane_change: None,
                lane_offsets_m: vec![],
                name: String::new(),
                keep_distance_m: None,
                tow: None,
            }
        };
        s.cars = vec![
            // Ahead of the stopped car (a car stops against what it meets).
            car(365.0, 1000.0, 1.75, 25.0),
            car(500.0, 0.0, -1.75, 10.0),
            car(360.0, 1000.0, 1.75, 0.0),
        ];
        s.streams = crate::rx::Graph::new(nodes).unwrap();
        s
    }

    #[test]
    fn a_partial_snapshot_leaves_out_only_what_it_was_told_to() {
        let spec = with_cars();
        let mut sim = Simulation::new(&spec).unwrap();
        let control = Control {
            throttle: 0.3,
            steering: 0.0,
        };
        let mut closing = 0;
        for _ in 0..600 {
            sim.step(control, &mut NoHost).unwrap();
            sim.evaluate(&mut NoHost).unwrap();
            let full = sim.snapshot();
            let none = sim.snapshot_of(SnapshotParts {
                ttc: false,
                lane_offset: false,
            });
            assert!(none.ttc_s.is_nan() && none.ego_lane_offset_m.is_nan());
            let filled = Snapshot {
                ttc_s: full.ttc_s,
                ego_lane_offset_m: full.ego_lane_offset_m,
                ..none
            };
            assert_eq!(format!("{full:?}"), format!("{filled:?}"));
            let ttc_only = sim.snapshot_of(SnapshotParts {
                ttc: true,
                lane_offset: false,
            });
            assert_eq!(ttc_only.ttc_s.to_bits(), full.ttc_s.to_bits());
            closing += usize::from(full.ttc_s.is_finite());
        }
        assert!(
            closing > 0,
            "the stopped car ahead gives a finite time to collision"
        );
    }

    #[test]
    fn far_cars_sleep_out_of_the_physics_step_and_nothing_observed_changes() {
        let spec = with_cars();
        let mut sleepy = Simulation::new(&spec).unwrap();
        let mut awake = Simulation::new(&spec).unwrap();
        awake.mount(Box::new(Unbounded)).unwrap();
        let (mut asleep_steps, mut woke, mut was_asleep) = (0, 0, vec![false; 3]);
        let (mut seen_oncoming, mut seen_asleep) = (false, 0);
        // 30 s at a steady throttle: the first car leaves the lidar's reach, the oncoming one
        // enters it, passes and leaves, and the ego closes on the stopped one.
        for _ in 0..1800 {
            let control = Control {
                throttle: 0.2,
                steering: 0.0,
            };
            sleepy.step(control, &mut NoHost).unwrap();
            awake.step(control, &mut NoHost).unwrap();
            assert_eq!(
                format!("{:?}", sleepy.snapshot()),
                format!("{:?}", awake.snapshot())
            );
            assert_eq!(sleepy.observation().lidar(), awake.observation().lidar());
            let oncoming_seen = sleepy
                .observation()
                .lidar()
                .iter()
                .any(|r| r.point_m[2] < -2.5);
            seen_oncoming |= oncoming_seen;
            // The lidar sees an asleep car where it would be awake.
            let oncoming = sleepy.actors.cars.values().nth(1).unwrap();
            seen_asleep += usize::from(oncoming_seen && oncoming.is_asleep(&sleepy.physics));
            for (i, car) in sleepy.actors.cars.values().enumerate() {
                let asleep = car.is_asleep(&sleepy.physics);
                asleep_steps += usize::from(asleep);
                woke += usize::from(was_asleep[i] && !asleep);
                was_asleep[i] = asleep;
                let (_, collider) = car.body.unwrap();
                if !asleep {
                    // An awake car's collider is where the car says it is, bit for bit.
                    assert_eq!(*sleepy.physics.colliders[collider].position(), car.pose());
                }
            }
            assert!(awake
                .actors
                .cars
                .values()
                .all(|c| !c.is_asleep(&awake.physics)));
        }
        assert!(asleep_steps > 1000, "{asleep_steps}");
        assert!(woke >= 2, "{woke}");
        assert!(seen_oncoming);
        assert!(seen_asleep > 60, "{seen_asleep}");
    }

    #[test]
    fn one_compound_road_gives_the_bits_of_separate_colliders() {
        // A segment, a cross junction, a segment, a T junction, a segment: 11 road shapes in
        // one compound. The ego drives through both junctions with a little steering, so its
        // wheels cross from slab to slab, and passes a car stopped in the other lane.
        let mut n = Network::new();
        let seg = |n: &mut Network, name: &str| {
            n.add(
                name,
                PieceKind::Segment {
                    length_m: 60.0,
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap()
        };
        let a = seg(&mut n, "a");
        let x = n
            .add(
                "x",
                PieceKind::CrossIntersection {
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap();
        let b = seg(&mut n, "b");
        let t = n
            .add(
                "t",
                PieceKind::TIntersection {
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap();
        let c = seg(&mut n, "c");
        n.connect(a, 1, x, 2).unwrap();
        n.connect(x, 0, b, 0).unwrap();
        n.connect(b, 1, t, 2).unwrap();
        n.connect(t, 0, c, 0).unwrap();
        // Then a bend: its slices stay colliders of their own either way.
        let ease = n
            .add(
                "ease",
                PieceKind::Clothoid {
                    length_m: 30.0,
                    curv_start: 0.0,
                    curv_end: 1.0 / 60.0,
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap();
        n.connect(c, 1, ease, 0).unwrap();
        let mut spec = with_cars();
        spec.ego.start = n.on_lane(a, Lane::Driving(1), 10.0).unwrap();
        let far = n.on_lane(c, Lane::Driving(-1), 40.0).unwrap().pos_m;
        spec.cars.truncate(1);
        spec.cars[0].path = vec![[far[0], far[2]], [far[0] + 50.0, far[2]]];
        let stopped = spec.cars[0].speed;
        let mut nodes = spec.streams.nodes().to_vec();
        nodes[stopped.0] = crate::rx::Node::Const(Value::Num(0.0));
        spec.streams = crate::rx::Graph::new(nodes).unwrap();
        spec.network = n;
        let compound = Simulation::new(&spec).unwrap();
        crate::network::SEPARATE_ROAD.with(|s| s.set(true));
        let separate = Simulation::new(&spec).unwrap();
        crate::network::SEPARATE_ROAD.with(|s| s.set(false));
        assert_eq!(
            compound.physics.colliders.len() + 10,
            separate.physics.colliders.len()
        );
        let (mut compound, mut separate) = (compound, separate);
        for k in 0..1500 {
            let control = Control {
                throttle: 0.4,
                steering: 0.02 * ((k as f64) * 0.01).sin(),
            };
            compound.step(control, &mut NoHost).unwrap();
            separate.step(control, &mut NoHost).unwrap();
            assert_eq!(
                format!("{:?}", compound.snapshot()),
                format!("{:?}", separate.snapshot()),
                "step {k}"
            );
            assert_eq!(
                compound.observation().lidar(),
                separate.observation().lidar()
            );
        }
        // The ego crossed both junctions and reached the bend.
        assert!(
            compound.ego_state().pos_m[0] > 260.0,
            "{:?}",
            compound.ego_state()
        );
    }

    #[test]
    fn time_advances_by_whole_steps() {
        let mut sim = Simulation::new(&spec()).unwrap();
        for _ in 0..60 {
            sim.step(Control::default(), &mut NoHost).unwrap();
        }
        assert!((sim.t_s() - 1.0).abs() < 1e-12);
        assert_eq!(sim.snapshot().t_s, sim.t_s());
    }

    #[test]
    fn constant_inputs_are_read_once_and_streams_each_step() {
        let s = spec();
        let sim = Simulation::new(&s).unwrap();
        // The study's light, fog and walking speed are constants: known when the world is
        // built, never read back from the graph.
        assert!(matches!(
            sim.light_fog_inputs,
            (Input::Const(_), Input::Const(_))
        ));
        let walker = sim.actors.pedestrians.values().next().unwrap();
        assert_eq!(walker.speed_stream, Input::Const(1.0));
        // A light that varies over the test stays a stream, read each step.
        let mut nodes = s.streams.nodes().to_vec();
        nodes[s.environment.light.0] = crate::rx::Node::Tick;
        let varying = crate::rx::Graph::new(nodes).unwrap();
        assert_eq!(
            Input::of(&varying, s.environment.light),
            Input::Stream(s.environment.light)
        );
        // A constant that is no finite number is read each step, and refused there.
        let nan =
            crate::rx::Graph::new(vec![crate::rx::Node::Const(Value::Num(f64::NAN))]).unwrap();
        assert_eq!(Input::of(&nan, StreamId(0)), Input::Stream(StreamId(0)));
    }

    #[test]
    fn fog_shortens_the_lidar_range() {
        let mut s = spec();
        let mut nodes = s.streams.nodes().to_vec();
        // Fog 1: visibility 7.8 m, so the pedestrian 30 m ahead disappears from the scan.
        nodes[s.environment.fog.0] = crate::rx::Node::Const(Value::Num(1.0));
        s.streams = crate::rx::Graph::new(nodes).unwrap();
        let mut sim = Simulation::new(&s).unwrap();
        sim.step(Control::default(), &mut NoHost).unwrap();
        assert_eq!(sim.snapshot().fog, 1.0);
        assert!(sim.observation().lidar().iter().all(|r| r.range_m < 7.9));
    }
}
