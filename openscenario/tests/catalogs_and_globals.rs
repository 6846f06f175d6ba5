//! Maneuver, trajectory, route and environment catalogs with their parameter assignments,
//! and the global actions (environment, parameter and variable) with their conditions, read
//! from `tests/data/xosc/written/catalogs_and_global_actions.xosc` (written here; esmini
//! moves it as paracosm does, `scenarios/tests/xosc_esmini.rs`).

use std::path::PathBuf;

use paracosm_openscenario::model::{Action, ConditionKind, Environment, Position, TrajectoryShape};
use paracosm_openscenario::params::ParamType;
use paracosm_openscenario::{read_scenario, Value};

fn written(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/xosc/written")
        .join(name)
}

/// Every action of the scenario's stories, in the file's order.
fn actions(s: &paracosm_openscenario::model::Scenario) -> Vec<&Action> {
    s.stories
        .iter()
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .flat_map(|g| &g.maneuvers)
        .flat_map(|m| &m.events)
        .flat_map(|e| &e.actions)
        .map(|a| &a.action)
        .collect()
}

#[test]
fn catalog_entries_take_their_references_assignments() {
    let s = read_scenario(&written("catalogs_and_global_actions.xosc"), &[]).unwrap();
    let acts = actions(&s);
    // The maneuver catalog's speed change, Target = 8 and Rate = 2 assigned (declared 20, 1).
    let slow = s.stories[0].acts[0].groups[0].maneuvers[0].events[0].actions[0].clone();
    match &slow.action {
        Action::Speed { target, dynamics } => {
            assert_eq!(
                *target,
                paracosm_openscenario::model::SpeedTarget::Absolute(8.0)
            );
            assert_eq!(dynamics.value, 2.0);
        }
        other => panic!("the catalog's maneuver: {other:?}"),
    }
    assert!(slow.pos.file.ends_with("Moves.xosc"), "{}", slow.pos);
    // The trajectory catalog's polyline, Across = 1 assigned (declared 0).
    let drift = acts
        .iter()
        .find_map(|a| match a {
            Action::FollowTrajectory {
                shape: TrajectoryShape::Polyline(v),
                position_mode,
                ..
            } => Some((v.clone(), *position_mode)),
            _ => None,
        })
        .expect("the trajectory");
    assert!(drift.1, "followingMode position");
    match &drift.0[1].1 {
        Position::Lane { offset, s, .. } => assert_eq!((*offset, *s), (1.0, 300.0)),
        other => panic!("{other:?}"),
    }
    // The route catalog's waypoints in Init, From = 15 assigned (declared 10).
    let route = s
        .init
        .iter()
        .find_map(|(_, a)| match &a.action {
            Action::AssignRoute { waypoints } => Some(waypoints.clone()),
            _ => None,
        })
        .expect("the route");
    match &route[0].0 {
        Position::Lane { s, .. } => assert_eq!(*s, 15.0),
        other => panic!("{other:?}"),
    }
    // The environment catalog's entry, Range = 50 assigned (declared 200).
    let env = acts
        .iter()
        .find_map(|a| match a {
            Action::Environment(e) if e.friction_scale.is_some() => Some(e.clone()),
            _ => None,
        })
        .expect("the catalog's environment");
    assert_eq!(
        env,
        Environment {
            time_of_day: Some((17.0 * 3600.0, false)),
            fog_visual_range_m: Some(50.0),
            friction_scale: Some(0.7),
            ..Environment::default()
        }
    );
}

#[test]
fn global_actions_and_value_conditions_are_read() {
    let s = read_scenario(&written("catalogs_and_global_actions.xosc"), &[]).unwrap();
    assert_eq!(
        s.variables,
        vec![("Count".to_string(), ParamType::Int, Value::Num(0.0))]
    );
    assert_eq!(s.init_global.len(), 1);
    assert!(matches!(
        &s.init_global[0].action,
        Action::Environment(Environment {
            time_of_day: Some((t, true)),
            fog_visual_range_m: Some(r),
            ..
        }) if *t == 12.0 * 3600.0 && *r == 100_000.0
    ));
    let acts = actions(&s);
    assert!(acts.iter().any(|a| matches!(a,
        Action::SetValue { name, variable: false, value: Value::Num(v) } if name == "Phase" && *v == 1.0)));
    assert!(acts.iter().any(|a| matches!(a,
        Action::ModifyValue { name, variable: true, multiply: false, by } if name == "Count" && *by == 2.0)));
    let conditions: Vec<&ConditionKind> = s
        .stories
        .iter()
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .flat_map(|g| &g.maneuvers)
        .flat_map(|m| &m.events)
        .filter_map(|e| e.start.as_ref())
        .flat_map(|t| t.0.iter().flatten())
        .map(|c| &c.kind)
        .collect();
    assert!(conditions
        .iter()
        .any(|c| matches!(c, ConditionKind::Parameter { name, .. } if name == "Phase")));
    assert!(conditions
        .iter()
        .any(|c| matches!(c, ConditionKind::Variable { name, .. } if name == "Count")));
}

