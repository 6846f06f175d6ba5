use std::collections::VecDeque;

use super::{Func, Graph, NativeError, Node, RxError, StreamId, Value};
use crate::behaviour::{Action, Probe};

/// The physics outputs a graph's [`Node::Probe`]s read, supplied by the simulation each step.
pub trait Inputs {
    /// The current value of `probe`; [`Value::Unit`] for an actor that is not in the test
    /// (a disabled car), whose probes then have no event.
    fn probe(&self, probe: Probe) -> Value;
}

/// A host function's failure ([`Host::call`]): its message, as the program's author reads it
/// (a Starlark error with its located frames, a limit the call ran into).
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[error("{0}")]
pub struct HostError(pub String);

impl From<String> for HostError {
    fn from(message: String) -> Self {
        HostError(message)
    }
}

/// Calls host functions (Starlark lambdas) for [`Func::Host`].
pub trait Host {
    /// Calls host function `f` with `args`. `streams` gives the latest value of every stream
    /// of the graph (see [`Runtime::current`]), for functions that read streams they captured.
    ///
    /// # Errors
    /// The function's own failure, as a [`HostError`] carrying its message.
    fn call(&mut self, f: u32, args: &[Value], streams: &Runtime) -> Result<Value, HostError>;

    /// The actions host functions performed since the last call of this method, as
    /// `(action, value)` pairs in the order they were performed (a Starlark `def` given to
    /// `foreach` that calls `car.brake(6)`). The default host performs none.
    fn performed(&mut self) -> Vec<(Action, Value)> {
        Vec::new()
    }

    /// The lines host functions printed since the last call of this method (Starlark's
    /// `print`), for the test's log. The default host prints none.
    fn log(&mut self) -> Vec<String> {
        Vec::new()
    }

    /// The streams whose latest values this host's functions read through
    /// [`Runtime::current`] besides their arguments (a Starlark lambda sees the program's
    /// module-level stream variables). A runtime that evaluates only the streams something
    /// reads ([`Runtime::evaluate_only`]) keeps these. The default host reads none.
    fn reads(&self) -> &[StreamId] {
        &[]
    }

    /// Whether the test is over by the host's own account (an OpenSCENARIO storyboard's stop
    /// trigger has fired): the runner then ends it as if its horizon had come. The default
    /// host never ends a test.
    fn ended(&self) -> bool {
        false
    }

    /// Called once when the test reaches its horizon at `t_s` (s) with no monitor failed and
    /// the host not [`Host::ended`]: whether the test counts as played. The default host's
    /// tests always count.
    ///
    /// # Errors
    /// A [`HostError`] saying why the test cannot count (an OpenSCENARIO storyboard cut short
    /// while its events still waited to start): the runner ends the test as an error.
    fn finish(&mut self, t_s: f64) -> Result<(), HostError> {
        let _ = t_s;
        Ok(())
    }
}

/// A [`Host`] without functions: every call is an error. For graphs built in Rust.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHost;

impl Host for NoHost {
    fn call(&mut self, f: u32, _args: &[Value], _streams: &Runtime) -> Result<Value, HostError> {
        Err(HostError(format!("no host function {f} in this world")))
    }
}

#[derive(Debug, Clone, Default)]
struct State {
    value: Option<Value>,
    fired: bool,
    done: bool,
    count: u64,
    open: bool,
    queue_a: VecDeque<Value>,
    queue_b: VecDeque<Value>,
}

/// A graph being run: each stream's current value, fired flag and internal state.
#[derive(Debug, Clone)]
pub struct Runtime {
    graph: Graph,
    states: Vec<State>,
    /// The nodes a step evaluates ([`Runtime::evaluate_only`]); `None`: every node.
    live: Option<Vec<bool>>,
    /// Whether the host's reads ([`Host::reads`]) have been added to `live`: at the first
    /// step, so that a stream they keep has every event from the start.
    host_reads_kept: bool,
}

