//! `paracosm-fuzz xosc`: an OpenSCENARIO logical scenario as paracosm reads it (issue "The
//! industry's logical scenarios as campaigns"). Given a parameter value distribution file
//! (or a scenario file), it reads the scenario it names with `paracosm-openscenario`, turns
//! each varied parameter into a parameter of paracosm's space, and lists the scenario's
//! entities, `Init` and storyboard, and everything read but not honoured as written.

mod describe;
mod space;

use std::path::{Path, PathBuf};

use paracosm_generators::Param;
use paracosm_openscenario::distribution::{read_variation, VariationFile};
use paracosm_openscenario::model::Scenario;
use paracosm_openscenario::{read_scenario_in, FileSet, XoscError};

use crate::scenario_ref::{ScenarioRef, XoscRef};

use crate::Error;

pub use space::{open_param, value_sets_param, varied_param};

/// A logical scenario read for listing ([`inspect`]).
#[derive(Debug, Clone)]
pub struct Inspection {
    /// The file given (a variation file or a scenario).
    pub file: PathBuf,
    /// The variation file, when one was given.
    pub variation: Option<VariationFile>,
    /// The scenario, read with its parameters' declared values.
    pub scenario: Scenario,
    /// paracosm's space: one parameter per varied parameter, then one per `--open`.
    pub space: Vec<Param>,
    /// How many runs the variation file's own deterministic grid has (the product of its
    /// parameters' level counts), when it is deterministic.
    pub grid_runs: Option<u64>,
    /// What paracosm does not yet honour of the distributions (one line each).
    pub limits: Vec<String>,
}

/// Reads `path` (a `ParameterValueDistribution` file, or a scenario) and opens the declared
/// parameters `opens` names (`Name=lo..hi` or `Name=a,b,c`). With `continuous`, a
/// `DistributionRange` becomes an interval over its range instead of its levels.
///
/// # Errors
/// [`Error::Input`] naming the file, line and column: a file that is not OpenSCENARIO, a
/// variation whose scenario does not read, an `--open` of a parameter that is not declared,
/// is varied already, or whose range breaks its constraint groups.
pub fn inspect(path: &Path, opens: &[String], continuous: bool) -> Result<Inspection, Error> {
    inspect_in(&FileSet::new(), path, opens, continuous)
}

