//! The full-factorial design: every combination of the discrete parameters' levels, once
//! each, in mixed-radix order (the first parameter's level changes slowest). It is what an
//! OpenSCENARIO variation file's deterministic distributions enumerate (OpenSCENARIO 1.3 User
//! Guide, "Parameter value distributions": the combination of every deterministic
//! distribution), kept so a campaign can run a file's own grid exactly for comparison.

use crate::{Generator, GeneratorError, ParamSpace, Point};

/// Every combination of the levels of a space without continuous parameters.
#[derive(Debug, Clone)]
pub struct FullFactorial {
    counts: Vec<u32>,
    next: u64,
    size: u64,
}

impl FullFactorial {
    /// The design of `space`.
    ///
    /// # Errors
    /// [`GeneratorError::InvalidDomain`] for a space with a continuous parameter (a grid
    /// has no levels for it: open it with levels instead), and
    /// [`GeneratorError::CapacityExceeded`] when the combinations overflow `u64`.
    pub fn new(space: &ParamSpace) -> Result<Self, GeneratorError> {
        if let Some(p) = space
            .params()
            .iter()
            .find(|p| matches!(p.domain, crate::Domain::Interval { .. }))
        {
            return Err(GeneratorError::InvalidDomain {
                name: p.name.clone(),
                reason: "the full-factorial design takes discrete parameters only (levels, not an interval)".into(),
            });
        }
        let counts: Vec<u32> = space.level_counts();
        let size = counts
            .iter()
            .try_fold(1u64, |acc, &c| acc.checked_mul(u64::from(c)))
            .ok_or(GeneratorError::CapacityExceeded {
                generator: "full-factorial",
                limit: u64::MAX,
                what: "points",
                requested: u64::MAX,
            })?;
        Ok(FullFactorial {
            counts,
            next: 0,
            size,
        })
    }

    /// The number of combinations: the product of the level counts.
    pub fn size(&self) -> u64 {
        self.size
    }

    fn point(&self, mut i: u64) -> Point {
        let mut discrete = vec![0; self.counts.len()];
        for (k, &c) in self.counts.iter().enumerate().rev() {
            discrete[k] = (i % u64::from(c)) as u32;
            i /= u64::from(c);
        }
        Point {
            discrete,
            continuous: vec![],
        }
    }
}

impl Generator for FullFactorial {
    fn name(&self) -> &'static str {
        "full-factorial"
    }

    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let end = self.next.saturating_add(n as u64);
        if end > self.size {
            return Err(GeneratorError::CapacityExceeded {
                generator: "full-factorial",
                limit: self.size,
                what: "points (the product of the level counts)",
                requested: end,
            });
        }
        let out = (self.next..end).map(|i| self.point(i)).collect();
        self.next = end;
        Ok(out)
    }

    fn skip(&mut self, n: u64) -> Result<(), GeneratorError> {
        self.next = self.next.saturating_add(n);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Param, Value};

    #[test]
    fn every_combination_once_then_refuses_more() {
        let space = ParamSpace::new(vec![
            Param::levels("a", vec![Value::Int(1), Value::Int(2)]),
            Param::levels("b", vec![Value::Int(1), Value::Int(2), Value::Int(3)]),
        ])
        .unwrap();
        let mut g = FullFactorial::new(&space).unwrap();
        assert_eq!(g.size(), 6);
        let pts = g.ask(6).unwrap();
        let mut seen: Vec<Vec<u32>> = pts.iter().map(|p| p.discrete.clone()).collect();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), 6);
        assert_eq!(
            pts[1].discrete,
            vec![0, 1],
            "the last parameter changes fastest"
        );
        assert!(g.ask(1).is_err());
    }

    #[test]
    fn an_interval_is_refused() {
        let space = ParamSpace::new(vec![Param::interval("x", 0.0, 1.0, "m")]).unwrap();
        assert!(FullFactorial::new(&space).is_err());
    }
}
