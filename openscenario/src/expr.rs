//! OpenSCENARIO expressions: the text inside `${...}` (ASAM OpenSCENARIO XML 1.3 User Guide,
//! section 9.2 "Expressions"; XSD simple type `expression`).
//!
//! What is accepted, from the highest precedence to the lowest:
//!
//! * operands: decimal numbers (`3`, `2.5`, `1e-3`, `2.1E+7`: digits, an optional `.` followed
//!   by digits, an optional exponent), parameter references `$name` (`name` is
//!   `[A-Za-z_][A-Za-z0-9_]*`), the literals `true` and `false`, parentheses;
//! * the functions `round(x)` (half away from zero), `floor(x)`, `ceil(x)`, `sqrt(x)`,
//!   `pow(x, y)`, and those the 1.3 standard added: `sin(x)`, `cos(x)`, `tan(x)`, `asin(x)`,
//!   `acos(x)`, `atan(x)` (radians), `sign(x)` (-1, 0 or 1), `abs(x)`, `max(a, b)`,
//!   `min(a, b)`;
//! * unary minus `-x`;
//! * `*`, `/`, `%` (the remainder takes the dividend's sign, as C's `fmod`), left-associative;
//! * `+`, `-`, left-associative;
//! * `not x`;
//! * `a and b`, left-associative;
//! * `a or b`, left-associative.
//!
//! Arithmetic takes numbers only: a boolean there is an error; a string parameter is used when
//! its text is a number (the ALKS scenarios keep lane ids such as `-4` in string parameters),
//! otherwise it is an error. `not`, `and`, `or` take booleans only (a string parameter holding
//! `true` or `false` counts). Both operands are always evaluated (no short circuit), so an
//! error on either side is reported.
//!
//! Refused, each with the byte offset of the fault: anything else (unary `+`, comparisons,
//! esmini's `pi` and string concatenation, `atan2`, `.5` without a leading digit), an undeclared
//! parameter, dividing by zero, `sqrt` of a negative number, a result that is not a finite
//! number (`pow(-8, 0.5)`, `asin(2)`, overflow), nesting deeper than [`MAX_DEPTH`], and texts
//! longer than [`MAX_EXPR_BYTES`].

use std::fmt;

use crate::Value;

/// The longest expression text evaluated, bytes (64 KiB).
pub const MAX_EXPR_BYTES: usize = 64 * 1024;

/// The deepest nesting of parentheses and function arguments evaluated.
pub const MAX_DEPTH: usize = 256;

/// Why an expression cannot be evaluated, and where.
#[derive(Debug, Clone, PartialEq)]
pub struct ExprError {
    /// Byte offset in the expression's text (the text inside `${...}`) of the token at fault.
    pub offset: usize,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "at byte {}: {}", self.offset, self.reason)
    }
}

impl std::error::Error for ExprError {}

fn err<T>(offset: usize, reason: impl Into<String>) -> Result<T, ExprError> {
    Err(ExprError {
        offset,
        reason: reason.into(),
    })
}

/// The constants an expression may name: `pi` and `e`, as esmini's expressions know them
/// (its `simple_expr.c`). OpenSCENARIO 1.3's grammar has none; files written for esmini
/// (Vector's Euro NCAP scenarios: `${65*pi/180}`) use `pi`, so it is read as a dialect.
fn constant(name: &str) -> Option<f64> {
    match name {
        "pi" => Some(std::f64::consts::PI),
        "e" => Some(std::f64::consts::E),
        _ => None,
    }
}

/// The functions an expression may call with their number of arguments (OpenSCENARIO 1.3 User
/// Guide, 9.2.1 "Operators").
const FUNCTIONS: [(&str, usize); 15] = [
    ("round", 1),
    ("floor", 1),
    ("ceil", 1),
    ("sqrt", 1),
    ("pow", 2),
    ("sin", 1),
    ("cos", 1),
    ("tan", 1),
    ("asin", 1),
    ("acos", 1),
    ("atan", 1),
    ("sign", 1),
    ("abs", 1),
    ("max", 2),
    ("min", 2),
];

