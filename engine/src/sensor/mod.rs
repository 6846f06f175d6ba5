//! Sensors on the ego vehicle, behind one trait: the ray-cast lidar ([`crate::LidarSpec`]) and
//! the camera (feature `render`). A simulation keeps its sensors in a [`Set`] and captures
//! each at its rate; a system under test gets their readings in its
//! [`crate::Observation`], and an external one receives each as named arrays
//! (SUT_PROTOCOL.md).
//!
//! A new sensor is its own file in this folder implementing [`Sensor`] (its reading is
//! [`Reading::Arrays`], the named arrays SUT_PROTOCOL.md sends), a `mod` line and its
//! registration in [`mounted`] (this file), and a paragraph in SUT_PROTOCOL.md: three files.

pub(crate) mod lidar;

use rapier3d::prelude::*;

use crate::actor::{Set, VisibleBox};
use crate::{CameraFrame, EgoState, EngineError, LidarReturn};

/// What a sensor sees the world through when it captures.
pub struct Scene<'a> {
    /// The physics world (ray casts, colliders).
    pub physics: &'a PhysicsWorld,
    /// The ego vehicle's body (a sensor's own body, for ray casts to skip).
    pub ego_body: RigidBodyHandle,
    /// The ego vehicle's state.
    pub ego: EgoState,
    /// Light now, `[0, 1]`.
    pub light: f64,
    /// Fog now, `[0, 1]`.
    pub fog: f64,
    /// Time since the start, s.
    pub t_s: f64,
    /// The boxes a camera draws (cars, pedestrians, obstacles).
    pub boxes: &'a [VisibleBox],
    /// The colliders of [`Scene::physics`] taken out of the physics step (NPC cars asleep:
    /// disabled, and left where they fell asleep), each with the pose it would have awake.
    /// A sensor that casts into the physics world sees them there ([`Sensor::physics_reach_m`]).
    pub asleep: &'a [(ColliderHandle, Pose)],
}

/// A sensor's last reading.
#[derive(Debug, Clone, Copy)]
pub enum Reading<'a> {
    /// Lidar returns, in the vehicle frame.
    Lidar(&'a [LidarReturn]),
    /// A camera frame: RGB and depth.
    Camera(&'a CameraFrame),
    /// Named arrays: the reading of a sensor with no variant of its own, as the protocol
    /// sends it; systems in process read them by name.
    Arrays(&'a [Payload]),
}

/// One named array of a reading, as SUT_PROTOCOL.md sends it.
#[derive(Debug, Clone, PartialEq)]
pub struct Payload {
    /// Its name in the protocol: `camera`, `depth`, `lidar`.
    pub name: &'static str,
    /// Element type: `uint8` or `float32`.
    pub dtype: &'static str,
    /// Shape, row-major.
    pub shape: Vec<usize>,
    /// The bytes, little-endian.
    pub bytes: Vec<u8>,
    /// Simulated time the reading was taken, s, when the protocol sends it (a camera frame).
    pub t_s: Option<f64>,
}

impl Reading<'_> {
    /// Its arrays for an external system: a camera sends `camera` (h × w × 3, uint8) and,
    /// with `depth`, `depth` (h × w, float32 metres); a lidar sends `lidar` (n × 3, float32,
    /// points in the vehicle frame, metres).
    pub fn payloads(&self, depth: bool) -> Vec<Payload> {
        match self {
            Reading::Camera(frame) => {
                let (h, w) = (frame.height as usize, frame.width as usize);
                let mut out = vec![Payload {
                    name: "camera",
                    dtype: "uint8",
                    shape: vec![h, w, 3],
                    bytes: frame.rgb.clone(),
                    t_s: Some(frame.t_s),
                }];
                if depth {
                    out.push(Payload {
                        name: "depth",
                        dtype: "float32",
                        shape: vec![h, w],
                        bytes: frame.depth_m.iter().flat_map(|d| d.to_le_bytes()).collect(),
                        t_s: None,
                    });
                }
                out
            }
            Reading::Lidar(returns) => vec![Payload {
                name: "lidar",
                dtype: "float32",
                shape: vec![returns.len(), 3],
                bytes: returns
                    .iter()
                    .flat_map(|r| r.point_m.map(|v| v as f32))
                    .flat_map(f32::to_le_bytes)
                    .collect(),
                t_s: None,
            }],
            Reading::Arrays(arrays) => arrays.to_vec(),
        }
    }
}

/// A sensor mounted on the ego vehicle.
pub trait Sensor: Send {
    /// Its name in observations and in SUT_PROTOCOL.md: `lidar`, `camera`.
    fn name(&self) -> &'static str;
    /// Every how many physics steps it captures, `>= 1`.
    fn period_ticks(&self) -> u64;
    /// Whether it needs [`Scene::boxes`] (a camera draws them; a lidar casts rays instead).
    /// Default false.
    fn draws(&self) -> bool {
        false
    }
    /// How far from the ego chassis centre, in metres, this sensor can sense an NPC car's
    /// collider through [`Scene::physics`] alone. An NPC car farther than every sensor's
    /// reach, and too far to touch the ego, is taken out of the physics step until it comes
    /// nearer (its body and collider disabled; [`crate::Simulation::step`]), so a sensor that
    /// reads the physics world must not under-state this. Default: unbounded (no car is ever
    /// taken out). A sensor that sees the cars taken out where [`Scene::asleep`] puts them, as
    /// the lidar does, or that draws [`Scene::boxes`] instead, as a camera does: 0.
    fn physics_reach_m(&self) -> f64 {
        f64::INFINITY
    }
    /// Captures a reading of `scene`.
    ///
    /// # Errors
    /// [`EngineError::Sensor`] when the device fails (the GPU for a camera).
    fn capture(&mut self, scene: &Scene<'_>) -> Result<(), EngineError>;
    /// Its last reading, `None` before its first capture.
    fn reading(&self) -> Option<Reading<'_>>;
}

/// The sensors of one simulation.
pub type Sensors = Set<Box<dyn Sensor>>;

/// The sensors every simulation of `spec` mounts: the lidar. (A camera is mounted when a
/// system under test asks for one, [`crate::Simulation::attach_camera`].) A new sensor is
/// registered here.
pub fn mounted(spec: &crate::WorldSpec) -> Sensors {
    let mut sensors = Sensors::default();
    sensors.insert(Box::new(lidar::Lidar::new(&spec.lidar, spec.dt_s)));
    sensors
}
