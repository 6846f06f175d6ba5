use std::ops::ControlFlow;

use crate::{Frame, Monitor, Verdict};

/// How a [`StreamMonitor`] turns a signal's values over a test into one robustness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Over {
    /// The minimum over the test: it fails when the value is ever `<= 0`, and settles at the
    /// first such value (the test may stop there).
    Always,
    /// The value at the end of the test (the last frame observed).
    End,
    /// The maximum over the test: it passes when the value is ever `> 0`.
    Eventually,
}

impl Over {
    /// Parses `"always"`, `"end"` or `"eventually"`.
    pub fn parse(text: &str) -> Option<Over> {
        match text {
            "always" => Some(Over::Always),
            "end" => Some(Over::End),
            "eventually" => Some(Over::Eventually),
            _ => None,
        }
    }

    /// The word [`Over::parse`] reads.
    pub fn as_str(self) -> &'static str {
        match self {
            Over::Always => "always",
            Over::End => "end",
            Over::Eventually => "eventually",
        }
    }
}

/// A user-written monitor (LANGUAGE.md, `Monitor(stream, over=)` and `Assert(stream)`): the
/// robustness is one signal's value taken [`Over`] the test, in the signal's unit; it passes
/// when the robustness is `> 0`.
///
/// Frames in which the signal has no value (its stream has not fired yet) are not judged. A
/// test in which it never has one fails with robustness `-inf`. A value that is not a number
/// (NaN), in any frame and whatever `over` is, fails it at once with robustness `-inf`: a
/// later or larger value does not make up for it (`Eventually` took the maximum, and `End`
/// the last value, past it). Nothing a monitor was asked to judge is skipped silently. `End`
/// and `Eventually` otherwise settle only at the end of the test; `Always` settles at its
/// first violation.
///
/// `first_violation_s`, the time a failed verdict was decided (what `TimeToFailure` and the
/// `time_to_failure_s` metric read), s: the frame of the first NaN; for `Always`, the frame
/// of the first value `<= 0`;
/// otherwise, and for an `Always` whose signal never had a value, the last frame observed,
/// with or without a value: the end of the test (or the moment it stopped).
/// With `boolean`, the value is a truth value (`> 0.5` true) and the robustness is `+1` or
/// `-1` (`Assert`).
#[derive(Debug, Clone)]
pub struct StreamMonitor {
    name: String,
    signal: String,
    over: Over,
    boolean: bool,
    value: Option<f64>,
    /// Time of the last frame observed, with or without a value, s.
    last_frame_s: f64,
    first_violation_s: Option<f64>,
}

impl StreamMonitor {
    /// A monitor named `name` over the values of signal `signal`.
    pub fn new(name: impl Into<String>, signal: impl Into<String>, over: Over) -> Self {
        StreamMonitor {
            name: name.into(),
            signal: signal.into(),
            over,
            boolean: false,
            value: None,
            last_frame_s: 0.0,
            first_violation_s: None,
        }
    }

    /// The Boolean form: the signal is a truth value that must always hold; robustness `±1`.
    pub fn assertion(name: impl Into<String>, signal: impl Into<String>) -> Self {
        StreamMonitor {
            boolean: true,
            ..StreamMonitor::new(name, signal, Over::Always)
        }
    }
}

