//! `fig10`: the paper's Figure 10 studies with learned drivers (docs/experiments.md,
//! "Figure 10").
//!
//! `cargo run --release -p paracosm-experiments --bin fig10 -- --docs docs`

use std::path::PathBuf;

use anyhow::Result;
use clap::Parser;
use paracosm_experiments::figure10::{self, LOOP_TIMEOUT_S};

/// Reproduce PARACOSM Figure 10a, 10b and 10c with the networks of `experiments/models/`.
#[derive(Debug, Parser)]
#[command(name = "fig10")]
struct Cli {
    /// Which studies: a (light × fog), b (200 s loop against fog), c (3-D components).
    #[arg(long, default_value = "abc")]
    parts: String,
    /// Halton tests of Figure 10a.
    #[arg(long, default_value_t = 1000, value_parser = paracosm::cli::positive)]
    budget_a: u64,
    /// Halton tests of Figure 10b.
    #[arg(long, default_value_t = 400, value_parser = paracosm::cli::positive)]
    budget_b: u64,
    /// Halton tests of Figure 10c's sweep over lead speeds and gaps.
    #[arg(long, default_value_t = 200, value_parser = paracosm::cli::positive)]
    budget_c: u64,
    /// Figure 10b with this ONNX network (its manifest beside it) instead of the shipped
    /// experiments/models/loop.onnx, e.g. one of another training seed.
    #[arg(long, value_name = "MODEL.onnx")]
    loop_onnx: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output folder; each study writes to OUT/fig10{a,b,c}/.
    #[arg(long, default_value = "experiments/out")]
    out: PathBuf,
    /// Also copy each figure's PNG into this folder (as fig10a_follow.png, fig10b_loop.png,
    /// fig10c_follow.png).
    #[arg(long)]
    docs: Option<PathBuf>,
}

/// Whether a Figure 10a test lies in a region of light × fog.
type Region = fn(&figure10::LightFogTest) -> bool;

/// `[lo, hi)` bands of width `step` over `[0, 1]`, the last one closed.
fn band(x: f64, step: f64) -> usize {
    ((x / step) as usize).min((1.0 / step).round() as usize - 1)
}

/// Figure 10b by fog band: how many tests left the road, how many stayed on it short of 1,000 m (stopped or crawled), how many
/// drove the whole 200 s (with a 95 % Wilson interval), and the median time to failure of
/// those that left the road.
fn loop_bands(tests: &[figure10::LoopTest]) {
    let edges = [0.0, 0.025, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5, 1.0];
    println!("| fog | tests | drove 200 s (95 % interval) | left the road | median time to leaving | on the road, short of 1,000 m |");
    println!("|---|---|---|---|---|---|");
    for w in edges.windows(2) {
        let last = w[1] >= 1.0;
        let band: Vec<_> = tests
            .iter()
            .filter(|t| t.fog >= w[0] && (t.fog < w[1] || (last && t.fog <= w[1])))
            .collect();
        let mut left: Vec<f64> = band.iter().filter_map(|t| t.time_to_failure_s).collect();
        left.sort_by(f64::total_cmp);
        let drove = band
            .iter()
            .filter(|t| {
                t.time_to_failure_s.is_none() && t.distance_m >= figure10::LOOP_MIN_DISTANCE_M
            })
            .count();
        let stopped = band.len() - drove - left.len();
        let (lo, hi) = paracosm_experiments::wilson95(drove as u64, band.len() as u64);
        let median = match left.len() {
            0 => "–".to_owned(),
            n if n % 2 == 1 => format!("{:.1} s", left[n / 2]),
            n => format!("{:.1} s", 0.5 * (left[n / 2 - 1] + left[n / 2])),
        };
        println!(
            "| {}–{} | {} | {drove} ({:.0}–{:.0} %) | {} | {median} | {stopped} |",
            w[0],
            w[1],
            band.len(),
            100.0 * lo,
            100.0 * hi,
            left.len()
        );
    }
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let jobs = paracosm_experiments::jobs_or_all_cores(cli.jobs);
    let copy = |from: &PathBuf, name: &str| -> Result<()> {
        if let Some(docs) = &cli.docs {
            paracosm::atomic::write(&docs.join(name), &std::fs::read(from)?)?;
        }
        Ok(())
    };
    if cli.parts.contains('a') {
        figure_a(&cli, jobs, &copy)?;
    }
    if cli.parts.contains('b') {
        figure_b(&cli, jobs, &copy)?;
    }
    if cli.parts.contains('c') {
        figure_c(&cli, jobs, &copy)?;
    }
    Ok(())
}

