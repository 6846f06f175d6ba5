//! Whole-file writes that never leave a half-written file: write a temporary file in the same
//! folder, then rename it over the target (atomic on POSIX file systems).
//!
//! A rename replaces whatever the target path names, so it is done only when the target is
//! absent or a regular file. A symlink, a directory, a device (`/dev/full`, `/dev/null`) or a
//! FIFO is refused with [`Error::BadInput`] (exit 2), before anything is written: paracosm
//! never replaces what is not its own file (docs/limits.md).

use std::io::Write;
use std::path::Path;

use crate::Error;

/// Writes `bytes` to `path` through a temporary file and a rename.
///
/// # Errors
/// [`Error::BadInput`] when `path` is neither absent nor a regular file ([`check_target`]);
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
/// [`Error::BadInput`] when `path` is neither absent nor a regular file ([`check_target`]);
/// [`Error::Write`] naming `path` when `fill` or the rename fails; the temporary file is
/// removed.
pub fn with_temp<E: std::fmt::Display>(
    path: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), Error> {
    check_target(path)?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    let dir = dir.unwrap_or(Path::new("."));
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let mut builder = tempfile::Builder::new();
    builder.prefix(".paracosm-").suffix(&suffix);
    // As any file a program creates: readable by others as the umask allows (tempfile's own
    // default, 0600, kept summaries, plots and exports from the rest of a team).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let tmp = builder
        .tempfile_in(dir)
        .map_err(|e| Error::write(path, e))?;
    let tmp_path = tmp.into_temp_path();
    fill(&tmp_path).map_err(|e| Error::write(path, e))?;
    tmp_path.persist(path).map_err(|e| Error::write(path, e))
}

/// Opens `path` for writing without following a link and without blocking: a new file is
/// created; an existing one must be a regular file with one name (a hard link elsewhere is
/// refused too), and is then truncated, or appended to when `append`. The one way paracosm
/// opens an output it writes in pieces (`results.jsonl`); whole files go through [`write`].
///
/// # Errors
/// [`Error::BadInput`] naming `path` when it is a symbolic link, a directory, a FIFO, a device
/// or a file with other names ([`check_target`]); [`Error::Write`] for the file system's other
/// reasons.
pub fn open_regular(path: &Path, append: bool) -> Result<std::fs::File, Error> {
    check_target(path)?;
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create(true).append(append);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // A link planted between the check and the open is not followed; a FIFO does not
        // block the open (ENXIO without a reader), so it is named below, not waited on.
        options.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
    }
    let refused = |what: &str| {
        Error::BadInput(format!(
            "`{}` is {what}: paracosm writes its outputs only to new or regular files; give \
             another path",
            path.display()
        ))
    };
    let file = options.open(path).map_err(|e| match e.raw_os_error() {
        #[cfg(unix)]
        Some(libc::ELOOP) => refused("a symbolic link"),
        #[cfg(unix)]
        Some(libc::ENXIO) => refused("a FIFO"),
        _ => Error::write(path, e),
    })?;
    let meta = file.metadata().map_err(|e| Error::write(path, e))?;
    if let Some(what) = paracosm_engine::files::kind_of(&meta.file_type()) {
        return Err(refused(what));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if meta.nlink() > 1 {
            return Err(refused("a file with other names (a hard link)"));
        }
    }
    if !append {
        file.set_len(0).map_err(|e| Error::write(path, e))?;
    }
    Ok(file)
}

/// Checks every path of `names` in `dir` with [`check_target`]: for a command that will write
/// them, before it does any work.
///
/// # Errors
/// The first path that is not absent or a regular file, as [`check_target`].
pub fn check_targets<'a>(
    dir: &Path,
    names: impl IntoIterator<Item = &'a str>,
) -> Result<(), Error> {
    for n in names {
        check_target(&dir.join(n))?;
    }
    Ok(())
}

