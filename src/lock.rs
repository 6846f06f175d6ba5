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

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use crate::Error;

/// The lock file's name inside a campaign folder.
pub const LOCK_FILE: &str = ".paracosm.lock";

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
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| {
                Error::BadInput(format!(
                    "cannot write to output folder `{}`: {e}",
                    dir.display()
                ))
            })?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                let holder = holder.trim();
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
        // Ours now: record who holds it, for the message a second writer gets.
        let pid = std::process::id().to_string();
        let written = file
            .set_len(0)
            .and_then(|()| file.rewind())
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
            std::fs::read_to_string(first.path()).unwrap(),
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
}
