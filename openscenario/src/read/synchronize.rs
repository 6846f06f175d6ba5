//! `SynchronizeAction` (OpenSCENARIO 1.3 User Guide, "SynchronizeAction"): an entity timed to
//! arrive at a place when a master entity arrives at another.

use roxmltree::Node;

use super::{position, Reader};
use crate::error::XoscError;
use crate::model::{Action, FinalSpeed, SteadyState, Synchronize};
use crate::quantity::Quantity;
use crate::xml::{child, choice, need, only};

/// A `<SynchronizeAction>`: its master, both target positions, the tolerances (0 m when
/// absent, esmini's default) and the final speed with its steady state.
///
/// # Errors
/// Invalid at a missing target position, a negative tolerance, a relative final speed whose
/// `speedTargetValueType` is neither `delta` nor `factor`, a negative absolute final speed
/// (backwards), a negative steady state, a steady state with a final speed of 0 m/s or less
/// (no time at that speed reaches the target); unsupported at esmini's
/// `TargetPositionSteadyState`, which no published schema has.
pub(super) fn read(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    only(
        r.text,
        node,
        &["TargetPositionMaster", "TargetPosition", "FinalSpeed"],
    )?;
    let tolerance = |attr: &str| -> Result<f64, XoscError> {
        let v = r
            .scope
            .opt_num_in(r.text, node, attr, Quantity::Distance)?
            .unwrap_or(0.0);
        if v < 0.0 {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(node, attr),
                reason: format!("{attr} is a distance >= 0 m, not {v}"),
            });
        }
        Ok(v)
    };
    Ok(Action::Synchronize(Box::new(Synchronize {
        master: r.entity(node, "masterEntityRef")?,
        master_target: position::read(r, need(r.text, node, "TargetPositionMaster")?)?,
        target: position::read(r, need(r.text, node, "TargetPosition")?)?,
        master_tolerance_m: tolerance("targetToleranceMaster")?,
        tolerance_m: tolerance("targetTolerance")?,
        final_speed: child(node, "FinalSpeed")
            .map(|f| final_speed(r, f))
            .transpose()?,
    })))
}

/// A `<FinalSpeed>`: `AbsoluteSpeed` or `RelativeSpeedToMaster`, each with an optional
/// steady state.
fn final_speed(r: &Reader<'_>, node: Node<'_, '_>) -> Result<FinalSpeed, XoscError> {
    let (s, tag) = choice(r.text, node, &crate::support::FINAL_SPEED)?;
    let relative = if tag == "AbsoluteSpeed" {
        None
    } else {
        Some(
            match r
                .scope
                .opt_string(r.text, s, "speedTargetValueType")?
                .as_deref()
            {
                Some("delta") => false,
                Some("factor") => true,
                None => {
                    r.note(
                        s,
                        "a RelativeSpeedToMaster without speedTargetValueType is read as \
                         delta, as esmini reads it",
                    );
                    false
                }
                Some(other) => {
                    return Err(XoscError::Invalid {
                        pos: r.text.attr_pos(s, "speedTargetValueType"),
                        reason: format!("speedTargetValueType is delta or factor, not {other:?}"),
                    })
                }
            },
        )
    };
    let quantity = if relative == Some(true) {
        Quantity::Factor
    } else {
        Quantity::Speed
    };
    let value = r.scope.num_in(r.text, s, "value", quantity)?;
    only(
        r.text,
        s,
        &["TargetDistanceSteadyState", "TargetTimeSteadyState"],
    )?;
    let not_negative = |node: Node<'_, '_>, attr: &str, q: Quantity| -> Result<f64, XoscError> {
        let v = r.scope.num_in(r.text, node, attr, q)?;
        if v < 0.0 {
            return Err(XoscError::Invalid {
                pos: r.text.attr_pos(node, attr),
                reason: format!("a steady state's {attr} is >= 0, not {v}"),
            });
        }
        Ok(v)
    };
    let steady = if let Some(d) = child(s, "TargetDistanceSteadyState") {
        Some(SteadyState::Distance(not_negative(
            d,
            "distance",
            Quantity::Distance,
        )?))
    } else if let Some(t) = child(s, "TargetTimeSteadyState") {
        Some(SteadyState::Time(not_negative(
            t,
            "time",
            Quantity::Duration,
        )?))
    } else {
        None
    };
    if relative.is_none() && value < 0.0 {
        return Err(XoscError::Invalid {
            pos: r.text.attr_pos(s, "value"),
            reason: format!(
                "a final speed of {value} m/s drives backwards, which paracosm does not do \
                 (its storyboard moves entities forward only)"
            ),
        });
    }
    if steady.is_some() && relative.is_none() && value <= 0.0 {
        return Err(r.text.invalid(
            s,
            format!(
                "a steady state needs a final speed above 0 m/s (the entity would never reach \
                 its target at {value} m/s)"
            ),
        ));
    }
    Ok(FinalSpeed {
        relative,
        value,
        steady,
    })
}
