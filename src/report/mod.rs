//! What a campaign leaves besides `results.jsonl`: `summary.json`, the plots, JUnit XML, and
//! the human summary printed by `paracosm-fuzz`, `merge` and `report`.

pub mod html;
pub mod junit;
pub mod on_map;
pub mod plot;
pub mod summary;
pub mod triage;

use std::path::Path;

use paracosm_generators::{Domain, Param, ParamSpace, Point};
use paracosm_scenarios::Scenario;

use crate::campaign::file::CampaignFile;
use crate::campaign::RESULTS_FILE;
use crate::export::replay::replay_command;
use crate::record::{RunRecord, Status};
use crate::report::summary::{Counts, FailureEntry, FirstFailure, Summary};
use crate::report::triage::Triage;

pub use crate::report::summary::SUMMARY_FILE;

/// Every failed test, smallest robustness first (ties by id; NaN last).
pub fn failures(records: &[RunRecord], out: &Path) -> Vec<FailureEntry> {
    let mut list: Vec<FailureEntry> = records
        .iter()
        .filter(|r| r.status == Status::Fail)
        .map(|r| FailureEntry {
            id: r.id,
            robustness: r.robustness(),
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
    /// the caller, [`crate::report::junit::write`]).
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

/// A plot of a campaign folder.
#[derive(Debug, Clone, PartialEq)]
pub enum Plot {
    /// The failure map (paper Figure 9) over one or two parameters, its points coloured by
    /// outcome or robustness.
    Map {
        /// One or two parameter names.
        axes: Vec<String>,
        /// What the points are coloured by.
        color: crate::report::plot::Coloring,
    },
    /// The failure-rate heat map (Figure 10a) over one or two parameters, with cells adapted
    /// to the number of tests ([`crate::report::plot::adaptive_bins`]).
    Rate {
        /// One or two parameter names.
        axes: Vec<String>,
    },
    /// The scatterplot matrix of the parameters ([`pairs_params`]).
    Pairs,
}

/// The parameters the pairs plot shows, in declaration order, and those it leaves out: all of
/// them up to [`crate::report::plot::MAX_PAIRS`], else the most relevant by `triage`'s ranking (the
/// first ones declared without a ranking).
pub fn pairs_params(
    space: &ParamSpace,
    triage: Option<&crate::report::triage::Triage>,
) -> (Vec<String>, Vec<String>) {
    let all: Vec<String> = space.params().iter().map(|p| p.name.clone()).collect();
    if all.len() <= crate::report::plot::MAX_PAIRS {
        return (all, Vec::new());
    }
    let ranked: Vec<String> = match triage {
        Some(t) => t.ranking.iter().map(|r| r.param.clone()).collect(),
        None => all.clone(),
    };
    let chosen = &ranked[..crate::report::plot::MAX_PAIRS];
    let (shown, left): (Vec<String>, Vec<String>) =
        all.into_iter().partition(|n| chosen.contains(n));
    (shown, left)
}

/// What a campaign's plots are drawn from.
pub struct PlotData<'a> {
    /// The scenario's name (in titles).
    pub scenario: &'a str,
    /// The strategy's name (in titles).
    pub strategy: &'a str,
    /// The scenario's parameters.
    pub space: &'a ParamSpace,
    /// The records.
    pub records: &'a [RunRecord],
    /// The failure rules and ranking, which pick the pairs plot's parameters.
    pub triage: Option<&'a crate::report::triage::Triage>,
}

impl PlotData<'_> {
    /// Draws `plot` into `stem.png` and `stem.svg` and returns their paths.
    ///
    /// # Errors
    /// [`crate::report::plot::PlotError`] when an axis is not a parameter, or a file cannot be written.
    pub fn draw(
        &self,
        stem: &Path,
        plot: &Plot,
    ) -> Result<[std::path::PathBuf; 2], crate::report::plot::PlotError> {
        let n = self.records.len();
        let fail = self
            .records
            .iter()
            .filter(|r| r.status == Status::Fail)
            .count();
        match plot {
            Plot::Map { axes, color } => {
                let title = format!(
                    "{}: {}, {n} tests, {fail} failed",
                    self.scenario, self.strategy
                );
                crate::report::plot::failure_map(
                    stem,
                    self.space,
                    axes,
                    &[(&title, self.records)],
                    *color,
                )
            }
            Plot::Rate { axes } => crate::report::plot::failure_rate_map(
                stem,
                self.space,
                axes,
                &format!("{}: failure rate ({n} tests)", self.scenario),
                self.records,
                crate::report::plot::adaptive_bins(n, self.space, axes),
            ),
            Plot::Pairs => {
                let (shown, left) = pairs_params(self.space, self.triage);
                let note = if left.is_empty() {
                    String::new()
                } else {
                    format!(
                        "{} more parameters, less relevant, not shown: {}",
                        left.len(),
                        left.join(", ")
                    )
                };
                crate::report::plot::pairs_plot(
                    stem,
                    self.space,
                    &shown,
                    &format!(
                        "{}: {}, {n} tests, {fail} failed",
                        self.scenario, self.strategy
                    ),
                    &note,
                    self.records,
                )
            }
        }
    }
}

/// The plots of a campaign, by file stem: the failure map and the failure-rate heat map over
/// the scenario's map axes, and the pairs plot; none without open parameters.
fn plan_plots(scenario: &Scenario, triage: Option<&Triage>) -> Vec<(&'static str, Plot)> {
    let axes = map_axes(scenario, triage);
    if axes.is_empty() {
        return Vec::new();
    }
    vec![
        (
            "failure_map",
            Plot::Map {
                axes: axes.clone(),
                color: crate::report::plot::Coloring::Outcome,
            },
        ),
        ("failure_rate", Plot::Rate { axes }),
        ("pairs", Plot::Pairs),
    ]
}

/// The failure map's axes: the two parameters `triage` ranks most relevant for a scenario
/// that asks for them ([`Scenario::map_axes_by_relevance`]) when it ranks two that vary
/// (a parameter nothing reads, [`Scenario::unused_params`], or of one level, is no axis: on
/// Euro NCAP's CCRs grid, all of whose tests pass, the ranking's ties put the unread
/// `Scenario_ID` second), else the scenario's own.
fn map_axes(scenario: &Scenario, triage: Option<&Triage>) -> Vec<String> {
    let varies = |name: &str| {
        !scenario.unused_params().iter().any(|u| u == name)
            && scenario
                .space()
                .param(name)
                .is_some_and(|p| match &p.domain {
                    paracosm_generators::Domain::Levels(l) => l.len() > 1,
                    paracosm_generators::Domain::Interval { .. } => true,
                })
    };
    let ranked: Vec<String> = triage
        .filter(|_| scenario.map_axes_by_relevance())
        .map(|t| {
            t.ranking
                .iter()
                .map(|r| r.param.clone())
                .filter(|p| varies(p))
                .collect()
        })
        .unwrap_or_default();
    if ranked.len() >= 2 {
        return ranked.into_iter().take(2).collect();
    }
    scenario.map_axes().to_vec()
}

/// How a plot's title names a campaign's scenario: an OpenSCENARIO file by its file name,
/// without the options its campaign name carries (` --open ...`); any other by its name.
fn shown_name(name: &str) -> String {
    let path = name.split(" --").next().unwrap_or(name);
    if !crate::scenario_ref::is_xosc(path) {
        return name.to_owned();
    }
    Path::new(path)
        .file_name()
        .map_or_else(|| path.to_owned(), |f| f.to_string_lossy().into_owned())
}

/// Writes `summary.json`, then the plots (`failure_map`, `failure_rate`, `pairs`: none without
/// open parameters, a strip plot with one, categorical columns for discrete ones), each file
/// through a temporary file and a rename. The summary comes first so that no plotting problem
/// can cost it: a plot that cannot be drawn is a warning, and the summary is written again
/// without it and with the warning.
///
/// # Errors
/// [`crate::Error::Write`] when `summary.json` cannot be written.
pub fn write_outputs(f: &Finished<'_>) -> Result<Written, crate::Error> {
    let scenario = f.scenario;
    let plot_files = |stems: &[&str]| -> Vec<String> {
        stems
            .iter()
            .flat_map(|s| [format!("{s}.png"), format!("{s}.svg")])
            .collect()
    };
    let mut outputs = vec![
        RESULTS_FILE.to_owned(),
        SUMMARY_FILE.to_owned(),
        crate::campaign::file::CAMPAIGN_FILE.to_owned(),
    ];
    if let Some(j) = f.junit {
        // Relative to the output folder, as the other files are (`--junit o7/j.xml --out o7`
        // was listed as o7/o7/j.xml); a file outside it by its absolute path.
        let (j_abs, out_abs) = (
            std::path::absolute(j).unwrap_or_else(|_| j.to_owned()),
            std::path::absolute(f.out).unwrap_or_else(|_| f.out.to_owned()),
        );
        outputs.push(match j_abs.strip_prefix(&out_abs) {
            Ok(inside) => inside.display().to_string(),
            Err(_) => j_abs.display().to_string(),
        });
    }
    let base = outputs.clone();
    // The same files whatever the axes (an empty space draws none).
    let stems: Vec<&str> = plan_plots(scenario, None).iter().map(|(s, _)| *s).collect();
    outputs.extend(plot_files(&stems));
    outputs.push(crate::report::html::REPORT_FILE.to_owned());
    let mut summary = summarise(f, outputs);
    write_summary(f.out, &summary)?;
    // Planned once the triage has ranked the parameters.
    let planned = plan_plots(scenario, summary.triage.as_ref());
    let shown = shown_name(scenario.name());
    let data = PlotData {
        scenario: &shown,
        strategy: &f.file.strategy,
        space: scenario.space(),
        records: f.records,
        triage: summary.triage.as_ref(),
    };
    let mut drawn = Vec::new();
    let mut plot_warnings = Vec::new();
    for (stem, plot) in &planned {
        match data.draw(&f.out.join(stem), plot) {
            Ok(_) => drawn.push(*stem),
            Err(e) => plot_warnings.push(format!("the plot {stem} was not drawn: {e}")),
        }
    }
    let page = crate::report::html::write(&crate::report::html::Page {
        out: f.out,
        summary: &summary,
        space: scenario.space(),
        records: f.records,
        map_axes: &map_axes(scenario, summary.triage.as_ref()),
    });
    if let Err(e) = &page {
        plot_warnings.push(format!(
            "the page {} was not written: {e}",
            crate::report::html::REPORT_FILE
        ));
    }
    if !plot_warnings.is_empty() {
        let mut outputs = base;
        outputs.extend(plot_files(&drawn));
        if page.is_ok() {
            outputs.push(crate::report::html::REPORT_FILE.to_owned());
        }
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
    if !space.params().iter().any(|p| unused.contains(&p.name)) {
        // The space itself, with its constraints: coverage counts the valid space.
        return (space.clone(), points.to_vec());
    }
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
        .warnings_for(scenario.sut())
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
        let (space, points) = used_only(scenario.space(), &points, scenario.unused_params());
        let set = crate::cover::TestSet { space, points };
        let metrics: Vec<crate::cover::Metric> = ["dispersion", "cd", "wd", "md", "l2star", "star"]
            .iter()
            .filter_map(|m| m.parse().ok())
            .collect();
        // k-wise coverage up to the campaign's strength (at least 2): an `ipog` or `kwise`
        // campaign of strength 3 reports its 3-wise coverage.
        let nd = set.space.level_counts().len();
        let strength = (nd > 0).then(|| f.file.strength.max(2).min(nd.min(6)));
        if set.space.params().is_empty() {
            None
        } else {
            crate::cover::estimate(&set, &metrics, strength, None, 10, None).ok()
        }
    };
    Summary {
        failures: failures(f.records, f.out),
        tool: format!("paracosm {}", env!("CARGO_PKG_VERSION")),
        scenario: scenario.name().to_owned(),
        sut: Some(crate::report::summary::SutSummary::of(
            scenario.sut(),
            &f.file.sut,
        )),
        ego: scenario.ego().map(str::to_owned),
        strategy: f.file.strategy.clone(),
        seed: f.file.seed,
        budget: f.file.budget,
        shard: f.file.shard,
        tests_run: f.records.len() as u64,
        jobs: f.jobs,
        space: scenario.space().params().to_vec(),
        unused_params: scenario.unused_params().to_vec(),
        counts: Counts::of(f.records),
        first_failure: FirstFailure::of(f.records),
        coverage,
        valid_space: valid_space(scenario.space()),
        triage: crate::report::triage::triage(scenario.space(), f.records),
        warnings: f.warnings.clone(),
        wall_s: f.wall_s,
        outputs,
    }
}

/// What the constraints of `space` leave valid, `None` for an unconstrained space (or one
/// whose fraction cannot be computed: its campaign's load refused it already).
fn valid_space(space: &ParamSpace) -> Option<crate::report::summary::ValidSpace> {
    if !space.is_constrained() {
        return None;
    }
    let fraction = space.valid_fraction().ok()?;
    Some(crate::report::summary::ValidSpace {
        constraints: space
            .constraints()
            .iter()
            .map(|c| c.name().to_owned())
            .collect::<Vec<_>>()
            .join(", "),
        fraction,
    })
}

/// The human summary: counts and speed, the first failure, coverage, and the files.
/// `ran_now`: how many of the tests this process ran in `summary.wall_s` (a resume ran only
/// the missing ones; a merge ran none), `None` when the summary's time covers them all.
pub fn human(
    summary: &Summary,
    scenario: &Scenario,
    out: &Path,
    expected: u64,
    ran_now: Option<u64>,
) -> String {
    let c = summary.counts;
    let ran = ran_now.unwrap_or(summary.tests_run);
    let speed = if ran == 0 {
        "no test run now".to_owned()
    } else if summary.wall_s > 0.0 {
        format!(
            "{}in {:.1} s ({:.0} tests/s)",
            if ran == summary.tests_run {
                String::new()
            } else {
                format!("{ran} run now ")
            },
            summary.wall_s,
            ran as f64 / summary.wall_s
        )
    } else {
        format!("{ran} run now")
    };
    let mut lines = vec![format!(
        "{} of {} tests of {} ({}, seed {}{}): {} passed, {} failed, {} errors{}{speed}",
        summary.tests_run,
        expected,
        scenario.name(),
        summary.strategy,
        summary.seed,
        summary
            .shard
            .map(|s| format!(", shard {s}"))
            .unwrap_or_default(),
        c.pass,
        c.fail,
        c.error,
        if speed.starts_with("in ") { " " } else { "; " },
    )];
    if let Some(sut) = &summary.sut {
        lines.push(format!("system under test: {}", sut.text()));
    }
    if let Some(ego) = &summary.ego {
        lines.push(format!("ego vehicle: {ego}"));
    }
    if let Some(f) = &summary.first_failure {
        lines.push(first_failure_line(f, scenario));
        lines.push(format!("replay it: {}", replay_command(out, f.id)));
    }
    if let Some(v) = &summary.valid_space {
        lines.push(format!(
            "valid space: {} under {}; no test runs outside it",
            v.fraction, v.constraints
        ));
    }
    if let Some(cov) = &summary.coverage {
        lines.extend(coverage_line(cov));
    }
    if let Some(t) = &summary.triage {
        lines.extend(triage_lines(t));
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

/// The human summary's line on the first failure `f`: its id, its parameters with their units
/// (reals to 3 decimals), and the monitors that failed.
fn first_failure_line(f: &FirstFailure, scenario: &Scenario) -> String {
    let values: Vec<String> = f
        .params
        .iter()
        .map(|(n, v)| {
            let unit = scenario
                .space()
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
    format!(
        "first failure: test {}{values}, monitors failed: {}",
        f.id,
        f.failed_monitors.join(", ")
    )
}

/// The human summary's coverage line: dispersion, star discrepancy, what was skipped, k-wise
/// coverage; `None` when there is nothing to say.
fn coverage_line(cov: &crate::cover::Estimate) -> Option<String> {
    let mut parts = Vec::new();
    if let Some(d) = &cov.dispersion {
        parts.push(if d.exact {
            format!("dispersion {:.4}", d.lower)
        } else {
            format!("dispersion in [{:.4}, {:.4}]", d.lower, d.upper)
        });
    }
    if let Some(star) = &cov.star {
        parts.push(if star.exact {
            format!("star discrepancy {:.4}", star.lower)
        } else {
            format!("star discrepancy in [{:.4}, {:.4}]", star.lower, star.upper)
        });
    }
    if let Some(g) = &cov.valid_gap {
        parts.push(format!("valid-region gap ≥ {:.4}", g.radius));
    }
    for note in &cov.skipped {
        parts.push(note.clone());
    }
    for k in &cov.kwise {
        parts.push(if k.forbidden > 0 {
            format!(
                "{}-wise coverage {}/{} valid tuples ({} forbidden)",
                k.strength, k.covered, k.total, k.forbidden
            )
        } else {
            format!("{}-wise coverage {}/{}", k.strength, k.covered, k.total)
        });
    }
    (!parts.is_empty()).then(|| format!("coverage: {}", parts.join(", ")))
}

/// Rules shown on the console; the others are in `summary.json`.
const RULES_SHOWN: usize = 5;

/// The console lines of a triage: the failure regions, then the parameters by relevance.
fn triage_lines(t: &crate::report::triage::Triage) -> Vec<String> {
    let mut lines = Vec::new();
    if !t.rules.is_empty() {
        lines.push(format!(
            "where failures are (decision tree of depth {} on {} tests):",
            t.max_depth, t.tests
        ));
        for r in t.rules.iter().take(RULES_SHOWN) {
            lines.push(format!("  {}", r.text));
        }
        if t.rules.len() > RULES_SHOWN {
            lines.push(format!(
                "  and {} more regions in summary.json",
                t.rules.len() - RULES_SHOWN
            ));
        }
    }
    let ranked: Vec<String> = t
        .ranking
        .iter()
        .map(|r| {
            let assoc = match (r.association, r.association_kind.as_str()) {
                (Some(a), "eta") => format!(", η {a:.2}"),
                (Some(a), _) => format!(", ρ {a:+.2}"),
                (None, _) => String::new(),
            };
            format!("{} (importance {:.2}{assoc})", r.param, r.importance)
        })
        .collect();
    lines.push(format!("parameters by relevance: {}", ranked.join(", ")));
    lines
}

/// `paracosm-fuzz report DIR`: the human summary of a finished or partial campaign folder,
/// computed again from its records (and the wall time and thread count of its
/// `summary.json`, when there is one), with a line on how to finish a partial one; then the
/// plots `redraw` asks for, drawn from the records (their paths are added to the text).
/// Returns the text and the counts.
///
/// # Errors
/// [`crate::Error::Input`] when `campaign.json` or `results.jsonl` is missing or malformed;
/// [`crate::Error::Scenario`] when the campaign's scenario no longer loads;
/// [`crate::Error::BadInput`] when `--map` names a parameter the scenario lacks, or not one
/// or two; [`crate::Error::Plot`] when a plot cannot be written.
pub fn reread(dir: &Path, redraw: &crate::cli::Redraw) -> Result<(String, Counts), crate::Error> {
    let file = CampaignFile::read(dir)?;
    let mut scenario = file.scenario.load()?;
    if let Some(s) = file.sut.config()? {
        scenario.set_sut(s);
    }
    let ids = file.ids();
    let existing = crate::campaign::results::load(dir, &scenario, ids.clone(), false)?;
    let stored = Summary::read(dir).ok();
    let wall_s = stored.as_ref().map_or_else(
        || existing.records.iter().map(|r| r.wall_ms).sum::<f64>() / 1e3,
        |s| s.wall_s,
    );
    let outputs: Vec<String> = crate::atomic::CAMPAIGN_OUTPUTS
        .iter()
        .filter(|f| **f != crate::campaign::file::CAMPAIGN_FILE)
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
    // The stored time is the campaign's when its summary counted these very records; else
    // no speed is claimed (the report runs no test).
    let timed = stored
        .as_ref()
        .is_some_and(|s| s.tests_run == existing.records.len() as u64);
    let mut text = human(
        &summary,
        &scenario,
        dir,
        expected,
        if timed { None } else { Some(0) },
    );
    if (existing.records.len() as u64) < expected {
        text.push_str(&format!(
            "\npartial: {} of {expected} tests; finish it with `paracosm-fuzz --resume --out {}`",
            existing.records.len(),
            dir.display()
        ));
    }
    let shown = shown_name(scenario.name());
    let axes = map_axes(&scenario, summary.triage.as_ref());
    let data = PlotData {
        scenario: &shown,
        strategy: &file.strategy,
        space: scenario.space(),
        records: &existing.records,
        triage: summary.triage.as_ref(),
    };
    // A folder that takes no new file is bad input, found before anything is drawn.
    if redraw.map.is_some()
        || redraw.color.is_some()
        || redraw.pairs
        || redraw.html
        || redraw.on_map
    {
        crate::atomic::probe_writable(dir)?;
    }
    if redraw.html {
        crate::atomic::check_target(&dir.join(crate::report::html::REPORT_FILE))?;
    }
    let mut drawn = redraw_plots(dir, &data, &axes, redraw)?;
    if redraw.html {
        let page = crate::report::html::write(&crate::report::html::Page {
            out: dir,
            summary: &summary,
            space: scenario.space(),
            records: &existing.records,
            map_axes: &axes,
        })?;
        drawn.push(page.display().to_string());
    }
    if redraw.on_map {
        let (files, line) = on_map::draw(dir, &scenario, &existing.records)?;
        text.push_str(&format!("\n{line}"));
        drawn.extend(files);
    }
    if !drawn.is_empty() {
        text.push_str(&format!("\nwrote: {}", drawn.join(", ")));
    }
    Ok((text, summary.counts))
}

/// Draws what `redraw` asks for into `dir` and returns the files' paths.
fn redraw_plots(
    dir: &Path,
    data: &PlotData<'_>,
    map_axes: &[String],
    redraw: &crate::cli::Redraw,
) -> Result<Vec<String>, crate::Error> {
    let mut plots: Vec<(String, Plot)> = Vec::new();
    if redraw.map.is_some() || redraw.color.is_some() {
        let axes = redraw.map.clone().unwrap_or_else(|| map_axes.to_vec());
        let names: Vec<String> = data.space.params().iter().map(|p| p.name.clone()).collect();
        if axes.is_empty() || axes.len() > 2 {
            return Err(crate::Error::BadInput(format!(
                "--map takes one or two parameters, got {}; the scenario's: {}",
                axes.len(),
                names.join(", ")
            )));
        }
        if let Some(bad) = axes.iter().find(|a| !names.contains(a)) {
            return Err(crate::Error::BadInput(format!(
                "--map: `{bad}` is not a parameter of the scenario; its parameters: {}",
                names.join(", ")
            )));
        }
        let color = redraw.color.unwrap_or_default();
        let suffix = if color == crate::report::plot::Coloring::Robustness {
            "-robustness"
        } else {
            ""
        };
        let key = axes.join("-");
        plots.push((
            format!("failure_map-{key}{suffix}"),
            Plot::Map {
                axes: axes.clone(),
                color,
            },
        ));
        plots.push((format!("failure_rate-{key}"), Plot::Rate { axes }));
    }
    if redraw.pairs {
        plots.push(("pairs".to_owned(), Plot::Pairs));
    }
    for (stem, _) in &plots {
        for ext in ["png", "svg"] {
            crate::atomic::check_target(&dir.join(format!("{stem}.{ext}")))?;
        }
    }
    let mut drawn = Vec::new();
    for (stem, plot) in &plots {
        let [png, svg] = data.draw(&dir.join(stem), plot)?;
        drawn.push(png.display().to_string());
        drawn.push(svg.display().to_string());
    }
    Ok(drawn)
}
