//! Global actions (OpenSCENARIO 1.3 User Guide, "Global actions"): `EnvironmentAction`
//! (inline or from an environment catalog), `ParameterAction` and `VariableAction` (set or
//! modify), `EntityAction` (add or delete an entity). Infrastructure (traffic signal),
//! traffic and monitor actions are refused, naming what is read.

use roxmltree::Node;

use super::Reader;
use crate::error::XoscError;
use crate::model::{Action, Environment};
use crate::params::ParamType;
use crate::support;
use crate::xml::{child, choice, elements, need, only};
use crate::Value;

/// A `<GlobalAction>`.
///
/// # Errors
/// [`XoscError::Unsupported`] for a global action paracosm does not read; Invalid for an
/// undeclared parameter or variable, a value not of its type, a modification of one that is
/// not a number, an environment value out of range.
pub(super) fn global(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Action, XoscError> {
    let (a, tag) = choice(r.text, node, &support::GLOBAL_ACTION)?;
    match tag {
        "InfrastructureAction" => {
            let s = need(r.text, a, "TrafficSignalAction")?;
            let (st, _) = choice(r.text, s, &support::TRAFFIC_SIGNAL_ACTION)?;
            Ok(Action::TrafficSignalState {
                signal: r.scope.string(r.text, st, "name")?,
                state: r.scope.string(r.text, st, "state")?,
            })
        }
        "EnvironmentAction" => {
            let (e, tag) = choice(r.text, a, &support::ENVIRONMENT_ACTION)?;
            let env = if tag == "Environment" {
                environment(&r.scoped(e)?, e)?
            } else {
                r.catalogs.read_entry(r, e, &["Environment"], environment)?
            };
            Ok(Action::Environment(env))
        }
        "EntityAction" => entity_action(r, a),
        "ParameterAction" => value_action(r, a, false),
        _ => value_action(r, a, true),
    }
}

/// An `EntityAction`: its `AddEntityAction` (with its `Position`) or `DeleteEntityAction`
/// on the entity `entityRef` names.
///
/// # Errors
/// Invalid for an entity the file does not declare; Unsupported for an entity selection.
fn entity_action(r: &Reader<'_>, a: Node<'_, '_>) -> Result<Action, XoscError> {
    let entity = r.entity(a, "entityRef")?;
    let (op, tag) = choice(r.text, a, &support::ENTITY_ACTION)?;
    if tag == "DeleteEntityAction" {
        return Ok(Action::DeleteEntity { entity });
    }
    Ok(Action::AddEntity {
        entity,
        position: super::position::read(r, need(r.text, op, "Position")?)?,
    })
}

/// A `ParameterAction` (`parameterRef`) or `VariableAction` (`variableRef`): its
/// `SetAction` or `ModifyAction` (1.0 and 1.1 name them so under `ParameterAction`; 1.2's
/// `ParameterSetAction` and `VariableSetAction` are the same elements).
fn value_action(r: &Reader<'_>, a: Node<'_, '_>, variable: bool) -> Result<Action, XoscError> {
    let attr = if variable {
        "variableRef"
    } else {
        "parameterRef"
    };
    let name = r.name_ref(a, attr)?;
    let ty = declared_type(r, a, attr, &name, variable)?;
    let (op, tag) = choice(r.text, a, &support::VALUE_ACTION)?;
    if tag == "SetAction" {
        let text = r.scope.string(r.text, op, "value")?;
        let value = ty
            .coerce(Value::Str(text.clone()))
            .map_err(|e| XoscError::Invalid {
                pos: r.text.attr_pos(op, "value"),
                reason: format!("{name} is of type {}: {}", ty.xsd_name(), e.0),
            })?;
        return Ok(Action::SetValue {
            name,
            variable,
            value,
        });
    }
    if !ty.is_numeric() {
        return Err(r.text.invalid(
            op,
            format!(
                "{name} is of type {}: only a number can be added to or multiplied",
                ty.xsd_name()
            ),
        ));
    }
    let rule = need(r.text, op, "Rule")?;
    let (v, tag) = choice(r.text, rule, &support::MODIFY_RULE)?;
    let by = r.scope.num(r.text, v, "value")?;
    Ok(Action::ModifyValue {
        name,
        variable,
        multiply: tag == "MultiplyByValue",
        by,
    })
}

/// The declared type of parameter or variable `name` (named by `node`'s attribute `attr`).
fn declared_type(
    r: &Reader<'_>,
    node: Node<'_, '_>,
    attr: &str,
    name: &str,
    variable: bool,
) -> Result<ParamType, XoscError> {
    let found = if variable {
        r.variables
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, ty)| *ty)
    } else {
        r.globals.iter().find(|(n, _)| n == name).map(|(_, ty)| *ty)
    };
    found.ok_or_else(|| XoscError::Invalid {
        pos: r.text.attr_pos(node, attr),
        reason: if variable {
            format!("variable {name:?} is not declared in the scenario's <VariableDeclarations>")
        } else {
            format!(
                "parameter {name:?} is not declared in the scenario's own \
                 <ParameterDeclarations> (a parameter a story, maneuver or catalog entry \
                 declares is not set or read while a test runs)"
            )
        },
    })
}

