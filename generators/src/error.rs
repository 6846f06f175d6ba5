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
}
