//! The ego of an OpenSCENARIO file is the file's vehicle (issue "An imported scenario tests
//! the ego it names"): its `BoundingBox` is its body, the storyboard's `SpeedAction`s on it
//! become its system's set speed, what paracosm cannot hand the system is refused at load,
//! a file that does not say which vehicle is the ego needs `--ego`, and a rising edge needs
//! the condition false first. Every scenario here is written for the test, on the ALKS
//! straight road (`tests/data/xosc/alks/`), with outcomes computed by hand.

use std::path::{Path, PathBuf};
use std::process::Command;

/// One step of the simulation, s.
const STEP_S: f64 = 1.0 / 60.0;

fn road() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_straight.xodr")
}

/// A vehicle `name` with a bounding box `[length, width, height]` whose centre is `cx` m ahead
/// of its reference point.
fn vehicle(name: &str, [l, w, h]: [f64; 3], cx: f64) -> String {
    format!(
        r#"<ScenarioObject name="{name}">
  <Vehicle name="{name}_v" vehicleCategory="car">
    <BoundingBox><Center x="{cx}" y="0" z="{hz}"/><Dimensions width="{w}" length="{l}" height="{h}"/></BoundingBox>
    <Axles>
      <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/>
      <RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/>
    </Axles>
    <Properties/>
  </Vehicle>
</ScenarioObject>"#,
        hz = h / 2.0
    )
}

/// A parked box `name`, `length` m long, centred at `s` m of lane −4.
fn parked_box(name: &str, length: f64) -> String {
    format!(
        r#"<ScenarioObject name="{name}">
  <MiscObject name="box" miscObjectCategory="obstacle" mass="500">
    <BoundingBox><Center x="0" y="0" z="0.75"/><Dimensions width="1.8" length="{length}" height="1.5"/></BoundingBox>
    <Properties/>
  </MiscObject>
</ScenarioObject>"#
    )
}

fn teleport(entity: &str, s: f64, speed: f64) -> String {
    format!(
        r#"<Private entityRef="{entity}">
      <PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="{s}" offset="0"/></Position></TeleportAction></PrivateAction>
      <PrivateAction><LongitudinalAction><SpeedAction>
        <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
        <SpeedActionTarget><AbsoluteTargetSpeed value="{speed}"/></SpeedActionTarget>
      </SpeedAction></LongitudinalAction></PrivateAction>
    </Private>"#
    )
}

/// A whole scenario: `entities`, `init`, then `story` (a `<Story>` or nothing) and a stop
/// trigger at `stop_s`.
fn scenario(entities: &str, init: &str, story: &str, stop: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-28T00:00:00" description="ego" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>
  <Entities>
{entities}
  </Entities>
  <Storyboard>
<Init><Actions>
{init}
</Actions></Init>
{story}
<StopTrigger><ConditionGroup>
{stop}
</ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
        road = road().display()
    )
}

/// [`scenario`] of two entities, each `(its ScenarioObject, its name, its s on lane −4 in m,
/// its Init speed in m/s)`.
fn two_entities(
    first: (String, &str, f64, f64),
    second: (String, &str, f64, f64),
    story: &str,
    stop: &str,
) -> String {
    scenario(
        &format!("{}\n{}", first.0, second.0),
        &format!(
            "{}\n{}",
            teleport(first.1, first.2, first.3),
            teleport(second.1, second.2, second.3)
        ),
        story,
        stop,
    )
}

fn at_time(name: &str, t: f64, edge: &str) -> String {
    format!(
        r#"<Condition name="{name}" delay="0" conditionEdge="{edge}">
  <ByValueCondition><SimulationTimeCondition value="{t}" rule="greaterThan"/></ByValueCondition>
</Condition>"#
    )
}

