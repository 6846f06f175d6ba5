//! Online monitoring: an STL formula as a [`Monitor`] that settles its verdict as soon as the
//! samples seen decide it.

use std::ops::ControlFlow;

use super::eval::{eval_bounds, reads, robustness, Trace};
use super::Formula;
use crate::{Frame, Monitor, Verdict};

/// The trace's name for the frames' times, kept only for a formula that reads no signal
/// (`G[0,1] (3 > 2)`): a trace's length is its signals', and without one every window would
/// be empty (robustness `+inf`). No formula can name it: a signal name has no space.
const CLOCK: &str = " clock";

/// Check whether the verdict is settled every this many samples (0.25 s at 60 Hz): each check
/// re-evaluates the trace, so checking every sample would make a test quadratic.
const CHECK_EVERY: usize = 15;

/// An STL formula over the runner's signals, judged at time 0 of the run (the formula's
/// robustness at the first sample).
///
/// Samples are taken at the frames' times, assumed uniform (the step is the gap between the
/// first two frames). Every [`CHECK_EVERY`] samples it bounds the robustness over every
/// possible continuation: unknown future samples count as `+inf` for the upper bound. When
/// that bound is `<= 0` the formula is violated whatever comes next: the verdict settles
/// (robustness: that upper bound, a sound over-estimate) and the run may stop. A formula
/// already satisfied does not settle: it keeps observing, so that its robustness is the
/// trace's and not the lower bound at the moment it was decided (for `F[0,15] x > 60` that
/// bound is the first sample's margin over 60, not the largest), which would tell a
/// falsifier that every passing test was near failure. At the end of the run the verdict
/// is the offline robustness of the trace seen (windows cut at its end).
///
/// `first_violation_s` of a violated formula is the time of the first sample whose prefix
/// decides the violation, whatever the check's period: for `G[0,10] (x < 30)` the sample
/// where `x` reaches 30, not the check that found it (so `TimeToFailure` compares the
/// moment of the failure with its `minT`); the last sample's time when only the end of the
/// trace decided it.
///
/// A signal without a value in a frame (its stream has not fired), or whose value is not a
/// number (NaN), fails the formula at that frame with robustness `-inf` when the formula reads
/// that sample ([`reads`]: `G[0.5,10] (x > 0)` reads `x` from 0.5 s to 10 s, so a signal that
/// first fires at 0.1 s is no failure): such a sample is not left out of a window's minimum or
/// maximum. One the formula does not read changes nothing.
#[derive(Debug, Clone)]
pub struct StlMonitor {
    name: String,
    formula: Formula,
    signals: Vec<String>,
    times: Vec<f64>,
    /// The samples so far; `dt_s` is set from the first two frames.
    trace: Trace,
    settled: Option<Verdict>,
    /// The samples where a signal had no value (its stream had not fired) or one that is not
    /// a number: `(signal, sample index)`, in order. The trace holds 0 there.
    missing: Vec<(String, usize)>,
    /// The samples of each signal the formula reads ([`reads`]), once the step is known.
    read: Option<std::collections::BTreeMap<String, Vec<(usize, usize)>>>,
    /// The first missing sample the formula reads: it fails there with robustness `-inf`.
    undefined: Option<usize>,
    /// Samples whose prefix is known not to decide a violation (the upper bound over their
    /// continuations was `> 0` at the last check).
    undecided: usize,
}

impl StlMonitor {
    /// A monitor named `name` (its key in results files) for `formula`.
    pub fn new(name: &str, formula: Formula) -> Self {
        let signals = formula.signals();
        let mut columns: std::collections::BTreeMap<String, Vec<f64>> =
            signals.iter().map(|s| (s.clone(), Vec::new())).collect();
        if columns.is_empty() {
            columns.insert(CLOCK.to_owned(), Vec::new());
        }
        StlMonitor {
            name: name.to_owned(),
            trace: Trace {
                dt_s: 1.0,
                signals: columns,
            },
            signals,
            formula,
            times: Vec::new(),
            settled: None,
            missing: Vec::new(),
            read: None,
            undefined: None,
            undecided: 0,
        }
    }

