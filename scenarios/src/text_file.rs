//! Reading a text input (a program, a space, a CSV) with a size limit and a UTF-8 check that
//! names the line and column of the first bad byte: the project's one door for inputs,
//! [`paracosm_files`], with the limits of each kind of file.

/// Largest program, space or model file read, bytes (64 MiB).
pub const MAX_SOURCE_BYTES: u64 = 64 << 20;
/// Largest data file (a CSV of points) read, bytes (1 GiB).
pub const MAX_DATA_BYTES: u64 = 1 << 30;

pub use paracosm_files::{not_utf8, read_text, TextError};
