//! Warnings for a parameter declared in one unit (`unit = "km/h"`) that feeds an input in
//! another (LANGUAGE.md, "Warnings").

use super::names::Syntax;
use super::scene::ParamDecl;
use super::types;
use crate::scenario::Warning;

/// A warning for each parameter declared with a `unit=` that is passed whole to an input in
/// another unit (`unit = "km/h"` feeding `Car(speed=)`, in m/s).
pub fn unit_warnings(params: &[(String, ParamDecl)], syntax: &Syntax) -> Vec<Warning> {
    // Spellings of one unit compare equal: spaces dropped, `m/s^2` and `m/s**2` are `m/s²`.
    let norm = |u: &str| {
        u.split_whitespace()
            .collect::<String>()
            .replace("**", "^")
            .replace("^2", "²")
            .replace("^3", "³")
    };
    let mut out = Vec::new();
    for (name, decl) in params {
        let (Some(unit), Some(site)) = (&decl.unit, syntax.site(&decl.site.to_string())) else {
            continue;
        };
        // Where it is passed whole: through its variable, or written inline in the call; or
        // added to other numbers through its variable (`onLane(1, 10.0 + gap)`).
        let mut inputs: Vec<(&str, &str)> = site
            .variable
            .as_deref()
            .map(|v| {
                let mut all = syntax.passed_to(v);
                all.extend(syntax.summed_in(v));
                all
            })
            .unwrap_or_default();
        if let Some((builtin, keyword)) = &site.argument_of {
            inputs.push((builtin, keyword));
        }
        for (builtin, keyword) in inputs {
            if let Some(input) = super::builtins::input_of(builtin, keyword) {
                if let types::Kind::Number { unit: theirs, .. } = input.kind {
                    // A dimensionless input: any unit but "1" or "-" says the program expects
                    // another scale (`unit = "%"` for a fog in [0, 1]).
                    let plain = theirs.is_empty();
                    let mismatch = if plain {
                        !matches!(norm(unit).as_str(), "" | "1" | "-")
                    } else {
                        norm(theirs) != norm(unit)
                    };
                    if mismatch {
                        let theirs = if plain {
                            "a plain number (no unit)".to_owned()
                        } else {
                            format!("in {theirs}")
                        };
                        out.push(Warning {
                            at: decl.site.to_string(),
                            message: format!(
                                "`{name}` is declared in {unit} but feeds {builtin}({keyword}=), \
                                 which is {theirs}"
                            ),
                        });
                    }
                }
            }
        }
    }
    out
}
