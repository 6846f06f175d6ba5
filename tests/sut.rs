//! Systems under test end to end: the Python client library, misbehaving external programs,
//! the camera-based `vision`, and `replay`.

use std::path::Path;
use std::process::Command;

mod common;
use common::{expect_code, fuzz, records};

fn statuses(dir: &Path) -> Vec<String> {
    records(dir)
        .iter()
        .map(|r| r["status"].as_str().unwrap().to_owned())
        .collect()
}

fn script(name: &str) -> String {
    format!(
        "python3 {}",
        Path::new(env!("CARGO_MANIFEST_DIR")).join(name).display()
    )
}

#[test]
fn the_python_example_runs_the_pedestrian_study_with_the_verdicts_of_aeb() {
    let dir = tempfile::tempdir().unwrap();
    let (py, aeb) = (dir.path().join("py"), dir.path().join("aeb"));
    let common = [
        "pedestrian-crossing",
        "--budget",
        "12",
        "--jobs",
        "2",
        "--out",
    ];
    let cmd = script("examples/python/paracosm_sut.py");
    let mut args = common.to_vec();
    args.extend([py.to_str().unwrap(), "--sut-cmd", &cmd]);
    let o = fuzz(&args);
    let mut args = common.to_vec();
    args.push(aeb.to_str().unwrap());
    fuzz(&args);
    let (a, b) = (statuses(&py), statuses(&aeb));
    assert_eq!(a.len(), 12);
    assert!(!a.contains(&"error".to_owned()), "{a:?}");
    assert!(
        a.contains(&"fail".to_owned()),
        "test 9 is a collision: {a:?}"
    );
    // The example brakes by the same rule as aeb; on the straight road they agree.
    assert_eq!(a, b);
    expect_code(&o, 1);
    let campaign: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(py.join("campaign.json")).unwrap()).unwrap();
    assert_eq!(campaign["sut"]["kind"], "command");
}

#[test]
fn every_misbehaving_program_becomes_an_error_record_and_the_campaign_goes_on() {
    let cases = [
        ("crash.py", "RuntimeError: controller exploded"),
        ("hang.py", "did not answer within 1 s"),
        ("garbage.py", "is it printing to stdout?"),
        ("nan.py", "NaN and Infinity are not JSON numbers"),
        ("out_of_range.py", "answered throttle = 3, outside [-1, 1]"),
        (
            "answers_twice.py",
            "answered step 0 to the observation of step 1: an extra or late answer",
        ),
        ("no_step.py", "without `step`"),
    ];
    for (file, message) in cases {
        let dir = tempfile::tempdir().unwrap();
        let cmd = script(&format!("tests/sut_faults/{file}"));
        let o = fuzz(&[
            "pedestrian-crossing",
            "--budget",
            "2",
            "--jobs",
            "1",
            "--sut-timeout",
            "1",
            "--out",
            dir.path().to_str().unwrap(),
            "--sut-cmd",
            &cmd,
        ]);
        expect_code(&o, 3);
        let rs = records(dir.path());
        assert_eq!(rs.len(), 2, "{file}: both tests are recorded");
        for r in rs {
            assert_eq!(r["status"], "error", "{file}");
            let error = r["error"].as_str().unwrap();
            assert!(error.contains(message), "{file}: {error}");
        }
        assert!(dir.path().join("summary.json").exists(), "{file}");
    }
}

