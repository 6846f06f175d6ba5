//! An OpenSCENARIO logical scenario as a campaign reads it: the typed reference a campaign
//! keeps ([`XoscRef`]: the file and the command line's options), the reading that
//! `paracosm-fuzz xosc` lists ([`inspect`]: given a parameter value distribution file or a
//! scenario file, the scenario it names read with `paracosm-openscenario`, each varied or
//! `--open`ed parameter a parameter of paracosm's space), and the campaign's
//! [`crate::Scenario`] over it ([`campaign_scenario`], its files read once into a [`FileSet`]).

use std::path::{Path, PathBuf};

use paracosm_generators::Param;
use paracosm_openscenario::distribution::{read_variation, VariationFile};
use paracosm_openscenario::model::Scenario;
use paracosm_openscenario::{read_scenario_in, FileSet, Value, XoscError};

use crate::ScenarioError;

use super::space::{open_param, value_sets_param, varied_param};

/// An OpenSCENARIO scenario or variation file and the options of `paracosm-fuzz FILE.xosc`.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct XoscRef {
    /// The file (a variation file, or a scenario alone), as given or made absolute.
    pub xosc: String,
    /// `--open`: declared parameters opened, `Name=lo..hi` or `Name=a,b,c`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub open: Vec<String>,
    /// `--continuous`: a `DistributionRange` becomes an interval over its range.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub continuous: bool,
    /// `--scripted-ego`: the storyboard moves the ego as every other entity (no system under
    /// test), to replay an exported test.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub scripted_ego: bool,
    /// `--ego NAME`: the vehicle the system under test drives, for a file that does not say
    /// plainly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego: Option<String>,
    /// `--horizon`: the longest test, s (finite, `> 0`); a storyboard without a stop trigger
    /// needs it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon_s: Option<f64>,
    /// `--ego-speed`: the system under test's set speed, m/s (finite, `> 0`), for a file that
    /// asks its ego no speed (CARLA's leave it to the agent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego_speed_mps: Option<f64>,
    /// `--maps DIR`: a folder where a map the file names but that is not where it says (a
    /// CARLA town, `Town01`) is found ([`paracosm_openscenario::FileSet::with_maps`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maps: Option<String>,
    /// `--carla`: read the file as CARLA's scenario_runner reads its own (its frame, its
    /// conditions, its speed actions), also when its `FileHeader` does not say `CARLA:`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub carla: bool,
}

impl std::fmt::Display for XoscRef {
    /// The file with its options as `paracosm-fuzz` takes them (`file.xosc --open A=1..2
    /// --continuous`): a campaign's name for it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.xosc)?;
        for o in &self.open {
            write!(f, " --open {o}")?;
        }
        if self.continuous {
            f.write_str(" --continuous")?;
        }
        if self.scripted_ego {
            f.write_str(" --scripted-ego")?;
        }
        if let Some(e) = &self.ego {
            write!(f, " --ego {e}")?;
        }
        if let Some(h) = self.horizon_s {
            write!(f, " --horizon {h}")?;
        }
        if let Some(v) = self.ego_speed_mps {
            write!(f, " --ego-speed {v}")?;
        }
        if let Some(d) = &self.maps {
            write!(f, " --maps {d}")?;
        }
        if self.carla {
            f.write_str(" --carla")?;
        }
        Ok(())
    }
}

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
    /// Where each parameter of the space is set, in its order: the variation file's
    /// distribution (`file:line:col`), or `--open Name=...`.
    pub sites: Vec<String>,
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
/// [`ScenarioError::Input`] naming the file, line and column: a file that is not OpenSCENARIO, a
/// variation whose scenario does not read, an `--open` of a parameter that is not declared,
/// is varied already, or whose range breaks its constraint groups.
pub fn inspect(
    path: &Path,
    opens: &[String],
    continuous: bool,
) -> Result<Inspection, ScenarioError> {
    inspect_in(&FileSet::new(), path, opens, continuous)
}

