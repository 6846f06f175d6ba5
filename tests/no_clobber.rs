//! Issue 22, requirement 1: outputs never replace what is not paracosm's own file. A symbolic
//! link, a device, a FIFO or a directory given as `--junit` or `--output` is refused with
//! exit 2 before any test runs and is left as it was; the campaign's own files are refused as
//! `--junit` targets.

use std::os::unix::fs::FileTypeExt;
use std::path::Path;
use std::process::Command;

mod common;
use common::{expect_code, fuzz, ran};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn campaign_with_junit(out: &Path, junit: &Path) -> std::process::Output {
    fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "2",
        "--out",
        out.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
    ])
}

#[test]
fn junit_targets_that_are_not_regular_files_are_refused_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let mine = dir.path().join("mine.xml");
    std::fs::write(&mine, "keep me").unwrap();
    let link = dir.path().join("link.xml");
    std::os::unix::fs::symlink(&mine, &link).unwrap();
    let fifo = dir.path().join("pipe.xml");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success(), "mkfifo");
    for (target, what) in [
        (link.as_path(), "symbolic link"),
        (fifo.as_path(), "FIFO"),
        (Path::new("/dev/null"), "device"),
        (dir.path(), "directory"),
    ] {
        let out = dir.path().join(format!("run-{}", what.replace(' ', "-")));
        let o = campaign_with_junit(&out, target);
        expect_code(&o, 2);
        let err = stderr(&o);
        assert!(
            err.contains(what) && err.contains("give another path"),
            "{err}"
        );
        // Refused before the first test: no campaign folder was made.
        assert!(!out.exists(), "{what}: the campaign ran");
    }
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "keep me");
}

#[test]
fn the_campaign_s_own_files_are_refused_as_junit_targets() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    // A finished campaign, then a resume-free rerun that would put JUnit over its records.
    let o = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    ran(&o);
    let records = std::fs::read(out.join("results.jsonl")).unwrap();
    for name in ["results.jsonl", "campaign.json", "summary.json"] {
        let o = fuzz(&[
            "pedestrian-crossing",
            "--budget",
            "2",
            "--resume",
            "--out",
            out.to_str().unwrap(),
            "--junit",
            out.join(name).to_str().unwrap(),
        ]);
        expect_code(&o, 2);
        assert!(stderr(&o).contains("campaign's own"), "{}", stderr(&o));
    }
    assert_eq!(std::fs::read(out.join("results.jsonl")).unwrap(), records);
    ran(&fuzz(&["report", out.to_str().unwrap()]));
    // Another name in the folder is fine.
    ran(&campaign_with_junit(
        &dir.path().join("e"),
        &dir.path().join("e/junit.xml"),
    ));
    assert!(std::fs::read_to_string(dir.path().join("e/junit.xml"))
        .unwrap()
        .contains("<testsuite"));
}

/// `paracosm-cover generate` of 4 Halton points of pedestrian-crossing into `output`.
fn generate(output: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_paracosm-cover"))
        .args([
            "generate",
            "--space",
            "pedestrian-crossing",
            "--budget",
            "4",
            "--output",
        ])
        .arg(output)
        .output()
        .unwrap()
}

#[test]
fn cover_output_that_is_a_link_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mine = dir.path().join("mine.csv");
    std::fs::write(&mine, "keep me").unwrap();
    let link = dir.path().join("design.csv");
    std::os::unix::fs::symlink(&mine, &link).unwrap();
    let o = generate(&link);
    expect_code(&o, 2);
    assert!(stderr(&o).contains("symbolic link"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "keep me");
    // A regular file is replaced whole.
    let plain = dir.path().join("plain.csv");
    std::fs::write(&plain, "old").unwrap();
    let o = generate(&plain);
    expect_code(&o, 0);
    assert_eq!(
        std::fs::read_to_string(&plain).unwrap().lines().count(),
        5,
        "a header and 4 rows"
    );
}

/// `--resume` in a folder that holds records but no campaign.json is refused and leaves them
/// (it started a new campaign that replaced them), and a campaign that stops at its first
/// failure stops there when resumed without the flag (the flag was not kept, so a resumed
/// run went on to the whole budget).
#[test]
fn resume_keeps_orphan_records_and_the_stop_at_the_first_failure() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let o = common::fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "60",
        "--stop-at-first-failure",
        "--out",
        whole.to_str().unwrap(),
    ]);
    common::expect_code(&o, 1);
    let n = common::records(&whole).len();
    assert!((2..60).contains(&n), "{n} records");
    // Interrupted after the first record: resume without the flag.
    let cut = dir.path().join("cut");
    std::fs::create_dir_all(&cut).unwrap();
    std::fs::copy(whole.join("campaign.json"), cut.join("campaign.json")).unwrap();
    let first = std::fs::read_to_string(whole.join("results.jsonl")).unwrap();
    let first = format!("{}\n", first.lines().next().unwrap());
    std::fs::write(cut.join("results.jsonl"), &first).unwrap();
    let o = common::fuzz(&["--resume", "--out", cut.to_str().unwrap()]);
    common::expect_code(&o, 1);
    assert_eq!(common::comparable(&cut), common::comparable(&whole));
    // Records without their campaign.json.
    let orphan = dir.path().join("orphan");
    std::fs::create_dir_all(&orphan).unwrap();
    std::fs::write(orphan.join("results.jsonl"), &first).unwrap();
    let o = common::fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "5",
        "--resume",
        "--out",
        orphan.to_str().unwrap(),
    ]);
    common::expect_code(&o, 2);
    assert!(
        stderr(&o).contains("but no campaign.json"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_to_string(orphan.join("results.jsonl")).unwrap(),
        first
    );
}
