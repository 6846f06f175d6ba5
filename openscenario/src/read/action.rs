//! Private actions (OpenSCENARIO 1.3 User Guide, "Actions"): speed, longitudinal distance,
//! lane change, lane offset, teleport, follow trajectory (polyline), activate controller; controller actions in
//! `controller.rs`, synchronize in `synchronize.rs`.
//! Every other action is refused with what is supported.

use roxmltree::Node;

use super::{position, Reader};
use crate::error::XoscError;
use crate::model::{
    Action, Dimension, DistanceConstraints, Dynamics, LaneTarget, OffsetTarget, Position, Shape,
    SpeedProfile, SpeedTarget, TrajectoryShape,
};
use crate::quantity::Quantity;
use crate::support;
use crate::xml::{child, choice, elements, need};

/// A `<PrivateAction>`.
pub(super) fn private(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let (a, tag) = choice(r.text, node, &support::PRIVATE_ACTION)?;
    match tag {
        "SynchronizeAction" => super::synchronize::read(r, a),
        "TrailerAction" => {
            let (t, tag) = choice(r.text, a, &support::TRAILER_ACTION)?;
            if tag == "DisconnectTrailerAction" {
                return Ok(Action::Trailer(None));
            }
            Ok(Action::Trailer(Some(r.entity(t, "trailerRef")?)))
        }
        "AppearanceAction" => appearance(r, a),
        "VisibilityAction" => visibility(r, a),
        // OpenSCENARIO 1.0 puts it directly under <PrivateAction>.
        "ActivateControllerAction" => activate(r, a),
        "LongitudinalAction" => {
            let (l, tag) = choice(r.text, a, &support::LONGITUDINAL_ACTION)?;
            match tag {
                "SpeedAction" => speed(r, l),
                "SpeedProfileAction" => speed_profile(r, l),
                _ => distance(r, l),
            }
        }
        "LateralAction" => {
            let (l, tag) = choice(r.text, a, &support::LATERAL_ACTION)?;
            match tag {
                "LaneChangeAction" => lane_change(r, l),
                "LaneOffsetAction" => lane_offset(r, l),
                _ => lateral_distance(r, l),
            }
        }
        "TeleportAction" => Ok(Action::Teleport(position::read(
            r,
            need(r.text, a, "Position")?,
        )?)),
        "RoutingAction" => {
            let (f, tag) = choice(r.text, a, &support::ROUTING_ACTION)?;
            match tag {
                "AssignRouteAction" => assign_route(r, f),
                "AcquirePositionAction" => Ok(Action::AcquirePosition(position::read(
                    r,
                    need(r.text, f, "Position")?,
                )?)),
                _ => follow_trajectory(r, f),
            }
        }
        _ => super::controller::read(r, a),
    }
}

/// An `ActivateControllerAction`: 1.3's `animation` and `lighting` are refused when set;
/// which controller it names is noted ([`crate::support::CONTROLLER_NAMED`]).
pub(super) fn activate(r: &Reader<'_>, c: Node<'_, '_>) -> Result<Action, XoscError> {
    for a in ["animation", "lighting"] {
        if r.scope.opt_bool(r.text, c, a)? == Some(true) {
            return Err(XoscError::Unsupported {
                pos: r.text.attr_pos(c, a),
                reason: format!("activating a controller's {a} is not supported"),
            });
        }
    }
    if c.attribute("objectControllerRef").is_some() || c.attribute("controllerRef").is_some() {
        r.note(c, support::CONTROLLER_NAMED.note);
    }
    Ok(Action::ActivateController {
        lateral: r.scope.opt_bool(r.text, c, "lateral")?,
        longitudinal: r.scope.opt_bool(r.text, c, "longitudinal")?,
    })
}

