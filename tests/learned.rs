//! Learned systems under test from the command line (issue 20, requirements 2 and 3):
//! `--sut pilotnet` (the shipped network) and `--sut-onnx MODEL` run in process, give the same
//! records for any `--jobs`, are fingerprinted by the model's bytes, and a model without its
//! manifest is refused before any test.

use std::path::{Path, PathBuf};

mod common;
use common::{comparable, expect_code, fuzz};

fn shipped(ext: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("assets/models/pilotnet.{ext}"))
}

#[test]
fn the_shipped_network_drives_and_its_records_do_not_depend_on_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let run = |jobs: &str| {
        let out = dir.path().join(format!("jobs{jobs}"));
        let o = fuzz(&[
            "pedestrian-crossing",
            "--sut",
            "pilotnet",
            "--budget",
            "6",
            "--seed",
            "2",
            "--jobs",
            jobs,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            matches!(o.status.code(), Some(0 | 1)),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        out
    };
    let (a, b) = (run("1"), run("2"));
    let lines = comparable(&a);
    assert_eq!(lines.len(), 6);
    assert_eq!(lines, comparable(&b));
    assert!(
        lines.iter().all(|l| !l.contains("\"status\":\"error\"")),
        "{lines:?}"
    );
    let campaign = std::fs::read_to_string(a.join("campaign.json")).unwrap();
    assert!(campaign.contains("\"pilotnet\""), "{campaign}");
    // The network drives: past the crossing at 100 m (95 m from its start), in every test
    // that does not end in a collision, and it keeps its lane.
    for l in &lines {
        let v: serde_json::Value = serde_json::from_str(&format!("{l}}}")).unwrap();
        let d = v["metrics"]["distance_travelled_m"].as_f64().unwrap();
        let collided = v["monitors"]["collision"]["passed"] == false;
        assert!(collided || d > 95.0, "{l}");
        assert_eq!(v["monitors"]["offroad"]["passed"], true, "{l}");
    }
}

#[test]
fn a_model_file_is_fingerprinted_and_refused_without_its_manifest_or_when_changed() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("driver.onnx");
    std::fs::copy(shipped("onnx"), &model).unwrap();
    // No manifest beside it: refused before any test.
    let out = dir.path().join("run");
    let args = |budget: &'static str, resume: bool| {
        let mut a = vec![
            "pedestrian-crossing".to_owned(),
            "--sut-onnx".into(),
            model.display().to_string(),
            "--budget".into(),
            budget.into(),
            "--out".into(),
            out.display().to_string(),
        ];
        if resume {
            a.push("--resume".into());
        }
        a
    };
    let call = |a: Vec<String>| fuzz(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = call(args("2", false));
    expect_code(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--sut-onnx") && err.contains("driver.toml"),
        "{err}"
    );
    assert!(!out.join("results.jsonl").exists());
    // With it, the campaign runs and records the model's hash.
    std::fs::copy(shipped("toml"), dir.path().join("driver.toml")).unwrap();
    let o = call(args("2", false));
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    let campaign = std::fs::read_to_string(out.join("campaign.json")).unwrap();
    assert!(campaign.contains("\"sha256\""), "{campaign}");
    // A weight changed (one bit in the middle of the file, inside the dense layer's
    // weights): --resume refuses the campaign.
    let mut bytes = std::fs::read(&model).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 1;
    std::fs::write(&model, bytes).unwrap();
    let o = call(args("4", true));
    expect_code(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("sut") || err.contains("model"), "{err}");
    assert_eq!(
        comparable(&out).len(),
        2,
        "the records already written are kept"
    );
}
