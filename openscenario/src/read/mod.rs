//! Reading a scenario file (`.xosc` with a `Storyboard`) into [`crate::model::Scenario`].

mod action;
mod catalog;
mod condition;
mod controller;
mod entities;
mod global;
mod position;
mod storyboard;
mod synchronize;

use std::path::{Path, PathBuf};

use roxmltree::Node;

use crate::error::XoscError;
use crate::files::FileSet;
use crate::model::{Note, Scenario};
use crate::params::{read_declarations, Scope};
use crate::text::Text;
use crate::xml::{child, need};
use crate::Value;

pub use catalog::Catalogs;

/// The state of reading one scenario file: its text, its parameters, its entities' names.
pub(crate) struct Reader<'t> {
    pub(crate) text: &'t Text,
    /// The scenario's files: its catalogs are read through it.
    pub(crate) files: &'t FileSet,
    pub(crate) scope: Scope,
    /// The entities' names, shared by the readers of nested scopes.
    pub(crate) names: std::rc::Rc<Vec<String>>,
    /// Each `EntitySelection`'s name and members (indices into the entities, in the order
    /// of the entities, each once).
    pub(crate) selections: std::rc::Rc<Vec<(String, Vec<usize>)>>,
    pub(crate) notes: std::rc::Rc<std::cell::RefCell<Vec<Note>>>,
    /// Where an orientation tilts an entity ([`Scenario::tilts`]).
    pub(crate) tilts: std::rc::Rc<std::cell::RefCell<Vec<Note>>>,
    pub(crate) dir: PathBuf,
    /// The scenario's catalog folders (read once its `CatalogLocations` are), shared by the
    /// readers of nested scopes and of catalog entries.
    pub(crate) catalogs: std::rc::Rc<Catalogs>,
    /// The scenario's own parameters (its root `ParameterDeclarations`) and their types: the
    /// ones a `ParameterCondition` reads and a `ParameterAction` sets while a test runs.
    pub(crate) globals: std::rc::Rc<Vec<(String, crate::params::ParamType)>>,
    /// The scenario's variables (`VariableDeclarations`) and their types.
    pub(crate) variables: std::rc::Rc<Vec<(String, crate::params::ParamType)>>,
    /// Whether the scenario is written for CARLA ([`crate::model::Scenario::carla`]): its
    /// positions are in CARLA's left-handed frame ([`Reader::flip`]).
    pub(crate) carla: bool,
    /// The scenario's `FileHeader` revision, `(major, minor)`.
    pub(crate) version: (u32, u32),
}

impl<'t> Reader<'t> {
    /// The entity named by `node`'s attribute `attr`.
    pub(crate) fn entity(&self, node: Node<'_, '_>, attr: &str) -> Result<usize, XoscError> {
        let name = self.scope.string(self.text, node, attr)?;
        if let Some(k) = self.names.iter().position(|n| *n == name) {
            return Ok(k);
        }
        if self.selections.iter().any(|(n, _)| *n == name) {
            return Err(XoscError::Unsupported {
                pos: self.text.attr_pos(node, attr),
                reason: format!(
                    "{name:?} is an entity selection: paracosm reads a selection among a \
                     maneuver group's actors and a condition's triggering entities, not here, \
                     where one entity is meant"
                ),
            });
        }
        Err(XoscError::Invalid {
            pos: self.text.attr_pos(node, attr),
            reason: format!(
                "no entity is named {name:?}; the scenario's entities are {}",
                self.names.join(", ")
            ),
        })
    }

    /// The entities named by `node`'s attribute `attr`: the entity of that name, or the
    /// members of the `EntitySelection` of that name (actors and triggering entities).
    ///
    /// # Errors
    /// Invalid when neither an entity nor a selection has the name.
    pub(crate) fn entities(&self, node: Node<'_, '_>, attr: &str) -> Result<Vec<usize>, XoscError> {
        let name = self.scope.string(self.text, node, attr)?;
        match self.selections.iter().find(|(n, _)| *n == name) {
            Some((_, members)) => Ok(members.clone()),
            None => Ok(vec![self.entity(node, attr)?]),
        }
    }

