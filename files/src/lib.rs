//! How paracosm opens an input file: the one door every input goes through (a program, a
//! map, an OpenSCENARIO scenario, variation, catalog or imported file, a space, a CSV, a
//! model, a results file).
//!
//! What paracosm reads must be a regular file (after following links): a FIFO blocks its
//! reader until something writes to it (paracosm hung, nothing printed), a device such as
//! `/dev/zero` never ends, and a directory is no file; each is refused before it is opened,
//! and [`read_text`] reads at most its limit plus one byte whatever the file turns out to be.
#![warn(missing_docs)]

use std::io::Read;
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

/// Reads `path` as UTF-8 text of at most `limit` bytes (checked while reading, so a file
/// that grows after it was looked at is refused too, and a device such as `/dev/zero` costs
/// `limit + 1` bytes at most). A path that is not a regular file
/// (a FIFO, which would block; a device; a directory) is refused before it is opened.
///
/// # Errors
/// A [`TextError`], whose message names no path (the caller adds it with its own location
/// format).
pub fn read_text(path: &Path, limit: u64) -> Result<String, TextError> {
    regular_file(path)?;
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(TextError::TooLarge { mib: limit >> 20 });
    }
    String::from_utf8(bytes).map_err(|e| TextError::NotUtf8(not_utf8(e.as_bytes(), e.utf8_error())))
}

/// Why a text input cannot be read ([`read_text`]).
#[derive(Debug, thiserror::Error)]
pub enum TextError {
    /// "is a FIFO, not a regular file" ([`regular_file`]).
    #[error(transparent)]
    NotRegular(#[from] NotRegular),
    /// The operating system's error.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// Larger than the limit for its kind of file.
    #[error("larger than the limit of {mib} MiB for this kind of file")]
    TooLarge {
        /// The limit, MiB.
        mib: u64,
    },
    /// "not UTF-8 text: the first bad byte (0xNN) is at line L, column C" ([`not_utf8`]).
    #[error("{0}")]
    NotUtf8(String),
}

/// "not UTF-8 text: the first bad byte (0xNN) is at line L, column C" for `bytes`, whose
/// decoding failed with `e`.
pub fn not_utf8(bytes: &[u8], e: std::str::Utf8Error) -> String {
    let good = e.valid_up_to();
    let (line, column) = line_column(&bytes[..good]);
    format!(
        "not UTF-8 text: the first bad byte (0x{:02x}) is at line {line}, column {column}",
        bytes.get(good).copied().unwrap_or(0)
    )
}

/// Line and column (from 1, the column in characters) just after the valid UTF-8 `prefix`.
fn line_column(prefix: &[u8]) -> (usize, usize) {
    let text = std::str::from_utf8(prefix).unwrap_or("");
    let line = text.matches('\n').count() + 1;
    let column = text.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
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

    #[test]
    fn a_bad_byte_is_named_by_line_and_column() {
        let dir = std::env::temp_dir().join(format!("paracosm-text-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("bad.star");
        std::fs::write(&f, b"x = 1\ny = \"\xc3\xa9\xff\"\n").unwrap();
        let e = read_text(&f, 1 << 20).unwrap_err().to_string();
        assert!(e.contains("(0xff) is at line 2, column 7"), "{e}");
        std::fs::write(&f, b"0123456789").unwrap();
        let e = read_text(&f, 4).unwrap_err().to_string();
        assert!(e.contains("larger than the limit"), "{e}");
        assert_eq!(read_text(&f, 10).unwrap(), "0123456789");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
