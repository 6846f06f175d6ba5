//! Covering arrays and k-wise coverage: `paracosm.covering`'s native half.

use numpy::prelude::*;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

use paracosm_generators::coverage::kwise_coverage_rows;
use paracosm_generators::covering::{
    coverage_with_constraints, ipog_with, random_kwise_with, random_until_covered_with, Constraints,
};

use crate::value_error;

/// Registers the functions in `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(covering_array, m)?)?;
    m.add_function(wrap_pyfunction!(kwise_coverage, m)?)?;
    Ok(())
}

/// Forbidden combinations as the generators take them.
fn constraints(forbidden: Vec<Vec<(usize, u32)>>) -> Constraints {
    Constraints::new(forbidden)
}

/// A covering array of strength `strength` over columns with `levels` levels, as an
/// `(N, k)` int64 array of level indices. `algorithm`: `ipog` (deterministic), `kwise`
/// (random rows sized by the paper's Proposition 3.2 for confidence `1 − 0.01`), `random`
/// (random rows until every tuple is covered, seeded by `seed`).
#[pyfunction]
#[pyo3(signature = (levels, strength, algorithm, forbidden, seed))]
fn covering_array<'py>(
    py: Python<'py>,
    levels: Vec<u32>,
    strength: usize,
    algorithm: &str,
    forbidden: Vec<Vec<(usize, u32)>>,
    seed: u64,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let c = constraints(forbidden);
    let array = py
        .detach(|| match algorithm {
            "ipog" => Ok(ipog_with(&levels, strength, &c, &[])),
            "kwise" => Ok(random_kwise_with(&levels, strength, 0.01, seed, &c, &[])),
            "random" => Ok(random_until_covered_with(
                &levels,
                strength,
                seed,
                10_000_000,
                &c,
                &[],
            )),
            other => Err(other.to_owned()),
        })
        .map_err(|other| {
            value_error(format!(
                "algorithm {other:?} is not one of 'ipog', 'kwise', 'random'"
            ))
        })?
        .map_err(value_error)?;
    let k = array.levels.len();
    let n = array.len();
    let cells: Vec<i64> = array.rows.iter().map(|&v| i64::from(v)).collect();
    cells.into_pyarray(py).reshape([n, k])
}

/// The most t-tuples counted under constraints: each is checked against the constraints
/// one by one (2^27, about a minute).
const MAX_CONSTRAINED_TUPLES: u64 = 1 << 27;

/// k-wise coverage of `array` (`(n, k)` level indices, checked by the caller to lie in
/// range): `(covered, total, missing)`; with forbidden combinations, `total` counts only the
/// tuples some allowed row can hold, and `missing` is empty.
#[pyfunction]
#[pyo3(signature = (array, levels, strength, forbidden, max_missing))]
#[allow(clippy::type_complexity)]
fn kwise_coverage(
    py: Python<'_>,
    array: PyReadonlyArray2<'_, i64>,
    levels: Vec<u32>,
    strength: usize,
    forbidden: Vec<Vec<(usize, u32)>>,
    max_missing: usize,
) -> PyResult<(u64, u64, Vec<Vec<(usize, u32)>>)> {
    let values = array
        .as_slice()
        .map_err(|_| value_error("array must be a C-contiguous (n, k) array"))?;
    let rows: Vec<u32> = values
        .iter()
        .map(|&v| u32::try_from(v).map_err(|_| value_error(format!("level index {v} < 0"))))
        .collect::<PyResult<_>>()?;
    let c = constraints(forbidden);
    py.detach(|| {
        // The plain count checks the strength, the shape and every level index.
        let raw = kwise_coverage_rows(&levels, &rows, strength, max_missing)?;
        if c.is_empty() {
            Ok((raw.covered, raw.total, raw.missing))
        } else if raw.total > MAX_CONSTRAINED_TUPLES {
            Err(paracosm_generators::coverage::CoverageError::Shape(
                format!(
                    "with constraints every {strength}-tuple is checked for an allowed row, and \
                 these levels have {} of them (at most {MAX_CONSTRAINED_TUPLES})",
                    raw.total
                ),
            ))
        } else {
            let (covered, total) = coverage_with_constraints(&levels, &rows, strength, &c);
            Ok((covered, total, Vec::new()))
        }
    })
    .map_err(|e: paracosm_generators::coverage::CoverageError| value_error(e))
}
