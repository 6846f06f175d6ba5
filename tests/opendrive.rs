//! Issue 21, requirements 2 and 3: `OpenDrive("map.xodr")` in programs. The shipped map
//! scenarios run; programs written in forms not shipped (NPC traffic round the roundabout
//! map, an open choice of map, a map beside the program) work; a changed map stops
//! `--resume`; what a map holds that paracosm does not use is named at load; wrong roads and
//! lanes are refused with the program's file, line and column.

use std::path::{Path, PathBuf};

mod common;
use common::{campaign, expect_code, fuzz, records};

fn maps() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/maps")
}

/// `dir` with `src` as `name` and a copy of the shipped maps under `dir/maps`.
fn program(dir: &Path, name: &str, src: &str) -> PathBuf {
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    for f in ["bend.xodr", "junction.xodr", "roundabout.xodr"] {
        std::fs::copy(maps().join(f), dir.join("maps").join(f)).unwrap();
    }
    let p = dir.join(name);
    std::fs::write(&p, src).unwrap();
    p
}

#[test]
fn the_shipped_map_scenarios_run_and_find_what_they_are_built_to_find() {
    let dir = tempfile::tempdir().unwrap();
    // The pedestrian study on the bend: the ego keeps its lane all the way round (never
    // nearer the edge than 1.7 m: the lane is 3.5 m wide).
    let out = dir.path().join("curve");
    let o = fuzz(&[
        "curve-pedestrian",
        "--budget",
        "60",
        "--out",
        out.to_str().unwrap(),
    ]);
    // Exit 1: some tests failed (collisions with the pedestrian).
    expect_code(&o, 1);
    let rs = records(&out);
    assert_eq!(rs.len(), 60);
    for r in &rs {
        assert_eq!(r["monitors"]["offroad"]["passed"], true, "{r}");
        assert!(
            r["metrics"]["min_road_edge_m"].as_f64().unwrap() > 1.7,
            "{r}"
        );
        // Round the bend to the crossing, unless a collision there cut the run short.
        let distance = &r["monitors"]["distance"];
        assert!(
            distance["passed"] == true || distance["cut_short"] == true,
            "{r}"
        );
    }
    // The left turn across oncoming traffic: collisions happen, and only where the oncoming
    // car reaches the junction while the ego turns (its arrival time at/speed in a band).
    let out = dir.path().join("junction");
    let o = fuzz(&[
        "opendrive-junction",
        "--budget",
        "120",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 1);
    let rs = records(&out);
    let arrival = |r: &serde_json::Value| {
        r["params"]["oncoming_at"].as_f64().unwrap()
            / r["params"]["oncoming_speed"].as_f64().unwrap()
    };
    let failed: Vec<&serde_json::Value> = rs.iter().filter(|r| r["status"] == "fail").collect();
    assert!(
        failed.len() >= 5 && failed.len() <= 60,
        "{} of 120 failed",
        failed.len()
    );
    for r in &failed {
        assert_eq!(r["monitors"]["collision"]["passed"], false, "{r}");
        let t = arrival(r);
        assert!(
            (2.5..=7.5).contains(&t),
            "a collision with the car arriving after {t} s: {r}"
        );
    }
    // Cars arriving early or late never collide.
    for r in rs.iter().filter(|r| !(2.5..=7.5).contains(&arrival(r))) {
        assert_eq!(r["status"], "pass", "{r}");
    }
}

/// A program not shipped: the roundabout map, the ego coming in from the west arm and
/// leaving north, an NPC car circulating from the south arm; a monitor checks the NPC car
/// keeps the ring's lane (radius 21.75 m) while on the ring. The ego's collisions are no
/// concern here (NPC cars do not yield), so the exit code is not checked.
const ROUNDABOUT: &str = r#"
mu = VarInterval(0.4, 1.0)
start = VarInterval(30.0, 50.0, unit = "m")
w = World()
rb = OpenDrive("maps/roundabout.xodr", friction = mu)
ego = AutonomousVehicle(loc = rb.onLane(road = "3", lane = 1, s = start), route = ["right"], speed = 6.0)
npc = Car(loc = rb.onLane(road = "4", lane = 1, s = 20.0), speed = 5.0, route = [], color = "red")
w.place(rb, ego, npc)

def off_ring(p):
    # Inside 22.1 m from the centre only the ring's lane (and the last metres of an entry,
    # which meets it tangentially) lie.
    r = hypot(p.x, p.z)
    return 0.4 - abs(r - 21.75) if r < 22.1 and r > 19.0 else 0.4
ring = Monitor(npc.pos.map(off_ring), unit = "m")
went = Monitor(npc.pos.map(lambda p: 1.0 if hypot(p.x, p.z) < 22.1 else -1.0), over = "eventually")
CollisionMonitor(ego)
test(horizon = 12.0, map = ("mu",))
"#;

#[test]
fn npc_traffic_circulates_on_the_roundabout_map_in_its_lane() {
    let dir = tempfile::tempdir().unwrap();
    let file = program(dir.path(), "ring.star", ROUNDABOUT);
    let out = dir.path().join("out");
    let o = campaign(&file, "4", &out);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    let rs = records(&out);
    assert_eq!(rs.len(), 4);
    for r in &rs {
        let ring = &r["monitors"]["ring"];
        assert_eq!(ring["passed"], true, "{r}");
        // It reached the ring (`went` passes "eventually": its robustness is the maximum).
        assert_eq!(
            r["monitors"]["went"]["robustness"].as_f64(),
            Some(1.0),
            "{r}"
        );
        // Nearer than 40 cm to its lane's circle all the way round.
        assert!(ring["robustness"].as_f64().unwrap() > 0.0, "{r}");
        assert_eq!(r["error"], serde_json::Value::Null);
    }
    let mus: Vec<f64> = rs
        .iter()
        .map(|r| r["params"]["mu"].as_f64().unwrap())
        .collect();
    assert!(
        mus.iter().any(|&m| m < 0.6) && mus.iter().any(|&m| m > 0.7),
        "{mus:?}"
    );
}

#[test]
fn the_map_may_be_open_and_a_changed_map_stops_resume() {
    let dir = tempfile::tempdir().unwrap();
    // A narrower copy of the bend, chosen by an open VarEnum.
    let narrow = std::fs::read_to_string(maps().join("bend.xodr"))
        .unwrap()
        .replace("a=\"3.500000000000\"", "a=\"3.000000000000\"");
    let src = r#"
which = VarEnum(["maps/bend.xodr", "maps/narrow.xodr"])
w = World()
m = OpenDrive(which)
v = AutonomousVehicle(loc = m.onLane(road = "1", lane = -1, s = 10.0))
w.place(m, v)
CollisionMonitor(v)
test(horizon = 4.0)
"#;
    let file = program(dir.path(), "open_map.star", src);
    std::fs::write(dir.path().join("maps/narrow.xodr"), narrow).unwrap();
    let out = dir.path().join("out");
    let o = campaign(&file, "4", &out);
    expect_code(&o, 0);
    let rs = records(&out);
    let edges: Vec<(String, f64)> = rs
        .iter()
        .map(|r| {
            (
                r["params"]["which"].as_str().unwrap().to_owned(),
                r["metrics"]["min_road_edge_m"].as_f64().unwrap(),
            )
        })
        .collect();
    // The ego keeps its lane's centre: 1.75 m from the edge on the bend, 1.5 m on the copy.
    for (map, edge) in &edges {
        let half = if map.contains("narrow") { 1.5 } else { 1.75 };
        assert!((edge - half).abs() < 0.05, "{map}: {edge}");
    }
    assert!(
        edges.iter().any(|(m, _)| m.contains("narrow"))
            && edges.iter().any(|(m, _)| !m.contains("narrow"))
    );
    // The files read enter campaign.json and its fingerprint.
    let campaign_json = std::fs::read_to_string(out.join("campaign.json")).unwrap();
    assert!(
        campaign_json.contains("maps/narrow.xodr") && campaign_json.contains("sha256"),
        "{campaign_json}"
    );
    // Change a map: --resume refuses, naming it; put it back: it resumes.
    let bend = dir.path().join("maps/bend.xodr");
    let before = std::fs::read_to_string(&bend).unwrap();
    std::fs::write(
        &bend,
        before.replacen("a=\"2.000000000000\"", "a=\"2.100000000000\"", 1),
    )
    .unwrap();
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("the file `maps/bend.xodr` that the scenario program reads changed"),
        "{stderr}"
    );
    std::fs::write(&bend, before).unwrap();
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    expect_code(&o, 0);
}

