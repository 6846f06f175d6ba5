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
        "v's <Performance> limits are not applied",
    ] {
        assert!(out.contains(want), "`{want}` not in\n{out}");
    }
}

/// A variation file with a `ValueSetDistribution` (parameters assigned together) beside a
/// single-parameter one: the sets become one discrete parameter and the grid multiplies.
#[test]
fn value_sets_become_one_parameter_of_their_sets() {
    let dir = tempfile::tempdir().unwrap();
    let alks = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks");
    let template =
        alks.join("concrete_scenarios/alks_scenario_4_2_3_crossing_pedestrian_template.xosc");
    let variation = dir.path().join("sets.xosc");
    std::fs::write(
        &variation,
        format!(
            r#"<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-26T00:00:00" description="sets" author="paracosm"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="{}"/>
    <Deterministic>
      <DeterministicSingleParameterDistribution parameterName="Ego_InitSpeed_Ve0_kph">
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
      </DeterministicMultiParameterDistribution>
    </Deterministic>
  </ParameterValueDistribution>
</OpenSCENARIO>
"#,
            template.display()
        ),
    )
    .unwrap();
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
