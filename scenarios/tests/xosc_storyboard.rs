//! The OpenSCENARIO storyboard runtime on the ALKS suite (openMSL, MPL-2.0,
//! `tests/data/xosc/alks`): every entity scripted (the ego at its `Init` speed), the
//! storyboard stepped at 1/60 s, and the motion each template's storyboard describes checked
//! against what its parameters say it should be.

use std::path::{Path, PathBuf};

use paracosm_engine::network::roads::Roads;
use paracosm_engine::network::{opendrive, MapRef};
use paracosm_openscenario::read_scenario;
use paracosm_scenarios::xosc::story::{StoryError, Storyboard};

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
    let overrides: Vec<(String, paracosm_openscenario::Value)> = overrides
        .iter()
        .map(|(a, b)| {
            (
                a.to_string(),
                paracosm_openscenario::Value::Str(b.to_string()),
            )
        })
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
    let mut arrived = None;
    let mut headway_then = 0.0;
    let end = run(&mut sb, 60.0, |t, sb| {
        let p = sb.actors[ped].state.pose;
        if started.is_none() && (p.y - start.y).abs() > 1e-6 {
            started = Some(t);
            let e = &sb.actors[ego].state;
            headway_then = (p.x - e.pose.x) / e.speed;
        }
        if arrived.is_none() && (p.y - (lane_y + 5.0)).abs() < 1e-6 {
            arrived = Some((t, p));
        }
    });
    let t0 = started.expect("the pedestrian starts to cross");
    // Between reference points: the 3.6 s between boxes plus the ego's front overhang and
    // the pedestrian's half depth at 10 m/s (under 0.6 s).
    assert!(
        (3.55..4.2).contains(&headway_then),
        "the crossing started at a headway of {headway_then} s"
    );
    let (t1, p) = arrived.expect("it reaches 5 m on the other side of the lane centre");
    assert!(
        (p.x - start.x).abs() < 1e-6,
        "it crosses straight: from {start:?} to {p:?}"
    );
    // 10 m at 5 km/h.
    let crossing = 10.0 / (5.0 / 3.6);
    assert!(
        ((t1 - t0) - crossing).abs() < 2.0 * DT,
        "crossed in {} s, not {crossing} s",
        t1 - t0
    );
    // The stop trigger: 200 m at 10 m/s plus 10 s.
    assert!((end - 30.0).abs() < 2.0 * DT, "ended at {end} s");
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

/// A start trigger counts only while its element waits: an event whose condition
/// (`SimulationTime > 5`, `delay` 3 s) holds from the start, in an act that starts at 10 s,
/// starts at 13 s, not at 10 s; and an element-state condition sees the transition of the
/// step before (a second event starts on the first's `endTransition`).
/// The ALKS suite's straight road, for the scenarios written here.
fn straight_road() -> PathBuf {
    alks("road_networks/alks_road_straight.xodr")
}

/// A box-shaped obstacle named `name` (4 × 1.8 × 1.5 m), as a `ScenarioObject`.
fn box_object(name: &str) -> String {
    format!(
        r#"<ScenarioObject name="{name}"><MiscObject name="box" miscObjectCategory="obstacle" mass="500">
        <BoundingBox><Center x="0" y="0" z="0.75"/><Dimensions width="1.8" length="4" height="1.5"/></BoundingBox>
        <Properties/></MiscObject></ScenarioObject>"#
    )
}

/// A `SpeedAction` to `v` m/s at once, as a `PrivateAction`.
fn step_to(v: f64) -> String {
    format!(
        r#"<PrivateAction><LongitudinalAction><SpeedAction>
              <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
              <SpeedActionTarget><AbsoluteTargetSpeed value="{v}"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction></PrivateAction>"#
    )
}

/// A scenario on the ALKS suite's straight road: its `entities`, its `Init` actions, its
/// `stories` (whole `<Story>` elements) and a stop trigger at `stop_s` seconds.
fn on_straight_road(
    description: &str,
    entities: &str,
    init: &str,
    stories: &str,
    stop_s: f64,
) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="{description}" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>
  <Entities>{entities}</Entities>
  <Storyboard>
    <Init><Actions>{init}</Actions></Init>
    {stories}
    <StopTrigger><ConditionGroup>
      <Condition name="End" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="{stop_s}" rule="greaterOrEqual"/></ByValueCondition>
      </Condition>
    </ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
        road = straight_road().display(),
    )
}

/// The storyboard of the scenario `text` (written to a file named by `tag` and read from it),
/// every entity scripted, or why its `Init` cannot be performed.
fn storyboard_of(tag: &str, text: &str) -> Result<Storyboard, StoryError> {
    let file = std::env::temp_dir().join(format!("paracosm-{tag}-{}.xosc", std::process::id()));
    std::fs::write(&file, text).unwrap();
    let model = read_scenario(&file, &[]).expect("reads");
    std::fs::remove_file(&file).ok();
    let road = model.road_network.as_ref().expect("a road network");
    let map = MapRef::new(
        opendrive::import(&road.item, &std::fs::read_to_string(&road.item).unwrap())
            .unwrap()
            .map,
    );
    Storyboard::new(&model, Roads::new(&map), None)
}

