//! Issue 22, requirement 3: one writer per campaign folder. A second `--resume` (or a merge
//! into the folder) while a run writes it exits 2 naming the running process, and leaves the
//! folder whole; once that process is gone (even by `kill -9`), the lock is taken over and
//! the campaign finishes.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{expect_code, fuzz, ran};

fn lines(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("results.jsonl"))
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

#[test]
fn a_second_writer_is_refused_while_the_first_runs_and_takes_over_after_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    let budget = "40";
    let mut first = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args(["t-loop", "--budget", budget, "--jobs", "1", "--out"])
        .arg(&out)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while lines(&out) == 0 {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "the first run wrote no record"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let resume = || {
        fuzz(&[
            "t-loop",
            "--budget",
            budget,
            "--resume",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let before = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let o = resume();
    // The first run is still going: 40 tests of 200 s take it several seconds.
    assert!(
        first.try_wait().unwrap().is_none(),
        "the first run ended before the second started; the test proves nothing"
    );
    expect_code(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("is being written by process {}", first.id())),
        "{err}"
    );
    let merge = fuzz(&[
        "merge",
        out.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--force",
    ]);
    expect_code(&merge, 2);
    assert!(String::from_utf8_lossy(&merge.stderr).contains("is being written by process"));
    // The refused writers wrote nothing: the records only grew, in order, by the first run.
    let after = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    assert!(after.starts_with(&before));

    // kill -9: the operating system releases the lock with the process.
    first.kill().unwrap();
    first.wait().unwrap();
    let o = resume();
    ran(&o);
    let ids: Vec<u64> = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["id"]
                .as_u64()
                .unwrap()
        })
        .collect();
    assert_eq!(ids, (0..40).collect::<Vec<u64>>());
    ran(&fuzz(&["report", out.to_str().unwrap()]));
}
