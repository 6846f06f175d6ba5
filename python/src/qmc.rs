//! Samplers and estimators of the unit cube: `paracosm.qmc`'s native half.

use numpy::prelude::*;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

use paracosm_generators::coverage::{
    discrepancy as discrepancy_of, dispersion as dispersion_of, star_discrepancy as star_of,
    CoverageError, Discrepancy, DispersionOptions, StarOptions,
};
use paracosm_generators::{Halton, ParamSpace, Sobol, SOBOL_MAX_DIMENSIONS};

use crate::value_error;

/// Registers the samplers and estimators in `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<HaltonEngine>()?;
    m.add_class::<SobolEngine>()?;
    m.add_function(wrap_pyfunction!(discrepancy, m)?)?;
    m.add_function(wrap_pyfunction!(star_discrepancy, m)?)?;
    m.add_function(wrap_pyfunction!(dispersion, m)?)?;
    m.add("SOBOL_MAX_POINTS", paracosm_generators::SOBOL_MAX_POINTS)?;
    m.add("SOBOL_MAX_DIMENSIONS", SOBOL_MAX_DIMENSIONS)?;
    m.add("HALTON_MAX_DIMENSIONS", HALTON_MAX_DIMENSIONS)?;
    m.add("HALTON_MAX_INDEX", HALTON_MAX_INDEX)?;
    Ok(())
}

/// An `n × d` row-major vector as a numpy `(n, d)` array, without a copy.
fn matrix<'py>(py: Python<'py>, v: Vec<f64>, d: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n = v.len().checked_div(d).unwrap_or(0);
    v.into_pyarray(py).reshape([n, d])
}

/// The Halton sequence in `d` dimensions (paper §3.2), unscrambled (`seed = None`, from
/// index 0, as `scipy.stats.qmc.Halton(d, scramble=False)`) or with Owen's random digit
/// permutations drawn from `seed` (ChaCha8).
#[pyclass(module = "paracosm._native")]
pub struct HaltonEngine {
    halton: Halton,
    d: usize,
    next: u64,
}

#[pymethods]
impl HaltonEngine {
    /// A sequence of dimension `1 <= d <= HALTON_MAX_DIMENSIONS`.
    #[new]
    #[pyo3(signature = (d, seed=None))]
    fn new(d: usize, seed: Option<u64>) -> PyResult<Self> {
        if d == 0 {
            return Err(value_error("d must be at least 1"));
        }
        if d > HALTON_MAX_DIMENSIONS {
            return Err(value_error(format!(
                "d = {d} is more than the {HALTON_MAX_DIMENSIONS} dimensions Halton supports"
            )));
        }
        let space = ParamSpace::unit_cube(d);
        Ok(HaltonEngine {
            halton: match seed {
                Some(s) => Halton::scrambled(&space, s),
                None => Halton::new(&space),
            },
            d,
            next: 0,
        })
    }

    /// The next `n` points as an `(n, d)` float64 array in `[0, 1)`.
    ///
    /// Errors: ValueError past index `HALTON_MAX_INDEX`; MemoryError when `n × d` values
    /// cannot be allocated.
    fn random<'py>(&mut self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let start = self.next;
        within_halton(start, n as u64)?;
        reserve(n, self.d)?;
        let halton = &self.halton;
        let v = py.detach(|| halton.unit_points(start, n));
        self.next += n as u64;
        matrix(py, v, self.d)
    }

    /// Index of the next point.
    #[getter]
    fn num_generated(&self) -> u64 {
        self.next
    }

    /// Moves to index `i <= HALTON_MAX_INDEX`; ValueError past it.
    fn seek(&mut self, i: u64) -> PyResult<()> {
        within_halton(i, 0)?;
        self.next = i;
        Ok(())
    }
}

/// Dimensions a Halton sequence supports: one prime base each, the largest 821,641.
pub(crate) const HALTON_MAX_DIMENSIONS: usize = 1 << 16;

/// Points a Halton sequence holds: past index `2^53` a base-2 radical inverse has more bits
/// than an `f64` and rounds to 1.
pub(crate) const HALTON_MAX_INDEX: u64 = 1 << 53;

/// ValueError unless points `start..start + n` are within [`HALTON_MAX_INDEX`].
fn within_halton(start: u64, n: u64) -> PyResult<()> {
    match start.checked_add(n) {
        Some(end) if end <= HALTON_MAX_INDEX => Ok(()),
        _ => Err(value_error(format!(
            "Halton points past index 2**53 are not representable in float64 (they round to \
             1): index {start} + {n} points"
        ))),
    }
}

/// MemoryError unless an `n × d` float64 array can be allocated (numpy's own error).
fn reserve(n: usize, d: usize) -> PyResult<()> {
    let too_big = || {
        pyo3::exceptions::PyMemoryError::new_err(format!(
            "Unable to allocate an array of {n} × {d} float64 values"
        ))
    };
    let cells = n.checked_mul(d).ok_or_else(too_big)?;
    let mut probe: Vec<f64> = Vec::new();
    probe.try_reserve_exact(cells).map_err(|_| too_big())
}

