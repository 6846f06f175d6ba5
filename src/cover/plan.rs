//! `paracosm-cover plan`: how many tests a (k, ε)-covering set needs.

use std::fmt;

use serde::Serialize;

use paracosm_generators::coverage::{
    dispersion, subset_products, CoverageError, DispersionOptions,
};
use paracosm_generators::covering::CoveringError;
use paracosm_generators::{Halton, ParamSpace};

/// Why [`plan`] or [`suite_per_row`] cannot count a test set.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// `ε` so small that a discrete group would need more than [`MAX_MEASURED`] Halton points.
    #[error(
        "ε = {epsilon:e} needs about {points:.3e} Halton points per discrete group, more than \
         the {max} whose dispersion a plan measures; give a larger --epsilon",
        max = MAX_MEASURED
    )]
    PointsPerGroup {
        /// The target dispersion.
        epsilon: f64,
        /// The points per group it needs, `ceil(C / ε)`.
        points: f64,
    },
    /// A row's dispersion could not be shown to be at most `ε` ([`suite_per_row`]): past the
    /// exact limits ([`PLAN_EXACT_MAX_POINTS`]) it is bracketed, and the bracket's upper end
    /// exceeds `ε`.
    #[error(
        "ε = {epsilon:e} needs about {points} Halton points per row in d = {dims}, past what \
         can be measured exactly (PLAN_EXACT_MAX_POINTS), and the bracket there cannot show \
         that a row's dispersion is at most ε; give a larger --epsilon, or --budget"
    )]
    Unmeasured {
        /// The target dispersion.
        epsilon: f64,
        /// The points per row estimated or tried.
        points: u64,
        /// Continuous dimensions.
        dims: usize,
    },
    /// Rows × points per group reach [`MAX_PLANNED`] tests.
    #[error(
        "the plan needs {rows} rows × {points} points, more than the {max} tests a \
         plan counts; give a larger --epsilon or --delta",
        max = MAX_PLANNED
    )]
    Tests {
        /// Rows of the random k-wise family.
        rows: u64,
        /// Halton points per row.
        points: u64,
    },
    /// The suite would write more than the command's limit.
    #[error(
        "a suite with every row's dispersion at most ε = {epsilon:e} needs {rows} rows \
         × {per_row} points or more, past the {max_points} this command writes; give a \
         larger --epsilon"
    )]
    Suite {
        /// The target dispersion.
        epsilon: f64,
        /// Rows of the covering array.
        rows: u64,
        /// Points per row tried.
        per_row: u64,
        /// The most points the command writes.
        max_points: u64,
    },
    /// The covering array cannot be built (a strength out of range).
    #[error(transparent)]
    Covering(#[from] CoveringError),
    /// A block's dispersion cannot be measured.
    #[error(transparent)]
    Coverage(#[from] CoverageError),
}

/// A test budget plan for a space.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plan {
    /// Strength `k`.
    pub strength: usize,
    /// Target dispersion `ε` of each discrete group's continuous part.
    pub epsilon: f64,
    /// Failure probability `δ` of the random k-wise family.
    pub delta: f64,
    /// Rows of a random k-wise family by Proposition 3.2, `2^k (k ln N − ln δ)`: valid for
    /// binary parameters; `None` unless every discrete parameter has 2 levels.
    pub random_kwise_prop32: Option<u64>,
    /// Rows of a random k-wise family by the union bound for mixed levels,
    /// `m = ceil(ln(T / δ) / −ln(1 − 1 / V))` with `T` the number of k-tuples and `V` the
    /// largest product of `k` level counts.
    pub random_kwise_union: Option<u64>,
    /// The smallest `m` with `Σ_tuples (1 − 1/Π_S v)^m <= δ` (the exact union bound).
    pub random_kwise_exact_union: Option<u64>,
    /// `n · dispersion` of the Halton sequence in the continuous dimension, measured at
    /// `n = 64, 256, 1024` (largest value; upper bounds where dispersion is bracketed).
    pub halton_constant: Option<f64>,
    /// Continuous dimensions of the space.
    pub continuous_dims: usize,
    /// Halton points per discrete group: the least `n` whose first `n` Halton points have a
    /// measured dispersion at most `ε` ([`halton_points_for`]).
    pub halton_per_group: Option<u64>,
    /// The measured dispersion of those points, in `[0, ε]` (the bracket's upper end where
    /// the dispersion is bracketed).
    pub halton_dispersion: Option<f64>,
    /// Whether that dispersion is exact (`false`: an upper bound, and fewer points may do).
    pub halton_dispersion_exact: Option<bool>,
    /// Whether `halton_per_group` was measured to meet `ε` ([`HaltonSize::verified`]); when
    /// `false` it is an estimate and `halton_dispersion` is `None`.
    pub halton_verified: Option<bool>,
    /// What `generate --strategy ipog` and `--strategy kwise` with `--epsilon ε` write for
    /// this space (filled by [`plan_suites`]; empty without discrete parameters, where both
    /// write `halton_per_group` points).
    pub suites: Vec<SuitePlan>,
    /// Total tests: rows × points per group (each factor 1 when absent).
    pub total: u64,
}

