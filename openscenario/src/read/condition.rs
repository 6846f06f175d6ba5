//! Triggers and conditions (OpenSCENARIO 1.3 User Guide, "Conditions and triggers").

use roxmltree::Node;

use super::{position, Reader};
use crate::error::XoscError;
use crate::model::{
    AngleTest, Clearance, Condition, ConditionKind, Edge, EntityTest, Gap, PositionGap, Rule,
    Trigger,
};
use crate::quantity::Quantity;
use crate::support;
use crate::xml::{choice, elements, need};

/// A `StartTrigger` or `StopTrigger`: its condition groups.
pub(super) fn trigger(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Trigger, XoscError> {
    let mut groups = Vec::new();
    for g in elements(node) {
        if g.tag_name().name() != "ConditionGroup" {
            return Err(r
                .text
                .unsupported(g, "a trigger holds <ConditionGroup> elements only"));
        }
        let mut conditions = Vec::new();
        let mut criteria = 0;
        for c in elements(g) {
            if c.tag_name().name() != "Condition" {
                return Err(r
                    .text
                    .unsupported(c, "a condition group holds <Condition> elements only"));
            }
            if let Some(name) = carla_criterion(r, c) {
                r.note(
                    c,
                    format!(
                        "{name} is one of CARLA's evaluation criteria written as a condition on \
                         no parameter: it is not a condition, and paracosm's monitors (collision, \
                         off-road) judge the test, not it"
                    ),
                );
                criteria += 1;
                continue;
            }
            conditions.push(condition(r, c)?);
        }
        if conditions.is_empty() && criteria == 0 {
            return Err(r
                .text
                .invalid(g, "a condition group needs at least one condition"));
        }
        if !conditions.is_empty() {
            groups.push(conditions);
        }
    }
    Ok(Trigger(groups))
}

/// The name of condition `c` when it is one of CARLA's evaluation criteria
/// (scenario_runner's convention: a condition named `criteria_...` whose
/// `ParameterCondition` names no declared parameter, `parameterRef=""` or CARLA's
/// `distance_success`); `None` for any other condition.
fn carla_criterion(r: &Reader<'_>, c: Node<'_, '_>) -> Option<String> {
    let name = c.attribute("name")?;
    if !name.starts_with("criteria_") {
        return None;
    }
    let p = crate::xml::child(
        crate::xml::child(c, "ByValueCondition")?,
        "ParameterCondition",
    )?;
    let reference = p.attribute("parameterRef")?.trim_start_matches('$');
    let declared = r.globals.iter().any(|(n, _)| n == reference);
    (!declared).then(|| name.to_owned())
}

fn condition(r: &Reader<'_>, c: Node<'_, '_>) -> Result<Condition, XoscError> {
    let delay_s = r.scope.num_in(r.text, c, "delay", Quantity::Duration)?;
    if delay_s.is_nan() || delay_s < 0.0 {
        return Err(XoscError::Invalid {
            pos: r.text.attr_pos(c, "delay"),
            reason: format!("a condition's delay must be >= 0 s, not {delay_s}"),
        });
    }
    let edge = match r.scope.string(r.text, c, "conditionEdge")?.as_str() {
        "none" => Edge::None,
        "rising" => Edge::Rising,
        "falling" => Edge::Falling,
        "risingOrFalling" => Edge::RisingOrFalling,
        other => {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(c, "conditionEdge"),
                reason: format!(
                    "conditionEdge is none, rising, falling or risingOrFalling, not {other:?}"
                ),
            })
        }
    };
    let (by, tag) = choice(r.text, c, &support::CONDITION)?;
    let kind = if tag == "ByValueCondition" {
        by_value(r, by)?
    } else {
        by_entity(r, by)?
    };
    // A condition's name is a label nothing in the standard refers to; esmini's expressions
    // also concatenate texts (`${Brake + _ + $Gap}`), which paracosm's do not: a name that
    // does not evaluate is kept as written, with a note.
    let name = match r.scope.string(r.text, c, "name") {
        Ok(name) => name,
        Err(_)
            if c.attribute("name")
                .is_some_and(|n| n.trim_start().starts_with("${")) =>
        {
            let raw = c.attribute("name").unwrap_or_default().to_string();
            r.note(
                c,
                format!(
                    "this condition's name {raw:?} {}",
                    support::CONDITION_NAME.note
                ),
            );
            raw
        }
        Err(e) => return Err(e),
    };
    Ok(Condition {
        name,
        delay_s,
        edge,
        kind,
        pos: r.text.pos(c),
    })
}

