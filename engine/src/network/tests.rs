use super::*;

fn seg(n: &mut Network, name: &str, len: f64, lanes: u32) -> PieceId {
    n.add(
        name,
        PieceKind::Segment {
            length_m: len,
            lanes,
            friction: 0.8,
        },
    )
    .unwrap()
}

fn cross(n: &mut Network, name: &str, lanes: u32) -> PieceId {
    n.add(
        name,
        PieceKind::CrossIntersection {
            lanes,
            friction: 0.8,
        },
    )
    .unwrap()
}

const ONE: usize = 0;
const TWO: usize = 1;
const THREE: usize = 2;
const FOUR: usize = 3;

fn close(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
}

/// The paper's example: a T-intersection with three roads (east, south, west).
#[test]
fn the_papers_t_intersection_places_its_roads_at_its_ports() {
    let mut n = Network::new();
    let t = n
        .add(
            "t",
            PieceKind::TIntersection {
                lanes: 4,
                friction: 0.8,
            },
        )
        .unwrap();
    let e = seg(&mut n, "e", 50.0, 4);
    let s = seg(&mut n, "s", 50.0, 4);
    let w = seg(&mut n, "w", 20.0, 4);
    n.connect(t, ONE, e, TWO).unwrap();
    n.connect(t, TWO, s, ONE).unwrap();
    n.connect(t, THREE, w, ONE).unwrap();
    // Half the junction: 4 lanes · 3.5 m / 2 + 2 m sidewalk + 3 m apron = 12 m.
    let port = |p: PieceId, i: usize| n.piece(p).port(i).unwrap();
    assert!(close(port(e, TWO).pos, [12.0, 0.0]));
    // e joins with its end TWO, so it runs back toward the junction: its ONE is 50 m east.
    assert!(close(port(e, ONE).pos, [62.0, 0.0]));
    assert!(close(port(s, TWO).pos, [0.0, 62.0]));
    assert!(close(port(w, TWO).pos, [-32.0, 0.0]));
    assert_eq!(n.group_of(t).len(), 4);
    assert_eq!(n.links().len(), 3);
    // onLane on the rotated south road: lane 1 drives away from the junction (+z).
    let l = n.on_lane(s, Lane::Driving(1), 10.0).unwrap();
    assert!(close([l.pos_m[0], l.pos_m[2]], [-1.75, 22.0]));
    assert!((wrap(l.heading_rad + std::f64::consts::FRAC_PI_2)).abs() < 1e-12);
}

#[test]
fn a_lane_count_mismatch_is_refused() {
    let mut n = Network::new();
    let a = seg(&mut n, "a", 50.0, 2);
    let b = seg(&mut n, "b", 50.0, 6);
    let err = n.connect(a, TWO, b, ONE).unwrap_err().to_string();
    assert_eq!(
        err,
        "invalid world: lane-count mismatch: a.TWO has 2 lanes but b.ONE has 6"
    );
}

#[test]
fn ports_that_do_not_coincide_are_refused_when_closing_a_loop() {
    let mut n = Network::new();
    let a = seg(&mut n, "a", 50.0, 2);
    let b = seg(&mut n, "b", 30.0, 2);
    let c = seg(&mut n, "c", 30.0, 2);
    n.connect(a, TWO, b, ONE).unwrap();
    n.connect(b, TWO, c, ONE).unwrap();
    // a, b, c lie in a straight line: a.ONE at x = 0, c.TWO at x = 110.
    let err = n.connect(c, TWO, a, ONE).unwrap_err().to_string();
    assert!(
        err.contains("connection points do not coincide: c.TWO is at (110.00, 0.00) m"),
        "{err}"
    );
    assert!(err.contains("a.ONE at (0.00, 0.00) m"), "{err}");
}