impl Runtime {
    /// A runtime at time zero, before the first step. The graph must be bound (no
    /// [`Node::Param`] left).
    pub fn new(graph: Graph) -> Self {
        let states = vec![State::default(); graph.nodes().len()];
        Runtime {
            graph,
            states,
            live: None,
            host_reads_kept: false,
        }
    }

    /// Evaluates, from the first step on, only the streams something reads: `roots` (the
    /// streams the caller reads with [`Runtime::current`] or [`Runtime::fired`]), the streams
    /// the host's functions read ([`Host::reads`], added at the first step), every node that
    /// acts or may fail (a `foreach`, a function of the program or a native one, a `sum`, a
    /// [`Node::Check`]), and every stream these read, transitively. The others (a probe of an
    /// actor's output no monitor reads, a `zip` of them, a constant) are pure and cannot
    /// fail, so leaving them out changes no event of a stream that is evaluated, no action
    /// and no error; their [`Runtime::current`] stays `None`.
    ///
    /// Call it before the first [`Runtime::step`]; a later call is ignored (a stream kept
    /// from then on would have missed events).
    pub fn evaluate_only(&mut self, roots: impl IntoIterator<Item = StreamId>) {
        if self.host_reads_kept || self.states.iter().any(|s| s.value.is_some()) {
            return;
        }
        let nodes = self.graph.nodes();
        let mut live: Vec<bool> = nodes
            .iter()
            .map(|n| {
                !matches!(
                    n,
                    Node::Const(_)
                        | Node::Tick
                        | Node::Open(_)
                        | Node::Probe(_)
                        | Node::Zip(..)
                        | Node::Take { .. }
                        | Node::SkipUntil { .. }
                        | Node::TakeUntil { .. }
                        | Node::Concat(..)
                )
            })
            .collect();
        for id in roots {
            if let Some(l) = live.get_mut(id.0) {
                *l = true;
            }
        }
        self.live = Some(live);
        self.propagate_live();
    }

    /// Marks every stream a live stream reads as live: one pass against the topological
    /// order, since a node's inputs come before it.
    fn propagate_live(&mut self) {
        let Some(live) = self.live.as_mut() else {
            return;
        };
        let nodes = self.graph.nodes();
        for &i in self.graph.order().iter().rev() {
            if live[i] {
                for input in nodes[i].inputs() {
                    live[input.0] = true;
                }
            }
        }
    }

    /// The graph.
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// The last value of `id`, `None` before its first event.
    pub fn current(&self, id: StreamId) -> Option<&Value> {
        self.states.get(id.0).and_then(|s| s.value.as_ref())
    }

    /// Whether `id` fired in the last step.
    pub fn fired(&self, id: StreamId) -> bool {
        self.states.get(id.0).is_some_and(|s| s.fired)
    }

    /// Whether `id` has completed.
    pub fn completed(&self, id: StreamId) -> bool {
        self.states.get(id.0).is_some_and(|s| s.done)
    }

    /// Evaluates every stream once for the step at `t_s` seconds, in topological order.
    /// Events reaching `foreach` sinks are appended to `sinks` as `(sink, value)`, in node
    /// order.
    ///
    /// # Errors
    /// [`RxError::Type`] for a value of the wrong kind, [`RxError::Host`] when a host function
    /// fails, [`RxError::Unbound`] for an unbound parameter.
    pub fn step(
        &mut self,
        t_s: f64,
        inputs: &dyn Inputs,
        host: &mut dyn Host,
        sinks: &mut Vec<(Action, Value)>,
    ) -> Result<(), RxError> {
        if !self.host_reads_kept {
            self.host_reads_kept = true;
            if let Some(live) = self.live.as_mut() {
                for id in host.reads() {
                    if let Some(l) = live.get_mut(id.0) {
                        *l = true;
                    }
                }
                self.propagate_live();
            }
        }
        for k in 0..self.graph.order().len() {
            let i = self.graph.order()[k];
            if self.live.as_ref().is_some_and(|live| !live[i]) {
                continue;
            }
            // A constant, or an open stream given one value for the test, emits the same value
            // every step: keep the one it holds.
            if let (Node::Const(_) | Node::Open(super::OpenStream::Constant(_)), Some(_)) =
                (&self.graph.nodes()[i], &self.states[i].value)
            {
                self.states[i].fired = !self.states[i].done;
                continue;
            }
            let out = self
                .eval(i, t_s, inputs, host, sinks)
                .map_err(|e| match e {
                    RxError::Host {
                        node,
                        at,
                        message,
                        t_s: None,
                    } => RxError::Host {
                        node,
                        at,
                        message,
                        t_s: Some(t_s),
                    },
                    e => e,
                })?;
            let s = &mut self.states[i];
            s.fired = out.is_some();
            if let Some(v) = out {
                s.value = Some(v);
            }
        }
        Ok(())
    }

