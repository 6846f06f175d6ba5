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

/// A rate (frames, scans or decisions per simulated second) that is not a whole number of
/// physics steps per period ([`crate::steps_per_period`]). Its message names the rate and the
/// nearest rates that are whole steps.
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "{name} {hz} is not a whole number of physics steps ({step_hz} per second) per period: \
     use {step_hz} / k for a whole k{}",
    such_as(near)
)]
pub struct RateError {
    /// What the rate is, e.g. `camera rate_hz`.
    pub name: String,
    /// The rate asked for, Hz (any `f64`: NaN, negative and infinite ones included).
    pub hz: f64,
    /// The physics steps per second, `1 / dt_s`.
    pub step_hz: f64,
    /// The nearest rates that are whole steps per period, Hz, slower first: none, one or two.
    pub near: Vec<f64>,
}

/// ", such as A or B" for the rates `near`; empty for none.
fn such_as(near: &[f64]) -> String {
    if near.is_empty() {
        String::new()
    } else {
        let near: Vec<String> = near.iter().map(|hz| format!("{hz}")).collect();
        format!(", such as {}", near.join(" or "))
    }
}