/// A `rule` attribute.
pub(super) fn rule(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Rule, XoscError> {
    Ok(match r.scope.string(r.text, node, "rule")?.as_str() {
        "greaterThan" => Rule::Gt,
        "lessThan" => Rule::Lt,
        "equalTo" => Rule::Eq,
        "greaterOrEqual" => Rule::Ge,
        "lessOrEqual" => Rule::Le,
        "notEqualTo" => Rule::Ne,
        other => {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(node, "rule"),
                reason: format!(
                    "a rule is greaterThan, lessThan, equalTo, greaterOrEqual, lessOrEqual or notEqualTo, not {other:?}"
                ),
            })
        }
    })
}

fn by_value(r: &Reader<'_>, by: Node<'_, '_>) -> Result<ConditionKind, XoscError> {
    let (v, tag) = choice(r.text, by, &support::BY_VALUE_CONDITION)?;
    Ok(match tag {
        "TrafficSignalCondition" => ConditionKind::TrafficSignal {
            signal: r.scope.string(r.text, v, "name")?,
            state: r.scope.string(r.text, v, "state")?,
        },
        "SimulationTimeCondition" => ConditionKind::SimulationTime {
            rule: rule(r, v)?,
            value: r.scope.num_in(r.text, v, "value", Quantity::Time)?,
        },
        "StoryboardElementStateCondition" => {
            let one_of = |attr: &str, allowed: &[&str]| -> Result<String, XoscError> {
                let v_ = r.scope.string(r.text, v, attr)?;
                if allowed.contains(&v_.as_str()) {
                    Ok(v_)
                } else {
                    Err(XoscError::Invalid {
                        pos: r.text.attr_pos(v, attr),
                        reason: format!("{attr} is one of {}, not {v_:?}", allowed.join(", ")),
                    })
                }
            };
            ConditionKind::ElementState {
                element_type: one_of(
                    "storyboardElementType",
                    &[
                        "story",
                        "act",
                        "maneuverGroup",
                        "maneuver",
                        "event",
                        "action",
                    ],
                )?,
                element: r.scope.string(r.text, v, "storyboardElementRef")?,
                state: one_of(
                    "state",
                    &[
                        "startTransition",
                        "endTransition",
                        "stopTransition",
                        "skipTransition",
                        "completeState",
                        "runningState",
                        "standbyState",
                    ],
                )?,
            }
        }
        _ => {
            let variable = tag == "VariableCondition";
            let attr = if variable {
                "variableRef"
            } else {
                "parameterRef"
            };
            let name = r.name_ref(v, attr)?;
            let declared = if variable { &r.variables } else { &r.globals };
            if !declared.iter().any(|(n, _)| *n == name) {
                return Err(XoscError::Invalid {
                    pos: r.text.attr_pos(v, attr),
                    reason: if variable {
                        format!("variable {name:?} is not declared in the scenario's <VariableDeclarations>")
                    } else {
                        format!(
                            "parameter {name:?} is not declared in the scenario's own \
                             <ParameterDeclarations> (a condition reads the scenario's \
                             parameters while a test runs)"
                        )
                    },
                });
            }
            let (rule, value) = (rule(r, v)?, r.scope.string(r.text, v, "value")?);
            if variable {
                ConditionKind::Variable { name, rule, value }
            } else {
                ConditionKind::Parameter { name, rule, value }
            }
        }
    })
}

