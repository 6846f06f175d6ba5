//! Where an OpenSCENARIO campaign's time goes, phase by phase ("OpenSCENARIO campaigns at the
//! speed of the closed loop", requirement 1), on three ALKS variation files (the crossing
//! pedestrian 4.2.3, the cut-in 4.4.1, free driving 4.1.1) and a chain of 100,000 events,
//! each test under `--scripted-ego`:
//!
//! - `load/NAME`: the campaign's load, `campaign_scenario` (the variation file, its template
//!   and catalogs read and checked, the space, every map a level chooses baked);
//! - `setup/NAME`: one test's setup, its values substituted into the scenario, its scene and
//!   world built and its `Simulation` made, without a step;
//! - `storyboard_1s/NAME`: the storyboard alone stepped over 1 s (60 steps of 1/60 s) from its
//!   start, at the template's default values;
//! - `test_1s/NAME`: the test's first second in the closed loop (60 `Simulation::step`s: the
//!   stream graph with the storyboard's host, the engine's actors and rapier); the engine's
//!   share is `test_1s` less `storyboard_1s`;
//! - `run/NAME`: one whole test as a campaign runs it (`Scenario::run`: the setup, every step
//!   to the storyboard's end or the horizon, the snapshot each step and the monitors): the
//!   marginal cost of a test without the campaign's records and reports;
//! - `map_bake/ring_10km` and `map_bake/ring_100km`: baking one road, an arc of 0.9 of a
//!   circle with a lane each way (`opendrive::import`), whose cost grows with the lanes' length.
//!
//! Run with `cargo bench -p paracosm-scenarios --bench xosc_phases`; docs/performance.md
//! ("Where an OpenSCENARIO test's time goes") has the table.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use paracosm_engine::network::roads::Roads;
use paracosm_engine::network::{opendrive, MapRef};
use paracosm_engine::{Control, Simulation};
use paracosm_generators::Point;
use paracosm_scenarios::xosc::story::Storyboard;
use paracosm_scenarios::xosc::{campaign_scenario, XoscRef};

mod common;

const DT: f64 = 1.0 / 60.0;

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/xosc")
}

/// The three ALKS cases: a name, the variation file, its template.
fn alks() -> Vec<(&'static str, PathBuf, PathBuf)> {
    let alks = data().join("alks");
    [
        ("crossing_pedestrian", "4_2_3_crossing_pedestrian"),
        ("cut_in", "4_4_1_cut_in_no_collision"),
        ("free_driving", "4_1_1_free_driving"),
    ]
    .into_iter()
    .map(|(name, stem)| {
        (
            name,
            alks.join(format!("alks_scenario_{stem}_variation.xosc")),
            alks.join(format!(
                "concrete_scenarios/alks_scenario_{stem}_template.xosc"
            )),
        )
    })
    .collect()
}

fn reference(xosc: &Path) -> XoscRef {
    XoscRef {
        xosc: xosc.display().to_string(),
        open: Vec::new(),
        continuous: false,
        scripted_ego: true,
        ego: None,
        ..XoscRef::default()
    }
}

/// The chain of 100,000 events, written beside a link to the shipped folders so that its
/// map's relative path reads.
fn chain_file() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("paracosm-bench-phases-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("written")).unwrap();
    let _ = std::fs::remove_file(dir.join("esmini"));
    std::os::unix::fs::symlink(data().join("esmini"), dir.join("esmini")).unwrap();
    let file = dir.join("written/chain.xosc");
    std::fs::write(&file, common::event_chain(100_000)).unwrap();
    file
}

/// A storyboard of `scenario` (a template or a scenario file) at its default values.
fn storyboard(scenario: &Path) -> Storyboard {
    let model = paracosm_openscenario::read_scenario(scenario, &[]).unwrap();
    let road = model.road_network.as_ref().unwrap();
    let text = std::fs::read_to_string(&road.item).unwrap();
    let map = MapRef::new(opendrive::import(&road.item, &text).unwrap().map);
    Storyboard::new(&model, Roads::new(&map), None).unwrap()
}

fn phases(c: &mut Criterion) {
    let chain = chain_file();
    let mut cases: Vec<(&str, PathBuf, PathBuf)> = alks();
    cases.push(("events_100000", chain.clone(), chain));
    let mut group = c.benchmark_group("xosc_phases");
    group.sample_size(10);
    for (name, variation, scenario) in &cases {
        let x = reference(variation);
        group.bench_function(format!("load/{name}"), |b| {
            b.iter(|| campaign_scenario(&x).unwrap())
        });
        let s = campaign_scenario(&x).unwrap();
        // The middle of the space: the middle level of each discrete parameter, the middle of
        // each interval.
        let middle = Point {
            discrete: s.space().level_counts().iter().map(|c| c / 2).collect(),
            continuous: vec![0.5; s.space().continuous_dims()],
        };
        let a = s.space().decode(&middle).unwrap();
        group.bench_function(format!("setup/{name}"), |b| {
            b.iter(|| {
                s.with_world(&a, &mut |spec, _| {
                    Simulation::new(spec).unwrap();
                })
                .unwrap()
            })
        });
        group.bench_function(format!("storyboard_1s/{name}"), |b| {
            b.iter_batched(
                || storyboard(scenario),
                |mut sb| {
                    for i in 0..60 {
                        sb.step(f64::from(i) * DT, DT).unwrap();
                    }
                    sb
                },
                BatchSize::PerIteration,
            )
        });
        group.bench_function(format!("test_1s/{name}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    s.with_world(&a, &mut |spec, host| {
                        let mut sim = Simulation::new(spec).unwrap();
                        let t0 = Instant::now();
                        for _ in 0..60 {
                            sim.step(Control::default(), host).unwrap();
                        }
                        total += t0.elapsed();
                    })
                    .unwrap();
                }
                total
            })
        });
        group.bench_function(format!("run/{name}"), |b| b.iter(|| s.run(&a, 0).unwrap()));
    }
    for km in [10, 100] {
        let text = common::ring_road(f64::from(km) * 1000.0);
        group.bench_function(format!("map_bake/ring_{km}km"), |b| {
            b.iter(|| opendrive::import("ring.xodr", &text).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, phases);
criterion_main!(benches);
