//! Controller actions (OpenSCENARIO 1.3 User Guide, "Controller actions"): assigning a
//! controller, overriding its values (read only when every value is inactive) and
//! activating its domains.

use roxmltree::Node;

use super::Reader;
use crate::error::XoscError;
use crate::model::Action;
use crate::xml::{child, choice, elements, only};

/// The values an `OverrideControllerValueAction` may override (1.0 to 1.3).
const OVERRIDES: [&str; 6] = [
    "Throttle",
    "Brake",
    "Clutch",
    "ParkingBrake",
    "SteeringWheel",
    "Gear",
];

/// A `<ControllerAction>`: 1.0's pair of `AssignControllerAction` and
/// `OverrideControllerValueAction`, or 1.1+'s one of them or an `ActivateControllerAction`.
///
/// # Errors
/// Unsupported at an override that is active (paracosm's vehicles have no pedals, wheel or
/// gears to override), at an activated lighting or animation domain; what reading the
/// controller returns.
pub(super) fn read(r: &Reader<'_>, a: Node<'_, '_>) -> Result<Action, XoscError> {
    only(
        r.text,
        a,
        &[
            "AssignControllerAction",
            "OverrideControllerValueAction",
            "ActivateControllerAction",
        ],
    )?;
    if let Some(o) = child(a, "OverrideControllerValueAction") {
        inactive_override(r, o)?;
    }
    if let Some(c) = child(a, "ActivateControllerAction") {
        return super::action::activate(r, c);
    }
    match child(a, "AssignControllerAction") {
        Some(c) => assign(r, c),
        None => Ok(Action::OverrideController),
    }
}

/// Checks that every value of an `OverrideControllerValueAction` is inactive (the action
/// then does nothing: it is noted).
fn inactive_override(r: &Reader<'_>, o: Node<'_, '_>) -> Result<(), XoscError> {
    only(r.text, o, &OVERRIDES)?;
    for v in elements(o) {
        // 1.2 wraps a value in a choice (`<Brake><BrakePercent .../></Brake>`) and keeps
        // `active` on the value itself.
        if r.scope.opt_bool(r.text, v, "active")? == Some(true) {
            return Err(r.text.unsupported(
                v,
                format!(
                    "an active override of the {} is not supported: paracosm's vehicles have \
                     no pedals, steering wheel or gears to override, their motion is set by \
                     the storyboard or the system under test",
                    v.tag_name().name()
                ),
            ));
        }
    }
    r.note(o, crate::support::INACTIVE_OVERRIDE.note);
    Ok(())
}

/// An `AssignControllerAction`: the controller (inline, from a catalog, or in 1.3's
/// `ObjectController`), its kind (CARLA's `module` property, esmini's `esminiController`)
/// and the domains it activates (`activateLateral`, `activateLongitudinal`, OpenSCENARIO
/// 1.2+; without them none, as the standard and esmini read it: an
/// `ActivateControllerAction` activates it). In a file written for CARLA, whose
/// scenario_runner hands the entity to an assigned controller at once, both (noted).
fn assign(r: &Reader<'_>, c: Node<'_, '_>) -> Result<Action, XoscError> {
    for a in ["activateAnimation", "activateLighting"] {
        if r.scope.opt_bool(r.text, c, a)? == Some(true) {
            return Err(XoscError::Unsupported {
                pos: r.text.attr_pos(c, a),
                reason: format!("{a} is not supported: paracosm draws no lights or animations"),
            });
        }
    }
    let holder = child(c, "ObjectController").unwrap_or(c);
    let (def, tag) = choice(r.text, holder, &crate::support::CONTROLLER)?;
    let (controller, kind) = if tag == "Controller" {
        name_and_kind(r, def)?
    } else {
        r.catalogs
            .read_entry(r, def, &["Controller"], name_and_kind)?
    };
    let mut lateral = r.scope.opt_bool(r.text, c, "activateLateral")?;
    let mut longitudinal = r.scope.opt_bool(r.text, c, "activateLongitudinal")?;
    if r.carla && lateral.is_none() && longitudinal.is_none() {
        r.note(
            c,
            format!(
                "controller {controller:?} takes the entity over at once, as CARLA's \
                 scenario_runner reads an assignment"
            ),
        );
        (lateral, longitudinal) = (Some(true), Some(true));
    }
    Ok(Action::AssignController {
        controller,
        kind,
        lateral,
        longitudinal,
    })
}

/// A `Controller` element's name and kind: the value of its `module` (CARLA) or
/// `esminiController` (esmini) property.
fn name_and_kind(r: &Reader<'_>, def: Node<'_, '_>) -> Result<(String, Option<String>), XoscError> {
    let name = r.scope.string(r.text, def, "name")?;
    let mut kind = None;
    if let Some(props) = child(def, "Properties") {
        for p in elements(props).filter(|p| p.has_tag_name("Property")) {
            let key = r.scope.string(r.text, p, "name")?;
            if key == "module" || key == "esminiController" {
                kind = Some(r.scope.string(r.text, p, "value")?);
            }
        }
    }
    Ok((name, kind))
}
