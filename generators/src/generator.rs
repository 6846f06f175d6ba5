use crate::{GeneratorError, Point};

/// A test generator: proposes points of a parameter space, in the ask/tell shape of black-box
/// optimisers.
///
/// Non-adaptive generators (random, Halton, Sobol) ignore [`Generator::tell`]. Points are
/// index-addressable where the construction allows it, so a campaign can skip to its shard and
/// run the tests in any order.
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

    /// Moves past the next `n` points without returning them, as if asked for and dropped (a
    /// campaign's shard starts there). The default asks in chunks of 65,536 points, so memory
    /// stays bounded; index-addressable generators may jump.
    ///
    /// # Errors
    /// As [`Generator::ask`].
    fn skip(&mut self, n: u64) -> Result<(), GeneratorError> {
        let mut left = n;
        while left > 0 {
            let chunk = left.min(1 << 16);
            self.ask(chunk as usize)?;
            left -= chunk;
        }
        Ok(())
    }

    /// Reports evaluated points with their robustness (`> 0` satisfied, `< 0` violated).
    /// Adaptive strategies use it; the default ignores it.
    fn tell(&mut self, _evaluated: &[(Point, f64)]) {}

    /// `None` for a non-adaptive generator: its points do not depend on what it is told, so
    /// a campaign asks for them in chunks of its own size, as it runs. `Some(b)` for an adaptive one: the
    /// campaign asks `b` points (fewer at the end of the budget), runs them, tells their
    /// robustness in the order asked, and asks again. `b` never depends on the number of
    /// worker threads.
    fn batch(&self) -> Option<usize> {
        None
    }
}
