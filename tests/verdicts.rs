//! Issue 14: verdicts a tester can trust. Each silent case the issue lists, run on the
//! scenario files of `tests/scenarios/` (each says in its header what it must show).

mod common;

use std::path::{Path, PathBuf};

use common::{expect_code, fuzz};
use paracosm_generators::Point;
use serde_json::Value;

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/scenarios")
        .join(name)
}

/// Runs a campaign of `budget` Halton tests of `file` into `out`, with `extra` arguments.
fn campaign(file: &Path, budget: u32, out: &Path, extra: &[&str]) -> std::process::Output {
    let budget = budget.to_string();
    let mut args = vec![
        file.to_str().unwrap(),
        "--budget",
        &budget,
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    fuzz(&args)
}

fn records(out: &Path) -> Vec<Value> {
    std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn summary(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A copy of scenario `name` with `from` replaced by `to`, in `dir`.
fn variant(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenario(name)).unwrap();
    assert!(text.contains(from), "{name} has no {from:?}");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    path
}

#[test]
fn a_formula_decided_at_once_changes_no_collision_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let (alone, with_stl) = (dir.path().join("alone"), dir.path().join("stl"));
    expect_code(
        &campaign(&scenario("fog_slow_car.star"), 16, &alone, &[]),
        1,
    );
    expect_code(
        &campaign(&scenario("fog_slow_car_stl.star"), 16, &with_stl, &[]),
        1,
    );
    let (a, b) = (records(&alone), records(&with_stl));
    let collisions = a
        .iter()
        .filter(|r| r["monitors"]["collision"]["passed"] == false)
        .count();
    assert!(
        (1..16).contains(&collisions),
        "the fog must hide the car in some tests but not all: {collisions} of 16"
    );
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(
            x["monitors"]["collision"], y["monitors"]["collision"],
            "test {}",
            x["id"]
        );
        assert_eq!(x["status"], y["status"], "test {}", x["id"]);
        // The formula settled at once and kept its verdict: the ego moved at 12 m/s at t = 0.
        assert_eq!(y["monitors"]["moving"]["passed"], true);
        assert!((y["monitors"]["moving"]["robustness"].as_f64().unwrap() - 11.0).abs() < 0.1);
    }
}

/// The robustness of monitor `name` in the one test of a parameterless program.
fn robustness_of(file: &str, name: &str) -> f64 {
    let s = paracosm_scenarios::load(scenario(file).to_str().unwrap()).unwrap();
    let a = s
        .space()
        .decode(&Point {
            discrete: vec![],
            continuous: vec![],
        })
        .unwrap();
    let o = s.run(&a, 0).unwrap();
    o.monitors
        .iter()
        .find(|(n, _)| n == name)
        .unwrap()
        .1
        .robustness
}

#[test]
fn a_monitors_robustness_does_not_depend_on_the_other_monitors() {
    let alone = robustness_of("rising_fog_always.star", "always");
    let both = robustness_of("rising_fog_both.star", "always");
    assert_eq!(alone.to_bits(), both.to_bits());
    // The signal `fog` is the fog now: at the last frame, t = 20 s, it peaks at 20 / 40 (it
    // read the value of the step before, (20 - 1/60) / 40, until the snapshot evaluated the
    // world's streams at its own time); cut at 0.25 s the robustness would be 0.894.
    let peak = 20.0 / 40.0;
    assert!((alone - (0.9 - peak)).abs() < 1e-9, "{alone}");
    assert!((robustness_of("rising_fog_both.star", "now") - 0.9).abs() < 1e-9);
}

