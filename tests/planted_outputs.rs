//! Hostile input, second round, requirements 1 and 7: no file outside the campaign folder is
//! ever written. A symbolic link (to a file outside), a directory and a FIFO planted at every
//! path a campaign writes, in a fresh run (`--force`) and in `--resume`, are refused with
//! exit 2 before any test runs, within seconds (a FIFO never blocks), and what the link points
//! to is left as it was. The same for the files of `export`, `replay --frames` and `report`,
//! and an output folder that cannot be made is exit 2 before any work in every subcommand.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use paracosm::atomic::CAMPAIGN_OUTPUTS;

/// Runs `paracosm-fuzz` with `args`, killed after 60 s (`timeout`): a FIFO that blocked a
/// write would show as exit 124 or 137, not as a hung test.
fn fuzz(args: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let o = Command::new("timeout")
        .args(["-k", "5", "60", env!("CARGO_BIN_EXE_paracosm-fuzz")])
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("paracosm-fuzz runs");
    (o, start.elapsed())
}

#[derive(Clone, Copy, Debug)]
enum Plant {
    Link,
    Directory,
    Fifo,
}

/// Plants `kind` at `path`; a link points to `outside`.
fn plant(kind: Plant, path: &Path, outside: &Path) {
    let _ = std::fs::remove_file(path);
    let _ = std::fs::remove_dir_all(path);
    match kind {
        Plant::Link => std::os::unix::fs::symlink(outside, path).unwrap(),
        Plant::Directory => std::fs::create_dir_all(path.join("inside")).unwrap(),
        Plant::Fifo => {
            let made = Command::new("mkfifo").arg(path).status().unwrap();
            assert!(made.success(), "mkfifo");
        }
    }
}

fn what(kind: Plant) -> &'static str {
    match kind {
        Plant::Link => "is a symbolic link",
        Plant::Directory => "is a directory",
        Plant::Fifo => "is a FIFO",
    }
}

/// Asserts exit 2 within 30 s, a message naming `path` and what it is, no new record, and
/// `outside` as it was.
fn assert_refused(
    case: &str,
    (o, took): &(Output, Duration),
    path: &Path,
    kind: Plant,
    outside: &Path,
) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{case}: {stderr}");
    assert!(*took < Duration::from_secs(30), "{case}: took {took:?}");
    assert!(
        stderr.contains(&path.display().to_string()) && stderr.contains(what(kind)),
        "{case}: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{case}: {stderr}");
    assert_eq!(
        std::fs::read_to_string(outside).unwrap(),
        "keep me",
        "{case}"
    );
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

#[test]
fn a_link_a_directory_or_a_fifo_at_any_campaign_output_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let outside = dir.path().join("outside.txt");
    std::fs::write(&outside, "keep me").unwrap();
    // A finished campaign to resume: every output exists in it.
    let done = dir.path().join("done");
    let (o, _) = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "4",
        "--out",
        done.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    let names: Vec<&str> = CAMPAIGN_OUTPUTS
        .iter()
        .copied()
        .chain([".paracosm.lock"])
        .collect();
    for name in &names {
        assert!(
            *name == ".paracosm.lock" || done.join(name).exists(),
            "the campaign writes {name}"
        );
    }
    let mut cases = 0;
    for name in &names {
        for kind in [Plant::Link, Plant::Directory, Plant::Fifo] {
            // A fresh run into the folder, replacing it (--force).
            let out = dir.path().join(format!("fresh-{name}-{kind:?}"));
            std::fs::create_dir_all(&out).unwrap();
            let target = out.join(name);
            plant(kind, &target, &outside);
            let run = fuzz(&[
                "pedestrian-crossing",
                "--budget",
                "2",
                "--out",
                out.to_str().unwrap(),
                "--force",
            ]);
            let case = format!("fresh, {name} {kind:?}");
            assert_refused(&case, &run, &target, kind, &outside);
            assert!(
                !out.join("results.jsonl").is_file() || *name == "results.jsonl",
                "{case}"
            );
            // --resume of the finished campaign.
            if *name == "campaign.json" {
                continue; // read before it is written: refused as an input (below)
            }
            let out = dir.path().join(format!("resume-{name}-{kind:?}"));
            copy_dir(&done, &out);
            // Read before the plant: a FIFO planted there would block a read.
            let before = std::fs::read(out.join("results.jsonl")).ok();
            let target = out.join(name);
            plant(kind, &target, &outside);
            let run = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
            let case = format!("resume, {name} {kind:?}");
            if *name == ".paracosm.lock" {
                // The lock's own message: "the lock file `...` is a symbolic link".
                let stderr = String::from_utf8_lossy(&run.0.stderr);
                assert_eq!(run.0.status.code(), Some(2), "{case}: {stderr}");
                assert!(stderr.contains("the lock file"), "{case}: {stderr}");
                assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep me");
            } else {
                assert_refused(&case, &run, &target, kind, &outside);
            }
            // No test ran: the results are as they were.
            if *name != "results.jsonl" {
                assert_eq!(
                    std::fs::read(out.join("results.jsonl")).ok(),
                    before,
                    "{case}"
                );
            }
            cases += 2;
        }
    }
    // The campaign file is read first on --resume: a link to another file is read (and
    // refused as no campaign file), a directory or a FIFO refused as an input; none written.
    for kind in [Plant::Link, Plant::Directory, Plant::Fifo] {
        let out = dir.path().join(format!("resume-campaign-{kind:?}"));
        copy_dir(&done, &out);
        plant(kind, &out.join("campaign.json"), &outside);
        let (o, took) = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{kind:?}: {o:?}");
        assert!(took < Duration::from_secs(30));
        assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep me");
        cases += 1;
    }
    println!("{cases} planted outputs refused, none followed");
}