#[test]
fn a_delay_counts_from_when_the_element_waits_and_transitions_are_seen_next_step() {
    let init = r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction></Private>
      <Private entityRef="B"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-3" s="60" offset="0"/></Position></TeleportAction></PrivateAction></Private>"#;
    let story = format!(
        r#"<Story name="S">
      <Act name="Late">
        <ManeuverGroup maximumExecutionCount="1" name="G">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/><EntityRef entityRef="B"/></Actors>
          <Maneuver name="M">
            <Event name="First" priority="parallel">
              <Action name="Go">{go}</Action>
              <StartTrigger><ConditionGroup>
                <Condition name="C" delay="3" conditionEdge="none">
                  <ByValueCondition><SimulationTimeCondition value="5" rule="greaterThan"/></ByValueCondition>
                </Condition>
              </ConditionGroup></StartTrigger>
            </Event>
            <Event name="Second" priority="parallel">
              <Action name="Faster">{faster}</Action>
              <StartTrigger><ConditionGroup>
                <Condition name="D" delay="0" conditionEdge="none">
                  <ByValueCondition><StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="First" state="endTransition"/></ByValueCondition>
                </Condition>
              </ConditionGroup></StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup>
          <Condition name="T" delay="0" conditionEdge="none">
            <ByValueCondition><SimulationTimeCondition value="10" rule="greaterOrEqual"/></ByValueCondition>
          </Condition>
        </ConditionGroup></StartTrigger>
      </Act>
    </Story>"#,
        go = step_to(5.0),
        faster = step_to(10.0),
    );
    let entities = box_object("A") + &box_object("B");
    let text = on_straight_road("delay", &entities, init, &story, 20.0);
    let mut sb = storyboard_of("delay", &text).expect("Init performs");
    let (mut went, mut faster) = (None, None);
    run(&mut sb, 30.0, |t, sb| {
        let v = sb.actors[0].state.speed;
        if went.is_none() && v > 0.0 {
            went = Some(t);
        }
        if faster.is_none() && v > 5.0 {
            faster = Some(t);
        }
    });
    let went = went.expect("the first event starts");
    // The act starts at 10 s; its event's trigger waits from the next step, true at once,
    // and reports 3 s later.
    assert!(
        (13.0..13.1).contains(&went),
        "the first event started at {went} s"
    );
    let faster = faster.expect("the second event starts");
    assert!(
        faster > went && faster - went < 4.0 * DT,
        "the second event started {} s after the first",
        faster - went
    );
}

/// A chain of events, each started when the one before ends, named plainly or qualified
/// with its maneuver (`M::e3`, OpenSCENARIO 1.1+): every event fires, in order. Each
/// condition reads the element it names, found once when the storyboard is built (a
/// qualified name passed the load's check but matched nothing when run, so the chain stopped
/// at its first qualified link).
#[test]
fn a_chain_of_events_fires_in_order_each_when_the_one_before_ends() {
    let n = 40;
    let mut events = String::new();
    for i in 0..n {
        let start = if i == 0 {
            r#"<SimulationTimeCondition value="0.5" rule="greaterThan"/>"#.to_owned()
        } else {
            let name = if i % 2 == 0 {
                format!("e{}", i - 1)
            } else {
                format!("M::e{}", i - 1)
            };
            format!(
                r#"<StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="{name}" state="endTransition"/>"#
            )
        };
        events.push_str(&format!(
            r#"<Event name="e{i}" priority="parallel"><Action name="a{i}">{go}</Action>
            <StartTrigger><ConditionGroup><Condition name="c{i}" delay="0" conditionEdge="none"><ByValueCondition>{start}</ByValueCondition></Condition></ConditionGroup></StartTrigger></Event>
"#,
            go = step_to(0.25 * f64::from(i + 1))
        ));
    }
    let init = r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction></Private>"#;
    let story = format!(
        r#"<Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="G">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/></Actors>
        <Maneuver name="M">{events}</Maneuver>
      </ManeuverGroup>
      <StartTrigger><ConditionGroup><Condition name="T" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition>
      </Condition></ConditionGroup></StartTrigger>
    </Act></Story>"#
    );
    let text = on_straight_road("chain", &box_object("A"), init, &story, 5.0);
    let mut sb = storyboard_of("chain", &text).expect("Init performs");
    let mut speeds = Vec::new();
    run(&mut sb, 10.0, |_, sb| speeds.push(sb.actors[0].state.speed));
    assert!(
        speeds.windows(2).all(|w| w[1] >= w[0]),
        "the events fired out of order: {speeds:?}"
    );
    let last = speeds.last().copied().unwrap_or_default();
    assert_eq!(last, 0.25 * f64::from(n), "the chain stopped at {last} m/s");
}

/// A position relative to an entity that is on no lane names where that entity stands, so
/// that the reader finds the placement at fault (the ego's teleport far off the map), not
/// only the relative position that could not be resolved.
#[test]
fn a_position_relative_to_an_entity_off_the_map_says_where_that_entity_stands() {
    let init = r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><WorldPosition x="5000000" y="0"/></Position></TeleportAction></PrivateAction></Private>
      <Private entityRef="B"><PrivateAction><TeleportAction><Position><RelativeRoadPosition entityRef="A" ds="30" dt="0"/></Position></TeleportAction></PrivateAction></Private>"#;
    let entities = box_object("A") + &box_object("B");
    let text = on_straight_road("far", &entities, init, "", 5.0);
    let e = storyboard_of("far", &text).unwrap_err();
    let message = e.to_string();
    assert!(
        message.contains("to A, which is not on a lane: it stands at x = 5000000.0 m, y = 0.0 m"),
        "{message}"
    );
}