/// The scenario file that the variation file `path` (read as `v`) names, relative to its
/// folder with `.` components removed.
///
/// # Errors
/// [`ScenarioError::Input`] at the `ScenarioFile` element when it is absent or not a regular
/// file (naming what it is: a FIFO would block the read, a device never end it).
fn scenario_of(path: &Path, v: &VariationFile) -> Result<PathBuf, ScenarioError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let p: PathBuf = dir
        .join(&v.scenario_file)
        .components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect();
    let what = match std::fs::metadata(&p) {
        Err(_) => Some("is not there".to_owned()),
        Ok(m) => paracosm_files::kind_of(&m.file_type())
            .map(|kind| format!("is {kind}, not a regular file")),
    };
    if let Some(what) = what {
        return Err(ScenarioError::Input {
            path: path.to_path_buf(),
            message: format!(
                "{}: the scenario file {} {what}",
                v.scenario_pos,
                p.display()
            ),
        });
    }
    Ok(p)
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
) -> Result<Inspection, ScenarioError> {
    let input = |e: XoscError| ScenarioError::Input {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let text = files.text(path).map_err(input)?;
    let doc = text.parse().map_err(input)?;
    let is_variation = paracosm_openscenario::distribution::is_variation(doc);
    let (variation, scenario_path) = if is_variation {
        let v = read_variation(&text).map_err(input)?;
        let p = scenario_of(path, &v)?;
        (Some(v), p)
    } else {
        (None, path.to_path_buf())
    };
    let scenario = read_scenario_in(files, &scenario_path, &[]).map_err(input)?;
    let mut space = Vec::new();
    let mut sites = Vec::new();
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
                return Err(ScenarioError::Input {
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
            sites.push(p.pos.to_string());
        }
        for (k, sets) in v.multi.iter().enumerate() {
            let (param, runs) = value_sets_param(path, k, sets, &scenario)?;
            grid_runs = grid_runs.and_then(|g| g.checked_mul(runs));
            space.push(param);
            sites.push(sets.pos.to_string());
        }
    } else {
        grid_runs = None;
    }
    for o in opens {
        let param = open_param(o, &scenario, &space)?;
        space.push(param);
        sites.push(format!("--open {o}"));
    }
    Ok(Inspection {
        file: path.to_path_buf(),
        variation,
        scenario,
        space,
        sites,
        grid_runs,
        limits,
    })
}

/// [`inspect`], and the scenario's OpenDRIVE map loaded as a campaign over it would load it
/// (`paracosm-fuzz xosc`: a file whose campaign would refuse its map is refused when listed).
///
/// # Errors
/// As [`inspect`]; [`ScenarioError::Load`] when the map does not load (naming the `LogicFile`'s
/// line and column).
pub fn inspect_with_map(
    path: &Path,
    opens: &[String],
    continuous: bool,
    (maps, carla): (Option<&Path>, bool),
) -> Result<Inspection, ScenarioError> {
    let files = FileSet::with_maps(maps.map(Path::to_path_buf)).as_carla(carla);
    let found = inspect_in(&files, path, opens, continuous)?;
    super::load_map(&found.scenario)?;
    Ok(found)
}

/// The scenario a campaign over the OpenSCENARIO file `x` runs: its space is the variation
/// file's varied parameters then the `--open`ed ones; the files are read once, here, and each
/// test reads the scenario's text with its values (a value set expands to its parameters).
///
/// # Errors
/// [`ScenarioError::Input`] as [`inspect`]; a scenario that does not build
/// (`paracosm_scenarios::xosc::scenario`).
pub fn campaign_scenario(x: &XoscRef) -> Result<crate::Scenario, ScenarioError> {
    let path = x.xosc.as_str();
    let (opens, continuous) = (&x.open, x.continuous);
    let files = FileSet::with_maps(x.maps.as_ref().map(PathBuf::from)).as_carla(x.carla);
    let files = std::sync::Arc::new(files);
    let found = inspect_in(&files, Path::new(path), opens, continuous)?;
    let space = paracosm_generators::ParamSpace::new(found.space.clone()).map_err(|e| {
        ScenarioError::Input {
            path: PathBuf::from(path),
            message: format!("{path}: {e}"),
        }
    })?;
    // Each value set's parameter, its levels (the sets as written, `Name=value, ...`) and
    // the assignments each level makes, as the variation file parsed them: a test binds the
    // set by its level, never by splitting the level's text (a value may hold `, ` or `=`).
    let sets: Vec<ValueSetLevels> = found
        .variation
        .iter()
        .flat_map(|v| v.multi.iter().enumerate())
        .map(|(k, multi)| {
            let name = format!("value_set_{k}");
            let levels = match space.param(&name).map(|p| &p.domain) {
                Some(paracosm_generators::Domain::Levels(l)) => l.clone(),
                _ => Vec::new(),
            };
            let pairs = multi
                .sets
                .iter()
                .map(|set| {
                    set.iter()
                        .map(|a| (a.name.clone(), Value::Str(a.value.clone())))
                        .collect()
                })
                .collect();
            (name, levels, pairs)
        })
        .collect();
    let overrides: super::Overrides = std::sync::Arc::new(move |a| {
        let mut out = Vec::new();
        for (name, value) in a.iter() {
            if let Some((_, levels, pairs)) = sets.iter().find(|(n, _, _)| n == name) {
                let k = levels.iter().position(|l| l == value).ok_or_else(|| {
                    super::OverrideError(format!("{name}: {value:?} is not one of its value sets"))
                })?;
                out.extend(pairs[k].iter().cloned());
                continue;
            }
            out.push((name.to_owned(), typed(value)));
        }
        Ok(out)
    });
    let template = PathBuf::from(&found.scenario.file);
    let space = constrained_space(space, &files, &template, &overrides, path)?;
    let scenario = super::scenario(super::Source {
        template,
        files,
        // The file's name and options, not its folder: the fingerprint of a campaign is the
        // same from any folder and on any machine (shards on other mount points merge).
        // `--maps` too: its maps are fingerprinted as input files, by their place in it.
        name: XoscRef {
            xosc: file_name(path),
            maps: None,
            ..x.clone()
        }
        .to_string(),
        files_base: Path::new(path).parent().unwrap_or(Path::new("")).to_owned(),
        space,
        param_sites: found.sites.clone(),
        overrides,
        scripted_ego: x.scripted_ego,
        ego: x.ego.clone(),
        horizon_s: x.horizon_s,
        ego_speed_mps: x.ego_speed_mps,
        warnings: found
            .limits
            .iter()
            .map(|l| crate::Warning {
                at: path.to_owned(),
                message: l.clone(),
            })
            .collect(),
    })?;
    Ok(scenario)
}

/// The template's `ConstraintGroup`s as a constraint of the campaign's space: no test runs on
/// a combination they refuse.
#[derive(Debug)]
struct TemplateConstraints {
    constrained: paracosm_openscenario::params::Constrained,
    overrides: OverridesDebug,
}

/// The campaign's overrides, which `Debug` shows by name only.
struct OverridesDebug(super::Overrides);

impl std::fmt::Debug for OverridesDebug {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Overrides")
    }
}

