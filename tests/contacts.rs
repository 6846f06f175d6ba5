//! NPC cars obey contacts: a car meets an `Obstacle`, another car or a pedestrian as the ego
//! does (it stops against it, never drives through it, and both record the collision:
//! `c.collided`, `CollisionMonitor(c)`); with `keep_distance=` it brakes to stop that far
//! short. A car's speed is over the ground, on a lane change too, and a pedestrian walked by
//! two behaviours, or a window past the horizon, is refused at load.

mod common;

use paracosm_engine::behaviour::{ActorRef, Output};
use paracosm_engine::rx::Value;
use paracosm_engine::sut::SutConfig;
use paracosm_engine::Simulation;
use paracosm_generators::Strategy;
use paracosm_scenarios::Scenario;

fn load(source: &str) -> Result<Scenario, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.star");
    std::fs::write(&path, source).unwrap();
    paracosm_scenarios::load(path.to_str().unwrap()).map_err(|e| e.to_string())
}

/// Steps the first test of `source` for `seconds` with `aeb` and returns what `f` reads from
/// the simulation after each step.
fn trace<T>(source: &str, seconds: f64, mut f: impl FnMut(&Simulation) -> T) -> Vec<T> {
    let scenario = load(source).unwrap();
    let point = Strategy::Halton
        .build(scenario.space(), 0)
        .unwrap()
        .ask(1)
        .unwrap()
        .remove(0);
    let assignment = scenario.space().decode(&point).unwrap();
    let mut out = Vec::new();
    scenario
        .with_world(&assignment, &mut |spec, host| {
            let mut sim = Simulation::new(spec).unwrap();
            let mut sut = SutConfig::builtin("aeb").unwrap().build();
            sut.reset(0).unwrap();
            for _ in 0..(seconds / spec.dt_s).round() as usize {
                sim.evaluate(host).unwrap();
                out.push(f(&sim));
                let control = sut.act(&sim.observation()).unwrap();
                sim.step(control, host).unwrap();
            }
        })
        .unwrap();
    out
}

fn x_of(sim: &Simulation, a: ActorRef) -> f64 {
    match sim.read(a, Output::Pos) {
        Value::Vec3(p) => p[0],
        v => panic!("{v:?}"),
    }
}

fn flag(sim: &Simulation, a: ActorRef, o: Output) -> bool {
    matches!(sim.read(a, o), Value::Bool(true))
}

const ROAD: &str = r#"
w = World(light = 0.5, fog = 0.0)
r = RoadSegment(len = 300.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(-1, 290), sut = "aeb", speed = 0.0)
"#;

#[test]
fn an_npc_car_stops_against_an_obstacle_and_both_record_it() {
    // The car's centre starts at 20 m, its front at 22.25 m; the box's back face is at
    // 60 - 0.75 = 59.25 m. Before: the car drove through it (its front 44.75 m past it).
    let program = format!(
        "{ROAD}c = Car(loc = r.onLane(1, 20), speed = 10.0)
o = Obstacle(loc = r.onLane(1, 60), size = (1.5, 1.8, 1.5))
w.place(r, v, c, o)
hit = CollisionMonitor(c)
test(horizon = 10.0, offroad = False)
"
    );
    let xs = trace(&program, 8.0, |s| {
        (
            x_of(s, car(s, 0)),
            flag(s, car(s, 0), Output::Collided),
            s.read(car(s, 0), Output::Speed).as_num().unwrap(),
        )
    });
    let (x, collided, speed) = *xs.last().unwrap();
    let front = x + 2.25;
    assert!(
        (front - 59.25).abs() < 0.01,
        "its front stops at {front} m, the obstacle's face is at 59.25 m"
    );
    assert!(collided && speed == 0.0, "{collided} {speed}");
    assert!(xs.iter().all(|(x, _, _)| x + 2.25 <= 59.25 + 1e-3));
    // The monitor named by its variable fails, with robustness 0 (it touched).
    let scenario = load(&program).unwrap();
    assert!(scenario.monitors().iter().any(|m| m.name() == "hit"));
    let a = common::no_params(&scenario);
    let outcome = scenario.run(&a, 0).unwrap();
    let (_, hit) = outcome.monitors.iter().find(|(n, _)| n == "hit").unwrap();
    assert!(!hit.passed && hit.robustness == 0.0, "{hit:?}");
}