    /// Calls every function of the graph once, in topological order, on a sample value of
    /// each stream at `t_s`: sources give their value now, and every combinator passes its
    /// source's sample on whatever its gate (a `filter` whose predicate is false, a
    /// `skipUntil` not yet opened) would do, so each function sees a value of the type it
    /// will see during a test. Each stream's sample becomes its current value, so functions
    /// reading captured streams see values too. Actions performed are discarded. Used to find
    /// type errors in lambdas when a program loads rather than in every test.
    ///
    /// # Errors
    /// The first [`RxError::Host`] or [`RxError::Type`] a function raised: a filter predicate
    /// that returns no bool, a `sum` of values that do not add; [`RxError::Input`] for an
    /// input checked by a [`Node::Check`] whose sample is of the wrong kind (a string or a
    /// bool where a number belongs; not a number out of range, which the tests find).
    pub fn check(
        &mut self,
        t_s: f64,
        inputs: &dyn Inputs,
        host: &mut dyn Host,
    ) -> Result<(), RxError> {
        for k in 0..self.graph.order().len() {
            let i = self.graph.order()[k];
            let sample = |s: &Self, id: &StreamId| s.states[id.0].value.clone();
            let node = self.graph.nodes()[i].clone();
            let out = match &node {
                Node::Const(_) | Node::Tick | Node::Open(_) | Node::Probe(_) | Node::Param(_) => {
                    source(i, &node, t_s, inputs)?
                }
                Node::Map { src, f } => match sample(self, src) {
                    Some(v) => Some(call(i, f, &[v], host, self)?),
                    None => None,
                },
                Node::Filter { src, pred } => match sample(self, src) {
                    Some(v) => {
                        let keep = call(i, pred, std::slice::from_ref(&v), host, self)?;
                        if keep.as_bool().is_none() {
                            return Err(type_error(
                                &self.graph,
                                i,
                                "filter predicate",
                                "bool",
                                &keep,
                            ));
                        }
                        Some(v)
                    }
                    None => None,
                },
                Node::Zip(a, b) => match (sample(self, a), sample(self, b)) {
                    (Some(a), Some(b)) => Some(Value::Tuple(vec![a, b])),
                    _ => None,
                },
                Node::Take { src, .. }
                | Node::SkipUntil { src, .. }
                | Node::TakeUntil { src, .. } => sample(self, src),
                // The kind of an input's value is known from its sample (a string or a
                // position where a number belongs); its range is left to the tests, where
                // the values are real.
                Node::Check { src, expect, name } => match sample(self, src) {
                    Some(v) if !expect.accepts_kind(&v) => {
                        return Err(RxError::Input {
                            name: name.to_string(),
                            t_s,
                            value: super::describe(&v),
                            expected: expect.to_string(),
                        })
                    }
                    v => v,
                },
                Node::Concat(a, b) => sample(self, a).or_else(|| sample(self, b)),
                Node::Sum { src, init, f } => match sample(self, src) {
                    Some(v) => Some(match f {
                        Some(f) => call(i, f, &[init.clone(), v], host, self)?,
                        None => total(init, &v).ok_or_else(|| {
                            type_error(&self.graph, i, "sum", "numbers or vectors of one kind", &v)
                        })?,
                    }),
                    None => None,
                },
                Node::Perform { src, f } => {
                    if let Some(v) = sample(self, src) {
                        call_acting(i, f, &[v], host, self)?;
                        host.performed();
                    }
                    None
                }
                Node::Foreach { .. } => None,
            };
            self.states[i].value = out;
        }
        Ok(())
    }

