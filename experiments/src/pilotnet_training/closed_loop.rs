//! Judging an epoch in closed loop: the network, exported as it stands, drives held-out
//! tests of a scenario ([`super::TrainConfig::closed_loop`]).

use std::collections::BTreeMap;

use paracosm_engine::sut::Manifest;

use crate::pilotnet;
use crate::training_error::TrainingError;

/// Index of the first Halton point of the closed-loop tests (a data set's tests are the
/// first points).
pub(super) const CLOSED_LOOP_FROM: u64 = 4096;

/// How many closed-loop tests failed, and how many times each monitor failed (a test can
/// fail several), by name.
pub(super) type Failures = (usize, BTreeMap<String, usize>);

/// The held-out closed-loop tests that judge an epoch ([`super::TrainConfig::closed_loop`]).
pub(super) struct ClosedLoop {
    scenario: paracosm_scenarios::Scenario,
    /// The tests' parameters, Halton points from [`CLOSED_LOOP_FROM`] on.
    pub(super) points: Vec<paracosm_generators::Assignment>,
    manifest: Manifest,
}

impl ClosedLoop {
    /// `tests` tests of the scenario `name` (a built-in name or a `.star` file), driven by
    /// networks with `manifest`.
    pub(super) fn new(
        name: &str,
        tests: usize,
        manifest: &Manifest,
    ) -> Result<Self, TrainingError> {
        use paracosm_generators::{Generator, Halton};
        let scenario =
            paracosm_scenarios::load(name).map_err(|e| TrainingError::Scenario(e.to_string()))?;
        let mut halton = Halton::new(scenario.space());
        halton.skip(CLOSED_LOOP_FROM)?;
        let points = halton
            .ask(tests)?
            .iter()
            .map(|p| scenario.space().decode(p))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(ClosedLoop {
            scenario,
            points,
            manifest: manifest.clone(),
        })
    }

    /// How many of the tests fail with the network of `weights` driving, and how many times
    /// each monitor failed (a test can fail several), by name.
    pub(super) fn failures(&self, weights: &[pilotnet::Weight]) -> Result<Failures, TrainingError> {
        let onnx = pilotnet::to_onnx(weights, "an epoch under closed-loop validation");
        let config =
            paracosm_engine::sut::OnnxConfig::from_bytes("training", &onnx, self.manifest.clone())?;
        let mut s = self.scenario.clone();
        s.set_sut(paracosm_engine::sut::SutConfig::Onnx(Box::new(config)));
        let (mut failed, mut by_monitor) = (0, BTreeMap::new());
        for (i, a) in self.points.iter().enumerate() {
            let o = s
                .run(a, CLOSED_LOOP_FROM + i as u64)
                .map_err(|e| TrainingError::Scenario(e.to_string()))?;
            failed += usize::from(!o.passed());
            for (name, v) in &o.monitors {
                if !v.passed {
                    *by_monitor.entry(name.clone()).or_insert(0) += 1;
                }
            }
        }
        Ok((failed, by_monitor))
    }
}
