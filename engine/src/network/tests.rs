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
