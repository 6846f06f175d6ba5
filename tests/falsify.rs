//! Adaptive falsification on the real binary: batches through ask/tell, determinism over
//! thread counts, resume of an adaptive campaign, --stop-at-first-failure, and refusals.

use std::path::Path;

mod common;
use common::{expect_code, fuzz};

/// `results.jsonl` lines without `wall_ms`.
fn lines(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| l[..l.rfind(",\"wall_ms\":").unwrap()].to_owned())
        .collect()
}

fn run(out: &Path, strategy: &str, extra: &[&str]) -> std::process::Output {
    run_seeded(out, strategy, "3", extra)
}

fn run_seeded(out: &Path, strategy: &str, seed: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "pedestrian-crossing",
        "--strategy",
        strategy,
        "--budget",
        "40",
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    fuzz(&args)
}

#[test]
fn every_falsifier_spends_the_budget_exactly_and_does_not_depend_on_jobs() {
    let dir = tempfile::tempdir().unwrap();
    for strategy in [
        "falsify-nm",
        "falsify-pso",
        "falsify-sa",
        "falsify-ce",
        "falsify-bo",
        "falsify-bo-lcb",
    ] {
        let one = dir.path().join(format!("{strategy}-1"));
        let three = dir.path().join(format!("{strategy}-3"));
        let a = run(&one, strategy, &["--jobs", "1"]);
        let b = run(&three, strategy, &["--jobs", "3"]);
        assert!(matches!(a.status.code(), Some(0 | 1)), "{strategy}: {a:?}");
        assert_eq!(a.status.code(), b.status.code());
        let la = lines(&one);
        assert_eq!(la.len(), 40, "{strategy}");
        assert_eq!(la, lines(&three), "{strategy} depends on --jobs");
        for (i, l) in la.iter().enumerate() {
            let v: serde_json::Value = serde_json::from_str(&format!("{l}}}")).unwrap();
            assert_eq!(v["id"], i as u64);
            assert_eq!(v["strategy"], strategy);
            for x in v["point"]["continuous"].as_array().unwrap() {
                assert!((0.0..1.0).contains(&x.as_f64().unwrap()), "{strategy}: {l}");
            }
        }
    }
}

#[test]
fn a_resumed_adaptive_campaign_equals_an_uninterrupted_one() {
    for strategy in ["falsify-nm", "falsify-bo"] {
        let dir = tempfile::tempdir().unwrap();
        let whole = dir.path().join("whole");
        run(&whole, strategy, &[]);
        let expected = lines(&whole);
        // Keep 13 complete records and half of the 14th: the search has to be replayed from
        // the records (mid-batch; past falsify-bo's initial design of 8) before it can go on.
        let cut = dir.path().join("cut");
        std::fs::create_dir_all(&cut).unwrap();
        std::fs::copy(whole.join("campaign.json"), cut.join("campaign.json")).unwrap();
        let text = std::fs::read_to_string(whole.join("results.jsonl")).unwrap();
        let mut kept: String = text.split_inclusive('\n').take(13).collect();
        let fourteenth = text.split_inclusive('\n').nth(13).unwrap();
        kept.push_str(&fourteenth[..fourteenth.len() / 2]);
        std::fs::write(cut.join("results.jsonl"), kept).unwrap();
        let o = fuzz(&["--resume", "--out", cut.to_str().unwrap()]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{strategy}: {o:?}");
        assert_eq!(lines(&cut), expected, "{strategy}");
    }
}

#[test]
fn stop_at_first_failure_ends_the_file_at_the_first_failure_for_any_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stop");
    // Seed 6 fails in its second batch, while other tests of it are in flight.
    let o = run_seeded(
        &out,
        "falsify-sa",
        "6",
        &["--stop-at-first-failure", "--jobs", "1"],
    );
    expect_code(&o, 1);
    let records = lines(&out);
    let three = dir.path().join("three");
    run_seeded(
        &three,
        "falsify-sa",
        "6",
        &["--stop-at-first-failure", "--jobs", "3"],
    );
    assert_eq!(lines(&three), records, "the stopped file depends on --jobs");
    let failed: Vec<usize> = records
        .iter()
        .enumerate()
        .filter(|(_, l)| l.contains("\"status\":\"fail\""))
        .map(|(i, _)| i)
        .collect();
    // The file ends with the first failure.
    assert_eq!(failed, vec![records.len() - 1], "{records:#?}");
    assert_eq!(records.len(), 6);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains(&format!("{} of 40 tests", records.len())),
        "{stdout}"
    );
    // Resuming it with the same flag finds the failure already there and runs nothing.
    let again = fuzz(&[
        "--resume",
        "--stop-at-first-failure",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&again, 1);
    assert_eq!(lines(&out), records);
}

#[test]
fn falsifiers_refuse_shards_and_point_lists_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shard");
    let o = run(&out, "falsify-ce", &["--shard", "0/2"]);
    expect_code(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shard cannot split a falsify-ce"));
    assert!(!out.join("results.jsonl").exists());
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_paracosm-cover"))
        .args([
            "generate",
            "--space",
            "pedestrian-crossing",
            "--strategy",
            "falsify-nm",
            "--budget",
            "5",
        ])
        .output()
        .unwrap();
    expect_code(&o, 2);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("needs a simulator"),
        "{o:?}"
    );
}
