//! paracosm: coverage-driven testing and falsification of autonomous-driving systems.
//!
//! This root crate runs test campaigns: it asks a generator for points of a scenario's
//! parameter space, runs one closed-loop simulation per point in parallel, appends every
//! result to `results.jsonl` as soon as it is known, and writes `summary.json` and the failure
//! map. The command-line tools `paracosm-fuzz` and `paracosm-cover` sit on top
//! (`src/bin/`). See `ARCHITECTURE.md` for how the crates fit together.
#![warn(missing_docs)]

pub mod atomic;
pub mod campaign;
pub mod cli;
pub mod cover;
mod error;
pub mod export;
pub mod fuzz;
pub mod map;
pub mod record;
pub mod report;
pub mod scenario_ref;

pub use campaign::{Campaign, CampaignReport, Observer, OnRecord, ResultsFile};
pub use error::Error;
pub use record::{RunRecord, Status};
pub use scenario_ref::ScenarioRef;

/// The scenario `name` names: a built-in scenario, a `.star` program, or an OpenSCENARIO
/// file read as it is ([`ScenarioRef::named`]; with options, build a [`ScenarioRef`]).
///
/// # Errors
/// What [`ScenarioRef::load`] returns.
pub fn load_scenario(name: &str) -> Result<paracosm_scenarios::Scenario, Error> {
    ScenarioRef::named(name).load()
}

/// Refuses a system under test for a scenario whose ego a script places (`--scripted-ego`):
/// its control would never be read, and the test would not test it.
///
/// # Errors
/// [`Error::BadInput`] when `scenario`'s system under test is
/// [`paracosm_engine::sut::SutConfig::Scripted`].
pub fn refuse_sut_for_scripted_ego(scenario: &paracosm_scenarios::Scenario) -> Result<(), Error> {
    if matches!(scenario.sut(), paracosm_engine::sut::SutConfig::Scripted) {
        return Err(Error::BadInput(format!(
            "{}: the storyboard moves the ego (--scripted-ego), so no system under test drives \
             it: leave out --sut, --sut-cmd and --sut-onnx, or --scripted-ego",
            scenario.name()
        )));
    }
    Ok(())
}
