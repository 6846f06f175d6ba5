//! Constraints on the open parameters: the valid region of a [`ParamSpace`].
//!
//! A logical scenario forbids some combinations of its parameters (OpenSCENARIO's
//! `ConstraintGroup`s, a program's `Require`, a space file's `[[constraint]]`). A space carries
//! its constraints as predicates over a test's values ([`Constraint`]); every generator draws
//! valid points only ([`crate::ValidOnly`]), and the estimators count the valid space.
//!
//! Two derived facts are computed once per space and shared by its clones:
//! - [`ParamSpace::valid_fraction`]: the share of the space the constraints leave, exact by
//!   enumeration for a small discrete space, else estimated from uniform random points with
//!   Wilson's 95 % score interval (Wilson 1927, "Probable inference, the law of succession,
//!   and statistical inference", JASA 22);
//! - [`ParamSpace::forbidden_levels`]: the combinations of discrete levels that no valid point
//!   holds, as the covering arrays' forbidden tuples ([`crate::covering::Constraints`]).

use std::fmt;
use std::sync::{Arc, OnceLock};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::covering::Constraints;
use crate::{Assignment, GeneratorError, Halton, ParamSpace, Point, UniformRandom};

/// Why a constraint cannot be evaluated at some values (or, for a constraint written as an
/// expression, cannot be built): the message names the constraint.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ConstraintError(pub String);

impl From<String> for ConstraintError {
    fn from(s: String) -> Self {
        ConstraintError(s)
    }
}

/// A constraint over the open parameters: a named predicate over a test's values.
pub trait Constraint: Send + Sync + fmt::Debug {
    /// The constraint's name, as messages and summaries give it (e.g. `the template's
    /// constraint groups`, `slow_in_lane_2`).
    fn name(&self) -> &str;

    /// `Ok(None)` when `values` (every parameter of the space, in its unit) meet the
    /// constraint; `Ok(Some(reason))` when they break it, `reason` saying how.
    ///
    /// # Errors
    /// [`ConstraintError`] when the constraint cannot be evaluated for these values.
    fn violation(&self, values: &Assignment) -> Result<Option<String>, ConstraintError>;
}

/// A [`Constraint`] from a Rust function that tells whether values are valid.
pub struct FnConstraint<F> {
    name: String,
    holds: F,
}

impl<F> FnConstraint<F>
where
    F: Fn(&Assignment) -> bool + Send + Sync,
{
    /// The constraint `name` that `holds` decides.
    pub fn new(name: &str, holds: F) -> Self {
        FnConstraint {
            name: name.to_owned(),
            holds,
        }
    }
}

impl<F> fmt::Debug for FnConstraint<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "FnConstraint({:?})", self.name)
    }
}

impl<F> Constraint for FnConstraint<F>
where
    F: Fn(&Assignment) -> bool + Send + Sync,
{
    fn name(&self) -> &str {
        &self.name
    }

    fn violation(&self, values: &Assignment) -> Result<Option<String>, ConstraintError> {
        Ok((!(self.holds)(values)).then(|| format!("breaks {}", self.name)))
    }
}

/// A constraint a point breaks ([`ParamSpace::violation`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Violation {
    /// The constraint's name.
    pub constraint: String,
    /// How the point breaks it.
    pub reason: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.constraint, self.reason)
    }
}

/// The share of a space that its constraints leave valid ([`ParamSpace::valid_fraction`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidFraction {
    /// Points found valid.
    pub valid: u64,
    /// Points tried.
    pub tried: u64,
    /// Whether every combination was tried (a discrete space of at most
    /// [`MAX_ENUMERATED_COMBINATIONS`] combinations): the fraction is then exact.
    pub exact: bool,
    /// `valid / tried`, in `[0, 1]`.
    pub fraction: f64,
    /// The lower end of Wilson's 95 % score interval (`fraction` when exact).
    pub lo: f64,
    /// The upper end of Wilson's 95 % score interval (`fraction` when exact).
    pub hi: f64,
}