fn run(dir: &Path, file: &str, text: &str, args: &[&str]) -> (i32, String, Vec<serde_json::Value>) {
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    let out = dir.join(format!("{file}.out"));
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&path)
        .args(args)
        .args(if args.contains(&"--budget") {
            &[][..]
        } else {
            &["--budget", "1"][..]
        })
        .args(["--force", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let records = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (o.status.code().unwrap_or(-1), err, records)
}

/// A scripted ego at 10 m/s from s = 50 m into a box parked with its rear at s = 109 m: its
/// front starts `cx + length / 2` ahead of its reference point, so it touches the box after
/// `(109 − 50 − cx − length / 2) / 10` s. A 10 m truck (centre 4 m ahead) touches at 5.00 s,
/// a 5 × 2 m car (centre 1.4 m ahead) at 5.51 s; paracosm's own 4.5 m car would have
/// touched the box at 5.275 s and 5.535 s. The first step whose poses overlap is within one
/// step after the hand value, and the contact is reported one step later (rapier finds a
/// step's contacts before it moves the bodies: docs/openscenario.md).

#[test]
fn the_egos_body_is_its_bounding_box() {
    let dir = tempfile::tempdir().unwrap();
    for (name, size, cx) in [
        ("truck", [10.0, 2.5, 3.2], 4.0),
        ("car", [5.0, 2.0, 1.5], 1.4),
    ] {
        let text = two_entities(
            (vehicle("Ego", size, cx), "Ego", 50.0, 10.0),
            (parked_box("Box", 2.0), "Box", 110.0, 0.0),
            "",
            &at_time("End", 20.0, "rising"),
        );
        let (code, err, records) = run(
            dir.path(),
            &format!("{name}.xosc"),
            &text,
            &["--scripted-ego"],
        );
        assert_eq!(code, 1, "the ego hits the box: {err}");
        let r = &records[0];
        let hit = r["monitors"]["collision"]["first_violation_s"]
            .as_f64()
            .unwrap();
        let hand = (109.0 - 50.0 - cx - size[0] / 2.0) / 10.0;
        let overlap = (hand / STEP_S - 1e-6).ceil() * STEP_S;
        assert!(
            (hit - (overlap + STEP_S)).abs() < 1e-6,
            "{name}: touched at {hit} s, by hand {hand} s"
        );
    }
}

/// A bounding box outside the vehicle model's range is refused at load with its line and
/// column and the range; a 30 m ego is no car paracosm can drive.
#[test]
fn an_ego_outside_the_vehicle_models_range_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let text = scenario(
        &vehicle("Ego", [30.0, 2.5, 3.0], 4.0),
        &teleport("Ego", 50.0, 10.0),
        "",
        &at_time("End", 5.0, "rising"),
    );
    let (code, err, _) = run(dir.path(), "long.xosc", &text, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("long.xosc:8:") && err.contains("length 30 m") && err.contains("[2.5, 25]"),
        "{err}"
    );
}

/// The ego starts parked (as Euro NCAP's files and ASAM's SequentialEvents start it) and the
/// storyboard brings it to test speed: a `SpeedAction` to 20 m/s at 2 m/s² from t = 1 s, then,
/// when that event ends, one to 10 m/s at 2 m/s²; the stop trigger waits for the second to
/// end. Under `aeb` the ego follows them as its set speed: it comes within the action's
/// tolerance of 20 m/s (0.5 m/s + 5 %: 18.5 m/s; its proportional cruise control would
/// settle at 19.14 m/s), never much over it, and ends near 10 m/s. By hand the first
/// action's ramp ends at 11 s; the second ramps from the speed the ego has then (about
/// 18.5 m/s) at 2 m/s², about 4.3 s, so the test ends between 14.5 and 22 s (the cruise
/// controller lags a little behind each ramp). The ego the storyboard used to
/// leave parked never moves and fails the monitors below.
#[test]
fn the_storyboards_speed_actions_are_the_systems_set_speed() {
    let dir = tempfile::tempdir().unwrap();
    let speed = |event: &str, to: f64, start: &str| {
        format!(
            r#"<Event name="{event}" priority="override">
  <Action name="{event}Action"><PrivateAction><LongitudinalAction><SpeedAction>
    <SpeedActionDynamics dynamicsShape="linear" value="2" dynamicsDimension="rate"/>
    <SpeedActionTarget><AbsoluteTargetSpeed value="{to}"/></SpeedActionTarget>
  </SpeedAction></LongitudinalAction></PrivateAction></Action>
  <StartTrigger><ConditionGroup>{start}</ConditionGroup></StartTrigger>
</Event>"#
        )
    };
    let ended = |name: &str, event: &str| {
        format!(
            r#"<Condition name="{name}" delay="0" conditionEdge="rising">
  <ByValueCondition><StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="{event}" state="endTransition"/></ByValueCondition>
</Condition>"#
        )
    };
    let story = format!(
        r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
    <Maneuver name="M">
{}
{}
    </Maneuver>
  </ManeuverGroup>
</Act></Story>"#,
        speed("Accelerate", 20.0, &at_time("Go", 1.0, "rising")),
        speed("Slow", 10.0, &ended("Fast", "Accelerate"))
    );
    let text = scenario(
        &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
        &teleport("Ego", 50.0, 0.0),
        &story,
        &format!(
            "{}\n</ConditionGroup><ConditionGroup>{}",
            ended("Done", "Slow"),
            at_time("Cap", 60.0, "rising")
        ),
    );
    std::fs::write(dir.path().join("ncap.xosc"), &text).unwrap();
    let program = r#"w = World()
s = Import("ncap.xosc")
top = s.ego.speed.max()
Monitor(top.map(lambda v: v - 18.49), over = "end", name = "reaches_20")
Monitor(top.map(lambda v: 21.0 - v), over = "end", name = "not_over_21")
Monitor(s.ego.speed.map(lambda v: 1.5 - max(v - 10.0, 10.0 - v)), over = "end", name = "ends_near_10")
test(horizon = 100)
"#;
    let (code, err, records) = run(dir.path(), "prog.star", program, &[]);
    assert_eq!(code, 0, "{err}\n{records:?}");
    let r = &records[0];
    for m in ["reaches_20", "not_over_21", "ends_near_10", "offroad"] {
        assert_eq!(r["monitors"][m]["passed"], true, "{m}: {r}");
    }
    let end = r["metrics"]["simulated_s"].as_f64().unwrap();
    assert!(
        end > 14.5 && end < 22.0,
        "the second action's end stops the test: {end} s"
    );
}

