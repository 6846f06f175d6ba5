//! The typed error of the training runs and studies of the learned networks
//! ([`crate::perception::train`], [`crate::perception::studies`],
//! [`crate::pilotnet_training`]).
//!
//! Each variant's message is the text the binaries printed before these steps moved into the
//! library: a file that cannot be read says `reading PATH` and keeps the underlying error as
//! its [`source`](std::error::Error::source), and errors passed through unchanged are
//! `transparent`.

use std::path::PathBuf;

/// Why training a network, or a study with one, failed.
#[derive(Debug, thiserror::Error)]
pub enum TrainingError {
    /// candle failed: a tensor of an unexpected shape, a failed backward pass or optimiser
    /// step.
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
    /// A file (`annotations.json`, a data set's `dataset.json` by its path) cannot be read.
    #[error("reading {}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// A perception data set's `dataset.json` cannot be read (the message names the file,
    /// not its folder).
    #[error("reading dataset.json")]
    DatasetJson {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// A camera image or class mask cannot be opened or decoded.
    #[error("reading {}", .path.display())]
    Image {
        /// The image file.
        path: PathBuf,
        /// What the decoder said.
        #[source]
        source: image::ImageError,
    },
    /// A data set's `frames.csv` cannot be opened.
    #[error("reading {}", .path.display())]
    CsvOpen {
        /// The CSV file.
        path: PathBuf,
        /// What the CSV reader said.
        #[source]
        source: csv::Error,
    },
    /// Another file-system failure: a folder that cannot be created, a file that cannot be
    /// flushed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// A CSV file cannot be read or written.
    #[error(transparent)]
    Csv(#[from] csv::Error),
    /// A JSON file (`annotations.json`, `dataset.json`) is not valid JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A CSV field that should be a real number is not.
    #[error(transparent)]
    ParseFloat(#[from] std::num::ParseFloatError),
    /// A CSV field that should be an integer (a test id) is not.
    #[error(transparent)]
    ParseInt(#[from] std::num::ParseIntError),
    /// A road study's `--data FOCAL_MM=DIR` whose focal length is not a number.
    #[error("--data {arg}: focal")]
    Focal {
        /// The whole `FOCAL_MM=DIR` argument.
        arg: String,
        /// Why the focal length does not parse.
        #[source]
        source: std::num::ParseFloatError,
    },
    /// An output file cannot be written (paracosm's atomic write).
    #[error(transparent)]
    Write(#[from] paracosm::Error),
    /// A study's plot cannot be drawn.
    #[error(transparent)]
    Plot(#[from] paracosm::report::plot::PlotError),
    /// A perception network's ONNX file cannot be loaded or run by tract.
    #[error(transparent)]
    OnnxMap(#[from] crate::perception::OnnxMapError),
    /// The closed-loop tests' Halton points cannot be drawn or decoded.
    #[error(transparent)]
    Generator(#[from] paracosm_generators::GeneratorError),
    /// The PilotNet manifest does not parse, or an epoch's network cannot be loaded as a
    /// system under test.
    #[error(transparent)]
    Model(#[from] paracosm_engine::sut::ModelError),
    /// The closed-loop scenario does not load, or one of its tests cannot run: the
    /// scenario's message (without its causes, as the binary printed it).
    #[error("{0}")]
    Scenario(String),
    /// The data are not what training needs (a missing field or column, images of another
    /// size, too few tests for a validation part, no epoch run): the message.
    #[error("{0}")]
    Data(String),
}

/// An `Option` made a [`TrainingError::Data`] with a fixed message when it is `None` (as
/// anyhow's `context` on an `Option`).
pub(crate) trait OrData<T> {
    /// The value, or [`TrainingError::Data`] with `message`.
    fn or_data(self, message: &str) -> Result<T, TrainingError>;
}

impl<T> OrData<T> for Option<T> {
    fn or_data(self, message: &str) -> Result<T, TrainingError> {
        self.ok_or_else(|| TrainingError::Data(message.to_owned()))
    }
}
