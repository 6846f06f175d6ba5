use std::ops::ControlFlow;

use crate::{Frame, Monitor, Verdict};

/// Checks that the ego vehicle travelled at least `min_distance_m` metres (paper §2,
/// `DistanceMonitor`: `D = v.pos.zip(pOld).map(|_ - _|).sum()`, `assert(D >= minD)`).
///
/// Reads the planar position signals `x_signal` and `z_signal` (m) and sums the Euclidean
/// length of each step. Robustness is `D - minD` in metres. The verdict is only final at the
/// end of the run, so `observe` never breaks; a run stopped early (e.g. by a collision) is
/// judged on the distance covered until then.
#[derive(Debug, Clone)]
pub struct DistanceMonitor {
    name: String,
    x_signal: &'static str,
    z_signal: &'static str,
    min_distance_m: f64,
    travelled_m: f64,
    last: Option<(f64, f64)>,
    broken_trace: bool,
    /// Time of the last frame seen, seconds: when a failed verdict was reached.
    last_t_s: Option<f64>,
}

impl DistanceMonitor {
    /// A monitor requiring `min_distance_m` metres of travel, reading positions from
    /// `x_signal` and `z_signal` (m).
    pub fn new(
        name: impl Into<String>,
        x_signal: &'static str,
        z_signal: &'static str,
        min_distance_m: f64,
    ) -> Self {
        DistanceMonitor {
            name: name.into(),
            x_signal,
            z_signal,
            min_distance_m,
            travelled_m: 0.0,
            last: None,
            broken_trace: false,
            last_t_s: None,
        }
    }

    /// Distance travelled so far, in metres.
    pub fn travelled_m(&self) -> f64 {
        self.travelled_m
    }
}

impl Monitor for DistanceMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        self.last_t_s = Some(frame.t_s);
        let (Ok(x), Ok(z)) = (
            frame.signals.get(self.x_signal),
            frame.signals.get(self.z_signal),
        ) else {
            self.broken_trace = true;
            return ControlFlow::Break(());
        };
        if let Some((px, pz)) = self.last {
            self.travelled_m += (x - px).hypot(z - pz);
        }
        self.last = Some((x, z));
        ControlFlow::Continue(())
    }

    fn verdict(&self) -> Verdict {
        let robustness = if self.broken_trace {
            f64::NEG_INFINITY
        } else {
            self.travelled_m - self.min_distance_m
        };
        Verdict {
            // D >= minD holds at equality, but robustness 0 is the boundary: count it as passed
            // only with a positive margin, like every other monitor.
            passed: robustness > 0.0,
            robustness,
            // The distance is judged on the run as a whole: a failure is known at its last
            // frame (the horizon, or where the run stopped), or where the trace broke.
            first_violation_s: (robustness <= 0.0).then(|| self.last_t_s.unwrap_or(0.0)),
            metrics: vec![("distance_travelled_m", self.travelled_m)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Signals;

    fn feed(m: &mut DistanceMonitor, pts: &[(f64, f64)]) {
        for (i, &(x, z)) in pts.iter().enumerate() {
            let mut s = Signals::new();
            s.set("x", x);
            s.set("z", z);
            let _ = m.observe(&Frame {
                t_s: i as f64,
                signals: &s,
            });
        }
    }

    #[test]
    fn sums_step_lengths_and_robustness_is_margin() {
        let mut m = DistanceMonitor::new("distance", "x", "z", 6.0);
        feed(&mut m, &[(0.0, 0.0), (3.0, 4.0), (3.0, 7.0)]);
        assert_eq!(m.travelled_m(), 8.0);
        let v = m.verdict();
        assert!(v.passed);
        assert_eq!(v.robustness, 2.0);
        assert_eq!(v.first_violation_s, None);
    }

    #[test]
    fn standing_still_fails() {
        let mut m = DistanceMonitor::new("distance", "x", "z", 1.0);
        feed(&mut m, &[(5.0, 5.0); 10]);
        let v = m.verdict();
        assert!(!v.passed);
        assert_eq!(v.robustness, -1.0);
        assert_eq!(v.first_violation_s, Some(9.0), "judged at the last frame");
    }
}
