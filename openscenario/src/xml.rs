//! Small helpers over `roxmltree` nodes.

use roxmltree::Node;

use crate::error::XoscError;
use crate::support::Choice;
use crate::text::Text;

/// `node`'s element children.
pub fn elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(Node::is_element)
}

/// `node`'s first element child named `name`.
pub fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    elements(node).find(|c| c.tag_name().name() == name)
}

/// `node`'s element child named `name`, required.
///
/// # Errors
/// [`XoscError::Invalid`] at `node` when it has none.
pub fn need<'a, 'i>(
    text: &Text,
    node: Node<'a, 'i>,
    name: &str,
) -> Result<Node<'a, 'i>, XoscError> {
    child(node, name).ok_or_else(|| {
        text.invalid(
            node,
            format!("<{}> needs a <{name}>", node.tag_name().name()),
        )
    })
}

/// `node`'s single element child, which must be one of what choice group `group` reads
/// (the reader's table, [`crate::support`]), with its name.
///
/// # Errors
/// [`XoscError::Invalid`] when it has none or more than one; [`XoscError::Unsupported`] for
/// another element, naming what is supported (and why, for a member the table refuses).
pub fn choice<'a, 'i>(
    text: &Text,
    node: Node<'a, 'i>,
    group: &Choice,
) -> Result<(Node<'a, 'i>, &'a str), XoscError> {
    let choices = group.read;
    let Some(c) = elements(node).next() else {
        return Err(text.invalid(
            node,
            format!(
                "<{}> is empty; it needs one of {}",
                node.tag_name().name(),
                list(choices)
            ),
        ));
    };
    if let Some(second) = elements(node).nth(1) {
        return Err(text.invalid(
            second,
            format!(
                "<{}> holds one element, not <{}> and <{}>",
                node.tag_name().name(),
                c.tag_name().name(),
                second.tag_name().name()
            ),
        ));
    }
    let name = c.tag_name().name();
    match choices.iter().position(|&k| k == name) {
        Some(_) => Ok((c, name)),
        None => Err(refusal(text, node, c, group)),
    }
}

/// The refusal of element `c`, in `node`, which choice group `group` does not read: why, when
/// the table refuses it, and what is read there.
pub fn refusal(text: &Text, node: Node<'_, '_>, c: Node<'_, '_>, group: &Choice) -> XoscError {
    let name = c.tag_name().name();
    let why = group
        .refused
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(String::new(), |(_, why)| format!(": {why}"));
    text.unsupported(
        c,
        format!(
            "<{name}> in <{}> is not supported{why}; paracosm reads {}",
            node.tag_name().name(),
            list(group.read)
        ),
    )
}

/// `<A>, <B> or <C>`.
pub fn list(names: &[&str]) -> String {
    let tags: Vec<String> = names.iter().map(|n| format!("<{n}>")).collect();
    match tags.len() {
        0 => String::new(),
        1 => tags[0].clone(),
        n => format!("{} or {}", tags[..n - 1].join(", "), tags[n - 1]),
    }
}

/// Refuses any element child of `node` that is not one of `allowed` (the standard's
/// sequence there), so that a misspelt or unsupported element is never passed over.
///
/// # Errors
/// [`XoscError::Unsupported`] at the first other child, naming what is read there.
pub fn only(text: &Text, node: Node<'_, '_>, allowed: &[&str]) -> Result<(), XoscError> {
    match elements(node).find(|c| !allowed.contains(&c.tag_name().name())) {
        None => Ok(()),
        Some(c) => Err(text.unsupported(
            c,
            format!(
                "<{}> in <{}> is not supported; paracosm reads {} there",
                c.tag_name().name(),
                node.tag_name().name(),
                list(allowed)
            ),
        )),
    }
}