#[test]
fn keep_distance_stops_that_far_short_without_touching() {
    let program = format!(
        "{ROAD}c = Car(loc = r.onLane(1, 20), speed = 10.0, keep_distance = 5.0)
o = Obstacle(loc = r.onLane(1, 80), size = (1.5, 1.8, 1.5))
w.place(r, v, c, o)
CollisionMonitor(c)
test(horizon = 12.0, offroad = False)
"
    );
    let xs = trace(&program, 12.0, |s| {
        (
            x_of(s, car(s, 0)),
            flag(s, car(s, 0), Output::Collided),
            s.read(car(s, 0), Output::Separation).as_num().unwrap(),
        )
    });
    let (x, collided, gap) = *xs.last().unwrap();
    assert!(!collided);
    // Stopped 5 m short of the box's face (79.25 m), to the 1 cm the search resolves.
    assert!(
        ((79.25 - (x + 2.25)) - 5.0).abs() < 0.02,
        "front at {}",
        x + 2.25
    );
    assert!((gap - 5.0).abs() < 0.02, "separation {gap}");
    // It braked no harder than its tyres allow (0.8 g), measured from its positions.
    let dt = 1.0 / 60.0;
    let v: Vec<f64> = xs.windows(2).map(|w| (w[1].0 - w[0].0) / dt).collect();
    let hardest = v.windows(2).map(|w| (w[0] - w[1]) / dt).fold(0.0, f64::max);
    assert!(hardest <= 0.8 * 9.81 * 1.001, "{hardest} m/s²");
}

#[test]
fn a_car_running_into_a_stopped_car_stops_and_a_pedestrian_walking_into_one_collides() {
    let program = format!(
        "{ROAD}a = Car(loc = r.onLane(1, 20), speed = 12.0)
b = Car(loc = r.onLane(1, 70), speed = 0.0)
p = Pedestrian(start = r.onLane(r.SideWalk, 150), target = r.onLane(-r.SideWalk, 150), speed = 1.5, trigger = tick)
c = Car(loc = r.onLane(1, 149.0), speed = 0.0)
w.place(r, v, a, b, p, c)
CollisionMonitor(v)
test(horizon = 10.0, offroad = False)
"
    );
    let out = trace(&program, 9.0, |s| {
        (
            x_of(s, car(s, 0)),
            x_of(s, car(s, 1)),
            [0, 1, 2].map(|i| flag(s, car(s, i), Output::Collided)),
            flag(
                s,
                ActorRef::Pedestrian(s.pedestrians().next().unwrap()),
                Output::Collided,
            ),
        )
    });
    let (a, b, cars, ped) = *out.last().unwrap();
    // Car a's front (a + 2.25) meets car b's back (b - 2.25) and stops there.
    assert!(((b - 2.25) - (a + 2.25)).abs() < 0.01, "{a} {b}");
    assert!(b == 70.0, "b is not pushed: {b}");
    assert_eq!(cars, [true, true, true]);
    assert!(ped);
}

/// A car that rear-ends a slower one stays stopped where it hit it (it does not drive on and
/// ram it again), and the car it hit brakes to a stop: a crash ends both drives (LANGUAGE.md,
/// `Car`; a pedestrian met only stops a car until the pedestrian has walked on, as
/// `a_car_running_into_a_stopped_car_stops_and_a_pedestrian_walking_into_one_collides` and the
/// `t-loop` built-in have it).
#[test]
fn a_car_that_collides_stays_stopped() {
    let program = format!(
        "{ROAD}a = Car(loc = r.onLane(1, 20), speed = 15.0)
b = Car(loc = r.onLane(1, 40), speed = 3.0)
w.place(r, v, a, b)
test(horizon = 10.0, offroad = False)
"
    );
    let out = trace(&program, 9.0, |s| {
        (
            x_of(s, car(s, 0)),
            x_of(s, car(s, 1)),
            flag(s, car(s, 0), Output::Collided),
        )
    });
    let hit = out.iter().position(|o| o.2).expect("a runs into b");
    // 15.5 m between bumpers closing at 12 m/s: about 1.3 s.
    assert!((70..90).contains(&hit), "hit at step {hit}");
    let (a_then, _, _) = out[hit + 60];
    let (a_end, b_end, _) = *out.last().unwrap();
    assert_eq!(a_then, a_end, "a stays where it stopped");
    // b, run into at 3 m/s, brakes to a stop within a second at μ·g; it stays short of the
    // 9 s it would have driven on.
    let (_, b_then, _) = out[hit + 60];
    assert_eq!(b_then, b_end, "b has stopped: {b_then} {b_end}");
    assert!(b_end < 40.0 + 3.0 * 3.0, "{b_end}");
}

