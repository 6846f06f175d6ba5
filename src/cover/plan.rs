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
    /// `ε` so small that a discrete group would need [`MAX_PLANNED`] Halton points or more.
    #[error(
        "ε = {epsilon:e} needs about {points:.3e} Halton points per discrete group, more than \
         the {max} a plan counts; give a larger --epsilon",
        max = MAX_PLANNED
    )]
    PointsPerGroup {
        /// The target dispersion.
        epsilon: f64,
        /// The points per group it needs, `ceil(C / ε)`.
        points: f64,
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
    /// Halton points per discrete group: `ceil(C / ε)`.
    pub halton_per_group: Option<u64>,
    /// Total tests: rows × points per group (each factor 1 when absent).
    pub total: u64,
}

/// Plans a (k, ε)-covering test set for `space` (PARACOSM §3.2): a random k-wise family for
/// the discrete part (Proposition 3.2 and its union-bound form for mixed levels), and for each
/// of its rows a Halton set whose dispersion is at most `ε`, sized from the measured constant
/// `C = max_n n · dispersion(E_n)` (Proposition 3.3: dispersion is `O(1/n)`).
///
/// # Errors
/// [`PlanError::PointsPerGroup`] or [`PlanError::Tests`] when the plan would count
/// [`MAX_PLANNED`] tests or more (a tiny `ε`).
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
    let (mut constant, mut per_group) = (None, None);
    if nc > 0 {
        let h = Halton::new(space);
        let c = [64usize, 256, 1024]
            .iter()
            .map(|&n| {
                let pts = h.unit_points(0, n);
                let d =
                    dispersion(&pts, nc, &DispersionOptions::default()).map_or(1.0, |d| d.upper);
                n as f64 * d
            })
            .fold(0.0, f64::max);
        constant = Some(c);
        let n = (c / epsilon).ceil().max(1.0);
        if n >= MAX_PLANNED as f64 {
            return Err(PlanError::PointsPerGroup { epsilon, points: n });
        }
        per_group = Some(n as u64);
    }
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
        halton_constant: constant,
        halton_per_group: per_group,
        total,
    })
}

/// The most tests a plan counts, 2^53 (every count below it is exact as a float, and no
/// campaign comes near it).
pub const MAX_PLANNED: u64 = 1 << 53;

/// Halton points per row of a covering suite of strength `strength` over `space` such that
/// every row's block of points has dispersion at most `epsilon` (its upper bound where the
/// dispersion is bracketed): from [`plan`]'s `ceil(C / ε)`, measured on each row's own block
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
    let mut per_row = plan(space, strength, epsilon, 0.01)?
        .halton_per_group
        .unwrap_or(1);
    if nc == 0 {
        return Ok((1, 0.0));
    }
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
            let d = dispersion(&block, nc, &DispersionOptions::default())?;
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
        match (self.halton_constant, self.halton_per_group) {
            (Some(c), Some(n)) => writeln!(
                f,
                "continuous part: Halton, n = ceil(C / ε) with C = max n·dispersion = {c:.3} (n = 64, 256, 1024) => {n} points per row"
            )?,
            _ => writeln!(f, "continuous part: none")?,
        }
        writeln!(f, "total: {} tests", self.total)
    }
}
