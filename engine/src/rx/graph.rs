use std::fmt;
use std::sync::Arc;

use crate::behaviour::{Action, Probe};

use super::{OpenStream, RxError, Value};

/// Index of a stream in its [`Graph`].
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct StreamId(pub usize);

/// A native function on stream values: arguments in, a value or its refusal out.
pub type NativeFn = Arc<dyn Fn(&[Value]) -> Result<Value, NativeError> + Send + Sync>;

/// Why a native function refused its arguments (values of a kind it does not take); the
/// runtime reports it as [`super::RxError::Type`] at the node that called it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct NativeError(pub String);

impl From<String> for NativeError {
    fn from(message: String) -> Self {
        NativeError(message)
    }
}

impl From<&str> for NativeError {
    fn from(message: &str) -> Self {
        NativeError(message.to_owned())
    }
}

/// A function a combinator applies.
#[derive(Clone)]
pub enum Func {
    /// A Rust closure, with a name for messages.
    Native(&'static str, NativeFn),
    /// Host function number `n` (a Starlark lambda), called through [`super::Host`].
    Host(u32),
}

impl Func {
    /// A named native function.
    pub fn native(
        name: &'static str,
        f: impl Fn(&[Value]) -> Result<Value, NativeError> + Send + Sync + 'static,
    ) -> Self {
        Func::Native(name, Arc::new(f))
    }
}

impl fmt::Debug for Func {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Func::Native(name, _) => write!(f, "Native({name})"),
            Func::Host(n) => write!(f, "Host({n})"),
        }
    }
}

/// One stream of a graph. Combinators name their inputs by [`StreamId`].
#[derive(Debug, Clone)]
pub enum Node {
    /// `Const(v)`: `v` at every step.
    Const(Value),
    /// `tick`: the time in seconds at every step.
    Tick,
    /// An open parameter slot, bound to a test case's values by [`Graph::bind`].
    Param(usize),
    /// A bound open input stream.
    Open(OpenStream),
    /// A physics output of an actor (a position, a velocity, a contact flag...), read
    /// through [`super::Inputs`] at every step.
    Probe(Probe),
    /// `src.map(f)`.
    Map {
        /// Source.
        src: StreamId,
        /// Function of one argument.
        f: Func,
    },
    /// `src.filter(p)`.
    Filter {
        /// Source.
        src: StreamId,
        /// Predicate of one argument, returning a bool.
        pred: Func,
    },
    /// `a.zip(b)`: pairs as [`Value::Tuple`].
    Zip(StreamId, StreamId),
    /// `src.take(n)`.
    Take {
        /// Source.
        src: StreamId,
        /// Number of events passed.
        n: u64,
    },
    /// `src.skipUntil(trigger)`.
    SkipUntil {
        /// Source.
        src: StreamId,
        /// The stream whose first event opens the gate.
        trigger: StreamId,
    },
    /// `src.takeUntil(stop)`.
    TakeUntil {
        /// Source.
        src: StreamId,
        /// The stream whose first event closes the gate.
        stop: StreamId,
    },
    /// `a.concat(b)`.
    Concat(StreamId, StreamId),
    /// `src.sum()` (with `f: None`, adding numbers or vectors) or `src.sum(init, f)`.
    Sum {
        /// Source.
        src: StreamId,
        /// Initial accumulator: the first event emits `init + v` (or `f(init, v)`).
        init: Value,
        /// Fold `acc, v -> acc`; `None` adds.
        f: Option<Func>,
    },
    /// `src.foreach(sink)`: each event goes to the action `sink`, which acts on an actor.
    Foreach {
        /// Source.
        src: StreamId,
        /// The action, performed by the caller ([`super::Runtime::step`]'s sinks).
        sink: Action,
    },
    /// `src.foreach(f)` with a host function: `f(v)` for each event, for the actions it
    /// performs ([`super::Host::performed`]); what it returns is dropped.
    Perform {
        /// Source.
        src: StreamId,
        /// The function, of one argument.
        f: Func,
    },
    /// `src`'s events, each checked against `expect` before anything reads it: an input of the
    /// world fed by a stream whose values are known only while the test runs (a lambda's).
    /// A value it does not accept is [`RxError::Input`] naming `name`.
    Check {
        /// Source.
        src: StreamId,
        /// What the input accepts.
        expect: super::Expect,
        /// The input, for messages: e.g. `the speed of Car lead (follow.star:12:8)`.
        name: Arc<str>,
    },
}