#[test]
fn a_wet_patch_changes_outcomes_that_a_dry_patch_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let wet = dir.path().join("wet");
    campaign(&scenario("wet_patch.star"), 16, &wet, &[]);
    let wet_failures = summary(&wet)["counts"]["fail"].as_u64().unwrap();
    let dry_file = variant(
        dir.path(),
        "wet_patch.star",
        "VarInterval(0.1, 0.5)",
        "VarInterval(0.85, 0.9)",
    );
    let dry = dir.path().join("dry");
    expect_code(&campaign(&dry_file, 16, &dry, &[]), 0);
    assert_eq!(summary(&dry)["counts"]["fail"], 0);
    assert!(
        wet_failures >= 4,
        "on a wet patch the ego slides into the parked car: {wet_failures} of 16 failed"
    );
    // The failures are the slippery end of the patch's range.
    let recs = records(&wet);
    let friction = |r: &Value| r["params"]["patch_friction"].as_f64().unwrap();
    let worst_pass = recs
        .iter()
        .filter(|r| r["status"] == "pass")
        .map(friction)
        .fold(f64::INFINITY, f64::min);
    let best_fail = recs
        .iter()
        .filter(|r| r["status"] == "fail")
        .map(friction)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        best_fail < worst_pass,
        "fail up to {best_fail}, pass from {worst_pass}"
    );
}

#[test]
fn driving_off_a_dead_end_fails_the_default_offroad_monitor() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("default");
    expect_code(&campaign(&scenario("dead_end.star"), 1, &out, &[]), 1);
    let r = &records(&out)[0];
    let off = &r["monitors"]["offroad"];
    assert_eq!(off["passed"], false, "{r}");
    // 100 m from x = 10 to the end at 12 m/s: about 7.5 s (aeb accelerates a little).
    let t = off["first_violation_s"].as_f64().unwrap();
    assert!((7.0..9.0).contains(&t), "left the road at {t} s");
    assert!(off["robustness"].as_f64().unwrap() <= 0.0);
    assert_eq!(r["monitors"]["collision"]["passed"], true);
    assert_eq!(r["monitors"]["collision"]["cut_short"], true);

    // Declared explicitly, it takes its own name and no default is added.
    let named = variant(
        dir.path(),
        "dead_end.star",
        "CollisionMonitor(v)",
        "CollisionMonitor(v)\nOffRoadMonitor(v, name = \"road\")",
    );
    let out = dir.path().join("named");
    expect_code(&campaign(&named, 1, &out, &[]), 1);
    let r = &records(&out)[0];
    assert_eq!(r["monitors"]["road"]["passed"], false);
    assert!(r["monitors"].get("offroad").is_none(), "{r}");

    // Opting out leaves the leaving unjudged: a pass, by the program's own choice.
    let opted = variant(
        dir.path(),
        "dead_end.star",
        "test(horizon = 15.0)",
        "test(horizon = 15.0, offroad = False)",
    );
    let out = dir.path().join("opted");
    expect_code(&campaign(&opted, 1, &out, &[]), 0);
    assert!(records(&out)[0]["monitors"].get("offroad").is_none());
}

#[test]
fn mistyped_inputs_are_refused_at_load_with_file_line_col() {
    let dir = tempfile::tempdir().unwrap();
    for (file, message, at) in [
        (
            "fog_string.star",
            "World(fog=) takes a number in [0, 1], got \"thick\" (a string)",
            "fog_string.star:4:5",
        ),
        (
            "car_speed_string.star",
            "Car(speed=) takes a number in m/s, >= 0, got \"fast\" (a string)",
            "car_speed_string.star:7:5",
        ),
        (
            "fog_out_of_range.star",
            "World(fog=) takes a number in [0, 1], got 3 (a number)",
            "fog_out_of_range.star:6:5",
        ),
        (
            "fog_out_of_range.star",
            "(the world fails for the test values fog = 3)",
            "fog_out_of_range.star:6:5",
        ),
    ] {
        let out = dir.path().join(file);
        let o = campaign(&scenario(file), 3, &out, &[]);
        expect_code(&o, 2);
        let e = stderr(&o);
        assert!(e.contains(message), "{file}: {e}");
        assert!(e.contains(at), "{file}: {e}");
        assert!(!out.join("results.jsonl").exists());
    }
}

