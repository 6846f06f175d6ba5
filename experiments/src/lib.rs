//! Reproductions of the PARACOSM paper's figures and sampler comparisons. Outputs go to
//! `experiments/out/` by default.
//!
//! - [`figure9`]: the pedestrian-crossing failure map under random and Halton sampling, side
//!   by side (paper §4.2.2, Figure 9).
//! - [`falsification::falsification_study`]: simulations until the first failure, random and
//!   quasi-random sampling against the adaptive falsifiers.
//! - [`figure10`]: the paper's Figure 10 studies with learned drivers: light × fog, a 200 s
//!   loop against fog, and other 3-D components (§4.2.2).
//! - [`perception`]: the road-segmentation and vehicle-detection networks of the paper's
//!   §4.1 studies (Figures 5–8), their training ([`perception::train`]) and the studies
//!   ([`perception::studies`]).
//! - [`pilotnet_training`]: training the PilotNet-style driver ([`pilotnet`]) on recorded
//!   drives, with early stopping in closed loop.
//! - [`science`]: the coverage propositions of §3 measured (Proposition 3.2's bound, dispersion
//!   and star discrepancy against n).
#![warn(missing_docs)]

pub mod falsification;
pub mod figure10;
pub mod onnx_export;
pub mod perception;
pub mod pilotnet;
pub mod pilotnet_training;
pub mod science;
pub mod training_error;
pub mod weights;

pub use training_error::TrainingError;

use std::path::{Path, PathBuf};

use paracosm::Error;

/// What the experiments return: the root library's typed error.
pub type Result<T> = std::result::Result<T, Error>;
use paracosm::{Campaign, RunRecord};
use paracosm_generators::Strategy;

/// Worker threads: `jobs`, or every core when `None`; at least 1.
pub fn jobs_or_all_cores(jobs: Option<usize>) -> usize {
    jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1)
}

/// The 95 % Wilson score interval `[lo, hi]` ⊂ `[0, 1]` of a proportion observed as
/// `successes` of `n` trials (Wilson 1927; Agresti & Coull 1998). `n = 0` gives `[0, 1]`.
pub fn wilson95(successes: u64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (p, n) = (successes as f64 / n as f64, n as f64);
    let z = 1.959_964_f64;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / (1.0 + z * z / n);
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// The collision rate of the tests whose parameter lies in one band `[lo, hi)` (the last
/// band closed), with its 95 % Wilson interval ([`wilson95`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Lower end, in the parameter's unit.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Tests whose parameter lies in the band.
    pub tests: u64,
    /// Of them, tests whose `collision` monitor failed.
    pub collisions: u64,
    /// 95 % Wilson interval of `collisions / tests`, in `[0, 1]`.
    pub ci95: (f64, f64),
}

/// Splits `[lo, hi]` into `bands` equal bands of the real parameter `param` and counts, in
/// each, the tests of `records` and those whose `collision` monitor failed. Records without
/// the parameter (an error before the point was decoded) are left out.
pub fn collisions_by_band(
    records: &[RunRecord],
    param: &str,
    (lo, hi): (f64, f64),
    bands: usize,
) -> Vec<Band> {
    let bands = bands.max(1);
    let width = (hi - lo) / bands as f64;
    let mut counts = vec![(0u64, 0u64); bands];
    for r in records {
        let Some(x) = r.params.as_ref().and_then(|a| a.real(param)) else {
            continue;
        };
        let i = (((x - lo) / width).floor().max(0.0) as usize).min(bands - 1);
        counts[i].0 += 1;
        counts[i].1 += u64::from(
            r.monitors
                .iter()
                .any(|(name, m)| name == "collision" && !m.passed),
        );
    }
    counts
        .into_iter()
        .enumerate()
        .map(|(i, (tests, collisions))| Band {
            lo: lo + width * i as f64,
            hi: lo + width * (i + 1) as f64,
            tests,
            collisions,
            ci95: wilson95(collisions, tests),
        })
        .collect()
}

/// What [`figure9`] measured and wrote.
#[derive(Debug, Clone)]
pub struct Figure9 {
    /// Failed tests under random sampling (any monitor).
    pub random_failures: u64,
    /// Failed tests under Halton sampling (any monitor).
    pub halton_failures: u64,
    /// Exact dispersion (largest empty axis-aligned box, §3) of the random and the Halton
    /// points in the unit square.
    pub dispersion: [f64; 2],
    /// The PNG and SVG of the two-panel map.
    pub plots: [PathBuf; 2],
    /// The paper's finding put to the test ("the faster the pedestrian is, the more
    /// collisions there are", §4.2.2): the collision rate over both campaigns' tests in five
    /// bands of walking speed, 0.5–10 m/s ([`collisions_by_band`]).
    pub by_speed: Vec<Band>,
}

/// Runs `pedestrian-crossing` with `budget` tests under random sampling (seed `seed`) and
/// under Halton, writes each campaign's `results.jsonl` to `out/fig9/{random,halton}/`, and
/// draws both failure maps side by side into `out/fig9/figure9.{png,svg}`.
///
/// # Errors
/// When a campaign or a plot cannot be written.
pub fn figure9(budget: u64, seed: u64, jobs: usize, out: &Path) -> Result<Figure9> {
    figure9_with(budget, seed, jobs, &out.join("fig9"), None)
}