impl fmt::Display for ValidFraction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.exact {
            write!(
                f,
                "{:.1} % valid ({} of {} combinations)",
                100.0 * self.fraction,
                self.valid,
                self.tried
            )
        } else {
            write!(
                f,
                "{:.1} % valid (95 % interval {:.1}–{:.1} %; {} of {} uniform random points)",
                100.0 * self.fraction,
                100.0 * self.lo,
                100.0 * self.hi,
                self.valid,
                self.tried
            )
        }
    }
}

/// The most combinations of discrete levels a constrained space enumerates: for its exact
/// valid fraction, and for the forbidden tuples of its covering arrays and k-wise coverage.
pub const MAX_ENUMERATED_COMBINATIONS: u64 = 1 << 20;

/// Uniform random points drawn to estimate the valid fraction of a space that is not
/// enumerated.
pub const VALID_FRACTION_SAMPLES: u64 = 4096;

/// The most points tried per combination of levels to find a valid completion of its
/// continuous parameters (Halton points), shared out of a total of 2^22 evaluations.
pub const MAX_PROBES_PER_COMBINATION: u64 = 64;

/// A space's constraints and what is derived from them, shared by the space's clones.
#[derive(Default)]
pub(crate) struct Rules {
    pub(crate) list: Vec<Arc<dyn Constraint>>,
    forbidden: OnceLock<Result<Option<Constraints>, GeneratorError>>,
    fraction: OnceLock<Result<ValidFraction, GeneratorError>>,
}

impl fmt::Debug for Rules {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list()
            .entries(self.list.iter().map(|c| c.name()))
            .finish()
    }
}

impl Rules {
    pub(crate) fn new(list: Vec<Arc<dyn Constraint>>) -> Self {
        Rules {
            list,
            ..Rules::default()
        }
    }
}

impl ParamSpace {
    /// The space with `constraints` added to its own: its valid region is where all hold.
    pub fn with_constraints(mut self, constraints: Vec<Arc<dyn Constraint>>) -> Self {
        let mut list = self.rules.list.clone();
        list.extend(constraints);
        self.rules = Arc::new(Rules::new(list));
        self
    }

    /// The space without its constraints.
    pub fn unconstrained(&self) -> ParamSpace {
        let mut s = self.clone();
        s.rules = Arc::default();
        s
    }

    /// The constraints, in the order they were added.
    pub fn constraints(&self) -> &[Arc<dyn Constraint>] {
        &self.rules.list
    }

    /// Whether the space has a constraint.
    pub fn is_constrained(&self) -> bool {
        !self.rules.list.is_empty()
    }

    /// The first constraint `point` breaks, `None` when it is valid.
    ///
    /// # Errors
    /// As [`ParamSpace::decode`]; [`GeneratorError::ConstraintFailed`] when a constraint
    /// cannot be evaluated at the point.
    pub fn violation(&self, point: &Point) -> Result<Option<Violation>, GeneratorError> {
        if !self.is_constrained() {
            return Ok(None);
        }
        let values = self.decode(point)?;
        for c in &self.rules.list {
            let broken = c
                .violation(&values)
                .map_err(|e| GeneratorError::ConstraintFailed {
                    name: c.name().to_owned(),
                    reason: e.0,
                })?;
            if let Some(reason) = broken {
                return Ok(Some(Violation {
                    constraint: c.name().to_owned(),
                    reason,
                }));
            }
        }
        Ok(None)
    }

    /// Whether `point` meets every constraint.
    ///
    /// # Errors
    /// As [`ParamSpace::violation`].
    pub fn is_valid(&self, point: &Point) -> Result<bool, GeneratorError> {
        Ok(self.violation(point)?.is_none())
    }

