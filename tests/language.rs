//! Issue 16: the reactive language in full. Locations are values with coordinates; positions
//! subtract, measure and compare; math builtins; lambdas read the current value of the streams
//! they capture; the paper's trigger runs as written.

mod common;

use std::path::{Path, PathBuf};

use common::{assign, expect_code, fuzz};
use paracosm_generators::Value;
use serde_json::Value as Json;

fn path(dir: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join(name)
}

fn load_err(src: &str) -> String {
    match paracosm_scenarios::lang::load_source("t.star", src, "t") {
        Ok(_) => panic!("the program loaded:\n{src}"),
        Err(e) => e.to_string(),
    }
}

fn loads(src: &str) -> paracosm_scenarios::Scenario {
    paracosm_scenarios::lang::load_source("t.star", src, "t")
        .unwrap_or_else(|e| panic!("{e}\n{src}"))
}

/// The records of a campaign, each without its `wall_ms`.
fn records(out: &Path) -> Vec<Json> {
    std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let mut r: Json = serde_json::from_str(l).unwrap();
            r.as_object_mut().unwrap().remove("wall_ms");
            r
        })
        .collect()
}

fn campaign(file: &Path, budget: &str, code: i32) -> Vec<Json> {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        budget,
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, code);
    records(&out)
}

/// The paper's trigger `car.filter(|car - start| < dist)` written with a lambda over a
/// location and an open parameter gives the built-in trigger's results, test for test.
#[test]
fn the_papers_trigger_written_as_a_lambda_gives_the_built_in_results() {
    let built_in = campaign(&path("scenarios", "pedestrian_crossing.star"), "100", 1);
    let lambda = campaign(&path("tests/scenarios", "paper_trigger.star"), "100", 1);
    assert_eq!(built_in.len(), 100);
    let failed = built_in.iter().filter(|r| r["status"] == "fail").count();
    assert!(failed > 0 && failed < 100, "{failed} failed");
    for (a, b) in built_in.iter().zip(&lambda) {
        assert_eq!(a, b);
    }
}

/// A location has x, y, z (m), heading (rad) and lane; differences involving a location are
/// taken in the ground plane; `dist` and `abs` measure them; coordinates follow `connect`.
#[test]
fn locations_have_coordinates_a_heading_and_a_lane() {
    let src = r#"
def near(a, b, what):
    if abs(a - b) > 1e-9:
        fail("%s: %s, expected %s" % (what, a, b))

r = RoadSegment(len = 200.0, nlanes = 4)
a = r.onLane(1, 10)
b = r.onLane(-2, 50)
s = r.onLane(r.SideWalk, 30)
near(a.x, 10, "a.x")
near(a.y, 0, "a.y")
near(a.z, 1.75, "a.z")
near(a.heading, 0, "a.heading")
near(b.x, 50, "b.x")
near(b.z, -5.25, "b.z")
near(abs(b.heading), 3.141592653589793, "b.heading")
if a.lane != 1 or b.lane != -2 or s.lane != "SideWalk":
    fail("lanes %s %s %s" % (a.lane, b.lane, s.lane))
if s.y <= 0:
    fail("a sidewalk stands on the curb, y = %s" % s.y)
d = b - a
near(d.x, 40, "(b - a).x")
near(d.y, 0, "(b - a).y")
near(d.z, -7, "(b - a).z")
near(abs(d), hypot(40, 7), "abs(b - a)")
near(dist(a, b), hypot(40, 7), "dist(a, b)")
near(dist(s, a), dist(a, s), "dist is symmetric")
if not (a == r.onLane(1, 10.001)) or a == r.onLane(1, 10.1):
    fail("== has a tolerance of 0.01 m")
x, y, z = d
near(x + y + z, 33, "a Vector unpacks")
near(d[0], 40, "a Vector indexes")
near((2 * d).x, 80, "a Vector scales")

q = RoadSegment(len = 50.0, nlanes = 4)
c = q.onLane(1, 5)
near(c.x, 5, "c.x before connect")
net = r.connect((r.TWO, q, q.ONE))
near(c.x, 205, "c.x after connect")

w = World()
v = AutonomousVehicle(loc = a)
w.place(net, v)
CollisionMonitor(v)
"#;
    loads(src);
    // The checks can fail: a wrong expectation is a load error naming it.
    let e = load_err(&src.replace("near(a.x, 10, \"a.x\")", "near(a.x, 11, \"a.x\")"));
    assert!(e.contains("a.x: 10.0, expected 11"), "{e}");
}