#[test]
fn a_hello_that_cannot_be_honoured_ends_each_test_in_error_naming_it() {
    // Each of these was run another way without a word: "yes" sent no lidar, a misspelt
    // camera key gave the default camera, an unknown sensor sent nothing, 25 Hz ran at 30 Hz.
    let cases = [
        (r#"{"lidar": "yes"}"#, "null", "declared sensor `lidar` as \"yes\""),
        (r#"{"camera": {"widht": 64}}"#, "null", "unknown field `widht`"),
        (r#"{"camera": {"rate_hz": 25}}"#, "null", "camera rate_hz 25 is not a whole number"),
        (r#"{"lidr": true}"#, "null", "declared sensor `lidr`, which the simulation does not mount (it mounts: camera, depth, lidar)"),
        ("{}", "25", "declared control_hz 25 is not a whole number of physics steps (60 per second) per period: use 60 / k for a whole k, such as 30 or 20"),
        ("{}", "1000", "such as 60"),
    ];
    for (sensors, hz, message) in cases {
        let dir = tempfile::tempdir().unwrap();
        let cmd = format!("{} '{sensors}' {hz}", script("tests/sut_faults/asks.py"));
        let o = fuzz(&[
            "pedestrian-crossing",
            "--budget",
            "2",
            "--jobs",
            "1",
            "--out",
            dir.path().to_str().unwrap(),
            "--sut-cmd",
            &cmd,
        ]);
        expect_code(&o, 3);
        let records = records(dir.path());
        assert_eq!(records.len(), 2, "{sensors} {hz}");
        for r in records {
            assert_eq!(r["status"], "error", "{sensors} {hz}");
            let error = r["error"].as_str().unwrap();
            assert!(error.contains(message), "{sensors} {hz}: {error}");
        }
    }
    // What can be honoured runs: 20 Hz, a lidar, a camera at 10 frames a second.
    let dir = tempfile::tempdir().unwrap();
    let cmd = format!(
        "{} '{{\"lidar\": true, \"camera\": {{\"width\": 32, \"height\": 24, \"rate_hz\": 10}}}}' 20",
        script("tests/sut_faults/asks.py")
    );
    fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "1",
        "--out",
        dir.path().to_str().unwrap(),
        "--sut-cmd",
        &cmd,
    ]);
    assert_ne!(statuses(dir.path()), vec!["error".to_owned()]);
}

#[test]
fn after_a_crash_the_next_test_gets_a_fresh_process() {
    let dir = tempfile::tempdir().unwrap();
    let marker = dir.path().join("crashed-once");
    let out = dir.path().join("out");
    let cmd = script("tests/sut_faults/crash_first_test.py");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args([
            "pedestrian-crossing",
            "--budget",
            "4",
            "--jobs",
            "1",
            "--out",
            out.to_str().unwrap(),
            "--sut-cmd",
            &cmd,
        ])
        .env("CRASH_MARKER", &marker)
        .output()
        .unwrap();
    assert!(o.status.code() == Some(0) || o.status.code() == Some(3));
    let s = statuses(&out);
    assert_eq!(s[0], "error");
    assert!(records(&out)[0]["error"]
        .as_str()
        .unwrap()
        .contains("exit status: 7"));
    assert!(s[1..].iter().all(|s| s != "error"), "{s:?}");
}

#[test]
fn a_program_gets_the_camera_and_depth_it_asks_for_fresh_or_reused() {
    for fresh in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let cmd = script("tests/sut_faults/camera.py");
        let mut args = vec![
            "pedestrian-crossing",
            "--budget",
            "2",
            "--jobs",
            "1",
            "--out",
            dir.path().to_str().unwrap(),
            "--sut-cmd",
            &cmd,
        ];
        if fresh {
            args.push("--sut-fresh");
        }
        let o = fuzz(&args);
        expect_code(&o, 0);
        assert_eq!(statuses(dir.path()), ["pass", "pass"]);
    }
}

#[test]
fn replay_writes_frames_and_a_contact_sheet_and_confirms_the_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "12",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(statuses(&out)[9], "fail");
    let frames = dir.path().join("frames");
    let results = out.join("results.jsonl");
    let o = fuzz(&[
        "replay",
        results.to_str().unwrap(),
        "--id",
        "9",
        "--frames",
        frames.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("recorded fail, replayed fail"), "{stdout}");
    assert!(stdout.contains("equals the recorded one"), "{stdout}");
    let pngs = std::fs::read_dir(&frames)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with("frame_")
        })
        .count();
    // The collision is at about 7.35 s; a 20 Hz camera takes a frame every 50 ms.
    assert!((100..200).contains(&pngs), "{pngs} frames");
    let sheet = std::fs::read(frames.join("contact_sheet.png")).unwrap();
    assert_eq!(&sheet[..4], b"\x89PNG");
    let first = image::open(frames.join("frame_00000.png")).unwrap();
    assert_eq!((first.width(), first.height()), (320, 240));

    // An id that is not there is bad input.
    let o = fuzz(&["replay", results.to_str().unwrap(), "--id", "77"]);
    expect_code(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("no test with id 77"));
}

#[test]
fn vision_fails_in_fog_dark_and_glare_but_not_in_clear_nominal_light() {
    let mut s = paracosm_scenarios::builtin("fog-light").unwrap();
    s.set_sut(paracosm_engine::sut::SutConfig::builtin("vision").unwrap());
    let run = |light: f64, fog: f64| {
        // Both parameters span [0, 1], light first: the unit point is the value.
        let a = s
            .space()
            .decode(&paracosm_generators::Point {
                discrete: vec![],
                continuous: vec![light, fog],
            })
            .unwrap();
        assert_eq!(a.real("fog"), Some(fog));
        s.run(&a, 1).unwrap().passed()
    };
    assert!(run(0.5, 0.0), "clear, nominal light");
    assert!(run(0.4, 0.15), "light mist");
    assert!(
        !run(0.5, 0.7),
        "dense fog hides the white car until too late"
    );
    assert!(!run(0.03, 0.0), "too dark to see");
    assert!(
        !run(0.97, 0.0),
        "glare: the white car and the sky both clip at 255"
    );
}

/// Whether process `pid` is gone (or a zombie waiting for its reaper, which runs nothing).
fn gone(pid: &str) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit(')')
            .next()
            .is_some_and(|rest| rest.trim_start().starts_with('Z')),
    }
}