/// A point on a lane anchors at its own station, wherever it lies between the lane's
/// stations: an entity put by a world position and then driven along its lane starts where
/// it was put. (The station used to be one the map's index named near the point, up to
/// 1.15 m back: an exported test read back started its cars there.)
#[test]
fn a_point_on_a_lane_anchors_at_its_own_station() {
    // On a bend, within the sagitta of the map's 0.5 m chords (0.5² / (8 · 250) m).
    for (road, within) in [
        ("alks_road_straight.xodr", 1e-6),
        ("alks_road_left_radius_250m.xodr", 1e-3),
        ("alks_road_right_radius_1000m.xodr", 1e-3),
    ] {
        let path = alks("road_networks").join(road);
        let text = std::fs::read_to_string(&path).expect("the map reads");
        let map = MapRef::new(
            opendrive::import(path.to_str().unwrap(), &text)
                .expect("the map imports")
                .map,
        );
        let roads = Roads::new(&map);
        let mut worst = 0.0f64;
        for (k, lane) in roads
            .map()
            .lanes
            .iter()
            .enumerate()
            .filter(|(_, l)| l.drivable)
        {
            let (s0, s1) = (lane.s[0], lane.s[lane.s.len() - 1]);
            let mut s = s0 + 0.5;
            while s < s1 - 0.5 {
                let lp = paracosm_engine::network::roads::LanePos {
                    lane: k,
                    s,
                    d: 0.3,
                    rev: false,
                };
                let p = roads.pose_of(&lp);
                let at = roads.anchor(p.x, p.y).expect("on a lane");
                assert_eq!(at.lane, k, "{road}: lane at s = {s}");
                worst = worst.max((at.s - s).abs()).max((at.d - 0.3).abs());
                s += 0.37;
            }
        }
        assert!(worst < within, "{road}: anchored {worst} m off");
        println!("{road}: anchored within {worst:.2e} m");
    }
}

