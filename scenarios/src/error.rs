use paracosm_engine::sut::SutError;
use paracosm_engine::EngineError;
use paracosm_generators::GeneratorError;
use thiserror::Error;

/// Errors loading, instantiating or running a scenario.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ScenarioError {
    /// No built-in scenario has that name.
    #[error("unknown scenario `{name}` (built-in scenarios: {known})")]
    UnknownScenario {
        /// The name asked for.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// The assignment lacks a parameter the world needs, or has it with a non-numeric value.
    #[error("assignment has no numeric value for parameter `{0}`")]
    MissingParam(String),
    /// The parameter space or a point is invalid.
    #[error(transparent)]
    Space(#[from] GeneratorError),
    /// The instantiated world cannot be built.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// A scenario program is wrong: the message is a diagnostic naming the file, line and
    /// column, with the source line and a caret.
    #[error("{0}")]
    Language(String),
    /// A program does not load, or a world of it cannot be built: a diagnostic naming the
    /// file, line and column, typed by the phase that refused it.
    #[error(transparent)]
    Load(#[from] crate::lang::LoadError),
    /// A scenario file cannot be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The path.
        path: String,
        /// The system's message.
        message: String,
    },
    /// A test that reached its horizon but did not play as its scenario describes (an
    /// OpenSCENARIO storyboard cut short while events still waited to start, an ego that
    /// never moved): the message says what never happened and at what simulated time.
    #[error("{message}")]
    Unplayed {
        /// The horizon's simulated time, s.
        t_s: f64,
        /// What did not happen, from `t = ... s:`, naming the elements and where they are
        /// written.
        message: String,
    },
    /// An OpenSCENARIO file, or an option given with it, that a campaign cannot read: the
    /// message names the file (with the line and column) or the option.
    #[error("{message}")]
    Input {
        /// The file given.
        path: std::path::PathBuf,
        /// What is wrong, naming the file or the option.
        message: String,
    },
    /// The system under test failed.
    #[error(transparent)]
    Sut(#[from] SutError),
}
