//! Issue 21, requirement 2: OpenDRIVE maps read through the `xodr` crate. The lane centre
//! lines of the shipped bend agree with the same bend built from paracosm's own pieces at
//! every metre; width polynomials, lane offsets and paramPoly3 records agree with closed
//! forms; routes through the junction and the roundabout take the turns asked; the surface
//! answers on the map; what paracosm does not use is named in warnings.

use std::path::PathBuf;
use std::sync::Arc;

use paracosm_engine::network::opendrive::{import, Imported};
use paracosm_engine::network::{PieceKind, RoadMap, Surface, Turn, GROUND_FRICTION};
use paracosm_engine::{Lane, Network, PieceId};

fn shipped(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios/maps")
        .join(name);
    std::fs::read_to_string(p).unwrap()
}

fn map_network(name: &str, text: &str) -> (Network, PieceId, Arc<RoadMap>) {
    let Imported { map, .. } = import(name, text).unwrap();
    let mut n = Network::new();
    let id = n.add_map("OpenDrive m", map.clone(), 0.8).unwrap();
    (n, id, map)
}

/// The bend of `maps/bend.xodr` built from paracosm's pieces: 100 m straight, a clothoid from
/// curvature 0 to 1/40, an arc of radius 40 m turning 1 rad, the mirror clothoid, 100 m.
fn bend_from_pieces() -> (Network, Vec<(PieceId, f64)>) {
    let k = 1.0 / 40.0;
    let kinds = [
        PieceKind::Segment {
            length_m: 100.0,
            lanes: 2,
            friction: 0.8,
        },
        PieceKind::Clothoid {
            length_m: 30.0,
            curv_start: 0.0,
            curv_end: k,
            lanes: 2,
            friction: 0.8,
        },
        PieceKind::Arc {
            radius_m: 40.0,
            angle_rad: 1.0,
            lanes: 2,
            friction: 0.8,
        },
        PieceKind::Clothoid {
            length_m: 30.0,
            curv_start: k,
            curv_end: 0.0,
            lanes: 2,
            friction: 0.8,
        },
        PieceKind::Segment {
            length_m: 100.0,
            lanes: 2,
            friction: 0.8,
        },
    ];
    let mut n = Network::new();
    let mut pieces = Vec::new();
    let mut start = 0.0;
    for (i, kind) in kinds.into_iter().enumerate() {
        let length = kind.road_length_m().unwrap();
        let id = n.add(&format!("piece {i}"), kind).unwrap();
        if let Some(&(prev, _)) = pieces.last() {
            n.connect(prev, 1, id, 0).unwrap();
        }
        pieces.push((id, start));
        start += length;
    }
    (n, pieces)
}