#[test]
fn what_a_map_holds_that_paracosm_does_not_use_is_named_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let file = program(
        dir.path(),
        "signals.star",
        "w = World()\nm = OpenDrive(\"maps/signs.xodr\")\nv = AutonomousVehicle(loc = m.onLane(road = \"1\", lane = -1, s = 10.0))\nw.place(m, v)\n",
    );
    let with_signals = std::fs::read_to_string(maps().join("bend.xodr")).unwrap().replace(
        "    <lanes>",
        "    <signals><signal s=\"20\" t=\"-3\" id=\"9\" dynamic=\"no\" orientation=\"+\" type=\"206\" subtype=\"-1\"/></signals>\n    <lanes>",
    );
    std::fs::write(dir.path().join("maps/signs.xodr"), with_signals).unwrap();
    let out = dir.path().join("out");
    let o = campaign(&file, "1", &out);
    expect_code(&o, 0);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(
            "warning: 1 <signals> element ignored: traffic signals and signs are not simulated"
        ) && stderr.contains("signs.xodr:"),
        "{stderr}"
    );
}

#[test]
fn wrong_roads_lanes_and_calls_on_a_map_are_refused_with_the_program_s_place() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "m.onLane(road = \"9\", lane = -1, s = 10.0)",
            "has no road \"9\": it has 1 road (1); run `paracosm-fuzz map",
        ),
        (
            "m.onLane(road = \"1\", lane = -3, s = 10.0)",
            "has no lane -3 at s = 10 m; its lanes there:",
        ),
        (
            "m.onLane(road = \"1\", lane = -1, s = 400.0)",
            "s = 400 m is outside road \"1\"",
        ),
        (
            "m.onLane(-1, 10.0)",
            "an OpenDrive map's onLane takes road=, lane= and s= by name",
        ),
        ("m.onLane(road = \"1\", lane = 0, s = 10.0)", "not 0"),
    ];
    for (i, (call, phrase)) in cases.iter().enumerate() {
        let src = format!("w = World()\nm = OpenDrive(\"maps/bend.xodr\")\nv = AutonomousVehicle(loc = {call})\nw.place(m, v)\n");
        let file = program(dir.path(), &format!("bad{i}.star"), &src);
        let o = fuzz(&[
            file.to_str().unwrap(),
            "--budget",
            "1",
            "--out",
            dir.path().join(format!("o{i}")).to_str().unwrap(),
        ]);
        expect_code(&o, 2);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains(phrase),
            "{call}: `{phrase}` not in\n{stderr}"
        );
        assert!(
            stderr.contains(&format!("bad{i}.star:3:")),
            "{call}: no place in\n{stderr}"
        );
    }
    // A map that is not there.
    let file = program(
        dir.path(),
        "missing.star",
        "w = World()\nm = OpenDrive(\"maps/nowhere.xodr\")\n",
    );
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        dir.path().join("om").to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("cannot read the OpenDRIVE map")
            && stderr.contains("nowhere.xodr")
            && stderr.contains("missing.star:2:"),
        "{stderr}"
    );
}