    fn event(&self, id: StreamId) -> Option<&Value> {
        let s = &self.states[id.0];
        if s.fired {
            s.value.as_ref()
        } else {
            None
        }
    }

    fn eval(
        &mut self,
        i: usize,
        t_s: f64,
        inputs: &dyn Inputs,
        host: &mut dyn Host,
        sinks: &mut Vec<(Action, Value)>,
    ) -> Result<Option<Value>, RxError> {
        if self.states[i].done {
            return Ok(None);
        }
        let done = |s: &Self, id: StreamId| s.states[id.0].done;
        let node = &self.graph.nodes()[i];
        let out = match node {
            Node::Const(_) | Node::Tick | Node::Open(_) | Node::Probe(_) | Node::Param(_) => {
                source(i, node, t_s, inputs)?
            }
            Node::Map { src, f } => {
                let f = f.clone();
                self.map(i, *src, &f, host)?
            }
            Node::Filter { src, pred } => {
                let pred = pred.clone();
                self.filter(i, *src, &pred, host)?
            }
            Node::Zip(a, b) => self.zip(i, *a, *b),
            Node::Take { src, n } => self.take(i, *src, *n),
            Node::SkipUntil { src, trigger } => self.skip_until(i, *src, *trigger),
            Node::TakeUntil { src, stop } => self.take_until(i, *src, *stop),
            Node::Concat(a, b) => self.concat(i, *a, *b),
            Node::Sum { src, init, f } => {
                let (f, init) = (f.clone(), init.clone());
                self.sum(i, *src, init, f.as_ref(), host)?
            }
            Node::Check { src, expect, name } => {
                let src = *src;
                let out = self.event(src).cloned();
                if let Some(v) = &out {
                    if !expect.accepts(v) {
                        return Err(RxError::Input {
                            name: name.to_string(),
                            t_s,
                            value: super::describe(v),
                            expected: expect.to_string(),
                        });
                    }
                }
                self.states[i].done = done(self, src);
                out
            }
            Node::Perform { src, f } => {
                let f = f.clone();
                self.perform(i, *src, &f, host, sinks)?
            }
            Node::Foreach { src, sink } => {
                let (src, sink) = (*src, *sink);
                if let Some(v) = self.event(src) {
                    sinks.push((sink, v.clone()));
                }
                self.states[i].done = done(self, src);
                None
            }
        };
        Ok(out)
    }

    /// Whether stream `id` has completed.
    fn done(&self, id: StreamId) -> bool {
        self.states[id.0].done
    }

    /// `src.map(f)`, node `i`: `f` of `src`'s event.
    ///
    /// # Errors
    /// `f`'s failure ([`RxError::Type`], [`RxError::Host`]).
    fn map(
        &mut self,
        i: usize,
        src: StreamId,
        f: &Func,
        host: &mut dyn Host,
    ) -> Result<Option<Value>, RxError> {
        let out = match self.event(src).cloned() {
            Some(v) => Some(call(i, f, &[v], host, self)?),
            None => None,
        };
        self.states[i].done = self.done(src);
        Ok(out)
    }

    /// `src.filter(pred)`, node `i`: `src`'s event where `pred` of it is true.
    ///
    /// # Errors
    /// `pred`'s failure, or a predicate that gives no bool ([`RxError::Type`]).
    fn filter(
        &mut self,
        i: usize,
        src: StreamId,
        pred: &Func,
        host: &mut dyn Host,
    ) -> Result<Option<Value>, RxError> {
        let out = match self.event(src).cloned() {
            Some(v) => {
                let keep = call(i, pred, std::slice::from_ref(&v), host, self)?;
                match keep.as_bool() {
                    Some(true) => Some(v),
                    Some(false) => None,
                    None => {
                        return Err(type_error(
                            &self.graph,
                            i,
                            "filter predicate",
                            "bool",
                            &keep,
                        ))
                    }
                }
            }
            None => None,
        };
        self.states[i].done = self.done(src);
        Ok(out)
    }

