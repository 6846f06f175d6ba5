//! The types of the builtins' inputs (LANGUAGE.md, "Types of inputs"), checked when the
//! program loads wherever the value is known then (a constant, `Const(...)`, the range or
//! levels of a `VarInterval`/`VarEnum`, a stream whose kind the graph tells), and as the test
//! runs for streams computed by lambdas ([`paracosm_engine::rx::Node::Check`]).

use std::sync::Arc;

use anyhow::bail;
use paracosm_engine::rx::{describe, Expect, Node, StreamId, Value as Rx};
use paracosm_generators::Domain;

use super::scene::{level_value, SceneBuilder};
pub use crate::scene::SType;

/// What an input accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A finite number in `unit` (empty: unitless), in `[min, max]`, or `(min, max]` with
    /// `min_open`.
    Number {
        /// The unit, e.g. `m/s`.
        unit: &'static str,
        /// Lower bound.
        min: f64,
        /// Upper bound (may be infinite).
        max: f64,
        /// Whether `min` is excluded.
        min_open: bool,
    },
    /// A truth value.
    Bool,
    /// A colour name from [`paracosm_engine::colour::COLOURS`].
    Colour,
    /// A position `(x, y, z)` in metres.
    Position,
    /// Any events: only when they come matters (a trigger).
    Event,
}

/// An input of a builtin: its keyword and what it accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Input {
    /// The keyword, e.g. `fog`.
    pub keyword: &'static str,
    /// What it accepts.
    pub kind: Kind,
}

/// A number input: `keyword` in `unit`, in `[min, max]` (`(min, max]` with `min_open`).
pub(crate) const fn number(
    keyword: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    min_open: bool,
) -> Input {
    Input {
        keyword,
        kind: Kind::Number {
            unit,
            min,
            max,
            min_open,
        },
    }
}

/// `World(light=)`: `[0, 1]`, 0.5 nominal daylight.
pub const LIGHT: Input = number("light", "", 0.0, 1.0, false);
/// `World(fog=)`: `[0, 1]`.
pub const FOG: Input = number("fog", "", 0.0, 1.0, false);
/// `friction=` of every road piece: `(0, 2]`.
pub const FRICTION: Input = number("friction", "", 0.0, 2.0, true);
/// `Car(speed=)`, m/s, `>= 0`.
pub const CAR_SPEED: Input = number("speed", "m/s", 0.0, f64::INFINITY, false);
/// `Pedestrian(speed=)`, m/s, `>= 0`.
pub const PEDESTRIAN_SPEED: Input = number("speed", "m/s", 0.0, f64::INFINITY, false);
/// `Pedestrian(dist=)`, m, `>= 0`.
pub const TRIGGER_DISTANCE: Input = number("dist", "m", 0.0, f64::INFINITY, false);
/// `Pedestrian(car=)`: a position stream (or an actor, whose `pos` it reads).
pub const WATCHED_POSITION: Input = Input {
    keyword: "car",
    kind: Kind::Position,
};
/// `Pedestrian(trigger=)`: any stream; its first event starts the walk.
pub const TRIGGER: Input = Input {
    keyword: "trigger",
    kind: Kind::Event,
};
/// `Car(color=)`: a colour name.
pub const COLOR: Input = Input {
    keyword: "color",
    kind: Kind::Colour,
};
/// `Car(enabled=)`: a bool.
pub const ENABLED: Input = Input {
    keyword: "enabled",
    kind: Kind::Bool,
};

/// The largest turn of a curved piece, rad (3π/2).
pub(crate) const MAX_TURN: f64 = paracosm_engine::network::MAX_TURN_RAD;

impl Kind {
    /// The run-time check of a number stream; `None` for kinds that are not numbers.
    pub fn expect(&self) -> Option<Expect> {
        match *self {
            Kind::Number {
                unit,
                min,
                max,
                min_open,
            } => Some(Expect::Number {
                min,
                max,
                min_open,
                unit: unit.to_owned(),
            }),
            Kind::Bool => Some(Expect::Bool),
            Kind::Position => Some(Expect::Position),
            Kind::Colour | Kind::Event => None,
        }
    }

    /// Whether a value known when the program loads is accepted.
    pub fn accepts(&self, v: &Rx) -> bool {
        match self {
            Kind::Colour => {
                matches!(v, Rx::Text(t) if paracosm_engine::colour::albedo(t).is_some())
            }
            Kind::Event => true,
            _ => self.expect().is_some_and(|e| e.accepts(v)),
        }
    }

    fn stream_kind(&self) -> SType {
        match self {
            Kind::Number { .. } => SType::Num,
            Kind::Bool => SType::Bool,
            Kind::Colour => SType::Text,
            Kind::Position => SType::Vec3,
            Kind::Event => SType::Any,
        }
    }
}

impl std::fmt::Display for Kind {
    /// E.g. `a number in m/s, >= 0`, `a colour name (red, white, ...)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Kind::Colour => write!(f, "a colour name ({})", paracosm_engine::colour::names()),
            Kind::Event => f.write_str("any stream"),
            _ => match self.expect() {
                Some(e) => write!(f, "{e}"),
                None => Ok(()),
            },
        }
    }
}