#[test]
fn a_wrapper_script_and_the_helper_it_starts_are_killed_with_their_test() {
    // The system under test is a shell script that starts a helper (which would sleep five
    // minutes) and then runs the Python example: the helper is in the program's process group,
    // which is killed after each test (--sut-fresh) or when the campaign ends (reused).
    let dir = tempfile::tempdir().unwrap();
    let pids = dir.path().join("helpers.txt");
    let wrapper = dir.path().join("wrapper.sh");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\nsleep 300 </dev/null >/dev/null 2>&1 &\necho $! >> {}\nexec {}\n",
            pids.display(),
            script("examples/python/paracosm_sut.py")
        ),
    )
    .unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    for (name, fresh) in [("fresh", true), ("reused", false)] {
        let out = dir.path().join(name);
        let mut args = vec![
            "pedestrian-crossing",
            "--budget",
            "3",
            "--jobs",
            "1",
            "--sut-cmd",
            wrapper.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        if fresh {
            args.push("--sut-fresh");
        }
        fuzz(&args);
        assert!(!statuses(&out).contains(&"error".to_owned()), "{name}");
    }
    let started: Vec<String> = std::fs::read_to_string(&pids)
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect();
    assert!(
        started.len() >= 4,
        "3 fresh and at least 1 reused: {started:?}"
    );
    // SIGKILL is delivered when the killed process next runs: on a loaded machine a helper
    // may still show for a moment after paracosm-fuzz has exited. One that is still there
    // after 10 s was not killed.
    let mut alive: Vec<&String> = started.iter().collect();
    for _ in 0..100 {
        alive.retain(|p| !gone(p));
        if alive.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(alive.is_empty(), "helpers left running: {alive:?}");
}

/// Hostile input, second round, requirement 5: a controller whose helpers leave its process
/// group (`setsid`) or are orphaned by a double fork is still cleaned up: paracosm-fuzz adopts
/// them (`PR_SET_CHILD_SUBREAPER`) and kills them with their system under test.
#[test]
fn helpers_that_leave_the_process_group_are_killed_with_their_test() {
    let dir = tempfile::tempdir().unwrap();
    let pids = dir.path().join("helpers.txt");
    let wrapper = dir.path().join("wrapper.sh");
    // One helper in a session (and group) of its own, one orphaned by a double fork that
    // also leaves the group; each writes its own pid.
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\n\
             setsid sh -c 'echo $$ >> {p}; exec sleep 300' </dev/null >/dev/null 2>&1 &\n\
             (setsid sh -c 'echo $$ >> {p}; exec sleep 300' </dev/null >/dev/null 2>&1 &)\n\
             exec {}\n",
            script("examples/python/paracosm_sut.py"),
            p = pids.display(),
        ),
    )
    .unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    for (name, fresh) in [("fresh", true), ("reused", false)] {
        let out = dir.path().join(name);
        let mut args = vec![
            "pedestrian-crossing",
            "--budget",
            "3",
            "--jobs",
            "1",
            "--sut-cmd",
            wrapper.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        if fresh {
            args.push("--sut-fresh");
        }
        fuzz(&args);
        assert!(!statuses(&out).contains(&"error".to_owned()), "{name}");
    }
    let started: Vec<String> = std::fs::read_to_string(&pids)
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect();
    assert!(
        started.len() >= 8,
        "2 helpers a start, 4 starts at least: {started:?}"
    );
    // They left the group: each is its own session leader.
    let mut alive: Vec<&String> = started.iter().collect();
    for _ in 0..100 {
        alive.retain(|p| !gone(p));
        if alive.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    for p in &alive {
        let _ = std::process::Command::new("kill").args(["-9", p]).status();
    }
    assert!(
        alive.is_empty(),
        "helpers outside the group left running: {alive:?}"
    );
}

/// The children of process `pid` (every thread's, from `/proc`).
fn children(pid: u32) -> Vec<String> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("children")).ok())
        .flat_map(|c| c.split_whitespace().map(str::to_owned).collect::<Vec<_>>())
        .collect()
}

#[test]
fn the_system_under_test_dies_with_paracosm_killed_by_sigkill() {
    // Its own process group kept it alive after `kill -9` of paracosm (2 orphans per run): it
    // now asks the kernel to kill it when paracosm goes (PR_SET_PDEATHSIG).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut run = std::process::Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args([
            "pedestrian-crossing",
            "--budget",
            "100000",
            "--jobs",
            "2",
            "--sut-cmd",
            &script("examples/python/paracosm_sut.py"),
            "--out",
            out.to_str().unwrap(),
        ])
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut suts = Vec::new();
    for _ in 0..300 {
        suts = children(run.id());
        if !suts.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(!suts.is_empty(), "no system under test started within 30 s");
    // Let it run a few tests, then kill paracosm as a scheduler or a user would.
    std::thread::sleep(std::time::Duration::from_millis(500));
    suts = children(run.id());
    run.kill().unwrap();
    run.wait().unwrap();
    let mut alive: Vec<String> = suts;
    for _ in 0..100 {
        alive.retain(|p| !gone(p));
        if alive.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(
        alive.is_empty(),
        "systems under test left running: {alive:?}"
    );
}
