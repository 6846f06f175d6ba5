//! `report.html`: a campaign's results as one self-contained web page that works offline.
//!
//! The page inlines Vega, Vega-Lite and vega-embed (`assets/report/`, BSD-3-Clause, versions
//! in its README) and the campaign's data; a Content-Security-Policy of `default-src 'none'`
//! stops it from loading anything else. It shows the failure rules and the parameters'
//! relevance ([`crate::report::triage`]), a failure map whose axes and colouring (outcome or
//! robustness) are picked from menus, with each test's parameters, monitors and robustness on
//! hover and its replay command (and contact sheet, where `replay --frames` wrote one) on
//! click, a table of the failures sortable by any column, the pairs plot, the coverage block
//! and the settings.

use std::path::{Path, PathBuf};

use base64::Engine;
use image::ImageEncoder;
use serde_json::{json, Value as Json};

use paracosm_generators::{Domain, ParamSpace};

use crate::record::{RunRecord, Status};
use crate::report::summary::Summary;

/// The page's file name in a campaign folder.
pub const REPORT_FILE: &str = "report.html";

/// Contact sheets are embedded up to this many bytes in all; the page of a campaign with
/// more replayed tests shows the first ones (by id).
pub const SHEETS_LIMIT: u64 = 1_000_000;

const TEMPLATE: &str = include_str!("../../assets/report/template.html");
const VEGA: &str = include_str!("../../assets/report/vega.min.js");
const VEGA_LITE: &str = include_str!("../../assets/report/vega-lite.min.js");
const VEGA_EMBED: &str = include_str!("../../assets/report/vega-embed.min.js");

/// What the page shows.
pub struct Page<'a> {
    /// The campaign folder: the page is written there, and `pairs.png` and
    /// `frames-ID/contact_sheet.png` are read from there.
    pub out: &'a Path,
    /// The campaign's summary (as in `summary.json`).
    pub summary: &'a Summary,
    /// The scenario's parameters.
    pub space: &'a ParamSpace,
    /// Every record of the folder, by id.
    pub records: &'a [RunRecord],
    /// The parameters the failure map starts on (one or two names).
    pub map_axes: &'a [String],
}

/// A continuous parameter's value is sent as `round((v - lo) / (hi - lo) * STEPS)`, an
/// integer the page maps back into the interval: 1/10,000 of the range is finer than any
/// plot shows, and half the bytes of the value.
const STEPS: f64 = 10_000.0;

/// The page's copy of the pairs plot is scaled down until its PNG is at most this many bytes.
const PAIRS_LIMIT: usize = 450_000;

/// `x` with 5 significant digits (the page shows values, it does not compute with them);
/// `null` when not finite.
fn short(x: f64) -> Json {
    if !x.is_finite() {
        return Json::Null;
    }
    format!("{x:.4e}")
        .parse::<f64>()
        .ok()
        .and_then(serde_json::Number::from_f64)
        .map_or(Json::Null, Json::Number)
}

fn data_uri(bytes: &[u8]) -> String {
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

/// The contact sheets under `out` (`frames-ID/contact_sheet.png`), by id, as data URIs, up to
/// [`SHEETS_LIMIT`] bytes in all.
fn sheets(out: &Path) -> serde_json::Map<String, Json> {
    let mut found: Vec<(u64, PathBuf)> = std::fs::read_dir(out)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let id = name.strip_prefix("frames-")?.parse::<u64>().ok()?;
            let sheet = e.path().join("contact_sheet.png");
            sheet.is_file().then_some((id, sheet))
        })
        .collect();
    found.sort();
    let mut total = 0;
    let mut map = serde_json::Map::new();
    for (id, path) in found {
        let Ok(bytes) = std::fs::read(&path) else {
            continue;
        };
        total += bytes.len() as u64;
        if total > SHEETS_LIMIT {
            break;
        }
        map.insert(id.to_string(), Json::String(data_uri(&bytes)));
    }
    map
}

/// The page's data: the summary (without its failure list, which the page builds from the
/// tests), the parameters, and the tests by column.
fn data(page: &Page<'_>) -> Json {
    let records = page.records;
    let params: Vec<Json> = page
        .space
        .params()
        .iter()
        .map(|p| match &p.domain {
            Domain::Interval { lo, hi } => {
                json!({"name": p.name, "kind": "interval", "lo": lo, "hi": hi, "unit": p.unit})
            }
            Domain::Levels(levels) => {
                json!({"name": p.name, "kind": "levels", "levels": levels, "unit": p.unit})
            }
        })
        .collect();
    let mut monitors: Vec<String> = Vec::new();
    for r in records {
        for (m, _) in &r.monitors {
            if !monitors.contains(m) {
                monitors.push(m.clone());
            }
        }
    }
    let tests = tests_data(page, &monitors);
    let mut summary = serde_json::to_value(page.summary).expect("summaries serialise");
    if let Some(o) = summary.as_object_mut() {
        o.remove("failures");
    }
    let map_axes: Vec<usize> = page
        .map_axes
        .iter()
        .filter_map(|a| page.space.params().iter().position(|p| &p.name == a))
        .collect();
    let pairs = std::fs::read(page.out.join("pairs.png"))
        .ok()
        .and_then(|b| small_enough(b, PAIRS_LIMIT))
        .map(|b| data_uri(&b));
    json!({
        "title": title(page.summary),
        "summary": summary,
        "params": params,
        "monitors": monitors,
        "tests": tests,
        "map_axes": map_axes,
        "robustness_span": crate::report::plot::robustness_span(records),
        "replay": crate::export::replay::replay_command_for(page.out, "{id}"),
        "pairs": pairs,
        "sheets": sheets(page.out),
    })
}

