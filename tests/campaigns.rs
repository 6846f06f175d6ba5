//! Campaigns that survive: SIGKILL and resume, Ctrl-C, refused resumes, shards and merge,
//! JUnit, report, and output-folder safety. All on the real binary.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use rand::{Rng, SeedableRng};

mod common;
use common::{expect_code, fuzz};

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"));
    c.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    c
}

/// `results.jsonl` lines without `wall_ms`, sorted by id.
fn comparable(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("results.jsonl")).unwrap();
    assert!(text.is_empty() || text.ends_with('\n'));
    let mut lines: Vec<(u64, String)> = text
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let cut = l.rfind(",\"wall_ms\":").unwrap();
            (v["id"].as_u64().unwrap(), l[..cut].to_owned())
        })
        .collect();
    lines.sort();
    lines.into_iter().map(|(_, l)| l).collect()
}

const STUDY: [&str; 5] = ["pedestrian-crossing", "--budget", "400", "--jobs", "2"];

fn reference(dir: &Path) -> Vec<String> {
    let out = dir.join("reference");
    let mut args = STUDY.to_vec();
    args.extend(["--out", out.to_str().unwrap()]);
    expect_code(&fuzz(&args), 1);
    comparable(&out)
}

#[test]
fn killed_at_random_moments_and_resumed_it_equals_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let expected = reference(dir.path());
    assert_eq!(expected.len(), 400);
    let out = dir.path().join("killed");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut kills = 0;
    for attempt in 0..8 {
        let mut cmd = bin();
        if attempt == 0 {
            cmd.args(STUDY).args(["--out", out.to_str().unwrap()]);
        } else {
            cmd.args(["--resume", "--out", out.to_str().unwrap()]);
        }
        let mut child = cmd
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // A whole run takes about 1.5 s on two cores; kill somewhere inside the first part.
        std::thread::sleep(Duration::from_millis(rng.random_range(30..500)));
        if child.try_wait().unwrap().is_none() {
            child.kill().unwrap(); // SIGKILL
            kills += 1;
        }
        let status = child.wait().unwrap();
        if status.code() == Some(1) {
            break; // finished: it found the study's collisions
        }
    }
    assert!(kills >= 3, "only {kills} kills landed");
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    expect_code(&o, 1);
    assert_eq!(comparable(&out), expected);
    // A resume of a finished campaign runs nothing and changes nothing.
    expect_code(&fuzz(&["--resume", "--out", out.to_str().unwrap()]), 1);
    assert_eq!(comparable(&out), expected);
}

#[test]
fn a_half_written_last_line_is_repaired_and_that_test_runs_again() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cut");
    let mut args = STUDY.to_vec();
    args[2] = "60";
    args.extend(["--out", out.to_str().unwrap()]);
    expect_code(&fuzz(&args), 1);
    let full = comparable(&out);
    let path = out.join("results.jsonl");
    let text = std::fs::read_to_string(&path).unwrap();
    let cut = text.len() - 40;
    std::fs::write(&path, &text[..cut]).unwrap();
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    expect_code(&o, 1);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("cut a half-written last line"), "{stderr}");
    assert!(stderr.contains("59 of 60 tests already done"), "{stderr}");
    assert_eq!(comparable(&out), full);
}

