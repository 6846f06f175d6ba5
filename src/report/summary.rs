//! `summary.json`: a campaign's settings, counts and first failure.

use serde::{Deserialize, Serialize};

use paracosm_generators::{Assignment, Param};

use crate::campaign::file::SutChoice;
use crate::record::{RunRecord, Status};

/// File name of the summary in the output folder.
pub const SUMMARY_FILE: &str = "summary.json";

/// Counts of test outcomes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counts {
    /// Tests whose monitors all passed.
    pub pass: u64,
    /// Tests with at least one failed monitor.
    pub fail: u64,
    /// Tests that ended in an error.
    pub error: u64,
}

impl Counts {
    /// The tools' exit code for these outcomes: 1 when a test failed, else 3 when one ended
    /// in an error, else 0.
    pub fn exit_code(&self) -> u8 {
        if self.fail > 0 {
            1
        } else if self.error > 0 {
            3
        } else {
            0
        }
    }

    /// The outcome counts of `records`: the one place they are counted.
    pub fn of(records: &[RunRecord]) -> Counts {
        let mut c = Counts::default();
        for r in records {
            match r.status {
                Status::Pass => c.pass += 1,
                Status::Fail => c.fail += 1,
                Status::Error => c.error += 1,
            }
        }
        c
    }
}

/// The first failing test, by id.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FirstFailure {
    /// Test id.
    pub id: u64,
    /// Its parameter values.
    pub params: Assignment,
    /// The monitors that failed.
    pub failed_monitors: Vec<String>,
}

impl FirstFailure {
    /// The failing test of `records` (in id order) with the smallest id, if any.
    pub fn of(records: &[RunRecord]) -> Option<FirstFailure> {
        records.iter().find_map(|r| match (&r.status, &r.params) {
            (Status::Fail, Some(params)) => Some(FirstFailure {
                id: r.id,
                params: params.clone(),
                failed_monitors: r.failed_monitors(),
            }),
            _ => None,
        })
    }
}

/// A failed test as `summary.json` lists it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureEntry {
    /// Test id.
    pub id: u64,
    /// The smallest robustness over its monitors (the most violated); `null` when not a
    /// number (read back as NaN).
    #[serde(deserialize_with = "crate::record::f64_or_null")]
    pub robustness: f64,
    /// The monitors that failed.
    pub failed_monitors: Vec<String>,
    /// Its parameter values.
    pub params: Option<Assignment>,
    /// The command that re-runs it and writes its camera frames.
    pub replay: String,
}

/// The system under test a campaign ran, as `summary.json` and the report page name it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SutSummary {
    /// `builtin` (`aeb`, `vision`, `pilotnet`, `constant`), `onnx` (a model) or `command` (an
    /// external program speaking SUT_PROTOCOL.md).
    pub kind: String,
    /// The built-in's name, the model's path as given, or the command line (its words as a
    /// shell would take them).
    pub name: String,
    /// SHA-256 (hex) of the ONNX model's bytes, for `onnx` and for `pilotnet`; absent for the
    /// others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sha256: Option<String>,
    /// Who chose it: `scenario` (the program's `AutonomousVehicle(sut=...)` or its default),
    /// `--sut`, `--sut-onnx` or `--sut-cmd`.
    pub chosen_by: String,
}

impl SutSummary {
    /// The system `sut` that ran, chosen as `choice` records.
    pub fn of(sut: &paracosm_engine::sut::SutConfig, choice: &SutChoice) -> SutSummary {
        use paracosm_engine::sut::SutConfig;
        let chosen_by = match choice {
            SutChoice::Scenario => "scenario",
            SutChoice::Builtin { .. } => "--sut",
            SutChoice::Onnx { .. } => "--sut-onnx",
            SutChoice::Command { .. } => "--sut-cmd",
        }
        .to_owned();
        let sha256 = sut.model_sha256().map(str::to_owned);
        let (kind, name) = match sut {
            SutConfig::External(e) => (
                "command",
                shlex::try_join(e.command.iter().map(String::as_str))
                    .unwrap_or_else(|_| e.command.join(" ")),
            ),
            other => {
                let name = other.name();
                match name.strip_prefix("onnx:") {
                    Some(model) if sha256.is_some() => ("onnx", model.to_owned()),
                    _ => ("builtin", name),
                }
            }
        };
        SutSummary {
            kind: kind.to_owned(),
            name,
            sha256,
            chosen_by,
        }
    }

