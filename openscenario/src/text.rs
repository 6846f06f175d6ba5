//! One parsed XML file with fast positions: `roxmltree`'s `text_pos_at` walks the text from
//! its start at every call, so a file's line starts are found once and searched. The file is
//! parsed once and the document kept ([`Text::parse`]): the tests of a campaign read one
//! [`Text`] through the campaign's [`crate::FileSet`], and share its parse.

use std::sync::OnceLock;

use roxmltree::{Document, Node};

use crate::error::{Pos, XoscError};

/// The largest OpenSCENARIO file read, bytes (64 MiB): a scenario with a long trajectory is a
/// few MiB; past this the file is refused rather than parsed.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

self_cell::self_cell!(
    /// A parsed document and the copy of the text it borrows (the same bytes as
    /// [`Text::text`], so node offsets are offsets into it).
    struct Parsed {
        owner: Box<str>,
        #[covariant]
        dependent: Document,
    }
    impl {Debug}
);

/// A file's name and text with its line starts, and its parse once made.
#[derive(Debug)]
pub struct Text {
    /// The file as named.
    pub file: String,
    /// Its text.
    pub text: String,
    /// Byte offset of each line's start.
    line_starts: Vec<usize>,
    /// `(byte offset, characters before it)` every [`MARK_BYTES`] bytes or so (each on a
    /// character boundary), from 0: a column is counted from the nearest mark, not from the
    /// line's start, so a file written on one line costs no more than a pretty-printed one.
    char_marks: Vec<(usize, usize)>,
    /// The document of the first [`Text::parse`], or its error.
    parsed: OnceLock<Result<Parsed, XoscError>>,
}

/// The most attributes one element may have in an XML file paracosm reads (OpenSCENARIO or
/// OpenDRIVE): their elements have at most a few dozen. `roxmltree` compares each attribute
/// with every earlier one of its element, so 500,000 attributes on one element took minutes;
/// past this limit the file is refused before it is parsed.
pub const MAX_ATTRIBUTES: usize = 1000;

/// An element with more than [`MAX_ATTRIBUTES`] attributes, found by [`check_breadth`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "an element with more than {max} attributes: paracosm reads at most {max} on one element",
    max = MAX_ATTRIBUTES
)]
pub struct TooManyAttributes {
    /// The byte offset of the element's `<`.
    pub offset: usize,
}

