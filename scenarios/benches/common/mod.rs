//! What the benches share: generated OpenSCENARIO and OpenDRIVE files.

// Each bench that includes this module uses part of it.
#![allow(dead_code)]

/// A scenario on esmini's straight road (relative to `tests/data/xosc/written/`) of `n`
/// events in one maneuver: event 0 starts at 0.1 s, event `i` when event `i − 1` ends; each
/// sets the speed of the one entity.
pub fn event_chain(n: usize) -> String {
    let mut s = String::from(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="1" date="2026-11-29T00:00:00" description="a chain of events" author="paracosm"/>
  <RoadNetwork><LogicFile filepath="../esmini/xodr/straight_500m.xodr"/></RoadNetwork>
  <Entities>
    <ScenarioObject name="hero"><Vehicle name="v" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox><Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject>
  </Entities>
  <Storyboard>
    <Init><Actions><Private entityRef="hero">
      <PrivateAction><TeleportAction><Position><RoadPosition roadId="1" s="20" t="-1.5"/></Position></TeleportAction></PrivateAction>
      <PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="10"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>
    </Private></Actions></Init>
    <Story name="s"><Act name="a"><ManeuverGroup maximumExecutionCount="1" name="g"><Actors selectTriggeringEntities="false"><EntityRef entityRef="hero"/></Actors><Maneuver name="m">
"#,
    );
    for i in 0..n {
        let start = if i == 0 {
            r#"<ByValueCondition><SimulationTimeCondition value="0.1" rule="greaterThan"/></ByValueCondition>"#.to_owned()
        } else {
            format!(
                r#"<ByValueCondition><StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="e{}" state="endTransition"/></ByValueCondition>"#,
                i - 1
            )
        };
        s.push_str(&format!(
            r#"<Event name="e{i}" priority="parallel"><Action name="a{i}"><PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="{}"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction></Action><StartTrigger><ConditionGroup><Condition name="c{i}" delay="0" conditionEdge="none">{start}</Condition></ConditionGroup></StartTrigger></Event>
"#,
            10 + i % 2
        ));
    }
    s.push_str(
        r#"</Maneuver></ManeuverGroup><StartTrigger><ConditionGroup><Condition name="go" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Act></Story>
    <StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="2" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#,
    );
    s
}

/// An OpenDRIVE map of one road `length_m` long with one driving lane each way, each 3.5 m
/// wide all along: an arc turning through 0.9 of a circle, in records of 1 km, so that a
/// 100 km road fits the physics' extent (a map at most 131 km across, each record counted as
/// reaching its length from its start).
pub fn ring_road(length_m: f64) -> String {
    let k = 0.9 * std::f64::consts::TAU / length_m;
    let mut geometry = String::new();
    let mut s = 0.0;
    while s < length_m {
        let len = (length_m - s).min(1000.0);
        let (x, y, hdg) = ((k * s).sin() / k, (1.0 - (k * s).cos()) / k, k * s);
        geometry.push_str(&format!(
            r#"<geometry s="{s}" x="{x}" y="{y}" hdg="{hdg}" length="{len}"><arc curvature="{k}"/></geometry>"#
        ));
        s += len;
    }
    let lane = |id: i32| {
        format!(
            r#"<lane id="{id}" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>"#
        )
    };
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="ring" version="1"/>
  <road name="r" length="{length_m}" id="0" junction="-1">
    <link/>
    <planView>{geometry}</planView>
    <lanes>
      <laneSection s="0">
        <left>{}</left>
        <center><lane id="0" type="none" level="false"><link/></lane></center>
        <right>{}</right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>
"#,
        lane(1),
        lane(-1),
    )
}
