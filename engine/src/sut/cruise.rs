use serde::{Deserialize, Serialize};

/// Cruise control with emergency braking on time to collision: the longitudinal rule that
/// `aeb` and `vision` share (they differ in how they find the obstacle).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Cruise {
    /// Cruise speed in m/s. Default 12 m/s (43 km/h).
    pub target_speed_mps: f64,
    /// Cruise control gain: throttle per m/s of speed error. Default 0.5.
    pub speed_gain: f64,
    /// Half-width of the corridor ahead in which obstacles count, in metres, measured from the
    /// vehicle's axis. Default 1.3 m (half the car's width plus 0.4 m).
    pub corridor_half_width_m: f64,
    /// Time headway that triggers braking, in seconds: brake at full force when the gap to the
    /// nearest obstacle, less `standstill_gap_m`, is shorter than `speed · ttc_brake_s`, i.e.
    /// when the time to collision at the current speed drops below it. Default 1.4 s.
    pub ttc_brake_s: f64,
    /// Gap kept to an obstacle when stopped, in metres. Default 2 m.
    pub standstill_gap_m: f64,
    /// Distance from the chassis centre to the front bumper, in metres. Default 2.25 m.
    pub front_offset_m: f64,
}

impl Default for Cruise {
    fn default() -> Self {
        Cruise {
            target_speed_mps: 12.0,
            speed_gain: 0.5,
            corridor_half_width_m: 1.3,
            ttc_brake_s: 1.4,
            standstill_gap_m: 2.0,
            front_offset_m: 2.25,
        }
    }
}

impl Cruise {
    /// The throttle in `[-1, 1]` at speed `speed_mps` (m/s) toward `target_mps`, given the
    /// nearest obstacle in the corridor at `obstacle_m` metres ahead of the chassis centre:
    /// `-1` (full braking) when `gap - standstill_gap_m < max(speed, 0) · ttc_brake_s` with
    /// `gap = obstacle_m - front_offset_m`, else `speed_gain · (target - speed)` clipped.
    pub fn throttle(&self, speed_mps: f64, target_mps: f64, obstacle_m: Option<f64>) -> f64 {
        let brake = obstacle_m.is_some_and(|d| {
            d - self.front_offset_m - self.standstill_gap_m < speed_mps.max(0.0) * self.ttc_brake_s
        });
        if brake {
            -1.0
        } else {
            (self.speed_gain * (target_mps - speed_mps)).clamp(-1.0, 1.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brakes_inside_the_headway_and_tracks_the_speed_outside() {
        let c = Cruise::default();
        // 12 m/s: brake when the gap is under 2 + 16.8 m, i.e. the obstacle under 21.05 m.
        assert_eq!(c.throttle(12.0, 12.0, Some(21.0)), -1.0);
        assert_eq!(c.throttle(12.0, 12.0, Some(21.1)), 0.0);
        assert_eq!(c.throttle(10.0, 12.0, None), 1.0);
        assert_eq!(c.throttle(11.0, 12.0, None), 0.5);
    }
}