fn by_entity(r: &Reader<'_>, by: Node<'_, '_>) -> Result<ConditionKind, XoscError> {
    let t = need(r.text, by, "TriggeringEntities")?;
    let all = match r
        .scope
        .string(r.text, t, "triggeringEntitiesRule")?
        .as_str()
    {
        "any" => false,
        "all" => true,
        other => {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(t, "triggeringEntitiesRule"),
                reason: format!("triggeringEntitiesRule is any or all, not {other:?}"),
            })
        }
    };
    let mut entities = Vec::new();
    for e in elements(t) {
        if e.tag_name().name() != "EntityRef" {
            return Err(r
                .text
                .unsupported(e, "triggering entities are <EntityRef> elements"));
        }
        for k in r.entities(e, "entityRef")? {
            if !entities.contains(&k) {
                entities.push(k);
            }
        }
    }
    if entities.is_empty() {
        return Err(r.text.invalid(t, "no triggering entity is named"));
    }
    let (c, tag) = choice(
        r.text,
        need(r.text, by, "EntityCondition")?,
        &support::ENTITY_CONDITION,
    )?;
    Ok(ConditionKind::Entity {
        entities,
        all,
        test: entity_test(r, c, tag)?,
    })
}

/// Where a distance is measured (`coordinateSystem`, 1.1+; 1.0's `alongRoute="true"` is
/// `road`) and what distance (`relativeDistanceType`; 1.0's `cartesianDistance` is
/// `euclidianDistance`), with the standard's defaults (`entity`, `euclidianDistance`).
fn measure(r: &Reader<'_>, c: Node<'_, '_>) -> Result<(String, String), XoscError> {
    let (s, t) = (&r.scope, r.text);
    let one_of = |attr: &str, v: String, allowed: &[&str]| -> Result<String, XoscError> {
        if allowed.contains(&v.as_str()) {
            Ok(v)
        } else {
            Err(XoscError::Invalid {
                pos: t.attr_pos(c, attr),
                reason: format!("{attr} is one of {}, not {v:?}", allowed.join(", ")),
            })
        }
    };
    let frame = match (
        s.opt_string(t, c, "coordinateSystem")?,
        s.opt_bool(t, c, "alongRoute")?,
    ) {
        (Some(f), _) => one_of(
            "coordinateSystem",
            f,
            &["entity", "lane", "road", "trajectory"],
        )?,
        (None, Some(true)) => "road".to_string(),
        (None, _) => "entity".to_string(),
    };
    let kind = match s.opt_string(t, c, "relativeDistanceType")? {
        Some(k) if k == "cartesianDistance" => "euclidianDistance".to_string(),
        Some(k) => one_of(
            "relativeDistanceType",
            k,
            &["longitudinal", "lateral", "euclidianDistance"],
        )?,
        None => "euclidianDistance".to_string(),
    };
    if let Some(a) = s.opt_string(t, c, "routingAlgorithm")? {
        if a != "undefined" {
            return Err(XoscError::Unsupported {
                pos: t.attr_pos(c, "routingAlgorithm"),
                reason: format!("routingAlgorithm {a:?} is not supported: paracosm measures along the road the entity is on"),
            });
        }
    }
    Ok((frame, kind))
}

/// Refuses a distance measured along a trajectory (`coordinateSystem="trajectory"`), and
/// notes that a lateral or euclidean distance in lane coordinates is measured across the
/// road in metres, as in road coordinates (esmini's reading: its lane and road coordinates
/// give the same lateral distance).
fn not_along_a_trajectory(
    r: &Reader<'_>,
    c: Node<'_, '_>,
    frame: &str,
    kind: &str,
) -> Result<(), XoscError> {
    if frame == "trajectory" {
        return Err(XoscError::Unsupported {
            pos: r.text.attr_pos(c, "coordinateSystem"),
            reason: format!(
                "a {kind} distance in the trajectory's coordinate system is not supported: \
                 paracosm measures in the entity's, the road's and the lanes' coordinates"
            ),
        });
    }
    if frame == "lane" && kind != "longitudinal" {
        r.note(
            c,
            format!(
                "a {kind} distance in lane coordinates is measured across the road in metres \
                 (the difference of the two positions' t), as in road coordinates, as esmini \
                 measures it"
            ),
        );
    }
    Ok(())
}

