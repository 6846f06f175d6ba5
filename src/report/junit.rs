//! JUnit XML for CI systems (Jenkins, GitLab): one test case per generated test; failed tests
//! carry their monitor verdicts, parameters and the replay command; errors their message.

use std::path::Path;

use quick_xml::events::{BytesDecl, BytesText};
use quick_xml::Writer;

use crate::export::replay::replay_command;
use crate::record::{RunRecord, Status};

fn params(r: &RunRecord) -> String {
    match &r.params {
        Some(a) => a
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(", "),
        None => "(point does not decode)".into(),
    }
}

/// Writes `case` with one child `<tag message=.. type=..>text</tag>`: a failure or an error.
fn outcome<W: std::io::Write>(
    case: quick_xml::writer::ElementWriter<'_, W>,
    tag: &str,
    kind: &str,
    message: &str,
    text: &str,
) -> std::io::Result<()> {
    case.write_inner_content(|w| {
        w.create_element(tag)
            .with_attribute(("message", message))
            .with_attribute(("type", kind))
            .write_text_content(BytesText::new(text))?;
        Ok(())
    })?;
    Ok(())
}

fn verdicts(r: &RunRecord) -> String {
    r.monitors
        .iter()
        .map(|(n, m)| {
            format!(
                "{n}: {} (robustness {})",
                if m.passed { "passed" } else { "FAILED" },
                m.robustness
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The JUnit XML document for `records` of scenario `scenario` written in folder `out`.
pub fn render(scenario: &str, records: &[RunRecord], out: &Path) -> String {
    let failures = records.iter().filter(|r| r.status == Status::Fail).count();
    let errors = records.iter().filter(|r| r.status == Status::Error).count();
    let seconds = |ms: f64| format!("{:.3}", ms / 1e3);
    let total_ms: f64 = records.iter().map(|r| r.wall_ms).sum();
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    let counts = [
        ("tests", records.len().to_string()),
        ("failures", failures.to_string()),
        ("errors", errors.to_string()),
        ("time", seconds(total_ms)),
    ];
    let suite_name = format!("paracosm.{scenario}");
    let result = w
        .write_event(quick_xml::events::Event::Decl(BytesDecl::new(
            "1.0",
            Some("UTF-8"),
            None,
        )))
        .and_then(|()| {
            w.create_element("testsuites")
                .with_attributes(counts.iter().map(|(k, v)| (*k, v.as_str())))
                .write_inner_content(|w| {
                    w.create_element("testsuite")
                        .with_attribute(("name", suite_name.as_str()))
                        .with_attributes(counts.iter().map(|(k, v)| (*k, v.as_str())))
                        .write_inner_content(|w| {
                            for r in records {
                                let name = format!("test {} ({})", r.id, params(r));
                                let time = seconds(r.wall_ms);
                                let case = w
                                    .create_element("testcase")
                                    .with_attribute(("classname", suite_name.as_str()))
                                    .with_attribute(("name", name.as_str()))
                                    .with_attribute(("time", time.as_str()));
                                match r.status {
                                    Status::Pass => {
                                        case.write_empty()?;
                                    }
                                    Status::Fail => {
                                        let message = verdicts(r);
                                        let body = format!(
                                            "falsified: {message}\nparameters: {}\nseed: {}\nreplay: {}",
                                            params(r),
                                            r.seed,
                                            replay_command(out, r.id)
                                        );
                                        outcome(case, "failure", "falsified", &message, &body)?;
                                    }
                                    Status::Error => {
                                        let message = r.error.clone().unwrap_or_default();
                                        outcome(case, "error", "error", &message, &message)?;
                                    }
                                }
                            }
                            Ok(())
                        })?;
                    Ok(())
                })
                .map(|_| ())
        });
    result.expect("writing XML into memory cannot fail");
    String::from_utf8(w.into_inner()).expect("quick-xml writes UTF-8") + "\n"
}

/// Writes [`render`]'s document to `path` (through a temporary file and a rename).
///
/// # Errors
/// [`crate::Error::Write`] naming `path` when it cannot be written.
pub fn write(
    path: &Path,
    scenario: &str,
    records: &[RunRecord],
    out: &Path,
) -> Result<(), crate::Error> {
    crate::atomic::write(path, render(scenario, records, out).as_bytes())
}
