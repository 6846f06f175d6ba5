//! Positions (OpenSCENARIO 1.3 User Guide, "Positions"): world, relative world, relative
//! object, road, relative road, lane and relative lane positions; the others are refused.

use roxmltree::Node;

use super::Reader;
use crate::error::XoscError;
use crate::model::{Orientation, Position};
use crate::quantity::Quantity;
use crate::xml::{child, choice};

/// A `<Position>` element.
pub(super) fn read(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Position, XoscError> {
    let (p, tag) = choice(r.text, node, &crate::support::POSITION)?;
    let (s, t) = (&r.scope, r.text);
    Ok(match tag {
        "WorldPosition" => world(r, p)?,
        "RelativeWorldPosition" | "RelativeObjectPosition" => relative(r, p, tag)?,
        "RoadPosition" => Position::Road {
            road: s.string(t, p, "roadId")?,
            s: s.num_in(t, p, "s", Quantity::Distance)?,
            t: r.flip(s.num_in(t, p, "t", Quantity::Lateral)?),
            orientation: orientation(r, p)?,
        },
        "RelativeRoadPosition" => Position::RelativeRoad {
            entity: r.entity(p, "entityRef")?,
            ds: s.num_in(t, p, "ds", Quantity::Distance)?,
            dt: r.flip(s.num_in(t, p, "dt", Quantity::Lateral)?),
            orientation: orientation(r, p)?,
        },
        "LanePosition" => Position::Lane {
            road: s.string(t, p, "roadId")?,
            lane: lane_id(r, p, "laneId")?,
            s: s.num_in(t, p, "s", Quantity::Distance)?,
            offset: r.flip(
                s.opt_num_in(t, p, "offset", Quantity::Lateral)?
                    .unwrap_or(0.0),
            ),
            orientation: orientation(r, p)?,
        },
        "RoutePosition" => route(r, p)?,
        "TrajectoryPosition" => trajectory(r, p)?,
        _ => relative_lane(r, p)?,
    })
}

/// A `<TrajectoryPosition>`: `s` and `t` on its trajectory (`TrajectoryRef`: a `<Trajectory>`
/// or a trajectory catalog's `<CatalogReference>`) and its orientation.
///
/// # Errors
/// Invalid at a negative `s`, a `TrajectoryRef` that holds neither or both; what reading the
/// trajectory returns.
fn trajectory(r: &Reader<'_>, p: Node<'_, '_>) -> Result<Position, XoscError> {
    let (sc, t) = (&r.scope, r.text);
    let s = sc.num_in(t, p, "s", Quantity::Distance)?;
    if s < 0.0 {
        return Err(XoscError::Invalid {
            pos: t.attr_pos(p, "s"),
            reason: format!("a trajectory position's s is >= 0 m, not {s}"),
        });
    }
    let holder = crate::xml::need(t, p, "TrajectoryRef")?;
    let shape = super::action::trajectory_of(r, holder, false)?;
    Ok(Position::Trajectory {
        shape: Box::new(shape),
        s,
        t: r.flip(sc.opt_num_in(t, p, "t", Quantity::Lateral)?.unwrap_or(0.0)),
        orientation: orientation(r, p)?,
    })
}

/// A `<RoutePosition>`: its route (`RouteRef`: a `<Route>` or a route catalog's
/// `<CatalogReference>`), where on it (`InRoutePosition`) and its orientation.
fn route(r: &Reader<'_>, p: Node<'_, '_>) -> Result<Position, XoscError> {
    use crate::model::InRoute;
    let (s, t) = (&r.scope, r.text);
    let (holder, tag) = choice(
        t,
        crate::xml::need(t, p, "RouteRef")?,
        &crate::support::ROUTE_REF,
    )?;
    let waypoints = if tag == "Route" {
        super::action::route(&r.scoped(holder)?, holder)?
    } else {
        r.catalogs
            .read_entry(r, holder, &["Route"], super::action::route)?
    };
    let (w, tag) = choice(
        t,
        crate::xml::need(t, p, "InRoutePosition")?,
        &crate::support::IN_ROUTE_POSITION,
    )?;
    let at = match tag {
        "FromCurrentEntity" => InRoute::Entity(r.entity(w, "entityRef")?),
        "FromLaneCoordinates" => InRoute::Lane {
            path_s: s.num_in(t, w, "pathS", Quantity::Distance)?,
            lane: lane_id(r, w, "laneId")?,
            offset: r.flip(
                s.opt_num_in(t, w, "laneOffset", Quantity::Lateral)?
                    .unwrap_or(0.0),
            ),
        },
        _ => InRoute::Road {
            path_s: s.num_in(t, w, "pathS", Quantity::Distance)?,
            t: r.flip(s.num_in(t, w, "t", Quantity::Lateral)?),
        },
    };
    Ok(Position::Route {
        waypoints,
        at,
        orientation: orientation(r, p)?,
    })
}

/// Attribute `attr` of `p` read as a lane id: a whole number of at most 1000 in size.
pub(super) fn lane_id(r: &Reader<'_>, p: Node<'_, '_>, attr: &str) -> Result<i32, XoscError> {
    let (s, t) = (&r.scope, r.text);
    let v = s.num(t, p, attr)?;
    if v.fract() != 0.0 || v.abs() > 1000.0 {
        return Err(XoscError::Invalid {
            pos: t.attr_pos(p, attr),
            reason: format!("a lane id is a whole number, not {v}"),
        });
    }
    Ok(v as i32)
}

/// A `<WorldPosition>`: `x`, `y` (m) and heading `h` (rad); a `z`, pitch or roll other than
/// 0 is noted as not honoured.
fn world(r: &Reader<'_>, p: Node<'_, '_>) -> Result<Position, XoscError> {
    let (s, t) = (&r.scope, r.text);
    for a in ["z", "p", "r"] {
        if s.opt_num(t, p, a)?.is_some_and(|v| v != 0.0) {
            r.note(
                p,
                format!("a world position's {a} {}", crate::support::WORLD_Z.note),
            );
        }
    }
    Ok(Position::World {
        x: s.num_in(t, p, "x", Quantity::Coordinate)?,
        y: r.flip(s.num_in(t, p, "y", Quantity::Coordinate)?),
        h: s.opt_num_in(t, p, "h", Quantity::Angle)?.map(|h| r.flip(h)),
    })
}

/// A `<RelativeWorldPosition>` or `<RelativeObjectPosition>` (as `tag` says): the entity and
/// the offsets `dx`, `dy`, `dz` (m) from it, with its orientation; a `dz` other than 0 is
/// noted (its height is not modelled). In CARLA's reading both are offsets along the world's
/// axes.
fn relative(r: &Reader<'_>, p: Node<'_, '_>, tag: &str) -> Result<Position, XoscError> {
    let (s, t) = (&r.scope, r.text);
    let dz = s.opt_num_in(t, p, "dz", Quantity::Distance)?.unwrap_or(0.0);
    if dz != 0.0 {
        r.note(p, crate::support::RELATIVE_DZ.note);
    }
    let (entity, dx, dy) = (
        r.entity(p, "entityRef")?,
        s.num_in(t, p, "dx", Quantity::Distance)?,
        r.flip(s.num_in(t, p, "dy", Quantity::Distance)?),
    );
    let orientation = orientation(r, p)?;
    // scenario_runner adds a relative object position's offsets along the world's axes, as
    // a relative world position's (its `convert_position_to_transform`).
    Ok(if tag == "RelativeWorldPosition" || r.carla {
        Position::RelativeWorld {
            entity,
            dx,
            dy,
            orientation,
        }
    } else {
        Position::RelativeObject {
            entity,
            dx,
            dy,
            dz,
            orientation,
        }
    })
}

/// A `<RelativeLanePosition>`: the entity, the lanes `dLane` across, `ds` along (m) and the
/// lateral `offset` (m), with its orientation (the schema allows one; ASAM's own examples
/// and esmini's give it); a `dsLane` is refused.
fn relative_lane(r: &Reader<'_>, p: Node<'_, '_>) -> Result<Position, XoscError> {
    let (s, t) = (&r.scope, r.text);
    let ds = s.opt_num_in(t, p, "ds", Quantity::Distance)?;
    if ds.is_none() || p.attribute("dsLane").is_some() {
        return Err(r.text.unsupported(
            p,
            "a relative lane position needs ds (dsLane is not supported)",
        ));
    }
    Ok(Position::RelativeLane {
        entity: r.entity(p, "entityRef")?,
        d_lane: lane_id(r, p, "dLane")?,
        ds: ds.unwrap_or(0.0),
        offset: r.flip(
            s.opt_num_in(t, p, "offset", Quantity::Lateral)?
                .unwrap_or(0.0),
        ),
        orientation: orientation(r, p)?,
    })
}

/// A position's `<Orientation>`, if any (a missing `type` is absolute, as the standard's
/// schema says).
fn orientation(r: &Reader<'_>, p: Node<'_, '_>) -> Result<Option<Orientation>, XoscError> {
    let Some(o) = child(p, "Orientation") else {
        return Ok(None);
    };
    let relative = match r.scope.opt_string(r.text, o, "type")?.as_deref() {
        Some("relative") => true,
        None | Some("absolute") => false,
        Some(other) => {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(o, "type"),
                reason: format!("an orientation's type is relative or absolute, not {other:?}"),
            })
        }
    };
    for (a, what) in [("p", "pitch"), ("r", "roll")] {
        if let Some(v) = r
            .scope
            .opt_num_in(r.text, o, a, Quantity::Angle)?
            .filter(|v| *v != 0.0)
        {
            let text = format!(
                "an orientation's {what} of {v} rad tilts its entity: the storyboard moves its \
                 position and heading as written, and a campaign refuses it (paracosm's bodies \
                 stand upright on flat roads)"
            );
            r.tilts.borrow_mut().push(crate::model::Note {
                pos: r.text.attr_pos(o, a),
                text: text.clone(),
            });
            r.note(o, text);
        }
    }
    let angle = |a: &str| -> Result<f64, XoscError> {
        Ok(r.scope
            .opt_num_in(r.text, o, a, Quantity::Angle)?
            .unwrap_or(0.0))
    };
    Ok(Some(Orientation {
        // CARLA's left-handed frame mirrors y: heading and roll change sign.
        h: r.flip(angle("h")?),
        p: angle("p")?,
        r: r.flip(angle("r")?),
        relative,
    }))
}