    /// `a.zip(b)`, node `i`: pairs of the two streams' events, in order, each kept until the
    /// other side has one.
    fn zip(&mut self, i: usize, a: StreamId, b: StreamId) -> Option<Value> {
        let (ea, eb) = (self.event(a).cloned(), self.event(b).cloned());
        let (da, db) = (self.done(a), self.done(b));
        let s = &mut self.states[i];
        s.queue_a.extend(ea);
        s.queue_b.extend(eb);
        let out = if !s.queue_a.is_empty() && !s.queue_b.is_empty() {
            let pair = vec![s.queue_a.pop_front(), s.queue_b.pop_front()];
            Some(Value::Tuple(pair.into_iter().flatten().collect()))
        } else {
            None
        };
        s.done = (da && s.queue_a.is_empty()) || (db && s.queue_b.is_empty());
        out
    }

    /// `src.take(n)`, node `i`: `src`'s first `n` events.
    fn take(&mut self, i: usize, src: StreamId, n: u64) -> Option<Value> {
        let e = self.event(src).cloned();
        let d = self.done(src);
        let s = &mut self.states[i];
        let out = if s.count < n { e } else { None };
        if out.is_some() {
            s.count += 1;
        }
        s.done = s.count >= n || d;
        out
    }

    /// `src.skipUntil(trigger)`, node `i`: `src`'s events once `trigger` has fired.
    fn skip_until(&mut self, i: usize, src: StreamId, trigger: StreamId) -> Option<Value> {
        let opened = self.states[trigger.0].fired;
        let e = self.event(src).cloned();
        let d = self.done(src);
        let s = &mut self.states[i];
        s.open |= opened;
        s.done = d;
        if s.open {
            e
        } else {
            None
        }
    }

    /// `src.takeUntil(stop)`, node `i`: `src`'s events until `stop` fires.
    fn take_until(&mut self, i: usize, src: StreamId, stop: StreamId) -> Option<Value> {
        let closed = self.states[stop.0].fired;
        let e = self.event(src).cloned();
        let d = self.done(src);
        let s = &mut self.states[i];
        s.done = closed || d;
        if closed {
            None
        } else {
            e
        }
    }

    /// `a.concat(b)`, node `i`: `a`'s events, then, once `a` has completed, `b`'s.
    fn concat(&mut self, i: usize, a: StreamId, b: StreamId) -> Option<Value> {
        let a_done = self.done(a);
        let ea = self.event(a).cloned();
        let eb = self.event(b).cloned();
        let b_done = self.done(b);
        let s = &mut self.states[i];
        // `a`'s own flag: `open` marks that `a` had completed before this step.
        if !s.open {
            s.queue_a.extend(ea);
        }
        if a_done {
            s.open = true;
            s.queue_a.extend(eb);
        }
        let out = s.queue_a.pop_front();
        s.done = a_done && b_done && s.queue_a.is_empty();
        out
    }

    /// `src.sum(init, f)`, node `i`: the running total of `src`'s events from `init`, by `f`
    /// or, without one, by adding numbers or vectors.
    ///
    /// # Errors
    /// `f`'s failure, or events that cannot be added ([`RxError::Type`]).
    fn sum(
        &mut self,
        i: usize,
        src: StreamId,
        init: Value,
        f: Option<&Func>,
        host: &mut dyn Host,
    ) -> Result<Option<Value>, RxError> {
        let out = match self.event(src).cloned() {
            Some(v) => {
                let acc = self.states[i].value.clone().unwrap_or(init);
                Some(match f {
                    Some(f) => call(i, f, &[acc, v], host, self)?,
                    None => total(&acc, &v).ok_or_else(|| {
                        type_error(&self.graph, i, "sum", "numbers or vectors of one kind", &v)
                    })?,
                })
            }
            None => None,
        };
        self.states[i].done = self.done(src);
        Ok(out)
    }

