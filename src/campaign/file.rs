//! `campaign.json`: how a campaign was run, its fingerprint, and its shard.
//!
//! Written (atomically) before the first test. `--resume` compares the fingerprint of its
//! arguments with the stored one; `merge` checks that every shard has the same; `replay`
//! rebuilds any test from it.

use std::collections::BTreeMap;
use std::path::Path;

use paracosm_engine::sut::{ExternalConfig, SutConfig};
use paracosm_generators::Param;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::ScenarioRef;

/// File name of the campaign's settings in the output folder.
pub const CAMPAIGN_FILE: &str = "campaign.json";

/// Which system under test a campaign ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SutChoice {
    /// The scenario's own default (`AutonomousVehicle(sut=...)`).
    Scenario,
    /// A built-in system chosen with `--sut`.
    Builtin {
        /// `aeb` or `vision`.
        name: String,
    },
    /// A program chosen with `--sut-cmd`.
    Command {
        /// Program and arguments.
        command: Vec<String>,
        /// `--sut-timeout`, seconds.
        #[serde(deserialize_with = "buffered_f64")]
        timeout_s: f64,
        /// Whether processes were kept alive between tests.
        reuse: bool,
    },
    /// An ONNX model chosen with `--sut-onnx`.
    Onnx {
        /// The model's path as given.
        model: String,
        /// SHA-256 of its bytes, hex: `--resume` and `replay` refuse a changed model.
        sha256: String,
    },
}

/// A number inside an internally tagged enum. serde buffers such an enum before it picks the
/// variant, and under serde_json's `arbitrary_precision` (which starlark turns on) a buffered
/// number is a map that only `serde_json::Value` reads back as a number
/// (`tests/read_back.rs`).
fn buffered_f64<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    match serde_json::Value::deserialize(d)? {
        serde_json::Value::Number(n) => n
            .as_f64()
            .ok_or_else(|| serde::de::Error::custom(format!("{n} is not a number"))),
        other => Err(serde::de::Error::custom(format!(
            "expected a number, found `{other}`"
        ))),
    }
}

impl SutChoice {
    /// What `--sut`/`--sut-cmd` chose (`config`, from [`crate::cli::SutArgs::config`]).
    pub fn of(config: Option<&SutConfig>) -> SutChoice {
        match config {
            None => SutChoice::Scenario,
            Some(SutConfig::External(e)) => SutChoice::Command {
                command: e.command.clone(),
                timeout_s: e.timeout_s,
                reuse: e.reuse,
            },
            #[cfg(feature = "onnx")]
            Some(SutConfig::Onnx(c)) if c.source != paracosm_engine::sut::PILOTNET => {
                SutChoice::Onnx {
                    model: c.source.clone(),
                    sha256: c.sha256.clone(),
                }
            }
            Some(other) => SutChoice::Builtin { name: other.name() },
        }
    }

    /// The configuration to run, or `None` for the scenario's default.
    ///
    /// # Errors
    /// [`crate::Error::BadInput`] for an unknown built-in name.
    pub fn config(&self) -> Result<Option<SutConfig>, crate::Error> {
        match self {
            SutChoice::Scenario => Ok(None),
            SutChoice::Builtin { name } => SutConfig::builtin(name)
                .map(Some)
                .map_err(|e| crate::Error::BadInput(e.to_string())),
            SutChoice::Command {
                command,
                timeout_s,
                reuse,
            } => Ok(Some(SutConfig::External(ExternalConfig::new(
                command.clone(),
                *timeout_s,
                *reuse,
            )))),
            SutChoice::Onnx { model, sha256 } => {
                let config = SutConfig::onnx(Path::new(model))
                    .map_err(|e| crate::Error::BadInput(e.to_string()))?;
                match config.model_sha256() {
                    Some(now) if now != sha256 => Err(crate::Error::BadInput(format!(
                        "the model `{model}` changed since the campaign ran (SHA-256 {now}, \
                         recorded {sha256})"
                    ))),
                    _ => Ok(Some(config)),
                }
            }
        }
    }
}

/// Shard `index` of `count` (`--shard I/N`, `I` in `0..N`): the tests with ids in
/// [`Shard::range`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which shard, `0..count`.
    pub index: u64,
    /// How many shards, `>= 1`.
    pub count: u64,
}

/// A `--shard` value that is not `I/N` with `0 <= I < N`: the value as given.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not a shard I/N with 0 <= I < N (e.g. 0/4)")]
pub struct NotAShard(pub String);

