//! The simulation core of paracosm: the reactive stream runtime, road networks, a `rapier3d`
//! world with a physical ego vehicle (rapier's ray-cast vehicle controller), kinematic
//! pedestrians and NPC cars, a ray-cast lidar, a `wgpu` camera (RGB and depth, feature
//! `render`, on by default), and the systems under test that drive the ego vehicle.
//!
//! CameraFrame of reference (right-handed, SI units): `x` runs along the road in the driving direction
//! of the positive lanes, `y` points up, `z` points to the right of a driver on a positive lane.
//! Headings are in radians, counter-clockwise seen from above, `0` along `+x`.
//!
//! The physics runs at a fixed step ([`DEFAULT_DT_S`], 1/60 s) with rapier's
//! `enhanced-determinism` feature, so a world built from the same [`WorldSpec`] evolves
//! bit-identically on every run, thread and CPU.
#![warn(missing_docs)]

pub mod actor;
mod actors;
pub mod behaviour;
mod car;
pub mod colour;
mod contact;
mod control;
mod ego;
mod environment;
mod error;
pub mod files;
pub mod memory;
pub mod network;
mod obstacle;
mod pedestrian;
mod physics_step;
pub mod placement;
#[cfg(feature = "render")]
pub mod render;
pub mod rx;
pub mod segmentation;
pub mod sensor;
mod sim;
#[cfg(feature = "render")]
mod simd;
mod spec;
pub mod sut;
pub mod transition;
pub mod ttc;
mod vehicle;

pub use actor::{Handle, Set, Size, VisibleBox};
pub use car::{CarState, LaneChangeSpec, LaneChangeStart};
pub use control::Control;
pub use ego::EgoState;
pub use environment::{visibility_m, FOG_EXTINCTION_PER_M, NOMINAL_LIGHT};
pub use error::{EngineError, RateError};
pub use network::{Lane, Location, Network, PieceId, PieceKind};
pub use obstacle::ObstacleState;
pub use pedestrian::{PedestrianPhase, PedestrianState};
pub use segmentation::{ObjectBox, SemanticClass};
pub use sensor::camera::{
    BackProjector, CameraFrame, CameraSpec, FrameUse, SavePngError, SENSOR_HEIGHT_MM,
    SENSOR_WIDTH_MM,
};
pub use sensor::lidar::{LidarReturn, LidarSpec};
pub use sensor::{SensorSpec, SettingError};
pub use sim::{Observation, Simulation, Snapshot, SnapshotParts};
pub use spec::{
    CarSpec, EgoSpec, EnvironmentSpec, ObstacleSpec, PedestrianSpec, TriggeredPedestrian,
    WorldSpec, DEFAULT_DT_S,
};
pub use vehicle::{VehicleParams, EGO_SIZE_RANGE_M, GROUND_CLEARANCE_M};

/// The physics steps of `dt_s` seconds between two events of a rate of `hz` per simulated
/// second (`name` in messages), which must be a whole number `k >= 1`: `hz = 1 / (k · dt_s)`
/// (at 60 Hz: 60, 30, 20, 15, 12, 10, 7.5, 6, 5, ...), to a relative 1e-9.
///
/// # Errors
/// A [`RateError`] naming the rate and the nearest rates that are whole steps, for a rate that
/// is not positive and finite, faster than the step, or between two whole periods (25 Hz ran
/// as 30 Hz, 7 Hz as 6.67 Hz, 1,000 Hz as 60 Hz, each without a word).
pub fn steps_per_period(name: &str, hz: f64, dt_s: f64) -> Result<u64, RateError> {
    let steps = 1.0 / (hz * dt_s);
    let k = steps.round();
    if hz.is_finite() && hz > 0.0 && k >= 1.0 && (steps - k).abs() <= 1e-9 * k {
        return Ok(k as u64);
    }
    let step_hz = 1.0 / dt_s;
    let near: Vec<f64> = [steps.floor(), steps.ceil()]
        .into_iter()
        .filter(|k| k.is_finite() && *k >= 1.0)
        .map(|k| step_hz / k)
        .collect();
    Err(RateError {
        name: name.to_owned(),
        hz,
        step_hz,
        near,
    })
}
