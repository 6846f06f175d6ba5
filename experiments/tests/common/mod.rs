//! What the experiments' integration tests share: the repository's root and a data set
//! written by `paracosm-fuzz dataset`'s library call.
#![allow(dead_code)] // each test file uses what it needs

use std::path::{Path, PathBuf};

use paracosm::export::dataset::{export, DatasetRequest, DatasetSummary};
use paracosm_engine::CameraSpec;
use paracosm_generators::Strategy;

/// The repository's root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// How a test's data set is drawn: `budget` tests of `strategy` with `seed`, frames at
/// `rate_hz`, steering noise `±steer_noise` held `noise_hold_s` seconds (0: none).
pub struct Draw {
    pub strategy: Strategy,
    pub seed: u64,
    pub budget: u64,
    pub rate_hz: f64,
    pub steer_noise: f64,
    pub noise_hold_s: f64,
}

/// A data set of `scenario` (a path relative to the repository) seen by `camera`, written to
/// `out` with 2 workers; panics when the export fails.
pub fn dataset(scenario: &str, draw: &Draw, camera: CameraSpec, out: &Path) -> DatasetSummary {
    export(
        &DatasetRequest {
            scenario: repo().join(scenario).display().to_string(),
            strategy: draw.strategy,
            seed: draw.seed,
            budget: draw.budget,
            strength: 2,
            rate_hz: draw.rate_hz,
            camera,
            sut: None,
            out: out.to_path_buf(),
            replace: false,
            jobs: 2,
            steer_noise: draw.steer_noise,
            noise_hold_s: draw.noise_hold_s,
            learner: None,
            teacher_share: 0.0,
        },
        None,
    )
    .unwrap()
}
