//! `report.html` in a real browser (issue 18): headless Chromium (Debian's `chromium`, which
//! `scripts/test` installs when missing) driven by playwright-core (`tests/browser/`, which
//! `scripts/test` installs with `npm ci`). Fails, never skips, when either is missing.

mod common;

use std::path::Path;
use std::process::Command;

use common::{expect_code, fuzz};

/// Runs `tests/browser/report.test.mjs` on `report` expecting `tests` points; returns what it
/// printed.
fn open_in_chromium(report: &Path, tests: usize, screenshot: &Path, extra: &[&str]) -> String {
    let o = Command::new("node")
        .arg("tests/browser/report.test.mjs")
        .arg(report)
        .arg(tests.to_string())
        .arg(screenshot)
        .args(extra)
        .output()
        .expect("node runs (scripts/test installs the browser test's packages)");
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "the browser test failed\nstdout: {stdout}\nstderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

#[test]
fn the_report_page_loads_offline_draws_every_test_redraws_and_shows_a_replay_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("campaign");
    let o = fuzz(&[
        "scenarios/pedestrian_crossing.star",
        "--budget",
        "150",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let page = out.join("report.html");
    let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-screenshot.png");
    let seen = open_in_chromium(&page, 150, &shot, &[]);
    let seen: serde_json::Value = serde_json::from_str(seen.trim()).unwrap();
    assert_eq!(seen["domPoints"], 150);
    assert_eq!(seen["consoleErrors"].as_array().unwrap().len(), 0);
    // The page names the system under test that ran (pedestrian-crossing's own aeb).
    let settings = seen["settings"].as_str().unwrap();
    assert!(
        settings.contains("system under test") && settings.contains("aeb (built in)"),
        "{settings}"
    );
    assert_eq!(
        seen["requests"].as_array().unwrap().len(),
        1,
        "only the file itself"
    );
    let id = seen["clickedId"].as_u64().unwrap();
    let replay = seen["replay"].as_str().unwrap();
    assert_eq!(replay, paracosm::export::replay::replay_command(&out, id));
    // The clicked test failed in the records.
    let line = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .find(|r| r["id"] == id)
        .unwrap();
    assert_eq!(line["status"], "fail");
    let png = std::fs::read(&shot).unwrap();
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 50_000,
        "a screenshot of the page"
    );
}

#[test]
fn pages_of_scenarios_without_parameters_with_one_or_with_levels_only_load_and_draw_every_test() {
    let dir = tempfile::tempdir().unwrap();
    for (program, budget) in [
        ("tests/scenarios/no_params.star", 3),
        ("tests/scenarios/one_param.star", 12),
        ("tests/scenarios/all_discrete.star", 12),
    ] {
        let out = dir
            .path()
            .join(budget.to_string() + program.rsplit('/').next().unwrap());
        let o = fuzz(&[
            program,
            "--budget",
            &budget.to_string(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{program}: {o:?}");
        let seen = open_in_chromium(
            &out.join("report.html"),
            budget,
            &dir.path().join("shot.png"),
            &["--load-only"],
        );
        let seen: serde_json::Value = serde_json::from_str(seen.trim()).unwrap();
        assert_eq!(seen["scenePoints"], budget, "{program}");
    }
}

#[test]
fn the_page_of_ten_thousand_tests_is_under_two_megabytes_and_embeds_a_replayed_contact_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big");
    let o = fuzz(&[
        "tests/scenarios/failure_box.star",
        "--budget",
        "10000",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let size = std::fs::metadata(out.join("report.html")).unwrap().len();
    assert!(
        size < 2_000_000,
        "report.html of 10,000 tests: {size} bytes"
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(!html.contains("src=\"http") && !html.contains("href=\"http"));
    assert!(
        html.contains("default-src 'none'"),
        "the page may load nothing"
    );

    // After `replay --frames`, `report --html` embeds the test's contact sheet.
    let small = dir.path().join("small");
    let o = fuzz(&[
        "scenarios/pedestrian_crossing.star",
        "--budget",
        "12",
        "--out",
        small.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(small.join("summary.json")).unwrap())
            .unwrap();
    let id = summary["first_failure"]["id"].as_u64().unwrap();
    let frames = small.join(format!("frames-{id}"));
    let o = fuzz(&[
        "replay",
        small.join("results.jsonl").to_str().unwrap(),
        "--id",
        &id.to_string(),
        "--frames",
        frames.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let before = std::fs::metadata(small.join("report.html")).unwrap().len();
    let o = fuzz(&["report", small.to_str().unwrap(), "--html"]);
    expect_code(&o, 1);
    let html = std::fs::read_to_string(small.join("report.html")).unwrap();
    let sheet = std::fs::metadata(frames.join("contact_sheet.png"))
        .unwrap()
        .len();
    assert!(html.len() as u64 > before + sheet, "the sheet is embedded");
    assert!(html.contains(&format!("\"{id}\":\"data:image/png;base64,")));
}
