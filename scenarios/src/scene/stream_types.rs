//! What kind of values each stream of a scene carries, as far as its graph tells before a
//! test runs.

use paracosm_engine::behaviour::Output;
use paracosm_engine::rx::{Node, StreamId, Value as Rx};
use paracosm_generators::Domain;

use super::{level_value, ParamDecl};

/// The kind of values a stream carries, as far as the graph tells before a test runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SType {
    /// Numbers.
    Num,
    /// Bools.
    Bool,
    /// Strings.
    Text,
    /// Positions or velocities `(x, y, z)`.
    Vec3,
    /// Tuples (from `zip`).
    Tuple,
    /// Events without a value.
    Unit,
    /// Unknown until the test runs (a lambda's result), or mixed.
    Any,
}

impl SType {
    /// The kind in words, for messages: `numbers`, `bools`...
    pub fn name(self) -> &'static str {
        match self {
            SType::Num => "numbers",
            SType::Bool => "bools",
            SType::Text => "strings",
            SType::Vec3 => "positions",
            SType::Tuple => "tuples",
            SType::Unit => "events without a value",
            SType::Any => "values of any kind",
        }
    }
}

fn of_value(v: &Rx) -> SType {
    match v {
        Rx::Num(_) => SType::Num,
        Rx::Bool(_) => SType::Bool,
        Rx::Text(_) => SType::Text,
        Rx::Vec3(_) => SType::Vec3,
        Rx::Tuple(_) => SType::Tuple,
        Rx::Unit => SType::Unit,
    }
}

fn of_param(p: &ParamDecl) -> SType {
    match &p.domain {
        Domain::Interval { .. } => SType::Num,
        Domain::Levels(levels) => {
            let kinds: Vec<SType> = levels.iter().map(|l| of_value(&level_value(l))).collect();
            match kinds.split_first() {
                Some((k, rest)) if rest.iter().all(|r| r == k) => *k,
                _ => SType::Any,
            }
        }
    }
}

/// The static kind of every stream among `nodes` (a scene's graph so far), by [`StreamId`],
/// with `params` the scene's open parameters. Nodes only read
/// streams declared before them, so one pass in index order suffices.
pub fn stream_types(nodes: &[Node], params: &[ParamDecl]) -> Vec<SType> {
    let mut out: Vec<SType> = Vec::with_capacity(nodes.len());
    for node in nodes {
        let of = |s: &StreamId| out.get(s.0).copied().unwrap_or(SType::Any);
        let t = match node {
            Node::Const(v) => of_value(v),
            Node::Tick => SType::Num,
            Node::Param(p) => params.get(*p).map_or(SType::Any, of_param),
            Node::Open(_) => SType::Any,
            Node::Probe(p) => match p.output {
                Output::Pos | Output::Vel => SType::Vec3,
                Output::Heading | Output::Speed | Output::Separation => SType::Num,
                Output::Collision | Output::Collided => SType::Bool,
            },
            Node::Map { .. } => SType::Any,
            Node::Filter { src, .. }
            | Node::Take { src, .. }
            | Node::SkipUntil { src, .. }
            | Node::TakeUntil { src, .. }
            | Node::Check { src, .. } => of(src),
            Node::Zip(..) => SType::Tuple,
            Node::Concat(a, c) => {
                if of(a) == of(c) {
                    of(a)
                } else {
                    SType::Any
                }
            }
            Node::Sum { src, f, .. } => match f {
                None => of(src),
                Some(_) => SType::Any,
            },
            Node::Foreach { .. } | Node::Perform { .. } => SType::Unit,
        };
        out.push(t);
    }
    out
}