/// An `<Environment>` (inline, or a catalog entry read with its own scope): the parts it
/// gives. What paracosm's world has no counterpart for (clouds, wind, temperature, pressure,
/// the sun's azimuth) is noted.
///
/// # Errors
/// Invalid for a `dateTime` that is not one, a visual range <= 0, a negative illuminance,
/// precipitation intensity or friction scale factor, an unknown precipitation type.
pub(super) fn environment(r: &Reader<'_>, e: Node<'_, '_>) -> Result<Environment, XoscError> {
    if e.tag_name().name() != "Environment" {
        return Err(r.text.invalid(
            e,
            format!(
                "an environment catalog entry is an <Environment>, not <{}>",
                e.tag_name().name()
            ),
        ));
    }
    only(
        r.text,
        e,
        &[
            "ParameterDeclarations",
            "TimeOfDay",
            "Weather",
            "RoadCondition",
        ],
    )?;
    let (sc, t) = (&r.scope, r.text);
    let mut env = Environment::default();
    if let Some(tod) = child(e, "TimeOfDay") {
        let when = sc.string(t, tod, "dateTime")?;
        let secs = seconds_of_day(&when).ok_or_else(|| XoscError::Invalid {
            pos: t.attr_pos(tod, "dateTime"),
            reason: format!("dateTime {when:?} is not a date and time (YYYY-MM-DDThh:mm:ss)"),
        })?;
        env.time_of_day = Some((secs, sc.bool(t, tod, "animation")?));
    }
    if let Some(w) = child(e, "Weather") {
        weather(r, w, &mut env)?;
    }
    if let Some(rc) = child(e, "RoadCondition") {
        let f = sc.num(t, rc, "frictionScaleFactor")?;
        if !(0.0..=10.0).contains(&f) {
            return Err(XoscError::Invalid {
                pos: t.attr_pos(rc, "frictionScaleFactor"),
                reason: format!("frictionScaleFactor is 0 to 10, not {f}"),
            });
        }
        if elements(rc).next().is_some() || rc.attribute("wetness").is_some() {
            r.note(rc, support::ROAD_CONDITION.note);
        }
        env.friction_scale = Some(f);
    }
    Ok(env)
}

/// An `<Environment>`'s `<Weather>`: its sun, fog and precipitation into `env`; clouds,
/// temperature, pressure, wind and a dome image are noted.
///
/// # Errors
/// As [`environment`].
fn weather(r: &Reader<'_>, w: Node<'_, '_>, env: &mut Environment) -> Result<(), XoscError> {
    let (sc, t) = (&r.scope, r.text);
    only(t, w, &["Sun", "Fog", "Precipitation", "Wind", "DomeImage"])?;
    for a in [
        "cloudState",
        "fractionalCloudCover",
        "temperature",
        "atmosphericPressure",
    ] {
        if w.attribute(a).is_some() {
            r.note(
                w,
                format!("the weather's {a} {}", support::WEATHER_PART.note),
            );
        }
    }
    for c in ["Wind", "DomeImage"] {
        if let Some(n) = child(w, c) {
            r.note(n, format!("<{c}> {}", support::WEATHER_PART.note));
        }
    }
    if let Some(sun) = child(w, "Sun") {
        let lux = match sc.opt_num(t, sun, "illuminance")? {
            Some(v) => v,
            None => sc.num(t, sun, "intensity")?,
        };
        if !(0.0..=1e6).contains(&lux) {
            return Err(t.invalid(
                sun,
                format!("a sun's illuminance is 0 to 1,000,000 lx, not {lux}"),
            ));
        }
        let elevation = sc.num(t, sun, "elevation")?;
        r.note(sun, support::SUN_AZIMUTH.note);
        env.sun = Some((lux, elevation));
    }
    if let Some(fog) = child(w, "Fog") {
        let range = sc.num(t, fog, "visualRange")?;
        if range.is_nan() || range <= 0.0 {
            return Err(XoscError::Invalid {
                pos: t.attr_pos(fog, "visualRange"),
                reason: format!("a fog's visualRange is a distance > 0 m, not {range}"),
            });
        }
        if child(fog, "BoundingBox").is_some() {
            r.note(fog, support::FOG_BOX.note);
        }
        env.fog_visual_range_m = Some(range);
    }
    if let Some(p) = child(w, "Precipitation") {
        env.precipitation = Some(precipitation(r, p)?);
    }

    Ok(())
}

