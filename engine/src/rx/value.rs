use serde::{Deserialize, Serialize};

/// A value carried by a stream event.
///
/// `tick` carries the time in seconds as [`Value::Num`]; positions and velocities are
/// [`Value::Vec3`] `[x, y, z]` in metres or m/s; `zip` makes [`Value::Tuple`]s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

    /// The truth value: a [`Value::Bool`], or a number that is not `0`.
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Bool(b) => Some(*b),
            Value::Num(x) => Some(*x != 0.0),
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