/// Plans a (k, ε)-covering test set for `space` (PARACOSM §3.2): a random k-wise family for
/// the discrete part (Proposition 3.2 and its union-bound form for mixed levels), and for each
/// of its rows a Halton set whose measured dispersion is at most `ε` ([`halton_points_for`]).
/// `suites` is left empty: [`plan_suites`] fills it.
///
/// # Errors
/// [`PlanError::PointsPerGroup`] when a group would need more than [`MAX_MEASURED`] points,
/// [`PlanError::Tests`] when the plan would count [`MAX_PLANNED`] tests or more,
/// [`PlanError::Coverage`] when a dispersion cannot be measured.
pub fn plan(
    space: &ParamSpace,
    strength: usize,
    epsilon: f64,
    delta: f64,
) -> Result<Plan, PlanError> {
    let levels = space.level_counts();
    let nd = levels.len();
    let k = strength.min(nd);
    let (mut prop32, mut union, mut exact) = (None, None, None);
    if nd > 0 && k > 0 {
        if levels.iter().all(|&v| v == 2) {
            let m = 2f64.powi(k as i32) * (k as f64 * (nd as f64).ln() - delta.ln());
            prop32 = Some(m.ceil().max(1.0) as u64);
        }
        let products = subset_products(&levels, k);
        let tuples: f64 = products.iter().sum();
        let vmax = products.iter().copied().fold(1.0, f64::max);
        union = Some(if vmax <= 1.0 {
            1
        } else {
            ((tuples / delta).ln() / -(1.0 - 1.0 / vmax).ln())
                .ceil()
                .max(1.0) as u64
        });
        let bound = |m: f64| -> f64 { products.iter().map(|&p| p * (1.0 - 1.0 / p).powf(m)).sum() };
        let (mut lo, mut hi) = (0u64, union.unwrap_or(1).max(1));
        while lo < hi {
            let mid = (lo + hi) / 2;
            if bound(mid as f64) <= delta {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        exact = Some(lo.max(1));
    }
    let nc = space.continuous_dims();
    let halton = if nc > 0 {
        Some(halton_points_for(space, epsilon)?)
    } else {
        None
    };
    let per_group = halton.as_ref().map(|h| h.points);
    let rows = exact.unwrap_or(1);
    let total = rows
        .checked_mul(per_group.unwrap_or(1))
        .filter(|&t| t < MAX_PLANNED)
        .ok_or(PlanError::Tests {
            rows,
            points: per_group.unwrap_or(1),
        })?;
    Ok(Plan {
        strength: k,
        epsilon,
        delta,
        random_kwise_prop32: prop32,
        random_kwise_union: union,
        random_kwise_exact_union: exact,
        continuous_dims: nc,
        halton_constant: halton.as_ref().map(|h| h.constant),
        halton_per_group: per_group,
        halton_dispersion: halton.as_ref().and_then(|h| h.dispersion),
        halton_dispersion_exact: halton.as_ref().map(|h| h.exact),
        halton_verified: halton.as_ref().map(|h| h.verified),
        suites: Vec::new(),
        total,
    })
}

/// The most tests a plan counts, 2^53 (every count below it is exact as a float, and no
/// campaign comes near it).
pub const MAX_PLANNED: u64 = 1 << 53;

/// The most points whose dispersion a plan measures, 2^21 (about 1.3 s in `d = 2` on 2 cores):
/// a smaller `ε` is refused ([`PlanError::PointsPerGroup`]).
pub const MAX_MEASURED: u64 = 1 << 21;

/// The exact-dispersion limits a plan measures with (as
/// [`DispersionOptions::exact_max_points`], for `d = 3, 4, 5, 6`): higher than the default,
/// since a plan needs the value, not a bracket. The slowest, `d = 3` at 65,536 points, takes a
/// few minutes on 2 cores (70 s at 32,768, measured 2026-11-27).
pub const PLAN_EXACT_MAX_POINTS: [usize; 4] = [65_536, 4_000, 120, 60];

/// The Halton prefix a plan gives each discrete group ([`halton_points_for`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HaltonSize {
    /// `C = max n · dispersion(E_n)` over `n = 64, 256, 1024`: the first guess is `ceil(C / ε)`.
    pub constant: f64,
    /// Points `n`: the least whose measured dispersion is at most `ε` (see
    /// [`halton_points_for`]); when not `verified`, an estimate.
    pub points: u64,
    /// The measured dispersion of the first `points` points, in `[0, ε]`; `None` when not
    /// `verified`.
    pub dispersion: Option<f64>,
    /// Whether `dispersion` is exact rather than a bracket's upper end.
    pub exact: bool,
    /// Whether the dispersion of the first `points` points was shown to be at most `ε`.
    /// `false` past [`PLAN_EXACT_MAX_POINTS`] where the bracket is too loose (`d >= 4` with
    /// small `ε`, `d >= 5` almost always): `points` is then `ceil(C' / ε)` with `C'` the
    /// largest `n · dispersion` measured, and since Halton's `n · dispersion` keeps growing
    /// with `n`, the set may miss `ε`.
    pub verified: bool,
}

/// The number of leading Halton points over the continuous dimensions of `space` whose
/// dispersion (PARACOSM §3.1) is measured to be at most `epsilon`.
///
/// The first guess is `ceil(C / ε)` with `C` the constant measured at `n = 64, 256, 1024`
/// (Proposition 3.3: dispersion is `O(1/n)`); but `n · dispersion` keeps growing with `n` for
/// Halton points (by a log factor), so the guess alone falls short for small `ε` (in `d = 2`,
/// `ε = 0.001` gave 5,268 points of dispersion 1.05e-3). The guess is measured and raised in
/// proportion to the shortfall until it holds, then a bisection finds the least prefix that
/// holds. The first `n` points are a subset of the first `n + 1`, so the exact dispersion never
/// grows with `n`: in `d <= 2` the result is the least such `n`, in `d >= 3` within 4 % above
/// it (each measurement there costs seconds to minutes). Measurements are exact up to
/// [`PLAN_EXACT_MAX_POINTS`]; past them a bracket whose upper end meets `ε` is accepted (fewer
/// points may then in truth do), and where one does not, the result is an estimate marked
/// [`HaltonSize::verified`] `false`.
///
/// # Errors
/// [`PlanError::PointsPerGroup`] when a guess passes [`MAX_MEASURED`] points;
/// [`PlanError::Coverage`] when a dispersion cannot be measured. Without a continuous
/// dimension the result is 1 point of dispersion 0.
pub fn halton_points_for(space: &ParamSpace, epsilon: f64) -> Result<HaltonSize, PlanError> {
    let nc = space.continuous_dims();
    if nc == 0 {
        return Ok(HaltonSize {
            constant: 0.0,
            points: 1,
            dispersion: Some(0.0),
            exact: true,
            verified: true,
        });
    }
    let h = Halton::new(space);
    let options = DispersionOptions {
        exact_max_points: PLAN_EXACT_MAX_POINTS.to_vec(),
        ..DispersionOptions::default()
    };
    let measure = |n: u64| dispersion(&h.unit_points(0, n as usize), nc, &options);
    let mut constant: f64 = 0.0;
    for n in [64u64, 256, 1024] {
        constant = constant.max(n as f64 * measure(n)?.upper);
    }
    let guess = (constant / epsilon).ceil().max(1.0);
    if guess > MAX_MEASURED as f64 {
        return Err(PlanError::PointsPerGroup {
            epsilon,
            points: guess,
        });
    }
    // The largest n · dispersion measured exactly: an unverified plan's estimate.
    let seen = std::cell::Cell::new(constant);
    let checked = |n: u64| -> Result<Option<(f64, bool)>, PlanError> {
        let d = measure(n)?;
        if !d.exact && d.upper > epsilon {
            return Ok(None);
        }
        if d.exact {
            seen.set(seen.get().max(n as f64 * d.upper));
        }
        Ok(Some((d.upper, d.exact)))
    };
    match search(epsilon, nc, guess as u64, checked)? {
        Some((points, (dispersion, exact))) => Ok(HaltonSize {
            constant,
            points,
            dispersion: Some(dispersion),
            exact,
            verified: true,
        }),
        None => {
            let points = (seen.get() / epsilon).ceil().max(guess);
            if points > MAX_MEASURED as f64 {
                return Err(PlanError::PointsPerGroup { epsilon, points });
            }
            Ok(HaltonSize {
                constant,
                points: points as u64,
                dispersion: None,
                exact: false,
                verified: false,
            })
        }
    }
}

/// The search of [`halton_points_for`] from `guess` points: `measure(n)` gives the dispersion
/// of the first `n` points and whether it is exact, or `None` where it cannot be shown to meet
/// `ε`, which ends the search with `None`.
#[allow(clippy::type_complexity)]
fn search(
    epsilon: f64,
    nc: usize,
    guess: u64,
    measure: impl Fn(u64) -> Result<Option<(f64, bool)>, PlanError>,
) -> Result<Option<(u64, (f64, bool))>, PlanError> {
    let too_many = |n: f64| PlanError::PointsPerGroup { epsilon, points: n };
    // `fail` is the largest n known to miss ε, `pass` the smallest known to meet it.
    let (mut fail, mut pass) = (0u64, guess);
    let Some(mut at_pass) = measure(pass)? else {
        return Ok(None);
    };
    // Raise the guess until it holds, in proportion to the shortfall.
    while at_pass.0 > epsilon {
        fail = pass;
        let next = (pass as f64 * at_pass.0 / epsilon * 1.05)
            .ceil()
            .max(pass as f64 + 1.0);
        if next > MAX_MEASURED as f64 {
            return Err(too_many(next));
        }
        pass = next as u64;
        let Some(m) = measure(pass)? else {
            return Ok(None);
        };
        at_pass = m;
    }
    // Bisect: to the least n where measuring is cheap (d <= 2), to within 4 % above.
    let tolerance = |pass: u64| if nc <= 2 { 1 } else { (pass / 25).max(1) };
    if fail == 0 && nc > 2 {
        // The guess held: step down 4 % at a time to a failing n.
        loop {
            let lower = pass * 24 / 25;
            if lower == 0 {
                break;
            }
            match measure(lower)? {
                Some(m) if m.0 <= epsilon => (pass, at_pass) = (lower, m),
                _ => {
                    fail = lower;
                    break;
                }
            }
        }
    }
    while pass - fail > tolerance(pass) {
        let mid = fail + (pass - fail) / 2;
        match measure(mid)? {
            Some(m) if m.0 <= epsilon => (pass, at_pass) = (mid, m),
            _ => fail = mid,
        }
    }
    Ok(Some((pass, at_pass)))
}

/// What `paracosm-cover generate --strategy ipog|kwise --epsilon ε` writes for a space.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuitePlan {
    /// `ipog` or `kwise`.
    pub strategy: String,
    /// Rows of its covering array.
    pub rows: u64,
    /// Halton points per row ([`suite_per_row`]).
    pub per_row: u64,
    /// The largest measured dispersion of a row's block, in `[0, ε]`.
    pub worst_dispersion: f64,
    /// Tests: `rows × per_row`.
    pub total: u64,
}

