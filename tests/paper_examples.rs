//! Issue 16: the examples of the paper's §2 and §3.3, as written in `examples/paper/`, run for
//! a few tests each and do what the paper says they do.

mod common;

use std::path::{Path, PathBuf};

use common::{expect_code, fuzz};
use serde_json::Value as Json;

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/paper")
        .join(name)
}

/// Runs `file` for `budget` Halton tests; returns the records without `wall_ms`, and stderr.
fn run(file: &Path, budget: u32, code: i32) -> (Vec<Json>, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        &budget.to_string(),
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, code);
    let records = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(common::untagged_record)
        .collect();
    (records, String::from_utf8_lossy(&o.stderr).into_owned())
}

fn scenario(file: &Path) -> paracosm_scenarios::Scenario {
    paracosm_scenarios::load(file.to_str().unwrap()).unwrap()
}

/// "In this example, there are no open streams. Hence, the behavior is completely determined
/// by the initial state": every test is the same test.
#[test]
fn the_simple_world_has_no_open_stream_and_every_test_is_the_same() {
    let file = example("simple_world.star");
    assert!(scenario(&file).space().params().is_empty());
    let (records, stderr) = run(&file, 3, 0);
    assert!(!stderr.contains("warning"), "{stderr}");
    for r in &records[1..] {
        assert_eq!(r["monitors"], records[0]["monitors"]);
        assert_eq!(r["metrics"], records[0]["metrics"]);
    }
}

/// The family of worlds: six open streams with the paper's ranges and levels.
#[test]
fn the_family_of_worlds_has_the_papers_six_ranges() {
    let s = scenario(&example("family_of_worlds.star"));
    let names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        ["light", "fog", "friction", "nlanes", "dist", "speed"]
    );
    let nlanes = s.space().param("nlanes").unwrap();
    assert_eq!(
        format!("{:?}", nlanes.domain),
        format!(
            "{:?}",
            paracosm_generators::Domain::Levels(vec![
                paracosm_generators::Value::Int(2),
                paracosm_generators::Value::Int(4),
                paracosm_generators::Value::Int(6)
            ])
        )
    );
    let (records, _) = run(&example("family_of_worlds.star"), 4, 1);
    let distinct: std::collections::HashSet<String> =
        records.iter().map(|r| r["params"].to_string()).collect();
    assert_eq!(distinct.len(), 4);
}

/// The pedestrian's behaviour written as the paper writes it (trigger, done,
/// `tick.skipUntil(trigger).takeUntil(done).foreach(p.walk)`) gives byte-identical results to
/// the built-in behaviour of `scenarios/pedestrian_crossing.star` on 500 Halton tests.
#[test]
fn the_pedestrian_behaviour_as_user_code_equals_the_built_in_one_on_500_tests() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (built_in, _) = run(&root.join("scenarios/pedestrian_crossing.star"), 500, 1);
    let (user, stderr) = run(&example("pedestrian_behaviour.star"), 500, 1);
    assert!(!stderr.contains("warning"), "{stderr}");
    assert_eq!(built_in.len(), 500);
    let failed = built_in.iter().filter(|r| r["status"] == "fail").count();
    assert!(failed > 10 && failed < 490, "{failed} failed");
    for (a, b) in built_in.iter().zip(&user) {
        assert_eq!(a, b);
    }
}

/// Both monitors of §2 written as user code agree with the built-in ones on 100 tests: the
/// same verdicts, and the travelled distance's robustness within 1e-9 m.
#[test]
fn the_monitors_as_user_code_agree_with_the_built_in_ones() {
    let (records, _) = run(&example("monitors.star"), 100, 1);
    let mut collisions = 0;
    for r in &records {
        let m = &r["monitors"];
        assert_eq!(m["no_collision"]["passed"], m["collision"]["passed"], "{r}");
        assert_eq!(m["travelled"]["passed"], m["distance"]["passed"], "{r}");
        let (a, b) = (
            m["travelled"]["robustness"].as_f64().unwrap(),
            m["distance"]["robustness"].as_f64().unwrap(),
        );
        assert!((a - b).abs() <= 1e-9, "{a} vs {b}");
        collisions += usize::from(m["collision"]["passed"] == false);
        if m["no_collision"]["passed"] == false {
            assert_eq!(m["no_collision"]["robustness"], -1.0);
        }
    }
    assert!(collisions > 0, "no test collided");
}

/// The T-intersection network of §2 connects, and a vehicle drives through it.
#[test]
fn the_t_intersection_network_connects_and_is_driven_through() {
    let (records, _) = run(&example("t_intersection.star"), 2, 0);
    for r in &records {
        assert_eq!(r["status"], "pass", "{r}");
        assert!(r["metrics"]["simulated_s"].as_f64().unwrap() >= 6.0 - 1e-9);
    }
}

/// The grid built by iteration: its size and block length are open, and each value builds.
#[test]
fn the_grid_is_built_by_iteration_for_every_size() {
    let (records, _) = run(&example("grid.star"), 4, 0);
    let sizes: std::collections::HashSet<i64> = records
        .iter()
        .map(|r| r["params"]["N"].as_i64().unwrap())
        .collect();
    assert_eq!(sizes.len(), 2);
    assert!(records.iter().all(|r| r["status"] == "pass"));
}

/// §3.3: the fog as a cubic over the test is four coefficients, and the fog it gives stays
/// within [0, 1] (an `Stl` property of the published fog, which passes).
#[test]
fn the_fog_polynomial_is_four_coefficients() {
    let s = scenario(&example("fog_polynomial.star"));
    let names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["fog.c0", "fog.c1", "fog.c2", "fog.c3"]);
    let (records, _) = run(&example("fog_polynomial.star"), 3, 0);
    for r in &records {
        assert_eq!(r["monitors"]["fog_in_range"]["passed"], true, "{r}");
    }
}
