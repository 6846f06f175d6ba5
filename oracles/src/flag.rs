use std::ops::ControlFlow;

use crate::{Frame, Monitor, Verdict};

/// The shape shared by [`crate::CollisionMonitor`] and [`crate::OffRoadMonitor`]: a property
/// that fails at the first frame a boolean signal is set (a contact, leaving the road), with a
/// margin signal in metres that says how close it came (a separation, a distance to the road's
/// edge).
///
/// Robustness is the smallest margin over the run, and `<= 0` once the flag was seen even if
/// the margin lagged a step. The verdict settles at the first flagged frame (`Break`). A frame
/// without the two signals is a broken trace: robustness `-inf`, failed. The smallest margin is
/// also reported as the metric `metric`.
#[derive(Debug, Clone)]
pub(crate) struct FlagMonitor {
    name: String,
    flag_signal: &'static str,
    margin_signal: &'static str,
    metric: &'static str,
    min_margin: f64,
    first_flag_s: Option<f64>,
    broken_trace: bool,
}

impl FlagMonitor {
    pub(crate) fn new(
        name: String,
        flag_signal: &'static str,
        margin_signal: &'static str,
        metric: &'static str,
    ) -> Self {
        FlagMonitor {
            name,
            flag_signal,
            margin_signal,
            metric,
            min_margin: f64::INFINITY,
            first_flag_s: None,
            broken_trace: false,
        }
    }
}

impl Monitor for FlagMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        let (Ok(flag), Ok(margin)) = (
            frame.signals.get_bool(self.flag_signal),
            frame.signals.get(self.margin_signal),
        ) else {
            self.broken_trace = true;
            self.first_flag_s.get_or_insert(frame.t_s);
            return ControlFlow::Break(());
        };
        self.min_margin = self.min_margin.min(margin);
        if flag {
            self.min_margin = self.min_margin.min(0.0);
            self.first_flag_s.get_or_insert(frame.t_s);
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn verdict(&self) -> Verdict {
        let robustness = if self.broken_trace {
            f64::NEG_INFINITY
        } else {
            self.min_margin
        };
        Verdict {
            passed: self.first_flag_s.is_none() && robustness > 0.0,
            robustness,
            first_violation_s: self.first_flag_s,
            metrics: vec![(self.metric, self.min_margin)],
        }
    }
}

/// Implements [`Monitor`] for a newtype over [`FlagMonitor`].
macro_rules! flag_monitor {
    ($t:ty) => {
        impl $crate::Monitor for $t {
            fn name(&self) -> &str {
                self.0.name()
            }

            fn observe(&mut self, frame: &$crate::Frame<'_>) -> std::ops::ControlFlow<()> {
                self.0.observe(frame)
            }

            fn verdict(&self) -> $crate::Verdict {
                self.0.verdict()
            }
        }
    };
}
pub(crate) use flag_monitor;

/// Feeds `trace` (`(t s, flag, margin)` frames, signals named `flag` and `margin`) to `m` until
/// it settles; returns its verdict and the frames it saw.
#[cfg(test)]
pub(crate) fn feed(m: &mut dyn Monitor, trace: &[(f64, bool, f64)]) -> (Verdict, usize) {
    let mut seen = 0;
    for &(t, flag, margin) in trace {
        let mut s = crate::Signals::new();
        s.set_bool("flag", flag);
        s.set("margin", margin);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trace_without_the_signals_fails_instead_of_panicking() {
        let mut m = FlagMonitor::new("m".into(), "flag", "margin", "min_m");
        let s = crate::Signals::new();
        let frame = Frame {
            t_s: 0.0,
            signals: &s,
        };
        assert!(m.observe(&frame).is_break());
        assert!(!m.verdict().passed);
        assert_eq!(m.verdict().robustness, f64::NEG_INFINITY);
        assert_eq!(m.verdict().first_violation_s, Some(0.0));
    }
}