/// The name the template's constraint groups go by in messages and summaries.
pub const TEMPLATE_CONSTRAINTS: &str = "the template's constraint groups";

impl paracosm_generators::Constraint for TemplateConstraints {
    fn name(&self) -> &str {
        TEMPLATE_CONSTRAINTS
    }

    fn violation(
        &self,
        values: &paracosm_generators::Assignment,
    ) -> Result<Option<String>, paracosm_generators::ConstraintError> {
        let overrides =
            (self.overrides.0)(values).map_err(|e| paracosm_generators::ConstraintError(e.0))?;
        Ok(self.constrained.violation(&overrides))
    }
}

/// `space` with the constraint groups of the template at `template` (read through `files`),
/// when it has any, checked to leave some valid point.
///
/// # Errors
/// [`ScenarioError::Input`] when the template does not read, or its constraint groups refuse
/// every combination of the space.
fn constrained_space(
    space: paracosm_generators::ParamSpace,
    files: &FileSet,
    template: &Path,
    overrides: &super::Overrides,
    path: &str,
) -> Result<paracosm_generators::ParamSpace, ScenarioError> {
    let input = |message: String| ScenarioError::Input {
        path: PathBuf::from(path),
        message,
    };
    let constrained = paracosm_openscenario::params::Constrained::read(files, template)
        .map_err(|e| input(e.to_string()))?;
    if !constrained.has_constraints() || space.params().is_empty() {
        return Ok(space);
    }
    let space = space.with_constraints(vec![std::sync::Arc::new(TemplateConstraints {
        constrained,
        overrides: OverridesDebug(overrides.clone()),
    })]);
    space.valid_fraction().map_err(|e| {
        input(format!(
            "{path}: {e}: no test of this logical scenario can run ({} refuse every \
             combination of its parameters)",
            TEMPLATE_CONSTRAINTS
        ))
    })?;
    Ok(space)
}

/// A value set's parameter (`value_set_K`), its levels, and the assignments (name, value as
/// written, coerced to the declared type when the scenario is read) each level makes.
type ValueSetLevels = (
    String,
    Vec<paracosm_generators::Value>,
    Vec<Vec<(String, Value)>>,
);

/// A test's value of a parameter as the OpenSCENARIO value it overrides with: whole and real
/// numbers as numbers, texts as texts (a road file; coerced to the declared type when read).
fn typed(value: &paracosm_generators::Value) -> Value {
    match value {
        paracosm_generators::Value::Int(i) => Value::Num(*i as f64),
        paracosm_generators::Value::Real(x) => Value::Num(*x),
        paracosm_generators::Value::Bool(b) => Value::Bool(*b),
        paracosm_generators::Value::Text(t) => Value::Str(t.clone()),
    }
}

/// The last component of `path` (the path itself when it has none).
fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or_else(|| path.to_owned(), |f| f.to_string_lossy().into_owned())
}
