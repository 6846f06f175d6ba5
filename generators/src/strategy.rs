use std::str::FromStr;

use crate::falsify::{Acquisition, BayesOpt, BoTuning, Falsifier, Method};
use crate::{
    FullFactorial, Generator, GeneratorError, GivenPoints, Halton, ParamSpace, Sobol, UniformRandom,
};

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
    /// [`crate::covering::CoveringSuite`] on an IPOG array: a (k, ε)-covering suite (§3.2).
    Ipog,
    /// [`crate::covering::CoveringSuite`] on a random k-wise array (Proposition 3.2).
    KWise,
    /// [`Falsifier`] with Nelder–Mead and restarts (argmin).
    FalsifyNm,
    /// [`Falsifier`] with particle swarms (argmin).
    FalsifyPso,
    /// [`Falsifier`] with simulated annealing (argmin).
    FalsifySa,
    /// [`Falsifier`] with the cross-entropy method.
    FalsifyCe,
    /// [`BayesOpt`]: Gaussian-process Bayesian optimisation, expected improvement.
    FalsifyBo,
    /// [`BayesOpt`] with the lower confidence bound `μ − 2σ`.
    FalsifyBoLcb,
    /// [`GivenPoints`]: points chosen outside paracosm (`paracosm-fuzz --points FILE`, an
    /// array from Python), in their order; built by [`Strategy::build_given`].
    Points,
    /// [`FullFactorial`]: every combination of the discrete parameters' levels (an
    /// OpenSCENARIO variation file's own grid); `variation` names it too.
    FullFactorial,
}

impl Strategy {
    /// The covering-suite strategies, which need a budget and a strength
    /// ([`Strategy::build_sized`]).
    pub const SUITES: [Strategy; 2] = [Strategy::Ipog, Strategy::KWise];

    /// The adaptive falsifiers ([`Falsifier`], [`BayesOpt`]): their points depend on the
    /// robustness they are told, so they run only inside a campaign.
    pub const FALSIFIERS: [Strategy; 6] = [
        Strategy::FalsifyNm,
        Strategy::FalsifyPso,
        Strategy::FalsifySa,
        Strategy::FalsifyCe,
        Strategy::FalsifyBo,
        Strategy::FalsifyBoLcb,
    ];

    /// Every strategy, in the order the command line lists them: the one list from which
    /// names, help, parsing and error messages are derived.
    pub const LIST: [Strategy; 14] = [
        Strategy::Random,
        Strategy::Halton,
        Strategy::ScrambledHalton,
        Strategy::Sobol,
        Strategy::Ipog,
        Strategy::KWise,
        Strategy::FalsifyNm,
        Strategy::FalsifyPso,
        Strategy::FalsifySa,
        Strategy::FalsifyCe,
        Strategy::FalsifyBo,
        Strategy::FalsifyBoLcb,
        Strategy::Points,
        Strategy::FullFactorial,
    ];

