//! Scenarios: a parameter space of open inputs plus a world template that the engine runs.
//!
//! A [`Scenario`] declares its open parameters once ([`Scenario::space`]), turns an
//! [`Assignment`] of them into a concrete world ([`Scenario::instantiate`]), and runs one test
//! in closed loop with its system under test and monitors ([`Scenario::run`]).
//!
//! Scenarios are Starlark programs in the paper's vocabulary ([`lang`], LANGUAGE.md). The
//! shipped ones live in `scenarios/*.star`, are compiled into the binary, and are listed by
//! [`builtin_names`] and loaded by [`builtin`]; [`load`] takes a path or a built-in name.
#![warn(missing_docs)]

pub mod analysis;
mod error;
pub mod front_end;
pub mod lang;
pub mod map_files;
pub use paracosm_engine::memory;
pub mod reference;
mod runner;
mod scenario;
pub mod scene;
pub mod text_file;
pub mod xosc;

use std::path::Path;

pub use error::ScenarioError;
pub use front_end::{FrontEnd, RustScenes, SceneFn};
pub use runner::{signal, RunOptions, Sample, TestOutcome};
pub use scenario::{
    map_axes_of, monitors_of, scene_contract, CameraOnly, InputFile, Scenario, SceneContract,
    Warning,
};
pub use scene::MonitorSpec;

/// The shipped scenario programs: `(file name, source)`.
pub const BUILTIN_SOURCES: [(&str, &str); 11] = [
    (
        "pedestrian_crossing.star",
        include_str!("../pedestrian_crossing.star"),
    ),
    (
        "follow_lead_car.star",
        include_str!("../follow_lead_car.star"),
    ),
    ("fog_light.star", include_str!("../fog_light.star")),
    ("t_loop.star", include_str!("../t_loop.star")),
    ("grid_world.star", include_str!("../grid_world.star")),
    ("cut_in.star", include_str!("../cut_in.star")),
    ("roundabout.star", include_str!("../roundabout.star")),
    (
        "family_of_worlds.star",
        include_str!("../family_of_worlds.star"),
    ),
    ("example_3_1.star", include_str!("../example_3_1.star")),
    (
        "curve_pedestrian.star",
        include_str!("../curve_pedestrian.star"),
    ),
    (
        "opendrive_junction.star",
        include_str!("../opendrive_junction.star"),
    ),
];

/// Names of the built-in scenarios: the file stems with hyphens (`pedestrian-crossing`, ...).
pub fn builtin_names() -> Vec<String> {
    BUILTIN_SOURCES
        .iter()
        .map(|(f, _)| f.trim_end_matches(".star").replace('_', "-"))
        .collect()
}

/// The built-in scenario called `name` (hyphens or underscores).
///
/// # Errors
/// [`ScenarioError::UnknownScenario`] listing the known names.
pub fn builtin(name: &str) -> Result<Scenario, ScenarioError> {
    let wanted = name.replace('_', "-");
    for (file, source) in BUILTIN_SOURCES {
        let stem = file.trim_end_matches(".star").replace('_', "-");
        if stem == wanted {
            return lang::load_builtin(&format!("scenarios/{file}"), source, &stem);
        }
    }
    Err(ScenarioError::UnknownScenario {
        name: name.to_owned(),
        known: builtin_names().join(", "),
    })
}

/// A scenario by path (anything ending in `.star` or naming an existing file) or by built-in
/// name.
///
/// # Errors
/// As [`lang::load_file`] and [`builtin`].
pub fn load(name_or_path: &str) -> Result<Scenario, ScenarioError> {
    let path = Path::new(name_or_path);
    if name_or_path.ends_with(".star") || path.exists() {
        lang::load_file(path)
    } else {
        builtin(name_or_path)
    }
}
