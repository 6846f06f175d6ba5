//! One test's closed-loop simulation of the pedestrian-crossing study (physics, lidar, `aeb`,
//! monitors), written three ways: the Rust reference, `pedestrian_crossing.star` (native
//! trigger), and the same program with its trigger as a Starlark lambda called every step.
//! Issue 5 asks that per-step lambdas cost at most 2× the Rust version.
//!
//! `rapier_alone/lidar` is the same test's physics and lidar written with rapier only
//! (`engine/benches/rapier_alone.rs`): issue 23 asks that a whole test (`safe_15s/star`) cost
//! at most 1.2× that, measured in this one run.
//!
//! `long_horizons/*` runs one whole test of `grid-world` (40 s, four NPC cars) and of
//! `t-loop` (200 s): with `safe_15s/star` they give the cost per simulated second that issue
//! 23 compares (`experiments/bench/long_horizons.py` measures whole campaigns).
//!
//! `camera/*` runs one whole test of the pedestrian study with each system under test that
//! sees through the camera (`vision`, `pilotnet`, an external process) and with `aeb`.
//!
//! `maps/*` runs one test on paracosm's own straight road (a 500 m `RoadSegment`, the
//! baseline) and on three OpenDRIVE maps written by others (`tests/data/maps/`): esmini's
//! straight 500 m road, CARLA's Town07 and esmini's `multi_intersections` (63 roads), for
//! 0.1 s and 15 s, the ego under `aeb` at 8.5 m/s. The map's query index and
//! collision mesh are built once per program and shared by its tests (`MapRef`'s cache):
//! a test on a city map should cost about what one on a straight map of the same horizon
//! does.

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_generators::Point;
use paracosm_scenarios::{builtin, lang, reference, Scenario};

#[path = "../../engine/benches/rapier_alone.rs"]
mod rapier_alone;

fn bench(c: &mut Criterion) {
    let lambdas = lang::load_source(
        "pedestrian_crossing_lambdas.star",
        include_str!("pedestrian_crossing_lambdas.star"),
        "pedestrian-crossing-lambdas",
    )
    .unwrap();
    let versions: [(&str, Scenario); 3] = [
        ("rust_reference", reference::scenario()),
        ("star", builtin("pedestrian-crossing").unwrap()),
        ("star_lambdas", lambdas),
    ];
    let mut group = c.benchmark_group("pedestrian_crossing");
    // (walking speed, trigger distance) in unit coordinates.
    for (case, u) in [("safe_15s", [0.05, 0.9]), ("collision", [0.26, 0.09])] {
        for (name, s) in &versions {
            let a = s
                .space()
                .decode(&Point {
                    discrete: vec![],
                    continuous: u.to_vec(),
                })
                .unwrap();
            assert_eq!(
                s.run(&a, 0).unwrap().passed(),
                case == "safe_15s",
                "{name} {case}"
            );
            group.bench_function(format!("{case}/{name}"), |b| {
                b.iter(|| s.run(&a, 0).unwrap())
            });
        }
    }
    group.bench_function("rapier_alone/lidar", |b| {
        b.iter(|| rapier_alone::run_test(0.975, 54.5, true))
    });
    group.finish();

    // Issue 23's long horizons: one whole test of each, to its horizon (points of Halton
    // campaigns whose tests pass), named with the simulated time so a cost per simulated
    // second can be read off.
    let mut group = c.benchmark_group("long_horizons");
    group.sample_size(10);
    for (name, u) in [
        (
            "grid_world",
            [0.125, 0.4444444444444444, 0.8, 0.5714285714285714],
        ),
        (
            "t_loop",
            [0.625, 0.7777777777777778, 0.04, 0.7142857142857143],
        ),
    ] {
        let s = builtin(&name.replace('_', "-")).unwrap();
        let a = s
            .space()
            .decode(&Point {
                discrete: vec![],
                continuous: u.to_vec(),
            })
            .unwrap();
        let outcome = s.run(&a, 0).unwrap();
        assert!(outcome.passed(), "{name}");
        let simulated = outcome
            .metrics
            .iter()
            .find(|(k, _)| *k == "simulated_s")
            .map(|(_, v)| *v)
            .unwrap();
        assert_eq!(simulated, s.horizon_s(), "{name} runs to its horizon");
        group.bench_function(format!("{name}_{simulated}s"), |b| {
            b.iter(|| s.run(&a, 0).unwrap())
        });
    }
    group.finish();
    maps(c);
    camera(c);
}

