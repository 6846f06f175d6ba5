//! The simulation core of paracosm: a `rapier3d` world with a straight road, a physical ego
//! vehicle (rapier's ray-cast vehicle controller), kinematic pedestrians, a ray-cast lidar, and
//! the systems under test that drive the ego vehicle.
//!
//! Frame of reference (right-handed, SI units): `x` runs along the road in the driving direction
//! of the positive lanes, `y` points up, `z` points to the right of a driver on a positive lane.
//! Headings are in radians, counter-clockwise seen from above, `0` along `+x`.
//!
//! The physics runs at a fixed step ([`DEFAULT_DT_S`], 1/60 s) with rapier's
//! `enhanced-determinism` feature, so a world built from the same [`WorldSpec`] evolves
//! bit-identically on every run, thread and CPU.
#![warn(missing_docs)]

mod control;
mod error;
mod lidar;
mod pedestrian;
mod road;
pub mod rx;
mod sim;
mod spec;
pub mod sut;
mod vehicle;

pub use control::Control;
pub use error::EngineError;
pub use lidar::{LidarReturn, LidarSpec};
pub use pedestrian::{PedestrianPhase, PedestrianState};
pub use road::{Lane, RoadSegment};
pub use sim::{EgoState, Observation, Simulation, Snapshot};
pub use spec::{EgoSpec, PedestrianSpec, RoadSpec, WorldSpec, DEFAULT_DT_S};
pub use vehicle::VehicleParams;
