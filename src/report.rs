//! What a campaign leaves besides `results.jsonl`: `summary.json`, the plots, JUnit XML, and
//! the human summary printed by `paracosm-fuzz`, `merge` and `report`.

use std::path::Path;

use paracosm_generators::{Domain, Param, ParamSpace, Point};
use paracosm_scenarios::Scenario;

use crate::campaign::RESULTS_FILE;
use crate::campaign_file::CampaignFile;
use crate::record::{RunRecord, Status};
use crate::replay::replay_command;
use crate::summary::{Counts, FailureEntry, FirstFailure, Summary};

pub use crate::summary::SUMMARY_FILE;

/// Every failed test, smallest robustness first (ties by id; NaN last).
pub fn failures(records: &[RunRecord], out: &Path) -> Vec<FailureEntry> {
    let mut list: Vec<FailureEntry> = records
        .iter()
        .filter(|r| r.status == Status::Fail)
        .map(|r| FailureEntry {
            id: r.id,
            robustness: r
                .monitors
                .iter()
                .map(|(_, m)| m.robustness)
                .fold(f64::INFINITY, f64::min),
            failed_monitors: r.failed_monitors(),
            params: r.params.clone(),
            replay: replay_command(out, r.id),
        })
        .collect();
    list.sort_by(|a, b| {
        let key = |x: f64| if x.is_nan() { f64::INFINITY } else { x };
        key(a.robustness)
            .total_cmp(&key(b.robustness))
            .then(a.id.cmp(&b.id))
    });
    list
}

/// Settings of [`write_outputs`].
pub struct Finished<'a> {
    /// The output folder.
    pub out: &'a Path,
    /// The scenario.
    pub scenario: &'a Scenario,
    /// The campaign's settings.
    pub file: &'a CampaignFile,
    /// Every record of the folder, by id.
    pub records: &'a [RunRecord],
    /// Worker threads used.
    pub jobs: usize,
    /// Wall time in seconds.
    pub wall_s: f64,
    /// Where JUnit XML is written, if asked (listed in the summary's outputs; written by
    /// the caller, [`crate::junit::write`]).
    pub junit: Option<&'a Path>,
    /// The warnings the scenario loaded with for this campaign's system under test
    /// ([`Scenario::warnings_for`]), recorded in the summary.
    pub warnings: Vec<String>,
}

/// What [`write_outputs`] wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// The summary as written (its `outputs` list the plots that were drawn).
    pub summary: Summary,
    /// One line per plot that could not be drawn (also in the summary's `warnings`).
    pub plot_warnings: Vec<String>,
}

/// The plots of a campaign: `(file stem, what)` for the failure map and the failure-rate heat
/// map, none for a scenario without open parameters.
fn plan_plots(scenario: &Scenario) -> Vec<&'static str> {
    if scenario.map_axes.is_empty() {
        Vec::new()
    } else {
        vec!["failure_map", "failure_rate"]
    }
}

/// Writes `summary.json`, then the plots (`failure_map`,
/// `failure_rate`: none without open parameters, a strip plot with one, categorical columns for
/// discrete ones), each file through a temporary file and a rename. The summary comes first so
/// that no plotting problem can cost it: a plot that cannot be drawn is a warning, and the
/// summary is written again without it and with the warning.
///
/// # Errors
/// [`crate::Error::Write`] when `summary.json` cannot be written.
pub fn write_outputs(f: &Finished<'_>) -> Result<Written, crate::Error> {
    let scenario = f.scenario;
    let planned = plan_plots(scenario);
    let plot_files = |stems: &[&str]| -> Vec<String> {
        stems
            .iter()
            .flat_map(|s| [format!("{s}.png"), format!("{s}.svg")])
            .collect()
    };
    let mut outputs = vec![
        RESULTS_FILE.to_owned(),
        SUMMARY_FILE.to_owned(),
        crate::campaign_file::CAMPAIGN_FILE.to_owned(),
    ];
    if let Some(j) = f.junit {
        outputs.push(j.display().to_string());
    }
    let base = outputs.clone();
    outputs.extend(plot_files(&planned));
    let mut summary = summarise(f, outputs);
    write_summary(f.out, &summary)?;

    let counts = summary.counts;
    let mut drawn = Vec::new();
    let mut plot_warnings = Vec::new();
    for stem in planned {
        let path = f.out.join(stem);
        let result = match stem {
            "failure_map" => {
                let title = format!(
                    "{}: {}, {} tests, {} failed",
                    scenario.name,
                    f.file.strategy,
                    f.records.len(),
                    counts.fail
                );
                crate::plot::failure_map(
                    &path,
                    &scenario.space,
                    &scenario.map_axes,
                    &[(&title, f.records)],
                )
            }
            _ => crate::plot::failure_rate_map(
                &path,
                &scenario.space,
                &scenario.map_axes,
                &format!(
                    "{}: failure rate ({} tests)",
                    scenario.name,
                    f.records.len()
                ),
                f.records,
                8,
            ),
        };
        match result {
            Ok(_) => drawn.push(stem),
            Err(e) => plot_warnings.push(format!("the plot {stem} was not drawn: {e}")),
        }
    }
    if !plot_warnings.is_empty() {
        let mut outputs = base;
        outputs.extend(plot_files(&drawn));
        summary.outputs = outputs;
        summary.warnings.extend(plot_warnings.iter().cloned());
        write_summary(f.out, &summary)?;
    }
    Ok(Written {
        summary,
        plot_warnings,
    })
}

