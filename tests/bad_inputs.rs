//! The hostile-input corpus (`tests/bad_inputs/`): every malformed scenario, space, CSV,
//! results file and command line ends with exit code 2, a message that names the problem and
//! the file, and no panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(tool: &str, args: &[String]) -> Output {
    let exe = match tool {
        "fuzz" => env!("CARGO_BIN_EXE_paracosm-fuzz"),
        "cover" => env!("CARGO_BIN_EXE_paracosm-cover"),
        other => panic!("unknown tool {other}"),
    };
    Command::new(exe)
        .args(args)
        .current_dir(root())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap()
}

/// Asserts exit code 2, no panic, and each of `phrases` in stderr.
fn assert_refused(what: &str, o: &Output, phrases: &[&str]) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{what}: exit {:?}\n{stderr}",
        o.status
    );
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    // The one first line (docs/limits.md): the error leads, before any warning.
    let first = stderr.lines().next().unwrap_or_default();
    assert!(
        (first.starts_with("paracosm-fuzz: error: ")
            || first.starts_with("paracosm-cover: error: ")),
        "{what}: the first line is not the error:\n{stderr}"
    );
    for p in phrases {
        assert!(stderr.contains(p), "{what}: `{p}` not in\n{stderr}");
    }
}

fn files(kind: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("tests/bad_inputs").join(kind))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    assert!(!v.is_empty());
    v
}

fn rel(p: &Path) -> String {
    p.strip_prefix(root()).unwrap().display().to_string()
}

fn name(p: &Path) -> String {
    p.file_name().unwrap().to_string_lossy().into_owned()
}

#[test]
fn bad_scenario_programs() {
    let tmp = tempfile::tempdir().unwrap();
    for f in files("scenarios") {
        let out = tmp.path().join(name(&f));
        let o = run(
            "fuzz",
            &[
                rel(&f),
                "--budget".into(),
                "1".into(),
                "--out".into(),
                out.display().to_string(),
            ],
        );
        // A first line `# expect: PHRASE` names a phrase the message must contain too.
        let text = std::fs::read(&f).unwrap();
        let first =
            String::from_utf8_lossy(text.split(|&b| b == b'\n').next().unwrap_or(&[])).into_owned();
        let mut phrases = vec![name(&f)];
        if let Some(p) = first.strip_prefix("# expect: ") {
            phrases.push(p.trim().to_owned());
        }
        let phrases: Vec<&str> = phrases.iter().map(String::as_str).collect();
        assert_refused(&rel(&f), &o, &phrases);
        assert!(
            !out.join("results.jsonl").exists(),
            "{}: nothing runs",
            rel(&f)
        );
    }
    // A folder given as the scenario.
    let o = run("fuzz", &["tests/bad_inputs/scenarios".into()]);
    assert_refused("a folder", &o, &["is a directory, not a regular file"]);
}

/// A program in `dir` that loads the map at `map` and places the ego on its road "1".
fn map_program(dir: &Path, map: &Path) -> PathBuf {
    let program = dir.join(format!("{}.star", name(map)));
    std::fs::write(
        &program,
        format!(
            "w = World()\nm = OpenDrive(\"{}\")\nv = AutonomousVehicle(loc = m.onLane(road = \"1\", lane = -1, s = 10.0))\nw.place(m, v)\n",
            map.display()
        ),
    )
    .unwrap();
    program
}

