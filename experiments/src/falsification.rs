//! The falsification study: simulations until the first failure, per strategy and scenario.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use paracosm::Error;

use crate::Result;
use paracosm::Campaign;
use paracosm_generators::Strategy;
use serde::Serialize;

/// One campaign of the study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// Built-in scenario name.
    pub scenario: String,
    /// Strategy name.
    pub strategy: String,
    /// Campaign seed.
    pub seed: u64,
    /// Simulations up to and including the first failed one (its id + 1); `None` when no
    /// test failed within the cap.
    pub sims_to_first_failure: Option<u64>,
}

/// What [`falsification_study`] measured and wrote.
#[derive(Debug, Clone)]
pub struct Study {
    /// Every campaign, in run order.
    pub trials: Vec<Trial>,
    /// The table of medians (Markdown), also written to `study.md`.
    pub table: String,
    /// The per-trial CSV, the table, and the box plot's PNG and SVG.
    pub files: Vec<PathBuf>,
}

/// The study's settings.
#[derive(Debug, Clone)]
pub struct StudySettings<'a> {
    /// Built-in scenario names.
    pub scenarios: &'a [&'a str],
    /// Strategies compared. Those that ignore the seed (plain Halton) run once.
    pub strategies: &'a [Strategy],
    /// Seeds `0..seeds` per strategy.
    pub seeds: u64,
    /// Most simulations per campaign; a campaign without a failure by then is censored.
    pub cap: u64,
    /// Worker threads per campaign. The results do not depend on it.
    pub jobs: usize,
}

/// Median of `v` (sorted copy; mean of the middle two for even lengths), `None` when empty.
pub fn median(v: &[f64]) -> Option<f64> {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(s[n / 2]),
        _ => Some((s[n / 2 - 1] + s[n / 2]) / 2.0),
    }
}

/// Name of the synthetic problem in [`falsification_study`]'s outputs.
pub const SYNTHETIC: &str = "synthetic-disc";

/// The centre of the synthetic failure disc of problem `seed`: uniform in `[0.1, 0.9)²`
/// (ChaCha8), so that a deterministic sampler such as Halton meets a new problem per seed.
pub fn synthetic_centre(seed: u64) -> [f64; 2] {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    [
        0.1 + 0.8 * rng.random::<f64>(),
        0.1 + 0.8 * rng.random::<f64>(),
    ]
}

/// Robustness of the synthetic problem at unit-square point `x`: the distance to a disc of
/// radius 0.03 around `centre`, negative inside. Failures cover π·0.03² ≈ 0.28 % of the
/// square, and the robustness slopes toward them everywhere: the case adaptive search is for.
pub fn synthetic_robustness(centre: [f64; 2], x: &[f64]) -> f64 {
    ((x[0] - centre[0]).powi(2) + (x[1] - centre[1]).powi(2)).sqrt() - 0.03
}

/// Evaluations until the first failure of [`synthetic_robustness`] around
/// [`synthetic_centre`]`(seed)` for `strategy` seeded with `seed` (its id + 1), driving the
/// generator as a campaign does (whole budget, or batches with tell); `None` within `cap`.
///
/// # Errors
/// When the generator cannot be built or serve the points.
pub fn synthetic_first_failure(strategy: Strategy, seed: u64, cap: u64) -> Result<Option<u64>> {
    let space = paracosm_generators::ParamSpace::unit_cube(2);
    let centre = synthetic_centre(seed);
    let mut g = strategy.build_sized(&space, seed, cap, 2)?;
    let mut n = 0u64;
    while n < cap {
        let ask = g.batch().map_or(cap - n, |b| (b as u64).min(cap - n));
        let points = g.ask(ask as usize)?;
        if points.is_empty() {
            break;
        }
        let told: Vec<_> = points
            .iter()
            .map(|p| (p.clone(), synthetic_robustness(centre, &p.continuous)))
            .collect();
        if let Some(i) = told.iter().position(|(_, r)| *r <= 0.0) {
            return Ok(Some(n + i as u64 + 1));
        }
        g.tell(&told);
        n += points.len() as u64;
    }
    Ok(None)
}

