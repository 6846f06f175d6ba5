use crate::flag::{flag_monitor, FlagMonitor};

/// Fails on any contact between the ego vehicle and another body (paper §2,
/// `CollisionMonitor`: "assert(v.collider.isEmpty())").
///
/// Reads two signals: a boolean contact flag and the separation between the two bodies in
/// metres (`0` when touching). Robustness is the minimum separation over the run, and `<= 0`
/// whenever a contact was seen even if the separation signal lagged. The verdict is settled
/// at the first contact, so `observe` returns `Break` there. Metric `min_distance_m`: the
/// minimum separation.
#[derive(Debug, Clone)]
pub struct CollisionMonitor(FlagMonitor);

impl CollisionMonitor {
    /// A collision monitor reading `contact_signal` (boolean) and `separation_signal` (m).
    pub fn new(
        name: impl Into<String>,
        contact_signal: &'static str,
        separation_signal: &'static str,
    ) -> Self {
        CollisionMonitor(FlagMonitor::new(
            name.into(),
            contact_signal,
            separation_signal,
            "min_distance_m",
        ))
    }
}

flag_monitor!(CollisionMonitor);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Verdict;

    fn run(trace: &[(f64, bool, f64)]) -> (Verdict, usize) {
        crate::flag::feed(
            &mut CollisionMonitor::new("collision", "flag", "margin"),
            trace,
        )
    }

    #[test]
    fn no_contact_passes_with_min_separation_as_robustness() {
        let (v, seen) = run(&[(0.0, false, 5.0), (0.1, false, 1.5), (0.2, false, 3.0)]);
        assert!(v.passed);
        assert_eq!(v.robustness, 1.5);
        assert_eq!(v.first_violation_s, None);
        assert_eq!(seen, 3);
    }

    #[test]
    fn contact_fails_settles_early_and_robustness_is_not_positive() {
        // The separation signal still reads 0.2 at the contact frame (it lags a step).
        let (v, seen) = run(&[(0.0, false, 5.0), (0.1, true, 0.2), (0.2, false, 3.0)]);
        assert!(!v.passed);
        assert_eq!(v.robustness, 0.0);
        assert_eq!(v.first_violation_s, Some(0.1));
        assert_eq!(seen, 2);
    }
}
