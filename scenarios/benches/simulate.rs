//! One test's closed-loop simulation of the pedestrian-crossing study (physics, lidar, `aeb`,
//! monitors), written three ways: the Rust reference, `pedestrian_crossing.star` (native
//! trigger), and the same program with its trigger as a Starlark lambda called every step.
//! Issue 5 asks that per-step lambdas cost at most 2× the Rust version.
//!
//! `rapier_alone/lidar` is the same test's physics and lidar written with rapier only
//! (`engine/benches/rapier_alone.rs`): issue 23 asks that a whole test (`safe_15s/star`) cost
//! at most 1.2× that, measured in this one run.

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
                .space
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
}

criterion_group!(benches, bench);
criterion_main!(benches);