/// Reads 1.2's `direction` on speed and acceleration conditions: `longitudinal` is the speed
/// or acceleration along the entity's heading, which is what paracosm compares (its entities
/// face the way they move, so the longitudinal part is the whole); `lateral` and `vertical`
/// are refused.
fn no_direction(r: &Reader<'_>, c: Node<'_, '_>) -> Result<(), XoscError> {
    match r.scope.opt_string(r.text, c, "direction")?.as_deref() {
        None | Some("longitudinal") => Ok(()),
        Some(other) => Err(XoscError::Unsupported {
            pos: r.text.attr_pos(c, "direction"),
            reason: format!("a speed or acceleration condition's direction {other:?} is not supported: paracosm compares the speed or acceleration along the entity's heading (direction=\"longitudinal\")"),
        }),
    }
}

/// The [`Gap`] of condition `c`, whose other entity `target` names, its value a quantity
/// `q` (a time gap or a distance).
fn gap(
    r: &Reader<'_>,
    c: Node<'_, '_>,
    target: Node<'_, '_>,
    q: Quantity,
) -> Result<Gap, XoscError> {
    let (frame, kind) = measure(r, c)?;
    not_along_a_trajectory(r, c, &frame, &kind)?;
    Ok(Gap {
        entity: r.entity(target, "entityRef")?,
        rule: rule(r, c)?,
        value: r.scope.num_in(r.text, c, "value", q)?,
        freespace: r.scope.bool(r.text, c, "freespace")?,
        frame,
        kind,
    })
}

/// A condition's gap to the position `target`, its value in `q` (a time or a distance).
fn position_gap(
    r: &Reader<'_>,
    c: Node<'_, '_>,
    target: Node<'_, '_>,
    q: Quantity,
) -> Result<PositionGap, XoscError> {
    let (frame, kind) = measure(r, c)?;
    not_along_a_trajectory(r, c, &frame, &kind)?;
    Ok(PositionGap {
        position: position::read(r, target)?,
        rule: rule(r, c)?,
        value: r.scope.num_in(r.text, c, "value", q)?,
        freespace: r.scope.bool(r.text, c, "freespace")?,
        frame,
        kind,
    })
}

