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
            dirs.push((kind.to_string(), super::join(&r.dir, &path)));
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
        for (kind, dir) in self
            .dirs
            .iter()
            .filter(|(k, _)| kinds.contains(&k.as_str()))
        {
            for file in catalog_files(r, reference, dir)?.iter() {
                let text = r.files.text(file)?;
                let doc = text.parse()?;
                let Some(cat) = elements(doc.root_element()).find(|c| {
                    c.tag_name().name() == "Catalog"
                        && c.attribute("name") == Some(catalog.as_str())
                }) else {
                    continue;
                };
                if let Some(e) = elements(cat).find(|e| e.attribute("name") == Some(entry.as_str()))
                {
                    let decls = read_declarations(&text, child(e, "ParameterDeclarations"))?;
                    let scope = Scope::new(&text, &decls, &assignments)?;
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
        let name = r.scope.string(r.text, a, "parameterRef")?;
        let value = r.scope.string(r.text, a, "value")?;
        out.push((name.trim_start_matches('$').to_string(), value));
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
