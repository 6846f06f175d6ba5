//! The files a scenario reads, for every front end: a program's OpenDRIVE maps
//! (`OpenDrive("map.xodr")`, the one file access a program has) and the OpenSCENARIO files of
//! an `Import` or of an OpenSCENARIO campaign (its map, variation file, scenario and catalogs,
//! through [`paracosm_openscenario::FileSet`]).
//!
//! A path is resolved against the folder of the program's file (for a built-in scenario,
//! against the maps built into the binary; for a program given as text, against the current
//! folder). Each file is read and checked once per program: every later evaluation (one per
//! test) gets the same map, so a file changed during a campaign changes nothing in it. Its
//! SHA-256 enters the campaign's fingerprint ([`crate::Scenario::input_files`]), so
//! `--resume` refuses a campaign whose map has changed since.

use crate::lang::load_error::{refused, LoadError, LoadErrorKind};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use paracosm_engine::network::opendrive;
use paracosm_engine::network::MapRef;
use sha2::{Digest, Sha256};

use crate::scenario::InputFile;

/// Largest OpenDRIVE file read, bytes (16 MiB: a city district; larger maps are refused).
pub const MAX_MAP_BYTES: u64 = 16 << 20;

/// The maps shipped with the built-in scenarios: `(path as the programs write it, text)`.
pub const BUILTIN_MAPS: [(&str, &str); 3] = [
    ("maps/bend.xodr", include_str!("../maps/bend.xodr")),
    ("maps/junction.xodr", include_str!("../maps/junction.xodr")),
    (
        "maps/roundabout.xodr",
        include_str!("../maps/roundabout.xodr"),
    ),
];

/// Where a program's relative paths lead.
#[derive(Debug, Clone)]
pub(crate) enum Base {
    /// The folder of the program's file.
    Folder(PathBuf),
    /// A built-in scenario: [`BUILTIN_MAPS`].
    Builtin,
}

impl Base {
    /// The base for a program loaded as `file` (its path, or `scenarios/NAME.star` for a
    /// built-in one).
    pub(crate) fn of(file: &str, builtin: bool) -> Base {
        if builtin {
            return Base::Builtin;
        }
        let path = Path::new(file);
        match path.parent() {
            Some(dir) if path.is_file() => Base::Folder(dir.to_path_buf()),
            _ => Base::Folder(PathBuf::from(".")),
        }
    }
}

/// The text of the file `path` (as a program writes it) that the scenario `scenario` (a
/// program's path, or a built-in scenario's name, as `paracosm-fuzz` takes it) reads: what
/// `paracosm-fuzz export` copies beside the test it writes.
///
/// # Errors
/// [`LoadError`] of kind [`LoadErrorKind::Files`], naming the file, when it cannot be read,
/// is larger than [`MAX_MAP_BYTES`] or is not UTF-8, or when a built-in scenario has no such
/// map.
pub fn read_input_file(scenario: &str, path: &str) -> Result<String, LoadError> {
    let files = refused(LoadErrorKind::Files);
    let program = Path::new(scenario);
    let builtin = !(scenario.ends_with(".star") || program.exists());
    let base = Base::of(scenario, builtin);
    match base {
        Base::Builtin => BUILTIN_MAPS
            .iter()
            .find(|(p, _)| *p == path)
            .map(|(_, t)| (*t).to_owned())
            .ok_or_else(|| files(format!("no built-in map \"{path}\""))),
        Base::Folder(dir) => {
            let full = dir.join(path);
            crate::text_file::read_text(&full, MAX_MAP_BYTES)
                .map_err(|e| files(format!("cannot read {}: {e}", full.display())))
        }
    }
}

/// Imports the OpenDRIVE text of `file` ([`opendrive::import`]), first refusing an element
/// with more attributes than paracosm's XML readers take
/// ([`paracosm_openscenario::text::check_breadth`]: the parsers' cost grows with their
/// square). Every map a user names is read through here.
///
/// # Errors
/// [`opendrive::MapError`] at the element's line and column for too many attributes; the
/// importer's errors otherwise.
pub fn import_map(file: &str, text: &str) -> Result<opendrive::Imported, opendrive::MapError> {
    if let Err(e) = paracosm_openscenario::text::check_breadth(text) {
        let before = &text[..e.offset];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        return Err(opendrive::MapError {
            file: file.to_owned(),
            line: Some(before.matches('\n').count() as u32 + 1),
            column: Some(before[line_start..].chars().count() as u32 + 1),
            message: e.to_string(),
        });
    }
    opendrive::import(file, text)
}

#[derive(Debug, Clone)]
struct Loaded {
    /// The map with what is derived from it once for every test ([`MapRef`]'s cache).
    map: MapRef,
    warnings: Vec<String>,
    sha256: String,
}

