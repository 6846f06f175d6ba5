use serde::{Deserialize, Serialize};

use crate::{Lane, LidarSpec, VehicleParams};

/// The default physics step: 1/60 s (rapier's own default).
pub const DEFAULT_DT_S: f64 = 1.0 / 60.0;

/// A straight road segment along `+x`, starting at `x = 0` (paper §2, `RoadSegment`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoadSpec {
    /// Length along `x`, in metres, `> 0`. Default 200 m (the paper's example).
    pub length_m: f64,
    /// Number of driving lanes, even and `>= 2`: half drive along `+x` (lanes `1..=n/2`, right
    /// of the centre line), half along `-x` (lanes `-1..=-n/2`). Default 2.
    pub lanes: u32,
    /// Width of one lane, in metres. Default 3.5 m.
    pub lane_width_m: f64,
    /// Width of each of the two sidewalks, in metres. Default 2.0 m.
    pub sidewalk_width_m: f64,
    /// Tyre–road friction coefficient, dimensionless, in `(0, 2]`. Default 0.8 (dry asphalt).
    /// rapier's vehicle controller ignores collider friction, so this becomes each wheel's
    /// `friction_slip`.
    pub friction: f64,
}

impl Default for RoadSpec {
    fn default() -> Self {
        RoadSpec {
            length_m: 200.0,
            lanes: 2,
            lane_width_m: 3.5,
            sidewalk_width_m: 2.0,
            friction: 0.8,
        }
    }
}

/// The ego vehicle: where it starts and how it is built.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EgoSpec {
    /// The lane it starts on (a driving lane).
    pub lane: Lane,
    /// Start position along the road, in metres from `x = 0`.
    pub at_m: f64,
    /// Initial forward speed in m/s, `>= 0`.
    pub initial_speed_mps: f64,
    /// Mass, dimensions and actuator limits.
    pub vehicle: VehicleParams,
}

/// A pedestrian that waits at `start`, and walks in a straight line to `target` at `speed_mps`
/// once the ego vehicle comes within `trigger_distance_m` of `start` (paper §2, "Reactive
/// Behaviors": `tick.skipUntil(trigger).takeUntil(done).foreach(walk)`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PedestrianSpec {
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

/// Everything needed to build a [`crate::Simulation`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorldSpec {
    /// Physics step in seconds, `> 0`. Default [`DEFAULT_DT_S`].
    pub dt_s: f64,
    /// The road.
    pub road: RoadSpec,
    /// The ego vehicle.
    pub ego: EgoSpec,
    /// The pedestrians, in order.
    pub pedestrians: Vec<PedestrianSpec>,
    /// The ego vehicle's lidar.
    pub lidar: LidarSpec,
}
