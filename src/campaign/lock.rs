//! One writer per campaign folder (issue 22, requirement 3). Every command that writes a
//! campaign folder (a run, `--resume`, `merge --out`, the Python package's `Scenario.run`)
//! first takes an advisory lock on `.paracosm.lock` in it, with the operating system's
//! `flock` (through [`std::fs::File::try_lock`]), and holds it until it is done. A second
//! writer is refused at once with [`Error::BadInput`] (exit 2) naming the holder's process
//! id, which the holder writes into the file.
//!
//! The operating system releases the lock when its process ends, however it ends (`kill -9`
//! included), so a lock whose process is gone is simply taken: there is no stale lock to
//! remove. The file stays in the folder; readers ignore it.
//!
//! The lock never writes outside the folder: it is opened without following a symbolic link
//! (`O_NOFOLLOW`) and without blocking on a FIFO (`O_NONBLOCK`), must then be a regular file
//! with no other name (a hard link count of 1), and is never truncated: the process id is
//! written over its first bytes, padded to a fixed width. A lock path that is a link, a
//! directory, a FIFO or a second name of another file is refused (exit 2), naming it.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use crate::Error;

/// The lock file's name inside a campaign folder.
pub const LOCK_FILE: &str = ".paracosm.lock";

/// Opens (creating it) the lock file at `path` for reading and writing, refusing anything but
/// a regular file of its own: a symbolic link (not followed), a directory, a FIFO or device
/// (opened without blocking, then refused), a file with another name (hard links).
///
/// # Errors
/// [`Error::BadInput`] naming the path and what it is, or the I/O error.
fn open_own(path: &Path) -> Result<File, Error> {
    use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
    let refuse = |what: &str| {
        Error::BadInput(format!(
            "the lock file `{}` is {what}; paracosm writes only a regular lock file of its own \
             in its output folder: remove it",
            path.display()
        ))
    };
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| match e.raw_os_error() {
            Some(libc::ELOOP) => refuse("a symbolic link"),
            Some(libc::EISDIR) => refuse("a directory"),
            _ => Error::BadInput(format!(
                "cannot write the lock file `{}`: {e}",
                path.display()
            )),
        })?;
    let meta = file.metadata().map_err(|e| Error::write(path, e))?;
    if !meta.file_type().is_file() {
        return Err(refuse(if meta.is_dir() {
            "a directory"
        } else {
            "a FIFO, a device or a socket"
        }));
    }
    if meta.nlink() > 1 {
        return Err(refuse("a second name of another file (a hard link)"));
    }
    Ok(file)
}

/// A held lock on a campaign folder; released when dropped.
#[derive(Debug)]
pub struct CampaignLock {
    _file: File,
    path: PathBuf,
}

impl CampaignLock {
    /// Creates `dir` if needed and takes its lock.
    ///
    /// # Errors
    /// [`Error::BadInput`] when `dir` exists and is not a folder, cannot be created, or is
    /// being written by another process (the message names its process id).
    pub fn acquire(dir: &Path) -> Result<Self, Error> {
        if dir.exists() && !dir.is_dir() {
            return Err(Error::BadInput(format!(
                "--out `{}` is not a folder",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(|e| {
            Error::BadInput(format!(
                "cannot create output folder `{}`: {e}",
                dir.display()
            ))
        })?;
        let path = dir.join(LOCK_FILE);
        let mut file = open_own(&path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                // The pid written over the file's first bytes.
                let holder = holder.split_whitespace().next().unwrap_or("");
                let who = if holder.is_empty() {
                    "another process".to_owned()
                } else {
                    format!("process {holder}")
                };
                return Err(Error::BadInput(format!(
                    "`{}` is being written by {who}; wait for it to finish or stop it (its lock \
                     `{}` is released when it exits)",
                    dir.display(),
                    path.display()
                )));
            }
            Err(TryLockError::Error(e)) => {
                // A file system without locks (some network mounts): run, but say so.
                tracing::warn!(
                    "cannot lock `{}` ({e}): nothing stops a second writer of this folder",
                    path.display()
                );
                return Ok(Self { _file: file, path });
            }
        }
        // Ours now: record who holds it, for the message a second writer gets, over the
        // file's first bytes (never truncating it: a pid is at most 20 digits).
        let pid = format!("{:<20}\n", std::process::id());
        let written = file
            .rewind()
            .and_then(|()| file.write_all(pid.as_bytes()))
            .and_then(|()| file.flush());
        if let Err(e) = written {
            return Err(Error::write(&path, e));
        }
        Ok(Self { _file: file, path })
    }

    /// The lock file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_a_folder_is_refused_until_the_first_is_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().join("campaign");
        let first = CampaignLock::acquire(&d).unwrap();
        assert_eq!(
            std::fs::read_to_string(first.path()).unwrap().trim(),
            std::process::id().to_string()
        );
        let e = CampaignLock::acquire(&d).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "is being written by process {}",
                std::process::id()
            )),
            "{e}"
        );
        drop(first);
        let again = CampaignLock::acquire(&d).unwrap();
        drop(again);
        // A file where the folder should be is refused.
        let f = dir.path().join("file");
        std::fs::write(&f, "x").unwrap();
        assert!(CampaignLock::acquire(&f)
            .unwrap_err()
            .to_string()
            .contains("is not a folder"));
    }

    /// A link, a directory, a FIFO or a hard link planted at the lock's path is refused, and
    /// what it names is left as it was (a link to a file outside the folder had the writer's
    /// pid written over it, by a fresh run, --resume and --force alike).
    #[test]
    fn a_planted_lock_path_is_refused_and_nothing_outside_the_folder_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let outside = dir.path().join("precious.txt");
        std::fs::write(&outside, "keep me").unwrap();
        let plant = |name: &str, how: &dyn Fn(&Path)| {
            let d = dir.path().join(name);
            std::fs::create_dir(&d).unwrap();
            how(&d.join(LOCK_FILE));
            CampaignLock::acquire(&d).unwrap_err().to_string()
        };
        let e = plant("link", &|p| {
            std::os::unix::fs::symlink(&outside, p).unwrap()
        });
        assert!(e.contains("is a symbolic link"), "{e}");
        let e = plant("dir", &|p| std::fs::create_dir(p).unwrap());
        assert!(e.contains("is a directory"), "{e}");
        let e = plant("fifo", &|p| {
            assert!(std::process::Command::new("mkfifo")
                .arg(p)
                .status()
                .unwrap()
                .success())
        });
        assert!(e.contains("a FIFO"), "{e}");
        let e = plant("hard", &|p| std::fs::hard_link(&outside, p).unwrap());
        assert!(e.contains("hard link"), "{e}");
        assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep me");
        // A lock file that holds more than a pid is written over, not truncated.
        let d = dir.path().join("long");
        std::fs::create_dir(&d).unwrap();
        std::fs::write(d.join(LOCK_FILE), "x".repeat(40)).unwrap();
        let lock = CampaignLock::acquire(&d).unwrap();
        let text = std::fs::read_to_string(lock.path()).unwrap();
        assert_eq!(text.len(), 40);
        assert!(text.starts_with(&std::process::id().to_string()), "{text}");
    }
}