/// A `TransitionDynamics` element.
fn dynamics(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Dynamics, XoscError> {
    let shape = shape(r, node)?;
    let dimension = match r.scope.string(r.text, node, "dynamicsDimension")?.as_str() {
        "time" => Dimension::Time,
        "distance" => Dimension::Distance,
        "rate" => Dimension::Rate,
        other => {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(node, "dynamicsDimension"),
                reason: format!("dynamicsDimension is time, distance or rate, not {other:?}"),
            })
        }
    };
    if let Some(mode) = r.scope.opt_string(r.text, node, "followingMode")? {
        if mode != "position" {
            r.note(
                node,
                format!(
                    "followingMode {mode:?} {}",
                    support::DYNAMICS_FOLLOWING.note
                ),
            );
        }
    }
    let q = match dimension {
        Dimension::Rate => Quantity::Acceleration,
        Dimension::Time => Quantity::Duration,
        Dimension::Distance => Quantity::Distance,
    };
    let mut value = r.scope.num_in(r.text, node, "value", q)?;
    if dimension == Dimension::Rate && value < 0.0 {
        // The standard's value is >= 0; files (the ALKS cut-in) write a deceleration as a
        // negative rate. The target gives the direction, so the rate is its magnitude.
        r.note(
            node,
            format!(
                "a transition's rate of {value} is read as {}: {}",
                -value,
                support::NEGATIVE_RATE.note
            ),
        );
        value = -value;
    }
    if value.is_nan() || value < 0.0 {
        return Err(XoscError::Invalid {
            pos: r.text.attr_pos(node, "value"),
            reason: format!("a transition's value must be >= 0, not {value}"),
        });
    }
    Ok(Dynamics {
        shape,
        dimension,
        value,
    })
}

