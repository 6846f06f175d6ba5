//! The coverage estimators at the sizes issue 3 names: exact dispersion for d = 2 (n = 100,000)
//! and d = 3 (n = 1,000), the centered and wrap-around discrepancies (n = 4,000, d = 8), k-wise
//! coverage of 10,000 rows × 50 binary parameters at t = 3, the star discrepancy (d = 2,
//! n = 2,000; d = 3, n = 1,000), and the scrambled Halton sequence (2^16 points, d = 8).

use criterion::{criterion_group, criterion_main, Criterion};
use paracosm_generators::coverage::{
    discrepancy, dispersion, kwise_coverage_rows, star_discrepancy, Discrepancy, DispersionOptions,
    StarOptions,
};
use paracosm_generators::{Halton, ParamSpace, Strategy};

fn unit(d: usize) -> ParamSpace {
    ParamSpace::unit_cube(d)
}

fn points(s: Strategy, n: usize, d: usize) -> Vec<f64> {
    s.build(&unit(d), 1)
        .unwrap()
        .ask(n)
        .unwrap()
        .into_iter()
        .flat_map(|p| p.continuous)
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("coverage");
    g.sample_size(10);
    let opts = DispersionOptions::default();
    for s in [Strategy::Random, Strategy::Halton] {
        let p2 = points(s, 100_000, 2);
        g.bench_function(format!("dispersion_d2_n100000_{s}"), |b| {
            b.iter(|| dispersion(&p2, 2, &opts).unwrap())
        });
        let p3 = points(s, 1000, 3);
        g.bench_function(format!("dispersion_d3_n1000_{s}"), |b| {
            b.iter(|| dispersion(&p3, 3, &opts).unwrap())
        });
    }
    let x = points(Strategy::Random, 4000, 8);
    g.bench_function("cd_n4000_d8", |b| {
        b.iter(|| discrepancy(&x, 8, Discrepancy::Centered).unwrap())
    });
    g.bench_function("wd_n4000_d8", |b| {
        b.iter(|| discrepancy(&x, 8, Discrepancy::WrapAround).unwrap())
    });
    let rows: Vec<u32> = (0..10_000u64 * 50)
        .map(|i| ((i.wrapping_mul(2_654_435_761) >> 7) % 2) as u32)
        .collect();
    g.bench_function("kwise_10000x50_t3", |b| {
        b.iter(|| kwise_coverage_rows(&[2; 50], &rows, 3, 10).unwrap())
    });
    let s2 = points(Strategy::Halton, 2000, 2);
    g.bench_function("star_d2_n2000", |b| {
        b.iter(|| star_discrepancy(&s2, 2, &StarOptions::default()).unwrap())
    });
    // d = 3 by the sweep (star3d.rs): 1,000 points; `cargo run --release -p
    // paracosm-generators --example star3d -- N halton` times larger n.
    let s3 = points(Strategy::Halton, 1000, 3);
    g.bench_function("star_d3_n1000", |b| {
        b.iter(|| star_discrepancy(&s3, 3, &StarOptions::default()).unwrap())
    });
    // d = 4 by one scaled d = 3 sweep per prefix (star4d.rs): 256 points (`... --example star3d
    // -- N halton 4` times larger n).
    let s4 = points(Strategy::Halton, 256, 4);
    g.bench_function("star_d4_n256", |b| {
        b.iter(|| star_discrepancy(&s4, 4, &StarOptions::default()).unwrap())
    });
    let space8 = unit(8);
    g.bench_function("halton_scrambled_65536x8", |b| {
        b.iter(|| Halton::scrambled(&space8, 0).unit_points(0, 65_536))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
