use thiserror::Error;

/// Errors of parameter spaces and generators.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GeneratorError {
    /// A parameter's domain is empty or not finite (`lo >= hi`, NaN bounds, no levels).
    #[error("parameter `{name}`: {reason}")]
    InvalidDomain {
        /// The parameter's name.
        name: String,
        /// What is wrong with the domain.
        reason: String,
    },
    /// Two parameters share a name.
    #[error("parameter `{0}` is declared twice")]
    DuplicateParam(String),
    /// A point does not fit the space: wrong number of coordinates, a coordinate outside
    /// `[0, 1)`, or a level index out of range.
    #[error("point does not fit the parameter space: {0}")]
    PointMismatch(String),
    /// The generator cannot produce that many points, or that many dimensions.
    #[error("{generator} supports at most {limit} {what}, but {requested} were requested")]
    CapacityExceeded {
        /// The generator's name, e.g. `sobol`.
        generator: &'static str,
        /// `points` or `dimensions`.
        what: &'static str,
        /// The generator's limit.
        limit: u64,
        /// What was asked for.
        requested: u64,
    },
    /// A covering-suite strategy was built without a budget ([`crate::Strategy::build_sized`]).
    #[error("strategy `{0}` needs a budget and a strength")]
    NeedsBudget(&'static str),
    /// [`crate::Strategy::Points`] was built without its points ([`crate::Strategy::build_given`]).
    #[error("strategy `points` takes its points from a file: give --points FILE")]
    NeedsPoints,
    /// The covering array of a suite cannot be built.
    #[error("covering array: {0}")]
    Covering(String),
    /// A strategy name that no generator answers to.
    #[error("unknown strategy `{0}` (expected one of: {names})", names = crate::Strategy::names())]
    UnknownStrategy(String),
    /// A constraint could not be evaluated at a point.
    #[error("constraint `{name}` cannot be evaluated: {reason}")]
    ConstraintFailed {
        /// The constraint's name.
        name: String,
        /// Why.
        reason: String,
    },
    /// The constraints leave no valid point: the space is refused.
    #[error("the constraints ({constraints}) leave no valid point: none of {tried} points tried is valid")]
    NoValidPoint {
        /// The constraints' names, comma-separated.
        constraints: String,
        /// How many points were tried.
        tried: u64,
    },
    /// A given point breaks a constraint ([`crate::GivenPoints`]).
    #[error("point {index} breaks {violation}: a test is never run on a forbidden point")]
    Forbidden {
        /// The point's index, from 0.
        index: usize,
        /// The constraint it breaks, and how.
        violation: crate::Violation,
    },
    /// A constrained space has too many combinations of levels to enumerate for its
    /// forbidden tuples (covering arrays and k-wise coverage of the valid space).
    #[error(
        "the space has more than {limit} combinations of discrete levels: too many to find \
         those its constraints forbid (a covering suite over a constrained space needs them; \
         use a sampler such as halton, which skips invalid points)"
    )]
    TooManyCombinations {
        /// [`crate::MAX_ENUMERATED_COMBINATIONS`].
        limit: u64,
    },
}
