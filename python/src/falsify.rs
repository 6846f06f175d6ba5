//! paracosm's samplers and falsifiers over the unit cube, asked and told from Python:
//! `paracosm.falsify`'s native half.

use numpy::prelude::*;
use numpy::{PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;

use paracosm_generators::{Generator, ParamSpace, Point, Strategy};

use crate::value_error;

/// Registers the falsifier class in `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<FalsifierEngine>()?;
    Ok(())
}

/// A strategy of `paracosm-fuzz` (`falsify-bo`, `falsify-nm`, …, or a sampler such as
/// `halton-scrambled`) over the unit cube `[0, 1)^d`, in ask/tell form: the same generator, and
/// so the same points for the same seed and robustness, as a campaign over `d` continuous
/// parameters. Not shared between threads (the Nelder–Mead family runs its searches behind
/// channels).
#[pyclass(module = "paracosm._native", unsendable)]
pub struct FalsifierEngine {
    generator: Box<dyn Generator>,
    d: usize,
    /// Points asked for and not yet told, in the order handed out.
    pending: Vec<Point>,
}

#[pymethods]
impl FalsifierEngine {
    /// The strategy named `strategy` over `d >= 1` dimensions, seeded `seed`.
    #[new]
    fn new(strategy: &str, d: usize, seed: u64) -> PyResult<Self> {
        let s: Strategy = strategy.parse().map_err(value_error)?;
        if !(s.is_adaptive() || Strategy::ALL.contains(&s)) {
            return Err(value_error(format!(
                "`{s}` needs a budget or a list of points; give a falsifier ({}) or a sampler ({})",
                Strategy::FALSIFIERS.map(Strategy::name).join(", "),
                Strategy::ALL.map(Strategy::name).join(", ")
            )));
        }
        if d == 0 {
            return Err(value_error("d must be at least 1"));
        }
        let generator = s
            .build(&ParamSpace::unit_cube(d), seed)
            .map_err(value_error)?;
        Ok(FalsifierEngine {
            generator,
            d,
            pending: Vec::new(),
        })
    }

    /// Points per batch of an adaptive strategy (ask this many, tell them, ask again);
    /// `None` for a sampler.
    #[getter]
    fn batch(&self) -> Option<usize> {
        self.generator.batch()
    }

    /// Up to `n` points as an `(k, d)` float64 array in `[0, 1)`; fewer (possibly none) when
    /// an adaptive strategy waits for the robustness of points already asked for.
    fn ask<'py>(&mut self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let generator = &mut self.generator;
        let points = py.detach(|| generator.ask(n)).map_err(value_error)?;
        let values: Vec<f64> = points.iter().flat_map(|p| p.continuous.clone()).collect();
        self.pending.extend(points);
        let k = values.len() / self.d;
        values.into_pyarray(py).reshape([k, self.d])
    }

    /// The robustness of the oldest points asked for and not yet told, in that order
    /// (`robustness[i]` for the `i`-th of them; NaN for a test that errored).
    ///
    /// Raises `ValueError` when more values are given than points are pending.
    fn tell(&mut self, py: Python<'_>, robustness: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let r = robustness.as_slice().map_err(value_error)?;
        if r.len() > self.pending.len() {
            return Err(value_error(format!(
                "{} robustness values for {} points asked for and not yet told",
                r.len(),
                self.pending.len()
            )));
        }
        let told: Vec<(Point, f64)> = self
            .pending
            .drain(..r.len())
            .zip(r.iter().copied())
            .collect();
        let generator = &mut self.generator;
        py.detach(|| generator.tell(&told));
        Ok(())
    }

    /// Points asked for and not yet told.
    #[getter]
    fn pending(&self) -> usize {
        self.pending.len()
    }
}
