//! paracosm's closed loop against rapier alone (issue 23), in one run:
//!
//! - `rapier_alone/no_lidar`, `rapier_alone/lidar`: the physics of one pedestrian-crossing test
//!   written with rapier only (`rapier_alone.rs`), without and with the 121-beam lidar;
//! - `paracosm_engine/aeb`: the same test in paracosm's engine: `WorldSpec::straight_road`,
//!   the built-in `aeb` system under test, a snapshot (what monitors read) every step.
//!
//! Both run the case of `scenarios/benches/simulate.rs`'s `safe_15s` (walking speed
//! 0.975 m/s, trigger distance 54.5 m): 900 steps, no contact. The ratio
//! `paracosm_engine/aeb / rapier_alone/lidar` is the engine's overhead over rapier with the
//! same sensor; issue 23 asks for at most 1.2.

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_engine::rx::NoHost;
use paracosm_engine::sut::{Aeb, AebConfig, Sut};
use paracosm_engine::{Lane, Simulation, TriggeredPedestrian, WorldSpec};

mod rapier_alone;

const WALK_MPS: f64 = 0.975;
const TRIGGER_M: f64 = 54.5;

/// One 15 s test in paracosm's engine; returns the ego's final x (m).
fn paracosm_test(spec: &WorldSpec) -> f64 {
    let mut sim = Simulation::new(spec).unwrap();
    let mut sut = Aeb::new(AebConfig::default());
    sut.reset(0).unwrap();
    let mut min_sep = f64::INFINITY;
    for _ in 0..900 {
        let control = sut.act(&sim.observation()).unwrap();
        sim.step(control, &mut NoHost).unwrap();
        min_sep = min_sep.min(sim.snapshot().min_separation_m);
    }
    assert!(min_sep > 0.0, "the safe case touched the pedestrian");
    sim.ego_state().pos_m[0]
}

fn bench(c: &mut Criterion) {
    let spec = WorldSpec::straight_road(
        200.0,
        10.0,
        AebConfig::default().cruise.target_speed_mps,
        &[TriggeredPedestrian {
            start: (Lane::SideWalk, 100.0),
            target: (Lane::OppositeSideWalk, 100.0),
            trigger_distance_m: TRIGGER_M,
            speed_mps: WALK_MPS,
        }],
    )
    .unwrap();
    let mut group = c.benchmark_group("baseline");
    group.bench_function("rapier_alone/no_lidar", |b| {
        b.iter(|| rapier_alone::run_test(WALK_MPS as f32, TRIGGER_M as f32, false))
    });
    group.bench_function("rapier_alone/lidar", |b| {
        b.iter(|| rapier_alone::run_test(WALK_MPS as f32, TRIGGER_M as f32, true))
    });
    group.bench_function("paracosm_engine/aeb", |b| b.iter(|| paracosm_test(&spec)));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
