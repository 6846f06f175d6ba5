//! Helpers shared by the command-line integration tests.
#![allow(dead_code)] // each test crate uses its own subset

use std::process::{Command, Output};

use paracosm_generators::{Assignment, Domain, ParamSpace, Point, Value};

/// Runs `paracosm-fuzz` with `args` (with a runtime folder for Mesa, which wants one).
pub fn fuzz(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("paracosm-fuzz runs")
}

/// The lines of `dir/results.jsonl` without their `wall_ms` (the one field that depends on
/// the machine), for comparing runs.
pub fn comparable(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| l[..l.rfind(",\"wall_ms\":").unwrap()].to_owned())
        .collect()
}

/// Every record of `dir/results.jsonl`, as JSON, in file order.
pub fn records(dir: &std::path::Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Runs `paracosm-fuzz FILE --budget BUDGET --out OUT`.
pub fn campaign(file: &std::path::Path, budget: &str, out: &std::path::Path) -> Output {
    fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        budget,
        "--out",
        out.to_str().unwrap(),
    ])
}

/// A line of `results.jsonl` as JSON without `wall_ms` and without the campaign tag, for
/// comparing the records of two different campaigns (two programs that must behave alike);
/// the tag is checked to be there (16 hex digits) first.
pub fn untagged_record(line: &str) -> serde_json::Value {
    let mut r: serde_json::Value = serde_json::from_str(line).unwrap();
    let o = r.as_object_mut().unwrap();
    o.remove("wall_ms");
    let tag = o
        .remove("campaign")
        .expect("each record carries its campaign's tag");
    let tag = tag.as_str().unwrap();
    assert!(
        tag.len() == 16 && tag.bytes().all(|b| b.is_ascii_hexdigit()),
        "{tag}"
    );
    r
}

/// Asserts the exit code, showing stdout and stderr when it differs.
pub fn expect_code(o: &Output, code: i32) {
    assert_eq!(
        o.status.code(),
        Some(code),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Asserts that a run finished: exit 0 (all passed) or 1 (a test failed), not an error.
pub fn ran(o: &Output) {
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The assignment with the given values by name (levels by value, intervals by value), the
/// others at their lowest.
pub fn assign(space: &ParamSpace, values: &[(&str, Value)]) -> Assignment {
    let mut point = Point {
        discrete: Vec::new(),
        continuous: Vec::new(),
    };
    for p in space.params() {
        let given = values.iter().find(|(n, _)| *n == p.name).map(|(_, v)| v);
        match &p.domain {
            Domain::Interval { lo, hi } => {
                let x = given.and_then(Value::as_f64).unwrap_or(*lo);
                point.continuous.push((x - lo) / (hi - lo));
            }
            Domain::Levels(levels) => {
                let i = given.map_or(0, |v| levels.iter().position(|l| l == v).unwrap());
                point.discrete.push(i as u32);
            }
        }
    }
    space.decode(&point).unwrap()
}

/// The one test of a scenario without open parameters.
pub fn no_params(s: &paracosm_scenarios::Scenario) -> Assignment {
    s.space()
        .decode(&Point {
            discrete: vec![],
            continuous: vec![],
        })
        .unwrap()
}
