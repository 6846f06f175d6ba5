//! Inputs that are not regular files: a FIFO given as a program, a map, a model, a CSV of
//! points, a results file or a PICT model blocked forever (nothing printed); a device never
//! ended; a directory gave an I/O message. Each is refused at once, exit 2, naming the path
//! and what it is.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `bin` with `args` in `dir`; panics when it runs past 30 s (a FIFO blocked it).
fn run(bin: &str, args: &[&str], dir: &Path) -> (i32, String) {
    let mut child = Command::new(bin)
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("{bin} {args:?} still running after 30 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn mkfifo(path: &Path) {
    assert!(Command::new("mkfifo").arg(path).status().unwrap().success());
}

#[test]
fn fifos_devices_and_directories_given_as_inputs_are_refused_at_once_with_exit_2() {
    let fuzz = env!("CARGO_BIN_EXE_paracosm-fuzz");
    let cover = env!("CARGO_BIN_EXE_paracosm-cover");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    mkfifo(&d.join("p.star"));
    mkfifo(&d.join("m.xodr"));
    mkfifo(&d.join("model.onnx"));
    mkfifo(&d.join("points.csv"));
    mkfifo(&d.join("pict.txt"));
    std::fs::create_dir(d.join("dir.star")).unwrap();
    // A program whose map is a FIFO.
    std::fs::write(
        d.join("map.star"),
        "w = World(light = 0.5, fog = 0.0)\nm = OpenDrive(\"m.xodr\")\n",
    )
    .unwrap();
    // A campaign folder whose results file is a FIFO (replay and report read it).
    let ok = common::fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "2",
        "--out",
        d.join("c").to_str().unwrap(),
    ]);
    assert!(ok.status.code() == Some(1) || ok.status.success(), "{ok:?}");
    let results = d.join("c").join("results.jsonl");
    std::fs::remove_file(&results).unwrap();
    mkfifo(&results);
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        (
            fuzz,
            vec!["p.star", "--budget", "1", "--out", "o1"],
            "a FIFO",
        ),
        (
            fuzz,
            vec!["dir.star", "--budget", "1", "--out", "o2"],
            "a directory",
        ),
        (
            fuzz,
            vec!["/dev/zero", "--budget", "1", "--out", "o3"],
            "a character device",
        ),
        (
            fuzz,
            vec!["map.star", "--budget", "1", "--out", "o4"],
            "a FIFO",
        ),
        (
            fuzz,
            vec![
                "pedestrian-crossing",
                "--sut-onnx",
                "model.onnx",
                "--budget",
                "1",
                "--out",
                "o5",
            ],
            "a FIFO",
        ),
        (
            fuzz,
            vec![
                "pedestrian-crossing",
                "--points",
                "points.csv",
                "--out",
                "o6",
            ],
            "a FIFO",
        ),
        (
            fuzz,
            vec!["replay", "c/results.jsonl", "--id", "0"],
            "a FIFO",
        ),
        (fuzz, vec!["report", "c"], "a FIFO"),
        (cover, vec!["generate", "--model", "pict.txt"], "a FIFO"),
    ];
    for (bin, args, what) in cases {
        let (code, err) = run(bin, &args, d);
        assert_eq!(code, 2, "{args:?}: exit {code}\n{err}");
        assert!(err.contains(what), "{args:?}: {err}");
    }
}

/// No file outside the campaign folder is written through a link planted in it (the old
/// write probe followed one and emptied its target), and `--resume` removes the temporary
/// files a killed writer left (`.paracosm-*`), never what a link under such a name points to.
#[test]
fn links_planted_in_the_folder_are_never_followed_and_resume_removes_stale_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    let outside = dir.path().join("precious.txt");
    std::fs::write(&outside, "keep me").unwrap();
    let out = dir.path().join("c");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&outside, out.join(".paracosm-write-probe")).unwrap();
    std::os::unix::fs::symlink(&outside, out.join(".paracosm-abc.json")).unwrap();
    let o = out.to_str().unwrap();
    let first = common::fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "4",
        "--out",
        o,
        "--force",
    ]);
    assert!(first.status.code().is_some_and(|c| c <= 1), "{first:?}");
    // As if it had been killed after two tests, in the middle of writing its summary.
    let results = out.join("results.jsonl");
    let two: String = std::fs::read_to_string(&results)
        .unwrap()
        .lines()
        .take(2)
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&results, two).unwrap();
    std::fs::write(out.join(".paracosm-stale1.json"), "half a summary").unwrap();
    let resumed = common::fuzz(&["--resume", "--out", o]);
    assert!(resumed.status.code().is_some_and(|c| c <= 1), "{resumed:?}");
    assert!(
        !out.join(".paracosm-stale1.json").exists(),
        "the stale file is left"
    );
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep me");
    let lines = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 4);
}