#[test]
fn pieces_of_the_program_may_stand_beside_a_map_but_not_on_its_lanes() {
    let dir = tempfile::tempdir().unwrap();
    // A short segment at the origin: inside the roundabout's island (the ring's lanes start
    // 20 m out), so it touches no lane; at the junction's centre it lies on its lanes.
    let program_with = |map: &str, name: &str| {
        program(
            dir.path(),
            name,
            &format!(
                "w = World()\nm = OpenDrive(\"maps/{map}\")\nr = RoadSegment(len = 8.0)\nv = AutonomousVehicle(loc = m.onLane(road = \"1\", lane = 1, s = 40.0))\nw.place(m, r, v)\ntest(horizon = 1.0)\n"
            ),
        )
    };
    let ok = program_with("roundabout.xodr", "island.star");
    let o = fuzz(&[
        ok.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        dir.path().join("a").to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let bad = program_with("junction.xodr", "centre.star");
    let o = fuzz(&[
        bad.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        dir.path().join("b").to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("road pieces overlap: OpenDrive m") && stderr.contains("RoadSegment r"),
        "{stderr}"
    );
    // connect cannot join a piece to the map.
    let joined = program(
        dir.path(),
        "joined.star",
        "w = World()\nm = OpenDrive(\"maps/bend.xodr\")\nr = RoadSegment(len = 8.0)\nr.connect((r.TWO, m, m.ONE))\n",
    );
    let o = fuzz(&[
        joined.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        dir.path().join("c").to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("joined.star:4:"), "{stderr}");
    // Lane changes are not available on a map, and say so.
    let change = program(
        dir.path(),
        "change.star",
        "w = World()\nm = OpenDrive(\"maps/bend.xodr\")\nv = AutonomousVehicle(loc = m.onLane(road = \"1\", lane = -1, s = 10.0))\nc = Car(loc = m.onLane(road = \"1\", lane = -1, s = 40.0), speed = 5.0, lane_change = ChangeLane(to = 1, at = 2.0))\nw.place(m, v, c)\n",
    );
    let o = fuzz(&[
        change.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        dir.path().join("d").to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("on an OpenDRIVE map"), "{stderr}");
}

#[test]
fn vision_keeps_its_lane_round_the_map_bend() {
    // The camera-only system steers by the markings the map's lanes are drawn with.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v");
    let o = fuzz(&[
        "curve-pedestrian",
        "--sut",
        "vision",
        "--budget",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    for r in records(&out) {
        assert_eq!(r["monitors"]["offroad"]["passed"], true, "{r}");
        // Round the bend (the arc starts 120 m ahead of the start) and within 10 cm of the
        // lane's centre all the way (its edge is 1.75 m away).
        assert!(
            r["metrics"]["distance_travelled_m"].as_f64().unwrap() > 150.0,
            "{r}"
        );
        assert!(
            r["metrics"]["min_road_edge_m"].as_f64().unwrap() > 1.65,
            "{r}"
        );
    }
}

/// A route's turn that a fork of the map lacks is an error at load naming the turn, the
/// road and lane that end there and the turns the fork offers (with their connecting roads and
/// angles), as on paracosm's own pieces
/// (the ring's forks offer straight on and an exit to the right: `left` was taken as
/// straight on without a word). The turns it offers load.
#[test]
fn a_turn_a_map_fork_lacks_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let src = |route: &str| {
        format!(
            "m = OpenDrive(\"maps/roundabout.xodr\")\nw = World()\nc = Car(loc = m.onLane(road = \"1\", lane = 1, s = 40.0), speed = 6.0, route = {route})\nv = AutonomousVehicle(loc = m.onLane(road = \"3\", lane = -1, s = 55.0), speed = 0.0)\nw.place(m, v, c)\nCollisionMonitor(v)\n"
        )
    };
    let file = program(dir.path(), "left.star", &src("[\"left\", \"right\"]"));
    let o = fuzz(&[
        file.to_str().unwrap(),
        "--budget",
        "1",
        "--out",
        dir.path().join("o1").to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("Car c: the route's turn 1 (\"left\") is not possible at the fork")
            && stderr.contains(
                "roundabout.xodr ends: it offers \"straight\" (road:21, +45°) and \"right\" (road:41, -67°) there"
            )
            && stderr.contains("left.star:5:1"),
        "{stderr}"
    );
    for route in ["[\"straight\", \"right\"]", "[\"right\"]", "[]"] {
        let file = program(dir.path(), "ok.star", &src(route));
        let o = fuzz(&[
            file.to_str().unwrap(),
            "--budget",
            "1",
            "--out",
            dir.path().join("o2").to_str().unwrap(),
            "--force",
        ]);
        assert!(
            o.status.code() == Some(0) || o.status.code() == Some(1),
            "{route}: {o:?}"
        );
    }
}

/// `text` with every `<geometry>`'s `x` and `y` attributes moved by `by`, OpenDRIVE m.
fn moved_map(text: &str, by: [f64; 2]) -> String {
    let mut out = String::new();
    for (i, part) in text.split("<geometry ").enumerate() {
        if i == 0 {
            out.push_str(part);
            continue;
        }
        out.push_str("<geometry ");
        let end = part.find('>').unwrap();
        let mut head = part[..end].to_owned();
        for (k, key) in [" x=\"", " y=\""].into_iter().enumerate() {
            let at = head.find(key).unwrap() + key.len();
            let len = head[at..].find('"').unwrap();
            let v: f64 = head[at..at + len].parse().unwrap();
            head.replace_range(at..at + len, &format!("{}", v + by[k]));
        }
        out.push_str(&head);
        out.push_str(&part[end..]);
    }
    out
}

/// Hostile input, second round, requirement 2: the same junction study with its map moved to
/// x = 10^8 m (where an f32 resolves 8 m) gives the same verdicts as at the origin, names the
/// move in a warning, and exports the ego's start in the file's own coordinates.
#[test]
fn a_map_far_from_the_origin_gives_the_verdicts_it_gives_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let src = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/opendrive_junction.star"),
    )
    .unwrap();
    let near = program(&dir.path().join("near"), "junction.star", &src);
    let far = program(&dir.path().join("far"), "junction.star", &src);
    let by = [1e8, -2.5e6];
    let text = std::fs::read_to_string(maps().join("junction.xodr")).unwrap();
    std::fs::write(
        dir.path().join("far/maps/junction.xodr"),
        moved_map(&text, by),
    )
    .unwrap();
    let (out_near, out_far) = (dir.path().join("out-near"), dir.path().join("out-far"));
    let o = campaign(&near, "24", &out_near);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("moved by"));
    let o = campaign(&far, "24", &out_far);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("the map lies 100031.2 km from the origin")
            && stderr.contains("it is simulated moved by (-100000000, 2500000) m"),
        "{stderr}"
    );
    let (a, b) = (records(&out_near), records(&out_far));
    assert_eq!(a.len(), 24);
    let failed = a.iter().filter(|r| r["status"] == "fail").count();
    assert!(
        failed > 0 && failed < 24,
        "{failed} of 24 failed at the origin"
    );
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x["status"], y["status"], "{x}\n{y}");
        assert_eq!(x["monitors"], y["monitors"]);
    }
    // The export writes the ego's start where the file puts it: 10^8 m east.
    let first_fail = b.iter().find(|r| r["status"] == "fail").unwrap()["id"]
        .as_u64()
        .unwrap();
    for (out, shift) in [(&out_near, [0.0, 0.0]), (&out_far, by)] {
        let ex = out.join("export");
        let o = fuzz(&[
            "export",
            out.join("results.jsonl").to_str().unwrap(),
            "--id",
            &first_fail.to_string(),
            "--out",
            ex.to_str().unwrap(),
        ]);
        expect_code(&o, 0);
        let xosc = std::fs::read_to_string(ex.join(format!("test_{first_fail}.xosc"))).unwrap();
        let at = xosc.find("<WorldPosition ").unwrap();
        let el = &xosc[at..at + xosc[at..].find('>').unwrap()];
        let num = |k: &str| -> f64 {
            let v = &el[el.find(&format!(" {k}=\"")).unwrap() + k.len() + 3..];
            v[..v.find('"').unwrap()].parse().unwrap()
        };
        // The west arm's lane 1 at s = 45: x = -45 - 6 (the junction's half width), y = -1.75.
        println!(
            "export from {}: ego at ({}, {})",
            out.display(),
            num("x"),
            num("y")
        );
        assert!((num("x") - shift[0] + 51.0).abs() < 8.0, "{el}");
        assert!((num("y") - shift[1]).abs() < 8.0, "{el}");
    }
}

/// Issue 48, requirement 2, end to end: on CARLA's Town01 (`tests/data/maps/carla`), the ego
/// coming along lane -1 of road 0 into junction 43 turns left onto road 16 with
/// `route = ["left"]` or `route = ["road:56"]` (the connecting road's id), and goes straight on
/// onto road 1 with `["straight"]`: paracosm offered "straight" alone there before.
#[test]
fn the_ego_takes_every_turn_a_carla_junction_gives() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("maps")).unwrap();
    std::fs::copy(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/maps/carla/Town01.xodr"),
        dir.path().join("maps/Town01.xodr"),
    )
    .unwrap();
    let src = |route: &str| {
        format!(
            r#"m = OpenDrive("maps/Town01.xodr")
w = World()
v = AutonomousVehicle(loc = m.onLane(road = "0", lane = -1, s = 20.0), route = {route}, speed = 6.0)
w.place(m, v)
on16 = m.onLane(road = "16", lane = -1, s = 10.0)
on1 = m.onLane(road = "1", lane = -1, s = 10.0)
Monitor(v.pos.map(lambda p: 3.0 - dist(p, on16)), name = "road16", over = "eventually")
Monitor(v.pos.map(lambda p: 3.0 - dist(p, on1)), name = "road1", over = "eventually")
test(horizon = 10.0)
"#
        )
    };
    for (k, (route, onto)) in [
        ("[\"left\"]", "road16"),
        ("[\"road:56\"]", "road16"),
        ("[\"straight\"]", "road1"),
    ]
    .into_iter()
    .enumerate()
    {
        let file = dir.path().join(format!("turn{k}.star"));
        std::fs::write(&file, src(route)).unwrap();
        let out = dir.path().join(format!("out{k}"));
        let o = campaign(&file, "1", &out);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{route}: {o:?}");
        let r = &records(&out)[0];
        for m in ["road16", "road1"] {
            assert_eq!(r["monitors"][m]["passed"], m == onto, "{route}: {m}: {r}");
        }
    }
}

