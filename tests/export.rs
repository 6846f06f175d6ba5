//! Issue 21, requirement 5: `paracosm-fuzz export` writes a recorded test as OpenSCENARIO with
//! its network as OpenDRIVE. The pedestrian's trigger becomes a distance condition at the
//! trigger distance the test drew; cars follow the trajectories they drove; a network built
//! from pieces round-trips through the OpenDRIVE importer with its lanes where they were, to
//! a millimetre; the same test exports to the same bytes. (The XSD check of both files is in
//! python/tests/test_export.py, with the ASAM schemas that the `scenariogeneration` package
//! ships.)

use std::path::Path;

use paracosm_engine::network::opendrive::import;
use paracosm_engine::{Lane, PieceId};

mod common;
use common::{campaign, fuzz, records};

fn export(results: &Path, id: u64, out: &Path) -> (String, String) {
    export_with(results, id, out, &[])
}

/// [`export`] with more arguments.
fn export_with(results: &Path, id: u64, out: &Path, more: &[&str]) -> (String, String) {
    let id_text = id.to_string();
    let mut args = vec![
        "export",
        results.to_str().unwrap(),
        "--id",
        &id_text,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(more);
    let o = fuzz(&args);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let xosc = std::fs::read_to_string(out.join(format!("test_{id}.xosc"))).unwrap();
    let xodr = std::fs::read_to_string(out.join(format!("test_{id}.xodr"))).unwrap();
    (xosc, xodr)
}

/// The value of attribute `key` in the first element that starts with `tag` (`<Tag `).
fn attr(doc: &str, tag: &str, key: &str) -> f64 {
    let at = doc
        .find(&format!("<{tag} "))
        .unwrap_or_else(|| panic!("no <{tag}>"));
    let rest = &doc[at..];
    let end = rest.find('>').unwrap();
    let el = &rest[..end];
    let k = el
        .find(&format!(" {key}=\""))
        .unwrap_or_else(|| panic!("no {key} in {el}"));
    let v = &el[k + key.len() + 3..];
    v[..v.find('"').unwrap()].parse().unwrap()
}

#[test]
fn a_failing_pedestrian_test_exports_with_its_trigger_as_a_distance_condition() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let o = fuzz(&[
        "curve-pedestrian",
        "--budget",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "some tests fail: {o:?}");
    let rs = records(&out);
    let failed = rs.iter().find(|r| r["status"] == "fail").unwrap();
    let id = failed["id"].as_u64().unwrap();
    let trigger = failed["params"]["trigger_distance"].as_f64().unwrap();
    let (xosc, xodr) = export(&out.join("results.jsonl"), id, &dir.path().join("x"));
    // The map is copied as it is.
    let bend = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/maps/bend.xodr"),
    )
    .unwrap();
    assert_eq!(xodr, bend);
    assert!(xosc.contains("<LogicFile filepath=\"test_"), "{xosc}");
    // The walk starts when the ego comes within the drawn trigger distance, measured in the
    // recording from the ego's centre and written from its rear axle (the file's reference
    // point), 0.3 × 4.5 m behind: farther from a pedestrian ahead by up to that (within a
    // step's travel).
    let d = attr(&xosc, "DistanceCondition", "value");
    let behind = 0.3 * 4.5;
    assert!(
        d > trigger - 0.5 && d < trigger + behind + 0.5,
        "condition at {d} m, trigger {trigger} m"
    );
    assert!(xosc.contains("<EntityRef entityRef=\"ego\"/>"));
    // The parameters are declared with the values the test drew.
    assert!(
        xosc.contains(&format!(
            "name=\"trigger_distance\" parameterType=\"double\" value=\"{trigger}\""
        )),
        "{xosc}"
    );
    // The ego starts where the program puts it: road 1, lane -1, s = 10 (y = -1.75), its
    // rear axle 1.35 m behind.
    assert!((attr(&xosc, "WorldPosition", "x") - (10.0 - behind)).abs() < 1e-9);
    assert_eq!(attr(&xosc, "WorldPosition", "y"), -1.75);
    // Exporting again gives the same bytes.
    let (again, _) = export(&out.join("results.jsonl"), id, &dir.path().join("y"));
    assert_eq!(again, xosc);
}

