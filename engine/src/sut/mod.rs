//! Systems under test: the software that drives the ego vehicle, called once per physics step
//! with an [`Observation`] and answering a [`Control`].
//!
//! Built in: [`Aeb`] (cruise control with automatic emergency braking on lidar time to
//! collision) and [`ConstantControl`] (open loop, for baselines and physics tests).

mod aeb;
mod constant;

pub use aeb::{Aeb, AebConfig};
pub use constant::ConstantControl;

use serde::{Deserialize, Serialize};
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

/// A system under test.
pub trait Sut: Send {
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SutConfig {
    /// The built-in `aeb`.
    Aeb(AebConfig),
    /// Open-loop constant control.
    Constant(Control),
}

impl SutConfig {
    /// A fresh instance of the configured system.
    pub fn build(&self) -> Box<dyn Sut> {
        match self {
            SutConfig::Aeb(c) => Box::new(Aeb::new(c.clone())),
            SutConfig::Constant(c) => Box::new(ConstantControl(*c)),
        }
    }
}