impl Shard {
    /// Parses `I/N`.
    ///
    /// # Errors
    /// [`NotAShard`] when it is not two whole numbers with `N >= 1` and `I < N`.
    pub fn parse(s: &str) -> Result<Shard, NotAShard> {
        let bad = || NotAShard(s.to_owned());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<u64>().map_err(|_| bad())?,
            n.trim().parse::<u64>().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// The ids of this shard of a campaign of `budget` tests: the contiguous block
    /// `[index · budget / count, (index + 1) · budget / count)`, so the shards of a campaign
    /// cover `0..budget` exactly once, in order, and differ in size by at most one.
    pub fn range(&self, budget: u64) -> std::ops::Range<u64> {
        let at = |k: u64| (u128::from(k) * u128::from(budget) / u128::from(self.count)) as u64;
        at(self.index)..at(self.index + 1)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// What decides a campaign's tests besides its scenario: the settings [`CampaignFile::new`]
/// records (field by field, not flattened: serde's flattening reads numbers wrongly under
/// serde_json's `arbitrary_precision`, see `tests/read_back.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The system under test.
    pub sut: SutChoice,
    /// Strategy name (`halton`, `random`, ...; see `Strategy::LIST`).
    pub strategy: String,
    /// Campaign seed.
    pub seed: u64,
    /// Number of tests of the whole campaign, `>= 1`.
    pub budget: u64,
    /// Strength of the covering-suite strategies.
    pub strength: usize,
    /// The shard this folder runs, `None` for the whole campaign.
    pub shard: Option<Shard>,
    /// The points file of strategy `points` (`--points`), `None` for the others.
    pub points: Option<PointsFile>,
}

/// The file a `points` campaign takes its tests from: where it was and what it held. Its
/// hash enters the fingerprint, so `--resume` and `merge` refuse a changed file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PointsFile {
    /// The file's absolute path when the campaign started.
    pub path: String,
    /// SHA-256 (hex) of its bytes.
    pub sha256: String,
}

impl PointsFile {
    /// `path`'s absolute path and the hash of `bytes`, its contents.
    pub fn of(path: &Path, bytes: &[u8]) -> PointsFile {
        PointsFile {
            path: std::fs::canonicalize(path)
                .unwrap_or_else(|_| path.to_path_buf())
                .display()
                .to_string(),
            sha256: sha256_hex(bytes),
        }
    }
}

/// The contents of `campaign.json`: everything needed to rebuild any test of the campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignFile {
    /// `paracosm <version>`.
    pub tool: String,
    /// SHA-256 (hex) of the settings that decide every result: the scenario's program text
    /// and name, parameter space, system under test, strategy, seed, budget and strength.
    /// Shards of one campaign share it.
    pub fingerprint: String,
    /// The scenario: a built-in name or the absolute path of a `.star` file (a string), or an
    /// OpenSCENARIO file's absolute path with its options (an object, [`ScenarioRef`]).
    pub scenario: ScenarioRef,
    /// [`Settings::sut`].
    pub sut: SutChoice,
    /// [`Settings::strategy`].
    pub strategy: String,
    /// [`Settings::seed`].
    pub seed: u64,
    /// [`Settings::budget`].
    pub budget: u64,
    /// [`Settings::strength`].
    pub strength: usize,
    /// [`Settings::shard`] (`null` in the file for a whole campaign).
    pub shard: Option<Shard>,
    /// The scenario's open parameters.
    pub space: Vec<Param>,
    /// [`Settings::points`] (left out of the file for the other strategies).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<PointsFile>,
    /// SHA-256 (hex) of the scenario program's text, also folded into the fingerprint: kept
    /// apart so that `--resume` can tell a changed program from a hand-edited campaign.json.
    /// Absent in files written before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario_sha256: Option<String>,
    /// A short hash (8 hex digits of SHA-256) of each setting as written, by field name
    /// ([`CampaignFile::field_checks`]), so that `--resume` names the field of a hand-edited
    /// campaign.json. Absent in files written before it existed.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub checks: BTreeMap<String, String>,
    /// The files the scenario read (its OpenDRIVE maps; an OpenSCENARIO scenario's files)
    /// with their SHA-256, also folded into the fingerprint: kept apart so that `--resume`
    /// can name a changed file. Left out of the file when the program reads none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub input_files: Vec<paracosm_scenarios::InputFile>,
    /// Whether the campaign stops at its first failure (`--stop-at-first-failure`), kept so
    /// that `--resume` stops where the uninterrupted run would have. Left out of the file
    /// when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stop_at_first_failure: bool,
}

impl CampaignFile {
    /// The settings it records.
    pub fn settings(&self) -> Settings {
        Settings {
            sut: self.sut.clone(),
            strategy: self.strategy.clone(),
            seed: self.seed,
            budget: self.budget,
            strength: self.strength,
            shard: self.shard,
            points: self.points.clone(),
        }
    }
}