#[test]
fn overlapping_pieces_are_refused_and_nothing_moves() {
    // c with roads east (a) and south (s), junctions d and e at their ends, a long road south
    // from d; a road east from e must then cross it without a junction.
    let mut n = Network::new();
    let c = cross(&mut n, "c", 2);
    let a = seg(&mut n, "a", 30.0, 2);
    let s = seg(&mut n, "s", 30.0, 2);
    let d = cross(&mut n, "d", 2);
    let e = cross(&mut n, "e", 2);
    let long = seg(&mut n, "long", 100.0, 2);
    n.connect(c, ONE, a, ONE).unwrap();
    n.connect(c, TWO, s, ONE).unwrap();
    n.connect(a, TWO, d, THREE).unwrap();
    n.connect(s, TWO, e, FOUR).unwrap();
    n.connect(d, TWO, long, ONE).unwrap();
    let f = seg(&mut n, "f", 60.0, 2);
    let err = n.connect(e, ONE, f, ONE).unwrap_err().to_string();
    assert_eq!(err, "invalid world: road pieces overlap: f and long");
    assert_eq!(
        n.piece(f).pose,
        Pose2::default(),
        "the failed connect moved nothing"
    );
    assert_eq!(n.links().len(), 5);
    // Two unconnected roads at the origin overlap too (what `place` checks).
    let mut m = Network::new();
    seg(&mut m, "r1", 50.0, 2);
    seg(&mut m, "r2", 50.0, 2);
    assert_eq!(
        m.check_all_overlaps().unwrap_err().to_string(),
        "invalid world: road pieces overlap: r1 and r2"
    );
}

#[test]
fn ports_are_used_once_and_must_exist() {
    let mut n = Network::new();
    let a = seg(&mut n, "a", 50.0, 2);
    let b = seg(&mut n, "b", 50.0, 2);
    let c = seg(&mut n, "c", 50.0, 2);
    n.connect(a, TWO, b, ONE).unwrap();
    let err = n.connect(a, TWO, c, ONE).unwrap_err().to_string();
    assert!(err.contains("port a.TWO is already connected"), "{err}");
    let err = n.connect(a, FOUR, c, ONE).unwrap_err().to_string();
    assert!(
        err.contains("a has ports ONE, TWO; it has no port FOUR"),
        "{err}"
    );
}

/// The paper's Figure 3: a grid of cross-intersections built by iteration; closing each
/// square checks that the ports coincide.
fn grid(n: &mut Network, size: usize, block_m: f64) -> Vec<Vec<PieceId>> {
    let mut xs: Vec<Vec<PieceId>> = Vec::new();
    for i in 0..size {
        let mut row = Vec::new();
        for j in 0..size {
            let c = cross(n, &format!("x{i}{j}"), 2);
            if j > 0 {
                let s = seg(n, &format!("h{i}{j}"), block_m, 2);
                n.connect(row[j - 1], ONE, s, ONE).unwrap();
                n.connect(s, TWO, c, THREE).unwrap();
            }
            if i > 0 {
                let s = seg(n, &format!("v{i}{j}"), block_m, 2);
                let above: &Vec<PieceId> = &xs[i - 1];
                n.connect(above[j], TWO, s, ONE).unwrap();
                // For j > 0, c is already placed: this closes a block and checks the ports.
                n.connect(s, TWO, c, FOUR).unwrap();
            }
            row.push(c);
        }
        xs.push(row);
    }
    xs
}

#[test]
fn a_grid_of_cross_intersections_validates() {
    let mut n = Network::new();
    let xs = grid(&mut n, 3, 40.0);
    n.check_all_overlaps().unwrap();
    assert_eq!(n.group_of(xs[0][0]).len(), 9 + 12);
    // 3 × 3 junctions 40 m apart plus their 17 m sides: x22 sits at (2 · 57, 2 · 57).
    let p = n.piece(xs[2][2]).pose;
    assert!(close([p.x, p.z], [114.0, 114.0]), "{p:?}");
}

#[test]
fn routes_follow_the_lane_graph_and_its_turns() {
    let mut n = Network::new();
    let xs = grid(&mut n, 2, 40.0);
    let h = n
        .pieces()
        .iter()
        .position(|p| p.name == "h01")
        .map(PieceId)
        .unwrap();
    let start = n.on_lane(h, Lane::Driving(1), 5.0).unwrap();
    // East on h01 into x01, then right (south) down v11 into x11, then right (west).
    let route = n
        .route(&start, &[Turn::Right, Turn::Right], 1000.0)
        .unwrap();
    let last = *route.last().unwrap();
    let x10 = n.piece(xs[1][0]).pose;
    // After two right turns it drives west along h11 and ends at x10, where the network
    // offers only north or south... and keeps going: it must pass x10's east port.
    assert!(
        route.iter().any(|p| (p[0] - (x10.x + 8.5)).abs() < 1e-6),
        "{last:?}"
    );
    // Every step of the route is short (resampled to 1 m) and continuous.
    for w in route.windows(2) {
        assert!((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) <= 1.0 + 1e-9);
    }
    // Driving lanes keep to the right: heading east on lane 1 means z > junction z.
    assert!(start.pos_m[2] > 0.0);
}

