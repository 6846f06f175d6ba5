use serde::{Deserialize, Serialize};
use serde_json::Value as Json;

/// A value carried by a stream event.
///
/// `tick` carries the time in seconds as [`Value::Num`]; positions and velocities are
/// [`Value::Vec3`] `[x, y, z]` in metres or m/s; `zip` makes [`Value::Tuple`]s.
///
/// In JSON: `null`, a number, a bool, an array of three numbers (a vector), any other array
/// (a tuple), a string.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// The unit value (an event with no payload).
    Unit,
    /// A number, in the unit of the stream it travels on.
    Num(f64),
    /// A truth value.
    Bool(bool),
    /// A 3-vector `[x, y, z]`, e.g. a position in metres.
    Vec3([f64; 3]),
    /// A tuple, e.g. the pairs made by `zip`.
    Tuple(Vec<Value>),
    /// A text level, e.g. a colour from `VarEnum(["red", "white"])`.
    Text(String),
}

impl Value {
    /// The number, if this is a [`Value::Num`] (a [`Value::Bool`] counts as 0 or 1).
    pub fn as_num(&self) -> Option<f64> {
        match self {
            Value::Num(x) => Some(*x),
            Value::Bool(b) => Some(f64::from(u8::from(*b))),
            _ => None,
        }
    }

    /// The truth value of a [`Value::Bool`]; `None` for every other kind, numbers included:
    /// a number is not a truth value (`filter(lambda p: p.x - 100)` is a mistake, not "fires
    /// unless the difference is exactly 0").
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Bool(b) => Some(*b),
            _ => None,
        }
    }

    /// The vector, if this is a [`Value::Vec3`].
    pub fn as_vec3(&self) -> Option<[f64; 3]> {
        match self {
            Value::Vec3(v) => Some(*v),
            _ => None,
        }
    }

    /// A short name of the variant, for error messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Unit => "unit",
            Value::Num(_) => "number",
            Value::Bool(_) => "bool",
            Value::Vec3(_) => "vector",
            Value::Tuple(_) => "tuple",
            Value::Text(_) => "string",
        }
    }

    /// `self + other` for numbers and vectors (the `sum` combinator's default fold), `None`
    /// for other kinds.
    pub fn add(&self, other: &Value) -> Option<Value> {
        match (self, other) {
            (Value::Num(a), Value::Num(b)) => Some(Value::Num(a + b)),
            (Value::Vec3(a), Value::Vec3(b)) => {
                Some(Value::Vec3([a[0] + b[0], a[1] + b[1], a[2] + b[2]]))
            }
            _ => None,
        }
    }
}

/// Read through `serde_json::Value`, not derived: the workspace's serde_json has
/// `arbitrary_precision` (starlark turns it on), under which a derived untagged enum sees a
/// number as a map and matches no variant.
impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        from_json(Json::deserialize(d)?).map_err(serde::de::Error::custom)
    }
}

/// Why a JSON value is no stream value ([`Value`]'s `Deserialize`).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
enum NotAValue {
    /// A number `f64` cannot hold (its text).
    #[error("{0} is not a number")]
    Number(String),
    /// An object: stream values are numbers, bools, strings and tuples.
    #[error("a stream value is not an object")]
    Object,
}

fn from_json(j: Json) -> Result<Value, NotAValue> {
    let number =
        |n: &serde_json::Number| n.as_f64().ok_or_else(|| NotAValue::Number(n.to_string()));
    Ok(match j {
        Json::Null => Value::Unit,
        Json::Bool(b) => Value::Bool(b),
        Json::Number(n) => Value::Num(number(&n)?),
        Json::String(s) => Value::Text(s),
        Json::Array(a) => match a.as_slice() {
            [Json::Number(x), Json::Number(y), Json::Number(z)] => {
                Value::Vec3([number(x)?, number(y)?, number(z)?])
            }
            _ => Value::Tuple(a.into_iter().map(from_json).collect::<Result<_, _>>()?),
        },
        Json::Object(_) => return Err(NotAValue::Object),
    })
}

impl From<f64> for Value {
    fn from(x: f64) -> Self {
        Value::Num(x)
    }
}

impl From<bool> for Value {
    fn from(b: bool) -> Self {
        Value::Bool(b)
    }
}

impl From<[f64; 3]> for Value {
    fn from(v: [f64; 3]) -> Self {
        Value::Vec3(v)
    }
}
