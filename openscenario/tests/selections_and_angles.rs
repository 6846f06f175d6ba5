//! Entity selections in actors and triggering entities, collision conditions by type, angle
//! conditions (OpenSCENARIO 1.3), lateral distances in lane coordinates and empty bounding
//! boxes, read from scenarios written here; and the refusals that name what paracosm cannot
//! honour.

use paracosm_openscenario::model::{AngleTest, ConditionKind, EntityTest};
use paracosm_openscenario::read_scenario;

/// A scenario of a car `A`, a pedestrian `P`, a truck `T` and a box `X`, with `selections`
/// in its `Entities`, one maneuver group of `actors` whose event starts on `condition`
/// (an `EntityCondition`'s content) with `triggering` as its triggering entities.
fn scenario(selections: &str, actors: &str, triggering: &str, condition: &str) -> String {
    let vehicle = |name: &str, category: &str| {
        format!(
            r#"<ScenarioObject name="{name}"><Vehicle name="v" vehicleCategory="{category}"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox><Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject>"#
        )
    };
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="3" date="2026-11-29T00:00:00" description="selections" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork>
  <Entities>
    {a}
    {selections}
    <ScenarioObject name="P"><Pedestrian name="p" mass="80" pedestrianCategory="pedestrian"><BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.3" height="1.8"/></BoundingBox><Properties/></Pedestrian></ScenarioObject>
    {t}
    <ScenarioObject name="X"><MiscObject name="x" miscObjectCategory="obstacle" mass="50"><BoundingBox><Center x="0" y="0" z="0.5"/><Dimensions width="1" length="1" height="1"/></BoundingBox><Properties/></MiscObject></ScenarioObject>
  </Entities>
  <Storyboard>
    <Init><Actions/></Init>
    <Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="G">
        <Actors selectTriggeringEntities="false">{actors}</Actors>
        <Maneuver name="M"><Event name="E" priority="parallel"><Action name="a"><PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="3"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction></Action>
          <StartTrigger><ConditionGroup><Condition name="C" delay="0" conditionEdge="none"><ByEntityCondition>
            <TriggeringEntities triggeringEntitiesRule="any">{triggering}</TriggeringEntities>
            <EntityCondition>{condition}</EntityCondition>
          </ByEntityCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>
    </Act></Story>
    <StopTrigger><ConditionGroup><Condition name="End" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="10" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
        a = vehicle("A", "car"),
        t = vehicle("T", "truck"),
    )
}