/// Refuses an XML text with an element of more than [`MAX_ATTRIBUTES`] attributes, in one
/// pass over its bytes and before any parser sees it. An attribute is counted at each `=`
/// outside quotes inside a start tag; comments, CDATA sections, processing instructions and
/// the text between elements are skipped, so an `=` in them counts for nothing.
///
/// # Errors
/// [`TooManyAttributes`] with the element's byte offset.
pub fn check_breadth(text: &str) -> Result<(), TooManyAttributes> {
    let b = text.as_bytes();
    let skip_to = |from: usize, end: &[u8]| -> usize {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |i| from + i + end.len())
    };
    let mut i = 0;
    while let Some(lt) = b[i..].iter().position(|&c| c == b'<').map(|p| i + p) {
        let rest = &b[lt..];
        if rest.starts_with(b"<!--") {
            i = skip_to(lt + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(lt + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(lt + 2, b"?>");
        } else {
            let (mut quote, mut count, mut j) = (None, 0, lt + 1);
            while j < b.len() {
                match (quote, b[j]) {
                    (None, b'>') => break,
                    (None, q @ (b'"' | b'\'')) => quote = Some(q),
                    (None, b'=') => count += 1,
                    (Some(q), c) if c == q => quote = None,
                    _ => {}
                }
                j += 1;
            }
            if count > MAX_ATTRIBUTES {
                return Err(TooManyAttributes { offset: lt });
            }
            i = j;
        }
    }
    Ok(())
}

/// The spacing of [`Text`]'s character marks, bytes.
const MARK_BYTES: usize = 1024;

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
        let mut char_marks = vec![(0, 0)];
        let (mut at, mut chars) = (0, 0);
        while at + MARK_BYTES < text.len() {
            let mut next = at + MARK_BYTES;
            while !text.is_char_boundary(next) {
                next += 1;
            }
            chars += text[at..next].chars().count();
            char_marks.push((next, chars));
            at = next;
        }
        Text {
            file: file.into(),
            text,
            line_starts,
            char_marks,
            parsed: OnceLock::new(),
        }
    }

    /// Reads `path` (at most [`MAX_FILE_BYTES`]) through the project's one door for inputs
    /// ([`paracosm_files::read_text`]): only a regular file (or a link to one) is opened, as a
    /// FIFO would block the read and a device (`/dev/zero`) would never end it, and no more
    /// than the limit is read.
    ///
    /// # Errors
    /// [`XoscError::Io`] when the file is missing, not a regular file (naming what it is),
    /// unreadable, not UTF-8 (naming the line and column of the first bad byte) or too large.
    pub fn read(path: &std::path::Path) -> Result<Self, XoscError> {
        let file = path.display().to_string();
        let text = paracosm_files::read_text(path, MAX_FILE_BYTES).map_err(|e| XoscError::Io {
            file: file.clone(),
            reason: e.to_string(),
        })?;
        Ok(Text::new(file, text))
    }

    /// The number of characters before byte `offset` (a character boundary), counted from
    /// the nearest mark below it.
    fn chars_before(&self, offset: usize) -> usize {
        let i = self
            .char_marks
            .partition_point(|&(b, _)| b <= offset)
            .max(1)
            - 1;
        let (b, chars) = self.char_marks[i];
        chars + self.text.get(b..offset).map_or(0, |s| s.chars().count())
    }

    /// The position of byte `offset`: its line found by bisection, its column from the
    /// nearest character mark (both cost at most `log n + MARK_BYTES`).
    pub fn pos_at(&self, offset: usize) -> Pos {
        let offset = offset.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = self.line_starts[line - 1];
        let col = if self.text.is_char_boundary(offset) {
            self.chars_before(offset) - self.chars_before(start) + 1
        } else {
            1
        };
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

    /// The text's document (DTDs refused, as the standard has none): parsed at the first call
    /// and kept, so every later call (each test of a campaign that reads this file) costs
    /// nothing. The text is not to be changed after the first call.
    ///
    /// # Errors
    /// [`XoscError::Xml`] with the parser's position when the text is not well-formed;
    /// [`XoscError::Invalid`] for an element of more than [`MAX_ATTRIBUTES`] attributes (the
    /// same error at every call).
    pub fn parse(&self) -> Result<&Document<'_>, XoscError> {
        let parsed = self.parsed.get_or_init(|| {
            Parsed::try_new(self.text.clone().into_boxed_str(), |text| {
                self.parse_text(text)
            })
        });
        match parsed {
            Ok(p) => Ok(p.borrow_dependent()),
            Err(e) => Err(e.clone()),
        }
    }

    /// Parses `text` (this file's text) as [`Text::parse`] does.
    fn parse_text<'t>(&self, text: &'t str) -> Result<Document<'t>, XoscError> {
        check_breadth(text).map_err(|e| XoscError::Invalid {
            pos: self.pos_at(e.offset),
            reason: e.to_string(),
        })?;
        let opts = roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        };
        Document::parse_with_options(text, opts).map_err(|e| {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A text is parsed once: every call returns the one document, whose node offsets are
    /// offsets into the text (positions read as before); a text that is not well-formed gives
    /// the same error at every call.
    #[test]
    fn a_text_is_parsed_once_and_its_document_shared() {
        let text = Text::new("a.xosc", "\u{feff}<A>\n  <B x=\"1\"/>\n</A>\n");
        let first = text.parse().unwrap();
        let second = text.parse().unwrap();
        assert!(std::ptr::eq(first, second));
        let b = first.root_element().first_element_child().unwrap();
        let pos = text.attr_pos(b, "x");
        assert_eq!((pos.line, pos.col), (2, 9));
        let shared = std::sync::Arc::new(Text::new("b.xosc", "<A><B></A>"));
        let errors: Vec<XoscError> = (0..2)
            .map(|_| {
                let t = shared.clone();
                std::thread::spawn(move || t.parse().map(drop).unwrap_err())
                    .join()
                    .unwrap()
            })
            .collect();
        assert_eq!(errors[0], errors[1]);
        assert!(
            matches!(errors[0], XoscError::Xml { .. }),
            "{:?}",
            errors[0]
        );
    }

    /// Columns counted from the character marks equal a count from the line's start, on a
    /// long line of multi-byte characters and across line breaks.
    #[test]
    fn columns_from_the_marks_equal_a_count_from_the_line_start() {
        let mut s = String::new();
        for i in 0..3000 {
            s.push_str(if i % 7 == 0 { "é€ " } else { "ab " });
            if i % 1000 == 999 {
                s.push('\n');
            }
        }
        let t = Text::new("f.xosc", s.clone());
        for (offset, _) in s.char_indices().step_by(37) {
            let line_start = s[..offset].rfind('\n').map_or(0, |i| i + 1);
            let col = s[line_start..offset].chars().count() + 1;
            let line = s[..offset].matches('\n').count() + 1;
            let p = t.pos_at(offset);
            assert_eq!(
                (p.line, p.col),
                (line as u32, col as u32),
                "at byte {offset}"
            );
        }
        assert_eq!(t.pos_at(s.len()).line, 4);
    }

    /// An element's attributes are counted at each `=` outside quotes of its start tag;
    /// comments, CDATA, processing instructions, text and quoted values do not count.
    #[test]
    fn an_element_with_too_many_attributes_is_found_in_one_pass() {
        let attrs = |n: usize| -> String { (0..n).map(|i| format!(" a{i}=\"1\"")).collect() };
        let fine = format!(
            "<?xml version=\"1.0\"?><!-- {} --><r{}><![CDATA[{}]]>{}<e v=\"{}\"/></r>",
            "=".repeat(5000),
            attrs(MAX_ATTRIBUTES),
            "=".repeat(5000),
            "=".repeat(5000),
            "=".repeat(5000)
        );
        assert_eq!(check_breadth(&fine), Ok(()));
        let wide = format!("<r><x/><e{}/></r>", attrs(MAX_ATTRIBUTES + 1));
        assert_eq!(check_breadth(&wide), Err(TooManyAttributes { offset: 7 }));
        let t = Text::new("w.xosc", wide);
        let e = t.parse().unwrap_err().to_string();
        assert!(
            e.starts_with("w.xosc:1:8: an element with more than 1000"),
            "{e}"
        );
    }
}
