//! Vector's Euro NCAP scenarios (`tests/data/xosc/third_party/vector/`, MPL-2.0, provenance
//! in `tests/data/xosc/third_party/PROVENANCE.md`): the AEB car-to-car and vulnerable road
//! user scenarios of the 2023 protocols and the crash avoidance frontal collision scenarios of
//! 2026, with their variation files. Each file reads or is refused at load naming the element
//! that blocks it, and a test keeps the count of those that read from falling; the CCRs
//! logical scenario runs as its own grid and as a Halton campaign under `aeb`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The folder of Vector's OpenSCENARIO files.
fn ncap() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/third_party/vector/OpenSCENARIO/NCAP")
}

/// Every scenario and variation file under `dir` (catalogs left out), sorted.
fn scenario_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() && p.file_name().is_some_and(|n| n != "Catalogs") {
            scenario_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "xosc") {
            out.push(p);
        }
    }
    out.sort();
}

/// What blocks the files that do not read: the element each refusal names. None since
/// 2026-11-30 (an `EntityAction` blocked 7, a variation's value written as an expression 2).
const BLOCKERS: [&str; 0] = [];

#[test]
fn every_vector_file_reads_or_is_refused_naming_its_blocker() {
    let mut files = Vec::new();
    scenario_files(&ncap(), &mut files);
    assert_eq!(files.len(), 132, "Vector's scenario and variation files");
    let mut read = 0;
    for f in &files {
        match paracosm_scenarios::xosc::inspect_with_map(f, &[], false, (None, false)) {
            Ok(_) => read += 1,
            Err(e) => {
                let e = e.to_string();
                assert!(
                    BLOCKERS.iter().any(|b| e.contains(b)),
                    "{}: {e}",
                    f.display()
                );
                // The element's file, line and column.
                assert!(e.contains(".xosc:"), "{e}");
            }
        }
    }
    // 2026-11-30: 58 of 132 (none before esmini's constant `pi` was read); 79 once
    // `SynchronizeAction` was read; 123 with trajectory positions, clothoid splines and a
    // trajectory's initial offset; all 132 with `AddEntityAction`, `DeleteEntityAction` and
    // a variation's value written as an expression.
    assert!(read >= 132, "{read} of {} read", files.len());
}

thread_local! {
    /// The failure map (SVG) of the last [`campaign`] on this thread.
    static MAP: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
}

/// Runs `paracosm-fuzz ARGS` into a fresh folder: exit code, stderr and the records (the
/// failure map's SVG, when drawn, with them in `MAP.with`).
fn campaign(args: &[&str]) -> (i32, String, Vec<serde_json::Value>) {
    let out = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args(args)
        .arg("--out")
        .arg(out.path().join("o"))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    let map = std::fs::read_to_string(out.path().join("o/failure_map.svg")).unwrap_or_default();
    MAP.with(|m| *m.borrow_mut() = map);
    let records = std::fs::read_to_string(out.path().join("o/results.jsonl"))
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
        records,
    )
}

