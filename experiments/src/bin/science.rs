//! `science`: the coverage science of PARACOSM §3 measured (docs/coverage-science.md).
//!
//! - `science prop32 [--seeds 4000]`: Proposition 3.2's bound against the empirical cover time of
//!   random k-wise families, 12 models × δ ∈ {0.1, 0.05, 0.01};
//! - `science dispersion [--dims 2,3,4]`: dispersion and star discrepancy against n for
//!   random (3 seeds), Halton and Sobol points and the continuous half of an IPOG (2, ε)-covering
//!   suite (its worst row), n = 64 … 16,384, with fitted log–log slopes.
//!
//! `cargo run --release -p paracosm-experiments --bin science -- prop32`

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Parser, Subcommand};
use paracosm_experiments::science::{
    log_plot, log_slope, measure, prop32_models, prop32_study, Sampler,
};

/// Measure what the paper's coverage propositions say.
#[derive(Debug, Parser)]
#[command(name = "science")]
struct Cli {
    #[command(subcommand)]
    what: What,
    /// Output folder.
    #[arg(long, default_value = "experiments/out/science", global = true)]
    out: PathBuf,
}

#[derive(Debug, Subcommand)]
enum What {
    /// Proposition 3.2: the bound against the empirical cover time.
    Prop32 {
        /// Seeds per model (at least 200 for the 1 % quantile to mean something).
        #[arg(long, default_value_t = 4000, value_parser = paracosm::cli::positive)]
        seeds: u64,
    },
    /// Dispersion and star discrepancy against n, with fitted slopes.
    Dispersion {
        /// Dimensions, comma-separated.
        #[arg(long, default_value = "2,3,4", value_delimiter = ',')]
        dims: Vec<usize>,
        /// Largest n per dimension d = 2, 3, 4 (powers of 4 from 64 up to it).
        #[arg(long, default_value = "16384,16384,16384", value_delimiter = ',')]
        max_n: Vec<usize>,
    },
}

/// The 95 % Wilson score interval of a proportion `p` observed over `n` trials.
fn wilson(p: f64, n: f64) -> (f64, f64) {
    paracosm_experiments::wilson95((p * n).round() as u64, n as u64)
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    std::fs::create_dir_all(&cli.out)?;
    match cli.what {
        What::Prop32 { seeds } => prop32(&cli.out, seeds),
        What::Dispersion { dims, max_n } => dispersion_study(&cli.out, &dims, &max_n),
    }
}

