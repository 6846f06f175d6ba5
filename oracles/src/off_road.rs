use std::ops::ControlFlow;

use crate::{Frame, Monitor, Verdict};

/// Fails when the ego vehicle leaves the drivable surface: a sidewalk, an island, the ground
/// beside the road or beyond a dead end (issue 14; the paper's §2 lists monitors as user code,
/// this one is built in because every driving test needs it).
///
/// Reads a boolean off-road flag and the signed distance from the ego's footprint centre to
/// the edge of the driving surface in metres (`> 0` on it, `<= 0` off it). Robustness is the
/// smallest signed distance over the run: the margin to the edge when it stayed on the road,
/// how far off it went when it did not. The verdict is settled at the first frame off the road,
/// so `observe` returns `Break` there. Metric `min_road_edge_m`: that same smallest distance.
#[derive(Debug, Clone)]
pub struct OffRoadMonitor {
    name: String,
    off_road_signal: &'static str,
    edge_signal: &'static str,
    min_edge_m: f64,
    first_off_s: Option<f64>,
    broken_trace: bool,
}

impl OffRoadMonitor {
    /// A monitor reading `off_road_signal` (boolean) and `edge_signal` (signed distance, m).
    pub fn new(
        name: impl Into<String>,
        off_road_signal: &'static str,
        edge_signal: &'static str,
    ) -> Self {
        OffRoadMonitor {
            name: name.into(),
            off_road_signal,
            edge_signal,
            min_edge_m: f64::INFINITY,
            first_off_s: None,
            broken_trace: false,
        }
    }
}

impl Monitor for OffRoadMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        let (Ok(off), Ok(edge)) = (
            frame.signals.get_bool(self.off_road_signal),
            frame.signals.get(self.edge_signal),
        ) else {
            self.broken_trace = true;
            self.first_off_s.get_or_insert(frame.t_s);
            return ControlFlow::Break(());
        };
        self.min_edge_m = self.min_edge_m.min(edge);
        if off {
            self.min_edge_m = self.min_edge_m.min(0.0);
            self.first_off_s.get_or_insert(frame.t_s);
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn verdict(&self) -> Verdict {
        let robustness = if self.broken_trace {
            f64::NEG_INFINITY
        } else {
            self.min_edge_m
        };
        Verdict {
            passed: self.first_off_s.is_none() && robustness > 0.0,
            robustness,
            first_violation_s: self.first_off_s,
            metrics: vec![("min_road_edge_m", self.min_edge_m)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Signals;

    fn run(trace: &[(f64, bool, f64)]) -> (Verdict, usize) {
        let mut m = OffRoadMonitor::new("offroad", "off", "edge");
        let mut seen = 0;
        for &(t, off, edge) in trace {
            let mut s = Signals::new();
            s.set_bool("off", off);
            s.set("edge", edge);
            seen += 1;
            if m.observe(&Frame {
                t_s: t,
                signals: &s,
            })
            .is_break()
            {
                break;
            }
        }
        (m.verdict(), seen)
    }

    #[test]
    fn staying_on_the_road_passes_with_the_smallest_margin() {
        let (v, seen) = run(&[(0.0, false, 1.75), (0.1, false, 0.4), (0.2, false, 1.0)]);
        assert!(v.passed);
        assert_eq!(v.robustness, 0.4);
        assert_eq!(seen, 3);
    }

    #[test]
    fn leaving_the_road_fails_at_once_with_how_far_off_it_went() {
        let (v, seen) = run(&[(0.0, false, 1.0), (0.1, true, -0.3), (0.2, true, -2.0)]);
        assert!(!v.passed);
        assert_eq!(v.robustness, -0.3);
        assert_eq!(v.first_violation_s, Some(0.1));
        assert_eq!(seen, 2);
    }

    #[test]
    fn a_trace_without_the_signals_fails() {
        let mut m = OffRoadMonitor::new("offroad", "off", "edge");
        let s = Signals::new();
        assert!(m
            .observe(&Frame {
                t_s: 0.0,
                signals: &s
            })
            .is_break());
        assert!(!m.verdict().passed);
    }
}