/// Runs every scenario × strategy × seed as a campaign that stops at its first failure
/// (`Campaign::stop_at_first_failure`, at most `cap` simulations), into
/// `out/falsify/runs/<scenario>/<strategy>/seed-<k>/`, and the same on the synthetic problem
/// ([`synthetic_first_failure`], no simulation). Writes `out/falsify/trials.csv`, the
/// table of medians `out/falsify/study.md`, and the box plot `out/falsify/first_failure.{png,svg}`
/// (censored campaigns drawn at `cap + 1`).
///
/// # Errors
/// When a campaign, the CSV, the table or the plot cannot be written.
pub fn falsification_study(settings: &StudySettings<'_>, out: &Path) -> Result<Study> {
    let dir = out.join("falsify");
    let mut trials = campaign_trials(settings, &dir)?;
    // Every strategy meets every seed's problem here, Halton included.
    for &strategy in settings.strategies {
        for seed in 0..settings.seeds {
            trials.push(Trial {
                scenario: SYNTHETIC.to_owned(),
                strategy: strategy.name().to_owned(),
                seed,
                sims_to_first_failure: synthetic_first_failure(strategy, seed, settings.cap)?,
            });
        }
    }
    let columns: Vec<&str> = settings
        .scenarios
        .iter()
        .copied()
        .chain([SYNTHETIC])
        .collect();
    std::fs::create_dir_all(&dir).map_err(|e| Error::write(&dir, e))?;
    let csv_path = dir.join("trials.csv");
    let written = |e: &dyn std::fmt::Display| Error::write(&csv_path, e);
    let mut w = csv::Writer::from_path(&csv_path).map_err(|e| written(&e))?;
    for t in &trials {
        w.serialize(t).map_err(|e| written(&e))?;
    }
    w.flush().map_err(|e| written(&e))?;

    let values = |scenario: &str, strategy: &str| -> Vec<f64> {
        trials
            .iter()
            .filter(|t| t.scenario == scenario && t.strategy == strategy)
            .map(|t| t.sims_to_first_failure.unwrap_or(settings.cap + 1) as f64)
            .collect()
    };
    let table = median_table(settings, &columns, &values);
    let table_path = dir.join("study.md");
    paracosm::atomic::write(&table_path, table.as_bytes())?;

    let panels: Vec<paracosm::report::plot::BoxPanel> = columns
        .iter()
        .map(|s| {
            (
                format!("{s}: tests to the first failure"),
                settings
                    .strategies
                    .iter()
                    .map(|st| (st.name().to_owned(), values(s, st.name())))
                    .collect(),
            )
        })
        .collect();
    let plots = paracosm::report::plot::box_plot(
        &dir.join("first_failure"),
        "simulations until the first failure",
        &panels,
    )?;
    let mut files = vec![csv_path, table_path];
    files.extend(plots);
    Ok(Study {
        trials,
        table,
        files,
    })
}

/// Runs every scenario × strategy × seed of `settings` as a campaign that stops at its first
/// failure, into `dir/runs/<scenario>/<strategy>/seed-<k>/`; one trial each, in run order.
fn campaign_trials(settings: &StudySettings<'_>, dir: &Path) -> Result<Vec<Trial>> {
    let mut trials = Vec::new();
    for &name in settings.scenarios {
        let scenario = paracosm_scenarios::builtin(name)?;
        for &strategy in settings.strategies {
            let seeds = if strategy == Strategy::Halton {
                1
            } else {
                settings.seeds
            };
            for seed in 0..seeds {
                let campaign = Campaign {
                    scenario: &scenario,
                    strategy,
                    seed,
                    budget: settings.cap,
                    strength: 2,
                    jobs: settings.jobs,
                    stop_at_first_failure: true,
                    points: None,
                    trace: None,
                };
                let run_dir = dir
                    .join("runs")
                    .join(name)
                    .join(strategy.name())
                    .join(format!("seed-{seed}"));
                let report = campaign.run(&run_dir, |_| {})?;
                trials.push(Trial {
                    scenario: name.to_owned(),
                    strategy: strategy.name().to_owned(),
                    seed,
                    sims_to_first_failure: report.first_failure.map(|f| f.id + 1),
                });
            }
        }
    }
    Ok(trials)
}

