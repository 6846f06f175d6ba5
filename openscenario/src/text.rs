//! One parsed XML file with fast positions: `roxmltree`'s `text_pos_at` walks the text from
//! its start at every call, so a file's line starts are found once and searched.

use roxmltree::{Document, Node};

use crate::error::{Pos, XoscError};

/// The largest OpenSCENARIO file read, bytes (64 MiB): a scenario with a long trajectory is a
/// few MiB; past this the file is refused rather than parsed.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// A file's name and text with its line starts.
#[derive(Debug)]
pub struct Text {
    /// The file as named.
    pub file: String,
    /// Its text.
    pub text: String,
    /// Byte offset of each line's start.
    line_starts: Vec<usize>,
}

impl Text {
    /// `text`, named `file`.
    pub fn new(file: impl Into<String>, text: impl Into<String>) -> Self {
        let mut text: String = text.into();
        // A byte-order mark (the ALKS files have one) is not part of the document.
        if text.starts_with('\u{feff}') {
            text.drain(..'\u{feff}'.len_utf8());
        }
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Text {
            file: file.into(),
            text,
            line_starts,
        }
    }

    /// Reads `path` (at most [`MAX_FILE_BYTES`]). Only a regular file (or a link to one) is
    /// opened: a FIFO would block the read, a device (`/dev/zero`) would never end it.
    ///
    /// # Errors
    /// [`XoscError::Io`] when the file is missing, not a regular file, unreadable, not UTF-8
    /// or too large.
    pub fn read(path: &std::path::Path) -> Result<Self, XoscError> {
        use std::io::Read;
        let file = path.display().to_string();
        let io = |reason: String| XoscError::Io {
            file: file.clone(),
            reason,
        };
        let meta = std::fs::metadata(path).map_err(|e| io(e.to_string()))?;
        if !meta.is_file() {
            return Err(io(
                "not a regular file (a folder, a FIFO or a device): an OpenSCENARIO file is \
                 read from a regular file"
                    .into(),
            ));
        }
        let len = meta.len();
        if len > MAX_FILE_BYTES {
            return Err(io(format!(
                "{len} bytes, more than the {MAX_FILE_BYTES} an OpenSCENARIO file may have"
            )));
        }
        // The file may grow between the size check and the read: read at most one byte more
        // than the limit, and refuse it if it is there.
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| io(e.to_string()))?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(io(format!(
                "more than the {MAX_FILE_BYTES} bytes an OpenSCENARIO file may have"
            )));
        }
        let text = String::from_utf8(bytes)
            .map_err(|e| io(format!("not UTF-8 text ({})", e.utf8_error())))?;
        Ok(Text::new(file, text))
    }

    /// The position of byte `offset`.
    pub fn pos_at(&self, offset: usize) -> Pos {
        let line = self.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = self.line_starts[line - 1];
        let col = self
            .text
            .get(start..offset.min(self.text.len()))
            .map_or(1, |s| s.chars().count() + 1);
        Pos {
            file: self.file.clone(),
            line: line as u32,
            col: col as u32,
        }
    }

    /// The position of `node`'s start.
    pub fn pos(&self, node: Node<'_, '_>) -> Pos {
        self.pos_at(node.range().start)
    }

    /// The position of `node`'s attribute `name` (its value's start), or of the node when it
    /// has no such attribute.
    pub fn attr_pos(&self, node: Node<'_, '_>, name: &str) -> Pos {
        node.attribute_node(name)
            .map_or_else(|| self.pos(node), |a| self.pos_at(a.range_value().start))
    }

    /// Parses the text (DTDs refused, as the standard has none).
    ///
    /// # Errors
    /// [`XoscError::Xml`] with the parser's position when the text is not well-formed.
    pub fn parse(&self) -> Result<Document<'_>, XoscError> {
        let opts = roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        };
        Document::parse_with_options(&self.text, opts).map_err(|e| {
            let p = e.pos();
            XoscError::Xml {
                pos: Pos {
                    file: self.file.clone(),
                    line: p.row,
                    col: p.col,
                },
                reason: e.to_string(),
            }
        })
    }

    /// The root element of `doc` (this text parsed), which must be `<OpenSCENARIO>`.
    ///
    /// # Errors
    /// [`XoscError::Invalid`] at the root for any other element.
    pub fn open_root<'a, 'i>(&self, doc: &'a Document<'i>) -> Result<Node<'a, 'i>, XoscError> {
        let root = doc.root_element();
        if root.tag_name().name() != "OpenSCENARIO" {
            return Err(self.invalid(
                root,
                format!(
                    "the root element is <{}>; an OpenSCENARIO file's is <OpenSCENARIO>",
                    root.tag_name().name()
                ),
            ));
        }
        Ok(root)
    }

    /// An [`XoscError::Invalid`] at `node`.
    pub fn invalid(&self, node: Node<'_, '_>, reason: impl Into<String>) -> XoscError {
        XoscError::Invalid {
            pos: self.pos(node),
            reason: reason.into(),
        }
    }

    /// An [`XoscError::Unsupported`] at `node`.
    pub fn unsupported(&self, node: Node<'_, '_>, reason: impl Into<String>) -> XoscError {
        XoscError::Unsupported {
            pos: self.pos(node),
            reason: reason.into(),
        }
    }
}