/// The page's tests by column: status, parameter values (intervals in [`STEPS`] steps,
/// levels by index), robustness, and per monitor of `monitors` whether it failed and its
/// robustness; the ids as the first one when they are contiguous.
fn tests_data(page: &Page<'_>, monitors: &[String]) -> Json {
    let records = page.records;
    let status: String = records
        .iter()
        .map(|r| match r.status {
            Status::Pass => 'p',
            Status::Fail => 'f',
            Status::Error => 'e',
        })
        .collect();
    let values: Vec<Vec<Json>> = page
        .space
        .params()
        .iter()
        .map(|p| {
            records
                .iter()
                .map(|r| {
                    let a = r.params.as_ref();
                    match &p.domain {
                        Domain::Interval { lo, hi } => {
                            a.and_then(|a| a.real(&p.name)).map_or(Json::Null, |v| {
                                json!(((v - lo) / (hi - lo) * STEPS).round() as i64)
                            })
                        }
                        Domain::Levels(levels) => a
                            .and_then(|a| a.get(&p.name))
                            .and_then(|v| levels.iter().position(|l| l == v))
                            .map_or(Json::Null, |i| json!(i)),
                    }
                })
                .collect()
        })
        .collect();
    let monitor_failed: Vec<String> = monitors
        .iter()
        .map(|m| {
            records
                .iter()
                .map(|r| match r.monitors.iter().find(|(n, _)| n == m) {
                    Some((_, v)) if !v.passed => '1',
                    _ => '0',
                })
                .collect()
        })
        .collect();
    let monitor_robustness: Vec<Vec<Json>> = monitors
        .iter()
        .map(|m| {
            records
                .iter()
                .map(|r| {
                    r.monitors
                        .iter()
                        .find(|(n, _)| n == m)
                        .map_or(Json::Null, |(_, v)| short(v.robustness))
                })
                .collect()
        })
        .collect();
    let first = records.first().map_or(0, |r| r.id);
    let contiguous = records
        .iter()
        .enumerate()
        .all(|(i, r)| r.id == first + i as u64);
    let mut tests = json!({
        "status": status,
        "values": values,
        "robustness": records.iter().map(|r| short(r.robustness())).collect::<Vec<_>>(),
        "monitor_failed": monitor_failed,
        "monitor_robustness": monitor_robustness,
    });
    if contiguous {
        tests["first_id"] = json!(first);
    } else {
        tests["ids"] = json!(records.iter().map(|r| r.id).collect::<Vec<_>>());
    }
    tests
}

/// The PNG `png` if it has at most `limit` bytes, else scaled down (by 3/4 at a time) until
/// it has; `None` when it does not decode.
fn small_enough(png: Vec<u8>, limit: usize) -> Option<Vec<u8>> {
    if png.len() <= limit {
        return Some(png);
    }
    let image = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
        .ok()?
        .to_rgb8();
    let (w, h) = image.dimensions();
    let mut scale = 0.75;
    loop {
        let (sw, sh) = (
            ((f64::from(w) * scale) as u32).max(1),
            ((f64::from(h) * scale) as u32).max(1),
        );
        let small = image::imageops::resize(&image, sw, sh, image::imageops::FilterType::Triangle);
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Best,
            image::codecs::png::FilterType::Adaptive,
        )
        .write_image(small.as_raw(), sw, sh, image::ColorType::Rgb8)
        .ok()?;
        if out.len() <= limit || scale < 0.2 {
            return Some(out);
        }
        scale *= 0.75;
    }
}

/// The page's title: the scenario, the system under test (where the summary names it), the
/// strategy, seed and counts.
fn title(s: &Summary) -> String {
    format!(
        "{}{}: {}, seed {}, {} tests, {} failed",
        s.scenario,
        s.sut
            .as_ref()
            .map(|sut| format!(" under {}", sut.name))
            .unwrap_or_default(),
        s.strategy,
        s.seed,
        s.tests_run,
        s.counts.fail
    )
}

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The page as text.
pub fn render(page: &Page<'_>) -> String {
    // In a <script> element only `</` can end the element early; JSON allows `<\/`.
    let data = serde_json::to_string(&data(page))
        .expect("the page's data serialises")
        .replace("</", "<\\/");
    TEMPLATE
        .replace("__PARACOSM_TITLE__", &escape_html(&title(page.summary)))
        .replace("__VEGA__", VEGA)
        .replace("__VEGA_LITE__", VEGA_LITE)
        .replace("__VEGA_EMBED__", VEGA_EMBED)
        .replace("__PARACOSM_DATA__", &data)
}

/// Writes `report.html` into `page.out` (through a temporary file and a rename) and returns
/// its path.
///
/// # Errors
/// [`crate::Error::Write`] when the file cannot be written.
pub fn write(page: &Page<'_>) -> Result<PathBuf, crate::Error> {
    let path = page.out.join(REPORT_FILE);
    crate::atomic::write(&path, render(page).as_bytes())?;
    Ok(path)
}