#[test]
fn driving_surfaces_exclude_sidewalks_and_the_roundabout_island() {
    let mut n = Network::new();
    let r = seg(&mut n, "r", 100.0, 2);
    let o = n
        .add(
            "o",
            PieceKind::Roundabout {
                lanes: 2,
                radius_m: 20.0,
                friction: 0.8,
            },
        )
        .unwrap();
    n.connect(r, TWO, o, THREE).unwrap();
    assert_eq!(n.driving_surface_at([50.0, 1.0]), Some(r));
    assert_eq!(n.driving_surface_at([50.0, 4.5]), None, "sidewalk");
    assert_eq!(n.driving_surface_at([120.0, 0.0]), None, "island");
    assert_eq!(n.driving_surface_at([103.0, 0.0]), Some(o));
    let start = n.on_lane(r, Lane::Driving(1), 90.0).unwrap();
    let route = n.route(&start, &[Turn::Left], 200.0).unwrap();
    // Around the island counter-clockwise and out of the north port (-z).
    assert!(route
        .iter()
        .all(|p| (p[0] - 120.0).hypot(p[1]) > 15.0 - 1e-9));
    let end = route.last().unwrap();
    assert!(end[1] < -19.0, "{end:?}");
}

fn arc(n: &mut Network, name: &str, radius_m: f64, angle_rad: f64) -> PieceId {
    n.add(
        name,
        PieceKind::Arc {
            radius_m,
            angle_rad,
            lanes: 2,
            friction: 0.6,
        },
    )
    .unwrap()
}

fn clothoid(n: &mut Network, name: &str, length_m: f64, k0: f64, k1: f64) -> PieceId {
    n.add(
        name,
        PieceKind::Clothoid {
            length_m,
            curv_start: k0,
            curv_end: k1,
            lanes: 2,
            friction: 0.8,
        },
    )
    .unwrap()
}

/// Segment, clothoid easing into an arc, the arc, a clothoid out, segment: a quarter turn to
/// the left, every port meeting the next.
fn bend(n: &mut Network) -> [PieceId; 5] {
    use std::f64::consts::FRAC_PI_2;
    let r = 40.0;
    let a = seg(n, "a", 50.0, 2);
    let c1 = clothoid(n, "c1", 20.0, 0.0, 1.0 / r);
    let b = arc(n, "b", r, FRAC_PI_2 - 20.0 / r);
    let c2 = clothoid(n, "c2", 20.0, 1.0 / r, 0.0);
    let e = seg(n, "e", 50.0, 2);
    n.connect(a, TWO, c1, ONE).unwrap();
    n.connect(c1, TWO, b, ONE).unwrap();
    n.connect(b, TWO, c2, ONE).unwrap();
    n.connect(c2, TWO, e, ONE).unwrap();
    [a, c1, b, c2, e]
}

