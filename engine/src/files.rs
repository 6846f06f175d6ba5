//! Input files: what paracosm reads a program, a map, a model, a CSV or a results file from
//! must be a regular file (after following links); the checks are the project's one door for
//! inputs, [`paracosm_files`], re-exported here for the engine's own readers (a model, its
//! manifest).

pub use paracosm_files::{kind_of, not_regular, regular_file, NotRegular};
