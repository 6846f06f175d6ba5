//! Closed-loop physics tests of the engine: the ego vehicle, a pedestrian and the built-in
//! systems under test on a straight road.

use paracosm_engine::rx::NoHost;
use paracosm_engine::sut::{Aeb, AebConfig, ConstantControl, Sut};
use paracosm_engine::{Control, Lane, Simulation, TriggeredPedestrian, WorldSpec};

fn world(pedestrians: Vec<TriggeredPedestrian>, initial_speed_mps: f64) -> WorldSpec {
    WorldSpec::straight_road(200.0, 10.0, initial_speed_mps, &pedestrians).unwrap()
}

/// A pedestrian that stands still in lane 1 at `x` (its trigger never fires).
fn standing_in_lane(x: f64) -> TriggeredPedestrian {
    TriggeredPedestrian {
        start: (Lane::Driving(1), x),
        target: (Lane::Driving(1), x),
        trigger_distance_m: 1e-6,
        speed_mps: 1.0,
    }
}

/// Runs `sut` for `seconds`; returns the time of the first contact, the smallest separation
/// and the final state's x and speed.
fn drive(spec: &WorldSpec, sut: &mut dyn Sut, seconds: f64) -> (Option<f64>, f64, f64, f64) {
    let mut sim = Simulation::new(spec).unwrap();
    sut.reset(0).unwrap();
    let mut first_contact = None;
    let mut min_sep = f64::INFINITY;
    while sim.t_s() < seconds {
        let control = sut.act(&sim.observation()).unwrap();
        sim.step(control, &mut NoHost).unwrap();
        let snap = sim.snapshot();
        min_sep = min_sep.min(snap.min_separation_m);
        if snap.ego_contact && first_contact.is_none() {
            first_contact = Some(snap.t_s);
        }
    }
    let ego = sim.ego_state();
    (first_contact, min_sep, ego.pos_m[0], ego.speed_mps)
}

#[test]
fn constant_throttle_hits_a_pedestrian_standing_40_m_ahead() {
    // Same start as the aeb case below: 12 m/s, 40 m short of the pedestrian.
    let spec = world(vec![standing_in_lane(50.0)], 12.0);
    let mut sut = ConstantControl(Control {
        throttle: 0.3,
        steering: 0.0,
    });
    let (contact, min_sep, _, _) = drive(&spec, &mut sut, 15.0);
    let t = contact.expect("the car should reach the pedestrian");
    // 40 m less the bumper (2.25 m) and the capsule (0.3 m) at 12 m/s and more: under 3.1 s.
    assert!((2.0..3.2).contains(&t), "contact at {t} s");
    assert_eq!(min_sep, 0.0);
}

#[test]
fn aeb_stops_before_a_pedestrian_standing_40_m_ahead() {
    let spec = world(vec![standing_in_lane(50.0)], 12.0);
    let mut sut = Aeb::new(AebConfig::default());
    let (contact, min_sep, x, speed) = drive(&spec, &mut sut, 15.0);
    assert_eq!(contact, None, "aeb must not touch the pedestrian");
    assert!(min_sep > 0.5, "closest approach {min_sep} m");
    assert!(x < 50.0 - 2.25, "stopped at x = {x} m");
    assert!(speed.abs() < 0.2, "still moving at {speed} m/s");
}

#[test]
fn aeb_cruises_at_its_target_speed_and_keeps_its_lane_on_an_empty_road() {
    let spec = world(vec![], 0.0);
    let mut sut = Aeb::new(AebConfig::default());
    let mut sim = Simulation::new(&spec).unwrap();
    let mut max_lateral_error: f64 = 0.0;
    while sim.t_s() < 14.0 {
        let c = sut.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
        max_lateral_error = max_lateral_error.max((sim.ego_state().pos_m[2] - 1.75).abs());
    }
    let ego = sim.ego_state();
    assert!(
        (ego.speed_mps - 12.0).abs() < 0.3,
        "speed {}",
        ego.speed_mps
    );
    assert!(
        max_lateral_error < 0.2,
        "lateral error {max_lateral_error} m"
    );
    assert!(ego.heading_rad.abs() < 0.02, "heading {}", ego.heading_rad);
}

#[test]
fn full_brake_from_12_mps_stops_in_a_plausible_distance() {
    let spec = world(vec![], 12.0);
    let mut sut = ConstantControl(Control::FULL_BRAKE);
    let (_, _, x, speed) = drive(&spec, &mut sut, 4.0);
    let distance = x - 10.0;
    // v² / (2 a) = 9 m at 8 m/s²; allow for the suspension settling.
    assert!(
        (7.0..13.0).contains(&distance),
        "stopping distance {distance} m"
    );
    assert!(speed.abs() < 0.1);
}