#[test]
fn a_computed_stream_of_the_wrong_type_ends_its_test_as_an_error_and_the_campaign_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = campaign(&scenario("speed_lambda_string.star"), 4, &out, &[]);
    expect_code(&o, 3);
    let recs = records(&out);
    assert_eq!(recs.len(), 4);
    for r in &recs {
        assert_eq!(r["status"], "error");
        let e = r["error"].as_str().unwrap();
        let switch = r["params"]["switch"].as_f64().unwrap();
        let t: f64 = e
            .strip_prefix("at t = ")
            .and_then(|rest| rest.split(' ').next())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("no time in {e}"));
        // The first step at or after `switch` seconds (60 steps a second).
        assert!(
            t >= switch - 1e-9 && t < switch + 1.0 / 60.0 + 1e-3,
            "{t} vs {switch}: {e}"
        );
        for part in [
            "the speed of Car c (",
            "speed_lambda_string.star:14:5",
            "was \"fast\" (a string)",
            "must be a number in m/s, >= 0",
        ] {
            assert!(e.contains(part), "{part:?} not in {e}");
        }
    }
    assert_eq!(summary(&out)["counts"]["error"], 4);
}

#[test]
fn warnings_are_printed_once_per_campaign_and_deny_warnings_refuses_to_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("warned");
    let o = campaign(&scenario("no_monitor.star"), 6, &out, &[]);
    expect_code(&o, 0);
    let e = stderr(&o);
    assert_eq!(e.matches("declares no monitor").count(), 1, "{e}");
    assert!(e.contains("no_monitor.star:10:1"), "{e}");
    let s = summary(&out);
    assert_eq!(s["warnings"].as_array().unwrap().len(), 1);

    let denied = dir.path().join("denied");
    let o = campaign(
        &scenario("no_monitor.star"),
        6,
        &denied,
        &["--deny-warnings"],
    );
    expect_code(&o, 2);
    assert!(stderr(&o).contains("--deny-warnings"));
    assert!(!denied.join("results.jsonl").exists());
}

#[test]
fn an_unused_parameter_is_named_listed_and_left_out_of_coverage() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = campaign(&scenario("unused_param.star"), 12, &out, &[]);
    let e = stderr(&o);
    assert!(
        e.contains("`nlanes` is sampled but no object uses it"),
        "{e}"
    );
    assert!(e.contains("unused_param.star:5:10"), "{e}");
    let s = summary(&out);
    assert_eq!(s["unused_params"], serde_json::json!(["nlanes"]));
    let cov = &s["coverage"];
    assert_eq!(cov["continuous"], serde_json::json!(["speed", "dist"]));
    assert_eq!(cov["discrete"], serde_json::json!([]));
    assert!(cov["kwise"].as_array().unwrap().is_empty());
    // Still sampled and recorded.
    assert!(records(&out)[0]["params"].get("nlanes").is_some());
}

#[test]
fn inputs_that_cannot_affect_the_ego_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let o = campaign(
        &scenario("unreachable_friction.star"),
        2,
        &dir.path().join("friction"),
        &[],
    );
    let e = stderr(&o);
    assert!(
        e.contains("`wet` sets the friction of RoadSegment far"),
        "{e}"
    );
    assert!(e.contains("it cannot affect the ego"), "{e}");

    // A colour only a camera sees: named for `aeb` (lidar), not for `vision`.
    let o = campaign(
        &scenario("first_param_enum.star"),
        2,
        &dir.path().join("aeb"),
        &[],
    );
    assert!(
        stderr(&o).contains("`lead_color` sets the colour of Car "),
        "{}",
        stderr(&o)
    );
    // Only a campaign that rendered names the adapter it rendered with.
    assert!(!stderr(&o).contains("camera renderer"), "{}", stderr(&o));
    let o = campaign(
        &scenario("first_param_enum.star"),
        2,
        &dir.path().join("vision"),
        &["--sut", "vision"],
    );
    assert!(!stderr(&o).contains("lead_color"), "{}", stderr(&o));
    let named = stderr(&o)
        .lines()
        .find_map(|l| l.strip_prefix("paracosm-fuzz: camera renderer: "))
        .map(str::to_owned);
    assert!(
        named.is_some_and(|a| a.contains("Vulkan") || a.contains("Gl")),
        "{}",
        stderr(&o)
    );
}