impl Monitor for StreamMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        if self.first_violation_s.is_some() {
            return ControlFlow::Break(());
        }
        self.last_frame_s = frame.t_s;
        let Ok(raw) = frame.signals.get(&self.signal) else {
            return ControlFlow::Continue(());
        };
        if raw.is_nan() {
            self.value = Some(f64::NEG_INFINITY);
            self.first_violation_s = Some(frame.t_s);
            return ControlFlow::Break(());
        }
        let v = if self.boolean {
            if raw > 0.5 {
                1.0
            } else {
                -1.0
            }
        } else {
            raw
        };
        self.value = Some(match (self.over, self.value) {
            (_, None) | (Over::End, _) => v,
            (Over::Always, Some(m)) => m.min(v),
            (Over::Eventually, Some(m)) => m.max(v),
        });
        if self.over == Over::Always && v <= 0.0 {
            self.first_violation_s = Some(frame.t_s);
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn verdict(&self) -> Verdict {
        let robustness = self.value.unwrap_or(f64::NEG_INFINITY);
        let passed = robustness > 0.0;
        Verdict {
            passed,
            robustness,
            first_violation_s: match (self.over, self.first_violation_s) {
                // The first violation of `Always`, or a NaN under any `over`.
                (_, Some(t)) => Some(t),
                // Decided at the end: the last frame, whether or not it carried a value.
                _ => (!passed).then_some(self.last_frame_s),
            },
            metrics: vec![],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Signals;

    fn run(m: &mut StreamMonitor, values: &[Option<f64>]) -> Verdict {
        for (i, v) in values.iter().enumerate() {
            let mut s = Signals::new();
            if let Some(v) = v {
                s.set("x", *v);
            }
            if m.observe(&Frame {
                t_s: i as f64,
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
    fn always_is_the_minimum_and_settles_at_the_first_violation() {
        let mut m = StreamMonitor::new("m", "x", Over::Always);
        let v = run(
            &mut m,
            &[None, Some(3.0), Some(1.5), Some(-0.5), Some(-9.0)],
        );
        assert!(!v.passed);
        assert_eq!(v.robustness, -0.5);
        assert_eq!(v.first_violation_s, Some(3.0));
        let mut m = StreamMonitor::new("m", "x", Over::Always);
        let v = run(&mut m, &[Some(3.0), Some(1.5), Some(2.0)]);
        assert!(v.passed);
        assert_eq!(v.robustness, 1.5);
    }

    #[test]
    fn end_takes_the_last_value_and_eventually_the_maximum() {
        let mut m = StreamMonitor::new("m", "x", Over::End);
        let v = run(&mut m, &[Some(5.0), Some(-1.0), Some(0.25), None]);
        assert_eq!((v.passed, v.robustness), (true, 0.25));
        let mut m = StreamMonitor::new("m", "x", Over::Eventually);
        let v = run(&mut m, &[Some(-5.0), Some(2.0), Some(-1.0)]);
        assert_eq!((v.passed, v.robustness), (true, 2.0));
        let mut m = StreamMonitor::new("m", "x", Over::Eventually);
        let v = run(&mut m, &[Some(-5.0), Some(-2.0)]);
        assert_eq!(
            (v.passed, v.robustness, v.first_violation_s),
            (false, -2.0, Some(1.0))
        );
    }

    #[test]
    fn a_signal_that_never_comes_or_is_nan_fails() {
        let mut m = StreamMonitor::new("m", "x", Over::End);
        let v = run(&mut m, &[None, None]);
        assert!(!v.passed);
        assert_eq!(v.robustness, f64::NEG_INFINITY);
        // Decided when the test ended (the last frame, t = 1), not at t = 0, for every `over`.
        for over in [Over::End, Over::Eventually, Over::Always] {
            let mut m = StreamMonitor::new("m", "x", over);
            let v = run(&mut m, &[None, None]);
            assert_eq!(
                (v.passed, v.first_violation_s),
                (false, Some(1.0)),
                "{over:?}"
            );
        }
        // `end` is decided at the end even when its last value came earlier.
        let mut m = StreamMonitor::new("m", "x", Over::End);
        let v = run(&mut m, &[Some(-1.0), None, None]);
        assert_eq!(v.first_violation_s, Some(2.0));
        let mut m = StreamMonitor::new("m", "x", Over::Eventually);
        let v = run(&mut m, &[Some(f64::NAN)]);
        assert!(!v.passed);
    }

    #[test]
    fn a_nan_fails_at_once_whatever_comes_after_it() {
        // A NaN amid good values: `eventually` took the maximum past it and `end` the last
        // value, so both passed with 1.0.
        for over in [Over::Always, Over::End, Over::Eventually] {
            let mut m = StreamMonitor::new("m", "x", over);
            let v = run(&mut m, &[Some(1.0), Some(f64::NAN), Some(2.0), Some(3.0)]);
            assert_eq!(
                (v.passed, v.robustness, v.first_violation_s),
                (false, f64::NEG_INFINITY, Some(1.0)),
                "{over:?}"
            );
        }
        let mut m = StreamMonitor::assertion("a", "x");
        let v = run(&mut m, &[Some(1.0), Some(1.0), Some(f64::NAN), Some(1.0)]);
        assert_eq!(
            (v.passed, v.robustness, v.first_violation_s),
            (false, f64::NEG_INFINITY, Some(2.0))
        );
    }

    #[test]
    fn an_assertion_is_plus_or_minus_one() {
        let mut m = StreamMonitor::assertion("a", "x");
        let v = run(&mut m, &[Some(1.0), Some(1.0), Some(0.0), Some(1.0)]);
        assert_eq!(
            (v.passed, v.robustness, v.first_violation_s),
            (false, -1.0, Some(2.0))
        );
        let mut m = StreamMonitor::assertion("a", "x");
        let v = run(&mut m, &[Some(1.0)]);
        assert_eq!((v.passed, v.robustness), (true, 1.0));
    }
}
