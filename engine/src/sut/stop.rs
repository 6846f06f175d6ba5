//! A system under test that gives up: it drives as another system does until the ego vehicle
//! has travelled a given distance, then brakes to a standstill and stays there. It is no
//! driver; it checks a scenario's monitors for vacuity (a car that stops before the danger and
//! so never meets it must fail the scenario's liveness check, not pass it).

use super::{Sensors, Sut, SutError};
use crate::{Control, Observation};

/// Drives as `inner` until the ego has travelled `after_m` metres in the ground plane (summed
/// from its odometry, `x` and `z`), then answers [`Control::FULL_BRAKE`] at every step.
///
/// `inner` keeps its sensors and its rate of decision; once stopping it is no longer asked.
pub struct StopAfter {
    inner: Box<dyn Sut>,
    after_m: f64,
    travelled_m: f64,
    last_m: Option<[f64; 2]>,
}

impl StopAfter {
    /// `inner` until `after_m` metres (`>= 0`; `0` brakes from the first step), then a full
    /// brake.
    pub fn new(inner: Box<dyn Sut>, after_m: f64) -> Self {
        StopAfter {
            inner,
            after_m,
            travelled_m: 0.0,
            last_m: None,
        }
    }

    /// Metres travelled so far (ground plane), as this system counts them.
    pub fn travelled_m(&self) -> f64 {
        self.travelled_m
    }
}

impl Sut for StopAfter {
    fn sensors(&self) -> Sensors {
        self.inner.sensors()
    }

    fn reset(&mut self, seed: u64) -> Result<(), SutError> {
        self.travelled_m = 0.0;
        self.last_m = None;
        self.inner.reset(seed)
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let here = [obs.ego.pos_m[0], obs.ego.pos_m[2]];
        if let Some(last) = self.last_m {
            self.travelled_m += (here[0] - last[0]).hypot(here[1] - last[1]);
        }
        self.last_m = Some(here);
        if self.travelled_m >= self.after_m {
            return Ok(Control::FULL_BRAKE);
        }
        self.inner.act(obs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sut::ConstantControl;
    use crate::EgoState;

    fn obs(x: f64) -> Observation<'static> {
        Observation {
            t_s: 0.0,
            dt_s: 1.0 / 60.0,
            ego: EgoState {
                pos_m: [x, 0.5, 0.0],
                heading_rad: 0.0,
                speed_mps: 1.0,
            },
            route: &[],
            set_speed_mps: None,
            readings: Vec::new(),
        }
    }

    #[test]
    fn drives_as_the_inner_system_then_brakes_for_good() {
        let go = Control {
            throttle: 0.7,
            steering: 0.1,
        };
        let mut s = StopAfter::new(Box::new(ConstantControl(go)), 2.5);
        s.reset(1).unwrap();
        let answers: Vec<Control> = [0.0, 1.0, 2.0, 3.0, 2.0]
            .iter()
            .map(|&x| s.act(&obs(x)).unwrap())
            .collect();
        assert_eq!(answers[..3], [go, go, go]);
        // 3 m travelled at x = 3: brakes, and keeps braking though it rolls back.
        assert_eq!(answers[3..], [Control::FULL_BRAKE, Control::FULL_BRAKE]);
        assert_eq!(s.travelled_m(), 4.0);
        s.reset(2).unwrap();
        assert_eq!(
            s.act(&obs(10.0)).unwrap(),
            go,
            "reset starts counting again"
        );
    }
}