    /// A reader of the same file whose scope is this one's with `node`'s own
    /// `ParameterDeclarations` (OpenSCENARIO 1.0 lets a story or maneuver declare
    /// parameters), sharing the notes.
    pub(crate) fn scoped(&self, node: Node<'_, '_>) -> Result<Reader<'_>, XoscError> {
        let decls =
            crate::params::read_declarations(self.text, child(node, "ParameterDeclarations"))?;
        let scope = if decls.is_empty() {
            self.scope.clone()
        } else {
            self.scope.child(self.text, &decls)?
        };
        Ok(Reader {
            text: self.text,
            files: self.files,
            scope,
            names: std::rc::Rc::clone(&self.names),
            selections: std::rc::Rc::clone(&self.selections),
            notes: self.notes.clone(),
            tilts: self.tilts.clone(),
            dir: self.dir.clone(),
            catalogs: std::rc::Rc::clone(&self.catalogs),
            globals: std::rc::Rc::clone(&self.globals),
            variables: std::rc::Rc::clone(&self.variables),
            carla: self.carla,
            version: self.version,
        })
    }

    /// A reader of a catalog entry: `text` is the catalog file's, `scope` the entry's own
    /// (its declarations with the reference's assignments), the entities, notes and catalogs
    /// this one's; relative paths are taken from the catalog file's folder.
    pub(crate) fn in_catalog<'c>(&self, text: &'c Text, scope: &Scope) -> Reader<'c>
    where
        't: 'c,
    {
        Reader {
            text,
            files: self.files,
            scope: scope.clone(),
            names: std::rc::Rc::clone(&self.names),
            selections: std::rc::Rc::clone(&self.selections),
            notes: self.notes.clone(),
            tilts: self.tilts.clone(),
            dir: Path::new(&text.file)
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default(),
            catalogs: std::rc::Rc::clone(&self.catalogs),
            globals: std::rc::Rc::clone(&self.globals),
            variables: std::rc::Rc::clone(&self.variables),
            carla: self.carla,
            version: self.version,
        }
    }

    /// `node`'s attribute `attr` read as the name of a parameter or variable (a
    /// `parameterRef`, a `variableRef`): a name, not a reference to its value, so the `$`
    /// that esmini's files put before it is dropped.
    ///
    /// # Errors
    /// Invalid when the attribute is missing.
    pub(crate) fn name_ref(&self, node: Node<'_, '_>, attr: &str) -> Result<String, XoscError> {
        Ok(crate::params::required(self.text, node, attr)?
            .trim()
            .trim_start_matches('$')
            .to_string())
    }

    /// A lateral value (a world `y`, a heading, an offset to the left) as the standard's
    /// right-handed frame has it: `v`, or `-v` in a file written in CARLA's left-handed frame
    /// (scenario_runner reverses these signs unless the file is CARLA's, and its lane offsets
    /// count to the right); 0 stays +0.
    pub(crate) fn flip(&self, v: f64) -> f64 {
        if self.carla {
            0.0 - v
        } else {
            v
        }
    }

    /// Notes that `node` is read but not honoured as written.
    pub(crate) fn note(&self, node: Node<'_, '_>, text: impl Into<String>) {
        self.notes.borrow_mut().push(Note {
            pos: self.text.pos(node),
            text: text.into(),
        });
    }
}

/// Reads the scenario file at `path` with `overrides` (parameter name → typed value, from a
/// variation file, a campaign's test or a program's `Import`) for its declared parameters
/// ([`Scope::with_values`]: coerced to the declared type, never evaluated as text).
///
/// # Errors
/// [`XoscError`] naming the file, line and column: the file cannot be read, is not
/// well-formed, is not a scenario, declares or uses parameters wrongly, references missing
/// catalogs or entities, or holds an element paracosm does not support.
pub fn read_scenario(path: &Path, overrides: &[(String, Value)]) -> Result<Scenario, XoscError> {
    read_scenario_in(&FileSet::new(), path, overrides)
}

/// As [`read_scenario`], reading the file and its catalogs through `files`: each is read from
/// disk the first time and from `files` after, so the tests of a campaign read the texts its
/// load read.
///
/// # Errors
/// As [`read_scenario`].
pub fn read_scenario_in(
    files: &FileSet,
    path: &Path,
    overrides: &[(String, Value)],
) -> Result<Scenario, XoscError> {
    let text = files.text(path)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    read_with(files, &text, &dir, overrides)
}

/// `base` joined with `rel`, without `.` components (paths in messages read as written).
pub(crate) fn join(base: &Path, rel: &str) -> PathBuf {
    base.join(rel)
        .components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect()
}

/// As [`read_scenario`], for a file already read; relative paths in it (the road network,
/// catalogs) are taken from `dir`.
///
/// # Errors
/// As [`read_scenario`].
pub fn read_scenario_text(
    text: &Text,
    dir: &Path,
    overrides: &[(String, Value)],
) -> Result<Scenario, XoscError> {
    read_with(&FileSet::new(), text, dir, overrides)
}