    /// The share of the space its constraints leave valid (1 without constraints), computed
    /// once and shared by the space's clones: exact for a space of discrete parameters only
    /// with at most [`MAX_ENUMERATED_COMBINATIONS`] combinations (every one tried), else
    /// estimated from [`VALID_FRACTION_SAMPLES`] uniform random points (ChaCha8, seed 0,
    /// densities ignored) with Wilson's 95 % score interval.
    ///
    /// # Errors
    /// [`GeneratorError::NoValidPoint`] when no point tried is valid: the load refuses such a
    /// space; [`GeneratorError::ConstraintFailed`] as [`ParamSpace::violation`].
    pub fn valid_fraction(&self) -> Result<ValidFraction, GeneratorError> {
        self.rules
            .fraction
            .get_or_init(|| self.compute_valid_fraction())
            .clone()
    }

    fn compute_valid_fraction(&self) -> Result<ValidFraction, GeneratorError> {
        let combinations = self.combinations();
        let (points, exact): (Vec<Point>, bool) = match combinations {
            Some(n) if self.continuous_dims() == 0 && n <= MAX_ENUMERATED_COMBINATIONS => {
                ((0..n).map(|i| self.combination(i)).collect(), true)
            }
            _ => {
                let plain = ParamSpace::new(
                    self.params()
                        .iter()
                        .map(|p| crate::Param {
                            density: None,
                            ..p.clone()
                        })
                        .collect(),
                )?;
                let mut g = UniformRandom::new(&plain, 0);
                use crate::Generator;
                (g.ask(VALID_FRACTION_SAMPLES as usize)?, false)
            }
        };
        let flags = self.validity(&points)?;
        let valid = flags.iter().filter(|&&v| v).count() as u64;
        let tried = flags.len() as u64;
        if self.is_constrained() && valid == 0 {
            return Err(self.no_valid_point(tried));
        }
        let fraction = valid as f64 / tried.max(1) as f64;
        let (lo, hi) = if exact {
            (fraction, fraction)
        } else {
            wilson(valid, tried)
        };
        Ok(ValidFraction {
            valid,
            tried,
            exact,
            fraction,
            lo,
            hi,
        })
    }

    /// The error of a space whose constraints left none of `tried` points valid.
    pub(crate) fn no_valid_point(&self, tried: u64) -> GeneratorError {
        GeneratorError::NoValidPoint {
            constraints: self
                .rules
                .list
                .iter()
                .map(|c| c.name().to_owned())
                .collect::<Vec<_>>()
                .join(", "),
            tried,
        }
    }

    /// Validity of each of `points`, in parallel (rayon), in their order.
    fn validity(&self, points: &[Point]) -> Result<Vec<bool>, GeneratorError> {
        points.par_iter().map(|p| self.is_valid(p)).collect()
    }

    /// The number of combinations of the discrete parameters' levels, `None` on overflow.
    fn combinations(&self) -> Option<u64> {
        self.level_counts()
            .iter()
            .try_fold(1u64, |a, &c| a.checked_mul(u64::from(c)))
    }

    /// Combination `i` in mixed-radix order (the first parameter slowest), continuous
    /// coordinates at 0.
    fn combination(&self, mut i: u64) -> Point {
        let counts = self.level_counts();
        let mut discrete = vec![0; counts.len()];
        for (k, &c) in counts.iter().enumerate().rev() {
            discrete[k] = (i % u64::from(c)) as u32;
            i /= u64::from(c);
        }
        Point {
            discrete,
            continuous: vec![0.0; self.continuous_dims()],
        }
    }

    /// The combinations of discrete levels that no valid point holds, as forbidden tuples
    /// for the covering arrays and k-wise coverage ([`Constraints`]); `None` without
    /// constraints or discrete parameters. Computed once and shared by the space's clones.
    ///
    /// Every combination of levels is tried (at most [`MAX_ENUMERATED_COMBINATIONS`]), each
    /// with up to [`MAX_PROBES_PER_COMBINATION`] Halton points over the continuous
    /// parameters (so a combination valid only on a sliver of them may be missed); the
    /// combinations without a valid point are then reduced to the single levels and pairs
    /// of levels all of whose completions are forbidden, the rest kept whole.
    ///
    /// # Errors
    /// [`GeneratorError::TooManyCombinations`] past the enumeration's limit;
    /// [`GeneratorError::NoValidPoint`] when every combination is forbidden;
    /// [`GeneratorError::ConstraintFailed`] as [`ParamSpace::violation`].
    pub fn forbidden_levels(&self) -> Result<Option<Constraints>, GeneratorError> {
        self.rules
            .forbidden
            .get_or_init(|| self.compute_forbidden())
            .clone()
    }