    /// A `foreach` given a host function, node `i`: calls `f` on `src`'s event and collects
    /// the actions it performed into `sinks`.
    ///
    /// # Errors
    /// `f`'s failure ([`RxError::Host`]).
    fn perform(
        &mut self,
        i: usize,
        src: StreamId,
        f: &Func,
        host: &mut dyn Host,
        sinks: &mut Vec<(Action, Value)>,
    ) -> Result<Option<Value>, RxError> {
        if let Some(v) = self.event(src).cloned() {
            call_acting(i, f, &[v], host, self)?;
            sinks.extend(host.performed());
        }
        self.states[i].done = self.done(src);
        Ok(None)
    }
}

/// The value of source node `node` (number `i`) at `t_s`: a constant, the time, a bound open
/// stream or a probe.
///
/// # Errors
/// [`RxError::Unbound`] for an open parameter slot; [`RxError::Type`] for a node that is not
/// a source.
/// The event of source node `i` now: `None` for a probe of an actor that is not in the test
/// (its probe reads [`Value::Unit`]).
fn source(i: usize, node: &Node, t_s: f64, inputs: &dyn Inputs) -> Result<Option<Value>, RxError> {
    match node {
        Node::Const(v) => Ok(Some(v.clone())),
        Node::Tick => Ok(Some(Value::Num(t_s))),
        Node::Open(o) => Ok(Some(o.at(t_s))),
        Node::Probe(p) => Ok(match inputs.probe(*p) {
            Value::Unit => None,
            v => Some(v),
        }),
        Node::Param(slot) => Err(RxError::Unbound {
            node: i,
            slot: *slot,
        }),
        _ => Err(RxError::Type {
            node: i,
            at: format!("stream {i}"),
            message: "not a source stream".into(),
        }),
    }
}

/// A running total `acc + v` of numbers or vectors; `acc` [`Value::Unit`] (a `sum()` with no
/// initial value) starts the total from zero of `v`'s kind.
fn total(acc: &Value, v: &Value) -> Option<Value> {
    match acc {
        Value::Unit => match v {
            Value::Num(_) => Value::Num(0.0).add(v),
            Value::Vec3(_) => Value::Vec3([0.0; 3]).add(v),
            _ => None,
        },
        acc => acc.add(v),
    }
}

/// Calls `f` for node `node` where it computes a value (`map`, `filter`, `sum`): a host
/// function that performs an action here is an error, since only `foreach` performs them
/// (its actions would otherwise take effect whenever some `foreach` next ran).
fn call(
    node: usize,
    f: &Func,
    args: &[Value],
    host: &mut dyn Host,
    streams: &Runtime,
) -> Result<Value, RxError> {
    let out = call_acting(node, f, args, host, streams)?;
    if host.performed().is_empty() {
        Ok(out)
    } else {
        Err(RxError::Host {
            node,
            at: streams.graph.site(node),
            message: "a function given to map, filter or sum performed an action (car.setSpeed, \
                      car.brake, car.changeLane, p.walk): only foreach performs actions \
                      (`stream.foreach(f)`); map, filter and sum compute values"
                .into(),
            t_s: None,
        })
    }
}

/// Calls `f` for node `node`, leaving the actions it performs to the caller (`foreach`).
fn call_acting(
    node: usize,
    f: &Func,
    args: &[Value],
    host: &mut dyn Host,
    streams: &Runtime,
) -> Result<Value, RxError> {
    match f {
        Func::Native(_, f) => f(args).map_err(|NativeError(message)| RxError::Type {
            node,
            at: streams.graph.site(node),
            message,
        }),
        Func::Host(n) => host
            .call(*n, args, streams)
            .map_err(|HostError(message)| RxError::Host {
                node,
                at: streams.graph.site(node),
                message,
                t_s: None,
            }),
    }
}

fn type_error(graph: &Graph, node: usize, what: &str, expected: &str, got: &Value) -> RxError {
    RxError::Type {
        node,
        at: graph.site(node),
        message: format!("{what} needs {expected}, got a {}", got.kind()),
    }
}
