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

/// The records of a campaign, each without its `wall_ms` and campaign tag (tests here compare
/// different programs).
fn records(out: &Path) -> Vec<Json> {
    std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(common::untagged_record)
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
if not (a == r.onLane(1, 10.0000001)) or a == r.onLane(1, 10.00001):
    fail("== has a tolerance of 1e-6 m")
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
    let names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["lim[0]", "lim[1]"]);
    let _ = assign(s.space(), &[("lim[0]", Value::Real(3.0))]);
}

/// An actor's output read inside a lambda without a top-level variable stays a stream: the
/// error at load says how to read its current value, whatever the operation.
#[test]
fn a_stream_inside_a_lambda_is_refused_with_how_to_read_its_value() {
    let base = format!("{ROAD}lead = Car(loc = r.onLane(1, 100))\nw.place(r, v, lead)\n");
    for body in [
        "Monitor(v.speed.map(lambda s: s - lead.speed + 5))",
        "Assert(v.speed.map(lambda s: s < lead.speed + 5))",
        "Monitor(v.speed.map(lambda s: abs(lead.pos.x - 3)))",
        "Monitor(v.pos.map(lambda c: abs(c - lead.pos) - 4))",
    ] {
        let e = load_err(&format!("{base}{body}\n"));
        assert!(
            e.contains("t.star:7:")
                && e.contains("hint: inside a lambda, a stream reads as its current value"),
            "{body}: {e}"
        );
    }
    // As the hint says, a top-level variable reads as the current value.
    loads(&format!(
        "{base}lead_speed = lead.speed\nMonitor(v.speed.map(lambda s: lead_speed - s + 20))\n"
    ));
    // An error without a stream in it gets no such hint.
    let e = load_err(&format!(
        "{base}Monitor(v.speed.map(lambda s: s - \"a\"))\n"
    ));
    assert!(!e.contains("hint: inside a lambda"), "{e}");
}

const ROAD: &str = r#"
w = World()
r = RoadSegment(len = 300.0, nlanes = 4)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 0.0)
"#;