fn shape(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Shape, XoscError> {
    Ok(match r.scope.string(r.text, node, "dynamicsShape")?.as_str() {
        "step" => Shape::Step,
        "linear" => Shape::Linear,
        "cubic" => Shape::Cubic,
        "sinusoidal" => Shape::Sinusoidal,
        other => {
            return Err(XoscError::Unsupported {
                pos: r.text.attr_pos(node, "dynamicsShape"),
                reason: format!("dynamicsShape {other:?} is not supported; paracosm reads step, linear, cubic and sinusoidal"),
            })
        }
    })
}

fn speed(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let dynamics = dynamics(r, need(r.text, node, "SpeedActionDynamics")?)?;
    let (t, tag) = choice(
        r.text,
        need(r.text, node, "SpeedActionTarget")?,
        &support::SPEED_TARGET,
    )?;
    let target = if tag == "AbsoluteTargetSpeed" {
        SpeedTarget::Absolute(r.scope.num_in(r.text, t, "value", Quantity::Speed)?)
    } else {
        let factor = match r.scope.string(r.text, t, "speedTargetValueType")?.as_str() {
            "delta" => false,
            "factor" => true,
            other => {
                return Err(XoscError::Invalid {
                    pos: r.text.attr_pos(t, "speedTargetValueType"),
                    reason: format!("speedTargetValueType is delta or factor, not {other:?}"),
                })
            }
        };
        SpeedTarget::Relative {
            entity: r.entity(t, "entityRef")?,
            value: r.scope.num_in(
                r.text,
                t,
                "value",
                if factor {
                    Quantity::Factor
                } else {
                    Quantity::Speed
                },
            )?,
            factor,
            continuous: r.scope.bool(r.text, t, "continuous")?,
        }
    };
    Ok(Action::Speed { target, dynamics })
}

fn distance(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let distance_m = r
        .scope
        .opt_num_in(r.text, node, "distance", Quantity::Distance)?;
    let time_gap_s = r
        .scope
        .opt_num_in(r.text, node, "timeGap", Quantity::Duration)?;
    if distance_m.is_some() == time_gap_s.is_some() {
        return Err(r.text.invalid(
            node,
            "a longitudinal distance action gives either distance or timeGap",
        ));
    }
    let continuous = r.scope.bool(r.text, node, "continuous")?;
    let constraints = child(node, "DynamicConstraints")
        .map(|c| distance_constraints(r, c))
        .transpose()?;
    Ok(Action::LongitudinalDistance {
        entity: r.entity(node, "entityRef")?,
        distance_m,
        time_gap_s,
        freespace: r.scope.bool(r.text, node, "freespace")?,
        continuous,
        displacement: one_of(
            r,
            node,
            "displacement",
            &["trailingReferencedEntity", "leadingReferencedEntity", "any"],
        )?,
        frame: one_of(
            r,
            node,
            "coordinateSystem",
            &["entity", "lane", "road", "trajectory"],
        )?,
        constraints,
    })
}

/// An `AppearanceAction`: a vehicle's lights or an animation, noted (paracosm draws neither).
///
/// # Errors
/// What its choice's reader returns.
fn appearance(r: &Reader<'_>, a: Node<'_, '_>) -> Result<Action, XoscError> {
    let (kind, tag) = choice(r.text, a, &support::APPEARANCE_ACTION)?;
    let what = if tag == "LightStateAction" {
        "a vehicle's lights"
    } else {
        "an animation"
    };
    r.note(kind, format!("<{tag}> {}", support::APPEARANCE.note));
    Ok(Action::Appearance(what.to_string()))
}

/// A `VisibilityAction`.
///
/// # Errors
/// Unsupported for a visibility for some sensors only (`SensorReferenceSet`).
fn visibility(r: &Reader<'_>, a: Node<'_, '_>) -> Result<Action, XoscError> {
    if child(a, "SensorReferenceSet").is_some() {
        return Err(r.text.unsupported(
                a,
                "a visibility for some sensors only (<SensorReferenceSet>) is not supported: paracosm hides an entity from every sensor or none",
            ));
    }
    Ok(Action::Visibility {
        graphics: r.scope.bool(r.text, a, "graphics")?,
        traffic: r.scope.bool(r.text, a, "traffic")?,
        sensors: r.scope.bool(r.text, a, "sensors")?,
    })
}

/// A `LateralDistanceAction`: in OpenSCENARIO 1.1 and later a negative `distance` is read as
/// its magnitude (its side is `displacement`'s), noted, as esmini reads it; in 1.0 it is signed
/// (no `displacement`), and in CARLA's frame reversed ([`Reader::flip`]).
///
/// # Errors
/// Unsupported for a `coordinateSystem` other than `entity` and `road` (esmini measures only
/// those); what the attributes' readers return.
fn lateral_distance(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let frame = one_of(
        r,
        node,
        "coordinateSystem",
        &["entity", "road", "lane", "trajectory"],
    )?;
    if frame != "entity" && frame != "road" {
        return Err(XoscError::Unsupported {
            pos: r.text.attr_pos(node, "coordinateSystem"),
            reason: format!(
                "a lateral distance in {frame} coordinates is not supported: paracosm keeps it \
                 in the entity's or the road's (as esmini does)"
            ),
        });
    }
    let since_1_1 = r.version >= (1, 1);
    let mut distance_m = r
        .scope
        .opt_num_in(r.text, node, "distance", Quantity::Lateral)?
        .map(|d| r.flip(d));
    if let Some(d) = distance_m.filter(|d| since_1_1 && *d < 0.0) {
        r.note(
            node,
            format!(
                "a lateral distance of {d} m is read as {} m: from OpenSCENARIO 1.1 its side is \
                 displacement's, as esmini reads it",
                d.abs()
            ),
        );
        distance_m = Some(d.abs());
    }
    let displacement = if since_1_1 {
        one_of(
            r,
            node,
            "displacement",
            &["any", "leftToReferencedEntity", "rightToReferencedEntity"],
        )?
    } else {
        "any".to_string()
    };
    Ok(Action::LateralDistance {
        entity: r.entity(node, "entityRef")?,
        distance_m,
        freespace: r.scope.bool(r.text, node, "freespace")?,
        continuous: r.scope.bool(r.text, node, "continuous")?,
        displacement,
        frame,
        constraints: child(node, "DynamicConstraints")
            .map(|c| distance_constraints(r, c))
            .transpose()?,
    })
}

/// A `<SpeedProfileAction>` (OpenSCENARIO 1.2): its `DynamicConstraints` (each limit `> 0`)
/// and its entries, each `time` a duration (`>= 0`) when given.
fn speed_profile(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let follow = match r.scope.string(r.text, node, "followingMode")?.as_str() {
        "follow" => true,
        "position" => false,
        other => {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(node, "followingMode"),
                reason: format!("followingMode is position or follow, not {other:?}"),
            })
        }
    };
    let mut entries = Vec::new();
    for c in elements(node) {
        match c.tag_name().name() {
            "DynamicConstraints" => {}
            "SpeedProfileEntry" => {
                // A duration: within [0, 1e6] s.
                let time = r.scope.opt_num_in(r.text, c, "time", Quantity::Duration)?;
                entries.push((time, r.scope.num_in(r.text, c, "speed", Quantity::Speed)?));
            }
            other => {
                return Err(XoscError::Unsupported {
                    pos: r.text.pos(c),
                    reason: format!(
                        "<{other}> in <SpeedProfileAction> is not supported; paracosm reads \
                         <DynamicConstraints> and <SpeedProfileEntry> (the entity whose speed \
                         the entries are relative to is its entityRef attribute)"
                    ),
                })
            }
        }
    }
    if entries.is_empty() {
        return Err(r
            .text
            .invalid(node, "<SpeedProfileAction> needs a <SpeedProfileEntry>"));
    }
    let entity = match node.attribute("entityRef") {
        Some(_) => Some(r.entity(node, "entityRef")?),
        None => None,
    };
    Ok(Action::SpeedProfile(Box::new(SpeedProfile {
        entity,
        follow,
        constraints: child(node, "DynamicConstraints")
            .map(|c| distance_constraints(r, c))
            .transpose()?,
        entries,
    })))
}