/// A finished campaign of the pedestrian study in `dir/name`, with camera frames.
fn finished(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(name);
    let (o, _) = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    out
}

#[test]
fn export_replay_and_report_refuse_planted_files() {
    let dir = tempfile::tempdir().unwrap();
    let outside = dir.path().join("outside.txt");
    std::fs::write(&outside, "keep me").unwrap();
    let campaign = finished(dir.path(), "c");
    let results = campaign.join("results.jsonl");
    for kind in [Plant::Link, Plant::Directory, Plant::Fifo] {
        // export: test_0.xosc and test_0.xodr.
        for file in ["test_0.xosc", "test_0.xodr"] {
            let out = dir.path().join(format!("export-{file}-{kind:?}"));
            std::fs::create_dir_all(&out).unwrap();
            let target = out.join(file);
            plant(kind, &target, &outside);
            let run = fuzz(&[
                "export",
                results.to_str().unwrap(),
                "--id",
                "0",
                "--out",
                out.to_str().unwrap(),
            ]);
            assert_refused(
                &format!("export {file} {kind:?}"),
                &run,
                &target,
                kind,
                &outside,
            );
        }
        // replay --frames: its frames and contact sheet.
        for file in ["frame_00000.png", "contact_sheet.png"] {
            let frames = dir.path().join(format!("frames-{file}-{kind:?}"));
            std::fs::create_dir_all(&frames).unwrap();
            let target = frames.join(file);
            plant(kind, &target, &outside);
            let run = fuzz(&[
                "replay",
                results.to_str().unwrap(),
                "--id",
                "0",
                "--frames",
                frames.to_str().unwrap(),
            ]);
            assert_refused(
                &format!("replay {file} {kind:?}"),
                &run,
                &target,
                kind,
                &outside,
            );
        }
        // report --pairs and --html redraw into the campaign's folder.
        for (flag, file) in [("--pairs", "pairs.png"), ("--html", "report.html")] {
            let copy = dir.path().join(format!("report-{file}-{kind:?}"));
            copy_dir(&campaign, &copy);
            let target = copy.join(file);
            plant(kind, &target, &outside);
            let run = fuzz(&["report", copy.to_str().unwrap(), flag]);
            assert_refused(
                &format!("report {flag} {kind:?}"),
                &run,
                &target,
                kind,
                &outside,
            );
        }
    }
}

#[test]
fn an_output_folder_that_cannot_be_made_is_exit_2_before_any_work_in_every_subcommand() {
    let dir = tempfile::tempdir().unwrap();
    let campaign = finished(dir.path(), "c");
    let results = campaign.join("results.jsonl");
    // A folder under a regular file cannot be made, whoever runs the test (root included).
    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    let out = file.join("out");
    let out = out.to_str().unwrap();
    let runs: Vec<(&str, Vec<&str>)> = vec![
        (
            "campaign",
            vec!["pedestrian-crossing", "--budget", "2", "--out", out],
        ),
        (
            "dataset",
            vec![
                "dataset",
                "pedestrian-crossing",
                "--budget",
                "1",
                "--out",
                out,
            ],
        ),
        (
            "export",
            vec![
                "export",
                results.to_str().unwrap(),
                "--id",
                "0",
                "--out",
                out,
            ],
        ),
        (
            "merge",
            vec!["merge", campaign.to_str().unwrap(), "--out", out],
        ),
    ];
    for (what, args) in runs {
        let (o, took) = fuzz(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: {stderr}");
        assert!(took < Duration::from_secs(30), "{what}: {took:?}");
        assert!(stderr.contains("a-file/out"), "{what}: {stderr}");
        assert!(
            stderr.starts_with("paracosm-fuzz: error: "),
            "{what}: {stderr}"
        );
    }
}