#[test]
fn cars_follow_the_trajectories_they_drove() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("j");
    let o = fuzz(&[
        "opendrive-junction",
        "--budget",
        "12",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    let r = &records(&out)[3];
    let at = r["params"]["oncoming_at"].as_f64().unwrap();
    let (xosc, _) = export(&out.join("results.jsonl"), 3, &dir.path().join("x"));
    // car1 is the oncoming car: it starts on the east arm (road 1 runs east from x = 12),
    // lane 1 (y = +1.75), `oncoming_at` m out, and its trajectory's first vertex is there:
    // its rear axle (the file's reference point of a vehicle), which for a car facing west
    // lies east of its centre by its bounding box's offset.
    let car1 = &xosc[xosc.find("<ScenarioObject name=\"car1\"").unwrap()..];
    let ahead = attr(car1, "Center", "x");
    assert!((ahead - 0.3 * attr(car1, "Dimensions", "length")).abs() < 1e-9);
    assert_eq!(attr(car1, "RearAxle", "positionX"), 0.0);
    let traj = &xosc[xosc.find("<Trajectory name=\"car1 as driven\"").unwrap()..];
    let x = attr(traj, "WorldPosition", "x");
    let y = attr(traj, "WorldPosition", "y");
    assert!(
        (x - (12.0 + at + ahead)).abs() < 0.05 && (y - 1.75).abs() < 0.05,
        "({x}, {y}) vs at {at}"
    );
    let vertices = traj[..traj.find("</Trajectory>").unwrap()]
        .matches("<Vertex ")
        .count();
    // At every step of the test (10 s, or until a collision stopped it), and the start.
    let simulated = r["metrics"]["simulated_s"].as_f64().unwrap();
    let expected = (simulated / paracosm_engine::DEFAULT_DT_S).round() as usize + 1;
    assert_eq!(vertices, expected, "{vertices} vertices for {simulated} s");
}

/// `dir/g`: a one-test campaign of `grid-world` (the ego turns at its junctions).
fn grid_world_test(dir: &Path) -> std::path::PathBuf {
    let out = dir.join("g");
    let o = fuzz(&[
        "grid-world",
        "--budget",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    out
}

/// By default the ego exports as the trajectory it drove (no route): a timed polyline whose
/// vertices, one at every step, follow the ego from its start; with `--ego-route`, as its
/// route.
#[test]
fn the_ego_exports_as_the_trajectory_it_drove() {
    let dir = tempfile::tempdir().unwrap();
    let out = grid_world_test(dir.path());
    let (xosc, _) = export(&out.join("results.jsonl"), 0, &dir.path().join("x"));
    assert!(!xosc.contains("<Route "), "no route by default");
    let traj = &xosc[xosc
        .find("<Trajectory name=\"ego as driven\"")
        .expect("the ego's trajectory")..];
    let traj = &traj[..traj.find("</Trajectory>").unwrap()];
    // Its first vertex is where Init puts the ego.
    let init = &xosc[xosc.find("<Private entityRef=\"ego\"").unwrap()..];
    for key in ["x", "y", "h"] {
        let (a, b) = (
            attr(traj, "WorldPosition", key),
            attr(init, "WorldPosition", key),
        );
        assert!((a - b).abs() < 1e-9, "{key}: {a} vs {b}");
    }
    let r = &records(&out)[0];
    let simulated = r["metrics"]["simulated_s"].as_f64().unwrap();
    let vertices = traj.matches("<Vertex ").count();
    let expected = (simulated / paracosm_engine::DEFAULT_DT_S).round() as usize + 1;
    assert_eq!(vertices, expected, "{vertices} vertices for {simulated} s");
    let (routed, _) = export_with(
        &out.join("results.jsonl"),
        0,
        &dir.path().join("y"),
        &["--ego-route"],
    );
    assert!(routed.contains("<Route ") && !routed.contains("ego as driven"));
}

/// The ego's route exports (`--ego-route`) as waypoints that head along the route (every one
/// had `h = 0`, and a simulator matches a waypoint to the lane of its heading).
#[test]
fn the_egos_route_waypoints_head_along_the_route() {
    let dir = tempfile::tempdir().unwrap();
    let out = grid_world_test(dir.path());
    let (xosc, _) = export_with(
        &out.join("results.jsonl"),
        0,
        &dir.path().join("x"),
        &["--ego-route"],
    );
    let route = &xosc[xosc.find("<Route ").unwrap()..xosc.find("</Route>").unwrap()];
    let points: Vec<(f64, f64, f64)> = route
        .split("<Waypoint ")
        .skip(1)
        .map(|w| {
            (
                attr(w, "WorldPosition", "x"),
                attr(w, "WorldPosition", "y"),
                attr(w, "WorldPosition", "h"),
            )
        })
        .collect();
    assert!(points.len() > 20, "{}", points.len());
    let wrap = |a: f64| {
        (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    for pair in points.windows(2) {
        let ((x0, y0, h0), (x1, y1, _)) = (pair[0], pair[1]);
        // OpenSCENARIO's y is paracosm's -z, and its headings are paracosm's: the chord to
        // the next waypoint, 10 m on, is within most of a right-angle turn of the heading.
        let chord = (y1 - y0).atan2(x1 - x0);
        assert!(wrap(chord - h0).abs() < 1.2, "{pair:?}");
    }
    // The route turns (right, right, left): its waypoints head more than one way.
    let turned = points.iter().any(|p| wrap(p.2 - points[0].2).abs() > 1.0);
    assert!(turned, "{points:?}");
}

/// Segments, a clothoid, an arc and a cross-intersection, with a car so that the world has
/// traffic.
const PIECES: &str = r#"
w = World()
a = RoadSegment(len = 60.0)
ease = Clothoid(length = 30.0, curv_start = 0.0, curv_end = 0.02)
bend = Arc(radius = 50.0, angle = 0.6)
j = CrossIntersection()
out = RoadSegment(len = 40.0)
side = RoadSegment(len = 30.0, nlanes = 2)
a.connect((a.TWO, ease, ease.ONE), (ease.TWO, bend, bend.ONE), (bend.TWO, j, j.THREE), (j.ONE, out, out.ONE), (j.TWO, side, side.TWO))
v = AutonomousVehicle(loc = a.onLane(1, 10), route = ["straight"])
c = Car(loc = out.onLane(-1, 30), speed = 5.0, route = ["left"])
w.place(a, ease, bend, j, out, side, v, c)
test(horizon = 2.0)
"#;

#[test]
fn a_network_of_pieces_round_trips_through_the_opendrive_importer() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("pieces.star");
    std::fs::write(&file, PIECES).unwrap();
    let out = dir.path().join("o");
    let o = campaign(&file, "1", &out);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    let (_, xodr) = export(&out.join("results.jsonl"), 0, &dir.path().join("x"));
    let map = import("test_0.xodr", &xodr).unwrap().map;
    // The same network, built by the program.
    let scenario = paracosm_scenarios::load(file.to_str().unwrap()).unwrap();
    let mut network = None;
    let a = scenario.space().decode(&paracosm_generators::Point {
        discrete: vec![],
        continuous: vec![],
    });
    scenario
        .run_with(
            &a.unwrap(),
            0,
            &mut paracosm_scenarios::RunOptions {
                on_world: Some(&mut |w: &paracosm_engine::WorldSpec| {
                    network = Some(w.network.clone())
                }),
                ..Default::default()
            },
        )
        .unwrap();
    let network = network.unwrap();
    // Every lane of every road piece, every metre: paracosm's lane k is OpenDRIVE's -k.
    let (mut worst, mut compared) = (0.0f64, 0);
    for (i, p) in network.pieces().iter().enumerate() {
        let Some(length) = p.kind.road_length_m() else {
            continue;
        };
        let half = (p.kind.lanes() / 2) as i32;
        for k in (-half..=half).filter(|&k| k != 0) {
            for metre in 0..=length.floor() as i32 {
                let s = f64::from(metre);
                let a = network.on_lane(PieceId(i), Lane::Driving(k), s).unwrap();
                let lane = map.lane_at(&(i + 1).to_string(), -k, s).unwrap();
                let (b, _) = map.lanes[lane].pose(s);
                worst = worst.max((a.pos_m[0] - b[0]).hypot(a.pos_m[2] - b[1]));
                compared += 1;
            }
        }
    }
    // 60 + 30 + 30 + 40 + 30 m of road, two lanes, a point every metre.
    assert_eq!(compared, 390);
    assert!(worst < 1e-3, "lanes moved by {worst} m in the round trip");
    println!("round trip: {compared} lane points, worst {worst:.2e} m");
    // The junction's lane paths are its connecting roads: every point of each path lies on
    // the imported lane's centre line.
    let junction = network
        .pieces()
        .iter()
        .position(|p| p.kind.road_length_m().is_none())
        .unwrap();
    let paths = network.lane_paths(PieceId(junction));
    assert!(paths.len() >= 12, "{} paths", paths.len());
    for (n, path) in paths.iter().enumerate() {
        let id = (1000 * (junction + 1) + n).to_string();
        let lane = map.lane_at(&id, -1, 0.0).unwrap();
        let centre = &map.lanes[lane].centre;
        for q in &path.points {
            let d = centre
                .iter()
                .map(|c| (c[0] - q[0]).hypot(c[1] - q[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 0.3, "path {n}: a point {d} m from the imported lane");
        }
        // Linked: where a road comes in, its imported lane leads into the path; the north
        // port is a dead end, with nothing to come from.
        let entry = (PieceId(junction), path.entry.0);
        let fed = network.links().iter().any(|l| l.a == entry || l.b == entry);
        assert_eq!(
            map.lanes.iter().any(|l| l.successors.contains(&lane)),
            fed,
            "path {n} ({id}), entering by port {}",
            path.entry.0
        );
    }
}

/// An OpenSCENARIO campaign whose variation chooses the road network among five maps (ALKS
/// 4.3.1's `Road`) exports a test on a curve with that curve's map, byte for byte, not the
/// template's straight road.
#[test]
fn an_openscenario_test_exports_the_map_it_ran_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c");
    let alks = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks");
    let variation = alks.join("alks_scenario_4_3_1_follow_lead_vehicle_comfortable_variation.xosc");
    let o = campaign(&variation, "4", &out);
    assert!(matches!(o.status.code(), Some(0 | 1 | 3)), "{o:?}");
    let on_curve = records(&out)
        .into_iter()
        .find(|r| {
            r["status"] != "error"
                && r["params"]["Road"]
                    .as_str()
                    .is_some_and(|m| !m.contains("straight"))
        })
        .expect("a test on a curve among the first four");
    let road = on_curve["params"]["Road"].as_str().unwrap();
    let id = on_curve["id"].as_u64().unwrap();
    let (_, xodr) = export(&out.join("results.jsonl"), id, &dir.path().join("x"));
    let map = std::fs::read_to_string(alks.join("concrete_scenarios").join(road)).unwrap();
    println!("test {id} ran on {road}");
    assert!(
        xodr == map,
        "test {id} ran on {road}; the export wrote another map"
    );
}