/// One whole 15 s test of the pedestrian study (a point where the pedestrian stays clear)
/// driven by each system under test that sees through the camera: `vision` (160 × 120 at
/// 20 Hz, image and depth, pixel noise), `pilotnet` (320 × 240 at 10 Hz, its crop of the
/// image only, tract) and an external process (`camera_sut.py`: 320 × 240 at 10 Hz, every
/// frame sent through the protocol), beside `aeb` (lidar) for the ratio. The profile table
/// in docs/performance.md ("The camera loop") splits these tests' time.
fn camera(c: &mut Criterion) {
    use paracosm_engine::sut::{ExternalConfig, SutConfig};
    let base = builtin("pedestrian-crossing").unwrap();
    let a = base
        .space()
        .decode(&Point {
            discrete: vec![],
            continuous: vec![0.05, 0.9],
        })
        .unwrap();
    let external = SutConfig::External(ExternalConfig::new(
        vec!["python3".into(), "benches/camera_sut.py".into()],
        30.0,
        true,
    ));
    let mut group = c.benchmark_group("camera");
    group.sample_size(10);
    for (name, sut) in [
        (
            "aeb",
            SutConfig::named("aeb", std::path::Path::new(".")).unwrap(),
        ),
        (
            "vision",
            SutConfig::named("vision", std::path::Path::new(".")).unwrap(),
        ),
        (
            "pilotnet",
            SutConfig::named("pilotnet", std::path::Path::new(".")).unwrap(),
        ),
        ("external", external),
    ] {
        let mut s = base.clone();
        s.set_sut(sut);
        let outcome = s.run(&a, 0).unwrap();
        let simulated = outcome
            .metrics
            .iter()
            .find(|(k, _)| *k == "simulated_s")
            .map(|(_, v)| *v);
        assert!(
            simulated > Some(14.9),
            "{name} ran its whole test: {simulated:?}"
        );
        group.bench_function(name, |b| b.iter(|| s.run(&a, 0).unwrap()));
    }
    group.finish();
}

/// One test on each of three maps, for two horizons (see the module's documentation).
fn maps(c: &mut Criterion) {
    let mut group = c.benchmark_group("maps");
    group.sample_size(20);
    for (name, file, road) in [
        ("segment", "", ""),
        ("straight_500m", "esmini/straight_500m.xodr", "1"),
        ("town07", "carla/Town07.xodr", "0"),
        (
            "multi_intersections",
            "esmini/multi_intersections.xodr",
            "196",
        ),
    ] {
        for horizon in ["0.1", "15.0"] {
            // Paths in a program given as text are relative to the current folder: the
            // bench runs in `scenarios/`.
            // The segment is paracosm's own straight road, for the baseline.
            let (road_line, loc) = if file.is_empty() {
                (
                    "m = RoadSegment(len = 500.0, nlanes = 2)".to_string(),
                    "m.onLane(1, 5.0)".to_string(),
                )
            } else {
                (
                    format!("m = OpenDrive(\"../tests/data/maps/{file}\")"),
                    format!("m.onLane(road = \"{road}\", lane = -1, s = 5.0)"),
                )
            };
            let text = format!(
                "speed = VarInterval(5.0, 12.0, unit = \"m/s\")\n\
                 w = World(light = 0.5, fog = 0.0)\n\
                 {road_line}\n\
                 v = AutonomousVehicle(loc = {loc}, sut = \"aeb\", speed = speed)\n\
                 w.place(m, v)\n\
                 CollisionMonitor(v)\n\
                 test(horizon = {horizon})\n"
            );
            let s = lang::load_source(&format!("{name}.star"), &text, name).unwrap();
            let a = s
                .space()
                .decode(&Point {
                    discrete: vec![],
                    continuous: vec![0.5],
                })
                .unwrap();
            assert!(s.run(&a, 0).unwrap().passed(), "{name} {horizon}");
            group.bench_function(format!("{name}_{horizon}s"), |b| {
                b.iter(|| s.run(&a, 0).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
