use std::ops::ControlFlow;

use crate::{Frame, Monitor, Verdict};

/// Fails on any contact between the ego vehicle and another body (paper §2,
/// `CollisionMonitor`: "assert(v.collider.isEmpty())").
///
/// Reads two signals: a boolean contact flag and the separation between the two bodies in
/// metres (`0` when touching). Robustness is the minimum separation over the run, and `<= 0`
/// whenever a contact was seen even if the separation signal lagged. The verdict is settled
/// at the first contact, so `observe` returns `Break` there.
#[derive(Debug, Clone)]
pub struct CollisionMonitor {
    name: String,
    contact_signal: &'static str,
    separation_signal: &'static str,
    min_separation_m: f64,
    first_contact_s: Option<f64>,
    broken_trace: bool,
}

impl CollisionMonitor {
    /// A collision monitor reading `contact_signal` (boolean) and `separation_signal` (m).
    pub fn new(
        name: impl Into<String>,
        contact_signal: &'static str,
        separation_signal: &'static str,
    ) -> Self {
        CollisionMonitor {
            name: name.into(),
            contact_signal,
            separation_signal,
            min_separation_m: f64::INFINITY,
            first_contact_s: None,
            broken_trace: false,
        }
    }
}

impl Monitor for CollisionMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        let (Ok(contact), Ok(sep)) = (
            frame.signals.get_bool(self.contact_signal),
            frame.signals.get(self.separation_signal),
        ) else {
            self.broken_trace = true;
            self.first_contact_s.get_or_insert(frame.t_s);
            return ControlFlow::Break(());
        };
        self.min_separation_m = self.min_separation_m.min(sep);
        if contact {
            self.min_separation_m = self.min_separation_m.min(0.0);
            self.first_contact_s.get_or_insert(frame.t_s);
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn verdict(&self) -> Verdict {
        let robustness = if self.broken_trace {
            f64::NEG_INFINITY
        } else {
            self.min_separation_m
        };
        Verdict {
            passed: self.first_contact_s.is_none() && robustness > 0.0,
            robustness,
            first_violation_s: self.first_contact_s,
            metrics: vec![("min_distance_m", self.min_separation_m)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Signals;

    fn run(trace: &[(f64, bool, f64)]) -> (Verdict, usize) {
        let mut m = CollisionMonitor::new("collision", "contact", "sep");
        let mut seen = 0;
        for &(t, c, d) in trace {
            let mut s = Signals::new();
            s.set_bool("contact", c);
            s.set("sep", d);
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

    #[test]
    fn a_trace_without_the_signals_fails_instead_of_panicking() {
        let mut m = CollisionMonitor::new("collision", "contact", "sep");
        let s = Signals::new();
        assert!(m
            .observe(&Frame {
                t_s: 0.0,
                signals: &s
            })
            .is_break());
        assert!(!m.verdict().passed);
        assert_eq!(m.verdict().robustness, f64::NEG_INFINITY);
    }
}
