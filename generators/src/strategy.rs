use std::str::FromStr;

use crate::{Generator, GeneratorError, Halton, ParamSpace, Sobol, UniformRandom};

/// The test-generation strategies by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Strategy {
    /// [`UniformRandom`]: independent uniform points (ChaCha8, seeded).
    Random,
    /// [`Halton`]: the paper's low-dispersion sequence (§3.2); ignores the seed.
    Halton,
    /// [`Halton::scrambled`]: the Halton sequence with random digit permutations (Owen 2017);
    /// the seed draws the permutations.
    ScrambledHalton,
    /// [`Sobol`]: Owen-scrambled Sobol points; the seed selects the scramble.
    Sobol,
}

impl Strategy {
    /// Every strategy, in the order the CLI lists them.
    pub const ALL: [Strategy; 4] = [
        Strategy::Random,
        Strategy::Halton,
        Strategy::ScrambledHalton,
        Strategy::Sobol,
    ];

    /// The name used on the command line and in results files.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Random => "random",
            Strategy::Halton => "halton",
            Strategy::ScrambledHalton => "halton-scrambled",
            Strategy::Sobol => "sobol",
        }
    }

    /// The most points the strategy can produce, `None` when unbounded.
    pub fn capacity(self) -> Option<u64> {
        match self {
            Strategy::Sobol => Some(crate::SOBOL_MAX_POINTS),
            Strategy::Random | Strategy::Halton | Strategy::ScrambledHalton => None,
        }
    }

    /// A generator of this strategy over `space`, seeded with `seed` where the strategy uses one.
    ///
    /// # Errors
    /// [`GeneratorError::CapacityExceeded`] when the space has more dimensions than the
    /// strategy supports.
    pub fn build(
        self,
        space: &ParamSpace,
        seed: u64,
    ) -> Result<Box<dyn Generator>, GeneratorError> {
        Ok(match self {
            Strategy::Random => Box::new(UniformRandom::new(space, seed)),
            Strategy::Halton => Box::new(Halton::new(space)),
            Strategy::ScrambledHalton => Box::new(Halton::scrambled(space, seed)),
            Strategy::Sobol => Box::new(Sobol::new(space, seed)?),
        })
    }
}

impl FromStr for Strategy {
    type Err = GeneratorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Strategy::ALL
            .into_iter()
            .find(|st| st.name() == s)
            .ok_or_else(|| GeneratorError::UnknownStrategy(s.to_owned()))
    }
}

impl std::fmt::Display for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_are_errors() {
        for s in Strategy::ALL {
            assert_eq!(s.name().parse::<Strategy>().unwrap(), s);
        }
        assert_eq!(
            "annealing".parse::<Strategy>().unwrap_err().to_string(),
            "unknown strategy `annealing` (expected one of: random, halton, halton-scrambled, sobol)"
        );
    }
}