/// A `SpeedProfileAction` on the ego a system under test drives is its set speed over time:
/// from parked at 1 s, 20 m/s 6 s later and 10 m/s 8 s after that (follow mode: corners
/// rounded within 2 m/s³: its last corner, from −1.25 m/s² to none, takes 0.625 s about
/// 15 s, so its last speed is planned for about 15.3 s). Under `aeb` the ego
/// comes near 20 m/s, not over 21, and ends near 10 m/s; the stop trigger waits for the
/// profile's end, which comes once the ego is within the set speed's tolerance of 10 m/s,
/// after 15 s and before 25 s. A profile to a negative speed on it is refused
/// when it starts, naming the action (its systems drive forward only).
#[test]
fn a_speed_profile_is_the_systems_set_speed_over_time() {
    let dir = tempfile::tempdir().unwrap();
    let story = |entries: &str| {
        format!(
            r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
    <Maneuver name="M"><Event name="Profile" priority="override">
  <Action name="ProfileAction"><PrivateAction><LongitudinalAction><SpeedProfileAction followingMode="follow">
    <DynamicConstraints maxAcceleration="4" maxDeceleration="4" maxAccelerationRate="2" maxDecelerationRate="2"/>
    {entries}
  </SpeedProfileAction></LongitudinalAction></PrivateAction></Action>
  <StartTrigger><ConditionGroup>{}</ConditionGroup></StartTrigger>
</Event></Maneuver>
  </ManeuverGroup>
</Act></Story>"#,
            at_time("Go", 1.0, "rising")
        )
    };
    let stop = format!(
        r#"<Condition name="Done" delay="0" conditionEdge="rising">
  <ByValueCondition><StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="Profile" state="endTransition"/></ByValueCondition>
</Condition></ConditionGroup><ConditionGroup>{}"#,
        at_time("Cap", 60.0, "rising")
    );
    let file = |entries: &str| {
        scenario(
            &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
            &teleport("Ego", 50.0, 0.0),
            &story(entries),
            &stop,
        )
    };
    std::fs::write(
        dir.path().join("profile.xosc"),
        file(r#"<SpeedProfileEntry time="6" speed="20"/><SpeedProfileEntry time="8" speed="10"/>"#),
    )
    .unwrap();
    let program = r#"w = World()
s = Import("profile.xosc")
top = s.ego.speed.max()
Monitor(top.map(lambda v: v - 17.0), over = "end", name = "near_20")
Monitor(top.map(lambda v: 21.0 - v), over = "end", name = "not_over_21")
Monitor(s.ego.speed.map(lambda v: 1.5 - max(v - 10.0, 10.0 - v)), over = "end", name = "ends_near_10")
test(horizon = 100)
"#;
    let (code, err, records) = run(dir.path(), "prog.star", program, &[]);
    assert_eq!(code, 0, "{err}\n{records:?}");
    let r = &records[0];
    for m in ["near_20", "not_over_21", "ends_near_10", "offroad"] {
        assert_eq!(r["monitors"][m]["passed"], true, "{m}: {r}");
    }
    let end = r["metrics"]["simulated_s"].as_f64().unwrap();
    assert!(
        end > 15.0 && end < 25.0,
        "the profile's end stops the test: {end} s"
    );
    std::fs::write(
        dir.path().join("profile.xosc"),
        file(r#"<SpeedProfileEntry time="6" speed="-2"/>"#),
    )
    .unwrap();
    let (code, err, records) = run(dir.path(), "prog.star", program, &[]);
    assert_ne!(code, 0, "{err}");
    // The test is in error, its record naming the action.
    assert_eq!(records.len(), 1, "{err}");
    let r = records[0].to_string();
    assert!(
        r.contains(r#"SpeedProfileAction \"ProfileAction\" to -2 m/s asks Ego to drive backwards"#),
        "{r}"
    );
}

/// What paracosm cannot hand the system under test (here a teleport of the driven ego) is
/// refused at load with the action's line and column, not dropped with a warning; the same
/// file runs with `--scripted-ego`.
#[test]
fn an_ego_action_the_system_cannot_take_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let story = format!(
        r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
    <Maneuver name="M">
<Event name="Change" priority="override">
  <Action name="ChangeAction"><PrivateAction><TeleportAction><Position><RelativeLanePosition entityRef="Ego" dLane="0" ds="5"/></Position></TeleportAction></PrivateAction></Action>
  <StartTrigger><ConditionGroup>{}</ConditionGroup></StartTrigger>
</Event>
    </Maneuver>
  </ManeuverGroup>
</Act></Story>"#,
        at_time("Go", 1.0, "rising")
    );
    let text = scenario(
        &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
        &teleport("Ego", 50.0, 10.0),
        &story,
        &at_time("End", 6.0, "rising"),
    );
    let (code, err, _) = run(dir.path(), "change.xosc", &text, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("change.xosc:")
            && err.contains("TeleportAction")
            && err.contains("--scripted-ego"),
        "{err}"
    );
    let (code, err, records) = run(dir.path(), "change.xosc", &text, &["--scripted-ego"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(records[0]["status"], "pass");
}

/// A file with two vehicles, neither named Ego or hero, and no controller activated: which
/// one is the ego is not plain, so the load asks for `--ego NAME`; with it the summary names
/// the ego and its box.
#[test]
fn a_file_without_a_plain_ego_needs_ego_name() {
    let dir = tempfile::tempdir().unwrap();
    let text = scenario(
        &format!(
            "{}\n{}",
            vehicle("Car1", [4.0, 1.8, 1.5], 1.3),
            vehicle("Car2", [5.0, 2.0, 1.5], 1.4)
        ),
        &format!(
            "{}\n{}",
            teleport("Car1", 50.0, 10.0),
            teleport("Car2", 120.0, 10.0)
        ),
        "",
        &at_time("End", 3.0, "rising"),
    );
    let (code, err, _) = run(dir.path(), "two.xosc", &text, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--ego NAME") && err.contains("Car1, Car2"),
        "{err}"
    );
    let (code, err, _) = run(dir.path(), "two.xosc", &text, &["--ego", "Nobody"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("\"Nobody\""), "{err}");
    let path = dir.path().join("two.xosc");
    let out = dir.path().join("named");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&path)
        .args(["--ego", "Car2", "--budget", "1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        stdout.contains("ego vehicle: Car2, 5 × 2 × 1.5 m"),
        "{stdout}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ego"], "Car2, 5 × 2 × 1.5 m");
}

/// A rising edge needs the condition false before it is true: a stop trigger whose condition
/// holds from the start (`SimulationTime > −1`, rising) never fires, and the test runs to the
/// second group's time (8 s); with `none` it ends at once.
#[test]
fn the_start_of_the_simulation_is_no_rising_edge() {
    let dir = tempfile::tempdir().unwrap();
    for (edge, lo, hi) in [("rising", 8.0, 8.1), ("none", 0.0, 0.1)] {
        let text = scenario(
            &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
            &teleport("Ego", 50.0, 10.0),
            "",
            &format!(
                "{}\n</ConditionGroup><ConditionGroup>{}",
                at_time("Always", -1.0, edge),
                at_time("Late", 8.0, "rising")
            ),
        );
        let (code, err, records) = run(dir.path(), "edge.xosc", &text, &["--scripted-ego"]);
        assert_eq!(code, 0, "{err}");
        let end = records[0]["metrics"]["simulated_s"].as_f64().unwrap();
        assert!(end >= lo && end <= hi, "{edge}: ended at {end} s");
    }
}

/// An `<Action>` holds one action (the schema's choice): a second `<PrivateAction>` in it is
/// refused at its line and column, not silently dropped.
#[test]
fn an_action_with_two_actions_is_refused_at_the_second() {
    let dir = tempfile::tempdir().unwrap();
    let two = r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Box"/></Actors>
    <Maneuver name="M">
<Event name="E" priority="override">
  <Action name="Two">
    <PrivateAction><LongitudinalAction><SpeedAction>
      <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
      <SpeedActionTarget><AbsoluteTargetSpeed value="3"/></SpeedActionTarget>
    </SpeedAction></LongitudinalAction></PrivateAction>
    <PrivateAction><LongitudinalAction><SpeedAction>
      <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
      <SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget>
    </SpeedAction></LongitudinalAction></PrivateAction>
  </Action>
</Event>
    </Maneuver>
  </ManeuverGroup>
</Act></Story>"#;
    let text = scenario(
        &format!(
            "{}\n{}",
            vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
            parked_box("Box", 2.0)
        ),
        &format!(
            "{}\n{}",
            teleport("Ego", 50.0, 10.0),
            teleport("Box", 200.0, 0.0)
        ),
        two,
        &at_time("End", 3.0, "rising"),
    );
    let (code, err, _) = run(dir.path(), "two_actions.xosc", &text, &[]);
    assert_eq!(code, 2, "{err}");
    let line = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains("<PrivateAction><LongitudinalAction><SpeedAction>"))
        .nth(3)
        .map(|(i, _)| i + 1)
        .unwrap();
    assert!(
        err.contains(&format!("two_actions.xosc:{line}:")) && err.contains("one action"),
        "line {line}: {err}"
    );
}

/// A storyboard without a stop trigger has nothing to end its tests: it is refused at load,
/// asking for `--horizon`, rather than run to a cap; with `--horizon 5` each test ends at
/// 5 s.
#[test]
fn a_storyboard_without_a_stop_trigger_needs_a_horizon() {
    let dir = tempfile::tempdir().unwrap();
    let text = scenario(
        &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
        &teleport("Ego", 50.0, 10.0),
        "",
        "",
    )
    .replace(
        "<StopTrigger><ConditionGroup>\n\n</ConditionGroup></StopTrigger>",
        "",
    );
    assert!(!text.contains("StopTrigger"), "{text}");
    let (code, err, _) = run(dir.path(), "endless.xosc", &text, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("no stop trigger") && err.contains("--horizon"),
        "{err}"
    );
    let (code, err, records) = run(dir.path(), "endless.xosc", &text, &["--horizon", "5"]);
    assert_eq!(code, 0, "{err}");
    let end = records[0]["metrics"]["simulated_s"].as_f64().unwrap();
    assert!((end - 5.0).abs() < 0.02, "ended at {end} s");
}

/// `--trace` writes each test's trace laid out as esmini's CSV log: every entity's speed,
/// position and heading. At t = 0 the scripted box has its `Init` speed (5 m/s), a teleport
/// of it at 2 s keeps its speed (no jump over one step), and the ego's box centre moves 10 m
/// a second from 50 + 4 m (its reference point plus the box centre's offset).
#[test]
fn a_trace_records_every_entity_as_esminis_log_does() {
    let dir = tempfile::tempdir().unwrap();
    let story = format!(
        r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Box"/></Actors>
    <Maneuver name="M">
<Event name="Jump" priority="override">
  <Action name="JumpAction"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="400" offset="0"/></Position></TeleportAction></PrivateAction></Action>
  <StartTrigger><ConditionGroup>{}</ConditionGroup></StartTrigger>
</Event>
    </Maneuver>
  </ManeuverGroup>
</Act></Story>"#,
        at_time("Go", 2.0, "rising")
    );
    let text = scenario(
        &format!(
            "{}\n{}",
            vehicle("Ego", [10.0, 2.5, 3.2], 4.0),
            parked_box("Box", 2.0)
        ),
        &format!(
            "{}\n{}",
            teleport("Ego", 50.0, 10.0),
            teleport("Box", 200.0, 5.0)
        ),
        &story,
        &at_time("End", 4.0, "rising"),
    );
    let (code, err, records) = run(
        dir.path(),
        "traced.xosc",
        &text,
        &["--scripted-ego", "--trace-every", "0.01"],
    );
    assert_eq!(code, 0, "{err}");
    let log = records[0]["log"].to_string();
    assert!(
        log.contains("event \\\"Jump\\\" start"),
        "the timeline: {log}"
    );
    let csv = std::fs::read_to_string(dir.path().join("traced.xosc.out/trace/test_0.csv")).unwrap();
    let mut lines = csv.lines();
    assert!(lines.next().unwrap().starts_with("paracosm VERSION"));
    lines.next();
    assert!(lines.next().unwrap().starts_with("Number of Vehicles: 2"));
    let header = lines.next().unwrap();
    assert!(
        header.starts_with("Index [-], TimeStamp [s], #1 Entity_Name [-], #1 Entity_ID [-], #1 Current_Speed [m/s]"),
        "{header}"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(|c| c.trim().to_owned()).collect())
        .collect();
    // Every step of the 4 s test (and the start).
    assert!(rows.len() >= 240, "{} rows", rows.len());
    let num = |r: &[String], k: usize| r[k].parse::<f64>().unwrap();
    // Entity k's column c is at 2 + 31 k + c.
    let (ego, boxed) = (2, 2 + 31);
    assert_eq!(rows[0][ego], "Ego");
    assert_eq!(rows[0][boxed], "Box");
    assert!(
        (num(&rows[0], ego + 2) - 10.0).abs() < 1e-9,
        "{:?}",
        rows[0]
    );
    for r in &rows {
        let t = num(r, 1);
        let v = num(r, boxed + 2);
        assert!((v - 5.0).abs() < 1e-6, "the box's speed at {t} s: {v} m/s");
        let x = num(r, ego + 11);
        assert!(
            (x - (54.0 + 10.0 * t)).abs() < 0.02,
            "the ego's x at {t} s: {x} m"
        );
    }
    let box_x_late = num(rows.last().unwrap(), boxed + 11);
    assert!(
        box_x_late > 400.0,
        "the teleport moved the box: {box_x_late}"
    );
}

/// Lane and road references that do not depend on where an entity is are checked when the
/// file loads: a lane change to a lane no road has, and a teleport to a road the map lacks,
/// are refused at the action's line and column, naming the action (and `xosc FILE`, which
/// loads the map too, refuses a map that does not load).
#[test]
fn lane_and_road_references_are_checked_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let event = |action: &str| {
        format!(
            r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="Box"/></Actors>
    <Maneuver name="M">
<Event name="E" priority="override">
  <Action name="Bad"><PrivateAction>{action}</PrivateAction></Action>
  <StartTrigger><ConditionGroup>{}</ConditionGroup></StartTrigger>
</Event>
    </Maneuver>
  </ManeuverGroup>
</Act></Story>"#,
            at_time("Go", 1.0, "rising")
        )
    };
    for (file, action, want) in [
        (
            "lane.xosc",
            r#"<LateralAction><LaneChangeAction>
    <LaneChangeActionDynamics dynamicsShape="sinusoidal" value="3" dynamicsDimension="time"/>
    <LaneChangeTarget><AbsoluteTargetLane value="-9"/></LaneChangeTarget>
  </LaneChangeAction></LateralAction>"#,
            "lane -9",
        ),
        (
            "road.xosc",
            r#"<TeleportAction><Position><LanePosition roadId="77" laneId="-4" s="10" offset="0"/></Position></TeleportAction>"#,
            "77",
        ),
    ] {
        let text = scenario(
            &format!(
                "{}\n{}",
                vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
                parked_box("Box", 2.0)
            ),
            &format!(
                "{}\n{}",
                teleport("Ego", 50.0, 10.0),
                teleport("Box", 200.0, 5.0)
            ),
            &event(action),
            &at_time("End", 3.0, "rising"),
        );
        let line = text
            .lines()
            .position(|l| l.contains("<Action name=\"Bad\">"))
            .unwrap()
            + 1;
        let (code, err, _) = run(dir.path(), file, &text, &[]);
        assert_eq!(code, 2, "{file}: {err}");
        assert!(
            err.contains(&format!("{file}:{line}:"))
                && err.contains("\"Bad\"")
                && err.contains(want),
            "{file}: line {line}: {err}"
        );
        assert!(!err.contains("stream "), "{err}");
    }
}

/// In a program: an open parameter written inline in `Import(params = {...})` is named by the
/// file's parameter it opens (it was `param0`), and an imported entity bound to a variable
/// (`ped = s.TargetBlocking`) publishes its outputs under that name (`ped.speed`), as any
/// actor assigned to a variable does (it was refused: "nothing publishes").
#[test]
fn an_imported_entity_and_an_inline_parameter_take_the_programs_names() {
    let dir = tempfile::tempdir().unwrap();
    let template = Path::new(env!("CARGO_MANIFEST_DIR")).join(
        "tests/data/xosc/alks/concrete_scenarios/alks_scenario_4_2_3_crossing_pedestrian_template.xosc",
    );
    let program = format!(
        r#"w = World()
s = Import("{}", params = {{"TargetBlocking_Speed_kph": VarInterval(6, 12)}})
ped = s.TargetBlocking
Stl("G[0,60] (ped.speed < 4)", name = "ped_walks")
test(horizon = 60)
"#,
        template.display()
    );
    let (code, err, records) = run(dir.path(), "prog.star", &program, &["--budget", "2"]);
    assert!(matches!(code, 0 | 1), "{err}");
    assert_eq!(records.len(), 2, "{err}");
    for r in &records {
        let kph = r["params"]["TargetBlocking_Speed_kph"].as_f64().unwrap();
        assert!((6.0..12.0).contains(&kph), "{r}");
        assert_eq!(r["monitors"]["ped_walks"]["passed"], true, "{r}");
    }
}

/// A story whose one maneuver, on `actor`, holds `events`.
fn story_of(actor: &str, events: &[String]) -> String {
    format!(
        r#"<Story name="S"><Act name="A">
  <ManeuverGroup maximumExecutionCount="1" name="G">
    <Actors selectTriggeringEntities="false"><EntityRef entityRef="{actor}"/></Actors>
    <Maneuver name="M">
{}
    </Maneuver>
  </ManeuverGroup>
</Act></Story>"#,
        events.join("\n")
    )
}

/// An event `name` of one private action `action` (the XML inside `<PrivateAction>`),
/// started by the conditions `start`.
fn event(name: &str, action: &str, start: &str) -> String {
    format!(
        r#"<Event name="{name}" priority="override">
  <Action name="{name}Action"><PrivateAction>{action}</PrivateAction></Action>
  <StartTrigger><ConditionGroup>{start}</ConditionGroup></StartTrigger>
</Event>"#
    )
}

fn activate(lateral: bool, longitudinal: bool) -> String {
    format!(r#"<ActivateControllerAction lateral="{lateral}" longitudinal="{longitudinal}"/>"#)
}

fn speed_step(to: f64) -> String {
    format!(
        r#"<LongitudinalAction><SpeedAction>
    <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
    <SpeedActionTarget><AbsoluteTargetSpeed value="{to}"/></SpeedActionTarget>
  </SpeedAction></LongitudinalAction>"#
    )
}

/// The rows of trace `file` as (time s, the first entity's speed m/s, its centre's x and y
/// m, OpenDRIVE frame).
fn trace_rows(file: &Path) -> Vec<(f64, f64, f64, f64)> {
    trace_rows_of(file, 0)
}

/// [`trace_rows`] of the trace's entity `k` (its columns start at 2 + 31 k).
fn trace_rows_of(file: &Path, k: usize) -> Vec<(f64, f64, f64, f64)> {
    let o = 31 * k;
    let csv = std::fs::read_to_string(file).unwrap();
    csv.lines()
        .skip(4)
        .map(|l| {
            let c: Vec<f64> = l
                .split(',')
                .map(|c| c.trim().parse::<f64>().unwrap_or(f64::NAN))
                .collect();
            (c[1], c[o + 4], c[o + 13], c[o + 14])
        })
        .collect()
}

/// Where the storyboard activates the ego's controller, it moves the ego until then (its
/// SpeedAction to 15 m/s is the ego's speed at once, as esmini's default controller performs
/// it) and the system under test drives it after: by hand the ego's centre is at
/// 50 + 1.4 + 10 · 0.5 + 15 · 1.5 = 78.9 m at the hand-over (2 s), at exactly 15 m/s, and `aeb`
/// then cruises on near its set speed of 15 m/s (its proportional cruise settles a little
/// under it). Driven from the start, `aeb` would have reached about 11 m/s by 1 s.
#[test]
fn the_storyboard_drives_the_ego_until_it_activates_its_controller() {
    let dir = tempfile::tempdir().unwrap();
    let story = story_of(
        "Ego",
        &[
            event("Faster", &speed_step(15.0), &at_time("Go", 0.5, "rising")),
            event(
                "Activate",
                &format!(
                    "<ControllerAction>{}</ControllerAction>",
                    activate(true, true)
                ),
                &at_time("Hand", 2.0, "rising"),
            ),
        ],
    );
    let text = scenario(
        &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
        &teleport("Ego", 50.0, 10.0),
        &story,
        &at_time("End", 8.0, "rising"),
    );
    let (code, err, records) = run(
        dir.path(),
        "handover.xosc",
        &text,
        &["--trace-every", "0.1"],
    );
    assert_eq!(code, 0, "{err}\n{records:?}");
    let r = &records[0];
    assert_eq!(r["status"], "pass", "{r}");
    let log = r["log"].to_string();
    assert!(
        log.contains("the system under test takes over the ego Ego at 15.00 m/s"),
        "{log}"
    );
    let rows = trace_rows(&dir.path().join("handover.xosc.out/trace/test_0.csv"));
    let at = |t: f64| {
        *rows
            .iter()
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .unwrap()
    };
    let (_, v1, _, _) = at(1.0);
    assert!(
        (v1 - 15.0).abs() < 0.01,
        "scripted until 2 s: {v1} m/s at 1 s"
    );
    let (t2, _, x2, _) = at(2.0);
    let hand = 50.0 + 1.4 + 10.0 * 0.5 + 15.0 * 1.5;
    assert!(
        (x2 - hand).abs() < 0.3,
        "at {t2} s the ego's centre is at {x2} m, by hand {hand} m"
    );
    let (_, v8, x8, _) = *rows.last().unwrap();
    eprintln!("speed at 1 s {v1:.3} m/s; centre at {t2:.2} s {x2:.2} m (hand {hand:.2}); at the end {v8:.2} m/s, {x8:.1} m");
    assert!(
        (13.5..=15.5).contains(&v8),
        "aeb cruises near its set speed 15: {v8} m/s"
    );
    assert!(
        x8 > x2 + 5.5 * 13.5,
        "driven on after the hand-over: {x8} m"
    );
}

/// A deactivation of the driven ego's controller is refused at load; a storyboard that ends
/// before its activation is an error (the system under test never drove).
#[test]
fn an_ego_never_handed_over_is_an_error_and_a_deactivation_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let file = |lateral: bool, longitudinal: bool, at: f64| {
        scenario(
            &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
            &teleport("Ego", 50.0, 10.0),
            &story_of(
                "Ego",
                &[event(
                    "Activate",
                    &format!(
                        "<ControllerAction>{}</ControllerAction>",
                        activate(lateral, longitudinal)
                    ),
                    &at_time("Hand", at, "rising"),
                )],
            ),
            &at_time("End", 3.0, "rising"),
        )
    };
    let (code, err, _) = run(dir.path(), "off.xosc", &file(false, false, 1.0), &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("off.xosc:") && err.contains("deactivates"),
        "{err}"
    );
    let (code, err, records) = run(dir.path(), "late.xosc", &file(true, true, 5.0), &[]);
    assert_eq!(code, 3, "{err}");
    assert_eq!(records[0]["status"], "error", "{:?}", records[0]);
    assert!(
        records[0]["error"]
            .to_string()
            .contains("before its ActivateControllerAction handed the ego Ego"),
        "{:?}",
        records[0]
    );
    // Longitudinal only: the whole ego is handed over, and the load says so.
    let (code, err, _) = run(dir.path(), "half.xosc", &file(false, true, 1.0), &[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("activates only the longitudinal control of Ego"),
        "{err}"
    );
}

/// `aeb` stops the ego behind a parked box (rear at s = 149 m) while the stop trigger waits
/// for the ego to travel 250 m, past the box: nothing can move again, so after 10 s of
/// stillness (`STUCK_S`) the test ends as an error naming the condition, not at the 3,600 s
/// cap and not as a pass.
#[test]
fn a_storyboard_that_waits_on_what_cannot_happen_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = two_entities(
        (vehicle("Ego", [5.0, 2.0, 1.5], 1.4), "Ego", 50.0, 10.0),
        (parked_box("Box", 2.0), "Box", 150.0, 0.0),
        "",
        r#"<Condition name="PastTheBox" delay="0" conditionEdge="none">
  <ByEntityCondition><TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Ego"/></TriggeringEntities>
  <EntityCondition><TraveledDistanceCondition value="250"/></EntityCondition></ByEntityCondition>
</Condition>"#,
    );
    let (code, err, records) = run(dir.path(), "stuck.xosc", &text, &[]);
    assert_eq!(code, 3, "{err}");
    let r = &records[0];
    assert_eq!(r["status"], "error", "{r}");
    let why = r["error"].as_str().unwrap();
    assert!(
        why.contains("waits on \"PastTheBox\" (")
            && why.contains("stuck.xosc:42:1)")
            && why.contains("can no longer"),
        "{why}"
    );
    // "at t = 25.317 s, the storyboard of ...": stopped by the 10 s of stillness, not the cap.
    let end: f64 = why
        .strip_prefix("at t = ")
        .and_then(|w| w.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or(f64::NAN);
    eprintln!("stuck: {why}");
    assert!(end < 40.0, "ended {end} s in, not at the cap: {why}");
}

/// A lane change of the driven ego is the system's new route: `aeb`, on lane −4 at 10 m/s,
/// follows a route into lane −3 (3.5 m to its left) that joins it 3 s × 10 m/s = 30 m ahead;
/// the action ends once the ego is within 0.3 m of the lane's centre (`LANE_REACHED_M`), and
/// its end stops the test; the ego then drives on in the new lane, 3.5 m left of where it
/// started.
#[test]
fn a_lane_change_of_the_driven_ego_is_its_systems_route() {
    let dir = tempfile::tempdir().unwrap();
    let change = r#"<LateralAction><LaneChangeAction>
    <LaneChangeActionDynamics dynamicsShape="sinusoidal" value="3" dynamicsDimension="time"/>
    <LaneChangeTarget><RelativeTargetLane entityRef="Ego" value="1"/></LaneChangeTarget>
  </LaneChangeAction></LateralAction>"#;
    let story = story_of(
        "Ego",
        &[event("Change", change, &at_time("Go", 1.0, "rising"))],
    );
    let ended = r#"<Condition name="Changed" delay="0" conditionEdge="rising">
  <ByValueCondition><StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="Change" state="endTransition"/></ByValueCondition>
</Condition>
</ConditionGroup><ConditionGroup>"#
        .to_owned()
        + &at_time("Cap", 30.0, "rising");
    let text = scenario(
        &vehicle("Ego", [5.0, 2.0, 1.5], 1.4),
        &teleport("Ego", 50.0, 10.0),
        &story,
        &ended,
    );
    let (code, err, records) = run(dir.path(), "lane.xosc", &text, &["--trace-every", "0.1"]);
    assert_eq!(code, 0, "{err}\n{records:?}");
    let r = &records[0];
    assert_eq!(r["status"], "pass", "{r}");
    let log = r["log"].to_string();
    assert!(log.contains("is given a new route"), "{log}");
    let end = r["metrics"]["simulated_s"].as_f64().unwrap();
    assert!(
        end > 2.5 && end < 10.0,
        "the lane change's end stops the test: {end} s"
    );
    let rows = trace_rows(&dir.path().join("lane.xosc.out/trace/test_0.csv"));
    let (y0, y1) = (rows[0].3, rows.last().unwrap().3);
    eprintln!("lane change: y {y0:.3} -> {y1:.3} m, ended at {end:.2} s");
    assert!(
        ((y1 - y0) - 3.5).abs() < 0.35,
        "one lane (3.5 m) to the left: from y = {y0} to {y1} m"
    );
}

/// A pedestrian enters the test at its `Init` speed and heading: the trace's first row (t = 0)
/// has the walker's 1.5 m/s (before: 0 until its first step), and its x grows by 1.5 m/s.
#[test]
fn a_pedestrians_init_speed_is_its_speed_at_t_0() {
    let dir = tempfile::tempdir().unwrap();
    let walker = r#"<ScenarioObject name="Walker">
  <Pedestrian model3d="Adult" mass="70" name="walker" pedestrianCategory="pedestrian">
    <BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.5" height="1.8"/></BoundingBox>
    <Properties/>
  </Pedestrian>
</ScenarioObject>"#;
    let text = two_entities(
        (walker.to_owned(), "Walker", 100.0, 1.5),
        (vehicle("Ego", [5.0, 2.0, 1.5], 1.4), "Ego", 50.0, 10.0),
        "",
        &at_time("End", 1.0, "rising"),
    );
    let (code, err, _) = run(
        dir.path(),
        "walker.xosc",
        &text,
        &["--scripted-ego", "--trace-every", "0.1"],
    );
    assert_eq!(code, 0, "{err}");
    // The ego comes first in the trace, the walker second.
    let rows = trace_rows_of(&dir.path().join("walker.xosc.out/trace/test_0.csv"), 1);
    let (t0, v0, x0, _) = rows[0];
    let (t1, v1, x1, _) = *rows.last().unwrap();
    eprintln!("walker: {v0} m/s at {t0} s, {v1} m/s at {t1} s, x {x0} -> {x1} m");
    assert!(
        t0 == 0.0 && (v0 - 1.5).abs() < 1e-9,
        "at t = {t0} s: {v0} m/s"
    );
    assert!((v1 - 1.5).abs() < 1e-6, "at t = {t1} s: {v1} m/s");
    assert!(
        ((x1 - x0) - 1.5 * (t1 - t0)).abs() < 0.02,
        "x {x0} -> {x1} m over {t0}..{t1} s"
    );
}
