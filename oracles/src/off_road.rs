use crate::flag::{flag_monitor, FlagMonitor};

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
pub struct OffRoadMonitor(FlagMonitor);

impl OffRoadMonitor {
    /// A monitor reading `off_road_signal` (boolean) and `edge_signal` (signed distance, m).
    pub fn new(
        name: impl Into<String>,
        off_road_signal: &'static str,
        edge_signal: &'static str,
    ) -> Self {
        OffRoadMonitor(FlagMonitor::new(
            name.into(),
            off_road_signal,
            edge_signal,
            "min_road_edge_m",
        ))
    }
}

flag_monitor!(OffRoadMonitor);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Verdict;

    fn run(trace: &[(f64, bool, f64)]) -> (Verdict, usize) {
        crate::flag::feed(&mut OffRoadMonitor::new("offroad", "flag", "margin"), trace)
    }

    #[test]
    fn staying_on_the_road_passes_with_the_smallest_margin() {
        let (v, seen) = run(&[(0.0, false, 1.75), (0.1, false, 0.4), (0.2, false, 1.0)]);
        assert!(v.passed);
        assert_eq!(v.robustness, 0.4);
        assert_eq!(v.metrics, vec![("min_road_edge_m", 0.4)]);
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
}
