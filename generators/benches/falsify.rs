//! Overhead of the falsifiers: 1,000 ask/tell round trips on a free cost function (the
//! distance to a point), so what is measured is the search and its channels, not a
//! simulation.

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_generators::{ParamSpace, Point, Strategy};

fn bench(c: &mut Criterion) {
    let space = ParamSpace::unit_cube(4);
    let cost = |p: &Point| p.continuous.iter().map(|x| (x - 0.3).powi(2)).sum::<f64>();
    let mut group = c.benchmark_group("falsify_1000_evaluations_4d");
    group.sample_size(20);
    for s in Strategy::FALSIFIERS {
        group.bench_function(s.name(), |b| {
            b.iter(|| {
                let mut g = s.build(&space, 1).unwrap();
                let batch = g.batch().unwrap();
                let mut n = 0;
                while n < 1000 {
                    let pts = g.ask(batch.min(1000 - n)).unwrap();
                    let told: Vec<(Point, f64)> =
                        pts.iter().map(|p| (p.clone(), cost(p))).collect();
                    g.tell(&told);
                    n += pts.len();
                }
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
