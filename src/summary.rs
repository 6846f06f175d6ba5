//! `summary.json`: a campaign's settings, counts and first failure.

use serde::Serialize;

use paracosm_generators::{Assignment, Param};

/// Counts of test outcomes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Tests whose monitors all passed.
    pub pass: u64,
    /// Tests with at least one failed monitor.
    pub fail: u64,
    /// Tests that ended in an error.
    pub error: u64,
}

/// The first failing test, by id.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FirstFailure {
    /// Test id.
    pub id: u64,
    /// Its parameter values.
    pub params: Assignment,
    /// The monitors that failed.
    pub failed_monitors: Vec<String>,
}

/// A failed test as `summary.json` lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FailureEntry {
    /// Test id.
    pub id: u64,
    /// The smallest robustness over its monitors (the most violated); `null` when not a
    /// number.
    pub robustness: f64,
    /// The monitors that failed.
    pub failed_monitors: Vec<String>,
    /// Its parameter values.
    pub params: Option<Assignment>,
    /// The command that re-runs it and writes its camera frames.
    pub replay: String,
}

/// The contents of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Every failed test, most violated (smallest robustness) first, each with the command
    /// that replays it.
    pub failures: Vec<FailureEntry>,
    /// `paracosm <version>`.
    pub tool: String,
    /// Scenario name.
    pub scenario: String,
    /// Strategy name.
    pub strategy: String,
    /// Campaign seed.
    pub seed: u64,
    /// Number of tests of the whole campaign.
    pub budget: u64,
    /// The shard this folder holds (`null`: the whole campaign).
    pub shard: Option<crate::campaign_file::Shard>,
    /// Tests with a record in `results.jsonl`.
    pub tests_run: u64,
    /// Worker threads used (does not change any result).
    pub jobs: usize,
    /// The scenario's open parameters.
    pub space: Vec<Param>,
    /// The parameters (coordinates of `space`) that no object of the scenario reads: sampled
    /// and recorded, but left out of `coverage`.
    pub unused_params: Vec<String>,
    /// Outcome counts.
    pub counts: Counts,
    /// The failing test with the smallest id, if any.
    pub first_failure: Option<FirstFailure>,
    /// Coverage of the campaign's points over the parameters that objects read: k-wise
    /// coverage of the discrete parameters, dispersion, discrepancies and star discrepancy of
    /// the continuous ones (unit cube); `null` without such parameters.
    pub coverage: Option<crate::cover::Estimate>,
    /// The scenario's warnings for this campaign (LANGUAGE.md, "Warnings") and any plot that
    /// could not be drawn.
    pub warnings: Vec<String>,
    /// Wall-clock time of the whole campaign in seconds.
    pub wall_s: f64,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
}