/// A `RelativeAngleCondition` (OpenSCENARIO 1.3): B speeds up when A's heading, less B's,
/// comes within 0.003 rad of 0.03 rad while A changes into B's lane behind it; in the road's frame
/// (each heading less the road's direction where the entity is) as in B's own. The event
/// starts at the step after the condition first holds on the poses the test reads, and not
/// before A turns.
#[test]
fn a_relative_angle_condition_holds_when_one_heading_less_the_other_is_within_its_tolerance() {
    for frame in ["entity", "road"] {
        let init = format!(
            r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction>{a}</Private>
      <Private entityRef="B"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-3" s="60" offset="0"/></Position></TeleportAction></PrivateAction>{a}</Private>"#,
            a = step_to(20.0)
        );
        let story = format!(
            r#"<Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="GA">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/></Actors>
        <Maneuver name="MA"><Event name="Left" priority="parallel"><Action name="l"><PrivateAction><LateralAction><LaneChangeAction>
          <LaneChangeActionDynamics dynamicsShape="sinusoidal" value="4" dynamicsDimension="time"/>
          <LaneChangeTarget><RelativeTargetLane entityRef="A" value="1"/></LaneChangeTarget></LaneChangeAction></LateralAction></PrivateAction></Action>
          <StartTrigger><ConditionGroup><Condition name="At2" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="2" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>
      <ManeuverGroup maximumExecutionCount="1" name="GB">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="B"/></Actors>
        <Maneuver name="MB"><Event name="Faster" priority="parallel"><Action name="f">{faster}</Action>
          <StartTrigger><ConditionGroup><Condition name="Turned" delay="0" conditionEdge="none"><ByEntityCondition>
            <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="A"/></TriggeringEntities>
            <EntityCondition><RelativeAngleCondition entityRef="B" angleType="heading" angle="0.03" angleTolerance="0.003" coordinateSystem="{frame}"/></EntityCondition>
          </ByEntityCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>
      <StartTrigger><ConditionGroup><Condition name="T" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition>
      </Condition></ConditionGroup></StartTrigger>
    </Act></Story>"#,
            faster = step_to(25.0)
        );
        let entities = box_object("A") + &box_object("B");
        let text = on_straight_road("relative angle", &entities, &init, &story, 8.0);
        let text = text.replace(r#"revMinor="2""#, r#"revMinor="3""#);
        let mut sb = storyboard_of("relative-angle", &text).expect("Init performs");
        let (mut holds, mut faster) = (None, None);
        run(&mut sb, 10.0, |t, sb| {
            let (a, b) = (&sb.actors[0].state, &sb.actors[1].state);
            let rel = paracosm_engine::network::roads::wrap(a.pose.h - b.pose.h);
            if holds.is_none() && (rel - 0.03).abs() < 0.003 {
                holds = Some(t);
            }
            if faster.is_none() && b.speed > 20.0 {
                faster = Some(t);
            }
        });
        let holds = holds.expect("A turns 0.03 rad from B's heading");
        let faster = faster.unwrap_or_else(|| panic!("{frame}: B never sped up"));
        assert!(holds > 2.0, "{frame}: A turned at {holds} s");
        assert!(
            (faster - holds - DT).abs() < 1e-9,
            "{frame}: the condition held at {holds} s, B sped up at {faster} s"
        );
    }
}

/// A storyboard read as CARLA's scenario_runner reads its files (`CARLA:` in the
/// description): the event's two conditions hold at different times (`time < 0.5` at the
/// start, `time > 1` later), which fires a group once each has held (a latch), where the
/// standard's reading never fires it; its `SpeedAction` to 2 m/s by a distance of 20 m holds
/// the speed for those 20 m before the next event stops the box; and the storyboard ends
/// with its story, long before its stop trigger at 100 s.
#[test]
fn carlas_reading_latches_conditions_holds_a_speed_for_its_distance_and_ends_with_its_story() {
    let init = r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction></Private>"#;
    let speed = |v: f64, dimension: &str, value: f64| {
        format!(
            r#"<PrivateAction><LongitudinalAction><SpeedAction>
              <SpeedActionDynamics dynamicsShape="step" value="{value}" dynamicsDimension="{dimension}"/>
              <SpeedActionTarget><AbsoluteTargetSpeed value="{v}"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction></PrivateAction>"#
        )
    };
    let time = |rule: &str, v: f64| {
        format!(
            r#"<Condition name="T{rule}" delay="0" conditionEdge="rising"><ByValueCondition><SimulationTimeCondition value="{v}" rule="{rule}"/></ByValueCondition></Condition>"#
        )
    };
    let stories = format!(
        r#"<Story name="S"><Act name="Act"><ManeuverGroup maximumExecutionCount="1" name="G">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/></Actors>
          <Maneuver name="M">
            <Event name="Go" priority="overwrite"><Action name="Go">{go}</Action>
              <StartTrigger><ConditionGroup>{late}{early}</ConditionGroup></StartTrigger></Event>
            <Event name="Stop" priority="overwrite"><Action name="Stop">{stop}</Action>
              <StartTrigger><ConditionGroup><Condition name="AfterGo" delay="0" conditionEdge="none"><ByValueCondition>
                <StoryboardElementStateCondition storyboardElementType="action" storyboardElementRef="Go" state="endTransition"/>
              </ByValueCondition></Condition></ConditionGroup></StartTrigger></Event>
          </Maneuver></ManeuverGroup>
          <StartTrigger><ConditionGroup>{start}</ConditionGroup></StartTrigger></Act></Story>"#,
        go = speed(2.0, "distance", 20.0),
        stop = speed(0.0, "time", 0.0),
        late = time("greaterThan", 1.0),
        early = time("lessThan", 0.5),
        start = time("greaterOrEqual", 0.0),
    );
    for (description, carla) in [("plain", false), ("CARLA:Latch", true)] {
        let text = on_straight_road(description, &box_object("A"), init, &stories, 100.0);
        let mut sb = storyboard_of("carla-latch", &text).unwrap();
        let mut started = None;
        let end = run(&mut sb, 100.0, |t, sb| {
            if started.is_none() && sb.actors[0].state.speed > 1.0 {
                started = Some(t);
            }
        });
        let travelled = sb.actors[0].state.travelled_m;
        if !carla {
            assert_eq!(
                started, None,
                "the standard's reading never fires the group"
            );
            assert!(
                (end - 100.0).abs() < 0.02,
                "it runs to its stop trigger: {end}"
            );
            continue;
        }
        let started = started.expect("CARLA's reading fires the group");
        assert!(
            (started - 1.0).abs() < 0.05,
            "fired once time > 1 also held: {started}"
        );
        assert!(
            (travelled - 20.0).abs() < 0.05,
            "2 m/s held for 20 m: {travelled}"
        );
        assert_eq!(sb.actors[0].state.speed, 0.0, "then stopped");
        assert!(
            (end - (started + 10.0)).abs() < 0.1,
            "ended with its story: {end}"
        );
    }
}

/// A controller the storyboard assigns an entity that no system under test drives is the
/// storyboard's motion only when it is of a kind that follows the storyboard (esmini's
/// `DefaultController`, CARLA's `npc_vehicle_control`); an activated controller of another
/// kind (esmini's ACC) is refused at load, naming it, whether the assignment or a later
/// `ActivateControllerAction` activates it. An assignment that activates nothing is noted.
#[test]
fn an_activated_controller_the_storyboard_cannot_stand_for_is_refused() {
    let init = r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction></Private>"#;
    let story = |kind: &str, activate: &str, then: &str| {
        format!(
            r#"<Story name="S"><Act name="Act"><ManeuverGroup maximumExecutionCount="1" name="G">
              <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/></Actors>
              <Maneuver name="M"><Event name="E" priority="overwrite">
                <Action name="Assign"><PrivateAction><ControllerAction><AssignControllerAction {activate}><Controller name="c"><Properties><Property name="esminiController" value="{kind}"/></Properties></Controller></AssignControllerAction></ControllerAction></PrivateAction></Action>
                {then}
                <StartTrigger><ConditionGroup><Condition name="T" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StartTrigger>
              </Event></Maneuver></ManeuverGroup>
              <StartTrigger><ConditionGroup><Condition name="S" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Act></Story>"#
        )
    };
    let activate = r#"<Action name="On"><PrivateAction><ControllerAction><ActivateControllerAction longitudinal="true" lateral="true"/></ControllerAction></PrivateAction></Action>"#;
    let check = |tag: &str, stories: &str| {
        let text = on_straight_road("plain", &box_object("A"), init, stories, 10.0);
        let file =
            std::env::temp_dir().join(format!("paracosm-ctl-{tag}-{}.xosc", std::process::id()));
        std::fs::write(&file, text).unwrap();
        let model = read_scenario(&file, &[]).expect("reads");
        std::fs::remove_file(&file).ok();
        paracosm_scenarios::xosc::check(&model, None).map_err(|e| e.to_string())
    };
    let err = check("acc-later", &story("ACCController", "", activate)).unwrap_err();
    assert!(
        err.contains("activates a controller of A that paracosm cannot run"),
        "{err}"
    );
    assert!(err.contains("controller c (ACCController)"), "{err}");
    let err = check(
        "acc-now",
        &story("ACCController", r#"activateLongitudinal="true""#, ""),
    )
    .unwrap_err();
    assert!(
        err.contains("has controller c (ACCController) drive A"),
        "{err}"
    );
    let warnings = check("acc-idle", &story("ACCController", "", "")).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.message.contains("assigned to A but not activated")),
        "{warnings:?}"
    );
    let warnings = check("default", &story("DefaultController", "", activate)).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.message.contains("ActivateControllerAction does nothing")),
        "{warnings:?}"
    );
}

