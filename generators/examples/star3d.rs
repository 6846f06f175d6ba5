//! Times the exact star discrepancy in d = 3 (or the D given, 1 to 4) of the first N points
//! of a sampler:
//!
//! ```text
//! cargo run --release -p paracosm-generators --example star3d -- 10000 halton
//! cargo run --release -p paracosm-generators --example star3d -- 1024 halton 4
//! ```
//!
//! prints the value, whether it is exact, the seconds it took and the method.

use paracosm_generators::coverage::{star_discrepancy, StarOptions};
use paracosm_generators::{ParamSpace, Strategy};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: star3d N SAMPLER (random, halton, sobol) [D]";
    let n: usize = args.next().ok_or(usage)?.parse()?;
    let s: Strategy = args.next().ok_or(usage)?.parse()?;
    let d: usize = args.next().map_or(Ok(3), |a| a.parse())?;
    let pts: Vec<f64> = s
        .build(&ParamSpace::unit_cube(d), 1)?
        .ask(n)?
        .into_iter()
        .flat_map(|p| p.continuous)
        .collect();
    let t = std::time::Instant::now();
    let options = StarOptions {
        exact_max_points: [usize::MAX; 4],
        ..StarOptions::default()
    };
    let r = star_discrepancy(&pts, d, &options)?;
    println!(
        "n {n} {s}: D* {:.6e} exact {} in {:.2} s ({})",
        r.upper,
        r.exact,
        t.elapsed().as_secs_f64(),
        r.method
    );
    Ok(())
}
