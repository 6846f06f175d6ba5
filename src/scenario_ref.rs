//! What a campaign tests, as `campaign.json` keeps it: a built-in scenario or a program by
//! name or path, or an OpenSCENARIO file with the options that decide how it is read (the
//! parameters opened, `--continuous`, `--scripted-ego`, `--ego`, `--horizon`). Resume, merge,
//! report, replay and export rebuild the same scenario from it.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::Error;
pub use paracosm_scenarios::xosc::XoscRef;

/// The scenario of a campaign. In `campaign.json`, a program is its name or path (a string),
/// an OpenSCENARIO file an object with its options (`{"xosc": "/abs/file.xosc", "open":
/// ["Name=lo..hi"], ...}`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ScenarioRef {
    /// A built-in scenario's name or a `.star` program's path.
    Program(String),
    /// An OpenSCENARIO file and how the campaign reads it.
    OpenScenario(XoscRef),
}

impl<'de> Deserialize<'de> for ScenarioRef {
    /// A string is a program, or an OpenSCENARIO file read as it is ([`ScenarioRef::named`]);
    /// an object an OpenSCENARIO file with its options (read through
    /// a `serde_json::Value`: serde's untagged enums cannot read the numbers of a workspace
    /// whose `serde_json` keeps them as text).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error as _;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(s) if s.to_ascii_lowercase().contains(".xosc#") => {
                Err(D::Error::custom(format!(
                    "{s}: an OpenSCENARIO campaign written by a paracosm before 2026-11-28 \
                     (its options after `#`); its folder cannot be resumed, reported or merged \
                     by this one: rerun the campaign"
                )))
            }
            serde_json::Value::String(s) => Ok(ScenarioRef::named(&s)),
            v @ serde_json::Value::Object(_) => serde_json::from_value(v)
                .map(ScenarioRef::OpenScenario)
                .map_err(D::Error::custom),
            other => Err(D::Error::custom(format!(
                "a scenario is a name or path (a string) or an OpenSCENARIO file with its \
                 options (an object), not {other}"
            ))),
        }
    }
}

impl ScenarioRef {
    /// The scenario `name` names with no options: an OpenSCENARIO file (its extension `.xosc`,
    /// in any case) read as it is, else a built-in scenario or a program.
    pub fn named(name: &str) -> Self {
        if is_xosc(name) {
            ScenarioRef::OpenScenario(XoscRef {
                xosc: name.to_owned(),
                ..XoscRef::default()
            })
        } else {
            ScenarioRef::Program(name.to_owned())
        }
    }

    /// The same reference with its file's path made absolute (a built-in name, or a path that
    /// does not resolve, is kept as given), so that a campaign folder resumes from any folder.
    pub fn absolute(&self) -> Self {
        let abs = |p: &str| match std::fs::canonicalize(Path::new(p)) {
            Ok(abs) if Path::new(p).is_file() => abs.display().to_string(),
            _ => p.to_owned(),
        };
        let abs_dir = |p: &str| match std::fs::canonicalize(Path::new(p)) {
            Ok(abs) if abs.is_dir() => abs.display().to_string(),
            _ => p.to_owned(),
        };
        match self {
            ScenarioRef::Program(p) => ScenarioRef::Program(abs(p)),
            ScenarioRef::OpenScenario(x) => ScenarioRef::OpenScenario(XoscRef {
                xosc: abs(&x.xosc),
                maps: x.maps.as_deref().map(abs_dir),
                ..x.clone()
            }),
        }
    }

    /// The file or name it points at.
    pub fn path(&self) -> &str {
        match self {
            ScenarioRef::Program(p) => p,
            ScenarioRef::OpenScenario(x) => &x.xosc,
        }
    }

    /// The OpenSCENARIO file and its options, when it is one.
    pub fn xosc(&self) -> Option<&XoscRef> {
        match self {
            ScenarioRef::OpenScenario(x) => Some(x),
            ScenarioRef::Program(_) => None,
        }
    }

    /// Loads the scenario: [`paracosm_scenarios::load`] for a program,
    /// [`paracosm_scenarios::xosc::campaign_scenario`] for an OpenSCENARIO file.
    ///
    /// # Errors
    /// What those return.
    pub fn load(&self) -> Result<paracosm_scenarios::Scenario, Error> {
        match self {
            ScenarioRef::Program(name) => Ok(paracosm_scenarios::load(name)?),
            ScenarioRef::OpenScenario(x) => Ok(paracosm_scenarios::xosc::campaign_scenario(x)?),
        }
    }
}

impl std::fmt::Display for ScenarioRef {
    /// The name a campaign's summary gives it: the program's name or path, or the file with
    /// its options as `paracosm-fuzz` takes them (`file.xosc --open A=1..2 --continuous`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ScenarioRef::Program(p) => f.write_str(p),
            ScenarioRef::OpenScenario(x) => x.fmt(f),
        }
    }
}

/// Whether `name` is an OpenSCENARIO file's path (extension `.xosc`, in any case).
pub fn is_xosc(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".xosc")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_reads_back_as_it_was_written() {
        let program = ScenarioRef::named("pedestrian-crossing");
        let text = serde_json::to_string(&program).unwrap();
        assert_eq!(text, "\"pedestrian-crossing\"");
        assert_eq!(serde_json::from_str::<ScenarioRef>(&text).unwrap(), program);
        let xosc = ScenarioRef::OpenScenario(XoscRef {
            xosc: "/data/a.xosc".into(),
            open: vec!["Speed=1..2".into()],
            continuous: true,
            horizon_s: Some(30.0),
            ..XoscRef::default()
        });
        let text = serde_json::to_string(&xosc).unwrap();
        assert_eq!(
            text,
            r#"{"xosc":"/data/a.xosc","open":["Speed=1..2"],"continuous":true,"horizon_s":30.0}"#
        );
        assert_eq!(serde_json::from_str::<ScenarioRef>(&text).unwrap(), xosc);
        assert_eq!(
            xosc.to_string(),
            "/data/a.xosc --open Speed=1..2 --continuous --horizon 30"
        );
        assert!(matches!(
            ScenarioRef::named("b.XOSC"),
            ScenarioRef::OpenScenario(_)
        ));
        let plain: ScenarioRef = serde_json::from_str(r#""/data/b.xosc""#).unwrap();
        assert!(matches!(plain, ScenarioRef::OpenScenario(_)), "{plain:?}");
        let old = serde_json::from_str::<ScenarioRef>(r#""a.xosc#open=A=1..2""#).unwrap_err();
        assert!(old.to_string().contains("rerun the campaign"), "{old}");
        let unknown = serde_json::from_str::<ScenarioRef>(r#"{"xosc":"a.xosc","opne":[]}"#);
        assert!(
            unknown.is_err(),
            "a misspelt option is refused: {unknown:?}"
        );
    }
}