#[test]
fn a_lane_changing_car_moves_over_the_ground_at_its_speed_on_a_bend() {
    // Before: its speed was its progress along the start lane's path, so after changing
    // lane outward on an Arc it covered 8.275 m/s while reporting 8.0.
    let program = r#"
w = World(light = 0.5, fog = 0.0)
a = RoadSegment(len = 60.0, nlanes = 4)
b = Arc(radius = 40.0, angle = 3.0, nlanes = 4)
net = a.connect((a.TWO, b, b.ONE))
v = AutonomousVehicle(loc = a.onLane(-1, 50), sut = "aeb", speed = 0.0)
c = Car(loc = a.onLane(1, 5), speed = 8.0, lane_change = ChangeLane(to = 2, at = 0.5, duration = 2.0))
w.place(net, v, c)
CollisionMonitor(v)
test(horizon = 12.0, offroad = False)
"#;
    let dt = 1.0 / 60.0;
    let out = trace(program, 12.0, |s| {
        let p = match s.read(car(s, 0), Output::Pos) {
            Value::Vec3(p) => p,
            v => panic!("{v:?}"),
        };
        (p, s.read(car(s, 0), Output::Speed).as_num().unwrap())
    });
    let mut worst: f64 = 0.0;
    for w in out.windows(2).skip(1) {
        let ground = (w[1].0[0] - w[0].0[0]).hypot(w[1].0[2] - w[0].0[2]) / dt;
        assert!((ground - w[1].1).abs() < 1e-9, "{ground} vs {}", w[1].1);
        worst = worst.max((ground - 8.0).abs());
    }
    // The station is scaled until the ground point moves the command, to 1e-6.
    assert!(worst < 8.0 * 1e-5, "ground speed off by {worst} m/s");
}

#[test]
fn a_pedestrian_walked_by_two_behaviours_is_refused_naming_both() {
    let program = format!(
        "{ROAD}p = Pedestrian(start = r.onLane(r.SideWalk, 150), target = r.onLane(-r.SideWalk, 150), speed = 1.5, dist = 20.0, car = v)
tick.foreach(p.walk)
w.place(r, v, p)
CollisionMonitor(v)
"
    );
    let e = load(&program).unwrap_err();
    assert!(e.contains("walked by two behaviours"), "{e}");
    // The Pedestrian's line (5) and the foreach's (6), with their columns.
    assert!(e.contains("p.star:5:5") && e.contains("p.star:6:1"), "{e}");
    let twice = format!(
        "{ROAD}p = Pedestrian(start = r.onLane(r.SideWalk, 150), target = r.onLane(-r.SideWalk, 150), speed = 1.5)
tick.foreach(p.walk)
tick.filter(lambda t: t > 1).foreach(p.walk)
w.place(r, v, p)
CollisionMonitor(v)
"
    );
    let e = load(&twice).unwrap_err();
    assert!(e.contains("p.star:6:1") && e.contains("p.star:7:1"), "{e}");
    // One behaviour loads.
    let once = format!(
        "{ROAD}p = Pedestrian(start = r.onLane(r.SideWalk, 150), target = r.onLane(-r.SideWalk, 150), speed = 1.5)
tick.foreach(p.walk)
w.place(r, v, p)
CollisionMonitor(v)
"
    );
    load(&once).unwrap();
}