    /// Every point generator that needs no budget, in the order the CLI lists them.
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
            Strategy::Ipog => "ipog",
            Strategy::KWise => "kwise",
            Strategy::FalsifyNm => "falsify-nm",
            Strategy::FalsifyPso => "falsify-pso",
            Strategy::FalsifySa => "falsify-sa",
            Strategy::FalsifyCe => "falsify-ce",
            Strategy::FalsifyBo => "falsify-bo",
            Strategy::FalsifyBoLcb => "falsify-bo-lcb",
            Strategy::Points => "points",
            Strategy::FullFactorial => "full-factorial",
        }
    }

    /// One line on what the strategy does, for `--help`.
    pub fn help(self) -> &'static str {
        match self {
            Strategy::Random => "Uniform random points (ChaCha8, seeded by --seed)",
            Strategy::Halton => {
                "The Halton low-dispersion sequence from index 0 (paper §3.2); --seed is not used"
            }
            Strategy::ScrambledHalton => {
                "The Halton sequence with random digit permutations (Owen 2017), drawn by \
                 --seed; the same as halton with --scramble"
            }
            Strategy::Sobol => {
                "Owen-scrambled Sobol points (at most 65536); --seed selects the scramble"
            }
            Strategy::Ipog => {
                "A (k, ε)-covering suite: an IPOG covering array of strength --strength over the \
                 discrete parameters, and a block of Halton points per array row"
            }
            Strategy::KWise => "As ipog, with a random k-wise array sized by Proposition 3.2",
            Strategy::FalsifyNm => {
                "Falsification: Nelder–Mead with restarts minimising robustness (argmin); \
                 discrete parameters fixed per search by a pairwise covering array"
            }
            Strategy::FalsifyPso => "Falsification: particle swarms minimising robustness (argmin)",
            Strategy::FalsifySa => {
                "Falsification: simulated annealing minimising robustness (argmin)"
            }
            Strategy::FalsifyCe => "Falsification: the cross-entropy method minimising robustness",
            Strategy::FalsifyBo => {
                "Falsification: Bayesian optimisation, a Gaussian process (Matérn 5/2) over \
                 robustness and expected improvement maximised by L-BFGS (argmin, faer)"
            }
            Strategy::FalsifyBoLcb => {
                "Falsification: as falsify-bo with the lower confidence bound μ − 2σ"
            }
            Strategy::Points => {
                "The points of a CSV file, in file order (chosen by --points FILE, which sets \
                 the budget to the file's row count)"
            }
            Strategy::FullFactorial => {
                "Every combination of the discrete parameters' levels once (an OpenSCENARIO \
                 variation file's own grid; `variation` names it too); the budget is at most \
                 their product"
            }
        }
    }

    /// The names of [`Strategy::LIST`], comma-separated, for messages.
    pub fn names() -> String {
        Strategy::LIST.map(Strategy::name).join(", ")
    }

    /// Whether the strategy is adaptive ([`Strategy::FALSIFIERS`]): its points depend on the
    /// robustness it is told.
    pub fn is_adaptive(self) -> bool {
        Strategy::FALSIFIERS.contains(&self)
    }

    /// The search method of a [`Falsifier`] strategy, `None` for the others (the Bayesian
    /// ones included).
    pub fn method(self) -> Option<Method> {
        match self {
            Strategy::FalsifyNm => Some(Method::NelderMead),
            Strategy::FalsifyPso => Some(Method::ParticleSwarm),
            Strategy::FalsifySa => Some(Method::Annealing),
            Strategy::FalsifyCe => Some(Method::CrossEntropy),
            _ => None,
        }
    }

    /// The most points the strategy can produce, `None` when unbounded.
    pub fn capacity(self) -> Option<u64> {
        match self {
            Strategy::Sobol => Some(crate::SOBOL_MAX_POINTS),
            Strategy::Random
            | Strategy::Halton
            | Strategy::ScrambledHalton
            | Strategy::Ipog
            | Strategy::KWise
            | Strategy::FalsifyNm
            | Strategy::FalsifyPso
            | Strategy::FalsifySa
            | Strategy::FalsifyCe
            | Strategy::FalsifyBo
            | Strategy::FalsifyBoLcb
            | Strategy::Points
            | Strategy::FullFactorial => None,
        }
    }

    /// A generator of this strategy over `space`, seeded with `seed` where the strategy uses one;
    /// over a constrained space it draws valid points only ([`crate::ValidOnly`]).
    ///
    /// # Errors
    /// [`GeneratorError::CapacityExceeded`] when the space has more dimensions than the
    /// strategy supports; [`GeneratorError::Covering`] for a falsifier over a space without
    /// continuous parameters; [`GeneratorError::NeedsBudget`] for the covering suites, which are
    /// built by [`Strategy::build_sized`]; [`GeneratorError::NeedsPoints`] for
    /// [`Strategy::Points`], built by [`Strategy::build_given`].
    pub fn build(
        self,
        space: &ParamSpace,
        seed: u64,
    ) -> Result<Box<dyn Generator>, GeneratorError> {
        Ok(valid_only(self.build_unconstrained(space, seed)?, space))
    }

    fn build_unconstrained(
        self,
        space: &ParamSpace,
        seed: u64,
    ) -> Result<Box<dyn Generator>, GeneratorError> {
        Ok(match self {
            Strategy::Random => Box::new(UniformRandom::new(space, seed)),
            Strategy::Halton => Box::new(Halton::new(space)),
            Strategy::ScrambledHalton => Box::new(Halton::scrambled(space, seed)),
            Strategy::Sobol => Box::new(Sobol::new(space, seed)?),
            Strategy::Ipog | Strategy::KWise => {
                return Err(GeneratorError::NeedsBudget(self.name()))
            }
            Strategy::Points => return Err(GeneratorError::NeedsPoints),
            Strategy::FullFactorial => Box::new(FullFactorial::new(space)?),
            Strategy::FalsifyNm
            | Strategy::FalsifyPso
            | Strategy::FalsifySa
            | Strategy::FalsifyCe => {
                let method = self.method().expect("a falsifier has a method");
                Box::new(Falsifier::new(space, method, seed)?)
            }
            Strategy::FalsifyBo => Box::new(BayesOpt::new(space, seed)?),
            Strategy::FalsifyBoLcb => Box::new(BayesOpt::with_tuning(
                space,
                seed,
                BoTuning {
                    acquisition: Acquisition::LowerConfidenceBound { beta: 2.0 },
                    ..BoTuning::default()
                },
            )?),
        })
    }
}