/// The files a campaign writes into its folder (beside the lock), every one through this
/// module: a link, a directory or a FIFO planted at any of them is refused before a test runs.
/// In the order `summary.json` lists them, `campaign.json` last (it is not listed there).
pub const CAMPAIGN_OUTPUTS: [&str; 10] = [
    "results.jsonl",
    "summary.json",
    "failure_map.png",
    "failure_map.svg",
    "failure_rate.png",
    "failure_rate.svg",
    "pairs.png",
    "pairs.svg",
    "report.html",
    "campaign.json",
];

/// Makes the output folder `dir` (and its parents) and checks that it takes new files
/// ([`probe_writable`]): for a command's `--out`, before any work.
///
/// # Errors
/// [`Error::BadInput`] (exit 2) naming the folder, when it cannot be made or written.
pub fn make_output_folder(dir: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::BadInput(format!(
            "cannot create the output folder `{}`: {e}",
            dir.display()
        ))
    })?;
    probe_writable(dir)
}

/// Checks that `dir` (a folder that exists) takes new files: one of a fresh name is created
/// exclusively (so a link planted in the folder is never followed) and removed at once.
///
/// # Errors
/// [`Error::BadInput`] naming the folder and the reason (read-only, not a folder, no space):
/// bad input, exit 2, before any work.
pub fn probe_writable(dir: &Path) -> Result<(), Error> {
    tempfile::Builder::new()
        .prefix(".paracosm-probe-")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| {
            Error::BadInput(format!(
                "cannot write to the output folder `{}`: {e}",
                dir.display()
            ))
        })
}

/// Removes the temporary files ([`with_temp`]'s `.paracosm-*`) that a writer of `dir` killed
/// mid-write left there. Call it holding the folder's lock ([`crate::campaign::lock`]), so that no other
/// writer's temporary file is taken. Only regular files are removed (a link planted under such
/// a name is left, and never followed); a file that cannot be removed is left as it is.
pub fn remove_stale_temps(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let ours = name.to_string_lossy().starts_with(".paracosm-");
        if ours && e.file_type().is_ok_and(|t| t.is_file()) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// What `path` names when it is not a regular file: "a symlink", "a directory", "a device or
/// a FIFO"; `None` when it is a regular file or absent (or cannot be looked at: the write then
/// reports why).
fn not_regular(path: &Path) -> Option<&'static str> {
    // The link itself, not what it points to: a rename would replace the link.
    paracosm_engine::files::kind_of(&std::fs::symlink_metadata(path).ok()?.file_type())
}

/// Checks that an output path may be replaced by a rename: it is absent or a regular file.
///
/// # Errors
/// [`Error::BadInput`] naming `path` and what it is (a symbolic link, a directory, a device,
/// FIFO or socket).
pub fn check_target(path: &Path) -> Result<(), Error> {
    match not_regular(path) {
        None => Ok(()),
        Some(what) => Err(Error::BadInput(format!(
            "`{}` is {what}: paracosm writes an output through a temporary file and a rename, \
             which would replace it, so it writes only to a new or a regular file; give \
             another path",
            path.display()
        ))),
    }
}

