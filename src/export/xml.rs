//! A small element tree, serialised by quick-xml (which escapes attribute values): the
//! OpenSCENARIO and OpenDRIVE writers build one and write it out.

use quick_xml::events::{BytesDecl, Event};
use quick_xml::Writer;

/// One XML element: its name, attributes in order, and children.
#[derive(Debug, Clone, PartialEq)]
pub struct El {
    /// The tag.
    pub name: String,
    /// `(name, value)` pairs, written in order.
    pub attrs: Vec<(String, String)>,
    /// Child elements, in order.
    pub children: Vec<El>,
}

impl El {
    /// An element with no attributes or children.
    pub fn new(name: &str) -> El {
        El {
            name: name.to_owned(),
            attrs: Vec::new(),
            children: Vec::new(),
        }
    }

    /// `self` with attribute `key="value"`.
    pub fn attr(mut self, key: &str, value: impl ToString) -> El {
        self.attrs.push((key.to_owned(), value.to_string()));
        self
    }

    /// `self` with a number attribute, written with up to 6 decimals (µm, µrad).
    pub fn num(self, key: &str, value: f64) -> El {
        let text = format!("{value:.6}");
        let text = text.trim_end_matches('0').trim_end_matches('.');
        let text = if text == "-0" { "0" } else { text };
        self.attr(key, text)
    }

    /// `self` with a number attribute written exactly: the shortest text that reads back as
    /// the same `f64` (a replay places each entity where the test had it, bit for bit).
    pub fn exact(self, key: &str, value: f64) -> El {
        let value = if value == 0.0 { 0.0 } else { value };
        self.attr(key, format!("{value}"))
    }

    /// `self` with `child` appended.
    pub fn child(mut self, child: El) -> El {
        self.children.push(child);
        self
    }

    /// `self` with `children` appended.
    pub fn children(mut self, children: impl IntoIterator<Item = El>) -> El {
        self.children.extend(children);
        self
    }

    fn write(&self, w: &mut Writer<Vec<u8>>) -> std::io::Result<()> {
        let attrs = self.attrs.iter().map(|(k, v)| (k.as_str(), v.as_str()));
        let e = w.create_element(self.name.as_str()).with_attributes(attrs);
        if self.children.is_empty() {
            e.write_empty()?;
        } else {
            e.write_inner_content(|w| {
                for c in &self.children {
                    c.write(w)?;
                }
                Ok(())
            })?;
        }
        Ok(())
    }

    /// The document: an XML declaration, then `self` as its root, indented by 2.
    pub fn document(&self) -> String {
        let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
        let written = w
            .write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
            .and_then(|()| self.write(&mut w));
        written.expect("writing to memory does not fail");
        let mut text = String::from_utf8(w.into_inner()).expect("the tree is UTF-8");
        text.push('\n');
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_are_escaped_and_numbers_trimmed() {
        let doc = El::new("a")
            .attr("name", "x<\"y\">&")
            .num("v", 1.5)
            .num("w", -0.0000001)
            .child(El::new("b"))
            .document();
        assert!(
            doc.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>"),
            "{doc}"
        );
        assert!(
            doc.contains("name=\"x&lt;&quot;y&quot;&gt;&amp;\""),
            "{doc}"
        );
        assert!(
            doc.contains("v=\"1.5\"") && doc.contains("w=\"0\""),
            "{doc}"
        );
        assert!(doc.contains("<b/>"), "{doc}");
    }
}
