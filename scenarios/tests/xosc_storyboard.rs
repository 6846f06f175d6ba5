//! The OpenSCENARIO storyboard runtime on the ALKS suite (openMSL, MPL-2.0,
//! `tests/data/xosc/alks`): every entity scripted (the ego at its `Init` speed), the
//! storyboard stepped at 1/60 s, and the motion each template's storyboard describes checked
//! against what its parameters say it should be.

use std::path::{Path, PathBuf};

use paracosm_engine::network::{opendrive, MapRef};
use paracosm_openscenario::read_scenario;
use paracosm_scenarios::xosc::road::Roads;
use paracosm_scenarios::xosc::story::Storyboard;

const DT: f64 = 1.0 / 60.0;

thread_local! {
    /// Each road of the suite read once per test thread.
    static MAPS: std::cell::RefCell<std::collections::HashMap<String, MapRef>> =
        std::cell::RefCell::new(std::collections::HashMap::new());
}

fn alks(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/xosc/alks/concrete_scenarios")
        .join(name)
}

/// The storyboard of template `name` with `overrides`, every entity scripted, and the index
/// of each entity by name.
fn storyboard(name: &str, overrides: &[(&str, &str)]) -> (Storyboard, Vec<String>) {
    let overrides: Vec<(String, String)> = overrides
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let model = read_scenario(&alks(name), &overrides).expect("the template reads");
    let road = model.road_network.as_ref().expect("a road network");
    let map = MAPS.with(|maps| {
        maps.borrow_mut()
            .entry(road.item.clone())
            .or_insert_with(|| {
                let text = std::fs::read_to_string(&road.item).expect("the map reads");
                MapRef::new(
                    opendrive::import(&road.item, &text)
                        .expect("the map imports")
                        .map,
                )
            })
            .clone()
    });
    let names = model.entities.iter().map(|e| e.name.clone()).collect();
    let sb = Storyboard::new(&model, Roads::new(&map), None).expect("Init performs");
    (sb, names)
}

fn index(names: &[String], name: &str) -> usize {
    names.iter().position(|n| n == name).expect("entity")
}

/// Steps `sb` until its stop trigger (or `limit_s`), calling `each` with the time after each
/// step; returns the time it ended.
fn run(sb: &mut Storyboard, limit_s: f64, mut each: impl FnMut(f64, &Storyboard)) -> f64 {
    let mut t = 0.0;
    while !sb.ended && t < limit_s {
        sb.step(t, DT).expect("the storyboard steps");
        t += DT;
        each(t, sb);
    }
    t
}

#[test]
fn the_crossing_pedestrian_crosses_at_its_speed_when_the_ego_is_its_headway_away() {
    let (mut sb, names) = storyboard(
        "alks_scenario_4_2_3_crossing_pedestrian_template.xosc",
        &[
            ("Ego_InitSpeed_Ve0_kph", "36"),
            ("Ego_InitPosition_LaneId", "-4"),
            ("TargetBlocking_InitPosition_LongitudinalOffset_m", "200"),
        ],
    );
    let (ego, ped) = (index(&names, "Ego"), index(&names, "TargetBlocking"));
    let start = sb.actors[ped].state.pose;
    let lane_y = sb.actors[ego].state.pose.y;
    // Lateral offset -5 m (right of the lane), 5 km/h, crossing 10 m: 7.2 s, starting when the
    // ego's time headway to it drops below 5 / (5 / 3.6) = 3.6 s.
    let mut started = None;
    let mut headway_then = 0.0;
    let end = run(&mut sb, 60.0, |t, sb| {
        let p = sb.actors[ped].state.pose;
        if started.is_none() && (p.y - start.y).abs() > 1e-6 {
            started = Some(t);
            let e = &sb.actors[ego].state;
            // Freespace: from the ego's front bumper to the pedestrian's box.
            headway_then = (p.x - e.pose.x) / e.speed;
        }
    });
    let t0 = started.expect("the pedestrian starts to cross");
    // Between reference points: the 3.6 s between boxes plus the ego's front overhang and
    // the pedestrian's half depth at 10 m/s (under 0.6 s).
    assert!(
        (3.55..4.2).contains(&headway_then),
        "the crossing started at a headway of {headway_then} s"
    );
    let p = sb.actors[ped].state.pose;
    assert!(
        (p.y - (lane_y + 5.0)).abs() < 0.05,
        "it ends 5 m on the other side of the lane centre: {} vs {}",
        p.y,
        lane_y + 5.0
    );
    assert!(
        (p.x - start.x).abs() < 1e-6,
        "it crosses straight: from {start:?} to {p:?}"
    );
    // The stop trigger: 200 m at 10 m/s plus 10 s.
    assert!((end - 30.0).abs() < 2.0 * DT, "ended at {end} s");
    // 10 m at 5 km/h.
    let crossing = 10.0 / (5.0 / 3.6);
    assert!(t0 + crossing < end);
}

