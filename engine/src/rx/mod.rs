//! The reactive runtime: synchronous dataflow over the `tick` stream (paper §2).
//!
//! A [`Graph`] is a list of stream [`Node`]s: sources (`Const`, `tick`, open parameters,
//! physics probes) and combinators (`map`, `filter`, `zip`, `take`, `skipUntil`, `takeUntil`,
//! `concat`, `sum`, `foreach`). A [`Runtime`] evaluates every node once per physics step, in
//! topological order, so a node sees this step's events of the nodes it reads. Each stream
//! has a current value (the last event) and a per-step "fired" flag; a completed stream never
//! fires again. `foreach` sinks report their events to the caller, which acts on the world.
//!
//! Semantics (one event per stream per step at most):
//! - `Const(v)`, `tick`, open parameters and probes fire every step. `tick` carries the time
//!   in seconds (the paper's unit event, with the clock attached).
//! - `map(f)` / `filter(p)` fire when their source fires (and `p` holds).
//! - `take(n)` passes the first `n` events, then completes.
//! - `skipUntil(t)` passes events from the first step in which `t` fires, inclusive.
//! - `takeUntil(s)` passes events until the first step in which `s` fires, exclusive, then
//!   completes.
//! - `zip(a, b)` pairs the `i`-th events of `a` and `b` (queues, as Rx's `zip`).
//! - `concat(a, b)` emits `a`'s events, then `b`'s, starting with `b`'s event in the step in
//!   which `a` completes; events queue so one leaves per step. Hence the paper's
//!   `pos.take(1).concat(pos)` is `pos` delayed by one step.
//! - `sum()` emits the running total (numbers or vectors); `sum(init, f)` the running fold
//!   `acc = f(acc, v)`.
//! - `Check` passes its source's events after checking each against what an input of the
//!   world accepts ([`Expect`]); the first value it refuses ends the step with
//!   [`RxError::Input`].
//!
//! Functions are native Rust closures or host functions (Starlark lambdas), called through the
//! [`Host`] trait so this crate does not depend on the language front end.

mod expect;
mod graph;
mod input;
mod open;
mod runtime;
#[cfg(test)]
mod tests;
mod value;

pub use expect::{describe, Expect};
pub use graph::{Func, Graph, NativeError, NativeFn, Node, StreamId};
pub(crate) use input::{constant, number, Input};
pub use open::OpenStream;
pub use runtime::{Host, HostError, Inputs, NoHost, Runtime};
pub use value::Value;

use thiserror::Error;

/// Errors building or running a stream graph.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RxError {
    /// The graph has a cycle through the named node.
    #[error("stream graph has a cycle through stream {0}")]
    Cycle(usize),
    /// A node reads a stream that does not exist.
    #[error("stream {node} reads stream {missing}, which does not exist")]
    Dangling {
        /// The reading node.
        node: usize,
        /// The missing index.
        missing: usize,
    },
    /// An open parameter slot was not bound before running.
    #[error("stream {node} reads open parameter {slot}, which was not bound")]
    Unbound {
        /// The node.
        node: usize,
        /// The parameter slot.
        slot: usize,
    },
    /// A value of the wrong kind reached a combinator or a function.
    #[error("{at}: {message}")]
    Type {
        /// The node.
        node: usize,
        /// Where the node was made (`f.star:5:15`), else `stream N` ([`Graph::site`]).
        at: String,
        /// What was expected and what came.
        message: String,
    },
    /// An input of the world received a value it does not accept (see [`Node::Check`]).
    #[error("at t = {t_s:.3} s, {name} was {value}; it must be {expected}")]
    Input {
        /// The input, e.g. `the speed of Car lead (follow.star:12:8)`.
        name: String,
        /// Simulated time of the event, s.
        t_s: f64,
        /// The value, with its kind (see [`describe`]).
        value: String,
        /// What it accepts (see [`Expect`]).
        expected: String,
    },
    /// A host function (a Starlark lambda) failed.
    #[error("{}{at}: {message}", at_time(.t_s))]
    Host {
        /// The node that called it.
        node: usize,
        /// Where the node was made (`f.star:5:15`), else `stream N` ([`Graph::site`]).
        at: String,
        /// The host's message.
        message: String,
        /// Simulated time of the step it failed in, s; `None` outside a step (the check at
        /// load).
        t_s: Option<f64>,
    },
}

/// `at t = 1.017 s, ` for an error at a known time, else nothing.
fn at_time(t_s: &Option<f64>) -> String {
    t_s.map(|t| format!("at t = {t:.3} s, "))
        .unwrap_or_default()
}