/// `text` read from a file of its own; the error's text when it is refused.
fn read(tag: &str, text: &str) -> Result<paracosm_openscenario::model::Scenario, String> {
    let dir = std::env::temp_dir().join(format!("paracosm-sel-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("s.xosc");
    std::fs::write(&file, text).unwrap();
    let out = read_scenario(&file, &[]).map_err(|e| e.to_string());
    std::fs::remove_dir_all(&dir).ok();
    out
}

/// Fails unless one of `s`'s notes contains `text`.
fn assert_noted(s: &paracosm_openscenario::model::Scenario, text: &str) {
    assert!(
        s.notes.iter().any(|n| n.text.contains(text)),
        "no note says {text:?}: {:?}",
        s.notes
    );
}

fn group_and_condition(
    s: &paracosm_openscenario::model::Scenario,
) -> (Vec<usize>, Vec<usize>, EntityTest) {
    let g = &s.stories[0].acts[0].groups[0];
    let event = &g.maneuvers[0].events[0];
    let c = &event.start.as_ref().expect("a start trigger").0[0][0];
    match &c.kind {
        ConditionKind::Entity { entities, test, .. } => {
            (g.actors.clone(), entities.clone(), test.clone())
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_selection_stands_for_its_members_among_actors_and_triggering_entities() {
    // Entities in the order A, P, T, X; Vehicles = A and T by type; Moving = Vehicles and P
    // (a selection of a selection, declared before it); a member named twice is one actor.
    let selections = r#"<EntitySelection name="Moving"><Members><EntityRef entityRef="P"/><EntityRef entityRef="Vehicles"/></Members></EntitySelection>
    <EntitySelection name="Vehicles"><Members><ByType objectType="vehicle"/></Members></EntitySelection>"#;
    let text = scenario(
        selections,
        r#"<EntityRef entityRef="Vehicles"/><EntityRef entityRef="A"/>"#,
        r#"<EntityRef entityRef="Moving"/>"#,
        r#"<CollisionCondition><ByType type="pedestrian"/></CollisionCondition>"#,
    );
    let s = read("members", &text).unwrap();
    let (actors, triggering, test) = group_and_condition(&s);
    assert_eq!(actors, vec![0, 2], "A and T");
    assert_eq!(triggering, vec![0, 1, 2], "A, P and T");
    assert_eq!(test, EntityTest::CollisionByType("pedestrian".into()));
}

#[test]
fn angle_conditions_read_their_frames_and_refuse_what_paracosm_cannot_compare() {
    let read_condition = |tag: &str, condition: &str| {
        read(
            tag,
            &scenario(
                "",
                r#"<EntityRef entityRef="A"/>"#,
                r#"<EntityRef entityRef="A"/>"#,
                condition,
            ),
        )
        .map(|s| group_and_condition(&s).2)
    };
    assert_eq!(
        read_condition(
            "world",
            r#"<AngleCondition angleType="heading" angle="0.5" angleTolerance="0.1"/>"#
        )
        .unwrap(),
        EntityTest::Angle(AngleTest {
            angle: 0.5,
            tolerance: 0.1,
            frame: "world".into()
        })
    );
    assert_eq!(
        read_condition("rel", r#"<RelativeAngleCondition entityRef="T" angleType="heading" angle="-0.2" angleTolerance="0.05" coordinateSystem="lane"/>"#).unwrap(),
        EntityTest::RelativeAngle {
            entity: 2,
            test: AngleTest { angle: -0.2, tolerance: 0.05, frame: "lane".into() }
        }
    );
    for (tag, condition, want) in [
        (
            "roll",
            r#"<AngleCondition angleType="roll" angle="0" angleTolerance="0.1"/>"#,
            "an angle condition on the roll is not supported",
        ),
        (
            "traj",
            r#"<AngleCondition angleType="heading" angle="0" angleTolerance="0.1" coordinateSystem="trajectory"/>"#,
            "trajectory's coordinate system is not supported",
        ),
        (
            "neg",
            r#"<AngleCondition angleType="heading" angle="0" angleTolerance="-0.1"/>"#,
            "angleTolerance is an angle >= 0 rad",
        ),
        (
            "ext",
            r#"<CollisionCondition><ByType type="external"/></CollisionCondition>"#,
            "a collision with an external object is not supported",
        ),
    ] {
        let e = read_condition(tag, condition).unwrap_err();
        assert!(e.contains(want), "{tag}: {e}");
        assert!(e.contains("s.xosc:"), "{tag}: no place in {e}");
    }
}

#[test]
fn a_selection_is_refused_where_one_entity_is_meant_and_when_it_includes_itself() {
    let speed = r#"<SpeedCondition value="1" rule="greaterThan"/>"#;
    let cases = [
        (
            "loop",
            r#"<EntitySelection name="Loop"><Members><EntityRef entityRef="Again"/></Members></EntitySelection>
    <EntitySelection name="Again"><Members><EntityRef entityRef="Loop"/></Members></EntitySelection>"#,
            "",
            speed,
            "includes itself",
        ),
        (
            "one",
            r#"<EntitySelection name="Cars"><Members><ByType objectType="vehicle"/></Members></EntitySelection>"#,
            r#"<EntityRef entityRef="Cars"/>"#,
            r#"<RelativeSpeedCondition entityRef="Cars" value="1" rule="greaterThan"/>"#,
            "\"Cars\" is an entity selection",
        ),
        (
            "empty",
            r#"<EntitySelection name="Walkers"><Members><ByType objectType="pedestrian"/></Members></EntitySelection><EntitySelection name="Empty"><Members/></EntitySelection>"#,
            "",
            speed,
            "selects no entity",
        ),
    ];
    for (tag, selections, actors, condition, want) in cases {
        let text = scenario(
            selections,
            actors,
            r#"<EntityRef entityRef="A"/>"#,
            condition,
        );
        let e = read(tag, &text).unwrap_err();
        assert!(e.contains(want), "{tag}: {e}");
    }
}

#[test]
fn a_lateral_distance_in_lane_coordinates_is_read_as_esmini_reads_it_and_a_trajectorys_is_refused()
{
    let condition = |frame: &str| {
        format!(
            r#"<RelativeDistanceCondition entityRef="T" relativeDistanceType="lateral" coordinateSystem="{frame}" value="2" rule="lessThan" freespace="false"/>"#
        )
    };
    let trigger = r#"<EntityRef entityRef="A"/>"#;
    let s = read("lane", &scenario("", trigger, trigger, &condition("lane"))).unwrap();
    match group_and_condition(&s).2 {
        EntityTest::RelativeDistance(g) => {
            assert_eq!((g.frame.as_str(), g.kind.as_str()), ("lane", "lateral"))
        }
        other => panic!("{other:?}"),
    }
    assert_noted(&s, "measured across the road in metres");
    let e = read(
        "traj",
        &scenario("", trigger, trigger, &condition("trajectory")),
    )
    .unwrap_err();
    assert!(
        e.contains("trajectory's coordinate system is not supported"),
        "{e}"
    );
}

#[test]
fn a_box_with_a_side_of_0_m_is_read_as_written_with_a_note_and_a_negative_one_is_refused() {
    let trigger = r#"<EntityRef entityRef="A"/>"#;
    let speed = r#"<SpeedCondition value="1" rule="greaterThan"/>"#;
    let text = scenario("", trigger, trigger, speed).replace(
        r#"<Dimensions width="1" length="1" height="1"/>"#,
        r#"<Dimensions width="0" length="0" height="0"/>"#,
    );
    let s = read("zero", &text).unwrap();
    assert_eq!(s.entities[3].dimensions_m, [0.0, 0.0, 0.0]);
    assert_noted(&s, "x's bounding box has a side of 0 m");
    let e = read(
        "negative",
        &text.replace(r#"width="0" length="0""#, r#"width="0" length="-1""#),
    )
    .unwrap_err();
    assert!(
        e.contains("-1 is out of range for a size (m): paracosm accepts 0 to 100"),
        "{e}"
    );
}