fn entity_test(r: &Reader<'_>, c: Node<'_, '_>, tag: &str) -> Result<EntityTest, XoscError> {
    let (s, t) = (&r.scope, r.text);
    if matches!(
        tag,
        "SpeedCondition" | "RelativeSpeedCondition" | "AccelerationCondition"
    ) {
        no_direction(r, c)?;
    }
    Ok(match tag {
        "TimeHeadwayCondition" => EntityTest::TimeHeadway(gap(r, c, c, Quantity::Duration)?),
        "TimeToCollisionCondition" => {
            let (target, tag) = choice(
                t,
                need(t, c, "TimeToCollisionConditionTarget")?,
                &support::TTC_TARGET,
            )?;
            if tag == "EntityRef" {
                EntityTest::TimeToCollision(gap(r, c, target, Quantity::Duration)?)
            } else {
                EntityTest::TimeToPosition(position_gap(r, c, target, Quantity::Duration)?)
            }
        }
        "RelativeDistanceCondition" => {
            if c.attribute("relativeDistanceType").is_none() {
                return Err(t.invalid(
                    c,
                    "a relative distance condition needs relativeDistanceType",
                ));
            }
            EntityTest::RelativeDistance(gap(r, c, c, Quantity::Distance)?)
        }
        "DistanceCondition" => EntityTest::Distance(position_gap(
            r,
            c,
            need(t, c, "Position")?,
            Quantity::Distance,
        )?),
        "ReachPositionCondition" => EntityTest::ReachPosition {
            position: position::read(r, need(t, c, "Position")?)?,
            tolerance: s.num_in(t, c, "tolerance", Quantity::Size)?,
        },
        "SpeedCondition" => EntityTest::Speed {
            rule: rule(r, c)?,
            value: s.num_in(t, c, "value", Quantity::Speed)?,
        },
        "RelativeSpeedCondition" => EntityTest::RelativeSpeed {
            entity: r.entity(c, "entityRef")?,
            rule: rule(r, c)?,
            value: s.num_in(t, c, "value", Quantity::Speed)?,
        },
        "AccelerationCondition" => EntityTest::Acceleration {
            rule: rule(r, c)?,
            value: s.num_in(t, c, "value", Quantity::Acceleration)?,
        },
        "StandStillCondition" => {
            EntityTest::Standstill(s.num_in(t, c, "duration", Quantity::Duration)?)
        }
        "TraveledDistanceCondition" => {
            EntityTest::TraveledDistance(s.num_in(t, c, "value", Quantity::Distance)?)
        }
        "EndOfRoadCondition" => {
            EntityTest::EndOfRoad(s.num_in(t, c, "duration", Quantity::Duration)?)
        }
        "OffroadCondition" => {
            EntityTest::Offroad(s.num_in(t, c, "duration", Quantity::Duration)?)
        }
        "AngleCondition" => EntityTest::Angle(angle_test(r, c, "world")?),
        "RelativeClearanceCondition" => EntityTest::RelativeClearance(clearance(r, c)?),
        "RelativeAngleCondition" => EntityTest::RelativeAngle {
            entity: r.entity(c, "entityRef")?,
            test: angle_test(r, c, "entity")?,
        },
        _ => {
            let (target, tag) = choice(t, c, &support::COLLISION_TARGET)?;
            if tag == "EntityRef" {
                EntityTest::Collision(Some(r.entity(target, "entityRef")?))
            } else {
                EntityTest::CollisionByType(object_type(r, target)?)
            }
        }
    })
}

/// The `type` of a collision condition's `ByType`: `vehicle`, `pedestrian` or
/// `miscellaneous`; `external` (an object outside the scenario) is refused, as paracosm's
/// world holds the file's entities only.
fn object_type(r: &Reader<'_>, by: Node<'_, '_>) -> Result<String, XoscError> {
    let kind = r.scope.string(r.text, by, "type")?;
    match kind.as_str() {
        k if crate::model::OBJECT_TYPES.contains(&k) => Ok(kind),
        "external" => Err(XoscError::Unsupported {
            pos: r.text.attr_pos(by, "type"),
            reason: "a collision with an external object is not supported: paracosm's world \
                     holds the scenario's own entities only"
                .into(),
        }),
        other => Err(XoscError::Invalid {
            pos: r.text.attr_pos(by, "type"),
            reason: format!(
                "type is one of {}, external, not {other:?}",
                crate::model::OBJECT_TYPES.join(", ")
            ),
        }),
    }
}

