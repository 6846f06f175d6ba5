//! Catalogs (OpenSCENARIO 1.3 User Guide, "Catalogs"): `CatalogLocations` names a folder per
//! kind; a `CatalogReference` names a catalog (`<Catalog name>` in one of the folder's
//! `.xosc` files) and an entry in it, with `ParameterAssignments` for the entry's own
//! `ParameterDeclarations`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use roxmltree::Node;

use super::Reader;
use crate::error::XoscError;
use crate::params::{read_declarations, Scope};
use crate::text::Text;
use crate::xml::{child, elements};

/// The most `.xosc` files a catalog folder may hold.
const MAX_CATALOG_FILES: usize = 1000;

/// The catalog folders of a scenario, by kind (`Vehicle`, `Pedestrian`, `MiscObject`,
/// `Controller`, ...).
#[derive(Debug, Default)]
pub struct Catalogs {
    dirs: Vec<(String, PathBuf)>,
}

impl Catalogs {
    /// Reads `CatalogLocations` (none: no catalogs).
    pub(crate) fn read(r: &Reader<'_>, node: Option<Node<'_, '_>>) -> Result<Self, XoscError> {
        let mut dirs = Vec::new();
        for loc in node.into_iter().flat_map(elements) {
            let kind = loc.tag_name().name();
            let Some(kind) = kind.strip_suffix("Catalog") else {
                return Err(r
                    .text
                    .unsupported(loc, format!("<{kind}> is not a catalog location")));
            };
            let dir = child(loc, "Directory").ok_or_else(|| {
                r.text
                    .invalid(loc, format!("<{kind}Catalog> needs a <Directory>"))
            })?;
            let path = r.scope.string(r.text, dir, "path")?;
            let joined = super::join(&r.dir, &path);
            if joined.is_file() {
                r.note(
                    dir,
                    format!(
                        "the {kind} catalog's directory {path:?} names a file, as openPASS's \
                         configurations do: that file is the location's one catalog file"
                    ),
                );
            }
            dirs.push((kind.to_string(), joined));
        }
        Ok(Catalogs { dirs })
    }

    /// Finds the entry `reference` (a `<CatalogReference>`) names, of kind `kind`, and calls
    /// `read` with the catalog file's text, the entry element and the entry's scope (its
    /// declared parameters, with the reference's assignments).
    ///
    /// # Errors
    /// [`XoscError::Invalid`] at the reference when no location of that kind is declared,
    /// the folder cannot be read, or no file in it has the catalog or the entry; what `read`
    /// returns.
    pub(crate) fn with_entry<R>(
        &self,
        r: &Reader<'_>,
        reference: Node<'_, '_>,
        kinds: &[&str],
        read: impl FnOnce(&Text, Node<'_, '_>, &Scope) -> Result<R, XoscError>,
    ) -> Result<R, XoscError> {
        let catalog = r.scope.string(r.text, reference, "catalogName")?;
        let entry = r.scope.string(r.text, reference, "entryName")?;
        let assignments = assignments(r, reference)?;
        let mut missing = Vec::new();
        let dirs: Vec<&(String, PathBuf)> = self
            .dirs
            .iter()
            .filter(|(k, _)| kinds.contains(&k.as_str()))
            .collect();
        // The standard names a catalog by its <Catalog name>; esmini finds it by its file's
        // name (`catalogName.xosc`), and files written for esmini rely on that: a catalog
        // no <Catalog name> matches is looked for so, with a note.
        let none_named = dirs.iter().all(|(_, d)| !has_catalog_named(r, d, &catalog));
        let named = |file: &Path, cat: &str| {
            none_named && file.file_stem().and_then(|f| f.to_str()) == Some(cat)
        };
        for (kind, dir) in dirs.iter().map(|(k, d)| (k, d)) {
            for file in catalog_files(r, reference, dir)?.iter() {
                let text = r.files.text(file)?;
                let doc = text.parse()?;
                let by_file = named(file, &catalog);
                let Some(cat) = elements(doc.root_element()).find(|c| {
                    c.tag_name().name() == "Catalog"
                        && (by_file || c.attribute("name") == Some(catalog.as_str()))
                }) else {
                    continue;
                };
                if by_file {
                    r.note(
                        reference,
                        format!(
                            "no catalog is named {catalog:?}: the one in {} (named {:?}) is \
                             read, found by its file's name as esmini finds it",
                            file.display(),
                            cat.attribute("name").unwrap_or_default()
                        ),
                    );
                }
                if let Some(e) = elements(cat).find(|e| e.attribute("name") == Some(entry.as_str()))
                {
                    let decls = read_declarations(&text, child(e, "ParameterDeclarations"))?;
                    let scope = Scope::new(&text, &decls, &assignments)?;
                    let borrowed = borrowed_parameters(r, e, &scope);
                    if borrowed.is_empty() {
                        return read(&text, e, &scope);
                    }
                    // esmini resolves a name the entry does not declare in the scenario that
                    // references it; the standard gives an entry its own declarations only.
                    r.note(
                        reference,
                        format!(
                            "catalog entry {entry:?} reads {}, which it does not declare: the \
                             referencing scenario's value is used, as esmini reads it",
                            borrowed.join(", ")
                        ),
                    );
                    let scope = r.scope.child_with(&text, &decls, &assignments)?;
                    return read(&text, e, &scope);
                }
                missing.push(format!(
                    "{kind} catalog {catalog:?} in {} has no entry {entry:?}",
                    file.display()
                ));
            }
        }
        Err(r.text.invalid(
            reference,
            if missing.is_empty() {
                format!(
                    "no {} catalog named {catalog:?} is found in the scenario's CatalogLocations",
                    kinds.join("/")
                )
            } else {
                missing.join("; ")
            },
        ))
    }
}