/// Left-hand traffic (`rule="LHT"`, documented in docs/maps.md with
/// `examples/left_hand_traffic.star`): on esmini's three-way junction, whose roads all say
/// `rule="LHT"`, lane 1 of road 0 drives along increasing `s` (towards the junction, where
/// the ego turns left into road 2), and lane -1 of road 2 towards the junction. The same
/// program on the same map with the rule taken out drives each lane the other way.
#[test]
fn left_hand_traffic_drives_each_lane_the_other_way() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let lht = std::fs::read_to_string(
        root.join("tests/data/maps/esmini/simple_3way_intersection_lht.xodr"),
    )
    .unwrap();
    assert_eq!(lht.matches("rule=\"LHT\"").count(), 6);
    let dir = tempfile::tempdir().unwrap();
    // The ego's first and last route points, world [x, z] m, and the car's first two.
    let drive = |map: &str, route: &str| {
        std::fs::write(dir.path().join("m.xodr"), map).unwrap();
        let p = dir.path().join("p.star");
        std::fs::write(
            &p,
            format!(
                "w = World()\nm = OpenDrive(\"m.xodr\")\n\
                 v = AutonomousVehicle(loc = m.onLane(road = \"0\", lane = 1, s = 50.0), \
                 route = {route})\n\
                 c = Car(loc = m.onLane(road = \"2\", lane = -1, s = 50.0), speed = 5.0)\n\
                 w.place(m, v, c)\ntest(horizon = 5.0)\n"
            ),
        )
        .unwrap();
        let s = paracosm_scenarios::load(p.to_str().unwrap()).unwrap();
        let a = s
            .space()
            .decode(&paracosm_generators::Point::default())
            .unwrap();
        let w = s.instantiate(&a).unwrap();
        let route = &w.ego.route;
        (
            route[0],
            route[route.len() - 1],
            w.cars[0].path[0],
            w.cars[0].path[1],
        )
    };
    // Road 0 runs along +x from the origin to the junction at x = 100.
    let (first, last, car0, car1) = drive(&lht, "[\"left\"]");
    assert!(
        first[0] < last[0] && last[0] > 100.0,
        "{first:?} -> {last:?}"
    );
    // Road 2 leaves the junction: its lane -1 comes back towards it, so the car's path
    // approaches the junction's centre.
    let junction = [105.0, 0.0];
    let dist = |p: [f64; 2]| (p[0] - junction[0]).hypot(p[1] - junction[1]);
    assert!(dist(car1) < dist(car0), "{car0:?} -> {car1:?}");
    // Right-hand traffic: lane 1 of road 0 drives away from the junction, to x < 50.
    let rht = lht.replace(" rule=\"LHT\"", "");
    let (first, last, car0, car1) = drive(&rht, "None");
    assert!(
        last[0] < first[0] && last[0] < 50.0,
        "{first:?} -> {last:?}"
    );
    assert!(dist(car1) > dist(car0), "{car0:?} -> {car1:?}");
}

