//! Covering array sizes against the best known: IPOG, the algebraic construction the pass
//! starts from where it is smaller (`-` where none applies), then the annealing
//! post-optimisation, for uniform models `v^k` at strength `t`, each row with its wall time.
//!
//! `cargo run --release -p paracosm-generators --example covering_frontier -- SECONDS t:v:k ...`
//! (e.g. `30 2:3:10 3:5:10`): prints `t v k ipog construction optimised seconds`, one model per
//! line.

use std::time::Instant;

use paracosm_generators::covering::{construct, ipog, optimise, Constraints, Optimise};

fn main() {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args
        .next()
        .and_then(|s| s.parse().ok())
        .expect("first argument: seconds of optimisation");
    println!("t v k ipog construction optimised seconds");
    for model in args {
        let n: Vec<usize> = model
            .split(':')
            .map(|x| x.parse().expect("t:v:k"))
            .collect();
        let (t, v, k) = (n[0], n[1] as u32, n[2]);
        let levels = vec![v; k];
        let start = Instant::now();
        let a = ipog(&levels, t).expect("an IPOG array");
        let built = construct(v, k, t).map_or("-".to_owned(), |c| c.len().to_string());
        let b = optimise(
            &a,
            &Constraints::default(),
            0,
            Optimise::seconds(seconds, 1),
        );
        let raw = paracosm_generators::coverage::kwise_coverage_rows(&levels, &b.rows, t, 0)
            .expect("a coverage count");
        assert_eq!(
            raw.covered, raw.total,
            "the optimised array covers every tuple"
        );
        println!(
            "{t} {v} {k} {} {built} {} {:.1}",
            a.len(),
            b.len(),
            start.elapsed().as_secs_f64()
        );
    }
}