/// The Markdown table of the study: per strategy and column (scenario), the median and
/// quartiles of `values` (censored ones past `settings.cap` shown as `> cap`) and how many
/// trials found a failure.
fn median_table(
    settings: &StudySettings<'_>,
    columns: &[&str],
    values: &dyn Fn(&str, &str) -> Vec<f64>,
) -> String {
    let mut table = String::from("| strategy |");
    for s in columns {
        let _ = write!(table, " {s}: median [quartiles] | found |");
    }
    table.push_str("\n|---|");
    for _ in columns {
        table.push_str("---|---|");
    }
    table.push('\n');
    for strategy in settings.strategies {
        let _ = write!(table, "| {} |", strategy.name());
        for s in columns {
            let v = values(s, strategy.name());
            let found = v.iter().filter(|&&x| x <= settings.cap as f64).count();
            let shown = |x: f64| {
                if x > settings.cap as f64 {
                    format!("> {}", settings.cap)
                } else {
                    format!("{x}")
                }
            };
            let mut sorted = v.clone();
            sorted.sort_by(f64::total_cmp);
            let q = |p: f64| sorted[((sorted.len() - 1) as f64 * p).round() as usize];
            let _ = write!(
                table,
                " {} [{}, {}] | {found}/{} |",
                shown(median(&v).unwrap_or(f64::NAN)),
                shown(q(0.25)),
                shown(q(0.75)),
                v.len()
            );
        }
        table.push('\n');
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_the_synthetic_disc_nelder_mead_beats_halton_by_far() {
        // Over 9 discs, the descent finds the 0.28 % region in at most half the tests that
        // filling the square with Halton points needs (median).
        let tests = |st: Strategy| -> Vec<f64> {
            (0..9)
                .map(|s| synthetic_first_failure(st, s, 5000).unwrap().unwrap() as f64)
                .collect()
        };
        let (nm, halton) = (tests(Strategy::FalsifyNm), tests(Strategy::Halton));
        assert!(
            median(&nm).unwrap() * 2.0 <= median(&halton).unwrap(),
            "{nm:?} vs {halton:?}"
        );
    }

    #[test]
    fn median_of_odd_and_even_lengths() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
    }

    #[test]
    fn a_tiny_study_finds_pedestrian_crossing_failures_and_writes_its_files() {
        let dir = tempfile::tempdir().unwrap();
        let study = falsification_study(
            &StudySettings {
                scenarios: &["pedestrian-crossing"],
                strategies: &[Strategy::Halton, Strategy::FalsifyNm],
                seeds: 2,
                cap: 60,
                jobs: 2,
            },
            dir.path(),
        )
        .unwrap();
        // Halton runs once (it has no seed), the falsifier once per seed; then both once
        // per seed on the synthetic problem (a new disc per seed).
        assert_eq!(study.trials.len(), 7);
        // Halton's first collision is test 9 (see the shipped Figure 9 run).
        assert_eq!(study.trials[0].sims_to_first_failure, Some(10));
        assert!(study.trials[..3]
            .iter()
            .all(|t| t.sims_to_first_failure.is_some()));
        assert_eq!(study.trials[3].scenario, SYNTHETIC);
        assert!(
            study.table.contains("| halton | 10 [10, 10] | 1/1 |"),
            "{}",
            study.table
        );
        for f in &study.files {
            assert!(std::fs::metadata(f).unwrap().len() > 100, "{}", f.display());
        }
    }
}
