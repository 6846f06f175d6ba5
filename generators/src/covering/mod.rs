//! Covering arrays for the discrete parameters (PARACOSM §3.2): an `n × k` array of level
//! indices in which every t-tuple of levels appears in some row.
//!
//! - [`ipog`]: the IPOG strategy with IPOG-F's global choice in horizontal growth.
//! - [`random_kwise`] and [`random_until_covered`]: random arrays sized by Proposition 3.2 and
//!   its union bound, or grown until the coverage checker is satisfied.

mod constraints;
mod construct;
mod ipog;
mod optimise;
mod random;
mod suite;

pub use constraints::Constraints;
pub use construct::{construct, doubling, orthogonal_array, product};
pub use ipog::{ipog, ipog_with};
pub use optimise::{optimise, Optimise, WORK_UNIT_S};
pub use random::{
    random_kwise, random_kwise_covering, random_kwise_rows, random_kwise_with,
    random_until_covered, random_until_covered_with, RandomKWiseSize,
};
pub use suite::{ArrayKind, CoveringSuite};

use serde::Serialize;
use thiserror::Error;

/// Errors building a covering array.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CoveringError {
    /// The strength is not in `1..=min(6, k)`.
    #[error("strength t = {t} is not in 1..={max} for {k} parameters")]
    Strength {
        /// The strength asked for.
        t: usize,
        /// The largest allowed.
        max: usize,
        /// The number of parameters.
        k: usize,
    },
    /// A parameter has no level.
    #[error("parameter {0} has no levels")]
    NoLevels(usize),
    /// A seed row does not fit the parameters or breaks a constraint.
    #[error("seed row {row}: {reason}")]
    Seed {
        /// Seed index, from 0.
        row: usize,
        /// What is wrong.
        reason: String,
    },
    /// A constraint names a column or level that does not exist.
    #[error("constraint {index}: {reason}")]
    Constraint {
        /// Constraint index, from 0.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// The constraints forbid every row.
    #[error("the constraints forbid every row: no test can be built")]
    Unsatisfiable,
    /// The combinations a constrained space forbids could not be found
    /// ([`crate::ParamSpace::forbidden_levels`]).
    #[error("{0}")]
    Forbidden(String),
    /// The array, or the table of `t`-tuples it must cover, is too large to build.
    #[error(
        "a covering array of strength {t} over these levels needs at least {rows} rows (the \
         product of the {t} largest level counts) and a table of about {cells} {t}-tuples, more \
         than the limits of {max_rows} rows and {max_cells} tuples; use fewer levels or a lower \
         strength"
    )]
    TooLarge {
        /// The strength.
        t: usize,
        /// A lower bound on the rows.
        rows: u128,
        /// The `t`-tuples to cover: the sum over column sets of their level products (an
        /// upper estimate: `C(k, t)` times the product of the `t` largest).
        cells: u128,
        /// [`MAX_ROWS`].
        max_rows: u128,
        /// [`MAX_TUPLES`].
        max_cells: u128,
    },
    /// A random array hit its row limit before covering every tuple.
    #[error("{rows} random rows did not cover every {t}-tuple")]
    NotCovered {
        /// Rows drawn.
        rows: usize,
        /// The strength.
        t: usize,
    },
}

/// A covering array: `rows` is `n × k` row-major level indices, row `r` being
/// `rows[r * k..(r + 1) * k]`, with `levels[j]` the level count of column `j`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CoveringArray {
    /// Level counts, one per column.
    pub levels: Vec<u32>,
    /// The strength the array was built for.
    pub strength: usize,
    /// `n × k` level indices, row-major.
    pub rows: Vec<u32>,
}

impl CoveringArray {
    /// Number of rows `n`.
    pub fn len(&self) -> usize {
        if self.levels.is_empty() {
            0
        } else {
            self.rows.len() / self.levels.len()
        }
    }

    /// Whether the array has no row.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `r`, `k` level indices.
    pub fn row(&self, r: usize) -> &[u32] {
        let k = self.levels.len();
        &self.rows[r * k..(r + 1) * k]
    }
}

