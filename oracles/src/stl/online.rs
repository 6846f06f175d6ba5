//! Online monitoring: an STL formula as a [`Monitor`] that settles its verdict as soon as the
//! samples seen decide it.

use std::ops::ControlFlow;

use super::eval::{eval_bounds, robustness, Trace};
use super::Formula;
use crate::{Frame, Monitor, Verdict};

/// Check whether the verdict is settled every this many samples (0.25 s at 60 Hz): each check
/// re-evaluates the trace, so checking every sample would make a test quadratic.
const CHECK_EVERY: usize = 15;

/// An STL formula over the runner's signals, judged at time 0 of the run (the formula's
/// robustness at the first sample).
///
/// Samples are taken at the frames' times, assumed uniform (the step is the gap between the
/// first two frames). Every [`CHECK_EVERY`] samples it bounds the robustness over every
/// possible continuation: unknown future samples count as `-inf` for the lower bound and
/// `+inf` for the upper. When the upper bound is `<= 0` the formula is violated whatever
/// comes next: the verdict settles (robustness: that upper bound, a sound over-estimate) and
/// the run may stop; when the lower bound is `> 0` it is satisfied. At the end of the run the
/// verdict is the offline robustness of the trace seen (windows cut at its end).
#[derive(Debug, Clone)]
pub struct StlMonitor {
    name: String,
    formula: Formula,
    signals: Vec<String>,
    times: Vec<f64>,
    /// The samples so far; `dt_s` is set from the first two frames.
    trace: Trace,
    settled: Option<Verdict>,
    missing: Option<(String, f64)>,
}

impl StlMonitor {
    /// A monitor named `name` (its key in results files) for `formula`.
    pub fn new(name: &str, formula: Formula) -> Self {
        let signals = formula.signals();
        StlMonitor {
            name: name.to_owned(),
            trace: Trace {
                dt_s: 1.0,
                signals: signals.iter().map(|s| (s.clone(), Vec::new())).collect(),
            },
            signals,
            formula,
            times: Vec::new(),
            settled: None,
            missing: None,
        }
    }
}

impl Monitor for StlMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        if self.settled.is_some() || self.missing.is_some() {
            return ControlFlow::Break(());
        }
        for s in &self.signals {
            match frame.signals.get(s) {
                Ok(v) => self
                    .trace
                    .signals
                    .get_mut(s)
                    .expect("one per signal")
                    .push(v),
                Err(_) => {
                    self.missing = Some((s.clone(), frame.t_s));
                    return ControlFlow::Break(());
                }
            }
        }
        self.times.push(frame.t_s);
        if let [t0, t1] = self.times[..] {
            if t1 > t0 {
                self.trace.dt_s = t1 - t0;
            }
        }
        if self.times.len() % CHECK_EVERY != 0 || self.times.len() < 2 {
            return ControlFlow::Continue(());
        }
        let (lo, hi) = match eval_bounds(&self.formula, &self.trace) {
            Ok(b) => b,
            Err(_) => return ControlFlow::Continue(()),
        };
        if hi <= 0.0 {
            self.settled = Some(Verdict {
                passed: false,
                robustness: hi,
                first_violation_s: Some(frame.t_s),
                metrics: vec![],
            });
            ControlFlow::Break(())
        } else if lo > 0.0 {
            self.settled = Some(Verdict {
                passed: true,
                robustness: lo,
                first_violation_s: None,
                metrics: vec![],
            });
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    fn verdict(&self) -> Verdict {
        if let Some((_, t)) = &self.missing {
            return Verdict {
                passed: false,
                robustness: f64::NEG_INFINITY,
                first_violation_s: Some(*t),
                metrics: vec![],
            };
        }
        if let Some(v) = &self.settled {
            return v.clone();
        }
        let r = robustness(&self.formula, &self.trace)
            .ok()
            .and_then(|r| r.first().copied())
            .unwrap_or(f64::INFINITY);
        Verdict {
            passed: r > 0.0,
            robustness: r,
            first_violation_s: (r <= 0.0).then(|| self.times.last().copied().unwrap_or(0.0)),
            metrics: vec![],
        }
    }
}
