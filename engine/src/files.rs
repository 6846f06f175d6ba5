//! Input files: what paracosm reads a program, a map, a model, a CSV or a results file from
//! must be a regular file (after following links). A FIFO blocks its reader until something
//! writes to it (paracosm hung, nothing printed), a device such as `/dev/zero` never ends, and
//! a directory is no file; each is refused before it is opened.

use std::path::Path;

/// What `path` is when it is not a regular file: `"a directory"`, `"a FIFO"`, `"a character
/// device"`, `"a block device"`, `"a socket"`; `None` for a regular file (links followed) and
/// for a path that cannot be looked at (absent, no permission: opening it then says why).
pub fn not_regular(path: &Path) -> Option<&'static str> {
    kind_of(&std::fs::metadata(path).ok()?.file_type())
}

/// What a file of type `t` is when it is not a regular file (`"a directory"`, `"a FIFO"`,
/// `"a character device"`, `"a block device"`, `"a socket"`, `"a symbolic link"` for a link
/// itself); `None` for a regular file.
pub fn kind_of(t: &std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    if t.is_file() {
        None
    } else if t.is_dir() {
        Some("a directory")
    } else if t.is_fifo() {
        Some("a FIFO")
    } else if t.is_char_device() {
        Some("a character device")
    } else if t.is_block_device() {
        Some("a block device")
    } else if t.is_socket() {
        Some("a socket")
    } else if t.is_symlink() {
        Some("a symbolic link")
    } else {
        Some("not a regular file")
    }
}

/// A path that is not a regular file ([`regular_file`]): what it is instead. The message
/// leaves the path out (the caller adds it with its own location format).
#[derive(Debug, thiserror::Error, Clone, Copy, PartialEq, Eq)]
#[error(
    "is {kind}, not a regular file: paracosm reads its inputs from files (a FIFO would block, \
     a device never ends)"
)]
pub struct NotRegular {
    /// What the path is ([`not_regular`]): `"a directory"`, `"a FIFO"`...
    pub kind: &'static str,
}

/// Refuses `path` when it is not a regular file ([`not_regular`]).
///
/// # Errors
/// [`NotRegular`]: "is a FIFO, not a regular file: ..." (without the path, which the caller
/// adds with its own location format).
pub fn regular_file(path: &Path) -> Result<(), NotRegular> {
    match not_regular(path) {
        None => Ok(()),
        Some(kind) => Err(NotRegular { kind }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directories_fifos_and_devices_are_named_and_files_pass() {
        let dir = std::env::temp_dir().join(format!("paracosm-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("f.txt");
        std::fs::write(&file, "x").unwrap();
        let link = dir.join("link.txt");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&file, &link).unwrap();
        assert_eq!(not_regular(&file), None);
        assert_eq!(not_regular(&link), None, "a link to a file is read");
        assert_eq!(not_regular(&dir.join("absent")), None);
        assert_eq!(not_regular(&dir), Some("a directory"));
        assert_eq!(
            not_regular(Path::new("/dev/zero")),
            Some("a character device")
        );
        let fifo = dir.join("pipe");
        let _ = std::fs::remove_file(&fifo);
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        assert!(regular_file(&fifo)
            .unwrap_err()
            .to_string()
            .starts_with("is a FIFO"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