/// [`read_scenario_text`] with the catalogs read through `files`.
fn read_with(
    files: &FileSet,
    text: &Text,
    dir: &Path,
    overrides: &[(String, Value)],
) -> Result<Scenario, XoscError> {
    let doc = text.parse()?;
    let root = text.open_root(doc)?;
    if child(root, "ParameterValueDistribution").is_some() {
        return Err(text.invalid(
            root,
            "this is a parameter value distribution, not a scenario: read it as a variation file",
        ));
    }
    crate::xml::only(
        text,
        root,
        &[
            "FileHeader",
            "ParameterDeclarations",
            "CatalogLocations",
            "RoadNetwork",
            "Entities",
            "Storyboard",
            "VariableDeclarations",
        ],
    )?;
    let version = read_version(text, root)?;
    // scenario_runner's test of a file written in CARLA's frame (its
    // `OpenScenarioConfiguration._set_scenario_name`).
    let carla = files.carla()
        || child(root, "FileHeader")
            .and_then(|h| h.attribute("description"))
            .is_some_and(|d| d.starts_with("CARLA:"));
    let storyboard = need(text, root, "Storyboard")?;
    let decls = read_declarations(text, child(root, "ParameterDeclarations"))?;
    let scope = Scope::with_values(text, &decls, overrides)?;
    let params = decls
        .iter()
        .map(|d| {
            (
                d.clone(),
                scope
                    .get(&d.name)
                    .cloned()
                    .unwrap_or(Value::Str(String::new())),
            )
        })
        .collect();
    let mut r = Reader {
        text,
        files,
        scope,
        names: std::rc::Rc::default(),
        selections: std::rc::Rc::default(),
        notes: Default::default(),
        tilts: Default::default(),
        dir: dir.to_path_buf(),
        catalogs: std::rc::Rc::default(),
        globals: std::rc::Rc::new(decls.iter().map(|d| (d.name.clone(), d.ty)).collect()),
        variables: std::rc::Rc::default(),
        carla,
        version,
    };
    if carla {
        r.note(
            need(text, root, "FileHeader")?,
            "read as CARLA's scenario_runner reads its files (the description starts with \
             CARLA:, or --carla): positions in CARLA's left-handed frame (world y, headings \
             and lateral offsets, t, dt, offset, dy and the offsets of lane offset and lane \
             change actions, with their sign reversed), conditions that latch, a SpeedAction \
             that lasts its dynamics' distance or time, and a scenario that ends with its \
             stories",
        );
    }
    let variables = read_variables(&r, child(root, "VariableDeclarations"))?;
    r.variables = std::rc::Rc::new(variables.iter().map(|(n, t, _)| (n.clone(), *t)).collect());
    r.catalogs = std::rc::Rc::new(Catalogs::read(&r, child(root, "CatalogLocations"))?);
    let road_network = entities::road_network(&r, child(root, "RoadNetwork"))?;
    let catalogs = std::rc::Rc::clone(&r.catalogs);
    let entities = entities::read(&mut r, &catalogs, child(root, "Entities"))?;
    let (init, init_global, stories, stop) = storyboard::read(&r, storyboard)?;
    Ok(Scenario {
        file: text.file.clone(),
        version,
        carla,
        params,
        scope: r.scope.clone(),
        road_network,
        entities,
        init,
        init_global,
        variables,
        stories,
        stop,
        notes: r.notes.take(),
        tilts: r.tilts.take(),
    })
}

/// `VariableDeclarations` (OpenSCENARIO 1.2): each `VariableDeclaration`'s name, type
/// (`variableType`) and initial value, in order.
///
/// # Errors
/// Invalid for a name declared twice, an unknown type, a value not of its type (or not
/// resolved: a variable's value may be `$parameter` or `${expr}`).
fn read_variables(
    r: &Reader<'_>,
    node: Option<Node<'_, '_>>,
) -> Result<Vec<(String, crate::params::ParamType, Value)>, XoscError> {
    let mut out: Vec<(String, crate::params::ParamType, Value)> = Vec::new();
    for v in node.into_iter().flat_map(crate::xml::elements) {
        if v.tag_name().name() != "VariableDeclaration" {
            return Err(r.text.unsupported(
                v,
                format!(
                    "<{}> in <VariableDeclarations>: only <VariableDeclaration> belongs there",
                    v.tag_name().name()
                ),
            ));
        }
        let name = crate::params::required(r.text, v, "name")?.to_string();
        if out.iter().any(|(n, _, _)| *n == name) {
            return Err(r
                .text
                .invalid(v, format!("variable {name} is declared twice")));
        }
        let ty_name = crate::params::required(r.text, v, "variableType")?;
        let ty = crate::params::ParamType::from_xsd(ty_name).ok_or_else(|| XoscError::Invalid {
            pos: r.text.attr_pos(v, "variableType"),
            reason: format!("unknown variableType {ty_name:?}"),
        })?;
        let text = r.scope.string(r.text, v, "value")?;
        let value = ty
            .coerce(Value::Str(text))
            .map_err(|e| XoscError::Invalid {
                pos: r.text.attr_pos(v, "value"),
                reason: format!("variable {name} is of type {}: {}", ty.xsd_name(), e.0),
            })?;
        out.push((name, ty, value));
    }
    Ok(out)
}

/// `FileHeader`'s revision, 1.0 to 1.3.
fn read_version(text: &Text, root: Node<'_, '_>) -> Result<(u32, u32), XoscError> {
    let header = need(text, root, "FileHeader")?;
    let num = |attr: &str| -> Result<u32, XoscError> {
        header
            .attribute(attr)
            .and_then(|v| v.trim().parse().ok())
            .ok_or_else(|| XoscError::Invalid {
                pos: text.attr_pos(header, attr),
                reason: format!("<FileHeader {attr}> must be a whole number"),
            })
    };
    let version = (num("revMajor")?, num("revMinor")?);
    if version.0 != 1 || version.1 > 3 {
        return Err(text.unsupported(
            header,
            format!(
                "OpenSCENARIO {}.{} is not supported; paracosm reads 1.0 to 1.3",
                version.0, version.1
            ),
        ));
    }
    Ok(version)
}