/// Owen-scrambled Sobol points (`sobol_burley`: Joe–Kuo direction numbers, hash-based Owen
/// scrambling after Burley 2020, `f32` precision widened to `f64`); at most
/// `SOBOL_MAX_POINTS` points and `SOBOL_MAX_DIMENSIONS` dimensions.
#[pyclass(module = "paracosm._native")]
pub struct SobolEngine {
    sobol: Sobol,
    d: usize,
    next: u64,
}

#[pymethods]
impl SobolEngine {
    /// A scrambled sequence of dimension `1 <= d <= SOBOL_MAX_DIMENSIONS`, scramble `seed`.
    #[new]
    fn new(d: usize, seed: u64) -> PyResult<Self> {
        if d == 0 {
            return Err(value_error("d must be at least 1"));
        }
        let sobol = Sobol::new(&ParamSpace::unit_cube(d), seed).map_err(value_error)?;
        Ok(SobolEngine { sobol, d, next: 0 })
    }

    /// The next `n` points as an `(n, d)` float64 array in `[0, 1)`.
    fn random<'py>(&mut self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let start = self.next;
        let sobol = &self.sobol;
        let v = py
            .detach(|| sobol.unit_points(start, n))
            .map_err(value_error)?;
        self.next += n as u64;
        matrix(py, v, self.d)
    }

    /// Index of the next point.
    #[getter]
    fn num_generated(&self) -> u64 {
        self.next
    }

    /// Moves to index `i`.
    fn seek(&mut self, i: u64) {
        self.next = i;
    }
}

/// An estimator's error as Python's: MemoryError when its working memory cannot be allocated
/// (the process never aborts), ValueError for the rest.
fn estimator_error(e: CoverageError) -> PyErr {
    match e {
        CoverageError::OutOfMemory { .. } => {
            pyo3::exceptions::PyMemoryError::new_err(e.to_string())
        }
        e => value_error(e),
    }
}

/// A C-contiguous `(n, d)` float64 array's values and `d`.
fn rows<'a>(sample: &'a PyReadonlyArray2<'_, f64>) -> PyResult<(&'a [f64], usize)> {
    let d = sample.shape()[1];
    let values = sample
        .as_slice()
        .map_err(|_| value_error("sample must be a C-contiguous (n, d) array"))?;
    Ok((values, d))
}

/// `scipy.stats.qmc.discrepancy(sample, method=...)`: `method` is `CD`, `WD`, `MD` or
/// `L2-star`; CD, WD and MD squared, L2-star square-rooted, as scipy returns them.
#[pyfunction]
fn discrepancy(py: Python<'_>, sample: PyReadonlyArray2<'_, f64>, method: &str) -> PyResult<f64> {
    let kind = match method {
        "CD" => Discrepancy::Centered,
        "WD" => Discrepancy::WrapAround,
        "MD" => Discrepancy::Mixture,
        "L2-star" => Discrepancy::L2Star,
        other => {
            return Err(value_error(format!(
                "method {other:?} is not one of 'CD', 'WD', 'MD', 'L2-star'"
            )))
        }
    };
    let (values, d) = rows(&sample)?;
    py.detach(|| discrepancy_of(values, d, kind))
        .map_err(estimator_error)
}

/// The L∞ star discrepancy: `(lower, upper, exact, corner, method)`, the box being
/// `[0, corner)`.
#[pyfunction]
#[pyo3(signature = (sample, seed=0))]
fn star_discrepancy(
    py: Python<'_>,
    sample: PyReadonlyArray2<'_, f64>,
    seed: u64,
) -> PyResult<(f64, f64, bool, Vec<f64>, String)> {
    let (values, d) = rows(&sample)?;
    let options = StarOptions {
        seed,
        ..StarOptions::default()
    };
    let s = py
        .detach(|| star_of(values, d, &options))
        .map_err(estimator_error)?;
    Ok((s.lower, s.upper, s.exact, s.witness, s.method))
}

/// The dispersion (largest empty open box): `(lower, upper, exact, lo, hi, method)`.
#[pyfunction]
#[pyo3(signature = (sample, seed=0))]
#[allow(clippy::type_complexity)]
fn dispersion(
    py: Python<'_>,
    sample: PyReadonlyArray2<'_, f64>,
    seed: u64,
) -> PyResult<(f64, f64, bool, Vec<f64>, Vec<f64>, String)> {
    let (values, d) = rows(&sample)?;
    let options = DispersionOptions {
        seed,
        ..DispersionOptions::default()
    };
    let s = py
        .detach(|| dispersion_of(values, d, &options))
        .map_err(estimator_error)?;
    Ok((
        s.lower,
        s.upper,
        s.exact,
        s.witness.lo,
        s.witness.hi,
        s.method,
    ))
}
