//! Failure triage (issue 18): the failure rules recover known failure regions, the irrelevant
//! parameters rank last, and `report` redraws the plots on any parameters from the records.

mod common;

use std::path::Path;

use common::{expect_code, fuzz};
use serde_json::Value as Json;

fn summary(dir: &Path) -> Json {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The bounds of the rule's condition on `param`: `(lo, hi)`, `None` for an open side.
fn bounds(rule: &Json, param: &str) -> (Option<f64>, Option<f64>) {
    let c = rule["conditions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["param"] == param)
        .unwrap_or_else(|| panic!("no condition on {param} in {rule}"));
    (c["lo"].as_f64(), c["hi"].as_f64())
}

#[test]
fn the_rules_recover_a_box_in_four_dimensions_and_the_irrelevant_parameters_rank_last() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box");
    let o = fuzz(&[
        "tests/scenarios/failure_box.star",
        "--strategy",
        "halton",
        "--budget",
        "1000",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let s = summary(&out);
    let t = &s["triage"];
    let rules = t["rules"].as_array().unwrap();
    assert_eq!(rules.len(), 1, "one region: {rules:?}");
    let rule = &rules[0];
    // One grid step: the finest failure-rate grid has 16 cells over the 10-unit range.
    let step = 10.0 / 16.0;
    let (a_lo, a_hi) = bounds(rule, "a");
    let (b_lo, b_hi) = bounds(rule, "b");
    for (got, want) in [(a_lo, 2.0), (a_hi, 6.0), (b_lo, 3.0), (b_hi, 8.0)] {
        let got = got.expect("both sides bounded");
        assert!((got - want).abs() < step, "bound {got} vs {want}");
    }
    assert_eq!(rule["conditions"].as_array().unwrap().len(), 2);
    let failed = s["counts"]["fail"].as_u64().unwrap();
    assert_eq!(rule["failed"].as_u64(), Some(failed));
    assert_eq!(
        rule["tests"].as_u64(),
        Some(failed),
        "the box holds only failures"
    );
    let ranking: Vec<&str> = t["ranking"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["param"].as_str().unwrap())
        .collect();
    assert_eq!(ranking.len(), 4);
    let mut first_two = ranking[..2].to_vec();
    first_two.sort();
    assert_eq!(first_two, ["a", "b"], "ranking {ranking:?}");
    for r in &t["ranking"].as_array().unwrap()[2..] {
        assert_eq!(r["importance"].as_f64(), Some(0.0));
        assert!(r["association"].as_f64().unwrap().abs() < 0.1, "{r}");
    }
    // The console names the region in words.
    let stdout = String::from_utf8_lossy(&o.stdout);
    let text = rule["text"].as_str().unwrap();
    assert!(stdout.contains(text), "{stdout}");
    assert!(
        text.contains(" ≤ a < ") && text.contains(" m and ") && text.ends_with(" failed"),
        "{text}"
    );
}

#[test]
fn a_region_bounded_by_a_level_names_the_level() {
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("levels.star");
    std::fs::write(
        &program,
        r#"
speed = VarInterval(0, 20, unit = "m/s")
road = VarEnum(["dry", "wet", "icy"])
noise = VarInterval(0, 1)
w = World(light = 0.5, fog = 0.0)
r = RoadSegment(len = 100.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10))
w.place(r, v)
slips = road == "icy" and speed >= 12.0
grip = Monitor(tick.map(lambda t: -1.0 if slips else 1.0), over = "end")
test(horizon = 0.1)
"#,
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        program.to_str().unwrap(),
        "--strategy",
        "random",
        "--budget",
        "600",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let s = summary(&out);
    let rules = s["triage"]["rules"].as_array().unwrap();
    assert_eq!(rules.len(), 1, "{rules:?}");
    let text = rules[0]["text"].as_str().unwrap();
    assert!(text.starts_with("speed ≥ 1"), "{text}");
    assert!(text.contains(" m/s and road = icy: "), "{text}");
    let (lo, hi) = bounds(&rules[0], "speed");
    assert!(
        (lo.unwrap() - 12.0).abs() < 20.0 / 16.0 && hi.is_none(),
        "{text}"
    );
    let levels = rules[0]["conditions"][1]["levels"].as_array().unwrap();
    assert_eq!(levels, &[Json::from("icy")]);
    assert_eq!(s["triage"]["ranking"][2]["param"], "noise");
}

#[test]
fn few_tests_give_no_triage_and_without_failures_there_is_a_ranking_but_no_rule() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("few");
    let o = fuzz(&[
        "tests/scenarios/failure_box.star",
        "--budget",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.code() == Some(0) || o.status.code() == Some(1));
    assert!(summary(&out)["triage"].is_null(), "5 tests: too few");
    assert!(!String::from_utf8_lossy(&o.stdout).contains("where failures are"));

    let program = dir.path().join("passes.star");
    std::fs::write(
        &program,
        r#"
a = VarInterval(0, 1, unit = "m")
b = VarInterval(0, 1, unit = "m")
w = World(light = 0.5, fog = 0.0)
r = RoadSegment(len = 100.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10))
w.place(r, v)
margin = Monitor(tick.map(lambda t: 0.1 + 0.5 * a), unit = "m", over = "end")
test(horizon = 0.1)
"#,
    )
    .unwrap();
    let out = dir.path().join("passes");
    let o = fuzz(&[
        program.to_str().unwrap(),
        "--budget",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let t = &summary(&out)["triage"];
    assert_eq!(t["rules"].as_array().unwrap().len(), 0);
    assert_eq!(t["failed"].as_u64(), Some(0));
    // The robustness is 0.1 + a / 2 (below the offroad margin of 1.75 m): a ranks first, with ρ = 1.
    assert_eq!(t["ranking"][0]["param"], "a");
    assert!((t["ranking"][0]["association"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!stdout.contains("where failures are"), "{stdout}");
    assert!(
        stdout.contains("parameters by relevance: a (importance 0.00, ρ +1.00)"),
        "{stdout}"
    );
    // Above the default off-road monitor's margin (1.75 m in the middle of a lane): the
    // test's robustness is the falsifiers' cost, which counts that monitor only where it
    // fails, so `a` still ranks first with ρ = 1 (every test read 1.75 m, and ρ was 0).
    std::fs::write(
        &program,
        std::fs::read_to_string(&program)
            .unwrap()
            .replace("0.1 + 0.5 * a", "5.0 + a"),
    )
    .unwrap();
    let out = dir.path().join("above");
    let o = fuzz(&[
        program.to_str().unwrap(),
        "--budget",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let t = &summary(&out)["triage"];
    assert_eq!(t["ranking"][0]["param"], "a", "{t}");
    assert!(
        (t["ranking"][0]["association"].as_f64().unwrap() - 1.0).abs() < 1e-12,
        "{t}"
    );
    // The report's per-test robustness too (its colours).
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    let at = report
        .find("\"robustness\":[")
        .expect("the tests' robustness")
        + 14;
    let first: f64 = report[at..]
        .split([',', ']'])
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((5.0..6.0).contains(&first), "{first}");
}

/// The texts an SVG shows.
fn svg_texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap();
    let re = regex::Regex::new(r"<text[^>]*>\s*([^<]*?)\s*</text>").unwrap();
    re.captures_iter(&svg).map(|c| c[1].to_owned()).collect()
}

#[test]
fn report_redraws_the_maps_on_any_two_parameters_colours_by_robustness_and_draws_the_pairs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box");
    let o = fuzz(&[
        "tests/scenarios/failure_box.star",
        "--budget",
        "500",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    // Every campaign writes the pairs plot and the page, and lists them.
    let s = summary(&out);
    for f in ["pairs.png", "pairs.svg", "report.html"] {
        assert!(out.join(f).is_file(), "{f}");
        assert!(
            s["outputs"].as_array().unwrap().contains(&Json::from(f)),
            "{f}"
        );
    }
    let pairs = svg_texts(&out.join("pairs.svg"));
    for label in [
        "a [m]",
        "b [m/s]",
        "c [s]",
        "d",
        "dry",
        "wet",
        "icy",
        "failure rate",
    ] {
        assert!(
            pairs.iter().any(|t| t == label),
            "pairs lacks {label}: {pairs:?}"
        );
    }
    std::fs::remove_file(out.join("pairs.svg")).unwrap();

    let o = fuzz(&[
        "report",
        out.to_str().unwrap(),
        "--map",
        "c,d",
        "--color",
        "robustness",
        "--pairs",
    ]);
    expect_code(&o, 1);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let map = out.join("failure_map-c-d-robustness.svg");
    let rate = out.join("failure_rate-c-d.svg");
    assert!(stdout.contains(&map.display().to_string()), "{stdout}");
    assert!(
        out.join("pairs.svg").is_file(),
        "--pairs redraws the matrix"
    );
    let texts = svg_texts(&map);
    assert!(texts.iter().any(|t| t == "c [s]") && texts.iter().any(|t| t == "d"));
    assert!(texts
        .iter()
        .any(|t| t == "robustness (smallest over monitors)"));
    // 500 tests over a continuous and a three-level axis: about 5 per cell gives
    // round(500 / 15) = 33, at most 16 cells along c, so 16 x 3 cells, each labelled.
    let cells = svg_texts(&rate)
        .into_iter()
        .filter(|t| regex::Regex::new(r"^\d+/\d+$").unwrap().is_match(t))
        .count();
    assert_eq!(cells, 16 * 3);

    for (args, message) in [
        (
            vec!["--map", "a,nope"],
            "`nope` is not a parameter of the scenario; its parameters: a, b, c, d",
        ),
        (
            vec!["--map", "a,b,c"],
            "--map takes one or two parameters, got 3",
        ),
    ] {
        let mut all = vec!["report", out.to_str().unwrap()];
        all.extend(args);
        let o = fuzz(&all);
        expect_code(&o, 2);
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(message),
            "{:?}",
            o
        );
    }
    let o = fuzz(&["report", out.to_str().unwrap(), "--color", "blue"]);
    expect_code(&o, 2);
}
