//! Throughput of the generators: 10,000 points in 8 continuous dimensions.

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_generators::{ParamSpace, Strategy};

fn bench(c: &mut Criterion) {
    let space = ParamSpace::unit_cube(8);
    let mut group = c.benchmark_group("ask_10000x8");
    for s in Strategy::ALL {
        group.bench_function(s.name(), |b| {
            b.iter(|| s.build(&space, 1).unwrap().ask(10_000).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