fn write_summary(out: &Path, summary: &Summary) -> Result<(), crate::Error> {
    let text = serde_json::to_string_pretty(summary).expect("summaries serialise") + "\n";
    crate::atomic::write(&out.join(SUMMARY_FILE), text.as_bytes())
}

/// `space` and `points` without the parameters named in `unused` (coordinates by name).
fn used_only(space: &ParamSpace, points: &[Point], unused: &[String]) -> (ParamSpace, Vec<Point>) {
    // For each parameter: whether it is kept, and its index among the continuous or the
    // discrete coordinates of a point.
    let mut keep = Vec::new();
    let (mut c, mut d) = (0usize, 0usize);
    for p in space.params() {
        let used = !unused.contains(&p.name);
        match p.domain {
            Domain::Interval { .. } => {
                keep.push((used, true, c));
                c += 1;
            }
            Domain::Levels(_) => {
                keep.push((used, false, d));
                d += 1;
            }
        }
    }
    let params: Vec<Param> = space
        .params()
        .iter()
        .zip(&keep)
        .filter(|(_, k)| k.0)
        .map(|(p, _)| p.clone())
        .collect();
    let sub = ParamSpace::new(params).expect("a subset of a valid space is valid");
    let points = points
        .iter()
        .map(|pt| {
            let mut out = Point {
                discrete: Vec::new(),
                continuous: Vec::new(),
            };
            for &(used, continuous, i) in &keep {
                match (used, continuous) {
                    (true, true) => out.continuous.extend(pt.continuous.get(i)),
                    (true, false) => out.discrete.extend(pt.discrete.get(i)),
                    _ => {}
                }
            }
            out
        })
        .collect();
    (sub, points)
}

/// The scenario's warnings for its system under test, as text.
pub fn warnings_of(scenario: &Scenario) -> Vec<String> {
    scenario
        .warnings_for(&scenario.sut)
        .iter()
        .map(ToString::to_string)
        .collect()
}

/// The summary of a folder's records, listing `outputs` as the files written. Coverage is
/// computed over the parameters that objects read; the others are listed as `unused_params`.
pub fn summarise(f: &Finished<'_>, outputs: Vec<String>) -> Summary {
    let scenario = f.scenario;
    let coverage = {
        let points: Vec<Point> = f.records.iter().map(|r| r.point.clone()).collect();
        let (space, points) = used_only(&scenario.space, &points, &scenario.unused_params);
        let set = crate::cover::TestSet { space, points };
        let metrics: Vec<crate::cover::Metric> = ["dispersion", "cd", "wd", "md", "l2star", "star"]
            .iter()
            .filter_map(|m| m.parse().ok())
            .collect();
        if set.space.params().is_empty() {
            None
        } else {
            crate::cover::estimate(&set, &metrics, None, None, 10).ok()
        }
    };
    Summary {
        failures: failures(f.records, f.out),
        tool: format!("paracosm {}", env!("CARGO_PKG_VERSION")),
        scenario: scenario.name.clone(),
        strategy: f.file.strategy.clone(),
        seed: f.file.seed,
        budget: f.file.budget,
        shard: f.file.shard,
        tests_run: f.records.len() as u64,
        jobs: f.jobs,
        space: scenario.space.params().to_vec(),
        unused_params: scenario.unused_params.clone(),
        counts: Counts::of(f.records),
        first_failure: FirstFailure::of(f.records),
        coverage,
        warnings: f.warnings.clone(),
        wall_s: f.wall_s,
        outputs,
    }
}

