//! What an input of the world accepts from a stream, checked on every event by
//! [`super::Node::Check`]: a stream computed by a lambda cannot be typed when the program
//! loads, so its values are checked as they come.

use std::fmt;

use super::Value;

/// The type and range of values an input accepts.
#[derive(Debug, Clone, PartialEq)]
pub enum Expect {
    /// A finite number in `[min, max]` (`(min, max]` with `min_open`; either bound may be
    /// infinite), in `unit` (empty for a unitless number).
    Number {
        /// Lower bound, in `unit`.
        min: f64,
        /// Upper bound, in `unit`.
        max: f64,
        /// Whether `min` itself is excluded.
        min_open: bool,
        /// The unit, e.g. `m/s`; empty when the number has none.
        unit: String,
    },
    /// A truth value.
    Bool,
    /// A position `(x, y, z)` in metres.
    Position,
}

impl Expect {
    /// Whether `v` is an accepted value.
    pub fn accepts(&self, v: &Value) -> bool {
        match (self, v) {
            (
                Expect::Number {
                    min, max, min_open, ..
                },
                Value::Num(x),
            ) => x.is_finite() && (if *min_open { *x > *min } else { *x >= *min }) && *x <= *max,
            (Expect::Bool, Value::Bool(_)) => true,
            (Expect::Position, Value::Vec3(p)) => p.iter().all(|c| c.is_finite()),
            _ => false,
        }
    }
}

impl Expect {
    /// Whether `v` is of the accepted kind (a number, a bool, a position), whatever its value:
    /// `NaN` and `-1` are numbers here, and a string is not.
    pub fn accepts_kind(&self, v: &Value) -> bool {
        matches!(
            (self, v),
            (Expect::Number { .. }, Value::Num(_))
                | (Expect::Bool, Value::Bool(_))
                | (Expect::Position, Value::Vec3(_))
        )
    }
}

impl fmt::Display for Expect {
    /// E.g. `a number in m/s, >= 0`, `a number in [0, 1]`, `a bool`, `a position`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Expect::Number {
                min,
                max,
                min_open,
                unit,
            } => {
                f.write_str("a number")?;
                if !unit.is_empty() {
                    write!(f, " in {unit}")?;
                }
                let sep = if unit.is_empty() { " " } else { ", " };
                match (min.is_finite(), max.is_finite()) {
                    (true, true) => {
                        let open = if *min_open { "(" } else { "[" };
                        let sep = if unit.is_empty() { " in " } else { ", within " };
                        write!(f, "{sep}{open}{min}, {max}]")
                    }
                    (true, false) => {
                        write!(f, "{sep}{} {min}", if *min_open { ">" } else { ">=" })
                    }
                    (false, true) => write!(f, "{sep}<= {max}"),
                    (false, false) => Ok(()),
                }
            }
            Expect::Bool => f.write_str("a bool"),
            Expect::Position => f.write_str("a position (x, y, z) in m"),
        }
    }
}

/// A value as a message shows it, with its kind: `"fast" (a string)`, `-2 (a number)`.
pub fn describe(v: &Value) -> String {
    match v {
        Value::Unit => "an event without a value".into(),
        Value::Num(x) => format!("{x} (a number)"),
        Value::Bool(b) => format!("{} (a bool)", if *b { "True" } else { "False" }),
        Value::Vec3(p) => format!("({}, {}, {}) (a position)", p[0], p[1], p[2]),
        Value::Tuple(items) => {
            let inner: Vec<String> = items.iter().map(plain).collect();
            format!("({}) (a tuple)", inner.join(", "))
        }
        Value::Text(t) => format!("{t:?} (a string)"),
    }
}

fn plain(v: &Value) -> String {
    match v {
        Value::Unit => "()".into(),
        Value::Num(x) => x.to_string(),
        Value::Bool(b) => if *b { "True" } else { "False" }.into(),
        Value::Vec3(p) => format!("({}, {}, {})", p[0], p[1], p[2]),
        Value::Tuple(items) => {
            let inner: Vec<String> = items.iter().map(plain).collect();
            format!("({})", inner.join(", "))
        }
        Value::Text(t) => format!("{t:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn number(min: f64, max: f64, min_open: bool, unit: &str) -> Expect {
        Expect::Number {
            min,
            max,
            min_open,
            unit: unit.into(),
        }
    }

    #[test]
    fn numbers_are_checked_for_kind_finiteness_and_range() {
        let speed = number(0.0, f64::INFINITY, false, "m/s");
        assert!(speed.accepts(&Value::Num(0.0)));
        assert!(speed.accepts(&Value::Num(30.0)));
        assert!(!speed.accepts(&Value::Num(-0.1)));
        assert!(!speed.accepts(&Value::Num(f64::NAN)));
        assert!(!speed.accepts(&Value::Num(f64::INFINITY)));
        assert!(!speed.accepts(&Value::Text("fast".into())));
        // A bool is not a number here, though `Value::as_num` would read it as 0 or 1.
        assert!(!speed.accepts(&Value::Bool(true)));
        let friction = number(0.0, 2.0, true, "");
        assert!(!friction.accepts(&Value::Num(0.0)));
        assert!(friction.accepts(&Value::Num(2.0)));
        assert!(!friction.accepts(&Value::Num(2.01)));
    }

    #[test]
    fn messages_say_what_is_accepted_and_what_came() {
        assert_eq!(
            number(0.0, f64::INFINITY, false, "m/s").to_string(),
            "a number in m/s, >= 0"
        );
        assert_eq!(
            number(0.0, 1.0, false, "").to_string(),
            "a number in [0, 1]"
        );
        assert_eq!(number(0.0, 2.0, true, "").to_string(), "a number in (0, 2]");
        assert_eq!(describe(&Value::Text("fast".into())), "\"fast\" (a string)");
        assert_eq!(describe(&Value::Num(-2.0)), "-2 (a number)");
    }
}