/// Euro NCAP's car-to-car rear stationary test (CCRs, 2026): its StandardRange grid (ego at
/// 10 to 50 km/h, five impact locations) under `aeb`, which stops short of the target in
/// every test; and the logical scenario with the ego's speed opened to 130 km/h, where the
/// failures the grid cannot see appear, all at 70 km/h and above (docs/results.md).
#[test]
fn vectors_ccrs_grid_passes_under_aeb_and_an_opened_campaign_finds_the_speed_it_fails_at() {
    let grid = ncap().join("CA-FC_2026/Variations/StandardRange/CCRs.xosc");
    let (code, err, r) = campaign(&[
        grid.to_str().unwrap(),
        "--strategy",
        "variation",
        "--budget",
        "25",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(r.len(), 25);
    // The failure map is drawn over the two parameters that vary, not over the unread,
    // one-level `Scenario_ID` that ties with them when nothing fails.
    let map = MAP.with(|m| m.borrow().clone());
    assert!(
        map.contains("Ego_speed_kph") && map.contains("ImpactLocation"),
        "axes"
    );
    assert!(
        !map.contains("Scenario_ID"),
        "an unread parameter is no axis"
    );
    for t in &r {
        assert_eq!(t["status"], "pass", "{t}");
        // The ego drove up to the target and stopped: the stop trigger's "still" group.
        let end = t["metrics"]["simulated_s"].as_f64().unwrap();
        assert!(end > 5.0 && end < 30.0, "{t}");
    }
    let logical = ncap().join("CA-FC_2026/CCRs.xosc");
    let (code, err, r) = campaign(&[
        logical.to_str().unwrap(),
        "--open",
        "Ego_speed_kph=10..130",
        "--open",
        "ImpactLocation=-25..125",
        "--strategy",
        "halton",
        "--budget",
        "60",
    ]);
    assert_eq!(code, 1, "some test failed: {err}");
    assert_eq!(r.len(), 60);
    let speed = |t: &serde_json::Value| t["params"]["Ego_speed_kph"].as_f64().unwrap();
    let failed: Vec<f64> = r
        .iter()
        .filter(|t| t["status"] == "fail")
        .map(speed)
        .collect();
    assert!(
        !failed.is_empty(),
        "aeb fails against a stationary target at high speed"
    );
    assert!(failed.iter().all(|&v| v >= 70.0), "{failed:?}");
    assert!(r.iter().all(|t| t["error"].is_null()), "no test in error");
    assert!(r
        .iter()
        .filter(|t| speed(t) <= 50.0)
        .all(|t| t["status"] == "pass"));
}

/// A `FollowTrajectoryAction` on the ego a system under test drives hands the system the
/// trajectory as its route (CPTA: the ego turns left across the pedestrian's path on a
/// clothoid spline in `Init`): the ego starts where the trajectory does, facing east, and
/// ends the test turned north onto the crossing road, within a lane's width of the
/// trajectory's end line (x = 263.19 m).
#[test]
fn a_driven_egos_trajectory_is_its_systems_route() {
    let file = ncap().join("AEB_VRU_2023/NCAP_AEB_VRU_CPTA_2023.xosc");
    let out = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--budget", "1", "--trace", "--out"])
        .arg(out.path().join("o"))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let trace = std::fs::read_to_string(out.path().join("o/trace/test_0.csv")).unwrap();
    let ego: Vec<(f64, f64, f64)> = trace
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| {
            let c: Vec<&str> = l.split(", ").collect();
            let at = c.iter().position(|v| *v == "Ego").unwrap();
            let num = |k: usize| c[k].trim().parse::<f64>().unwrap();
            (num(at + 11), num(at + 12), num(at + 24))
        })
        .collect();
    let (x0, y0, h0) = ego[0];
    assert!(
        (y0 + 1.75).abs() < 0.1 && h0.abs() < 0.01,
        "starts east: {:?}",
        ego[0]
    );
    assert!(x0 > 200.0, "{x0}");
    let &(x1, y1, h1) = ego.last().unwrap();
    assert!(
        (h1 - std::f64::consts::FRAC_PI_2).abs() < 0.2,
        "ends turned north: {h1} rad at ({x1}, {y1})"
    );
    assert!((x1 - 263.19).abs() < 1.75, "on the crossing road: {x1}");
}

/// Each of Vector's 132 scenario and variation files runs as a campaign of one test under
/// `aeb` (a pass or a failure, never an error), except the six CPRA files, refused at load at
/// their ego's `SpeedAction` to −1.1 m/s (paracosm's systems under test drive forward only):
/// 126 of 132 (2026-11-30; issue "The field's OpenSCENARIO files run as their authors meant",
/// requirement 6, asks 90 %). Keeps that count from falling.
#[test]
fn every_vector_file_runs_as_a_campaign_but_the_reversing_cpra_files() {
    let mut files = Vec::new();
    scenario_files(&ncap(), &mut files);
    let (mut ran, mut refused) = (0, Vec::new());
    for f in &files {
        let (code, err, records) = campaign(&[f.to_str().unwrap(), "--budget", "1"]);
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        match code {
            0 | 1 => {
                assert_eq!(records.len(), 1, "{name}: {err}");
                let status = records[0]["status"].as_str().unwrap_or("").to_owned();
                assert!(status == "pass" || status == "fail", "{name}: {status}");
                ran += 1;
            }
            _ => {
                assert!(
                    name.contains("CPRA")
                        && err.contains("drive backwards")
                        && err.contains(".xosc:"),
                    "{name}: exit {code}: {err}"
                );
                refused.push(name);
            }
        }
    }
    assert_eq!(files.len(), 132);
    assert!(
        ran >= 126,
        "{ran} of {} ran; refused: {refused:?}",
        files.len()
    );
}