impl Node {
    /// The streams this node reads.
    pub fn inputs(&self) -> Vec<StreamId> {
        match self {
            Node::Const(_) | Node::Tick | Node::Param(_) | Node::Open(_) | Node::Probe(_) => {
                vec![]
            }
            Node::Map { src, .. }
            | Node::Filter { src, .. }
            | Node::Take { src, .. }
            | Node::Sum { src, .. }
            | Node::Foreach { src, .. }
            | Node::Perform { src, .. }
            | Node::Check { src, .. } => vec![*src],
            Node::Zip(a, b) | Node::Concat(a, b) => vec![*a, *b],
            Node::SkipUntil { src, trigger: o } | Node::TakeUntil { src, stop: o } => {
                vec![*src, *o]
            }
        }
    }
}

/// A checked stream graph: nodes plus their evaluation order.
#[derive(Debug, Clone)]
pub struct Graph {
    nodes: Vec<Node>,
    order: Vec<usize>,
    /// Where each node was made, when known (see [`Graph::site`]).
    sites: Vec<Option<String>>,
}

impl Graph {
    /// Checks `nodes` and orders them topologically (Kahn's algorithm; ties in index order, so
    /// the order is deterministic).
    ///
    /// # Errors
    /// [`RxError::Dangling`] for a reference past the end, [`RxError::Cycle`] for a cycle.
    pub fn new(nodes: Vec<Node>) -> Result<Self, RxError> {
        let n = nodes.len();
        let mut indegree = vec![0usize; n];
        let mut readers = vec![Vec::new(); n];
        for (i, node) in nodes.iter().enumerate() {
            for StreamId(j) in node.inputs() {
                if j >= n {
                    return Err(RxError::Dangling {
                        node: i,
                        missing: j,
                    });
                }
                indegree[i] += 1;
                readers[j].push(i);
            }
        }
        let mut ready: std::collections::BTreeSet<usize> =
            (0..n).filter(|&i| indegree[i] == 0).collect();
        let mut order = Vec::with_capacity(n);
        while let Some(i) = ready.pop_first() {
            order.push(i);
            for &r in &readers[i] {
                indegree[r] -= 1;
                if indegree[r] == 0 {
                    ready.insert(r);
                }
            }
        }
        if let Some(stuck) = (0..n).find(|&i| indegree[i] > 0) {
            return Err(RxError::Cycle(stuck));
        }
        Ok(Graph {
            sites: vec![None; nodes.len()],
            nodes,
            order,
        })
    }

    /// The graph with node `i` made at `sites[i]` (a program's `file:line:col`); missing or
    /// `None` entries stay unknown.
    pub fn with_sites(mut self, mut sites: Vec<Option<String>>) -> Self {
        sites.resize(self.nodes.len(), None);
        self.sites = sites;
        self
    }

    /// How messages name node `node`: where it was made (`f.star:5:15`), else `stream N`.
    pub fn site(&self, node: usize) -> String {
        match self.sites.get(node) {
            Some(Some(site)) => site.clone(),
            _ => format!("stream {node}"),
        }
    }

    /// Where node `node` was made (a program's `file:line:col`), when known.
    pub fn made_at(&self, node: usize) -> Option<&str> {
        self.sites.get(node).and_then(|s| s.as_deref())
    }

    /// The nodes, by [`StreamId`].
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The evaluation order (node indices).
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// The graph with every [`Node::Param`]`(slot)` replaced by `Open(values[slot])`: a test
    /// case closing the open streams.
    ///
    /// # Errors
    /// [`RxError::Unbound`] for a slot past the end of `values`.
    pub fn bind(&self, values: &[OpenStream]) -> Result<Graph, RxError> {
        let mut nodes = self.nodes.clone();
        for (i, node) in nodes.iter_mut().enumerate() {
            if let Node::Param(slot) = *node {
                let v = values.get(slot).ok_or(RxError::Unbound { node: i, slot })?;
                *node = Node::Open(v.clone());
            }
        }
        Ok(Graph {
            nodes,
            order: self.order.clone(),
            sites: self.sites.clone(),
        })
    }
}
