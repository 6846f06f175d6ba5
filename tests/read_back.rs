//! Everything paracosm writes as JSON reads back equal. The workspace's serde_json has the
//! `arbitrary_precision` feature (starlark turns it on), under which serde's buffered forms
//! (untagged and internally tagged enums, flattened structs) do not see numbers as numbers:
//! these round trips fail if one of them is derived again.

mod common;

use common::{expect_code, fuzz};
use paracosm::campaign::file::SutChoice;
use paracosm_engine::rx::Value as StreamValue;
use paracosm_engine::sut::{AebConfig, VisionConfig};
use paracosm_generators::{Domain, Param, ParamSpace, Value};
use serde::{de::DeserializeOwned, Serialize};
use std::fmt::Debug;

fn round_trip<T: Serialize + DeserializeOwned + PartialEq + Debug>(x: &T) {
    let text = serde_json::to_string(x).unwrap();
    let back: T = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"));
    assert_eq!(&back, x, "{text}");
}

#[test]
fn a_space_with_levels_of_every_kind_reads_back() {
    let space = ParamSpace::new(vec![
        Param {
            name: "friction".into(),
            domain: Domain::Levels(vec![Value::Real(0.4), Value::Real(0.8)]),
            unit: None,
            density: None,
        },
        Param {
            name: "lanes".into(),
            domain: Domain::Levels(vec![Value::Int(2), Value::Int(-4)]),
            unit: None,
            density: None,
        },
        Param {
            name: "colour".into(),
            domain: Domain::Levels(vec![Value::Text("red".into()), Value::Text("true".into())]),
            unit: None,
            density: None,
        },
        Param {
            name: "oncoming".into(),
            domain: Domain::Levels(vec![Value::Bool(true), Value::Bool(false)]),
            unit: None,
            density: None,
        },
        Param::interval("speed", 0.5, 2.5, "m/s"),
    ])
    .unwrap();
    round_trip(&space);
    // An integer level stays an integer, a real that is whole stays a real.
    let v: Vec<Value> = serde_json::from_str("[3, 3.0, 1e-3, \"x\"]").unwrap();
    assert_eq!(
        v,
        [
            Value::Int(3),
            Value::Real(3.0),
            Value::Real(1e-3),
            Value::Text("x".into())
        ]
    );
    // A bool level is a bool; a text "true" stays a text.
    assert_eq!(
        serde_json::from_str::<Value>("true").unwrap(),
        Value::Bool(true)
    );
    assert_eq!(
        serde_json::from_str::<Value>("\"true\"").unwrap(),
        Value::Text("true".into())
    );
    assert!(serde_json::from_str::<Value>("[1]").is_err());
}

#[test]
fn systems_under_test_and_their_settings_read_back() {
    round_trip(&SutChoice::Command {
        command: vec!["python3".into(), "sut.py".into()],
        timeout_s: 2.5,
        reuse: true,
    });
    round_trip(&SutChoice::Builtin { name: "aeb".into() });
    round_trip(&AebConfig::default());
    round_trip(&VisionConfig::default());
}

#[test]
fn stream_values_read_back() {
    for v in [
        StreamValue::Unit,
        StreamValue::Num(0.25),
        StreamValue::Bool(true),
        StreamValue::Vec3([1.5, 0.0, -2.0]),
        StreamValue::Tuple(vec![StreamValue::Num(1.0), StreamValue::Text("a".into())]),
        StreamValue::Text("red".into()),
    ] {
        round_trip(&v);
    }
}

