//! The text syntax, parsed with `pest` (grammar in `grammar.pest`).

use pest::iterators::Pair;
use pest::Parser;

use super::{Cmp, Formula, StlError};

#[derive(pest_derive::Parser)]
#[grammar = "stl/grammar.pest"]
struct StlParser;

/// Parses an STL formula.
///
/// # Errors
/// [`StlError::Parse`] with the offending line and a caret under the column (pest's report);
/// [`StlError::Interval`] for a bound that is negative, reversed or not finite;
/// [`StlError::TooComplex`] past [`super::MAX_OPERATORS`] (checked before parsing).
pub fn parse(text: &str) -> Result<Formula, StlError> {
    let n = complexity(text);
    if n > super::MAX_OPERATORS {
        return Err(StlError::TooComplex(n));
    }
    let mut pairs =
        StlParser::parse(Rule::formula, text).map_err(|e| StlError::Parse(e.to_string()))?;
    let formula = pairs.next().expect("the formula rule");
    let inner = formula.into_inner().next().expect("an implication");
    build(inner)
}

/// An upper bound on the depth the parser and the formula's tree reach: the operators
/// (`!`, `&`, `|`, `->`, `G[`, `F[`, `U[`, and the words `and`, `or`, `not`) plus the deepest
/// bracket nesting. One pass, no recursion.
fn complexity(text: &str) -> usize {
    let bytes = text.as_bytes();
    let (mut operators, mut depth, mut deepest) = (0usize, 0usize, 0usize);
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < bytes.len()
                && (bytes[i].is_ascii_alphanumeric() || matches!(bytes[i], b'_' | b'.'))
            {
                i += 1;
            }
            let word = &text[start..i];
            let next = bytes[i..].iter().find(|b| !b.is_ascii_whitespace());
            if matches!(word, "and" | "or" | "not")
                || (matches!(word, "G" | "F" | "U") && next == Some(&b'['))
            {
                operators += 1;
            }
            continue;
        }
        match c {
            b'!' | b'&' | b'|' => operators += 1,
            b'-' if bytes.get(i + 1) == Some(&b'>') => operators += 1,
            b'(' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b')' => depth = depth.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
    operators + deepest
}

fn number(p: Pair<'_, Rule>) -> f64 {
    p.as_str().parse().unwrap_or(f64::NAN)
}

fn interval(p: Pair<'_, Rule>) -> Result<(f64, f64), StlError> {
    let mut it = p.into_inner();
    let (a, b) = (
        number(it.next().expect("lo")),
        number(it.next().expect("hi")),
    );
    if !(a.is_finite() && b.is_finite() && 0.0 <= a && a <= b) {
        return Err(StlError::Interval(a, b));
    }
    Ok((a, b))
}

fn build(p: Pair<'_, Rule>) -> Result<Formula, StlError> {
    let (rule, text) = (p.as_rule(), p.as_str());
    let mut it = p.into_inner();
    Ok(match rule {
        Rule::implication => {
            let left = build(it.next().expect("left"))?;
            match (it.next(), it.next()) {
                (Some(_implies), Some(right)) => {
                    Formula::Implies(Box::new(left), Box::new(build(right)?))
                }
                _ => left,
            }
        }
        Rule::disjunction | Rule::conjunction => {
            let mut acc = build(it.next().expect("operand"))?;
            while let (Some(_op), Some(next)) = (it.next(), it.next()) {
                let rhs = Box::new(build(next)?);
                acc = if rule == Rule::disjunction {
                    Formula::Or(Box::new(acc), rhs)
                } else {
                    Formula::And(Box::new(acc), rhs)
                };
            }
            acc
        }
        Rule::until_expr => {
            let left = build(it.next().expect("left"))?;
            match it.next() {
                Some(_until) => {
                    let (a, b) = interval(it.next().expect("interval"))?;
                    let right = build(it.next().expect("right"))?;
                    Formula::Until(a, b, Box::new(left), Box::new(right))
                }
                None => left,
            }
        }
        Rule::unary | Rule::atom => build(it.next().expect("inner"))?,
        Rule::not_expr => {
            it.next(); // the `!`
            Formula::Not(Box::new(build(it.next().expect("operand"))?))
        }
        Rule::globally | Rule::eventually => {
            let (a, b) = interval(it.next().expect("interval"))?;
            let f = Box::new(build(it.next().expect("operand"))?);
            if rule == Rule::globally {
                Formula::Globally(a, b, f)
            } else {
                Formula::Eventually(a, b, f)
            }
        }
        Rule::constant if text.starts_with("true") => Formula::True,
        Rule::constant => Formula::False,
        Rule::predicate => {
            let signal = it.next().expect("ident").as_str().to_owned();
            let op = match it.next().expect("cmp").as_str() {
                "<" => Cmp::Lt,
                "<=" => Cmp::Le,
                ">" => Cmp::Gt,
                _ => Cmp::Ge,
            };
            Formula::Pred {
                signal,
                op,
                value: number(it.next().expect("number")),
            }
        }
        other => unreachable!("rule {other:?} is never built directly"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stl::{robustness, Trace, MAX_OPERATORS};

    #[test]
    fn a_chain_past_the_operator_limit_is_an_error_not_a_stack_overflow() {
        let chain = format!("{}(x > 0)", "G[0,1] ".repeat(10_000));
        assert_eq!(parse(&chain), Err(StlError::TooComplex(10_001)));
        let deep = format!("{}x > 0{}", "(".repeat(5_000), ")".repeat(5_000));
        assert!(matches!(parse(&deep), Err(StlError::TooComplex(5_000))));
        // Just under the limit parses: the words `and`, `not` count, names do not.
        let ok = format!("{}(x > 0)", "not ".repeat(MAX_OPERATORS - 1));
        assert!(parse(&ok).is_ok());
        assert!(parse("G[0,1] (and_x > 0 and notx > 1)").is_ok());
    }

    #[test]
    fn clamping_bounds_to_the_horizon_keeps_the_robustness() {
        let xs: Vec<f64> = (0..61).map(|i| (f64::from(i) * 0.3).sin()).collect();
        let trace = Trace {
            dt_s: 0.05,
            signals: [("x".to_owned(), xs)].into_iter().collect(),
        };
        for text in [
            "G[0,1e308] (x > -0.5)",
            "F[1,1e6] (x > 0.9)",
            "G[0,2] F[0,1e9] (x > 0.5)",
            "(x > 0) U[0,1e300] (x < -0.9)",
            "F[50,60] (x > 0)",
        ] {
            let f = parse(text).unwrap();
            let (c, changed) = f.clamped(3.0);
            assert!(changed, "{text}");
            assert_eq!(robustness(&f, &trace), robustness(&c, &trace), "{text}");
        }
        assert!(!parse("G[0,2] (x > 0)").unwrap().clamped(3.0).1);
    }
}
