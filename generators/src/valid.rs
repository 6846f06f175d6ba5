//! Every generator over a constrained space draws valid points only: [`ValidOnly`] wraps it.

use std::collections::VecDeque;

use crate::{Generator, GeneratorError, ParamSpace, Point};

/// The most invalid points in a row [`ValidOnly`] passes over before it gives up (the valid
/// region is then too thin to sample).
pub const MAX_REJECTED_IN_A_ROW: u64 = 1_000_000;

/// A generator whose points break no constraint of its space
/// ([`ParamSpace::with_constraints`]): [`crate::Strategy`] wraps every generator of a
/// constrained space in it.
///
/// - A sampler (random, Halton, Sobol, a covering suite, the full-factorial design) has its
///   invalid points skipped: the valid points come in the sampler's order, whatever the
///   chunks they are asked in, so a shard and a resumed campaign get the same points. The
///   valid points of a low-discrepancy sequence are the sequence restricted to the valid
///   region (docs/coverage.md measures what that does to its discrepancy).
/// - An adaptive falsifier has the valid points of each batch run; each invalid one is told
///   back to it, without being run, at a penalty robustness: the largest robustness told so
///   far, and at least 0 (a point that falsifies nothing), so its search turns away from the
///   forbidden region.
pub struct ValidOnly {
    inner: Box<dyn Generator>,
    space: ParamSpace,
    /// Valid points drawn from `inner` but not yet handed out.
    buffer: VecDeque<Point>,
    /// An adaptive generator's last batch with each point's validity, until it is told.
    pending: Option<Vec<(Point, bool)>>,
    /// The largest robustness told so far (at least 0): the penalty of an invalid point.
    penalty: f64,
}

impl std::fmt::Debug for ValidOnly {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ValidOnly({})", self.inner.name())
    }
}

impl ValidOnly {
    /// `inner`'s valid points over `space`.
    pub fn new(inner: Box<dyn Generator>, space: &ParamSpace) -> Self {
        ValidOnly {
            inner,
            space: space.clone(),
            buffer: VecDeque::new(),
            pending: None,
            penalty: 0.0,
        }
    }

    /// Which of `points` are valid.
    fn flags(&self, points: &[Point]) -> Result<Vec<bool>, GeneratorError> {
        points.iter().map(|p| self.space.is_valid(p)).collect()
    }

    fn ask_adaptive(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let mut rejected = 0u64;
        loop {
            let batch = self.inner.ask(n)?;
            if batch.is_empty() {
                return Ok(batch);
            }
            let flags = self.flags(&batch)?;
            if flags.iter().any(|&v| v) {
                let out = (batch.iter().zip(&flags))
                    .filter(|(_, &v)| v)
                    .map(|(p, _)| p.clone())
                    .collect();
                self.pending = Some(batch.into_iter().zip(flags).collect());
                return Ok(out);
            }
            rejected += batch.len() as u64;
            if rejected > MAX_REJECTED_IN_A_ROW {
                return Err(self.space.no_valid_point(rejected));
            }
            let told: Vec<(Point, f64)> = batch.into_iter().map(|p| (p, self.penalty)).collect();
            self.inner.tell(&told);
        }
    }

    fn ask_sampled(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let mut out: Vec<Point> = Vec::with_capacity(n);
        while out.len() < n {
            if let Some(p) = self.buffer.pop_front() {
                out.push(p);
                continue;
            }
            let mut rejected = 0u64;
            while self.buffer.is_empty() {
                let want = n - out.len();
                let drawn = self.inner.ask(want)?;
                let flags = self.flags(&drawn)?;
                rejected += flags.iter().filter(|&&v| !v).count() as u64;
                self.buffer.extend(
                    drawn
                        .into_iter()
                        .zip(flags)
                        .filter(|(_, v)| *v)
                        .map(|(p, _)| p),
                );
                if self.buffer.is_empty() && rejected > MAX_REJECTED_IN_A_ROW {
                    return Err(self.space.no_valid_point(rejected));
                }
            }
        }
        Ok(out)
    }
}

impl Generator for ValidOnly {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        if self.inner.batch().is_some() {
            self.ask_adaptive(n)
        } else {
            self.ask_sampled(n)
        }
    }

    fn tell(&mut self, evaluated: &[(Point, f64)]) {
        for (_, r) in evaluated {
            if r.is_finite() {
                self.penalty = self.penalty.max(*r);
            }
        }
        let Some(pending) = self.pending.take() else {
            self.inner.tell(evaluated);
            return;
        };
        let mut runs = evaluated.iter();
        let merged: Vec<(Point, f64)> = pending
            .into_iter()
            .filter_map(|(p, valid)| {
                if valid {
                    runs.next().map(|(q, r)| (q.clone(), *r))
                } else {
                    Some((p, self.penalty))
                }
            })
            .collect();
        self.inner.tell(&merged);
    }

    fn batch(&self) -> Option<usize> {
        self.inner.batch()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::{Assignment, FnConstraint, Strategy};

    fn half_disc() -> ParamSpace {
        ParamSpace::unit_cube(2).with_constraints(vec![Arc::new(FnConstraint::new(
            "inside",
            |a: &Assignment| {
                let (x, y) = (a.real("x0").unwrap(), a.real("x1").unwrap());
                (x - 0.5).powi(2) + (y - 0.5).powi(2) < 0.16
            },
        ))])
    }

    #[test]
    fn skipped_points_come_in_the_same_order_whatever_the_chunks() {
        let s = half_disc();
        let whole = Strategy::Halton.build(&s, 0).unwrap().ask(300).unwrap();
        let mut g = Strategy::Halton.build(&s, 0).unwrap();
        let mut parts = g.ask(7).unwrap();
        g.skip(100).unwrap();
        parts.extend(g.ask(193).unwrap());
        assert_eq!(&whole[..7], &parts[..7]);
        assert_eq!(&whole[107..], &parts[7..]);
        assert!(whole.iter().all(|p| s.is_valid(p).unwrap()));
        // They are the unconstrained sequence's valid points, in its order.
        let all = Strategy::Halton
            .build(&s.unconstrained(), 0)
            .unwrap()
            .ask(600)
            .unwrap();
        let kept: Vec<Point> = all
            .into_iter()
            .filter(|p| s.is_valid(p).unwrap())
            .take(300)
            .collect();
        assert_eq!(kept, whole);
    }

    #[test]
    fn a_falsifier_is_told_every_point_it_asked_for() {
        let s = half_disc();
        let mut g = Strategy::FalsifyCe.build(&s, 3).unwrap();
        let b = g.batch().unwrap();
        let mut ran = 0;
        for _ in 0..20 {
            let pts = g.ask(b).unwrap();
            assert!(pts.iter().all(|p| s.is_valid(p).unwrap()));
            let told: Vec<(Point, f64)> = pts
                .iter()
                .map(|p| (p.clone(), p.continuous[0] - 0.2))
                .collect();
            ran += told.len();
            g.tell(&told);
        }
        assert!(ran > 0);
    }

    #[test]
    fn a_region_too_thin_to_sample_is_an_error_not_a_hang() {
        let s = ParamSpace::unit_cube(1).with_constraints(vec![Arc::new(FnConstraint::new(
            "never",
            |_: &Assignment| false,
        ))]);
        let e = Strategy::Random.build(&s, 0).unwrap().ask(1).unwrap_err();
        assert!(matches!(e, GeneratorError::NoValidPoint { .. }), "{e}");
    }
}
