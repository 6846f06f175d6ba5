//! Systems under test: the software that drives the ego vehicle, called once per physics step
//! with an [`Observation`] and answering a [`Control`].
//!
//! Built in: [`Aeb`] (cruise control with automatic emergency braking on lidar time to
//! collision), [`Vision`] (lane keeping and braking from the camera image and depth map) and
//! [`ConstantControl`] (open loop, for baselines and physics tests). [`ExternalSut`] runs a
//! system under test in another process, in any language (SUT_PROTOCOL.md).

mod aeb;
mod constant;
mod cruise;
mod external;
mod vision;

pub use aeb::{Aeb, AebConfig};
pub use constant::ConstantControl;
pub use cruise::Cruise;
pub use external::{ExternalConfig, ExternalSut, ProcessPool, PROTOCOL_VERSION};
pub use vision::{Perception, Vision, VisionConfig};

use thiserror::Error;

use crate::{Control, Observation};

/// A failure of the system under test itself (not of the world): the test is recorded as an
/// `error`, not as a pass or fail.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SutError {
    /// The system could not produce a control (crashed, timed out, malformed answer).
    #[error("system under test failed: {0}")]
    Failed(String),
}

/// The sensors a system under test reads, beyond odometry and lidar (always present).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sensors {
    /// A camera on the ego vehicle (RGB and depth), rendered at its `rate_hz`.
    pub camera: Option<crate::CameraSpec>,
    /// How often it decides, in Hz of simulated time; `None`: every physics step. Between
    /// decisions the last control is held.
    pub control_hz: Option<f64>,
}

/// A system under test.
pub trait Sut: Send {
    /// The sensors it needs; asked after each [`Sut::reset`]. Default: odometry and lidar,
    /// deciding every step.
    fn sensors(&self) -> Sensors {
        Sensors::default()
    }

    /// Prepares a fresh run; `seed` drives any randomness of the system.
    ///
    /// # Errors
    /// [`SutError::Failed`] if the system cannot start.
    fn reset(&mut self, seed: u64) -> Result<(), SutError>;

    /// The control for the coming step, given what the vehicle senses now.
    ///
    /// # Errors
    /// [`SutError::Failed`] if the system cannot answer.
    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError>;
}

/// A system under test by configuration: what a scenario names and a campaign builds per test.
#[derive(Debug, Clone, PartialEq)]
pub enum SutConfig {
    /// The built-in `aeb`.
    Aeb(AebConfig),
    /// The built-in `vision`.
    Vision(VisionConfig),
    /// Open-loop constant control.
    Constant(Control),
    /// A program in another process (`--sut-cmd`).
    External(ExternalConfig),
}

/// Names of the built-in systems under test, for `--sut` and `AutonomousVehicle(sut=)`.
pub const BUILTIN_SUTS: [&str; 2] = ["aeb", "vision"];

impl SutConfig {
    /// The built-in system called `name` (see [`BUILTIN_SUTS`]) with default settings.
    ///
    /// # Errors
    /// A message listing the known names.
    pub fn builtin(name: &str) -> Result<SutConfig, String> {
        match name {
            "aeb" => Ok(SutConfig::Aeb(AebConfig::default())),
            "vision" => Ok(SutConfig::Vision(VisionConfig::default())),
            _ => Err(format!(
                "unknown system under test `{name}`; built in: {}",
                BUILTIN_SUTS.join(", ")
            )),
        }
    }

    /// A short name for reports: `aeb`, `vision`, `constant`, or the external command line.
    pub fn name(&self) -> String {
        match self {
            SutConfig::Aeb(_) => "aeb".into(),
            SutConfig::Vision(_) => "vision".into(),
            SutConfig::Constant(_) => "constant".into(),
            SutConfig::External(e) => e.command.join(" "),
        }
    }

    /// Whether the system reads a camera: `Some(false)` for `aeb` and constant control,
    /// `Some(true)` for `vision`, `None` for an external program (it declares its sensors in
    /// its handshake, when a test starts).
    pub fn has_camera(&self) -> Option<bool> {
        match self {
            SutConfig::Aeb(_) | SutConfig::Constant(_) => Some(false),
            SutConfig::Vision(_) => Some(true),
            SutConfig::External(_) => None,
        }
    }

    /// A fresh instance of the configured system.
    pub fn build(&self) -> Box<dyn Sut> {
        match self {
            SutConfig::Aeb(c) => Box::new(Aeb::new(c.clone())),
            SutConfig::Vision(c) => Box::new(Vision::new(c.clone())),
            SutConfig::Constant(c) => Box::new(ConstantControl(*c)),
            SutConfig::External(c) => Box::new(ExternalSut::new(c.clone())),
        }
    }
}
