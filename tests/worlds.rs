//! Issue 15: a family of worlds. Every input may be open, road geometry included; each test
//! builds its own world; load checks every level and interval end; new vocabulary (lane
//! changes, locations in junctions, obstacles). The scenario files are in `tests/scenarios/`
//! and `scenarios/`, each saying what it shows.

mod common;

use std::path::{Path, PathBuf};

use common::{assign, expect_code, fuzz};
use paracosm_engine::rx::NoHost;
use paracosm_engine::sut::{ConstantControl, Sut};
use paracosm_engine::{Control, Simulation};
use paracosm_generators::{Assignment, ParamSpace, Point, Value};
use paracosm_scenarios::Scenario;
use serde_json::Value as Json;

fn path(dir: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join(name)
}

fn load(dir: &str, name: &str) -> Scenario {
    paracosm_scenarios::load(path(dir, name).to_str().unwrap()).unwrap()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn worlds_with_2_4_and_6_lanes_really_differ() {
    let s = load("tests/scenarios", "lanes_family.star");
    let mut lateral = Vec::new();
    let mut bearings = Vec::new();
    for n in [2, 4, 6] {
        // The cone ~37 m ahead: within the lidar's ±30° even across six lanes.
        let a = assign(
            s.space(),
            &[("nlanes", Value::Int(n)), ("gap", Value::Real(39.5))],
        );
        let world = s.instantiate(&a).unwrap();
        let sim = Simulation::new(&world).unwrap();
        // The outermost lane's centre: (n/2 - 1/2) · 3.5 m right of the centre line.
        let z = sim.ego_state().pos_m[2];
        assert!(
            (z - (n as f64 / 2.0 - 0.5) * 3.5).abs() < 1e-6,
            "{n} lanes: z = {z}"
        );
        lateral.push(z);
        // The cone on the left sidewalk: the nearest lidar return to the left.
        let obs = sim.observation();
        let cone = obs
            .lidar()
            .iter()
            .filter(|r| r.point_m[2] < -0.5)
            .min_by(|a, b| a.range_m.total_cmp(&b.range_m))
            .expect("the lidar sees the cone");
        bearings.push(cone.azimuth_rad);
        // The road itself: 2·n/2 lanes of 3.5 m, so the edge is n·1.75 m from the centre.
        assert!((world.network.pieces()[0].kind.half_road_m() - n as f64 * 1.75).abs() < 1e-9);
    }
    assert!(lateral.windows(2).all(|w| w[1] > w[0] + 3.0), "{lateral:?}");
    // The wider the road, the farther to the left the cone appears.
    assert!(
        bearings.windows(2).all(|w| w[1] > w[0] + 0.02),
        "the cone's bearing must differ by level: {bearings:?}"
    );

    // A campaign counts the three levels in its k-wise coverage.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        path("tests/scenarios", "lanes_family.star")
            .to_str()
            .unwrap(),
        "--budget",
        "12",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let summary: Json =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let kwise = &summary["coverage"]["kwise"][0];
    assert_eq!(
        (kwise["covered"].as_u64(), kwise["total"].as_u64()),
        (Some(3), Some(3))
    );
}

#[test]
fn an_open_place_on_a_lane_moves_the_car_to_the_sampled_gap() {
    let s = load("scenarios", "cut_in.star");
    for gap in [2.0, 11.5, 29.0] {
        let a = assign(s.space(), &[("gap", Value::Real(gap))]);
        let sim = Simulation::new(&s.instantiate(&a).unwrap()).unwrap();
        let snap = sim.snapshot();
        let ego_x = snap.ego.pos_m[0];
        let car_x = snap.cars[0].pos_m[0];
        // Bumper to bumper: the car's centre is 4.5 m plus the gap ahead of the ego's.
        assert!(
            (car_x - ego_x - 4.5 - gap).abs() < 1e-6,
            "gap {gap}: {car_x} - {ego_x}"
        );
    }
}

/// Full brake from 25 m/s for the whole test; where the ego stops, m from its start.
fn braking_distance(s: &Scenario, first: f64, second: f64) -> f64 {
    let a = assign(
        s.space(),
        &[
            ("friction[0]", Value::Real(first)),
            ("friction[1]", Value::Real(second)),
        ],
    );
    let mut sim = Simulation::new(&s.instantiate(&a).unwrap()).unwrap();
    let start = sim.ego_state().pos_m[0];
    let mut brake = ConstantControl(Control {
        throttle: -1.0,
        steering: 0.0,
    });
    while sim.t_s() < s.horizon_s() {
        let c = brake.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
    }
    sim.ego_state().pos_m[0] - start
}

#[test]
fn a_friction_that_drops_halfway_lengthens_the_braking_distance() {
    let s = load("tests/scenarios", "friction_drops.star");
    let names: Vec<&str> = s.space().params().iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["friction[0]", "friction[1]"]);
    let dry = braking_distance(&s, 0.85, 0.85);
    let drops = braking_distance(&s, 0.85, 0.1);
    // 25 m/s at about 8 m/s² stops in about 3.1 s and 39 m; after 2 s on ice (0.1) it slides
    // on at about 1 m/s² for the rest of the test.
    assert!((30.0..45.0).contains(&dry), "dry: {dry:.1} m");
    assert!(
        drops > dry + 3.0,
        "drops at 2 s: {drops:.1} m vs dry {dry:.1} m"
    );
    assert_eq!(braking_distance(&s, 0.85, 0.85), dry, "deterministic");
}

