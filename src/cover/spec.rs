//! `--space SPEC`: a built-in scenario's space, a scenario program's (`.star`), or a small TOML
//! file.

use std::path::Path;

use serde::Deserialize;
use thiserror::Error;

use paracosm_generators::{Domain, Param, ParamSpace, Value};

/// Errors loading a space spec.
#[derive(Debug, Error)]
pub enum SpecError {
    /// Neither a built-in scenario nor a readable file.
    #[error("`{0}` is neither a built-in scenario ({1}) nor a readable file")]
    NotFound(String, String),
    /// The file exists but cannot be read: a folder, unreadable, larger than
    /// [`paracosm_scenarios::text_file::MAX_SOURCE_BYTES`], or not UTF-8 (line and column).
    #[error("{0}: cannot read: {1}")]
    Unreadable(String, String),
    /// The scenario program (`.star`) does not load; the message names its file, line and
    /// column.
    #[error("{0}")]
    Program(String),
    /// The TOML file does not parse or describes an invalid space.
    #[error("{file}: {reason}")]
    Invalid {
        /// The file.
        file: String,
        /// What is wrong, with the line and column where the TOML parser gives them.
        reason: String,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecFile {
    param: Vec<SpecParam>,
    #[serde(default)]
    constraint: Vec<SpecConstraint>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecConstraint {
    name: toml::Spanned<String>,
    require: toml::Spanned<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecParam {
    name: toml::Spanned<String>,
    interval: Option<toml::Spanned<Vec<f64>>>,
    levels: Option<toml::Spanned<Vec<toml::Value>>>,
    unit: Option<String>,
}

/// The space named by `spec`: a built-in scenario name (e.g. `pedestrian-crossing`), a scenario
/// program (a file ending in `.star`: the space of its open parameters, as `paracosm-fuzz` samples
/// it), or a TOML file of `[[param]]` tables, each with a `name`, either `interval = [lo, hi]` or
/// `levels = [...]` (integers, numbers or strings), and an optional `unit`:
///
/// ```toml
/// [[param]]
/// name = "walking_speed"
/// interval = [0.5, 10.0]
/// unit = "m/s"
///
/// [[param]]
/// name = "lanes"
/// levels = [2, 4, 6]
///
/// [[constraint]]
/// name = "slow_on_two_lanes"
/// require = "lanes != 2 or walking_speed < 5"
/// ```
///
/// Each `[[constraint]]` is a Starlark expression over the parameters' names that is `True`
/// where a point is valid ([`paracosm_scenarios::lang::constraint::ExprConstraint`]); the
/// space refuses constraints that leave no valid point
/// ([`ParamSpace::valid_fraction`]).
///
/// # Errors
/// [`SpecError`] naming the file, and the line and column of a TOML error or of the program's
/// error ([`SpecError::Program`]).
pub fn load_space(spec: &str) -> Result<ParamSpace, SpecError> {
    if let Ok(s) = paracosm_scenarios::builtin(spec) {
        return Ok(s.space().clone());
    }
    let path = Path::new(spec);
    if spec.ends_with(".star") {
        return paracosm_scenarios::load(spec)
            .map(|s| s.space().clone())
            .map_err(|e| SpecError::Program(e.to_string()));
    }
    if !path.exists() {
        return Err(SpecError::NotFound(
            spec.to_owned(),
            paracosm_scenarios::builtin_names().join(", "),
        ));
    }
    let text = paracosm_scenarios::text_file::read_text(
        path,
        paracosm_scenarios::text_file::MAX_SOURCE_BYTES,
    )
    .map_err(|e| SpecError::Unreadable(spec.to_owned(), e.to_string()))?;
    parse_space(spec, &text)
}

/// The space described by the TOML `text` of the file named `file` (see [`load_space`]).
///
/// # Errors
/// [`SpecError::Invalid`] naming the file, with the line and column of a TOML error.
pub fn parse_space(file: &str, text: &str) -> Result<ParamSpace, SpecError> {
    let invalid = |reason: String| SpecError::Invalid {
        file: file.to_owned(),
        reason,
    };
    // "line L, column C: " of a byte offset of `text`.
    let at = |start: usize| {
        let before = &text[..start.min(text.len())];
        let line = before.matches('\n').count() + 1;
        let col = before.chars().count()
            - before
                .rfind('\n')
                .map_or(0, |i| before[..=i].chars().count())
            + 1;
        format!("line {line}, column {col}: ")
    };
    let parsed: SpecFile = toml::from_str(text).map_err(|e| {
        let place = e.span().map(|s| at(s.start)).unwrap_or_default();
        invalid(format!("{place}{}", e.message()))
    })?;
    let mut params: Vec<Param> = Vec::new();
    for p in parsed.param {
        let name_at = at(p.name.span().start);
        let name = p.name.into_inner();
        if params.iter().any(|q| q.name == name) {
            return Err(invalid(format!(
                "{name_at}parameter `{name}` is declared twice"
            )));
        }
        let domain = match (p.interval, p.levels) {
            (Some(interval), None) => {
                let here = at(interval.span().start);
                match interval.into_inner()[..] {
                    [lo, hi] if lo < hi => Domain::Interval { lo, hi },
                    [lo, hi] => {
                        return Err(invalid(format!(
                            "{here}parameter `{name}`: interval [{lo}, {hi}] is empty: lo must \
                             be below hi"
                        )))
                    }
                    ref other => {
                        return Err(invalid(format!(
                            "{here}parameter `{name}`: interval = [lo, hi] takes two numbers, \
                             got {}",
                            other.len()
                        )))
                    }
                }
            }
            (None, Some(levels)) => Domain::Levels(
                levels
                    .into_inner()
                    .into_iter()
                    .map(|v| match v {
                        toml::Value::Integer(i) => Ok(Value::Int(i)),
                        toml::Value::Float(x) => Ok(Value::Real(x)),
                        toml::Value::String(s) => Ok(Value::Text(s)),
                        toml::Value::Boolean(b) => Ok(Value::Bool(b)),
                        other => Err(invalid(format!(
                            "{name_at}parameter `{name}`: level {other} is not a number, a bool \
                             or a string"
                        ))),
                    })
                    .collect::<Result<_, _>>()?,
            ),
            _ => {
                return Err(invalid(format!(
                    "{name_at}parameter `{name}` needs exactly one of `interval` and `levels`"
                )))
            }
        };
        // The same level twice would be one value counted as two: k-wise coverage would ask
        // for tuples nobody can tell apart. Levels are compared as written (1 and 1.0 alike).
        if let Domain::Levels(levels) = &domain {
            for (j, l) in levels.iter().enumerate() {
                if levels[..j].iter().any(|m| m.to_string() == l.to_string()) {
                    return Err(invalid(format!(
                        "{name_at}parameter `{name}`: the level {l} is listed twice"
                    )));
                }
            }
        }
        params.push(Param {
            name,
            domain,
            unit: p.unit,
            density: None,
        });
    }
    let space = ParamSpace::new(params).map_err(|e| invalid(e.to_string()))?;
    with_constraints(file, space, parsed.constraint, &at)
}

/// `space` with the file's `[[constraint]]`s, checked to leave some valid point; `at` gives
/// the "line L, column C: " of a byte offset of the file.
///
/// # Errors
/// [`SpecError::Invalid`]: a constraint named twice, one that does not build
/// ([`paracosm_scenarios::lang::constraint::ExprConstraint::new`]), or constraints no point
/// meets.
fn with_constraints(
    file: &str,
    space: ParamSpace,
    specs: Vec<SpecConstraint>,
    at: &dyn Fn(usize) -> String,
) -> Result<ParamSpace, SpecError> {
    let invalid = |reason: String| SpecError::Invalid {
        file: file.to_owned(),
        reason,
    };
    let mut constraints: Vec<std::sync::Arc<dyn paracosm_generators::Constraint>> = Vec::new();
    for c in specs {
        let here = at(c.require.span().start);
        let name = c.name.into_inner();
        if constraints.iter().any(|d| d.name() == name) {
            return Err(invalid(format!(
                "{here}constraint `{name}` is declared twice"
            )));
        }
        let label = format!("{file}: [[constraint]] {name}");
        let made = paracosm_scenarios::lang::constraint::ExprConstraint::new(
            &name,
            c.require.get_ref(),
            &label,
            &space,
        )
        .map_err(|e| invalid(format!("{here}{e}")))?;
        constraints.push(std::sync::Arc::new(made));
    }
    if constraints.is_empty() {
        return Ok(space);
    }
    let space = space.with_constraints(constraints);
    space
        .valid_fraction()
        .map_err(|e| invalid(format!("{e}: no test could be run in this space")))?;
    Ok(space)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Settings that make no sense are refused with the line and column of the parameter:
    /// an interval of three numbers (the third was dropped), an empty one, a name twice.
    #[test]
    fn senseless_settings_name_their_line() {
        for (text, needle) in [
            (
                "[[param]]\nname = \"a\"\ninterval = [0, 1, 2]\n",
                "line 3, column 12: parameter `a`: interval = [lo, hi] takes two numbers, got 3",
            ),
            (
                "[[param]]\nname = \"a\"\ninterval = [1, 0]\n",
                "line 3, column 12: parameter `a`: interval [1, 0] is empty",
            ),
            (
                "[[param]]\nname = \"a\"\nlevels = [1]\n[[param]]\nname = \"a\"\nlevels = [2]\n",
                "line 5, column 8: parameter `a` is declared twice",
            ),
        ] {
            let e = parse_space("s.toml", text).unwrap_err().to_string();
            assert!(e.contains(needle), "{e}");
        }
    }

    #[test]
    fn loads_builtin_and_toml_spaces_and_reports_errors_with_position() {
        assert_eq!(load_space("pedestrian-crossing").unwrap().params().len(), 2);
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("s.toml");
        std::fs::write(
            &good,
            "[[param]]\nname = \"v\"\ninterval = [0.5, 10.0]\nunit = \"m/s\"\n\n[[param]]\nname = \"lanes\"\nlevels = [2, 4]\n",
        )
        .unwrap();
        let s = load_space(good.to_str().unwrap()).unwrap();
        assert_eq!(s.level_counts(), [2]);
        assert_eq!(s.continuous_dims(), 1);
        let bad = dir.path().join("b.toml");
        std::fs::write(&bad, "[[param]]\nname = \"v\"\ninterval = [0.5, \n").unwrap();
        let e = load_space(bad.to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains("line 3"), "{e}");
        let both = dir.path().join("c.toml");
        std::fs::write(&both, "[[param]]\nname = \"v\"\n").unwrap();
        assert!(load_space(both.to_str().unwrap())
            .unwrap_err()
            .to_string()
            .contains("exactly one of"));
        assert!(matches!(load_space("nope"), Err(SpecError::NotFound(..))));
    }

    #[test]
    fn a_scenario_program_gives_the_space_of_its_open_parameters() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("w.star");
        std::fs::write(
            &good,
            "w = World(fog = VarEnum([0.0, 0.3, 0.6]))\n\
             r = RoadSegment(len = 120.0, nlanes = 2)\n\
             ego = AutonomousVehicle(loc = r.onLane(1, 10.0))\n\
             gap = VarInterval(20.0, 60.0, unit = \"m\")\n\
             lead = Car(loc = r.onLane(1, gap), speed = Const(5.0))\n\
             w.place(r, ego, lead)\n\
             CollisionMonitor(ego)\n",
        )
        .unwrap();
        let s = load_space(good.to_str().unwrap()).unwrap();
        let names: Vec<&str> = s.params().iter().map(|p| p.name.as_str()).collect();
        assert!(
            names.contains(&"w.fog") && names.contains(&"gap"),
            "{names:?}"
        );
        assert_eq!(s.level_counts(), [3]);
        assert_eq!(s.continuous_dims(), 1);
        // A program that does not load is an error naming its file, line and column, not a
        // TOML error.
        let bad = dir.path().join("b.star");
        std::fs::write(&bad, "w = World(fog = VarInterval(0.5))\n").unwrap();
        let e = load_space(bad.to_str().unwrap()).unwrap_err();
        assert!(matches!(e, SpecError::Program(_)), "{e:?}");
        let e = e.to_string();
        assert!(e.contains("b.star:1:"), "{e}");
    }
}