/// A distance action's `<DynamicConstraints>`: each limit given is `> 0`.
fn distance_constraints(r: &Reader<'_>, c: Node<'_, '_>) -> Result<DistanceConstraints, XoscError> {
    let limit = |attr: &str, q: Quantity| -> Result<Option<f64>, XoscError> {
        let v = r.scope.opt_num_in(r.text, c, attr, q)?;
        if let Some(v) = v.filter(|v| *v <= 0.0) {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(c, attr),
                reason: format!("{attr} is a limit above 0, not {v}"),
            });
        }
        Ok(v)
    };
    Ok(DistanceConstraints {
        max_acceleration_mps2: limit("maxAcceleration", Quantity::Acceleration)?,
        max_deceleration_mps2: limit("maxDeceleration", Quantity::Acceleration)?,
        max_acceleration_rate_mps3: limit("maxAccelerationRate", Quantity::Acceleration)?,
        max_deceleration_rate_mps3: limit("maxDecelerationRate", Quantity::Acceleration)?,
        max_speed_mps: limit("maxSpeed", Quantity::Speed)?,
    })
}

/// Attribute `attr`, one of `allowed`; the first when absent (the standard's default).
fn one_of(
    r: &Reader<'_>,
    node: Node<'_, '_>,
    attr: &str,
    allowed: &[&str],
) -> Result<String, XoscError> {
    match r.scope.opt_string(r.text, node, attr)? {
        None => Ok(allowed[0].to_string()),
        Some(v) if allowed.contains(&v.as_str()) => Ok(v),
        Some(v) => Err(XoscError::Invalid {
            pos: r.text.attr_pos(node, attr),
            reason: format!("{attr} is one of {}, not {v:?}", allowed.join(", ")),
        }),
    }
}

fn lane_change(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let dynamics = dynamics(r, need(r.text, node, "LaneChangeActionDynamics")?)?;
    let (t, tag) = choice(
        r.text,
        need(r.text, node, "LaneChangeTarget")?,
        &support::LANE_CHANGE_TARGET,
    )?;
    let whole = |attr: &str| -> Result<i32, XoscError> {
        let v = r.scope.num(r.text, t, attr)?;
        if v.fract() != 0.0 || v.abs() > 1000.0 {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(t, attr),
                reason: format!("a lane is a whole number, not {v}"),
            });
        }
        Ok(v as i32)
    };
    let target = if tag == "AbsoluteTargetLane" {
        LaneTarget::Absolute(whole("value")?)
    } else {
        LaneTarget::Relative {
            entity: r.entity(t, "entityRef")?,
            lanes: whole("value")?,
        }
    };
    Ok(Action::LaneChange {
        target,
        dynamics,
        offset_m: r.flip(
            r.scope
                .opt_num_in(r.text, node, "targetLaneOffset", Quantity::Lateral)?
                .unwrap_or(0.0),
        ),
    })
}

fn lane_offset(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let d = need(r.text, node, "LaneOffsetActionDynamics")?;
    let (t, tag) = choice(
        r.text,
        need(r.text, node, "LaneOffsetTarget")?,
        &support::LANE_OFFSET_TARGET,
    )?;
    let target = if tag == "AbsoluteTargetLaneOffset" {
        OffsetTarget::Absolute(r.flip(r.scope.num_in(r.text, t, "value", Quantity::Lateral)?))
    } else {
        OffsetTarget::Relative {
            entity: r.entity(t, "entityRef")?,
            value: r.flip(r.scope.num_in(r.text, t, "value", Quantity::Lateral)?),
        }
    };
    Ok(Action::LaneOffset {
        target,
        shape: shape(r, d)?,
        max_lateral_acc: r
            .scope
            .opt_num_in(r.text, d, "maxLateralAcc", Quantity::Acceleration)?,
        continuous: r.scope.bool(r.text, node, "continuous")?,
    })
}