/// Checks, before any work, an output `option` names for a command that reads `inputs`: it
/// may be replaced ([`check_target`]), its folder exists, and it is none of the inputs (the
/// same file by device and inode, however it is spelt or linked: `map M.xodr --png M.xodr`
/// would replace the map it draws).
///
/// # Errors
/// [`Error::BadInput`] naming `option`, the path and what is wrong.
pub fn check_output(path: &Path, option: &str, inputs: &[&Path]) -> Result<(), Error> {
    use std::os::unix::fs::MetadataExt;
    check_target(path)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(Error::BadInput(format!(
                "{option} `{}`: the folder `{}` does not exist; create it first",
                path.display(),
                dir.display()
            )));
        }
    }
    let Ok(out) = std::fs::metadata(path) else {
        return Ok(());
    };
    for input in inputs {
        if std::fs::metadata(input).is_ok_and(|m| m.dev() == out.dev() && m.ino() == out.ino()) {
            return Err(Error::BadInput(format!(
                "{option} `{}` is the input `{}`: writing it would replace what is read; give \
                 another path",
                path.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// The files of a campaign folder that the campaign itself writes and reads back.
pub const CAMPAIGN_OWNED: [&str; 3] = ["results.jsonl", "campaign.json", "summary.json"];

/// Checks a path given for another output (`--junit`) of the campaign in `out`: it may be
/// replaced ([`check_target`]) and is not one of the campaign's own files
/// ([`CAMPAIGN_OWNED`]) in `out`.
///
/// # Errors
/// [`Error::BadInput`] naming `path` and `option`.
pub fn check_side_output(path: &Path, option: &str, out: &Path) -> Result<(), Error> {
    check_target(path)?;
    // Its folder must exist: found only when the campaign has run, the file could not be
    // written after all that work.
    // (The campaign's folder itself is made before any test runs.)
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        let plain = |p: &Path| -> std::path::PathBuf {
            p.components()
                .filter(|c| !matches!(c, std::path::Component::CurDir))
                .collect()
        };
        if !dir.is_dir() && plain(dir) != plain(out) {
            return Err(Error::BadInput(format!(
                "{option} `{}`: the folder `{}` does not exist; create it first",
                path.display(),
                dir.display()
            )));
        }
    }
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return Ok(());
    };
    if !CAMPAIGN_OWNED.contains(&name) {
        return Ok(());
    }
    let absolute = |p: &Path| -> std::path::PathBuf {
        let p = if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        };
        std::fs::canonicalize(p).unwrap_or_else(|_| {
            std::env::current_dir()
                .map(|d| d.join(p))
                .unwrap_or_else(|_| p.to_path_buf())
        })
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    if absolute(dir) == absolute(out) {
        return Err(Error::BadInput(format!(
            "{option} `{}` is the campaign's own `{name}` in `{}`: writing there would destroy \
             it; give another path",
            path.display(),
            out.display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file written through a temporary file has the mode any new file gets (0666 less the
    /// umask), not tempfile's private 0600.
    #[cfg(target_os = "linux")]
    #[test]
    fn written_files_are_as_readable_as_the_umask_allows() {
        use std::os::unix::fs::PermissionsExt;
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let umask = status
            .lines()
            .find_map(|l| l.strip_prefix("Umask:"))
            .map(|m| u32::from_str_radix(m.trim(), 8).unwrap())
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        write(&path, b"{}").unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o666 & !umask);
    }

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

    #[test]
    fn links_directories_and_devices_are_refused_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.xml");
        std::fs::write(&real, b"mine").unwrap();
        let link = dir.path().join("link.xml");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        for (path, what) in [
            (link.as_path(), "symbolic link"),
            (dir.path(), "directory"),
            (Path::new("/dev/null"), "device"),
        ] {
            let e = write(path, b"x").unwrap_err();
            assert!(matches!(e, Error::BadInput(_)), "{e}");
            assert!(e.to_string().contains(what), "{e}");
        }
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"mine");
        // A regular file and an absent one are written.
        write(&real, b"new").unwrap();
        write(&dir.path().join("fresh.xml"), b"new").unwrap();
    }

    #[test]
    fn the_campaign_s_own_files_are_refused_as_side_outputs() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("d");
        for name in CAMPAIGN_OWNED {
            let e = check_side_output(&out.join(name), "--junit", &out).unwrap_err();
            assert!(e.to_string().contains("campaign's own"), "{e}");
        }
        // The same names elsewhere, and other names inside, are fine.
        check_side_output(&dir.path().join("results.jsonl"), "--junit", &out).unwrap();
        check_side_output(&out.join("junit.xml"), "--junit", &out).unwrap();
        // A folder that does not exist (but the campaign's own, made before any test).
        let missing = dir.path().join("nowhere").join("junit.xml");
        let e = check_side_output(&missing, "--junit", &out).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let fresh = dir.path().join("fresh");
        check_side_output(&fresh.join("junit.xml"), "--junit", &fresh).unwrap();
        // Spelled another way, it is still the same folder.
        std::fs::create_dir_all(&out).unwrap();
        let other = dir.path().join("d/../d/summary.json");
        assert!(check_side_output(&other, "--junit", &out).is_err());
    }
}
