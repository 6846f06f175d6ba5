//! The road surface under the vehicles (issue 14): each wheel of the ego vehicle and each NPC
//! car grips with the friction of the piece under it, and leaving the road is seen.

use paracosm_engine::behaviour::GraphBuilder;
use paracosm_engine::network::{PieceKind, GROUND_FRICTION};
use paracosm_engine::rx::{Func, NoHost, Node, Value};
use paracosm_engine::sut::ConstantControl;
use paracosm_engine::sut::Sut;
use paracosm_engine::{
    CarSpec, Control, EgoSpec, EnvironmentSpec, Lane, LidarSpec, Network, PieceId, SensorSpec,
    Simulation, Size, VehicleParams, WorldSpec, DEFAULT_DT_S,
};

fn segment(length_m: f64, friction: f64) -> PieceKind {
    PieceKind::Segment {
        length_m,
        lanes: 2,
        friction,
    }
}

/// Segments end to end with the given `(length m, friction)`, connected ONE to TWO.
fn road(pieces: &[(f64, f64)]) -> Network {
    let mut n = Network::new();
    let mut last: Option<PieceId> = None;
    for (i, &(len, mu)) in pieces.iter().enumerate() {
        let id = n.add(&format!("piece {i}"), segment(len, mu)).unwrap();
        if let Some(prev) = last {
            n.connect(prev, 1, id, 0).unwrap();
        }
        last = Some(id);
    }
    n
}

/// An NPC car: where it starts on lane 1 of piece 0 (m), and its speed (m/s) as a function of
/// time (s).
type Npc = (f64, fn(f64) -> f64);

/// The ego on lane 1 of piece 0 at `at_m`, moving at `speed_mps`, and `cars`.
fn world(network: Network, at_m: f64, speed_mps: f64, cars: &[Npc]) -> WorldSpec {
    let start = network.on_lane(PieceId(0), Lane::Driving(1), at_m).unwrap();
    let mut g = GraphBuilder::new();
    let light = g.push(Node::Const(Value::Num(0.5)));
    let fog = g.push(Node::Const(Value::Num(0.0)));
    let tick = g.push(Node::Tick);
    let mut specs = Vec::new();
    for &(car_at, profile) in cars {
        let speed = g.push(Node::Map {
            src: tick,
            f: Func::native("profile", move |a| {
                Ok(Value::Num(profile(a[0].as_num().unwrap())))
            }),
        });
        let loc = network
            .on_lane(PieceId(0), Lane::Driving(1), car_at)
            .unwrap();
        specs.push(CarSpec {
            path: network.route(&loc, &[], 5000.0).unwrap(),
            speed,
            color: "red".into(),
            size: Size::CAR,
            enabled: true,
            lane_change: None,
            lane_offsets_m: vec![],
            name: String::new(),
            keep_distance_m: None,
            tow: None,
        });
    }
    WorldSpec {
        dt_s: DEFAULT_DT_S,
        network,
        frictions: vec![],
        ego: EgoSpec {
            start,
            initial_speed_mps: speed_mps,
            vehicle: VehicleParams::default(),
            route: vec![],
            set_speed_mps: None,
            scripted: false,
        },
        pedestrians: vec![],
        cars: specs,
        obstacles: vec![],
        environment: EnvironmentSpec { light, fog },
        streams: g.finish().unwrap(),
        published: vec![],
        sensors: vec![SensorSpec::Lidar(LidarSpec::default())],
    }
}

/// Front wheels' hard points are 1.45 m ahead of the chassis centre (4.5 m body, axle 0.8 m
/// in from each end), the rear ones 1.45 m behind.
const AXLE_M: f64 = 4.5 / 2.0 - 0.8;

#[test]
fn a_wheel_crossing_onto_the_next_piece_grips_with_its_friction_within_one_step() {
    let spec = world(road(&[(60.0, 0.9), (200.0, 0.2)]), 50.0, 12.0, &[]);
    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = ConstantControl(Control::default());
    let (mut front_wet, mut rear_wet) = (false, false);
    while sim.t_s() < 2.0 {
        let x = sim.ego_state().pos_m[0];
        let control = sut.act(&sim.observation()).unwrap();
        sim.step(control, &mut NoHost).unwrap();
        let mu = sim.ego_wheel_frictions();
        assert_eq!(mu.len(), 4);
        // The friction used in this step is the one under the wheel when the step began.
        for (wheel, ahead) in [(0, AXLE_M), (1, AXLE_M), (2, -AXLE_M), (3, -AXLE_M)] {
            let x_wheel = x + ahead;
            if (x_wheel - 60.0).abs() < 0.01 {
                continue;
            }
            let expected = if x_wheel > 60.0 { 0.2 } else { 0.9 };
            assert!(
                (mu[wheel] - expected).abs() < 1e-6,
                "wheel {wheel} at x = {x_wheel:.3} m gripped with {} (expected {expected})",
                mu[wheel]
            );
        }
        front_wet |= mu[0] < 0.5 && mu[2] > 0.5;
        rear_wet |= mu[2] < 0.5;
    }
    assert!(
        front_wet,
        "a step with the front wheels on the wet piece and the rear on the dry"
    );
    assert!(rear_wet, "the rear wheels reached the wet piece");
}

