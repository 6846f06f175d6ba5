//! Offline robustness over a whole trace.

use std::collections::BTreeMap;

use super::window::{sliding_max, sliding_min};
use super::{Cmp, Formula, StlError};

/// A uniformly sampled trace: named signals, each `n` samples, `dt_s` seconds apart, the
/// first at time 0.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trace {
    /// Sampling period in seconds, `> 0`.
    pub dt_s: f64,
    /// Samples by signal name, all of the same length.
    pub signals: BTreeMap<String, Vec<f64>>,
}

impl Trace {
    /// Number of samples (0 without signals).
    pub fn len(&self) -> usize {
        self.signals.values().next().map_or(0, Vec::len)
    }

    /// Whether the trace has no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn check(&self) -> Result<(), StlError> {
        if !(self.dt_s.is_finite() && self.dt_s > 0.0) {
            return Err(StlError::Trace(format!(
                "step {} s is not positive",
                self.dt_s
            )));
        }
        let n = self.len();
        if let Some((name, v)) = self.signals.iter().find(|(_, v)| v.len() != n) {
            return Err(StlError::Trace(format!(
                "signal `{name}` has {} samples, others {n}",
                v.len()
            )));
        }
        Ok(())
    }

    /// The sample offsets `[a/dt, b/dt]` of a time interval `[a, b]` in seconds (a bound that
    /// falls between samples rounds inward, within 1e-9 of a sample it counts as on it).
    fn steps(&self, a: f64, b: f64) -> (usize, usize) {
        let lo = (a / self.dt_s - 1e-9).ceil().max(0.0) as usize;
        let hi = (b / self.dt_s + 1e-9).floor().max(0.0) as usize;
        (lo, hi.max(lo))
    }
}

/// The robustness of `f` at every sample of `trace`: `out[i]` is ρ(f, trace, i) (module docs).
///
/// # Errors
/// [`StlError::MissingSignal`] for a signal the trace lacks; [`StlError::Trace`] for a
/// malformed trace.
pub fn robustness(f: &Formula, trace: &Trace) -> Result<Vec<f64>, StlError> {
    trace.check()?;
    eval(f, trace)
}

fn eval(f: &Formula, t: &Trace) -> Result<Vec<f64>, StlError> {
    let n = t.len();
    Ok(match f {
        Formula::True => vec![f64::INFINITY; n],
        Formula::False => vec![f64::NEG_INFINITY; n],
        Formula::Pred { terms, op, value } => {
            // Σ c·x, summed in the order written; a single term with coefficient 1 is the
            // signal itself, bit for bit.
            let mut sum = vec![0.0; n];
            for (k, (c, signal)) in terms.iter().enumerate() {
                let x = t
                    .signals
                    .get(signal)
                    .ok_or_else(|| StlError::MissingSignal(signal.clone()))?;
                for (s, v) in sum.iter_mut().zip(x) {
                    *s = if k == 0 { c * v } else { *s + c * v };
                }
            }
            match op {
                Cmp::Gt | Cmp::Ge => sum.iter().map(|v| v - value).collect(),
                Cmp::Lt | Cmp::Le => sum.iter().map(|v| value - v).collect(),
            }
        }
        Formula::Not(g) => eval(g, t)?.into_iter().map(|r| -r).collect(),
        Formula::And(a, b) => zip(eval(a, t)?, eval(b, t)?, f64::min),
        Formula::Or(a, b) => zip(eval(a, t)?, eval(b, t)?, f64::max),
        Formula::Implies(a, b) => zip(eval(a, t)?, eval(b, t)?, |x, y| (-x).max(y)),
        Formula::Globally(a, b, g) => {
            let (lo, hi) = t.steps(*a, *b);
            sliding_min(&eval(g, t)?, lo, hi)
        }
        Formula::Eventually(a, b, g) => {
            let (lo, hi) = t.steps(*a, *b);
            sliding_max(&eval(g, t)?, lo, hi)
        }
        Formula::Until(a, b, left, right) => {
            let (lo, hi) = t.steps(*a, *b);
            until(&eval(left, t)?, &eval(right, t)?, lo, hi)
        }
    })
}