#[test]
fn the_same_world_gives_the_same_bits_twice() {
    let run = || {
        let spec = world(vec![standing_in_lane(60.0)], 12.0);
        let mut sim = Simulation::new(&spec).unwrap();
        let mut sut = Aeb::new(AebConfig::default());
        for _ in 0..600 {
            let c = sut.act(&sim.observation()).unwrap();
            sim.step(c, &mut NoHost).unwrap();
        }
        let e = sim.ego_state();
        [
            e.pos_m[0],
            e.pos_m[1],
            e.pos_m[2],
            e.heading_rad,
            e.speed_mps,
        ]
        .map(f64::to_bits)
    };
    assert_eq!(run(), run());
}

#[test]
fn a_walking_pedestrian_crosses_once_triggered() {
    let spec = world(
        vec![TriggeredPedestrian {
            start: (Lane::SideWalk, 60.0),
            target: (Lane::OppositeSideWalk, 60.0),
            trigger_distance_m: 30.0,
            speed_mps: 3.0,
        }],
        12.0,
    );
    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = ConstantControl(Control::FULL_BRAKE);
    // The car stops at ~x = 19 m, 41 m from the pedestrian: no trigger.
    for _ in 0..300 {
        let c = sut.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
    }
    let snap = sim.snapshot();
    assert_eq!(snap.pedestrians[0].triggered_at_s, None);
    assert_eq!(snap.pedestrians[0].pos_m, [60.0, 0.15, 4.5]);

    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = ConstantControl(Control::default());
    let mut triggered = None;
    while sim.t_s() < 10.0 {
        let c = sut.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
        triggered = triggered.or(sim.snapshot().pedestrians[0].triggered_at_s);
    }
    // Coasting at ~12 m/s from x = 10 m: within 30 m of x = 60 after about 1.7 s.
    let t = triggered.expect("the trigger should fire");
    assert!((1.3..2.2).contains(&t), "triggered at {t} s");
    // 9 m across at 3 m/s: arrived 3 s later.
    let p = sim.snapshot().pedestrians[0];
    assert_eq!(p.pos_m, [60.0, 0.15, -4.5]);
}