/// What decides a campaign's results, hashed into its fingerprint.
#[derive(Serialize)]
struct Fingerprinted<'a> {
    scenario_name: &'a str,
    scenario_source_sha256: String,
    space: &'a [Param],
    sut: &'a SutChoice,
    strategy: &'a str,
    seed: u64,
    budget: u64,
    strength: usize,
    /// Only for `points` campaigns, so the fingerprints of the others stay as they were.
    #[serde(skip_serializing_if = "Option::is_none")]
    points_sha256: Option<&'a str>,
    /// Only when the scenario's own system under test is an ONNX model.
    #[serde(skip_serializing_if = "Option::is_none")]
    scenario_model_sha256: Option<&'a str>,
    /// The files the scenario read and their SHA-256; only when it read any,
    /// so the fingerprints of the others stay as they were.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    input_files: &'a [paracosm_scenarios::InputFile],
}

/// The SHA-256 of `bytes`, in lowercase hex.
pub(crate) fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

impl CampaignFile {
    /// The campaign of `scenario` (loaded from `scenario_arg`) with `settings`, and its
    /// fingerprint.
    pub fn new(
        scenario_arg: &ScenarioRef,
        scenario: &paracosm_scenarios::Scenario,
        settings: Settings,
    ) -> CampaignFile {
        let Settings {
            sut,
            strategy,
            seed,
            budget,
            strength,
            shard,
            points,
        } = settings;
        let strategy = strategy.as_str();
        let space = scenario.space().params().to_vec();
        let source_sha256 = sha256_hex(scenario.source().as_bytes());
        let fingerprint = {
            let f = Fingerprinted {
                scenario_name: scenario.name(),
                scenario_source_sha256: source_sha256.clone(),
                space: &space,
                sut: &sut,
                strategy,
                seed,
                budget,
                strength,
                points_sha256: points.as_ref().map(|p| p.sha256.as_str()),
                scenario_model_sha256: scenario.sut().model_sha256(),
                input_files: scenario.input_files(),
            };
            sha256_hex(&serde_json::to_vec(&f).expect("settings serialise"))
        };
        CampaignFile {
            tool: format!("paracosm {}", env!("CARGO_PKG_VERSION")),
            fingerprint,
            scenario: scenario_arg.absolute(),
            sut,
            strategy: strategy.to_owned(),
            seed,
            budget,
            strength,
            shard,
            space,
            points,
            scenario_sha256: Some(source_sha256),
            checks: BTreeMap::new(),
            input_files: scenario.input_files().to_vec(),
            stop_at_first_failure: false,
        }
        .checked()
    }

    /// `self` with [`CampaignFile::checks`] computed from its fields.
    pub(crate) fn checked(mut self) -> CampaignFile {
        self.checks = self.field_checks();
        self
    }

