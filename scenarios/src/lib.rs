//! Scenarios: a parameter space of open inputs plus a world template that the engine runs.
//!
//! A [`Scenario`] declares its open parameters once ([`Scenario::space`]), turns an
//! [`Assignment`] of them into a concrete world ([`Scenario::instantiate`]), and runs one test
//! in closed loop with its system under test and monitors ([`Scenario::run`]).
//!
//! The built-in scenarios are listed by [`builtin_names`] and loaded by [`builtin`]. Until the
//! Starlark front end lands they are defined in Rust; their names, ranges and units live in one
//! place per scenario (e.g. [`pedestrian_crossing`]).
#![warn(missing_docs)]

mod error;
pub mod pedestrian_crossing;
mod runner;
mod scenario;

pub use error::ScenarioError;
pub use runner::{signal, TestOutcome};
pub use scenario::{MonitorSpec, Scenario};

use paracosm_generators::Assignment;

/// Names of the built-in scenarios, for `paracosm-fuzz NAME`.
pub fn builtin_names() -> &'static [&'static str] {
    &[pedestrian_crossing::NAME]
}

/// The built-in scenario called `name`.
///
/// # Errors
/// [`ScenarioError::UnknownScenario`] listing the known names.
pub fn builtin(name: &str) -> Result<Scenario, ScenarioError> {
    match name {
        pedestrian_crossing::NAME => Ok(pedestrian_crossing::scenario()),
        _ => Err(ScenarioError::UnknownScenario {
            name: name.to_owned(),
            known: builtin_names().join(", "),
        }),
    }
}

/// The real value of `name` in `a`.
///
/// # Errors
/// [`ScenarioError::MissingParam`] if absent or not numeric.
pub(crate) fn real(a: &Assignment, name: &str) -> Result<f64, ScenarioError> {
    a.real(name)
        .ok_or_else(|| ScenarioError::MissingParam(name.to_owned()))
}