/// Full braking from 12 m/s; returns the distance to a stop, m.
fn stopping_distance(network: Network) -> f64 {
    let spec = world(network, 50.0, 12.0, &[]);
    let mut sim = Simulation::new(&spec).unwrap();
    let start = sim.ego_state().pos_m[0];
    let mut brake = ConstantControl(Control {
        throttle: -1.0,
        steering: 0.0,
    });
    while sim.t_s() < 30.0 && sim.ego_state().speed_mps > 0.05 {
        let c = brake.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
    }
    sim.ego_state().pos_m[0] - start
}

#[test]
fn braking_on_a_wet_piece_ahead_takes_longer_than_on_a_dry_one() {
    let dry = stopping_distance(road(&[(55.0, 0.9), (200.0, 0.9)]));
    let wet = stopping_distance(road(&[(55.0, 0.9), (200.0, 0.1)]));
    // Dry: about 12² / (2 · 8) = 9 m. On the wet piece (from 5 m on) the tyres slide.
    assert!(dry < 12.0, "dry stopping distance {dry:.1} m");
    assert!(wet > 2.0 * dry, "wet {wet:.1} m vs dry {dry:.1} m");
}

/// The ego's mean deceleration under full braking from 12 m/s on one segment of friction
/// `mu`, m/s², measured from 11 m/s down to 3 m/s.
fn ego_deceleration(mu: f64) -> f64 {
    let spec = world(road(&[(300.0, mu)]), 50.0, 12.0, &[]);
    let mut sim = Simulation::new(&spec).unwrap();
    let mut brake = ConstantControl(Control {
        throttle: -1.0,
        steering: 0.0,
    });
    let (mut t11, mut t3) = (None, None);
    while sim.t_s() < 30.0 && t3.is_none() {
        let c = brake.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
        let v = sim.ego_state().speed_mps;
        if v <= 11.0 && t11.is_none() {
            t11 = Some(sim.t_s());
        }
        if v <= 3.0 {
            t3 = Some(sim.t_s());
        }
    }
    8.0 / (t3.unwrap() - t11.unwrap())
}

#[test]
fn the_ego_brakes_no_harder_than_mu_g_nor_than_its_brakes() {
    // rapier's ray-cast vehicle alone let a tyre brake with twice its friction (2.1 m/s² on
    // ice, 0.1): the friction circle held by `hold_to_grip` keeps it to μ·g.
    // The chassis' linear damping, 0.02 /s, adds 0.02·v: at most 0.22 m/s² from 11 m/s.
    let g = 9.81;
    // LANGUAGE.md gives the figure on ice as measured: it must be this one.
    let docs = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../LANGUAGE.md"),
    )
    .unwrap()
    .split_whitespace()
    .collect::<Vec<_>>()
    .join(" ");
    let ice = format!(
        "measured {:.2} with the body's air drag",
        ego_deceleration(0.1)
    );
    assert!(docs.contains(&ice), "LANGUAGE.md does not say \"{ice}\"");
    assert!(docs.contains("the default friction 0.8 included (7.85 m/s²)"));
    for mu in [0.1, 0.3, 0.5] {
        let a = ego_deceleration(mu);
        eprintln!("μ = {mu}: {a:.3} m/s²");
        assert!(
            a <= mu * g + 0.02 * 11.0 && a >= mu * g * 0.95,
            "μ = {mu}: {a:.3} m/s², μ·g = {:.3}",
            mu * g
        );
    }
    // On dry asphalt the brakes, 8 m/s², are the limit, not the tyres (0.9 · g = 8.8).
    let dry = ego_deceleration(0.9);
    assert!((dry - 8.0).abs() < 0.4, "dry: {dry:.3} m/s²");
}

/// Speed lost over 2 s from 12 m/s on ice with full steering and `throttle`, m/s.
fn speed_lost_turning_on_ice(throttle: f64) -> f64 {
    let spec = world(road(&[(300.0, 0.1)]), 50.0, 12.0, &[]);
    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = ConstantControl(Control {
        throttle,
        steering: 1.0,
    });
    while sim.t_s() < 2.0 {
        let c = sut.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
    }
    12.0 - sim.ego_state().speed_mps.abs()
}

