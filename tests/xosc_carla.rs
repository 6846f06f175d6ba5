//! CARLA scenario_runner's OpenSCENARIO examples (`tests/data/xosc/third_party/carla/`, MIT,
//! provenance in `tests/data/xosc/third_party/PROVENANCE.md`), read as scenario_runner reads
//! them: the ego is the vehicle given `external_control`, the system under test is its
//! controller, positions are in CARLA's left-handed frame, conditions latch, a `SpeedAction`
//! lasts its distance or time, and a scenario ends with its stories. Each of the 16 files
//! runs as a campaign or is refused at load naming the element that blocks it, and a test
//! keeps the count of those that run from falling.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The files that run as campaigns under `aeb` with `--ego-speed` (their ego's speed is left
/// to CARLA's agent) and `--horizon 150` (`Slalom`'s act starts at 120 s). Three of them since
/// rain is modelled by its extinction and 1.0's precipitation share read (`ChangingWeather`,
/// `PedestrianCrossingFront`, `Slalom`), `ChangingWeather` also since an empty `<Action>` is
/// read as scenario_runner reads it and its "never" (an event at 10^7 s) waits past every test.
/// Two more since: `LaneOffsetActionExample` (a `LaneOffsetAction` on the hero is a route along
/// its lane at the offset, for its system) and `CyclistCrossing` (CARLA's
/// `vehicle_longitudinal_control` moves its cyclist straight along its heading; the hero's
/// route, which the file leaves open, turns away at the junction, so the cyclist's events never
/// start, and the record says so). And `VehicleLateralDistance` since `LateralDistanceAction`
/// is read (its adversary steered towards 2 m beside the hero, in the hero's frame).
const RUN: [&str; 14] = [
    "ChangingWeather.xosc",
    "CyclistCrossing.xosc",
    "FollowLeadingVehicle.xosc",
    "InitAddEntityAction.xosc",
    "InitDeleteEntityAction.xosc",
    "IntersectionCollisionAvoidance.xosc",
    "LaneChangeSimple.xosc",
    "LaneOffsetActionExample.xosc",
    "OscControllerExample.xosc",
    "PedestrianCrossingFront.xosc",
    "Slalom.xosc",
    "StoryDeleteEntityAction.xosc",
    "SyncArrivalIntersection.xosc",
    "VehicleLateralDistance.xosc",
];

/// The files that run as campaigns but whose test is an error, with what the error says:
/// `StoryAddEntityAction` adds `adversary2` 120 m ahead of the hero, in its lane, where
/// `aeb` stops the hero, so the act's stop trigger (the hero travels 200 m) never comes; and
/// its `AddEntityA2` event, of priority `overwrite`, stops the running
/// `LeadingVehicleKeepsVelocity` event, so `LeadingVehicleWaits`, which waits for that
/// action's end, can never start. The horizon names it.
const RUN_UNPLAYED: [(&str, &str); 1] = [(
    "StoryAddEntityAction.xosc",
    "event \"LeadingVehicleWaits\" (",
)];

/// The files refused at load, each with what its error names.
const REFUSED: [(&str, &str); 1] = [("CatalogExample.xosc", "CARLA's autopilot")];

/// The CARLA example `file`.
fn carla(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/third_party/carla")
        .join(file)
}

/// `--maps` and the folder of CARLA's towns (`Town01`, `Town04`: `tests/data/maps/carla/`),
/// where a campaign finds the town a file names.
fn maps() -> [String; 2] {
    let towns = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/maps/carla");
    ["--maps".into(), towns.display().to_string()]
}

/// Runs `paracosm-fuzz FILE ARGS --budget 1` in a fresh output folder: exit code, stderr,
/// the record and the trace (when `--trace` was given).
fn run(file: &Path, args: &[&str]) -> (i32, String, serde_json::Value, String) {
    let out = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(file)
        .args(args)
        .args(maps())
        .args(["--budget", "1", "--out"])
        .arg(out.path().join("o"))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    let o_dir = out.path().join("o");
    let record = std::fs::read_to_string(o_dir.join("results.jsonl"))
        .ok()
        .and_then(|t| t.lines().next().map(|l| serde_json::from_str(l).unwrap()))
        .unwrap_or(serde_json::Value::Null);
    let trace = std::fs::read_to_string(o_dir.join("trace/test_0.csv")).unwrap_or_default();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
        record,
        trace,
    )
}

/// Each trace line's columns for entity `name` (esmini's CSV layout: name, id, speed, ...,
/// then x and y eight and nine columns after the speed): `(t, speed, x, y)`.
fn track(trace: &str, name: &str) -> Vec<(f64, f64, f64, f64)> {
    trace
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| {
            let c: Vec<&str> = l.split(", ").collect();
            let at = c.iter().position(|v| *v == name).unwrap();
            let num = |k: usize| c[k].trim().parse::<f64>().unwrap();
            (num(1), num(at + 2), num(at + 11), num(at + 12))
        })
        .collect()
}

