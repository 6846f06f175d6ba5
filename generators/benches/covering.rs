//! IPOG covering arrays: 5^10 at t = 3 and TCAS (2^7 3^2 4^1 10^2) at t = 4.

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_generators::covering::ipog;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("ipog");
    g.sample_size(10);
    g.bench_function("5^10_t3", |b| b.iter(|| ipog(&[5; 10], 3).unwrap()));
    let tcas = [2, 2, 2, 2, 2, 2, 2, 3, 3, 4, 10, 10];
    g.bench_function("tcas_t4", |b| b.iter(|| ipog(&tcas, 4).unwrap()));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