/// aeb follows a route around a loop of T-intersections (the shape of `t_loop.star`):
/// after 60 s it has gone round more than once and never left the driving surface.
#[test]
fn aeb_follows_a_route_around_a_loop_of_t_intersections() {
    use paracosm_engine::network::{Network, PieceKind, Turn};
    use paracosm_engine::PieceId;
    let mut n = Network::new();
    let t: Vec<PieceId> = (0..4)
        .map(|i| {
            n.add(
                &format!("t{i}"),
                PieceKind::TIntersection {
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap()
        })
        .collect();
    let r: Vec<PieceId> = (0..4)
        .map(|i| {
            n.add(
                &format!("r{i}"),
                PieceKind::Segment {
                    length_m: 80.0,
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap()
        })
        .collect();
    let (one, two, three) = (0, 1, 2);
    n.connect(t[0], one, r[0], one).unwrap();
    n.connect(r[0], two, t[1], three).unwrap();
    n.connect(t[1], two, r[1], one).unwrap();
    n.connect(r[1], two, t[2], three).unwrap();
    n.connect(t[2], two, r[2], one).unwrap();
    n.connect(r[2], two, t[3], two).unwrap();
    n.connect(t[3], one, r[3], one).unwrap();
    n.connect(r[3], two, t[0], two).unwrap();
    let mut spec = WorldSpec::straight_road(200.0, 10.0, 0.0, &[]).unwrap();
    spec.ego.start = n.on_lane(r[0], Lane::Driving(1), 10.0).unwrap();
    spec.ego.route = n.route(&spec.ego.start, &[] as &[Turn], 2000.0).unwrap();
    spec.network = n.clone();
    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = Aeb::new(AebConfig::default());
    let mut travelled = 0.0;
    let mut last = sim.ego_state().pos_m;
    while sim.t_s() < 60.0 {
        let c = sut.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
        let p = sim.ego_state().pos_m;
        travelled += (p[0] - last[0]).hypot(p[2] - last[2]);
        last = p;
        assert!(
            n.driving_surface_at([p[0], p[2]]).is_some(),
            "left the road at t = {} s, ({}, {})",
            sim.t_s(),
            p[0],
            p[2]
        );
    }
    // One lap is about 4 · (80 + 11) m = 364 m.
    assert!(travelled > 400.0, "travelled {travelled} m");
}

/// A sensor written outside the engine: the ego's speed, every 6 steps, as one named array.
struct Speedometer {
    arrays: Vec<paracosm_engine::sensor::Payload>,
    captures: usize,
}

impl paracosm_engine::sensor::Sensor for Speedometer {
    fn name(&self) -> &'static str {
        "speedometer"
    }
    fn period_ticks(&self) -> u64 {
        6
    }
    fn capture(
        &mut self,
        scene: &paracosm_engine::sensor::Scene<'_>,
    ) -> Result<(), paracosm_engine::EngineError> {
        self.captures += 1;
        self.arrays = vec![paracosm_engine::sensor::Payload {
            name: "speed",
            dtype: "float32",
            shape: vec![1],
            bytes: (scene.ego.speed_mps as f32).to_le_bytes().to_vec(),
            t_s: Some(scene.t_s),
        }];
        Ok(())
    }
    fn reading(&self) -> Option<paracosm_engine::sensor::Reading<'_>> {
        Some(paracosm_engine::sensor::Reading::Arrays(&self.arrays))
    }
}

#[test]
fn a_sensor_written_outside_the_engine_mounts_and_its_readings_reach_the_observation() {
    use paracosm_engine::sensor::Reading;
    let spec = world(vec![], 12.0);
    let mut sim = Simulation::new(&spec).unwrap();
    sim.mount(Box::new(Speedometer {
        arrays: Vec::new(),
        captures: 0,
    }))
    .unwrap();
    let coast = Control {
        throttle: 0.0,
        steering: 0.0,
    };
    for _ in 0..13 {
        sim.step(coast, &mut NoHost).unwrap();
    }
    let obs = sim.observation();
    let names: Vec<&str> = obs.readings.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["lidar", "speedometer"]);
    let (_, reading) = obs.readings[1];
    let Reading::Arrays(arrays) = reading else {
        panic!("{reading:?}")
    };
    // Mounted at t = 0, then captured at steps 6 and 12: the last reading is from t = 0.2 s.
    assert_eq!(arrays[0].t_s, Some(12.0 / 60.0));
    let speed = f32::from_le_bytes(arrays[0].bytes[..4].try_into().unwrap());
    assert!((11.0..12.5).contains(&speed), "{speed}");
    // What SUT_PROTOCOL.md would send for it: its arrays as they are.
    assert_eq!(reading.payloads(false), arrays.to_vec());
}

/// Issue 21: on a bend of a clothoid, an arc and a clothoid the car rides on the curved
/// pieces' own colliders (its chassis keeps the height it has on the straight: without them
/// it would sink onto the grass 2 cm lower) and `aeb` follows its lane round the bend.
#[test]
fn aeb_drives_a_spiral_arc_spiral_bend_on_the_curved_pieces_colliders() {
    use paracosm_engine::network::{Network, PieceKind, Turn};
    let mut n = Network::new();
    let seg = |n: &mut Network, name: &str| {
        n.add(
            name,
            PieceKind::Segment {
                length_m: 60.0,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap()
    };
    let spiral = |n: &mut Network, name: &str, k0: f64, k1: f64| {
        n.add(
            name,
            PieceKind::Clothoid {
                length_m: 25.0,
                curv_start: k0,
                curv_end: k1,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap()
    };
    let r = 35.0;
    let a = seg(&mut n, "a");
    let c1 = spiral(&mut n, "c1", 0.0, -1.0 / r);
    let b = n
        .add(
            "b",
            PieceKind::Arc {
                radius_m: r,
                angle_rad: -1.4,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap();
    let c2 = spiral(&mut n, "c2", -1.0 / r, 0.0);
    let e = seg(&mut n, "e");
    n.connect(a, 1, c1, 0).unwrap();
    n.connect(c1, 1, b, 0).unwrap();
    n.connect(b, 1, c2, 0).unwrap();
    n.connect(c2, 1, e, 0).unwrap();
    let mut spec = WorldSpec::straight_road(200.0, 10.0, 0.0, &[]).unwrap();
    spec.ego.start = n.on_lane(a, Lane::Driving(1), 5.0).unwrap();
    spec.ego.route = n.route(&spec.ego.start, &[] as &[Turn], 1000.0).unwrap();
    spec.network = n.clone();
    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = Aeb::new(AebConfig::default());
    let mut settled_y = None;
    let mut on_curves = 0;
    while sim.t_s() < 18.0 {
        let c = sut.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
        let p = sim.ego_state().pos_m;
        let under = n.driving_surface_at([p[0], p[2]]);
        assert!(under.is_some(), "left the road at t = {} s", sim.t_s());
        if sim.t_s() > 2.0 {
            let y0 = *settled_y.get_or_insert(p[1]);
            assert!(
                (p[1] - y0).abs() < 0.01,
                "chassis at {} m, {} m on the straight, at t = {} s",
                p[1],
                y0,
                sim.t_s()
            );
        }
        if under.is_some_and(|id| [c1, b, c2].contains(&id)) {
            on_curves += 1;
        }
        assert!(
            sim.snapshot().ego_lane_offset_m.abs() < 0.6,
            "t = {}",
            sim.t_s()
        );
    }
    // 25 + 49 + 25 m of curves at up to 10 m/s: over 8 s of 60 Hz steps on them.
    assert!(on_curves > 480, "{on_curves} steps on the curved pieces");
    let end = sim.ego_state().pos_m;
    assert_eq!(n.driving_surface_at([end[0], end[2]]), Some(e));
}