impl Strategy {
    /// A generator of this strategy for a campaign of `budget` tests. The covering suites
    /// ([`Strategy::SUITES`]) build a strength-`strength` array over the discrete parameters
    /// and give each row `ceil(budget / rows)` Halton points; the others ignore `strength` and
    /// are as [`Strategy::build`].
    ///
    /// # Errors
    /// As [`Strategy::build`]; [`GeneratorError::Covering`] when the array cannot be built
    /// (e.g. `strength` above the number of discrete parameters).
    pub fn build_sized(
        self,
        space: &ParamSpace,
        seed: u64,
        budget: u64,
        strength: usize,
    ) -> Result<Box<dyn Generator>, GeneratorError> {
        use crate::covering::{ArrayKind, CoveringSuite};
        let kind = match self {
            Strategy::Ipog => ArrayKind::Ipog,
            Strategy::KWise => ArrayKind::RandomKWise,
            _ => return self.build(space, seed),
        };
        let err = |e: crate::covering::CoveringError| GeneratorError::Covering(e.to_string());
        // The array's size decides the block size: build once to count rows.
        let probe = CoveringSuite::new(space, strength, kind, 1, seed).map_err(err)?;
        let per_row = CoveringSuite::per_row_for_budget(probe.rows(), budget);
        let suite = CoveringSuite::new(space, strength, kind, per_row, seed).map_err(err)?;
        Ok(valid_only(Box::new(suite), space))
    }
}

impl Strategy {
    /// The generator of [`Strategy::Points`]: `points`, in their order.
    ///
    /// # Errors
    /// As [`GivenPoints::new`]; [`GeneratorError::Forbidden`] for the first point that breaks
    /// a constraint of `space` (a given point is never skipped in silence).
    pub fn build_given(
        space: &ParamSpace,
        points: Vec<crate::Point>,
    ) -> Result<Box<dyn Generator>, GeneratorError> {
        let given = GivenPoints::new(space, points.clone())?;
        for (index, p) in points.iter().enumerate() {
            if let Some(violation) = space.violation(p)? {
                return Err(GeneratorError::Forbidden { index, violation });
            }
        }
        Ok(Box::new(given))
    }
}

/// `g` as it is over an unconstrained space, else its valid points only.
fn valid_only(g: Box<dyn Generator>, space: &ParamSpace) -> Box<dyn Generator> {
    if space.is_constrained() {
        Box::new(crate::ValidOnly::new(g, space))
    } else {
        g
    }
}

impl FromStr for Strategy {
    type Err = GeneratorError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == "variation" {
            return Ok(Strategy::FullFactorial);
        }
        Strategy::LIST
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
        for s in Strategy::LIST {
            assert_eq!(s.name().parse::<Strategy>().unwrap(), s);
            assert!(!s.help().is_empty());
        }
        // The groups are parts of the list.
        for s in Strategy::ALL
            .into_iter()
            .chain(Strategy::SUITES)
            .chain(Strategy::FALSIFIERS)
        {
            assert!(Strategy::LIST.contains(&s));
        }
        // ... and with the given points and the full-factorial design, the whole list.
        assert_eq!(
            Strategy::ALL.len() + Strategy::SUITES.len() + Strategy::FALSIFIERS.len() + 2,
            Strategy::LIST.len()
        );
        assert_eq!(
            "variation".parse::<Strategy>().unwrap(),
            Strategy::FullFactorial
        );
        assert_eq!(
            "annealing".parse::<Strategy>().unwrap_err().to_string(),
            "unknown strategy `annealing` (expected one of: random, halton, halton-scrambled, sobol, ipog, kwise, falsify-nm, falsify-pso, falsify-sa, falsify-ce, falsify-bo, falsify-bo-lcb, points, full-factorial)"
        );
    }
}
