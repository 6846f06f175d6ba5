//! `paracosm-fuzz xosc`: an OpenSCENARIO logical scenario read and listed, on the ALKS suite
//! (written by BMW, `tests/data/xosc/alks/`) and on a scenario in the older forms the
//! standard allows (OpenSCENARIO 1.0), written here.

use std::process::Command;

fn xosc(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg("xosc")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

const CROSSING: &str =
    "tests/data/xosc/alks/alks_scenario_4_2_3_crossing_pedestrian_variation.xosc";

#[test]
fn the_crossing_pedestrian_becomes_a_space_with_the_files_grid_and_opened_parameters() {
    let (code, out, err) = xosc(&[
        CROSSING,
        "--open",
        "TargetBlocking_InitPosition_LateralOffset_m=-8..-2",
        "--open",
        "TargetBlocking_Speed_kph=2,5,10",
    ]);
    assert_eq!(code, 0, "{err}");
    for want in [
        "Ego_InitSpeed_Ve0_kph = 60   -> 12 levels {5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60}",
        "Ego_InitPosition_LaneId = -4   -> 2 levels {4, -4}",
        "Road = ./road_networks/alks_road_straight.xodr   -> 5 levels",
        "TargetBlocking_InitPosition_LateralOffset_m = -5   -> interval [-8, -2]",
        "TargetBlocking_Speed_kph = 5   -> 3 levels {2, 5, 10}",
        "the file's own grid: 120 runs",
        "TargetBlocking: pedestrian (pedestrian), 0.3 x 0.5 x 1.8 m",
        "event CrossEvent (TargetBlocking) starts when Ego: headway to TargetBlocking Lt 3.6 s",
        "stops when time Ge 40 s",
    ] {
        assert!(out.contains(want), "`{want}` not in\n{out}");
    }
    // --continuous turns the speed's range into an interval; the grid is still the file's.
    let (code, out, _) = xosc(&[CROSSING, "--continuous"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("Ego_InitSpeed_Ve0_kph = 60   -> interval [5, 60]"),
        "{out}"
    );
    assert!(out.contains("the file's own grid: 120 runs"), "{out}");
}

#[test]
fn an_open_outside_the_constraint_groups_or_of_an_undeclared_parameter_is_refused() {
    let (code, _, err) = xosc(&[CROSSING, "--open", "TargetBlocking_Speed_kph=0..40"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--open TargetBlocking_Speed_kph=0..40"),
        "{err}"
    );
    assert!(err.contains("meets none of its constraint groups"), "{err}");
    let (code, _, err) = xosc(&[CROSSING, "--open", "Ego_InitSpeed_Ve0_kph=5..60"]);
    assert_eq!(code, 2);
    assert!(err.contains("varied already"), "{err}");
    let (code, _, err) = xosc(&[CROSSING, "--open", "Nope=1..2"]);
    assert_eq!(code, 2);
    assert!(err.contains("is not declared"), "{err}");
    // A whole-number parameter opened as an interval, or given a fractional level, is refused
    // at load (exit 2, naming its declaration), not handed 0.5 in every test.
    let side = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(
        "tests/data/xosc/alks/concrete_scenarios/alks_scenario_4_1_3_side_vehicle_template.xosc",
    );
    let side = side.to_str().unwrap();
    for (open, says) in [
        (
            "SideVehicle_InitPosition_RelativeLaneId=-1..1",
            "is declared int",
        ),
        (
            "SideVehicle_InitPosition_RelativeLaneId=-1,0.5",
            "0.5 is not an int",
        ),
    ] {
        let (code, _, err) = xosc(&[side, "--open", open]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.starts_with("paracosm-fuzz: error: --open") && err.contains(says),
            "{err}"
        );
    }
    let (code, _, err) = xosc(&[
        side,
        "--open",
        "SideVehicle_InitPosition_RelativeLaneId=-1,1",
    ]);
    assert_eq!(code, 0, "{err}");
}

/// OpenSCENARIO 1.0's forms: an inline vehicle and pedestrian, `ActivateControllerAction`
/// directly under `PrivateAction`, parameters a story declares, an act without a start
/// trigger, a world position, a relative target speed, `overwrite` priority and a qualified
/// element name in a state condition.
#[test]
fn a_scenario_in_the_older_forms_reads() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("old.xosc");
    std::fs::write(
        &file,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2020-03-20T12:00:00" description="old" author="paracosm"/>
  <ParameterDeclarations>
    <ParameterDeclaration name="EgoSpeed" parameterType="double" value="20"/>
  </ParameterDeclarations>
  <RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork>
  <Entities>
    <ScenarioObject name="Hero">
      <Vehicle name="v" vehicleCategory="car">
        <ParameterDeclarations/>
        <Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/>
        <BoundingBox><Center x="1.3" y="0" z="0.8"/><Dimensions width="1.8" length="4.5" height="1.5"/></BoundingBox>
        <Axles>
          <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/>
          <RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/>
        </Axles>
        <Properties/>
      </Vehicle>
    </ScenarioObject>
    <ScenarioObject name="Walker">
      <Pedestrian name="p" model="m" mass="80" pedestrianCategory="pedestrian">
        <BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.6" length="0.6" height="1.8"/></BoundingBox>
        <Properties/>
      </Pedestrian>
    </ScenarioObject>
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
        <Private entityRef="Hero">
          <PrivateAction><TeleportAction><Position><WorldPosition x="10" y="-1.5" h="0"/></Position></TeleportAction></PrivateAction>
          <PrivateAction><ActivateControllerAction longitudinal="true" lateral="true"/></PrivateAction>
        </Private>
        <Private entityRef="Walker">
          <PrivateAction><TeleportAction><Position><RelativeObjectPosition entityRef="Hero" dx="60" dy="-4"/></Position></TeleportAction></PrivateAction>
        </Private>
      </Actions>
    </Init>
    <Story name="S">
      <ParameterDeclarations>
        <ParameterDeclaration name="Gap" parameterType="double" value="${$EgoSpeed * 2}"/>
      </ParameterDeclarations>
      <Act name="A">
        <ManeuverGroup maximumExecutionCount="1" name="G">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="Walker"/></Actors>
          <Maneuver name="M">
            <Event name="Go" priority="overwrite">
              <Action name="Walk">
                <PrivateAction>
                  <LongitudinalAction>
                    <SpeedAction>
                      <SpeedActionDynamics dynamicsShape="linear" value="1" dynamicsDimension="time"/>
                      <SpeedActionTarget><RelativeTargetSpeed entityRef="Hero" value="0.1" speedTargetValueType="factor" continuous="false"/></SpeedActionTarget>
                    </SpeedAction>
                  </LongitudinalAction>
                </PrivateAction>
              </Action>
              <StartTrigger>
                <ConditionGroup>
                  <Condition name="Near" delay="0" conditionEdge="rising">
                    <ByEntityCondition>
                      <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Hero"/></TriggeringEntities>
                      <EntityCondition><RelativeDistanceCondition entityRef="Walker" relativeDistanceType="cartesianDistance" value="$Gap" freespace="false" rule="lessThan"/></EntityCondition>
                    </ByEntityCondition>
                  </Condition>
                </ConditionGroup>
              </StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>
      </Act>
    </Story>
    <StopTrigger>
      <ConditionGroup>
        <Condition name="End" delay="2" conditionEdge="rising">
          <ByValueCondition><StoryboardElementStateCondition storyboardElementType="action" storyboardElementRef="Go::Walk" state="endTransition"/></ByValueCondition>
        </Condition>
      </ConditionGroup>
    </StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
    )
    .unwrap();
    // `xosc` loads the map as a campaign would: without it the file is refused, naming its
    // LogicFile.
    let (code, _, err) = xosc(&[file.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("road.xodr") && err.contains("old.xosc:7:"),
        "{err}"
    );
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_straight.xodr"),
        dir.path().join("road.xodr"),
    )
    .unwrap();
    let (code, out, err) = xosc(&[file.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for want in [
        "(OpenSCENARIO 1.0)",
        "Hero: vehicle (car), 4.5 x 1.8 x 1.5 m",
        "Walker: pedestrian (pedestrian), 0.6 x 0.6 x 1.8 m",
        "Hero: at world (10, -1.5) heading 0 rad",
        "Hero: the system under test takes over",
        "Walker: at 60 m ahead, -4 m left of Hero",
        "act A starts at once",
        "euclidianDistance distance to Walker Lt 40 m",
        "speed to 0.1 x Hero's speed (Linear by Time 1)",
        "stops when action Go::Walk endTransition (then 2 s later)",
    ] {
        assert!(out.contains(want), "`{want}` not in\n{out}");
    }
    // Its vehicle's `Performance` is applied to the storyboard's speed changes, not noted.
    assert!(!out.contains("<Performance>"), "{out}");
}

/// The listing reads an empty `<StartTrigger/>` as none (the act starts at once), and names
/// a `CollisionCondition` between two scripted entities, which the storyboard finds by their
/// boxes (`tests/data/xosc/written/contacts_and_road_edges.xosc`).
#[test]
fn an_empty_start_trigger_is_listed_as_starting_at_once() {
    let (code, out, err) = xosc(&["tests/data/xosc/written/contacts_and_road_edges.xosc"]);
    assert_eq!(code, 0, "{err}");
    for want in [
        "act a starts at once",
        "event hit (chaser) starts when chaser: touches lead",
        "stops when time Ge 14 s",
    ] {
        assert!(out.contains(want), "`{want}` not in\n{out}");
    }
    assert!(!out.contains("starts when \n"), "{out}");
}

/// A variation file in `dir` over ALKS 4.2.3 (the crossing pedestrian) whose `Deterministic`
/// element holds `distributions`.
fn crossing_variation(dir: &std::path::Path, distributions: &str) -> std::path::PathBuf {
    let alks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks");
    let template =
        alks.join("concrete_scenarios/alks_scenario_4_2_3_crossing_pedestrian_template.xosc");
    variation_over(dir, &template, distributions)
}

/// A variation file `sets.xosc` in `dir` over the scenario file `template` whose
/// `Deterministic` element holds `distributions` (they start on line 6).
fn variation_over(
    dir: &std::path::Path,
    template: &std::path::Path,
    distributions: &str,
) -> std::path::PathBuf {
    let variation = dir.join("sets.xosc");
    std::fs::write(
        &variation,
        format!(
            r#"<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-26T00:00:00" description="sets" author="paracosm"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="{}"/>
    <Deterministic>
{distributions}
    </Deterministic>
  </ParameterValueDistribution>
</OpenSCENARIO>
"#,
            template.display()
        ),
    )
    .unwrap();
    variation
}

/// A variation file with a `ValueSetDistribution` (parameters assigned together) beside a
/// single-parameter one: the sets become one discrete parameter and the grid multiplies.
#[test]
fn value_sets_become_one_parameter_of_their_sets() {
    let dir = tempfile::tempdir().unwrap();
    let variation = crossing_variation(
        dir.path(),
        r#"      <DeterministicSingleParameterDistribution parameterName="Ego_InitSpeed_Ve0_kph">
        <DistributionSet><Element value="30"/><Element value="50"/></DistributionSet>
      </DeterministicSingleParameterDistribution>
      <DeterministicMultiParameterDistribution>
        <ValueSetDistribution>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="4"/>
            <ParameterAssignment parameterRef="TargetBlocking_InitPosition_LateralOffset_m" value="-6"/>
          </ParameterValueSet>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="9"/>
            <ParameterAssignment parameterRef="TargetBlocking_InitPosition_LateralOffset_m" value="-3"/>
          </ParameterValueSet>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="12"/>
            <ParameterAssignment parameterRef="TargetBlocking_InitPosition_LateralOffset_m" value="-2"/>
          </ParameterValueSet>
        </ValueSetDistribution>
      </DeterministicMultiParameterDistribution>"#,
    );
    let (code, out, err) = xosc(&[variation.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for want in [
        "Ego_InitSpeed_Ve0_kph = 60   -> 2 levels {30, 50}",
        "value_set_0 (a ValueSetDistribution)   -> 3 levels {TargetBlocking_Speed_kph=4, TargetBlocking_InitPosition_LateralOffset_m=-6, TargetBlocking_Speed_kph=9, TargetBlocking_InitPosition_LateralOffset_m=-3, TargetBlocking_Speed_kph=12, TargetBlocking_InitPosition_LateralOffset_m=-2}",
        "the file's own grid: 6 runs",
    ] {
        assert!(out.contains(want), "`{want}` not in\n{out}");
    }
}

/// The crossing pedestrian on the straight road, the ego at 36 km/h in lane -4, the
/// pedestrian 100 m ahead (its longitudinal offset opened): with `aeb` the ego stops short
/// of it; with an `aeb` that never brakes (`ttc_brake_s` 0), the pedestrian the storyboard
/// sends across meets the ego's front, as the template's trigger intends.
#[test]
fn the_crossing_pedestrian_runs_on_the_storyboard_and_meets_an_ego_that_does_not_brake() {
    use paracosm_engine::sut::{AebConfig, SutConfig};
    use paracosm_generators::{Point, Value};
    let name = paracosm::ScenarioRef::OpenScenario(paracosm::scenario_ref::XoscRef {
        xosc: format!("{}/{CROSSING}", env!("CARGO_MANIFEST_DIR")),
        open: vec!["TargetBlocking_InitPosition_LongitudinalOffset_m=80..120".to_owned()],
        ..Default::default()
    });
    let mut scenario = name.load().expect("the campaign's scenario builds");
    let names: Vec<&str> = scenario
        .space()
        .params()
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "Road",
            "Ego_InitSpeed_Ve0_kph",
            "Ego_InitPosition_LaneId",
            "TargetBlocking_InitPosition_LongitudinalOffset_m"
        ]
    );
    let point = Point {
        discrete: vec![0, 6, 1],
        continuous: vec![0.5],
    };
    let a = scenario.space().decode(&point).expect("decodes");
    assert_eq!(a.get("Ego_InitSpeed_Ve0_kph"), Some(&Value::Int(35)));
    assert_eq!(a.get("Ego_InitPosition_LaneId"), Some(&Value::Int(-4)));
    let braking = scenario.run(&a, 1).expect("the test runs");
    assert!(braking.passed(), "{:?}", braking.monitors);
    let metric = |o: &paracosm_scenarios::TestOutcome, k: &str| {
        o.metrics.iter().find(|(n, _)| *n == k).map(|(_, v)| *v)
    };
    let gap = metric(&braking, "min_distance_m").expect("min distance");
    assert!(
        gap > 0.5 && gap < 5.0,
        "it stops short of the pedestrian: {gap} m"
    );
    // The storyboard's stop trigger: 100 m at 35 km/h, plus 10 s.
    let end = metric(&braking, "simulated_s").expect("simulated");
    assert!(
        (end - (100.0 / (35.0 / 3.6) + 10.0)).abs() < 0.05,
        "ended at {end} s"
    );
    let mut blind = AebConfig::default();
    blind.cruise.ttc_brake_s = 0.0;
    scenario.set_sut(SutConfig::Aeb(blind));
    let hit = scenario.run(&a, 1).expect("the test runs");
    let collision = hit
        .monitors
        .iter()
        .find(|(n, _)| n == "collision")
        .expect("a collision monitor");
    assert!(
        !collision.1.passed,
        "the pedestrian meets the ego: {:?}",
        hit.monitors
    );
}

/// A scenario written here (not shipped, not ALKS): a lead car placed 30 m ahead of the ego
/// by a `LongitudinalDistanceAction`, braking at an opened rate after 3 s, on the ALKS
/// straight road. Its campaign runs every test to the storyboard's stop trigger (15 s). The
/// same file with the distance action continuous runs too, and since the lead's own `Init`
/// `SpeedAction` (the same longitudinal domain) replaces the gap at once, its tests end as
/// the placed-once file's do.
#[test]
fn a_scenario_written_here_runs_as_a_campaign_with_a_distance_continuous_or_not() {
    let dir = tempfile::tempdir().unwrap();
    let file = brake_file(dir.path());
    let out = dir.path().join("out");
    let (code, err, records) = brake_campaign(&file, "LeadBrake=2..9", 4, &out);
    assert!(matches!(code, Some(0 | 1)), "{err}");
    for r in &records {
        assert_ne!(r["status"], "error", "{r}");
        assert!(r["monitors"]["collision"].is_object(), "{r}");
        let end = r["metrics"]["simulated_s"].as_f64().unwrap();
        assert!(
            (end - 15.0).abs() < 0.02,
            "the stop trigger ends the test: {end} s"
        );
        let gap = r["metrics"]["min_distance_m"].as_f64().unwrap();
        assert!(
            gap < 30.0,
            "the ego closes in on the braking lead car: {gap} m"
        );
    }
    std::fs::write(
        &file,
        brake_scenario("true", 20.0, "leadingReferencedEntity"),
    )
    .unwrap();
    let again = dir.path().join("again");
    let (code, err, continuous) = brake_campaign(&file, "LeadBrake=2..9", 4, &again);
    assert!(matches!(code, Some(0 | 1)), "{err}");
    assert_eq!(continuous.len(), records.len());
    for (c, r) in continuous.iter().zip(&records) {
        assert_eq!(c["status"], r["status"], "{c}");
        assert_eq!(
            c["metrics"]["min_distance_m"], r["metrics"]["min_distance_m"],
            "{c}"
        );
    }
}

/// A number out of its documented range that comes from a test's value (a braking rate of
/// up to 1e6 m/s², opened on the command line) ends that test in an error naming the file,
/// line and column of the action, its element and the range; the test whose value is in range
/// runs (the fixed numbers of a file are refused at load: `tests/bad_inputs/xosc/`).
#[test]
fn a_tests_value_out_of_range_ends_that_test_in_an_error_naming_the_action() {
    let dir = tempfile::tempdir().unwrap();
    let file = brake_file(dir.path());
    let out = dir.path().join("out");
    let (code, err, records) = brake_campaign(&file, "LeadBrake=2..1e6", 3, &out);
    // 3: a test ended in error and none failed; 1 if the one in range failed.
    assert!(matches!(code, Some(1 | 3)), "{err}");
    for r in &records {
        let rate = r["params"]["LeadBrake"].as_f64().unwrap();
        if rate <= 100.0 {
            assert_ne!(r["status"], "error", "{r}");
        } else {
            assert_eq!(r["status"], "error", "{r}");
            let why = r["error"].as_str().unwrap();
            assert!(
                why.contains("brake.xosc:")
                    && why.contains("<SpeedActionDynamics> attribute value")
                    && why.contains("out of range for an acceleration (m/s²)"),
                "{why}"
            );
        }
    }
    assert!(records.iter().any(|r| r["status"] == "error"));
    assert!(records.iter().any(|r| r["status"] != "error"));
}

/// Runs a campaign of `budget` tests over `file` with `--open open` into `out`: its exit code,
/// stderr and records (`budget` of them).
fn brake_campaign(
    file: &std::path::Path,
    open: &str,
    budget: usize,
    out: &std::path::Path,
) -> (Option<i32>, String, Vec<serde_json::Value>) {
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(file)
        .args(["--open", open, "--budget", &budget.to_string(), "--out"])
        .arg(out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let results =
        std::fs::read_to_string(out.join("results.jsonl")).unwrap_or_else(|e| panic!("{e}: {err}"));
    let records: Vec<serde_json::Value> = results
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), budget, "{err}");
    (o.status.code(), err, records)
}

/// `dir/brake.xosc`: [`brake_scenario`] placed once, not continuously, 20 m along the road.
fn brake_file(dir: &std::path::Path) -> std::path::PathBuf {
    let file = dir.join("brake.xosc");
    std::fs::write(
        &file,
        brake_scenario("false", 20.0, "leadingReferencedEntity"),
    )
    .unwrap();
    file
}

/// A scenario written here: the ego at `ego_s` m of lane −4 of the ALKS straight road at
/// 12 m/s, a lead box placed 30 m from it (`displacement`) by a LongitudinalDistanceAction
/// (`continuous`) at 12 m/s that brakes at `$LeadBrake` after 3 s; the test stops at 15 s.
fn brake_scenario(continuous: &str, ego_s: f64, displacement: &str) -> String {
    let road = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_straight.xodr");
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-26T00:00:00" description="brake" author="paracosm"/>
  <ParameterDeclarations>
<ParameterDeclaration name="LeadBrake" parameterType="double" value="6"/>
  </ParameterDeclarations>
  <RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>
  <Entities>
<ScenarioObject name="Ego">
  <Vehicle name="v" vehicleCategory="car">
    <BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.8" length="4.5" height="1.5"/></BoundingBox>
    <Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/>
    <Axles>
      <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/>
      <RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/>
    </Axles>
    <Properties/>
  </Vehicle>
</ScenarioObject>
<ScenarioObject name="Lead">
  <MiscObject name="box" miscObjectCategory="obstacle" mass="500">
    <BoundingBox><Center x="0" y="0" z="0.75"/><Dimensions width="1.8" length="4" height="1.5"/></BoundingBox>
    <Properties/>
  </MiscObject>
</ScenarioObject>
  </Entities>
  <Storyboard>
<Init>
  <Actions>
    <Private entityRef="Ego">
      <PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="{ego_s}" offset="0"/></Position></TeleportAction></PrivateAction>
      <PrivateAction><LongitudinalAction><SpeedAction>
        <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
        <SpeedActionTarget><AbsoluteTargetSpeed value="12"/></SpeedActionTarget>
      </SpeedAction></LongitudinalAction></PrivateAction>
    </Private>
    <Private entityRef="Lead">
      <PrivateAction><LongitudinalAction>
        <LongitudinalDistanceAction entityRef="Ego" distance="30" freespace="true" continuous="{continuous}" displacement="{displacement}"/>
      </LongitudinalAction></PrivateAction>
      <PrivateAction><LongitudinalAction><SpeedAction>
        <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
        <SpeedActionTarget><AbsoluteTargetSpeed value="12"/></SpeedActionTarget>
      </SpeedAction></LongitudinalAction></PrivateAction>
    </Private>
  </Actions>
</Init>
<Story name="S">
  <Act name="A">
    <ManeuverGroup maximumExecutionCount="1" name="G">
      <Actors selectTriggeringEntities="false"><EntityRef entityRef="Lead"/></Actors>
      <Maneuver name="M">
        <Event name="Brake" priority="override">
          <Action name="BrakeAction">
            <PrivateAction><LongitudinalAction><SpeedAction>
              <SpeedActionDynamics dynamicsShape="linear" value="$LeadBrake" dynamicsDimension="rate"/>
              <SpeedActionTarget><AbsoluteTargetSpeed value="0"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction></PrivateAction>
          </Action>
          <StartTrigger><ConditionGroup>
            <Condition name="T" delay="0" conditionEdge="rising">
              <ByValueCondition><SimulationTimeCondition value="3" rule="greaterThan"/></ByValueCondition>
            </Condition>
          </ConditionGroup></StartTrigger>
        </Event>
      </Maneuver>
    </ManeuverGroup>
    <StartTrigger><ConditionGroup>
      <Condition name="Go" delay="0" conditionEdge="none">
        <ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition>
      </Condition>
    </ConditionGroup></StartTrigger>
  </Act>
</Story>
<StopTrigger><ConditionGroup>
  <Condition name="End" delay="0" conditionEdge="rising">
    <ByValueCondition><SimulationTimeCondition value="15" rule="greaterOrEqual"/></ByValueCondition>
  </Condition>
</ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
        road = road.display()
    )
}

/// An ego that reaches the end of its road before the storyboard's stop trigger: the test
/// ends there and says so in its log, rather than failing off-road as the ego leaves the map.
#[test]
fn a_test_ends_where_the_egos_road_ends() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("end.xosc");
    std::fs::write(
        &file,
        brake_scenario("false", 9950.0, "trailingReferencedEntity"),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--budget", "1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let line = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let r: serde_json::Value = serde_json::from_str(line.lines().next().unwrap()).unwrap();
    assert_eq!(r["status"], "pass", "{r}");
    let end = r["metrics"]["simulated_s"].as_f64().unwrap();
    // 10,000 m − 9,950 m, less the ego's front and the 2 m margin, at 12 m/s: under 4 s.
    assert!(end > 2.0 && end < 4.0, "ended at {end} s");
    assert!(
        r.to_string()
            .contains("the ego reached the end of its road"),
        "the log says why: {r}"
    );
}

/// A stochastic variation file's distributions shape the `random` strategy's draws: the lead's
/// deceleration from a normal distribution N(3, 0.5²) truncated to [2, 8] has a sample mean
/// near 3 (uniform draws would give 5), and a probability set with weights 0 and 1 picks only
/// the weighted value. Coverage strategies keep covering the whole range.
#[test]
fn stochastic_distributions_weight_random_draws() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("brake.xosc");
    let scenario = brake_scenario("false", 20.0, "leadingReferencedEntity").replace(
        r#"<ParameterDeclaration name="LeadBrake" parameterType="double" value="6"/>"#,
        r#"<ParameterDeclaration name="LeadBrake" parameterType="double" value="6"/>
<ParameterDeclaration name="LeadSpeed" parameterType="double" value="12"/>"#,
    );
    std::fs::write(&file, scenario).unwrap();
    let variation = dir.path().join("brake_variation.xosc");
    std::fs::write(
        &variation,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-26T00:00:00" description="weights" author="paracosm"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="brake.xosc"/>
    <Stochastic numberOfTestRuns="20" randomSeed="1">
      <StochasticDistribution parameterName="LeadBrake">
        <NormalDistribution expectedValue="3" variance="0.25">
          <Range lowerLimit="2" upperLimit="8"/>
        </NormalDistribution>
      </StochasticDistribution>
      <StochasticDistribution parameterName="LeadSpeed">
        <ProbabilityDistributionSet>
          <Element value="10" weight="0"/>
          <Element value="12" weight="1"/>
        </ProbabilityDistributionSet>
      </StochasticDistribution>
    </Stochastic>
  </ParameterValueDistribution>
</OpenSCENARIO>
"#,
    )
    .unwrap();
    let run = |strategy: &str, out: &str| -> Vec<serde_json::Value> {
        let out = dir.path().join(out);
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .arg(&variation)
            .args(["--strategy", strategy, "--budget", "30", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
        assert!(
            !err.contains("not yet applied"),
            "the weights are applied: {err}"
        );
        std::fs::read_to_string(out.join("results.jsonl"))
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    };
    let brake = |rs: &[serde_json::Value]| -> Vec<f64> {
        rs.iter()
            .map(|r| r["params"]["LeadBrake"].as_f64().unwrap())
            .collect()
    };
    let random = run("random", "random");
    assert_eq!(random.len(), 30);
    let b = brake(&random);
    let mean = b.iter().sum::<f64>() / b.len() as f64;
    assert!((mean - 3.0).abs() < 0.35, "a normal around 3: mean {mean}");
    assert!(b.iter().all(|&x| (2.0..8.0).contains(&x)), "{b:?}");
    for r in &random {
        assert_eq!(r["params"]["LeadSpeed"].as_i64(), Some(12), "{r}");
    }
    // Halton covers the range: its mean sits near the middle, 5.
    let halton = brake(&run("halton", "halton"));
    let mean = halton.iter().sum::<f64>() / halton.len() as f64;
    assert!(
        (mean - 5.0).abs() < 0.35,
        "Halton covers [2, 8): mean {mean}"
    );
}

/// An external system under test (`--sut-cmd`, SUT_PROTOCOL.md) is told the speed the
/// scenario gives the ego to keep: the brake scenario's `Init` speed, 12 m/s, arrives as
/// `ego.set_speed_mps` in every observation.
#[test]
fn an_external_system_under_test_is_told_the_egos_set_speed() {
    let dir = tempfile::tempdir().unwrap();
    let file = brake_file(dir.path());
    let seen = dir.path().join("seen.txt");
    let script = dir.path().join("record.py");
    let lib = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/python");
    std::fs::write(
        &script,
        format!(
            r#"import sys
sys.path.insert(0, {lib:?})
from paracosm_sut import LidarBrake, serve

class Recording(LidarBrake):
    def act(self, obs):
        with open({seen:?}, "a") as f:
            f.write(repr(obs.ego.get("set_speed_mps")) + "\n")
        return LidarBrake.act(self, obs)

serve(Recording())
"#,
            lib = lib.to_str().unwrap(),
            seen = seen.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--budget", "1", "--sut-cmd"])
        .arg(format!("python3 {}", script.display()))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    let lines: Vec<String> = std::fs::read_to_string(&seen)
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect();
    assert!(lines.len() > 100, "{} observations", lines.len());
    assert!(lines.iter().all(|l| l == "12.0"), "{:?}", &lines[..3]);
}

/// The ALKS crossing-pedestrian template, for `Import`.
const CROSSING_TEMPLATE: &str =
    "tests/data/xosc/alks/concrete_scenarios/alks_scenario_4_2_3_crossing_pedestrian_template.xosc";

/// Runs `paracosm-fuzz` on `program` (written to `dir/prog.star`) with `args`.
fn run_program(dir: &std::path::Path, program: &str, args: &[&str]) -> std::process::Output {
    let path = dir.join("prog.star");
    std::fs::write(&path, program).unwrap();
    Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&path)
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

/// Runs a campaign of `budget` tests of `program` (written to `dir/prog.star`) into `dir/c`,
/// which it must finish (exit 0 or 1): the campaign's folder and what it wrote to stderr.
fn run_campaign(
    dir: &std::path::Path,
    program: &str,
    budget: usize,
) -> (std::path::PathBuf, String) {
    let out = dir.join("c");
    let budget = budget.to_string();
    let o = run_program(
        dir,
        program,
        &["--budget", &budget, "--out", out.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    (out, err)
}

/// A program imports an OpenSCENARIO scenario (`Import`), opens two of its parameters with
/// its own `VarInterval`s and adds monitors over its entities and signals: every test's
/// pedestrian walks at the speed the program's parameter gave the file (the storyboard moves
/// it when the ego comes near), and the program's monitors judge the imported world.
#[test]
fn a_program_imports_a_scenario_opens_its_parameters_and_adds_monitors() {
    let dir = tempfile::tempdir().unwrap();
    let template = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(CROSSING_TEMPLATE);
    let program = format!(
        r#"w = World()
s = Import("{}", params = {{
    "Ego_InitSpeed_Ve0_kph": VarInterval(50, 60, name = "ego_kph"),
    "TargetBlocking_Speed_kph": VarInterval(6, 12, name = "ped_kph"),
}})
CollisionMonitor(s.ego)
walked = s.TargetBlocking.speed.max()
Monitor(walked.map(lambda v: v - 1.0), over = "end", name = "ped_walked")
Stl("G[0,60] (ego_lane_edge_m > 0.1)", name = "keeps_lane")
test(horizon = 60)
"#,
        template.display()
    );
    let (out, _) = run_campaign(dir.path(), &program, 6);
    let text = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let records: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), 6);
    for r in &records {
        assert!(r["error"].is_null(), "{r}");
        let ped = r["params"]["ped_kph"].as_f64().unwrap();
        assert!((6.0..12.0).contains(&ped), "{r}");
        // The pedestrian's top speed is the one the program gave the file, m/s.
        let walked = r["monitors"]["ped_walked"]["robustness"].as_f64().unwrap() + 1.0;
        assert!(
            (walked - ped / 3.6).abs() < 1e-6,
            "walked at {walked} m/s, given {ped} km/h: {r}"
        );
        for m in ["collision", "keeps_lane", "offroad"] {
            assert!(r["monitors"][m].is_object(), "{m}: {r}");
        }
        // The storyboard's stop trigger (the time the ego needs to reach the pedestrian, plus
        // 10 s) ends the test before the program's 60 s horizon.
        let t = r["metrics"]["simulated_s"].as_f64().unwrap();
        assert!(t < 55.0, "{t}: {r}");
    }
    // A parameter the file does not declare, and an imported entity given to place(...).
    for (bad, want) in [
        (
            program.replace("\"TargetBlocking_Speed_kph\"", "\"Pedestrian_Speed\""),
            "Pedestrian_Speed",
        ),
        (
            format!("{program}w.place(s.ego)\n"),
            "leave it out of place",
        ),
    ] {
        let o = run_program(
            dir.path(),
            &bad,
            &[
                "--budget",
                "1",
                "--out",
                dir.path().join("bad").to_str().unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("prog.star:") && err.contains(want), "{err}");
    }
}

/// A parameter a program gives `Import(params=)` is read by the imported storyboard alone (the
/// pedestrian's speed): the load sees it change the test and keeps it in coverage, while a
/// parameter nothing reads is named unused.
#[test]
fn an_imported_storyboards_parameter_is_used_and_an_unread_one_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let template = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(CROSSING_TEMPLATE);
    let program = format!(
        r#"w = World()
spare = VarInterval(0.0, 1.0, name = "spare")
s = Import("{}", params = {{
    "Ego_InitSpeed_Ve0_kph": "40",
    "TargetBlocking_Speed_kph": VarEnum([3.0, 6.5], name = "ped_kph"),
}})
CollisionMonitor(s.ego)
DistanceMonitor(s.ego, minD = 5.0, name = "moved")
test(horizon = 60)
"#,
        template.display()
    );
    let (out, err) = run_campaign(dir.path(), &program, 2);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["unused_params"],
        serde_json::json!(["spare"]),
        "{err}"
    );
    assert!(
        err.contains("`spare` is sampled but no object uses it"),
        "{err}"
    );
    assert!(!err.contains("`ped_kph`"), "{err}");
}

/// Copies the folder `from` into `to`, recursively.
fn copy_folder(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_folder(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// A copy of the ALKS suite in a new temporary folder, the path of its file `name` there, and
/// the scenario that file loads.
fn copied_alks(
    name: &str,
) -> (
    tempfile::TempDir,
    std::path::PathBuf,
    paracosm_scenarios::Scenario,
) {
    let dir = tempfile::tempdir().unwrap();
    let alks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks");
    copy_folder(&alks, dir.path());
    let file = dir.path().join(name);
    let scenario = paracosm::load_scenario(file.to_str().unwrap()).expect("it loads");
    (dir, file, scenario)
}

/// A campaign is one fixed scenario: its load reads the variation file, the scenario and the
/// catalogs it names once, its fingerprint covers each of them, and every test reads those
/// texts. A copy of the crossing pedestrian's files is loaded, then its OpenSCENARIO files are
/// deleted: the campaign's tests still run (each test read them from disk again before).
#[test]
fn an_openscenario_campaign_reads_its_files_once_at_load() {
    use paracosm_generators::Point;
    let (dir, variation, scenario) =
        copied_alks("alks_scenario_4_2_3_crossing_pedestrian_variation.xosc");
    let read: Vec<&str> = scenario
        .input_files()
        .iter()
        .map(|f| f.path.as_str())
        .collect();
    println!("the campaign's input files: {read:#?}");
    let has = |tail: &str| read.iter().any(|p| p.ends_with(tail));
    assert!(
        has("alks_scenario_4_2_3_crossing_pedestrian_variation.xosc"),
        "{read:?}"
    );
    assert!(
        has("concrete_scenarios/alks_scenario_4_2_3_crossing_pedestrian_template.xosc"),
        "{read:?}"
    );
    assert!(has(".xodr"), "the map: {read:?}");
    assert!(
        read.iter().any(|p| p.contains("catalogs/vehicles/")),
        "a vehicle catalog: {read:?}"
    );
    assert!(
        read.iter().any(|p| p.contains("catalogs/pedestrians/")),
        "a pedestrian catalog: {read:?}"
    );
    assert!(scenario.input_files().iter().all(|f| f.sha256.len() == 64));
    let a = scenario
        .space()
        .decode(&Point {
            discrete: vec![0, 6, 1],
            continuous: vec![],
        })
        .expect("decodes");
    let before = scenario.run(&a, 1).expect("the test runs");
    std::fs::remove_file(&variation).unwrap();
    let scenarios = dir.path().join("concrete_scenarios");
    std::fs::remove_dir_all(scenarios.join("catalogs")).unwrap();
    for entry in std::fs::read_dir(&scenarios).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|x| x == "xosc") {
            std::fs::remove_file(path).unwrap();
        }
    }
    let after = scenario
        .run(&a, 1)
        .expect("the test runs on the files read at load");
    println!(
        "with its OpenSCENARIO files deleted, the test gives {:?}, as before",
        after.metrics
    );
    assert!(
        before
            .metrics
            .iter()
            .any(|(n, v)| *n == "simulated_s" && *v > 10.0),
        "{:?}",
        before.metrics
    );
    assert_eq!(format!("{before:?}"), format!("{after:?}"));
}

/// A campaign over an OpenSCENARIO file given by a relative path, with options, resumes bare
/// (`--resume --out DIR`, the command printed after Ctrl-C) from another folder:
/// `campaign.json` keeps the file's absolute path and its options, and the fingerprint names
/// the files relative to the file's folder. Then `report` reads the folder back.
#[test]
fn an_openscenario_campaign_resumes_bare_from_another_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let alks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks");
    let run = |cwd: &std::path::Path, args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .args(args)
            .current_dir(cwd)
            .output()
            .unwrap();
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = run(
        &alks,
        &[
            "alks_scenario_4_2_3_crossing_pedestrian_variation.xosc",
            "--open",
            "TargetBlocking_Speed_kph=2..10",
            "--budget",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!([0, 1, 3].contains(&code), "exit {code}: {err}");
    let campaign = std::fs::read_to_string(out.join("campaign.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&campaign).unwrap();
    println!("campaign.json's scenario: {}", json["scenario"]);
    assert_eq!(
        json["scenario"]["open"][0],
        "TargetBlocking_Speed_kph=2..10"
    );
    assert!(json["scenario"]["xosc"]
        .as_str()
        .is_some_and(|p| std::path::Path::new(p).is_absolute()));
    let (code, err) = run(dir.path(), &["--resume", "--out", out.to_str().unwrap()]);
    assert!([0, 1, 3].contains(&code), "exit {code}: {err}");
    assert!(!err.contains("refusing"), "{err}");
    let (code, err) = run(dir.path(), &["report", out.to_str().unwrap()]);
    assert!([0, 1, 3].contains(&code), "exit {code}: {err}");
}

/// A variation that chooses the road network among five maps (ALKS 4.3.1's `Road`) has every
/// one read, checked and fingerprinted at load: with the maps deleted afterwards, a test on
/// each level still runs, on the map the load read.
#[test]
fn every_map_a_level_chooses_is_read_at_load() {
    use paracosm_generators::Point;
    let (dir, _, scenario) =
        copied_alks("alks_scenario_4_3_1_follow_lead_vehicle_comfortable_variation.xosc");
    let maps: Vec<&str> = (scenario.input_files().iter())
        .map(|f| f.path.as_str())
        .filter(|p| p.ends_with(".xodr"))
        .collect();
    println!("the maps read at load: {maps:#?}");
    for m in [
        "alks_road_straight.xodr",
        "alks_road_left_radius_250m.xodr",
        "alks_road_right_radius_250m.xodr",
        "alks_road_left_radius_1000m.xodr",
        "alks_road_right_radius_1000m.xodr",
    ] {
        assert!(maps.iter().any(|p| p.ends_with(m)), "{m} in {maps:?}");
    }
    std::fs::remove_dir_all(dir.path().join("concrete_scenarios/road_networks")).unwrap();
    let space = scenario.space();
    assert_eq!(space.params()[0].name, "Road");
    let layout = space.layout();
    for level in 0..5 {
        // The other parameters at their middle level: the file's first lateral offset
        // (-1.75 m) breaks its own constraint (greater than -1.75 m).
        let mut discrete: Vec<u32> = layout.iter().flatten().map(|n| n / 2).collect();
        discrete[0] = level;
        let continuous = vec![0.5; layout.iter().filter(|l| l.is_none()).count()];
        let a = space.decode(&Point {
            discrete,
            continuous,
        });
        let record = scenario.run(&a.unwrap(), 1);
        assert!(record.is_ok(), "level {level}: {record:?}");
    }
}

/// A FIFO given as the scenario, named as a variation file's scenario, or lying in a catalog
/// folder (sorted after the entry the scenario needs, so no search would reach it) is refused
/// at once (exit 2, "is a FIFO, not a regular file") instead of blocking the read forever or
/// being passed over.
#[test]
fn a_fifo_in_place_of_an_openscenario_file_is_refused_not_waited_on() {
    let dir = tempfile::tempdir().unwrap();
    let alks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks");
    copy_folder(&alks, dir.path());
    let fifo = dir.path().join("fifo.xosc");
    let catalog_fifo = dir
        .path()
        .join("concrete_scenarios/catalogs/vehicles/zz_fifo.xosc");
    for f in [&fifo, &catalog_fifo] {
        let made = Command::new("mkfifo").arg(f).status().unwrap();
        assert!(made.success());
    }
    let crossing = dir
        .path()
        .join("alks_scenario_4_2_3_crossing_pedestrian_variation.xosc");
    let variation = dir.path().join("v.xosc");
    std::fs::write(
        &variation,
        r#"<OpenSCENARIO><FileHeader revMajor="1" revMinor="3" date="2026-11-29T00:00:00" description="v" author="x"/>
<ParameterValueDistribution><ScenarioFile filepath="fifo.xosc"/>
<Deterministic><DeterministicSingleParameterDistribution parameterName="P"><DistributionSet><Element value="1"/></DistributionSet></DeterministicSingleParameterDistribution></Deterministic>
</ParameterValueDistribution></OpenSCENARIO>"#,
    )
    .unwrap();
    for (file, why) in [
        (&fifo, "the scenario"),
        (&crossing, "a catalog"),
        (&variation, "a variation's scenario"),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .arg("xosc")
            .arg(file)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let started = std::time::Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            if started.elapsed().as_secs() > 30 {
                child.kill().unwrap();
                panic!("a FIFO as {why}: still waiting after 30 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        };
        let mut err = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
        println!("a FIFO as {why}: exit {:?}: {err}", status.code());
        assert_eq!(status.code(), Some(2), "{err}");
        assert!(
            err.starts_with("paracosm-fuzz: error: ")
                && err.contains("is a FIFO, not a regular file"),
            "{err}"
        );
    }
}

/// A value set binds its parameters as the variation file parsed them: a value whose text
/// holds `, Name=value` is that one parameter's value (here not a number, so the load refuses
/// it, naming that parameter and its declared type), never a second assignment.
#[test]
fn a_value_sets_value_is_one_value_not_more_assignments() {
    use paracosm_generators::Point;
    let dir = tempfile::tempdir().unwrap();
    let hostile = "4, TargetBlocking_InitPosition_LateralOffset_m=-1";
    let variation = crossing_variation(
        dir.path(),
        &format!(
            r#"      <DeterministicMultiParameterDistribution>
        <ValueSetDistribution>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="4"/>
            <ParameterAssignment parameterRef="TargetBlocking_InitPosition_LateralOffset_m" value="-6"/>
          </ParameterValueSet>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="{hostile}"/>
            <ParameterAssignment parameterRef="TargetBlocking_InitPosition_LateralOffset_m" value="-6"/>
          </ParameterValueSet>
        </ValueSetDistribution>
      </DeterministicMultiParameterDistribution>"#
        ),
    );
    let e = paracosm::ScenarioRef::named(variation.to_str().unwrap())
        .load()
        .map(|_| ())
        .expect_err("a value that is not a number is refused at load")
        .to_string();
    println!("{e}");
    assert!(
        e.contains(&format!("parameter TargetBlocking_Speed_kph = {hostile:?}"))
            && e.contains("not a number")
            && e.contains("declared double"),
        "{e}"
    );
    // The same sets with a number in its place build, and each set is one test.
    let variation = crossing_variation(
        dir.path(),
        r#"      <DeterministicMultiParameterDistribution>
        <ValueSetDistribution>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="4"/>
            <ParameterAssignment parameterRef="TargetBlocking_InitPosition_LateralOffset_m" value="-6"/>
          </ParameterValueSet>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetBlocking_Speed_kph" value="5"/>
          </ParameterValueSet>
        </ValueSetDistribution>
      </DeterministicMultiParameterDistribution>"#,
    );
    let scenario = paracosm::ScenarioRef::named(variation.to_str().unwrap())
        .load()
        .expect("the campaign's scenario builds");
    for set in 0..2 {
        let a = (scenario.space())
            .decode(&Point {
                discrete: vec![set],
                continuous: vec![],
            })
            .unwrap();
        assert!(scenario.run(&a, 0).is_ok(), "set {set}");
    }
}

/// A variation file that varies a parameter nothing in the scenario reads gets the warning a
/// program's unread parameter gets, naming the variation file's line, and the parameter is
/// left out of coverage (`unused_params`); a parameter only the storyboard reads (the
/// pedestrian's speed, a `SpeedAction`'s target) is used, though no entity's `Init` changes.
#[test]
fn a_varied_parameter_nothing_reads_is_named_unused_as_in_a_program() {
    let dir = tempfile::tempdir().unwrap();
    let concrete = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/alks/concrete_scenarios");
    let template = std::fs::read_to_string(
        concrete.join("alks_scenario_4_2_3_crossing_pedestrian_template.xosc"),
    )
    .unwrap()
    .replace("\"./", &format!("\"{}/", concrete.display()))
    .replacen(
        "<ParameterDeclarations>",
        "<ParameterDeclarations>\n    <ParameterDeclaration name=\"Unread\" \
         parameterType=\"double\" value=\"1.0\"/>",
        1,
    );
    let scenario_file = dir.path().join("crossing_with_unread.xosc");
    std::fs::write(&scenario_file, template).unwrap();
    let variation = variation_over(
        dir.path(),
        &scenario_file,
        r#"      <DeterministicSingleParameterDistribution parameterName="TargetBlocking_Speed_kph">
        <DistributionSet><Element value="3"/><Element value="6"/></DistributionSet>
      </DeterministicSingleParameterDistribution>
      <DeterministicSingleParameterDistribution parameterName="Unread">
        <DistributionSet><Element value="1"/><Element value="2"/><Element value="3"/></DistributionSet>
      </DeterministicSingleParameterDistribution>"#,
    );
    let scenario = paracosm::ScenarioRef::OpenScenario(paracosm::scenario_ref::XoscRef {
        xosc: variation.display().to_string(),
        ..Default::default()
    })
    .load()
    .expect("the variation loads");
    assert_eq!(scenario.unused_params(), ["Unread"]);
    let warning = scenario
        .warnings()
        .iter()
        .find(|w| w.message.contains("`Unread`"))
        .expect("a warning names the unread parameter");
    assert_eq!(
        warning.at,
        format!("{}:10:7", variation.display()),
        "{warning}"
    );
    assert!(
        warning.message.contains("no object uses it"),
        "the program's wording: {warning}"
    );
    assert!(
        !scenario
            .warnings()
            .iter()
            .any(|w| w.message.contains("TargetBlocking_Speed_kph")),
        "the storyboard reads the speed: {:?}",
        scenario.warnings()
    );
}

/// With `--scripted-ego` no system under test drives, so nothing reads the sensors and none
/// is mounted: each test's outcome is the one it has with the sensors mounted (a constant
/// control that the scripted ego never reads, so the lidar captures every step).
#[test]
fn a_scripted_ego_test_without_sensors_is_judged_as_with_them() {
    let mut scenario = paracosm::ScenarioRef::OpenScenario(paracosm::scenario_ref::XoscRef {
        xosc: format!("{}/{CROSSING}", env!("CARGO_MANIFEST_DIR")),
        scripted_ego: true,
        ..Default::default()
    })
    .load()
    .expect("the variation loads");
    assert_eq!(scenario.sut().name(), "scripted");
    let space = scenario.space().clone();
    let points: Vec<paracosm_generators::Point> = (0..3)
        .map(|i| paracosm_generators::Point {
            discrete: space.level_counts().iter().map(|c| (i * 7) % c).collect(),
            continuous: vec![0.25 + 0.25 * f64::from(i); space.continuous_dims()],
        })
        .collect();
    let outcomes = |s: &paracosm_scenarios::Scenario| -> Vec<_> {
        points
            .iter()
            .map(|p| s.run(&space.decode(p).unwrap(), 0).unwrap())
            .collect()
    };
    let unsensed = outcomes(&scenario);
    scenario.set_sut(paracosm_engine::sut::SutConfig::Constant(
        paracosm_engine::Control::default(),
    ));
    assert_eq!(unsensed, outcomes(&scenario));
    let simulated = |o: &paracosm_scenarios::TestOutcome| {
        o.metrics
            .iter()
            .find(|(k, _)| *k == "simulated_s")
            .map_or(0.0, |(_, v)| *v)
    };
    assert!(unsensed.iter().any(|o| simulated(o) > 30.0), "{unsensed:?}");
}

/// [`brake_scenario`] with an `EnvironmentAction` in `Init` that gives the world `weather`
/// (the inside of `<Weather>`), written to `dir/name`.
fn weather_file(dir: &std::path::Path, name: &str, weather: &str) -> std::path::PathBuf {
    let file = dir.join(name);
    let text = brake_scenario("false", 20.0, "leadingReferencedEntity").replacen(
        "<Init>\n  <Actions>",
        &format!(
            "<Init>\n  <Actions>\n    <GlobalAction><EnvironmentAction><Environment name=\"w\">\
             <Weather>{weather}</Weather></Environment></EnvironmentAction></GlobalAction>"
        ),
        1,
    );
    assert!(text.contains("EnvironmentAction"));
    std::fs::write(&file, text).unwrap();
    file
}

/// An `EnvironmentAction`'s fog is the world's: the system under test's sensors see as far
/// as its visual range. `aeb` stops behind the braking lead in clear air (100 km) and runs
/// into it in a fog of 8 m (fog density 0.98: its lidar's range capped at 8 m).
#[test]
fn an_environment_actions_fog_is_the_fog_the_system_under_test_senses() {
    let dir = tempfile::tempdir().unwrap();
    let clear = weather_file(dir.path(), "clear.xosc", r#"<Fog visualRange="100000"/>"#);
    let fog = weather_file(dir.path(), "fog.xosc", r#"<Fog visualRange="8"/>"#);
    let (code, err, clear) = brake_campaign(&clear, "LeadBrake=8..9", 2, &dir.path().join("c"));
    assert_eq!(code, Some(0), "{err}");
    let (code, err, fog) = brake_campaign(&fog, "LeadBrake=8..9", 2, &dir.path().join("f"));
    assert_eq!(code, Some(1), "{err}");
    for (c, f) in clear.iter().zip(&fog) {
        assert_eq!(c["status"], "pass", "{c}");
        assert_eq!(f["status"], "fail", "{f}");
        assert!(
            c["metrics"]["min_distance_m"].as_f64().unwrap() > 1.0,
            "{c}"
        );
        assert_eq!(f["metrics"]["min_distance_m"].as_f64().unwrap(), 0.0, "{f}");
    }
}

/// Rain and snow are the world's too, by their extinction (ITU-R P.1814), added to the
/// fog's: under `aeb` a rain of 4 mm/h (a visual range of 6.2 km alone) runs, named in a
/// warning, and the ego stops behind the braking lead as in clear air; a snowfall of
/// 100 mm/h (5.3 m) hides the lead from its lidar until too late, as the 8 m fog does.
/// OpenSCENARIO 1.0's `intensity`, a share in `[0, 1]`, is read as a share of 50 mm/h, noted,
/// and a share above 1 is refused at its attribute.
#[test]
fn rain_and_snow_thin_what_the_system_under_test_senses() {
    let dir = tempfile::tempdir().unwrap();
    let rain = weather_file(
        dir.path(),
        "rain.xosc",
        r#"<Precipitation precipitationType="rain" precipitationIntensity="4"/>"#,
    );
    let (code, err, rain) = brake_campaign(&rain, "LeadBrake=8..9", 2, &dir.path().join("r"));
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("rain.xosc:30:5"), "{err}");
    assert!(
        err.contains("rain (4 mm/h) is modelled by its extinction (ITU-R P.1814)")
            && err.contains("a 6237 m visual range"),
        "{err}"
    );
    let snow = weather_file(
        dir.path(),
        "snow.xosc",
        r#"<Precipitation precipitationType="snow" precipitationIntensity="100"/>"#,
    );
    let (code, err, snow) = brake_campaign(&snow, "LeadBrake=8..9", 2, &dir.path().join("s"));
    assert_eq!(code, Some(1), "{err}");
    for (r, s) in rain.iter().zip(&snow) {
        assert_eq!(r["status"], "pass", "{r}");
        assert!(
            r["metrics"]["min_distance_m"].as_f64().unwrap() > 1.0,
            "{r}"
        );
        assert_eq!(s["status"], "fail", "{s}");
        assert_eq!(s["metrics"]["min_distance_m"].as_f64().unwrap(), 0.0, "{s}");
    }
    // 1.0's share: 0.2 is 10 mm/h, noted; 1.5 is refused.
    let share = weather_file(
        dir.path(),
        "share.xosc",
        r#"<Precipitation type="rain" intensity="0.2"/>"#,
    );
    let (code, err, _) = brake_campaign(&share, "LeadBrake=8..9", 1, &dir.path().join("h"));
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("is read as 10 mm/h"), "{err}");
    let over = weather_file(
        dir.path(),
        "over.xosc",
        r#"<Precipitation type="rain" intensity="1.5"/>"#,
    );
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&over)
        .args(["--budget", "1", "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("over.xosc:30:") && err.contains("a share in [0, 1], not 1.5"),
        "{err}"
    );
}

/// `Init` places an entity relative to one the file places later (other readers accept it):
/// the lead, written first, is put 30 m ahead of the ego once the ego is placed.
#[test]
fn an_init_position_relative_to_an_entity_placed_later_waits_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let text = brake_scenario("false", 20.0, "leadingReferencedEntity");
    let lead = text.find("    <Private entityRef=\"Lead\">").unwrap();
    let end = text[lead..].find("    </Private>\n").unwrap() + lead + "    </Private>\n".len();
    let lead_block = text[lead..end].replace(
        r#"<LongitudinalDistanceAction entityRef="Ego" distance="30" freespace="true" continuous="false" displacement="leadingReferencedEntity"/>"#,
        "",
    );
    let lead_block = lead_block.replace(
        "<PrivateAction><LongitudinalAction>\n        \n      </LongitudinalAction></PrivateAction>",
        r#"<PrivateAction><TeleportAction><Position><RelativeLanePosition entityRef="Ego" dLane="0" ds="30"/></Position></TeleportAction></PrivateAction>"#,
    );
    assert!(lead_block.contains("RelativeLanePosition"), "{lead_block}");
    let ego = text.find("    <Private entityRef=\"Ego\">").unwrap();
    // The lead's block first, then the ego's.
    let reordered = format!(
        "{}{}{}{}",
        &text[..ego],
        lead_block,
        &text[ego..lead],
        &text[end..]
    );
    let file = dir.path().join("later.xosc");
    std::fs::write(&file, reordered).unwrap();
    let (code, err, records) = brake_campaign(&file, "LeadBrake=2..9", 2, &dir.path().join("o"));
    assert!(matches!(code, Some(0 | 1)), "{err}");
    for r in &records {
        assert_ne!(r["status"], "error", "{r}");
        let gap = r["metrics"]["min_distance_m"].as_f64().unwrap();
        assert!(
            gap < 30.0,
            "the lead stands ahead of the ego and brakes: {gap} m"
        );
    }
}

/// CARLA's scenarios name their map as CARLA names its towns (`<LogicFile
/// filepath="Town01"/>`): the town's OpenDRIVE file beside the scenario stands for it, with
/// a note; without it the load is refused, saying where to put it. Their stop triggers hold
/// CARLA's evaluation criteria (`criteria_...` on no parameter): notes, not conditions.
#[test]
fn a_carla_town_named_without_its_extension_is_read_from_beside_the_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("follow.xosc");
    std::fs::write(
        &scenario,
        r#"<OpenSCENARIO><FileHeader revMajor="1" revMinor="0" date="2026-11-29T00:00:00" description="CARLA town" author="x"/>
<ParameterDeclarations/>
<RoadNetwork><LogicFile filepath="Town01"/><SceneGraphFile filepath=""/></RoadNetwork>
<Entities><ScenarioObject name="hero"><Vehicle name="vehicle.lincoln.mkz2017" vehicleCategory="car"><ParameterDeclarations/><Performance maxSpeed="69.444" maxAcceleration="200" maxDeceleration="10.0"/><BoundingBox><Center x="1.5" y="0.0" z="0.9"/><Dimensions width="2.1" length="4.5" height="1.8"/></BoundingBox><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.8" positionX="3.1" positionZ="0.3"/><RearAxle maxSteering="0.0" wheelDiameter="0.6" trackWidth="1.8" positionX="0.0" positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject></Entities>
<Storyboard><Init><Actions><Private entityRef="hero">
<PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-1" s="20" offset="0"/></Position></TeleportAction></PrivateAction>
<PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>
</Private></Actions></Init>
<StopTrigger><ConditionGroup>
<Condition name="criteria_CollisionTest" delay="0" conditionEdge="rising"><ByValueCondition><ParameterCondition parameterRef="" value="" rule="lessThan"/></ByValueCondition></Condition>
<Condition name="criteria_DrivenDistanceTest" delay="0" conditionEdge="rising"><ByValueCondition><ParameterCondition parameterRef="distance_success" value="100" rule="lessThan"/></ByValueCondition></Condition>
</ConditionGroup></StopTrigger>
</Storyboard></OpenSCENARIO>"#,
    )
    .unwrap();
    let file = scenario.to_str().unwrap();
    let (code, _, err) = xosc(&[file]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("as CARLA names its towns"), "{err}");
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/maps/carla/Town01.xodr"),
        dir.path().join("Town01.xodr"),
    )
    .unwrap();
    let (code, out, err) = xosc(&[file]);
    assert_eq!(code, 0, "{err}");
    let text = format!("{out}{err}");
    assert!(
        text.contains("is named without its extension, as CARLA names its towns"),
        "{text}"
    );
    // Its stop trigger holds CARLA's evaluation criteria only: notes, not conditions, so
    // nothing ends a test but the horizon asked for.
    assert!(
        text.contains("criteria_DrivenDistanceTest is one of CARLA's evaluation criteria"),
        "{text}"
    );
    let campaign = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .arg(file)
            .args(["--budget", "1", "--scripted-ego", "--out"])
            .arg(dir.path().join("out"))
            .arg("--force")
            .args(extra)
            .output()
            .unwrap()
    };
    let o = campaign(&[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no stop trigger"), "{err}");
    let o = campaign(&["--horizon", "3"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// An ego whose bounding box has a side of 0 m (which the schema allows, and which other
/// entities may have) is refused at load, naming the box: its collisions could not be
/// judged.
#[test]
fn an_ego_of_no_size_is_refused_at_its_box() {
    let dir = tempfile::tempdir().unwrap();
    let road = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_straight.xodr");
    let scenario = dir.path().join("flat.xosc");
    std::fs::write(
        &scenario,
        format!(
            r#"<OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="flat ego" author="x"/>
<RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>
<Entities><ScenarioObject name="Ego"><Vehicle name="flat" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="2" length="4.5" height="0"/></BoundingBox><Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject></Entities>
<Storyboard><Init><Actions><Private entityRef="Ego">
<PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-4" s="20" offset="0"/></Position></TeleportAction></PrivateAction>
<PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="10"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>
</Private></Actions></Init>
<StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="rising"><ByValueCondition><SimulationTimeCondition value="5" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
</Storyboard></OpenSCENARIO>"#,
            road = road.display()
        ),
    )
    .unwrap();
    for scripted in [false, true] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"));
        cmd.arg(&scenario)
            .args(["--budget", "1", "--out"])
            .arg(dir.path().join("out"));
        if scripted {
            cmd.arg("--scripted-ego");
        }
        let o = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("flat.xosc:3:"), "{err}");
        assert!(err.contains("cannot be the ego"), "{err}");
    }
}

/// A speed parameter whose level is 0 asks the driven ego to stand: such a test, whose ego
/// never moves, ends as an error when its storyboard ends, not as a pass; the level that
/// asks it to drive runs as before. The file asks the ego a speed, so the load takes it.
#[test]
fn a_test_whose_values_ask_the_ego_no_speed_is_an_error_not_a_pass() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stand.xosc");
    let text = brake_scenario("false", 20.0, "leadingReferencedEntity").replacen(
        r#"<AbsoluteTargetSpeed value="12"/>"#,
        r#"<AbsoluteTargetSpeed value="$EgoSpeed"/>"#,
        1,
    );
    let text = text.replace(
        r#"<ParameterDeclaration name="LeadBrake""#,
        r#"<ParameterDeclaration name="EgoSpeed" parameterType="double" value="12"/>
<ParameterDeclaration name="LeadBrake""#,
    );
    std::fs::write(&file, text).unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args([
            "--open",
            "EgoSpeed=0,12",
            "--strategy",
            "variation",
            "--budget",
            "2",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let records: Vec<serde_json::Value> = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap_or_else(|e| panic!("{e}: {err}"))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), 2, "{err}");
    for r in &records {
        let v = r["params"]["EgoSpeed"].as_f64().unwrap();
        if v == 0.0 {
            assert_eq!(r["status"], "error", "{r}");
            let e = r["error"].as_str().unwrap();
            assert!(e.contains("asked it no speed above 0.1 m/s"), "{e}");
        } else {
            assert!(r["error"].is_null(), "{r}");
        }
    }
    // And --ego-speed, meant for a file that asks the ego no speed, is refused with one
    // that does, naming its SpeedAction.
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--ego-speed", "9", "--budget", "1", "--out"])
        .arg(dir.path().join("out2"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("stand.xosc:") && err.contains("--ego-speed is for a file that asks none"),
        "{err}"
    );
}

/// [`brake_scenario`]'s lead with the events `events` (whole `<Event>` elements) added to its
/// maneuver, and a second box, `Late`, that `Init` does not place; run once with the ego
/// scripted (nothing brakes it), its one record returned.
fn entities_campaign(dir: &std::path::Path, tag: &str, events: &str) -> serde_json::Value {
    let text = brake_scenario("false", 20.0, "leadingReferencedEntity")
        .replace(
            "</Entities>",
            r#"<ScenarioObject name="Late">
  <MiscObject name="box" miscObjectCategory="obstacle" mass="500">
    <BoundingBox><Center x="0" y="0" z="0.75"/><Dimensions width="1.8" length="4" height="1.5"/></BoundingBox>
    <Properties/>
  </MiscObject>
</ScenarioObject>
  </Entities>"#,
        )
        .replace(
            r#"<Event name="Brake" priority="override">"#,
            &format!(r#"{events}<Event name="Brake" priority="override">"#),
        );
    let file = dir.join(format!("{tag}.xosc"));
    std::fs::write(&file, text).unwrap();
    let out = dir.join(tag);
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--scripted-ego", "--budget", "1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    assert_eq!(
        err.contains("Late is never in the scenario"),
        !events.contains("AddEntityAction"),
        "a box never placed nor added is named: {err}"
    );
    let results =
        std::fs::read_to_string(out.join("results.jsonl")).unwrap_or_else(|e| panic!("{e}: {err}"));
    serde_json::from_str(results.lines().next().unwrap()).unwrap()
}

/// A global `<Event>` named `name` that performs `action` (an `EntityAction`'s inside) on
/// `entity` once the simulation time exceeds `t` s.
fn entity_event(name: &str, entity: &str, action: &str, t: f64) -> String {
    format!(
        r#"<Event name="{name}" priority="parallel">
          <Action name="{name}Action"><GlobalAction><EntityAction entityRef="{entity}">{action}</EntityAction></GlobalAction></Action>
          <StartTrigger><ConditionGroup>
            <Condition name="T{name}" delay="0" conditionEdge="rising">
              <ByValueCondition><SimulationTimeCondition value="{t}" rule="greaterThan"/></ByValueCondition>
            </Condition>
          </ConditionGroup></StartTrigger>
        </Event>"#
    )
}

/// `AddEntityAction` and `DeleteEntityAction` (OpenSCENARIO 1.3, 7.7.3): the scripted ego
/// at 12 m/s runs into its lead, which brakes hard after 3 s, unless the lead leaves the
/// scenario first; then nothing touches it and the test passes. An entity `Init` does not
/// place is out of the test's world (esmini's inactive entity, with a warning) until an
/// `AddEntityAction` puts it in, where the ego then runs into it.
#[test]
fn an_entity_deleted_leaves_the_world_and_one_added_enters_it() {
    let dir = tempfile::tempdir().unwrap();
    let collided = |r: &serde_json::Value| r["monitors"]["collision"]["passed"] == false;
    let kept = entities_campaign(dir.path(), "kept", "");
    assert_eq!(kept["status"], "fail", "the ego runs into the lead: {kept}");
    assert!(collided(&kept), "{kept}");
    let deleted = entities_campaign(
        dir.path(),
        "deleted",
        &entity_event("Gone", "Lead", "<DeleteEntityAction/>", 2.0),
    );
    assert_eq!(deleted["status"], "pass", "the lead left at 2 s: {deleted}");
    assert!(!collided(&deleted), "{deleted}");
    // The lead gone, the box added 60 m ahead of the ego at 4 s stands in its lane.
    let added = entities_campaign(
        dir.path(),
        "added",
        &(entity_event("Gone", "Lead", "<DeleteEntityAction/>", 2.0)
            + &entity_event(
                "Enter",
                "Late",
                r#"<AddEntityAction><Position><RelativeLanePosition entityRef="Ego" dLane="0" ds="60"/></Position></AddEntityAction>"#,
                4.0,
            )),
    );
    assert_eq!(
        added["status"], "fail",
        "the ego runs into the added box: {added}"
    );
    assert!(collided(&added), "{added}");
    // At 12 m/s, the ego's front (3.65 m ahead of its reference point) meets the box's back
    // (2 m behind the box's, 60 m ahead) 4.53 s after the box enters at 4 s: it was in the
    // world no sooner.
    let t = added["metrics"]["simulated_s"].as_f64().unwrap();
    assert!((8.3..8.8).contains(&t), "collided at {t} s: {added}");
}

/// A scripted ego asked a negative speed reverses along its lane through the engine too
/// (`--scripted-ego`): the brake scenario's ego, asked −3 m/s at 6 m/s² after 3 s, stops and
/// backs down its lane, its trace's speed −3 m/s and its position falling; the test passes.
/// Driven by a system under test, the same ego is refused at that `SpeedAction`: the system
/// drives forward only.
#[test]
fn a_scripted_ego_reverses_through_the_engine_and_a_driven_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = brake_scenario("false", 20.0, "leadingReferencedEntity")
        .replace(
            r#"<Actors selectTriggeringEntities="false"><EntityRef entityRef="Lead"/></Actors>"#,
            r#"<Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>"#,
        )
        .replace(
            r#"<AbsoluteTargetSpeed value="0"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction></PrivateAction>
          </Action>"#,
            r#"<AbsoluteTargetSpeed value="-3"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction></PrivateAction>
          </Action>"#,
        );
    assert!(text.contains(r#"value="-3""#));
    let file = dir.path().join("reverse.xosc");
    std::fs::write(&file, &text).unwrap();
    let out = dir.path().join("scripted");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--scripted-ego", "--budget", "1", "--trace", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let record: serde_json::Value = serde_json::from_str(results.lines().next().unwrap()).unwrap();
    assert_eq!(record["status"], "pass", "{record} {err}");
    // The trace's rows: time, then per entity its name, id, speed, ... x at 11 columns on.
    let trace = std::fs::read_to_string(out.join("trace/test_0.csv")).unwrap();
    let ego: Vec<(f64, f64, f64)> = trace
        .lines()
        .skip(4)
        .map(|l| {
            let f: Vec<&str> = l.split(',').map(str::trim).collect();
            let i = f.iter().position(|c| *c == "Ego").unwrap();
            let num = |k: usize| f[k].parse::<f64>().unwrap();
            (num(1), num(i + 2), num(i + 11))
        })
        .collect();
    let (_, v_end, x_end) = *ego.last().unwrap();
    let (_, _, x_10) = *ego.iter().find(|(t, _, _)| *t >= 10.0).unwrap();
    assert!(
        (v_end + 3.0).abs() < 0.01,
        "the ego's speed at the end: {v_end}"
    );
    assert!(
        x_end < x_10 - 10.0,
        "it backed down its lane: x {x_10} at 10 s, {x_end} at the end"
    );
    // Driven by the system under test, the same ego cannot be asked to reverse.
    let out = dir.path().join("driven");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--budget", "1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap_or_default();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        results.contains("drive backwards") || err.contains("drive backwards"),
        "{results} {err}"
    );
}

/// A scenario on the ALKS suite's straight road: `Ego` at 10 m/s on lane -5, `Truck` (a car
/// towing the trailer written in it; the ego too when `ego_tows`) 80 m ahead on lane -4 at
/// 10 m/s, and an event that stops the ego if the truck collides with any vehicle; `init`
/// is added to the truck's `Init`.
fn truck_scenario(ego_tows: bool, init: &str) -> String {
    let road = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_straight.xodr");
    let axles = r#"<Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles>"#;
    let trailer = format!(
        r#"<TrailerHitch dx="-1.2"/><Trailer><Trailer name="t"><Vehicle name="trailer" vehicleCategory="trailer"><BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="2" length="4.5" height="1.2"/></BoundingBox><Performance maxSpeed="60" maxAcceleration="10" maxDeceleration="10"/>{axles}<TrailerCoupler dx="3.25"/><Properties/></Vehicle></Trailer></Trailer>"#
    );
    let car = |tows: bool| {
        format!(
            r#"<Vehicle name="car" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox><Performance maxSpeed="60" maxAcceleration="10" maxDeceleration="10"/>{axles}{}<Properties/></Vehicle>"#,
            if tows { trailer.as_str() } else { "" }
        )
    };
    let at = |name: &str, lane: i32, s: f64, extra: &str| {
        format!(
            r#"<Private entityRef="{name}"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="{lane}" s="{s}" offset="0"/></Position></TeleportAction></PrivateAction><PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="10"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>{extra}</Private>"#
        )
    };
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="3" date="2026-11-30T00:00:00" description="truck" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>
  <Entities><ScenarioObject name="Ego">{ego}</ScenarioObject><ScenarioObject name="Truck">{truck}</ScenarioObject></Entities>
  <Storyboard>
    <Init><Actions>{ego_at}{truck_at}</Actions></Init>
    <Story name="S"><Act name="Act"><ManeuverGroup maximumExecutionCount="1" name="G">
      <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
      <Maneuver name="M"><Event name="Crash" priority="parallel"><Action name="Stop"><PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="0"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction></Action>
        <StartTrigger><ConditionGroup><Condition name="Hit" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Truck"/></TriggeringEntities><EntityCondition><CollisionCondition><ByType type="vehicle"/></CollisionCondition></EntityCondition></ByEntityCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
    </ManeuverGroup></Act></Story>
    <StopTrigger><ConditionGroup><Condition name="End" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="8" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
        ego = car(ego_tows),
        truck = car(true),
        ego_at = at("Ego", -5, 20.0, ""),
        truck_at = at("Truck", -4, 100.0, init),
        road = road.display(),
    )
}

/// A vehicle combination runs as a campaign: the trailer, an entity of its own (`Truck+`),
/// follows its tow through the engine, and the two, overlapping at the hitch, do not collide
/// (the storyboard's collision condition on the truck never fires). An ego towing a trailer,
/// and a `TrailerAction`, are refused at load, naming them.
#[test]
fn a_trailer_runs_with_its_tow_and_an_ego_towing_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("truck.xosc");
    std::fs::write(&file, truck_scenario(false, "")).unwrap();
    let out = dir.path().join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg(&file)
        .args(["--scripted-ego", "--budget", "1", "--trace", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let record: serde_json::Value = serde_json::from_str(results.lines().next().unwrap()).unwrap();
    assert_eq!(record["status"], "pass", "{record} {err}");
    let log: Vec<&str> = (record["log"].as_array().unwrap().iter())
        .filter_map(serde_json::Value::as_str)
        .collect();
    assert!(
        !log.iter().any(|l| l.contains("event \"Crash\" start")),
        "the truck collided with its trailer: {log:?}"
    );
    let trace = std::fs::read_to_string(out.join("trace/test_0.csv")).unwrap();
    let xs: Vec<f64> = trace
        .lines()
        .skip(4)
        .map(|l| {
            let f: Vec<&str> = l.split(',').map(str::trim).collect();
            let i = f
                .iter()
                .position(|c| *c == "Truck+")
                .expect("the trailer's columns");
            f[i + 11].parse::<f64>().unwrap()
        })
        .collect();
    let moved = (xs.last().unwrap() - xs[0]).abs();
    assert!(
        (moved - 80.0).abs() < 1.0,
        "8 s at 10 m/s: the trailer moved {moved} m"
    );

    for (name, text, why) in [
        (
            "ego",
            truck_scenario(true, ""),
            "the ego \"Ego\" tows a trailer",
        ),
        (
            "action",
            truck_scenario(
                false,
                r#"<PrivateAction><TrailerAction><DisconnectTrailerAction/></TrailerAction></PrivateAction>"#,
            ),
            "couples or uncouples a trailer",
        ),
    ] {
        let file = dir.path().join(format!("{name}.xosc"));
        std::fs::write(&file, text).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .arg(&file)
            .args(["--budget", "1", "--out"])
            .arg(dir.path().join(name))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(why), "{name}: {err}");
        assert!(err.contains(&format!("{name}.xosc:")), "{name}: {err}");
    }
}

/// esmini's `traffic_lights.xosc`: its storyboard sets and reads traffic signals of its
/// map, so it runs with `--scripted-ego` (its pedestrians cross on their lights); under a
/// system under test, which would neither see nor obey a signal, it is refused at the first
/// signal action; and a signal the map does not have is refused at load, naming the map's.
#[test]
fn traffic_signals_run_scripted_and_are_refused_under_a_system_that_cannot_see_them() {
    let dir = tempfile::tempdir().unwrap();
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/esmini/xosc");
    let run = |file: &std::path::Path, args: &[&str], out: &str| {
        Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .arg(file)
            .args(args)
            .args(["--budget", "1", "--out"])
            .arg(dir.path().join(out))
            .output()
            .unwrap()
    };
    let file = src.join("traffic_lights.xosc");
    let o = run(&file, &["--scripted-ego", "--ego", "Ego"], "scripted");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    let o = run(&file, &["--ego", "Ego"], "driven");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("traffic_lights.xosc:42:13:") && err.contains("would neither see nor obey"),
        "{err}"
    );
    // A signal the map does not have, in a copy whose relative paths (`../xodr`,
    // `../xosc/Catalogs`) resolve to the originals.
    let text = std::fs::read_to_string(&file).unwrap();
    let bad = text.replacen(
        r#"<TrafficSignalStateAction name="1""#,
        r#"<TrafficSignalStateAction name="99""#,
        1,
    );
    assert_ne!(bad, text);
    let xosc = dir.path().join("xosc");
    std::fs::create_dir_all(&xosc).unwrap();
    std::os::unix::fs::symlink(src.join("Catalogs"), xosc.join("Catalogs")).unwrap();
    std::os::unix::fs::symlink(src.join("../xodr"), dir.path().join("xodr")).unwrap();
    let copy = xosc.join("bad_signal.xosc");
    std::fs::write(&copy, bad).unwrap();
    let o = run(&copy, &["--scripted-ego", "--ego", "Ego"], "bad");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("has no traffic signal \"99\""), "{err}");
}

/// A tilted entity (esmini's `drop-bike`: a bicycle teleported with a roll of 1.57 rad off its
/// carrier, lying on the road) is listed, its roll noted at its line, and refused as a
/// campaign at that line and column, with --scripted-ego too: paracosm's bodies stand
/// upright, and a lying bicycle's footprint is not its upright box. Its storyboard moves it
/// as esmini does (`scenarios/tests/xosc_esmini.rs`). A file that names no road network
/// (`parking_lot`) is refused as a campaign, naming what is missing.
#[test]
fn a_tilted_entity_or_a_world_without_roads_is_listed_and_refused_as_a_campaign() {
    let file = "tests/data/xosc/esmini/xosc/drop-bike.xosc";
    let (code, out, err) = xosc(&[file]);
    assert_eq!(code, 0, "{err}");
    assert!(
        format!("{out}{err}").contains("roll of 1.57 rad tilts its entity"),
        "{out}{err}"
    );
    let dir = tempfile::tempdir().unwrap();
    for (extra, name) in [(&[][..], "driven"), (&["--scripted-ego"][..], "scripted")] {
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
            .arg(file)
            .args(extra)
            .args(["--budget", "1", "--out"])
            .arg(dir.path().join(name))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("drop-bike.xosc:123:")
                && err.contains("paracosm's engine cannot tilt a body"),
            "{err}"
        );
        assert!(!dir.path().join(name).join("results.jsonl").exists());
    }
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg("tests/data/xosc/esmini/xosc/parking_lot.xosc")
        .args(["--scripted-ego", "--budget", "1", "--out"])
        .arg(dir.path().join("lot"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("has no RoadNetwork LogicFile"), "{err}");
}

/// A synchronization's target beyond its road's end (esmini's `ltap-od-relative-speed`: s =
/// 455 m on a road of 304.19 m) is taken at the road's end, as esmini takes it, with a
/// warning at load naming the action, the station asked and where the road ends; the test
/// runs to its end (its two cars meet, as the file times them, so its collision monitor
/// fails).
#[test]
fn a_synchronized_target_beyond_its_road_is_taken_at_its_end_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .arg("tests/data/xosc/esmini/xosc/ltap-od-relative-speed.xosc")
        .args(["--scripted-ego", "--budget", "1", "--out"])
        .arg(dir.path().join("out"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(
            "SynchronizeAction \"SyncActionNPC\": its target at s = 455 m lies beyond its road, \
             which ends at 304.19 m: it is taken at the road's end"
        ),
        "{err}"
    );
    let records = std::fs::read_to_string(dir.path().join("out/results.jsonl")).unwrap();
    assert_eq!(records.lines().count(), 1, "{err}");
    // It ran to its end (the file times the two cars to meet: its collision monitor fails).
    assert!(!records.contains("\"status\":\"error\""), "{records}");
    assert!(records.contains("\"status\":\"fail\""), "{records}");
}