    /// One line for people: `aeb (built in, the scenario's)`, `onnx model m.onnx (SHA-256
    /// ...)`, `command "python3 sut.py" (--sut-cmd)`.
    pub fn text(&self) -> String {
        let by = if self.chosen_by == "scenario" {
            "the scenario's".to_owned()
        } else {
            self.chosen_by.clone()
        };
        let hash = self
            .sha256
            .as_ref()
            .map(|h| format!(", SHA-256 {h}"))
            .unwrap_or_default();
        match self.kind.as_str() {
            "onnx" => format!("ONNX model {} ({by}{hash})", self.name),
            "command" => format!("external command `{}` ({by})", self.name),
            _ => format!("{} (built in, {by}{hash})", self.name),
        }
    }
}

/// The contents of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Every failed test, most violated (smallest robustness) first, each with the command
    /// that replays it.
    pub failures: Vec<FailureEntry>,
    /// `paracosm <version>`.
    pub tool: String,
    /// Scenario name.
    pub scenario: String,
    /// The system under test that ran; `null` in summaries written before it was recorded.
    #[serde(default)]
    pub sut: Option<SutSummary>,
    /// The vehicle the system under test drives, when the scenario's file chose it among
    /// its entities (an OpenSCENARIO file: its name and bounding box, `Ego, 5 × 2 × 1.8 m`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego: Option<String>,
    /// Strategy name.
    pub strategy: String,
    /// Campaign seed.
    pub seed: u64,
    /// Number of tests of the whole campaign.
    pub budget: u64,
    /// The shard this folder holds (`null`: the whole campaign).
    pub shard: Option<crate::campaign::file::Shard>,
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
    /// What the scenario's constraints leave valid (its generators draw only there, and
    /// `coverage` counts only the valid t-tuples); absent for an unconstrained space.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub valid_space: Option<ValidSpace>,
    /// Where failures are: rules from a shallow decision tree fitted on the records, and the
    /// parameters ranked by how much they explain the outcome ([`crate::report::triage`]); `null` with
    /// fewer than 10 tests that passed or failed, or no open parameter.
    #[serde(default)]
    pub triage: Option<crate::report::triage::Triage>,
    /// The scenario's warnings for this campaign (LANGUAGE.md, "Warnings") and any plot that
    /// could not be drawn.
    pub warnings: Vec<String>,
    /// Wall-clock time of the whole campaign in seconds.
    pub wall_s: f64,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
}

impl Summary {
    /// Reads `summary.json` from the campaign folder `dir`.
    ///
    /// # Errors
    /// [`crate::Error::Input`] naming the file when it cannot be read or is not a summary
    /// (with its line and column).
    pub fn read(dir: &std::path::Path) -> Result<Summary, crate::Error> {
        let path = dir.join(SUMMARY_FILE);
        paracosm_engine::files::regular_file(&path).map_err(|e| crate::Error::input(&path, e))?;
        let text = std::fs::read_to_string(&path).map_err(|e| crate::Error::input(&path, e))?;
        serde_json::from_str(&text).map_err(|e| {
            let message = format!(
                "{}: not a summary: {e}",
                crate::error::located(&path, e.line(), e.column())
            );
            crate::Error::malformed(&path, message)
        })
    }
}

/// The valid part of a constrained space ([`Summary::valid_space`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidSpace {
    /// The constraints' names, comma-separated.
    pub constraints: String,
    /// The share of the space they leave, exact or estimated with its 95 % interval.
    pub fraction: paracosm_generators::ValidFraction,
}