/// In CARLA's reading a condition latches while its element waits, and only then: an event
/// run again (`maximumExecutionCount` 3) waits afresh, so a condition that held once before
/// its first run (`time < 0.05`) does not fire it again. Each run changes the box's speed at
/// once, so the event ends in the step it starts and is rearmed within that step.
#[test]
fn a_latch_does_not_outlive_the_run_its_event_waited_for() {
    let init = r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction></Private>"#;
    let stories = format!(
        r#"<Story name="S"><Act name="Act"><ManeuverGroup maximumExecutionCount="1" name="G">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/></Actors>
          <Maneuver name="M"><Event name="Go" priority="overwrite" maximumExecutionCount="3">
            <Action name="Go">{go}</Action>
            <StartTrigger><ConditionGroup>
              <Condition name="Early" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="0.05" rule="lessThan"/></ByValueCondition></Condition>
              <Condition name="Late" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition></Condition>
            </ConditionGroup></StartTrigger></Event></Maneuver></ManeuverGroup>
          <StartTrigger><ConditionGroup><Condition name="S" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Act></Story>"#,
        go = step_to(2.0),
    );
    let text = on_straight_road("CARLA:Rearm", &box_object("A"), init, &stories, 5.0);
    let mut sb = storyboard_of("carla-rearm", &text).unwrap();
    let mut starts = 0;
    run(&mut sb, 5.0, |_, sb| {
        starts += sb
            .transitions()
            .iter()
            .filter(|(kind, name, what)| *kind == "event" && *name == "Go" && *what == "start")
            .count();
    });
    assert_eq!(starts, 1, "the event ran once: its rearm waits afresh");
}

/// A car named `name` (4.6 × 1.9 × 1.5 m) whose `Performance` allows `max_acc` m/s², as a
/// `ScenarioObject`.
fn car_object(name: &str, max_acc: f64) -> String {
    format!(
        r#"<ScenarioObject name="{name}"><Vehicle name="car" vehicleCategory="car">
        <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox>
        <Performance maxSpeed="60" maxAcceleration="{max_acc}" maxDeceleration="9"/>
        <Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles>
        <Properties/></Vehicle></ScenarioObject>"#
    )
}

/// `entity` placed on lane `lane` of the straight road at station `s` (m), with `Init`'s speed
/// `v` (m/s).
fn placed(entity: &str, lane: i32, s: f64, v: f64) -> String {
    format!(
        r#"<Private entityRef="{entity}"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="{lane}" s="{s}" offset="0"/></Position></TeleportAction></PrivateAction>{speed}</Private>"#,
        speed = step_to(v)
    )
}

/// One story in which `actor` performs `action` (a `PrivateAction`) from the start.
fn story_of(actor: &str, action: &str) -> String {
    format!(
        r#"<Story name="S"><Act name="Act"><ManeuverGroup maximumExecutionCount="1" name="G">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="{actor}"/></Actors>
          <Maneuver name="M"><Event name="E" priority="overwrite"><Action name="A">{action}</Action>
            <StartTrigger><ConditionGroup><Condition name="Now" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event>
          </Maneuver></ManeuverGroup></Act></Story>"#
    )
}

/// A `SynchronizeAction` times its entity to reach its target when the master reaches the
/// master's (esmini's `SynchronizeAction::Step`): the master drives 200 m at 20 m/s, so the
/// synchronized car, standing 100 m from its target, covers them in the same 10 s and arrives
/// at the final speed asked (5 m/s), within a step; with a steady state of 2 s it drives its
/// last 2 s at that speed. The action then ends and the speed stays.
#[test]
fn a_synchronized_entity_arrives_at_its_target_with_its_master_at_the_final_speed() {
    for steady in ["", r#"<TargetTimeSteadyState time="2"/>"#] {
        let sync = format!(
            r#"<PrivateAction><SynchronizeAction masterEntityRef="Master">
              <TargetPositionMaster><LanePosition roadId="0" laneId="-4" s="220" offset="0"/></TargetPositionMaster>
              <TargetPosition><LanePosition roadId="0" laneId="-1" s="110" offset="0"/></TargetPosition>
              <FinalSpeed><AbsoluteSpeed value="5">{steady}</AbsoluteSpeed></FinalSpeed>
            </SynchronizeAction></PrivateAction>"#
        );
        let entities = format!("{}{}", box_object("Master"), box_object("Synced"));
        let init = format!(
            "{}{}",
            placed("Master", -4, 20.0, 20.0),
            placed("Synced", -1, 10.0, 0.0)
        );
        let text = on_straight_road("sync", &entities, &init, &story_of("Synced", &sync), 14.0);
        let mut sb = storyboard_of("sync", &text).unwrap();
        let (mut arrival, mut at_steady) = (None, None);
        run(&mut sb, 14.0, |t, sb| {
            let (m, y) = (&sb.actors[0].state, &sb.actors[1].state);
            if arrival.is_none() && m.lane.unwrap().s >= 220.0 {
                arrival = Some((t, y.lane.unwrap().s, y.speed));
            }
            if (t - 9.0).abs() < DT / 2.0 {
                at_steady = Some(y.speed);
            }
        });
        let (t, s, v) = arrival.expect("the master arrives");
        assert!(
            (t - 10.0).abs() < 2.0 * DT,
            "{steady}: the master at 220 m at {t} s"
        );
        assert!(
            (s - 110.0).abs() < 20.0 * DT,
            "{steady}: the synchronized car at {s} m"
        );
        assert!((v - 5.0).abs() < 1e-9, "{steady}: at {v} m/s");
        if !steady.is_empty() {
            let v9 = at_steady.unwrap();
            assert!(
                (v9 - 5.0).abs() < 1e-9,
                "in its steady state at 9 s: {v9} m/s"
            );
        }
        assert_eq!(
            sb.actors[1].state.speed, 5.0,
            "{steady}: the final speed stays"
        );
    }
}

