//! Varied and opened OpenSCENARIO parameters as parameters of paracosm's space.

use paracosm_generators::{Density, Param, Value};
use paracosm_openscenario::distribution::{Dist, ValueSets, Varied};
use paracosm_openscenario::model::Scenario;
use paracosm_openscenario::params::{ParamType, ValueError};

use crate::ScenarioError;

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
/// the file's own grid (none for a stochastic distribution), and what paracosm does not
/// honour of its distribution. A set becomes its levels; a range with a step its levels, or
/// with `continuous` the interval over its range; a stochastic distribution the interval of
/// its range (its levels for a probability set) with its density for random sampling
/// (normal and log-normal truncated to the range, a histogram's bins, a set's weights;
/// coverage strategies cover the whole range). A Poisson distribution is drawn uniformly over
/// its range, with a note.
pub fn varied_param(v: &Varied, continuous: bool) -> (Param, Option<u64>, Option<String>) {
    let name = v.name.as_str();
    let interval = |lo: f64, hi: f64, density: Option<Density>| Param {
        density,
        ..Param::interval(name, lo, hi, "")
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
            let weights = pairs.iter().map(|(_, w)| *w).collect();
            let p = Param {
                density: Some(Density::Weights(weights)),
                ..Param::levels(name, levels_of(&texts))
            };
            (p, None, None)
        }
        Dist::Normal { mean, variance, .. } => {
            let sd = variance.sqrt();
            let (lo, hi, note) = bounds(v, (mean - SPREAD * sd, mean + SPREAD * sd));
            let d = Density::Normal { mean: *mean, sd };
            (interval(lo, hi, Some(d)), None, note)
        }
        Dist::LogNormal { mu, sigma, .. } => {
            let (lo, hi, note) = bounds(
                v,
                ((mu - SPREAD * sigma).exp(), (mu + SPREAD * sigma).exp()),
            );
            let d = Density::LogNormal {
                mu: *mu,
                sigma: *sigma,
            };
            (interval(lo, hi, Some(d)), None, note)
        }
        Dist::Histogram(bins) => {
            let (lo, hi) = v.dist.range().unwrap_or((0.0, 0.0));
            (
                interval(lo, hi, Some(Density::Histogram(bins.clone()))),
                None,
                None,
            )
        }
        Dist::Poisson { expected, .. } => {
            let (lo, hi, _) = bounds(v, (0.0, expected + SPREAD * expected.sqrt() + 1.0));
            let note = format!(
                "{}: {name}'s Poisson distribution gives its range [{lo}, {hi}]; paracosm's \
                 random strategies draw uniformly over it (as real numbers)",
                v.pos
            );
            (interval(lo, hi, None), None, Some(note))
        }
        other => {
            let (lo, hi) = other.range().unwrap_or((0.0, 0.0));
            (interval(lo, hi, None), None, None)
        }
    }
}

/// How many standard deviations either side of the mean cover a distribution that its file
/// does not truncate with a `Range`.
const SPREAD: f64 = 6.0;

/// The range of `v`'s values: its truncating `Range`, else `wide` (the distribution's bulk),
/// with a note saying so.
fn bounds(v: &Varied, wide: (f64, f64)) -> (f64, f64, Option<String>) {
    match v.dist.range() {
        Some((lo, hi)) => (lo, hi, None),
        None => (
            wide.0,
            wide.1,
            Some(format!(
                "{}: {}'s distribution has no <Range>: paracosm covers [{}, {}] ({SPREAD} \
                 standard deviations either side of its mean), and draws it truncated there",
                v.pos, v.name, wide.0, wide.1
            )),
        ),
    }
}

/// The parameter `--open Name=lo..hi` or `--open Name=a,b,c` gives, for a parameter the
/// scenario declares and `space` does not already hold, checked against its constraint
/// groups (both ends of an interval, every level).
///
/// # Errors
/// [`ScenarioError::Input`] naming the option: the text is not `Name=lo..hi` or `Name=a,b,...`,
/// the name is not declared or is varied already, or a value breaks the declaration's
/// constraint groups.
pub fn open_param(
    text: &str,
    scenario: &Scenario,
    space: &[Param],
) -> Result<Param, ScenarioError> {
    open_levels(text, scenario, space).map_err(|why| ScenarioError::Input {
        path: std::path::PathBuf::from(&scenario.file),
        message: format!("--open {text}: {why}"),
    })
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
        if decl.ty != ParamType::Double {
            // An interval's values are real numbers: a whole-number, boolean or text
            // parameter would be handed 0.5 and every such test would end in error.
            return Err(format!(
                "{name} is declared {} (at {}): an interval gives it real numbers; open it \
                 as levels, Name=a,b,c",
                decl.ty.xsd_name(),
                decl.pos
            )
            .into());
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
        let v = decl.ty.coerce(v).map_err(|why| {
            ValueError(format!(
                "level {t:?}: {why} (the parameter is declared {} at {})",
                decl.ty.xsd_name(),
                decl.pos
            ))
        })?;
        check(v)?;
    }
    Ok(Param::levels(name, levels_of(&texts)))
}

