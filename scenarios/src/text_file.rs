//! Reading a text input (a program, a space, a CSV) with a size limit and a UTF-8 check that
//! names the line and column of the first bad byte.

use std::io::Read;
use std::path::Path;

/// Largest program, space or model file read, bytes (64 MiB).
pub const MAX_SOURCE_BYTES: u64 = 64 << 20;
/// Largest data file (a CSV of points) read, bytes (1 GiB).
pub const MAX_DATA_BYTES: u64 = 1 << 30;

/// Reads `path` as UTF-8 text of at most `limit` bytes. A path that is not a regular file
/// (a FIFO, which would block; a device; a directory) is refused before it is opened.
///
/// # Errors
/// A [`TextError`], whose message names no path (the caller adds it with its own location
/// format).
pub fn read_text(path: &Path, limit: u64) -> Result<String, TextError> {
    paracosm_engine::files::regular_file(path)?;
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
    /// "is a FIFO, not a regular file" ([`paracosm_engine::files::regular_file`]).
    #[error(transparent)]
    NotRegular(#[from] paracosm_engine::files::NotRegular),
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
    fn a_bad_byte_is_named_by_line_and_column() {
        let dir = std::env::temp_dir().join(format!("paracosm-text-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("bad.star");
        std::fs::write(&f, b"x = 1\ny = \"\xc3\xa9\xff\"\n").unwrap();
        let e = read_text(&f, MAX_SOURCE_BYTES).unwrap_err().to_string();
        assert!(e.contains("(0xff) is at line 2, column 7"), "{e}");
        std::fs::write(&f, b"0123456789").unwrap();
        let e = read_text(&f, 4).unwrap_err().to_string();
        assert!(e.contains("larger than the limit"), "{e}");
        assert_eq!(read_text(&f, 10).unwrap(), "0123456789");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