/// Evaluates `text`, an expression without its `${` and `}`, looking parameters up (by name,
/// without the `$`) in `lookup`.
///
/// # Errors
/// [`ExprError`] with the byte offset in `text` of the fault: a syntax error, an undeclared
/// parameter ("parameter $x is not declared"), a type error (a boolean in arithmetic, a number
/// in `and`), dividing by zero ("divides by zero"), `sqrt` of a negative number, a result that
/// is not finite, nesting deeper than [`MAX_DEPTH`], a text longer than [`MAX_EXPR_BYTES`].
pub fn eval(text: &str, lookup: &dyn Fn(&str) -> Option<Value>) -> Result<Value, ExprError> {
    if text.len() > MAX_EXPR_BYTES {
        return err(
            0,
            format!(
                "the expression is {} bytes long, more than the {MAX_EXPR_BYTES} evaluated",
                text.len()
            ),
        );
    }
    let toks = lex(text)?;
    if matches!(toks.first(), Some(t) if t.tok == Tok::End) {
        return err(0, "the expression is empty");
    }
    let mut m = Machine {
        vals: Vec::new(),
        ops: Vec::new(),
        depth: 0,
        lookup,
    };
    m.run(&toks, text.len()).map(|o| o.v)
}

/// The names (without `$`) of the parameters `text` (an expression without `${` and `}`)
/// refers to, in order of appearance, each once. A text that does not lex yields the names
/// before the fault; [`eval`] reports the fault.
pub fn params_in(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for t in lex_prefix(text) {
        if let Tok::Param(n) = t.tok {
            if !out.iter().any(|o| o == n) {
                out.push(n.to_string());
            }
        }
    }
    out
}

/// Parses a number as OpenSCENARIO attributes and parameter values write it (`xsd:double`,
/// surrounding white space ignored): finite values only (`INF`, `NaN` are refused).
pub fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    if t.is_empty() {
        return None;
    }
    t.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Whether `name` can follow `$` in a reference: `[A-Za-z_][A-Za-z0-9_]*` (XSD simple type
/// `parameter`).
pub fn is_param_name(name: &str) -> bool {
    let mut cs = name.chars();
    matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok<'a> {
    Num(f64),
    Param(&'a str),
    Word(&'a str),
    LParen,
    RParen,
    Comma,
    Plus,
    Minus,
    Star,
    Slash,
    Percent,
    End,
}

impl fmt::Display for Tok<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Tok::Num(v) => write!(f, "the number {v}"),
            Tok::Param(n) => write!(f, "${n}"),
            Tok::Word(w) => write!(f, "`{w}`"),
            Tok::LParen => f.write_str("`(`"),
            Tok::RParen => f.write_str("`)`"),
            Tok::Comma => f.write_str("`,`"),
            Tok::Plus => f.write_str("`+`"),
            Tok::Minus => f.write_str("`-`"),
            Tok::Star => f.write_str("`*`"),
            Tok::Slash => f.write_str("`/`"),
            Tok::Percent => f.write_str("`%`"),
            Tok::End => f.write_str("the end of the expression"),
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    tok: Tok<'a>,
    at: usize,
}

fn is_word_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The tokens of `text`, ending with [`Tok::End`].
fn lex(text: &str) -> Result<Vec<Token<'_>>, ExprError> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let at = i;
        let single = match c {
            b' ' | b'\t' | b'\r' | b'\n' => {
                i += 1;
                continue;
            }
            b'(' => Some(Tok::LParen),
            b')' => Some(Tok::RParen),
            b',' => Some(Tok::Comma),
            b'+' => Some(Tok::Plus),
            b'-' => Some(Tok::Minus),
            b'*' => Some(Tok::Star),
            b'/' => Some(Tok::Slash),
            b'%' => Some(Tok::Percent),
            _ => None,
        };
        if let Some(tok) = single {
            out.push(Token { tok, at });
            i += 1;
        } else if c.is_ascii_digit() {
            let (v, end) = lex_number(text, i)?;
            out.push(Token {
                tok: Tok::Num(v),
                at,
            });
            i = end;
        } else if c == b'$' {
            let end = word_end(b, i + 1);
            let name = &text[i + 1..end];
            if !is_param_name(name) {
                return err(
                    at,
                    "`$` must be followed by a parameter name ([A-Za-z_][A-Za-z0-9_]*)",
                );
            }
            out.push(Token {
                tok: Tok::Param(name),
                at,
            });
            i = end;
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let end = word_end(b, i);
            out.push(Token {
                tok: Tok::Word(&text[i..end]),
                at,
            });
            i = end;
        } else if c == b'.' {
            return err(at, "a number must start with a digit (write 0.5, not .5)");
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return err(at, format!("unexpected character {ch:?}"));
        }
    }
    out.push(Token {
        tok: Tok::End,
        at: b.len(),
    });
    Ok(out)
}