#[test]
fn a_resume_with_other_arguments_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let o = dir.path().join("c");
    expect_code(
        &fuzz(&[
            "pedestrian-crossing",
            "--budget",
            "10",
            "--out",
            o.to_str().unwrap(),
        ]),
        1,
    );
    let before = std::fs::read(out.join("results.jsonl")).unwrap();
    for (args, says) in [
        (
            vec!["pedestrian-crossing", "--budget", "10", "--seed", "1"],
            "seed: 0 vs 1",
        ),
        (
            vec!["pedestrian-crossing", "--budget", "20"],
            "budget: 10 vs 20",
        ),
        (
            vec!["fog-light", "--budget", "10"],
            "scenario: pedestrian-crossing vs fog-light",
        ),
        (vec!["--strategy", "random"], "strategy: halton vs random"),
        (vec!["--shard", "0/2"], "shard: none vs 0/2"),
    ] {
        let mut a = args.clone();
        a.extend(["--resume", "--out", out.to_str().unwrap()]);
        let r = fuzz(&a);
        expect_code(&r, 2);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert!(
            stderr.contains("refusing to resume") && stderr.contains(says),
            "{stderr}"
        );
    }
    assert_eq!(std::fs::read(out.join("results.jsonl")).unwrap(), before);
    // Without --resume or --force a non-empty folder is refused, and nothing is touched.
    let r = fuzz(&["pedestrian-crossing", "--out", out.to_str().unwrap()]);
    expect_code(&r, 2);
    assert!(String::from_utf8_lossy(&r.stderr).contains("is not empty"));
    assert_eq!(std::fs::read(out.join("results.jsonl")).unwrap(), before);
}

/// Starts a 3,000-test campaign in `out`, sends it `signal` after 0.7 s, and checks that it
/// exits with `code` having finished and written the tests in flight and printed how to
/// resume; returns how many tests it wrote.
fn interrupted_by(signal: &str, code: i32, out: &Path) -> usize {
    let child = bin()
        .args([
            "pedestrian-crossing",
            "--budget",
            "3000",
            "--jobs",
            "1",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    let status = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let o = child.wait_with_output().unwrap();
    expect_code(&o, code);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("interrupted") && stderr.contains("paracosm-fuzz --resume --out"),
        "{stderr}"
    );
    let done = comparable(out).len();
    assert!(done > 0 && done < 3000, "{done}");
    done
}

#[test]
fn ctrl_c_finishes_the_tests_in_flight_prints_how_to_resume_and_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("int");
    interrupted_by("-INT", 130, &out);
    // Finishing it gives the whole campaign.
    expect_code(
        &fuzz(&["--resume", "--out", out.to_str().unwrap(), "--jobs", "2"]),
        1,
    );
    assert_eq!(comparable(&out).len(), 3000);
}

/// SIGTERM, which Slurm and Kubernetes send to stop a job, behaves as Ctrl-C: the tests in
/// flight finish and are written, the resume command is printed; the exit code is 143.
#[test]
fn sigterm_finishes_the_tests_in_flight_prints_how_to_resume_and_exits_143() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("term");
    interrupted_by("-TERM", 143, &out);
    // Every line written is whole.
    let lines = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    for l in lines.lines() {
        serde_json::from_str::<serde_json::Value>(l).unwrap();
    }
}