/// The parameter for the `k`-th `ValueSetDistribution` of a variation file: one level per
/// value set, named `value_set_K` and written `Name=value, Name=value` (the assignments the
/// set makes together), with the number of sets the file's grid has for it.
///
/// # Errors
/// [`ScenarioError::Input`] naming the variation file's position when a set assigns a parameter the
/// scenario does not declare.
pub fn value_sets_param(
    file: &std::path::Path,
    k: usize,
    sets: &ValueSets,
    scenario: &Scenario,
) -> Result<(Param, u64), ScenarioError> {
    let mut levels = Vec::new();
    for set in &sets.sets {
        for a in set {
            let Some((decl, _)) = scenario.params.iter().find(|(d, _)| d.name == a.name) else {
                return Err(ScenarioError::Input {
                    path: file.to_path_buf(),
                    message: format!(
                        "{}: parameter {:?} is assigned but the scenario does not declare it",
                        a.pos, a.name
                    ),
                });
            };
            // The value is checked here, at load, as the declaration types and constrains
            // it: a value no test could use ends the load, not every test of its set.
            let v = paracosm_openscenario::Value::Str(a.value.clone());
            let checked = decl.ty.coerce(v).and_then(|v| {
                scenario
                    .scope
                    .check_constraints(decl, &v)
                    .map_err(|why| ValueError(why.to_string()))
            });
            if let Err(why) = checked {
                return Err(ScenarioError::Input {
                    path: file.to_path_buf(),
                    message: format!(
                        "{}: parameter {} = {:?}: {why} (declared {} at {})",
                        a.pos,
                        a.name,
                        a.value,
                        decl.ty.xsd_name(),
                        decl.pos
                    ),
                });
            }
        }
        levels.push(Value::Text(set_text(
            set.iter().map(|a| (a.name.as_str(), a.value.as_str())),
        )));
    }
    let n = levels.len() as u64;
    Ok((Param::levels(&format!("value_set_{k}"), levels), n))
}

/// A value set's level as listed and recorded: `Name=value, Name=value` in the set's order,
/// a name or value quoted as a Rust string literal (`"40, LeadSpeed=0.5"`) when it is empty,
/// holds `,`, `=`, `"`, `\\` or a control character, or starts or ends with a space, so that
/// two different sets never read alike.
pub fn set_text<'a>(assignments: impl Iterator<Item = (&'a str, &'a str)>) -> String {
    fn shown(s: &str) -> String {
        let plain = !s.is_empty()
            && s.trim() == s
            && !s
                .chars()
                .any(|c| matches!(c, ',' | '=' | '"' | '\\') || c.is_control());
        if plain {
            s.to_owned()
        } else {
            format!("{s:?}")
        }
    }
    let parts: Vec<String> = assignments
        .map(|(name, value)| format!("{}={}", shown(name), shown(value)))
        .collect();
    parts.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_sets_that_differ_are_listed_differently() {
        let one = set_text([("A", "40, LeadSpeed=0.5")].into_iter());
        let two = set_text([("A", "40"), ("LeadSpeed", "0.5")].into_iter());
        assert_eq!(one, r#"A="40, LeadSpeed=0.5""#);
        assert_eq!(two, "A=40, LeadSpeed=0.5");
        assert_ne!(one, two);
        assert_eq!(set_text([("A", "")].into_iter()), r#"A="""#);
        assert_eq!(set_text([("A", " x")].into_iter()), r#"A=" x""#);
        assert_eq!(
            set_text([("A", r#"say "hi""#)].into_iter()),
            r#"A="say \"hi\"""#
        );
        // Plain values are listed as written (the ALKS suite's levels are unchanged).
        assert_eq!(
            set_text([("Ego_Speed", "16.67"), ("Road", "r.xodr")].into_iter()),
            "Ego_Speed=16.67, Road=r.xodr"
        );
    }
}