/// A campaign whose parameters have real, integer, text and bool levels can be reported,
/// replayed and resumed: each reads `campaign.json` and `results.jsonl` back.
#[test]
fn a_campaign_with_levels_of_every_kind_is_reported_replayed_and_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("levels.star");
    std::fs::write(
        &file,
        "w = World()\n\
         r = RoadSegment(len = 200.0, nlanes = VarEnum([2, 4]), friction = VarEnum([0.4, 0.8]))\n\
         v = AutonomousVehicle(loc = r.onLane(1, 10), speed = VarInterval(5.0, 10.0))\n\
         lead = Car(loc = r.onLane(1, 60), color = VarEnum([\"red\", \"white\"]), enabled = VarEnum([True, False]))\n\
         w.place(r, v, lead)\n\
         CollisionMonitor(v)\n\
         test(horizon = 2.0)\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let (file, out_s) = (file.to_str().unwrap(), out.to_str().unwrap());
    let o = fuzz(&[file, "--budget", "6", "--out", out_s]);
    assert!(o.status.code().is_some_and(|c| c <= 1), "{o:?}");
    let results = out.join("results.jsonl");
    let report = fuzz(&["report", out_s]);
    expect_code(&report, o.status.code().unwrap());
    assert!(
        String::from_utf8_lossy(&report.stdout).contains("6 of 6"),
        "{report:?}"
    );
    let replay = fuzz(&["replay", "--id", "3", results.to_str().unwrap()]);
    expect_code(&replay, 0);
    // As after a kill: two records lost; --resume runs them again.
    let full = std::fs::read_to_string(&results).unwrap();
    let kept: String = full.lines().take(4).map(|l| format!("{l}\n")).collect();
    std::fs::write(&results, kept).unwrap();
    let resumed = fuzz(&[file, "--budget", "6", "--out", out_s, "--resume"]);
    expect_code(&resumed, o.status.code().unwrap());
    let again = std::fs::read_to_string(&results).unwrap();
    let no_wall = |t: &str| -> Vec<serde_json::Value> {
        t.lines()
            .map(|l| {
                let mut r: serde_json::Value = serde_json::from_str(l).unwrap();
                r.as_object_mut().unwrap().remove("wall_ms");
                r
            })
            .collect()
    };
    assert_eq!(no_wall(&again), no_wall(&full));
    assert!(full.contains("\"r.friction\":0.8"), "{full}");
}

/// A record whose status contradicts its verdicts (a line edited to read `pass` beside a
/// failed monitor) is refused where results are read back, naming its line: `report` counted
/// it as passed, and `--resume` and `merge` accepted it.
#[test]
fn a_record_whose_status_contradicts_its_monitors_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let text = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let n = text
        .lines()
        .position(|l| l.contains("\"status\":\"fail\""))
        .unwrap();
    let flipped: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let l = if i == n {
                l.replace("\"status\":\"fail\"", "\"status\":\"pass\"")
            } else {
                l.to_owned()
            };
            l + "\n"
        })
        .collect();
    std::fs::write(out.join("results.jsonl"), &flipped).unwrap();
    for args in [
        vec!["report", out.to_str().unwrap()],
        vec!["--resume", "--out", out.to_str().unwrap()],
    ] {
        let o = fuzz(&args);
        expect_code(&o, 2);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains(&format!("results.jsonl:{}:", n + 1))
                && stderr.contains("`status` is \"pass\" but monitor `collision` failed"),
            "{args:?}: {stderr}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(out.join("results.jsonl")).unwrap(),
        flipped
    );
}

/// A replay after the program was edited says so: the verdict it prints comes from the
/// program as it is now (a "DIFFERS" alone read as a reproducibility failure).
#[test]
fn a_replay_of_an_edited_program_names_the_change() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("p.star");
    let src = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pedestrian_crossing.star"),
    )
    .unwrap();
    std::fs::write(&file, &src).unwrap();
    let out = dir.path().join("o");
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        "30",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let results = out.join("results.jsonl");
    let o = fuzz(&["replay", results.to_str().unwrap(), "--id", "0"]);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        stdout.contains("equals the recorded one") && !stdout.contains("changed since"),
        "{stdout}"
    );
    std::fs::write(&file, format!("{src}\n# edited\n")).unwrap();
    let o = fuzz(&["replay", results.to_str().unwrap(), "--id", "0"]);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        stdout.contains("changed since the campaign ran"),
        "{stdout}"
    );
}