#[test]
fn a_cut_in_fails_some_tests_and_passes_others_and_both_replay_with_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = fuzz(&[
        path("scenarios", "cut_in.star").to_str().unwrap(),
        "--budget",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let records: Vec<Json> = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let collided = records
        .iter()
        .find(|r| r["monitors"]["collision"]["passed"] == false)
        .expect("a collision");
    let passed = records
        .iter()
        .find(|r| r["status"] == "pass")
        .expect("a pass");
    for r in [collided, passed] {
        let id = r["id"].to_string();
        let frames = dir.path().join(format!("frames-{id}"));
        let o = fuzz(&[
            "replay",
            out.join("results.jsonl").to_str().unwrap(),
            "--id",
            &id,
            "--frames",
            frames.to_str().unwrap(),
        ]);
        expect_code(&o, 0);
        assert!(frames.join("contact_sheet.png").exists());
        assert!(std::fs::read_dir(&frames).unwrap().count() > 10);
    }
}

#[test]
fn a_network_that_breaks_only_for_six_lanes_is_refused_at_load_naming_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let o = fuzz(&[
        path("tests/scenarios", "breaks_for_six.star")
            .to_str()
            .unwrap(),
        "--budget",
        "3",
        "--out",
        dir.path().join("out").to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let e = stderr(&o);
    assert!(e.contains("lane-count mismatch"), "{e}");
    assert!(
        e.contains("the world fails for the test values nlanes = 6"),
        "{e}"
    );
    assert!(e.contains("breaks_for_six.star:9:7"), "{e}");
}

#[test]
fn the_set_of_open_parameters_may_not_depend_on_their_values() {
    let e = paracosm_scenarios::load(
        path("tests/scenarios", "params_depend_on_values.star")
            .to_str()
            .unwrap(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("`extra`"), "{e}");
    assert!(
        e.contains("the open parameters depend on their values"),
        "{e}"
    );
    assert!(e.contains("exists only for some values"), "{e}");
    assert!(e.contains("params_depend_on_values.star:8:13"), "{e}");
    assert!(e.contains("lanes = 4"), "{e}");
}

#[test]
fn a_world_invalid_only_inside_an_interval_is_an_error_for_those_tests_alone() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = common::campaign(
        &path("tests/scenarios", "interior_collision.star"),
        "40",
        &out,
    );
    expect_code(&o, 3);
    let records: Vec<Json> = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), 40);
    let errors: Vec<&Json> = records.iter().filter(|r| r["status"] == "error").collect();
    assert!(
        !errors.is_empty() && errors.len() < 10,
        "{} errors",
        errors.len()
    );
    for r in &errors {
        let at = r["params"]["at"].as_f64().unwrap();
        // The cars (4.5 m long) overlap when their centres are closer than 4.5 m.
        assert!((at + 20.0 - 60.0).abs() < 4.6, "at = {at}");
        assert!(r["error"].as_str().unwrap().contains("start in collision"));
    }
    assert!(records.iter().any(|r| r["status"] == "pass"));
}

