//! Verdicts that must not depend on how a program is written: when a failure happened, which
//! signal a formula reads, what a wrapped monitor reports, and the load errors and warnings
//! that refuse or flag a program rather than judge it wrongly.

mod common;

use std::path::Path;

use common::{expect_code, fuzz};
use serde_json::Value as Json;

/// A 400 m road with the ego at 5 m/s and a lead car at 6 m/s, 50 m ahead.
const ROAD: &str = r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
lead = Car(loc = r.onLane(1, 60), speed = 6.0)
"#;

fn records(out: &Path) -> Vec<Json> {
    std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(common::untagged_record)
        .collect()
}

/// Runs `src` for one test; returns its record and what the run printed on stderr.
fn run_one(src: &str, code: i32) -> (Json, String) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.star");
    std::fs::write(&file, src).unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, code);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    (records(&out).remove(0), stderr)
}

fn load_err(src: &str) -> String {
    match paracosm_scenarios::lang::load_source("t.star", src, "t") {
        Ok(_) => panic!("the program loaded:\n{src}"),
        Err(e) => e.to_string(),
    }
}

fn number(v: &Json) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// An `Stl` formula's failure time is when the trace decided it, not when its periodic check
/// saw it: `TimeToFailure` over it fails a formula false from the start, and the moment of a
/// later failure is the step it happened at, with or without other monitors beside it.
#[test]
fn a_formulas_failure_time_is_when_it_failed() {
    let src = format!(
        "{ROAD}w.place(r, v, lead)
TimeToFailure(Stl(\"G[0,4] (lead.speed > 6.5)\", name = \"slow\"), minT = 0.2, name = \"early\")
test(horizon = 4.0, offroad = False)
"
    );
    let (r, _) = run_one(&src, 1);
    let early = &r["monitors"]["early"];
    assert_eq!(early["passed"], false, "{early}");
    assert_eq!(number(&early["first_violation_s"]), 0.0);
    assert!((number(&early["robustness"]) + 0.2).abs() < 1e-12);

    // The lead passes x = 100 at t = 40/6 = 6.67 s: the formula fails at the first step with
    // lead.pos.x >= 100 (robustness 0 is a violation), whether or not a user monitor of the
    // same condition runs beside it.
    let stl = "Stl(\"G[0,10] (lead.pos.x < 100)\", name = \"before\")";
    let alone =
        format!("{ROAD}w.place(r, v, lead)\n{stl}\ntest(horizon = 10.0, offroad = False)\n");
    let both = format!(
        "{ROAD}w.place(r, v, lead)\n{stl}\nMonitor(lead.pos.map(lambda p: 100 - p.x), name = \"m\")\ntest(horizon = 10.0, offroad = False)\n"
    );
    let (a, _) = run_one(&alone, 1);
    let (b, _) = run_one(&both, 1);
    let ta = number(&a["monitors"]["before"]["first_violation_s"]);
    let tb = number(&b["monitors"]["before"]["first_violation_s"]);
    let tm = number(&b["monitors"]["m"]["first_violation_s"]);
    assert_eq!(ta, tb);
    assert_eq!(
        ta, tm,
        "the formula and the user monitor fail at the same step"
    );
    assert!((ta - 40.0 / 6.0).abs() < 1.0 / 60.0 + 1e-9, "{ta}");
}

/// `TimeToFailure` over a monitor judged only at the end (a distance) compares the end with
/// `minT`; wrapping a monitor twice is refused; nesting judges the inner verdict.
#[test]
fn time_to_failure_judges_every_kind_of_monitor_once() {
    let src = r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
w.place(r, v)
TimeToFailure(DistanceMonitor(v, minD = 500), minT = 1.0, name = "late")
TimeToFailure(DistanceMonitor(v, minD = 500, name = "d2"), minT = 5.0, name = "early")
m = Monitor(tick.map(lambda t: 1.0 - t), name = "m")
TimeToFailure(TimeToFailure(m, minT = 0.5, name = "inner"), minT = 2.0, name = "outer")
test(horizon = 3.0, offroad = False)
"#;
    let (r, _) = run_one(src, 1);
    let m = &r["monitors"];
    // Judged at the end of the 3 s run: after minT = 1, before minT = 5.
    assert_eq!(m["late"]["passed"], true, "{m}");
    assert_eq!(number(&m["late"]["first_violation_s"]), 3.0);
    assert_eq!(m["early"]["passed"], false, "{m}");
    assert!((number(&m["early"]["robustness"]) + 2.0).abs() < 1e-9);
    // m fails at t = 1 >= 0.5: the inner one passes, so the outer one has no failure to time.
    assert_eq!(m["outer"]["passed"], true, "{m}");
    assert!(
        (number(&m["outer"]["robustness"]) - 0.5).abs() < 1e-9,
        "{m}"
    );

    let twice = load_err(
        r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
w.place(r, v)
m = Monitor(tick.map(lambda t: 1.0 - t), name = "m")
a = TimeToFailure(m, minT = 0.5, name = "ttf_a")
b = TimeToFailure(m, minT = 1.5, name = "ttf_b")
"#,
    );
    assert!(
        twice.contains("wrapped already, by TimeToFailure `ttf_a` (t.star:7:5)")
            && twice.contains("t.star:8:5"),
        "{twice}"
    );
}

/// `fog` and `light` are the world's values now, equal to the World's own streams at every
/// frame, from t = 0 on.
#[test]
fn fog_and_light_signals_are_the_worlds_values_now() {
    let src = r#"
w = World(light = tick.map(lambda t: 0.2 + t / 100), fog = tick.map(lambda t: 0.4 + t / 50))
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
w.place(r, v)
Signal("myfog", tick.map(lambda t: 0.4 + t / 50))
Signal("mylight", tick.map(lambda t: 0.2 + t / 100))
Stl("G[0,2] (myfog - fog < 1e-12 & fog - myfog < 1e-12)", name = "fog_now")
Stl("G[0,2] (mylight - light < 1e-12 & light - mylight < 1e-12)", name = "light_now")
Stl("G[0,2] (fog < 0.45)", name = "fog_peak")
test(horizon = 2.0, offroad = False)
"#;
    let (r, _) = run_one(src, 0);
    let m = &r["monitors"];
    assert_eq!(m["fog_now"]["passed"], true, "{m}");
    assert_eq!(m["light_now"]["passed"], true, "{m}");
    // The fog reaches 0.44 at t = 2: the margin is 0.45 - fog(2), not fog one step earlier
    // (which would leave 1/3000 more).
    let peak = number(&m["fog_peak"]["robustness"]);
    assert!((peak - 0.01).abs() < 1e-12, "{peak}");
}

/// A `Signal` may not take the name of an actor's output, which it would silently replace.
#[test]
fn a_signal_named_like_an_actors_output_is_refused() {
    for name in ["lead.speed", "lead.pos", "lead.pos.x"] {
        let e = load_err(&format!(
            "{ROAD}w.place(r, v, lead)\nSignal(\"{name}\", tick)\nStl(\"G[0,2] (lead.speed > 5)\")\n"
        ));
        assert!(
            e.contains(&format!("Signal `{name}` takes the name of an output of"))
                && e.contains("t.star:7:1"),
            "{e}"
        );
    }
    // Another name under the actor's variable is no output of it.
    let ok = format!(
        "{ROAD}w.place(r, v, lead)\nSignal(\"lead.gap\", tick)\nStl(\"G[0,2] (lead.gap > -1)\")\n"
    );
    paracosm_scenarios::lang::load_source("t.star", &ok, "t").unwrap();
}

/// `sum()` adds vectors as LANGUAGE.md promises, from zero or from a `Vector`; a fold keeps
/// starting from 0.0.
#[test]
fn sums_of_vectors_run() {
    let src = format!(
        "{ROAD}w.place(r, v, lead)
total = lead.vel.sum()
Monitor(total.map(lambda p: p.x), name = \"x\", over = \"end\")
base = r.onLane(1, 20) - r.onLane(1, 10)
shifted = lead.vel.sum(init = base)
Monitor(shifted.map(lambda p: p.x), name = \"from_base\", over = \"end\")
count = tick.sum(init = 0.0, f = lambda acc, t: acc + 1)
Monitor(count, name = \"count\", over = \"end\")
test(horizon = 1.0, offroad = False)
"
    );
    let (r, _) = run_one(&src, 0);
    let m = &r["monitors"];
    // 61 events (t = 0 .. 1 s) of 6 m/s along x.
    assert!((number(&m["x"]["robustness"]) - 366.0).abs() < 1e-9, "{m}");
    assert!(
        (number(&m["from_base"]["robustness"]) - 376.0).abs() < 1e-9,
        "{m}"
    );
    assert_eq!(number(&m["count"]["robustness"]), 61.0);
}

/// A constant stands for a constant stream in `Monitor` and `Assert` too, with a warning that
/// its verdict never depends on the world.
#[test]
fn a_monitor_of_a_constant_loads_with_a_warning() {
    let src = format!("{ROAD}w.place(r, v, lead)\nMonitor(5.0, name = \"c\")\nAssert(True, name = \"a\")\nCollisionMonitor(v)\n");
    let s = paracosm_scenarios::lang::load_source("t.star", &src, "t").unwrap();
    let w: Vec<String> = s
        .warnings()
        .iter()
        .map(|w| format!("{}: {}", w.at, w.message))
        .collect();
    assert!(
        w.iter()
            .any(|w| w.starts_with("t.star:7:1: monitor `c` judges a constant stream")),
        "{w:?}"
    );
    assert!(
        w.iter()
            .any(|w| w.contains("monitor `a` judges a constant")),
        "{w:?}"
    );
    let e = load_err(&format!("{ROAD}w.place(r, v, lead)\nMonitor(\"fast\")\n"));
    assert!(e.contains("Monitor needs a stream of numbers"), "{e}");
}

/// An action's argument of the wrong kind is refused at load, even from a stream that never
/// fires during a test; at run time, errors name the car by its variable.
#[test]
fn action_arguments_are_checked_at_load_and_name_their_car() {
    let e = load_err(&format!(
        "{ROAD}w.place(r, v, lead)\ntick.filter(lambda t: t > 100).map(lambda t: \"fast\").foreach(lead.setSpeed)\n"
    ));
    assert!(
        e.contains("setSpeed of Car lead is given \"fast\" (a string)") && e.contains("t.star:7:"),
        "{e}"
    );
    let src = format!(
        "{ROAD}w.place(r, v, lead)\ntick.filter(lambda t: t > 0.5).map(lambda t: -2.0).foreach(lead.setSpeed)\nCollisionMonitor(v)\ntest(horizon = 2.0)\n"
    );
    let (r, _) = run_one(&src, 3);
    let error = r["error"].as_str().unwrap();
    assert!(
        error.contains("the speed given to Car lead (")
            && error.contains("t.star:5:8)'s setSpeed was -2"),
        "{error}"
    );
}

/// Load errors that had only the file now point at the line: a lambda over the step limit
/// while loading, `test(map=)` naming no parameter, a monitor named `offroad`.
#[test]
fn load_errors_point_at_their_line() {
    for (tail, needles) in [
        (
            "Monitor(tick.map(lambda t: len([x for x in range(2000000)]) - t), name = \"m\")\n",
            ["step limit exceeded", "t.star:7:9"],
        ),
        (
            "CollisionMonitor(v)\ntest(map = \"speed\")\n",
            ["names `speed`", "t.star:8:1"],
        ),
        (
            "Monitor(v.speed, name = \"offroad\")\n",
            ["default OffRoadMonitor", "t.star:7:1"],
        ),
    ] {
        let e = load_err(&format!("{ROAD}w.place(r, v, lead)\n{tail}"));
        assert!(needles.iter().all(|n| e.contains(n)), "{e}");
    }
}

/// The costlier runner signals (time to collision, lane offset) are computed for a test only
/// when a monitor reads them, and then have their values: a stopped car 50 m ahead of the
/// ego is seconds away, and the ego keeps the centre of its lane.
#[test]
fn signals_computed_on_demand_have_their_values_when_read() {
    let src = r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
stopped = Car(loc = r.onLane(1, 60), speed = 0.0)
w.place(r, v, stopped)
Stl("G[0,0.5] (ego_ttc_s > 0)", name = "ttc")
Stl("G[0,0.5] (ego_lane_offset_m < 0.3 & ego_lane_offset_m > -0.3)", name = "lane")
test(horizon = 0.5, offroad = False)
"#;
    let (r, _) = run_one(src, 0);
    let m = &r["monitors"];
    // The gap between the bodies is 50 m less a car's length, closed at 5 m/s or more (the
    // system under test speeds up): finite, a few seconds; unset it would read -inf.
    let ttc = number(&m["ttc"]["robustness"]);
    assert!(ttc > 3.0 && ttc < 10.0, "{m}");
    let lane = number(&m["lane"]["robustness"]);
    assert!(lane > 0.25 && lane <= 0.3, "{m}");
}

/// A `VarInterval` given to an input of whole numbers is refused at load, though both ends of
/// its interval are whole: loading builds the world at a value inside it too.
#[test]
fn an_interval_for_a_whole_number_input_is_refused_at_load() {
    for (decl, what) in [
        ("r = RoadSegment(len = 200, nlanes = VarInterval(2, 6))\nv = AutonomousVehicle(loc = r.onLane(1, 10))", "nlanes must be an even whole number"),
        ("r = RoadSegment(len = 200, nlanes = 4)\nv = AutonomousVehicle(loc = r.onLane(VarInterval(1, 2), 10))", "a lane is a whole number"),
    ] {
        let e = load_err(&format!(
            "w = World()\n{decl}\nw.place(r, v)\nCollisionMonitor(v)\n"
        ));
        assert!(
            e.contains(what) && e.contains("inside its interval") && e.contains("t.star:"),
            "{e}"
        );
    }
}

/// Actions take their arguments by keyword as LANGUAGE.md names them, each once; their open
/// arguments and `onLane`'s are named alike by keyword and by position; a tuple assignment
/// names each parameter by its variable.
#[test]
fn keywords_and_positions_are_one_and_name_parameters_alike() {
    let src = r#"
w = World()
r = RoadSegment(len = 300, nlanes = 4)
s = RoadSegment(len = 300, nlanes = 4)
r.connect((r.TWO, s, s.ONE))
v = AutonomousVehicle(loc = r.onLane(1, 10))
lead = Car(loc = r.onLane(1, 60), speed = 5.0)
a, b = VarInterval(10, 20), VarInterval(0, 5)
c = Car(loc = s.onLane(lane = 1, at = VarInterval(10, 20)), speed = b)
e = Car(loc = r.onLane(VarEnum([-1, -2]), at = VarInterval(100, 120)))
tick.filter(lambda t: t > 3).take(1).foreach(lead.changeLane(lane = 2, duration = 2.0))
tick.filter(lambda t: t > 4).take(1).foreach(lead.setSpeed(v = a))
tick.filter(lambda t: t > 5).take(1).foreach(c.brake(decel = VarInterval(1, 3)))
w.place(r, s, v, lead, c, e)
CollisionMonitor(v)
"#;
    let s = paracosm_scenarios::lang::load_source("t.star", src, "t").unwrap();
    let mut names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    names.sort();
    assert_eq!(
        names,
        [
            "a",
            "b",
            "c.brake",
            "r.onLane[0]",
            "r.onLane[1]",
            "s.onLane"
        ]
    );
    for (call, message) in [
        (
            "lead.changeLane(lanes = 2)",
            "changeLane has no argument `lanes`: it is changeLane(lane, duration)",
        ),
        ("lead.brake(3, decel = 2)", "`decel` is given twice"),
        ("lead.setSpeed()", "setSpeed needs `v`"),
        ("lead.brake(1, 2)", "brake takes 1 argument"),
    ] {
        let e = load_err(&src.replace("lead.changeLane(lane = 2, duration = 2.0)", call));
        assert!(
            e.contains(message) && e.contains("t.star:11:"),
            "{call}: {e}"
        );
    }
}

/// Units are checked on every input that has one, whatever the form of the argument.
#[test]
fn units_are_checked_on_lane_changes_obstacles_positions_and_actions() {
    let src = r#"
w = World()
r = RoadSegment(len = 300, nlanes = 4)
v = AutonomousVehicle(loc = r.onLane(1, VarInterval(10, 20, unit = "s")))
c = Car(loc = r.onLane(lane = -1, at = VarInterval(50, 60, unit = "km")), lane_change = ChangeLane(to = -2, at = VarInterval(1, 2, unit = "m"), duration = VarInterval(1, 2, unit = "km")))
o = Obstacle(loc = r.onLane(-2, 200), size = (VarInterval(1, 2, unit = "s"), 1, 1))
d = VarInterval(2, 3, unit = "m/s")
sz = VarInterval(1, 2, unit = "km/h")
o2 = Obstacle(loc = r.onLane(-2, 250), size = (1, 1, sz))
tick.filter(lambda t: t > 100).take(1).foreach(c.brake(d))
tick.filter(lambda t: t > 100).take(1).foreach(c.changeLane(-1, duration = VarInterval(1, 2, unit = "m")))
dur = VarInterval(1, 2, unit = "km")
tick.filter(lambda t: t > 200).take(1).foreach(c.changeLane(-1, dur))
w.place(r, v, c, o, o2)
CollisionMonitor(v)
"#;
    let s = paracosm_scenarios::lang::load_source("t.star", src, "t").unwrap();
    let w: Vec<&str> = s.warnings().iter().map(|w| w.message.as_str()).collect();
    for expected in [
        "`r.onLane_1` is declared in s but feeds onLane(at=), which is in m",
        "`r.onLane_2` is declared in km but feeds onLane(at=), which is in m",
        "`ChangeLane.at` is declared in m but feeds ChangeLane(at=), which is in s",
        "`ChangeLane.duration` is declared in km but feeds ChangeLane(duration=), which is in s",
        "`o.size[0]` is declared in s but feeds Obstacle(size[0]=), which is in m",
        "`d` is declared in m/s but feeds brake(decel=), which is in m/s²",
        "`sz` is declared in km/h but feeds Obstacle(size[2]=), which is in m",
        "`c.changeLane` is declared in m but feeds changeLane(duration=), which is in s",
        "`dur` is declared in km but feeds changeLane(duration=), which is in s",
    ] {
        assert!(w.contains(&expected), "{expected}\n{w:#?}");
    }
}

/// A lane change into the other direction's lane is allowed, with a warning; levels that
/// depend on another parameter are refused with both sets of levels named.
#[test]
fn wrong_way_lane_changes_warn_and_levels_that_vary_are_named() {
    let src = r#"
w = World()
r = RoadSegment(len = 300, nlanes = 4)
v = AutonomousVehicle(loc = r.onLane(1, 10))
c = Car(loc = r.onLane(2, 60), speed = 5.0, lane_change = ChangeLane(to = -1, at = 1.0))
w.place(r, v, c)
CollisionMonitor(v)
"#;
    let s = paracosm_scenarios::lang::load_source("t.star", src, "t").unwrap();
    assert!(
        s.warnings().iter().any(|w| w.at == "t.star:5:5"
            && w.message.contains(
                "ChangeLane(to = -1) moves it from lane 2 into a lane of the other direction"
            )),
        "{:?}",
        s.warnings()
    );
    let e = load_err(
        r#"
n = VarEnum([2, 4])
w = World()
m = VarEnum([1, n // 2 + 5])
r = RoadSegment(len = 300, nlanes = n)
v = AutonomousVehicle(loc = r.onLane(1, 10 + m))
w.place(r, v)
CollisionMonitor(v)
"#,
    );
    assert!(
        e.contains("`m` has the levels [1, 6] for some values and the levels [1, 7] for others")
            && e.contains("t.star:4:5"),
        "{e}"
    );
}

/// `--strategy ipog` without `--strength` covers a program with one discrete parameter (the
/// default strength 2 is lowered to 1 there); asked for explicitly, strength 2 is refused.
#[test]
fn a_covering_suite_over_one_discrete_parameter_runs_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("one.star");
    std::fs::write(
        &file,
        "w = World()\nn = VarEnum([2, 4])\nr = RoadSegment(len = 200, nlanes = n)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\nCollisionMonitor(v)\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        let mut args = vec![
            file.to_str().unwrap(),
            "--strategy",
            "ipog",
            "--budget",
            "4",
            "--force",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        fuzz(&args)
    };
    let o = run(&[]);
    expect_code(&o, 0);
    let rs = records(&out);
    assert_eq!(rs.len(), 4);
    let levels: std::collections::BTreeSet<String> =
        rs.iter().map(|r| r["params"]["n"].to_string()).collect();
    assert_eq!(levels.len(), 2, "both levels covered: {levels:?}");
    let o = run(&["--strength", "2"]);
    expect_code(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr)
        .contains("--strength 2: a covering array of strength 2 needs 2 discrete parameters"));
    // For any other strategy --strength is the strength of the coverage reported: accepted.
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--strategy",
        "halton",
        "--strength",
        "1",
        "--budget",
        "2",
        "--force",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    // --sut-timeout and --sut-fresh without --sut-cmd were accepted and did nothing.
    for flag in [&["--sut-timeout", "3"][..], &["--sut-fresh"][..]] {
        let o = run(flag);
        expect_code(&o, 2);
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("--sut-cmd"),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// An NPC car's `pos` is its body's centre, as LANGUAGE.md says and as the ego's is its
/// chassis centre: above the road, not on it.
#[test]
fn a_cars_position_is_its_centre() {
    let src = format!(
        "{ROAD}w.place(r, v, lead)\nSignal(\"lead_y\", lead.pos.map(lambda p: p.y))\nStl(\"G[0,1] (lead_y > 0.5 & lead_y < 1.5)\", name = \"centre\")\ntest(horizon = 1.0, offroad = False)\n"
    );
    let (r, _) = run_one(&src, 0);
    assert_eq!(r["monitors"]["centre"]["passed"], true, "{}", r["monitors"]);
}

/// A formula compares numbers: a vector named whole (an actor's `pos`, a vector `Signal`),
/// a component of a number, or no output at all is an error at load with the formula's
/// line, never a test failed at `-inf`.
#[test]
fn a_formula_over_a_vector_or_a_missing_component_is_refused_at_load() {
    for (formula, message) in [
        ("lead.pos > 3", "`lead.pos` is a vector"),
        ("lead.vel > 3", "`lead.vel` is a vector"),
        (
            "lead.speed.x > 3",
            "`lead.speed` is a number, with no component `x`",
        ),
        ("lead.pos.w > 3", "`lead.pos.w` is no output of `lead.pos`"),
        ("lp > 0", "`lp` is a vector"),
        ("lq.x > 0", "`lq` carries numbers, with no component `x`"),
    ] {
        let e = load_err(&format!(
            "{ROAD}w.place(r, v, lead)\nSignal(\"lp\", lead.pos)\nSignal(\"lq\", lead.speed.map(lambda s: s))\nStl(\"G[0,10] ({formula})\")\n"
        ));
        assert!(
            e.contains(message) && e.contains("t.star:9:1"),
            "{formula}: {e}"
        );
    }
}

/// A monitor cut short by another's failure covers only the run up to it: it does not count
/// in the test's robustness nor among its failed monitors (an `eventually` cut at 0.2 s would
/// read `-inf`).
#[test]
fn monitors_cut_short_do_not_count_in_the_tests_verdict() {
    let src = r#"
w = World()
r = RoadSegment(len = 1000.0)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 12.0)
w.place(r, v)
test(horizon = 10.0, offroad = False)
late = Stl("F[9,10] (ego_x_m > 0)", name = "late")
now = Stl("ego_x_m > 11", name = "now")
"#;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.star");
    std::fs::write(&file, src).unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("monitors failed: now\n"), "{stdout}");
    let summary: Json =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let failure = &summary["failures"][0];
    assert_eq!(failure["failed_monitors"], serde_json::json!(["now"]));
    assert!(
        (number(&failure["robustness"]) + 1.0).abs() < 1e-9,
        "{failure}"
    );
    let r = &records(&out)[0];
    assert_eq!(r["monitors"]["late"]["cut_short"], true);
}

/// Headings are in `(-π, π]` everywhere: a car driving west publishes `π`, as the location it
/// starts at reports, and a monitor's name defaults to its variable for `Stl` as for `Monitor`.
#[test]
fn westbound_headings_agree_and_formulas_take_their_variables_name() {
    let src = r#"
w = World()
r = RoadSegment(len = 1000.0)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 12.0)
start = r.onLane(-1, 900)
opp = Car(loc = start, speed = 10.0)
w.place(r, v, opp)
test(horizon = 2.0, offroad = False)
CollisionMonitor(v)
westbound = Stl("G[0,2] (opp.heading > 3.14159)")
Signal("start_heading", tick.map(lambda t: start.heading))
same = Stl("G[0,2] (opp.heading - start_heading > -1e-12 & start_heading - opp.heading > -1e-12)")
"#;
    let (r, _) = run_one(src, 0);
    let m = &r["monitors"];
    assert_eq!(m["westbound"]["passed"], true, "{m}");
    assert_eq!(m["same"]["passed"], true, "{m}");
}

/// A monitor decided between two of an `Stl` formula's checks is not cut short by a monitor
/// that fails after it: the rear-ending car breaks the gap at 0.5 s, and the collision comes
/// at about 0.57 s, before the formula's next check (0.75 s).
#[test]
fn a_formula_violated_before_a_collision_fails_and_is_not_cut_short() {
    let src = r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 20), speed = 5.0)
c = Car(loc = r.onLane(1, 5), speed = 25.0)
w.place(r, v, c)
CollisionMonitor(v)
keep_gap = Stl("G[0,5] (ego_separation_m > 1)")
test(horizon = 5.0)
"#;
    let (r, _) = run_one(src, 1);
    let m = &r["monitors"];
    let gap = &m["keep_gap"];
    assert_eq!(gap["passed"], false, "{m}");
    assert!(gap.get("cut_short").is_none(), "{m}");
    let (t_gap, t_hit) = (
        number(&gap["first_violation_s"]),
        number(&m["collision"]["first_violation_s"]),
    );
    assert!(t_gap < t_hit, "{m}");
    assert_eq!(number(&r["metrics"]["time_to_failure_s"]), t_gap);
    // Alone, the formula gives the same verdict and failure time.
    let (alone, _) = run_one(&src.replace("CollisionMonitor(v)\n", ""), 1);
    let a = &alone["monitors"]["keep_gap"];
    assert_eq!(
        (a["passed"].clone(), number(&a["first_violation_s"])),
        (Json::Bool(false), t_gap)
    );
}

/// A monitor over a stream that never fires fails when the test ends, for every `over`: its
/// failure time is the last step, so `TimeToFailure` reads the same time for each.
#[test]
fn a_stream_that_never_fires_fails_at_the_end_whatever_its_over() {
    let src = r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
w.place(r, v)
late = tick.filter(lambda t: t > 100.0).map(lambda t: 1.0)
m_end = Monitor(late, over = "end")
m_alw = Monitor(late, over = "always")
m_evt = Monitor(late, over = "eventually")
TimeToFailure(m_end, minT = 1.0, name = "ttf_end")
TimeToFailure(m_alw, minT = 1.0, name = "ttf_alw")
TimeToFailure(m_evt, minT = 3.0, name = "ttf_evt")
test(horizon = 2.0)
"#;
    let (r, _) = run_one(src, 1);
    let m = &r["monitors"];
    for (name, passed) in [("ttf_end", true), ("ttf_alw", true), ("ttf_evt", false)] {
        assert_eq!(m[name]["passed"], passed, "{name}: {m}");
        let t = number(&m[name]["first_violation_s"]);
        assert!((t - 2.0).abs() < 1e-9, "{name}: {m}");
    }
    assert!((number(&r["metrics"]["time_to_failure_s"]) - 2.0).abs() < 1e-9);
}

/// The test's `time_to_failure_s` is the earliest failure of a monitor that failed it: a
/// `TimeToFailure` that passed (its monitor failed after `minT`) carries its monitor's time
/// but failed nothing, and the metric read that time.
#[test]
fn the_tests_time_to_failure_is_that_of_a_monitor_that_failed_it() {
    let program = |with_late_failure: bool| {
        format!(
            r#"
w = World()
r = RoadSegment(len = 400.0)
v = AutonomousVehicle(loc = r.onLane(1, 10.0), speed = 12.0)
w.place(r, v)
s = Stl("G[0,20] (ego_x_m < 60)", name = "below60")
TimeToFailure(s, minT = 3.0, name = "ttf_stl")
{}
test(horizon = 12.0)
"#,
            if with_late_failure {
                "m = Monitor(v.pos.map(lambda p: 100.0 - p.x), name = \"below100\")\nTimeToFailure(m, minT = 20.0, name = \"ttf_mon\")"
            } else {
                ""
            }
        )
    };
    // Only the passing TimeToFailure: no failure, no time.
    let (r, _) = run_one(&program(false), 0);
    let m = &r["monitors"];
    assert_eq!(m["ttf_stl"]["passed"], true, "{m}");
    assert!(number(&m["ttf_stl"]["first_violation_s"]) < 5.0, "{m}");
    assert!(
        r["metrics"].get("time_to_failure_s").is_none(),
        "{}",
        r["metrics"]
    );
    // With a later failure that fails the test: its time, not the passing one's.
    let (r, _) = run_one(&program(true), 1);
    let m = &r["monitors"];
    let t = number(&m["ttf_mon"]["first_violation_s"]);
    assert_eq!(m["ttf_mon"]["passed"], false, "{m}");
    assert!(t > number(&m["ttf_stl"]["first_violation_s"]), "{m}");
    assert_eq!(number(&r["metrics"]["time_to_failure_s"]), t);
}

/// An obstacle's colour is seen by a camera only: under `aeb` (lidar) an open one is named
/// in a warning, as a car's colour is.
#[test]
fn an_open_obstacle_colour_under_a_lidar_system_warns() {
    let src = r#"
w = World()
r = RoadSegment(len = 400.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)
box_color = VarEnum(["orange", "grey"])
o = Obstacle(loc = r.onLane(1, 200), size = (1.0, 1.0, 1.0), color = box_color)
w.place(r, v, o)
CollisionMonitor(v)
test(horizon = 1.0)
"#;
    let (_, stderr) = run_one(src, 0);
    assert!(
        stderr.contains("`box_color` sets the colour of Obstacle"),
        "{stderr}"
    );
}

/// A parameter that changes nothing from the first world, but does where another parameter
/// takes another value, is neither left out of coverage nor named in a warning: a radius read
/// only on the `bend` branch of an `if` (whichever level comes first), a friction reached only
/// from the second start. A parameter that changes nothing anywhere still is, and a friction
/// no start reaches still warns.
#[test]
fn a_parameter_that_matters_only_for_other_values_of_another_is_used() {
    let bend = |levels: &str| {
        format!(
            r#"
shape = VarEnum({levels})
rad = VarInterval(20.0, 60.0)
idle = VarInterval(0.0, 1.0)
s = RoadSegment(len = 50.0)
if shape == "bend":
    b = Arc(radius = rad, angle = 1.0)
else:
    b = RoadSegment(len = 40.0)
net = s.connect((s.TWO, b, b.ONE))
w = World()
v = AutonomousVehicle(loc = s.onLane(1, 5.0), speed = 5.0)
w.place(net, v)
CollisionMonitor(v)
DistanceMonitor(v, minD = 5.0)
test(horizon = 3.0)
"#
        )
    };
    for levels in [r#"["straight", "bend"]"#, r#"["bend", "straight"]"#] {
        let s = paracosm_scenarios::lang::load_source("t.star", &bend(levels), "t").unwrap();
        assert_eq!(s.unused_params(), vec!["idle".to_owned()], "{levels}");
        assert_eq!(s.warnings().len(), 1, "{levels}: {:?}", s.warnings());
        assert!(
            s.warnings()[0].message.contains("`idle`"),
            "{:?}",
            s.warnings()
        );
    }
    let start = |starts: &str| {
        format!(
            r#"
k = VarEnum([0, 1])
far_mu = VarInterval(0.1, 0.9)
a = RoadSegment(len = 600.0)
ice = RoadSegment(len = 100.0, friction = far_mu)
net = a.connect((a.TWO, ice, ice.ONE))
w = World()
v = AutonomousVehicle(loc = a.onLane(1, {starts}[k]), speed = 10.0)
o = Obstacle(loc = ice.onLane(1, 50.0))
w.place(net, v, o)
CollisionMonitor(v)
DistanceMonitor(v, minD = 5.0)
test(horizon = 10.0)
"#
        )
    };
    let s = paracosm_scenarios::lang::load_source("t.star", &start("[5.0, 580.0]"), "t").unwrap();
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
    let s = paracosm_scenarios::lang::load_source("t.star", &start("[5.0, 6.0]"), "t").unwrap();
    assert!(
        s.warnings().len() == 1
            && s.warnings()[0]
                .message
                .contains("`far_mu` sets the friction of"),
        "{:?}",
        s.warnings()
    );
}

/// A disabled car is left out of `place`'s checks as it is out of the test: two cars on one
/// spot, one enabled for each level, load; a disabled car overlapping the ego or on a sidewalk
/// loads, and the ego drives through it without a collision.
#[test]
fn a_disabled_car_is_left_out_of_the_placement_checks() {
    let head = "w = World()\nr = RoadSegment(len = 300.0, nlanes = 2)\nv = AutonomousVehicle(loc = r.onLane(1, 10), speed = 8.0)\n";
    let s = format!(
        "{head}on = VarEnum([True, False])\nc = Car(loc = r.onLane(1, 60.0), speed = 0.0, enabled = on)\nc2 = Car(loc = r.onLane(1, 60.0), speed = 0.0, enabled = not on)\nw.place(r, v, c, c2)\nCollisionMonitor(v)\n"
    );
    paracosm_scenarios::lang::load_source("t.star", &s, "t").unwrap();
    for loc in ["r.onLane(1, 10.0)", "r.onLane(r.SideWalk, 40.0)"] {
        let s = format!(
            "{head}ghost = Car(loc = {loc}, speed = 0.0, enabled = False)\nw.place(r, v, ghost)\nCollisionMonitor(v)\ntest(horizon = 3.0)\n"
        );
        let (r, _) = run_one(&s, 0);
        assert_eq!(r["monitors"]["collision"]["passed"], true, "{loc}: {r}");
    }
    // Enabled, the same car is refused.
    let s = format!(
        "{head}ghost = Car(loc = r.onLane(1, 10.0), speed = 0.0, enabled = True)\nw.place(r, v, ghost)\nCollisionMonitor(v)\n"
    );
    assert!(load_err(&s).contains("start in collision"));
}

/// Found by programs written from LANGUAGE.md: a number from a `filter` predicate is refused
/// (it was read as true unless exactly 0); a Signal named like a component of another
/// (`lp.x` beside a vector `lp`) is refused (it hid the vector's component); an explicit
/// name equal to the `param<i>` another parameter takes is refused (it renamed that one);
/// open parameters in a list or dict that a lambda reads are used (they were dropped from
/// coverage); a `def` that returns an unbound action performs it with the event's value; a
/// top-level variable holding `tick` reads as the time in a lambda.
#[test]
fn silent_misreadings_found_by_new_programs_are_refused_or_read_right() {
    let head = "w = World()\nr = RoadSegment(len = 400.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10), speed = 0.0)\nlead = Car(loc = r.onLane(1, 60), speed = 5.0)\nw.place(r, v, lead)\n";
    let e = load_err(&format!(
        "{head}m = Monitor(tick.filter(lambda t: t - 0.5).map(lambda t: 1.0).sum(), over = \"end\")\n"
    ));
    assert!(
        e.contains("filter predicate needs bool, got a number"),
        "{e}"
    );
    assert!(e.contains("t.star:6:"), "{e}");
    for (a, b) in [("lp", "lp.x"), ("lp.z", "lp")] {
        let first = if a == "lp" {
            "lead.pos"
        } else {
            "tick.map(lambda t: 5.0)"
        };
        let second = if a == "lp" {
            "tick.map(lambda t: 5.0)"
        } else {
            "lead.pos"
        };
        let e = load_err(&format!(
            "{head}Signal(\"{a}\", {first})\nSignal(\"{b}\", {second})\ns = Stl(\"G[0,1] (lp.x > 0)\")\n"
        ));
        assert!(e.contains("clash") && e.contains("t.star:7:1"), "{e}");
    }
    let e = load_err(&format!(
        "{head}z = [VarInterval(0, 1)]\nq = VarInterval(0, 1, name = \"param0\")\nMonitor(tick.map(lambda t: z[0] + q))\n"
    ));
    assert!(e.contains("takes from where it stands"), "{e}");
    let s = paracosm_scenarios::lang::load_source(
        "t.star",
        &format!(
            "{head}xs = [VarInterval(0, 1), VarInterval(0, 1)]\ncfg = {{\"lim\": VarInterval(0, 1)}}\ndef lim():\n    return cfg[\"lim\"]\nm = Monitor(tick.map(lambda t: xs[0] - 0.5), over = \"end\")\nm2 = Monitor(tick.map(lambda t: lim() - 0.5), over = \"end\")\n"
        ),
        "t",
    )
    .unwrap();
    assert!(s.unused_params().is_empty(), "{:?}", s.unused_params());
    assert!(s.warnings().is_empty(), "{:?}", s.warnings());
    // The returned unbound action sets the lead's speed to the event's value, 7 m/s.
    let (r, _) = run_one(
        &format!(
            "{head}def h(s):\n    return lead.setSpeed\ntick.filter(lambda t: t > 1).take(1).map(lambda t: 7.0).foreach(h)\ntop = Monitor(lead.speed.map(lambda s: s), over = \"end\")\nticks = tick\nclock = Monitor(v.speed.map(lambda s: 100 - ticks), over = \"end\")\ntest(horizon = 3.0, offroad = False)\n"
        ),
        0,
    );
    assert_eq!(r["status"], "pass", "{r}");
    assert!(
        (number(&r["monitors"]["top"]["robustness"]) - 7.0).abs() < 1e-9,
        "{r}"
    );
    assert!(
        (number(&r["monitors"]["clock"]["robustness"]) - 97.0).abs() < 1e-9,
        "{r}"
    );
}

/// A Monitor or Assert of an open parameter's value is no constant of the campaign: it is
/// neither warned about as one nor its parameter as unused; `Monitor(5.0)` still is.
#[test]
fn a_monitor_of_an_open_value_is_not_a_constant_one() {
    let s = paracosm_scenarios::lang::load_source(
        "t.star",
        "w = World()\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\nk = VarInterval(-1, 1)\nm = Monitor(k)\na = Assert(VarEnum([True, False]))\nc = Monitor(5.0)\n",
        "t",
    )
    .unwrap();
    let w: Vec<&str> = s.warnings().iter().map(|w| w.message.as_str()).collect();
    assert_eq!(w.len(), 1, "{w:#?}");
    assert!(
        w[0].contains("monitor `c` judges a constant stream"),
        "{w:#?}"
    );
    assert!(s.unused_params().is_empty(), "{:?}", s.unused_params());
}

/// A horizon between two steps is rounded up to whole steps of 1/60 s: 0.005 s runs one step
/// (it ran none, and every monitor judged an empty test), 1.01 s runs 61.
#[test]
fn a_horizon_between_steps_is_rounded_up() {
    for (horizon, steps) in [("0.005", 1.0), ("1.01", 61.0), ("2.0", 120.0)] {
        let (r, _) = run_one(
            &format!(
                "w = World()\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\nCollisionMonitor(v)\ntest(horizon = {horizon})\n"
            ),
            0,
        );
        let simulated = number(&r["metrics"]["simulated_s"]);
        assert!((simulated - steps / 60.0).abs() < 1e-9, "{horizon}: {r}");
    }
}

/// An error a lambda raises during a test names the moment, the stream that called it and
/// the program's line, without starlark's header for a call from the engine.
#[test]
fn a_lambdas_error_during_a_test_names_the_time_and_its_line() {
    let (r, _) = run_one(
        "w = World()\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\ndef f(t):\n    return 1 // 0 if t > 1 else 1.0\nm = Monitor(tick.map(f))\n",
        3,
    );
    let e = r["error"].as_str().unwrap();
    assert!(e.starts_with("at t = 1.017 s, "), "{e}");
    assert!(
        e.contains("t.star:7:13: ") && e.contains("t.star:6:12"),
        "{e}"
    );
    assert!(
        e.contains("Floor division by zero") && !e.contains("Traceback"),
        "{e}"
    );
}

/// An NPC car brakes ahead of a dead end no harder than its tyres let it (`μ·g`) and stops
/// with its front at the end (it stopped from 15 m/s within one step, its centre at the end).
#[test]
fn a_car_brakes_for_a_dead_end_within_its_grip() {
    for mu in [0.8, 0.1] {
        let (r, _) = run_one(
            &format!(
                r#"
r = RoadSegment(len = 300.0, friction = {mu})
w = World()
v = AutonomousVehicle(loc = r.onLane(-1, 295.0), speed = 0.0)
c = Car(loc = r.onLane(1, 5.0), speed = 15.0)
prev = c.speed.take(1).concat(c.speed)
decel = c.speed.zip(prev).map(lambda p: (p[1] - p[0]) * 60.0)
grip = Monitor(decel.map(lambda d: {mu} * 9.81 * (1 + 1e-6) - d))
front = Monitor(c.pos.map(lambda p: p.x + 2.25 - 300.0 + 1e-6), over = "end")
still = Monitor(c.speed.map(lambda s: 1e-9 - s), over = "end")
test(horizon = 30.0, offroad = False)
w.place(r, v, c)
"#
            ),
            0,
        );
        let m = &r["monitors"];
        for name in ["grip", "front", "still"] {
            assert_eq!(m[name]["passed"], true, "μ = {mu}, {name}: {m}");
        }
        assert!(number(&m["front"]["robustness"]) < 1e-3, "μ = {mu}: {m}");
    }
}

/// A car on a loop drives on for the whole horizon: routes are planned as far as 60 m/s goes
/// in the horizon (a route stopped at 5 km, so a car at 15 m/s stopped after 333 s of a
/// 600 s test).
#[test]
fn a_car_on_a_loop_drives_the_whole_of_a_long_horizon() {
    let (r, _) = run_one(
        r#"
R = 40.0
PI = 3.141592653589793
a1 = Arc(radius = R, angle = PI / 2)
a2 = Arc(radius = R, angle = PI / 2)
a3 = Arc(radius = R, angle = PI / 2)
a4 = Arc(radius = R, angle = PI / 2)
s1 = RoadSegment(len = 50.0)
s2 = RoadSegment(len = 50.0)
s1.connect((s1.TWO, a1, a1.ONE), (a1.TWO, a2, a2.ONE), (a2.TWO, s2, s2.ONE), (s2.TWO, a3, a3.ONE), (a3.TWO, a4, a4.ONE))
a4.connect((a4.TWO, s1, s1.ONE))
w = World()
v = AutonomousVehicle(loc = s1.onLane(1, 10), speed = 0.0)
c = Car(loc = s2.onLane(-1, 20), speed = 15.0)
moving = Monitor(c.speed.map(lambda s: s - 1.0), over = "end")
test(horizon = 600.0, offroad = False)
w.place(s1, s2, a1, a2, a3, a4, v, c)
"#,
        0,
    );
    assert!(
        (number(&r["monitors"]["moving"]["robustness"]) - 14.0).abs() < 1e-9,
        "{r}"
    );
}

/// An action performed by a function given to `map` is an error at the moment it happens (it
/// took effect only when some unrelated `foreach` next ran), and a computed input whose stream
/// has not fired is an error, not its default (a friction stream that fires only after 100 s
/// braked the car at 0.8·g; a fog stream, 0).
#[test]
fn actions_outside_foreach_and_inputs_without_a_value_end_the_test_in_error() {
    let road = "w = World()\nr = RoadSegment(len = 600.0)\nv = AutonomousVehicle(loc = r.onLane(-1, 590), speed = 0.0)\n";
    let cases = [
        (
            format!("{road}c = Car(loc = r.onLane(1, 10), speed = 20.0)\nw.place(r, v, c)\ndef slow(t):\n    if t > 1.0:\n        c.setSpeed(2.0)\n    return 1.0\nok = Monitor(tick.map(slow))\n"),
            "at t = 1.017 s, ",
            "only foreach performs actions",
        ),
        (
            // A piece of its own, beyond r, whose friction stream fires only after 100 s.
            format!("{road}r2 = RoadSegment(len = 50.0, friction = tick.filter(lambda t: t > 100).map(lambda t: 0.1))\nr.connect((r.TWO, r2, r2.ONE))\nw.place(r, v)\nCollisionMonitor(v)\n"),
            "at t = 0.000 s, the friction of",
            "without a value",
        ),
        (
            road.replace("World()", "World(fog = tick.filter(lambda t: t > 100).map(lambda t: 1.0))")
                + "w.place(r, v)\nCollisionMonitor(v)\n",
            "at t = 0.000 s, the fog",
            "without a value",
        ),
    ];
    for (i, (src, when, what)) in cases.iter().enumerate() {
        let (r, _) = run_one(src, 3);
        let e = r["error"].as_str().unwrap_or_default();
        assert!(e.starts_with(when) && e.contains(what), "{i}: {e}");
    }
}

/// `replay` says a monitor cut short by another's failure was cut short: it printed "failed",
/// though the campaign did not count it among the failed monitors.
#[test]
fn replay_names_a_monitor_cut_short_as_cut_short() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.star");
    let src = format!(
        "{ROAD}w.place(r, v, lead)\nCollisionMonitor(v)\nDistanceMonitor(v, minD = 300.0)\n\
         Monitor(lead.pos.map(lambda p: 80.0 - p.x), name = \"lead_near\")\ntest(horizon = 30.0)\n"
    );
    std::fs::write(&file, src).unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let r = &records(&out)[0];
    assert_eq!(r["monitors"]["distance"]["cut_short"], true, "{r}");
    let results = out.join("results.jsonl");
    let o = fuzz(&["replay", results.to_str().unwrap(), "--id", "0"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("distance cut short (robustness"),
        "{stdout}"
    );
    assert!(stdout.contains("lead_near failed (robustness"), "{stdout}");
}

/// A program whose monitors cannot fail a car that stops (collision and off-road only,
/// wrapped or not) is warned about at its `place`; one with a `DistanceMonitor`, or a
/// `Monitor` of its own, is not.
#[test]
fn monitors_that_a_stopped_car_passes_are_warned_about() {
    let program = |monitors: &str| {
        format!(
            "w = World()\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\n\
             p = Pedestrian(start = r.onLane(r.SideWalk, 100), target = r.onLane(-r.SideWalk, 100), \
             dist = 20.0, car = v.pos, speed = VarInterval(1.0, 3.0))\nw.place(r, p, v)\n{monitors}\n"
        )
    };
    let stopped = "a car that stops, and so never meets the danger, passes every test";
    for monitors in [
        "CollisionMonitor(v)",
        "TimeToFailure(CollisionMonitor(v), minT = 10.0)",
        "CollisionMonitor(v)\nOffRoadMonitor(v)",
    ] {
        let s = paracosm_scenarios::lang::load_source("t.star", &program(monitors), "t").unwrap();
        let w: Vec<_> = s
            .warnings()
            .iter()
            .filter(|w| w.message.contains(stopped))
            .collect();
        assert_eq!(w.len(), 1, "{monitors}: {:?}", s.warnings());
        assert_eq!(w[0].at, "t.star:5:1", "{monitors}");
    }
    for monitors in [
        "CollisionMonitor(v)\nDistanceMonitor(v, minD = 95.0)",
        "CollisionMonitor(v)\nMonitor(v.pos.map(lambda c: c.x - 105.0), over = \"eventually\")",
        "Stl(\"G[0,15] (ego_separation_m > 0.5)\")",
    ] {
        let s = paracosm_scenarios::lang::load_source("t.star", &program(monitors), "t").unwrap();
        assert!(
            s.warnings().iter().all(|w| !w.message.contains(stopped)),
            "{monitors}: {:?}",
            s.warnings()
        );
    }
}