#[test]
fn a_car_sliding_sideways_on_ice_still_brakes() {
    // Full steering on ice: the tyres slide sideways. Braking as well must still take its
    // share of the grip (holding the side force first left the brake none while sliding).
    let coasting = speed_lost_turning_on_ice(0.0);
    let braking = speed_lost_turning_on_ice(-1.0);
    eprintln!("lost {coasting:.3} m/s coasting, {braking:.3} m/s braking");
    assert!(
        braking > coasting + 0.4,
        "coasting {coasting:.3}, braking {braking:.3}"
    );
    // At most what rapier's limit lets the grip give, 1.32·μ·g over 2 s, plus drag.
    assert!(
        braking < 1.32 * 0.1 * 9.81 * 2.0 + 0.5,
        "braking {braking:.3}"
    );
}

#[test]
fn the_ego_pulls_away_on_ice_no_harder_than_its_driven_wheels_grip() {
    // Full throttle from rest on ice: only the rear wheels pull, so at most μ·g times their
    // share of the weight (about half), far below the engine's 3 m/s².
    let mu = 0.1;
    let spec = world(road(&[(300.0, mu)]), 50.0, 0.0, &[]);
    let mut sim = Simulation::new(&spec).unwrap();
    let mut gas = ConstantControl(Control {
        throttle: 1.0,
        steering: 0.0,
    });
    while sim.t_s() < 3.0 {
        let c = gas.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
    }
    let a = sim.ego_state().speed_mps / sim.t_s();
    assert!(
        a <= 0.55 * mu * 9.81 && a > 0.3 * mu * 9.81,
        "{a:.3} m/s² on ice"
    );
}

/// An NPC car told to stop dead at t = 1 s: its deceleration, m/s², measured over the step
/// after the command.
fn npc_deceleration(friction: f64) -> f64 {
    let stop_at_1 = |t: f64| if t < 1.0 { 10.0 } else { 0.0 };
    let spec = world(road(&[(300.0, friction)]), 10.0, 0.0, &[(40.0, stop_at_1)]);
    let mut sim = Simulation::new(&spec).unwrap();
    let mut speeds = Vec::new();
    while sim.t_s() < 1.5 {
        sim.step(Control::default(), &mut NoHost).unwrap();
        speeds.push((sim.t_s(), sim.snapshot().cars[0].speed_mps));
    }
    let at = |t: f64| speeds.iter().find(|(s, _)| *s >= t).unwrap().1;
    assert!(
        (at(0.5) - 10.0).abs() < 1e-9,
        "cruising at 10 m/s: {}",
        at(0.5)
    );
    (at(1.1) - at(1.3)) / 0.2
}

#[test]
fn an_npc_car_brakes_no_harder_than_the_friction_under_it_allows() {
    let g = 9.81;
    let dry = npc_deceleration(0.9);
    let wet = npc_deceleration(0.1);
    assert!((dry - 0.9 * g).abs() < 0.05 * g, "dry: {dry:.2} m/s²");
    assert!((wet - 0.1 * g).abs() < 0.01 * g, "wet: {wet:.2} m/s²");
}

#[test]
fn driving_past_a_dead_end_is_off_road_on_the_ground_beyond() {
    // A 100 m road ending in a dead end; the ego rolls off it at 12 m/s.
    let spec = world(road(&[(100.0, 0.8)]), 60.0, 12.0, &[]);
    let mut sim = Simulation::new(&spec).unwrap();
    let mut coast = ConstantControl(Control::default());
    let snap = sim.snapshot();
    assert!(!snap.ego_off_road);
    assert!(
        (snap.ego_road_edge_m - 1.75).abs() < 0.01,
        "{}",
        snap.ego_road_edge_m
    );
    assert!(
        snap.ego_lane_offset_m.abs() < 0.01,
        "{}",
        snap.ego_lane_offset_m
    );
    let mut left_at = None;
    while sim.t_s() < 6.0 {
        let c = coast.act(&sim.observation()).unwrap();
        sim.step(c, &mut NoHost).unwrap();
        let s = sim.snapshot();
        if s.ego_off_road && left_at.is_none() {
            left_at = Some(s.ego.pos_m[0]);
        }
        assert_eq!(
            s.ego_off_road,
            s.ego.pos_m[0] > 100.0,
            "at x = {}",
            s.ego.pos_m[0]
        );
    }
    let x = left_at.expect("the ego left the road");
    assert!((x - 100.0).abs() < 0.5, "left the road at x = {x}");
    let end = sim.snapshot();
    assert!(
        end.ego.pos_m[0] > 120.0,
        "it drove on: x = {}",
        end.ego.pos_m[0]
    );
    assert!(end.ego_road_edge_m < -20.0, "{}", end.ego_road_edge_m);
    // On the grass: its wheels grip with the ground's friction and it has not fallen.
    assert!(
        end.ego.pos_m[1] > 0.0,
        "chassis height {}",
        end.ego.pos_m[1]
    );
    assert!(sim
        .ego_wheel_frictions()
        .iter()
        .all(|&mu| (mu - GROUND_FRICTION).abs() < 1e-6));
}