/// As [`figure9`], into `dir`, with `sut` instead of the scenario's `aeb` (e.g. the shipped
/// `pilotnet`: docs/experiments.md, "Learned drivers").
///
/// # Errors
/// When a campaign or a plot cannot be written.
pub fn figure9_with(
    budget: u64,
    seed: u64,
    jobs: usize,
    dir: &Path,
    sut: Option<paracosm_engine::sut::SutConfig>,
) -> Result<Figure9> {
    let mut scenario = paracosm_scenarios::builtin("pedestrian-crossing")?;
    if let Some(sut) = sut {
        scenario.set_sut(sut);
    }
    let mut runs: Vec<(String, Vec<RunRecord>, u64)> = Vec::new();
    let mut dispersion = [0.0; 2];
    for strategy in [Strategy::Random, Strategy::Halton] {
        let campaign = Campaign {
            scenario: &scenario,
            strategy,
            seed,
            budget,
            strength: 2,
            jobs,
            stop_at_first_failure: false,
            points: None,
            trace: None,
        };
        let report = campaign.run(&dir.join(strategy.name()), |_| {})?;
        let flat: Vec<f64> = report
            .records
            .iter()
            .flat_map(|r| r.point.continuous.iter().copied())
            .collect();
        let d = paracosm_generators::coverage::dispersion(
            &flat,
            2,
            &paracosm_generators::coverage::DispersionOptions::default(),
        )
        .map_err(|e| Error::Internal(e.to_string()))?;
        dispersion[runs.len()] = d.lower;
        let collisions = report
            .records
            .iter()
            .filter(|r| {
                r.monitors
                    .iter()
                    .any(|(name, m)| name == "collision" && !m.passed)
            })
            .count();
        let title = format!(
            "{strategy}: {budget} tests, {} failed ({collisions} collisions), dispersion {:.4}",
            report.counts.fail, d.lower
        );
        runs.push((title, report.records, report.counts.fail));
    }
    let panels: Vec<(&str, &[RunRecord])> = runs
        .iter()
        .map(|(t, r, _)| (t.as_str(), r.as_slice()))
        .collect();
    let plots = paracosm::report::plot::failure_map(
        &dir.join("figure9"),
        scenario.space(),
        scenario.map_axes(),
        &panels,
        paracosm::report::plot::Coloring::Outcome,
    )?;
    let all: Vec<RunRecord> = runs
        .iter()
        .flat_map(|(_, r, _)| r.iter().cloned())
        .collect();
    Ok(Figure9 {
        random_failures: runs[0].2,
        halton_failures: runs[1].2,
        dispersion,
        plots,
        by_speed: collisions_by_band(&all, "walking_speed", (0.5, 10.0), 5),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figure9_writes_both_campaigns_and_the_two_panel_map() {
        let dir = tempfile::tempdir().unwrap();
        let f = figure9(30, 3, 2, dir.path()).unwrap();
        for s in ["random", "halton"] {
            let lines =
                std::fs::read_to_string(dir.path().join("fig9").join(s).join("results.jsonl"))
                    .unwrap()
                    .lines()
                    .count();
            assert_eq!(lines, 30);
        }
        assert!(f.random_failures <= 30 && f.halton_failures <= 30);
        assert!(std::fs::metadata(&f.plots[0]).unwrap().len() > 5_000);
        let svg = std::fs::read_to_string(&f.plots[1]).unwrap();
        assert!(svg.contains("random: 30 tests") && svg.contains("halton: 30 tests"));
        // The speed bands count every test once, and their collisions are the campaigns'.
        assert_eq!(f.by_speed.len(), 5);
        assert_eq!(f.by_speed.iter().map(|b| b.tests).sum::<u64>(), 60);
        let mut hits = 0u64;
        for s in ["random", "halton"] {
            let text =
                std::fs::read_to_string(dir.path().join("fig9").join(s).join("results.jsonl"))
                    .unwrap();
            for line in text.lines() {
                let r: serde_json::Value = serde_json::from_str(line).unwrap();
                hits += u64::from(r["monitors"]["collision"]["passed"] == false);
            }
        }
        assert_eq!(f.by_speed.iter().map(|b| b.collisions).sum::<u64>(), hits);
    }

    #[test]
    fn wilson_intervals_match_published_values() {
        // Agresti & Coull (1998), and scipy's `binomtest(...).proportion_ci("wilson")`:
        // 0 of 10 gives [0, 0.2775]; 5 of 10 [0.2366, 0.7634]; 81 of 263 [0.2553, 0.3662].
        let close =
            |(a, b): (f64, f64), (c, d): (f64, f64)| (a - c).abs() < 1e-4 && (b - d).abs() < 1e-4;
        assert!(
            close(wilson95(0, 10), (0.0, 0.2775)),
            "{:?}",
            wilson95(0, 10)
        );
        assert!(
            close(wilson95(5, 10), (0.2366, 0.7634)),
            "{:?}",
            wilson95(5, 10)
        );
        assert!(
            close(wilson95(81, 263), (0.2553, 0.3662)),
            "{:?}",
            wilson95(81, 263)
        );
        assert_eq!(wilson95(0, 0), (0.0, 1.0));
    }
}
