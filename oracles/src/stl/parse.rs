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
/// [`StlError::Interval`] for a bound that is negative, reversed or not finite.
pub fn parse(text: &str) -> Result<Formula, StlError> {
    let mut pairs =
        StlParser::parse(Rule::formula, text).map_err(|e| StlError::Parse(e.to_string()))?;
    let formula = pairs.next().expect("the formula rule");
    let inner = formula.into_inner().next().expect("an implication");
    build(inner)
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
