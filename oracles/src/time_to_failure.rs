use std::ops::ControlFlow;

use crate::{Frame, Monitor, Verdict};

/// `TimeToFailure(m, minT)`: wraps a monitor and judges *when* it first fails.
///
/// The time to failure `ttf` is the wrapped monitor's first violation time (seconds since the
/// start). The property holds when `m` never fails, or first fails at or after `min_s`.
/// Robustness: `ttf - min_s` in seconds when `m` failed; when it never failed, `m`'s own
/// robustness (in its unit, `> 0`), so a run that never failed is never a violation and
/// still says how close it came. The metric `time_to_failure_s` is reported by the runner from
/// the first violation.
pub struct TimeToFailureMonitor {
    name: String,
    inner: Box<dyn Monitor>,
    min_s: f64,
}

impl TimeToFailureMonitor {
    /// Wraps `inner`; `min_s` is the shortest acceptable time to failure, seconds.
    pub fn new(name: &str, inner: Box<dyn Monitor>, min_s: f64) -> Self {
        TimeToFailureMonitor {
            name: name.to_owned(),
            inner,
            min_s,
        }
    }
}

impl Monitor for TimeToFailureMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        self.inner.observe(frame)
    }

    fn verdict(&self) -> Verdict {
        let inner = self.inner.verdict();
        let (passed, robustness) = match inner.first_violation_s {
            Some(ttf) => (ttf >= self.min_s, ttf - self.min_s),
            None => (inner.passed, inner.robustness),
        };
        Verdict {
            passed,
            robustness,
            first_violation_s: inner.first_violation_s,
            metrics: inner.metrics,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CollisionMonitor, Signals};

    fn run(contact_at: Option<f64>, min_s: f64) -> Verdict {
        let inner = CollisionMonitor::new("collision", "contact", "sep");
        let mut m = TimeToFailureMonitor::new("ttf", Box::new(inner), min_s);
        let mut s = Signals::new();
        for i in 0..=10 {
            let t = i as f64;
            let touching = contact_at.is_some_and(|c| t >= c);
            s.set_bool("contact", touching);
            s.set("sep", if touching { 0.0 } else { 1.0 });
            if m.observe(&Frame {
                t_s: t,
                signals: &s,
            })
            .is_break()
            {
                break;
            }
        }
        m.verdict()
    }

    #[test]
    fn fails_only_when_the_first_failure_comes_too_early() {
        let early = run(Some(3.0), 5.0);
        assert!(!early.passed);
        assert_eq!(early.robustness, -2.0);
        assert_eq!(early.first_violation_s, Some(3.0));
        let late = run(Some(7.0), 5.0);
        assert!(late.passed);
        assert_eq!(late.robustness, 2.0);
        let never = run(None, 5.0);
        assert!(never.passed);
        assert_eq!(never.robustness, 1.0, "the wrapped monitor's separation");
    }
}
