//! Controller actions (`AssignControllerAction`, `OverrideControllerValueAction`) and files
//! written for CARLA's scenario_runner (its left-handed frame), read from scenarios written
//! here; and the refusals that name what paracosm cannot honour.

use paracosm_openscenario::model::{Action, Position};
use paracosm_openscenario::read_scenario;

/// A scenario of revision `1.minor` with `description`, one car `Ego` placed at `position`
/// (a `Position`'s content), and one event on it performing `action` (a `PrivateAction`'s
/// content).
fn scenario(minor: u32, description: &str, position: &str, action: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="{minor}" date="2026-11-30T00:00:00" description="{description}" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork>
  <Entities>
    <ScenarioObject name="Ego"><Vehicle name="v" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox><Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject>
  </Entities>
  <Storyboard>
    <Init><Actions><Private entityRef="Ego"><PrivateAction><TeleportAction><Position>{position}</Position></TeleportAction></PrivateAction></Private></Actions></Init>
    <Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="G">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
        <Maneuver name="M"><Event name="E" priority="parallel"><Action name="a"><PrivateAction>{action}</PrivateAction></Action>
          <StartTrigger><ConditionGroup><Condition name="C" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>
    </Act></Story>
    <StopTrigger><ConditionGroup><Condition name="End" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="10" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#
    )
}