/// One world per campaign: a map's query index and collision mesh are built once per program
/// and shared by its tests (`MapRef`'s cache, docs/performance.md), read-only, so a campaign
/// on a map written by others (CARLA's Town01, 7 tests at a time on two workers) gives the
/// same records with one worker and with two, and the same as each test run alone.
#[test]
fn a_map_campaign_gives_the_same_records_for_any_number_of_workers() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        root.join("tests/data/maps/carla/Town01.xodr"),
        dir.path().join("Town01.xodr"),
    )
    .unwrap();
    let p = dir.path().join("town.star");
    std::fs::write(
        &p,
        "speed = VarInterval(4.0, 14.0, unit = \"m/s\")\n\
         lead_at = VarInterval(8.0, 30.0, unit = \"m\")\n\
         w = World()\nm = OpenDrive(\"Town01.xodr\")\n\
         v = AutonomousVehicle(loc = m.onLane(road = \"0\", lane = -1, s = 2.0), \
         route = [\"left\"], speed = speed)\n\
         lead = Car(loc = m.onLane(road = \"0\", lane = -1, s = lead_at), speed = 3.0, \
         route = [\"left\"])\n\
         w.place(m, v, lead)\nCollisionMonitor(v)\ntest(horizon = 6.0)\n",
    )
    .unwrap();
    let run = |jobs: &str, budget: &str, name: &str| {
        let out = dir.path().join(name);
        let o = fuzz(&[
            p.to_str().unwrap(),
            "--budget",
            budget,
            "--jobs",
            jobs,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
        records(&out)
            .into_iter()
            .map(|mut r| {
                r.as_object_mut().unwrap().remove("wall_ms");
                r
            })
            .collect::<Vec<_>>()
    };
    let one = run("1", "14", "one");
    let two = run("2", "14", "two");
    assert_eq!(one.len(), 14);
    assert_eq!(one, two);
    // Some tests end in a collision with the lead car and some do not: the shared map is
    // the same world for every test, and the actors are each test's own.
    let failed = one.iter().filter(|r| r["status"] == "fail").count();
    assert!(0 < failed && failed < 14, "{failed} of 14 failed");
}

/// A road `<link>` naming a road the map lacks loads with a warning that names the link and
/// its line, and the road ends there (as esmini reads it): the ego's route stops at the road's
/// end, and the campaign runs.
#[test]
fn a_link_to_a_road_the_map_lacks_is_a_warning_and_the_road_ends_there() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        root.join("tests/data/maps/faults/missing_link_target.xodr"),
        dir.path().join("m.xodr"),
    )
    .unwrap();
    let p = dir.path().join("p.star");
    std::fs::write(
        &p,
        "w = World()\nm = OpenDrive(\"m.xodr\")\n\
         v = AutonomousVehicle(loc = m.onLane(road = \"1\", lane = -1, s = 10.0))\n\
         w.place(m, v)\nCollisionMonitor(v)\ntest(horizon = 2.0)\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = campaign(&p, "1", &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{stderr}");
    assert!(
        stderr.contains("<successor> of road \"1\" names road \"42\", which the map does not have: the road ends there")
            && stderr.contains("m.xodr:5"),
        "{stderr}"
    );
    let s = paracosm_scenarios::load(p.to_str().unwrap()).unwrap();
    let a = s
        .space()
        .decode(&paracosm_generators::Point::default())
        .unwrap();
    let route = s.instantiate(&a).unwrap().ego.route;
    let last = route[route.len() - 1];
    assert!((last[0] - 100.0).abs() < 0.01, "the route ends at {last:?}");
}
