//! Covering arrays for the discrete parameters (PARACOSM §3.2): an `n × k` array of level
//! indices in which every t-tuple of levels appears in some row.
//!
//! - [`ipog`]: the IPOG strategy with IPOG-F's global choice in horizontal growth.
//! - [`random_kwise`] and [`random_until_covered`]: random arrays sized by Proposition 3.2 and
//!   its union bound, or grown until the coverage checker is satisfied.

mod ipog;
mod random;

pub use ipog::ipog;
pub use random::{random_kwise, random_kwise_rows, random_until_covered, RandomKWiseSize};

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
    Ok(())
}