/// `text` read from a file of its own; the error's text when it is refused.
fn read(tag: &str, text: &str) -> Result<paracosm_openscenario::model::Scenario, String> {
    let dir = std::env::temp_dir().join(format!("paracosm-ctl-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("s.xosc");
    std::fs::write(&file, text).unwrap();
    let out = read_scenario(&file, &[]).map_err(|e| e.to_string());
    std::fs::remove_dir_all(&dir).ok();
    out
}

/// The event's action.
fn action(s: &paracosm_openscenario::model::Scenario) -> &Action {
    &s.stories[0].acts[0].groups[0].maneuvers[0].events[0].actions[0].action
}

const WORLD: &str = r#"<WorldPosition x="10" y="2" h="0.5"/>"#;
const CARLA_AGENT: &str = r#"<ControllerAction><AssignControllerAction><Controller name="HeroAgent"><Properties><Property name="module" value="external_control"/></Properties></Controller></AssignControllerAction><OverrideControllerValueAction><Throttle value="0" active="false"/><Brake value="0" active="false"/><Clutch value="0" active="false"/><ParkingBrake value="0" active="false"/><SteeringWheel value="0" active="false"/><Gear number="0" active="false"/></OverrideControllerValueAction></ControllerAction>"#;

/// Without `activateLateral` or `activateLongitudinal` (OpenSCENARIO 1.0 and 1.1 cannot say
/// them) an assignment activates nothing, as the standard and esmini read it; in a file
/// written for CARLA it takes the entity over at once, as scenario_runner reads it (noted).
/// Its kind is CARLA's `module` property; an override whose values are all inactive is read
/// as doing nothing.
#[test]
fn an_assigned_controller_is_active_at_once_only_in_carlas_reading() {
    let s = read("a10", &scenario(0, "plain", WORLD, CARLA_AGENT)).unwrap();
    assert!(!action(&s).hands_over(), "{:?}", action(&s));
    let s = read("a10c", &scenario(0, "CARLA:Test", WORLD, CARLA_AGENT)).unwrap();
    match action(&s) {
        Action::AssignController {
            controller,
            kind,
            lateral,
            longitudinal,
        } => {
            assert_eq!(controller, "HeroAgent");
            assert_eq!(kind.as_deref(), Some("external_control"));
            assert_eq!((*lateral, *longitudinal), (Some(true), Some(true)));
        }
        other => panic!("{other:?}"),
    }
    assert!(action(&s).hands_over());
    for text in ["takes the entity over at once", "overrides nothing"] {
        assert!(
            s.notes.iter().any(|n| n.text.contains(text)),
            "{text}: {:?}",
            s.notes
        );
    }
}

/// From 1.2 the assignment says what it activates: without `activateLateral` or
/// `activateLongitudinal` it activates nothing (an `ActivateControllerAction` does, later),
/// as esmini reads it; esmini's `esminiController` property is the kind.
#[test]
fn an_assigned_controller_of_1_2_activates_what_it_says() {
    let assign = |attrs: &str| {
        format!(
            r#"<ControllerAction><AssignControllerAction {attrs}><Controller name="acc"><Properties><Property name="esminiController" value="ACCController"/></Properties></Controller></AssignControllerAction></ControllerAction>"#
        )
    };
    let s = read("a12", &scenario(2, "plain", WORLD, &assign(""))).unwrap();
    assert!(!action(&s).hands_over(), "{:?}", action(&s));
    assert!(
        matches!(action(&s), Action::AssignController { kind: Some(k), .. } if k == "ACCController")
    );
    let s = read(
        "a12b",
        &scenario(2, "plain", WORLD, &assign(r#"activateLongitudinal="true""#)),
    )
    .unwrap();
    assert!(action(&s).hands_over());
    // 1.3 puts the controller in an ObjectController.
    let s = read(
        "a13",
        &scenario(
            3,
            "plain",
            WORLD,
            r#"<ControllerAction><AssignControllerAction activateLateral="true"><ObjectController><Controller name="drv"><Properties/></Controller></ObjectController></AssignControllerAction></ControllerAction>"#,
        ),
    )
    .unwrap();
    assert!(
        matches!(action(&s), Action::AssignController { controller, kind: None, .. } if controller == "drv")
    );
}

/// An active override (a pedal, the wheel, a gear) is refused at its element: paracosm's
/// vehicles have none to override.
#[test]
fn an_active_override_is_refused_at_its_element() {
    let text = scenario(
        1,
        "plain",
        WORLD,
        r#"<ControllerAction><OverrideControllerValueAction><Throttle value="0.5" active="true"/></OverrideControllerValueAction></ControllerAction>"#,
    );
    let err = read("ovr", &text).unwrap_err();
    let line = text.lines().position(|l| l.contains("Throttle")).unwrap() + 1;
    assert!(err.contains(&format!("s.xosc:{line}:")), "{err}");
    assert!(err.contains("active override of the Throttle"), "{err}");
}

/// A file whose description starts with `CARLA:` is in CARLA's left-handed frame, as
/// scenario_runner reads it: a world position's y and heading, a road position's t, a lane
/// position's offset and a relative position's dy are read with their signs reversed.
#[test]
fn a_carla_file_is_read_in_carlas_left_handed_frame() {
    for (desc, sign) in [("plain", 1.0), ("CARLA:Example", -1.0)] {
        let s = read("frame", &scenario(0, desc, WORLD, CARLA_AGENT)).unwrap();
        match &s.init[0].1.action {
            Action::Teleport(Position::World { x, y, h }) => {
                assert_eq!((*x, *y, *h), (10.0, sign * 2.0, Some(sign * 0.5)), "{desc}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(s.carla, sign < 0.0);
        let road = r#"<RoadPosition roadId="1" s="20" t="2.75"/>"#;
        let s = read("road", &scenario(0, desc, road, CARLA_AGENT)).unwrap();
        assert!(
            matches!(&s.init[0].1.action, Action::Teleport(Position::Road { t, .. }) if *t == sign * 2.75),
            "{desc}: {:?}",
            s.init[0].1.action
        );
        let lane = r#"<LanePosition roadId="1" laneId="-1" s="20" offset="1"/>"#;
        let s = read("lane", &scenario(0, desc, lane, CARLA_AGENT)).unwrap();
        assert!(
            matches!(&s.init[0].1.action, Action::Teleport(Position::Lane { offset, .. }) if *offset == sign),
            "{desc}: {:?}",
            s.init[0].1.action
        );
    }
}

/// `--carla` reads any file as CARLA's (a file written for CARLA by another tool, whose
/// description does not say `CARLA:`): its world y is reversed too.
#[test]
fn a_file_set_told_so_reads_any_file_as_carlas() {
    let dir = std::env::temp_dir().join(format!("paracosm-ctl-told-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("s.xosc");
    std::fs::write(&file, scenario(0, "plain", WORLD, CARLA_AGENT)).unwrap();
    let files = paracosm_openscenario::FileSet::new().as_carla(true);
    let s = paracosm_openscenario::read_scenario_in(&files, &file, &[]).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert!(s.carla);
    assert!(
        matches!(&s.init[0].1.action, Action::Teleport(Position::World { y, .. }) if *y == -2.0),
        "{:?}",
        s.init[0].1.action
    );
    assert!(
        action(&s).hands_over(),
        "CARLA's assignment takes over at once"
    );
}

/// scenario_runner adds a relative object position's offsets along the world's axes, as a
/// relative world position's: in CARLA's reading it is one, its `dy` reversed.
#[test]
fn a_carla_relative_object_position_is_along_the_worlds_axes() {
    let rel = r#"<RelativeObjectPosition entityRef="Ego" dx="5" dy="1"/>"#;
    for (desc, world, dy) in [("plain", false, 1.0), ("CARLA:Rel", true, -1.0)] {
        let s = read("rel", &scenario(0, desc, rel, CARLA_AGENT)).unwrap();
        match &s.init[0].1.action {
            Action::Teleport(Position::RelativeWorld { dx, dy: got, .. }) => {
                assert!(world, "{desc}");
                assert_eq!((*dx, *got), (5.0, dy));
            }
            Action::Teleport(Position::RelativeObject { dy: got, .. }) => {
                assert!(!world, "{desc}");
                assert_eq!(*got, dy);
            }
            other => panic!("{other:?}"),
        }
    }
}

/// An empty `<Action/>` (CARLA's `ChangingWeather` writes one in an event that waits for
/// 10^7 s): in a file read as CARLA's, an action that does nothing and completes at once, as
/// scenario_runner builds no behaviour for it, noted where it is written; in any other file it
/// is refused at its element (the schema asks one action).
#[test]
fn an_empty_action_does_nothing_only_in_carlas_reading() {
    let empty = |description: &str| {
        scenario(1, description, WORLD, "")
            .replace(
                r#"<Action name="a"><PrivateAction></PrivateAction></Action>"#,
                r#"<Action name="a"/>"#,
            )
            .replace(
                r#"value="1" rule="greaterThan""#,
                r#"value="10000000" rule="greaterThan""#,
            )
    };
    let text = empty("CARLA:empty");
    assert!(text.contains(r#"<Action name="a"/>"#) && text.contains("10000000"));
    let s = read("empty-carla", &text).expect("read as CARLA's");
    assert_eq!(*action(&s), Action::Nothing);
    assert!(action(&s).is_global());
    assert!(
        s.notes
            .iter()
            .any(|n| n.text.contains("an empty <Action>") && n.pos.to_string().contains("s.xosc:")),
        "{:?}",
        s.notes
    );
    let err = read("empty-other", &empty("plain")).expect_err("refused");
    assert!(
        err.contains("an <Action> holds one <PrivateAction> or <GlobalAction>, not nothing"),
        "{err}"
    );
}

/// A `LateralDistanceAction`: from OpenSCENARIO 1.1 its side is `displacement`'s and a
/// negative distance is read as its magnitude (noted, as esmini reads it); in 1.0 the
/// distance is signed (no `displacement`), and in CARLA's frame reversed; without a distance
/// the one at the start is kept; a distance in lane or trajectory coordinates is refused at
/// its attribute.
#[test]
fn a_lateral_distance_reads_its_side_by_the_files_version_and_frame() {
    let keep = |attrs: &str| {
        format!(
            r#"<LateralAction><LateralDistanceAction entityRef="Ego" freespace="false" continuous="true" {attrs}><DynamicConstraints maxAcceleration="2" maxSpeed="3"/></LateralDistanceAction></LateralAction>"#
        )
    };
    let of = |s: &paracosm_openscenario::model::Scenario| match action(s) {
        Action::LateralDistance {
            distance_m,
            displacement,
            frame,
            constraints,
            ..
        } => (
            *distance_m,
            displacement.clone(),
            frame.clone(),
            constraints.map(|c| (c.max_acceleration_mps2, c.max_speed_mps)),
        ),
        other => panic!("{other:?}"),
    };
    let s = read(
        "lat-13",
        &scenario(
            3,
            "plain",
            WORLD,
            &keep(
                r#"distance="-2" displacement="rightToReferencedEntity" coordinateSystem="road""#,
            ),
        ),
    )
    .unwrap();
    assert_eq!(
        of(&s),
        (
            Some(2.0),
            "rightToReferencedEntity".into(),
            "road".into(),
            Some((Some(2.0), Some(3.0)))
        )
    );
    assert!(s
        .notes
        .iter()
        .any(|n| n.text.contains("a lateral distance of -2 m is read as 2 m")));
    let s = read(
        "lat-10",
        &scenario(0, "plain", WORLD, &keep(r#"distance="-2""#)),
    )
    .unwrap();
    assert_eq!(of(&s).0, Some(-2.0));
    assert_eq!((of(&s).1.as_str(), of(&s).2.as_str()), ("any", "entity"));
    let s = read(
        "lat-carla",
        &scenario(0, "CARLA:lat", WORLD, &keep(r#"distance="-2""#)),
    )
    .unwrap();
    assert_eq!(of(&s).0, Some(2.0), "CARLA's frame reverses the side");
    let s = read("lat-none", &scenario(2, "plain", WORLD, &keep(""))).unwrap();
    assert_eq!(of(&s).0, None);
    let err = read(
        "lat-lane",
        &scenario(
            2,
            "plain",
            WORLD,
            &keep(r#"distance="1" coordinateSystem="lane""#),
        ),
    )
    .unwrap_err();
    assert!(
        err.contains("a lateral distance in lane coordinates is not supported"),
        "{err}"
    );
    assert!(err.contains("s.xosc:"), "{err}");
}