/// A `FollowTrajectoryAction`: its trajectory inline (`<TrajectoryRef><Trajectory>`, or 1.0's
/// `<Trajectory>`) or from a trajectory catalog (`<CatalogReference>` in either place), with
/// its timing.
fn follow_trajectory(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let initial_offset_m = r
        .scope
        .opt_num_in(r.text, node, "initialDistanceOffset", Quantity::Distance)?
        .unwrap_or(0.0);
    if initial_offset_m < 0.0 {
        return Err(XoscError::Invalid {
            pos: r.text.attr_pos(node, "initialDistanceOffset"),
            reason: format!("initialDistanceOffset is a distance >= 0 m, not {initial_offset_m}"),
        });
    }
    let time_ref = need(r.text, node, "TimeReference")?;
    let timing = match child(time_ref, "Timing") {
        None => None,
        Some(t) => {
            let absolute = match r
                .scope
                .string(r.text, t, "domainAbsoluteRelative")?
                .as_str()
            {
                "absolute" => true,
                "relative" => false,
                other => {
                    return Err(XoscError::Invalid {
                        pos: r.text.attr_pos(t, "domainAbsoluteRelative"),
                        reason: format!(
                            "domainAbsoluteRelative is absolute or relative, not {other:?}"
                        ),
                    })
                }
            };
            Some((
                absolute,
                r.scope.num_in(r.text, t, "scale", Quantity::Factor)?,
                r.scope.num_in(r.text, t, "offset", Quantity::Time)?,
            ))
        }
    };
    if let Some((_, scale, _)) = timing {
        if scale.is_nan() || scale <= 0.0 {
            return Err(r.text.invalid(
                time_ref,
                format!("a timing's scale must be > 0, not {scale}"),
            ));
        }
    }
    let holder = child(node, "TrajectoryRef").unwrap_or(node);
    let shape = trajectory_of(r, holder, timing.is_some())?;
    let mut position_mode = false;
    if let Some(m) = child(node, "TrajectoryFollowingMode") {
        let mode = r.scope.string(r.text, m, "followingMode")?;
        // `follow` is honoured as esmini honours it: a polyline's heading turned along each
        // leg, a timed polyline's legs at constant accelerations.
        position_mode = mode == "position";
    }
    if initial_offset_m != 0.0 && timing.is_some() {
        return Err(XoscError::Unsupported {
            pos: r.text.attr_pos(node, "initialDistanceOffset"),
            reason: "a timed trajectory's initialDistanceOffset is not supported: paracosm \
                     starts part way along a trajectory only when it is followed at the \
                     entity's speed"
                .into(),
        });
    }
    Ok(Action::FollowTrajectory {
        shape,
        timing,
        position_mode,
        initial_offset_m,
    })
}

/// The shape of the trajectory `holder` holds (a `TrajectoryRef`, or 1.0's action itself): one
/// `<Trajectory>` or one trajectory catalog's `<CatalogReference>`; with `timed`, each of its
/// points must have a time.
///
/// # Errors
/// Invalid when `holder` holds neither or both; what reading the trajectory returns.
pub(super) fn trajectory_of(
    r: &Reader<'_>,
    holder: Node<'_, '_>,
    timed: bool,
) -> Result<TrajectoryShape, XoscError> {
    let read = |r: &Reader<'_>, traj: Node<'_, '_>| trajectory(r, traj, timed);
    match (
        child(holder, "Trajectory"),
        child(holder, "CatalogReference"),
    ) {
        (Some(traj), None) => read(&r.scoped(traj)?, traj),
        (None, Some(c)) => r.catalogs.read_entry(r, c, &["Trajectory"], read),
        _ => Err(r.text.invalid(
            holder,
            "a trajectory is read from one <Trajectory> or one <CatalogReference> here",
        )),
    }
}