/// Fills `plan.suites` with what `generate --epsilon` writes for `space` with the covering
/// suites of strength `plan.strength` and seed `seed` (both kinds), so that a plan and
/// `generate` give the same numbers. Does nothing without discrete parameters, or when the
/// plan's Halton count is not verified (`generate --epsilon` then refuses the space).
///
/// # Errors
/// As [`suite_per_row`], with at most `max_points` points per suite.
pub fn plan_suites(
    plan: &mut Plan,
    space: &ParamSpace,
    seed: u64,
    max_points: u64,
) -> Result<(), PlanError> {
    use paracosm_generators::covering::{ArrayKind, CoveringSuite};
    if space.level_counts().is_empty() || plan.halton_verified == Some(false) {
        return Ok(());
    }
    for (kind, name) in [(ArrayKind::Ipog, "ipog"), (ArrayKind::RandomKWise, "kwise")] {
        let rows = CoveringSuite::new(space, plan.strength, kind, 1, seed)?.rows() as u64;
        let (per_row, worst) =
            suite_per_row(space, plan.strength, kind, plan.epsilon, seed, max_points)?;
        plan.suites.push(SuitePlan {
            strategy: name.to_owned(),
            rows,
            per_row,
            worst_dispersion: worst,
            total: rows.saturating_mul(per_row),
        });
    }
    Ok(())
}