    fn compute_forbidden(&self) -> Result<Option<Constraints>, GeneratorError> {
        let levels = self.level_counts();
        if !self.is_constrained() || levels.is_empty() {
            return Ok(None);
        }
        let n = self
            .combinations()
            .filter(|&n| n <= MAX_ENUMERATED_COMBINATIONS)
            .ok_or(GeneratorError::TooManyCombinations {
                limit: MAX_ENUMERATED_COMBINATIONS,
            })?;
        let nc = self.continuous_dims();
        let probes = if nc == 0 {
            1
        } else {
            ((1u64 << 22) / n).clamp(1, MAX_PROBES_PER_COMBINATION)
        };
        let halton = Halton::new(&ParamSpace::unit_cube(nc));
        let rows: Vec<Vec<u32>> = (0..n)
            .into_par_iter()
            .map(|i| -> Result<Option<Vec<u32>>, GeneratorError> {
                let mut p = self.combination(i);
                for j in 0..probes {
                    p.continuous = halton.point(j).continuous;
                    if self.is_valid(&p)? {
                        return Ok(None);
                    }
                }
                Ok(Some(p.discrete))
            })
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .flatten()
            .collect();
        if rows.len() as u64 == n {
            return Err(self.no_valid_point(n * probes));
        }
        Ok(Some(reduce(&levels, rows)))
    }
}

/// The forbidden rows `rows` (full combinations of `levels`) as forbidden tuples: each single
/// level and pair of levels whose every completion is among `rows`, and the rows no such
/// tuple explains.
fn reduce(levels: &[u32], rows: Vec<Vec<u32>>) -> Constraints {
    let k = levels.len();
    let total: u64 = levels.iter().map(|&l| u64::from(l)).product();
    let mut tuples: Vec<Vec<(usize, u32)>> = Vec::new();
    for t in 1..=k.min(2) {
        for cols in crate::coverage::subsets(k, t) {
            let size: u64 = cols.iter().map(|&c| u64::from(levels[c])).product();
            let rest = total / size;
            let mut count = vec![0u64; size as usize];
            for r in &rows {
                let idx = cols
                    .iter()
                    .fold(0usize, |a, &c| a * levels[c] as usize + r[c] as usize);
                count[idx] += 1;
            }
            for (idx, &c) in count.iter().enumerate() {
                if c != rest {
                    continue;
                }
                let mut left = idx;
                let mut cells = vec![(0usize, 0u32); t];
                for (slot, &col) in cells.iter_mut().zip(&cols).rev() {
                    *slot = (col, (left % levels[col] as usize) as u32);
                    left /= levels[col] as usize;
                }
                // A pair holding a forbidden level is implied by it.
                let implied = tuples
                    .iter()
                    .any(|f| f.iter().all(|cell| cells.contains(cell)));
                if !implied {
                    tuples.push(cells);
                }
            }
        }
    }
    for r in rows {
        let explained = tuples.iter().any(|f| f.iter().all(|&(c, v)| r[c] == v));
        if !explained {
            tuples.push(r.into_iter().enumerate().collect());
        }
    }
    Constraints::new(tuples)
}

