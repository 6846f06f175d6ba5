use serde::{Deserialize, Serialize};

use super::{Sut, SutError};
use crate::{Control, Observation};

/// Settings of the built-in [`Aeb`] system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AebConfig {
    /// Cruise speed in m/s. Default 12 m/s (43 km/h).
    pub target_speed_mps: f64,
    /// Cruise control gain: throttle per m/s of speed error. Default 0.5.
    pub speed_gain: f64,
    /// Half-width of the corridor ahead in which lidar returns count as obstacles, in metres,
    /// measured from the vehicle's axis. Default 1.3 m (half the car's width plus 0.4 m).
    pub corridor_half_width_m: f64,
    /// Time headway that triggers braking, in seconds: brake at full force when the gap to the
    /// nearest obstacle, less `standstill_gap_m`, is shorter than `speed · ttc_brake_s`, i.e.
    /// when the time to collision at the current speed drops below it. Default 1.4 s.
    pub ttc_brake_s: f64,
    /// Gap kept to an obstacle when stopped, in metres. Default 2 m.
    pub standstill_gap_m: f64,
    /// Distance from the chassis centre to the front bumper, in metres. Default 2.25 m.
    pub front_offset_m: f64,
    /// Returns lower than this, in metres relative to the chassis centre (`y` of the vehicle
    /// frame), are ground clutter and ignored. Default -0.6 m (about 0.25 m above the road).
    pub min_height_m: f64,
    /// Lane keeping: steering per metre of lateral offset from the start line. Default 0.1.
    pub lateral_gain: f64,
    /// Lane keeping: steering per radian of heading error. Default 1.0.
    pub heading_gain: f64,
}

impl Default for AebConfig {
    fn default() -> Self {
        AebConfig {
            target_speed_mps: 12.0,
            speed_gain: 0.5,
            corridor_half_width_m: 1.3,
            ttc_brake_s: 1.4,
            standstill_gap_m: 2.0,
            front_offset_m: 2.25,
            min_height_m: -0.6,
            lateral_gain: 0.1,
            heading_gain: 1.0,
        }
    }
}

/// `aeb`: a cruise controller with automatic emergency braking.
///
/// Each step it keeps the lane it started in (proportional control on lateral offset and
/// heading from odometry), and looks for lidar returns inside its corridor ahead. With `g` the
/// gap from the bumper to the nearest such return and `v` the speed, it brakes at full force
/// when `g - standstill_gap_m < v · ttc_brake_s` (time to collision below `ttc_brake_s`, a
/// static-obstacle assumption), and otherwise tracks `target_speed_mps`. It sees only what the
/// lidar sees: a pedestrian outside the corridor, or one that enters it too late, is not
/// avoided. That is the failure the pedestrian-crossing study looks for.
#[derive(Debug, Clone)]
pub struct Aeb {
    config: AebConfig,
    /// Start pose `(x, z, heading)`, the line lane keeping follows.
    line: Option<(f64, f64, f64)>,
}

impl Aeb {
    /// An `aeb` system with the given settings.
    pub fn new(config: AebConfig) -> Self {
        Aeb { config, line: None }
    }

    /// Gap in metres from the bumper to the nearest return in the corridor, if any.
    pub fn nearest_gap_m(&self, obs: &Observation<'_>) -> Option<f64> {
        let c = &self.config;
        obs.lidar
            .iter()
            .filter(|r| {
                r.point_m[0] > 0.0
                    && r.point_m[2].abs() <= c.corridor_half_width_m
                    && r.point_m[1] >= c.min_height_m
            })
            .map(|r| r.point_m[0] - c.front_offset_m)
            .reduce(f64::min)
    }
}

impl Sut for Aeb {
    fn reset(&mut self, _seed: u64) -> Result<(), SutError> {
        self.line = None;
        Ok(())
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let c = &self.config;
        let ego = obs.ego;
        let (x0, z0, h0) = *self
            .line
            .get_or_insert((ego.pos_m[0], ego.pos_m[2], ego.heading_rad));
        // Lateral offset to the right of the start line, in the start heading's frame.
        let (dx, dz) = (ego.pos_m[0] - x0, ego.pos_m[2] - z0);
        let right = dz * h0.cos() + dx * h0.sin();
        let heading_err = (ego.heading_rad - h0 + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        let steering = c.lateral_gain * right - c.heading_gain * heading_err;

        let v = ego.speed_mps.max(0.0);
        let brake = self
            .nearest_gap_m(obs)
            .is_some_and(|gap| gap - c.standstill_gap_m < v * c.ttc_brake_s);
        let throttle = if brake {
            -1.0
        } else {
            c.speed_gain * (c.target_speed_mps - ego.speed_mps)
        };
        Ok(Control { throttle, steering }.clamped())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EgoState, LidarReturn};

    fn obs(speed: f64, returns: &[[f64; 3]]) -> (EgoState, Vec<LidarReturn>) {
        let ego = EgoState {
            pos_m: [0.0, 0.85, 1.75],
            heading_rad: 0.0,
            speed_mps: speed,
        };
        let lidar = returns
            .iter()
            .map(|&p| LidarReturn {
                azimuth_rad: 0.0,
                elevation_rad: 0.0,
                range_m: p[0],
                point_m: p,
            })
            .collect();
        (ego, lidar)
    }

    fn act(speed: f64, returns: &[[f64; 3]]) -> Control {
        let (ego, lidar) = obs(speed, returns);
        let mut aeb = Aeb::new(AebConfig::default());
        aeb.act(&Observation {
            t_s: 0.0,
            dt_s: 1.0 / 60.0,
            ego,
            lidar: &lidar,
        })
        .unwrap()
    }

    #[test]
    fn brakes_when_time_to_collision_is_short() {
        // gap 10 m, 12 m/s: 10 - 2 < 12 · 1.4
        assert_eq!(act(12.0, &[[12.25, 0.1, 0.0]]).throttle, -1.0);
        // gap 40 m: 38 > 16.8, so it cruises
        assert!(act(12.0, &[[42.25, 0.1, 0.0]]).throttle >= 0.0);
    }

    #[test]
    fn ignores_returns_outside_the_corridor_and_ground_hits() {
        assert!(act(12.0, &[[10.0, 0.1, 2.0]]).throttle >= 0.0);
        assert!(act(12.0, &[[10.0, -0.8, 0.0]]).throttle >= 0.0);
    }

    #[test]
    fn holds_the_brake_at_standstill_close_to_an_obstacle() {
        assert_eq!(act(0.0, &[[3.5, 0.1, 0.0]]).throttle, -1.0);
        // and drives off once the way is clear
        assert!(act(0.0, &[]).throttle > 0.0);
    }
}
