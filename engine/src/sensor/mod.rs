//! Sensors on the ego vehicle, behind one trait: the ray-cast lidar ([`lidar`]) and the camera
//! ([`camera`], rendered with the feature `render`). A world lists the sensors it mounts with
//! their settings ([`crate::WorldSpec::sensors`], [`SensorSpec`]); a simulation keeps them in
//! a [`Set`] and captures each at its rate; a system under test gets their readings in its
//! [`crate::Observation`], by the sensor's name ([`crate::Observation::reading`]), and an
//! external one receives each as named arrays (SUT_PROTOCOL.md).
//!
//! A new configured sensor is its own file in this folder (its settings, and a type
//! implementing [`Sensor`] whose reading is [`Reading::Arrays`], the named arrays
//! SUT_PROTOCOL.md sends), its `mod` line and its variant of [`SensorSpec`] (this file), and a
//! paragraph in SUT_PROTOCOL.md: three files.

pub mod camera;
pub mod lidar;

use rapier3d::prelude::*;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::actor::{Set, VisibleBox};
use crate::network::Network;
use crate::{CameraFrame, CameraSpec, EgoState, EngineError, LidarReturn, LidarSpec, RateError};

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
    /// Whether it captures once more just before the first physics step, when the stream
    /// graph has given light and fog (its reading when it was mounted was taken before they
    /// were known). Default false; the lidar: true.
    fn recaptures_before_first_step(&self) -> bool {
        false
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

/// A sensor setting out of its documented range ([`SensorSpec::validate`]); the message
/// names the setting and its value.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SettingError {
    /// A lidar without a channel or without a beam ([`LidarSpec::channels`],
    /// [`LidarSpec::beams`]).
    #[error("lidar needs at least one channel and one beam")]
    LidarWithoutBeams,
    /// A lidar range, rate or horizontal field of view that is not positive and finite.
    #[error("lidar range, rate and horizontal field of view must be positive")]
    LidarNotPositive,
    /// A lidar horizontal field of view over 2π, in rad.
    #[error("lidar horizontal field of view {0} rad is more than a full turn (2π)")]
    LidarOverFullTurn(f64),
    /// A lidar vertical field of view outside `[0, π]`, in rad.
    #[error("lidar vertical field of view {0} rad is not in [0, π]")]
    LidarVertical(f64),
    /// A camera image size outside `1..=4096` pixels, width × height.
    #[error("camera resolution {width}x{height} is outside 1..=4096")]
    CameraResolution {
        /// Width asked for, pixels.
        width: u32,
        /// Height asked for, pixels.
        height: u32,
    },
    /// A camera setting outside its range ([`CameraSpec`]'s fields), or not finite.
    #[error("camera {name} {value} is out of range")]
    CameraOutOfRange {
        /// The setting: `focal_mm`, `pitch_rad`, `rate_hz`, `noise_sigma`, `blur_sigma_px`,
        /// `far_m`, `mount_m`.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A rate that is not a whole number of physics steps per period.
    #[error(transparent)]
    Rate(#[from] RateError),
}

/// A sensor a world mounts on its ego vehicle ([`crate::WorldSpec::sensors`]), with its
/// settings. In JSON, externally tagged: `{"lidar": {...}}`, `{"camera": {...}}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorSpec {
    /// The ray-cast lidar, named `lidar` in observations.
    Lidar(LidarSpec),
    /// A camera (RGB, depth and labels; feature `render`), named `camera` in observations.
    /// Mounted from the world, its pixel noise has the seed 0; a system under test's camera,
    /// seeded per test, is mounted by [`crate::Simulation::attach_camera`].
    Camera(CameraSpec),
}

impl SensorSpec {
    /// The sensors a world mounts unless it says otherwise: the lidar, with its default
    /// settings ([`LidarSpec::default`]).
    pub fn defaults() -> Vec<SensorSpec> {
        vec![SensorSpec::Lidar(LidarSpec::default())]
    }

    /// Checks the ranges its settings document.
    ///
    /// # Errors
    /// A [`SettingError`] naming the first value out of range ([`LidarSpec`],
    /// [`CameraSpec::validate`]).
    pub fn validate(&self) -> Result<(), SettingError> {
        match self {
            SensorSpec::Lidar(spec) => spec.validate(),
            SensorSpec::Camera(spec) => spec.validate(),
        }
    }

    /// The sensor, for a world on `network` whose physics step is `dt_s` seconds.
    ///
    /// # Errors
    /// [`EngineError::Sensor`] when it cannot be set up (a camera without a GPU adapter, or in
    /// a build without the `render` feature).
    fn build(&self, network: &Network, dt_s: f64) -> Result<Box<dyn Sensor>, EngineError> {
        match self {
            SensorSpec::Lidar(spec) => Ok(Box::new(lidar::Lidar::new(spec, dt_s))),
            SensorSpec::Camera(spec) => {
                camera::sensor(network, spec, camera::FrameUse::ALL, 0, dt_s)
            }
        }
    }
}

/// The sensors every simulation of `spec` mounts: those of [`crate::WorldSpec::sensors`], in
/// their order. (A system under test's camera is mounted when it asks for one,
/// [`crate::Simulation::attach_camera`].)
///
/// # Errors
/// As [`SensorSpec`]'s sensors are set up: [`EngineError::Sensor`].
pub fn mounted(spec: &crate::WorldSpec) -> Result<Sensors, EngineError> {
    let mut sensors = Sensors::default();
    for s in &spec.sensors {
        sensors.insert(s.build(&spec.network, spec.dt_s)?);
    }
    Ok(sensors)
}
