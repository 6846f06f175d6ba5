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
    /// The forbidden combinations of a constrained space could not be found
    /// ([`crate::ParamSpace::forbidden_levels`]).
    #[error("{0}")]
    Constraints(String),
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
    /// The estimator's working memory for this many points cannot be allocated (asked of
    /// the system before any of it is used: a point set too large is refused, never a crash).
    #[error(
        "{what} of {n} points in {d} dimensions needs {gib:.1} GiB of working memory, \
         which cannot be allocated"
    )]
    OutOfMemory {
        /// The estimator.
        what: &'static str,
        /// Number of points.
        n: usize,
        /// Dimension.
        d: usize,
        /// The working memory asked for, GiB.
        gib: f64,
    },
}

/// Asks the system for `bytes_per_point × n` bytes at once and gives them back unused: the
/// estimator `what` on `n` points in `d` dimensions then needs about that much, in buffers it
/// allocates as it goes, and a set too large for the machine is refused here with
/// [`CoverageError::OutOfMemory`] instead of aborting the process (a Rust allocation that
/// fails aborts; the Python package raises `MemoryError`).
///
/// # Errors
/// [`CoverageError::OutOfMemory`] when the product overflows or cannot be reserved.
pub(crate) fn reserve_working(
    what: &'static str,
    n: usize,
    d: usize,
    bytes_per_point: usize,
) -> Result<(), CoverageError> {
    let bytes = n.checked_mul(bytes_per_point);
    let refused = || CoverageError::OutOfMemory {
        what,
        n,
        d,
        gib: n as f64 * bytes_per_point as f64 / f64::from(1u32 << 30),
    };
    let bytes = bytes.ok_or_else(refused)?;
    let mut probe: Vec<u8> = Vec::new();
    probe.try_reserve_exact(bytes).map_err(|_| refused())
}