    /// The upper bound of the robustness over every continuation of the first `k` samples.
    fn upper_bound_after(&self, k: usize) -> f64 {
        let mut prefix = Trace {
            dt_s: self.trace.dt_s,
            signals: self.trace.signals.clone(),
        };
        for v in prefix.signals.values_mut() {
            v.truncate(k);
        }
        eval_bounds(&self.formula, &prefix).map_or(f64::INFINITY, |(_, hi)| hi)
    }

    /// The time of the first sample whose prefix decides the violation (the upper bound over
    /// its continuations is `<= 0`), searched among samples `undecided + 1 ..= n` (the bound
    /// only falls as samples come, so a bisection finds it); the last sample's time when no
    /// prefix decides it (a violation known only once the trace ended, windows cut there).
    fn first_violation_s(&self, n: usize) -> f64 {
        let (mut lo, mut hi) = (self.undecided, n);
        if self.upper_bound_after(hi) > 0.0 {
            return self.times[n - 1];
        }
        // Invariant: the prefix of `hi` samples decides it, that of `lo` does not.
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.upper_bound_after(mid) <= 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        self.times[hi - 1]
    }
}

impl StlMonitor {
    /// The first of `missing` that the formula reads, by `read`.
    fn first_read(
        missing: &[(String, usize)],
        read: &std::collections::BTreeMap<String, Vec<(usize, usize)>>,
    ) -> Option<usize> {
        missing
            .iter()
            .filter(|(s, k)| {
                read.get(s)
                    .is_some_and(|r| r.iter().any(|&(lo, hi)| lo <= *k && *k <= hi))
            })
            .map(|&(_, k)| k)
            .min()
    }

    /// The verdict of a formula that read a missing sample `k`: failed at `-inf`, at the
    /// first sample whose prefix decides a violation, which is `k` unless the samples before
    /// it already did.
    fn undefined_verdict(&self, k: usize) -> Verdict {
        let at = if k > self.undecided && self.upper_bound_after(k) <= 0.0 {
            self.first_violation_s(k)
        } else {
            self.times[k]
        };
        Verdict {
            passed: false,
            robustness: f64::NEG_INFINITY,
            first_violation_s: Some(at),
            metrics: vec![],
        }
    }

    /// Bounds the robustness over every continuation of the samples so far and settles the
    /// verdict as failed when that bound is `<= 0`; whether it settled.
    fn check(&mut self) -> bool {
        let hi = match eval_bounds(&self.formula, &self.trace) {
            Ok((_, hi)) => hi,
            Err(_) => return false,
        };
        if hi <= 0.0 {
            self.settled = Some(Verdict {
                passed: false,
                robustness: hi,
                first_violation_s: Some(self.first_violation_s(self.times.len())),
                metrics: vec![],
            });
            true
        } else {
            self.undecided = self.times.len();
            false
        }
    }
}