/// The tokens of `text` up to its first lexical fault (for [`params_in`]).
fn lex_prefix(text: &str) -> Vec<Token<'_>> {
    match lex(text) {
        Ok(t) => t,
        Err(e) => text
            .get(..e.offset)
            .map(|s| lex(s).unwrap_or_default())
            .unwrap_or_default(),
    }
}

fn word_end(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && is_word_char(b[i]) {
        i += 1;
    }
    i
}

/// A number starting at byte `start` (a digit): its value and the byte after it.
fn lex_number(text: &str, start: usize) -> Result<(f64, usize), ExprError> {
    let b = text.as_bytes();
    let digits = |mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = digits(start);
    if i < b.len() && b[i] == b'.' {
        if !(i + 1 < b.len() && b[i + 1].is_ascii_digit()) {
            return err(i, "a digit must follow the decimal point");
        }
        i = digits(i + 1);
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            i = digits(j);
        }
    }
    if i < b.len() && (is_word_char(b[i]) || b[i] == b'.') {
        return err(
            start,
            format!(
                "malformed number {:?}",
                &text[start..word_end(b, i).max(i + 1).min(b.len())]
            ),
        );
    }
    match text[start..i].parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((v, i)),
        _ => err(
            start,
            format!("the number {} is too large", &text[start..i]),
        ),
    }
}

/// A value with the offset of the operand it came from.
struct Opd {
    v: Value,
    at: usize,
}

fn describe(v: &Value) -> String {
    match v {
        Value::Num(x) => format!("the number {x}"),
        Value::Bool(b) => format!("the boolean {b}"),
        Value::Str(s) => format!("the string {s:?}"),
    }
}

fn num(o: &Opd, op: &str) -> Result<f64, ExprError> {
    match &o.v {
        Value::Num(x) => Ok(*x),
        Value::Str(s) => match parse_number(s) {
            Some(x) => Ok(x),
            None => err(o.at, format!("{op} takes numbers, not {}", describe(&o.v))),
        },
        Value::Bool(_) => err(o.at, format!("{op} takes numbers, not {}", describe(&o.v))),
    }
}

fn boolean(o: &Opd, op: &str) -> Result<bool, ExprError> {
    match &o.v {
        Value::Bool(b) => Ok(*b),
        Value::Str(s) if s.trim() == "true" => Ok(true),
        Value::Str(s) if s.trim() == "false" => Ok(false),
        v => err(o.at, format!("`{op}` takes booleans, not {}", describe(v))),
    }
}

fn finite(x: f64, at: usize, what: &str) -> Result<Value, ExprError> {
    if x.is_finite() {
        Ok(Value::Num(x))
    } else {
        err(at, format!("{what} is not a finite number"))
    }
}

