//! One test's closed-loop simulation of `pedestrian-crossing` (physics, lidar, `aeb`,
//! monitors): a safe run that lasts the full 15 s horizon, and a collision that ends early.

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_generators::Point;
use paracosm_scenarios::reference::scenario;

fn bench(c: &mut Criterion) {
    let s = scenario();
    let mut group = c.benchmark_group("pedestrian_crossing");
    // (walking speed, trigger distance) in unit coordinates.
    for (name, u) in [("safe_15s", [0.05, 0.9]), ("collision", [0.26, 0.09])] {
        let a = s
            .space
            .decode(&Point {
                discrete: vec![],
                continuous: u.to_vec(),
            })
            .unwrap();
        let expected_pass = name == "safe_15s";
        assert_eq!(s.run(&a, 0).unwrap().passed(), expected_pass, "{name}");
        group.bench_function(name, |b| b.iter(|| s.run(&a, 0).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
