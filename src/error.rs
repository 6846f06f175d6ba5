//! The root library's error: what went wrong, from which the tools' exit codes follow.

use std::fmt::Display;
use std::path::{Path, PathBuf};

use paracosm_generators::GeneratorError;
use paracosm_scenarios::ScenarioError;

/// Why a campaign, a report, a merge or a replay could not be done.
///
/// The variant decides the exit code ([`Error::exit_code`]): the user's input (2) or not (3).
/// A test that fails or ends in an error is a record, never an [`Error`].
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Arguments or settings that cannot be honoured: a budget a strategy cannot serve, a
    /// shard of an adaptive campaign, `--resume` with other settings, a non-empty `--out`.
    #[error("{0}")]
    BadInput(String),
    /// A file the user gave, or one the campaign reads back, cannot be read or is not what it
    /// should be. The message names the file (and the line and column when it has them).
    #[error("{message}")]
    Input {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the file.
        message: String,
    },
    /// The scenario does not load (its messages name the file, line and column).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The strategy cannot serve the campaign (e.g. Sobol past 2^16 points).
    #[error(transparent)]
    Generator(#[from] GeneratorError),
    /// A file of the campaign cannot be written (no space left, a read-only disk). What was
    /// written before stays.
    #[error("cannot write `{}`: {reason}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        reason: String,
    },
    /// A plot cannot be drawn (its file cannot be written): `PlotError`'s message.
    #[error("{0}")]
    Plot(String),
    /// What a command prints cannot be written to its standard output (a full disk; a closed
    /// pipe, which the tools take as the reader's choice and exit 0).
    #[error("cannot write the output: {0}")]
    Output(std::io::Error),
    /// A defect of paracosm or of its machine: a worker pool that does not start, a panic
    /// outside a test.
    #[error("internal error: {0}")]
    Internal(String),
}

impl Error {
    /// The exit code of the tools for this error: 2 for the user's input ([`Error::BadInput`],
    /// [`Error::Input`], [`Error::Scenario`], [`Error::Generator`]), 3 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::BadInput(_) | Error::Input { .. } | Error::Scenario(_) | Error::Generator(_) => {
                2
            }
            Error::Write { .. } | Error::Output(_) | Error::Plot(_) | Error::Internal(_) => 3,
        }
    }

    /// [`Error::Input`] for `path`: `cannot read `path`: reason`.
    pub fn input(path: &Path, reason: impl Display) -> Self {
        Error::Input {
            path: path.to_path_buf(),
            message: format!("cannot read `{}`: {reason}", path.display()),
        }
    }

    /// [`Error::Input`] for `path` with `message` as it is (it names the file itself, e.g.
    /// `campaign.json:3:7: not a campaign file`).
    pub fn malformed(path: &Path, message: String) -> Self {
        Error::Input {
            path: path.to_path_buf(),
            message,
        }
    }

    /// [`Error::Write`] for `path`.
    pub fn write(path: &Path, reason: impl Display) -> Self {
        Error::Write {
            path: path.to_path_buf(),
            reason: reason.to_string(),
        }
    }
}

/// `path:line:column`, or `path:line` when the column is unknown (0: serde_json's custom
/// errors have none), for messages about a file.
pub(crate) fn located(path: &std::path::Path, line: usize, column: usize) -> String {
    if column == 0 {
        format!("{}:{line}", path.display())
    } else {
        format!("{}:{line}:{column}", path.display())
    }
}
