use crate::{GeneratorError, Point};

/// A test generator: proposes points of a parameter space, in the ask/tell shape of black-box
/// optimisers.
///
/// Non-adaptive generators (random, Halton, Sobol) ignore [`Generator::tell`]. Points are
/// index-addressable where the construction allows it, so a campaign can ask for its whole
/// budget at once and run the tests in any order.
pub trait Generator: Send {
    /// The strategy's name as used on the command line, e.g. `halton`.
    fn name(&self) -> &'static str;

    /// The next `n` points, continuing from the last call.
    ///
    /// # Errors
    /// [`GeneratorError::CapacityExceeded`] when the construction cannot produce `n` more points
    /// (for example Sobol past 2^16 points). No point is returned in that case: a generator never
    /// wraps around silently.
    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError>;

    /// Reports evaluated points with their robustness (`> 0` satisfied, `< 0` violated).
    /// Adaptive strategies use it; the default ignores it.
    fn tell(&mut self, _evaluated: &[(Point, f64)]) {}

    /// `None` for a non-adaptive generator: its points do not depend on what it is told, so
    /// a campaign asks for its whole budget at once. `Some(b)` for an adaptive one: the
    /// campaign asks `b` points (fewer at the end of the budget), runs them, tells their
    /// robustness in the order asked, and asks again. `b` never depends on the number of
    /// worker threads.
    fn batch(&self) -> Option<usize> {
        None
    }
}
