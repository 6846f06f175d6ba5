//! Reading a scenario file (`.xosc` with a `Storyboard`) into [`crate::model::Scenario`].

mod action;
mod catalog;
mod condition;
mod entities;
mod position;
mod storyboard;

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
    pub(crate) notes: std::rc::Rc<std::cell::RefCell<Vec<Note>>>,
    pub(crate) dir: PathBuf,
}

impl Reader<'_> {
    /// The entity named by `node`'s attribute `attr`.
    pub(crate) fn entity(&self, node: Node<'_, '_>, attr: &str) -> Result<usize, XoscError> {
        let name = self.scope.string(self.text, node, attr)?;
        self.names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| XoscError::Invalid {
                pos: self.text.attr_pos(node, attr),
                reason: format!(
                    "no entity is named {name:?}; the scenario's entities are {}",
                    self.names.join(", ")
                ),
            })
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
            notes: self.notes.clone(),
            dir: self.dir.clone(),
        })
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
        ],
    )?;
    let version = read_version(text, root)?;
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
        notes: Default::default(),
        dir: dir.to_path_buf(),
    };
    let catalogs = Catalogs::read(&r, child(root, "CatalogLocations"))?;
    let road_network = entities::road_network(&r, child(root, "RoadNetwork"))?;
    let entities = entities::read(&mut r, &catalogs, child(root, "Entities"))?;
    let (init, stories, stop) = storyboard::read(&r, storyboard)?;
    Ok(Scenario {
        file: text.file.clone(),
        version,
        params,
        scope: r.scope.clone(),
        road_network,
        entities,
        init,
        stories,
        stop,
        notes: r.notes.take(),
    })
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