/// A `<Trajectory>`'s shape, read with `r`'s scope (the trajectory's own parameters in it);
/// with `timed`, each of its points must have a time.
fn trajectory(
    r: &Reader<'_>,
    traj: Node<'_, '_>,
    timed_: bool,
) -> Result<TrajectoryShape, XoscError> {
    if traj.tag_name().name() != "Trajectory" {
        return Err(r.text.invalid(
            traj,
            format!(
                "a trajectory catalog entry is a <Trajectory>, not <{}>",
                traj.tag_name().name()
            ),
        ));
    }
    if r.scope.bool(r.text, traj, "closed")? {
        if !timed_ {
            return Err(r.text.unsupported(
                traj,
                "a closed trajectory followed at the entity's speed is not supported (a timed \
                 one is: it ends at its last time)",
            ));
        }
        r.note(
            traj,
            "a closed trajectory followed by its times ends at its last time, as esmini's \
             does: closed changes nothing here",
        );
    }
    let (shape_node, kind) = choice(r.text, need(r.text, traj, "Shape")?, &support::SHAPE)?;
    let shape = match kind {
        "Polyline" => polyline(r, shape_node)?,
        "Clothoid" => clothoid(r, shape_node)?,
        "ClothoidSpline" => clothoid_spline(r, shape_node)?,
        _ => nurbs(r, shape_node)?,
    };
    if timed_ {
        timed(r, shape_node, &shape)?;
    }
    Ok(shape)
}

/// A `Polyline`: at least two `Vertex` elements, each with its position and time.
fn polyline(r: &Reader<'_>, shape: Node<'_, '_>) -> Result<TrajectoryShape, XoscError> {
    let mut vertices = Vec::new();
    for v in elements(shape) {
        if v.tag_name().name() != "Vertex" {
            return Err(r
                .text
                .unsupported(v, "a polyline holds <Vertex> elements only"));
        }
        let time = r.scope.opt_num_in(r.text, v, "time", Quantity::Time)?;
        vertices.push((time, position::read(r, need(r.text, v, "Position")?)?));
    }
    if vertices.len() < 2 {
        return Err(r
            .text
            .invalid(shape, "a polyline needs at least two vertices"));
    }
    Ok(TrajectoryShape::Polyline(vertices))
}

/// A `Clothoid`: `curvature`, `curvaturePrime` (1.0's `curvatureDot`), `length`, optional
/// `startTime` and `stopTime` (both or neither), and an optional start `Position`.
fn clothoid(r: &Reader<'_>, c: Node<'_, '_>) -> Result<TrajectoryShape, XoscError> {
    let (sc, t) = (&r.scope, r.text);
    let prime = match (
        sc.opt_num(t, c, "curvaturePrime")?,
        sc.opt_num(t, c, "curvatureDot")?,
    ) {
        (Some(p), _) | (None, Some(p)) => p,
        (None, None) => return Err(t.invalid(c, "a clothoid needs curvaturePrime")),
    };
    let length = sc.num_in(t, c, "length", Quantity::Distance)?;
    if !(length.is_finite() && length > 0.0) {
        return Err(XoscError::Invalid {
            pos: t.attr_pos(c, "length"),
            reason: format!("a clothoid's length must be > 0, not {length}"),
        });
    }
    let times = match (
        sc.opt_num_in(t, c, "startTime", Quantity::Time)?,
        sc.opt_num_in(t, c, "stopTime", Quantity::Time)?,
    ) {
        (Some(a), Some(b)) if b > a => Some((a, b)),
        (None, None) => None,
        _ => {
            return Err(t.invalid(
                c,
                "a clothoid's startTime and stopTime come together, stopTime after startTime",
            ))
        }
    };
    let start = match child(c, "Position") {
        Some(p) => Some(position::read(r, p)?),
        None => None,
    };
    Ok(TrajectoryShape::Clothoid {
        start,
        curvature: sc.num_in(t, c, "curvature", Quantity::Curvature)?,
        curvature_prime: prime,
        length,
        times,
    })
}

/// The longest clothoid spline read, m (it is sampled every metre).
const MAX_SPLINE_M: f64 = 100_000.0;

