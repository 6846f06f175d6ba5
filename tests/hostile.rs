//! Issue 22: hostile cases that are not a bad input file (those are in `tests/bad_inputs/`):
//! runs that must finish, with a warning, rather than hang.

use std::time::{Duration, Instant};

mod common;
use common::fuzz;

#[test]
fn a_parameter_range_wider_than_a_float_spans_gives_a_warning_not_a_hung_plot() {
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("huge.star");
    std::fs::write(
        &program,
        "x = VarInterval(-1e308, 1e308)\n\
         w = World(light = 0.5, fog = min(0.0, abs(x)))\n\
         r = RoadSegment(len = 200.0, nlanes = 2)\n\
         v = AutonomousVehicle(loc = r.onLane(1, 10), speed = 5.0)\n\
         w.place(r, v)\n\
         CollisionMonitor(v)\n\
         test(horizon = 2.0)\n",
    )
    .unwrap();
    let out = dir.path().join("o");
    let started = Instant::now();
    let o = fuzz(&[
        program.to_str().unwrap(),
        "--budget",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        started.elapsed() < Duration::from_secs(60),
        "took {:?}",
        started.elapsed()
    );
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("cannot plot `x`: its range [-1e308, 1e308] is wider than a 64-bit float"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["counts"]["pass"], 2);
    assert!(summary["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("cannot plot `x`")));
}