/// Runs `src` (written to a file) for `budget` tests with `extra` flags; returns the records,
/// stdout and stderr.
fn run_src(src: &str, budget: &str, extra: &[&str], code: i32) -> (Vec<Json>, String, String) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.star");
    std::fs::write(&file, src).unwrap();
    let out = dir.path().join("out");
    let mut args = vec![
        file.to_str().unwrap(),
        "--budget",
        budget,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = fuzz(&args);
    expect_code(&o, code);
    (
        records(&out),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// `Monitor(over=)` takes the minimum, the last value or the maximum; `Assert` is ±1; `Signal`
/// and every actor's outputs by variable name reach `Stl`; `min()`/`max()` run over streams.
#[test]
fn user_monitors_signals_and_actor_signals_judge_tests() {
    let src = format!(
        r#"{ROAD}
lead = Car(loc = r.onLane(1, 100), speed = tick.map(lambda t: 4 + t))
w.place(r, v, lead)
gap = lead.pos.map(lambda p: p.x - 100)          # how far the lead has gone, m
Monitor(gap.map(lambda g: g - 20), name = "end_pos", over = "end")
Monitor(gap.map(lambda g: 5 - g), name = "eventually_pos", over = "eventually")
Monitor(gap.max().map(lambda m: m - 1000), name = "max_never", over = "eventually")
Assert(lead.speed.map(lambda s: s < 100), name = "slow")
Signal("lead_gap", gap)
Stl("G[0,3] (lead.speed < 7.01 & lead_gap > -0.01 & lead.pos.x > 99)", name = "stl_ok")
Stl("F[0,3] (lead.speed > 100)", name = "stl_fail")
test(horizon = 3.0, offroad = False)
"#
    );
    let (records, _, _) = run_src(&src, "1", &[], 1);
    let m = &records[0]["monitors"];
    // No monitor stopped the test early.
    assert_eq!(records[0]["metrics"]["simulated_s"], 3.0, "{m}");
    // After 3 s at 4 + t m/s it has gone 12 + 4.5 = 16.5 m (within a step).
    let end = m["end_pos"]["robustness"].as_f64().unwrap();
    assert!((end + 3.5).abs() < 0.2, "{end}");
    assert_eq!(m["eventually_pos"]["passed"], true);
    assert!((m["eventually_pos"]["robustness"].as_f64().unwrap() - 5.0).abs() < 1e-9);
    assert_eq!(m["max_never"]["passed"], false);
    assert_eq!(m["slow"]["robustness"], 1.0);
    assert_eq!(m["stl_ok"]["passed"], true, "{m}");
    assert_eq!(m["stl_fail"]["passed"], false, "{m}");

    // `always`: fails, and stops the test, at the first value <= 0: the lead has gone 1 m a
    // quarter of a second in.
    let always = src.replace(
        "Monitor(gap.map(lambda g: g - 20)",
        "Monitor(gap.map(lambda g: 1 - g), name = \"always_neg\", over = \"always\")\nMonitor(gap.map(lambda g: g - 20)",
    );
    let (records, _, _) = run_src(&always, "1", &[], 1);
    let m = &records[0]["monitors"];
    assert_eq!(m["always_neg"]["passed"], false);
    let t = m["always_neg"]["first_violation_s"].as_f64().unwrap();
    assert!(t > 0.2 && t < 0.3, "{t}");
    assert_eq!(m["end_pos"]["cut_short"], true, "{m}");
}

/// A signal nobody publishes, a Monitor of bools and a Signal of strings are load errors.
#[test]
fn signals_and_monitors_of_the_wrong_kind_are_refused_at_load() {
    let base = format!("{ROAD}lead = Car(loc = r.onLane(1, 100))\nw.place(r, v, lead)\n");
    let e = load_err(&format!("{base}Stl(\"G[0,1] (lead.spin > 0)\")\n"));
    assert!(
        e.contains("`lead.spin`, which nothing publishes") && e.contains("t.star:"),
        "{e}"
    );
    let e = load_err(&format!("{base}Monitor(v.collision)\n"));
    assert!(e.contains("use Assert"), "{e}");
    let e = load_err(&format!("{base}Signal(\"c\", VarEnum([\"a\", \"b\"]))\n"));
    assert!(e.contains("a signal is a number"), "{e}");
    let e = load_err(&format!("{base}Monitor(v.speed, over = \"sometimes\")\n"));
    assert!(e.contains("\"always\", \"end\" or \"eventually\""), "{e}");
    // A lambda's stream has its kind from its sample value at load: a Signal of strings or
    // of tuples is refused there (it was an error in every test), with the Signal's place.
    let e = load_err(&format!(
        "{base}CollisionMonitor(v)\nSignal(\"label\", lead.pos.map(lambda p: \"near\" if p.x < 5 else \"far\"))\n"
    ));
    assert!(
        e.contains("Signal `label` carried \"far\" (a string)")
            && e.contains("a signal is a number, a bool or a vector")
            && e.contains("t.star:8:"),
        "{e}"
    );
    let e = load_err(&format!(
        "{base}CollisionMonitor(v)\nSignal(\"pair\", v.speed.map(lambda s: (s, s)))\n"
    ));
    assert!(
        e.contains("Signal `pair` carried") && e.contains("t.star:8:"),
        "{e}"
    );
    // A Signal of a lambda that gives numbers loads.
    loads(&format!(
        "{base}Signal(\"gap\", lead.pos.zip(v.pos).map(lambda p: p[0].x - p[1].x))\n\
         Stl(\"G[0,5] (gap > 1)\")\n"
    ));
    // Thresholds of the built-in monitors that no test could fail are refused.
    let e = load_err(&format!("{base}DistanceMonitor(v, minD = -5)\n"));
    assert!(e.contains("minD is a distance in metres, >= 0"), "{e}");
    let e = load_err(&format!(
        "{base}TimeToFailure(CollisionMonitor(v), minT = -1.0)\n"
    ));
    assert!(e.contains("minT is a time in seconds, >= 0"), "{e}");
}

/// A lambda's stream has no kind until it is called: a `Monitor` of a lambda that returns
/// bools, or an `Assert` of one that returns numbers, is refused at load from the sample
/// values (a bool was once read as 0 or 1 and failed the test as a verdict), and a value of
/// the wrong kind that only appears later ends the test as an error, not a verdict.
#[test]
fn monitors_of_lambdas_of_the_wrong_kind_are_refused_not_read_as_numbers() {
    let base = format!("{ROAD}lead = Car(loc = r.onLane(1, 100))\nw.place(r, v, lead)\n");
    let e = load_err(&format!(
        "{base}slow = Monitor(v.speed.map(lambda s: s < 3))\n"
    ));
    assert!(
        e.contains("monitor `slow`")
            && e.contains("a bool is not a number")
            && e.contains("t.star:"),
        "{e}"
    );
    let e = load_err(&format!(
        "{base}def margin(s):\n    return 20 - s\nok = Assert(v.speed.map(margin))\n"
    ));
    assert!(
        e.contains("monitor `ok`") && e.contains("a number is not a bool"),
        "{e}"
    );
    // Inside TimeToFailure too, and a vector is no number either.
    let e = load_err(&format!(
        "{base}TimeToFailure(Monitor(v.pos.map(lambda p: p - p), name = \"m\"), minT = 1.0)\n"
    ));
    assert!(
        e.contains("monitor `m`") && e.contains("Monitor reads numbers"),
        "{e}"
    );
    // Numbers at t = 0, a bool from 0.5 s on: each test ends as an error at that moment.
    let late = format!(
        "{base}late = Monitor(tick.map(lambda t: 1.0 if t < 0.5 else True))\nCollisionMonitor(v)\ntest(horizon = 2.0)\n"
    );
    let (records, _, _) = run_src(&late, "2", &[], 3);
    for r in &records {
        assert_eq!(r["status"], "error", "{r}");
        let m = r["error"].as_str().unwrap();
        assert!(
            m.contains("at t = 0.5") && m.contains("monitor `late`"),
            "{m}"
        );
    }
}

/// A computed input whose values are of the wrong kind (a string for a speed, a number for
/// the pedestrian's watched car) is refused when the program loads, naming the input and its
/// `file:line:col`, not read as something else in every test; a kind that only a later value
/// shows stays the test's error, and a number out of range is left to the tests.
#[test]
fn computed_inputs_of_the_wrong_kind_are_refused_at_load() {
    let walker = |dist: &str, car: &str| {
        format!(
            "{ROAD}p = Pedestrian(start = r.onLane(r.SideWalk, 60.0), \
             target = r.onLane(-r.SideWalk, 60.0), speed = 1.0, dist = {dist}, car = {car})\n\
             w.place(r, v, p)\nCollisionMonitor(v)\n"
        )
    };
    let e = load_err(&walker("tick.map(lambda t: \"far\")", "v"));
    assert!(
        e.contains("the dist of Pedestrian p (t.star:")
            && e.contains("\"far\" (a string)")
            && e.contains("a number in m, >= 0"),
        "{e}"
    );
    let e = load_err(&walker("20.0", "tick.map(lambda t: 3.0)"));
    assert!(
        e.contains("the car of Pedestrian p (t.star:") && e.contains("a position"),
        "{e}"
    );
    let e = load_err(&format!(
        "{ROAD}c = Car(loc = r.onLane(1, 60.0), speed = tick.map(lambda t: \"fast\"))\n\
         w.place(r, v, c)\nCollisionMonitor(v)\n"
    ));
    assert!(
        e.contains("the speed of Car c (t.star:") && e.contains("\"fast\" (a string)"),
        "{e}"
    );
    let e = load_err(&format!(
        "{}\nw.place(r, v)\nCollisionMonitor(v)\n",
        ROAD.replace("World()", "World(light = tick.map(lambda t: t > 1))")
    ));
    assert!(
        e.contains("the light of World w") && e.contains("False (a bool)"),
        "{e}"
    );
    // A distance that goes negative after 0.5 s loads, and each test ends as an error then.
    let late = format!(
        "{}test(horizon = 2.0)\n",
        walker("tick.map(lambda t: 10.0 - 20.0 * t)", "v")
    );
    let (records, _, _) = run_src(&late, "2", &[], 3);
    for r in &records {
        assert_eq!(r["status"], "error", "{r}");
        let m = r["error"].as_str().unwrap();
        assert!(
            m.contains("the dist of Pedestrian p") && m.contains(">= 0"),
            "{m}"
        );
    }
}

/// A disabled car is not in the test: its outputs have no events, so a pedestrian it would
/// trigger stays put, and a monitor over its outputs (which would judge a car that is not
/// there) is refused at load, naming the monitor and the car.
#[test]
fn a_disabled_cars_outputs_have_no_events_and_monitors_of_them_are_refused() {
    let base = format!(
        "{ROAD}c = Car(loc = r.onLane(2, 60.0), speed = 8.0, enabled = VarEnum([True, False]))\n\
         p = Pedestrian(start = r.onLane(r.SideWalk, 150.0), \
         target = r.onLane(-r.SideWalk, 150.0), speed = 1.5, dist = 500.0, car = c)\n\
         w.place(r, v, c, p)\nCollisionMonitor(v)\n"
    );
    let e = load_err(&format!(
        "{base}moves = Monitor(c.speed.map(lambda s: s - 1.0))\n"
    ));
    assert!(
        e.contains("monitor `moves` reads Car c")
            && e.contains("enabled = False")
            && e.contains("t.star:"),
        "{e}"
    );
    let e = load_err(&format!(
        "{base}Stl(\"G[0,3] (c.speed > 1)\", name = \"fast\")\n"
    ));
    assert!(e.contains("monitor `fast` reads Car c"), "{e}");
    // Through a top-level variable the program judges the car only when it is there; the
    // pedestrian walks only when the car that triggers it is in the test.
    let ok = format!(
        "{base}c_speed = c.speed\n\
         moves = Monitor(tick.map(lambda t: 1.0 if c_speed == None else c_speed - 1.0))\n\
         walked = Monitor(p.speed.max().map(lambda s: s - 0.5), over = \"end\")\n\
         test(horizon = 3.0)\n"
    );
    let (records, _, _) = run_src(&ok, "2", &[], 1);
    assert_eq!(records.len(), 2);
    for r in &records {
        let enabled = r["params"]["c.enabled"].as_bool().unwrap();
        let m = &r["monitors"];
        assert_eq!(m["walked"]["passed"].as_bool().unwrap(), enabled, "{r}");
        assert_eq!(m["moves"]["passed"], true, "{r}");
        let moves = m["moves"]["robustness"].as_f64().unwrap();
        let want = if enabled { 7.0 } else { 1.0 };
        assert!((moves - want).abs() < 1e-6, "{r}");
    }
}

/// A route's turn that a junction lacks is an error naming the actor, the turn and what the
/// junction offers, not another turn taken in its place.
#[test]
fn a_route_turn_the_junction_lacks_is_refused_not_replaced() {
    // A T whose three ports lead on: entered by its east port (ONE), it has straight and left.
    let net = r#"
w = World()
t = TIntersection()
e = RoadSegment(len = 60.0)
s = RoadSegment(len = 60.0)
x = RoadSegment(len = 60.0)
t.connect((t.ONE, e, e.TWO), (t.TWO, s, s.ONE), (t.THREE, x, x.ONE))
"#;
    let ego = |route: &str| {
        format!(
            "{net}v = AutonomousVehicle(loc = e.onLane(1, 5), route = {route})\n\
             w.place(t, e, s, x, v)\nCollisionMonitor(v)\n"
        )
    };
    let car = format!(
        "{net}v = AutonomousVehicle(loc = x.onLane(1, 50))\n\
         c = Car(loc = e.onLane(1, 5), route = [\"right\"])\n\
         w.place(t, e, s, x, v, c)\nCollisionMonitor(v)\n"
    );
    let e = load_err(&car);
    assert!(
        e.contains("Car c: the route's turn 1 (\"right\") is not possible at TIntersection t")
            && e.contains("it offers \"straight\" and \"left\"")
            && e.contains("t.star:"),
        "{e}"
    );
    // The stem (left) ends at s.TWO: a second turn is left over, which is no error (with an
    // open lane a route may be meant for one direction only).
    loads(&ego("[\"left\", \"right\"]"));
    // Each turn the junction has loads; an open turn is checked for each of its levels.
    loads(&ego("[\"left\"]"));
    loads(&ego("[\"straight\"]"));
    let e = load_err(&ego("[VarEnum([\"left\", \"right\"])]"));
    assert!(e.contains("(\"right\") is not possible"), "{e}");
    // A junction counts whether or not its other exits lead anywhere: on a cross with two
    // ports connected, "left" is the one way on, and "straight" drives into the dead end.
    let cross = |route: &str| {
        format!(
            "w = World()\nj = CrossIntersection()\ne = RoadSegment(len = 60.0)\n\
             s = RoadSegment(len = 60.0)\nj.connect((j.ONE, e, e.TWO), (j.TWO, s, s.ONE))\n\
             v = AutonomousVehicle(loc = e.onLane(1, 5), route = {route})\n\
             w.place(j, e, s, v)\nCollisionMonitor(v)\ntest(horizon = 8.0)\n"
        )
    };
    loads(&cross("[\"left\"]"));
    let (records, _, _) = run_src(&cross("[\"straight\"]"), "1", &[], 1);
    assert_eq!(
        records[0]["monitors"]["offroad"]["passed"], false,
        "{}",
        records[0]
    );
}

/// A car enters the test at its speed stream's first value, so its `speed` and `vel` read
/// that value at t = 0 too (they read 0 there, and a monitor over them failed at t = 0):
/// a constant speed, an open one varying over time, and STL over the published signal.
#[test]
fn a_cars_speed_at_t0_is_the_speed_it_enters_at() {
    let src = format!(
        "{ROAD}lead = Car(loc = r.onLane(1, 60.0), speed = 8.0)\n\
         other = Car(loc = r.onLane(2, 100.0), speed = VarInterval(6.0, 7.0, over_time = Piecewise(2), name = \"s\"))\n\
         w.place(r, v, lead, other)\n\
         Monitor(lead.speed.map(lambda s: s - 7.9), name = \"lead_speed\")\n\
         Monitor(lead.vel.map(lambda u: abs(u) - 7.9), name = \"lead_vel\")\n\
         Monitor(other.speed.map(lambda s: s - 5.9), name = \"other_speed\")\n\
         Stl(\"G[0,1] (lead.speed >= 7.9)\", name = \"stl\")\n\
         test(horizon = 1.0)\n"
    );
    let (records, _, _) = run_src(&src, "2", &[], 0);
    for r in &records {
        let m = &r["monitors"];
        for name in ["lead_speed", "lead_vel", "other_speed", "stl"] {
            assert_eq!(m[name]["passed"], true, "{name}: {r}");
        }
        assert!(
            (m["lead_speed"]["robustness"].as_f64().unwrap() - 0.1).abs() < 1e-9,
            "{r}"
        );
    }
}

/// `print` writes to the test's log: in results.jsonl, on stderr with --verbose, never on
/// stdout during a campaign.
#[test]
fn print_goes_to_the_tests_log_not_to_stdout() {
    let src = format!(
        r#"{ROAD}
w.place(r, v)
def show(t):
    if t > 0.99 and t < 1.01:
        print("one second in, t =", t)
    return t
tick.map(show)
print("loaded")
CollisionMonitor(v)
test(horizon = 1.5)
"#
    );
    let (records, stdout, stderr) = run_src(&src, "2", &["--verbose"], 0);
    assert!(
        !stdout.contains("one second") && !stdout.contains("loaded"),
        "{stdout}"
    );
    let log = records[1]["log"].as_array().unwrap();
    assert_eq!(log.len(), 2, "{log:?}");
    assert_eq!(log[0], "loaded");
    assert!(
        log[1].as_str().unwrap().starts_with("one second in"),
        "{log:?}"
    );
    assert!(stderr.contains("test 1: one second in"), "{stderr}");
    // What the program prints at load is shown once, though loading runs it more than once.
    assert_eq!(stderr.matches("print: loaded").count(), 1, "{stderr}");
}

/// Actions: `car.setSpeed` and `car.brake(decel)` change a car's speed, `car.changeLane(lane)`
/// moves it sideways, a `def` that calls actions works from `foreach`, and a pedestrian
/// without a trigger stands still until an action moves it.
#[test]
fn foreach_takes_any_action() {
    let src = format!(
        r#"{ROAD}
a = Car(loc = r.onLane(1, 60), speed = 10.0)
b = Car(loc = r.onLane(2, 60), speed = 10.0)
c = Car(loc = r.onLane(-1, 200), speed = 0.0)
p0 = r.onLane(r.SideWalk, 250)
q0 = r.onLane(r.SideWalk, 280)
p = Pedestrian(start = p0, target = r.onLane(-r.SideWalk, 250), speed = 1.0)
q = Pedestrian(start = q0, target = r.onLane(-r.SideWalk, 280), speed = 1.0)
w.place(r, v, a, b, c, p, q)
later = tick.filter(lambda t: t >= 1.0)
later.foreach(a.brake(4.0))
later.map(lambda t: 2.0).foreach(b.setSpeed)
def go(t):
    c.setSpeed(5.0)
    c.changeLane(-2, duration = 1.0)
later.foreach(go)
tick.filter(lambda t: t >= 2.0).foreach(q.walk)
Signal("a_speed", a.speed)
Signal("b_speed", b.speed)
Signal("c_speed", c.speed)
c0 = r.onLane(-1, 200)
Signal("c_shift", c.pos.map(lambda x: abs(x.z - c0.z)))
Signal("p_moved", p.pos.map(lambda x: abs(x - p0)))
Signal("q_moved", q.pos.map(lambda x: abs(x - q0)))
Stl("G[2.5,2.5] (a_speed < 4.1 & a_speed > 3.9)", name = "a_braked")
Stl("G[2.5,2.5] (b_speed < 2.01 & b_speed > 1.99)", name = "b_set")
Stl("G[2.5,2.5] (c_speed > 4.99)", name = "c_moved")
test(horizon = 3.0, offroad = False)
"#
    );
    let sc = loads(&src);
    let out = sc.run(&assign(sc.space(), &[]), 0).unwrap();
    let v = |n: &str| {
        out.monitors
            .iter()
            .find(|(m, _)| m == n)
            .unwrap_or_else(|| panic!("{n}"))
            .1
            .clone()
    };
    assert!(v("a_braked").passed, "{:?}", v("a_braked"));
    assert!(v("b_set").passed, "{:?}", v("b_set"));
    assert!(v("c_moved").passed, "{:?}", v("c_moved"));
    // Lane -1 to lane -2 is 3.5 m sideways, done within its 1 s; the pedestrian without a
    // trigger never moved, the one an action moved from t = 2 s walked 1 m/s for ~1 s.
    let src2 = src.replace(
        "Stl(\"G[2.5,2.5] (a_speed",
        "Stl(\"G[2.9,2.9] (c_shift > 3.49 & c_shift < 3.51 & p_moved < 0.000001 & q_moved > 0.8 & q_moved < 1.0)\", name = \"moved\")\nStl(\"G[2.5,2.5] (a_speed",
    );
    let sc = loads(&src2);
    let out = sc.run(&assign(sc.space(), &[]), 0).unwrap();
    let moved = out.monitors.iter().find(|(m, _)| m == "moved").unwrap();
    assert!(moved.1.passed, "{:?}", moved.1);
    // A lane the car's segment lacks is refused at load.
    let e = load_err(&src.replace("later.foreach(go)", "later.foreach(a.changeLane(7))"));
    assert!(
        e.contains("Car a.changeLane(7)") && e.contains("1, 2"),
        "{e}"
    );
}

/// A type error inside a lambda is one error at load, with file:line:col and exit code 2,
/// not one error per test.
#[test]
fn a_type_error_in_a_lambda_is_found_at_load() {
    let src = format!(
        "{ROAD}lead = Car(loc = r.onLane(1, 100))\nw.place(r, v, lead)\nfar = v.pos.filter(lambda c: c.x + \"m\" > 50)\nAssert(far.map(lambda c: True))\n"
    );
    let (_, _, stderr) = {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("t.star");
        std::fs::write(&file, &src).unwrap();
        let out = dir.path().join("out");
        let o = fuzz(&[
            file.to_str().unwrap(),
            "--budget",
            "50",
            "--out",
            out.to_str().unwrap(),
        ]);
        expect_code(&o, 2);
        assert!(!out.join("results.jsonl").exists());
        ((), (), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    assert_eq!(
        stderr.matches("not supported for types").count(),
        1,
        "{stderr}"
    );
    assert!(stderr.contains("t.star:7:30"), "{stderr}");
    // A division by zero that only the sample values cause is left to the tests.
    loads(&format!(
        "{ROAD}w.place(r, v)\nx = tick.filter(lambda t: t > 1).map(lambda t: 1 / t)\nAssert(x.map(lambda y: y < 2))\n"
    ));
}

/// A builtin that builds the world, called inside a lambda, is refused at load with the
/// lambda's place and the way out; the same value computed outside the lambda works.
#[test]
fn a_world_builtin_inside_a_lambda_is_refused_with_a_hint() {
    let e = load_err(&format!(
        "{ROAD}w.place(r, v)\nfar = v.pos.filter(lambda c: dist(c, r.onLane(1, 200)) < 5)\nAssert(far.map(lambda c: False))\n"
    ));
    assert!(e.contains("cannot run inside a lambda"), "{e}");
    assert!(e.contains("t.star:6:38"), "{e}");
    loads(&format!(
        "{ROAD}w.place(r, v)\nend = r.onLane(1, 200)\nfar = v.pos.filter(lambda c: dist(c, end) < 5)\nAssert(far.map(lambda c: False))\n"
    ));
}

/// Objects are named by their variable in messages, else by builtin and line, with the call
/// that made them when a function did.
#[test]
fn objects_are_named_by_their_variable_or_where_they_were_made() {
    let e = load_err(
        "def road(n):\n    return RoadSegment(len = 50.0, nlanes = n)\na = road(2)\nb = road(6)\na.connect((a.TWO, b, b.ONE))\n",
    );
    assert!(
        e.contains("RoadSegment at t.star:2:12 (called from t.star:3:5).TWO has 2 lanes but RoadSegment at t.star:2:12 (called from t.star:4:5).ONE has 6"),
        "{e}"
    );
    let e = load_err(&format!(
        "{ROAD}lead = Car(loc = r.onLane(1, 10))\nw.place(r, v, lead)\n"
    ));
    assert!(
        e.contains("AutonomousVehicle v (t.star:4:5) and Car lead (t.star:5:8) start in collision"),
        "{e}"
    );
}

/// An open parameter given as an action's argument is named after the method
/// (`lead.brake`), and the worlds it makes differ, so it is not reported unused.
#[test]
fn an_open_action_argument_is_named_and_used() {
    let sc = loads(&format!(
        "{ROAD}lead = Car(loc = r.onLane(1, 60), speed = 8.0)\nw.place(r, v, lead)\ntick.filter(lambda t: t > 1).foreach(lead.brake(VarEnum([3, 7])))\nCollisionMonitor(v)\nDistanceMonitor(v, minD = 20.0)\n"
    ));
    let names: Vec<&str> = sc
        .space()
        .params()
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(names, ["lead.brake"]);
    assert!(sc.unused_params().is_empty(), "{:?}", sc.unused_params());
    assert!(sc.warnings().is_empty(), "{:?}", sc.warnings());
}

/// A passing `Stl` formula reports the whole trace's robustness: `F[0,15] where.x > 60` over
/// a published vector equals the user monitor `max(x) - 60` (`over = "eventually"`), test for
/// test, and is far from 0 for a car that drives 100 m past the threshold.
#[test]
fn a_passing_stl_formula_reports_the_traces_robustness_as_a_user_monitor_does() {
    let src = "w = World()\nr = RoadSegment(len = 200, nlanes = 2)\nv = AutonomousVehicle(loc = r.onLane(1, 10), speed = VarInterval(4.0, 12.0))\nw.place(r, v)\nSignal(\"where\", v.pos)\nfar = Monitor(v.pos.map(lambda p: p.x - 60), over = \"eventually\")\nStl(\"F[0,15] (where.x > 60)\", name = \"gets_going\")\ntest(horizon = 15.0)\n";
    let (records, _, _) = run_src(src, "6", &[], 0);
    assert_eq!(records.len(), 6);
    for r in &records {
        let stl = r["monitors"]["gets_going"]["robustness"].as_f64().unwrap();
        let user = r["monitors"]["far"]["robustness"].as_f64().unwrap();
        assert!((stl - user).abs() < 1e-9, "{stl} vs {user}");
        assert!(stl > 50.0, "{stl}");
    }
}

/// A combinator given values of the wrong kind is named by where the program made it: at
/// load when the sample values show it (`v.pos.min()`), in the test's error when only a later
/// value does.
#[test]
fn a_combinator_of_the_wrong_kind_is_named_by_its_place() {
    let e = load_err(&format!(
        "{ROAD}w.place(r, v)\nlow = Monitor(v.pos.min(), name = \"m\")\n"
    ));
    assert!(
        e.contains("t.star:6:15: min() needs a stream of numbers, got a vector"),
        "{e}"
    );
    let src = format!(
        "{ROAD}w.place(r, v)\nodd = tick.map(lambda t: 1.0 if t < 1 else \"x\").max()\nMonitor(odd, name = \"m\")\n"
    );
    let (records, _, _) = run_src(&src, "1", &[], 3);
    let error = records[0]["error"].as_str().unwrap();
    assert!(
        error.contains("t.star:6:7: max() needs a stream of numbers, got a string"),
        "{error}"
    );
}

/// A level keeps its type: the text `"true"` stays a text (it was taken for a bool, so
/// `mode == "true"` was never true), and a bool level is a bool in the program and in the
/// results.
#[test]
fn levels_keep_their_type_a_text_true_is_not_a_bool() {
    let src = "w = World()\nr = RoadSegment(len = 300.0, nlanes = 4)\nmode = VarEnum([\"true\", \"off\"])\nfast = VarEnum([True, False])\nv = AutonomousVehicle(loc = r.onLane(1, 10), speed = 8.0 if mode == \"true\" else 3.0)\nlead = Car(loc = r.onLane(1, 200), enabled = fast)\nw.place(r, v, lead)\nstart = Monitor(v.speed.take(1), over = \"end\")\n";
    let (records, _, stderr) = run_src(src, "4", &["--strategy", "ipog"], 0);
    assert!(!stderr.contains("no object reads"), "{stderr}");
    let mut seen = std::collections::BTreeSet::new();
    for r in &records {
        let mode = r["params"]["mode"].as_str().expect("a text level");
        let fast = r["params"]["fast"].as_bool().expect("a bool level");
        let start = r["monitors"]["start"]["robustness"].as_f64().unwrap();
        // The program saw the text: "true" gives the 8 m/s start, "off" the 3 m/s one.
        let expected = if mode == "true" { 8.0 } else { 3.0 };
        assert!((start - expected).abs() < 0.5, "{r}");
        seen.insert((mode.to_owned(), fast));
    }
    assert_eq!(seen.len(), 4, "{seen:?}");
}

/// `onLane` takes its arguments by position or by keyword (LANGUAGE.md, Conventions), and
/// open values among several positional arguments of a method are named by position.
#[test]
fn on_lane_takes_keywords_and_its_open_arguments_have_names_of_their_own() {
    let names = |src: &str| -> Vec<String> {
        loads(src)
            .space()
            .params()
            .iter()
            .map(|p| p.name.clone())
            .collect()
    };
    let segment = "w = World()\nr = RoadSegment(len = 300.0, nlanes = 4)\n";
    let n = names(&format!(
        "{segment}v = AutonomousVehicle(loc = r.onLane(lane = 1, at = 10.0))\n\
         c = Car(loc = r.onLane(VarEnum([2, -2]), VarInterval(40.0, 60.0)))\n\
         d = Car(loc = r.onLane(-1, VarInterval(100.0, 120.0)))\n\
         w.place(r, v, c, d)\nCollisionMonitor(v)\n"
    ));
    assert_eq!(n, ["r.onLane[0]", "r.onLane[1]", "r.onLane"]);
    // The same place by keyword and by position (a difference fails the load).
    loads(&format!(
        "{segment}a = r.onLane(lane = -1, at = 42.0)\nb = r.onLane(-1, 42.0)\n\
         if not (a == b and a.heading == b.heading and a.lane == b.lane): fail(\"differ\")\n\
         if a == r.onLane(-1, 43.0): fail(\"1 m apart are equal\")\n\
         v = AutonomousVehicle(loc = r.onLane(1, at = 10.0))\nw.place(r, v)\nCollisionMonitor(v)\n"
    ));
    let e = load_err(&format!(
        "{segment}v = AutonomousVehicle(loc = r.onLane(1, lane = 2, at = 10.0))\nw.place(r, v)\n"
    ));
    assert!(e.contains("lane is given twice"), "{e}");
    let e = load_err(&format!(
        "{segment}v = AutonomousVehicle(loc = r.onLane(lane = 1))\nw.place(r, v)\n"
    ));
    assert!(e.contains("needs a lane and how far along it"), "{e}");
    let junction = "w = World()\nj = CrossIntersection(nlanes = 2)\n";
    loads(&format!(
        "{junction}v = AutonomousVehicle(loc = j.onLane(port = j.ONE, turn = \"left\", at = 3.0, lane = 1))\n\
         w.place(j, v)\nCollisionMonitor(v)\ntest(offroad = False)\n"
    ));
}