#[test]
fn the_bend_map_s_lane_centres_agree_with_the_same_bend_built_from_pieces_at_every_metre() {
    let (map_net, map_id, _) = map_network("bend.xodr", &shipped("bend.xodr"));
    let (pieces_net, pieces) = bend_from_pieces();
    // paracosm's lane 1 (right of the line, along it) is OpenDRIVE's lane -1; the sidewalk on
    // the right is lane -2.
    let pairs = [
        (Lane::Driving(1), -1),
        (Lane::Driving(-1), 1),
        (Lane::SideWalk, -2),
        (Lane::OppositeSideWalk, 2),
    ];
    let (mut worst_m, mut worst_rad, mut compared) = (0.0f64, 0.0f64, 0);
    for metre in 0..=300 {
        let s = f64::from(metre);
        // The piece holding s (the later one at a joint).
        let &(piece, from) = pieces.iter().rev().find(|(_, from)| *from <= s).unwrap();
        let at = (s - from).min(pieces_net.piece(piece).kind.road_length_m().unwrap());
        for (lane, od) in pairs {
            let a = pieces_net.on_lane(piece, lane, at).unwrap();
            let b = map_net.on_map_lane(map_id, "1", od, s).unwrap();
            let d = (a.pos_m[0] - b.pos_m[0]).hypot(a.pos_m[2] - b.pos_m[2]);
            worst_m = worst_m.max(d);
            if matches!(lane, Lane::Driving(_)) {
                let dh = paracosm_engine::network::wrap(a.heading_rad - b.heading_rad).abs();
                worst_rad = worst_rad.max(dh);
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 301 * 4);
    // xodr stores points in f32: about 2e-5 m at these coordinates.
    assert!(worst_m < 1e-3, "worst distance {worst_m} m");
    // Headings from central differences of the baked centre line, interpolated.
    assert!(worst_rad < 1e-3, "worst heading {worst_rad} rad");
    println!("bend: {compared} lane points, worst {worst_m:.2e} m, {worst_rad:.2e} rad");
}

/// A straight road 100 m long with a lane offset `a + b·s` and right lane width
/// `3 + 0.01·s`, left lane 3.5 m.
fn offset_map(record: &str, length: f64, offset: (f64, f64)) -> String {
    format!(
        r#"<OpenDRIVE><header revMajor="1" revMinor="6" name="t"/>
  <road name="r" length="{length}" id="1" junction="-1"><link/>
    <planView><geometry s="0" x="0" y="0" hdg="0" length="{length}">{record}</geometry></planView>
    <lanes>
      <laneOffset s="0" a="{}" b="{}" c="0" d="0"/>
      <laneSection s="0">
        <left><lane id="1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></left>
        <center><lane id="0" type="none" level="false"/></center>
        <right><lane id="-1" type="driving" level="false"><width sOffset="0" a="3.0" b="0.01" c="0" d="0"/></lane></right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>"#,
        offset.0, offset.1
    )
}

#[test]
fn width_polynomials_and_lane_offsets_agree_with_their_closed_forms() {
    let (n, id, map) = map_network("offset.xodr", &offset_map("<line/>", 100.0, (0.5, 0.002)));
    for metre in 0..=100 {
        let s = f64::from(metre);
        let offset = 0.5 + 0.002 * s;
        let w = 3.0 + 0.01 * s;
        // OpenDRIVE's t (left) is paracosm's -z.
        let right = n.on_map_lane(id, "1", -1, s).unwrap();
        let left = n.on_map_lane(id, "1", 1, s).unwrap();
        assert!((right.pos_m[0] - s).abs() < 1e-3, "{right:?}");
        assert!(
            (-right.pos_m[2] - (offset - w / 2.0)).abs() < 1e-3,
            "{s}: {right:?}"
        );
        assert!(
            (-left.pos_m[2] - (offset + 1.75)).abs() < 1e-3,
            "{s}: {left:?}"
        );
        let k = map.lane_at("1", -1, s).unwrap();
        let lane = &map.lanes[k];
        let i = lane.s.iter().position(|x| (x - s).abs() < 1e-9).unwrap();
        assert!((lane.width[i] - w).abs() < 1e-4, "{} vs {w}", lane.width[i]);
    }
}

#[test]
fn a_param_poly3_record_follows_its_parabola() {
    // u = L p, v = c L² p² over p in [0, 1]: the parabola y = c x² for x in [0, L].
    let (l, c) = (60.0f64, 0.004);
    // Its arc length, by Simpson's rule.
    let n = 20_000;
    let h = l / f64::from(n);
    let f = |x: f64| (1.0 + (2.0 * c * x).powi(2)).sqrt();
    let length = (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * f(f64::from(i) * h)
        })
        .sum::<f64>()
        * h
        / 3.0;
    let record = format!(
        r#"<paramPoly3 aU="0" bU="{l}" cU="0" dU="0" aV="0" bV="0" cV="{}" dV="0" pRange="normalized"/>"#,
        c * l * l
    );
    let (net, id, _) = map_network("parabola.xodr", &offset_map(&record, length, (0.0, 0.0)));
    let mut worst = 0.0f64;
    for metre in 0..length.floor() as i32 {
        let s = f64::from(metre);
        let a = net.on_map_lane(id, "1", 1, s).unwrap();
        let b = net.on_map_lane(id, "1", -1, s).unwrap();
        // The reference line lies between the lanes: 1.75 m from the left lane's centre and
        // (3 + 0.01 s) / 2 from the right one's, along the normal.
        let wr = (3.0 + 0.01 * s) / 2.0;
        let t = 1.75 / (1.75 + wr);
        let x = a.pos_m[0] + t * (b.pos_m[0] - a.pos_m[0]);
        let y = -(a.pos_m[2] + t * (b.pos_m[2] - a.pos_m[2]));
        worst = worst.max((y - c * x * x).abs());
    }
    assert!(
        worst < 2e-3,
        "the reference line leaves the parabola by {worst} m"
    );
    println!("paramPoly3: the reference line within {worst:.2e} m of y = c x^2");
}

/// The route's last point and the heading of its last step, rad.
fn route_end(
    net: &Network,
    id: PieceId,
    road: &str,
    lane: i32,
    s: f64,
    turns: &[Turn],
) -> ([f64; 2], f64) {
    let start = net.on_map_lane(id, road, lane, s).unwrap();
    let r = net.route(&start, turns, 400.0).unwrap();
    let (a, b) = (r[r.len() - 2], r[r.len() - 1]);
    (b, (-(b[1] - a[1])).atan2(b[0] - a[0]))
}

#[test]
fn routes_through_the_junction_take_the_turn_asked() {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (net, id, _) = map_network("junction.xodr", &shipped("junction.xodr"));
    // From the west arm (road 3, running west from the junction), lane 1 drives east toward
    // it. Straight on leaves by the east arm, left by the north one, right by the south one.
    for (turn, heading) in [
        (Turn::Straight, 0.0),
        (Turn::Left, FRAC_PI_2),
        (Turn::Right, -FRAC_PI_2),
    ] {
        let (end, h) = route_end(&net, id, "3", 1, 40.0, &[turn]);
        let dh = paracosm_engine::network::wrap(h - heading).abs();
        assert!(dh < 0.05, "{turn:?}: ends heading {h} rad, at {end:?}");
        // Each arm ends 82 m from the centre.
        assert!(
            (end[0].hypot(end[1]) - 82.0).abs() < 2.5,
            "{turn:?}: {end:?}"
        );
    }
    // Lane -1 of the west arm drives away from the junction, to the arm's end.
    let (end, h) = route_end(&net, id, "3", -1, 10.0, &[]);
    assert!(
        (paracosm_engine::network::wrap(h - PI)).abs() < 0.05 && end[0] < -80.0,
        "{end:?}"
    );
}

#[test]
fn the_roundabout_is_driven_counter_clockwise_and_left_where_asked() {
    let (net, id, map) = map_network("roundabout.xodr", &shipped("roundabout.xodr"));
    // From the east arm (road 1) inbound: round the ring counter-clockwise; `right` at the
    // first fork leaves by the north arm (road 2).
    let (end, h) = route_end(&net, id, "1", 1, 30.0, &[Turn::Right]);
    assert!(end[1] < -70.0 && end[0].abs() < 3.0, "north arm: {end:?}");
    assert!((paracosm_engine::network::wrap(h - std::f64::consts::FRAC_PI_2)).abs() < 0.05);
    // Straight on at every fork: it circulates until the route's 400 m are used up, turning
    // counter-clockwise (the cross product of successive steps is positive, seen from above).
    let start = net.on_map_lane(id, "1", 1, 30.0).unwrap();
    let r = net.route(&start, &[], 400.0).unwrap();
    let ring: Vec<&[f64; 2]> = r.iter().filter(|p| p[0].hypot(p[1]) < 23.0).collect();
    assert!(ring.len() > 200, "{} points on the ring", ring.len());
    let mut turning = 0.0;
    for w in ring.windows(3) {
        let (a, b, c) = (w[0], w[1], w[2]);
        // In (x, y = -z): the cross product of a→b and b→c.
        let cross = (b[0] - a[0]) * (-(c[1] - b[1])) - (-(b[1] - a[1])) * (c[0] - b[0]);
        turning += cross.signum();
    }
    assert!(turning > 0.0, "clockwise on the ring: {turning}");
    assert!(map.lanes.iter().filter(|l| l.drivable).count() >= 20);
}

#[test]
fn the_surface_of_a_map_knows_its_lanes_edges_and_friction() {
    let (net, _, _) = map_network("bend.xodr", &shipped("bend.xodr"));
    let surface = Surface::new(&net);
    // On the straight: lane -1's centre is 1.75 m right of the line (z = +1.75), 1.75 m from
    // the edge beyond which lies the sidewalk (lane -2).
    let e = surface.edge_distance_m([50.0, 1.75]);
    assert!((e - 1.75).abs() < 1e-3, "{e}");
    // Centre line: 3.5 m from either edge.
    assert!((surface.edge_distance_m([50.0, 0.0]) - 3.5).abs() < 1e-3);
    // The sidewalk is off the driving surface, 1 m beyond its edge at its centre.
    let e = surface.edge_distance_m([50.0, 4.5]);
    assert!((e + 1.0).abs() < 1e-3, "{e}");
    assert!(surface.off_road([50.0, 4.5]));
    assert_eq!(surface.friction_at([50.0, 1.75]), 0.8);
    assert_eq!(
        surface.friction_at([50.0, 4.5]),
        0.8,
        "sidewalks are the map's too"
    );
    assert_eq!(surface.friction_at([50.0, 30.0]), GROUND_FRICTION);
    // Past the map's dead end, off the road.
    assert!(surface.edge_distance_m([-2.0, 1.75]) < 0.0);
    // In the arc (centre (≈93, -44) in x, z... found from the lane itself): on lane -1.
    let on = net.on_map_lane(PieceId(0), "1", -1, 150.0).unwrap();
    let e = surface.edge_distance_m([on.pos_m[0], on.pos_m[2]]);
    assert!((e - 1.75).abs() < 5e-3, "{e}");
    assert!(!surface.off_road([on.pos_m[0], on.pos_m[2]]));
}

#[test]
fn what_paracosm_does_not_use_is_named_in_warnings() {
    let text = shipped("bend.xodr").replace(
        "    <lanes>",
        r#"    <elevationProfile><elevation s="0" a="0" b="0.02" c="0" d="0"/></elevationProfile>
    <signals><signal s="20" t="-3" id="9" dynamic="no" orientation="+" type="206" subtype="-1"/></signals>
    <objects><object id="1" s="10" t="-6" type="tree"/><object id="2" s="30" t="-6" type="tree"/></objects>
    <lanes>"#,
    );
    let Imported { warnings, .. } = import("bend+.xodr", &text).unwrap();
    let all = warnings.join("\n");
    for phrase in [
        "1 <elevation> element ignored: elevation is dropped: maps are flat",
        "1 <signals> element ignored",
        "1 <objects> element ignored",
    ] {
        assert!(all.contains(phrase), "`{phrase}` not in\n{all}");
    }
    assert!(
        all.contains("bend+.xodr:"),
        "warnings name the file and line: {all}"
    );
    // A flat elevation says nothing.
    let flat = shipped("bend.xodr").replace(
        "    <lanes>",
        "    <elevationProfile><elevation s=\"0\" a=\"0\" b=\"0\" c=\"0\" d=\"0\"/></elevationProfile>\n    <lanes>",
    );
    assert!(import("flat.xodr", &flat).unwrap().warnings.is_empty());
    // So do empty containers, as map editors write them on every road.
    let empty = shipped("bend.xodr").replace(
        "    <lanes>",
        "    <objects></objects>\n    <signals/>\n    <lanes>",
    );
    assert!(import("empty.xodr", &empty).unwrap().warnings.is_empty());
}

#[test]
fn connect_refuses_to_join_a_piece_to_a_map() {
    let (mut net, map, _) = map_network("bend.xodr", &shipped("bend.xodr"));
    let seg = net
        .add(
            "RoadSegment r",
            PieceKind::Segment {
                length_m: 20.0,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap();
    let e = net.connect(seg, 0, map, 0).unwrap_err().to_string();
    assert!(
        e.contains("is an OpenDRIVE map: its roads are linked by the map"),
        "{e}"
    );
}

/// Past the dead end of each outer road of `maps/junction.xodr`, the driving surface stops:
/// a point 0.5 m beyond the last station of a lane's centre line is off the road, one 0.5 m
/// before it on. (A vehicle 1 m past road 4's end once read as on the road.)
#[test]
fn the_junction_maps_dead_ends_end_the_road() {
    let (net, id, _) = map_network("junction.xodr", &shipped("junction.xodr"));
    let surface = Surface::new(&net);
    for road in ["1", "2", "3", "4"] {
        for lane in [-1, 1] {
            let end = net.on_map_lane(id, road, lane, 70.0).unwrap();
            let before = net.on_map_lane(id, road, lane, 69.0).unwrap();
            let dir = [
                end.pos_m[0] - before.pos_m[0],
                end.pos_m[2] - before.pos_m[2],
            ];
            let at = |k: f64| [end.pos_m[0] + k * dir[0], end.pos_m[2] + k * dir[1]];
            let inside = surface.edge_distance_m(at(-0.5));
            let outside = surface.edge_distance_m(at(0.5));
            assert!(inside > 0.0, "road {road} lane {lane}: {inside}");
            assert!(
                outside < 0.0 && surface.off_road(at(0.5)),
                "road {road} lane {lane}: {outside}"
            );
        }
    }
}

/// ALKS's left road of radius 250 m is one arc of 1,500 m: its lanes turn 6 rad, so that
/// their ends look back at their starts. Every point of lane -4, across its width and from
/// 10 m to 110 m (at its stations and between them), is on the driving surface: points on
/// the outside of the bend, in the wedge between two centre-line segments, once fell off it
/// (4.25 m "off-road" in the middle of the lane).
#[test]
fn the_outside_of_a_bend_that_turns_almost_full_circle_is_on_the_road() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/xosc/alks/concrete_scenarios/road_networks")
        .join("alks_road_left_radius_250m.xodr");
    let text = std::fs::read_to_string(p).unwrap();
    let (net, _, map) = map_network("alks_road_left_radius_250m.xodr", &text);
    let surface = Surface::new(&net);
    // Lane -4 spans t in [-9.75, -6.25]; the drivable lanes -3..-5 span [-13.25, -2.75].
    // From 10 m on: before, the nearest edge may be the road's start.
    for k in 0..400 {
        let s = 10.0 + 0.25 * k as f64;
        let a = s / 250.0;
        for t in [-6.5, -7.0, -8.0, -9.0, -9.5] {
            let r = 250.0 - t;
            let od = [r * a.sin(), 250.0 - r * a.cos()];
            let q = [od[0] - map.origin_m[0], -(od[1] - map.origin_m[1])];
            let e = surface.edge_distance_m(q);
            let want = (t + 13.25f64).min(-2.75 - t);
            assert!((e - want).abs() < 0.01, "s {s} t {t}: {e} (want {want})");
        }
    }
}
