//! Varied and opened OpenSCENARIO parameters as parameters of paracosm's space.

use paracosm_generators::{Param, Value};
use paracosm_openscenario::distribution::{Dist, ValueSets, Varied};
use paracosm_openscenario::model::Scenario;
use paracosm_openscenario::params::ValueError;

use crate::Error;

/// Levels as paracosm values: whole numbers as `Int` (lane ids), other numbers as `Real`,
/// anything else as `Text` (road files), all of one kind.
fn levels_of(texts: &[String]) -> Vec<Value> {
    let ints: Option<Vec<i64>> = texts.iter().map(|t| t.trim().parse::<i64>().ok()).collect();
    if let Some(ints) = ints {
        return ints.into_iter().map(Value::Int).collect();
    }
    let reals: Option<Vec<f64>> = texts
        .iter()
        .map(|t| t.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect();
    match reals {
        Some(r) => r.into_iter().map(Value::Real).collect(),
        None => texts.iter().cloned().map(Value::Text).collect(),
    }
}

/// The parameter of paracosm's space for a varied parameter, the number of levels it has in
/// the file's own grid (none for a stochastic distribution), and what paracosm does not yet
/// honour of its distribution. A set becomes its levels; a range with a step its levels, or
/// with `continuous` the interval over its range; a stochastic distribution the interval of
/// its range (random sampling draws uniformly over it).
pub fn varied_param(v: &Varied, continuous: bool) -> (Param, Option<u64>, Option<String>) {
    let name = v.name.as_str();
    let limit = |what: &str| {
        Some(format!(
            "{}: {name}'s {what} gives its range; paracosm's random strategies draw uniformly over it (its weights are not yet applied)",
            v.pos
        ))
    };
    match &v.dist {
        Dist::Set(texts) => (
            Param::levels(name, levels_of(texts)),
            Some(texts.len() as u64),
            None,
        ),
        Dist::Range { lo, hi, .. } if continuous => {
            let n = v.dist.levels().map(|l| l.len() as u64);
            (Param::interval(name, *lo, *hi, ""), n, None)
        }
        Dist::Range { .. } => {
            let texts = v.dist.levels().unwrap_or_default();
            let n = texts.len() as u64;
            (Param::levels(name, levels_of(&texts)), Some(n), None)
        }
        Dist::ProbabilitySet(pairs) => {
            let texts: Vec<String> = pairs.iter().map(|(t, _)| t.clone()).collect();
            (
                Param::levels(name, levels_of(&texts)),
                None,
                limit("probability set"),
            )
        }
        other => {
            let (lo, hi) = other.range().unwrap_or((0.0, 0.0));
            (
                Param::interval(name, lo, hi, ""),
                None,
                limit("distribution"),
            )
        }
    }
}

/// The parameter `--open Name=lo..hi` or `--open Name=a,b,c` gives, for a parameter the
/// scenario declares and `space` does not already hold, checked against its constraint
/// groups (both ends of an interval, every level).
///
/// # Errors
/// [`Error::BadInput`] naming the option: the text is not `Name=lo..hi` or `Name=a,b,...`,
/// the name is not declared or is varied already, or a value breaks the declaration's
/// constraint groups.
pub fn open_param(text: &str, scenario: &Scenario, space: &[Param]) -> Result<Param, Error> {
    open_levels(text, scenario, space)
        .map_err(|why| Error::BadInput(format!("--open {text}: {why}")))
}

fn open_levels(text: &str, scenario: &Scenario, space: &[Param]) -> Result<Param, ValueError> {
    let (name, spec) = text
        .split_once('=')
        .ok_or_else(|| ValueError("write Name=lo..hi or Name=a,b,c".into()))?;
    let name = name.trim();
    let Some((decl, _)) = scenario.params.iter().find(|(d, _)| d.name == name) else {
        let names: Vec<&str> = scenario
            .params
            .iter()
            .map(|(d, _)| d.name.as_str())
            .collect();
        return Err(ValueError(format!(
            "{name:?} is not declared; the scenario declares {}",
            names.join(", ")
        )));
    };
    if space.iter().any(|p| p.name == name) {
        return Err(format!("{name} is varied already").into());
    }
    let check = |v: paracosm_openscenario::Value| {
        scenario
            .scope
            .check_constraints(decl, &v)
            .map_err(|why| ValueError(format!("{why} (declared at {})", decl.pos)))
    };
    if let Some((lo, hi)) = spec.split_once("..") {
        let num = |t: &str| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| ValueError(format!("{t:?} is not a number")))
        };
        let (lo, hi) = (num(lo)?, num(hi)?);
        if lo >= hi {
            return Err(format!("the interval needs lo < hi, not {lo}..{hi}").into());
        }
        check(paracosm_openscenario::Value::Num(lo))?;
        check(paracosm_openscenario::Value::Num(hi))?;
        return Ok(Param::interval(name, lo, hi, ""));
    }
    let texts: Vec<String> = spec.split(',').map(|t| t.trim().to_string()).collect();
    if texts.iter().any(String::is_empty) {
        return Err(ValueError("a level is empty".into()));
    }
    for t in &texts {
        let v = match t.parse::<f64>() {
            Ok(n) if n.is_finite() => paracosm_openscenario::Value::Num(n),
            _ => paracosm_openscenario::Value::Str(t.clone()),
        };
        check(v)?;
    }
    Ok(Param::levels(name, levels_of(&texts)))
}

/// The parameter for the `k`-th `ValueSetDistribution` of a variation file: one level per
/// value set, named `value_set_K` and written `Name=value, Name=value` (the assignments the
/// set makes together), with the number of sets the file's grid has for it.
///
/// # Errors
/// [`Error::Input`] naming the variation file's position when a set assigns a parameter the
/// scenario does not declare.
pub fn value_sets_param(
    file: &std::path::Path,
    k: usize,
    sets: &ValueSets,
    scenario: &Scenario,
) -> Result<(Param, u64), Error> {
    let mut levels = Vec::new();
    for set in &sets.sets {
        for a in set {
            if !scenario.params.iter().any(|(d, _)| d.name == a.name) {
                return Err(Error::Input {
                    path: file.to_path_buf(),
                    message: format!(
                        "{}: parameter {:?} is assigned but the scenario does not declare it",
                        a.pos, a.name
                    ),
                });
            }
        }
        let text: Vec<String> = set
            .iter()
            .map(|a| format!("{}={}", a.name, a.value))
            .collect();
        levels.push(Value::Text(text.join(", ")));
    }
    let n = levels.len() as u64;
    Ok((Param::levels(&format!("value_set_{k}"), levels), n))
}