impl Monitor for StlMonitor {
    fn name(&self) -> &str {
        &self.name
    }

    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()> {
        if self.settled.is_some() || self.undefined.is_some() {
            return ControlFlow::Break(());
        }
        let k = self.times.len();
        let missing_before = self.missing.len();
        for s in &self.signals {
            let v = match frame.signals.get(s) {
                Ok(v) if !v.is_nan() => v,
                _ => {
                    self.missing.push((s.clone(), k));
                    0.0
                }
            };
            self.trace
                .signals
                .get_mut(s)
                .expect("one per signal")
                .push(v);
        }
        if let Some(clock) = self.trace.signals.get_mut(CLOCK) {
            clock.push(frame.t_s);
        }
        self.times.push(frame.t_s);
        if let [t0, t1] = self.times[..] {
            if t1 > t0 {
                self.trace.dt_s = t1 - t0;
            }
            // The step is known: which samples the formula reads, and whether it read a
            // missing one so far.
            self.read = Some(reads(&self.formula, &self.trace));
        }
        // Once the step is known, only this frame's missing samples are new.
        let new = if k == 1 { 0 } else { missing_before };
        if let Some(read) = &self.read {
            if let Some(k) = Self::first_read(&self.missing[new..], read) {
                self.undefined = Some(k);
                return ControlFlow::Break(());
            }
        }
        if !self.times.len().is_multiple_of(CHECK_EVERY) || self.times.len() < 2 {
            return ControlFlow::Continue(());
        }
        if self.check() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    fn settle_now(&mut self) -> bool {
        self.settled.is_some()
            || self.undefined.is_some()
            || (self.times.len() >= 2 && self.check())
    }

    fn verdict(&self) -> Verdict {
        if let Some(k) = self.undefined {
            return self.undefined_verdict(k);
        }
        // A run of one frame: the step is not known, and the trace's default holds.
        if self.read.is_none() {
            if let Some(k) = Self::first_read(&self.missing, &reads(&self.formula, &self.trace)) {
                return self.undefined_verdict(k);
            }
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
            first_violation_s: (r <= 0.0).then(|| match self.times.len() {
                0 => 0.0,
                n => self.first_violation_s(n),
            }),
            metrics: vec![],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Signals;

    /// Feeds `x` at 60 Hz until the monitor settles; its verdict and how many samples it took.
    fn run(formula: &str, x: impl Fn(usize) -> f64, n: usize) -> (Verdict, usize) {
        let mut m = StlMonitor::new("stl", super::super::parse(formula).unwrap());
        let mut fed = 0;
        for i in 0..n {
            let mut s = Signals::new();
            s.set("x", x(i));
            fed += 1;
            if m.observe(&Frame {
                t_s: i as f64 / 60.0,
                signals: &s,
            })
            .is_break()
            {
                break;
            }
        }
        (m.verdict(), fed)
    }

    #[test]
    fn a_satisfied_formula_keeps_observing_and_reports_the_traces_robustness() {
        // x rises 1 per sample: F[0,10] x > 60 holds from sample 61 on, and its robustness
        // over 600 samples is the largest margin, 599 - 60, not the margin when it was decided.
        let (v, fed) = run("F[0,10] (x > 60)", |i| i as f64, 600);
        assert_eq!(fed, 600);
        assert!(v.passed);
        assert_eq!(v.robustness, 539.0);
    }

    #[test]
    fn the_first_violation_is_the_sample_that_decides_it_not_the_check_that_saw_it() {
        // x = i: x < 30 fails from sample 30 (robustness 0 is a violation), at 0.5 s; the
        // check every 15 samples sees it at sample 44.
        let (v, fed) = run("G[0,10] (x < 30)", |i| i as f64, 600);
        assert_eq!((fed, v.first_violation_s), (45, Some(30.0 / 60.0)));
        // Violated from the first sample.
        let (v, _) = run("G[0,4] (x > 6.5)", |_| 6.0, 600);
        assert_eq!(v.first_violation_s, Some(0.0));
        // A trace that ends before a check: the verdict at the end finds it too.
        let (v, fed) = run("G[0,10] (x < 30)", |i| i as f64, 40);
        assert_eq!((fed, v.passed, v.first_violation_s), (40, false, Some(0.5)));
        // Decided only by the end of the trace (the window reaches past it): its last sample.
        let (v, _) = run("F[0,10] (x > 1000)", |i| i as f64, 100);
        assert_eq!((v.passed, v.first_violation_s), (false, Some(99.0 / 60.0)));
    }

    #[test]
    fn a_formula_of_constants_has_the_robustness_of_its_comparison() {
        for (formula, expected) in [("G[0,1] (3 > 2)", 1.0), ("F[0,1] (2 >= 3)", -1.0)] {
            let (v, _) = run(formula, |_| 0.0, 120);
            assert_eq!(v.robustness, expected, "{formula}");
            assert_eq!(v.passed, expected > 0.0, "{formula}");
        }
    }

    #[test]
    fn a_stop_between_checks_settles_a_formula_the_frames_already_violate() {
        // 40 samples end before the check at sample 45: x reached 30 at sample 30.
        let mut m = StlMonitor::new("stl", super::super::parse("G[0,10] (x < 30)").unwrap());
        let mut n = StlMonitor::new("ok", super::super::parse("G[0,10] (x < 300)").unwrap());
        for i in 0..40 {
            let mut s = Signals::new();
            s.set("x", i as f64);
            let f = Frame {
                t_s: i as f64 / 60.0,
                signals: &s,
            };
            assert!(m.observe(&f).is_continue() && n.observe(&f).is_continue());
        }
        assert!(m.settle_now());
        let v = m.verdict();
        assert_eq!((v.passed, v.first_violation_s), (false, Some(0.5)));
        assert!(v.robustness <= 0.0);
        // Not yet violated: not settled, still passing so far.
        assert!(!n.settle_now());
        assert!(n.verdict().passed);
    }

    #[test]
    fn a_nan_sample_fails_the_formula_where_it_comes() {
        // x is NaN from sample 30 on: G took the minimum over the others and passed with 1.
        for formula in [
            "G[0,1] (x > 0)",
            "F[0,1] (x > 0)",
            "G[0,10] (x > 0 | x < 5)",
        ] {
            let (v, fed) = run(formula, |i| if i >= 30 { f64::NAN } else { 1.0 }, 120);
            assert_eq!(
                (v.passed, v.robustness, v.first_violation_s, fed),
                (false, f64::NEG_INFINITY, Some(0.5), 31),
                "{formula}"
            );
        }
        // All NaN: failed at the first sample, with its time.
        let (v, _) = run("G[0,1] (x > 0)", |_| f64::NAN, 120);
        assert_eq!((v.passed, v.first_violation_s), (false, Some(0.0)));
    }

    #[test]
    fn a_missing_sample_the_formula_does_not_read_changes_nothing() {
        // x has no value for the first 0.1 s (a Signal that fires late): G[0.5,10] reads
        // x from 0.5 s on, so it passes with the margin of x = 8 over 7 (it failed at t = 0).
        let late = |i: usize| if i < 6 { f64::NAN } else { 8.0 };
        let (v, fed) = run("G[0.5,10] (x > 7)", late, 900);
        assert_eq!((v.passed, v.robustness, fed), (true, 1.0, 900));
        // Two windows with a gap: NaN in the gap (2 to 4 s) is read by neither.
        let gap = |i: usize| {
            if (120..240).contains(&i) {
                f64::NAN
            } else {
                1.0
            }
        };
        let (v, _) = run("G[0,1] (x > 0) & G[5,6] (x > 0)", gap, 900);
        assert_eq!((v.passed, v.robustness), (true, 1.0));
        // U[0,2] reads its left operand from 0 up to the sample before 2 s, its right one
        // over [0, 2]: NaN at 3 s is read by neither.
        let (v, _) = run(
            "(x > 0) U[0,2] (x > 5)",
            |i| match i {
                180 => f64::NAN,
                i if i >= 60 => 6.0,
                _ => 1.0,
            },
            900,
        );
        assert_eq!((v.passed, v.robustness), (true, 1.0));
        // Read by the window: failed at -inf where it comes, as before.
        let (v, fed) = run("G[0.05,10] (x > 7)", late, 900);
        assert_eq!(
            (v.passed, v.robustness, v.first_violation_s, fed),
            (false, f64::NEG_INFINITY, Some(3.0 / 60.0), 4)
        );
        let (v, _) = run("F[2,3] (x > 0)", gap, 900);
        assert_eq!((v.passed, v.first_violation_s), (false, Some(2.0)));
        // A violation decided before the missing sample keeps its own time.
        let (v, _) = run(
            "G[0,10] (x < 30)",
            |i| if i >= 40 { f64::NAN } else { i as f64 },
            900,
        );
        assert_eq!((v.passed, v.first_violation_s), (false, Some(0.5)));
    }

    #[test]
    fn a_violated_formula_settles_at_once() {
        let (v, fed) = run("G[0,10] (x < 30)", |i| i as f64, 600);
        assert!(!v.passed);
        assert!(fed < 60, "{fed}");
        assert!(v.robustness <= 0.0);
    }
}
