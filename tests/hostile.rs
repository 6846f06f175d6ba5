//! Issue 22: hostile cases that are not a bad input file (those are in `tests/bad_inputs/`):
//! runs that must end with a clear error or a warning rather than hang, abort or mislead.

mod common;
use common::{fuzz, records};

#[test]
fn a_parameter_range_wider_than_a_float_spans_is_refused_at_load() {
    // hi - lo overflows: every point would decode to an infinity (and the plots' axes loop).
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("huge.star");
    std::fs::write(
        &program,
        "x = VarInterval(-1e308, 1e308)\n\
         w = World(light = 0.5, fog = min(0.0, abs(x)))\n\
         r = RoadSegment(len = 200.0, nlanes = 2)\n\
         v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)\n\
         w.place(r, v)\n\
         CollisionMonitor(v)\n\
         test(horizon = 2.0)\n",
    )
    .unwrap();
    let out = dir.path().join("o");
    let o = fuzz(&[
        program.to_str().unwrap(),
        "--budget",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("wider than a float can hold"), "{err}");
    assert!(err.contains("huge.star:1:5"), "{err}");
    assert!(!out.join("results.jsonl").exists());
}

/// A program whose fog is `fog` (a stream expression over `k` in [0, 1)), on an empty road.
fn program(dir: &std::path::Path, fog: &str, extra: &str) -> std::path::PathBuf {
    let p = dir.join("p.star");
    std::fs::write(
        &p,
        format!(
            "k = VarInterval(0.0, 1.0)\n\
             {extra}\n\
             w = World(light = 0.5, fog = {fog})\n\
             r = RoadSegment(len = 200.0 + k, nlanes = 2)\n\
             v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)\n\
             w.place(r, v)\n\
             CollisionMonitor(v)\n\
             DistanceMonitor(v, minD = 5.0)\n\
             test(horizon = 2.0)\n"
        ),
    )
    .unwrap();
    p
}

#[test]
fn a_lambda_past_the_step_or_heap_limit_ends_its_test_and_the_campaign_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "steps",
            "def slow(t):\n    n = 0\n    for i in range(1000000000):\n        n += i\n    return 0.0",
            "step limit exceeded: a lambda took more than 1000000 steps",
        ),
        (
            "heap",
            "def slow(t):\n    l = []\n    for i in range(100):\n        l.append(\"a\" * 1000000)\n    return 0.0",
            "heap limit: a lambda allocated more than 64 MiB in one call",
        ),
    ];
    for (name, def, phrase) in cases {
        let p = program(
            dir.path(),
            "tick.map(lambda t: 0.0 if t < 1.0 or k < 0.5 else slow(t))",
            def,
        );
        let out = dir.path().join(name);
        let o = fuzz(&[
            p.to_str().unwrap(),
            "--budget",
            "4",
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        // Exit 3: some tests ended in error; every test has its record.
        assert_eq!(o.status.code(), Some(3), "{name}: {err}");
        let r = records(&out);
        assert_eq!(r.len(), 4, "{name}");
        for rec in &r {
            let k = rec["params"]["k"].as_f64().unwrap();
            if k < 0.5 {
                assert_eq!(rec["status"], "pass", "{name}: {rec}");
            } else {
                assert_eq!(rec["status"], "error", "{name}: {rec}");
                let e = rec["error"].as_str().unwrap();
                assert!(e.contains(phrase), "{name}: {e}");
                assert!(e.contains("p.star:"), "{name}: the lambda's place: {e}");
            }
        }
        assert!(out.join("summary.json").exists(), "{name}");
    }
}

#[test]
fn a_lambda_allocating_past_the_hard_limit_exits_2_and_keeps_the_results_written() {
    // Halton in 1-D: k = 0, 0.5, 0.25, 0.75; only the last one allocates 800 MB.
    let dir = tempfile::tempdir().unwrap();
    let p = program(
        dir.path(),
        "tick.map(lambda t: 0.0 if t < 1.0 or k < 0.7 else len([0] * 100000000) * 0.0)",
        "",
    );
    let out = dir.path().join("o");
    let o = fuzz(&[
        p.to_str().unwrap(),
        "--budget",
        "4",
        "--jobs",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with(
            "paracosm-fuzz: error: a lambda, during a test, exceeded the heap limit of 256 MiB"
        ),
        "{err}"
    );
    assert!(err.contains("p.star"), "{err}");
    let r = records(&out);
    assert_eq!(r.len(), 3, "the three tests before it are kept");
    assert!(r.iter().all(|x| x["status"] == "pass"));
}

#[test]
fn an_stl_bound_past_the_horizon_is_lowered_with_a_warning_and_judges_as_before() {
    let dir = tempfile::tempdir().unwrap();
    let mut outs = Vec::new();
    for (name, bound) in [("huge", "1e308"), ("horizon", "2")] {
        let p = dir.path().join(format!("{name}.star"));
        std::fs::write(
            &p,
            format!(
                "k = VarInterval(1.0, 5.0)\n\
                 w = World(light = 0.5, fog = 0.0)\n\
                 r = RoadSegment(len = 200.0, nlanes = 2)\n\
                 v = AutonomousVehicle(loc = r.onLane(1, 10), speed = k)\n\
                 w.place(r, v)\n\
                 DistanceMonitor(v, minD = 5.0)\n\
                 Stl(\"G[0,{bound}] (ego_speed_mps > 2)\", name = \"fast\")\n\
                 test(horizon = 2.0)\n"
            ),
        )
        .unwrap();
        let out = dir.path().join(name);
        let o = fuzz(&[
            p.to_str().unwrap(),
            "--budget",
            "8",
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(
            err.contains("time bounds past the test's horizon of 2 s are lowered to 3 s"),
            name == "huge",
            "{name}: {err}"
        );
        outs.push(records(&out));
    }
    // Same verdicts, robustness and length; a passing test ran its whole horizon (before,
    // the bound 1e308 stopped every test at 0.25 s with a false failure).
    for (a, b) in outs[0].iter().zip(&outs[1]) {
        assert_eq!(a["monitors"], b["monitors"]);
        assert_eq!(a["metrics"]["simulated_s"], b["metrics"]["simulated_s"]);
        if a["status"] == "pass" {
            assert_eq!(a["metrics"]["simulated_s"], 2.0);
        }
    }
    assert!(outs[0].iter().any(|r| r["status"] == "fail"));
    assert!(outs[0].iter().any(|r| r["status"] == "pass"));
}

#[test]
fn two_hundred_open_parameters_get_a_summary_with_cheap_coverage_brackets() {
    // Exact dispersion in 200 dimensions never ended, so summary.json was never written.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p200.star");
    let mut src: Vec<String> = (0..200)
        .map(|i| format!("p{i} = VarInterval(0.0, 1.0)"))
        .collect();
    src.push(format!(
        "total = {}",
        (0..200)
            .map(|i| format!("p{i}"))
            .collect::<Vec<_>>()
            .join(" + ")
    ));
    src.extend(
        [
            "w = World(light = 0.5, fog = 0.0)",
            "r = RoadSegment(len = 200.0 + total, nlanes = 2)",
            "v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)",
            "w.place(r, v)",
            "CollisionMonitor(v)",
            "test(horizon = 1.0)",
        ]
        .map(str::to_owned),
    );
    std::fs::write(&p, src.join("\n") + "\n").unwrap();
    let out = dir.path().join("o");
    let o = fuzz(&[
        p.to_str().unwrap(),
        "--budget",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let cov = &summary["coverage"];
    let d = &cov["dispersion"];
    assert_eq!(d["upper"], 1.0);
    assert!(d["lower"].as_f64().unwrap() > 0.5, "{d}");
    assert!(
        d["method"].as_str().unwrap().contains("search limits"),
        "{d}"
    );
    let s = &cov["star"];
    assert!(
        s["method"].as_str().unwrap().contains("search limits"),
        "{s}"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("star discrepancy in ["), "{stdout}");
}