#[test]
fn bad_opendrive_maps() {
    let tmp = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for f in files("maps") {
        let program = map_program(tmp.path(), &f);
        let out = tmp.path().join(format!("out-{}", name(&f)));
        let o = run(
            "fuzz",
            &[
                program.display().to_string(),
                "--budget".into(),
                "1".into(),
                "--out".into(),
                out.display().to_string(),
            ],
        );
        // A first line `<!-- expect: PHRASE -->` names a phrase the message must contain.
        let text = std::fs::read_to_string(&f).unwrap();
        let mut phrases = vec![name(&f), "the OpenDRIVE map".to_owned()];
        if let Some(p) = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("<!-- expect: "))
            .and_then(|l| l.strip_suffix(" -->"))
        {
            phrases.push(p.to_owned());
        }
        let phrases: Vec<&str> = phrases.iter().map(String::as_str).collect();
        // Every case is judged; the failures are listed together.
        if let Err(e) = std::panic::catch_unwind(|| assert_refused(&rel(&f), &o, &phrases)) {
            failures.push(
                e.downcast_ref::<String>()
                    .cloned()
                    .unwrap_or_else(|| rel(&f)),
            );
        }
        assert!(
            !out.join("results.jsonl").exists(),
            "{}: nothing runs",
            rel(&f)
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn a_50_mb_map_is_refused_by_its_size_before_it_is_parsed() {
    let tmp = tempfile::tempdir().unwrap();
    let big = tmp.path().join("huge.xodr");
    let valid = std::fs::read_to_string(root().join("scenarios/maps/bend.xodr")).unwrap();
    let padding = format!("<!-- {} -->\n", "x".repeat(50 << 20));
    std::fs::write(
        &big,
        valid.replacen("<OpenDRIVE>", &format!("<OpenDRIVE>\n{padding}"), 1),
    )
    .unwrap();
    assert!(std::fs::metadata(&big).unwrap().len() > 50 << 20);
    let program = map_program(tmp.path(), &big);
    let out = tmp.path().join("out");
    let o = run(
        "fuzz",
        &[
            program.display().to_string(),
            "--budget".into(),
            "1".into(),
            "--out".into(),
            out.display().to_string(),
        ],
    );
    assert_refused(
        "a 50 MB map",
        &o,
        &["huge.xodr", "larger than the limit of 16 MiB"],
    );
}

#[test]
fn bad_space_files() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("tests.csv");
    std::fs::write(&csv, "v\n0.5\n").unwrap();
    let mut cases = files("spaces");
    cases.push(root().join("tests/bad_inputs/spaces"));
    for f in cases {
        let o = run(
            "cover",
            &[
                "estimate".into(),
                "--space".into(),
                rel(&f),
                csv.display().to_string(),
            ],
        );
        assert_refused(&rel(&f), &o, &[&name(&f)]);
    }
}

#[test]
fn bad_csv_files() {
    let mut cases = files("csv");
    cases.push(root().join("tests/bad_inputs/csv"));
    for f in cases {
        let o = run("cover", &["estimate".into(), rel(&f)]);
        assert_refused(&rel(&f), &o, &[&name(&f)]);
    }
}

#[test]
fn bad_results_files_for_every_reader() {
    let tmp = tempfile::tempdir().unwrap();
    // A real campaign's campaign.json, beside which each bad results file is put.
    let base = tmp.path().join("base");
    let o = run(
        "fuzz",
        &[
            "pedestrian-crossing".into(),
            "--budget".into(),
            "2".into(),
            "--out".into(),
            base.display().to_string(),
        ],
    );
    assert!(o.status.code() == Some(0) || o.status.code() == Some(1));
    for f in files("results") {
        let what = rel(&f);
        let o = run(
            "cover",
            &[
                "estimate".into(),
                "--space".into(),
                "pedestrian-crossing".into(),
                what.clone(),
            ],
        );
        assert_refused(&what, &o, &[&name(&f)]);
        if name(&f) == "empty.jsonl" {
            continue; // an empty results file is a campaign that has not started
        }
        let dir = tmp.path().join(name(&f));
        std::fs::create_dir(&dir).unwrap();
        std::fs::copy(base.join("campaign.json"), dir.join("campaign.json")).unwrap();
        std::fs::copy(&f, dir.join("results.jsonl")).unwrap();
        let before = std::fs::read(dir.join("results.jsonl")).unwrap();
        let d = dir.display().to_string();
        let results = dir.join("results.jsonl").display().to_string();
        for args in [
            vec!["report".to_owned(), d.clone()],
            vec!["--resume".to_owned(), "--out".to_owned(), d.clone()],
            vec![
                "replay".to_owned(),
                results.clone(),
                "--id".to_owned(),
                "0".to_owned(),
            ],
        ] {
            let o = run("fuzz", &args);
            assert_refused(&format!("{what} with {}", args[0]), &o, &["results.jsonl"]);
        }
        // A refused resume loses nothing.
        if name(&f) != "binary_garbage.jsonl" {
            let after = std::fs::read(dir.join("results.jsonl")).unwrap();
            let whole = |b: &[u8]| b.iter().rposition(|&c| c == b'\n').map_or(0, |i| i + 1);
            assert_eq!(&after[..whole(&after)], &before[..whole(&before)], "{what}");
        }
    }
}

#[test]
fn bad_command_lines() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir(tmp.path().join("empty")).unwrap();
    let text = std::fs::read_to_string(root().join("tests/bad_inputs/args.txt")).unwrap();
    let mut n = 0;
    for line in text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
    {
        let (cmd, expect) = line.split_once(" => ").expect("TOOL ARGS => phrase");
        let words = shlex::split(&cmd.replace("{TMP}", &tmp.path().display().to_string()))
            .expect("a shell-like line");
        let o = run(&words[0], &words[1..]);
        assert_refused(line, &o, &[expect]);
        n += 1;
    }
    assert!(n >= 30, "{n} cases");
}