#[test]
fn the_cut_in_vehicle_changes_into_the_ego_lane_at_its_lateral_speed() {
    let (mut sb, names) = storyboard("alks_scenario_4_4_1_cut_in_no_collision_template.xosc", &[]);
    let (ego, cut) = (index(&names, "Ego"), index(&names, "CutInVehicle"));
    let ego_y = sb.actors[ego].state.pose.y;
    let y0 = sb.actors[cut].state.pose.y;
    assert!((y0 - ego_y).abs() > 3.0, "it starts in the next lane");
    let mut max_vy: f64 = 0.0;
    let mut last = y0;
    let mut moved_at = None;
    let mut settled_at = None;
    let end = run(&mut sb, 120.0, |t, sb| {
        let y = sb.actors[cut].state.pose.y;
        let vy = (y - last) / DT;
        max_vy = max_vy.max(vy.abs());
        if moved_at.is_none() && (y - y0).abs() > 1e-6 {
            moved_at = Some(t);
        }
        if moved_at.is_some()
            && settled_at.is_none()
            && (y - sb.actors[ego].state.pose.y).abs() < 1e-6
        {
            settled_at = Some(t);
        }
        last = y;
    });
    let (t0, t1) = (
        moved_at.expect("it moves over"),
        settled_at.expect("it arrives"),
    );
    // A sinusoidal change at a peak of 2 m/s over the lane width w: π w / 4 s.
    let width = (y0 - ego_y).abs();
    let expected = std::f64::consts::PI * width / (2.0 * 2.0);
    assert!(
        ((t1 - t0) - expected).abs() < 3.0 * DT,
        "{} vs {expected}",
        t1 - t0
    );
    assert!((max_vy - 2.0).abs() < 0.01, "peak lateral speed {max_vy}");
    assert!(end > t1, "the storyboard ends after the cut-in ({end} s)");
}

#[test]
fn the_lead_vehicle_brakes_at_its_deceleration_after_starting_at_its_headway() {
    let (mut sb, names) = storyboard(
        "alks_scenario_4_3_2_follow_lead_vehicle_emergency_brake_template.xosc",
        &[("LeadVehicle_Deceleration_Rate_mps2", "6")],
    );
    let (ego, lead) = (index(&names, "Ego"), index(&names, "LeadVehicle"));
    let e = sb.actors[ego].clone();
    let l = sb.actors[lead].clone();
    // Init: 2 s of time gap between the boxes at 60 km/h.
    let gap = (l.state.pose.x + l.centre_m[0] - l.size_m[0] / 2.0)
        - (e.state.pose.x + e.centre_m[0] + e.size_m[0] / 2.0);
    assert!((gap - 2.0 * 60.0 / 3.6).abs() < 0.05, "initial gap {gap} m");
    let mut decel: f64 = 0.0;
    let mut stopped = false;
    run(&mut sb, 120.0, |_, sb| {
        let a = sb.actors[lead].state.accel;
        decel = decel.max(-a);
        stopped |= sb.actors[lead].state.speed == 0.0;
    });
    assert!(
        (decel - 6.0).abs() < 0.05,
        "largest deceleration {decel} m/s²"
    );
    assert!(stopped, "the lead vehicle stops");
}

#[test]
fn every_alks_template_runs_to_its_stop_trigger() {
    let dir = alks("");
    let mut ran = 0;
    for entry in std::fs::read_dir(&dir).expect("the suite") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "xosc") {
            continue;
        }
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("name")
            .to_owned();
        let (mut sb, _) = storyboard(&name, &[]);
        let end = run(&mut sb, 2000.0, |_, _| {});
        assert!(sb.ended, "{name} did not end by 2000 s");
        assert!(end > 1.0, "{name} ended at {end} s");
        ran += 1;
    }
    assert_eq!(ran, 15);
}