#[test]
fn three_shards_merge_into_the_single_machine_run() {
    let dir = tempfile::tempdir().unwrap();
    let expected = reference(dir.path());
    let shard = |i: u32| dir.path().join(format!("shard-{i}"));
    for i in 0..3 {
        let s = format!("{i}/3");
        let mut args = STUDY.to_vec();
        let p = shard(i);
        args.extend(["--shard", &s, "--out", p.to_str().unwrap()]);
        let o = fuzz(&args);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    }
    let merged = dir.path().join("merged");
    let junit = dir.path().join("junit.xml");
    let (s0, s1, s2) = (shard(0), shard(1), shard(2));
    let (s0, s1, s2) = (
        s0.to_str().unwrap(),
        s1.to_str().unwrap(),
        s2.to_str().unwrap(),
    );
    let o = fuzz(&[
        "merge",
        s0,
        s1,
        s2,
        "--out",
        merged.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    assert_eq!(comparable(&merged), expected);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(merged.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["tests_run"], 400);
    assert_eq!(summary["shard"], serde_json::Value::Null);
    assert!(merged.join("failure_map.png").exists());
    // Every file listed is where the list says, relative to the output folder: the JUnit
    // file too, whether inside it or not.
    let outputs: Vec<&str> = summary["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o.as_str().unwrap())
        .collect();
    assert!(outputs.len() > 5, "{outputs:?}");
    for o in &outputs {
        assert!(
            merged.join(o).is_file(),
            "{o} is not a file under {}",
            merged.display()
        );
    }
    assert!(
        outputs.iter().any(|o| merged.join(o) == junit),
        "{outputs:?}"
    );

    // JUnit: well-formed, one test case per test, a failure per failed test.
    let xml = std::fs::read_to_string(&junit).unwrap();
    let mut reader = quick_xml::Reader::from_str(&xml);
    let (mut cases, mut failures) = (0, 0);
    loop {
        match reader.read_event().unwrap() {
            quick_xml::events::Event::Start(e) | quick_xml::events::Event::Empty(e) => {
                match e.name().as_ref() {
                    b"testcase" => cases += 1,
                    b"failure" => failures += 1,
                    _ => {}
                }
            }
            quick_xml::events::Event::Eof => break,
            _ => {}
        }
    }
    assert_eq!(cases, 400);
    assert_eq!(failures, summary["counts"]["fail"].as_u64().unwrap());
    assert!(xml.contains("paracosm-fuzz replay"));

    // summary.json lists the failures first, most violated first, with replay commands.
    let text = std::fs::read_to_string(merged.join("summary.json")).unwrap();
    assert!(text.trim_start().starts_with("{\n  \"failures\""));
    let list = summary["failures"].as_array().unwrap();
    assert_eq!(
        list.len() as u64,
        summary["counts"]["fail"].as_u64().unwrap()
    );
    let rob: Vec<f64> = list
        .iter()
        .map(|f| f["robustness"].as_f64().unwrap())
        .collect();
    assert!(rob.windows(2).all(|w| w[0] <= w[1]));
    assert!(list[0]["replay"].as_str().unwrap().contains("--id"));

    // A missing shard, a shard given twice, and an incomplete one are refused (exit 2,
    // with the reason on stderr).
    let m2 = dir.path().join("m2");
    let refused = |shards: &[&str], reason: &str| {
        let mut args = vec!["merge"];
        args.extend(shards);
        args.extend(["--out", m2.to_str().unwrap(), "--force"]);
        let o = fuzz(&args);
        expect_code(&o, 2);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(reason), "{stderr}");
    };
    refused(&[s0, s2], "shard 1/3 of the campaign is missing");
    refused(&[s0, s1, s1, s2], "shard 1/3 is given twice");
    let results = shard(1).join("results.jsonl");
    let text = std::fs::read_to_string(&results).unwrap();
    let keep: String = text.lines().take(10).map(|l| format!("{l}\n")).collect();
    std::fs::write(&results, keep).unwrap();
    refused(&[s0, s1, s2], "is incomplete: 10 of 133 tests");
    // `report` on the partial shard says so.
    let o = fuzz(&["report", s1]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("partial: 10 of 133 tests"), "{stdout}");
    // A shard of another campaign is refused.
    let other = dir.path().join("other");
    let p = other.to_str().unwrap();
    fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "400",
        "--seed",
        "9",
        "--shard",
        "1/3",
        "--out",
        p,
    ]);
    let o = fuzz(&["merge", s0, p, s2, "--out", m2.to_str().unwrap(), "--force"]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("different campaigns") && stderr.contains("seed: 0 vs 9"),
        "{stderr}"
    );
}

