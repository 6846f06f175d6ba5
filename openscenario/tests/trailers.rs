//! Vehicle combinations: a vehicle's `Trailer` (written in it, from a catalog, or a
//! `TrailerRef` to another entity), its `TrailerHitch` and the trailer's `TrailerCoupler`,
//! and `TrailerAction`; and the refusals that name what cannot be coupled.

use paracosm_openscenario::model::Action;
use paracosm_openscenario::read_scenario;

/// A vehicle named `name` whose extra elements (after its `Axles`) are `extra`.
fn vehicle(name: &str, extra: &str) -> String {
    format!(
        r#"<Vehicle name="{name}" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox><Performance maxSpeed="70" maxAcceleration="5" maxDeceleration="10"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles>{extra}<Properties/></Vehicle>"#
    )
}

/// A scenario whose entities are `entities` (`ScenarioObject`s), `Init` placing `Tow` (and
/// `Loose`, when there is one), and one event on `Tow` performing `action` (a
/// `PrivateAction`'s content) at 1 s.
fn scenario(entities: &str, action: &str) -> String {
    let loose = if entities.contains("\"Loose\"") {
        r#"<Private entityRef="Loose"><PrivateAction><TeleportAction><Position><LanePosition roadId="1" laneId="-1" s="60"/></Position></TeleportAction></PrivateAction></Private>"#
    } else {
        ""
    };
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="3" date="2026-11-30T00:00:00" description="trailers" author="paracosm"/>
  <CatalogLocations><VehicleCatalog><Directory path="cat"/></VehicleCatalog></CatalogLocations>
  <RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork>
  <Entities>{entities}</Entities>
  <Storyboard>
    <Init><Actions>
      <Private entityRef="Tow"><PrivateAction><TeleportAction><Position><LanePosition roadId="1" laneId="-1" s="30"/></Position></TeleportAction></PrivateAction></Private>{loose}
    </Actions></Init>
    <Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="G">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="Tow"/></Actors>
        <Maneuver name="M"><Event name="E" priority="parallel"><Action name="a"><PrivateAction>{action}</PrivateAction></Action>
          <StartTrigger><ConditionGroup><Condition name="C" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>
    </Act></Story>
    <StopTrigger/>
  </Storyboard>
</OpenSCENARIO>
"#
    )
}

/// A catalog of one trailer, `box_trailer`, coupled 3.25 m ahead of its reference point.
fn catalog() -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="3" date="2026-11-30T00:00:00" description="cat" author="paracosm"/>
<Catalog name="VehicleCatalog">{}</Catalog></OpenSCENARIO>
"#,
        vehicle("box_trailer", r#"<TrailerCoupler dx="3.25"/>"#)
    )
}

