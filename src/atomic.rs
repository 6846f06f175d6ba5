//! Whole-file writes that never leave a half-written file: write a temporary file in the same
//! folder, then rename it over the target (atomic on POSIX file systems).

use std::io::Write;
use std::path::Path;

use crate::Error;

/// Writes `bytes` to `path` through a temporary file and a rename.
///
/// # Errors
/// [`Error::Write`] naming `path` with the file system's reason (e.g. no space left on
/// device); the previous contents of `path`, if any, are then untouched.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    with_temp(path, |tmp| {
        let mut f = std::fs::File::create(tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })
}

/// Calls `fill` with a temporary path (same folder and extension as `path`), then renames it
/// over `path`. For writers that want a path, such as plotters' backends.
///
/// # Errors
/// [`Error::Write`] naming `path` when `fill` or the rename fails; the temporary file is
/// removed.
pub fn with_temp<E: std::fmt::Display>(
    path: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), Error> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    let dir = dir.unwrap_or(Path::new("."));
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(".paracosm-")
        .suffix(&suffix)
        .tempfile_in(dir)
        .map_err(|e| Error::write(path, e))?;
    let tmp_path = tmp.into_temp_path();
    fill(&tmp_path).map_err(|e| Error::write(path, e))?;
    tmp_path.persist(path).map_err(|e| Error::write(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("summary.json");
        write(&target, b"old").unwrap();
        let err = with_temp(&target, |_| Err::<(), _>("disk full"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("summary.json") && err.contains("disk full"),
            "{err}"
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["summary.json"]);
        write(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
    }
}