/// The samples of each signal that the robustness at sample 0 reads, as inclusive ranges of
/// sample indices (not cut at the trace's end): a predicate reads its own sample, `G`/`F` over
/// `[a, b]` shift their operand's samples by `[a/dt, b/dt]`, and `U[a, b]` reads its right
/// operand there and its left from the sample itself to one before the window's end.
/// A value at any other sample changes nothing at sample 0.
pub(crate) fn reads(f: &Formula, trace: &Trace) -> BTreeMap<String, Vec<(usize, usize)>> {
    fn walk(
        f: &Formula,
        t: &Trace,
        (lo, hi): (usize, usize),
        out: &mut BTreeMap<String, Vec<(usize, usize)>>,
    ) {
        match f {
            Formula::True | Formula::False => {}
            Formula::Pred { terms, .. } => {
                for (_, signal) in terms {
                    out.entry(signal.clone()).or_default().push((lo, hi));
                }
            }
            Formula::Not(g) => walk(g, t, (lo, hi), out),
            Formula::And(a, b) | Formula::Or(a, b) | Formula::Implies(a, b) => {
                walk(a, t, (lo, hi), out);
                walk(b, t, (lo, hi), out);
            }
            Formula::Globally(a, b, g) | Formula::Eventually(a, b, g) => {
                let (wl, wh) = t.steps(*a, *b);
                walk(g, t, (lo.saturating_add(wl), hi.saturating_add(wh)), out);
            }
            Formula::Until(a, b, left, right) => {
                let (wl, wh) = t.steps(*a, *b);
                walk(
                    right,
                    t,
                    (lo.saturating_add(wl), hi.saturating_add(wh)),
                    out,
                );
                // min over k in [i, j), j <= i + wh.
                if wh > 0 {
                    walk(left, t, (lo, hi.saturating_add(wh - 1)), out);
                }
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(f, trace, (0, 0), &mut out);
    out
}

/// Bounds `(lower, upper)` of the robustness at sample 0 over every continuation of `trace`:
/// the trace is extended by the formula's horizon with unknown samples, which count as `-inf`
/// in the lower bound and `+inf` in the upper (robustness is monotone in every predicate
/// value, negation swapping the two).
///
/// # Errors
/// As [`robustness`].
pub fn eval_bounds(f: &Formula, trace: &Trace) -> Result<(f64, f64), StlError> {
    trace.check()?;
    let known = trace.len();
    let horizon = trace.steps(0.0, horizon_s(f)).1;
    let (lo, hi) = bounds(f, trace, known, known + horizon)?;
    Ok((
        lo.first().copied().unwrap_or(f64::NEG_INFINITY),
        hi.first().copied().unwrap_or(f64::INFINITY),
    ))
}

/// How far ahead of a sample `f` looks, in seconds.
fn horizon_s(f: &Formula) -> f64 {
    match f {
        Formula::True | Formula::False | Formula::Pred { .. } => 0.0,
        Formula::Not(g) => horizon_s(g),
        Formula::And(a, b) | Formula::Or(a, b) | Formula::Implies(a, b) => {
            horizon_s(a).max(horizon_s(b))
        }
        Formula::Globally(_, hi, g) | Formula::Eventually(_, hi, g) => hi + horizon_s(g),
        Formula::Until(_, hi, a, b) => hi + horizon_s(a).max(horizon_s(b)),
    }
}

type Bounds = (Vec<f64>, Vec<f64>);

fn bounds(f: &Formula, t: &Trace, known: usize, len: usize) -> Result<Bounds, StlError> {
    let both = |v: f64| (vec![v; len], vec![v; len]);
    Ok(match f {
        Formula::True => both(f64::INFINITY),
        Formula::False => both(f64::NEG_INFINITY),
        Formula::Pred { .. } => {
            let mut known_values = eval(f, t)?;
            known_values.truncate(known);
            let pad = |v: f64| {
                let mut out = known_values.clone();
                out.resize(len, v);
                out
            };
            (pad(f64::NEG_INFINITY), pad(f64::INFINITY))
        }
        Formula::Not(g) => {
            let (lo, hi) = bounds(g, t, known, len)?;
            (
                hi.into_iter().map(|r| -r).collect(),
                lo.into_iter().map(|r| -r).collect(),
            )
        }
        Formula::And(a, b) | Formula::Or(a, b) => {
            let ((alo, ahi), (blo, bhi)) = (bounds(a, t, known, len)?, bounds(b, t, known, len)?);
            let op = if matches!(f, Formula::And(..)) {
                f64::min
            } else {
                f64::max
            };
            (zip(alo, blo, op), zip(ahi, bhi, op))
        }
        Formula::Implies(a, b) => {
            let ((alo, ahi), (blo, bhi)) = (bounds(a, t, known, len)?, bounds(b, t, known, len)?);
            (
                zip(ahi, blo, |x, y| (-x).max(y)),
                zip(alo, bhi, |x, y| (-x).max(y)),
            )
        }
        Formula::Globally(a, b, g) | Formula::Eventually(a, b, g) => {
            let (lo_w, hi_w) = t.steps(*a, *b);
            let (glo, ghi) = bounds(g, t, known, len)?;
            if matches!(f, Formula::Globally(..)) {
                (sliding_min(&glo, lo_w, hi_w), sliding_min(&ghi, lo_w, hi_w))
            } else {
                (sliding_max(&glo, lo_w, hi_w), sliding_max(&ghi, lo_w, hi_w))
            }
        }
        Formula::Until(a, b, left, right) => {
            let (lo_w, hi_w) = t.steps(*a, *b);
            let ((llo, lhi), (rlo, rhi)) =
                (bounds(left, t, known, len)?, bounds(right, t, known, len)?);
            (until(&llo, &rlo, lo_w, hi_w), until(&lhi, &rhi, lo_w, hi_w))
        }
    })
}

fn zip(a: Vec<f64>, b: Vec<f64>, op: impl Fn(f64, f64) -> f64) -> Vec<f64> {
    a.into_iter().zip(b).map(|(x, y)| op(x, y)).collect()
}

/// `out[i] = max_{j ∈ [i+lo, i+hi], j < n} min(ψ(j), min_{k ∈ [i, j)} φ(k))`.
///
/// For each `i` the inner minimum over `[i, j)` grows one sample at a time as `j` advances,
/// so one pass over the window suffices: O(n · (hi − lo + 1) + n · lo).
fn until(phi: &[f64], psi: &[f64], lo: usize, hi: usize) -> Vec<f64> {
    let n = phi.len();
    let mut out = vec![f64::NEG_INFINITY; n];
    for (i, slot) in out.iter_mut().enumerate() {
        let mut prefix = f64::INFINITY; // min of φ over [i, j)
        let mut best = f64::NEG_INFINITY;
        for j in i..n.min(i.saturating_add(hi).saturating_add(1)) {
            if j >= i + lo {
                best = best.max(psi[j].min(prefix));
            }
            prefix = prefix.min(phi[j]);
        }
        *slot = best;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::parse;
    use super::*;
    use proptest::prelude::*;

    fn trace(a: &[f64], b: &[f64]) -> Trace {
        let mut signals = BTreeMap::new();
        signals.insert("a".to_owned(), a.to_vec());
        signals.insert("b".to_owned(), b.to_vec());
        Trace { dt_s: 1.0, signals }
    }

    fn rho(text: &str, t: &Trace) -> Vec<f64> {
        robustness(&parse(text).unwrap(), t).unwrap()
    }

    #[test]
    fn hand_computed_values() {
        let t = trace(&[1.0, -2.0, 3.0, 0.5], &[0.0, 2.0, 0.0, 5.0]);
        assert_eq!(rho("a > 0", &t), [1.0, -2.0, 3.0, 0.5]);
        assert_eq!(rho("b < 1", &t), [1.0, -1.0, 1.0, -4.0]);
        assert_eq!(rho("G[0,1] a > 0", &t), [-2.0, -2.0, 0.5, 0.5]);
        assert_eq!(
            rho("F[1,2] (a > 0)", &t),
            [3.0, 3.0, 0.5, f64::NEG_INFINITY]
        );
        assert_eq!(rho("a > 0 & b < 1", &t), [1.0, -2.0, 1.0, -4.0]);
        assert_eq!(rho("a > 0 -> b < 1", &t), [1.0, 2.0, 1.0, -0.5]);
        // a U[1,2] (b > 1): at 0, j = 1: min(ψ(1) = 1, φ(0) = 1) = 1; j = 2: min(-1, -2).
        assert_eq!(rho("a > 0 U[1,2] b > 1", &t)[0], 1.0);
        assert_eq!(rho("true", &t), [f64::INFINITY; 4]);
        assert_eq!(
            parse("G[0,10](a > 0 -> F[0,2](b < 1))").unwrap().signals(),
            ["a", "b"]
        );
    }

    #[test]
    fn bounds_contain_the_final_value_and_tighten_as_samples_come() {
        let full = trace(&[1.0, 2.0, -1.0, 3.0, 4.0], &[0.0; 5]);
        let f = parse("G[0,4] a > 0").unwrap();
        let last = robustness(&f, &full).unwrap()[0];
        for k in 1..=5 {
            let mut part = full.clone();
            for v in part.signals.values_mut() {
                v.truncate(k);
            }
            let (lo, hi) = eval_bounds(&f, &part).unwrap();
            assert!(lo <= last && last <= hi, "{k}: {lo} {last} {hi}");
            if k >= 3 {
                assert_eq!(hi, -1.0, "the violation at sample 2 settles it");
            }
        }
    }

    #[test]
    fn errors_show_the_column_and_name_the_problem() {
        let e = parse("G[0,1] (a > )").unwrap_err().to_string();
        assert!(
            e.contains("1:13") && e.contains('^') && e.contains("expected a signal or a number"),
            "{e}"
        );
        assert_eq!(parse("F[2,1] a > 0"), Err(StlError::Interval(2.0, 1.0)));
        let t = trace(&[1.0], &[1.0]);
        assert_eq!(
            robustness(&parse("c > 0").unwrap(), &t),
            Err(StlError::MissingSignal("c".into()))
        );
    }

    fn values() -> impl Strategy<Value = Vec<f64>> {
        prop::collection::vec(-10.0f64..10.0, 1..40)
    }

    proptest! {
        #[test]
        fn textbook_identities(a in values(), lo in 0u32..5, w in 0u32..5) {
            let b: Vec<f64> = a.iter().rev().copied().collect();
            let t = trace(&a, &b);
            let hi = lo + w;
            let eq = |x: &str, y: &str| -> Result<(), TestCaseError> {
                prop_assert_eq!(rho(x, &t), rho(y, &t), "{} vs {}", x, y);
                Ok(())
            };
            eq(&format!("F[{lo},{hi}] a > 1"), &format!("!G[{lo},{hi}] !(a > 1)"))?;
            eq(&format!("G[{lo},{hi}] (a > 1 & b < 2)"),
               &format!("G[{lo},{hi}] a > 1 & G[{lo},{hi}] b < 2"))?;
            eq(&format!("F[{lo},{hi}] a > 1"), &format!("true U[{lo},{hi}] a > 1"))?;
            eq("a > 1 -> b < 2", "!(a > 1) | b < 2")?;
        }

        /// `reads` holds every sample whose value can change the robustness at sample 0: a
        /// formula that reads a missing sample fails, and one it leaves out cannot matter.
        #[test]
        fn a_sample_outside_reads_never_changes_the_robustness_at_zero(
            a in values(), lo in 0u32..4, w in 0u32..4, which in 0usize..6,
        ) {
            let b: Vec<f64> = a.iter().map(|x| 3.0 - x).collect();
            let hi = lo + w;
            let formula = [
                format!("G[{lo},{hi}] a > 1"),
                format!("F[{lo},{hi}] (a > 1 & b < 2)"),
                format!("a > 0 U[{lo},{hi}] b > 1"),
                format!("G[0,{lo}] F[{lo},{hi}] a > 0 | b < 0"),
                format!("(G[{lo},{hi}] a > 0) & F[{hi},{}] b > 0", hi + 2),
                format!("!(a > 0 U[{lo},{hi}] (G[0,{w}] b > 1)) -> a < 3"),
            ][which].clone();
            let f = parse(&formula).unwrap();
            let t = trace(&a, &b);
            let read = reads(&f, &t);
            let base = robustness(&f, &t).unwrap()[0];
            for signal in ["a", "b"] {
                for k in 0..a.len() {
                    let in_reads = read
                        .get(signal)
                        .is_some_and(|r| r.iter().any(|&(l, h)| l <= k && k <= h));
                    for v in [-1e6, 1e6] {
                        let mut changed = t.clone();
                        changed.signals.get_mut(signal).unwrap()[k] = v;
                        let r = robustness(&f, &changed).unwrap()[0];
                        prop_assert!(
                            in_reads || r == base,
                            "{}: {}[{}] = {} changed {} to {} outside {:?}",
                            formula, signal, k, v, base, r, read
                        );
                    }
                }
            }
        }
    }
}