/// The maps a program has read, by the path it wrote, and the OpenSCENARIO files it or its
/// scenario has read (`Import`, an OpenSCENARIO campaign): each read once, for every test.
#[derive(Debug)]
pub(crate) struct MapFiles {
    base: Base,
    loaded: Mutex<BTreeMap<String, Loaded>>,
    /// The OpenSCENARIO files read: a scenario, its catalogs, a variation file.
    pub(crate) xosc: std::sync::Arc<paracosm_openscenario::FileSet>,
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

impl MapFiles {
    pub(crate) fn new(base: Base) -> MapFiles {
        Self::sharing(base, Default::default())
    }

    /// As [`MapFiles::new`], with the OpenSCENARIO files `xosc` already read (an OpenSCENARIO
    /// campaign's load reads its variation file and scenario before its maps).
    pub(crate) fn sharing(
        base: Base,
        xosc: std::sync::Arc<paracosm_openscenario::FileSet>,
    ) -> MapFiles {
        MapFiles {
            base,
            loaded: Mutex::new(BTreeMap::new()),
            xosc,
        }
    }

    /// The map at `path` (as the program writes it): read and checked the first time, the
    /// same map after, with the same cache of what is derived from it (its query index and
    /// collision mesh are built once per program, not once per test).
    ///
    /// # Errors
    /// [`LoadError`] of kind [`LoadErrorKind::Files`], naming the file: it cannot be read, is
    /// larger than [`MAX_MAP_BYTES`], is not UTF-8, or is no usable OpenDRIVE map
    /// ([`opendrive::import`]'s message, with the line).
    pub(crate) fn load(&self, path: &str) -> Result<MapRef, LoadError> {
        let files = refused(LoadErrorKind::Files);
        let mut loaded = self
            .loaded
            .lock()
            .map_err(|_| files("a map load panicked".to_owned()))?;
        if let Some(l) = loaded.get(path) {
            return Ok(l.map.clone());
        }
        let (shown, text) = match &self.base {
            Base::Builtin => {
                let text = BUILTIN_MAPS
                    .iter()
                    .find(|(p, _)| *p == path)
                    .map(|(_, t)| (*t).to_owned())
                    .ok_or_else(|| {
                        let known: Vec<&str> = BUILTIN_MAPS.iter().map(|(p, _)| *p).collect();
                        files(format!(
                            "no built-in map \"{path}\" (the built-in maps: {})",
                            known.join(", ")
                        ))
                    })?;
                (format!("scenarios/{path}"), text)
            }
            Base::Folder(dir) => {
                let full = dir.join(path);
                let shown = full.display().to_string();
                let text = crate::text_file::read_text(&full, MAX_MAP_BYTES).map_err(|e| {
                    let town = if full.extension().is_none() {
                        " (a map named without its extension, as CARLA names its towns, is read \
                         from NAME.xodr beside the scenario or in the folder --maps DIR names: \
                         CARLA's towns ship with CARLA, as CarlaUE4/Content/Carla/Maps/OpenDrive)"
                    } else {
                        ""
                    };
                    files(format!("cannot read the OpenDRIVE map {shown}: {e}{town}"))
                })?;
                (shown, text)
            }
        };
        let imported =
            import_map(&shown, &text).map_err(|e| files(format!("the OpenDRIVE map {e}")))?;
        let map = MapRef::new(imported.map);
        loaded.insert(
            path.to_owned(),
            Loaded {
                map: map.clone(),
                warnings: imported.warnings,
                sha256: sha256_hex(text.as_bytes()),
            },
        );
        Ok(map)
    }

    /// The file `path` (as the program writes it) is, relative to the program's folder;
    /// `None` for a built-in scenario (it reads only [`BUILTIN_MAPS`]).
    pub(crate) fn resolve(&self, path: &str) -> Option<PathBuf> {
        match &self.base {
            Base::Folder(dir) => Some(dir.join(path)),
            Base::Builtin => None,
        }
    }

    /// Every file read so far with its SHA-256: the maps in order of path, then the
    /// OpenSCENARIO files in order of path (hashed as read: UTF-8 text without a byte-order
    /// mark).
    pub(crate) fn inputs(&self) -> Vec<InputFile> {
        let mut out: Vec<InputFile> = self
            .loaded
            .lock()
            .map(|l| {
                l.iter()
                    .map(|(path, f)| InputFile {
                        path: path.clone(),
                        sha256: f.sha256.clone(),
                    })
                    .collect()
            })
            .unwrap_or_default();
        out.extend(self.xosc.texts().into_iter().map(|(path, text)| InputFile {
            path: path.display().to_string(),
            sha256: sha256_hex(text.text.as_bytes()),
        }));
        out
    }

    /// What the maps read so far do not use: `(file, message)`.
    pub(crate) fn warnings(&self) -> Vec<String> {
        self.loaded
            .lock()
            .map(|l| l.values().flat_map(|f| f.warnings.clone()).collect())
            .unwrap_or_default()
    }
}
