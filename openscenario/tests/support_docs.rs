//! docs/openscenario.md's lists of what the reader reads, refuses and notes are the reader's
//! own tables (`paracosm_openscenario::support`), rendered: this test fails when they differ.
//! `PARACOSM_BLESS=1 cargo test -p paracosm-openscenario --test support_docs` rewrites them.

use std::path::PathBuf;

const BEGIN: &str = "<!-- support tables: begin -->";
const END: &str = "<!-- support tables: end -->";

#[test]
fn the_docs_lists_are_the_readers_tables() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/openscenario.md");
    let text = std::fs::read_to_string(&path).unwrap();
    let (Some(b), Some(e)) = (text.find(BEGIN), text.find(END)) else {
        panic!("{} has no {BEGIN} ... {END} block", path.display());
    };
    let have = &text[b + BEGIN.len()..e];
    let want = format!("\n{}", paracosm_openscenario::support::markdown());
    if have == want {
        return;
    }
    if std::env::var_os("PARACOSM_BLESS").is_some() {
        let new = format!("{}{}{}", &text[..b + BEGIN.len()], want, &text[e..]);
        std::fs::write(&path, new).unwrap();
        return;
    }
    panic!(
        "docs/openscenario.md's support tables differ from the reader's (rerun with \
         PARACOSM_BLESS=1 to rewrite them):\n--- docs\n{have}\n--- reader\n{want}"
    );
}

/// Each table is the schema's: no member is both read and refused, none twice, and every
/// note names what it notes.
#[test]
fn each_choice_group_lists_a_member_once() {
    use paracosm_openscenario::support::{CHOICES, NOTED};
    for c in CHOICES {
        let mut all: Vec<&str> = c.read.to_vec();
        all.extend(c.refused.iter().map(|(n, _)| *n));
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n, "{} lists a member twice", c.parent);
        assert!(c.refused.iter().all(|(_, why)| !why.is_empty()));
    }
    assert!(NOTED
        .iter()
        .all(|n| !n.what.is_empty() && !n.note.is_empty()));
}