/// A `ClothoidSpline`: its `ClothoidSplineSegment`s (at least one; `curvatureStart`,
/// `curvatureEnd`, `length` > 0, `hOffset` 0 when absent) and the first one's optional
/// `PositionStart`.
///
/// A segment after the first with a `PositionStart` starts there (esmini's reading).
///
/// # Errors
/// Invalid at a segment of no length, an empty spline, one longer than [`MAX_SPLINE_M`];
/// times given in part (a `timeEnd` needs every segment's `timeStart`, and they it), or
/// that do not increase.
fn clothoid_spline(r: &Reader<'_>, c: Node<'_, '_>) -> Result<TrajectoryShape, XoscError> {
    let (sc, t) = (&r.scope, r.text);
    crate::xml::only(t, c, &["ClothoidSplineSegment"])?;
    let time_end = sc.opt_num_in(t, c, "timeEnd", Quantity::Time)?;
    let mut starts: Vec<Option<f64>> = Vec::new();
    let mut start = None;
    let mut restarts = Vec::new();
    let mut segments = Vec::new();
    for (k, seg) in elements(c).enumerate() {
        crate::xml::only(t, seg, &["PositionStart"])?;
        let time_start = sc.opt_num_in(t, seg, "timeStart", Quantity::Time)?;
        if time_start.is_some() != time_end.is_some() {
            return Err(t.invalid(
                seg,
                "a clothoid spline's times are its segments' timeStart and its timeEnd: give \
                 all of them, or none (followed at the entity's speed)",
            ));
        }
        starts.push(time_start);
        if let Some(p) = child(seg, "PositionStart") {
            let p = position::read(r, p)?;
            if k == 0 {
                start = Some(p);
            } else {
                restarts.push((k, p));
            }
        }
        let length = sc.num_in(t, seg, "length", Quantity::Distance)?;
        if !(length.is_finite() && length > 0.0) {
            return Err(XoscError::Invalid {
                pos: t.attr_pos(seg, "length"),
                reason: format!("a clothoid spline segment's length must be > 0, not {length}"),
            });
        }
        segments.push([
            r.flip(sc.num_in(t, seg, "curvatureStart", Quantity::Curvature)?),
            r.flip(sc.num_in(t, seg, "curvatureEnd", Quantity::Curvature)?),
            length,
            r.flip(
                sc.opt_num_in(t, seg, "hOffset", Quantity::Angle)?
                    .unwrap_or(0.0),
            ),
        ]);
    }
    if segments.is_empty() {
        return Err(t.invalid(
            c,
            "a clothoid spline needs at least one <ClothoidSplineSegment>",
        ));
    }
    let total: f64 = segments.iter().map(|g| g[2]).sum();
    if total > MAX_SPLINE_M {
        return Err(t.invalid(
            c,
            format!(
                "a clothoid spline of {total} m: paracosm samples one every metre, up to \
                 {MAX_SPLINE_M} m"
            ),
        ));
    }
    let times = match time_end {
        Some(end) => {
            let starts: Vec<f64> = starts.into_iter().flatten().collect();
            let mut all = starts.clone();
            all.push(end);
            if all.windows(2).any(|w| w[1] <= w[0]) {
                return Err(t.invalid(
                    c,
                    "a clothoid spline's times (each segment's timeStart, then its timeEnd) \
                     must increase",
                ));
            }
            Some((starts, end))
        }
        None => None,
    };
    Ok(TrajectoryShape::ClothoidSpline {
        start,
        segments,
        restarts,
        times,
    })
}

/// A `Nurbs`: `order` (at least 2), its `ControlPoint`s (at least `order`; `weight` > 0, 1
/// when absent) and `Knot`s (control points + order of them, non-decreasing, the first below
/// the last).
fn nurbs(r: &Reader<'_>, n: Node<'_, '_>) -> Result<TrajectoryShape, XoscError> {
    let (sc, t) = (&r.scope, r.text);
    let order = sc.num(t, n, "order")?;
    if !(order.fract() == 0.0 && (2.0..=16.0).contains(&order)) {
        return Err(XoscError::Invalid {
            pos: t.attr_pos(n, "order"),
            reason: format!("a NURBS's order is a whole number from 2 to 16, not {order}"),
        });
    }
    let order = order as usize;
    let mut points = Vec::new();
    let mut knots = Vec::new();
    for e in elements(n) {
        match e.tag_name().name() {
            "ControlPoint" => {
                let weight = sc.opt_num(t, e, "weight")?.unwrap_or(1.0);
                if !(weight.is_finite() && weight > 0.0) {
                    return Err(XoscError::Invalid {
                        pos: t.attr_pos(e, "weight"),
                        reason: format!("a control point's weight must be > 0, not {weight}"),
                    });
                }
                let time = sc.opt_num_in(t, e, "time", Quantity::Time)?;
                points.push((time, weight, position::read(r, need(t, e, "Position")?)?));
            }
            "Knot" => knots.push(sc.num(t, e, "value")?),
            _ => {
                return Err(
                    t.unsupported(e, "a NURBS holds <ControlPoint> and <Knot> elements only")
                )
            }
        }
    }
    if points.len() < order {
        return Err(t.invalid(
            n,
            format!(
                "a NURBS of order {order} needs at least {order} control points, not {}",
                points.len()
            ),
        ));
    }
    if knots.len() != points.len() + order {
        return Err(t.invalid(
            n,
            format!(
                "a NURBS of order {order} with {} control points needs {} knots, not {}",
                points.len(),
                points.len() + order,
                knots.len()
            ),
        ));
    }
    if knots.windows(2).any(|w| w[1] < w[0]) || knots[order - 1] >= knots[points.len()] {
        return Err(t.invalid(
            n,
            "a NURBS's knots must not decrease, and must span its curve (the order-th knot below the one after the last control point's)",
        ));
    }
    Ok(TrajectoryShape::Nurbs {
        order,
        points,
        knots,
    })
}