pub(crate) fn check(levels: &[u32], t: usize) -> Result<(), CoveringError> {
    let k = levels.len();
    let max = crate::coverage::MAX_STRENGTH.min(k);
    if t == 0 || t > max {
        return Err(CoveringError::Strength { t, max, k });
    }
    if let Some(j) = levels.iter().position(|&v| v == 0) {
        return Err(CoveringError::NoLevels(j));
    }
    let mut sorted: Vec<u128> = levels.iter().map(|&v| u128::from(v)).collect();
    sorted.sort_unstable_by(|a, b| b.cmp(a));
    let rows: u128 = sorted[..t].iter().fold(1u128, |a, &v| a.saturating_mul(v));
    let subsets: u128 =
        (0..t as u128).fold(1u128, |a, i| a.saturating_mul(k as u128 - i) / (i + 1));
    let cells = rows.saturating_mul(subsets);
    if rows > MAX_ROWS || cells > MAX_TUPLES {
        return Err(CoveringError::TooLarge {
            t,
            rows,
            cells,
            max_rows: MAX_ROWS,
            max_cells: MAX_TUPLES,
        });
    }
    Ok(())
}

/// Most rows a covering array may need (10 million); see [`CoveringError::TooLarge`].
pub const MAX_ROWS: u128 = 10_000_000;
/// Most `t`-tuples a covering array's table may hold (100 million; IPOG keeps a 4-byte count
/// per tuple); see [`CoveringError::TooLarge`].
pub const MAX_TUPLES: u128 = 100_000_000;

/// Checks constraints and seeds against `levels`; returns the seeds with open cells as
/// `OPEN`.
pub(crate) fn check_seeds(
    levels: &[u32],
    constraints: &Constraints,
    seeds: &[Vec<Option<u32>>],
) -> Result<Vec<Vec<u32>>, CoveringError> {
    let k = levels.len();
    for (index, f) in constraints.forbidden().iter().enumerate() {
        for &(c, v) in f {
            if c >= k || v >= levels[c] {
                return Err(CoveringError::Constraint {
                    index,
                    reason: format!("column {c} level {v} does not exist"),
                });
            }
        }
    }
    if !constraints.is_empty()
        && constraints
            .complete(levels, &vec![constraints::OPEN; k])
            .is_none()
    {
        // An empty array would cover every (zero) allowed tuple: a silent non-answer.
        return Err(CoveringError::Unsatisfiable);
    }
    seeds
        .iter()
        .enumerate()
        .map(|(row, s)| {
            if s.len() != k {
                return Err(CoveringError::Seed {
                    row,
                    reason: format!("has {} cells, the array has {k} columns", s.len()),
                });
            }
            let cells: Vec<u32> = s.iter().map(|c| c.unwrap_or(constraints::OPEN)).collect();
            if let Some(c) =
                (0..k).find(|&c| cells[c] != constraints::OPEN && cells[c] >= levels[c])
            {
                return Err(CoveringError::Seed {
                    row,
                    reason: format!(
                        "level {} of column {c} is out of range 0..{}",
                        cells[c], levels[c]
                    ),
                });
            }
            if constraints.complete(levels, &cells).is_none() {
                return Err(CoveringError::Seed {
                    row,
                    reason: "breaks a constraint".into(),
                });
            }
            Ok(cells)
        })
        .collect()
}

/// t-wise coverage of `rows` (`n × k` row-major) counting only the t-tuples that extend to a
/// row allowed by `constraints` ("coverable"): `(covered, coverable)`.
pub fn coverage_with_constraints(
    levels: &[u32],
    rows: &[u32],
    t: usize,
    constraints: &Constraints,
) -> (u64, u64) {
    let (raw, _) = crate::coverage::valid_tuples(levels, rows, t, 0, constraints);
    (raw.covered, raw.total)
}

/// Test helper: constraints forbidding the pairs `(column, level, column, level)` drawn by a
/// property test, folded into range (pairs on one column are dropped).
#[cfg(test)]
pub(crate) fn forbidden_pairs(levels: &[u32], pairs: &[(usize, u32, usize, u32)]) -> Constraints {
    let k = levels.len();
    Constraints::new(
        pairs
            .iter()
            .filter(|&&(a, _, b, _)| a % k != b % k)
            .map(|&(a, va, b, vb)| vec![(a % k, va % levels[a % k]), (b % k, vb % levels[b % k])])
            .collect(),
    )
}