/// A value set must be of its declared type: an int set to 1.5 is refused at the attribute.
#[test]
fn a_set_value_not_of_its_type_is_refused_at_its_attribute() {
    let text = std::fs::read_to_string(written("catalogs_and_global_actions.xosc")).unwrap();
    let bad = text.replace(r#"<SetAction value="1"/>"#, r#"<SetAction value="1.5"/>"#);
    assert_ne!(bad, text);
    // Read as a text from the written folder (its catalogs and map found there).
    let text = paracosm_openscenario::Text::new("bad_set.xosc", bad);
    let dir = written("");
    let e = paracosm_openscenario::read_scenario_text(&text, &dir, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad_set.xosc:"), "{e}");
    assert!(e.contains("Phase is of type int"), "{e}");
}

/// openPASS's configurations name a catalog's file as its location's `Directory`
/// (`<Directory path="VehicleModelsCatalog.xosc"/>`): that file is the location's one
/// catalog file, with a note; an entry of it is found as in a folder.
#[test]
fn a_catalog_location_naming_a_file_reads_that_file() {
    let dir = std::env::temp_dir().join(format!("paracosm-openpass-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("VehicleModelsCatalog.xosc"),
        r#"<OpenSCENARIO><FileHeader revMajor="1" revMinor="0" date="2026-11-29T00:00:00" description="c" author="x"/>
<Catalog name="VehicleCatalog"><Vehicle name="car_one" vehicleCategory="car"><BoundingBox><Center x="1.3" y="0" z="0.7"/><Dimensions width="1.8" length="4.4" height="1.4"/></BoundingBox><Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle></Catalog></OpenSCENARIO>"#,
    )
    .unwrap();
    let scenario = dir.join("s.xosc");
    std::fs::write(
        &scenario,
        r#"<OpenSCENARIO><FileHeader revMajor="1" revMinor="0" date="2026-11-29T00:00:00" description="openPASS" author="x"/>
<ParameterDeclarations/>
<CatalogLocations><VehicleCatalog><Directory path="VehicleModelsCatalog.xosc"/></VehicleCatalog></CatalogLocations>
<RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork>
<Entities><ScenarioObject name="Ego"><CatalogReference catalogName="VehicleCatalog" entryName="car_one"/></ScenarioObject></Entities>
<Storyboard><Init><Actions/></Init>
<StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="rising"><ByValueCondition><SimulationTimeCondition value="5" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
</Storyboard></OpenSCENARIO>"#,
    )
    .unwrap();
    let s = read_scenario(&scenario, &[]);
    std::fs::remove_dir_all(&dir).ok();
    let s = s.unwrap();
    assert_eq!(s.entities[0].dimensions_m, [4.4, 1.8, 1.4]);
    assert!(
        s.notes
            .iter()
            .any(|n| n.text.contains("names a file, as openPASS's")),
        "{:?}",
        s.notes
    );
}

/// esmini's `traffic_lights.xosc` (MPL-2.0, `tests/data/xosc/esmini/`): its
/// `InfrastructureAction`s set traffic signals by name to states as written, and its
/// `TrafficSignalCondition`s read them; a signal controller's action is refused at its
/// element (paracosm runs no signal controllers).
#[test]
fn traffic_signal_actions_and_conditions_are_read() {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/xosc/esmini/xosc/traffic_lights.xosc");
    let s = read_scenario(&file, &[]).expect("reads");
    let set: Vec<(&str, &str)> = s
        .init_global
        .iter()
        .filter_map(|a| match &a.action {
            Action::TrafficSignalState { signal, state } => Some((signal.as_str(), state.as_str())),
            _ => None,
        })
        .collect();
    assert_eq!(set.len(), 3, "{set:?}");
    assert_eq!(set[0].0, "1");
    assert!(set[0].1.contains(';'), "a state as written: {set:?}");
    let conditions: Vec<&ConditionKind> = s
        .stories
        .iter()
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .flat_map(|g| &g.maneuvers)
        .flat_map(|m| &m.events)
        .filter_map(|e| e.start.as_ref())
        .flat_map(|t| t.0.iter().flatten())
        .map(|c| &c.kind)
        .filter(|k| matches!(k, ConditionKind::TrafficSignal { .. }))
        .collect();
    assert!(!conditions.is_empty());
    let text = std::fs::read_to_string(&file).unwrap();
    let bad = text.replacen(
        r#"<TrafficSignalStateAction name="1" state="$TrafficLightGreen"/>"#,
        r#"<TrafficSignalControllerAction trafficSignalControllerRef="c" phase="go"/>"#,
        1,
    );
    assert_ne!(bad, text);
    let text = paracosm_openscenario::Text::new("bad_signal.xosc", bad);
    let e = paracosm_openscenario::read_scenario_text(&text, file.parent().unwrap(), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad_signal.xosc:45:"), "{e}");
    assert!(e.contains("<TrafficSignalControllerAction>"), "{e}");
}