/// Wilson's 95 % score interval of a proportion `k / n` (Wilson 1927), clamped to `[0, 1]`.
pub fn wilson(k: u64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054_f64;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let denom = 1.0 + z * z / n;
    let centre = (p + z * z / (2.0 * n)) / denom;
    let half = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Param, Value};

    fn lanes_and_speed() -> ParamSpace {
        ParamSpace::new(vec![
            Param::levels("lane", vec![Value::Int(1), Value::Int(2), Value::Int(3)]),
            Param::levels("kind", vec![Value::Int(0), Value::Int(1)]),
            Param::interval("speed", 0.0, 40.0, "m/s"),
        ])
        .unwrap()
        .with_constraints(vec![Arc::new(FnConstraint::new(
            "slow_in_lane_2",
            |a: &Assignment| a.real("lane") != Some(2.0) || a.real("speed").unwrap() < 10.0,
        ))])
    }

    #[test]
    fn a_violation_names_its_constraint() {
        let s = lanes_and_speed();
        let fast_in_2 = Point {
            discrete: vec![1, 0],
            continuous: vec![0.5],
        };
        let v = s.violation(&fast_in_2).unwrap().unwrap();
        assert_eq!(v.constraint, "slow_in_lane_2");
        let slow_in_2 = Point {
            discrete: vec![1, 0],
            continuous: vec![0.1],
        };
        assert!(s.is_valid(&slow_in_2).unwrap());
    }

    #[test]
    fn the_valid_fraction_is_estimated_with_an_interval_around_the_truth() {
        // Valid: lanes 1 and 3 (2/3), and lane 2 below 10 m/s (1/3 × 1/4): 3/4.
        let f = lanes_and_speed().valid_fraction().unwrap();
        assert!(!f.exact);
        assert!(f.lo < 0.75 && 0.75 < f.hi, "{f:?}");
        assert!(f.hi - f.lo < 0.03, "{f:?}");
    }

    #[test]
    fn a_discrete_space_is_enumerated_exactly() {
        let s = ParamSpace::new(vec![
            Param::levels("a", vec![Value::Int(0), Value::Int(1), Value::Int(2)]),
            Param::levels("b", vec![Value::Int(0), Value::Int(1)]),
        ])
        .unwrap()
        .with_constraints(vec![Arc::new(FnConstraint::new(
            "a_not_2",
            |a: &Assignment| a.real("a") != Some(2.0),
        ))]);
        let f = s.valid_fraction().unwrap();
        assert!(f.exact);
        assert_eq!((f.valid, f.tried), (4, 6));
        // The forbidden level is found as a single level, not as its two rows.
        let cons = s.forbidden_levels().unwrap().unwrap();
        assert_eq!(cons.forbidden(), &[vec![(0, 2)]]);
    }

    #[test]
    fn a_space_whose_constraints_leave_nothing_is_refused() {
        let s = ParamSpace::unit_cube(2).with_constraints(vec![Arc::new(FnConstraint::new(
            "never",
            |_: &Assignment| false,
        ))]);
        let e = s.valid_fraction().unwrap_err();
        assert_eq!(
            e.to_string(),
            "the constraints (never) leave no valid point: none of 4096 points tried is valid"
        );
    }

    #[test]
    fn forbidden_pairs_are_found_where_the_continuous_part_cannot_help() {
        // Lane 2 with kind 1 is forbidden whatever the speed; lane 2 is fine with kind 0.
        let s = ParamSpace::new(vec![
            Param::levels("lane", vec![Value::Int(1), Value::Int(2), Value::Int(3)]),
            Param::levels("kind", vec![Value::Int(0), Value::Int(1)]),
            Param::interval("speed", 0.0, 40.0, "m/s"),
        ])
        .unwrap()
        .with_constraints(vec![Arc::new(FnConstraint::new(
            "pair",
            |a: &Assignment| !(a.real("lane") == Some(2.0) && a.real("kind") == Some(1.0)),
        ))]);
        let cons = s.forbidden_levels().unwrap().unwrap();
        assert_eq!(cons.forbidden(), &[vec![(0, 1), (1, 1)]]);
        // The speed constraint of lanes_and_speed leaves every combination some valid speed.
        let open = lanes_and_speed().forbidden_levels().unwrap().unwrap();
        assert!(open.is_empty());
    }

    #[test]
    fn wilson_brackets_the_proportion() {
        let (lo, hi) = wilson(50, 100);
        assert!((lo - 0.4038).abs() < 1e-3 && (hi - 0.5962).abs() < 1e-3);
        assert_eq!(wilson(0, 0), (0.0, 1.0));
    }
}