/// An operator waiting on the evaluator's stack.
#[derive(Debug, Clone, Copy)]
enum Op<'t> {
    /// A binary operator token at its byte.
    Bin(Tok<'t>, usize),
    /// Unary minus at its byte.
    Neg(usize),
    /// `not` at its byte.
    Not(usize),
    /// An open parenthesis at its byte.
    Paren(usize),
    /// A function call: its name, the name's byte, the `(`'s byte, the commas seen.
    Call(&'t str, usize, usize, usize),
}

/// A binary operator's precedence (higher binds tighter), or `None` for other tokens.
fn bin_prec(t: Tok<'_>) -> Option<u8> {
    match t {
        Tok::Word("or") => Some(1),
        Tok::Word("and") => Some(2),
        Tok::Plus | Tok::Minus => Some(4),
        Tok::Star | Tok::Slash | Tok::Percent => Some(5),
        _ => None,
    }
}

impl Op<'_> {
    /// The precedence of an operator; `None` for parentheses and calls (which stop reduction).
    fn prec(self) -> Option<u8> {
        match self {
            Op::Bin(t, _) => bin_prec(t),
            Op::Not(_) => Some(3),
            Op::Neg(_) => Some(6),
            Op::Paren(_) | Op::Call(..) => None,
        }
    }
}

/// An operator-precedence evaluator with explicit stacks: no recursion, so no input can
/// exhaust the thread's stack.
struct Machine<'t, 'l> {
    vals: Vec<Opd>,
    ops: Vec<Op<'t>>,
    depth: usize,
    lookup: &'l dyn Fn(&str) -> Option<Value>,
}

