//! Loading programs: the vocabulary, and an error a user can act on for every mistake.

use super::load_source;
use crate::ScenarioError;

const HEADER: &str = "w = World(light = 1.0, fog = 0.0)\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\n";

fn err(src: &str) -> String {
    match load_source("bad.star", src, "bad") {
        Err(ScenarioError::Language(m)) => m,
        Err(ScenarioError::Load(e)) => {
            // The typed site is the one the message points at.
            if let Some(at) = &e.at {
                assert!(e.message.contains(&at.to_string()), "{e:?}");
            }
            e.message
        }
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

/// A refusal is typed by the phase of the load that refused it, and located where its
/// diagnostic points.
#[test]
fn a_refusal_says_which_phase_of_the_load_refused_it() {
    use crate::lang::LoadErrorKind as K;
    let place = "w.place(r, v)\n";
    let cases = [
        (
            format!("{HEADER}c = Car(loc = r.onLane(1, 50))\nc.brake(6)\nw.place(r, v, c)\n"),
            K::Syntax,
        ),
        (format!("{HEADER}x = VarInterval(0, 1, name = 1.5)\n{place}"), K::Evaluation),
        (HEADER.to_owned(), K::Declarations),
        (
            format!(
                "{HEADER}a = VarInterval(0, 1, name = \"x\")\nb = VarInterval(0, 1, name = \"x\")\n{place}"
            ),
            K::Parameters,
        ),
        (
            format!(
                "{HEADER}k = VarEnum([\"a\", \"b\"])\nif k == \"b\":\n    y = VarInterval(0, 1)\n{place}"
            ),
            K::Worlds,
        ),
        (
            format!("{HEADER}a = VarInterval(0, 1)\ntest(map = [\"nope\"])\n{place}"),
            K::Settings,
        ),
    ];
    for (src, kind) in cases {
        match load_source("bad.star", &src, "bad") {
            Err(ScenarioError::Load(e)) => {
                assert_eq!(e.kind, kind, "{src}\n{}", e.message);
                match &e.at {
                    Some(at) => {
                        assert_eq!(at.file, "bad.star", "{}", e.message);
                        assert!(at.line >= 1 && at.col >= 1, "{at}");
                    }
                    // A refusal of the whole program points at its file.
                    None => assert!(e.message.contains(" --> bad.star"), "{}", e.message),
                }
            }
            Err(e) => panic!("not a load error: {e}\n{src}"),
            Ok(_) => panic!("loaded:\n{src}"),
        }
    }
}

/// Every builtin's keywords come from its spec, so "did you mean" works for each, also for
/// the builtins a hand-kept list once missed (`Monitor`, `Assert`, `Signal`'s neighbours).
#[test]
fn an_unknown_keyword_of_any_builtin_gets_a_suggestion() {
    for (call, wrong, right) in [
        ("Monitor(tick, nme = \"m\")", "nme", "name"),
        ("Assert(tick, nam = \"a\")", "nam", "name"),
        ("VarInterval(0, 1, unti = \"m\")", "unti", "unit"),
        ("Car(loc = r.onLane(1, 5), sped = 3.0)", "sped", "speed"),
        ("test(horizn = 3.0)", "horizn", "horizon"),
    ] {
        let m = err(&format!("{HEADER}x = {call}\n"));
        assert!(
            m.contains(&format!("Found `{wrong}` extra named parameter"))
                && m.contains(&format!("did you mean `{right}`?")),
            "{call}: {m}"
        );
    }
}

#[test]
fn a_wrong_argument_type_names_the_parameter() {
    assert_diag(
        "r = RoadSegment(len = \"long\")\n",
        "RoadSegment(len=) must be a number, got a string",
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
fn an_infinite_bound_is_named_as_such() {
    for (src, shown) in [
        (
            "speed = VarInterval(0, float(\"inf\"))\n",
            "VarInterval(0, inf)",
        ),
        (
            "speed = VarInterval(-float(\"inf\"), 3.0)\n",
            "VarInterval(-inf, 3)",
        ),
    ] {
        assert_diag(
            src,
            &format!("{shown}: both bounds must be finite numbers"),
            "1:9",
        );
    }
}

#[test]
fn an_invalid_connection_is_refused() {
    let src = "a = RoadSegment(len = 50.0, nlanes = 2)\nb = RoadSegment(len = 50.0, nlanes = 6)\na.connect((a.TWO, b, b.ONE))\n";
    assert_diag(
        src,
        "lane-count mismatch: RoadSegment a.TWO has 2 lanes but RoadSegment b.ONE has 6",
        "3:1",
    );
}

#[test]
fn objects_starting_in_collision_are_both_named() {
    let src = format!("{HEADER}c = Car(loc = r.onLane(1, 12))\nw.place(r, v, c)\n");
    assert_diag(
        &src,
        "AutonomousVehicle v (bad.star:3:5) and Car c (bad.star:4:5) start in collision",
        "5:1",
    );
}

#[test]
fn a_vehicle_off_the_road_is_refused() {
    let src = format!("{HEADER}c = Car(loc = r.onLane(r.SideWalk, 50))\nw.place(r, v, c)\n");
    assert_diag(&src, "Car c (bad.star:4:5) is off the road", "5:1");
}

/// Overlapping road pieces are named with where each was declared (LANGUAGE.md, `place`).
#[test]
fn overlapping_pieces_are_named_with_their_lines() {
    let src = format!(
        "{HEADER}r2 = RoadSegment(len = 50.0)
w.place(r, v)
"
    );
    assert_diag(
        &src,
        "road pieces overlap: RoadSegment r (bad.star:2:5) and RoadSegment r2 (bad.star:4:6)",
        "5:1",
    );
}

#[test]
fn an_infinite_loop_is_stopped() {
    let m = err("def f():\n    for i in range(1000000000):\n        pass\nf()\n");
    assert!(m.contains("tick") || m.contains("limit"), "{m}");
    // The statement it was running is named, at the top level as in a `def` (it named the
    // file only).
    assert!(m.contains("bad.star:2:5"), "{m}");
    assert!(m.contains("2 |     for i in range(1000000000):"), "{m}");
    let m = err("x = 0\nfor i in range(20000000):\n    x += 1\n");
    assert!(m.contains("limit") && m.contains("bad.star:3:5"), "{m}");
    assert!(m.contains("3 |     x += 1\n  |     ^"), "{m}");
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
    let names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["fog.c0", "fog.c1", "fog.c2", "levels"]);
    // Items of a tuple or list argument are named by their index.
    let src = format!(
        "{HEADER}o = Obstacle(loc = r.onLane(-1, 80), size = (VarInterval(0.5, 2), 1.0, VarInterval(1, 2)))\nc = Car(loc = r.onLane(1, 40), route = [VarEnum([\"left\", \"right\"])])\nw.place(r, v, o, c)\nCollisionMonitor(v)\n"
    );
    let s = load_source("ok.star", &src, "ok").unwrap();
    let names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["o.size[0]", "o.size[2]", "c.route[0]"]);
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
            .space()
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

    // A predicate may compare signals: the pedestrian's distance ahead of the ego along x,
    // against the ego's own speed. Its robustness is the difference of the two sides.
    let both = program.replace(
        "G[0,15] (ego_separation_m > 0.5)",
        "G[0,15] (p.pos.x - ego_x_m + 1 > 0.5 * ego_speed_mps)",
    )
        + "Stl(\"G[0,15] (p.pos.x - ego_x_m > 0.5 * ego_speed_mps - 1)\", name = \"ahead\")\n";
    let s2 = load_source("stl.star", &both, "stl").unwrap();
    let a = s2
        .space()
        .decode(&paracosm_generators::Point {
            discrete: vec![],
            continuous: vec![(1.0 - 0.5) / 9.5, (55.0 - 5.0) / 55.0],
        })
        .unwrap();
    let o = s2.run(&a, 1).unwrap();
    let rho = |name: &str| {
        o.monitors
            .iter()
            .find(|(n, _)| n == name)
            .unwrap()
            .1
            .robustness
    };
    // The same inequality written two ways; a finite margin that a pass and a failure would
    // both show.
    assert!(rho("keep_clear").is_finite() && rho("keep_clear") != 0.0);
    assert!((rho("keep_clear") - rho("ahead")).abs() < 1e-9, "{o:?}");

    let bad = |f: &str| {
        let p = program.replace("G[0,15] (ego_separation_m > 0.5)", f);
        load_source("stl.star", &p, "stl").unwrap_err().to_string()
    };
    let e = bad("G[0,15] (ego_separation_m > )");
    assert!(
        e.contains("expected a signal or a number") && e.contains('^') && e.contains("stl.star:"),
        "{e}"
    );
    let e = bad("G[0,15] (dist_ped > 0.5)");
    assert!(
        e.contains("reads the signal `dist_ped`, which nothing publishes")
            && e.contains("ego_separation_m")
            && e.contains("stl.star:"),
        "{e}"
    );
}

/// A world with a road `r`, the ego `v` and a car `c` built from `car` (the keyword arguments
/// after `loc`), `extra` lines before `place`.
fn with_car(car: &str, extra: &str) -> String {
    format!("{HEADER}c = Car(loc = r.onLane(1, 60){car})\n{extra}w.place(r, v, c)\nCollisionMonitor(v)\n")
}

/// Issue 14, requirement 4: every input declares its type, unit and range; what is known when
/// the program loads is checked then, in forms beyond the shipped programs.
#[test]
fn inputs_of_the_wrong_kind_or_out_of_range_are_refused_at_load() {
    let world = |args: &str| {
        format!("w = World({args})\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\n")
    };
    let road = |args: &str| {
        format!("w = World()\nr = RoadSegment(len = 200.0, {args})\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\n")
    };
    let walker = |args: &str| {
        format!("{HEADER}p = Pedestrian(start = r.onLane(r.SideWalk, 100), target = r.onLane(-r.SideWalk, 100), {args})\nw.place(r, v, p)\n")
    };
    let cases: Vec<(String, &str, &str)> = vec![
        (world("light = 1.5"), "World(light=) takes a number in [0, 1], got 1.5 (a number)", "1:5"),
        (world("").replace("len = 200.0", "len = 1e39"), "RoadSegment length 1e39 m is outside (0, 100000]", "2:5"),
        (format!("{HEADER}a = Arc(radius = 2e5, angle = 0.5)\nw.place(r, a, v)\n"), "Arc radius 200000 m is over 100000 m", "4:5"),
        (format!("{HEADER}o = Roundabout(radius = 1500.0)\nw.place(r, o, v)\n"), "Roundabout radius 1500 m is over 1000 m", "4:5"),
        (world("fog = Const(-0.1)"), "World(fog=) takes a number in [0, 1], got -0.1", "1:5"),
        (world("fog = True"), "World(fog=) takes a number in [0, 1], got True (a bool)", "1:5"),
        (world("fog = VarEnum([0.2, 1.5])"), "World(fog=) takes a number in [0, 1], got 1.5 (a number)", "1:5"),
        (world("fog = VarEnum([0.2, 1.5])"), "(the world fails for the test values w.fog = 1.5)", "1:5"),
        (
            world("fog = VarInterval(0.2, 0.5, over_time = Piecewise(3)), light = VarInterval(-1, 1)"),
            "World(light=) takes a number in [0, 1], got -1 (a number)",
            "1:5",
        ),
        (road("friction = 0"), "RoadSegment(friction=) takes a number in (0, 2], got 0", "2:5"),
        (
            road("friction = VarInterval(0, 0.5)"),
            "RoadSegment(friction=) takes a number in (0, 2], got 0 (a number)",
            "2:5",
        ),
        (road("friction = VarEnum([0.3, 2.5])"), "got 2.5 (a number)\n", "2:5"),
        (road("friction = VarEnum([0.3, 2.5])"), "for the test values r.friction = 2.5", "2:5"),
        (with_car(", color = \"purple\"", ""), "Car(color=) takes a colour name (red, white", "4:5"),
        (with_car(", color = VarEnum([\"red\", \"plaid\"])", ""), "Car(color=) takes a colour name (red, white, black, blue, green, yellow, orange, silver, grey), got \"plaid\" (a string)", "4:5"),
        (with_car(", enabled = 1", ""), "Car(enabled=) takes a bool, got 1 (a number)", "4:5"),
        (with_car(", enabled = VarEnum([1, 0])", ""), "Car(enabled=) takes a bool, got 1 (a number)", "4:5"),
        (with_car(", speed = -3", ""), "Car(speed=) takes a number in m/s, >= 0, got -3", "4:5"),
        (with_car(", speed = v.pos", ""), "Car(speed=) takes a number in m/s, >= 0, but this stream carries positions", "4:5"),
        (with_car(", speed = tick.zip(tick)", ""), "but this stream carries tuples", "4:5"),
        (walker("speed = \"slow\", trigger = tick"), "Pedestrian(speed=) takes a number in m/s, >= 0, got \"slow\"", "4:5"),
        (walker("speed = 1.0, dist = VarInterval(-5, 5), car = v"), "Pedestrian(dist=) takes a number in m, >= 0, got -5 (a number)", "4:5"),
        (format!("{HEADER}o = Obstacle(loc = r.onLane(-1, 80), size = (50.0, 0.5, 1e30))\n"), "Obstacle(size=) needs three lengths in m, each > 0 and <= 1000, got (50, 0.5, 1000000000000000000000000000000)", "4:5"),
        (walker("speed = 1.0, dist = 10.0, car = 3.0"), "Pedestrian(car=) takes a position (x, y, z) in m that moves", "4:5"),
        (walker("speed = 1.0, dist = 10.0, car = (30.0, 0.0, 1.75)"), "got (30.0, 0.0, 1.75) (a tuple); a fixed point cannot come near", "4:5"),
        (walker("speed = 1.0, dist = 10.0, car = r.onLane(1, 30.0)"), "(a Location); a fixed point cannot come near", "4:5"),
        (walker("speed = 1.0, dist = 10.0, car = v.speed"), "but this stream carries numbers", "4:5"),
        (
            world("") + "test(horizon = 5.0)\ntest(horizon = 8.0)\n",
            "test(...) is called once per program; it was already called at bad.star:5:1",
            "6:1",
        ),
        (
            with_car("", "") + "OffRoadMonitor(c)\n",
            "OffRoadMonitor watches the AutonomousVehicle; got a Car (to judge another actor",
            "7:1",
        ),
        (
            format!("{HEADER}c = Car(loc = r.onLane(1, 60))\nw.place(r, v)\n"),
            "Car c is not in this place(...): place(...) is called once, and lists every actor",
            "5:1",
        ),
        (
            format!("{HEADER}a = Arc(nlanes = 2, numLane = 4)\n"),
            "Arc takes nlanes= or numLane= (the paper's spelling of it), not both",
            "4:5",
        ),
        (
            format!("{HEADER}w.place(r, v)\nc = Car(loc = r.onLane(1, 60))\n"),
            "Car c is declared after place(...), so it is never placed",
            "5:5",
        ),
    ];
    for (src, message, at) in cases {
        let m = err(&src);
        assert!(m.contains(message), "{message:?} not in:\n{m}\nfor:\n{src}");
        assert!(m.contains(&format!("bad.star:{at}")), "{at} not in:\n{m}");
    }
}

#[test]
fn inputs_of_the_right_kind_load_whatever_their_form() {
    for (car, extra) in [
        (", speed = v.speed", ""),
        (", speed = tick.map(lambda t: 2.0)", ""),
        (", speed = VarEnum([2, 4.5])", ""),
        (", color = VarEnum([\"red\", \"White\"])", ""),
        (", enabled = VarEnum([True, False])", ""),
        (", speed = w.fog.map(lambda f: 10 * (1 - f))", ""),
    ] {
        let src = with_car(car, extra);
        if let Err(e) = load_source("ok.star", &src, "ok") {
            panic!("{car}: {e}");
        }
    }
    // `numLane=`, the paper's spelling, on every piece, open or not.
    let src = "w = World()\nn = VarEnum([2, 4])\nr = RoadSegment(len = 100.0, numLane = n)\na = Arc(radius = 40.0, numLane = n)\nk = Clothoid(numLane = n)\nx = CrossIntersection(numLane = n)\nro = Roundabout(numLane = n)\nr.connect((r.TWO, a, a.ONE), (a.TWO, k, k.ONE), (k.TWO, x, x.ONE), (x.THREE, ro, ro.ONE))\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, a, k, x, ro, v)\nCollisionMonitor(v)\n";
    let s = load_source("ok.star", src, "ok").unwrap();
    assert_eq!(s.space().params()[0].name, "n");
    let src = format!("{HEADER}r2 = RoadSegment(len = 50.0, friction = VarEnum([0.3, 0.9]))\nnet = r.connect((r.TWO, r2, r2.ONE))\np = Pedestrian(start = r.onLane(r.SideWalk, 100), target = r.onLane(-r.SideWalk, 100), speed = 1.0, dist = 10.0, car = v.pos.map(lambda p: p))\nw.place(r, r2, v, p)\nCollisionMonitor(v)\n");
    load_source("ok.star", &src, "ok").unwrap();
}

/// Runs the one test of a program without open parameters.
fn run_once(src: &str) -> Result<crate::TestOutcome, crate::ScenarioError> {
    let s = load_source("run.star", src, "run").unwrap();
    let a = s
        .space()
        .decode(&paracosm_generators::Point {
            discrete: vec![],
            continuous: vec![],
        })
        .unwrap();
    s.run(&a, 0)
}

/// Issue 14, requirement 4: a computed stream that leaves its input's type or range ends the
/// test with an error naming the stream, the time and the value.
#[test]
fn computed_values_are_checked_as_the_test_runs() {
    let fog = "w = World(fog = tick.map(lambda t: t / 2))\nr = RoadSegment(len = 200.0)\nv = AutonomousVehicle(loc = r.onLane(1, 10))\nw.place(r, v)\nCollisionMonitor(v)\n";
    let e = run_once(fog).unwrap_err().to_string();
    // The first step past 2 s: t = 121/60 s, fog 1.0083.
    assert!(
        e.starts_with("at t = 2.017 s, the fog of World w (run.star:1:5) was 1.0083333333333333 (a number); it must be a number in [0, 1]"),
        "{e}"
    );
    let e = run_once(&with_car(
        ", speed = tick.map(lambda t: -1.0 if t > 1 else 3.0)",
        "",
    ))
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("the speed of Car c (run.star:4:5)") && e.contains("was -1 (a number)"),
        "{e}"
    );
    // A value of the wrong kind is found at load, where every stream is sampled once.
    for (speed, value) in [
        ("tick.map(lambda t: t > 1)", "was False (a bool)"),
        ("tick.map(lambda t: (t, t))", "(a tuple)"),
    ] {
        let src = with_car(&format!(", speed = {speed}"), "");
        let Err(e) = load_source("run.star", &src, "run") else {
            panic!("{speed}: a speed of the wrong kind loads");
        };
        let e = e.to_string();
        assert!(
            e.contains("the speed of Car c (run.star:4:5)") && e.contains(value),
            "{speed}: {e}"
        );
    }
    // Within range all along: no error.
    run_once(&with_car(
        ", speed = tick.map(lambda t: max(0.0, 5 - t))",
        "",
    ))
    .unwrap();
}

#[test]
fn a_parameter_in_another_unit_than_its_input_is_a_warning() {
    let src = with_car(", speed = kmh", "").replace(
        "w = World",
        "kmh = VarInterval(10, 50, unit = \"km/h\")\nw = World",
    );
    let s = load_source("unit.star", &src, "unit").unwrap();
    let w: Vec<String> = s.warnings().iter().map(|w| w.to_string()).collect();
    assert!(
        w.iter().any(
            |w| w.contains("declared in km/h but feeds Car(speed=), which is in m/s")
                && w.contains("unit.star:1:7")
        ),
        "{w:?}"
    );
    // Written inline in the call, as a new user writes it; and a unit on an input that has
    // none (fog is a plain number in [0, 1]).
    let inline = with_car(", speed = VarInterval(10, 50, unit = \"km/h\")", "").replace(
        "w = World(light = 1.0, fog = 0.0)",
        "w = World(light = 1.0, fog = VarInterval(0, 0.5, unit = \"%\"))",
    );
    assert!(inline.contains("fog = VarInterval"), "{inline}");
    let s = load_source("inline.star", &inline, "inline").unwrap();
    let w: Vec<String> = s.warnings().iter().map(|w| w.to_string()).collect();
    assert!(
        w.iter()
            .any(|w| w
                .contains("`c.speed` is declared in km/h but feeds Car(speed=), which is in m/s")),
        "{w:?}"
    );
    assert!(
        w.iter().any(|w| w.contains(
            "`w.fog` is declared in % but feeds World(fog=), which is a plain number (no unit)"
        )),
        "{w:?}"
    );
    // The input's own unit, or "1" on a plain number, is no warning.
    let fine = with_car(", speed = VarInterval(1, 5, unit = \"m/s\")", "").replace(
        "w = World(light = 1.0, fog = 0.0)",
        "w = World(fog = VarInterval(0, 0.5, unit = \"1\"))",
    );
    let s = load_source("fine.star", &fine, "fine").unwrap();
    assert!(
        !s.warnings()
            .iter()
            .any(|w| w.to_string().contains("is declared in")),
        "{:?}",
        s.warnings()
    );
    // Spellings of m/s² a user types (the shipped follow-lead-car writes `m/s^2`), and a
    // wrong one that still warns.
    for (unit, warns) in [
        ("m/s^2", false),
        ("m / s**2", false),
        ("m/s²", false),
        ("m/s", true),
    ] {
        let src = with_car(
            "",
            &format!(
                "decel = VarInterval(2.0, 8.0, unit = \"{unit}\")\n\
                 tick.filter(lambda t: t > 3.0).foreach(c.brake(decel))\n"
            ),
        );
        let s = load_source("decel.star", &src, "decel").unwrap();
        let warned = s
            .warnings()
            .iter()
            .any(|w| w.to_string().contains("is declared in"));
        assert_eq!(warned, warns, "{unit}: {:?}", s.warnings());
    }
    // Added to other numbers, a parameter keeps its unit: `r.onLane(1, 10.0 + gap)` with a
    // gap in s, and a speed in km/h less a constant, warn; a product may convert a unit
    // (`kmh / 3.6`) and does not.
    for (extra, car, warns) in [
        (
            "gap = VarInterval(20.0, 40.0, unit = \"s\")\n",
            "",
            "`gap` is declared in s but feeds onLane(at=), which is in m",
        ),
        ("gap = VarInterval(20.0, 40.0, unit = \"m\")\n", "", ""),
        (
            "kmh = VarInterval(30.0, 50.0, unit = \"km/h\")\n",
            ", speed = -(2.0 - kmh)",
            "`kmh` is declared in km/h but feeds Car(speed=), which is in m/s",
        ),
        (
            "kmh = VarInterval(30.0, 50.0, unit = \"km/h\")\n",
            ", speed = kmh / 3.6",
            "",
        ),
    ] {
        let src = format!(
            "{extra}{}",
            with_car(car, "").replace("r.onLane(1, 60)", "r.onLane(1, 10.0 + gap)")
        );
        let src = if extra.starts_with("kmh") {
            src.replace("10.0 + gap", "60")
        } else {
            src
        };
        let s = load_source("sum.star", &src, "sum").unwrap();
        let w: Vec<String> = s
            .warnings()
            .iter()
            .map(|w| w.to_string())
            .filter(|w| w.contains("is declared in"))
            .collect();
        if warns.is_empty() {
            assert!(w.is_empty(), "{src}: {w:?}");
        } else {
            assert!(w.len() == 1 && w[0].contains(warns), "{src}: {w:?}");
        }
    }
}

#[test]
fn a_stream_nothing_reads_is_named_in_a_warning() {
    let unread = |s: &crate::Scenario| -> Vec<String> {
        s.warnings()
            .iter()
            .map(|w| w.to_string())
            .filter(|w| w.contains("nothing uses this stream's values"))
            .collect()
    };
    // `k` feeds a stream that no object, monitor or action reads: it was counted in coverage
    // with no word, though it changes nothing.
    let src = with_car(
        "",
        "k = VarInterval(0.0, 1.0)\ns = tick.map(lambda t: t * k).filter(lambda x: x > 0.5)\n",
    );
    let s = load_source("unread.star", &src, "unread").unwrap();
    let w = unread(&s);
    assert_eq!(w.len(), 1, "{:?}", s.warnings());
    // The last stream of the chain (the filter), not each one.
    assert!(w[0].contains("unread.star:6:"), "{w:?}");
    // Read by a car, a Signal, a foreach or a monitor: no warning.
    for (car, used) in [
        (", speed = tick.map(lambda t: 5.0 + t)", ""),
        ("", "Signal(\"late\", tick.map(lambda t: t - 1.0))\n"),
        ("", "tick.filter(lambda t: t > 3.0).foreach(c.brake(2.0))\n"),
        ("", "Monitor(c.speed.map(lambda v: 30.0 - v))\n"),
    ] {
        let src = with_car(car, used);
        let s = load_source("used.star", &src, "used").unwrap();
        assert!(unread(&s).is_empty(), "{used}: {:?}", s.warnings());
    }
    // Read by its name in a lambda (LANGUAGE.md, "Streams"), which makes no edge in the
    // graph: `limit` was named, and `k`, which changes the car's speed, called inert.
    let src = with_car(", speed = tick.map(lambda t: max(0.0, limit))", "").replace(
        "c = Car",
        "k = VarInterval(5.0, 15.0)\nlimit = tick.map(lambda t: k - t)\nc = Car",
    );
    let s = load_source("named.star", &src, "named").unwrap();
    assert!(unread(&s).is_empty(), "{:?}", s.warnings());
    // Read in some worlds of the family only: not unread. The first world (`mode = "b"`)
    // leaves the stream unread; it is held in a list, so no variable names it.
    let src = with_car(", speed = fast[0] if mode == \"a\" else 5.0", "").replace(
        "c = Car",
        "mode = VarEnum([\"b\", \"a\"])\nfast = [tick.map(lambda t: 5.0 + t)]\nc = Car",
    );
    let s = load_source("some.star", &src, "some").unwrap();
    assert!(unread(&s).is_empty(), "{:?}", s.warnings());
}

#[test]
fn monitors_have_unique_names_and_the_default_offroad_monitor_yields_to_a_declared_one() {
    let m = err(&format!(
        "{HEADER}w.place(r, v)\nCollisionMonitor(v)\nCollisionMonitor(v)\n"
    ));
    assert!(m.contains("two monitors are named `collision`"), "{m}");
    assert!(m.contains("bad.star:6:1"), "{m}");
    let m = err(&format!(
        "{HEADER}w.place(r, v)\nStl(\"ego_speed_mps > 1\", name = \"offroad\")\n"
    ));
    assert!(m.contains("the name of the default OffRoadMonitor"), "{m}");
    for bad in ["", "a b", "tab\\t", "a,b"] {
        for monitor in [
            format!("Stl(\"G[0,10] (ego_speed_mps > 3)\", name = \"{bad}\")"),
            format!("CollisionMonitor(v, name = \"{bad}\")"),
            format!("Monitor(v.speed, name = \"{bad}\")"),
        ] {
            let m = err(&format!("{HEADER}w.place(r, v)\n{monitor}\n"));
            assert!(
                m.contains("is made of letters, digits and _ . [ ] only"),
                "{monitor}: {m}"
            );
            assert!(m.contains("bad.star:5:1"), "{monitor}: {m}");
        }
    }

    let names = |src: &str| -> Vec<String> {
        let s = load_source("m.star", src, "m").unwrap();
        s.monitors().iter().map(|m| m.name().to_owned()).collect()
    };
    let base = format!("{HEADER}w.place(r, v)\nCollisionMonitor(v)\n");
    assert_eq!(names(&base), ["collision", "offroad"]);
    assert_eq!(
        names(&format!(
            "{base}TimeToFailure(OffRoadMonitor(v, name = \"lane\"), minT = 5)\n"
        )),
        ["collision", "time_to_failure"]
    );
    assert_eq!(
        names(&format!("{base}test(offroad = False)\n")),
        ["collision"]
    );
    let s = load_source("m.star", &base, "m").unwrap();
    assert_eq!(s.passive_monitors(), ["offroad"]);
}

#[test]
fn the_map_names_one_or_two_parameters_of_any_kind() {
    let base = format!(
        "c = VarEnum([\"red\", \"white\"], name = \"c\")\nf = VarInterval(0.0, 1.0)\n{}",
        with_car(", color = c", "").replace(
            "w = World(light = 1.0, fog = 0.0)",
            "w = World(light = 1.0, fog = f)"
        )
    );
    let axes = |map: &str| -> Result<Vec<String>, String> {
        load_source("map.star", &format!("{base}test(map = {map})\n"), "map")
            .map(|s| s.map_axes().to_vec())
            .map_err(|e| e.to_string())
    };
    assert_eq!(axes("\"c\"").unwrap(), ["c"]);
    assert_eq!(axes("(\"c\", \"f\")").unwrap(), ["c", "f"]);
    assert_eq!(axes("[\"f\", \"c\"]").unwrap(), ["f", "c"]);
    let e = axes("\"nope\"").unwrap_err();
    assert!(
        e.contains("names `nope`, which is not a parameter (the parameters: c, f)"),
        "{e}"
    );
    let e = axes("(\"c\", \"f\", \"c\")").unwrap_err();
    assert!(e.contains("one or two parameter names"), "{e}");
    let e = axes("(\"c\", \"c\")").unwrap_err();
    assert!(e.contains("names `c` twice"), "{e}");
    // Without test(map=), the first two parameters, whatever their kind.
    let s = load_source("map.star", &base, "map").unwrap();
    assert_eq!(s.map_axes(), ["c", "f"]);
}

#[test]
fn a_test_without_monitors_runs_to_its_horizon() {
    let src = format!("{HEADER}w.place(r, v)\ntest(horizon = 3.0, offroad = False)\n");
    let s = load_source("none.star", &src, "none").unwrap();
    assert!(s.monitors().is_empty());
    assert!(s
        .warnings()
        .iter()
        .any(|w| w.message.contains("every test passes")));
    let o = run_once(&src).unwrap();
    let simulated = o
        .metrics
        .iter()
        .find(|(n, _)| *n == "simulated_s")
        .unwrap()
        .1;
    assert!((simulated - 3.0).abs() < 1e-9, "{simulated}");
}

/// Levels equal under `==` are one level: `VarEnum([1, 1.0])` would count one value twice in
/// k-wise coverage. A bool is not a number, so `[1, True]` is two levels, as Starlark says.
#[test]
fn a_varenum_refuses_levels_that_are_equal() {
    for levels in [
        "[1, 1.0]",
        "[0.0, -0.0]",
        "[0, -0.0]",
        "[\"a\", \"b\", \"a\"]",
        "[2, 3, 2]",
    ] {
        let m = err(&format!("{HEADER}w.place(r, v)\nx = VarEnum({levels})\n"));
        assert!(m.contains("twice"), "{levels}: {m}");
        assert!(m.contains("bad.star:5:5"), "{levels}: {m}");
    }
    for levels in ["[1, True]", "[1, 2.5]", "[\"1\", 1]"] {
        load_source(
            "ok.star",
            &format!("{HEADER}w.place(r, v)\nx = VarEnum({levels})\n"),
            "ok",
        )
        .unwrap_or_else(|e| panic!("{levels}: {e}"));
    }
}

/// Errors that paracosm words itself (not starlark) show the source line and a caret under
/// their `file:line:col` too.
#[test]
fn every_located_error_shows_its_source_line_and_a_caret() {
    let m = err(&format!(
        "{HEADER}w.place(r, v)\nCollisionMonitor(v)\nk = VarEnum([1, 2])\nif k == 2:\n    extra = VarInterval(0.0, 1.0)\n"
    ));
    assert!(m.contains("depend on their values"), "{m}");
    assert!(
        m.contains("bad.star:8:13\n  |\n8 |     extra = VarInterval(0.0, 1.0)\n  |             ^"),
        "{m}"
    );
    // starlark's own diagnostics keep their one snippet.
    let m = err(&format!("{HEADER}x = VarInterval(5, 1)\n"));
    assert_eq!(m.matches("x = VarInterval(5, 1)").count(), 2, "{m}");
}

/// A program without an ego vehicle, and two parameters of one explicit name, are located.
#[test]
fn whole_program_errors_point_at_a_line() {
    let m = err("w = World()\nr = RoadSegment(len = 100.0)\nc = Car(loc = r.onLane(1, 10))\nw.place(r, c)\n");
    assert!(
        m.contains("places no AutonomousVehicle") && m.contains("bad.star:4:1\n"),
        "{m}"
    );
    let m = err(&format!(
        "{HEADER}a = VarInterval(0, 1, name = \"x\")\nb = VarInterval(0, 1, name = \"x\")\nw.place(r, v)\n"
    ));
    assert!(
        m.contains("two open parameters are named `x`") && m.contains("--> bad.star:5:5\n"),
        "{m}"
    );
    // An explicit name another parameter takes from its variable, in either order.
    for (first, second, at) in [
        (
            "a = VarInterval(1, 2)",
            "b = VarInterval(5, 6, name = \"a\")",
            "bad.star:5:5",
        ),
        (
            "b = VarInterval(5, 6, name = \"a\")",
            "a = VarInterval(1, 2)",
            "bad.star:4:5",
        ),
    ] {
        let m = err(&format!("{HEADER}{first}\n{second}\nw.place(r, v)\n"));
        assert!(
            m.contains("name = \"a\"") && m.contains("takes from where it stands"),
            "{m}"
        );
        assert!(m.contains(&format!("--> {at}\n")), "{m}");
    }
    // An explicit name equal to a coordinate of a parameter varying over time, or to a suffix.
    for (decl, coordinate) in [
        (
            "f = VarInterval(0.1, 0.9, over_time = Piecewise(2))\ng = VarInterval(0.1, 0.9, name = \"f[0]\")",
            "f[0]",
        ),
        (
            "f = VarInterval(0.1, 0.9, over_time = Polynomial(1))\ng = VarInterval(0.1, 0.9, name = \"f.c1\")",
            "f.c1",
        ),
        (
            "for i in range(2):\n    x = VarInterval(0, 1)\ng = VarInterval(0.1, 0.9, name = \"x_1\")",
            "x_1",
        ),
    ] {
        let m = err(&format!("{HEADER}{decl}\nw.place(r, v)\n"));
        assert!(
            m.contains(&format!("give a coordinate the name `{coordinate}`")),
            "{m}"
        );
        assert!(m.contains(" --> bad.star:"), "{m}");
    }
}

/// Messages that name a value's type read as English (`an int`, `None`), a `ChangeLane` given
/// both starts says so, and the paper's `VarEnum({2, 4, 6})` gets a note that `{...}` is a
/// dict in Starlark.
#[test]
fn type_names_take_their_article_and_common_slips_get_a_hint() {
    let m = err(&format!("{HEADER}w.place(r, v)\nTimeToFailure(5)\n"));
    assert!(
        m.contains("TimeToFailure wraps a monitor, got an int"),
        "{m}"
    );
    let m = err(&format!("{HEADER}w.place(r, v)\nTimeToFailure(None)\n"));
    assert!(m.contains("got None"), "{m}");
    let m = err(&format!(
        "{HEADER}c = Car(loc = r.onLane(1, 40), lane_change = ChangeLane(to = -1, at = 1.0, when = tick))\nw.place(r, v, c)\n"
    ));
    assert!(m.contains("not both") && m.contains("bad.star:4:"), "{m}");
    let m = err(&format!(
        "{HEADER}n = VarEnum({{2, 4, 6}})\nw.place(r, v)\n"
    ));
    assert!(
        m.contains("bad.star:4:")
            && m.contains("write the paper's `VarEnum({2, 4, 6})` as `VarEnum([2, 4, 6])`"),
        "{m}"
    );
    // Another syntax error gets no such note.
    let m = err(&format!("{HEADER}n = [2, 4\nw.place(r, v)\n"));
    assert!(!m.contains("VarEnum([2, 4, 6])"), "{m}");
}

/// A junction's `onLane` takes its lane fourth by position as by keyword.
#[test]
fn a_junctions_lane_may_come_fourth() {
    let src = "t = TIntersection(nlanes = 4)\ne = RoadSegment(len = 60.0, nlanes = 4)\ns = RoadSegment(len = 60.0, nlanes = 4)\nt.connect((t.ONE, e, e.ONE), (t.TWO, s, s.ONE))\nw = World()\nv = AutonomousVehicle(loc = s.onLane(-1, 40))\na = t.onLane(t.ONE, \"left\", 1.0, 2)\nb = t.onLane(t.ONE, \"left\", 1.0, lane = 2)\nc = t.onLane(t.ONE, \"left\", 1.0)\nif a.lane != 2 or a != b or a == c:\n    fail(\"lane by position\")\nw.place(t, e, s, v)\nCollisionMonitor(v)\n";
    load_source("ok.star", src, "ok").unwrap_or_else(|e| panic!("{e}"));
}

/// `connect`'s mistakes name the pieces and ports by their variables.
#[test]
fn connect_errors_name_pieces_by_their_variables() {
    let head =
        "a = RoadSegment(len = 50.0)\nb = RoadSegment(len = 50.0)\nc = RoadSegment(len = 50.0)\n";
    let m = err(&format!("{head}a.connect((a.TWO, b, c.ONE))\n"));
    assert!(
        m.contains("the child port RoadSegment c.ONE is not a port of the child RoadSegment b"),
        "{m}"
    );
    let m = err(&format!("{head}a.connect((b.TWO, c, c.ONE))\n"));
    assert!(
        m.contains("the port RoadSegment b.TWO belongs to neither RoadSegment a nor"),
        "{m}"
    );
    let m = err(&format!("{head}a.connect((a.TWO, 5, c.ONE))\n"));
    assert!(m.contains("a road piece second, got an int"), "{m}");
}

/// A parameter's explicit name is a key of results.jsonl and a CSV column: empty or with
/// spaces it is refused.
#[test]
fn a_parameter_name_with_spaces_or_none_is_refused() {
    for name in ["", "a b", " a", "a\tb"] {
        let m = err(&format!(
            "{HEADER}x = VarInterval(0, 1, name = {name:?})\nw.place(r, v)\n"
        ));
        assert!(
            m.contains("is no parameter name") && m.contains("bad.star:4:5"),
            "{m}"
        );
    }
    load_source(
        "ok.star",
        &format!("{HEADER}x = VarInterval(0, 1, name = \"lead.gap[0]\")\nw.place(r, v)\nCollisionMonitor(v)\n"),
        "ok",
    )
    .unwrap();
}

/// An action called on a line of its own does nothing, and says so at load; a changeLane
/// action into the other direction's lane warns as ChangeLane(to=) does.
#[test]
fn a_dropped_action_is_refused_and_a_changelane_across_warns() {
    let car =
        "c = Car(loc = r.onLane(-1, 150), speed = 5.0)\nw.place(r, v, c)\nCollisionMonitor(v)\n";
    for stmt in [
        "c.setSpeed(2.0)",
        "c.brake(3)",
        "if True:\n    c.changeLane(1)",
    ] {
        let m = err(&format!("{HEADER}{car}{stmt}\n"));
        assert!(
            m.contains("on a line of its own does nothing") && m.contains(" --> bad.star:"),
            "{m}"
        );
    }
    let s = load_source("ok.star", &format!("{HEADER}{car}tick.take(1).foreach(c.changeLane(1))\ndef f(t):\n    c.brake(3)\ntick.filter(lambda t: t > 1).foreach(f)\n"), "ok").unwrap();
    assert!(
        s.warnings().iter().any(|w| w.message.contains(
            "Car c.changeLane(1) moves it from lane -1 into a lane of the other direction"
        ) && w.at == "ok.star:7:1"),
        "{:?}",
        s.warnings()
    );
}

#[test]
fn a_parameter_of_a_car_disabled_in_every_test_changes_nothing() {
    // `enabled = False`: the car is in no test, so its open speed and colour build the same
    // test; they were counted in coverage without a word.
    let src = with_car(", speed = s, color = paint, enabled = False", "").replace(
        "c = Car",
        "s = VarInterval(1.0, 9.0)\npaint = VarEnum([\"red\", \"blue\"])\nc = Car",
    );
    let s = load_source("off.star", &src, "off").unwrap();
    assert_eq!(s.unused_params(), ["s", "paint"], "{:?}", s.warnings());
    // Enabled in some tests: both matter.
    let src = src.replace("enabled = False", "enabled = VarEnum([False, True])");
    let s = load_source("some.star", &src, "some").unwrap();
    assert!(s.unused_params().is_empty(), "{:?}", s.unused_params());
}

/// Hostile input, second round, requirement 4: the most parameters a program may declare
/// (none used, so every one is probed and looked at again from a shared budget of
/// evaluations, one combination each) load and are each named unused; one more is refused
/// with the limit and its place.
#[test]
fn the_most_parameters_a_program_may_declare_load_and_one_more_is_refused() {
    let program = |n: usize| {
        let mut s = format!("{HEADER}w.place(r, v)\nCollisionMonitor(v)\n");
        for i in 0..n {
            s.push_str(&format!("p{i} = VarInterval(0.0, 1.0)\n"));
        }
        s
    };
    let most = super::MAX_PARAMS;
    let s = load_source("most.star", &program(most), "most").unwrap();
    assert_eq!(s.space().params().len(), most);
    assert_eq!(s.unused_params().len(), most, "none of them is used");
    let m = err(&program(most + 1));
    assert!(
        m.contains(&format!(
            "declares {} open parameters; the limit is {most}",
            most + 1
        )) && m.contains(&format!("bad.star:{}:", most + 6)),
        "{m}"
    );
}