/// Figure 10a: collisions and distance covered by light × fog band, then the collision
/// rates with intervals in three regions.
fn figure_a(cli: &Cli, jobs: usize, copy: &dyn Fn(&PathBuf, &str) -> Result<()>) -> Result<()> {
    let f = figure10::figure10a(cli.budget_a, jobs, &cli.out.join("fig10a"))?;
    copy(&f.plots[0], "fig10a_follow.png")?;
    println!(
        "Figure 10a: {} tests ({} in error), {} collisions; wrote {}",
        f.tests.len(),
        f.errors,
        f.tests.iter().filter(|t| t.collision).count(),
        f.plots[0].display()
    );
    println!("collisions / tests and mean distance covered (m), light (columns) × fog (rows):");
    println!("| fog \\ light | 0–0.2 | 0.2–0.4 | 0.4–0.6 | 0.6–0.8 | 0.8–1 |");
    println!("|---|---|---|---|---|---|");
    for fb in 0..4 {
        let mut row = format!("| {:.2}–{:.2} |", fb as f64 * 0.25, fb as f64 * 0.25 + 0.25);
        for lb in 0..5 {
            let cell: Vec<_> = f
                .tests
                .iter()
                .filter(|t| band(t.fog, 0.25) == fb && band(t.light, 0.2) == lb)
                .collect();
            let hits = cell.iter().filter(|t| t.collision).count();
            let mean = cell.iter().map(|t| t.distance_m).sum::<f64>() / cell.len().max(1) as f64;
            row.push_str(&format!(" {hits}/{}, {mean:.1} m |", cell.len()));
        }
        println!("{row}");
    }
    // The paper's finding ("the car performs best around the parameter values used
    // during training"), with 95 % Wilson intervals over three regions.
    let regions: [(&str, Region); 3] = [
        ("light 0.4–0.6, fog < 0.25 (around training)", |t| {
            (0.4..0.6).contains(&t.light) && t.fog < 0.25
        }),
        ("light < 0.4 or ≥ 0.6, fog < 0.25", |t| {
            !(0.4..0.6).contains(&t.light) && t.fog < 0.25
        }),
        ("fog ≥ 0.25", |t| t.fog >= 0.25),
    ];
    for (name, inside) in regions {
        let n = f.tests.iter().filter(|t| inside(t)).count() as u64;
        let k = f.tests.iter().filter(|t| inside(t) && t.collision).count() as u64;
        let (lo, hi) = paracosm_experiments::wilson95(k, n);
        println!(
            "  {name}: {k} of {n} collide ({:.1} %, 95 % interval {:.1}–{:.1} %)",
            100.0 * k as f64 / n.max(1) as f64,
            100.0 * lo,
            100.0 * hi
        );
    }
    Ok(())
}

/// Figure 10b: the tests by fog band, then each test's fate in order of fog.
fn figure_b(cli: &Cli, jobs: usize, copy: &dyn Fn(&PathBuf, &str) -> Result<()>) -> Result<()> {
    let f = figure10::figure10b(
        cli.budget_b,
        jobs,
        &cli.out.join("fig10b"),
        cli.loop_onnx.as_deref(),
    )?;
    copy(&f.plots[0], "fig10b_loop.png")?;
    let failed = f
        .tests
        .iter()
        .filter(|t| t.time_to_failure_s.is_some())
        .count();
    println!(
        "Figure 10b: {} tests ({} in error), {failed} left the road within {LOOP_TIMEOUT_S} s; \
         wrote {}",
        f.tests.len(),
        f.errors,
        f.plots[0].display()
    );
    loop_bands(&f.tests);
    let mut sorted = f.tests.clone();
    sorted.sort_by(|a, b| a.fog.total_cmp(&b.fog));
    for t in &sorted {
        match t.time_to_failure_s {
            Some(s) => println!(
                "  fog {:.3}: left the road at {s:.1} s after {:.0} m",
                t.fog, t.distance_m
            ),
            None => println!(
                "  fog {:.3}: on the road at {LOOP_TIMEOUT_S} s after {:.0} m",
                t.fog, t.distance_m
            ),
        }
    }
    Ok(())
}

/// Figure 10c: the four single runs with their speeds, then the sweep over lead speeds and
/// gaps with rates and intervals.
fn figure_c(cli: &Cli, jobs: usize, copy: &dyn Fn(&PathBuf, &str) -> Result<()>) -> Result<()> {
    let f = figure10::figure10c(&cli.out.join("fig10c"))?;
    copy(&f.plots[0], "fig10c_follow.png")?;
    println!("Figure 10c: wrote {}", f.plots[0].display());
    for c in &f.cases {
        let at = |t: f64| {
            c.speed
                .iter()
                .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
                .map_or(f64::NAN, |p| p.1)
        };
        let low = c.speed.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        println!(
            "  {}: speed at 5/10/15/20 s {:.1}/{:.1}/{:.1}/{:.1} m/s, lowest {low:.1} m/s",
            c.name,
            at(5.0),
            at(10.0),
            at(15.0),
            at(20.0)
        );
    }
    let (cases, errors) =
        figure10::figure10c_sweep(cli.budget_c, jobs, &cli.out.join("fig10c-sweep"))?;
    println!(
        "Figure 10c over {} Halton tests (lead speed 3-8 m/s, gap 15-40 m; {errors} in error):",
        cli.budget_c
    );
    for c in &cases {
        let (cl, ch) = paracosm_experiments::wilson95(c.collisions, c.tests);
        let (bl, bh) = paracosm_experiments::wilson95(c.fell_behind, c.tests);
        println!(
            "- {} lead{}: {} tests, {} collisions ({:.1}-{:.1} %), {} fell behind \
             ({:.1}-{:.1} %), mean distance {:.1} m",
            c.lead_color,
            if c.oncoming { ", oncoming red car" } else { "" },
            c.tests,
            c.collisions,
            100.0 * cl,
            100.0 * ch,
            c.fell_behind,
            100.0 * bl,
            100.0 * bh,
            c.mean_distance_m
        );
    }
    Ok(())
}