impl<'t> Machine<'t, '_> {
    fn run(&mut self, toks: &[Token<'t>], end: usize) -> Result<Opd, ExprError> {
        let mut i = 0;
        let mut operand = true;
        loop {
            let t = toks.get(i).copied().unwrap_or(Token {
                tok: Tok::End,
                at: end,
            });
            i += 1;
            if operand {
                match t.tok {
                    Tok::Minus => self.ops.push(Op::Neg(t.at)),
                    Tok::Plus => return err(t.at, "`+` is not a unary operator"),
                    Tok::Word("not") => self.ops.push(Op::Not(t.at)),
                    Tok::LParen => {
                        self.open(t.at)?;
                        self.ops.push(Op::Paren(t.at));
                    }
                    Tok::Word(w)
                        if !matches!(w, "true" | "false" | "and" | "or")
                            && constant(w).is_none() =>
                    {
                        let open = toks.get(i).copied().unwrap_or(Token {
                            tok: Tok::End,
                            at: end,
                        });
                        i += 1;
                        self.start_call(w, t.at, open)?;
                    }
                    _ => {
                        let v = self.atom(t)?;
                        self.vals.push(v);
                        operand = false;
                    }
                }
                continue;
            }
            match t.tok {
                Tok::RParen => self.close(t.at)?,
                Tok::Comma => {
                    self.comma(t.at)?;
                    operand = true;
                }
                Tok::End => return self.finish(t.at),
                tok => match bin_prec(tok) {
                    Some(p) => {
                        self.reduce(p)?;
                        self.ops.push(Op::Bin(tok, t.at));
                        operand = true;
                    }
                    None => {
                        return err(
                            t.at,
                            format!("expected an operator, `)` or the end, found {tok}"),
                        )
                    }
                },
            }
        }
    }

    /// A number, parameter or boolean literal.
    fn atom(&self, t: Token<'t>) -> Result<Opd, ExprError> {
        let v = match t.tok {
            Tok::Num(x) => Value::Num(x),
            Tok::Param(n) => match (self.lookup)(n) {
                Some(v) => v,
                None => return err(t.at, format!("parameter ${n} is not declared")),
            },
            Tok::Word("true") => Value::Bool(true),
            Tok::Word("false") => Value::Bool(false),
            Tok::Word(w) if constant(w).is_some() => Value::Num(constant(w).unwrap_or(f64::NAN)),
            tok => {
                return err(
                    t.at,
                    format!(
                    "expected a number, a $parameter, true, false, a function or `(`, found {tok}"
                ),
                )
            }
        };
        Ok(Opd { v, at: t.at })
    }

    fn open(&mut self, at: usize) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return err(at, format!("nested more than {MAX_DEPTH} deep"));
        }
        Ok(())
    }

    /// The start of a call of `name` (at byte `at`), whose next token must be `(`.
    fn start_call(&mut self, name: &'t str, at: usize, open: Token<'t>) -> Result<(), ExprError> {
        if !FUNCTIONS.iter().any(|(f, _)| *f == name) {
            let known: Vec<&str> = FUNCTIONS.iter().map(|(f, _)| *f).collect();
            return err(
                at,
                format!(
                    "unknown name `{name}`: expressions know the functions {}, the operators \
                     not, and, or, the literals true, false and esmini's constants pi and e; \
                     parameters are written $name",
                    known.join(", ")
                ),
            );
        }
        if open.tok != Tok::LParen {
            return err(open.at, format!("`{name}` must be followed by `(`"));
        }
        self.open(open.at)?;
        self.ops.push(Op::Call(name, at, open.at, 0));
        Ok(())
    }

    fn pop(&mut self, at: usize) -> Result<Opd, ExprError> {
        match self.vals.pop() {
            Some(v) => Ok(v),
            None => err(at, "an operator lacks an operand"),
        }
    }

    /// Applies the stacked operators of precedence `min` or more.
    fn reduce(&mut self, min: u8) -> Result<(), ExprError> {
        while let Some(&op) = self.ops.last() {
            match op.prec() {
                Some(p) if p >= min => {
                    self.ops.pop();
                    self.apply(op)?;
                }
                _ => break,
            }
        }
        Ok(())
    }

    fn apply(&mut self, op: Op<'t>) -> Result<(), ExprError> {
        let o = match op {
            Op::Neg(at) => {
                let x = num(&self.pop(at)?, "unary `-`")?;
                Opd {
                    v: Value::Num(-x),
                    at,
                }
            }
            Op::Not(at) => {
                let b = boolean(&self.pop(at)?, "not")?;
                Opd {
                    v: Value::Bool(!b),
                    at,
                }
            }
            Op::Bin(tok, at) => {
                let r = self.pop(at)?;
                let l = self.pop(at)?;
                Opd {
                    v: binary(tok, at, &l, &r)?,
                    at: l.at,
                }
            }
            Op::Paren(at) | Op::Call(_, _, at, _) => return err(at, "an unclosed `(`"),
        };
        self.vals.push(o);
        Ok(())
    }

    fn close(&mut self, at: usize) -> Result<(), ExprError> {
        self.reduce(0)?;
        match self.ops.pop() {
            Some(Op::Paren(open)) => {
                self.depth -= 1;
                if let Some(v) = self.vals.last_mut() {
                    v.at = open;
                }
                Ok(())
            }
            Some(Op::Call(name, name_at, _, commas)) => {
                self.depth -= 1;
                let arity = FUNCTIONS
                    .iter()
                    .find(|(f, _)| *f == name)
                    .map_or(0, |&(_, n)| n);
                if commas + 1 != arity {
                    return err(
                        name_at,
                        format!("{name} takes {arity} argument(s), not {}", commas + 1),
                    );
                }
                let y = if arity == 2 {
                    Some(self.pop(at)?)
                } else {
                    None
                };
                let x = self.pop(at)?;
                let what = format!("`{name}`");
                let yv = match &y {
                    Some(a) => num(a, &what)?,
                    None => 0.0,
                };
                let v = apply(name, num(&x, &what)?, yv, name_at)?;
                self.vals.push(Opd { v, at: name_at });
                Ok(())
            }
            _ => err(at, "a `)` without a matching `(`"),
        }
    }

    fn comma(&mut self, at: usize) -> Result<(), ExprError> {
        self.reduce(0)?;
        match self.ops.last_mut() {
            Some(Op::Call(_, _, _, commas)) => {
                *commas += 1;
                Ok(())
            }
            _ => err(at, "a `,` outside a function's arguments"),
        }
    }

    fn finish(&mut self, at: usize) -> Result<Opd, ExprError> {
        self.reduce(0)?;
        match self.ops.last() {
            Some(Op::Paren(open) | Op::Call(_, _, open, _)) => {
                err(at, format!("expected `)` closing the `(` at byte {open}"))
            }
            _ => self.pop(at),
        }
    }
}

