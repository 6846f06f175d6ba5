//! `SynchronizeAction`, a `TimeToCollisionCondition` to a position, a vehicle's
//! `Performance` and a catalog entry that reads a parameter it does not declare, read from
//! scenarios written here; and the refusals that name what paracosm cannot honour.

use paracosm_openscenario::model::{
    Action, ConditionKind, EntityTest, FinalSpeed, Performance, Position, PositionGap, SteadyState,
};
use paracosm_openscenario::read_scenario;

/// A scenario with two cars, `Ego` (its `Performance` element `performance`, if any) and
/// `Npc` (a pedestrian when `walker`), both placed on road 1, and one event on `Npc`
/// performing `action` (a `PrivateAction`'s content), started when `condition` (an
/// `EntityCondition`'s content on `Ego`) holds.
fn scenario(performance: &str, walker: bool, action: &str, condition: &str) -> String {
    let npc = if walker {
        r#"<Pedestrian name="p" pedestrianCategory="pedestrian" mass="80"><BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.6" height="1.8"/></BoundingBox><Properties/></Pedestrian>"#.to_string()
    } else {
        car("Performance maxSpeed=\"70\" maxAcceleration=\"200\" maxDeceleration=\"10\"/")
    };
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-11-30T00:00:00" description="sync" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork>
  <Entities>
    <ScenarioObject name="Ego">{ego}</ScenarioObject>
    <ScenarioObject name="Npc">{npc}</ScenarioObject>
  </Entities>
  <Storyboard>
    <Init><Actions>
      <Private entityRef="Ego"><PrivateAction><TeleportAction><Position><LanePosition roadId="1" laneId="-1" s="10"/></Position></TeleportAction></PrivateAction></Private>
      <Private entityRef="Npc"><PrivateAction><TeleportAction><Position><LanePosition roadId="1" laneId="-1" s="40"/></Position></TeleportAction></PrivateAction></Private>
    </Actions></Init>
    <Story name="S"><Act name="Act">
      <ManeuverGroup maximumExecutionCount="1" name="G">
        <Actors selectTriggeringEntities="false"><EntityRef entityRef="Npc"/></Actors>
        <Maneuver name="M"><Event name="E" priority="parallel"><Action name="a"><PrivateAction>{action}</PrivateAction></Action>
          <StartTrigger><ConditionGroup><Condition name="C" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Ego"/></TriggeringEntities><EntityCondition>{condition}</EntityCondition></ByEntityCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>
      </ManeuverGroup>
    </Act></Story>
    <StopTrigger><ConditionGroup><Condition name="End" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="10" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
        ego = car(performance),
    )
}

/// A car whose `Performance` element is `<{performance}>` (none when empty).
fn car(performance: &str) -> String {
    let performance = if performance.is_empty() {
        String::new()
    } else {
        format!("<{performance}>")
    };
    format!(
        r#"<Vehicle name="v" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox>{performance}<Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle>"#
    )
}

const PERFORMANCE: &str = r#"Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/"#;
const SPEED: &str = r#"<SpeedCondition value="1" rule="greaterThan"/>"#;

/// A `SynchronizeAction` with `attrs` on it and `final_speed` (a `FinalSpeed`'s content).
fn sync(attrs: &str, final_speed: &str) -> String {
    format!(
        r#"<SynchronizeAction masterEntityRef="Ego" {attrs}><TargetPositionMaster><LanePosition roadId="1" laneId="-1" s="100"/></TargetPositionMaster><TargetPosition><WorldPosition x="120" y="-1.75" h="0"/></TargetPosition>{final_speed}</SynchronizeAction>"#
    )
}