#[test]
fn a_spiral_arc_spiral_bend_turns_a_quarter_with_every_port_meeting_the_next() {
    let mut n = Network::new();
    let [a, c1, b, c2, e] = bend(&mut n);
    // Each clothoid turns (0 + 1/40)/2 · 20 = 0.25 rad, the arc the rest: π/2 in all.
    let out = n.piece(e).port(TWO).unwrap();
    assert!(
        (out.heading_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
        "{}",
        out.heading_rad
    );
    assert!(
        (n.piece(e).pose.heading_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
        "the exit road heads north"
    );
    for (p, q) in [(a, c1), (c1, b), (b, c2), (c2, e)] {
        let (x, y) = (n.piece(p).port(TWO).unwrap(), n.piece(q).port(ONE).unwrap());
        assert!(close(x.pos, y.pos), "{x:?} {y:?}");
    }
    n.check_all_overlaps().unwrap();
    // The arc's world end, from the circle: its start pose rotated about the centre.
    let start = n.piece(b).pose;
    let line = n.piece(b).kind.ref_line().unwrap();
    let k = 1.0 / 40.0;
    let local = [
        (k * line.length_m).sin() / k,
        -(1.0 - (k * line.length_m).cos()) / k,
    ];
    assert!(close(start.apply(local), n.piece(b).port(TWO).unwrap().pos));
}

#[test]
fn curved_pieces_that_cross_are_refused_as_overlapping() {
    use std::f64::consts::PI;
    let mut n = Network::new();
    let a = arc(&mut n, "a", 20.0, PI);
    let s = seg(&mut n, "s", 50.0, 2);
    let b = arc(&mut n, "b", 20.0, PI);
    let back = seg(&mut n, "back", 100.0, 2);
    n.connect(a, TWO, s, ONE).unwrap();
    n.connect(s, TWO, b, ONE).unwrap();
    // b ends at (-50, 0) heading +x: a road east from there runs through a's start.
    let err = n.connect(b, TWO, back, ONE).unwrap_err().to_string();
    assert!(err.contains("road pieces overlap"), "{err}");
    assert!(err.contains("back") && err.contains('a'), "{err}");
    // The same loop closed by a road that stops short of a touches it only at a's port ONE.
    let mut m = Network::new();
    let a = arc(&mut m, "a", 20.0, PI);
    let s1 = seg(&mut m, "s1", 50.0, 2);
    let b = arc(&mut m, "b", 20.0, PI);
    let s2 = seg(&mut m, "s2", 50.0, 2);
    m.connect(a, TWO, s1, ONE).unwrap();
    m.connect(s1, TWO, b, ONE).unwrap();
    m.connect(b, TWO, s2, ONE).unwrap();
    m.connect(s2, TWO, a, ONE).unwrap();
    m.check_all_overlaps().unwrap();
}

#[test]
fn on_lane_follows_an_arc_with_the_lanes_direction_of_travel() {
    use std::f64::consts::{FRAC_PI_2, PI};
    let mut n = Network::new();
    let b = arc(&mut n, "b", 30.0, FRAC_PI_2);
    // A left turn about the centre (0, -30): lane 1 (right of travel) is outside it.
    let centre = [0.0, -30.0];
    let r = |p: [f64; 3]| (p[0] - centre[0]).hypot(p[2] - centre[1]);
    for at in [0.0, 10.0, 30.0, 47.1] {
        let theta = at / 30.0;
        let l1 = n.on_lane(b, Lane::Driving(1), at).unwrap();
        assert!((r(l1.pos_m) - 31.75).abs() < 1e-9);
        assert!((l1.heading_rad - theta).abs() < 1e-12);
        let back = n.on_lane(b, Lane::Driving(-1), at).unwrap();
        assert!((r(back.pos_m) - 28.25).abs() < 1e-9);
        assert!((wrap(back.heading_rad - theta - PI)).abs() < 1e-12);
        let walk = n.on_lane(b, Lane::SideWalk, at).unwrap();
        assert!((r(walk.pos_m) - (30.0 + 3.5 + 1.0)).abs() < 1e-9);
        assert_eq!(walk.pos_m[1], CURB_HEIGHT_M);
        let other = n.on_lane(b, Lane::OppositeSideWalk, at).unwrap();
        assert!((r(other.pos_m) - (30.0 - 3.5 - 1.0)).abs() < 1e-9);
    }
    let err = n
        .on_lane(b, Lane::Driving(1), 48.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("outside b [0, 47.12"), "{err}");
    let err = n
        .on_junction_lane(b, 0, Turn::Straight, 1, 1.0)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("b is a Arc: give onLane a lane number"),
        "{err}"
    );
}

#[test]
fn the_surface_of_a_curve_is_its_carriageway_and_its_lanes_follow_the_curve() {
    let mut n = Network::new();
    let [a, _, b, _, _] = bend(&mut n);
    let s = Surface::new(&n);
    let arc_piece = n.piece(b);
    let line = arc_piece.kind.ref_line().unwrap();
    let at = |t: f64| arc_piece.pose.apply(line.offset(line.length_m / 2.0, t));
    // Lane 1's centre: 1.75 m from either edge, on lane (offset 0), the arc's friction.
    let centre = at(1.75);
    assert!((s.edge_distance_m(centre) - 1.75).abs() < 2e-3);
    let heading = arc_piece.pose.heading_rad + line.heading(line.length_m / 2.0);
    assert!(s.lane_offset_m(centre, heading).abs() < 2e-3);
    assert!((s.lane_offset_m(at(2.05), heading) - 0.3).abs() < 2e-3);
    assert_eq!(s.friction_at(centre), 0.6);
    // The sidewalk is the arc's but off the driving surface; beyond it and inside the bend
    // (within the arc's bounding box) is grass.
    assert_eq!(s.friction_at(at(4.5)), 0.6);
    assert!((s.edge_distance_m(at(4.5)) + 1.0).abs() < 2e-3);
    assert_eq!(s.friction_at(at(-8.0)), GROUND_FRICTION);
    assert_eq!(s.friction_at(at(-20.0)), GROUND_FRICTION);
    assert!(n.driving_surface_at(at(-20.0)).is_none());
    assert_eq!(n.driving_surface_at(centre), Some(b));
    assert!((n.distance_to_piece_m(b, at(-8.0)) - 2.5).abs() < 2e-3);
    // A route from the straight approach follows lane 1 round the bend, every point on the
    // lane's centre line.
    let start = n.on_lane(a, Lane::Driving(1), 5.0).unwrap();
    let route = n.route(&start, &[], 1000.0).unwrap();
    let worst = route
        .iter()
        .map(|&p| {
            s.lane_offset_m(p, 0.0)
                .abs()
                .min(3.5 - s.lane_offset_m(p, 0.0).abs())
        })
        .fold(0.0f64, f64::max);
    assert!(
        worst < 5e-3,
        "a route point {worst} m off its lane's centre line"
    );
    let end = route.last().unwrap();
    let exit = n.piece(PieceId(4)).port(TWO).unwrap().pos;
    assert!((end[0] - exit[0] - 1.75).abs() < 1e-6 && (end[1] - exit[1]).abs() < 1e-6);
    let length: f64 = route
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    // 45 m + 20 m + the arc + 20 m + 50 m, each curved piece's lane 1.75 m outside its line.
    assert!(length > 45.0 + 40.0 + 40.0 * 1.07 + 50.0, "{length}");
}

/// Every lane path through a junction or a roundabout is a G1 chain of lines and arcs: each
/// piece starts where the last ended with its heading (to 1e-6 m, 1e-9 rad), the chain starts
/// at its entry port heading into the piece and ends at its exit port heading out, no arc is
/// tighter than `MIN_PATH_RADIUS_M`, and the sampled polyline's headings
/// (`vertex_tangents`) turn by at most a leg's curvature between vertices.
#[test]
fn junction_and_roundabout_paths_are_g1_chains_of_lines_and_arcs() {
    let mut kinds = Vec::new();
    for lanes in [2, 4, 6] {
        kinds.push(PieceKind::CrossIntersection {
            lanes,
            friction: 0.8,
        });
        kinds.push(PieceKind::TIntersection {
            lanes,
            friction: 0.8,
        });
        let min = lanes::min_roundabout_radius_m(lanes);
        // Smaller plazas are refused, with the smallest that fits named.
        let small = PieceKind::Roundabout {
            lanes,
            radius_m: min - 0.25,
            friction: 0.8,
        };
        let e = small.validate().unwrap_err().to_string();
        assert!(e.contains(&format!("at least {min} m")), "{e}");
        for radius_m in [min, min + 0.5, 12.0, 20.0, 35.0, 120.0, 1000.0] {
            if radius_m >= min {
                kinds.push(PieceKind::Roundabout {
                    lanes,
                    radius_m,
                    friction: 0.8,
                });
            }
        }
    }
    let mut paths = 0;
    for kind in kinds {
        let mut n = Network::new();
        let id = n.add("j", kind.clone()).unwrap();
        // Turned and moved, so that the frame's pose is part of what is checked.
        n.pieces[id.0].pose = Pose2 {
            x: 30.0,
            z: -12.0,
            heading_rad: 0.4,
        };
        let piece = n.piece(id).clone();
        for path in n.lane_paths(id) {
            paths += 1;
            let what = format!("{kind:?} {:?} -> {:?}", path.entry, path.exit);
            assert!(!path.curve.is_empty(), "{what}");
            let entry = piece.port(path.entry.0).unwrap();
            let exit = piece.port(path.exit.0).unwrap();
            let (first, _) = path.curve[0];
            assert!(
                wrap(first.heading_rad - (entry.heading_rad + std::f64::consts::PI)).abs() < 1e-9,
                "{what}: starts heading {} at the port of {}",
                first.heading_rad,
                entry.heading_rad
            );
            for w in path.curve.windows(2) {
                let (pose, line) = w[0];
                let [x, z] = pose.apply(line.point(line.length_m));
                let h = pose.heading_rad + line.heading(line.length_m);
                let next = w[1].0;
                assert!(
                    (x - next.x).hypot(z - next.z) < 1e-6,
                    "{what}: a gap of {} m",
                    (x - next.x).hypot(z - next.z)
                );
                assert!(wrap(h - next.heading_rad).abs() < 1e-9, "{what}: a kink");
            }
            let (pose, line) = *path.curve.last().unwrap();
            let end = pose.apply(line.point(line.length_m));
            assert!(
                wrap(pose.heading_rad + line.heading(line.length_m) - exit.heading_rad).abs()
                    < 1e-9,
                "{what}: ends off the exit's heading"
            );
            assert!(close(end, *path.points.last().unwrap()), "{what}");
            for (_, line) in &path.curve {
                let k = line.curv_start.abs();
                assert!(
                    k <= 1.0 / MIN_PATH_RADIUS_M + 1e-9,
                    "{what}: a radius of {} m",
                    1.0 / k
                );
            }
            // The polyline's vertex tangents turn by at most the curvature times the leg.
            let t = lanes::vertex_tangents(&path.points);
            for (i, w) in path.points.windows(2).enumerate() {
                let leg = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
                assert!(leg <= lanes::LANE_STEP_M + 1e-9, "{what}: a leg of {leg} m");
                let turn = wrap(t[i + 1] - t[i]).abs();
                assert!(
                    turn <= leg / MIN_PATH_RADIUS_M * 1.001 + 1e-9,
                    "{what}: {turn} rad over {leg} m"
                );
            }
            // Its first and last tangents are the ports' headings.
            assert!(
                wrap(t[0] - first.heading_rad).abs() < 1e-3,
                "{what}: {}",
                t[0]
            );
            assert!(
                wrap(t[t.len() - 1] - exit.heading_rad).abs() < 1e-3,
                "{what}"
            );
        }
    }
    assert!(paths > 300, "{paths}");
}

/// A car placed at a junction's or a roundabout's port faces the arm's heading (it was 0.73
/// rad off at a roundabout's port: the first leg of the path ran straight at the ring).
#[test]
fn a_location_at_a_port_faces_the_arm() {
    for kind in [
        PieceKind::Roundabout {
            lanes: 2,
            radius_m: 20.0,
            friction: 0.8,
        },
        PieceKind::CrossIntersection {
            lanes: 2,
            friction: 0.8,
        },
    ] {
        let mut n = Network::new();
        let id = n.add("j", kind.clone()).unwrap();
        for port in 0..4 {
            for turn in [Turn::Straight, Turn::Left, Turn::Right] {
                let at = n.on_junction_lane(id, port, turn, 1, 0.0).unwrap();
                let inward = n.piece(id).port(port).unwrap().heading_rad + std::f64::consts::PI;
                assert!(
                    wrap(at.heading_rad - inward).abs() < 1e-3,
                    "{kind:?} port {port} {turn:?}: {} against {}",
                    at.heading_rad,
                    wrap(inward)
                );
            }
        }
    }
}

#[test]
fn turns_are_named_by_their_angle_and_a_road_id_is_a_turn() {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    for (delta, turn) in [
        (0.0, Turn::Straight),
        (FRAC_PI_4, Turn::Straight),
        (-FRAC_PI_4, Turn::Straight),
        (0.8, Turn::Left),
        (FRAC_PI_2, Turn::Left),
        (3.0 * FRAC_PI_4, Turn::Left),
        (-FRAC_PI_2, Turn::Right),
        (-3.0 * FRAC_PI_4, Turn::Right),
        (2.4, Turn::UTurn),
        (PI, Turn::UTurn),
        (-PI, Turn::UTurn),
        (2.0 * PI + 0.1, Turn::Straight),
    ] {
        assert_eq!(Turn::of_heading(delta), turn, "{delta} rad");
    }
    assert!(Turn::Left.off_nominal_rad(1.4) < Turn::Left.off_nominal_rad(0.9));
    // Ways out that share a name: the nearest keeps it, the next takes the free name on its
    // side, or none (then only its road names it).
    let deg = |d: &[f64]| Turn::name_ways(&d.iter().map(|x| x.to_radians()).collect::<Vec<_>>());
    let (s, l, r, u) = (
        Some(Turn::Straight),
        Some(Turn::Left),
        Some(Turn::Right),
        Some(Turn::UTurn),
    );
    assert_eq!(deg(&[29.0, -42.0]), [s, r]);
    assert_eq!(deg(&[-90.0, 90.0]), [r, l]);
    assert_eq!(deg(&[0.0, 90.0, 130.0]), [s, l, u]);
    assert_eq!(deg(&[0.0, -90.0, -44.0]), [s, r, None]);
    assert_eq!(deg(&[45.0, -66.0]), [s, r]);
    assert_eq!(deg(&[10.0, -10.0, 0.0]), [l, r, s]);
    for name in [
        "straight",
        "left",
        "right",
        "uturn",
        "road:56",
        "road:ring.3-a",
    ] {
        let t = Turn::parse(name).unwrap();
        assert_eq!(t.name(), name);
    }
    assert_eq!(
        Turn::parse("road:56"),
        Some(Turn::Road(RoadName::new("56").unwrap()))
    );
    let long = format!("road:{}", "x".repeat(RoadName::MAX_BYTES + 1));
    for bad in ["", "road:", "Left", "u-turn", "56", long.as_str()] {
        assert_eq!(Turn::parse(bad), None, "{bad:?}");
    }
    let road = Turn::Road(RoadName::new("56").unwrap());
    assert_eq!(serde_json::to_string(&road).unwrap(), r#"{"road":"56"}"#);
    assert_eq!(serde_json::to_string(&Turn::UTurn).unwrap(), r#""uturn""#);
    assert_eq!(
        serde_json::from_str::<Turn>(r#"{"road":"56"}"#).unwrap(),
        road
    );
}

#[test]
fn a_t_intersections_stem_offers_left_and_right_and_no_uturn_or_road() {
    let mut n = Network::new();
    let t = n
        .add(
            "t",
            PieceKind::TIntersection {
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap();
    let paths = n.lane_paths(t);
    let turns = |port: usize| {
        let mut v: Vec<String> = paths
            .iter()
            .filter(|p| p.entry.0 == port)
            .map(|p| p.turn.name())
            .collect();
        v.sort();
        v
    };
    let all: Vec<Vec<String>> = (0..3).map(turns).collect();
    assert!(
        all.contains(&vec!["left".to_owned(), "right".to_owned()]),
        "{all:?}"
    );
    assert_eq!(
        all.iter()
            .filter(|v| v.contains(&"straight".to_owned()))
            .count(),
        2
    );
    for turn in [Turn::UTurn, Turn::parse("road:1").unwrap()] {
        let e = n
            .on_junction_lane(t, ONE, turn, 1, 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("no \"{}\" turn", turn.name())), "{e}");
    }
}

#[test]
fn a_maps_index_and_mesh_are_built_once_and_shared_by_every_world() {
    let text = include_str!("../../../scenarios/maps/junction.xodr");
    let map = crate::network::opendrive::import("junction.xodr", text)
        .unwrap()
        .map;
    let shared = MapRef::new(map);
    // Two tests' networks clone the handle: both read one index, built once.
    let (a, b) = (shared.clone(), shared.clone());
    assert!(a.index().shares_trees_with(&b.index()));
    // A handle of the same map made anew has a cache of its own.
    let fresh = MapRef::new(shared.0.clone());
    assert!(!fresh.index().shares_trees_with(&a.index()));
    // The mesh is built at the first call for a pose, then handed out; another pose builds
    // its own.
    let builds = std::cell::Cell::new(0);
    let build = || {
        builds.set(builds.get() + 1);
        Some(7u32)
    };
    assert_eq!(a.mesh([0, 0, 0], build), Some(7));
    assert_eq!(b.mesh([0, 0, 0], build), Some(7));
    assert_eq!(builds.get(), 1);
    assert_eq!(b.mesh([1, 0, 0], build), Some(7));
    assert_eq!(builds.get(), 2);
    // Queries through the shared index answer as through one built alone.
    let alone = MapIndex::new(shared.0.clone());
    let index = a.index();
    for x in (-60..=60).step_by(3) {
        for z in (-60..=60).step_by(3) {
            let p = [f64::from(x) + 0.25, f64::from(z) - 0.5];
            assert_eq!(index.on_any_lane(p), alone.on_any_lane(p), "{p:?}");
            assert_eq!(
                index.edge_distance_m(p).to_bits(),
                alone.edge_distance_m(p).to_bits(),
                "{p:?}"
            );
        }
    }
}