#[test]
fn every_monitor_builtin_takes_its_variables_name() {
    let program = format!(
        "{ROAD}c = Car(loc = r.onLane(1, 20), speed = 10.0)
w.place(r, v, c)
hit = CollisionMonitor(v)
d100 = DistanceMonitor(v, minD = 100.0)
d130 = DistanceMonitor(v, minD = 130.0)
edge = OffRoadMonitor(v)
late = TimeToFailure(CollisionMonitor(c), minT = 3.0)
phi = Stl(\"G[0,5] (c.speed > 1 & c.separation > 0.5)\")
named = DistanceMonitor(v, minD = 1.0, name = \"given\")
CollisionMonitor(c)
test(horizon = 10.0)
"
    );
    let s = load(&program).unwrap();
    let names: Vec<&str> = s.monitors().iter().map(|m| m.name()).collect();
    assert_eq!(
        names,
        [
            "hit",
            "d100",
            "d130",
            "edge",
            "late",
            "phi",
            "given",
            "collision"
        ]
    );
}

#[test]
fn an_stl_window_entirely_past_the_horizon_is_refused_at_load() {
    for (formula, op) in [
        ("F[10,20] (ego_speed_mps > 1)", "F[10,20]"),
        ("G[6,8] (ego_speed_mps > 1)", "G[6,8]"),
        ("G[2,3] F[4,6] (ego_speed_mps > 1)", "F[4,6]"),
    ] {
        let program = format!(
            "{ROAD}w.place(r, v)
s = Stl(\"{formula}\")
test(horizon = 5.0)
"
        );
        let e = load(&program).unwrap_err();
        assert!(
            e.contains(op) && e.contains("horizon of 5 s"),
            "{formula}: {e}"
        );
        assert!(e.contains("p.star:6:5"), "{e}");
    }
    // A window that reaches into the test loads.
    let program = format!(
        "{ROAD}w.place(r, v)
s = Stl(\"F[4,20] (ego_speed_mps > 1)\")
test(horizon = 5.0)
"
    );
    load(&program).unwrap();
}

#[test]
fn the_ego_placed_on_a_roundabout_ring_without_a_route_follows_the_ring() {
    // Before: it drove straight off the ring in 1.8 s; with any route= it followed it.
    let program = r#"
w = World(light = 0.5, fog = 0.0)
rb = Roundabout(nlanes = 2, radius = 20.0)
e = RoadSegment(len = 60.0, nlanes = 2)
s = RoadSegment(len = 60.0, nlanes = 2)
wr = RoadSegment(len = 60.0, nlanes = 2)
n = RoadSegment(len = 60.0, nlanes = 2)
net = rb.connect((rb.ONE, e, e.ONE), (rb.TWO, s, s.ONE), (rb.THREE, wr, wr.ONE), (rb.FOUR, n, n.ONE))
v = AutonomousVehicle(loc = rb.onLane(rb.TWO, "left", 8.0), sut = "aeb", speed = 5.0)
w.place(net, v)
OffRoadMonitor(v)
test(horizon = 8.0)
"#;
    let scenario = load(program).unwrap();
    let a = common::no_params(&scenario);
    let outcome = scenario.run(&a, 0).unwrap();
    let (_, offroad) = &outcome.monitors[0];
    assert!(offroad.passed, "{offroad:?}");
    // It went round: more than a quarter of the ring from where it started.
    let r = trace(program, 4.0, |s| match s.read(ActorRef::Ego, Output::Pos) {
        Value::Vec3(p) => (-p[2]).atan2(p[0]),
        v => panic!("{v:?}"),
    });
    let swept: f64 = r
        .windows(2)
        .map(|w| paracosm_engine::network::wrap(w[1] - w[0]))
        .sum();
    assert!(swept > 0.8, "it swept {swept} rad round the centre");
}

#[test]
fn speed_actions_and_a_lane_change_compose_and_the_last_speed_set_in_a_step_wins() {
    // setSpeed (the last of two in one step wins: 5 m/s) while its lane change moves it
    // sideways: it moves at 5 m/s over the ground and ends in lane 2.
    let program = format!(
        "{ROAD}c = Car(loc = r.onLane(1, 20), speed = 10.0, lane_change = ChangeLane(to = -1, at = 1.0, duration = 3.0))
tick.take(1).foreach(c.setSpeed(9.0))
tick.take(1).foreach(c.setSpeed(5.0))
w.place(r, v, c)
CollisionMonitor(v)
test(horizon = 10.0, offroad = False)
"
    );
    let out = trace(&program, 8.0, |s| {
        (
            match s.read(car(s, 0), Output::Pos) {
                Value::Vec3(p) => p,
                v => panic!("{v:?}"),
            },
            s.read(car(s, 0), Output::Speed).as_num().unwrap(),
        )
    });
    // From the second step on (the first sets the speed), at 5 m/s over the ground.
    for (k, (_, speed)) in out.iter().enumerate().skip(2) {
        assert!((speed - 5.0).abs() < 1e-4, "step {k}: {speed} m/s");
    }
    // Into the other direction's lane 1: 3.5 m to the left of where it started (z = -1.75).
    let (p, _) = out.last().unwrap();
    assert!((p[2] + 1.75).abs() < 1e-6, "{p:?}");
}

/// The `i`-th car of the world `s` runs.
fn car(s: &Simulation, i: usize) -> ActorRef {
    ActorRef::Car(s.cars().nth(i).expect("the world has that car"))
}