/// The human summary: counts and speed, the first failure, coverage, and the files.
pub fn human(summary: &Summary, scenario: &Scenario, out: &Path, expected: u64) -> String {
    let c = summary.counts;
    let mut lines = vec![format!(
        "{} of {} tests of {} ({}, seed {}{}): {} passed, {} failed, {} errors in {:.1} s ({:.0} tests/s)",
        summary.tests_run,
        expected,
        scenario.name,
        summary.strategy,
        summary.seed,
        summary
            .shard
            .map(|s| format!(", shard {s}"))
            .unwrap_or_default(),
        c.pass,
        c.fail,
        c.error,
        summary.wall_s,
        summary.tests_run as f64 / summary.wall_s.max(1e-9)
    )];
    if let Some(f) = &summary.first_failure {
        let values: Vec<String> = f
            .params
            .iter()
            .map(|(n, v)| {
                let unit = scenario
                    .space
                    .param(n)
                    .and_then(|p| p.unit.as_ref())
                    .map(|u| format!(" {u}"))
                    .unwrap_or_default();
                match v {
                    paracosm_generators::Value::Real(x) => format!("{n} = {x:.3}{unit}"),
                    _ => format!("{n} = {v}{unit}"),
                }
            })
            .collect();
        let values = if values.is_empty() {
            String::new()
        } else {
            format!(" ({})", values.join(", "))
        };
        lines.push(format!(
            "first failure: test {}{values}, monitors failed: {}",
            f.id,
            f.failed_monitors.join(", ")
        ));
        lines.push(format!("replay it: {}", replay_command(out, f.id)));
    }
    if let Some(cov) = &summary.coverage {
        let mut parts = Vec::new();
        if let Some(d) = &cov.dispersion {
            parts.push(if d.exact {
                format!("dispersion {:.4}", d.lower)
            } else {
                format!("dispersion in [{:.4}, {:.4}]", d.lower, d.upper)
            });
        }
        if let Some(star) = &cov.star {
            parts.push(format!("star discrepancy {:.4}", star.upper));
        }
        for k in &cov.kwise {
            parts.push(format!(
                "{}-wise coverage {}/{}",
                k.strength, k.covered, k.total
            ));
        }
        if !parts.is_empty() {
            lines.push(format!("coverage: {}", parts.join(", ")));
        }
    }
    lines.push(format!(
        "files: {}",
        summary
            .outputs
            .iter()
            .map(|o| out.join(o).display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    lines.join("\n")
}

/// `paracosm-fuzz report DIR`: the human summary of a finished or partial campaign folder,
/// computed again from its records (and the wall time and thread count of its
/// `summary.json`, when there is one), with a line on how to finish a partial one. Returns
/// the text and the counts.
///
/// # Errors
/// [`crate::Error::Input`] when `campaign.json` or `results.jsonl` is missing or malformed;
/// [`crate::Error::Scenario`] when the campaign's scenario no longer loads.
pub fn reread(dir: &Path) -> Result<(String, Counts), crate::Error> {
    let file = CampaignFile::read(dir)?;
    let mut scenario = paracosm_scenarios::load(&file.scenario)?;
    if let Some(s) = file.sut.config()? {
        scenario.sut = s;
    }
    let ids = file.ids();
    let existing = crate::results::load(dir, &scenario.space, ids.clone(), false)?;
    let stored = Summary::read(dir).ok();
    let wall_s = stored.as_ref().map_or_else(
        || existing.records.iter().map(|r| r.wall_ms).sum::<f64>() / 1e3,
        |s| s.wall_s,
    );
    let outputs: Vec<String> = [
        RESULTS_FILE,
        SUMMARY_FILE,
        "failure_map.png",
        "failure_map.svg",
        "failure_rate.png",
        "failure_rate.svg",
    ]
    .iter()
    .filter(|f| dir.join(f).exists())
    .map(|f| f.to_string())
    .collect();
    let summary = summarise(
        &Finished {
            out: dir,
            scenario: &scenario,
            file: &file,
            records: &existing.records,
            jobs: stored.as_ref().map_or(1, |s| s.jobs),
            wall_s,
            junit: None,
            warnings: warnings_of(&scenario),
        },
        outputs,
    );
    let expected = ids.end - ids.start;
    let mut text = human(&summary, &scenario, dir, expected);
    if (existing.records.len() as u64) < expected {
        text.push_str(&format!(
            "\npartial: {} of {expected} tests; finish it with `paracosm-fuzz --resume --out {}`",
            existing.records.len(),
            dir.display()
        ));
    }
    Ok((text, summary.counts))
}
