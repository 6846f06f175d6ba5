//! Positions (OpenSCENARIO 1.3 User Guide, "Positions"): world, relative world, relative
//! object, road, relative road, lane and relative lane positions; the others are refused.

use roxmltree::Node;

use super::Reader;
use crate::error::XoscError;
use crate::model::{Orientation, Position};
use crate::xml::{child, choice};

/// The positions paracosm reads.
const POSITIONS: &[&str] = &[
    "WorldPosition",
    "RelativeWorldPosition",
    "RelativeObjectPosition",
    "RoadPosition",
    "RelativeRoadPosition",
    "LanePosition",
    "RelativeLanePosition",
];

/// A `<Position>` element.
pub(super) fn read(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Position, XoscError> {
    let (p, tag) = choice(r.text, node, POSITIONS)?;
    let (s, t) = (&r.scope, r.text);
    let lane_id = |attr: &str| -> Result<i32, XoscError> {
        let v = s.num(t, p, attr)?;
        if v.fract() != 0.0 || v.abs() > 1000.0 {
            return Err(XoscError::Invalid {
                pos: t.attr_pos(p, attr),
                reason: format!("a lane id is a whole number, not {v}"),
            });
        }
        Ok(v as i32)
    };
    Ok(match tag {
        "WorldPosition" => {
            for a in ["z", "p", "r"] {
                if s.opt_num(t, p, a)?.is_some_and(|v| v != 0.0) {
                    r.note(
                        p,
                        format!(
                            "a world position's {a} is not honoured: paracosm's roads are flat"
                        ),
                    );
                }
            }
            Position::World {
                x: s.num(t, p, "x")?,
                y: s.num(t, p, "y")?,
                h: s.opt_num(t, p, "h")?,
            }
        }
        "RelativeWorldPosition" | "RelativeObjectPosition" => {
            if s.opt_num(t, p, "dz")?.is_some_and(|v| v != 0.0) {
                r.note(
                    p,
                    "a relative position's dz is not honoured: paracosm's roads are flat",
                );
            }
            let (entity, dx, dy) = (
                r.entity(p, "entityRef")?,
                s.num(t, p, "dx")?,
                s.num(t, p, "dy")?,
            );
            let orientation = orientation(r, p)?;
            if tag == "RelativeWorldPosition" {
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
                    orientation,
                }
            }
        }
        "RoadPosition" => Position::Road {
            road: s.string(t, p, "roadId")?,
            s: s.num(t, p, "s")?,
            t: s.num(t, p, "t")?,
            orientation: orientation(r, p)?,
        },
        "RelativeRoadPosition" => Position::RelativeRoad {
            entity: r.entity(p, "entityRef")?,
            ds: s.num(t, p, "ds")?,
            dt: s.num(t, p, "dt")?,
            orientation: orientation(r, p)?,
        },
        "LanePosition" => Position::Lane {
            road: s.string(t, p, "roadId")?,
            lane: lane_id("laneId")?,
            s: s.num(t, p, "s")?,
            offset: s.opt_num(t, p, "offset")?.unwrap_or(0.0),
            orientation: orientation(r, p)?,
        },
        _ => {
            if child(p, "Orientation").is_some() {
                return Err(r.text.unsupported(
                    p,
                    "an orientation on a relative lane position is not supported",
                ));
            }
            let ds = s.opt_num(t, p, "ds")?;
            if ds.is_none() || p.attribute("dsLane").is_some() {
                return Err(r.text.unsupported(
                    p,
                    "a relative lane position needs ds (dsLane is not supported)",
                ));
            }
            Position::RelativeLane {
                entity: r.entity(p, "entityRef")?,
                d_lane: lane_id("dLane")?,
                ds: ds.unwrap_or(0.0),
                offset: s.opt_num(t, p, "offset")?.unwrap_or(0.0),
            }
        }
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
    for a in ["p", "r"] {
        if r.scope.opt_num(r.text, o, a)?.is_some_and(|v| v != 0.0) {
            return Err(r.text.unsupported(o, format!("an orientation's {a} (pitch or roll) is not supported: paracosm's roads are flat")));
        }
    }
    Ok(Some(Orientation {
        h: r.scope.opt_num(r.text, o, "h")?.unwrap_or(0.0),
        relative,
    }))
}