#[test]
fn branching_on_a_value_a_junction_location_an_obstacle_and_an_open_ego_speed() {
    let src = r#"
lanes = VarEnum([2, 4])
start_speed = VarInterval(4.0, 10.0, unit = "m/s")
rb = Roundabout(nlanes = 2, radius = 20.0)
west = RoadSegment(len = 100.0)
net = rb.connect((rb.THREE, west, west.ONE))
if lanes == 4:
    road = RoadSegment(len = 10.0 * lanes, nlanes = 2)
    net = net.connect((west.TWO, road, road.ONE))
w = World()
v = AutonomousVehicle(loc = west.onLane(-1, 60), speed = start_speed)
ring = Car(loc = rb.onLane(rb.TWO, "left", 12), speed = 5.0, route = [])
box = Obstacle(loc = west.onLane(-1, 20), size = (1.0, 2.0, 1.5), color = "yellow")
w.place(net, v, ring, box)
CollisionMonitor(v)
"#;
    let s = paracosm_scenarios::lang::load_source("t.star", src, "t").unwrap();
    for (lanes, pieces) in [(2, 2), (4, 3)] {
        let a = assign(
            s.space(),
            &[
                ("lanes", Value::Int(lanes)),
                ("start_speed", Value::Real(7.5)),
            ],
        );
        let world = s.instantiate(&a).unwrap();
        assert_eq!(world.network.pieces().len(), pieces, "lanes = {lanes}");
        let sim = Simulation::new(&world).unwrap();
        assert!((sim.ego_state().speed_mps - 7.5).abs() < 0.01);
        let snap = sim.snapshot();
        // The ring car is on the roundabout's ring, between the island and the plaza's edge.
        let r = snap.cars[0].pos_m[0].hypot(snap.cars[0].pos_m[2]);
        assert!((12.0..20.0).contains(&r), "ring car at radius {r}");
        assert_eq!(snap.obstacles.len(), 1);
        assert_eq!(snap.obstacles[0].size.width_m, 2.0);
        // The obstacle stands in the ego's lane 40 m ahead; the lidar sees it.
        let ahead = sim
            .observation()
            .lidar()
            .iter()
            .filter(|r| r.point_m[2].abs() < 0.3)
            .map(|r| r.range_m)
            .fold(f64::INFINITY, f64::min);
        assert!(
            (ahead - 37.5).abs() < 1.0,
            "nearest return straight ahead at {ahead} m"
        );
    }
}

#[test]
fn driving_into_an_obstacle_is_a_collision() {
    let src = r#"
w = World()
r = RoadSegment(len = 200.0)
v = AutonomousVehicle(loc = r.onLane(1, 10), sut = "aeb")
wall = Obstacle(loc = r.onLane(1, 60), size = (0.5, 3.0, 1.0))
w.place(r, v, wall)
CollisionMonitor(v)
"#;
    let s = paracosm_scenarios::lang::load_source("t.star", src, "t").unwrap();
    let a = assign(s.space(), &[]);
    // aeb sees it with its lidar and stops.
    let o = s.run(&a, 0).unwrap();
    assert!(o.passed(), "{o:?}");
    // Full throttle into it: a collision.
    let mut hits = s.clone();
    hits.set_sut(paracosm_engine::sut::SutConfig::Constant(Control {
        throttle: 0.5,
        steering: 0.0,
    }));
    let o = hits.run(&a, 0).unwrap();
    let (_, collision) = o.monitors.iter().find(|(n, _)| n == "collision").unwrap();
    assert!(!collision.passed, "{o:?}");
    assert!(collision.first_violation_s.unwrap() < 5.0);
}

