//! Loading programs: the vocabulary, and an error a user can act on for every mistake.

use super::load_source;
use crate::ScenarioError;

const HEADER: &str = "w = World(light = 1.0, fog = 0.0)\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\n";

fn err(src: &str) -> String {
    match load_source("bad.star", src, "bad") {
        Err(ScenarioError::Language(m)) => m,
        Err(e) => panic!("not a language error: {e}"),
        Ok(_) => panic!("loaded:\n{src}"),
    }
}

/// The message, the `file:line:col` and the caret line.
fn assert_diag(src: &str, message: &str, at: &str) {
    let m = err(src);
    assert!(m.contains(message), "message {message:?} not in:\n{m}");
    assert!(
        m.contains(&format!("bad.star:{at}")),
        "location {at} not in:\n{m}"
    );
    assert!(m.contains('^'), "no caret in:\n{m}");
}

#[test]
fn a_syntax_error_points_at_the_token() {
    assert_diag("x = = 1\n", "Parse error: unexpected symbol '='", "1:5");
}

#[test]
fn a_typo_suggests_the_right_name() {
    assert_diag(
        "x = VarIntervall(0, 1)\n",
        "Variable `VarIntervall` not found, did you mean `VarInterval`?",
        "1:5",
    );
}

#[test]
fn an_unknown_keyword_is_refused() {
    assert_diag(
        "r = RoadSegment(lenght = 10.0)\n",
        "Found `lenght` extra named parameter(s) for call to RoadSegment, did you mean `len`?",
        "1:5",
    );
}

#[test]
fn a_wrong_argument_type_names_the_parameter() {
    assert_diag(
        "r = RoadSegment(len = \"long\")\n",
        "len must be a number, got a string",
        "1:5",
    );
}

#[test]
fn an_empty_interval_is_refused() {
    assert_diag(
        "speed = VarInterval(5, 1)\n",
        "VarInterval(5, 1) is empty: lo must be below hi",
        "1:9",
    );
}

#[test]
fn an_invalid_connection_is_refused() {
    let src = "a = RoadSegment(len = 50.0, nlanes = 2)\nb = RoadSegment(len = 50.0, nlanes = 6)\na.connect((a.TWO, b, b.ONE))\n";
    assert_diag(
        src,
        "lane-count mismatch: RoadSegment declared at bad.star:1:5.TWO has 2 lanes but RoadSegment declared at bad.star:2:5.ONE has 6",
        "3:1",
    );
}

#[test]
fn objects_starting_in_collision_are_both_named() {
    let src = format!("{HEADER}c = Car(loc = r.onLane(1, 12))\nw.place(r, v, c)\n");
    assert_diag(
        &src,
        "AutonomousVehicle declared at bad.star:3:5 and Car declared at bad.star:4:5 start in collision",
        "5:1",
    );
}

#[test]
fn a_vehicle_off_the_road_is_refused() {
    let src = format!("{HEADER}c = Car(loc = r.onLane(r.SideWalk, 50))\nw.place(r, v, c)\n");
    assert_diag(&src, "Car declared at bad.star:4:5 is off the road", "5:1");
}

#[test]
fn an_infinite_loop_is_stopped() {
    let m = err("def f():\n    for i in range(1000000000):\n        pass\nf()\n");
    assert!(m.contains("tick") || m.contains("limit"), "{m}");
}

#[test]
fn runaway_allocation_is_stopped() {
    let m = err("def f():\n    x = []\n    for i in range(100000000):\n        x.append([i, i, i, i])\nf()\n");
    assert!(m.contains("limit") || m.contains("heap"), "{m}");
}

#[test]
fn a_program_cannot_read_files_or_the_clock() {
    for (src, name) in [
        ("open('/etc/passwd')\n", "open"),
        ("load('x.star', 'y')\n", "load"),
        ("time()\n", "time"),
    ] {
        let m = err(src);
        assert!(m.contains("bad.star:1:1"), "{name}: {m}");
    }
}

#[test]
fn parameters_take_their_global_names_and_over_time_adds_coordinates() {
    let src = format!(
        "fog = VarInterval(0.0, 1.0, over_time = Polynomial(2))\nlevels = VarEnum([2, 4])\nw2 = 0\n{}\n",
        "w = World(light = 1.0, fog = fog)\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\nCollisionMonitor(v)\n"
    );
    let s = load_source("ok.star", &src, "ok").unwrap();
    let names: Vec<&str> = s.space.params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["fog.c0", "fog.c1", "fog.c2", "levels"]);
}

#[test]
fn brackets_nested_too_deep_are_an_error_not_a_stack_overflow() {
    let deep = format!("x = {}{}\n", "[".repeat(20_000), "]".repeat(20_000));
    let e = super::load_source("deep.star", &deep, "deep")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("nest deeper than 100 levels") && e.contains("deep.star:1:105"),
        "{e}"
    );
    // Brackets inside strings and comments do not count.
    let fine = format!(
        "# {}\ns = \"{}\"\nt = \"\"\"{}\"\"\"\n",
        "[".repeat(500),
        "(".repeat(500),
        "{".repeat(500)
    );
    assert!(super::check_nesting(&fine).is_ok());
    assert_eq!(super::check_nesting("a = [[1]]\nb = ((2))"), Ok(()));
}

#[test]
fn stl_monitors_judge_tests_and_settle_early() {
    let program = include_str!("../../pedestrian_crossing.star").replace(
        "CollisionMonitor(v)",
        "CollisionMonitor(v)\nStl(\"G[0,15] (ego_separation_m > 0.5)\", name = \"keep_clear\")",
    );
    let s = load_source("stl.star", &program, "stl").unwrap();
    let run = |speed: f64, trigger: f64| {
        let a = s
            .space
            .decode(&paracosm_generators::Point {
                discrete: vec![],
                continuous: vec![(speed - 0.5) / 9.5, (trigger - 5.0) / 55.0],
            })
            .unwrap();
        s.run(&a, 1).unwrap()
    };
    let hit = run(3.0, 10.0);
    let (name, stl) = &hit.monitors[1];
    assert_eq!(name, "keep_clear");
    assert!(!stl.passed && stl.robustness <= 0.0, "{stl:?}");
    let simulated = hit
        .metrics
        .iter()
        .find(|(n, _)| *n == "simulated_s")
        .unwrap()
        .1;
    assert!(simulated < 15.0, "the run stops early: {simulated}");
    let safe = run(1.0, 55.0);
    assert!(safe.monitors[1].1.passed && safe.monitors[1].1.robustness > 0.5);

    let bad = |f: &str| {
        let p = program.replace("G[0,15] (ego_separation_m > 0.5)", f);
        load_source("stl.star", &p, "stl").unwrap_err().to_string()
    };
    let e = bad("G[0,15] (ego_separation_m > )");
    assert!(
        e.contains("expected number") && e.contains('^') && e.contains("stl.star:"),
        "{e}"
    );
    let e = bad("G[0,15] (dist_ped > 0.5)");
    assert!(
        e.contains("unknown signal `dist_ped`") && e.contains("ego_separation_m"),
        "{e}"
    );
}
