//! The files one OpenSCENARIO scenario reads (its variation file, its scenario, its catalogs
//! and the catalog folders' listings), each read from disk once and kept: a campaign is one
//! fixed scenario, so every test reads the texts its load read, even if a file changes on disk
//! while the campaign runs, and a test costs no file system calls.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use crate::error::XoscError;
use crate::text::Text;

/// The files a scenario has read, by path as named with `.` components removed and `dir/..`
/// folded (so `a/./b/../c.xosc` and `a/c.xosc` are one file; a path is not made absolute),
/// and the `.xosc` files of each catalog folder it listed. Shared between threads: the tests
/// of a campaign read through one set.
#[derive(Debug, Default)]
pub struct FileSet {
    texts: Mutex<BTreeMap<PathBuf, Arc<Text>>>,
    folders: Mutex<BTreeMap<PathBuf, Arc<[PathBuf]>>>,
    maps: Vec<PathBuf>,
    carla: bool,
}

impl FileSet {
    /// An empty set: the first read of each file goes to disk.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty set whose scenarios find a map their `LogicFile` names but that is not where
    /// it says (a CARLA town, `Town01`) in the folder `maps` too (`--maps`).
    pub fn with_maps(maps: Option<PathBuf>) -> Self {
        Self {
            maps: maps.into_iter().collect(),
            ..Self::default()
        }
    }

    /// The folders of maps ([`FileSet::with_maps`]): none, or the one given.
    pub fn maps(&self) -> &[PathBuf] {
        &self.maps
    }

    /// The same set, whose scenarios are read as CARLA's scenario_runner reads its own
    /// (`--carla`; [`crate::model::Scenario::carla`]) whatever their `FileHeader` says.
    pub fn as_carla(self, carla: bool) -> Self {
        Self { carla, ..self }
    }

    /// Whether its scenarios are read as CARLA's ([`FileSet::as_carla`]).
    pub fn carla(&self) -> bool {
        self.carla
    }

    /// The text of `path`: read from disk ([`Text::read`]) the first time, from the set after.
    ///
    /// # Errors
    /// [`XoscError::Io`] when the file is missing, unreadable, not UTF-8 or larger than
    /// [`crate::text::MAX_FILE_BYTES`] (an error is not kept: a later call reads again).
    pub fn text(&self, path: &Path) -> Result<Arc<Text>, XoscError> {
        let key = folded(path);
        if let Some(t) = lock(&self.texts).get(&key) {
            return Ok(t.clone());
        }
        let text = Arc::new(Text::read(path)?);
        // Two threads may read the same file at once; the first one kept wins, so every
        // reader sees one text.
        Ok(lock(&self.texts).entry(key).or_insert(text).clone())
    }

    /// The `.xosc` files of the folder `dir` (extension compared without case), sorted, or
    /// `dir` alone when it is a `.xosc` file (openPASS's catalog locations name their file):
    /// listed the first time, from the set after. The first listing also reads each of them
    /// ([`FileSet::text`]; one that cannot be read is left to the read that needs it, which
    /// reports it), so that a test whose values choose another catalog entry reads the text
    /// the campaign's load read, and the campaign's fingerprint covers it.
    ///
    /// # Errors
    /// The [`std::io::Error`] of a folder that cannot be listed, or one naming a `.xosc` entry
    /// that is not a regular file (a FIFO, a device, a folder: its entries could not be
    /// searched, and reading it would block or never end).
    pub fn xosc_files(&self, dir: &Path) -> Result<Arc<[PathBuf]>, std::io::Error> {
        let key = folded(dir);
        if let Some(files) = lock(&self.folders).get(&key) {
            return Ok(files.clone());
        }
        if dir.is_file()
            && dir
                .extension()
                .is_some_and(|x| x.eq_ignore_ascii_case("xosc"))
        {
            // A location that names its one catalog file (openPASS's configurations).
            let _ = self.text(dir);
            let files: Arc<[PathBuf]> = vec![dir.to_path_buf()].into();
            return Ok(lock(&self.folders).entry(key).or_insert(files).clone());
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| {
                p.extension()
                    .is_some_and(|x| x.eq_ignore_ascii_case("xosc"))
            })
            .collect();
        files.sort();
        for f in &files {
            if let Some(kind) = paracosm_files::not_regular(f) {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!(
                        "its entry {} is {kind}, not a regular file: every .xosc file of a \
                         catalog folder is read for the entries it holds",
                        f.display()
                    ),
                ));
            }
            let _ = self.text(f);
        }
        let files: Arc<[PathBuf]> = files.into();
        Ok(lock(&self.folders).entry(key).or_insert(files).clone())
    }

    /// Every file read so far, by path, with its text: what a campaign's fingerprint covers.
    pub fn texts(&self) -> Vec<(PathBuf, Arc<Text>)> {
        lock(&self.texts)
            .iter()
            .map(|(p, t)| (p.clone(), t.clone()))
            .collect()
    }
}

/// `path` with its `.` components removed and each `name/..` folded (lexically: a link is
/// not followed), the key of a file in the set.
fn folded(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out: Vec<Component<'_>> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out.iter().collect()
}

/// The map behind `m`; a thread that panicked while holding it left it whole (each insert is
/// one call), so its contents are still good.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_file_spelled_two_ways_is_one_key() {
        assert_eq!(folded(Path::new("a/./b/../c.xosc")), Path::new("a/c.xosc"));
        assert_eq!(folded(Path::new("../x/./y.xosc")), Path::new("../x/y.xosc"));
        assert_eq!(folded(Path::new("/r/a/../../b")), Path::new("/b"));
    }

    #[test]
    fn a_file_is_read_once_and_kept_though_it_changes_on_disk() {
        let dir = std::env::temp_dir().join(format!("paracosm-fileset-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.xosc");
        std::fs::write(&path, "<OpenSCENARIO/>").unwrap();
        let files = FileSet::new();
        let first = files.text(&path).unwrap();
        std::fs::write(&path, "<Changed/>").unwrap();
        let second = files.text(&path).unwrap();
        assert!(Arc::ptr_eq(&first, &second));
        assert_eq!(second.text, "<OpenSCENARIO/>");
        std::fs::write(dir.join("b.XOSC"), "").unwrap();
        std::fs::write(dir.join("c.txt"), "").unwrap();
        let listed = files.xosc_files(&dir).unwrap();
        assert_eq!(listed.len(), 2, "{listed:?}");
        std::fs::write(dir.join("d.xosc"), "").unwrap();
        assert_eq!(
            files.xosc_files(&dir).unwrap().len(),
            2,
            "the listing is kept"
        );
        assert_eq!(
            files.texts().len(),
            2,
            "a listed folder's files are read with it"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