/// Halton points per row of a covering suite of strength `strength` over `space` such that
/// every row's block of points has dispersion at most `epsilon` (its upper bound where the
/// dispersion is bracketed): from [`halton_points_for`]'s first block, measured on each row's own block
/// and raised in proportion until every block meets `ε` (the rows take consecutive blocks of
/// the Halton sequence, and a later block's `n · dispersion` can exceed the constant measured
/// at the sequence's start). Returns the points per row and the largest block dispersion.
///
/// # Errors
/// As [`plan`] when the plan overflows; [`PlanError::Covering`] when the covering array cannot
/// be built (a strength out of range); [`PlanError::Suite`] when the suite would need more
/// than `max_points` points.
pub fn suite_per_row(
    space: &ParamSpace,
    strength: usize,
    kind: paracosm_generators::covering::ArrayKind,
    epsilon: f64,
    seed: u64,
    max_points: u64,
) -> Result<(u64, f64), PlanError> {
    use paracosm_generators::covering::CoveringSuite;
    let nc = space.continuous_dims();
    if nc == 0 {
        return Ok((1, 0.0));
    }
    let first = halton_points_for(space, epsilon)?;
    if !first.verified {
        return Err(PlanError::Unmeasured {
            epsilon,
            points: first.points,
            dims: nc,
        });
    }
    let mut per_row = first.points;
    let options = DispersionOptions {
        exact_max_points: PLAN_EXACT_MAX_POINTS.to_vec(),
        ..DispersionOptions::default()
    };
    loop {
        let suite = CoveringSuite::new(space, strength, kind, per_row, seed)?;
        let rows = suite.rows() as u64;
        if rows.saturating_mul(per_row) > max_points {
            return Err(PlanError::Suite {
                epsilon,
                rows,
                per_row,
                max_points,
            });
        }
        let mut worst: f64 = 0.0;
        for r in 0..rows {
            let block: Vec<f64> = (0..per_row)
                .flat_map(|i| suite.point(r + rows * i).continuous)
                .collect();
            let d = dispersion(&block, nc, &options)?;
            if !d.exact && d.upper > epsilon {
                return Err(PlanError::Unmeasured {
                    epsilon,
                    points: per_row,
                    dims: nc,
                });
            }
            worst = worst.max(d.upper);
        }
        if worst <= epsilon {
            return Ok((per_row, worst));
        }
        // n · dispersion is about constant: scale by the shortfall, 5 % more.
        let next = (per_row as f64 * worst / epsilon * 1.05).ceil() as u64;
        per_row = next.max(per_row + 1);
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let k = if self.random_kwise_exact_union.is_some() {
            self.strength.to_string()
        } else {
            "k".to_owned()
        };
        writeln!(
            f,
            "plan for a ({k}, {})-covering set with failure probability δ = {}",
            self.epsilon, self.delta
        )?;
        match self.random_kwise_exact_union {
            None => writeln!(f, "discrete part: none")?,
            Some(exact) => {
                if let Some(m) = self.random_kwise_prop32 {
                    writeln!(
                        f,
                        "random k-wise, Prop. 3.2  2^k (k ln N - ln δ)               = {m} rows"
                    )?;
                }
                if let Some(m) = self.random_kwise_union {
                    writeln!(
                        f,
                        "random k-wise, union bound ln(T/δ) / -ln(1 - 1/V)         = {m} rows"
                    )?;
                }
                writeln!(
                    f,
                    "random k-wise, exact union bound Σ (1 - 1/Π v)^m <= δ    = {exact} rows"
                )?;
            }
        }
        match (
            self.halton_constant,
            self.halton_per_group,
            self.halton_dispersion,
        ) {
            (Some(c), Some(n), None) => {
                writeln!(
                    f,
                    "continuous part: Halton, n = ceil(C' / ε) with C' = largest n·dispersion measured (from {c:.3} at n = 64, 256, 1024) => {n} points per row"
                )?;
                writeln!(
                    f,
                    "  NOT VERIFIED: in d = {} the dispersion of {n} points is past what can be measured exactly, so this is an estimate and the set may miss ε (Halton's n·dispersion grows with n); `generate --epsilon` refuses this space",
                    self.continuous_dims
                )?;
            }
            (Some(c), Some(n), Some(d)) => {
                let guess = (c / self.epsilon).ceil();
                let how = if self.halton_dispersion_exact != Some(true) {
                    "upper bound of a bracket; fewer points may do"
                } else if self.continuous_dims <= 2 {
                    "exact; the least such n"
                } else {
                    "exact; within 4 % of the least such n"
                };
                writeln!(
                    f,
                    "continuous part: Halton, first guess ceil(C / ε) = {guess} with C = max n·dispersion = {c:.3} (n = 64, 256, 1024)"
                )?;
                writeln!(
                    f,
                    "  measured: the first {n} points have dispersion {d:.4e} <= ε ({how}) => {n} points per row"
                )?;
            }
            _ => writeln!(f, "continuous part: none")?,
        }
        writeln!(f, "total: {} tests", self.total)?;
        for s in &self.suites {
            writeln!(
                f,
                "generate --strategy {} --epsilon {}: {} rows × {} points = {} tests (largest row dispersion {:.4e})",
                s.strategy, self.epsilon, s.rows, s.per_row, s.total, s.worst_dispersion
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dispersion of the first `n` Halton points of the unit cube, measured exactly.
    fn exact_dispersion(d: usize, n: u64) -> f64 {
        let pts = Halton::new(&ParamSpace::unit_cube(d)).unit_points(0, n as usize);
        let options = DispersionOptions {
            exact_max_points: vec![usize::MAX; 4],
            ..DispersionOptions::default()
        };
        let m = dispersion(&pts, d, &options).unwrap();
        assert!(m.exact);
        m.upper
    }

    /// The plan's promise, checked by a measurement of its own: the planned prefix has
    /// dispersion at most ε, and in `d = 2` one point fewer does not, in `d = 3` 4 % fewer does
    /// not. The first guess `ceil(C / ε)` fell short at ε = 1e-3 and 5e-4 in `d = 2`
    /// (dispersion 1.05e-3 and 6.32e-4). `d = 3` at ε = 1e-3 and 5e-4 (13,027 and 22,124
    /// points, 43 s and minutes of exact sweeps each) are checked by
    /// `scripts/regenerate-docs --expensive` (docs/coverage.md, "How many tests a plan asks
    /// for"), not here: with its second sweep at 4 % fewer points, 1e-3 made this test take
    /// minutes.
    #[test]
    fn a_plan_measures_what_it_promises_in_two_and_three_dimensions() {
        let cases = [
            (2usize, 1e-2),
            (2, 5e-3),
            (2, 1e-3),
            (2, 5e-4),
            (3, 1e-2),
            (3, 5e-3),
        ];
        for (d, epsilon) in cases {
            let space = ParamSpace::unit_cube(d);
            let h = halton_points_for(&space, epsilon).unwrap();
            assert!(h.exact && h.verified, "d = {d}, ε = {epsilon}: {h:?}");
            let at_n = exact_dispersion(d, h.points);
            assert_eq!(Some(at_n), h.dispersion, "d = {d}, ε = {epsilon}");
            assert!(at_n <= epsilon, "d = {d}, ε = {epsilon}: {at_n:e} at {h:?}");
            let fewer = if d == 2 {
                h.points - 1
            } else {
                h.points * 24 / 25 - 1
            };
            let at_fewer = exact_dispersion(d, fewer);
            assert!(
                at_fewer > epsilon,
                "d = {d}, ε = {epsilon}: {fewer} points suffice"
            );
            if d == 2 {
                let p = plan(&space, 2, epsilon, 0.01).unwrap();
                assert_eq!(p.halton_per_group, Some(h.points));
                assert_eq!(p.total, h.points);
            }
        }
    }

    #[test]
    fn a_plan_refuses_an_epsilon_it_cannot_measure() {
        let e = halton_points_for(&ParamSpace::unit_cube(2), 1e-8).unwrap_err();
        assert!(matches!(e, PlanError::PointsPerGroup { .. }), "{e}");
        assert!(e.to_string().contains("give a larger --epsilon"), "{e}");
    }
}