/// How a program names an open parameter in messages: `` `speed` (VarInterval at f.star:3:9) ``.
fn param_label(b: &SceneBuilder, p: usize) -> String {
    let d = &b.scene.params()[p];
    let what = match d.domain {
        Domain::Interval { .. } => "VarInterval",
        Domain::Levels(_) => "VarEnum",
    };
    match &d.name {
        Some(n) => format!("`{n}` ({what} at {})", d.site),
        None => format!("the {what} at {}", d.site),
    }
}

/// Checks that every value open parameter `p` (one that varies over time, the only kind that
/// stays a stream) can take is accepted by `input` of `owner` (e.g. `World`).
///
/// # Errors
/// A message naming the input, what it accepts, and the parameter's range or level.
pub fn check_param(
    b: &mut SceneBuilder,
    p: usize,
    input: &Input,
    owner: &str,
) -> anyhow::Result<()> {
    let label = param_label(b, p);
    let d = b.scene.params()[p].clone();
    let kind = input.kind;
    match (&d.domain, kind) {
        (_, Kind::Event) => {}
        (
            Domain::Interval { lo, hi },
            Kind::Number {
                min, max, min_open, ..
            },
        ) => {
            let low_ok = if min_open { *lo > min } else { *lo >= min };
            if !low_ok || *hi > max {
                bail!(
                    "{owner}({}=) takes {kind}, but {label} ranges over [{lo}, {hi})",
                    input.keyword
                );
            }
        }
        (Domain::Interval { lo, hi }, _) => bail!(
            "{owner}({}=) takes {kind}, but {label} is a number in [{lo}, {hi})",
            input.keyword
        ),
        (Domain::Levels(levels), _) => {
            for l in levels {
                let v = level_value(l);
                if !kind.accepts(&v) {
                    bail!(
                        "{owner}({}=) takes {kind}, but {label} has the level {}",
                        input.keyword,
                        describe(&v)
                    );
                }
            }
        }
    }
    Ok(())
}

/// Checks a value known when the program loads against `input` of `owner`.
///
/// # Errors
/// A message naming the input, what it accepts and what it got.
pub fn check_const(v: &Rx, input: &Input, owner: &str) -> anyhow::Result<()> {
    if !input.kind.accepts(v) {
        bail!(
            "{owner}({}=) takes {}, got {}",
            input.keyword,
            input.kind,
            describe(v)
        );
    }
    Ok(())
}

/// The stream to feed `input` of `owner` (named `at` in run-time messages, e.g. `Car declared
/// at f.star:3:5`) from the program's stream `id`: checked now where its values are known
/// (a constant, an open parameter), refused when its kind is wrong, and otherwise wrapped in a
/// [`Node::Check`] that checks each value as the test runs.
///
/// # Errors
/// A message naming the input, what it accepts and what the stream carries.
pub fn typed_stream(
    b: &mut SceneBuilder,
    id: StreamId,
    input: &Input,
    owner: &str,
    at: &str,
) -> anyhow::Result<StreamId> {
    if input.kind == Kind::Event {
        return Ok(id);
    }
    match b.scene.nodes().get(id.0) {
        Some(Node::Const(v)) => {
            let v = v.clone();
            check_const(&v, input, owner)?;
            return Ok(id);
        }
        Some(Node::Param(p)) => {
            let p = *p;
            check_param(b, p, input, owner)?;
            return Ok(id);
        }
        _ => {}
    }
    let types = b.scene.stream_types();
    let carried = types.get(id.0).copied().unwrap_or(SType::Any);
    let wanted = input.kind.stream_kind();
    if carried != SType::Any && carried != wanted {
        bail!(
            "{owner}({}=) takes {}, but this stream carries {}",
            input.keyword,
            input.kind,
            carried.name()
        );
    }
    // Positions and bools from the graph are exact; numbers need their range checked, and a
    // lambda's values their kind too.
    if carried == wanted && matches!(wanted, SType::Vec3 | SType::Bool) {
        return Ok(id);
    }
    let Some(expect) = input.kind.expect() else {
        return Ok(id);
    };
    let name: Arc<str> = Arc::from(format!("the {} of {owner} {at}", input.keyword));
    Ok(b.scene.push(Node::Check {
        src: id,
        expect,
        name,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_accept_what_they_say_and_describe_it() {
        assert!(FOG.kind.accepts(&Rx::Num(0.5)));
        assert!(!FOG.kind.accepts(&Rx::Num(3.0)));
        assert!(!FOG.kind.accepts(&Rx::Text("thick".into())));
        assert!(!FRICTION.kind.accepts(&Rx::Num(0.0)));
        assert!(COLOR.kind.accepts(&Rx::Text("white".into())));
        assert!(!COLOR.kind.accepts(&Rx::Text("purple".into())));
        assert!(!ENABLED.kind.accepts(&Rx::Num(1.0)));
        assert_eq!(FOG.kind.to_string(), "a number in [0, 1]");
        assert_eq!(CAR_SPEED.kind.to_string(), "a number in m/s, >= 0");
        assert!(COLOR
            .kind
            .to_string()
            .starts_with("a colour name (red, white"));
    }
}
