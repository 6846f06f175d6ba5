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
pub mod behaviour;
mod camera;
mod car;
pub mod colour;
mod control;
mod environment;
mod error;
pub mod network;
mod obstacle;
mod pedestrian;
pub mod placement;
#[cfg(feature = "render")]
pub mod render;
pub mod rx;
pub mod segmentation;
pub mod sensor;
mod sim;
mod spec;
pub mod sut;
pub mod ttc;
mod vehicle;

pub use actor::{Handle, Set, Size, VisibleBox};
pub use camera::{CameraFrame, CameraSpec, SENSOR_HEIGHT_MM, SENSOR_WIDTH_MM};
pub use car::{CarState, LaneChangeSpec, LaneChangeStart};
pub use control::Control;
pub use environment::{visibility_m, FOG_EXTINCTION_PER_M, NOMINAL_LIGHT};
pub use error::EngineError;
pub use network::{Lane, Location, Network, PieceId, PieceKind};
pub use obstacle::ObstacleState;
pub use pedestrian::{PedestrianPhase, PedestrianState};
pub use segmentation::{ObjectBox, SemanticClass};
pub use sensor::lidar::{LidarReturn, LidarSpec};
pub use sim::{EgoState, Observation, Simulation, Snapshot, SnapshotParts};
pub use spec::{
    CarSpec, EgoSpec, EnvironmentSpec, ObstacleSpec, PedestrianSpec, TriggeredPedestrian,
    WorldSpec, DEFAULT_DT_S,
};
pub use vehicle::VehicleParams;