/// A sum of 290 terms (under the expression depth limit of 300) loads and runs its tests on
/// the worker threads; 1,000 terms (`scenarios/long_sum.star`) is refused at load.
#[test]
fn a_long_expression_under_the_depth_limit_runs_on_the_workers() {
    let tmp = tempfile::tempdir().unwrap();
    let program = tmp.path().join("sum.star");
    let sum = vec!["x"; 290].join(" + ");
    std::fs::write(
        &program,
        format!(
            "x = VarInterval(1.0, 2.0, unit = \"m\")\ny = {sum}\nw = World(light = 0.5, fog = 0.0)\nr = RoadSegment(len = 200.0 + y * 0.0, nlanes = 2)\nv = AutonomousVehicle(loc = r.onLane(1, 10), sut = \"aeb\")\nw.place(r, v)\nCollisionMonitor(v)\ntest(horizon = 1.0)\n"
        ),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = run(
        "fuzz",
        &[
            program.display().to_string(),
            "--budget".into(),
            "4".into(),
            "--jobs".into(),
            "2".into(),
            "--out".into(),
            out.display().to_string(),
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let lines = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 4);
}

/// OpenSCENARIO files (`tests/bad_inputs/xosc/`): `paracosm-fuzz xosc FILE` refuses each
/// with exit 2, the file's name with a line and column, and the phrase its first line
/// `<!-- expect: PHRASE -->` gives; and a file past the size limit is refused unread.
#[test]
fn bad_openscenario_files() {
    let mut failures = Vec::new();
    let at = regex::Regex::new(r"\.xosc:\d+:\d+").unwrap();
    for f in files("xosc") {
        let o = run("fuzz", &["xosc".into(), f.display().to_string()]);
        let text = std::fs::read_to_string(&f).unwrap();
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("<!-- expect: "))
            .and_then(|l| l.strip_suffix(" -->"))
            .unwrap_or_else(|| panic!("{} has no expect line", rel(&f)))
            .to_owned();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        // file:line:col of the element at fault (the missing scenario is named by path).
        let located = at.is_match(&stderr);
        if let Err(e) = std::panic::catch_unwind(|| {
            assert_refused(&rel(&f), &o, &[&name(&f), &expect]);
            assert!(located, "{}: no file:line:col in\n{stderr}", rel(&f));
        }) {
            failures.push(
                e.downcast_ref::<String>()
                    .cloned()
                    .unwrap_or_else(|| rel(&f)),
            );
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    let tmp = tempfile::tempdir().unwrap();
    let huge = tmp.path().join("huge.xosc");
    let f = std::fs::File::create(&huge).unwrap();
    f.set_len(paracosm_openscenario::text::MAX_FILE_BYTES + 1)
        .unwrap();
    let o = run("fuzz", &["xosc".into(), huge.display().to_string()]);
    assert_refused(
        "huge.xosc",
        &o,
        &["huge.xosc", "larger than the limit of 64 MiB"],
    );
}