#[test]
fn parameters_are_values_the_program_computes_with() {
    // range(), int(), indexing and arithmetic on both sides of an operator all work.
    let src = r#"
n = VarEnum([2, 4])
gap = VarInterval(10.0, 20.0)
w = World()
r = RoadSegment(len = 200.0, nlanes = n)
v = AutonomousVehicle(loc = r.onLane(1, 10))
cars = [Car(loc = r.onLane(lane, 100 - gap + 5 * lane), speed = 2.0) for lane in range(1, n // 2 + 1)]
names = ["one", "two"][int(n / 2) - 1]
w.place(r, v, *cars)
CollisionMonitor(v, name = "collision_" + names)
"#;
    let e = paracosm_scenarios::lang::load_source("t.star", src, "t")
        .unwrap_err()
        .to_string();
    // The monitor's name depends on n: refused, and said so.
    assert!(
        e.contains("the monitors depend on the open parameters' values"),
        "{e}"
    );
    let fixed = src.replace("name = \"collision_\" + names", "name = \"collision\"");
    let s = paracosm_scenarios::lang::load_source("t.star", &fixed, "t").unwrap();
    let a = assign(
        s.space(),
        &[("n", Value::Int(4)), ("gap", Value::Real(12.0))],
    );
    let world = s.instantiate(&a).unwrap();
    assert_eq!(world.cars.len(), 2);
    let sim = Simulation::new(&world).unwrap();
    let xs: Vec<f64> = sim.snapshot().cars.iter().map(|c| c.pos_m[0]).collect();
    assert_eq!(xs, [93.0, 98.0]);
}

/// Bit-identical results for any thread count, on every shipped scenario (the new ones with a
/// per-test evaluation of the program and worlds of different shapes included).
#[test]
fn every_shipped_scenario_gives_the_same_results_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    for name in paracosm_scenarios::builtin_names() {
        let run = |jobs: &str| {
            let out = dir.path().join(format!("{name}-{jobs}"));
            let o = fuzz(&[
                &name,
                "--budget",
                "6",
                "--seed",
                "5",
                "--strategy",
                "random",
                "--jobs",
                jobs,
                "--out",
                out.to_str().unwrap(),
            ]);
            assert!(
                matches!(o.status.code(), Some(0 | 1)),
                "{name}: {}",
                stderr(&o)
            );
            std::fs::read_to_string(out.join("results.jsonl"))
                .unwrap()
                .lines()
                .map(|l| l[..l.rfind(",\"wall_ms\":").unwrap()].to_owned())
                .collect::<Vec<_>>()
        };
        let (one, two) = (run("1"), run("2"));
        assert_eq!(one.len(), 6, "{name}");
        assert_eq!(one, two, "{name}");
    }
}

#[test]
fn checking_a_slow_program_stops_at_the_load_budget_and_says_so() {
    let s = load("tests/scenarios", "slow_to_evaluate.star");
    let w: Vec<String> = s.warnings().iter().map(|w| w.to_string()).collect();
    let budget = paracosm_scenarios::lang::MAX_CHECK_STEPS;
    let found = w
        .iter()
        .find(|m| m.contains("loading checked"))
        .unwrap_or_else(|| panic!("no budget warning in {w:?}"));
    // 3 million steps an evaluation: the budget of 50 million is passed after 17 of 32.
    assert!(
        found.contains("checked 17 of the 32 combinations"),
        "{found}"
    );
    assert!(found.contains(&budget.to_string()), "{found}");
}

/// One input of the program in [`EVERY_INPUT`]: its placeholder, its value as a plain
/// constant, an open form (named `x`, two or more values that must give different worlds),
/// and whether LANGUAGE.md's table says it accepts a stream that varies over time
/// (`over_time=`, where the input is a number) and a computed stream.
struct Slot {
    key: &'static str,
    plain: &'static str,
    open: &'static str,
    over_time: Option<bool>,
    computed: bool,
}

const fn slot(
    key: &'static str,
    plain: &'static str,
    open: &'static str,
    over_time: Option<bool>,
    computed: bool,
) -> Slot {
    Slot {
        key,
        plain,
        open,
        over_time,
        computed,
    }
}

/// A program that uses every input LANGUAGE.md lists, each a placeholder `{key}`.
const EVERY_INPUT: &str = r#"n = {n}
w = World(light = {light}, fog = {fog})
r = RoadSegment(len = {len}, nlanes = n, friction = {friction})
j = CrossIntersection(nlanes = n, friction = {jfriction})
x = RoadSegment(len = 60.0, nlanes = n)
k = Roundabout(nlanes = n, radius = {radius})
net = r.connect((r.TWO, j, j.THREE))
net = j.connect((j.ONE, x, x.ONE))
net = x.connect((x.TWO, k, k.THREE))
v = AutonomousVehicle(loc = r.onLane({ego_lane}, {ego_at}), speed = {ego_speed}, route = {ego_route})
c = Car(loc = r.onLane({car_lane}, {car_at}), speed = {car_speed}, color = {color}, enabled = {enabled}, route = {car_route}, lane_change = ChangeLane(to = {lc_to}, at = {lc_at}, duration = {lc_duration}))
d = Car(loc = k.onLane(k.ONE, {j_turn}, {j_at}, lane = {j_lane}), speed = 5.0)
o = Obstacle(loc = r.onLane(-r.SideWalk, {obs_at}), size = ({obs_len}, 0.5, {obs_h}), color = {obs_color})
pa = {ped_at}
p = Pedestrian(start = r.onLane(r.SideWalk, pa), target = r.onLane(-r.SideWalk, pa), speed = {ped_speed}, dist = {ped_dist}, car = v)
w.place(net, v, c, d, o, p)
CollisionMonitor(v)
DistanceMonitor(v, minD = {minD})
test(horizon = {horizon})
"#;

const SLOTS: &[Slot] = &[
    slot(
        "light",
        "0.5",
        "VarInterval(0.3, 0.7, name = \"x\")",
        Some(true),
        true,
    ),
    slot(
        "fog",
        "0.1",
        "VarInterval(0.0, 0.5, name = \"x\")",
        Some(true),
        true,
    ),
    slot(
        "len",
        "200.0",
        "VarInterval(180.0, 250.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "n",
        "4",
        "VarEnum([4, 6], name = \"x\")",
        Some(false),
        false,
    ),
    // 28 m at least for 6 lanes (the ways onto and off the ring of its outer lane).
    slot(
        "radius",
        "30.0",
        "VarInterval(30.0, 40.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "friction",
        "0.8",
        "VarInterval(0.2, 0.9, name = \"x\")",
        Some(true),
        true,
    ),
    slot(
        "jfriction",
        "0.8",
        "VarEnum([0.3, 0.9], name = \"x\")",
        Some(true),
        true,
    ),
    slot(
        "ego_lane",
        "1",
        "VarEnum([1, 2], name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "ego_at",
        "10.0",
        "VarInterval(5.0, 15.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "ego_speed",
        "12.0",
        "VarInterval(5.0, 15.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "ego_route",
        "\"straight\"",
        "VarEnum([\"left\", \"straight\"], name = \"x\")",
        None,
        false,
    ),
    slot(
        "car_lane",
        "2",
        "VarEnum([2, -1], name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "car_at",
        "40.0",
        "VarInterval(30.0, 60.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "car_speed",
        "8.0",
        "VarInterval(5.0, 10.0, name = \"x\")",
        Some(true),
        true,
    ),
    slot(
        "color",
        "\"red\"",
        "VarEnum([\"red\", \"blue\"], name = \"x\")",
        None,
        false,
    ),
    slot(
        "enabled",
        "True",
        "VarEnum([True, False], name = \"x\")",
        None,
        false,
    ),
    slot(
        "car_route",
        "\"straight\"",
        "VarEnum([\"left\", \"right\"], name = \"x\")",
        None,
        false,
    ),
    slot(
        "lc_to",
        "1",
        "VarEnum([1, -1], name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "lc_at",
        "2.0",
        "VarInterval(1.0, 3.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "lc_duration",
        "3.0",
        "VarInterval(2.0, 4.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "j_turn",
        "\"right\"",
        "VarEnum([\"right\", \"straight\"], name = \"x\")",
        None,
        false,
    ),
    slot(
        "j_at",
        "5.0",
        "VarInterval(2.0, 8.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "j_lane",
        "1",
        "VarEnum([1, 2], name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "obs_at",
        "150.0",
        "VarInterval(120.0, 140.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "obs_len",
        "0.5",
        "VarInterval(0.3, 0.6, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "obs_h",
        "1.2",
        "VarInterval(0.5, 1.5, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "obs_color",
        "\"orange\"",
        "VarEnum([\"orange\", \"grey\"], name = \"x\")",
        None,
        false,
    ),
    slot(
        "ped_at",
        "100.0",
        "VarInterval(90.0, 110.0, name = \"x\")",
        Some(false),
        false,
    ),
    slot(
        "ped_speed",
        "1.5",
        "VarInterval(1.0, 2.0, name = \"x\")",
        Some(true),
        true,
    ),
    slot(
        "ped_dist",
        "30.0",
        "VarInterval(20.0, 40.0, name = \"x\")",
        Some(true),
        true,
    ),
];

/// Inputs that are the same for every test of a campaign: constants only.
const CAMPAIGN_CONSTANTS: &[(&str, &str, &str)] = &[
    ("minD", "10.0", "VarInterval(5.0, 15.0, name = \"x\")"),
    ("horizon", "3.0", "VarInterval(2.0, 4.0, name = \"x\")"),
];

fn every_input(with: &[(&str, &str)]) -> String {
    let mut src = EVERY_INPUT.to_owned();
    for (k, v) in with {
        src = src.replace(&format!("{{{k}}}"), v);
    }
    for s in SLOTS {
        src = src.replace(&format!("{{{}}}", s.key), s.plain);
    }
    for (k, plain, _) in CAMPAIGN_CONSTANTS {
        src = src.replace(&format!("{{{k}}}"), plain);
    }
    src
}

/// The parameter `x` at the start (`0.1` of the interval, first level) or the end.
fn x_at(space: &ParamSpace, end: bool) -> Assignment {
    let mut point = Point {
        discrete: Vec::new(),
        continuous: Vec::new(),
    };
    for p in space.params() {
        match &p.domain {
            paracosm_generators::Domain::Interval { .. } => {
                point.continuous.push(if end { 0.9 } else { 0.1 })
            }
            paracosm_generators::Domain::Levels(levels) => {
                point
                    .discrete
                    .push(if end { levels.len() as u32 - 1 } else { 0 })
            }
        }
    }
    space.decode(&point).unwrap()
}

/// The line of `key`'s placeholder in [`EVERY_INPUT`], from 1.
fn line_of(key: &str) -> usize {
    // `n` and `pa` are assigned on lines of their own, and used on the next line but one.
    let key = match key {
        "n" => "len",
        "ped_at" => "ped_speed",
        k => k,
    };
    EVERY_INPUT
        .lines()
        .position(|l| l.contains(&format!("{{{key}}}")))
        .unwrap()
        + 1
}

#[test]
fn every_input_takes_a_constant_const_an_open_value_and_what_the_reference_says() {
    let load = |src: &str| paracosm_scenarios::lang::load_source("every.star", src, "every");
    let base = load(&every_input(&[])).unwrap_or_else(|e| panic!("{e}"));
    let empty = base.space().decode(&Point {
        discrete: vec![],
        continuous: vec![],
    });
    let base_run = format!("{:?}", base.run(&empty.unwrap(), 0).unwrap());
    for s in SLOTS {
        // Const(v) is v: the same test, verdicts, robustness and metrics.
        let c = format!("Const({})", s.plain);
        let with_const =
            load(&every_input(&[(s.key, &c)])).unwrap_or_else(|e| panic!("{}: Const: {e}", s.key));
        let run = with_const.run(&empty_assignment(&with_const), 0).unwrap();
        assert_eq!(
            format!("{run:?}"),
            base_run,
            "{}: Const({}) is not {}",
            s.key,
            s.plain,
            s.plain
        );

        // Open per test: the two ends give different worlds, and both run.
        let open = load(&every_input(&[(s.key, s.open)]))
            .unwrap_or_else(|e| panic!("{}: open: {e}", s.key));
        assert_eq!(open.space().params().len(), 1, "{}", s.key);
        let (a, b) = (x_at(open.space(), false), x_at(open.space(), true));
        let (wa, wb) = (open.instantiate(&a).unwrap(), open.instantiate(&b).unwrap());
        assert_ne!(
            format!("{wa:?}"),
            format!("{wb:?}"),
            "{}: the open value changes nothing",
            s.key
        );
        for x in [&a, &b] {
            open.run(x, 0)
                .unwrap_or_else(|e| panic!("{}: open: {x:?}: {e}", s.key));
        }

        // Over time and computed: accepted and run, or refused at load naming the line.
        let lo_hi = s.open.trim_start_matches("VarInterval(");
        let mut forms = Vec::new();
        if let Some(ok) = s.over_time {
            let varying = if s.open.starts_with("VarInterval") {
                format!(
                    "VarInterval({}",
                    lo_hi.replace("name = \"x\"", "name = \"x\", over_time = Piecewise(2)")
                )
            } else {
                format!(
                    "VarInterval({0}, {0} + 1, name = \"x\", over_time = Piecewise(2))",
                    s.plain
                )
            };
            forms.push(("over time", varying, ok));
        }
        forms.push((
            "computed",
            format!("tick.map(lambda t: {})", s.plain),
            s.computed,
        ));
        for (what, form, ok) in forms {
            let got = load(&every_input(&[(s.key, &form)]));
            match (got, ok) {
                (Ok(sc), true) => {
                    let a = x_at(sc.space(), true);
                    sc.run(&a, 0)
                        .unwrap_or_else(|e| panic!("{} {what}: {e}", s.key));
                }
                (Err(e), false) => {
                    let e = e.to_string();
                    let at = format!("every.star:{}:", line_of(s.key));
                    assert!(e.contains(&at), "{} {what}: {at} missing from\n{e}", s.key);
                    assert!(
                        e.contains("stream"),
                        "{} {what}: the refusal must say a stream is not taken here:\n{e}",
                        s.key
                    );
                }
                (Ok(_), false) => panic!("{} {what}: accepted, but LANGUAGE.md says no", s.key),
                (Err(e), true) => {
                    panic!("{} {what}: refused, but LANGUAGE.md says yes: {e}", s.key)
                }
            }
        }
    }
    // Inputs fixed for the whole campaign: a constant or Const, never open.
    for (key, plain, open) in CAMPAIGN_CONSTANTS {
        let c = format!("Const({plain})");
        load(&every_input(&[(key, &c)])).unwrap_or_else(|e| panic!("{key}: Const: {e}"));
        let e = load(&every_input(&[(key, open)])).unwrap_err().to_string();
        assert!(
            e.contains("depends on the open parameters")
                || e.contains("depend on the open parameters"),
            "{key}: {e}"
        );
        let at = format!("every.star:{}:", line_of(key));
        assert!(e.contains(&at), "{key}: {at} missing from\n{e}");
    }
}

fn empty_assignment(s: &Scenario) -> Assignment {
    s.space()
        .decode(&Point {
            discrete: vec![],
            continuous: vec![],
        })
        .unwrap()
}

#[test]
fn a_lambda_reads_the_tests_value_of_an_open_parameter() {
    // A car's speed computed by a lambda that reads `cruise` gives the same test as the
    // speed `cruise` itself, for every value; and different values give different tests.
    let src = |speed: &str| {
        format!(
            r#"
cruise = VarInterval(2.0, 10.0, unit = "m/s")
w = World()
r = RoadSegment(len = 300.0, nlanes = 2)
v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 12.0)
c = Car(loc = r.onLane(1, 60), speed = {speed})
w.place(r, v, c)
CollisionMonitor(v)
test(horizon = 6.0)
"#
        )
    };
    let direct = paracosm_scenarios::lang::load_source("d.star", &src("cruise"), "d").unwrap();
    let lambda =
        paracosm_scenarios::lang::load_source("l.star", &src("tick.map(lambda t: cruise)"), "l")
            .unwrap();
    let mut seen = Vec::new();
    for x in [2.5, 6.0, 9.5] {
        let a = assign(direct.space(), &[("cruise", Value::Real(x))]);
        let (d, l) = (direct.run(&a, 0).unwrap(), lambda.run(&a, 0).unwrap());
        assert_eq!(format!("{d:?}"), format!("{l:?}"), "cruise = {x}");
        let (_, collision) = d.monitors.iter().find(|(n, _)| n == "collision").unwrap();
        seen.push(collision.robustness);
    }
    assert!(
        seen.windows(2).all(|w| w[0] != w[1]),
        "the value changes nothing: {seen:?}"
    );
}