    /// The short hash of each setting's JSON as it stands now: `sut`, `strategy`, `seed`,
    /// `budget`, `strength`, `shard`, `space`, `points` and `fingerprint`.
    pub fn field_checks(&self) -> BTreeMap<String, String> {
        fn h<T: Serialize>(v: &T) -> String {
            let json = serde_json::to_vec(v).expect("settings serialise");
            sha256_hex(&json)[..8].to_owned()
        }
        [
            ("sut", h(&self.sut)),
            ("strategy", h(&self.strategy)),
            ("seed", h(&self.seed)),
            ("budget", h(&self.budget)),
            ("strength", h(&self.strength)),
            ("shard", h(&self.shard)),
            ("space", h(&self.space)),
            ("points", h(&self.points)),
            ("fingerprint", h(&self.fingerprint)),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v))
        .collect()
    }

    /// The fields whose [`CampaignFile::checks`] no longer match their values (empty for a
    /// file without checks): the fields edited by hand since the campaign was written.
    pub fn edited_fields(&self) -> Vec<String> {
        if self.checks.is_empty() {
            return Vec::new();
        }
        let now = self.field_checks();
        now.iter()
            .filter(|(k, v)| self.checks.get(*k) != Some(v))
            .map(|(k, _)| k.clone())
            .collect()
    }

    /// The campaign's tag, written into each of its records (`campaign`): the first 16 hex
    /// digits (64 bits) of [`CampaignFile::fingerprint`]. Shards of one campaign share it.
    pub fn tag(&self) -> String {
        self.fingerprint.chars().take(16).collect()
    }

    /// The ids this folder runs: its shard's, or all.
    pub fn ids(&self) -> std::ops::Range<u64> {
        self.shard.map_or(0..self.budget, |s| s.range(self.budget))
    }

    /// How `other` differs from `self` in what the fingerprint covers and the shard, as
    /// `name: ours vs theirs` items (empty: same campaign and shard).
    pub fn differences(&self, other: &CampaignFile) -> Vec<String> {
        let mut out = Vec::new();
        let mut cmp = |name: &str, a: String, b: String| {
            if a != b {
                out.push(format!("{name}: {a} vs {b}"));
            }
        };
        cmp(
            "scenario",
            self.scenario.to_string(),
            other.scenario.to_string(),
        );
        cmp("strategy", self.strategy.clone(), other.strategy.clone());
        cmp("seed", self.seed.to_string(), other.seed.to_string());
        cmp("budget", self.budget.to_string(), other.budget.to_string());
        cmp(
            "strength",
            self.strength.to_string(),
            other.strength.to_string(),
        );
        cmp(
            "system under test",
            format!("{:?}", self.sut),
            format!("{:?}", other.sut),
        );
        let shard = |s: &Option<Shard>| s.map_or("none".to_owned(), |s| s.to_string());
        cmp("shard", shard(&self.shard), shard(&other.shard));
        // The hash, not the path: shards may read copies of one file on other machines.
        let points = |p: &Option<PointsFile>| {
            p.as_ref()
                .map_or("none".to_owned(), |p| format!("sha256 {}", p.sha256))
        };
        cmp("points file", points(&self.points), points(&other.points));
        if self.space != other.space {
            out.push("parameter space differs".into());
        }
        if out.is_empty() && self.fingerprint != other.fingerprint {
            out.push("the scenario program's text differs".into());
        }
        out
    }

    /// Reads `campaign.json` from `dir`.
    ///
    /// # Errors
    /// [`crate::Error::Input`] naming the file when it is missing or malformed (with line
    /// and column).
    pub fn read(dir: &Path) -> Result<CampaignFile, crate::Error> {
        let path = dir.join(CAMPAIGN_FILE);
        paracosm_engine::files::regular_file(&path).map_err(|e| crate::Error::input(&path, e))?;
        let text = std::fs::read_to_string(&path).map_err(|e| crate::Error::input(&path, e))?;
        serde_json::from_str(&text).map_err(|e| {
            let message = format!(
                "{}: not a campaign file: {e}",
                crate::error::located(&path, e.line(), e.column())
            );
            crate::Error::malformed(&path, message)
        })
    }

    /// Writes `campaign.json` into `dir` (through a temporary file and a rename).
    ///
    /// # Errors
    /// [`crate::Error::Write`] with the file system's reason.
    pub fn write(&self, dir: &Path) -> Result<(), crate::Error> {
        let text = serde_json::to_string_pretty(self).expect("serialises") + "\n";
        crate::atomic::write(&dir.join(CAMPAIGN_FILE), text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_the_budget_once_in_order() {
        for (budget, count) in [(10u64, 3u64), (7, 7), (5, 8), (1_000_003, 16)] {
            let mut next = 0;
            for index in 0..count {
                let r = Shard { index, count }.range(budget);
                assert_eq!(r.start, next);
                assert!(r.end - r.start <= budget / count + 1);
                next = r.end;
            }
            assert_eq!(next, budget);
        }
        assert_eq!(Shard::parse("2/4"), Ok(Shard { index: 2, count: 4 }));
        for bad in ["4/4", "1/0", "x/2", "1", "-1/2", ""] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(
            Shard::parse("4/4").unwrap_err().to_string(),
            "`4/4` is not a shard I/N with 0 <= I < N (e.g. 0/4)"
        );
    }

    #[test]
    fn the_fingerprint_covers_the_settings_and_the_program_text() {
        let s = paracosm_scenarios::builtin("pedestrian-crossing").unwrap();
        let settings = |seed, shard| Settings {
            points: None,
            sut: SutChoice::Scenario,
            strategy: "halton".into(),
            seed,
            budget: 100,
            strength: 2,
            shard,
        };
        let make = |seed, shard| {
            CampaignFile::new(
                &ScenarioRef::named("pedestrian-crossing"),
                &s,
                settings(seed, shard),
            )
        };
        let a = make(0, None);
        assert_eq!(a.fingerprint, make(0, None).fingerprint);
        assert_ne!(a.fingerprint, make(1, None).fingerprint);
        let sharded = make(0, Some(Shard { index: 1, count: 2 }));
        assert_eq!(a.fingerprint, sharded.fingerprint, "shards share it");
        assert_eq!(a.differences(&make(1, None)), ["seed: 0 vs 1"]);
        // The same program with one more comment line.
        let edited = paracosm_scenarios::lang::load_source(
            "pedestrian_crossing.star",
            &format!("{}# edited\n", s.source()),
            "pedestrian-crossing",
        )
        .unwrap();
        let b = CampaignFile::new(
            &ScenarioRef::named("pedestrian-crossing"),
            &edited,
            settings(0, None),
        );
        assert_eq!(a.differences(&b), ["the scenario program's text differs"]);
    }
}
