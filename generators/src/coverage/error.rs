use thiserror::Error;

/// Errors of the coverage estimators.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CoverageError {
    /// The input does not have the documented shape (`n × d` row-major, `d >= 1`).
    #[error("bad point set: {0}")]
    Shape(String),
    /// A value is NaN, infinite, or outside `[0, 1]`. Rows and columns count from 0.
    #[error("row {row}, column {column}: value {value} is not in [0, 1]")]
    OutsideUnitCube {
        /// Row (point) index, from 0.
        row: usize,
        /// Column (coordinate) index, from 0.
        column: usize,
        /// The offending value.
        value: f64,
    },
    /// A level index is out of its parameter's range. Rows and columns count from 0.
    #[error("row {row}, column {column}: level index {level} is out of range 0..{levels}")]
    LevelOutOfRange {
        /// Row index, from 0.
        row: usize,
        /// Discrete column index, from 0.
        column: usize,
        /// The offending level index.
        level: u32,
        /// The parameter's number of levels.
        levels: u32,
    },
    /// A strength `t` outside `1..=min(6, number of discrete parameters)`.
    #[error("strength t = {t} is not in 1..={max} (there are {discrete} discrete parameters)")]
    Strength {
        /// The strength asked for.
        t: usize,
        /// The largest strength allowed here.
        max: usize,
        /// The number of discrete parameters.
        discrete: usize,
    },
    /// The number of t-tuples does not fit in 64 bits.
    #[error("too many {t}-tuples to count")]
    TooManyTuples {
        /// The strength.
        t: usize,
    },
}
