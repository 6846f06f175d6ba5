//! Issue 21, requirement 1: curved roads in the language. `Arc` and `Clothoid` connect like
//! segments, `onLane(lane, at)` follows the curve, NPC cars and the ego's `aeb` and `vision`
//! keep their lanes round it, the radius may be open, and bad curves are refused at load with
//! the file, line and column.

use std::path::Path;

mod common;
use common::{campaign, expect_code, fuzz, records};

fn write(dir: &Path, name: &str, src: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, src).unwrap();
    p.to_str().unwrap().to_owned()
}

/// A right-hand bend whose radius is open: an arc of the test's radius between two straights.
/// An NPC car drives the bend the other way in lane -1; a monitor checks that it stays within
/// 30 cm of its lane's circle (about the arc's centre, which lies `R` m to the right of the
/// arc's start) while it is on the arc; the lambda reads the test's value of `R`.
const OPEN_RADIUS: &str = r#"
R = VarInterval(30.0, 90.0, unit = "m")
w = World()
lead_in = RoadSegment(len = 40.0)
turn = Arc(radius = R, angle = -1.2)
lead_out = RoadSegment(len = 150.0)
lead_in.connect((lead_in.TWO, turn, turn.ONE), (turn.TWO, lead_out, lead_out.ONE))
ego = AutonomousVehicle(loc = lead_in.onLane(1, 5), sut = SUT, speed = 10.0)
npc = Car(loc = turn.onLane(-1, 1.2 * 30.0 - 1.0), speed = 6.0, route = [])
w.place(lead_in, turn, lead_out, ego, npc)

def off_circle(p, r):
    # The arc turns right: its centre is r m right of its start, at (40, r) here; lane -1,
    # left of the line, is on the outside.
    d = hypot(p.x - 40.0, p.z - r)
    on_arc = p.z > 0.0 and p.x > 40.0
    return 0.3 - abs(d - (r + 1.75)) if on_arc else 0.3
npc_lane = Monitor(npc.pos.map(lambda p: off_circle(p, R)), unit = "m")
CollisionMonitor(ego)
DistanceMonitor(ego, minD = 100.0)
test(horizon = 16.0)
"#;

#[test]
fn an_open_radius_bend_is_driven_by_aeb_vision_and_an_npc_car_in_their_lanes() {
    let dir = tempfile::tempdir().unwrap();
    for sut in ["aeb", "vision"] {
        let src = format!("SUT = \"{sut}\"\n{OPEN_RADIUS}");
        let file = write(dir.path(), &format!("bend_{sut}.star"), &src);
        let out = dir.path().join(sut);
        let o = campaign(Path::new(&file), "6", &out);
        expect_code(&o, 0);
        let rs = records(&out);
        assert_eq!(rs.len(), 6);
        let radii: Vec<f64> = rs
            .iter()
            .map(|r| r["params"]["R"].as_f64().unwrap())
            .collect();
        assert!(
            radii.iter().any(|&r| r < 40.0) && radii.iter().any(|&r| r >= 75.0),
            "{radii:?}"
        );
        for r in &rs {
            assert_eq!(r["status"], "pass", "{sut}: {r}");
            // The ego kept to the road all round the bend, well inside its edges.
            let offroad = r["monitors"]["offroad"]["robustness"].as_f64().unwrap();
            assert!(offroad > 0.8, "{sut}: {r}");
            let npc = r["monitors"]["npc_lane"]["robustness"].as_f64().unwrap();
            // Within 1 cm of its lane's centre line on the arc (and the monitor saw it there:
            // off the arc it reads 0.3 exactly).
            assert!(
                npc > 0.29 && npc < 0.3,
                "{sut}: the NPC car left its lane: {r}"
            );
            assert!(
                r["metrics"]["distance_travelled_m"].as_f64().unwrap() > 140.0,
                "{r}"
            );
        }
    }
}

#[test]
fn curved_pieces_with_bad_sizes_are_refused_at_load_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "r = Arc(radius = 5.0)",
            "Arc radius 5 m is too tight for 2 lanes (at least 10 m)",
        ),
        (
            "r = Arc(radius = 12.0, nlanes = 8)",
            "too tight for 8 lanes",
        ),
        ("r = Arc(angle = 0.0)", "Arc angle 0 rad must be non-zero"),
        ("r = Arc(angle = 5.0)", "within ±3π/2"),
        ("r = Arc(radius = \"wide\")", "radius"),
        (
            "r = Clothoid(curv_end = 0.5)",
            "Clothoid curvature from 0 to 0.5 1/m is too tight",
        ),
        (
            "r = Clothoid(length = -3.0)",
            "Clothoid length -3 m is outside (0, 10000]",
        ),
        (
            "r = Clothoid(length = 2000.0, curv_end = 0.01)",
            "Clothoid turns 10.0000 rad",
        ),
        (
            "r = Arc()\nj = r.onLane(r.ONE, \"left\", 3.0)",
            "(lane, at)",
        ),
        ("r = Arc()\nx = r.onLane(1, 100.0)", "outside"),
    ];
    for (i, (line, phrase)) in cases.iter().enumerate() {
        let src = format!(
            "w = World()\n{line}\nv = AutonomousVehicle(loc = r.onLane(1, 1))\nw.place(r, v)\n"
        );
        let file = write(dir.path(), &format!("bad{i}.star"), &src);
        let o = fuzz(&[
            &file,
            "--budget",
            "1",
            "--out",
            dir.path().join(format!("o{i}")).to_str().unwrap(),
        ]);
        expect_code(&o, 2);
        let err = String::from_utf8_lossy(&o.stderr);
        let first = err.lines().next().unwrap_or("");
        assert!(first.starts_with("paracosm-fuzz: error: "), "{line}: {err}");
        assert!(err.contains(phrase), "{line}: {err}");
        assert!(err.contains(&format!("bad{i}.star:")), "{line}: {err}");
    }
}

#[test]
fn the_curve_study_finds_collisions_and_keeps_the_ego_on_the_road() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/curve_pieces.star");
    let o = campaign(&study, "40", &out);
    expect_code(&o, 1);
    let rs = records(&out);
    let collided = rs
        .iter()
        .filter(|r| !r["monitors"]["collision"]["passed"].as_bool().unwrap())
        .count();
    assert!(collided > 0 && collided < 40, "{collided} collisions");
    for r in &rs {
        assert!(r["monitors"]["offroad"]["passed"].as_bool().unwrap(), "{r}");
    }
}
