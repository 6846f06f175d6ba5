//! Errors of reading an OpenSCENARIO file: every one names the file, the line and column of
//! the element or attribute at fault, and what is wrong or what is supported instead.

use std::fmt;

/// Where in a file: 1-based line and column (columns count characters).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pos {
    /// The file as the user named it (or as a variation file names it).
    pub file: String,
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1.
    pub col: u32,
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// What went wrong reading an OpenSCENARIO file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum XoscError {
    /// The file cannot be read (missing, unreadable, too large).
    #[error("{file}: {reason}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        reason: String,
    },
    /// The text is not well-formed XML.
    #[error("{pos}: not well-formed XML: {reason}")]
    Xml {
        /// Where the parser stopped.
        pos: Pos,
        /// The parser's message.
        reason: String,
    },
    /// An element or attribute paracosm does not support, or one the standard does not know,
    /// with what is supported there.
    #[error("{pos}: {reason}")]
    Unsupported {
        /// The element or attribute.
        pos: Pos,
        /// What it is and what is supported instead.
        reason: String,
    },
    /// A value that is wrong: a missing required attribute, a number that is not one, a
    /// parameter that is not declared, a circular reference, an expression that fails
    /// (dividing by zero), a constraint a value breaks.
    #[error("{pos}: {reason}")]
    Invalid {
        /// The element or attribute.
        pos: Pos,
        /// What is wrong.
        reason: String,
    },
}

impl XoscError {
    /// Where the error is, when it is in a file's text.
    pub fn pos(&self) -> Option<&Pos> {
        match self {
            XoscError::Io { .. } => None,
            XoscError::Xml { pos, .. }
            | XoscError::Unsupported { pos, .. }
            | XoscError::Invalid { pos, .. } => Some(pos),
        }
    }
}