/// A vehicle's `Performance` limits the speed changes the storyboard makes it perform, as
/// esmini's `LongSpeedAction` keeps them: asked from 0 to 20 m/s over 2 s, a car allowed 2 m/s²
/// takes 10 s (10 m/s at 5 s), and its action ends once it is there; a pedestrian, without
/// limits in esmini too, follows the transition.
#[test]
fn a_vehicles_performance_limits_its_speed_changes() {
    let speed = r#"<PrivateAction><LongitudinalAction><SpeedAction>
        <SpeedActionDynamics dynamicsShape="linear" value="2" dynamicsDimension="time"/>
        <SpeedActionTarget><AbsoluteTargetSpeed value="20"/></SpeedActionTarget>
      </SpeedAction></LongitudinalAction></PrivateAction>"#;
    for (object, at_5s, reached) in [
        (car_object("A", 2.0), 10.0, 10.0),
        (
            r#"<ScenarioObject name="A"><Pedestrian name="p" pedestrianCategory="pedestrian" mass="80"><BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.6" height="1.8"/></BoundingBox><Properties/></Pedestrian></ScenarioObject>"#.to_string(),
            20.0,
            2.0,
        ),
    ] {
        let text = on_straight_road(
            "performance",
            &object,
            &placed("A", -4, 20.0, 0.0),
            &story_of("A", speed),
            12.0,
        );
        let mut sb = storyboard_of("performance", &text).unwrap();
        let (mut v5, mut done) = (None, None);
        run(&mut sb, 12.0, |t, sb| {
            if (t - 5.0).abs() < DT / 2.0 {
                v5 = Some(sb.actors[0].state.speed);
            }
            if done.is_none() && sb.transitions().contains(&("action", "A", "end")) {
                done = Some(t);
            }
        });
        let v5 = v5.unwrap();
        assert!((v5 - at_5s).abs() < 0.05, "{v5} m/s at 5 s, not {at_5s}");
        let done = done.expect("the action ends");
        assert!(
            (done - reached).abs() < 2.0 * DT,
            "ended at {done} s, not {reached}"
        );
    }
}

