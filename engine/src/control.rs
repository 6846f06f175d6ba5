use serde::{Deserialize, Serialize};

/// The ego vehicle's two normalised control inputs (paper §2, "System Under Test").
///
/// - `throttle` in `[-1, 1]`: positive drives (engine force `throttle ·
///   VehicleParams::max_engine_force_n`), negative brakes (brake force `-throttle ·
///   VehicleParams::max_brake_force_n`), `0` coasts.
/// - `steering` in `[-1, 1]`: front-wheel angle `steering · VehicleParams::max_steer_rad`,
///   positive turns left (counter-clockwise seen from above).
///
/// Values outside `[-1, 1]` are clamped and NaN counts as `0` when applied.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Control {
    /// Throttle (`> 0`) or brake (`< 0`), in `[-1, 1]`.
    pub throttle: f64,
    /// Steering, positive to the left, in `[-1, 1]`.
    pub steering: f64,
}

impl Control {
    /// Full braking, no steering.
    pub const FULL_BRAKE: Control = Control {
        throttle: -1.0,
        steering: 0.0,
    };

    /// The control with both inputs clamped to `[-1, 1]` and NaN replaced by `0`.
    pub fn clamped(self) -> Control {
        let c = |v: f64| if v.is_nan() { 0.0 } else { v.clamp(-1.0, 1.0) };
        Control {
            throttle: c(self.throttle),
            steering: c(self.steering),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_limits_range_and_removes_nan() {
        let c = Control {
            throttle: 3.0,
            steering: f64::NAN,
        }
        .clamped();
        assert_eq!(
            c,
            Control {
                throttle: 1.0,
                steering: 0.0
            }
        );
        let c = Control {
            throttle: -2.0,
            steering: -0.5,
        }
        .clamped();
        assert_eq!(
            c,
            Control {
                throttle: -1.0,
                steering: -0.5
            }
        );
    }
}