#[test]
fn a_full_disk_is_a_clear_error_and_keeps_what_was_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("full");
    // A file size limit of 16 KiB (`ulimit -f`, with SIGXFSZ ignored so that a write past it
    // fails with EFBIG, as a full disk fails with ENOSPC): `results.jsonl` reaches it after
    // some twenty records. (A link to /dev/full is now refused as a planted link, exit 2.)
    let o = std::process::Command::new("bash")
        .args([
            "-c",
            "trap '' XFSZ; ulimit -f 16; exec \"$0\" \"$@\"",
            env!("CARGO_BIN_EXE_paracosm-fuzz"),
            "pedestrian-crossing",
            "--budget",
            "60",
            "--jobs",
            "1",
            "--out",
            out.to_str().unwrap(),
        ])
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    // Not the user's input: the machine's (exit 3, `Error::Write`).
    expect_code(&o, 3);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("results.jsonl") && stderr.contains("File too large"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
    // What was written stays, whole records only, and resumes once there is room.
    let text = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let kept = text.lines().count();
    assert!(kept > 5 && kept < 60, "{kept} records kept");
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    assert_eq!(
        std::fs::read_to_string(out.join("results.jsonl"))
            .unwrap()
            .lines()
            .count(),
        60
    );
}

#[test]
fn the_sbatch_script_maps_array_tasks_to_shards_and_failures_to_success() {
    let dir = tempfile::tempdir().unwrap();
    // A stand-in for paracosm-fuzz that records its arguments and exits with $FAKE_CODE.
    let fake = dir.path().join("fake-fuzz");
    std::fs::write(
        &fake,
        "#!/bin/sh\necho \"$@\" >> \"$FAKE_LOG\"\nexit \"$FAKE_CODE\"\n",
    )
    .unwrap();
    std::process::Command::new("chmod")
        .args(["+x", fake.to_str().unwrap()])
        .status()
        .unwrap();
    let log = dir.path().join("log");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/slurm/paracosm-array.sbatch");
    let run = |task: &str, min: &str, code: &str| {
        Command::new("bash")
            .arg(&script)
            .args(["pedestrian-crossing", "/runs/x", "--budget", "1000"])
            .env("PARACOSM_FUZZ", &fake)
            .env("FAKE_LOG", &log)
            .env("FAKE_CODE", code)
            .env("SLURM_ARRAY_TASK_ID", task)
            .env("SLURM_ARRAY_TASK_COUNT", "4")
            .env("SLURM_ARRAY_TASK_MIN", min)
            .env("SLURM_CPUS_PER_TASK", "2")
            .status()
            .unwrap()
            .code()
    };
    // Tasks 4..7 of an array --array=4-7 run shards 0..3.
    assert_eq!(run("5", "4", "0"), Some(0));
    assert_eq!(
        run("7", "4", "1"),
        Some(0),
        "failures found is a successful shard"
    );
    assert_eq!(run("4", "4", "2"), Some(2), "bad input fails the task");
    let calls = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = calls.lines().collect();
    assert_eq!(
        lines[0],
        "pedestrian-crossing --shard 1/4 --out /runs/x/shard-1 --jobs 2 --resume --budget 1000"
    );
    assert!(lines[1].contains("--shard 3/4 --out /runs/x/shard-3"));
    assert!(lines[2].contains("--shard 0/4 --out /runs/x/shard-0"));
    // Without the array variables it refuses to run.
    let o = Command::new("bash")
        .arg(&script)
        .args(["s", "o"])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(!o.status.success());
}

#[test]
fn the_kubernetes_indexed_job_shards_by_completion_index() {
    let yaml = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/kubernetes/indexed-job.yaml"),
    )
    .unwrap();
    assert!(yaml.contains("completionMode: Indexed"));
    let field = |name: &str| -> u64 {
        let re = regex::Regex::new(&format!(r"(?m)^\s+{name}: (\d+)$")).unwrap();
        re.captures(&yaml).unwrap()[1].parse().unwrap()
    };
    let shard = regex::Regex::new(r#"--shard "\$\{JOB_COMPLETION_INDEX\}/(\d+)""#).unwrap();
    let n: u64 = shard.captures(&yaml).expect("a --shard argument")[1]
        .parse()
        .unwrap();
    assert_eq!(field("completions"), n, "one pod per shard");
    assert!(yaml.contains("--out \"/results/shard-${JOB_COMPLETION_INDEX}\""));
    assert!(yaml.contains("paracosm-fuzz merge /results/shard-* --out /results/merged"));
}