/// `text` read from a file of its own; the error's text when it is refused.
fn read(tag: &str, text: &str) -> Result<paracosm_openscenario::model::Scenario, String> {
    let dir = std::env::temp_dir().join(format!("paracosm-sync-{tag}-{}", std::process::id()));
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

/// A synchronization reads its master, both targets, its tolerances (0 m when absent, as
/// esmini has them) and its final speed: absolute with a steady state in time or distance,
/// or relative to the master's speed (a factor or a difference).
#[test]
fn a_synchronize_action_reads_its_targets_tolerances_and_final_speed() {
    let s = read(
        "abs",
        &scenario(
            PERFORMANCE,
            false,
            &sync(
                r#"targetToleranceMaster="1.5""#,
                r#"<FinalSpeed><AbsoluteSpeed value="4"><TargetTimeSteadyState time="2"/></AbsoluteSpeed></FinalSpeed>"#,
            ),
            SPEED,
        ),
    )
    .unwrap();
    let Action::Synchronize(y) = action(&s) else {
        panic!("{:?}", action(&s))
    };
    assert_eq!(y.master, 0);
    assert!(matches!(y.master_target, Position::Lane { .. }));
    assert!(matches!(y.target, Position::World { .. }));
    assert_eq!((y.master_tolerance_m, y.tolerance_m), (1.5, 0.0));
    assert_eq!(
        y.final_speed,
        Some(FinalSpeed {
            relative: None,
            value: 4.0,
            steady: Some(SteadyState::Time(2.0))
        })
    );
    let s = read(
        "rel",
        &scenario(
            PERFORMANCE,
            false,
            &sync(
                "",
                r#"<FinalSpeed><RelativeSpeedToMaster value="1.2" speedTargetValueType="factor"><TargetDistanceSteadyState distance="5"/></RelativeSpeedToMaster></FinalSpeed>"#,
            ),
            SPEED,
        ),
    )
    .unwrap();
    let Action::Synchronize(y) = action(&s) else {
        panic!("{:?}", action(&s))
    };
    assert_eq!(
        y.final_speed,
        Some(FinalSpeed {
            relative: Some(true),
            value: 1.2,
            steady: Some(SteadyState::Distance(5.0))
        })
    );
    // Without a final speed: none.
    let s = read("none", &scenario(PERFORMANCE, false, &sync("", ""), SPEED)).unwrap();
    let Action::Synchronize(y) = action(&s) else {
        panic!("{:?}", action(&s))
    };
    assert_eq!(y.final_speed, None);
}

/// What a synchronization cannot honour is refused at its line and column: a negative
/// tolerance, a value type neither delta nor factor, a steady state at 0 m/s (it would never
/// arrive), esmini's `TargetPositionSteadyState`, which no published schema has, a final
/// speed backwards and a negative steady state.
#[test]
fn a_synchronization_that_cannot_be_honoured_is_refused_where_it_is_written() {
    let cases = [
        (
            sync(r#"targetTolerance="-1""#, ""),
            "targetTolerance is a distance >= 0 m",
        ),
        (
            sync(
                "",
                r#"<FinalSpeed><RelativeSpeedToMaster value="1" speedTargetValueType="ratio"/></FinalSpeed>"#,
            ),
            "speedTargetValueType is delta or factor",
        ),
        (
            sync(
                "",
                r#"<FinalSpeed><AbsoluteSpeed value="0"><TargetDistanceSteadyState distance="5"/></AbsoluteSpeed></FinalSpeed>"#,
            ),
            "a steady state needs a final speed above 0 m/s",
        ),
        (
            sync(
                "",
                r#"<FinalSpeed><AbsoluteSpeed value="3"><TargetPositionSteadyState><WorldPosition x="0" y="0"/></TargetPositionSteadyState></AbsoluteSpeed></FinalSpeed>"#,
            ),
            "<TargetPositionSteadyState> in <AbsoluteSpeed> is not supported",
        ),
        (
            sync(
                "",
                r#"<FinalSpeed><AbsoluteSpeed value="-2"/></FinalSpeed>"#,
            ),
            "a final speed of -2 m/s drives backwards",
        ),
        (
            sync(
                "",
                r#"<FinalSpeed><RelativeSpeedToMaster value="1" speedTargetValueType="factor"><TargetDistanceSteadyState distance="-5"/></RelativeSpeedToMaster></FinalSpeed>"#,
            ),
            "a steady state's distance is >= 0, not -5",
        ),
    ];
    for (i, (action, why)) in cases.iter().enumerate() {
        let e = read(
            &format!("bad{i}"),
            &scenario(PERFORMANCE, false, action, SPEED),
        )
        .unwrap_err();
        assert!(e.contains(why), "{why:?} not in {e}");
        assert!(e.contains("s.xosc:"), "{e}");
    }
}

/// A vehicle's `Performance` is read with its values (large ones, `maxAcceleration="200"`,
/// are files' way of saying no limit, and are kept); a vehicle without one gets esmini's
/// defaults, noted; a pedestrian has no limits; a value of 0 is refused.
#[test]
fn a_vehicles_performance_is_read_and_a_pedestrian_has_none() {
    let action = r#"<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="linear" value="2" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget></SpeedAction></LongitudinalAction>"#;
    let s = read("perf", &scenario(PERFORMANCE, false, action, SPEED)).unwrap();
    assert_eq!(
        s.entities[0].performance,
        Performance {
            max_speed_mps: 50.0,
            max_acceleration_mps2: 5.0,
            max_deceleration_mps2: 9.0
        }
    );
    assert_eq!(s.entities[1].performance.max_acceleration_mps2, 200.0);
    let s = read("noperf", &scenario("", true, action, SPEED)).unwrap();
    assert_eq!(s.entities[0].performance, Performance::VEHICLE_DEFAULT);
    assert!(
        s.notes
            .iter()
            .any(|n| n.text.contains("has no <Performance>")),
        "{:?}",
        s.notes
    );
    assert_eq!(s.entities[1].performance, Performance::UNBOUNDED);
    let e = read(
        "zero",
        &scenario(
            r#"Performance maxSpeed="50" maxAcceleration="0" maxDeceleration="9"/"#,
            false,
            action,
            SPEED,
        ),
    )
    .unwrap_err();
    assert!(e.contains("maxAcceleration must be > 0"), "{e}");
}

/// A `TimeToCollisionCondition` may name a position as its target (esmini's
/// `TrigByTimeToCollision`): read with its rule, value and how it measures.
#[test]
fn a_time_to_collision_to_a_position_is_read() {
    let ttc = r#"<TimeToCollisionCondition value="3" freespace="false" rule="lessThan" relativeDistanceType="longitudinal" coordinateSystem="road"><TimeToCollisionConditionTarget><Position><LanePosition roadId="1" laneId="-1" s="80"/></Position></TimeToCollisionConditionTarget></TimeToCollisionCondition>"#;
    let action = r#"<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget></SpeedAction></LongitudinalAction>"#;
    let s = read("ttc", &scenario(PERFORMANCE, false, action, ttc)).unwrap();
    let start = s.stories[0].acts[0].groups[0].maneuvers[0].events[0]
        .start
        .as_ref()
        .unwrap();
    match &start.0[0][0].kind {
        ConditionKind::Entity {
            test:
                EntityTest::TimeToPosition(PositionGap {
                    position: Position::Lane { .. },
                    value,
                    kind,
                    frame,
                    ..
                }),
            ..
        } => {
            assert_eq!(*value, 3.0);
            assert_eq!((kind.as_str(), frame.as_str()), ("longitudinal", "road"));
        }
        other => panic!("{other:?}"),
    }
}

/// OpenSCENARIO 1.3's `ClothoidSpline` (segments with their curvatures, lengths and heading
/// offsets, the first one's `PositionStart`), a `TrajectoryPosition` on a trajectory and a
/// `FollowTrajectoryAction`'s `initialDistanceOffset` are read (a `PositionStart` after the
/// first segment restarts the spline there, as esmini lays it); a timed trajectory with an
/// offset and a spline's times are refused where they are written.
#[test]
fn clothoid_splines_trajectory_positions_and_initial_offsets_are_read() {
    let spline = |attrs: &str, second: &str| {
        format!(
            r#"<Trajectory name="T" closed="false"><Shape><ClothoidSpline {attrs}><ClothoidSplineSegment curvatureStart="0" curvatureEnd="0" length="10"><PositionStart><LanePosition roadId="1" laneId="-1" s="5"/></PositionStart></ClothoidSplineSegment><ClothoidSplineSegment curvatureStart="0" curvatureEnd="0.1" length="7" hOffset="0.2">{second}</ClothoidSplineSegment></ClothoidSpline></Shape></Trajectory>"#
        )
    };
    let follow = |offset: &str, timing: &str, trajectory: &str| {
        format!(
            r#"<RoutingAction><FollowTrajectoryAction initialDistanceOffset="{offset}"><TrajectoryRef>{trajectory}</TrajectoryRef><TimeReference>{timing}</TimeReference><TrajectoryFollowingMode followingMode="follow"/></FollowTrajectoryAction></RoutingAction>"#
        )
    };
    let s = read(
        "spline",
        &scenario(
            PERFORMANCE,
            false,
            &follow("3", "<None/>", &spline("", "")),
            SPEED,
        ),
    )
    .unwrap();
    match action(&s) {
        Action::FollowTrajectory {
            shape:
                paracosm_openscenario::model::TrajectoryShape::ClothoidSpline {
                    start,
                    segments,
                    restarts,
                    times,
                },
            initial_offset_m,
            ..
        } => {
            assert!(matches!(start, Some(Position::Lane { .. })));
            assert_eq!(segments, &vec![[0.0, 0.0, 10.0, 0.0], [0.0, 0.1, 7.0, 0.2]]);
            assert!(restarts.is_empty());
            assert!(times.is_none());
            assert_eq!(*initial_offset_m, 3.0);
        }
        other => panic!("{other:?}"),
    }
    let restarted = follow(
        "0",
        "<None/>",
        &spline(
            "",
            r#"<PositionStart><LanePosition roadId="1" laneId="-1" s="50"/></PositionStart>"#,
        ),
    );
    let s = read("restart", &scenario(PERFORMANCE, false, &restarted, SPEED)).unwrap();
    assert!(
        matches!(action(&s), Action::FollowTrajectory {
            shape: paracosm_openscenario::model::TrajectoryShape::ClothoidSpline { restarts, .. },
            ..
        } if restarts.len() == 1 && restarts[0].0 == 1),
        "{:?}",
        action(&s)
    );
    // A trajectory position: its s, t and shape.
    let target = format!(
        r#"<TrajectoryPosition s="12" t="-1"><TrajectoryRef>{}</TrajectoryRef></TrajectoryPosition>"#,
        spline("", "")
    );
    let synced = format!(
        r#"<SynchronizeAction masterEntityRef="Ego"><TargetPositionMaster><LanePosition roadId="1" laneId="-1" s="100"/></TargetPositionMaster><TargetPosition>{target}</TargetPosition></SynchronizeAction>"#
    );
    let s = read("trajpos", &scenario(PERFORMANCE, false, &synced, SPEED)).unwrap();
    let Action::Synchronize(y) = action(&s) else {
        panic!("{:?}", action(&s))
    };
    assert!(
        matches!(&y.target, Position::Trajectory { s, t, .. } if *s == 12.0 && *t == -1.0),
        "{:?}",
        y.target
    );
    let timing = r#"<Timing domainAbsoluteRelative="relative" scale="1" offset="0"/>"#;
    let polyline = r#"<Trajectory name="P" closed="false"><Shape><Polyline><Vertex time="0"><Position><WorldPosition x="0" y="0"/></Position></Vertex><Vertex time="2"><Position><WorldPosition x="10" y="0"/></Position></Vertex></Polyline></Shape></Trajectory>"#;
    let cases = [
        (
            follow("3", timing, polyline),
            "a timed trajectory's initialDistanceOffset is not supported",
        ),
        (
            follow("0", "<None/>", &spline(r#"timeEnd="4""#, "")),
            "give all of them, or none",
        ),
    ];
    for (i, (action, why)) in cases.iter().enumerate() {
        let e = read(
            &format!("spl{i}"),
            &scenario(PERFORMANCE, false, action, SPEED),
        )
        .unwrap_err();
        assert!(e.contains(why), "{why:?} not in {e}");
        assert!(e.contains("s.xosc:"), "{e}");
    }
    // A timed spline (1.3): each segment's timeStart and the spline's timeEnd; a closed
    // trajectory followed by its times is read (it ends at its last time, noted).
    let timed_spline = r#"<Trajectory name="T" closed="true"><Shape><ClothoidSpline timeEnd="6"><ClothoidSplineSegment curvatureStart="0" curvatureEnd="0" length="10" timeStart="0"/><ClothoidSplineSegment curvatureStart="0" curvatureEnd="0.1" length="7" timeStart="2.5"/></ClothoidSpline></Shape></Trajectory>"#;
    let s = read(
        "timed",
        &scenario(
            PERFORMANCE,
            false,
            &follow("0", timing, timed_spline),
            SPEED,
        ),
    )
    .unwrap();
    assert!(
        matches!(action(&s), Action::FollowTrajectory {
            shape: paracosm_openscenario::model::TrajectoryShape::ClothoidSpline { times: Some((starts, end)), .. },
            ..
        } if starts == &vec![0.0, 2.5] && *end == 6.0),
        "{:?}",
        action(&s)
    );
    assert!(s
        .notes
        .iter()
        .any(|n| n.text.contains("closed changes nothing")));
    let untimed_closed = timed_spline
        .replace(r#" timeEnd="6""#, "")
        .replace(r#" timeStart="0""#, "")
        .replace(r#" timeStart="2.5""#, "");
    let e = read(
        "closed",
        &scenario(
            PERFORMANCE,
            false,
            &follow("0", "<None/>", &untimed_closed),
            SPEED,
        ),
    )
    .unwrap_err();
    assert!(
        e.contains("a closed trajectory followed at the entity's speed is not supported"),
        "{e}"
    );
    let backwards = timed_spline.replace(r#"timeStart="2.5""#, r#"timeStart="7""#);
    let e = read(
        "backwards",
        &scenario(PERFORMANCE, false, &follow("0", timing, &backwards), SPEED),
    )
    .unwrap_err();
    assert!(e.contains("must increase"), "{e}");
}

/// A `LongitudinalDistanceAction`'s `DynamicConstraints` are read as written, each limit
/// left out `None` (the entity's `Performance` fills it when the storyboard runs); a limit
/// of 0 or below is refused at its attribute.
#[test]
fn a_distance_actions_dynamic_constraints_are_read_and_a_limit_of_zero_refused() {
    let keep = |constraints: &str| {
        format!(
            r#"<LongitudinalAction><LongitudinalDistanceAction entityRef="Ego" timeGap="2" freespace="true" continuous="true">{constraints}</LongitudinalDistanceAction></LongitudinalAction>"#
        )
    };
    let s = read(
        "dc",
        &scenario(
            PERFORMANCE,
            false,
            &keep(r#"<DynamicConstraints maxAcceleration="3" maxDeceleration="4" maxSpeed="30" maxDecelerationRate="1.5"/>"#),
            SPEED,
        ),
    )
    .unwrap();
    let Action::LongitudinalDistance { constraints, .. } = action(&s) else {
        panic!("not a distance action: {:?}", action(&s));
    };
    let c = constraints.expect("its constraints");
    assert_eq!(
        (
            c.max_acceleration_mps2,
            c.max_deceleration_mps2,
            c.max_speed_mps,
            c.max_acceleration_rate_mps3,
            c.max_deceleration_rate_mps3
        ),
        (Some(3.0), Some(4.0), Some(30.0), None, Some(1.5))
    );
    let s = read("nodc", &scenario(PERFORMANCE, false, &keep(""), SPEED)).unwrap();
    assert!(matches!(
        action(&s),
        Action::LongitudinalDistance {
            constraints: None,
            ..
        }
    ));
    let e = read(
        "dc0",
        &scenario(
            PERFORMANCE,
            false,
            &keep(r#"<DynamicConstraints maxAcceleration="0" maxDeceleration="4" maxSpeed="30"/>"#),
            SPEED,
        ),
    )
    .unwrap_err();
    assert!(
        e.contains("s.xosc:") && e.contains("maxAcceleration is a limit above 0, not 0"),
        "{e}"
    );
}

/// A `SpeedProfileAction` reads its mode, its reference entity (the `entityRef` attribute),
/// its constraints and its entries, a time left out as `None`; a negative time, a profile
/// without entries, an unknown mode and esmini's `<EntityRef>` child (not in the schema) are
/// refused at their line and column.
#[test]
fn a_speed_profile_reads_its_entries_and_refuses_what_it_cannot_honour() {
    let profile = |attrs: &str, inner: &str| {
        format!(
            r#"<LongitudinalAction><SpeedProfileAction {attrs}>{inner}</SpeedProfileAction></LongitudinalAction>"#
        )
    };
    let s = read(
        "profile",
        &scenario(
            PERFORMANCE,
            false,
            &profile(
                r#"followingMode="follow" entityRef="Ego""#,
                r#"<DynamicConstraints maxAcceleration="3" maxAccelerationRate="2"/><SpeedProfileEntry time="0" speed="1"/><SpeedProfileEntry time="2.5" speed="-4"/><SpeedProfileEntry speed="6"/>"#,
            ),
            SPEED,
        ),
    )
    .unwrap();
    let Action::SpeedProfile(p) = action(&s) else {
        panic!("{:?}", action(&s))
    };
    assert!(p.follow);
    assert_eq!(p.entity, Some(0));
    assert_eq!(
        p.entries,
        vec![(Some(0.0), 1.0), (Some(2.5), -4.0), (None, 6.0)]
    );
    let c = p.constraints.unwrap();
    assert_eq!(
        (
            c.max_acceleration_mps2,
            c.max_acceleration_rate_mps3,
            c.max_speed_mps
        ),
        (Some(3.0), Some(2.0), None)
    );
    let refused = |tag: &str, attrs: &str, inner: &str| {
        read(
            tag,
            &scenario(PERFORMANCE, false, &profile(attrs, inner), SPEED),
        )
        .unwrap_err()
    };
    let e = refused(
        "negative",
        r#"followingMode="position""#,
        r#"<SpeedProfileEntry time="-1" speed="3"/>"#,
    );
    assert!(
        e.contains(":17:") && e.contains("out of range for a duration"),
        "{e}"
    );
    let e = refused("empty", r#"followingMode="position""#, "");
    assert!(e.contains("needs a <SpeedProfileEntry>"), "{e}");
    let e = refused(
        "mode",
        r#"followingMode="smooth""#,
        r#"<SpeedProfileEntry time="1" speed="3"/>"#,
    );
    assert!(e.contains("followingMode is position or follow"), "{e}");
    let e = refused(
        "child",
        r#"followingMode="follow""#,
        r#"<EntityRef entityRef="Ego"/><SpeedProfileEntry time="1" speed="3"/>"#,
    );
    assert!(
        e.contains("<EntityRef> in <SpeedProfileAction> is not supported")
            && e.contains("entityRef attribute"),
        "{e}"
    );
}

/// An orientation's pitch or roll (a bicycle falling over) is read: listed among the
/// scenario's tilts at its attribute, and noted; a pitch and roll of 0 are no tilt.
#[test]
fn a_pitch_or_roll_is_read_as_a_tilt_at_its_attribute() {
    let teleport = |o: &str| {
        format!(
            r#"<TeleportAction><Position><RelativeObjectPosition entityRef="Ego" dx="1" dy="0">{o}</RelativeObjectPosition></Position></TeleportAction>"#
        )
    };
    let s = read(
        "tilt",
        &scenario(
            PERFORMANCE,
            false,
            &teleport(r#"<Orientation type="relative" h="0" p="0" r="1.5"/>"#),
            SPEED,
        ),
    )
    .unwrap();
    assert_eq!(s.tilts.len(), 1, "{:?}", s.tilts);
    let t = &s.tilts[0];
    assert!(t.pos.to_string().contains(":17:"), "{}", t.pos);
    assert!(
        t.text.contains("roll of 1.5 rad tilts its entity"),
        "{}",
        t.text
    );
    assert!(s.notes.iter().any(|n| n.text == t.text));
    let s = read(
        "flat",
        &scenario(
            PERFORMANCE,
            false,
            &teleport(r#"<Orientation type="relative" h="0.2" p="0" r="0"/>"#),
            SPEED,
        ),
    )
    .unwrap();
    assert!(s.tilts.is_empty());
}