/// The texts an SVG shows.
fn svg_texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap();
    let re = regex::Regex::new(r"<text[^>]*>\s*([^<]*?)\s*</text>").unwrap();
    re.captures_iter(&svg).map(|c| c[1].to_owned()).collect()
}

#[test]
fn every_campaign_ends_with_a_summary_whatever_its_parameters() {
    let dir = tempfile::tempdir().unwrap();
    // (file, texts the failure map must show; None: no map at all)
    let cases: [(&str, Option<&[&str]>); 5] = [
        ("no_params.star", None),
        ("one_param.star", Some(&["fog", "outcome", "pass", "fail"])),
        (
            "all_discrete.star",
            Some(&["lead_color", "lead_speed", "red", "white", "0", "6"]),
        ),
        ("first_param_enum.star", Some(&["lead_color", "fog", "red"])),
        (
            "map_discrete.star",
            Some(&["lead_color", "oncoming", "true", "false"]),
        ),
    ];
    for (file, texts) in cases {
        let out = dir.path().join(file);
        let o = campaign(&scenario(file), 8, &out, &[]);
        let code = o.status.code();
        assert!(
            matches!(code, Some(0 | 1)),
            "{file}: {code:?}\n{}",
            stderr(&o)
        );
        let s = summary(&out);
        let c = &s["counts"];
        let total = c["pass"].as_u64().unwrap() + c["fail"].as_u64().unwrap();
        assert_eq!(total, 8, "{file}: {c}");
        match texts {
            None => {
                assert!(!out.join("failure_map.png").exists(), "{file}");
                assert!(s["coverage"].is_null());
                assert!(!s["outputs"].to_string().contains("failure_map"));
            }
            Some(texts) => {
                for plot in ["failure_map.png", "failure_map.svg", "failure_rate.svg"] {
                    assert!(out.join(plot).exists(), "{file}: {plot}");
                }
                let shown = svg_texts(&out.join("failure_map.svg"));
                for t in texts {
                    assert!(shown.iter().any(|s| s == t), "{file}: {t} not in {shown:?}");
                }
            }
        }
    }
}

#[test]
fn a_plot_that_cannot_be_drawn_is_a_warning_and_costs_no_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    expect_code(&campaign(&scenario("one_param.star"), 4, &out, &[]), 0);
    std::fs::remove_file(out.join("summary.json")).unwrap();
    // Files of at most 8 KiB (`ulimit -f`, SIGXFSZ ignored: a longer write fails with
    // EFBIG): the summary (1.6 KB) fits, the plots' PNGs (10 to 14 KB) do not. (A directory planted at a plot's path
    // is now refused before any work, exit 2.)
    let o = std::process::Command::new("bash")
        .args([
            "-c",
            "trap '' XFSZ; ulimit -f 8; exec \"$0\" \"$@\"",
            env!("CARGO_BIN_EXE_paracosm-fuzz"),
            "--resume",
            "--out",
            out.to_str().unwrap(),
        ])
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    expect_code(&o, 0);
    assert!(
        stderr(&o).contains("warning: the plot failure_map was not drawn"),
        "{}",
        stderr(&o)
    );
    let s = summary(&out);
    assert_eq!(s["counts"]["pass"], 4);
    let outputs = s["outputs"].to_string();
    assert!(
        outputs.contains("results.jsonl") && !outputs.contains("failure_map"),
        "{outputs}"
    );
    assert!(s["warnings"]
        .to_string()
        .contains("failure_map was not drawn"));
}