/// Reads `text` as `s.xosc` beside the catalog folder `cat`.
fn read(tag: &str, text: &str) -> Result<paracosm_openscenario::model::Scenario, String> {
    let dir = std::env::temp_dir().join(format!("paracosm-trailers-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("cat")).unwrap();
    std::fs::write(dir.join("cat/VehicleCatalog.xosc"), catalog()).unwrap();
    let file = dir.join("s.xosc");
    std::fs::write(&file, text).unwrap();
    let out = read_scenario(&file, &[]).map_err(|e| e.to_string());
    std::fs::remove_dir_all(&dir).ok();
    out
}

const WAIT: &str = r#"<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget></SpeedAction></LongitudinalAction>"#;

/// A trailer written in its tow (inline, and from a catalog inside that) is an entity of its
/// own, named as esmini names it (`Tow+`, `Tow++`), after its tow, with its hitch and
/// coupler; a `TrailerRef` hitches another entity.
#[test]
fn a_vehicle_combination_becomes_entities_named_as_esmini_names_them() {
    let inner = r#"<Trailer><Trailer name="t2"><CatalogReference catalogName="VehicleCatalog" entryName="box_trailer"/></Trailer></Trailer>"#;
    let middle = vehicle(
        "dolly",
        &format!(r#"<TrailerHitch dx="-1.0"/><TrailerCoupler dx="2.0"/>{inner}"#),
    );
    let tow = vehicle(
        "truck",
        &format!(
            r#"<TrailerHitch dx="1.0"/><Trailer><Trailer name="t1">{middle}</Trailer></Trailer>"#
        ),
    );
    let s = read(
        "inline",
        &scenario(
            &format!(r#"<ScenarioObject name="Tow">{tow}</ScenarioObject>"#),
            WAIT,
        ),
    )
    .expect("reads");
    let names: Vec<&str> = s.entities.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["Tow", "Tow+", "Tow++"]);
    assert_eq!(s.entities[0].trailer, Some(1));
    assert_eq!(s.entities[1].trailer, Some(2));
    assert_eq!(s.entities[2].trailer, None);
    assert_eq!(s.entities[0].hitch_dx_m, Some(1.0));
    assert_eq!(s.entities[1].coupler_dx_m, Some(2.0));
    assert_eq!(s.entities[2].coupler_dx_m, Some(3.25));
    assert!(s.entities[2]
        .pos
        .to_string()
        .contains("VehicleCatalog.xosc"));

    // A TrailerRef to another entity, which may be declared after its tow.
    let tow = vehicle(
        "car",
        r#"<TrailerHitch dx="-1.2"/><Trailer><TrailerRef entityRef="Loose"/></Trailer>"#,
    );
    let s = read(
        "ref",
        &scenario(
            &format!(
                r#"<ScenarioObject name="Tow">{tow}</ScenarioObject><ScenarioObject name="Loose"><CatalogReference catalogName="VehicleCatalog" entryName="box_trailer"/></ScenarioObject>"#
            ),
            r#"<TrailerAction><DisconnectTrailerAction/></TrailerAction>"#,
        ),
    )
    .expect("reads");
    assert_eq!(s.entities[0].trailer, Some(1));
    let a = &s.stories[0].acts[0].groups[0].maneuvers[0].events[0].actions[0].action;
    assert_eq!(*a, Action::Trailer(None));
}

/// `ConnectTrailerAction` names the trailer it hitches.
#[test]
fn a_trailer_action_names_its_trailer() {
    let tow = vehicle("car", r#"<TrailerHitch dx="-1.2"/>"#);
    let s = read(
        "connect",
        &scenario(
            &format!(
                r#"<ScenarioObject name="Tow">{tow}</ScenarioObject><ScenarioObject name="Loose"><CatalogReference catalogName="VehicleCatalog" entryName="box_trailer"/></ScenarioObject>"#
            ),
            r#"<TrailerAction><ConnectTrailerAction trailerRef="Loose"/></TrailerAction>"#,
        ),
    )
    .expect("reads");
    let a = &s.stories[0].acts[0].groups[0].maneuvers[0].events[0].actions[0].action;
    assert_eq!(*a, Action::Trailer(Some(1)));
    assert_eq!(a.kind_name(), "ConnectTrailerAction");
}

/// What cannot be coupled is refused where it is written: a tow without a hitch, a trailer
/// without a coupler, a reference to no entity or to a vehicle that is no trailer, and a
/// trailer that two vehicles tow.
#[test]
fn a_combination_that_cannot_be_coupled_is_refused_where_it_is_written() {
    let cases = [
        (
            "no-hitch",
            format!(
                r#"<ScenarioObject name="Tow">{}</ScenarioObject>"#,
                vehicle(
                    "car",
                    r#"<Trailer><Trailer name="t"><CatalogReference catalogName="VehicleCatalog" entryName="box_trailer"/></Trailer></Trailer>"#
                )
            ),
            "needs a <TrailerHitch>",
        ),
        (
            "no-coupler",
            format!(
                r#"<ScenarioObject name="Tow">{}</ScenarioObject>"#,
                vehicle(
                    "car",
                    &format!(
                        r#"<TrailerHitch dx="-1"/><Trailer><Trailer name="t">{}</Trailer></Trailer>"#,
                        vehicle("plain", "")
                    )
                )
            ),
            "needs a <TrailerCoupler>",
        ),
        (
            "no-entity",
            format!(
                r#"<ScenarioObject name="Tow">{}</ScenarioObject>"#,
                vehicle(
                    "car",
                    r#"<TrailerHitch dx="-1"/><Trailer><TrailerRef entityRef="Nobody"/></Trailer>"#
                )
            ),
            "no entity is named \"Nobody\"",
        ),
        (
            "not-a-trailer",
            format!(
                r#"<ScenarioObject name="Tow">{}</ScenarioObject><ScenarioObject name="Loose">{}</ScenarioObject>"#,
                vehicle(
                    "car",
                    r#"<TrailerHitch dx="-1"/><Trailer><TrailerRef entityRef="Loose"/></Trailer>"#
                ),
                vehicle("plain", "")
            ),
            "is no trailer",
        ),
        (
            "two-tows",
            format!(
                r#"<ScenarioObject name="Tow">{}</ScenarioObject><ScenarioObject name="Other">{}</ScenarioObject><ScenarioObject name="Loose"><CatalogReference catalogName="VehicleCatalog" entryName="box_trailer"/></ScenarioObject>"#,
                vehicle(
                    "car",
                    r#"<TrailerHitch dx="-1"/><Trailer><TrailerRef entityRef="Loose"/></Trailer>"#
                ),
                vehicle(
                    "car",
                    r#"<TrailerHitch dx="-1"/><Trailer><TrailerRef entityRef="Loose"/></Trailer>"#
                )
            ),
            "a trailer has one tow",
        ),
    ];
    for (tag, entities, why) in cases {
        let err = read(tag, &scenario(&entities, WAIT)).expect_err(tag);
        assert!(err.contains(why), "{tag}: {err}");
        assert!(
            err.contains("s.xosc:") || err.contains("VehicleCatalog.xosc:"),
            "{tag}: {err}"
        );
    }
}

/// esmini's `refpoint_x_offset` property puts a vehicle's reference point that far ahead of
/// its rear axle: it is read, and the bounding box's centre is taken from the reference
/// point; a value that is not a length is refused where it is written.
#[test]
fn a_reference_point_ahead_of_the_rear_axle_is_read_from_esminis_property() {
    let with = |value: &str| {
        vehicle("car", "").replace(
            "<Properties/>",
            &format!(r#"<Properties><Property name="model_id" value="0"/><Property name="refpoint_x_offset" value="{value}"/></Properties>"#),
        )
    };
    let entities = format!(
        r#"<ScenarioObject name="Tow">{}</ScenarioObject>"#,
        with("2.8")
    );
    let s = read("refpoint", &scenario(&entities, WAIT)).unwrap();
    let tow = &s.entities[0];
    assert_eq!(tow.refpoint_dx_m, Some(2.8));
    // The box's centre, 1.4 m ahead of the rear axle, is 1.4 m behind the reference point.
    assert!(
        (tow.centre_m[0] - (1.4 - 2.8)).abs() < 1e-12,
        "{:?}",
        tow.centre_m
    );
    // Without the property the reference point is the rear axle.
    let plain = format!(
        r#"<ScenarioObject name="Tow">{}</ScenarioObject>"#,
        vehicle("car", "")
    );
    let s = read("refpoint-none", &scenario(&plain, WAIT)).unwrap();
    assert_eq!(s.entities[0].refpoint_dx_m, None);
    assert_eq!(s.entities[0].centre_m[0], 1.4);
    let bad = format!(
        r#"<ScenarioObject name="Tow">{}</ScenarioObject>"#,
        with("front")
    );
    let err = read("refpoint-bad", &scenario(&bad, WAIT)).unwrap_err();
    assert!(err.contains("s.xosc:") && err.contains("value"), "{err}");
}