/// A `Precipitation`'s type (`dry`, `rain`, `snow`; 1.0's `type`) and intensity, mm/h (1.1's
/// `precipitationIntensity`, or 1.0's `intensity` share in `[0, 1]` of
/// [`FULL_PRECIPITATION_MM_PER_H`], noted).
///
/// # Errors
/// Invalid for another type, a negative intensity or a share above 1.
fn precipitation(r: &Reader<'_>, p: Node<'_, '_>) -> Result<(String, f64), XoscError> {
    let (t, sc) = (r.text, &r.scope);
    let kind = match sc.opt_string(t, p, "precipitationType")? {
        Some(k) => k,
        // 1.0 names it `type`.
        None => sc.string(t, p, "type")?,
    };
    if !["dry", "rain", "snow"].contains(&kind.as_str()) {
        return Err(t.invalid(
            p,
            format!("precipitationType is dry, rain or snow, not {kind:?}"),
        ));
    }
    let intensity = match sc.opt_num(t, p, "precipitationIntensity")? {
        Some(v) => v,
        // 1.0's `intensity` is a share, [0, 1], of no stated rate.
        None => match sc.opt_num(t, p, "intensity")? {
            None => 0.0,
            Some(share) if (0.0..=1.0).contains(&share) => {
                if share > 0.0 {
                    r.note(
                        p,
                        format!(
                            "OpenSCENARIO 1.0's precipitation intensity {share} (a share in [0, 1], of \
                             no stated rate) is read as {} mm/h: a share of {FULL_PRECIPITATION_MM_PER_H} mm/h, \
                             the WMO's threshold of violent rain",
                            share * FULL_PRECIPITATION_MM_PER_H
                        ),
                    );
                }
                share * FULL_PRECIPITATION_MM_PER_H
            }
            Some(share) => {
                return Err(XoscError::Invalid {
                    pos: t.attr_pos(p, "intensity"),
                    reason: format!(
                    "OpenSCENARIO 1.0's precipitation intensity is a share in [0, 1], not {share}"
                ),
                })
            }
        },
    };
    if intensity.is_nan() || intensity < 0.0 {
        return Err(t.invalid(
            p,
            format!("a precipitation's intensity is >= 0 mm/h, not {intensity}"),
        ));
    }
    Ok((kind, intensity))
}

/// What OpenSCENARIO 1.0's precipitation `intensity` of 1 (a share in `[0, 1]`; 1.1 replaced
/// it by `precipitationIntensity` in mm/h) is read as, mm/h: the World Meteorological
/// Organization's threshold of violent rain (WMO Guide to Instruments and Methods of
/// Observation, No. 8, rain intensity classes: light < 2.5, moderate to 10, heavy to 50,
/// violent above, mm/h). The standard states no rate; this choice is noted where it is read.
pub(crate) const FULL_PRECIPITATION_MM_PER_H: f64 = 50.0;

/// The time of day of an XSD `dateTime` (`YYYY-MM-DDThh:mm:ss[.fff][zone]`), s after
/// midnight as written (the zone is the place's own clock).
fn seconds_of_day(when: &str) -> Option<f64> {
    let (_, clock) = when.trim().split_once('T')?;
    let mut parts = clock.splitn(3, ':');
    let h: f64 = parts.next()?.parse().ok()?;
    let m: f64 = parts.next()?.parse().ok()?;
    let rest = parts.next()?;
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(rest.len());
    let s: f64 = rest[..end].parse().ok()?;
    ((0.0..24.0).contains(&h) && (0.0..60.0).contains(&m) && (0.0..61.0).contains(&s))
        .then_some(h * 3600.0 + m * 60.0 + s)
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_date_time_gives_its_time_of_day() {
        let s = super::seconds_of_day("2025-06-13T06:30:15.500+02:00").unwrap();
        assert!((s - (6.0 * 3600.0 + 30.0 * 60.0 + 15.5)).abs() < 1e-9);
        assert_eq!(super::seconds_of_day("2025-06-13"), None);
        assert_eq!(super::seconds_of_day("2025-06-13T25:00:00"), None);
    }
}