/// Checks, with a `<Timing>`, that `shape` gives its times: every vertex (increasing), the
/// clothoid's start and stop, every control point.
fn timed(r: &Reader<'_>, node: Node<'_, '_>, shape: &TrajectoryShape) -> Result<(), XoscError> {
    let times: Option<Vec<f64>> = match shape {
        TrajectoryShape::Polyline(v) => v.iter().map(|(t, _)| *t).collect(),
        TrajectoryShape::Clothoid { times, .. } => times.map(|(a, b)| vec![a, b]),
        TrajectoryShape::ClothoidSpline { times, .. } => times.as_ref().map(|(s, end)| {
            let mut all = s.clone();
            all.push(*end);
            all
        }),
        TrajectoryShape::Nurbs { points, .. } => points.iter().map(|(t, _, _)| *t).collect(),
    };
    match times {
        None => Err(r.text.invalid(
            node,
            "with a <Timing>, every vertex or control point needs a time (a clothoid its startTime and stopTime)",
        )),
        Some(t) if t.windows(2).any(|w| w[1] <= w[0]) => Err(r
            .text
            .invalid(node, "a trajectory's times must increase")),
        Some(_) => Ok(()),
    }
}

/// An `AssignRouteAction`: its `<Route>`, inline (with its own parameter declarations) or
/// from a route catalog (`<CatalogReference>`, with the reference's parameter assignments).
fn assign_route(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let (holder, tag) = choice(r.text, node, &support::ROUTE_REF)?;
    let waypoints = if tag == "Route" {
        route(&r.scoped(holder)?, holder)?
    } else {
        r.catalogs.read_entry(r, holder, &["Route"], route)?
    };
    Ok(Action::AssignRoute { waypoints })
}

/// A `<Route>`'s waypoints, read with `r`'s scope (the route's own parameters in it).
pub(super) fn route(
    r: &Reader<'_>,
    route: Node<'_, '_>,
) -> Result<Vec<(Position, String)>, XoscError> {
    if route.tag_name().name() != "Route" {
        return Err(r.text.invalid(
            route,
            format!(
                "a route catalog entry is a <Route>, not <{}>",
                route.tag_name().name()
            ),
        ));
    }
    if r.scope.bool(r.text, route, "closed")? {
        return Err(r.text.unsupported(route, "a closed route is not supported"));
    }
    let mut waypoints = Vec::new();
    for w in elements(route) {
        match w.tag_name().name() {
            "Waypoint" => {
                let strategy = r.scope.string(r.text, w, "routeStrategy")?;
                if !["fastest", "shortest", "leastIntersections", "random"]
                    .contains(&strategy.as_str())
                {
                    return Err(XoscError::Invalid {
                        pos: r.text.attr_pos(w, "routeStrategy"),
                        reason: format!("routeStrategy is fastest, shortest, leastIntersections or random, not {strategy:?}"),
                    });
                }
                waypoints.push((position::read(r, need(r.text, w, "Position")?)?, strategy));
            }
            "ParameterDeclarations" => {}
            other => {
                return Err(r.text.unsupported(
                    w,
                    format!("<{other}> in <Route> is not supported; paracosm reads <Waypoint>"),
                ))
            }
        }
    }
    if waypoints.len() < 2 {
        return Err(r
            .text
            .invalid(route, "a route needs at least two waypoints"));
    }
    Ok(waypoints)
}
