//! Coverage of a test set (PARACOSM §3.1): k-wise combinatorial coverage for the discrete
//! parameters, dispersion and discrepancies for the continuous ones, and the paper's
//! (k, ε)-covering criterion that joins them.
//!
//! Point sets are passed as `n × d` row-major slices of `f64` with every value in `[0, 1]`
//! (the unit cube), discrete rows as `n × k` row-major slices of level indices.

mod covering;
mod discrepancy;
mod dispersion;
mod error;
mod kwise;
mod ordered_sum;
mod star;
mod star3d;
mod star4d;
mod valid_gap;
mod wrap_around;

pub use covering::{k_epsilon_covering, KEpsilonCovering};

/// A hook an exact computation calls as it goes: `(done, total)` units of its work (the
/// sweep's planes for the star discrepancy in d = 3, its prefixes in d = 4, the supporting
/// points of the dispersion's sweep), from any of its threads; `done` only grows.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// A [`Progress`] that reports nothing.
pub fn no_progress(_done: u64, _total: u64) {}
pub use discrepancy::{discrepancy, Discrepancy};
pub use dispersion::{
    dispersion, dispersion_with_progress, Dispersion, DispersionOptions, EmptyBox,
};
pub use error::CoverageError;
pub(crate) use kwise::valid_tuples;
pub use kwise::{
    kwise_coverage, kwise_coverage_rows, subset_products, subsets, KWiseCoverage, MissingTuple,
    RawKWise, MAX_STRENGTH,
};
pub use star::{star_discrepancy, star_discrepancy_with_progress, StarDiscrepancy, StarOptions};
pub use valid_gap::{valid_gap, ValidGap, VALID_GAP_PROBES};

/// Checks an `n × d` row-major point set: `d >= 1`, length a multiple of `d`, every value
/// finite and in `[0, 1]`. Returns `n`.
pub(crate) fn check_unit_points(points: &[f64], d: usize) -> Result<usize, CoverageError> {
    if d == 0 {
        return Err(CoverageError::Shape(
            "dimension d must be at least 1".into(),
        ));
    }
    if !points.len().is_multiple_of(d) {
        return Err(CoverageError::Shape(format!(
            "{} values do not form rows of {d}",
            points.len()
        )));
    }
    for (k, &v) in points.iter().enumerate() {
        if !(0.0..=1.0).contains(&v) {
            return Err(CoverageError::OutsideUnitCube {
                row: k / d,
                column: k % d,
                value: v,
            });
        }
    }
    Ok(points.len() / d)
}