#[test]
fn the_reference_example_places_a_truck_only_on_six_lanes() {
    let s = load("tests/scenarios", "truck_on_six_lanes.star");
    for (n, trucks) in [(2, 0), (4, 0), (6, 1)] {
        let a = assign(
            s.space(),
            &[("nlanes", Value::Int(n)), ("gap", Value::Real(30.0))],
        );
        let world = s.instantiate(&a).unwrap();
        assert_eq!(world.obstacles.len(), trucks, "{n} lanes");
        assert_eq!(world.cars.len(), 1);
        s.run(&a, 0).unwrap();
    }
}

/// A campaign has one length and one system under test: a `test(horizon=)` or an
/// `AutonomousVehicle(sut=)` computed from an open parameter is refused at load, naming the
/// line that declares it; the same program with them fixed loads.
#[test]
fn a_horizon_or_a_system_under_test_that_depends_on_values_is_refused_naming_its_line() {
    let base = r#"
n = VarEnum([2, 4])
w = World()
r = RoadSegment(len = 200.0, nlanes = n)
v = AutonomousVehicle(loc = r.onLane(1, 10), sut = SUT)
w.place(r, v)
CollisionMonitor(v)
test(horizon = HORIZON)
"#;
    let with = |sut: &str, horizon: &str| base.replace("SUT", sut).replace("HORIZON", horizon);
    let e = paracosm_scenarios::lang::load_source("t.star", &with("\"aeb\"", "5.0 * n"), "t")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("test(horizon=) depends on the open parameters' values"),
        "{e}"
    );
    assert!(e.contains("t.star:8:1"), "{e}");
    let e = paracosm_scenarios::lang::load_source(
        "t.star",
        &with("\"aeb\" if n == 2 else \"vision\"", "10.0"),
        "t",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("AutonomousVehicle(sut=) depends on the open parameters' values"),
        "{e}"
    );
    assert!(e.contains("t.star:5:5"), "{e}");
    let s = paracosm_scenarios::lang::load_source("t.star", &with("\"aeb\"", "10.0"), "t").unwrap();
    assert_eq!(s.horizon_s(), 10.0);
}
