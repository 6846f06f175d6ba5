use thiserror::Error;

/// Errors building or running a world.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EngineError {
    /// A world description that cannot be built (a non-positive length, an odd lane count, an
    /// actor off the road...). The message names the field and the offending value.
    #[error("invalid world: {0}")]
    InvalidWorld(String),
    /// The stream graph failed while running (a lambda raised, a value of the wrong kind).
    #[error(transparent)]
    Stream(#[from] crate::rx::RxError),
    /// A sensor cannot be set up or read (no GPU adapter for the camera, a camera setting out
    /// of range, a lost device).
    #[error("sensor: {0}")]
    Sensor(String),
}