/// `l tok r` for a binary operator `tok` at byte `at`.
fn binary(tok: Tok<'_>, at: usize, l: &Opd, r: &Opd) -> Result<Value, ExprError> {
    let sym = match tok {
        Tok::Word("or") => return Ok(Value::Bool(boolean(l, "or")? | boolean(r, "or")?)),
        Tok::Word("and") => return Ok(Value::Bool(boolean(l, "and")? & boolean(r, "and")?)),
        Tok::Plus => "`+`",
        Tok::Minus => "`-`",
        Tok::Star => "`*`",
        Tok::Slash => "`/`",
        _ => "`%`",
    };
    let (a, b) = (num(l, sym)?, num(r, sym)?);
    let v = match tok {
        Tok::Plus => a + b,
        Tok::Minus => a - b,
        Tok::Star => a * b,
        _ if b == 0.0 => return err(at, format!("{sym} divides by zero")),
        Tok::Slash => a / b,
        _ => a % b,
    };
    finite(v, at, &format!("the result of {sym}"))
}

/// Function `name` of `x` (and `y` for the two-argument ones), called at byte `at`.
fn apply(name: &str, x: f64, y: f64, at: usize) -> Result<Value, ExprError> {
    let v = match name {
        "round" => x.round(),
        "floor" => x.floor(),
        "ceil" => x.ceil(),
        "sqrt" if x < 0.0 => return err(at, format!("sqrt of the negative number {x}")),
        "sqrt" => x.sqrt(),
        "pow" => x.powf(y),
        "sin" => x.sin(),
        "cos" => x.cos(),
        "tan" => x.tan(),
        "asin" => x.asin(),
        "acos" => x.acos(),
        "atan" => x.atan(),
        "sign" if x > 0.0 => 1.0,
        "sign" if x < 0.0 => -1.0,
        "sign" => 0.0,
        "abs" => x.abs(),
        "max" => x.max(y),
        "min" => x.min(y),
        _ => return err(at, format!("unknown function `{name}`")),
    };
    let call = if matches!(name, "pow" | "max" | "min") {
        format!("{name}({x}, {y})")
    } else {
        format!("{name}({x})")
    };
    finite(v, at, &call)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lookup(name: &str) -> Option<Value> {
        match name {
            "x" => Some(Value::Num(3.0)),
            "v" => Some(Value::Num(36.0)),
            "zero" => Some(Value::Num(0.0)),
            "yes" => Some(Value::Bool(true)),
            "no" => Some(Value::Bool(false)),
            "lane" => Some(Value::Str("-4".into())),
            "word" => Some(Value::Str("car".into())),
            "flag" => Some(Value::Str("true".into())),
            _ => None,
        }
    }

    fn ev(text: &str) -> Result<Value, ExprError> {
        eval(text, &lookup)
    }

    fn num_of(text: &str) -> f64 {
        match ev(text) {
            Ok(Value::Num(x)) => x,
            other => panic!("{text}: {other:?}"),
        }
    }

    fn fails(text: &str) -> ExprError {
        match ev(text) {
            Err(e) => e,
            Ok(v) => panic!("{text} evaluated to {v:?}"),
        }
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(num_of("1 + 2 * 3"), 7.0);
        assert_eq!(num_of("(1 + 2) * 3"), 9.0);
        assert_eq!(num_of("10 - 4 - 3"), 3.0);
        assert_eq!(num_of("64 / 4 / 2"), 8.0);
        assert_eq!(num_of("-2 * 3"), -6.0);
        assert_eq!(num_of("2 * -3"), -6.0);
        assert_eq!(num_of("2 - -3"), 5.0);
        assert_eq!(num_of("--2"), 2.0);
        assert_eq!(num_of("7 % 4 + 1"), 4.0);
        assert_eq!(num_of("-7 % 4"), -3.0);
        assert_eq!(num_of("2.5e2 + 1E-1"), 250.1);
        assert_eq!(num_of("-$x"), -3.0);
    }

    /// esmini's constants, which Vector's Euro NCAP files use (`${65*pi/180}`).
    #[test]
    fn esminis_constants_pi_and_e() {
        assert_eq!(num_of("65 * pi / 180"), 65.0 * std::f64::consts::PI / 180.0);
        assert_eq!(num_of("-pi"), -std::f64::consts::PI);
        assert_eq!(num_of("pow(e, 2)"), std::f64::consts::E.powi(2));
        assert!(fails("pi(1)").reason.contains("expected an operator"));
    }

    #[test]
    fn alks_expressions() {
        // From the ALKS templates (openMSL sl-3-1-osc-alks-scenarios).
        let v = num_of("2 * sqrt( $x * $x ) / ($v / 3.6)");
        assert!((v - 0.6).abs() < 1e-12, "{v}");
        assert_eq!(num_of("$v / 3.6"), 10.0);
        assert_eq!(num_of("-$v"), -36.0);
        // A string parameter holding a number is used as one.
        assert_eq!(num_of("$lane + 1"), -3.0);
        assert_eq!(ev("$word"), Ok(Value::Str("car".into())));
    }

    #[test]
    fn functions() {
        assert_eq!(num_of("round(2.5)"), 3.0);
        assert_eq!(num_of("round(-2.5)"), -3.0);
        assert_eq!(num_of("floor(-1.5)"), -2.0);
        assert_eq!(num_of("ceil(1.2)"), 2.0);
        assert_eq!(num_of("sqrt(16)"), 4.0);
        assert_eq!(num_of("pow(2, 10)"), 1024.0);
        assert_eq!(num_of("pow(2, -1)"), 0.5);
        assert_eq!(num_of("max(1, $x)"), 3.0);
        assert_eq!(num_of("min(1, $x)"), 1.0);
        assert_eq!(num_of("abs(-2)"), 2.0);
        assert_eq!(num_of("sign(-2) + sign(0) + sign(5)"), 0.0);
        assert_eq!(num_of("sin(0) + cos(0) + tan(0)"), 1.0);
        let v = num_of("asin(1) + acos(1) + atan(1)");
        assert!((v - 3.0 * std::f64::consts::FRAC_PI_4).abs() < 1e-12, "{v}");
        assert_eq!(num_of("2 * round(pow(1.5, 2))"), 4.0);
    }

    #[test]
    fn booleans() {
        assert_eq!(ev("true"), Ok(Value::Bool(true)));
        assert_eq!(ev("not true"), Ok(Value::Bool(false)));
        assert_eq!(ev("not not $yes"), Ok(Value::Bool(true)));
        assert_eq!(ev("true or false and false"), Ok(Value::Bool(true)));
        assert_eq!(ev("(true or false) and false"), Ok(Value::Bool(false)));
        assert_eq!(ev("not $no and $yes"), Ok(Value::Bool(true)));
        assert_eq!(ev("$flag and true"), Ok(Value::Bool(true)));
        let e = fails("true + 1");
        assert_eq!(e.offset, 0);
        assert!(e.reason.contains("takes numbers"), "{e}");
        let e = fails("1 and true");
        assert!(e.reason.contains("takes booleans"), "{e}");
        let e = fails("not 1");
        assert_eq!(e.offset, 4);
        let e = fails("-$yes");
        assert_eq!(e.offset, 1);
    }

    #[test]
    fn errors_carry_offsets() {
        let e = fails("1 + $nope");
        assert_eq!(
            (e.offset, e.reason.as_str()),
            (4, "parameter $nope is not declared")
        );
        let e = fails("$x / (2 - 2)");
        assert_eq!(e.offset, 3);
        assert!(e.reason.contains("divides by zero"), "{e}");
        let e = fails("5 % $zero");
        assert_eq!(e.offset, 2);
        assert!(e.reason.contains("divides by zero"), "{e}");
        let e = fails("1 + sqrt(-4)");
        assert_eq!(e.offset, 4);
        assert!(e.reason.contains("sqrt of the negative number -4"), "{e}");
        assert!(fails("pow(-8, 0.5)").reason.contains("not a finite number"));
        assert!(fails("pow(0, -1)").reason.contains("not a finite number"));
        assert!(fails("asin(2)").reason.contains("not a finite number"));
        assert!(fails("1e308 * 10").reason.contains("not a finite number"));
        assert_eq!(fails("1e999").offset, 0);
        assert_eq!(fails("tau / 2").offset, 0);
        assert!(fails("tau / 2").reason.contains("unknown name `tau`"));
        assert_eq!(fails("2 +").offset, 3);
        assert_eq!(fails("(1 + 2").offset, 6);
        assert_eq!(fails("1 + 2)").offset, 5);
        assert_eq!(fails("+1").offset, 0);
        assert_eq!(fails("1 < 2").offset, 2);
        assert_eq!(fails(".5").offset, 0);
        assert_eq!(fails("5.").offset, 1);
        assert_eq!(fails("2x").offset, 0);
        assert_eq!(fails("$ x").offset, 0);
        assert_eq!(fails("pow(2)").offset, 0);
        assert!(fails("pow(2)").reason.contains("takes 2"));
        assert_eq!(fails("sqrt 4").offset, 5);
        assert_eq!(fails("").reason, "the expression is empty");
        assert_eq!(fails("  ").reason, "the expression is empty");
        assert_eq!(fails("$word * 2").offset, 0);
        assert_eq!(fails("1 + é").offset, 4);
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let ok = format!("{}1{}", "(".repeat(MAX_DEPTH), ")".repeat(MAX_DEPTH));
        assert_eq!(ev(&ok), Ok(Value::Num(1.0)));
        let deep = format!(
            "{}1{}",
            "(".repeat(MAX_DEPTH + 1),
            ")".repeat(MAX_DEPTH + 1)
        );
        let e = fails(&deep);
        assert_eq!(e.offset, MAX_DEPTH);
        assert!(e.reason.contains("nested"));
        let calls = format!("{}1{}", "abs(".repeat(10_000), ")".repeat(10_000));
        assert!(fails(&calls).reason.contains("nested"));
        // Long chains of unary operators are iterative.
        assert_eq!(num_of(&format!("{}1", "-".repeat(20_000))), 1.0);
        assert_eq!(
            ev(&format!("{}true", "not ".repeat(10_000))),
            Ok(Value::Bool(true))
        );
        let long = "1+".repeat(MAX_EXPR_BYTES / 2) + "1";
        assert!(fails(&long).reason.contains("more than"));
    }

    #[test]
    fn arbitrary_inputs_never_panic() {
        // A fixed pseudo-random sweep over the expression alphabet: every input either
        // evaluates or errors with an offset inside the text.
        let alphabet: [&str; 24] = [
            "1", "2.5", "0", "1e3", "$x", "$zero", "$word", "$nope", "true", "not ", " and ",
            " or ", "+", "-", "*", "/", "%", "(", ")", ",", "pow(", "sqrt(", "max(", "é",
        ];
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..20_000 {
            let mut text = String::new();
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            for k in 0..(state % 12) {
                let pick = (state >> (k * 5)) as usize % alphabet.len();
                text.push_str(alphabet[pick]);
            }
            if let Err(e) = ev(&text) {
                assert!(e.offset <= text.len(), "{text:?}: {e}");
            }
        }
    }

    #[test]
    fn parameter_names_and_numbers() {
        assert_eq!(
            params_in("$a + $b * $a / sqrt($c_1)"),
            vec!["a", "b", "c_1"]
        );
        assert_eq!(params_in("$a + $"), vec!["a"]);
        assert!(is_param_name("_x9"));
        assert!(!is_param_name("9x"));
        assert!(!is_param_name(""));
        assert_eq!(parse_number(" -4 "), Some(-4.0));
        assert_eq!(parse_number("1e3"), Some(1000.0));
        assert_eq!(parse_number("inf"), None);
        assert_eq!(parse_number("NaN"), None);
        assert_eq!(parse_number("car"), None);
        let e = ExprError {
            offset: 3,
            reason: "x".into(),
        };
        assert_eq!(e.to_string(), "at byte 3: x");
    }
}