#[test]
fn every_carla_example_runs_as_a_campaign_or_is_refused_naming_its_blocker() {
    let mut runs = 0;
    for f in RUN {
        let (code, err, r, _) = run(&carla(f), &["--ego-speed", "8", "--horizon", "150"]);
        // Exit 1: its test failed (a verdict).
        assert!(code == 0 || code == 1, "{f}: {err}");
        assert!(r["error"].is_null(), "{f}: {r}");
        assert!(r["status"] == "pass" || r["status"] == "fail", "{f}: {r}");
        runs += 1;
    }
    for (f, why) in RUN_UNPLAYED {
        let (code, err, r, _) = run(&carla(f), &["--ego-speed", "8", "--horizon", "150"]);
        // Exit 3: a test ended in an error.
        assert_eq!(code, 3, "{f}: {err}");
        assert_eq!(r["status"], "error", "{f}: {r}");
        let e = r["error"].as_str().unwrap_or_default();
        assert!(e.contains(why) && e.contains("never started"), "{f}: {e}");
        runs += 1;
    }
    for (f, why) in REFUSED {
        let (code, err, _, _) = run(&carla(f), &["--ego-speed", "8", "--horizon", "150"]);
        assert_eq!(code, 2, "{f} is refused at load: {err}");
        assert!(err.contains(why), "{f}: {why:?} not in {err}");
        // Its file (or the catalog holding the element), line and column.
        let at = [f, "ManeuverCatalog.xosc"]
            .iter()
            .filter_map(|name| err.split(&format!("{name}:")).nth(1))
            .next();
        assert!(
            at.is_some_and(|rest| rest.starts_with(|c: char| c.is_ascii_digit())),
            "{f} names its file, line and column: {err}"
        );
    }
    // The counts: scenario_runner ships 16 examples; none ran before this reading.
    assert_eq!(runs + REFUSED.len(), 16);
    // 5 ran before `AddEntityAction` and `DeleteEntityAction` were read, 9 since, 12 since
    // rain is modelled, 14 since a driven ego's lane offset and CARLA's longitudinal-only
    // controller are, 15 since `LateralDistanceAction` is (2026-11-30).
    assert!(runs >= 15, "{runs} of 16 CARLA examples run");
}