/// An entity out of the scenario is left out of conditions, as esmini's conditions skip an
/// inactive one: `B`, which `Init` does not place, enters at 1 s (`AddEntityAction`) and
/// leaves at 3 s (`DeleteEntityAction`); A speeds up when any of A and B stands still
/// (`all`: B is left out, so A alone decides), and C stops when B travelled 0 m or more,
/// which holds only once B is in the scenario.
#[test]
fn conditions_leave_out_an_entity_out_of_the_scenario() {
    let init = format!(
        r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction></Private>
      <Private entityRef="C"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-2" s="20" offset="0"/></Position></TeleportAction></PrivateAction>{v}</Private>"#,
        v = step_to(5.0)
    );
    let global = |name: &str, inside: &str, t: f64| {
        format!(
            r#"<Event name="{name}" priority="parallel"><Action name="{name}"><GlobalAction><EntityAction entityRef="B">{inside}</EntityAction></GlobalAction></Action>
          <StartTrigger><ConditionGroup><Condition name="T{name}" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="{t}" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event>"#
        )
    };
    let when = |name: &str, who: &str, test: &str, action: String| {
        let (rule, refs) = if who == "B" {
            ("any", r#"<EntityRef entityRef="B"/>"#)
        } else {
            (
                "all",
                r#"<EntityRef entityRef="A"/><EntityRef entityRef="B"/>"#,
            )
        };
        format!(
            r#"<Event name="{name}" priority="parallel"><Action name="{name}">{action}</Action>
          <StartTrigger><ConditionGroup><Condition name="C{name}" delay="0" conditionEdge="none"><ByEntityCondition>
            <TriggeringEntities triggeringEntitiesRule="{rule}">{refs}</TriggeringEntities>
            <EntityCondition>{test}</EntityCondition></ByEntityCondition></Condition></ConditionGroup></StartTrigger></Event>"#
        )
    };
    let story = format!(
        r#"<Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="GA">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="A"/></Actors>
        <Maneuver name="MA">{enter}{leave}{a}</Maneuver>
      </ManeuverGroup>
      <ManeuverGroup maximumExecutionCount="1" name="GC">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="C"/></Actors>
        <Maneuver name="MC">{c}</Maneuver>
      </ManeuverGroup>
      <StartTrigger><ConditionGroup><Condition name="T" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition>
      </Condition></ConditionGroup></StartTrigger>
    </Act></Story>"#,
        enter = global(
            "Enter",
            r#"<AddEntityAction><Position><LanePosition roadId="0" laneId="-3" s="40" offset="0"/></Position></AddEntityAction>"#,
            1.0
        ),
        leave = global("Leave", "<DeleteEntityAction/>", 3.0),
        a = when(
            "AStill",
            "A and B",
            r#"<StandStillCondition duration="0.5"/>"#,
            step_to(7.0)
        ),
        c = when(
            "BThere",
            "B",
            r#"<TraveledDistanceCondition value="0"/>"#,
            step_to(0.0)
        ),
    );
    let entities = box_object("A") + &box_object("B") + &box_object("C");
    let text = on_straight_road("presence", &entities, &init, &story, 6.0);
    let mut sb = storyboard_of("presence", &text).expect("Init performs");
    assert_eq!(
        sb.actors.iter().map(|a| a.present).collect::<Vec<_>>(),
        [true, false, true],
        "Init places A and C"
    );
    let (mut a_faster, mut c_stopped, mut b_in) = (None, None, Vec::new());
    run(&mut sb, 6.0, |t, sb| {
        if sb.actors[1].present {
            b_in.push(t);
        }
        if a_faster.is_none() && sb.actors[0].state.speed > 6.0 {
            a_faster = Some(t);
        }
        if c_stopped.is_none() && sb.actors[2].state.speed < 1.0 {
            c_stopped = Some(t);
        }
    });
    let (first, last) = (b_in[0], *b_in.last().unwrap());
    assert!((first - 1.0).abs() <= 2.0 * DT, "B entered at {first} s");
    assert!((last - 3.0).abs() <= 2.0 * DT, "B left at {last} s");
    let p = sb.actors[1].state.pose;
    assert!(
        (p.x - 40.0).abs() < 1e-6,
        "B entered where its action put it: {p:?}"
    );
    let a = a_faster.expect("A stood 0.5 s and sped up");
    assert!(
        (a - 0.5).abs() <= 2.0 * DT,
        "A alone decided the `all` condition, at {a} s"
    );
    let c = c_stopped.expect("C stopped once B was in the scenario");
    assert!(
        (c - first).abs() <= 2.0 * DT,
        "C's condition on B held only from B's entry: {c} s, B entered at {first} s"
    );
}

/// A scripted entity asked a negative speed reverses along its lane, as esmini's `MoveAlongS`
/// by a negative distance moves it: `A`, standing at s = 100 m, is asked −3 m/s at 1 s and
/// backs 3 m/s × 2 s = 6 m down its lane by 3 s, facing the way it faced, with its speed
/// −3 m/s; `B` beside it, asked +3 m/s at the same time, moves 6 m the other way.
#[test]
fn a_scripted_entity_asked_a_negative_speed_reverses_along_its_lane() {
    let place = |name: &str, lane: i32| {
        format!(
            r#"<Private entityRef="{name}"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="{lane}" s="100" offset="0"/></Position></TeleportAction></PrivateAction></Private>"#
        )
    };
    let init = place("A", -2) + &place("B", -3);
    let at_one = |name: &str, v: f64| {
        format!(
            r#"<ManeuverGroup maximumExecutionCount="1" name="G{name}">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="{name}"/></Actors>
        <Maneuver name="M{name}"><Event name="E{name}" priority="parallel"><Action name="V{name}">{action}</Action>
          <StartTrigger><ConditionGroup><Condition name="T{name}" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>"#,
            action = step_to(v)
        )
    };
    let story = format!(
        r#"<Story name="S"><Act name="Act">{a}{b}
      <StartTrigger><ConditionGroup><Condition name="T" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition>
      </Condition></ConditionGroup></StartTrigger>
    </Act></Story>"#,
        a = at_one("A", -3.0),
        b = at_one("B", 3.0),
    );
    let entities = box_object("A") + &box_object("B");
    let text = on_straight_road("reverse", &entities, &init, &story, 3.0);
    let mut sb = storyboard_of("reverse", &text).expect("Init performs");
    let (h0, x0, xb0) = (
        sb.actors[0].state.pose.h,
        sb.actors[0].state.pose.x,
        sb.actors[1].state.pose.x,
    );
    let end = run(&mut sb, 3.0, |_, _| {});
    let (a, b) = (&sb.actors[0].state, &sb.actors[1].state);
    // The event starts in the step after 1 s, and each step moves at the new speed.
    let moving_s = end - 1.0;
    assert!((a.speed + 3.0).abs() < 1e-9, "A's speed {}", a.speed);
    assert!(
        (a.pose.x - (x0 - 3.0 * moving_s)).abs() < 3.0 * 2.0 * DT,
        "A backed from x {x0} to {} in {moving_s} s",
        a.pose.x
    );
    assert!(
        (b.pose.x - (xb0 + 3.0 * moving_s)).abs() < 3.0 * 2.0 * DT,
        "B drove from x {xb0} to {}",
        b.pose.x
    );
    assert!(
        (a.pose.h - h0).abs() < 1e-9,
        "A still faces {h0}: {}",
        a.pose.h
    );
}

/// A car named `name` with a hitch 1.2 m behind its reference point towing `trailer`
/// (the elements inside its `<Trailer>`).
fn tow_object(name: &str, trailer: &str) -> String {
    format!(
        r#"<ScenarioObject name="{name}"><Vehicle name="car" vehicleCategory="car">
        <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox>
        <Performance maxSpeed="60" maxAcceleration="10" maxDeceleration="10"/>
        <Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles>
        <TrailerHitch dx="-1.2"/><Trailer>{trailer}</Trailer>
        <Properties/></Vehicle></ScenarioObject>"#
    )
}

/// A trailer whose coupler is 3.25 m ahead of its reference point, as a `Vehicle`.
const BOX_TRAILER: &str = r#"<Vehicle name="trailer" vehicleCategory="trailer">
        <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="2" length="4.5" height="1.2"/></BoundingBox>
        <Performance maxSpeed="60" maxAcceleration="10" maxDeceleration="10"/>
        <Axles><FrontAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles>
        <TrailerCoupler dx="3.25"/><Properties/></Vehicle>"#;

/// A trailer is pulled by its tow's hitch, as esmini pulls it: it enters the scenario with
/// its tow, lined up straight behind it; at every step its coupler is at the hitch, it faces
/// the hitch and it has its tow's speed, so through a lane change it swings out less than its
/// tow and settles behind it in the new lane. A `DisconnectTrailerAction` leaves it at the
/// speed it had, and its tow drives away from it.
#[test]
fn a_trailer_follows_its_tows_hitch_until_it_is_unhitched() {
    let entities = tow_object(
        "Tow",
        &format!(r#"<Trailer name="t">{BOX_TRAILER}</Trailer>"#),
    );
    let init = placed("Tow", -2, 100.0, 10.0);
    let lane_change = r#"<PrivateAction><LateralAction><LaneChangeAction>
        <LaneChangeActionDynamics dynamicsShape="sinusoidal" value="3" dynamicsDimension="time"/>
        <LaneChangeTarget><RelativeTargetLane entityRef="Tow" value="-1"/></LaneChangeTarget>
      </LaneChangeAction></LateralAction></PrivateAction>"#;
    let unhitch = format!(
        r#"<Event name="Off" priority="parallel">
          <Action name="Unhitch"><PrivateAction><TrailerAction><DisconnectTrailerAction/></TrailerAction></PrivateAction></Action>
          <Action name="Faster">{}</Action>
          <StartTrigger><ConditionGroup><Condition name="At8" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="8" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event>"#,
        step_to(15.0)
    );
    let story = format!(
        r#"<Story name="S"><Act name="Act"><ManeuverGroup maximumExecutionCount="1" name="G">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="Tow"/></Actors>
          <Maneuver name="M"><Event name="E" priority="parallel"><Action name="A">{lane_change}</Action>
            <StartTrigger><ConditionGroup><Condition name="At1" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event>{unhitch}
          </Maneuver></ManeuverGroup></Act></Story>"#
    );
    let text = on_straight_road("trailer", &entities, &init, &story, 12.0);
    let mut sb = storyboard_of("trailer", &text).expect("Init performs");
    assert_eq!(sb.actors[1].name, "Tow+");
    // Lined up behind its tow at Init: the coupler 3.25 m ahead of the trailer's reference
    // point, at the hitch 1.2 m behind the tow's.
    let (tow, trailer) = (sb.actors[0].state.pose, sb.actors[1].state.pose);
    assert!(sb.actors[1].present);
    assert!((tow.x - 1.2 - 3.25 - trailer.x).abs() < 1e-9 && (tow.y - trailer.y).abs() < 1e-9);
    let hitch_gap = |sb: &Storyboard| {
        let (t, r) = (sb.actors[0].state.pose, sb.actors[1].state.pose);
        let hitch = [t.x - 1.2 * t.h.cos(), t.y - 1.2 * t.h.sin()];
        let coupler = [r.x + 3.25 * r.h.cos(), r.y + 3.25 * r.h.sin()];
        (hitch[0] - coupler[0]).hypot(hitch[1] - coupler[1])
    };
    let (mut tow_swing, mut trailer_swing) = (0.0_f64, 0.0_f64);
    let y0 = tow.y;
    let mut gap_after = 0.0;
    run(&mut sb, 12.0, |t, sb| {
        let (a, b) = (&sb.actors[0].state, &sb.actors[1].state);
        if t < 8.0 - 1e-9 {
            assert!(
                hitch_gap(sb) < 1e-9,
                "t = {t}: coupler {} m from the hitch",
                hitch_gap(sb)
            );
            assert_eq!(a.speed, b.speed, "t = {t}");
            tow_swing = tow_swing.max((a.pose.h).abs());
            trailer_swing = trailer_swing.max((b.pose.h).abs());
        } else {
            gap_after = hitch_gap(sb);
        }
    });
    let (a, b) = (&sb.actors[0].state, &sb.actors[1].state);
    assert!(tow_swing > 0.05, "the tow turned {tow_swing} rad");
    assert!(
        trailer_swing < tow_swing && trailer_swing > 0.01,
        "the trailer turned {trailer_swing} rad, its tow {tow_swing}"
    );
    // Settled in the new lane, a lane over, before it was unhitched; then left behind.
    assert!(
        (a.pose.y - y0).abs() > 1.5,
        "tow from y {y0} to {}",
        a.pose.y
    );
    assert!(
        (b.pose.y - a.pose.y).abs() < 0.05,
        "trailer at y {}, its tow at {}",
        b.pose.y,
        a.pose.y
    );
    assert!((b.speed - 10.0).abs() < 1e-9 && (a.speed - 15.0).abs() < 1e-9);
    assert!(gap_after > 15.0, "4 s at 5 m/s more: {gap_after} m");
}

/// CARLA's `vehicle_longitudinal_control` drives an entity's speed only, its steering left
/// straight: the storyboard moves it straight along its heading, not along its lane. Placed
/// 0.3 rad off its lane's direction, it leaves the lane's line (10 m/s for 5 s: 14.8 m
/// across), where an entity the storyboard moves along its lane keeps to the lane.
#[test]
fn carlas_longitudinal_only_controller_moves_its_entity_straight_along_its_heading() {
    let run_with = |module: &str| {
        let assign = format!(
            r#"<PrivateAction><ControllerAction><AssignControllerAction><Controller name="c"><Properties><Property name="module" value="{module}"/></Properties></Controller></AssignControllerAction></ControllerAction></PrivateAction>"#
        );
        let init = format!(
            r#"<Private entityRef="A"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="100" offset="0"><Orientation type="relative" h="0.3"/></LanePosition></Position></TeleportAction></PrivateAction>{assign}{speed}</Private>"#,
            speed = step_to(10.0)
        );
        let text = on_straight_road("CARLA:straight", &car_object("A", 10.0), &init, "", 5.0);
        let mut sb = storyboard_of(&format!("straight-{module}"), &text).expect("Init performs");
        let (y0, h0) = (sb.actors[0].state.pose.y, sb.actors[0].state.pose.h);
        run(&mut sb, 5.0, |_, _| {});
        let p = sb.actors[0].state.pose;
        (p.y - y0, p.h - h0)
    };
    let (dy, dh) = run_with("vehicle_longitudinal_control");
    // CARLA's frame: the file's relative heading 0.3 is read as -0.3 (left-handed).
    assert!(
        (dy.abs() - 5.0 * 10.0 * 0.3f64.sin()).abs() < 0.6,
        "straight: {dy} m across"
    );
    assert!(dh.abs() < 1e-9, "its heading stays: {dh}");
    let (dy, _) = run_with("npc_vehicle_control");
    assert!(dy.abs() < 0.5, "along its lane: {dy} m across");
}