/// [`inspect`], reading every file through `files` (a campaign keeps them for its tests).
///
/// # Errors
/// As [`inspect`].
pub fn inspect_in(
    files: &FileSet,
    path: &Path,
    opens: &[String],
    continuous: bool,
) -> Result<Inspection, Error> {
    let input = |e: XoscError| Error::Input {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let text = files.text(path).map_err(input)?;
    let doc = text.parse().map_err(input)?;
    let is_variation = paracosm_openscenario::distribution::is_variation(&doc);
    drop(doc);
    let (variation, scenario_path) = if is_variation {
        let v = read_variation(&text).map_err(input)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let p: PathBuf = dir
            .join(&v.scenario_file)
            .components()
            .filter(|c| !matches!(c, std::path::Component::CurDir))
            .collect();
        if !p.is_file() {
            return Err(Error::Input {
                path: path.to_path_buf(),
                message: format!(
                    "{}: the scenario file {} is not there",
                    v.scenario_pos,
                    p.display()
                ),
            });
        }
        (Some(v), p)
    } else {
        (None, path.to_path_buf())
    };
    let scenario = read_scenario_in(files, &scenario_path, &[]).map_err(input)?;
    let mut space = Vec::new();
    let mut limits = Vec::new();
    let mut grid_runs = Some(1u64);
    if let Some(v) = &variation {
        if !matches!(
            v.kind,
            paracosm_openscenario::distribution::Kind::Deterministic
        ) {
            grid_runs = None;
        }
        for p in &v.params {
            let declared = scenario.params.iter().any(|(d, _)| d.name == p.name);
            if !declared {
                return Err(Error::Input {
                    path: path.to_path_buf(),
                    message: format!(
                        "{}: parameter {:?} is varied but {} does not declare it",
                        p.pos,
                        p.name,
                        scenario_path.display()
                    ),
                });
            }
            let (param, levels, limit) = varied_param(p, continuous);
            grid_runs = grid_runs.and_then(|g| levels.and_then(|n| g.checked_mul(n)));
            limits.extend(limit);
            space.push(param);
        }
        for (k, sets) in v.multi.iter().enumerate() {
            let (param, runs) = value_sets_param(path, k, sets, &scenario)?;
            grid_runs = grid_runs.and_then(|g| g.checked_mul(runs));
            space.push(param);
        }
    } else {
        grid_runs = None;
    }
    for o in opens {
        let param = open_param(o, &scenario, &space)?;
        space.push(param);
    }
    Ok(Inspection {
        file: path.to_path_buf(),
        variation,
        scenario,
        space,
        grid_runs,
        limits,
    })
}

/// [`inspect`], and the scenario's OpenDRIVE map loaded as a campaign over it would load it
/// (`paracosm-fuzz xosc`: a file whose campaign would refuse its map is refused when listed).
///
/// # Errors
/// As [`inspect`]; [`Error::Scenario`] when the map does not load (naming the `LogicFile`'s
/// line and column).
pub fn inspect_with_map(
    path: &Path,
    opens: &[String],
    continuous: bool,
) -> Result<Inspection, Error> {
    let found = inspect(path, opens, continuous)?;
    paracosm_scenarios::xosc::load_map(&found.scenario)?;
    Ok(found)
}

/// The scenario a campaign over the OpenSCENARIO file `x` runs: its space is the variation
/// file's varied parameters then the `--open`ed ones; the files are read once, here, and each
/// test reads the scenario's text with its values (a value set expands to its parameters).
///
/// # Errors
/// [`Error::Input`] or [`Error::BadInput`] as [`inspect`]; a scenario that does not build
/// (`paracosm_scenarios::xosc::scenario`).
pub fn campaign_scenario(x: &XoscRef) -> Result<paracosm_scenarios::Scenario, Error> {
    let path = x.xosc.as_str();
    let (opens, continuous) = (&x.open, x.continuous);
    let files = std::sync::Arc::new(FileSet::new());
    let found = inspect_in(&files, Path::new(path), opens, continuous)?;
    let space = paracosm_generators::ParamSpace::new(found.space.clone())
        .map_err(|e| Error::BadInput(format!("{path}: {e}")))?;
    let sets: Vec<String> = (0..found.variation.as_ref().map_or(0, |v| v.multi.len()))
        .map(|k| format!("value_set_{k}"))
        .collect();
    let overrides: paracosm_scenarios::xosc::Overrides = std::sync::Arc::new(move |a| {
        let mut out = Vec::new();
        for (name, value) in a.iter() {
            let text = match value {
                paracosm_generators::Value::Int(i) => i.to_string(),
                paracosm_generators::Value::Real(x) => format!("{x}"),
                paracosm_generators::Value::Bool(b) => b.to_string(),
                paracosm_generators::Value::Text(t) => t.clone(),
            };
            if sets.iter().any(|s| s == name) {
                for pair in text.split(", ") {
                    let (n, v) = pair.split_once('=').ok_or_else(|| {
                        paracosm_scenarios::xosc::OverrideError(format!(
                            "{name}: the value set {text:?} is not Name=value"
                        ))
                    })?;
                    out.push((n.to_owned(), v.to_owned()));
                }
            } else {
                out.push((name.to_owned(), text));
            }
        }
        Ok(out)
    });
    let template = PathBuf::from(&found.scenario.file);
    let mut scenario = paracosm_scenarios::xosc::scenario(paracosm_scenarios::xosc::Source {
        template,
        files,
        // The file's name and options, not its folder: the fingerprint of a campaign is the
        // same from any folder and on any machine (shards on other mount points merge).
        name: ScenarioRef::OpenScenario(XoscRef {
            xosc: file_name(path),
            ..x.clone()
        })
        .to_string(),
        space,
        overrides,
        scripted_ego: x.scripted_ego,
        ego: x.ego.clone(),
        horizon_s: x.horizon_s,
    })?;
    let base = Path::new(path).parent().unwrap_or(Path::new(""));
    for f in &mut scenario.input_files {
        f.path = relative_to(base, &f.path);
    }
    scenario
        .warnings
        .extend(found.limits.iter().map(|l| paracosm_scenarios::Warning {
            at: path.to_owned(),
            message: l.clone(),
        }));
    Ok(scenario)
}

/// The last component of `path` (the path itself when it has none).
fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or_else(|| path.to_owned(), |f| f.to_string_lossy().into_owned())
}

/// `path` relative to the folder `base` when it lies inside it (both resolved by the file
/// system), else `path` as it is: a campaign's input files are named the same from any
/// folder, so its fingerprint is too.
pub(crate) fn relative_to(base: &Path, path: &str) -> String {
    let canon = |p: &Path| {
        std::fs::canonicalize(if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        })
    };
    match (canon(base), canon(Path::new(path))) {
        (Ok(b), Ok(p)) => p
            .strip_prefix(&b)
            .map_or_else(|_| path.to_owned(), |r| r.display().to_string()),
        _ => path.to_owned(),
    }
}