/// The [`AngleTest`] of an `AngleCondition` or `RelativeAngleCondition` `c`, whose
/// `coordinateSystem` defaults to `default`. Only `angleType="heading"` is read: paracosm's
/// storyboard moves its entities in the plane of the map, with no pitch or roll to compare;
/// a trajectory's frame is refused as in distance conditions.
fn angle_test(r: &Reader<'_>, c: Node<'_, '_>, default: &str) -> Result<AngleTest, XoscError> {
    let (s, t) = (&r.scope, r.text);
    let kind = s.string(t, c, "angleType")?;
    if kind != "heading" {
        let reason = if matches!(kind.as_str(), "pitch" | "roll") {
            format!(
                "an angle condition on the {kind} is not supported: paracosm's storyboard \
                 moves its entities in the plane of the map, and compares headings only"
            )
        } else {
            format!("angleType is heading, pitch or roll, not {kind:?}")
        };
        return Err(XoscError::Unsupported {
            pos: t.attr_pos(c, "angleType"),
            reason,
        });
    }
    let frame = s
        .opt_string(t, c, "coordinateSystem")?
        .unwrap_or_else(|| default.to_owned());
    if !matches!(frame.as_str(), "world" | "entity" | "road" | "lane") {
        let reason = if frame == "trajectory" {
            "an angle condition in the trajectory's coordinate system is not supported: \
             paracosm compares headings in the world's, the entity's, the road's and the \
             lane's"
                .to_owned()
        } else {
            format!(
                "coordinateSystem is one of world, entity, road, lane, trajectory, not {frame:?}"
            )
        };
        return Err(XoscError::Unsupported {
            pos: t.attr_pos(c, "coordinateSystem"),
            reason,
        });
    }
    let tolerance = s.num_in(t, c, "angleTolerance", Quantity::Angle)?;
    if tolerance < 0.0 {
        return Err(XoscError::Invalid {
            pos: t.attr_pos(c, "angleTolerance"),
            reason: format!("angleTolerance is an angle >= 0 rad, not {tolerance}"),
        });
    }
    Ok(AngleTest {
        angle: s.num_in(t, c, "angle", Quantity::Angle)?,
        tolerance,
        frame,
    })
}

/// A `RelativeClearanceCondition` (1.2): its distances (`distanceForward`,
/// `distanceBackward`, 0 m when absent), `freeSpace` (esmini's `freespace` spelling read
/// too), `oppositeLanes`, its `RelativeLaneRange`s and its `EntityRef`s.
///
/// # Errors
/// Invalid for a negative distance, a range whose `from` exceeds its `to`, a missing
/// `freeSpace` or `oppositeLanes`; unsupported for another child.
fn clearance(r: &Reader<'_>, c: Node<'_, '_>) -> Result<Clearance, XoscError> {
    let (s, t) = (&r.scope, r.text);
    let distance = |attr: &str| -> Result<f64, XoscError> {
        let d = s.opt_num_in(t, c, attr, Quantity::Distance)?.unwrap_or(0.0);
        if d < 0.0 {
            return Err(XoscError::Invalid {
                pos: t.attr_pos(c, attr),
                reason: format!("{attr} is a distance >= 0 m, not {d}"),
            });
        }
        Ok(d)
    };
    let freespace = match s.opt_bool(t, c, "freeSpace")? {
        Some(b) => b,
        None => match s.opt_bool(t, c, "freespace")? {
            Some(b) => b,
            None => s.bool(t, c, "freeSpace")?,
        },
    };
    let mut out = Clearance {
        forward_m: distance("distanceForward")?,
        backward_m: distance("distanceBackward")?,
        freespace,
        opposite_lanes: s.bool(t, c, "oppositeLanes")?,
        ranges: Vec::new(),
        entities: Vec::new(),
    };
    for e in elements(c) {
        match e.tag_name().name() {
            "RelativeLaneRange" => {
                let bound = |attr: &str, unbounded: i64| -> Result<i64, XoscError> {
                    Ok(match e.attribute(attr) {
                        None => unbounded,
                        Some(_) => i64::from(position::lane_id(r, e, attr)?),
                    })
                };
                let (from, to) = (bound("from", i64::MIN / 4)?, bound("to", i64::MAX / 4)?);
                if from > to {
                    return Err(r.text.invalid(e, format!("a lane range from {from} to {to} is empty")));
                }
                out.ranges.push((from, to));
            }
            "EntityRef" => {
                for k in r.entities(e, "entityRef")? {
                    if !out.entities.contains(&k) {
                        out.entities.push(k);
                    }
                }
            }
            other => {
                return Err(r.text.unsupported(
                    e,
                    format!("<{other}> in <RelativeClearanceCondition>: paracosm reads <RelativeLaneRange> and <EntityRef>"),
                ))
            }
        }
    }
    Ok(out)
}
