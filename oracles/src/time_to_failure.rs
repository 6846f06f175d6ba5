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
    /// Time of the last frame seen, seconds.
    last_t_s: Option<f64>,
}

impl TimeToFailureMonitor {
    /// Wraps `inner`; `min_s` is the shortest acceptable time to failure, seconds.
    pub fn new(name: &str, inner: Box<dyn Monitor>, min_s: f64) -> Self {
        TimeToFailureMonitor {
            name: name.to_owned(),
            inner,
            min_s,
            last_t_s: None,
        }
    }
}

impl Monitor for TimeToFailureMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        self.last_t_s = Some(frame.t_s);
        self.inner.observe(frame)
    }

    fn settle_now(&mut self) -> bool {
        self.inner.settle_now()
    }

    fn verdict(&self) -> Verdict {
        let inner = self.inner.verdict();
        // Only a failed verdict has a time to failure: a wrapped `TimeToFailure` that passed
        // (its monitor failed late) reports that failure's time but did not fail itself. A
        // failure with no time of its own counts from the last frame seen.
        let (passed, robustness) = match (inner.passed, inner.first_violation_s) {
            (false, ttf) => {
                let ttf = ttf.or(self.last_t_s).unwrap_or(0.0);
                (ttf >= self.min_s, ttf - self.min_s)
            }
            (true, _) => (true, inner.robustness),
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

    /// A monitor that fails at the end of the run and gives no time of its own.
    struct FailsUntimed;

    impl Monitor for FailsUntimed {
        fn name(&self) -> &str {
            "untimed"
        }
        fn observe(&mut self, _: &Frame<'_>) -> ControlFlow<()> {
            ControlFlow::Continue(())
        }
        fn verdict(&self) -> Verdict {
            Verdict {
                passed: false,
                robustness: -3.0,
                first_violation_s: None,
                metrics: vec![],
            }
        }
    }

    fn feed(m: &mut dyn Monitor, until_s: f64) {
        let s = Signals::new();
        let mut t = 0.0;
        while t <= until_s {
            let _ = m.observe(&Frame {
                t_s: t,
                signals: &s,
            });
            t += 1.0;
        }
    }

    #[test]
    fn a_failure_without_a_time_counts_from_the_last_frame() {
        let mut late = TimeToFailureMonitor::new("ttf", Box::new(FailsUntimed), 1.0);
        feed(&mut late, 3.0);
        let v = late.verdict();
        assert_eq!((v.passed, v.robustness), (true, 2.0));
        let mut early = TimeToFailureMonitor::new("ttf", Box::new(FailsUntimed), 5.0);
        feed(&mut early, 3.0);
        let v = early.verdict();
        assert_eq!((v.passed, v.robustness), (false, -2.0));
    }

    #[test]
    fn a_wrapped_time_to_failure_that_passed_is_no_failure() {
        // The inner one passes (collision at 7 s, minT 5 s); the outer one, minT 10 s, must
        // not read the collision as the inner one's failure.
        let inner = TimeToFailureMonitor::new(
            "inner",
            Box::new(CollisionMonitor::new("collision", "contact", "sep")),
            5.0,
        );
        let mut outer = TimeToFailureMonitor::new("outer", Box::new(inner), 10.0);
        let mut s = Signals::new();
        for i in 0..=10 {
            let t = i as f64;
            s.set_bool("contact", t >= 7.0);
            s.set("sep", if t >= 7.0 { 0.0 } else { 1.0 });
            if outer
                .observe(&Frame {
                    t_s: t,
                    signals: &s,
                })
                .is_break()
            {
                break;
            }
        }
        let v = outer.verdict();
        assert_eq!((v.passed, v.robustness), (true, 2.0), "{v:?}");
    }
}