/// `SyncArrivalIntersection`: the adversary's `SynchronizeAction` times it to reach its
/// place by the junction (92, 63.8 in CARLA's frame) when the hero reaches its own (103, 55),
/// 3 m/s faster than the hero then; the scenario ends with its story, at that arrival. So at
/// the trace's last line both stand at their places (within a step's travel) and the
/// adversary drives at the hero's speed plus 3 m/s.
#[test]
fn carlas_synchronized_arrival_reaches_both_places_together() {
    let (code, err, r, trace) = run(
        &carla("SyncArrivalIntersection.xosc"),
        &["--ego-speed", "8", "--trace"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(r["status"], "pass", "{r}");
    let hero = track(&trace, "hero");
    let adversary = track(&trace, "adversary");
    let (&(t, v_hero, hx, hy), &(_, v_adv, ax, ay)) =
        (hero.last().unwrap(), adversary.last().unwrap());
    // CARLA's y is reversed on reading. The trace gives each box's centre, up to half a
    // length (2.5 m) from the reference point the file's positions place; the last line is
    // at most a step (1/60 s) and its 0.1 s sampling before the end.
    let near = |(x, y): (f64, f64), (px, py): (f64, f64)| (x - px).hypot(y - py);
    let slack = |v: f64| 2.5 + v * (1.0 / 60.0 + 0.1);
    assert!(
        near((hx, hy), (103.0, -55.0)) < slack(v_hero),
        "hero at ({hx}, {hy}) at {t} s"
    );
    assert!(
        near((ax, ay), (92.0, -63.8)) < slack(v_adv),
        "adversary at ({ax}, {ay}) at {t} s"
    );
    assert!(
        (v_adv - (v_hero + 3.0)).abs() < 0.2,
        "{v_adv} m/s against {v_hero}"
    );
    // The synchronization ends in the test's last step.
    let end = r["metrics"]["simulated_s"].as_f64().unwrap();
    let log = r["log"].as_array().unwrap();
    let synchronized = format!("t = {end:.3} s: action \"ActorSynchronization\" end");
    assert!(
        log.iter()
            .any(|l| l.as_str() == Some(synchronized.as_str())),
        "{synchronized:?} not in {log:?}"
    );
}

/// A test cut by `--horizon` while its storyboard still waits for events to start did not
/// play what the file describes: an error naming the events, never a pass on monitors alone
/// (`LaneChangeSimple` with the hero crawling at 0.5 m/s: the adversary's events wait on the
/// hero's approach).
#[test]
fn a_test_cut_by_its_horizon_before_its_events_start_is_an_error() {
    let (code, err, r, _) = run(
        &carla("LaneChangeSimple.xosc"),
        &["--ego-speed", "0.5", "--horizon", "20"],
    );
    assert_eq!(code, 3, "every test errs: {err}");
    assert_eq!(r["status"], "error", "{r}");
    let e = r["error"].as_str().unwrap();
    assert!(
        e.contains("the horizon came before the storyboard ended")
            && e.contains("\"AdversaryAccelerates\"")
            && e.contains("LaneChangeSimple.xosc:"),
        "{e}"
    );
}

/// `FollowLeadingVehicle`: the hero, at road 4 s 48.58 and t 2.75 in CARLA's frame (2.75 m to
/// the right of the reference line: lane −1, as the file's own commented-out `LanePosition`
/// says), drives at the set speed `--ego-speed` gives; once it is within 40 m (free space)
/// of the adversary, 50 m ahead and 1 m to its left, the adversary keeps 2 m/s for 20 m and
/// then stops for 10 s, and the scenario ends with its story. Before, the hero was refused
/// (its `AssignControllerAction`), and read as the standard reads it, the act never started
/// (its start conditions hold at different times) and the adversary stood still.
#[test]
fn carlas_follow_leading_vehicle_plays_as_scenario_runner_reads_it() {
    let file = carla("FollowLeadingVehicle.xosc");
    // Without --maps the town is nowhere: refused, saying where it is looked for.
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args([
            "--ego-speed",
            "8",
            "--horizon",
            "60",
            "--budget",
            "1",
            "--out",
        ])
        .arg(tempfile::tempdir().unwrap().path().join("o"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("Town01") && err.contains("--maps DIR"),
        "{err}"
    );
    let (code, err, _, _) = run(&file, &["--horizon", "60"]);
    assert_eq!(code, 2, "no speed asked of the hero: {err}");
    assert!(
        err.contains("FollowLeadingVehicle.xosc:13:5") && err.contains("--ego-speed"),
        "{err}"
    );
    let (code, err, r, trace) = run(
        &file,
        &[
            "--ego-speed",
            "8",
            "--horizon",
            "60",
            "--trace",
            "--trace-every",
            "0.5",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(r["status"], "pass", "{r}");
    let hero = track(&trace, "hero");
    let adversary = track(&trace, "adversary");
    // In CARLA's frame: the hero on the right lane (south of the road's reference line,
    // which runs east at y ≈ −132.5), the adversary 1 m to its left.
    let (_, _, hx, hy) = hero[0];
    let (_, _, ax, ay) = adversary[0];
    assert!((ax - hx - 50.0).abs() < 0.5, "50 m ahead: {hx} {ax}");
    assert!(
        (ay - hy - 1.0).abs() < 0.05,
        "1 m to the hero's left: {hy} {ay}"
    );
    // The adversary moves 20 m at 2 m/s, then stands.
    let moved = adversary.last().unwrap().2 - ax;
    assert!(
        (moved - 20.0).abs() < 0.2,
        "the adversary kept 2 m/s for {moved} m"
    );
    assert!(adversary.iter().any(|a| (a.1 - 2.0).abs() < 1e-6));
    // The hero drove up behind it and stopped; the test ended with the story (the 10 s
    // wait), long before the horizon.
    assert!(
        hero.iter().any(|h| h.1 > 7.0),
        "the hero reached its set speed"
    );
    let end = r["metrics"]["simulated_s"].as_f64().unwrap();
    assert!(end > 15.0 && end < 30.0, "ended with its story at {end} s");
}

/// A campaign whose town is found with a relative `--maps` resumes bare from another folder:
/// campaign.json keeps the folder absolute, and the fingerprint names the map by its place in
/// the folder of maps, not by the path typed.
#[test]
fn a_campaign_with_maps_resumes_bare_from_another_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = |cwd: &Path, args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .args(args)
            .current_dir(cwd)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .unwrap();
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let file = carla("FollowLeadingVehicle.xosc");
    let (code, err) = run(
        root,
        &[
            file.to_str().unwrap(),
            "--maps",
            "tests/data/maps/carla",
            "--ego-speed",
            "8",
            "--horizon",
            "30",
            "--budget",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("campaign.json")).unwrap()).unwrap();
    let maps = json["scenario"]["maps"].as_str().unwrap();
    assert!(Path::new(maps).is_absolute(), "{maps}");
    let (code, err) = run(dir.path(), &["--resume", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("refusing"), "{err}");
}

/// `LaneOffsetActionExample`: its `Init` asks the hero, which the system under test drives,
/// for a continuous lane offset of 3 m (CARLA's -3, to the left); the system is handed a
/// route along its lane at that offset and drives it: 5 s on, the hero is 3 m across from
/// where it started on its straight road.
#[test]
fn a_lane_offset_asked_of_the_driven_hero_is_its_route() {
    let (code, err, r, trace) = run(
        &carla("LaneOffsetActionExample.xosc"),
        &["--ego-speed", "8", "--horizon", "10", "--trace"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(r["status"], "pass", "{r}");
    let hero = track(&trace, "hero");
    let (_, _, x0, y0) = hero[0];
    let &(t, _, x, y) = hero.iter().find(|p| p.0 >= 5.0).unwrap();
    assert!(x - x0 > 20.0, "it drove on: x {x0} to {x} at {t} s");
    assert!(
        ((y - y0).abs() - 3.0).abs() < 0.3,
        "3 m across: y {y0} to {y} at {t} s"
    );
}