#[test]
fn comparing_a_position_with_something_else_is_an_error_not_false() {
    let base = r#"
r = RoadSegment(len = 200.0)
a = r.onLane(1, 10)
w = World()
v = AutonomousVehicle(loc = a)
w.place(r, v)
CollisionMonitor(v)
"#;
    // (Starlark compares with a constant itself, without asking the position, so the other
    // side is computed here, as a stream's value in a lambda is; LANGUAGE.md says so.)
    for bad in ["a == t", "a != t", "a - n", "abs(a)"] {
        let e = load_err(&format!(
            "{base}t = tuple([10.0, 0.0, 1.75])\nn = int(\"5\")\nx = {bad}\n"
        ));
        assert!(
            e.contains("position") || e.contains("Location"),
            "{bad}: {e}"
        );
        assert!(e.contains("t.star:10:5"), "{bad}: {e}");
    }
}

#[test]
fn math_builtins_compute_and_refuse_streams_with_a_hint() {
    loads(
        r#"
for got, want in [(sqrt(16), 4), (hypot(3, 4), 5), (clamp(5, 0, 2), 2), (clamp(-1.5, 0, 2), 0),
                  (abs(-3), 3), (abs(-2.5), 2.5), (sqrt(2.25), 1.5)]:
    if got != want:
        fail("%s != %s" % (got, want))
r = RoadSegment(len = 200.0)
w = World()
v = AutonomousVehicle(loc = r.onLane(1, 10))
w.place(r, v)
CollisionMonitor(v)
"#,
    );
    let base =
        "r = RoadSegment(len = 200.0)\nw = World()\nv = AutonomousVehicle(loc = r.onLane(1, 10))\n";
    for (bad, says) in [
        ("sqrt(-1)", "sqrt of a negative number"),
        ("clamp(1, 2, 0)", "needs lo <= hi"),
        (
            "sqrt(v.speed)",
            "a stream has a value only while a test runs",
        ),
        (
            "abs(v.speed)",
            "a stream has a value only while a test runs",
        ),
        ("hypot(\"3\", 4)", "hypot takes numbers, got a string"),
    ] {
        let e = load_err(&format!("{base}x = {bad}\n"));
        assert!(e.contains(says), "{bad}: {e}");
        assert!(e.contains("t.star:4:5"), "{bad}: {e}");
    }
}

/// A lambda that reads a stream captured from the program sees its current value: a car whose
/// speed is `tick.map(lambda t: lim)`, with `lim` open over time, drives as one whose speed is
/// `lim` itself.
#[test]
fn a_lambda_reads_a_captured_stream_as_its_current_value() {
    let program = |speed: &str| {
        format!(
            r#"
lim = VarInterval(0.0, 10.0, over_time = Piecewise(2))
r = RoadSegment(len = 300.0)
w = World()
v = AutonomousVehicle(loc = r.onLane(1, 10), sut = "aeb")
c = Car(loc = r.onLane(1, 40), speed = {speed}, route = [])
w.place(r, v, c)
CollisionMonitor(v)
test(horizon = 10.0)
"#
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let mut runs = Vec::new();
    for (name, speed) in [("direct", "lim"), ("lambda", "tick.map(lambda t: lim)")] {
        let file = dir.path().join(format!("{name}.star"));
        std::fs::write(&file, program(speed)).unwrap();
        let o = fuzz(&[
            file.to_str().unwrap(),
            "--budget",
            "12",
            "--out",
            dir.path().join(name).to_str().unwrap(),
        ]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
        runs.push(records(&dir.path().join(name)));
    }
    let gap = |r: &Json| r["metrics"]["min_distance_m"].as_f64().unwrap();
    for (a, b) in runs[0].iter().zip(&runs[1]) {
        assert_eq!(a["params"], b["params"]);
        assert_eq!(gap(a), gap(b), "{a} vs {b}");
        assert_eq!(a["status"], b["status"]);
    }
    // The speed matters: the closest approach differs between tests.
    let gaps: Vec<f64> = runs[0].iter().map(gap).collect();
    assert!(gaps.iter().any(|g| (g - gaps[0]).abs() > 0.5), "{gaps:?}");
    // Library check of the same world: the lambda's speed is the parameter's value.
    let s = loads(&program("tick.map(lambda t: lim)"));
    let names: Vec<&str> = s.space.params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["lim[0]", "lim[1]"]);
    let _ = assign(&s.space, &[("lim[0]", Value::Real(3.0))]);
}
