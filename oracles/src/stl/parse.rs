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
        StlParser::parse(Rule::formula, text).map_err(|e| StlError::Parse(describe(e)))?;
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

/// pest's report, with the grammar's rules named as a reader of the formula knows them.
fn describe(e: pest::error::Error<Rule>) -> String {
    e.renamed_rules(|rule| {
        match rule {
            Rule::sum | Rule::term => "a signal or a number (a sum like `a - b + 2`)",
            Rule::cmp => "a comparison (<, <=, >, >=)",
            Rule::addop => "+ or -",
            Rule::number => "a number",
            Rule::ident => "a signal",
            Rule::interval => "a time interval [a,b]",
            Rule::implies => "->",
            Rule::or => "| (or)",
            Rule::and => "& (and)",
            Rule::until => "U[a,b]",
            Rule::EOI => "the end of the formula",
            other => return format!("{other:?}"),
        }
        .to_owned()
    })
    .to_string()
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

/// Adds `sign ×` the sum `p` to `terms` (a signal written twice gets one coefficient) and
/// `constant`.
fn linear(p: Pair<'_, Rule>, sign: f64, terms: &mut Vec<(f64, String)>, constant: &mut f64) {
    let mut term_sign = sign;
    for part in p.into_inner() {
        match part.as_rule() {
            Rule::addop => term_sign = if part.as_str() == "-" { -sign } else { sign },
            _ => {
                let mut coefficient = term_sign;
                let mut signal = None;
                for x in part.into_inner() {
                    match x.as_rule() {
                        Rule::number => coefficient *= number(x),
                        _ => signal = Some(x.as_str().to_owned()),
                    }
                }
                match signal {
                    Some(name) => match terms.iter_mut().find(|(_, s)| *s == name) {
                        Some((c, _)) => *c += coefficient,
                        None => terms.push((coefficient, name)),
                    },
                    None => *constant += coefficient,
                }
            }
        }
    }
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
            let left = it.next().expect("left sum");
            let op = match it.next().expect("cmp").as_str() {
                "<" => Cmp::Lt,
                "<=" => Cmp::Le,
                ">" => Cmp::Gt,
                _ => Cmp::Ge,
            };
            let right = it.next().expect("right sum");
            // L op R as (L - R) op 0: signals to the left, constants to the right.
            let mut terms: Vec<(f64, String)> = Vec::new();
            let mut constant = 0.0;
            for (sum, sign) in [(left, 1.0), (right, -1.0)] {
                linear(sum, sign, &mut terms, &mut constant);
            }
            Formula::Pred {
                terms,
                op,
                value: -constant,
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
    fn predicates_compare_linear_combinations_of_signals() {
        let trace = Trace {
            dt_s: 0.1,
            signals: [
                ("a".to_owned(), vec![10.0, 12.0, 7.5]),
                ("b.x".to_owned(), vec![1.0, 5.0, -2.0]),
            ]
            .into_iter()
            .collect(),
        };
        let rho = |text: &str| robustness(&parse(text).unwrap(), &trace).unwrap();
        // L > R is L - R, L < R is R - L.
        assert_eq!(rho("a - b.x > 8"), [1.0, -1.0, 1.5]);
        assert_eq!(rho("a < b.x + 9"), [0.0, 2.0, -0.5]);
        assert_eq!(rho("2 * b.x <= a - 1"), [7.0, 1.0, 10.5]);
        assert_eq!(rho("-a + 3 >= -2 * b.x"), [-5.0, 1.0, -8.5]);
        // A signal written twice gets one coefficient; a plain predicate is unchanged.
        assert_eq!(rho("a + a > a + 1"), rho("a > 1"));
        assert_eq!(
            parse("a + a > a + 1").unwrap(),
            Formula::Pred {
                terms: vec![(1.0, "a".into())],
                op: Cmp::Gt,
                value: 1.0
            }
        );
        assert_eq!(parse("x - y > 1").unwrap().signals(), ["x", "y"]);
        // `->` after a predicate is still an implication, not a minus.
        assert!(matches!(
            parse("a > 0 -> b.x < 1").unwrap(),
            Formula::Implies(..)
        ));
        assert!(matches!(
            parse("a > 0->b.x < 1").unwrap(),
            Formula::Implies(..)
        ));
        // Products of signals are not linear: a syntax error.
        assert!(matches!(parse("a * b.x > 1"), Err(StlError::Parse(_))));
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
