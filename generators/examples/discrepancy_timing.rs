//! Times the discrepancies the way `paracosm-cover bench` does (a global pool of 2 threads,
//! called from outside it): the best of 7 runs after a warm-up, in ms, with each value and
//! its bits (to compare with scipy's). Needs only this crate, not the workspace.
//!
//! `cargo run --release -p paracosm-generators --example discrepancy_timing [FILE [D]]`:
//! FILE holds `n × D` little-endian f64 in `[0, 1]` (D = 8 by default), e.g. numpy's
//! `default_rng(0).random((4000, 8))` written with `tofile`; without FILE, 4000 × 8 uniform
//! points from a seeded ChaCha8. `KINDS=cd,wd` picks the discrepancies (default: cd, wd, md).

use std::time::Instant;

use paracosm_generators::coverage::{discrepancy, Discrepancy};
use rand::{Rng, SeedableRng};

fn main() {
    let mut args = std::env::args().skip(1);
    let file = args.next();
    let d: usize = args.next().map_or(8, |d| d.parse().expect("D, a number"));
    let x: Vec<f64> = match file {
        Some(path) => std::fs::read(path)
            .expect("the array file")
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect(),
        None => {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
            (0..4000 * d).map(|_| rng.random::<f64>()).collect()
        }
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build_global()
        .unwrap();
    let kinds: Vec<Discrepancy> = match std::env::var("KINDS") {
        Ok(k) => Discrepancy::ALL
            .into_iter()
            .filter(|d| k.split(',').any(|n| n == d.name()))
            .collect(),
        Err(_) => vec![
            Discrepancy::Centered,
            Discrepancy::WrapAround,
            Discrepancy::Mixture,
        ],
    };
    for kind in kinds {
        let value = discrepancy(&x, d, kind).unwrap();
        let mut best = f64::INFINITY;
        for _ in 0..7 {
            let t = Instant::now();
            let v = discrepancy(&x, d, kind).unwrap();
            best = best.min(t.elapsed().as_secs_f64() * 1e3);
            assert_eq!(v.to_bits(), value.to_bits());
        }
        println!(
            "{} {best:.2} ms value {value:e} bits {:#018x}",
            kind.name(),
            value.to_bits()
        );
    }
}