/// `science prop32`: the table on standard output and in `prop32.md`, the CDF plot.
fn prop32(out: &Path, seeds: u64) -> Result<()> {
    let deltas = [0.1, 0.05, 0.01];
    let (rows, plots) = prop32_study(&prop32_models(), &deltas, seeds, out)?;
    let mut t = String::from(
        "| model | δ | bound m(δ) | empirical (1 − δ)-quantile | bound / quantile | share of seeds above the bound [95 % Wilson interval] |\n|---|---:|---:|---:|---:|---:|\n",
    );
    for r in &rows {
        let (lo, hi) = wilson(r.miss_rate, r.seeds as f64);
        writeln!(
            t,
            "| {} | {} | {} | {:.1} | {:.2} | {:.4} [{lo:.4}, {hi:.4}] |",
            r.model,
            r.delta,
            r.bound,
            r.quantile,
            r.bound as f64 / r.quantile,
            r.miss_rate
        )?;
    }
    std::fs::write(out.join("prop32.md"), &t)?;
    print!("{t}");
    for p in plots {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// `science dispersion`: the tables on standard output and in `dispersion.md`, the values in
/// `dispersion.csv`, one plot per dimension and quantity.
fn dispersion_study(out: &Path, dims: &[usize], max_n: &[usize]) -> Result<()> {
    let mut csv =
        String::from("sampler,d,n,dispersion_lower,dispersion_upper,star_lower,star_upper\n");
    let mut table = String::from(
        "| d | sampler | n | dispersion | n · dispersion | star discrepancy |\n|---:|---|---:|---:|---:|---:|\n",
    );
    let mut slopes = String::from(
        "| d | sampler | dispersion slope (exact points) | its reference: ln n / n (random), 1/n (QMC and suite, Prop. 3.3) | star discrepancy slope (exact points) | its reference: n^(-1/2) (random), (ln n)^d / n (QMC and suite) |\n|---:|---|---:|---:|---:|---:|\n",
    );
    let mut plots = Vec::new();
    for &d in dims {
        let mut disp_series = Vec::new();
        let mut star_series = Vec::new();
        let top = max_n.get(d.saturating_sub(2)).copied().unwrap_or(1024);
        let ns: Vec<usize> = (0..)
            .map(|k| 64usize << (2 * k))
            .take_while(|&n| n <= top)
            .collect();
        for sampler in [
            Sampler::Random(0),
            Sampler::Halton,
            Sampler::Sobol,
            Sampler::Suite,
        ] {
            let seeds: Vec<Sampler> = match sampler {
                Sampler::Random(_) => (0..3).map(Sampler::Random).collect(),
                s => vec![s],
            };
            let (disp_pts, star_pts) =
                measure_sizes(&seeds, sampler, d, &ns, &mut csv, &mut table)?;
            let fit = |p: &[(f64, f64)]| {
                if p.len() >= 2 {
                    format!("{:.3}", log_slope(p))
                } else {
                    "–".into()
                }
            };
            let random = matches!(sampler, Sampler::Random(_));
            let disp_ref: Vec<(f64, f64)> = disp_pts
                .iter()
                .map(|&(n, _)| (n, if random { n.ln() / n } else { 1.0 / n }))
                .collect();
            let star_ref: Vec<(f64, f64)> = star_pts
                .iter()
                .map(|&(n, _)| {
                    (
                        n,
                        if random {
                            n.powf(-0.5)
                        } else {
                            n.ln().powi(d as i32) / n
                        },
                    )
                })
                .collect();
            writeln!(
                slopes,
                "| {d} | {} | {} ({} points) | {} | {} ({} points) | {} |",
                sampler.name(),
                fit(&disp_pts),
                disp_pts.len(),
                fit(&disp_ref),
                fit(&star_pts),
                star_pts.len(),
                fit(&star_ref)
            )?;
            disp_series.push((sampler.name().to_owned(), disp_pts));
            star_series.push((sampler.name().to_owned(), star_pts));
            eprintln!("d = {d}: {} done", sampler.name());
        }
        disp_series.retain(|(_, p)| p.len() >= 2);
        star_series.retain(|(_, p)| p.len() >= 2);
        if !disp_series.is_empty() {
            plots.extend(log_plot(
                &out.join(format!("dispersion_d{d}")),
                &format!("Dispersion against n, d = {d} (exact values)"),
                "log10 dispersion",
                &disp_series,
            )?);
        }
        if !star_series.is_empty() {
            plots.extend(log_plot(
                &out.join(format!("star_discrepancy_d{d}")),
                &format!("Star discrepancy against n, d = {d} (exact values)"),
                "log10 star discrepancy",
                &star_series,
            )?);
        }
    }
    std::fs::write(out.join("dispersion.csv"), &csv)?;
    let text = format!("{table}\n{slopes}");
    std::fs::write(out.join("dispersion.md"), &text)?;
    print!("{text}");
    for p in plots {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// `(n, value)` pairs of one quantity.
type Pairs = Vec<(f64, f64)>;

/// The exact or bracketed values of `seeds` (one sampler; random's 3 seeds averaged
/// geometrically) at each of `ns` in `d` dimensions, written to `csv` and `table`; returns the
/// exact `(n, dispersion)` and `(n, star discrepancy)` pairs.
fn measure_sizes(
    seeds: &[Sampler],
    sampler: Sampler,
    d: usize,
    ns: &[usize],
    csv: &mut String,
    table: &mut String,
) -> Result<(Pairs, Pairs)> {
    // Exact dispersion as far as it runs in a minute or so; star discrepancy exact in
    // d <= 2 (O(n²)), d = 3 to n = 16,384 (the sweep, O(n^{5/2}): 16,384 points in about
    // 2.5 minutes and 5 GB) and d = 4 to 1,024 (the prefix sweeps, O(n^{7/2}): about 3
    // minutes), bracketed beyond.
    let dispersion_exact = [16_384, 4_096, 120, 60];
    let star_exact = [usize::MAX, 20_000, 16_384, 1_024];
    let mut disp_pts = Vec::new();
    let mut star_pts = Vec::new();
    for &n in ns {
        // Random: the geometric mean over 3 seeds.
        let ms: Vec<_> = seeds
            .iter()
            .map(|&s| measure(s, d, n, &dispersion_exact, star_exact))
            .collect::<std::result::Result<_, _>>()?;
        let gm = |f: &dyn Fn(&paracosm_experiments::science::Measure) -> f64| {
            (ms.iter().map(|m| f(m).ln()).sum::<f64>() / ms.len() as f64).exp()
        };
        let (dl, du) = (gm(&|m| m.dispersion.0), gm(&|m| m.dispersion.1));
        let (sl, su) = (gm(&|m| m.star.0), gm(&|m| m.star.1));
        for m in &ms {
            writeln!(
                csv,
                "{},{d},{n},{:e},{:e},{:e},{:e}",
                m.sampler, m.dispersion.0, m.dispersion.1, m.star.0, m.star.1
            )?;
        }
        // A bracket with how far it can be from the exact value.
        let show = |l: f64, u: f64| {
            if l == u {
                format!("{l:.3e}")
            } else {
                format!("[{l:.2e}, {u:.2e}] (×{:.1})", u / l)
            }
        };
        // A suite uses rows × points per row, at most n.
        let n = ms[0].n;
        // n · dispersion of a bracket: at most n times its upper end.
        let scaled = if dl == du {
            format!("{:.2}", n as f64 * du)
        } else {
            format!("≤ {:.2}", n as f64 * du)
        };
        writeln!(
            table,
            "| {d} | {} | {n} | {} | {scaled} | {} |",
            sampler.name(),
            show(dl, du),
            show(sl, su)
        )?;
        if dl == du {
            disp_pts.push((n as f64, du));
        }
        if sl == su {
            star_pts.push((n as f64, su));
        }
    }
    Ok((disp_pts, star_pts))
}
