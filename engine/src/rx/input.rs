//! A number the world reads each step ([`Input`]): a constant known when the world is built, or
//! a stream read each step; and the one reader of each.

use super::{Runtime, StreamId, Value};
use crate::EngineError;

/// A number the world reads each step: a constant, known when the world is built and never
/// read back from the stream graph, or a stream read each step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Input {
    /// A finite constant.
    Const(f64),
    /// A stream, read at each step.
    Stream(StreamId),
}

impl Input {
    /// What `id` of `graph` is as an input: a constant when its node is a finite number
    /// (anything else, a non-finite constant included, is read each step and judged then).
    pub(crate) fn of(graph: &crate::rx::Graph, id: StreamId) -> Input {
        match graph.nodes().get(id.0) {
            Some(crate::rx::Node::Const(Value::Num(v))) if v.is_finite() => Input::Const(*v),
            _ => Input::Stream(id),
        }
    }

    /// The stream, for an input read each step.
    pub(crate) fn stream(self) -> Option<StreamId> {
        match self {
            Input::Const(_) => None,
            Input::Stream(id) => Some(id),
        }
    }
}

/// The number `input` holds now: a constant's value, or its stream's latest event.
///
/// # Errors
/// [`crate::rx::RxError::Input`] naming `what` when the stream has no value yet (it has not
/// fired) or its latest value is not a finite number: an input is never read as a default or
/// as 0 in its place.
pub(crate) fn number(
    rt: &Runtime,
    input: Input,
    t_s: f64,
    what: impl FnOnce() -> String,
) -> Result<f64, EngineError> {
    let id = match input {
        Input::Const(v) => return Ok(v),
        Input::Stream(id) => id,
    };
    match rt.current(id) {
        // Never a default in place of a value the program's stream did not give.
        None => Err(crate::rx::RxError::Input {
            name: what(),
            t_s,
            value: "without a value (its stream had not fired yet)".into(),
            expected: "a number from the test's first step on: a computed input needs a \
                       stream that fires at t = 0, such as tick.map(lambda t: 0.1 if t > 100 \
                       else 0.8)"
                .into(),
        }
        .into()),
        Some(Value::Num(x)) if x.is_finite() => Ok(*x),
        Some(v) => Err(crate::rx::RxError::Input {
            name: what(),
            t_s,
            value: crate::rx::describe(v),
            expected: "a finite number".into(),
        }
        .into()),
    }
}

/// The number stream `id` carries at t = 0 when that is known without running the program's
/// code: a constant or a bound open stream (also one varying over time). The one place the
/// engine reads a constant from the graph; a bool or any other value is not a number here.
pub(crate) fn constant(graph: &crate::rx::Graph, id: StreamId) -> Option<f64> {
    let value = match graph.nodes().get(id.0)? {
        crate::rx::Node::Const(v) => v.clone(),
        crate::rx::Node::Open(open) => open.at(0.0),
        _ => return None,
    };
    match value {
        Value::Num(v) => Some(v),
        _ => None,
    }
}