impl Catalogs {
    /// As [`Catalogs::with_entry`], calling `read` with a reader of the entry
    /// ([`Reader::in_catalog`]: the catalog file's text, the entry's scope, the scenario's
    /// entities, notes and catalogs), for entries that hold storyboard elements (maneuvers,
    /// routes, trajectories, environments).
    ///
    /// # Errors
    /// As [`Catalogs::with_entry`].
    pub(crate) fn read_entry<R>(
        &self,
        r: &Reader<'_>,
        reference: Node<'_, '_>,
        kinds: &[&str],
        read: impl FnOnce(&Reader<'_>, Node<'_, '_>) -> Result<R, XoscError>,
    ) -> Result<R, XoscError> {
        self.with_entry(r, reference, kinds, |text, entry, scope| {
            read(&r.in_catalog(text, scope), entry)
        })
    }
}

/// Whether a file of catalog folder `dir` holds a `<Catalog name="cat">` (a folder that
/// cannot be read holds none: its error is the lookup's).
fn has_catalog_named(r: &Reader<'_>, dir: &Path, cat: &str) -> bool {
    let Ok(files) = r.files.xosc_files(dir) else {
        return false;
    };
    files.iter().any(|f| {
        r.files.text(f).is_ok_and(|text| {
            text.parse().is_ok_and(|doc| {
                elements(doc.root_element())
                    .any(|c| c.tag_name().name() == "Catalog" && c.attribute("name") == Some(cat))
            })
        })
    })
}

/// The parameters (`$name`) that catalog entry `e`'s attributes read but that neither its own
/// scope `own` nor the standard gives it, and that the referencing scope declares: each once,
/// in the order first read.
fn borrowed_parameters(r: &Reader<'_>, e: Node<'_, '_>, own: &Scope) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in e.descendants().filter(Node::is_element) {
        for a in n.attributes() {
            for name in crate::params::refs_of(a.value()) {
                if own.get(&name).is_none() && r.scope.get(&name).is_some() && !out.contains(&name)
                {
                    out.push(name);
                }
            }
        }
    }
    out.into_iter().map(|n| format!("${n}")).collect()
}

/// The reference's `ParameterAssignments`, each value resolved in the scenario's scope.
fn assignments(
    r: &Reader<'_>,
    reference: Node<'_, '_>,
) -> Result<Vec<(String, String)>, XoscError> {
    let mut out = Vec::new();
    for a in child(reference, "ParameterAssignments")
        .into_iter()
        .flat_map(elements)
    {
        // `parameterRef` names the entry's parameter, not the scenario's.
        let name = r.name_ref(a, "parameterRef")?;
        let value = r.scope.string(r.text, a, "value")?;
        out.push((name, value));
    }
    Ok(out)
}

/// The `.xosc` files of a catalog folder, sorted (listed once per scenario's file set).
fn catalog_files(
    r: &Reader<'_>,
    reference: Node<'_, '_>,
    dir: &Path,
) -> Result<Arc<[PathBuf]>, XoscError> {
    let files = r.files.xosc_files(dir).map_err(|e| {
        r.text.invalid(
            reference,
            format!("the catalog folder {} cannot be read: {e}", dir.display()),
        )
    })?;
    if files.len() > MAX_CATALOG_FILES {
        return Err(r.text.invalid(
            reference,
            format!(
                "the catalog folder {} holds more than {MAX_CATALOG_FILES} files",
                dir.display()
            ),
        ));
    }
    Ok(files)
}
